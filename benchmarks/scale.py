"""Scale benchmark: seconds per stage and peak memory from 69k to millions of faces.

Usage: python benchmarks/scale.py [--max-faces 2e6] [-k 150] [--alpha 200] [--threads N]

Rows: the Bunny once (a first run; nothing is compiled at run time), then the
Bunny at k = 50, 150, 500 and 2000 (cost should not grow with k), then hand_olivier
and its subdivisions
(``benchmarks/large_meshes.py`` makes and caches them: 0.42M, 1.7M, 6.8M,
27M faces) up to ``--max-faces``. Each row runs in a fresh process: import
the package (timed apart), read the file, segment, all timed; "total" is
read + segment in a new process. Peak resident
memory is the process's own; bytes/face is reported both for the whole
process and above the resident size right after import
(Python, numpy, scipy: about 100 MiB). The paper's Table 1 time of the mesh of comparable
size (single-threaded C++, 3.2 GHz) is shown beside, and, measured in the same process
after ours, the graph-segmentation baseline (Felzenszwalb-Huttenlocher with the ScanNet
Segmentator's weights, on the same faces): its threshold searched until it gives k
segments, and one run at the Segmentator's default threshold. First, the bunny from the
command line in a new process (wall clock, 3 runs).
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
sys.path.insert(0, str(ROOT / "benchmarks"))

# paper's Table 1 (k = 150, alpha = 200): faces -> (name, seconds)
PAPER = [(69_451, "Bunny", 22), (105_860, "Hand", 39), (400_000, "Lion vase", 137),
         (1_652_528, "Ramesses", 738), (7_219_045, "Dragon", 3_125)]


def _current_rss() -> int:
    """Resident memory now, bytes (Linux; else the peak so far)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except OSError:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def one(path: str, k: int, alpha: float, threads: int | None, baseline: bool = False) -> dict:
    t = time.perf_counter()
    from superfacets import read_mesh, segment

    t_import = time.perf_counter() - t
    rss0 = _current_rss()
    t = time.perf_counter()
    mesh = read_mesh(path)
    t_read = time.perf_counter() - t
    r = segment(mesh, k, alpha=alpha, n_threads=threads)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    out = dict(faces=mesh.n_faces, superfacets=r.n_segments, n_iter=r.n_iter,
               passes=r.timings["passes"], converged=r.converged, read=t_read,
               graph=r.timings["graph"] + r.timings["weights"], init=r.timings["init"],
               iterations=r.timings["iterations"], total=t_read + r.timings["total"],
               expansions=r.timings["expansions"], rss0=rss0, peak=peak, import_s=t_import,
               coarse=r.timings.get("coarse", 0.0),
               coarse_elements=r.timings.get("coarse_elements", 0),
               coarse_passes=r.timings.get("coarse_passes", 0))
    if baseline:  # the same faces, in the same process, after ours (its peak is not counted)
        from superfacets.evaluation.baselines.graph_segmentation import graph_segmentation

        t = time.perf_counter()
        labels = graph_segmentation(mesh, 0.01, 20, n_segments=k)  # threshold searched to k
        out["gs_search"] = time.perf_counter() - t
        out["gs_segments"] = int(labels.max()) + 1
        t = time.perf_counter()
        graph_segmentation(mesh, 0.01, 20)  # one run at the Segmentator's default threshold
        out["gs_one"] = time.perf_counter() - t
    return out


def cli_seconds(path: Path, k: int, alpha: float, runs: int = 3) -> list[float]:
    """Wall clock of ``superfacets segment PATH -k K`` in a new process, ``runs`` times."""
    exe = Path(sys.executable).with_name("superfacets")
    cmd = [str(exe) if exe.exists() else sys.executable, *([] if exe.exists() else
           ["-m", "superfacets"]), "segment", str(path), "-k", str(k), "--alpha", str(alpha),
           "-q"]
    out = []
    for _ in range(runs):
        t = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        out.append(time.perf_counter() - t)
    return out


def child(path: Path, k: int, alpha: float, threads: int | None, env=None,
          baseline: bool = False) -> dict:
    cmd = [sys.executable, __file__, "--one", str(path), "-k", str(k), "--alpha", str(alpha)]
    if threads:
        cmd += ["--threads", str(threads)]
    if baseline:
        cmd += ["--baseline"]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True,
                         env=None if env is None else {**os.environ, **env})
    return json.loads(out.stdout.strip().splitlines()[-1])


