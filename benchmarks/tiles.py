"""Tiled runs against one run: quality, border stitching, time and memory per worker.

Usage: python benchmarks/tiles.py [--mesh-id 281] [--subdivide 2 3] [--points 1000000]
       [-k 2000] [--tiles 8] [--workers 2] [--halo 3] [--no-mesh] [--tiled-only]
       [--seeds 0 1 2] [--fine] [--rotations N [--rotations-tiled]]
       python benchmarks/tiles.py --compare [-k 600] [--tiles 8] [--halo 3] [--paper]
       [--times 1] [--per-category 1] [--refine 1] [--compare-points N] [--merge-from F]
       [--start sample|tiles]

``--compare``: the first benchmark mesh of each category (``--per-category N``: the
first N), subdivided ``--times``
times (default once), segmented once and tiled (in process), the mean
undersegmentation error of each, the superfacets cut by a border and the
disagreements (docs/notes/tiles.md). ``--refine``: the tiles' refine rounds
(default: ``segment_tiled``'s); ``--start``: where they start (``segment_tiled``'s
``start``). ``--compare-points N``: ``N`` points sampled
on each mesh (seed 0, each with its face's class) instead of the subdivided
faces, the UE on the whole cloud's point graph. ``--merge-from F``: both runs with
``merge_from=F`` (1: no merges to the count).

Inputs with ground truth, larger than the benchmark's: a benchmark mesh
(``../shared/data/psb.tar.xz``) subdivided ``s`` times (each triangle into 4,
its ground-truth label kept), written as a binary PLY; and points sampled on
it (``.npy``), labelled by their face. Each input is segmented

- once, in a new process (``superfacets.segment``, the default method),
- tiled (``superfacets.segment_tiled``) from the file, read in chunks by each
  task, on a local Dask cluster of ``--workers`` processes,

and the table gives the undersegmentation error of each against the ground
truth, the superfacets cut by a tile border (labels that are not one
connected piece of the whole input's graph; the stitching's promise is 0),
the border disagreements, wall time and peak resident memory (the single
run's process; the largest of the tiles' tasks).

``--fine`` (clouds merged to the count): also the superpoints before the merges, the UE
of each run's and of one run's merges (on the whole graph) of the tiled run's: whether a
difference comes from the superpoints the tiles make or from the merges of their sums
(the single run's peak then includes saving its superpoints). ``--rotations N``
(points): also one run on the same cloud turned by N random rotations, in a new process
each: the spread of one run's error on the same points (the UE, each point once, does
not change under a rotation); with ``--rotations-tiled`` each turned cloud is also
tiled, and the two runs' means over the orientations are compared. ``--seeds``: one
cloud per seed of the sampling (default 0), to tell the spread of the tiled run's
difference from a bias. ``--no-mesh``: only the point rows.
``--tiled-only``: no single run (for a cloud larger than this machine holds): the UE
counts each point once (as ``superfacets experiment --elements points``), and "cut by a
border" is checked tile by tile, without the whole graph: each tile's box, grown by
``1.5 window r``, is read and its point graph built; every superpoint whose
center lies in the tile's core must lie in the box and be one connected piece
of that graph (the box's graph is the whole cloud's away from the box edge).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

_SINGLE = r"""
import json, resource, sys, time
import numpy as np
from superfacets import segment
from superfacets.io.regions import RegionReader
src, k, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
if len(sys.argv) > 4:  # --fine: the superpoints before the merges to the count, saved
    import superfacets.method.pipeline as pl
    built, merge = {}, pl.merge_to_count
    def _built(*a, _build=pl.build_graph, **kw):
        built["source"] = (got := _build(*a, **kw))[0]
        return got
    def _merge(graph, labels, rules):
        np.save(sys.argv[4], built["source"].to_rows(labels))
        return merge(graph, labels, rules)
    pl.build_graph, pl.merge_to_count = _built, _merge
if src.endswith(".npy"):
    data = np.load(src)
else:
    r = RegionReader.open(src)
    _, _, data = r.read_box([-np.inf] * 3, [np.inf] * 3)
