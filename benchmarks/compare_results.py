"""Compare two result files of ``superfacets experiment`` run by run: a markdown table.

Usage: python benchmarks/compare_results.py BASE.csv NEW.csv [--where COL=VALUE ...]
       [--new-where COL=VALUE ...] [--by alpha,n_segments]

Rows are matched on (mesh, alpha, n_segments, elements) among the ``ok`` rows
of each file (after the filters; ``--where`` applies to both files,
``--new-where`` to NEW only). For each group of ``--by``: the mean of each
metric per category, then over categories (as the paper), for BASE and NEW,
and the relative change; also the mean iterations and seconds. Only meshes
present in both files count, so a partial NEW is compared fairly.
"""

from __future__ import annotations

import argparse
import sys

import pandas as pd

KEYS = ["mesh", "alpha", "n_segments", "elements"]
METRICS = [("undersegmentation_error", "UE"), ("compactness", "compactness"),
           ("boundary_recall", "BR")]


def _load(path: str, where: list[str]) -> pd.DataFrame:
    df = pd.read_csv(path)
    df = df[df["status"] == "ok"]
    for item in where:
        col, _, val = item.partition("=")
        df = df[df[col].astype(str) == val]
    return df


def compare(base: pd.DataFrame, new: pd.DataFrame, by: list[str]) -> pd.DataFrame:
    """Per group of ``by``: category-balanced means of BASE and NEW, and the changes."""
    keys = [k for k in KEYS if k in base.columns and k in new.columns] + ["category"]
    cols = keys + ["iterations", "seconds"] + [m for m, _ in METRICS]
    m = base[cols].merge(new[cols], on=keys, suffixes=("_base", "_new"))
    rows = []
    for key, g in m.groupby(by):
        key = key if isinstance(key, tuple) else (key,)
        cat = g.groupby("category").mean(numeric_only=True).mean()
        row = dict(zip(by, key), runs=len(g))
        for metric, short in METRICS:
            b, n = cat[f"{metric}_base"], cat[f"{metric}_new"]
            row[f"{short} base"] = round(b, 4)
            row[f"{short} new"] = round(n, 4)
            row[f"{short} change %"] = round(100 * (n - b) / b, 2) if b else float("nan")
        row["iterations base"] = round(g["iterations_base"].mean(), 1)
        row["iterations new"] = round(g["iterations_new"].mean(), 1)
        row["seconds base"] = round(g["seconds_base"].sum(), 1)
        row["seconds new"] = round(g["seconds_new"].sum(), 1)
        rows.append(row)
    return pd.DataFrame(rows)


def markdown(table: pd.DataFrame) -> str:
    """``table`` as a markdown table (no extra dependency)."""
    lines = ["| " + " | ".join(map(str, table.columns)) + " |",
             "|" + "---|" * len(table.columns)]
    for row in table.itertuples(index=False):
        lines.append("| " + " | ".join(f"{v:g}" if isinstance(v, float) else str(v)
                                       for v in row) + " |")
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("base")
    ap.add_argument("new")
    ap.add_argument("--where", action="append", default=[], metavar="COL=VALUE")
    ap.add_argument("--new-where", action="append", default=[], metavar="COL=VALUE")
    ap.add_argument("--base-where", action="append", default=[], metavar="COL=VALUE")
    ap.add_argument("--by", default="alpha,n_segments")
    args = ap.parse_args()
    base = _load(args.base, args.where + args.base_where)
    new = _load(args.new, args.where + args.new_where)
    table = compare(base, new, [c for c in args.by.split(",") if c])
    if table.empty:
        print("no run in common", file=sys.stderr)
        return 1
    print(markdown(table))
    worst = table[[c for c in table.columns if c.endswith("change %")]].abs().max()
    print("\nlargest change, %: " + ", ".join(f"{k[:-9]} {v:.2f}" for k, v in worst.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
