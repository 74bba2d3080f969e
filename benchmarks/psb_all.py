"""Segment every mesh of the Princeton benchmark and check the output invariants.

Usage: python benchmarks/psb_all.py [PSB_DIR] [-k 150] [--alpha 200]

PSB_DIR is the unpacked archive (default: ~/.cache/superfacets/psb, unpacked
from ../shared/data/psb.tar.xz if missing). Prints one line per category and
a summary; exits 1 if any mesh fails an invariant (one label per face, dense
labels, every superfacet face-connected).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

from superfacets import read_mesh, segment  # noqa: E402
from superfacets.elements import face_graph
from superfacets.evaluation.datasets.psb import category, psb_root  # noqa: E402
from superfacets.method.connectivity import label_components  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("psb", nargs="?", default=None)
    ap.add_argument("-k", type=int, default=150)
    ap.add_argument("--alpha", type=float, default=200.0)
    args = ap.parse_args()
    root = Path(args.psb) if args.psb else psb_root()
    files = sorted((root / "off").glob("*.off"), key=lambda p: int(p.stem))
    rows = defaultdict(list)
    failures = []
    t_all = time.perf_counter()
    for path in files:
        t = time.perf_counter()
        mesh = read_mesh(path)
        r = segment(mesh, args.k, alpha=args.alpha)
        sec = time.perf_counter() - t
        lab = r.labels
        k = int(lab.max()) + 1
        ok = (lab.shape == (mesh.n_faces,) and lab.min() == 0 and np.unique(lab).size == k
              and int(label_components(face_graph(mesh), lab).max()) + 1 == k)
        if not ok:
            failures.append(path.name)
        rows[category(int(path.stem))].append((mesh.n_faces, k, r.n_iter, r.converged, sec))
    total = time.perf_counter() - t_all
    print(f"{'category':<10} {'meshes':>6} {'faces (median)':>14} {'superfacets (min-max)':>22} "
          f"{'iterations (mean)':>17} {'converged':>9} {'s/mesh':>7}")
    for cat, rs in rows.items():
        a = np.array([(f, k, it, c, s) for f, k, it, c, s in rs], dtype=float)
        print(f"{cat:<10} {len(rs):>6} {int(np.median(a[:, 0])):>14} "
              f"{int(a[:, 1].min()):>10}-{int(a[:, 1].max()):<11} {a[:, 2].mean():>17.1f} "
              f"{int(a[:, 3].sum()):>9} {a[:, 4].mean():>7.2f}")
    allk = np.array([k for rs in rows.values() for _, k, *_ in rs])
    print(f"\n{len(files)} meshes in {total:.1f} s; superfacets per mesh {allk.min()}-{allk.max()} "
          f"(k = {args.k}); invariant failures: {len(failures)} {failures[:10]}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
