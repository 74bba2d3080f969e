"""Superpoints on labelled real scans, against the tools scan users run, at equal counts.

Usage: python benchmarks/real_scans.py [--scans NAME ...] [-k 300 1000 3000]
       [--methods superfacets graph_segmentation cut_pursuit spt_partition vccs]
       [--spt-levels 1 2] [--beta auto 0]
       [--neighbors 10] [--split-merge] [--min-points 3] [--content] [--adaptive]
       [--size-ratios 0 8 4 2] [--fine-floors 8 4] [--merge-from 5] [--up-weights 2 4]
       [--leave-out CLASS ...] [--every 2] [--voxel 2] [--views 10] [--level-views 10]
       [--view-k 30 100] [--stations 5]
       [--csv results.csv] [--download] [--rooms 3]

Each scan of ``superfacets.evaluation.datasets.scans.SCANS`` found in the cache
(``$SUPERFACETS_SCANS``, default ``~/.cache/superfacets/scans``; ``--download``
fetches the missing ones, a few MB each), and the first ``--rooms N`` made-up rooms
(``superfacets.evaluation.datasets.rooms``: S3DIS-like, with colour, classes and objects;
no download), is segmented by every method at
each k, on the same point graph (10 nearest neighbours), and measured
against its per-point classes (unlabelled points left out; each point
weighs the same): undersegmentation error (eq. 4, lower is better),
boundary recall, boundary precision (the share of a method's own boundary
points near a true boundary: recall alone rewards long boundaries) and
achievable accuracy and the oracle mIoU (each superpoint given its majority class: the
figure Superpoint Transformer publishes for its partitions; higher is better), the number
of superpoints, their
median size in points and the share of single-point superpoints, and the
seconds (in process, one after the other, this
machine's threads); on scans with object instances (the ScanNet rooms)
also UE and recall against those.

Methods (the registry's, so ``superfacets experiment`` runs the same code):

- ``superfacets``: this package's default on points (its automatic
  ``density``: 0.5 on the sweeps, 0 on the airborne tile and the rooms), its requested count
  lowered where orphans add superpoints, so that it returns at most k
  (``_equal_count``), its colour term read from the data where the scan has
  RGB (``beta`` auto); ``--beta`` lists the settings (default ``auto 0``: also
  without colour, on scans with RGB); with ``--beta B`` also
  the colour term (scans with RGB only); with ``--split-merge`` also
  split-and-merge (off by default on points); with ``--min-points N`` also
  its superpoints of fewer than N points merged into a neighbour
  (``segment(..., min_elements=N)``), the request raised until
  the count is reached; with ``--size-ratios R ...`` also its merges with each largest
  superpoint (``max_size_ratio``: R times the mean; 0 no bound, as before the bound);
  with ``--fine-floors N ...`` also its first run (before the merges) allowed down to N
  points per superpoint (``method.rules.MIN_FINE_ELEMENTS``, 12, set for the run); with
  ``--merge-from N ...`` also its runs with ``merge_from`` N (the merges on every cloud,
  uneven density included);
  with ``--adaptive`` also the content-adaptive
  superpoints (``adaptive_superpoints``: exactly k);
- ``graph_segmentation``: the ScanNet Segmentator's method, its threshold
  searched for k;
- ``cut_pursuit`` (only when named in ``--methods``): Superpoint Graph's partition
  (``cut-pursuit-py``, the ``baselines`` extra), its regularisation searched for k;
  skipped if not installed; out of the default comparison, since cut-pursuit-py cannot
  run it in Superpoint Graph's configuration (most of its superpoints at equal counts
  are single points);
- ``spt_partition``: cut pursuit as Superpoint Transformer runs its
  partition (``superfacets.evaluation.baselines.spt_partition``), with the
  dataset settings nearest the scan (``ScanSource.spt_preset``: ScanNet for
  the rooms, KITTI-360 for the sweeps, DALES for the airborne tile), the
  regularisation of its level 1 or 2 searched for k (``--spt-levels``: each
  level asked for is a row; default: the level the count chooses); skipped
  unless ``pycut-pursuit`` (GPL-3, installed by hand) is importable;
- ``vccs``: PCL's supervoxels through the external ``vccs_supervoxel``
  module (docs/notes/superpoints.md says how to build it), its seed resolution
  searched for k; skipped if it is not importable.

Prints a Markdown table per scan, then one per kind of scan (airborne, street, indoor):
in how many scans the default is within the targets of the best other method at each k
(UE at most, boundary recall at least minus 0.02, oracle mIoU at least; a baseline's rows
within 10 % of k, ``EQUAL_COUNT``), and the means, and the settings where all three are
met (the missed ones named); ``--every N`` runs every method on every N-th point of each
labelled scan (its ground truth with it: the same scans at a lower density); ``--voxel F``
each through a voxel grid filter, one point a voxel F times its median spacing wide
(:func:`voxeled`: evenly thinned, as users prepare a scan); ``--views N``
also N frame-like views of each indoor scan (:func:`frame_views`: what an RGB-D camera
looking down at the floor and tables sees, a kind of their own, at ``--view-k``);
``--level-views N`` N such views looking level, at the walls; ``--stations N`` N
terrestrial-like stations in each indoor scan (:func:`station_views`: what a laser scanner on
a tripod records all around, one point per half degree, hidden points removed, at ``-k``);
``--csv`` also writes every row. ``--rows A.csv ...`` adds the rows of earlier runs to that
table (a baseline run in another environment: ``spt_partition`` needs a NumPy before 2 for
``pycut-pursuit``); with ``--rows`` and no ``--methods`` nothing is run again.
"""

