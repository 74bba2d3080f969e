"""Tetrahedral meshes: the method on volumes, with and without the material term.

Usage: python benchmarks/volumes.py [--points 5000 20000 80000] [-k 50]

Each row: the Delaunay tetrahedralisation (scipy) of uniform random points in
a unit cube (and its 8 corners), two materials split by a wavy surface
``x > 0.5 + 0.15 sin(2 pi y)``; segmented in process (one thread, the graph
built in the run) with ``beta = 0`` (geometry alone) and ``beta = 50`` (the
materials one-hot as features). Undersegmentation error by volume against
the materials, compactness ``area / volume^(2/3)`` (a cube 6, a ball 4.84).
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def wavy_cube(n: int, seed: int = 0):
    from scipy.spatial import Delaunay

    from superfacets.inputs.tetmesh import TetMesh

    corners = np.array(np.meshgrid([0.0, 1.0], [0.0, 1.0], [0.0, 1.0])).reshape(3, -1).T
    p = np.r_[np.random.default_rng(seed).random((n, 3)), corners]
    tets = Delaunay(p).simplices
    c = p[tets].mean(axis=1)
    material = (c[:, 0] > 0.5 + 0.15 * np.sin(2 * np.pi * c[:, 1])).astype(np.int64)
    return TetMesh(p, tets, materials=material)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, nargs="+", default=[5000, 20000, 80000])
    ap.add_argument("-k", type=int, default=50)
    a = ap.parse_args()
    from superfacets import segment
    from superfacets.elements.cells import cell_graph
    from superfacets.evaluation.metrics import compactness, undersegmentation_error
    from superfacets.inputs.tetmesh import TetMesh

    print("| points | tetrahedra | beta | superfacets | UE by volume | compactness | seconds |")
    print("|---|---|---|---|---|---|---|")
    for n in a.points:
        base = wavy_cube(n)
        for beta in (0.0, 50.0):
            t = TetMesh(base.vertices, base.tets, materials=base.materials)  # graph built anew
            s = time.perf_counter()
            r = segment(t, a.k, beta=beta, n_threads=1)
            sec = time.perf_counter() - s
            g = cell_graph(t)
            ue = undersegmentation_error(g, r.labels, t.materials)
            print(f"| {n} | {t.n_tets} | {beta:g} | {r.n_segments} | {ue:.4f} | "
                  f"{compactness(g, r.labels):.2f} | {sec:.2f} |")


if __name__ == "__main__":
    main()
