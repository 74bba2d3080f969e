"""How much faster two threads can be on this machine at best: the ceiling of
``--threads 2`` against ``--threads 1``.

Usage: ``python benchmarks/machine_scaling.py [--rounds 3]``

Two workloads with nothing shared, each run alone and then as two processes at once
(so no lock, no serial part and no imbalance between them): a pure-compute loop, and
random reads of a 400 MB array (the access pattern of the passes' expansions over a
graph). The ceiling is ``2 * alone / together``: what a perfectly parallel program
reaches with two threads here. Prints a table of the medians over ``--rounds``.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys

CODE = """
import sys, time
import numpy as np
if sys.argv[1] == "memory":
    rng = np.random.default_rng(0)
    a, at = rng.random(50_000_000), rng.integers(0, 50_000_000, 20_000_000)
    t = time.perf_counter()
    for _ in range(5):
        a[at].sum()
else:
    t = time.perf_counter()
    s = 0
    for i in range(15_000_000):
        s += i * i
print(time.perf_counter() - t)
"""


def _seconds(kind: str, copies: int) -> float:
    """The slowest of ``copies`` processes of ``kind`` run at once."""
    procs = [subprocess.Popen([sys.executable, "-c", CODE, kind], stdout=subprocess.PIPE,
                              text=True) for _ in range(copies)]
    return max(float(p.communicate()[0].split()[-1]) for p in procs)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--rounds", type=int, default=3)
    a = p.parse_args()
    print("| workload | one process, s | two at once, s | ceiling of 2 threads |")
    print("|---|---|---|---|")
    for kind in ("compute", "memory"):
        alone, both = [], []
        for _ in range(a.rounds):  # alternating
            alone.append(_seconds(kind, 1))
            both.append(_seconds(kind, 2))
        one, two = statistics.median(alone), statistics.median(both)
        print(f"| {kind} | {one:.2f} | {two:.2f} | {2 * one / two:.2f}x |")


if __name__ == "__main__":
    main()