from __future__ import annotations

import argparse
import csv
import importlib.util
import sys
import time

import numpy as np

METHODS = ("superfacets", "graph_segmentation", "cut_pursuit", "spt_partition", "vccs")
#: The comparison's methods by default: not ``cut_pursuit`` (cut-pursuit-py's partition
#: cannot be given Superpoint Graph's configuration, and its count search leaves 30-58 %
#: of its superpoints a single point on 3 cm rooms: ``docs/notes/superpoints-defaults.md``)
COMPARED = ("superfacets", "graph_segmentation", "spt_partition", "vccs")
COLUMNS = ("scan", "points", "method", "beta", "k", "segments", "undersegmentation_error",
           "undersegmentation_error_np", "boundary_recall", "boundary_precision",
           "achievable_accuracy", "oracle_miou", "median_points", "single_points", "seconds",
           "instances_undersegmentation_error", "instances_boundary_recall",
           "left_out_undersegmentation_error", "left_out_boundary_recall")


def available(method: str) -> bool:
    if method == "cut_pursuit":
        return importlib.util.find_spec("cp_kmpp") is not None or \
            importlib.util.find_spec("cut_pursuit_py") is not None
    if method == "vccs":
        return importlib.util.find_spec("vccs_supervoxel") is not None
    if method == "spt_partition":
        try:  # a wheel built against NumPy 1 is found but does not import
            import pycut_pursuit.cp_d0_dist  # noqa: F401
        except ImportError:
            return False
    return True


def run(scan, method: str, k: int, beta: float, options: dict | None = None,
        neighbors: int = 10, leave_out: tuple = ()) -> dict:
    """One method on one scan at ``k``: the metrics and the seconds (its search and its
    point graph included, each method on a fresh cloud object);
    with ``leave_out`` classes, also UE and recall with their points unlabelled."""
    from dataclasses import replace

    from superfacets import segment
    from superfacets.evaluation.datasets.scans import evaluate_scan

    # a fresh cloud object: the point graph is cached on the cloud, so each method builds
    # its own inside its time (with one shared cloud the first method paid for all)
    cloud = replace(scan.cloud)
    t0 = time.perf_counter()
    if method == "superfacets":  # the registry's run, with the colour weight
        options = dict(options or {})
        options["min_elements"] = options.pop("min_points", 1)
        floor = options.pop("fine_floor", None)

        def superpoints(req):
            return segment(cloud, req, beta=beta, n_neighbors=neighbors, **options).labels

        if options.pop("adaptive", False):  # the planarity level: exactly k segments
            from superfacets import adaptive_superpoints

            labels = adaptive_superpoints(cloud, k, beta=beta, n_neighbors=neighbors,
                                          **options)
        elif floor is not None:  # a module constant: set for this run only
            from superfacets.method import rules

            kept, rules.MIN_FINE_ELEMENTS = rules.MIN_FINE_ELEMENTS, int(floor)
            try:
                labels = _equal_count(superpoints, k)
            finally:
                rules.MIN_FINE_ELEMENTS = kept
        else:
            labels = _equal_count(superpoints, k)
    elif method == "graph_segmentation":  # as the registry runs them, with the neighbours
        from superfacets.evaluation.baselines.graph_segmentation import graph_segmentation

        labels = graph_segmentation(cloud, n_segments=k, elements="points",
                                    n_neighbors=neighbors)
    elif method == "cut_pursuit":
        from superfacets.evaluation.baselines.cut_pursuit import cut_pursuit

        labels = cut_pursuit(cloud, k, elements="points", n_neighbors=neighbors)
    elif method == "spt_partition":  # its own graph and voxels: the neighbours are its own
        from superfacets.evaluation.baselines.spt_partition import spt_partition

        labels = spt_partition(cloud, k, preset=scan.source.spt_preset,
                               level=(options or {}).get("level", "auto"))
    else:
        from superfacets.evaluation.baselines.vccs import vccs

        labels = vccs(cloud, k, n_neighbors=neighbors)
    seconds = time.perf_counter() - t0
    labels = np.asarray(labels)
    row = evaluate_scan(scan, labels)  # always on the 10-neighbour graph
    sizes = np.bincount(labels[labels >= 0])
    sizes = sizes[sizes > 0]
    row.update(seconds=seconds, median_points=float(np.median(sizes)),
               single_points=float(np.mean(sizes == 1)))
    if leave_out:  # the same labels, those classes' points left out as unlabelled
        from dataclasses import replace

        gt = np.asarray(scan.ground_truth)
        kept = evaluate_scan(replace(scan, ground_truth=np.where(np.isin(gt, leave_out), -1,
                                                                 gt)), labels)
        row.update(left_out_undersegmentation_error=kept["undersegmentation_error"],
                   left_out_boundary_recall=kept["boundary_recall"])
    if scan.instances is not None:  # the same labels against the object instances
        obj = evaluate_scan(scan, np.asarray(labels), against="instances")
        row.update(instances_undersegmentation_error=obj["undersegmentation_error"],
                   instances_boundary_recall=obj["boundary_recall"])
    return row


