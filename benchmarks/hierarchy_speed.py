"""Seconds of the hierarchy and of content-adaptive superpoints, up to millions of points.

Usage: python benchmarks/hierarchy_speed.py [--points 100000 1000000] [-k 1000 5000]
       [--start 10] [--threads N]

A synthetic terrain (a seeded uniform sample of a ground with hills, a
step and noise, the same for every row) of each size is segmented into
``start * k`` superpoints; then, each timed apart in the same process: the
superpoint graph of the planarity cost (:func:`superfacets.graph.hierarchy.planarity_graph`,
each point weighing one), the level of ``k`` with the planarity cost, the
same level with Ward's cost (on :meth:`SegmentationResult.graph`), and
:func:`superfacets.adaptive_superpoints` from the start (segmentation, graph
and merges). The first row also pays numba's compilation of the merging
kernel where its cache is cold (run twice to see the warm numbers).
Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def terrain(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    xy = rng.random((n, 2)) * 100.0
    z = (3.0 * np.sin(xy[:, 0] / 9.0) * np.cos(xy[:, 1] / 13.0)
         + 2.0 * (xy[:, 0] > 60.0) + 0.02 * rng.standard_normal(n))
    return np.c_[xy, z]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, nargs="+", default=[100_000, 1_000_000])
    ap.add_argument("-k", type=int, nargs="+", default=[1000, 5000])
    ap.add_argument("--start", type=int, default=10)
    ap.add_argument("--threads", type=int, default=None)
    a = ap.parse_args()

    from superfacets import adaptive_superpoints, segment
    from superfacets.graph.hierarchy import hierarchy, planarity_graph

    print("| points | k | superpoints merged | segment (s) | planarity graph (s) | "
          "planarity level (s) | Ward level (s) | adaptive_superpoints (s) |")
    print("|---|---|---|---|---|---|---|---|")
    for n in a.points:
        pts = terrain(n)
        for k in a.k:
            start = min(a.start * k, n)
            t = time.perf_counter()
            r = segment(pts, start, n_threads=a.threads)
            t_seg = time.perf_counter() - t
            t = time.perf_counter()
            g = planarity_graph(r.elements.graph, r.element_labels)
            t_graph = time.perf_counter() - t
            t = time.perf_counter()
            hierarchy(g, [k], cost="planarity")
            t_plan = time.perf_counter() - t
            t = time.perf_counter()
            r.hierarchy([k])
            t_ward = time.perf_counter() - t
            t = time.perf_counter()
            adaptive_superpoints(pts, k, start=a.start, n_threads=a.threads)
            t_all = time.perf_counter() - t
            print(f"| {n:,} | {k:,} | {r.n_segments:,} | {t_seg:.2f} | {t_graph:.2f} | "
                  f"{t_plan:.2f} | {t_ward:.2f} | {t_all:.2f} |", flush=True)


if __name__ == "__main__":
    main()