t = time.perf_counter()
res = segment(data, k)
sec = time.perf_counter() - t
np.save(out, res.labels)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(dict(seconds=sec, peak_mib=peak,
                      n_segments=res.n_segments)))
"""


def _subdivided(mesh_id: int, s: int, folder: Path):
    import trimesh

    from superfacets.evaluation.datasets.psb import list_meshes
    from superfacets.io import read_labels, read_mesh

    b = next(m for m in list_meshes() if m.id == mesh_id)
    m = read_mesh(b.path)
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    gt = read_labels(b.seg_paths[0], f.shape[0])
    for _ in range(s):
        v, f = trimesh.remesh.subdivide(v, f)  # face i -> faces 4i .. 4i + 3
        gt = np.repeat(gt, 4)
    path = folder / f"psb{mesh_id}_s{s}.ply"
    from plyfile import PlyData, PlyElement

    vert = np.empty(v.shape[0], dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    vert["x"], vert["y"], vert["z"] = v.T
    face = np.empty(f.shape[0], dtype=[("vertex_indices", "i4", (3,))])
    face["vertex_indices"] = f
    PlyData([PlyElement.describe(vert, "vertex"), PlyElement.describe(face, "face")]).write(
        str(path))
    return path, v, f, gt


def _graph(data):
    """The whole input's element graph, for the metrics: without the run's memory check
    (the graph alone needs less than a run; after a 50M-point run and its tiles, the
    run's estimate would refuse it)."""
    from unittest import mock

    from superfacets.elements.builders import elements_of

    with mock.patch("superfacets._runtime.memory.check_memory", lambda *a, **k: None):
        return elements_of(data)


def _row(name, n, data, gt, path, k, a, folder):
    from superfacets.scale.tiles.run import segment_tiled

    out, fine = folder / "single.npy", folder / "single_fine.npy"
    t = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", _SINGLE, str(path), str(k), str(out)]
                       + ([str(fine)] if a.fine else []),
                       capture_output=True, text=True, check=True)
    single = json.loads(p.stdout.strip().splitlines()[-1])
    single["wall"] = time.perf_counter() - t
    s_labels = np.load(out)
    t = time.perf_counter()
    with _tiled_fine(a.fine) as t_fine:
        tiled = segment_tiled(path, k, tiles=a.tiles, workers=a.workers, halo=a.halo)
    wall = time.perf_counter() - t
    ue_s, ue_t, cut = _measured(data, gt, s_labels, tiled.labels)
    peak = max(t[f"{ph}_peak_mib"] or 0 for t in tiled.tiles for ph in ("centers", "labels"))
    if isinstance(data, (np.ndarray, Path)):  # points: also the experiment's measure
        print(f"  each point counted once: UE {_equal_weight_ue(s_labels, gt):.4f} / "
              f"{_equal_weight_ue(tiled.labels, gt):.4f}", flush=True)
    print(f"| {name} | {n:,} | {k} | {tiled.layout.describe()} | "
          f"{single['n_segments']} / {tiled.n_segments} | {ue_s:.4f} / {ue_t:.4f} "
          f"({100 * (ue_t / ue_s - 1):+.1f} %) | {cut} | {tiled.disagreements} | "
          f"{single['wall']:.1f} / {wall:.1f} | {single['peak_mib']:.0f} / {peak:.0f} |",
          flush=True)
    if not (a.rotations or a.fine):
        return
    from superfacets._runtime.memory import give_back_free_memory

    give_back_free_memory()  # (50M points: the runs below need the whole graph's memory)
    if a.rotations and isinstance(data, Path):
        _rotated_rows(data, gt, k, a.rotations, folder, a,
                      _equal_weight_ue(tiled.labels, gt) if a.rotations_tiled else None)
    if a.fine and t_fine:  # the whole graph again, alone
        _fine_row(data, gt, np.load(fine), t_fine[0], k)


