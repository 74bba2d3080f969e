"""Tiled runs against one run on the labelled scans: border disagreements and UE.

Usage: python benchmarks/tiles_scans.py [--scans NAME ...] [-k 1000] [--tiles 4 8]

Each labelled scan of ``superfacets.evaluation.datasets.scans.SCANS`` found in the cache
(``$SUPERFACETS_SCANS``, default ``~/.cache/superfacets/scans``; ``benchmarks/
real_scans.py --download`` fetches them) is segmented once and in each number of tiles
(``segment_tiled``, in process: one worker), with the package's defaults. Prints, per
scan, one run's undersegmentation error against its classes and, per tile count, the
border points two tiles labelled differently and the tiled UE; then the means.
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from superfacets import segment, segment_tiled
from superfacets.evaluation.datasets.scans import SCANS, evaluate_scan, load_scan, scan_files


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scans", nargs="+", default=None, choices=list(SCANS))
    ap.add_argument("-k", type=int, default=1000)
    ap.add_argument("--tiles", nargs="+", type=int, default=[4, 8])
    args = ap.parse_args(argv)
    names = [n for n in (args.scans or SCANS) if all(p.is_file() for p in scan_files(n))]
    if not names:
        raise SystemExit("no labelled scan in the cache: run benchmarks/real_scans.py "
                         "--download first")
    head = "".join(f" {f'{t} tiles: apart, UE':>22}" for t in args.tiles)
    print(f"{'scan':<24} {'one run UE':>10}{head}")
    ue = {t: [] for t in ["one", *args.tiles]}
    apart = dict.fromkeys(args.tiles, 0)
    for name in names:
        scan = load_scan(name)
        one = segment(replace(scan.cloud), args.k)  # (a fresh cloud: no graph kept)
        ue["one"].append(evaluate_scan(scan, one.labels)["undersegmentation_error"])
        row = f"{name:<24} {ue['one'][-1]:>10.4f}"
        for t in args.tiles:
            r = segment_tiled(replace(scan.cloud), args.k, tiles=t, workers=1)
            ue[t].append(evaluate_scan(scan, r.labels)["undersegmentation_error"])
            apart[t] += int(r.disagreements)
            row += f" {int(r.disagreements):>12,} {ue[t][-1]:>9.4f}"
        print(row, flush=True)
    means = "".join(f" {apart[t]:>12,} {np.mean(ue[t]):>9.4f}" for t in args.tiles)
    print(f"{'all (sum, mean)':<24} {np.mean(ue['one']):>10.4f}{means}")


if __name__ == "__main__":
    main()
