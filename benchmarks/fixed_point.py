"""Candidate of issue 16, measured and dropped: iterating to a true fixed point.

Usage: python benchmarks/fixed_point.py [-k 150] [--alpha 200] [--per-category 20]

When the list of centers repeats (a cycle: a few centers step back and
forth between neighbouring elements), the method jumps to the state the
cycle would be in at ``max_iter`` (the paper's rule, computed without the
passes). The candidate instead freezes the centers that move within the
cycle where they are and goes on until no other center moves: every run
ends at a true fixed point. It is run here without changing the package:
the passes run with cycle jumps off, and the center update is wrapped so
that a center list seen before freezes the centers that differ between it
and the lists since.

Each mesh is segmented with the paper's rule (``tol = 0, center_tol = 0``)
and with the defaults, each with and without the candidate; the script
prints the means over the meshes of undersegmentation error, compactness
and boundary recall, how the runs ended, and on how many meshes the
candidate's undersegmentation error is lower or higher.
"""

from __future__ import annotations

import argparse
from collections import Counter

import numpy as np


class FreezeCycles:
    """``update_centers`` of :mod:`superfacets.method.passes`, freezing the centers of a cycle."""

    def __init__(self, update):
        self.update = update
        self.seen: dict[bytes, int] = {}
        self.history: list[np.ndarray] = []
        self.frozen = np.zeros(0, dtype=bool)

    def __call__(self, label, k, sizes, positions, used):
        moved = self.update(label, k, sizes, positions, used)
        if used.size and (used < 0).all():  # final_centers, after the passes
            return moved
        key = used.tobytes()
        if key in self.seen:  # this pass's centers were seen: freeze what moves in the cycle
            frozen = np.zeros(used.shape[0], dtype=bool)
            for state in self.history[self.seen[key]:]:
                if state.shape == used.shape:
                    frozen |= state != used
            self.frozen = frozen if self.frozen.shape != used.shape else self.frozen | frozen
            self.seen.clear()
            self.history.clear()
        self.seen[key] = len(self.history)
        self.history.append(used.copy())
        if self.frozen.shape == used.shape:
            keep = self.frozen & (moved >= 0)
            moved[keep] = used[keep]
        return moved


def run(mesh, k, alpha, freeze: bool, **kw):
    import superfacets.method.passes as passes
    from superfacets.api.segmentation import pipeline
    from superfacets.method.params import resolve

    params = resolve(n_segments=k, alpha=alpha, **kw)
    if not freeze:
        return pipeline(mesh, params)
    real = passes.update_centers
    passes.update_centers = FreezeCycles(real)
    try:
        return pipeline(mesh, params, jump_cycles=False)
    finally:
        passes.update_centers = real


def ending(r) -> str:
    t = r.timings
    return ("tolerance" if t["stopped_by_tol"] else "cycle" if t["cycle_period"]
            else "converged" if r.converged else "max_iter")


def main() -> None:
    from superfacets.evaluation.datasets.psb import first_per_category, list_meshes, psb_root
    from superfacets.evaluation.metrics import evaluate

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-k", type=int, default=150)
    ap.add_argument("--alpha", type=float, default=200.0)
    ap.add_argument("--per-category", type=int, default=20)
    args = ap.parse_args()

    meshes = first_per_category(list_meshes(psb_root()), args.per_category)
    settings = {"paper's rule": dict(tol=0.0, center_tol=0.0), "defaults": {}}
    keys = ["undersegmentation_error", "compactness", "boundary_recall"]
    print(f"{len(meshes)} meshes, k = {args.k}, alpha = {args.alpha:g}\n")
    print("| setting | cycles | UE | compactness | BR | runs ended by | UE lower / higher |")
    print("|---|---|---|---|---|---|---|")
    for name, kw in settings.items():
        scores = {False: [], True: []}
        ends = {False: Counter(), True: Counter()}
        for bm in meshes:
            mesh = bm.load()
            gts = bm.ground_truths(mesh.n_faces)
            for freeze in (False, True):
                r = run(mesh, args.k, args.alpha, freeze, **kw)
                scores[freeze].append(evaluate(mesh, r.labels, gts))
                ends[freeze][ending(r)] += 1
        ue = {f: np.array([s[keys[0]] for s in scores[f]]) for f in (False, True)}
        for freeze in (False, True):
            v = [np.mean([s[key] for s in scores[freeze]]) for key in keys]
            how = ", ".join(f"{e} {n}" for e, n in sorted(ends[freeze].items()))
            cmp = (f"{(ue[True] < ue[False]).mean():.0%} / {(ue[True] > ue[False]).mean():.0%}"
                   if freeze else "")
            print(f"| {name} | {'frozen: fixed point' if freeze else 'jump (the method)'} | "
                  f"{v[0]:.4f} | {v[1]:.3f} | {v[2]:.3f} | {how} | {cmp} |")


if __name__ == "__main__":
    main()
