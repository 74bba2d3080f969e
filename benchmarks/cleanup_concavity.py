"""Candidate of issue 16, measured and dropped: a smoothed concavity cue in the clean-up.

Usage: python benchmarks/cleanup_concavity.py [--per-category 3] [-k 150] [--alpha 200]

The clean-up's boundary cost makes an adjacency cheaper by its own dihedral
angle (``superfacets.method.cleanup.cut_costs``). Human part boundaries follow the
minima rule: they lie where the surface is concave, and on a smooth neck the
concavity is spread over many faces whose dihedral angles are each small.
This candidate adds a multi-ring cue: the concave angle integrated over each
face's edges (``theta * |e|``, concave adjacencies only), smoothed together
with the face areas by ``(scale * r / mean edge)^2`` steps of neighbour
averaging (a diffusion reaching about ``scale * r``), divided by the smoothed
area and scaled by ``r / 2`` (a dimensionless curvature ``kappa``); the cut
cost of an adjacency is then divided by ``1 + beta * (kappa_i + kappa_j) / 2``.

It runs the paper's method once per mesh (the first ``--per-category`` of
each category), then the package's clean-up and each (beta, scale) variant on
the same labels, and prints the mean undersegmentation error, compactness
and boundary recall, and the number of categories where the undersegmentation
error is worse than the paper's.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from superfacets.elements import face_graph

VARIANTS = [(beta, scale) for scale in (0.1, 0.25) for beta in (0.3, 1.0, 3.0)]


def smoothed_concavity(graph, radius: float, scale: float) -> np.ndarray:
    """``kappa`` of the module notes, one value per element (dimensionless)."""
    import scipy.sparse as sp

    g = graph
    t = g.terms
    theta = np.arccos(t.cos) * t.concave
    i, j = g.pairs[:, 0], g.pairs[:, 1]
    n = g.n_elements
    q = (np.bincount(i, weights=theta * g.lengths, minlength=n)
         + np.bincount(j, weights=theta * g.lengths, minlength=n))
    adj = sp.csr_array((np.ones(2 * i.size), (np.r_[i, j], np.r_[j, i])), shape=(n, n))
    degree = np.maximum(np.asarray(adj.sum(axis=1)).ravel(), 1)
    steps = int(min(200, max(1, round((scale * radius / np.mean(g.lengths)) ** 2))))
    qs, area = q.astype(float), g.sizes.astype(float)
    for _ in range(steps):
        qs = 0.5 * qs + 0.5 * (adj @ qs) / degree
        area = 0.5 * area + 0.5 * (adj @ area) / degree
    return qs / np.maximum(area, 1e-300) * radius * 0.5


def main() -> None:
    import superfacets.method.cleanup as cl
    from superfacets import segment
    from superfacets.evaluation.datasets.psb import first_per_category, list_meshes, psb_root
    from superfacets.evaluation.metrics import evaluate

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--per-category", type=int, default=3)
    ap.add_argument("-k", type=int, default=150)
    ap.add_argument("--alpha", type=float, default=200.0)
    args = ap.parse_args()

    meshes = first_per_category(list_meshes(psb_root()), args.per_category)
    names = ["paper", "clean-up (defaults)"] + [f"concavity, beta {b:g}, scale {s:g} r"
                                                for b, s in VARIANTS]
    scores: dict[str, list] = {n: [] for n in names}
    cats = []
    real = cl.cut_costs
    t0 = time.perf_counter()
    for bm in meshes:
        mesh = bm.load()
        gts = bm.ground_truths(mesh.n_faces)
        g = face_graph(mesh)
        r = segment(mesh, args.k, alpha=args.alpha)
        cats.append(bm.category)
        scores["paper"].append(evaluate(g, r.labels, gts))
        scores[names[1]].append(evaluate(g, cl.clean_boundaries(
            g, r.labels, r.centers, alpha=args.alpha), gts))
        radius = np.sqrt(g.area / (args.k * np.pi))
        for name, (beta, scale) in zip(names[2:], VARIANTS):
            kappa = smoothed_concavity(g, radius, scale)
            factor = 1.0 / (1.0 + beta * 0.5 * (kappa[g.pairs[:, 0]] + kappa[g.pairs[:, 1]]))
            cl.cut_costs = lambda graph, factor=factor, **kw: real(graph, **kw) * factor
            try:
                labels = cl.clean_boundaries(g, r.labels, r.centers, alpha=args.alpha)
            finally:
                cl.cut_costs = real
            scores[name].append(evaluate(g, labels, gts))

    cats = np.array(cats)
    print(f"{len(meshes)} meshes ({args.per_category} per category), k = {args.k}, "
          f"alpha = {args.alpha:g}, {time.perf_counter() - t0:.0f} s\n")
    print("| candidate | UE | compactness | BR | categories worse on UE |")
    print("|---|---|---|---|---|")
    keys = ["undersegmentation_error", "compactness", "boundary_recall"]
    base = np.array([s[keys[0]] for s in scores["paper"]])
    for n in names:
        v = {k: np.array([s[k] for s in scores[n]]) for k in keys}
        worse = sum(1 for c in np.unique(cats)
                    if v[keys[0]][cats == c].mean() > base[cats == c].mean())
        print(f"| {n} | {v[keys[0]].mean():.4f} | {v[keys[1]].mean():.3f} | "
              f"{v[keys[2]].mean():.3f} | {worse} of {np.unique(cats).size} |")


if __name__ == "__main__":
    main()
