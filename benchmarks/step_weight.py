"""What a scene's neighbours along its surface cost: seconds of ``segment`` on the labelled
scans with ``step_weight`` 1 (the plain graph) and the default (4 on a scene), in process,
the graph built in each run, the two alternately, best of ``--repeat``.

Usage: python benchmarks/step_weight.py [--scans NAME ...] [-k 100 300 1000 3000]
       [--repeat 2]

Reads the scans of ``superfacets.evaluation.datasets.scans.SCANS`` found in the cache
(``$SUPERFACETS_SCANS``, default ``~/.cache/superfacets/scans``; ``benchmarks/
real_scans.py --download`` fetches them). Prints one row per scan (seconds summed over the
counts) and the total: the ratio of the sums, the geometric mean of the runs' ratios and
how many runs took more than 1.2 times the plain graph's time.
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace

from superfacets import segment
from superfacets.evaluation.datasets.scans import SCANS, load_scan, scan_files


def _seconds(cloud, k: int, step: float | None) -> float:
    fresh = replace(cloud)  # (no graph kept from an earlier run)
    t0 = time.perf_counter()
    segment(fresh, k, step_weight=step)
    return time.perf_counter() - t0


def _best_pair(cloud, k: int, repeat: int) -> list[float]:
    """Best of ``repeat`` for step 1 and the default, run alternately (a busy spell of the
    machine hits both)."""
    best = [math.inf, math.inf]
    for _ in range(repeat):
        best = [min(best[0], _seconds(cloud, k, 1.0)), min(best[1], _seconds(cloud, k, None))]
    return best


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scans", nargs="+", default=None, choices=list(SCANS))
    ap.add_argument("-k", nargs="+", type=int, default=[100, 300, 1000, 3000])
    ap.add_argument("--repeat", type=int, default=2)
    args = ap.parse_args(argv)
    names = [n for n in (args.scans or SCANS) if all(p.is_file() for p in scan_files(n))]
    if not names:
        raise SystemExit("no labelled scan in the cache: run benchmarks/real_scans.py "
                         "--download first")
    print(f"{'scan':<24} {'points':>9} {'step 1 (s)':>11} {'default (s)':>12} {'ratio':>6}")
    sums, logs, over = [0.0, 0.0], [], 0
    for name in names:
        cloud = load_scan(name).cloud
        row = [0.0, 0.0]
        for k in args.k:
            t = _best_pair(cloud, k, args.repeat)
            logs.append(math.log(t[1] / t[0]))
            over += t[1] > 1.2 * t[0]
            row = [row[0] + t[0], row[1] + t[1]]
        sums = [sums[0] + row[0], sums[1] + row[1]]
        print(f"{name:<24} {cloud.n_total:>9,} {row[0]:>11.2f} {row[1]:>12.2f} "
              f"{row[1] / row[0]:>6.2f}", flush=True)
    print(f"{'total':<24} {'':>9} {sums[0]:>11.2f} {sums[1]:>12.2f} {sums[1] / sums[0]:>6.3f}")
    print(f"geometric mean of {len(logs)} runs' ratios {math.exp(sum(logs) / len(logs)):.3f}; "
          f"above 1.2: {over}")


if __name__ == "__main__":
    main()