def _at_least_one(text: str) -> int:
    """``--fine-floors`` and ``--merge-from``: an integer ``>= 1``."""
    import argparse

    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}")
    return value


def _beta(text: str):
    """``--beta``: ``auto`` (None: read from the data) or a number."""
    return None if text.strip().lower() == "auto" else float(text)


def _equal_count(run_k, k: int, tries: int = 4):
    """Labels with at most ``k`` superpoints, as near ``k`` as ``tries`` runs get.

    Every connected piece of a scan's point graph gets a center within the
    ``k``, but elements no window reaches still seed superpoints of their own,
    so ``segment(cloud, k)`` can return more than ``k`` (311 for k = 300 on a
    sweep). The baselines'
    parameters are searched for ``k``; this lowers the requested count by the
    excess until the result has at most ``k``, so every method is compared at
    (about) the same count, the search included in the seconds.
    """
    req, best = k, None
    for _ in range(tries):
        labels = np.asarray(run_k(req))
        count = int(np.unique(labels[labels >= 0]).size)
        if count <= k and (best is None or count > best[0]):
            best = (count, labels)
        if count == k or req <= 1:
            break
        # too many: lower by the excess; too few (superpoints merged away): scale up
        req = max(1, req - (count - k)) if count > k else \
            req + max(1, round((k - count) * req / max(count, 1)))
    return labels if best is None else best[1]


def _scans(a):
    """``(name, scan)`` of each labelled scan asked for and found, then the made-up rooms."""
    from superfacets.evaluation.datasets.rooms import load_room, room_names
    from superfacets.evaluation.datasets.scans import fetch_scan, load_scan, scan_files

    for name in a.scans:
        if a.download:
            try:
                fetch_scan(name)
            except FileNotFoundError as exc:
                print(f"skipped {name}: {exc}", file=sys.stderr)
                continue
        missing = [p for p in scan_files(name) if not p.is_file()]
        if missing:
            print(f"skipped {name}: {missing[0]} is missing (--download fetches it)",
                  file=sys.stderr)
            continue
        scan = load_scan(name)
        scan = scan if a.every == 1 else thinned(scan, a.every)
        if a.voxel:
            scan, width = voxeled(scan, a.voxel)
            print(f"{name}: voxels {width:.3g} wide, {scan.cloud.points.shape[0]:,} points kept",
                  file=sys.stderr)
        yield name, scan
        if scan_kind(name) == "indoor":
            for i, keep in enumerate(frame_views(scan, a.views) if a.views else ()):
                yield f"{name}-view{i}", subset(scan, keep)
            for i, keep in enumerate(frame_views(scan, a.level_views, tilt=(0.0, 20.0))
                                     if a.level_views else ()):
                yield f"{name}-level{i}", subset(scan, keep)
            for i, keep in enumerate(station_views(scan, a.stations) if a.stations else ()):
                yield f"{name}-station{i}", subset(scan, keep)
    for name in room_names(a.rooms):
        yield name, load_room(name)


