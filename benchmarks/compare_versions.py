"""Two versions of the package on the same inputs, alternating, each run a new process.

For a change that must not alter speed or memory (a reorganisation): build the version
before it beside this one (``benchmarks/_versions.py`` says how), then

    python benchmarks/compare_versions.py /tmp/before-site installed --rounds 3

Each case runs ``rounds`` times per version, the versions alternating (A B A B ...) so
a busy hour weighs on both alike; the table gives the fastest time of each (the
segmentation alone, in process, after a warm-up run that compiles and loads the
kernels) and the peak resident memory of the process (interpreter included).
Labels are compared too: a reorganisation gives the same ones.

Cases: the Table-1 bunny (69,451 faces) at k = 150 on faces and on vertices, and
1,000,000 points sampled on the horse at k = 500 (``../shared/data/meshes``).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from _versions import run_code

HERE = Path(__file__).resolve().parent
SHARED = HERE.parents[1] / "shared" / "data" / "meshes"

CASE = r"""
import hashlib, json, resource, sys, time
import numpy as np, trimesh
from superfacets import read_mesh, segment
case = sys.argv[1]
mesh = read_mesh(sys.argv[2] + ("/horse.tri.xz" if case == "points" else "/bunny.tri.xz"))
if case == "points":
    tm = trimesh.Trimesh(mesh.vertices, np.asarray(mesh.corners).reshape(-1, 3), process=False)
    obj, k, opts = trimesh.sample.sample_surface(tm, 1_000_000, seed=0)[0], 500, {}
else:
    obj, k, opts = mesh, 150, ({"elements": "vertices"} if case == "vertices" else {})
segment(obj, k, **opts)  # warm-up: kernels compiled or loaded, graph cached on faces
if case != "points":
    mesh = read_mesh(sys.argv[2] + "/bunny.tri.xz")  # a fresh mesh: its graph built again
    obj = mesh
t = time.perf_counter()
r = segment(obj, k, **opts)
dt = time.perf_counter() - t
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
digest = hashlib.sha256(np.ascontiguousarray(r.labels, "<i8").tobytes()).hexdigest()[:16]
print(json.dumps({"seconds": dt, "peak_mib": peak, "labels": digest}))
"""


def run(version: str, case: str) -> dict:
    out = run_code(version, CASE, case, str(SHARED))
    if out.returncode:
        raise SystemExit(f"{version}, {case}: {out.stderr.strip()[-500:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("before", help="the version before: 'installed' or the folder of "
                    "a built version (benchmarks/_versions.py)")
    ap.add_argument("after", help="the version after, likewise")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--cases", nargs="+", default=["faces", "vertices", "points"])
    args = ap.parse_args(argv)
    rows = []
    for case in args.cases:
        got = {"before": [], "after": []}
        for _ in range(args.rounds):
            for name in ("before", "after"):
                got[name].append(run(getattr(args, name), case))
        b, a = (min(got[n], key=lambda r: r["seconds"]) for n in ("before", "after"))
        peak_b = max(r["peak_mib"] for r in got["before"])
        peak_a = max(r["peak_mib"] for r in got["after"])
        same = len({r["labels"] for r in got["before"] + got["after"]}) == 1
        rows.append((case, b["seconds"], a["seconds"], peak_b, peak_a, same))
    print("| case | before (s) | after (s) | after/before | peak before (MiB) | "
          "peak after (MiB) | same labels |")
    print("|---|---|---|---|---|---|---|")
    for case, tb, ta, pb, pa, same in rows:
        print(f"| {case} | {tb:.3f} | {ta:.3f} | {ta / tb:.2f} | {pb:.0f} | {pa:.0f} | "
              f"{'yes' if same else 'NO'} |")
    print(f"\n{args.rounds} rounds, alternating; fastest time, largest peak; "
          f"{os.cpu_count()} cores; {sys.version.split()[0]}")


if __name__ == "__main__":
    main()
