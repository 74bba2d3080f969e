"""Speed and memory on the meshes of the paper's Table 1 that are public here.

Usage: python benchmarks/table1.py [-k 150] [--alpha 200] [--repeat 3]

Each mesh runs in a fresh process (so peak resident memory is its own):
read the file, then segment at k = 150, alpha = 200, a few times; the table
shows the fastest run per stage. A first row measures the bunny's first run
alone (nothing is compiled at run time: it should equal the others).
The paper's times are single-threaded C++ on a 3.2 GHz desktop (Table 1).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MESHES = Path(os.environ.get("SUPERFACETS_SHARED", ROOT.parent / "shared")) / "data" / "meshes"
PAPER = {"bunny": 22, "horse": 34, "hand_olivier": 39}


def one(name: str, k: int, alpha: float, repeat: int) -> dict:
    t0 = time.perf_counter()
    from superfacets import read_mesh, segment

    t_import = time.perf_counter() - t0
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    best = None
    for _ in range(repeat):
        t = time.perf_counter()
        mesh = read_mesh(MESHES / f"{name}.tri.xz")
        t_read = time.perf_counter() - t
        r = segment(mesh, k, alpha=alpha)
        row = dict(read=t_read, graph=r.timings["graph"], weights=r.timings["weights"],
                   init=r.timings["init"], iter_s=r.timings["iterations"],
                   connectivity=r.timings["connectivity"])
        row["end_to_end"] = t_read + r.timings["total"]
        if best is None or row["end_to_end"] < best["end_to_end"]:
            best = row
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    return dict(name=name, faces=mesh.n_faces, superfacets=r.n_segments, iterations=r.n_iter,
                converged=r.converged, import_s=t_import, baseline_rss=rss0, peak_rss=peak, **best)


def run_child(name: str, args, env=None) -> dict:
    cmd = [sys.executable, __file__, "--one", name, "-k", str(args.k), "--alpha", str(args.alpha),
           "--repeat", str(args.repeat)]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True, env=env)
    return json.loads(out.stdout.strip().splitlines()[-1])


def cli_times(args) -> list[float]:
    """Wall-clock seconds of ``superfacets segment`` on the bunny, each a new process."""
    out = []
    for _ in range(max(3, args.repeat)):
        t = time.perf_counter()
        subprocess.run([sys.executable, "-m", "superfacets", "segment",
                        str(MESHES / "bunny.tri.xz"), "-k", str(args.k), "--alpha",
                        str(args.alpha), "-q"], check=True)
        out.append(time.perf_counter() - t)
    return out


def help_time() -> float:
    t = time.perf_counter()
    subprocess.run([sys.executable, "-m", "superfacets", "--help"], check=True,
                   capture_output=True)
    return time.perf_counter() - t


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-k", type=int, default=150)
    ap.add_argument("--alpha", type=float, default=200.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--one", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        print(json.dumps(one(args.one, args.k, args.alpha, args.repeat)))
        return 0
    missing = [n for n in PAPER if not (MESHES / f"{n}.tri.xz").exists()]
    if missing:
        print(f"missing: {', '.join(str(MESHES / f'{n}.tri.xz') for n in missing)}",
              file=sys.stderr)
        return 1
    rows = []
    cold = run_child("bunny", argparse.Namespace(k=args.k, alpha=args.alpha, repeat=1),
                     dict(os.environ))
    cold["name"] = "bunny (first run)"
    rows.append(cold)
    for name in PAPER:
        rows.append(run_child(name, args))
    cols = ["mesh", "faces", "superfacets", "iterations", "read s", "graph s", "weights s",
            "init s", "iterations s", "connectivity s", "total s", "paper s", "speed-up",
            "peak MiB"]
    print(f"k = {args.k}, alpha = {args.alpha}; best of {args.repeat} runs per mesh "
          f"(first row: 1 run)\n")
    print("| " + " | ".join(cols) + " |")
    print("|" + "|".join(["---"] * len(cols)) + "|")
    for r in rows:
        paper = PAPER.get(r["name"].split()[0]) if "first" not in r["name"] else None
        cells = [r["name"], f"{r['faces']:,}", r["superfacets"],
                 f"{r['iterations']}{'' if r['converged'] else ' (max)'}",
                 *(f"{r[s]:.2f}" for s in ("read", "graph", "weights", "init", "iter_s",
                                             "connectivity", "end_to_end")),
                 paper or "", f"{paper / r['end_to_end']:.0f}x" if paper else "",
                 f"{r['peak_rss'] / 2**20:.0f}"]
        print("| " + " | ".join(str(c) for c in cells) + " |")
    print(f"\nimport of the package: {rows[-1]['import_s']:.2f} s; resident memory after import "
          f"{rows[-1]['baseline_rss'] / 2**20:.0f} MiB (Python, numpy); 'total' is read + "
          "segment, in process, after import.")
    cli = cli_times(args)
    print(f"\nbunny from the command line in a new process (`superfacets segment bunny.tri.xz "
          f"-k {args.k} -q`, wall clock, {len(cli)} runs): best {min(cli):.2f} s, median "
          f"{sorted(cli)[len(cli) // 2]:.2f} s; `superfacets --help`: {help_time():.2f} s.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
