"""How many rounds of split-and-merge swaps pay: UE, compactness, boundary recall per round limit.

Usage: python benchmarks/split_merge_rounds.py [--rounds 1 3 6 10] [--per-category 4]
       [-k 150] [--alpha 200] [--out DIR]

For each round limit, runs ``superfacets experiment`` in this process (one
worker) with ``split_merge=true`` and the limit of
:func:`superfacets.method.splitmerge.swap_and_iterate` set to it, plus one run of
the paper's method, on the first meshes of each category; then prints one
Markdown row per setting (means over meshes) and whether every run kept the
paper's number of superfacets. The CSV files stay in ``--out`` (rerunning
continues them).
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path


def _run(out: Path, args, rounds: int | None) -> Path:
    from superfacets.cli import main
    from superfacets.method import splitmerge

    path = out / ("paper.csv" if rounds is None else f"rounds_{rounds}.csv")
    kw = splitmerge.swap_and_iterate.__kwdefaults__
    default = kw["rounds"]
    kw["rounds"] = default if rounds is None else rounds
    try:
        main(["experiment", "--alpha", str(args.alpha), "-k", str(args.k),
              "--per-category", str(args.per_category), "-j", "1", "-q", "-o", str(path),
              "--param", f"split_merge={'false' if rounds is None else 'true'}"])
    finally:
        kw["rounds"] = default
    return path


def _means(path: Path) -> tuple[dict, dict]:
    with open(path, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["status"] == "ok"]
    means = {m: sum(float(r[m]) for r in rows) / len(rows)
             for m in ("undersegmentation_error", "compactness", "boundary_recall", "seconds")}
    means["seconds"] *= len(rows)
    means["runs"] = len(rows)
    return means, {r["mesh_id"]: r["segments"] for r in rows}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, nargs="+", default=[1, 3, 6, 10])
    ap.add_argument("--per-category", type=int, default=4)
    ap.add_argument("-k", type=int, default=150)
    ap.add_argument("--alpha", type=float, default=200.0)
    ap.add_argument("--out", type=Path, default=Path("split_merge_rounds"))
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    paper, k_paper = _means(_run(args.out, args, None))
    print("| rounds at most | UE | compactness | boundary recall | seconds (sum) | K kept |")
    print("|---|---|---|---|---|---|")
    print(f"| paper | {paper['undersegmentation_error']:.4f} | {paper['compactness']:.3f} | "
          f"{paper['boundary_recall']:.3f} | {paper['seconds']:.1f} | |")
    for r in args.rounds:
        m, k = _means(_run(args.out, args, r))
        kept = "yes" if k == k_paper else "no"
        print(f"| {r} | {m['undersegmentation_error']:.4f} | {m['compactness']:.3f} | "
              f"{m['boundary_recall']:.3f} | {m['seconds']:.1f} | {kept} |")


if __name__ == "__main__":
    main()
