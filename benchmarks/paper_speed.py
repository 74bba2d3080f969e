"""The better method against the paper's, at the paper's speed: quality and time, in one run.

Usage: python benchmarks/paper_speed.py [-k 150] [--per-category 0] [--threads 1]
       [--settings paper,better] [--elements faces|vertices|points] [--points 20000]

Settings: ``paper`` (``paper=True``: the method as published), ``better``
(``split_merge=True, cleanup=True``: early swaps, one round, a few passes, the
clean-up), ``default`` (the package's defaults). Every mesh is segmented by each
setting in turn (the order alternating from mesh to mesh), each run on a fresh
:class:`~superfacets.Mesh` (the face graph built in the timed run, as a user's
first run), in this process, ``--threads`` threads each. Prints the means over
meshes (undersegmentation error, compactness, boundary recall), the segment
seconds summed, per-mesh wins, a table per category and how many runs kept the
first setting's number of superfacets. ``--per-category 0``: all meshes.

``--elements vertices`` / ``points``: the mesh's vertices (ground truth: the
majority of the incident faces) or ``--points`` points sampled by area (fixed
seed, each with its face's ground truth), as ``superfacets experiment`` builds
them; each run gets a fresh mesh or cloud (its graph built in the timed run),
and the metrics count every element once.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

SETTINGS = {
    "paper": dict(paper=True),
    "better": dict(split_merge=True, cleanup=True),
    "default": dict(),
}


def main() -> None:
    from superfacets import Mesh, PointCloud, segment
    from superfacets.elements.builders import elements_of
    from superfacets.evaluation.datasets.psb import first_per_category, list_meshes
    from superfacets.evaluation.datasets.sampling import sample_points, vertex_ground_truth
    from superfacets.evaluation.metrics import evaluate
    from superfacets.io import read_mesh

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("-k", type=int, default=150)
    ap.add_argument("--alpha", type=float, default=200.0)
    ap.add_argument("--per-category", type=int, default=0)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--settings", default="paper,better")
    ap.add_argument("--elements", choices=("faces", "vertices", "points"), default="faces")
    ap.add_argument("--points", type=int, default=20_000)
    args = ap.parse_args()
    names = args.settings.split(",")
    meshes = list_meshes()
    if args.per_category:
        meshes = first_per_category(meshes, args.per_category)
    res: dict[str, list] = {n: [] for n in names}
    cats = []
    for bm in meshes:
        mesh = read_mesh(bm.path)
        gts = bm.ground_truths(mesh.n_faces)
        cats.append(bm.category)
        kind = args.elements
        if kind == "faces":
            graph, first = mesh, None
        else:
            if kind == "vertices":
                gts = [vertex_ground_truth(mesh, g) for g in gts]
                fresh_input = lambda: Mesh(mesh.vertices, mesh.faces)  # noqa: E731
            else:
                pts, face = sample_points(mesh, args.points, seed=0)
                gts = [g[face] for g in gts]
                fresh_input = lambda: PointCloud(pts)  # noqa: E731
            src = elements_of(fresh_input(), kind)
            graph = src.graph
            first = src.first_rows(np.arange(graph.n_elements))
            gts = [g[first] for g in gts]
        for n in (names if bm.id % 2 else names[::-1]):
            fresh = Mesh(mesh.vertices, mesh.faces) if kind == "faces" else fresh_input()
            t = time.perf_counter()
            r = segment(fresh, args.k, alpha=args.alpha, n_threads=args.threads,
                        **({} if kind == "faces" else {"elements": kind}), **SETTINGS[n])
            sec = time.perf_counter() - t
            labels = r.labels if first is None else np.asarray(r.labels)[first]
            m = evaluate(graph, labels, gts, equal_weight=kind != "faces")
            res[n].append((m["undersegmentation_error"], m["compactness"],
                           m["boundary_recall"], sec, r.n_segments))
    base = np.array(res[names[0]])
    print(f"{len(meshes)} meshes ({args.elements}), k = {args.k}, alpha = {args.alpha:g}, "
          f"{args.threads} thread(s), in process")
    print()
    print("| setting | UE | compactness | boundary recall | seconds (sum) | time | UE lower "
          "| compactness lower |")
    print("|---|---|---|---|---|---|---|---|")
    for n in names:
        a = np.array(res[n])
        ue, c = a[:, 0].mean(), a[:, 1].mean()
        print(f"| {n} | {ue:.4f} ({100 * (ue / base[:, 0].mean() - 1):+.1f} %) | {c:.3f} "
              f"({100 * (c / base[:, 1].mean() - 1):+.1f} %) | {a[:, 2].mean():.3f} | "
              f"{a[:, 3].sum():.1f} | x{a[:, 3].sum() / base[:, 3].sum():.2f} | "
              f"{(a[:, 0] < base[:, 0]).mean():.0%} | {(a[:, 1] < base[:, 1]).mean():.0%} |")
    if len(names) < 2:
        return
    a, b = base, np.array(res[names[1]])
    cat = np.array(cats)
    print()
    print(f"| category | UE {names[0]} | UE {names[1]} | compactness {names[0]} | "
          f"compactness {names[1]} | recall {names[0]} | recall {names[1]} | verdict |")
    print("|---|---|---|---|---|---|---|---|")
    for c in sorted(set(cats)):
        m = cat == c
        ua, ub, ca, cb = a[m, 0].mean(), b[m, 0].mean(), a[m, 1].mean(), b[m, 1].mean()
        verdict = ("better on both" if ub < ua and cb < ca else
                   "**UE worse**" if ub >= ua else "**compactness worse**")
        print(f"| {c} | {ua:.4f} | {ub:.4f} | {ca:.3f} | {cb:.3f} | {a[m, 2].mean():.3f} | "
              f"{b[m, 2].mean():.3f} | {verdict} |")
    print()
    print(f"number of superfacets the same in {int((a[:, 4] == b[:, 4]).sum())} of {len(a)} runs")


if __name__ == "__main__":
    main()
