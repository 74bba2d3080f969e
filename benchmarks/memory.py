"""Peak memory per element of a run from the command line, each run a new process.

Usage: python benchmarks/memory.py [--cases faces points2m points10m] [--rounds 1]
       python benchmarks/memory.py --before /tmp/before-site [--rounds 2]
       python benchmarks/memory.py --cases faces --threads 2 8 16

Each row is ``superfacets segment INPUT -k K -o OUT.seg`` with the defaults, in a new
process (start-up, reading and writing included); the peak is the process's largest
resident set (``wait4``'s ``ru_maxrss``: the interpreter, numpy and scipy
included, about 100-160 MiB), divided by the input's elements. Cases:

- ``faces``: ``hand_olivier`` subdivided three times (6,775,040 faces, made once by
  ``benchmarks/large_meshes.py`` into ``~/.cache/superfacets/large``), k = 150;
- ``points2m`` / ``points10m`` / ``points50m``: 2M / 10M / 50M points sampled uniformly
  on the horse (``../shared/data/meshes``; seed 0, saved once as ``.npy`` in
  ``~/.cache/superfacets/memory``: 1.2 GB for 50M), k = 1,000; ``points50m`` only when
  asked (about 5 minutes, 20 GB);
- ``sweeps10m``: 10M points of a real, uneven LiDAR scan: the SemanticKITTI sweep
  000700 (``superfacets.evaluation.datasets.scans``, downloaded once) repeated on an
  11 x 11 grid, side by side, cut at 10M points (its density falls with the range, so the
  automatic density and the exact classification run, and its 2,101 separate pieces
  leave the exact count more superpoints than asked), k = 1,000; only when asked;
- ``scanlines10m``: 10M points of a made-up spinning LiDAR (64 rings over a ground
  plane at z = 0 inside walls, sweeps side by side; :func:`_scan_lines`), k = 1,000;
  only when asked.

With ``--before SITE`` each case also runs on another built version of the package
(``benchmarks/_versions.py`` says how to build one), the two alternating, and
the labels of both are compared. With ``--threads T ...`` each run is made with each
``--threads`` given (a row each; the labels of all compared): how the peak grows with the
threads (on a machine of fewer cores the threads share them, and the times mean
little). The table gives the fastest wall time and the largest peak of each version's
rounds.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _versions import PRELUDE, version_env

HERE = Path(__file__).resolve().parent
SHARED = Path(os.environ.get("SUPERFACETS_SHARED", HERE.parents[1] / "shared")) / "data"
CACHE = Path(os.environ.get("SUPERFACETS_CACHE", Path.home() / ".cache" / "superfacets"))

CASES = {"faces": ("faces", 6_775_040, 150), "points2m": ("points", 2_000_000, 1000),
         "points10m": ("points", 10_000_000, 1000), "points50m": ("points", 50_000_000, 1000),
         "sweeps10m": ("points", 10_000_000, 1000),
         "scanlines10m": ("points", 10_000_000, 1000)}
DEFAULT = ["faces", "points2m", "points10m"]


def make_input(case: str) -> Path:
    """The case's input file, made once into the cache."""
    kind, n, _ = CASES[case]
    if kind == "faces":
        sys.path.insert(0, str(HERE))
        from large_meshes import make

        return make("hand_olivier", 3, CACHE / "large")
    if case == "sweeps10m":
        return _sweeps(n)
    if case == "scanlines10m":
        return _scan_lines(n)
    path = CACHE / "memory" / f"horse_{n}.npy"
    if not path.exists():
        import numpy as np

        from superfacets import read_mesh
        from superfacets.evaluation.datasets.sampling import sample_points

        pts, _ = sample_points(read_mesh(SHARED / "meshes" / "horse.tri.xz"), n, seed=0)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".part.npy")
        np.save(tmp, np.ascontiguousarray(pts, dtype=np.float64))
        tmp.replace(path)
    return path


def _sweeps(n: int) -> Path:
    """``n`` points of a LiDAR sweep repeated side by side on a square grid, made once."""
    path = CACHE / "memory" / f"sweeps_{n}.npy"
    if not path.exists():
        import numpy as np

        from superfacets.evaluation.datasets.scans import load_scan

        cloud = load_scan("semantickitti-000700").cloud
        p = np.asarray(cloud.points)[np.asarray(cloud.valid)]
        step = np.ptp(p, axis=0) + 1.0
        reps = int(np.ceil(np.sqrt(n / p.shape[0])))
        grid = [p + [i * step[0], j * step[1], 0.0] for i in range(reps) for j in range(reps)]
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".part.npy")
        np.save(tmp, np.ascontiguousarray(np.concatenate(grid)[:n]))
        tmp.replace(path)
    return path


