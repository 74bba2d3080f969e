"""Candidates for the boundary clean-up, measured on a stratified subset of the benchmark.

Usage: python benchmarks/cleanup_candidates.py [--per-category 5] [-k 150] [--alpha 200]

Runs the paper's method once per mesh (k, alpha), then applies each
candidate to the same labels and prints one Markdown row per candidate: mean
undersegmentation error, compactness, boundary recall, achievable accuracy,
clean-up seconds (in process, after a warm-up), and the number of categories
where the candidate is worse than the paper on UE or on compactness.

Candidates:

- ``floor``: three rounds of majority smoothing (each boundary element takes
  the neighbouring label that minimises its boundary cost, concave creases
  cheaper, as :func:`superfacets.method.cleanup.cut_costs`), then the connectivity step;
- ``cut ...``: :func:`superfacets.method.cleanup.clean_boundaries` with the parameters shown
  (the package's defaults first);
- ``oracle``: the same graph cut with the human boundaries made 100x cheaper
  (the fraction of the humans who cut an edge), with the default band, with
  a wider band and more sweeps, and with the human cue alone (no crease term). Not a
  method: the ceiling of moving
  boundaries within their bands, whatever the cue.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from superfacets.elements import face_graph

CANDIDATES = [
    ("cut (defaults)", {}),
    ("cut, 2 sweeps", {"sweeps": 2}),
    ("cut, band 0.5 r, 3 sweeps", {"band": 0.5, "sweeps": 3}),
    ("cut, no crease term", {"crease": 0.0}),
    ("cut, full crease term", {"crease": 1.0}),
    ("cut, crease term x5", {"crease": 5.0}),
    ("cut, no data term", {"smoothness": 0.0}),
    ("cut, strong data term", {"smoothness": 3.0}),
]


def majority_smoothing(graph, labels, cost, rounds: int = 3) -> np.ndarray:
    """Each element takes the label (its own or a neighbour's) of least boundary cost."""
    ip, ix, de = graph.indptr, graph.indices, graph.dual_edge
    c = cost[de]
    lab = labels.copy()
    row = np.repeat(np.arange(graph.n_elements), np.diff(ip))
    for _ in range(rounds):
        nb = lab[ix]
        best = lab.copy()
        best_cost = np.bincount(row, weights=c * (nb != lab[row]), minlength=lab.size)
        # candidates: the label of each neighbour
        for t in range(int(np.diff(ip).max())):
            has = np.diff(ip) > t
            f = np.flatnonzero(has)
            cand = lab[ix[ip[f] + t]]
            tot = np.zeros(f.size)
            for u in range(int(np.diff(ip).max())):
                ok = np.diff(ip)[f] > u
                e = ip[f[ok]] + u
                tot[ok] += c[e] * (lab[ix[e]] != cand[ok])
            better = tot < best_cost[f] - 1e-15
            best[f[better]] = cand[better]
            best_cost[f[better]] = tot[better]
        if np.array_equal(best, lab):
            break
        lab = best
    return lab


def main() -> None:
    from superfacets import segment
    from superfacets.evaluation.datasets.psb import first_per_category, list_meshes, psb_root
    from superfacets.evaluation.metrics import evaluate
    from superfacets.method.cleanup import clean_boundaries, cut_costs
    from superfacets.method.connectivity import enforce_connectivity

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--per-category", type=int, default=5)
    ap.add_argument("-k", type=int, default=150)
    ap.add_argument("--alpha", type=float, default=200.0)
    args = ap.parse_args()

    meshes = first_per_category(list_meshes(psb_root()), args.per_category)
    names = (["paper", "floor"] + [n for n, _ in CANDIDATES]
             + ["oracle", "oracle, band 0.5 r, 3 sweeps",
                "oracle without creases, band 0.5 r, 3 sweeps"])
    scores = {n: [] for n in names}
    seconds = dict.fromkeys(names, 0.0)
    cats = []
    warm = False
    for bm in meshes:
        mesh = bm.load()
        gts = bm.ground_truths(mesh.n_faces)
        g = face_graph(mesh)
        r = segment(mesh, args.k, alpha=args.alpha)
        if not warm:  # compile the kernels outside the timings
            clean_boundaries(g, r.labels, r.centers, alpha=args.alpha)
            warm = True
        cats.append(bm.category)
        human = np.mean([gt[g.pairs[:, 0]] != gt[g.pairs[:, 1]] for gt in gts], axis=0)

        def run(name, fn):
            t = time.perf_counter()
            labels = fn()
            seconds[name] += time.perf_counter() - t
            scores[name].append(evaluate(g, labels, gts))

        run("paper", lambda: r.labels)
        cost = cut_costs(g, alpha=args.alpha)
        run("floor", lambda: enforce_connectivity(
            g, majority_smoothing(g, r.labels, cost), r.centers))
        for name, kw in CANDIDATES:
            run(name, lambda kw=kw: clean_boundaries(g, r.labels, r.centers, alpha=args.alpha,
                                                     **kw))
        import superfacets.method.cleanup as cl

        real = cl.cut_costs
        cl.cut_costs = lambda graph, **kw: real(graph, **kw) * (1 - 0.99 * human)
        try:
            run("oracle", lambda: clean_boundaries(g, r.labels, r.centers, alpha=args.alpha))
            run("oracle, band 0.5 r, 3 sweeps", lambda: clean_boundaries(
                g, r.labels, r.centers, alpha=args.alpha, band=0.5, sweeps=3))
            cl.cut_costs = lambda graph, **kw: graph.lengths * (1 - 0.99 * human)
            run("oracle without creases, band 0.5 r, 3 sweeps", lambda: clean_boundaries(
                g, r.labels, r.centers, alpha=args.alpha, band=0.5, sweeps=3))
        finally:
            cl.cut_costs = real

    cats = np.array(cats)
    print(f"{len(meshes)} meshes ({args.per_category} per category), k = {args.k}, "
          f"alpha = {args.alpha:g}\n")
    print("| candidate | UE | compactness | BR | ASA | clean-up s | categories worse |")
    print("|---|---|---|---|---|---|---|")
    keys = ["undersegmentation_error", "compactness", "boundary_recall", "achievable_accuracy"]
    base = {k: np.array([s[k] for s in scores["paper"]]) for k in keys}
    for n in names:
        v = {k: np.array([s[k] for s in scores[n]]) for k in keys}
        worse = sum(1 for c in np.unique(cats)
                    if v[keys[0]][cats == c].mean() > base[keys[0]][cats == c].mean()
                    or v[keys[1]][cats == c].mean() > base[keys[1]][cats == c].mean())
        print(f"| {n} | {v[keys[0]].mean():.4f} | {v[keys[1]].mean():.3f} | "
              f"{v[keys[2]].mean():.3f} | {v[keys[3]].mean():.4f} | {seconds[n]:.1f} | "
              f"{worse} of {np.unique(cats).size} |")


if __name__ == "__main__":
    main()