def _measured(data, gt, one, tiled) -> tuple[float, float, int]:
    """The UE of one run's labels and of the tiled run's on the whole input's graph, and
    the tiled superfacets in pieces (the graph freed on return)."""
    from superfacets.evaluation.metrics import undersegmentation_error
    from superfacets.method.connectivity import label_components

    src = _graph(np.load(data) if isinstance(data, Path) else data)  # (a cloud: loaded now)
    g = src.graph
    first = src.first_rows(np.arange(g.n_elements)) if src.index is not None else None

    def per_element(labels):
        return labels if first is None else labels[first]

    pieces = label_components(g, per_element(tiled))
    cut = int(np.unique(pieces).size - np.unique(per_element(tiled)).size)
    return (undersegmentation_error(g, per_element(one), per_element(gt)),
            undersegmentation_error(g, per_element(tiled), per_element(gt)), cut)


@contextlib.contextmanager
def _tiled_fine(on: bool):
    """``--fine``: the tiled run's stitched superpoints before its merges to the count,
    kept (the driver's call of ``merged_labels``, wrapped while the run lasts)."""
    import superfacets.scale.tiles.run as runner

    kept, merged = [], runner.merged_labels

    def keep(labels, *rest):
        kept.append(labels.copy())
        return merged(labels, *rest)

    if on:
        runner.merged_labels = keep
    try:
        yield kept
    finally:
        runner.merged_labels = merged


def _fine_row(data, gt, one_fine, tiled_fine, k) -> None:
    """``--fine``: where a tiled run's error differs from one run's, before or in the
    merges to the count: the UE of each run's superpoints before the merges, and of one
    run's merges (on the whole graph) of the tiled run's superpoints."""
    from unittest import mock

    from superfacets.evaluation.metrics import undersegmentation_error
    from superfacets.method.merges import merge_to_count
    from superfacets.method.params import resolve
    from superfacets.method.stages import build_graph, resolve_rules

    with mock.patch("superfacets._runtime.memory.check_memory", lambda *a, **kw: None):
        source, graph, p = build_graph(np.load(data) if isinstance(data, Path) else data,
                                       resolve(n_segments=k))
    first = source.first_rows(np.arange(graph.n_elements))  # each element's first row

    def ue(element_labels):
        return undersegmentation_error(graph, element_labels, gt[first])

    _, tiled = np.unique(tiled_fine[first], return_inverse=True)
    merged, _ = merge_to_count(graph, tiled.astype(np.int64), resolve_rules(graph, p))
    print(f"  before the merges ({int(one_fine.max()) + 1} / {int(tiled.max()) + 1} "
          f"superpoints): UE {ue(one_fine[first]):.4f} / {ue(tiled):.4f}; one run's merges "
          f"of the tiled superpoints: UE {ue(merged):.4f}", flush=True)


def _rotated_rows(path: Path, gt, k: int, n: int, folder: Path, a, tiled_ue=None) -> None:
    """``--rotations N``: one run (a new process) on the same cloud turned by ``N`` random
    rotations (scipy's ``Rotation.random(random_state=s)``, s = 0 .. N-1): how much one
    run's error moves on the same points in another orientation (the UE does not
    change under a rotation; the run's start and its orders of the points do). With
    ``--rotations-tiled`` (``tiled_ue``: the tiled run's UE on the cloud as read), each
    turned cloud is also tiled, and the two runs' means over the orientations compared."""
    from scipy.spatial.transform import Rotation

    from superfacets.scale.tiles.run import segment_tiled

    ues = [_equal_weight_ue(np.load(folder / "single.npy"), gt)]
    tiled = [] if tiled_ue is None else [tiled_ue]
    for s in range(n):
        turned, out = folder / "turned.npy", folder / "turned_labels.npy"
        np.save(turned, np.load(path) @ Rotation.random(random_state=s).as_matrix().T)
        p = subprocess.run([sys.executable, "-c", _SINGLE, str(turned), str(k), str(out)],
                           capture_output=True, text=True, check=True)
        sec = json.loads(p.stdout.strip().splitlines()[-1])["seconds"]
        ues.append(_equal_weight_ue(np.load(out), gt))
        line = (f"  the cloud turned (rotation {s}): UE each point once, one run "
                f"{ues[-1]:.4f} ({sec:.0f} s)")
        if tiled_ue is not None:
            t = time.perf_counter()
            res = segment_tiled(turned, k, tiles=a.tiles, workers=a.workers, halo=a.halo)
            tiled.append(_equal_weight_ue(res.labels, gt))
            line += f", tiled {tiled[-1]:.4f} ({time.perf_counter() - t:.0f} s)"
            del res
        print(line, flush=True)
        turned.unlink()
    print(f"  one run over the {n + 1} orientations: UE each point once {np.mean(ues):.4f} "
          f"(from {min(ues):.4f} to {max(ues):.4f})", flush=True)
    if tiled:
        print(f"  tiled over the {n + 1} orientations: UE each point once {np.mean(tiled):.4f} "
              f"(from {min(tiled):.4f} to {max(tiled):.4f}), "
              f"{100 * (np.mean(tiled) / np.mean(ues) - 1):+.1f} % against one run's mean",
              flush=True)