def _scan_lines(n: int) -> Path:
    """``n`` points of a made-up spinning LiDAR, made once: 64 rings (elevations -24.8
    to -2 degrees, a point every 0.09 degrees) from 1.73 m over a ground plane at z = 0,
    inside square walls (12-36 m), 1 cm noise; sweeps side by side, 150 m apart, 12 to a
    row. Needs no download (``sweeps10m`` does)."""
    import numpy as np

    path = CACHE / "memory" / f"scanlines_{n}.npy"
    if not path.exists():
        rng = np.random.default_rng(0)
        elevation = np.deg2rad(np.linspace(-24.8, -2.0, 64))
        d = np.deg2rad(np.arange(0, 360, 0.09))
        d = np.c_[np.cos(d), np.sin(d)]
        to_wall = 1.0 / np.maximum(np.abs(d[:, 0]), np.abs(d[:, 1]))  # times the half side
        sweeps, total = [], 0
        while total < n:
            k = len(sweeps)
            wall = (12.0 + 6.0 * ((7 * k) % 5)) * to_wall
            rings = []
            for e in elevation:
                ground = 1.73 / np.tan(-e)
                r = np.minimum(ground, wall)
                z = np.where(ground <= wall, 0.0, 1.73 + r * np.tan(e))
                rings.append(np.c_[d * r[:, None] + [150.0 * (k % 12), 150.0 * (k // 12)], z])
            sweeps.append(np.concatenate(rings) + rng.normal(0.0, 0.01, (64 * len(d), 3)))
            total += sweeps[-1].shape[0]
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".part.npy")
        np.save(tmp, np.concatenate(sweeps)[:n])
        tmp.replace(path)
    return path


def _input(case: str) -> Path:
    """:func:`make_input` in a child process: this one stays small, since a child forked
    from it starts with its peak (``ru_maxrss`` counts the parent's resident set at the
    fork: a 2M-point run measured after making the 6.8M-face mesh here read 1,905 MiB)."""
    out = subprocess.run([sys.executable, __file__, "--make-input", case], check=True,
                         stdout=subprocess.PIPE, text=True).stdout
    return Path(out.strip().splitlines()[-1])


def run(version: str, path: Path, k: int, out: Path, threads: int | None = None
        ) -> tuple[float, float, str]:
    """Wall seconds, peak MiB and the labels' digest of one run of ``version``
    (:mod:`_versions`) in a new process (with ``--threads threads`` where given)."""
    code = PRELUDE + "import runpy; runpy.run_module('superfacets', run_name='__main__')"
    more = [] if threads is None else ["--threads", str(threads)]
    t = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-c", code, "segment", str(path),
                             "-k", str(k), "-o", str(out), "-q", *more],
                            env=version_env(version))
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode:
        raise SystemExit(f"{path.name}: exit {proc.returncode}")
    return wall, usage.ru_maxrss / 1024, hashlib.sha256(out.read_bytes()).hexdigest()[:16]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", nargs="+", default=DEFAULT, choices=list(CASES))
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--before", help="a built copy of another version (benchmarks/_versions.py)")
    ap.add_argument("--threads", type=int, nargs="+", help="run each case with these")
    ap.add_argument("--make-input", choices=list(CASES), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.make_input:  # (in a child process: see _input)
        print(make_input(args.make_input))
        return
    versions = [(f"{name}{'' if t is None else f', {t} threads'}", src, t)
                for name, src in ([("before", args.before)] if args.before else [])
                + [("this", "installed")] for t in (args.threads or [None])]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for case in args.cases:
            path = _input(case)
            kind, n, k = CASES[case]
            got = {name: [] for name, _, _ in versions}
            for _ in range(args.rounds):
                for i, (name, src, t) in enumerate(versions):
                    got[name].append(run(src, path, k, Path(tmp) / f"{i}.seg", t))
            digests = {r[2] for runs in got.values() for r in runs}
            for name, _, _ in versions:
                wall = min(r[0] for r in got[name])
                peak = max(r[1] for r in got[name])
                rows.append((case, f"{n:,} {kind}", k, name, wall, peak,
                             peak * 2**20 / n, "yes" if len(digests) == 1 else "NO"))
    print("| case | input | k | version | wall s | peak MiB | B per element | same labels |")
    print("|---|---|---|---|---|---|---|---|")
    for case, what, k, name, wall, peak, per, same in rows:
        print(f"| {case} | {what} | {k} | {name} | {wall:.1f} | {peak:.0f} | {per:.0f} | "
              f"{same} |")
    print(f"\n{args.rounds} round(s){', alternating' if args.before else ''}; new process "
          f"each; {os.cpu_count()} cores; Python {sys.version.split()[0]}")


if __name__ == "__main__":
    main()
