"""The merges' cost to the count, measured on the labelled scans: the rule ``auto`` against
the plane's rise scaled by the parts' own plane residual.

``auto`` (``merge_cost='auto'``, the default before 2026-11-30; earlier records call it
``today``: ``superfacets.method.merges.merge_nodes``) the merges down to ``k`` take the plane's
rise where the flat merges' regions hold most of the points (``FLAT_SHARE``) and Ward's cost
elsewhere. The rise is a length squared: two smooth planes a curb apart (road and sidewalk)
rise less than two rough pieces of one tree, so the count goes to the vegetation and the
curb is merged away. Scaled by the parts' own residual per point ``v`` (floored at the
scan's noise ``s``), a step is charged for what it is against the surfaces' own roughness:

- ``rise``: the rise, as ``auto``'s kernel (a check of this script: the same labels);
- ``own``: ``rise / max(v, s)``;
- ``half``: ``rise / sqrt(max(v, s) s)`` (half way, in logarithms; the rise where ``s`` is 0);
- ``blend``: ``rise / max(s, v~) + ward / r^2``, both in points: the rise in units of the noise
  (``v~`` the first superpoints' median residual per point, where the noise reads lower) plus
  Ward's term in units of the superpoint's size (``r^2 = A / (pi k)``);
- ``scene``: the package's ``merge_cost='scene'`` (``superfacets.method.merges.
  scene_merge_nodes``): ``blend`` with ``v~`` the median residual of each superpoint's
  union with its neighbours, times the paper's crease factor (eqs. 2-3);
- ``noise``: the package's ``merge_cost='noise'``: ``scene`` with its rise weighted by
  ``min(1, s / v)``, ``v`` the first superpoints' median residual per point
  (``superfacets.method.merges.rise_weight``); ``auto``'s merges where the noise reads 0.

The merging here is a heap in Python (a prototype, not the package's compiled kernel), with
the package's size bound (``max_size_ratio``) and colour guard. Each setting is judged as
``real_scans.py`` judges it: against the Segmentator's graph segmentation, UE at most its,
boundary recall at least its minus 0.02, oracle mIoU at least its.

    python benchmarks/merge_costs.py --costs auto half --everywhere --merge-from 5
    python benchmarks/merge_costs.py --objects 3 --noise 0.002 --costs auto half --everywhere

(``--everywhere``: the scaled cost replaces Ward's too, whatever the flat share;
``--merge-from 5``: merges on clouds of uneven density too; ``--objects N``: instead of the
scans, the first N benchmark meshes of each category sampled to 20,000 points with Gaussian
noise of ``--noise`` times the diagonal, a scanned object, judged by UE against the first
human segmentation.) The scans come from ``superfacets.evaluation.datasets.scans``
(``--download`` fetches them).
``docs/notes/superpoints-defaults.md``, "The merges' cost scaled by the parts' own residual",
has the results.
"""

from __future__ import annotations

import argparse
import heapq
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

COSTS = ("auto", "rise", "own", "half", "blend", "scene", "noise")
#: The costs the package has (``merge_cost``): run through the parameter.
PACKAGE = ("auto", "scene", "noise")


def package(cost: str) -> dict:
    """The run's options for ``cost``: the parameter for the package's own costs (its
    ``merge_from`` then as the package sets it), ``auto``'s for the prototypes, which
    replace its merges."""
    return {"merge_cost": cost if cost in PACKAGE else "auto"}


def smallest_eigenvalue(s: np.ndarray) -> np.ndarray:
    """The smallest eigenvalue of each symmetric 3x3 scatter, ``>= 0``."""
    return np.maximum(np.linalg.eigvalsh(s)[..., 0], 0.0)


