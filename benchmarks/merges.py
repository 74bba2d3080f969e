"""The merges to the count (``merge_from``, the default on clouds of even density)
against the method's own superpoints (``merge_from=1``): time and error, alternating.

Usage: python benchmarks/merges.py [--rounds 3] [--cases sampled rooms tile million]
       python benchmarks/merges.py --kernel [--cases ...]

Each case is segmented with ``merge_from=1`` and with the default (``merge_from=None``:
5 on these clouds), in process, the two alternating for ``--rounds`` rounds; the table
gives the fastest time of each, their ratio, and the undersegmentation error of each
(the same labels every round). Cases:

- ``sampled``: the first benchmark mesh of each category (15), 20,000 points sampled
  on each (``superfacets.evaluation.datasets.sampling``), against the
  benchmark's segmentations, k = 50, 150, 300 (the times summed and the errors
  averaged over the 15);
- ``rooms``: the ScanNet rooms 0000_00 and 0000_01 (``superfacets.evaluation.datasets.
  scans``, in the cache), k = 300, 1,000, 3,000, against their classes (as
  ``benchmarks/real_scans.py`` measures them);
- ``tile``: the airborne LiDAR tile, k = 1,000;
- ``million``: 1,000,000 points sampled on the horse (``../shared/data/meshes``),
  k = 500 (no ground truth).

A case whose data is missing is skipped with a line saying which.

``--kernel``: the merging kernel alone (``hierarchy.merge_levels``, the flat merges and
the merges to the count): each call the default run of a case makes is recorded, then
run again on copies of its arrays, the fastest of ``--rounds``; one row a call (the
superpoints it starts from, its cost: 2 the flat merges, 3 the scene's, 1 the plane's
rise, 0 Ward's) and the total. The labelled scans' cases also take the Autzen town and
the lidR forest plot (k = 3,000 and 1,000).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SHARED = HERE.parents[1] / "shared"


def _sampled():
    from superfacets.evaluation.datasets.psb import first_per_category, list_meshes, psb_root
    from superfacets.evaluation.datasets.sampling import sample_points

    items = []
    for bm in first_per_category(list_meshes(psb_root()), 1):
        mesh = bm.load()
        pts, faces = sample_points(mesh, 20_000, 0)
        items.append((pts, [gt[faces] for gt in bm.ground_truths(mesh.n_faces)]))
    return [("15 sampled clouds (20,000 points)", k, items) for k in (50, 150, 300)]


def _scans(names, ks):
    from superfacets.evaluation.datasets.scans import load_scan, scan_files

    out = []
    for name in names:
        if not all(p.exists() for p in scan_files(name)):
            print(f"skipped {name}: not in the scan cache", file=sys.stderr)
            continue
        scan = load_scan(name)
        for k in ks:
            out.append((f"{name} ({scan.cloud.n_total:,} points)", k, [(scan, None)]))
    return out


def _million():
    from superfacets import read_mesh
    from superfacets.evaluation.datasets.sampling import sample_points

    path = SHARED / "data" / "meshes" / "horse.tri.xz"
    if not path.exists():
        print(f"skipped million: {path} is missing", file=sys.stderr)
        return []
    pts, _ = sample_points(read_mesh(path), 1_000_000, 0)
    return [("1M points on the horse", 500, [(pts, None)])]


def _run(items, k, merge_from):
    from superfacets import PointCloud, segment
    from superfacets.evaluation.datasets.scans import evaluate_scan
    from superfacets.evaluation.metrics import evaluate_rows

    seconds, errors = 0.0, []
    for pts, truths in items:
        scan = None if isinstance(pts, np.ndarray) else pts  # a labelled scan
        cloud = PointCloud(pts) if scan is None else replace(scan.cloud)
        t = time.perf_counter()
        labels = segment(cloud, k, merge_from=merge_from).labels
        seconds += time.perf_counter() - t
        if scan is not None:  # as benchmarks/real_scans.py measures it
            errors.append(evaluate_scan(scan, labels)["undersegmentation_error"])
        elif truths is not None:
            errors.append(evaluate_rows(cloud, labels, truths)["undersegmentation_error"])
    return seconds, (float(np.mean(errors)) if errors else float("nan"))


def _kernel_calls(items, k) -> list:
    """The merging kernel's calls in the default run of ``items`` at ``k``, their arrays
    copied as the kernel received them (it updates the nodes' in place)."""
    from superfacets import PointCloud, segment
    from superfacets._kernels import native

    path = "hierarchy.merge_levels"
    real = native.kernel(path)
    calls = []

    def recorded(*args):
        calls.append([x.copy() if isinstance(x, np.ndarray) else x for x in args])
        return real(*args)

    native._chosen[path] = recorded
    try:
        for pts, _ in items:
            cloud = PointCloud(pts) if isinstance(pts, np.ndarray) else replace(pts.cloud)
            segment(cloud, k)
    finally:
        native._chosen[path] = real
    return calls


def _kernel_table(cases, rounds: int) -> None:
    from superfacets._kernels import native

    kernel = native.kernel("hierarchy.merge_levels")
    print("| input | k | superpoints | cost | ms |")
    print("|---|---|---|---|---|")
    total = 0.0
    for name, k, items in cases:
        for args in _kernel_calls(items, k):
            best = np.inf
            for _ in range(rounds):
                fresh = [x.copy() if isinstance(x, np.ndarray) else x for x in args]
                t = time.perf_counter()
                kernel(*fresh)
                best = min(best, time.perf_counter() - t)
            total += best
            print(f"| {name} | {k:,} | {args[0]:,} | {args[8]} | {1e3 * best:.1f} |",
                  flush=True)
    print(f"| all | | | | {1e3 * total:.1f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--cases", nargs="+", default=["sampled", "rooms", "tile", "million"],
                    choices=["sampled", "rooms", "tile", "million"])
    ap.add_argument("--kernel", action="store_true",
                    help="time the merging kernel's calls alone (see above)")
    a = ap.parse_args()
    cases = []
    if "sampled" in a.cases:
        cases += _sampled()
    if "rooms" in a.cases:
        cases += _scans(["scannet-scene0000_00", "scannet-scene0000_01"], [300, 1000, 3000])
    if "tile" in a.cases:
        cases += _scans(["lidarhd-rgb"], [1000])
    if "million" in a.cases:
        cases += _million()
    if a.kernel:
        if "tile" in a.cases:
            cases += _scans(["pdal-autzen"], [3000]) + _scans(["lidr-megaplot"], [1000])
        _kernel_table(cases, a.rounds)
        return
    print("| input | k | merge_from=1: s / UE | default: s / UE | time ratio |")
    print("|---|---|---|---|---|")
    for name, k, items in cases:
        _run(items[:1], k, None)  # warm-up: caches, thread pools
        best = {1: (np.inf, np.nan), None: (np.inf, np.nan)}
        for _ in range(a.rounds):
            for mf in (1, None):
                s, ue = _run(items, k, mf)
                best[mf] = (min(best[mf][0], s), ue)
        (s1, u1), (s5, u5) = best[1], best[None]
        print(f"| {name} | {k:,} | {s1:.3f} / {u1:.4f} | {s5:.3f} / {u5:.4f} | "
              f"{s5 / s1:.2f} |", flush=True)


if __name__ == "__main__":
    main()
