"""Reading a point cloud: each format of one cloud, a new process per read.

The same ``--points`` random points are written as a binary PLY (float32 x, y, z), an
ASCII PLY, an ``.xyz`` text file (6 decimals), a gzipped binary PLY and an ``.npy``;
each is read by :func:`superfacets.read_cloud` in a new process (the read alone, in
process), against another built version where one is given (``--version``, as in
``benchmarks/frames.py``), the versions alternating. The table gives the fastest of
``--rounds``.

Usage: python benchmarks/reading.py [--points 2000000] [--rounds 2] [--version DIR ...]
"""

from __future__ import annotations

import argparse
import gzip
import json
import subprocess
import tempfile
from pathlib import Path

import numpy as np
from _versions import run_code

CASE = r"""
import json, sys, time
from superfacets import read_cloud
t = time.perf_counter()
c = read_cloud(sys.argv[1])
print(json.dumps({"seconds": time.perf_counter() - t, "points": int(c.n_points)}))
"""


def write_all(folder: Path, n: int) -> list[tuple[str, Path]]:
    """The cloud in every format read here: (name, path)."""
    from plyfile import PlyData, PlyElement

    rng = np.random.default_rng(0)
    pts = rng.random((n, 3)) * 60.0
    v = np.empty(n, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    v["x"], v["y"], v["z"] = pts.T
    out = []
    PlyData([PlyElement.describe(v, "vertex")]).write(str(folder / "c.ply"))
    out.append(("binary PLY", folder / "c.ply"))
    (folder / "c.ply.gz").write_bytes(gzip.compress((folder / "c.ply").read_bytes(), 1))
    out.append(("binary PLY, gzip", folder / "c.ply.gz"))
    PlyData([PlyElement.describe(v, "vertex")], text=True).write(str(folder / "a.ply"))
    out.append(("ASCII PLY", folder / "a.ply"))
    np.savetxt(folder / "c.xyz", pts, fmt="%.6f")
    out.append((".xyz (text)", folder / "c.xyz"))
    np.save(folder / "c.npy", pts)
    out.append((".npy", folder / "c.npy"))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=2_000_000)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--version", action="append", dest="versions",
                    help="'installed' or a folder of another built version; default: installed")
    ap.add_argument("--timeout", type=float, default=300.0)
    args = ap.parse_args()
    versions = args.versions or ["installed"]
    with tempfile.TemporaryDirectory() as tmp:
        files = write_all(Path(tmp), args.points)
        best: dict = {}
        for _ in range(args.rounds):
            for v in versions:
                for name, path in files:
                    try:
                        done = run_code(v, CASE, str(path), timeout=args.timeout)
                    except subprocess.TimeoutExpired:
                        best[(v, name)] = None
                        continue
                    if done.returncode:
                        raise SystemExit(f"{v} on {name}: {done.stderr.strip()[-300:]}")
                    r = json.loads(done.stdout.strip().splitlines()[-1])
                    old = best.get((v, name))
                    if old is None or r["seconds"] < old["seconds"]:
                        best[(v, name)] = r
        sizes = {name: path.stat().st_size / 2**20 for name, path in files}
    print(f"{args.points:,} points, fastest of {args.rounds} (read_cloud in process, a new "
          "process each)\n")
    print("| format | MiB | " + " | ".join(f"{v} s" for v in versions) + " |")
    print("|---|---|" + "---|" * len(versions))
    for name, _ in files:
        cells = [f"{best[(v, name)]['seconds']:.2f}" if best.get((v, name)) else "stopped"
                 for v in versions]
        print(f"| {name} | {sizes[name]:.0f} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