def scaled_rise_merges(graph, target: int, cap: float, noise: float, scale: str,
                       size: float = 1.0, floor: float = 0.0) -> np.ndarray:
    """Merge the cheapest adjacent pair of ``graph``'s nodes until ``target`` remain (or no
    pair is left), first under the size bound ``cap`` (0: none), then above it.

    Parameters
    ----------
    graph : object
        With ``n_segments``, ``area`` (K,) (points per node), ``centroid`` (K, 3),
        ``scatter`` (K, 3, 3) (about the centroid) and ``edge_index`` (2, E).
    target : int
    cap : float
        The most points of a union while another pair may merge; 0: no bound.
    noise : float
        The scan's noise variance (squared input units), ``>= 0``.
    scale : {'rise', 'own', 'half', 'blend'}
    size, floor : float
        With ``'blend'``: ``r^2`` and ``v~`` (module notes), squared input units.

    Returns
    -------
    (K,) int64 ndarray
        Each node's group, dense.
    """
    k = int(graph.n_segments)
    count = np.array(graph.area, dtype=np.float64)
    mean = np.array(graph.centroid, dtype=np.float64)
    scatter = np.array(graph.scatter, dtype=np.float64)
    own = smallest_eigenvalue(scatter)
    edges = np.asarray(graph.edge_index).reshape(2, -1).T
    adjacent = [set() for _ in range(k)]
    for a, b in edges.tolist():
        if a != b:
            adjacent[a].add(b)
            adjacent[b].add(a)
    owner, version = np.arange(k), np.zeros(k, dtype=np.int64)

    def cost(a, b):
        n = count[a] + count[b]
        d = mean[a] - mean[b]
        union = scatter[a] + scatter[b] + count[a] * count[b] / n * np.outer(d, d)
        lam = float(smallest_eigenvalue(union))
        rise = max(lam - own[a] - own[b], 0.0)
        v = max((own[a] + own[b]) / n, noise)
        if scale == "own" and v > 0:
            rise /= v
        elif scale == "half" and noise > 0:
            rise /= np.sqrt(v * noise)
        elif scale == "blend":
            rise = rise / max(noise, floor, 1e-300) + count[a] * count[b] / n * float(d @ d) / size
        return rise, n, union, lam

    live = k
    for bounded in ((True, False) if cap > 0 else (False,)):
        heap = [(cost(a, b)[0], a, b, version[a], version[b]) for a in range(k)
                if owner[a] == a for b in adjacent[a]
                if a < b and not (bounded and count[a] + count[b] > cap)]
        heapq.heapify(heap)
        while live > target and heap:
            _, a, b, va, vb = heapq.heappop(heap)
            if owner[a] != a or owner[b] != b or version[a] != va or version[b] != vb:
                continue
            _, n, union, lam = cost(a, b)
            mean[a] = (count[a] * mean[a] + count[b] * mean[b]) / n
            count[a], scatter[a], own[a] = n, union, lam
            owner[b] = a
            version[a] += 1
            version[b] += 1
            live -= 1
            for x in adjacent[b] - {a}:
                adjacent[x].discard(b)
                adjacent[x].add(a)
            adjacent[a] |= adjacent[b]
            adjacent[a] -= {a, b}
            adjacent[b] = set()
            for x in adjacent[a]:
                lo, hi = min(a, x), max(a, x)
                if not (bounded and count[lo] + count[hi] > cap):
                    heapq.heappush(heap, (cost(lo, hi)[0], lo, hi, version[lo], version[hi]))
    root = owner.copy()
    while not np.array_equal(root[root], root):
        root = root[root]
    return np.unique(root, return_inverse=True)[1].astype(np.int64)


def merges_with(scale: str, everywhere: bool):
    """A replacement of ``merges.merge_nodes`` whose plane's rise is ``scale``'s; with
    ``everywhere``, also where ``auto`` takes Ward's cost."""
    from superfacets.graph.hierarchy import pieces
    from superfacets.method import merges

    original = merges.merge_nodes

    def merge_nodes(nodes, pairs, target, max_rise, alpha, eta_convex, *, max_jump=None,
                    max_ratio=0.0, cost="auto"):
        if max_rise is None:
            return original(nodes, pairs, target, max_rise, alpha, eta_convex,
                         max_jump=max_jump, max_ratio=max_ratio)
        count = nodes["count"]
        k = count.shape[0]
        cap = max_ratio * float(count.sum()) / target if max_ratio > 0 else 0.0
        flat = merges.flat_merge_nodes(merges._planes_graph(nodes, pairs, None, max_jump),
                                       target, max_rise, alpha, eta_convex, cap)
        n_flat = int(flat.max()) + 1 if k else 0
        if not n_flat or (not everywhere and merges.flat_share(np.arange(k), flat, count)
                          < merges.FLAT_SHARE):
            return original(nodes, pairs, target, max_rise, alpha, eta_convex,
                         max_jump=max_jump, max_ratio=max_ratio)
        final, fewest = flat, target
        for guard in ((max_jump, None) if max_jump is not None else (None,)):
            graph = merges._planes_graph(nodes, pairs, final, guard)
            fewest = max(target, pieces(graph))
            if graph.n_segments > fewest:
                size = float(nodes["area"].sum()) / (np.pi * target)
                floor = float(np.median(smallest_eigenvalue(nodes["scatter"])
                                        / np.maximum(count, 1.0)))
                final = scaled_rise_merges(graph, fewest, cap, max_rise / merges.FLAT_NOISE,
                                           scale, size, floor)[final]
        return flat, final, min(fewest, n_flat)

    return merge_nodes


@contextmanager
def merge_cost(scale: str, everywhere: bool):
    """``merges.merge_nodes`` replaced for the block (the package's costs: left as it
    is)."""
    from superfacets.method import merges

    original = merges.merge_nodes
    if scale not in PACKAGE:
        merges.merge_nodes = merges_with(scale, everywhere)
    try:
        yield
    finally:
        merges.merge_nodes = original