def paper_time(faces: int):
    for n, name, sec in PAPER:
        if abs(faces - n) <= 0.15 * n:
            return f"{sec:,} ({name})"
    return ""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-k", type=int, default=150)
    ap.add_argument("--alpha", type=float, default=200.0)
    ap.add_argument("--max-faces", type=float, default=2e6)
    ap.add_argument("--threads", type=int, default=None,
                    help="threads of segment() (default: all cores)")
    ap.add_argument("--no-baseline", action="store_true",
                    help="skip the graph-segmentation baseline column")
    ap.add_argument("--rows", default="",
                    help="only the rows whose name contains one of these comma-separated "
                         "words (e.g. x64)")
    ap.add_argument("--no-cli", action="store_true",
                    help="skip the bunny from the command line")
    ap.add_argument("--one", help=argparse.SUPPRESS)
    ap.add_argument("--baseline", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        print(json.dumps(one(args.one, args.k, args.alpha, args.threads, args.baseline)))
        return 0
    from large_meshes import make

    from superfacets.evaluation.datasets.psb import default_archive, default_cache

    meshes = default_archive().parent / "meshes"
    runs = [("bunny k=150, first run", meshes / "bunny.tri.xz", 150)]
    runs += [(f"bunny k={k}", meshes / "bunny.tri.xz", k) for k in (50, 150, 500, 2000)]
    runs.append(("hand_olivier", meshes / "hand_olivier.tri.xz", args.k))
    for level in (1, 2, 3, 4):
        if 105_860 * 4 ** level > args.max_faces:
            break
        runs.append((f"hand x{4 ** level}", make("hand_olivier", level, default_cache() / "large"),
                     args.k))
    if args.rows:
        words = [w for w in args.rows.split(",") if w]
        runs = [r for r in runs if any(w in r[0] for w in words)]
    cols = ["mesh", "faces", "k", "superfacets", "iterations (passes)",
            "coarse: clusters, passes, s", "import s", "read s",
            "graph s", "init s (coarse incl.)", "iterations s", "total s", "s/pass", "peak MiB",
            "B/face",
            "B/face above import", "paper s", "graph segm. s (to k; one run)"]
    print(f"alpha = {args.alpha}; threads = {args.threads or 'all cores'}; one fresh process "
          "per row; total = read + segment\n")
    if not args.no_cli:
        cli = cli_seconds(meshes / "bunny.tri.xz", 150, args.alpha)
        print(f"bunny k = 150 from the command line, new process (superfacets segment ... -q), "
              f"3 runs: {', '.join(f'{x:.2f}' for x in cli)} s\n")
    print("| " + " | ".join(cols) + " |")
    print("|" + "---|" * len(cols))
    for name, path, k in runs:
        if "first run" in name:
            r = child(path, k, args.alpha, args.threads)
        else:
            r = child(path, k, args.alpha, args.threads,
                      baseline=not args.no_baseline and k == args.k)
        cells = [name, f"{r['faces']:,}", k, r["superfacets"],
                 f"{r['n_iter']}{'' if r['converged'] else ' (max)'} ({r['passes']})",
                 f"{r['coarse_elements']:,}, {r['coarse_passes']}, {r['coarse']:.2f}"
                 if r["coarse_elements"] else "",
                 f"{r['import_s']:.2f}",
                 *(f"{r[s]:.2f}" for s in ("read", "graph", "init", "iterations", "total")),
                 f"{r['iterations'] / max(r['passes'], 1):.3f}", f"{r['peak'] / 2**20:,.0f}",
                 f"{r['peak'] / r['faces']:,.0f}", f"{(r['peak'] - r['rss0']) / r['faces']:,.0f}",
                 paper_time(r["faces"]) if k == 150 and "first run" not in name else "",
                 f"{r['gs_search']:.2f} ({r['gs_segments']}); {r['gs_one']:.2f}"
                 if "gs_search" in r else ""]
        print("| " + " | ".join(str(c) for c in cells) + " |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