def _equal_weight_ue(labels, gt, tau=0.05) -> float:
    """Paper eq. 4 with every element counted once (points)."""
    ok = labels >= 0
    s, g = labels[ok], gt[ok]
    _, s = np.unique(s, return_inverse=True)
    n_g = int(g.max()) + 1
    key, count = np.unique(s.astype(np.int64) * n_g + g, return_counts=True)
    s_size = np.bincount(s)
    sa = s_size[key // n_g]
    counted = count > tau * sa
    return float((sa[counted] - count[counted]).sum() / s.size)


def _cut_per_tile(path: Path, res, n_neighbors: int) -> tuple[int, int]:
    """(superpoints in pieces, superpoints not inside their tile's checked box)."""
    from superfacets.elements.builders import elements_of
    from superfacets.io.regions import RegionReader
    from superfacets.method.connectivity import label_components
    from superfacets.scale.tiles.buckets import bucket
    from superfacets.scale.tiles.layout import tile_box, tile_of

    reader = RegionReader.open(path)
    edges = res.layout
    pts = np.load(path, mmap_mode="r")
    center_tile = tile_of(np.asarray(pts[res.centers], dtype=np.float64), edges)
    size = np.bincount(res.labels[res.labels >= 0], minlength=res.n_segments)
    margin = 1.5 * res.params["window"] * res.mesh_radius
    cut = outside = 0
    with tempfile.TemporaryDirectory(prefix="sf-cut-") as tmp:
        buckets = bucket(reader, edges, tmp)
        for t in range(edges.n_tiles):
            mine = np.flatnonzero(center_tile == t)
            if not mine.size:
                continue
            lo, hi = tile_box(edges, t, margin)
            rows, _, cloud = buckets.read_box(lo, hi)
            src = elements_of(cloud, "points", n_neighbors=n_neighbors)
            first = src.first_rows(np.arange(src.graph.n_elements))
            lab = res.labels[rows]
            pieces = label_components(src.graph, lab[first])
            el = lab[first]
            seen = np.bincount(lab[lab >= 0], minlength=res.n_segments)
            outside += int((seen[mine] < size[mine]).sum())
            n_pieces = np.zeros(res.n_segments, dtype=np.int64)
            pairs = np.unique(np.c_[el, pieces], axis=0)
            np.add.at(n_pieces, pairs[:, 0], 1)
            cut += int((n_pieces[mine] > 1).sum())
            print(f"  tile {t}: {rows.size:,} points checked, {mine.size} superpoints, "
                  f"{int((n_pieces[mine] > 1).sum())} in pieces", flush=True)
    return cut, outside


def _row_tiled_only(name, n, gt, path, k, a) -> None:
    from superfacets.scale.tiles.run import segment_tiled

    t = time.perf_counter()
    res = segment_tiled(path, k, tiles=a.tiles, workers=a.workers, halo=a.halo, progress=True)
    wall = time.perf_counter() - t
    peak = max(t[f"{ph}_peak_mib"] or 0 for t in res.tiles for ph in ("centers", "labels"))
    ue = _equal_weight_ue(res.labels, gt)
    phases = json.dumps({k: round(v, 1) for k, v in res.timings.items()})
    print(f"tiled: {wall:.1f} s, phases {phases}",
          flush=True)
    t = time.perf_counter()
    cut, outside = _cut_per_tile(path, res, res.params["n_neighbors"])
    print(f"cut check: {time.perf_counter() - t:.1f} s", flush=True)
    print(f"| {name} | {n:,} | {k} | {res.layout.describe()} | {res.n_segments} | "
          f"{ue:.4f} | {cut} ({outside} not inside the checked box) | {res.disagreements} | "
          f"{wall:.1f} | {peak:.0f} |", flush=True)


def compare(a) -> None:
    import trimesh

    from superfacets import Mesh, segment
    from superfacets.elements.faces import face_graph
    from superfacets.evaluation.datasets.psb import first_per_category, list_meshes
    from superfacets.evaluation.metrics import compactness, undersegmentation_error
    from superfacets.io import read_labels, read_mesh
    from superfacets.method.connectivity import label_components
    from superfacets.scale.tiles.run import segment_tiled

    extra = dict(paper=True) if a.paper else {}
    if a.merge_from is not None:
        extra["merge_from"] = a.merge_from
    ue_s, ue_t, co_s, co_t, cut, dis, secs = [], [], [], [], 0, 0, 0.0
    print("| mesh | elements | segments: one / tiled | UE: one / tiled | "
          "compactness: one / tiled |\n|---|---|---|---|---|")
    for b in first_per_category(list_meshes(), a.per_category):
        m = read_mesh(b.path)
        v, f = np.asarray(m.vertices), np.asarray(m.faces)
        gt = read_labels(b.seg_paths[0], m.n_faces)
        if a.compare_points:  # a cloud sampled on the mesh, each point with its face's class
            from superfacets import PointCloud
            from superfacets.elements.builders import elements_of
            from superfacets.evaluation.datasets.sampling import sample_points

            pts, face = sample_points(m, a.compare_points, seed=0)
            data = PointCloud(pts)
            src = elements_of(data, "points")
            g = src.graph
            first = src.first_rows(np.arange(g.n_elements))  # each element's first row
            gt, n_el = gt[face][first], pts.shape[0]
        else:
            for _ in range(a.times):
                v, f = trimesh.remesh.subdivide(v, f)  # face i -> faces 4i .. 4i + 3
                gt = np.repeat(gt, 4)
            data = Mesh(v, f)
            g, first, n_el = face_graph(data), None, f.shape[0]
        s = segment(data, a.k, **extra)
        more = dict({} if a.refine is None else dict(refine=a.refine), start=a.start)
        t0 = time.perf_counter()
        t = segment_tiled(data, a.k, tiles=a.tiles, halo=a.halo, **more, **extra)
        secs += time.perf_counter() - t0
        one_l, tiled_l = np.asarray(s.labels), np.asarray(t.labels)
        if first is not None:
            one_l, tiled_l = one_l[first], tiled_l[first]
        ue_s.append(undersegmentation_error(g, one_l, gt))
        ue_t.append(undersegmentation_error(g, tiled_l, gt))
        co_s.append(compactness(g, one_l))
        co_t.append(compactness(g, tiled_l))
        cut += int(np.unique(label_components(g, tiled_l)).size - np.unique(tiled_l).size)
        dis += t.disagreements
        print(f"| {b.id} | {n_el:,} | {s.n_segments} / {t.n_segments} | "
              f"{ue_s[-1]:.4f} / {ue_t[-1]:.4f} | {co_s[-1]:.4f} / {co_t[-1]:.4f} |", flush=True)
    one, tiled = float(np.mean(ue_s)), float(np.mean(ue_t))
    c_one, c_tiled = float(np.mean(co_s)), float(np.mean(co_t))
    what = (f"{a.compare_points:,} points per mesh" if a.compare_points
            else f"subdivided {a.times}x")
    print(f"{'paper' if a.paper else 'default'}, {what}, k = {a.k}, "
          f"{a.tiles} tiles, halo {a.halo:g}, refine {a.refine if a.refine is not None else 1}: "
          f"UE {one:.4f} -> {tiled:.4f} ({100 * (tiled / one - 1):+.1f} %), compactness "
          f"{c_one:.4f} -> {c_tiled:.4f} ({100 * (c_tiled / c_one - 1):+.1f} %), cut {cut}, "
          f"disagreements {dis}, tiled runs {secs:.1f} s in process")


def main() -> None:
    from superfacets.cli.tiles import tiles_arg

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh-id", type=int, default=281)
    ap.add_argument("--subdivide", type=int, nargs="+", default=[2, 3])
    ap.add_argument("--points", type=int, nargs="*", default=[1_000_000])
    ap.add_argument("-k", type=int, default=2000)
    ap.add_argument("--tiles", type=tiles_arg, default=8,
                    help="N balanced tiles, or NX,NY,NZ: a regular grid")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--halo", type=float, default=3.0)
    ap.add_argument("--compare", action="store_true")
    ap.add_argument("--paper", action="store_true")
    ap.add_argument("--refine", type=int, default=None)
    ap.add_argument("--start", choices=("sample", "tiles"), default="sample",
                    help="--compare: where the refine rounds start (segment_tiled's start)")
    ap.add_argument("--merge-from", type=int, default=None,
                    help="--compare: merge_from of both runs (default: the method's)")
    ap.add_argument("--per-category", type=int, default=1,
                    help="--compare: benchmark meshes per category (the first ones)")
    ap.add_argument("--times", type=int, default=1, help="--compare: subdivisions per mesh")
    ap.add_argument("--compare-points", type=int, default=0, metavar="N",
                    help="--compare: N points sampled on each mesh instead of its faces")
    ap.add_argument("--no-mesh", action="store_true", help="only the point rows")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0],
                    help="the points' sampling: one cloud per seed")
    ap.add_argument("--fine", action="store_true",
                    help="also the superpoints before the merges to the count: the UE of "
                         "each run's, and of one run's merges of the tiled run's")
    ap.add_argument("--rotations", type=int, default=0, metavar="N",
                    help="points: also one run on the cloud turned by N random rotations")
    ap.add_argument("--rotations-tiled", action="store_true",
                    help="--rotations: each turned cloud also tiled, the means compared")
    ap.add_argument("--tiled-only", action="store_true",
                    help="points only, no single run (equal-weight UE, cut checked per tile)")
    a = ap.parse_args()
    if a.compare:
        return compare(a)
    from superfacets import Mesh
    from superfacets.evaluation.datasets.sampling import sample_points

    print(f"machine: {os.cpu_count()} cores; single run in a new process (1 thread per "
          f"core, default method); tiled: {a.workers} Dask workers, halo {a.halo:g}")
    if a.tiled_only:
        print("| input | elements | k | tiles | superpoints | UE (each point once) | "
              "cut by a border | disagreements | seconds | peak MiB (largest task) |")
        print("|---|---|---|---|---|---|---|---|---|---|")
    else:
        print("| input | elements | k | tiles | superfacets (one / tiled) | UE (one / tiled) | "
              "cut by a border | disagreements | seconds (one / tiled) | peak MiB (one / "
              "largest task) |")
        print("|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="sf-tiles-bench-") as tmp:
        folder = Path(tmp)
        for s in a.subdivide:
            path, v, f, gt = _subdivided(a.mesh_id, s, folder)
            mesh = Mesh(v, f)
            if not (a.no_mesh or a.tiled_only):
                _row(f"PSB {a.mesh_id} subdivided {s}x", f.shape[0], mesh, gt, path, a.k, a,
                     folder)
            for n, seed in ((n, seed) for n in (a.points if s == a.subdivide[-1] else [])
                            for seed in a.seeds):
                pts, face = sample_points(mesh, n, seed=seed)
                pp = folder / f"points{n}.npy"
                np.save(pp, pts)
                label = gt[face]
                del pts, face
                name = "points on it" + (f", seed {seed}" if a.seeds != [0] else "")
                if a.tiled_only:
                    _row_tiled_only(f"points on PSB {a.mesh_id} subdivided {s}x"
                                    + name[len("points on it"):], n, label, pp, a.k, a)
                else:
                    # the cloud is read from its file by each run, and by this process
                    # only after them (50M points: the single run needs the memory)
                    _row(name, n, pp, label, pp, a.k, a, folder)


if __name__ == "__main__":
    main()