def objects(per_category: int, noise: float, ks: list, costs: list, everywhere: bool) -> None:
    """Print the mean UE of each cost on the first ``per_category`` benchmark meshes of each
    category, sampled to 20,000 points with Gaussian noise of ``noise`` times the diagonal."""
    from superfacets import PointCloud, segment
    from superfacets.evaluation.datasets.psb import first_per_category, list_meshes
    from superfacets.evaluation.datasets.sampling import sample_points
    from superfacets.evaluation.metrics import undersegmentation_error

    ue = {(c, k): [] for c in costs for k in ks}
    meshes = first_per_category(list_meshes(), per_category)
    for m in meshes:
        mesh = m.load()
        truth = m.ground_truths(len(mesh.faces))[0]
        points, face = sample_points(mesh, 20_000, seed=0)
        diagonal = float(np.linalg.norm(points.max(0) - points.min(0)))
        points = points + noise * diagonal * np.random.default_rng(1).standard_normal(points.shape)
        for c in costs:
            for k in ks:
                with merge_cost(c, everywhere):
                    r = segment(PointCloud(points), k, **package(c))
                ue[c, k].append(undersegmentation_error(r.elements.graph, r.labels,
                                                        np.asarray(truth)[face]))
    print(f"\nMean UE on {len(meshes)} benchmark meshes sampled with noise {noise:g} of the "
          f"diagonal (everywhere={everywhere}); against '{costs[0]}'\n")
    print("| k | " + " | ".join(costs) + " |")
    print("|---|" + "---|" * len(costs))
    for k in ks:
        base = np.mean(ue[costs[0], k])
        cells = [f"{np.mean(ue[c, k]):.4f} ({100 * (np.mean(ue[c, k]) / base - 1):+.1f} %)"
                 for c in costs]
        print(f"| {k} | " + " | ".join(cells) + " |")


def meets(ours: dict, ref: dict) -> bool:
    """The three targets against the reference run."""
    return (ours["undersegmentation_error"] <= ref["undersegmentation_error"]
            and ours["boundary_recall"] >= ref["boundary_recall"] - 0.02
            and ours["oracle_miou"] >= ref["oracle_miou"])


def main() -> None:
    import real_scans as bench

    from superfacets.evaluation.datasets.scans import SCANS, load_scan

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scans", nargs="+", default=list(SCANS), choices=list(SCANS))
    ap.add_argument("-k", type=int, nargs="+", default=[100, 300, 1000, 3000])
    ap.add_argument("--costs", nargs="+", choices=COSTS, default=["auto", "half"])
    ap.add_argument("--everywhere", action="store_true",
                    help="the scaled rise also where ``auto`` takes Ward's cost")
    ap.add_argument("--merge-from", type=bench._at_least_one, default=None, metavar="N",
                    help="merge_from of every run (default: the package's)")
    ap.add_argument("--download", action="store_true", help="fetch missing scans first")
    ap.add_argument("--objects", type=bench._at_least_one, default=None, metavar="N",
                    help="the first N benchmark meshes of each category, not the scans")
    ap.add_argument("--noise", type=float, default=0.002,
                    help="with --objects: the noise, a fraction of the diagonal")
    a = ap.parse_args()
    if a.objects:
        objects(a.objects, a.noise, a.k if a.k != [100, 300, 1000, 3000] else [50, 150, 300],
                a.costs, a.everywhere)
        return
    opts = {} if a.merge_from is None else {"merge_from": a.merge_from}
    met = {c: {} for c in a.costs}
    ue = {c: {} for c in a.costs}
    t0 = time.perf_counter()
    for name in a.scans:
        scan = load_scan(name, download=a.download)
        kind = bench.scan_kind(name)
        for k in a.k:
            ref = bench.run(scan, "graph_segmentation", k, None)
            for c in a.costs:
                with merge_cost(c, a.everywhere):
                    row = bench.run(scan, "superfacets", k, None, dict(opts, **package(c)))
                met[c].setdefault(kind, []).append(meets(row, ref))
                ue[c].setdefault(kind, []).append(row["undersegmentation_error"])
        print(f"{name}: done ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    first = a.costs[0]
    print(f"\nTargets met against the Segmentator (everywhere={a.everywhere}, "
          f"merge_from={a.merge_from or 'default'}); mean UE against '{first}'\n")
    print("| kind | settings | " + " | ".join(a.costs) + " |")
    print("|---|---|" + "---|" * len(a.costs))
    for kind in sorted(met[first]) + ["all"]:
        cells = []
        for c in a.costs:
            m = sum((met[c][x] for x in met[c]), []) if kind == "all" else met[c][kind]
            u = np.concatenate([ue[c][x] for x in ue[c]]) if kind == "all" else ue[c][kind]
            u0 = (np.concatenate([ue[first][x] for x in ue[first]]) if kind == "all"
                  else ue[first][kind])
            cells.append(f"{sum(m)} ({100 * np.mean(np.asarray(u) / u0 - 1):+.1f} %)")
        print(f"| {kind} | {len(m)} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
