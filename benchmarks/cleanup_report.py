"""Verdict tables of the boundary clean-up against the paper's method.

Usage: python benchmarks/cleanup_report.py RESULTS.csv [RESULTS.csv ...] [--k-focus 150]

RESULTS.csv from ``superfacets experiment --alpha ... --param cleanup=false,true``
(both series on the same meshes, in the same run). Prints Markdown: per alpha
and k, the means of both series, the relative change and whether the clean-up
Pareto-dominates (lower UE and lower compactness); the time it adds (sum of
seconds with over without); per category at ``--k-focus`` and alpha = 200,
both metrics and the verdict; the issue's targets.
"""

from __future__ import annotations

import argparse

METRICS = ["undersegmentation_error", "compactness", "boundary_recall", "achievable_accuracy"]
SHORT = {"undersegmentation_error": "UE", "compactness": "C", "boundary_recall": "BR",
         "achievable_accuracy": "ASA"}


def main() -> None:
    import pandas as pd

    from superfacets.evaluation.report.tables import load_results, ok_rows

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", nargs="+")
    ap.add_argument("--k-focus", type=int, default=150)
    args = ap.parse_args()
    df = ok_rows(load_results(args.results))
    df = df[df["method"] == "superfacets"].copy()
    df["alpha"] = pd.to_numeric(df["alpha"])
    df["clean"] = df["cleanup"].astype(str).str.lower() == "true"
    # only meshes, alphas and k present in both series
    key = ["mesh", "alpha", "n_segments"]
    both = df.groupby(key)["clean"].nunique()
    both = both[both == 2].reset_index()[key]
    df = df.merge(both, on=key)
    n_meshes = df["mesh"].nunique()

    print(f"## Both series on {n_meshes} meshes\n")
    print("| alpha | k | UE paper | UE clean-up | C paper | C clean-up | BR paper | "
          "BR clean-up | ASA paper | ASA clean-up | time added | Pareto |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    means = df.groupby(["alpha", "n_segments", "clean"])[METRICS + ["seconds"]].agg(
        {**{m: "mean" for m in METRICS}, "seconds": "sum"})
    for (alpha, k), _ in means.groupby(level=[0, 1]):
        p = means.loc[(alpha, k, False)]
        c = means.loc[(alpha, k, True)]
        pareto = (c["undersegmentation_error"] < p["undersegmentation_error"]
                  and c["compactness"] < p["compactness"])
        cells = []
        for m in METRICS:
            cells += [f"{p[m]:.4f}", f"{c[m]:.4f} ({100 * (c[m] / p[m] - 1):+.1f} %)"]
        print(f"| {alpha:g} | {k} | " + " | ".join(cells)
              + f" | {100 * (c['seconds'] / p['seconds'] - 1):+.0f} % | "
              + ("yes" if pareto else "**no**") + " |")

    focus = df[(df["alpha"] == 200) & (df["n_segments"] == args.k_focus)]
    if focus.empty:
        return
    print(f"\n## Per category, k = {args.k_focus}, alpha = 200\n")
    print("| category | meshes | UE paper | UE clean-up | C paper | C clean-up | "
          "BR paper | BR clean-up | verdict |")
    print("|---|---|---|---|---|---|---|---|---|")
    cat = focus.groupby(["category", "clean"])[METRICS].mean()
    counts = focus[~focus["clean"]].groupby("category")["mesh"].nunique()
    n_worse = 0
    for name in sorted(focus["category"].unique()):
        p, c = cat.loc[(name, False)], cat.loc[(name, True)]
        ue = c["undersegmentation_error"] - p["undersegmentation_error"]
        comp = c["compactness"] - p["compactness"]
        if ue < 0 and comp < 0:
            verdict = "better on both"
        elif ue > 0 and comp > 0:
            verdict = "**worse on both**"
        else:
            verdict = f"**UE worse** ({ue:+.4f})" if ue > 0 else f"**C worse** ({comp:+.3f})"
        n_worse += verdict.startswith("**")
        print(f"| {name} | {counts[name]} | {p['undersegmentation_error']:.4f} | "
              f"{c['undersegmentation_error']:.4f} | {p['compactness']:.3f} | "
              f"{c['compactness']:.3f} | {p['boundary_recall']:.3f} | "
              f"{c['boundary_recall']:.3f} | {verdict} |")
    p = focus[~focus["clean"]]
    c = focus[focus["clean"]]
    seg_equal = (c.sort_values("mesh")["segments"].to_numpy()
                 == p.sort_values("mesh")["segments"].to_numpy()).all()
    print(f"\n## Targets (k = {args.k_focus}, alpha = 200)\n")
    rows = [
        ("UE <= 0.120", c["undersegmentation_error"].mean(), 0.120, "le"),
        ("compactness <= 4.60", c["compactness"].mean(), 4.60, "le"),
        ("boundary recall >= 0.82", c["boundary_recall"].mean(), 0.82, "ge"),
    ]
    print("| target | measured | met |")
    print("|---|---|---|")
    for name, v, lim, how in rows:
        ok = v <= lim if how == "le" else v >= lim
        print(f"| {name} | {v:.4f} | {'yes' if ok else '**no**'} |")
    print(f"| no category worse on either metric | {n_worse} worse | "
          f"{'yes' if n_worse == 0 else '**no**'} |")
    print(f"| number of superfacets unchanged | {'all meshes' if seg_equal else 'not all'} | "
          f"{'yes' if seg_equal else '**no**'} |")
    added = c["seconds"].sum() / p["seconds"].sum() - 1
    print(f"| clean-up adds <= 25 % to a run | {100 * added:+.0f} % | "
          f"{'yes' if added <= 0.25 else '**no**'} |")


if __name__ == "__main__":
    main()