def thinned(scan, every: int):
    """Every ``every``-th point of a labelled scan (in file order), with its colours,
    fields, ground truth and instances: the same scan at a lower density."""
    cloud = scan.cloud
    if cloud.shape is not None or cloud.objects:
        raise SystemExit(f"{scan.name}: --every thins unorganized clouds of one object only")
    return subset(scan, np.arange(0, cloud.points.shape[0], every))


def voxeled(scan, factor: float):
    """A labelled scan through a voxel grid filter, as users thin a scan before they segment
    it: one point a voxel (the first in file order), the voxels ``factor`` times the scan's
    median spacing (each point's distance to its nearest other, on at most 20,000 evenly
    spaced points) wide, from the box's lowest corner. Returns the scan and the voxel's
    width."""
    from scipy.spatial import cKDTree

    cloud = scan.cloud
    if cloud.shape is not None or cloud.objects:
        raise SystemExit(f"{scan.name}: --voxel filters unorganized clouds of one object only")
    p = np.asarray(cloud.points, dtype=np.float64)
    rows = np.flatnonzero(np.isfinite(p).all(axis=1))
    q = p[rows]
    d, _ = cKDTree(q).query(q[::max(1, q.shape[0] // 20_000)], k=2)
    spacing = d[:, 1][d[:, 1] > 0]
    width = factor * float(np.median(spacing)) if spacing.size else 1.0
    _, first = np.unique(np.floor((q - q.min(axis=0)) / width).astype(np.int64), axis=0,
                         return_index=True)
    return subset(scan, rows[np.sort(first)]), width


def subset(scan, keep):
    """The points ``keep`` (indices into the file's points) of a labelled scan, with their
    colours, fields, ground truth and instances."""
    from dataclasses import replace

    cloud = scan.cloud

    def part(a):
        return None if a is None else np.asarray(a)[keep]

    cloud = replace(cloud, points=cloud.points[keep], normals=part(cloud.normals),
                    colors=part(cloud.colors),
                    fields={k: v[keep] for k, v in (cloud.fields or {}).items()} or None)
    return replace(scan, cloud=cloud, ground_truth=scan.ground_truth[keep],
                   instances=part(scan.instances))


#: A frame-like view keeps at least this many points (fewer: another camera is drawn)
MIN_VIEW_POINTS = 800
#: The radius in metres of the disc each point is drawn as in a view (a ScanNet room's
#: points are about 3 cm apart: the discs close the gaps a camera would not see through)
SPLAT = 0.02


def _nearest_surface(row, col, depth, radius, shape):
    """Per point drawn at pixel ``(row, col)`` at ``depth``, as a disc of ``radius`` pixels:
    the nearest depth drawn over its pixel (each radius's discs by a minimum filter)."""
    from scipy.ndimage import minimum_filter

    h, w = shape
    pixel = row * w + col
    nearest = np.full(shape, np.inf)
    for r in np.unique(radius):
        drawn = np.full(h * w, np.inf)
        np.minimum.at(drawn, pixel[radius == r], depth[radius == r])
        nearest = np.minimum(nearest, minimum_filter(drawn.reshape(shape), 2 * r + 1))
    return nearest.ravel()[pixel]


def _views(scan, n: int, seed: int, tries: int, height, see, fewest: int):
    """Up to ``n`` point index arrays ``see(points, eye, rng)`` of at least ``fewest`` points,
    each from an eye ``height`` metres above the floor at 15-85 % across the room, at most
    ``tries`` eyes in all (their places and ``see``'s draws from one seeded generator)."""
    p = np.asarray(scan.cloud.points, dtype=np.float64)
    lo, hi = np.nanmin(p, axis=0), np.nanmax(p, axis=0)
    rng = np.random.default_rng(seed)
    found = 0
    for _ in range(tries):
        eye = np.r_[lo[:2] + (0.15 + 0.7 * rng.random(2)) * (hi[:2] - lo[:2]),
                    lo[2] + rng.uniform(*height)]
        keep = see(p, eye, rng)
        if keep.size >= fewest:
            yield keep
            found += 1
            if found == n:
                return


def frame_views(scan, n: int, seed: int = 0, tries: int = 200, tilt=(45.0, 80.0)):
    """The point indices of ``n`` frame-like views of an indoor scan: what an RGB-D camera
    sees from 1.2-1.6 m above the floor, at 15-85 % across the room, turned at random and
    tilted down by ``tilt`` degrees (45-80: at the floor and the tables; 0-20: level, at
    the walls), through a 60 x 45 degree field out to 4 m: the nearest
    surface of each pixel of a 160 x 120 grid (each point drawn as a disc of :data:`SPLAT`;
    points within 5 cm behind a pixel's nearest kept). Views of fewer than
    :data:`MIN_VIEW_POINTS` points are drawn again, at most ``tries`` cameras in all."""
    def see(p, eye, rng):
        yaw, pitch = rng.uniform(0, 2 * np.pi), np.radians(rng.uniform(*tilt))
        ahead = np.array([np.cos(yaw) * np.cos(pitch), np.sin(yaw) * np.cos(pitch),
                          -np.sin(pitch)])
        right = np.cross(ahead, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        d = p - eye
        z, above = d @ ahead, d @ np.cross(right, ahead)
        u, v = np.arctan2(d @ right, z), np.arctan2(above, z)
        seen = np.flatnonzero((z > 0.3) & (np.linalg.norm(d, axis=1) < 4.0)
                              & (np.abs(u) < np.radians(30)) & (np.abs(v) < np.radians(22.5)))
        row = ((v[seen] / np.radians(45) + 0.5) * 120).astype(int).clip(0, 119)
        col = ((u[seen] / np.radians(60) + 0.5) * 160).astype(int).clip(0, 159)
        # each point drawn as a disc of SPLAT metres (a sampled surface hides what is
        # behind it, near the camera too): its pixels' radius by its distance
        radius = np.ceil(np.arctan(SPLAT / z[seen]) / np.radians(60 / 160)).astype(int)
        return seen[z[seen] <= _nearest_surface(row, col, z[seen], radius, (120, 160))
                    + 0.05]

    return _views(scan, n, seed, tries, (1.2, 1.6), see, MIN_VIEW_POINTS)


#: A station's angular step in degrees (a terrestrial scanner's resolution, coarse: about
#: the ScanNet rooms' 3 cm spacing at 3.4 m, so that the density falls with the range
#: beyond)
STATION_STEP = 0.5
#: A station keeps at least this many points (fewer: another place is drawn)
MIN_STATION_POINTS = 5_000


#: Hidden point removal's radius (Katz, Tal and Basri 2007, "Direct visibility of point
#: sets"): the points flipped about a sphere of this many times their largest distance
HPR_RADIUS = 100.0


def station(points, eye) -> np.ndarray:
    """The indices of ``points`` a terrestrial scanner at ``eye`` records: all around and
    from 60 degrees below the level up (not its tripod's cone), one point per
    :data:`STATION_STEP` degrees of azimuth and elevation, the nearest of those visible
    there (hidden point removal: the points flipped about a sphere, :data:`HPR_RADIUS`,
    on their convex hull with the eye): the density falls with the square of the range,
    as a station's does, and a surface seen at a grazing angle (the floor far off) stays.
    Sorted."""
    from scipy.spatial import ConvexHull

    p = np.asarray(points, dtype=np.float64)
    d = p - np.asarray(eye, dtype=np.float64)
    far = np.linalg.norm(d, axis=1)
    d, far, idx = d[far > 0.3], far[far > 0.3], np.flatnonzero(far > 0.3)
    flipped = d + (2 * (HPR_RADIUS * far.max() - far) / far)[:, None] * d
    hull = ConvexHull(np.vstack([flipped, np.zeros(3)])).vertices
    hull = hull[hull < far.size]  # (not the eye)
    d, far, idx = d[hull], far[hull], idx[hull]
    up = np.arcsin(np.clip(d[:, 2] / far, -1.0, 1.0))
    ok = up > -np.radians(60)
    step = np.radians(STATION_STEP)
    pixel = (((up + np.radians(60)) / step).astype(np.int64) * int(round(360 / STATION_STEP))
             + ((np.arctan2(d[:, 1], d[:, 0]) + np.pi) / step).astype(np.int64)
             % int(round(360 / STATION_STEP)))[ok]
    order = np.lexsort((far[ok], pixel))  # per pixel, the nearest visible point
    first = order[np.r_[True, pixel[order][1:] != pixel[order][:-1]]]
    return np.sort(idx[ok][first])


def station_views(scan, n: int, seed: int = 0, tries: int = 200):
    """The point indices of ``n`` terrestrial-like stations in an indoor scan
    (:func:`station`): a scanner on a tripod 1.2-1.7 m above the floor, at 15-85 % across
    the room. Stations of fewer than :data:`MIN_STATION_POINTS` points (inside furniture)
    are drawn again, at most ``tries`` places in all."""
    return _views(scan, n, seed, tries, (1.2, 1.7), lambda p, eye, rng: station(p, eye),
                  MIN_STATION_POINTS)


def scan_kind(name: str) -> str:
    """The kind of scan ``name`` for the summary: airborne, street, indoor, indoor frame
    (:func:`frame_views`) or made-up."""
    from superfacets.evaluation.datasets.scans import SCANS

    for mark, kind in (("-view", "indoor frame"), ("-level", "indoor frame, level"),
                       ("-station", "indoor station")):
        if mark in name:
            return kind
    kind = SCANS[name].kind.lower() if name in SCANS else "made-up room"
    return next((k for k, words in (("airborne", ("airborne",)), ("street", ("mobile",)),
                                    ("indoor", ("indoor", "rgb-d"))) if any(w in kind
                                                                           for w in words)),
                "made-up" if "made-up" in kind else "other")


#: A baseline's row counts in the table per kind where its count is within this share of
#: ``k`` (equal counts: cut pursuit's search stops 20-70 % short of k on some scans)
EQUAL_COUNT = 0.1


def _by_kind(rows: list, kinds: dict) -> None:
    """Per kind of scan and k: in how many scans the package's default is within the
    issue's targets of the best other method at an equal count (:data:`EQUAL_COUNT`; UE at
    most, boundary recall at least minus 0.02, oracle mIoU at least), and the mean of each
    over the kind's scans."""
    print("\n### Per kind of scan: superfacets against the best other method\n")
    print("| kind | k | scans | UE <= best | recall >= best - 0.02 | mIoU >= best | "
          "all three | mean UE (ours / best) | mean recall | mean oracle mIoU |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    missed, total, np_won = [], 0, 0
    for kind in sorted(set(kinds.values())):
        for k in sorted({r["k"] for r in rows}):
            won, means = [0, 0, 0, 0], [[], [], [], [], [], []]
            scans = sorted(s for s in {r["scan"] for r in rows} if kinds[s] == kind)
            for s in scans:
                ours = [r for r in rows if r["scan"] == s and r["k"] == k and
                        r["method"].split(" ")[0] == "superfacets"][:1]
                others = [r for r in rows if r["scan"] == s and r["k"] == k and
                          not r["method"].startswith("superfacets") and
                          abs(int(r["segments"]) / k - 1) <= EQUAL_COUNT]
                if not ours or not others:
                    continue
                o = ours[0]
                best = (min(r["undersegmentation_error"] for r in others),
                        max(r["boundary_recall"] for r in others),
                        max(r["oracle_miou"] for r in others))
                met = (o["undersegmentation_error"] <= best[0],
                       o["boundary_recall"] >= best[1] - 0.02, o["oracle_miou"] >= best[2])
                for i, ok in enumerate(met + (all(met),)):
                    won[i] += ok
                np_won += o.get("undersegmentation_error_np", np.inf) <= min(
                    r.get("undersegmentation_error_np", np.inf) for r in others)
                if not all(met):
                    missed.append(f"{s} at {k} ("
                                  + ", ".join(w for w, ok in zip(("UE", "recall", "mIoU"), met)
                                              if not ok) + ")")
                for i, v in enumerate((o["undersegmentation_error"], best[0],
                                       o["boundary_recall"], best[1], o["oracle_miou"],
                                       best[2])):
                    means[i].append(v)
            if not means[0]:
                continue
            m = [float(np.mean(x)) for x in means]
            n = len(means[0])
            total += n
            print(f"| {kind} | {k} | {n} | {won[0]}/{n} | {won[1]}/{n} | {won[2]}/{n} | "
                  f"{won[3]}/{n} | {m[0]:.3f} / {m[1]:.3f} | {m[2]:.3f} / {m[3]:.3f} | "
                  f"{m[4]:.3f} / {m[5]:.3f} |")
    if total:
        print(f"\nAll three targets met in {total - len(missed)} of {total} settings"
              + (f"; missed: {'; '.join(missed)}." if missed else "."))
        print(f"UE by Neubert and Protzel's definition (no tolerance) at most the best other "
              f"method's in {np_won} of {total} settings.")


def _read_rows(path: str) -> list[dict]:
    """The rows of a ``--csv`` file, their counts and metrics as numbers."""
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    for r in rows:
        r["k"] = int(r["k"])
        for c in ("undersegmentation_error", "boundary_recall", "oracle_miou",
                  "undersegmentation_error_np"):
            if r.get(c) not in (None, ""):  # (files from before the NP error: without it)
                r[c] = float(r[c])
    return rows


def main() -> None:
    from superfacets.evaluation.datasets.scans import SCANS
    from superfacets.inputs.cloud import surface_up_weight

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scans", nargs="+", default=list(SCANS), choices=list(SCANS))
    ap.add_argument("-k", type=int, nargs="+", default=[300, 1000, 3000])
    ap.add_argument("--methods", nargs="+", default=None, choices=METHODS,
                    help="default: all but cut_pursuit (see COMPARED); none with --rows")
    ap.add_argument("--rows", nargs="+", default=[], metavar="CSV",
                    help="also the rows of these CSV files (--csv of earlier runs) in the "
                         "table per kind")
    ap.add_argument("--beta", type=_beta, nargs="+", default=[None, 0.0],
                    help="colour weights of superfacets: auto (the default's, read from the "
                         "data) or a number (other than auto only on scans with RGB)")
    ap.add_argument("--neighbors", type=int, default=10,
                    help="nearest neighbours of every method's point graph (the metrics stay "
                         "on the 10-neighbour graph)")
    ap.add_argument("--split-merge", action="store_true",
                    help="also superfacets with split-and-merge (off by default on points)")
    ap.add_argument("--min-points", type=int, default=0,
                    help="also superfacets with superpoints of fewer points merged into a "
                         "neighbour (segment's min_elements), the count searched")
    ap.add_argument("--size-ratios", type=float, nargs="+", default=[], metavar="R",
                    help="also superfacets with these max_size_ratio values (the merges' "
                         "largest superpoint in mean sizes; 0: no bound), a row each")
    ap.add_argument("--fine-floors", type=_at_least_one, nargs="+", default=[], metavar="N",
                    help="also superfacets with its first run allowed down to N points per "
                         "superpoint (method.rules.MIN_FINE_ELEMENTS, 12), a row each")
    ap.add_argument("--merge-from", type=_at_least_one, nargs="+", default=[], metavar="N",
                    help="also superfacets with merge_from N (merged from N times k, on every "
                         "cloud: the default merges only clouds of even density), a row each")
    ap.add_argument("--up-weights", type=float, nargs="+", default=[], metavar="W",
                    help="also superfacets with these up_weight values (the up coordinate W "
                         "times in the distances), a row each")
    ap.add_argument("--content", action="store_true",
                    help="also superfacets with content-sensitive sizes (density=0.5, "
                         "roughness=1)")
    ap.add_argument("--leave-out", type=int, nargs="+", default=[], metavar="CLASS",
                    help="also UE and recall with these classes' points unlabelled (e.g. 1: "
                         "ASPRS 'unclassified', scattered points on the airborne tile)")
    ap.add_argument("--adaptive", action="store_true",
                    help="also superfacets' content-adaptive superpoints (adaptive_superpoints)")
    ap.add_argument("--spt-levels", type=int, nargs="+", choices=(1, 2), default=[],
                    help="spt_partition: search these levels' regularisation, a row each "
                         "(default: the level the count chooses)")
    ap.add_argument("--every", type=_at_least_one, default=1, metavar="N",
                    help="every N-th point of each labelled scan (its ground truth with it): "
                         "the same scans at a lower density (default 1: all)")
    ap.add_argument("--voxel", type=float, default=0.0, metavar="F",
                    help="each labelled scan through a voxel grid filter first, one point a "
                         "voxel F times its median spacing wide (its ground truth with it; "
                         "after --every; default 0: none)")
    ap.add_argument("--views", type=int, default=0, metavar="N",
                    help="also N frame-like views of each indoor scan (what an RGB-D camera "
                         "looking down sees; frame_views), a kind of their own (default 0)")
    ap.add_argument("--level-views", type=int, default=0, metavar="N",
                    help="also N frame-like views looking level, at the walls (frame_views "
                         "tilted 0-20 degrees down), a kind of their own (default 0)")
    ap.add_argument("--stations", type=int, default=0, metavar="N",
                    help="also N terrestrial-like stations in each indoor scan (what a "
                         "scanner on a tripod sees all around; station_views), at -k, a kind "
                         "of their own (default 0)")
    ap.add_argument("--view-k", type=int, nargs="+", default=[30, 100], metavar="K",
                    help="the counts of the views (800-1,500 points each; default 30 100)")
    ap.add_argument("--csv", help="also write every row to this CSV file")
    ap.add_argument("--download", action="store_true", help="fetch missing scans first")
    ap.add_argument("--rooms", type=int, default=3, metavar="N",
                    help="also the first N made-up labelled rooms (S3DIS-like, "
                         "superfacets.evaluation.datasets.rooms; default: 3)")
    a = ap.parse_args()
    if not a.voxel >= 0:
        ap.error(f"--voxel: expected a number >= 0, got {a.voxel}")
    if a.methods is None:
        a.methods = [] if a.rows else list(COMPARED)

    rows = [r for path in a.rows for r in _read_rows(path)]
    for name, scan in (_scans(a) if a.methods else ()):
        n = int(scan.cloud.n_total)
        coloured = scan.cloud.colors is not None
        up = scan.cloud.up  # (the weight of its heights the default reads, on a scene)
        weight = "" if up is None else \
            f", heights weighed {surface_up_weight(scan.cloud.points, up):g} by default"
        print(f"\n### {name}: {n:,} points, {scan.source.kind}"
              f"{', RGB' if coloured else ''}{weight}\n")
        objects = scan.instances is not None
        print("| k | method | UE | UE (NP) | boundary recall | boundary precision | "
              "achievable accuracy "
              "| oracle mIoU | superpoints | median points | single points | s |"
              + (" UE, instances | recall, instances |" if objects else "")
              + (" UE, classes left out | recall, classes left out |" if a.leave_out else ""))
        print("|---|---|---|---|---|---|---|---|---|---|---|---|" + ("---|---|" if objects else "")
              + ("---|---|" if a.leave_out else ""))
        for k in (a.view_k if scan_kind(name).startswith("indoor frame") else a.k):
            for method in a.methods:
                if not available(method):
                    print(f"| {k} | {method} | not installed | | | | | | | | |"
                          + (" | |" if objects else ""))
                    continue
                betas = [b for b in a.beta if b is None or coloured] \
                    if method == "superfacets" else [0.0]
                variants = [(b, {}) for b in betas]
                if method == "spt_partition" and a.spt_levels:
                    variants = [(0.0, {"level": lv}) for lv in a.spt_levels]
                if method == "superfacets" and a.split_merge:
                    variants += [(b, {"split_merge": True}) for b in betas]
                if method == "superfacets" and a.content:
                    variants += [(0.0, {"density": 0.5, "roughness": 1.0})]
                if method == "superfacets" and a.adaptive:
                    variants += [(0.0, {"adaptive": True})]
                if method == "superfacets":
                    variants += [(None, {"max_size_ratio": v}) for v in a.size_ratios]
                    variants += [(None, {"fine_floor": v}) for v in a.fine_floors]
                    variants += [(None, {"merge_from": v}) for v in a.merge_from]
                    variants += [(None, {"up_weight": v}) for v in a.up_weights]
                if method == "superfacets" and a.min_points > 1:
                    variants += [(0.0, {"min_points": a.min_points})]
                for beta, options in variants:
                    r = run(scan, method, k, beta, options, a.neighbors, tuple(a.leave_out))
                    label = method + (f" beta={beta:g}" if beta is not None and method ==
                                      "superfacets" and coloured else "") + \
                        (" split-and-merge" if options.get("split_merge") else "") + \
                        (" content" if "density" in options else "") + \
                        (" adaptive" if options.get("adaptive") else "") + \
                        (f" level {options['level']}" if "level" in options else "") + \
                        (f" min {options['min_points']} points" if "min_points" in options
                         else "") + \
                        (f" max size {options['max_size_ratio']:g}" if "max_size_ratio" in
                         options else "") + \
                        (f" floor {options['fine_floor']}" if "fine_floor" in options else "") + \
                        (f" up weight {options['up_weight']:g}" if "up_weight" in options
                         else "") + \
                        (f" merge from {options['merge_from']}" if "merge_from" in options
                         else "")
                    print(f"| {k} | {label} | {r['undersegmentation_error']:.4f} | "
                          f"{r['undersegmentation_error_np']:.4f} | "
                          f"{r['boundary_recall']:.4f} | {r['boundary_precision']:.4f} | "
                          f"{r['achievable_accuracy']:.4f} | {r['oracle_miou']:.4f} | "
                          f"{r['segments']} | "
                          f"{r['median_points']:g} | {r['single_points']:.1%} | "
                          f"{r['seconds']:.1f} |"
                          + (f" {r['instances_undersegmentation_error']:.4f} | "
                             f"{r['instances_boundary_recall']:.4f} |" if objects else "")
                          + (f" {r['left_out_undersegmentation_error']:.4f} | "
                             f"{r['left_out_boundary_recall']:.4f} |" if a.leave_out else ""),
                          flush=True)
                    rows.append(dict(scan=name, points=n, method=label, beta=beta, k=k,
                                     **{c: r.get(c, "") for c in COLUMNS[5:]}))
    _by_kind(rows, {name: scan_kind(name) for name in {r["scan"] for r in rows}})
    if a.csv:
        with open(a.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=COLUMNS)
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main()
