"""Tables and a figure of the superpoint benchmark (faces, vertices, points; two methods).

Usage: python benchmarks/superpoints_report.py RESULTS.csv [-o docs/results] [-k 150]

RESULTS.csv comes from
``superfacets experiment -k 150 --alpha 200 -m superfacets -m graph_segmentation
--elements faces,vertices,points``. Prints Markdown tables (means per element
kind and method; per category, point mode against graph segmentation; the
verdict on the issue's targets) and writes ``superpoints_categories.png``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

METRICS = ["undersegmentation_error", "compactness", "boundary_recall", "achievable_accuracy"]


def md(frame) -> str:
    """A DataFrame as a Markdown table (index first)."""
    head = [frame.index.name or "", *map(str, frame.columns)]
    rows = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for idx, values in frame.iterrows():
        idx = " / ".join(map(str, idx)) if isinstance(idx, tuple) else str(idx)
        cells = [f"{v:.4g}" if isinstance(v, float) else str(v) for v in values]
        rows.append("| " + " | ".join([idx, *cells]) + " |")
    return "\n".join(rows)


def main() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import pandas as pd

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results")
    ap.add_argument("-o", "--output-dir", default="docs/results")
    ap.add_argument("-k", type=int, default=150)
    args = ap.parse_args()
    df = pd.read_csv(args.results)
    df = df[(df.status == "ok") & (df.n_segments == args.k)]
    df["elements"] = df["elements"].fillna("faces")
    df["series"] = df.method + " / " + df.elements

    print(f"## Means over {df.mesh.nunique()} meshes, k = {args.k}\n")
    cols = ["segments", *METRICS, "seconds"]
    mean = df.groupby(["elements", "method"])[cols].mean()
    mean.insert(0, "meshes", df.groupby(["elements", "method"]).size())
    print(md(mean) + "\n")

    ue = df.pivot_table(index="category", columns="series", values="undersegmentation_error")
    print("## Undersegmentation error per category (lower is better)\n")
    print(md(ue) + "\n")

    sp, fh = "superfacets / points", "graph_segmentation / points"
    sv, fv = "superfacets / vertices", "graph_segmentation / vertices"
    mesh_ue = df[(df.method == "superfacets") & (df.elements == "faces")] \
        .set_index("mesh").undersegmentation_error
    point_ue = df[(df.method == "superfacets") & (df.elements == "points")] \
        .set_index("mesh").undersegmentation_error
    both = mesh_ue.index.intersection(point_ue.index)
    ratio = point_ue[both].mean() / mesh_ue[both].mean()
    wins = int((ue[sp] < ue[fh]).sum()) if {sp, fh} <= set(ue) else 0
    wins_v = int((ue[sv] < ue[fv]).sum()) if {sv, fv} <= set(ue) else 0
    print("## Verdict\n")
    print("| target | measured | met |\n|---|---|---|")
    print(f"| point UE within 1.15x of mesh UE (same meshes) | {ratio:.3f}x | "
          f"{'yes' if ratio <= 1.15 else 'no'} |")
    print(f"| point UE below graph segmentation in >= 13 of {len(ue)} categories | "
          f"{wins} of {len(ue)} | {'yes' if wins >= 13 else 'no'} |")
    print(f"| (vertices) UE below graph segmentation | {wins_v} of {len(ue)} categories | - |")
    print("| cut pursuit | not run (pycut-pursuit cannot be imported with NumPy 2) | - |\n")

    out = Path(args.output_dir)
    out.mkdir(parents=True, exist_ok=True)
    order = [s for s in ["superfacets / faces", sv, fv, sp, fh] if s in ue]
    ax = ue[order].plot.bar(figsize=(12, 4.5), width=0.82)
    ax.set_ylabel("undersegmentation error")
    ax.set_title(f"Undersegmentation error per category, k = {args.k} (lower is better)")
    ax.legend(fontsize=8, ncol=3)
    plt.tight_layout()
    plt.savefig(out / "superpoints_categories.png", dpi=110)
    print(f"wrote {out / 'superpoints_categories.png'}")


if __name__ == "__main__":
    main()
