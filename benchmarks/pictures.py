"""Pictures and pages of large clouds: the commands a user runs, a new process each.

Points are sampled on PSB mesh 281 (as ``benchmarks/tiles_cost.py`` samples them, from
``../shared``) and segmented once (``segment -k K -o labels.seg``, not timed); then
``render CLOUD labels.seg -o x.png`` and ``html CLOUD labels.seg -o x.html`` run in new
processes, each timed on its own (wall seconds, and the peak resident memory of that
process), the fastest of ``--rounds``. A picture draws at most its pixels' worth of points
and a page 2 million (:func:`superfacets.viz.render.drawn_share`), so past those their time
follows the reading, not the points drawn.

Usage: python benchmarks/pictures.py [--points 1000000 5000000] [-k 2000] [--rounds 1]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from tiles_cost import _cloud  # noqa: E402

COMMAND = [sys.executable, "-m", "superfacets"]
#: One command in a new process, its own peak resident memory (KiB) printed last.
CODE = """
import resource, sys, time
t = time.perf_counter()
from superfacets.cli import main
code = main(sys.argv[1:])
print(time.perf_counter() - t, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
sys.exit(code)
"""


def timed(args: list[str]) -> tuple[float, float]:
    """Wall seconds (the interpreter's start-up too) and peak resident MiB of one command
    in a new process."""
    t = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", CODE, *args], check=True,
                         capture_output=True, text=True).stdout.split()
    return time.perf_counter() - t, float(out[-1]) / 1024


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--points", type=int, nargs="+", default=[1_000_000, 5_000_000])
    p.add_argument("-k", type=int, default=2000)
    p.add_argument("--rounds", type=int, default=1)
    a = p.parse_args()
    print("| points | command | wall s | peak MiB |")
    print("|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for n in sorted(a.points):
            cloud = _cloud(n, 0, folder)
            labels = folder / f"l{n}.seg"
            subprocess.run(COMMAND + ["segment", str(cloud), "-k", str(a.k), "-o",
                                      str(labels), "-q"], check=True)
            for name, out in (("render", "x.png"), ("html", "x.html")):
                best = min(timed([name, str(cloud), str(labels), "-o", str(folder / out),
                                  "-q"]) for _ in range(a.rounds))
                print(f"| {n:,} | {name} | {best[0]:.1f} | {best[1]:,.0f} |", flush=True)


if __name__ == "__main__":
    main()
