"""The memory check's estimate against the measured peak, input by input.

Usage: python benchmarks/memory_check.py [--cases NAME ...]

Each case is ``superfacets segment INPUT -k K -o OUT.seg -q`` in a new process, whose
memory check (:func:`superfacets._runtime.memory.check_memory`) is watched: the estimate
is what the process held when it checked plus what the check reckoned the run would add
(``held + estimated_peak(n, bytes per element, held)``, the largest of its checks); the
peak is the process's largest resident set (``ru_maxrss``). Inputs (made once into
``~/.cache/superfacets``; ``benchmarks/memory.py`` and ``benchmarks/large_meshes.py``
make the large ones):

- faces and vertices: ``hand_olivier`` subdivided 1, 2 and 3 times (PLY);
- points sampled on the horse (1M, 3M, 10M; ``.npy``);
- a made-up spinning LiDAR (``scanlines``: rings over a ground at z = 0, 3M points);
- LiDAR sweeps: the SemanticKITTI sweep 000700 side by side (10M points; needs the
  labelled-scan cache);
- an RGB-D frame (``../shared/data/clouds``, PCD, 307,200 points);
- a ScanNet room (the labelled-scan cache) and a made-up room
  (``superfacets.evaluation.datasets.rooms``), as PLY with colours.

Prints a Markdown table: elements, estimate, peak, estimate / peak.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
CACHE = Path(os.environ.get("SUPERFACETS_CACHE", Path.home() / ".cache" / "superfacets"))
SHARED = Path(os.environ.get("SUPERFACETS_SHARED", HERE.parents[1] / "shared")) / "data"

CHILD = """
import json, resource, sys
from superfacets._runtime import memory
from superfacets.cli import main
seen = []
check = memory.check_memory
def spy(n, bpe, what, **kw):
    if n * bpe > 256 * 2**20:  # (as the check does: what the read freed, given back)
        memory.give_back_free_memory()
    held = memory.resident_bytes()
    seen.append((int(n), held + memory.estimated_peak(n, bpe, held=held,
                                                      input_bytes=kw.get("held_input", 0))))
    return check(n, bpe, what, **kw)
memory.check_memory = spy
code = main(["segment", *sys.argv[1:], "-q"])
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
n, est = max(seen, key=lambda s: s[1]) if seen else (0, 0)
print(json.dumps({"code": code, "n": n, "estimate": est, "peak": peak}))
"""


def _large(level: int) -> Path:
    sys.path.insert(0, str(HERE))
    from large_meshes import make

    return make("hand_olivier", level, CACHE / "large")


def _memory(case: str) -> Path:
    sys.path.insert(0, str(HERE))
    import memory

    return memory.make_input(case)


def _horse(n: int) -> Path:
    import numpy as np

    path = CACHE / "memory" / f"horse_{n}.npy"
    if not path.exists():
        from superfacets import read_mesh
        from superfacets.evaluation.datasets.sampling import sample_points

        pts, _ = sample_points(read_mesh(SHARED / "meshes" / "horse.tri.xz"), n, seed=0)
        path.parent.mkdir(parents=True, exist_ok=True)
        np.save(path, pts)
    return path


def _scan_lines(n: int) -> Path:
    sys.path.insert(0, str(HERE))
    import memory

    return memory._scan_lines(n)


def _coloured_ply(name: str, cloud) -> Path:
    import numpy as np
    from plyfile import PlyData, PlyElement

    path = CACHE / "memory" / f"{name}.ply"
    if not path.exists():
        ok = np.asarray(cloud.valid)
        pts = np.asarray(cloud.points)[ok].astype(np.float32)
        rgb = np.round(np.asarray(cloud.colors)[ok] * 255).astype(np.uint8)
        rows = np.empty(len(pts), dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"),
                                         ("red", "u1"), ("green", "u1"), ("blue", "u1")])
        for i, c in enumerate("xyz"):
            rows[c] = pts[:, i]
        for i, c in enumerate(("red", "green", "blue")):
            rows[c] = rgb[:, i]
        path.parent.mkdir(parents=True, exist_ok=True)
        PlyData([PlyElement.describe(rows, "vertex")]).write(str(path))
    return path


def _scannet() -> Path:
    from superfacets.evaluation.datasets.scans import load_scan

    return _coloured_ply("scannet_0000_00", load_scan("scannet-scene0000_00").cloud)


def _room() -> Path:
    from superfacets.evaluation.datasets.rooms import load_room

    return _coloured_ply("room_0", load_room("room-0").cloud)


CASES = {
    "faces x4": (lambda: _large(1), ["-k", "150"]),
    "faces x16": (lambda: _large(2), ["-k", "150"]),
    "faces x64": (lambda: _large(3), ["-k", "150"]),
    "vertices x16": (lambda: _large(2), ["-k", "150", "--elements", "vertices"]),
    "vertices x64": (lambda: _large(3), ["-k", "150", "--elements", "vertices"]),
    "points 1M": (lambda: _horse(1_000_000), ["-k", "1000"]),
    "points 3M": (lambda: _horse(3_000_000), ["-k", "1000"]),
    "points 10M": (lambda: _horse(10_000_000), ["-k", "1000"]),
    "rings 3M": (lambda: _scan_lines(3_000_000), ["-k", "1000"]),
    "sweeps 10M": (lambda: _memory("sweeps10m"), ["-k", "1000"]),
    "RGB-D frame": (lambda: SHARED / "clouds" / "table_scene_mug_stereo_textured.pcd",
                    ["-k", "300"]),
    "ScanNet room": (_scannet, ["-k", "1000"]),
    "made-up room": (_room, ["-k", "1000"]),
}


def _input(case: str) -> Path:
    """The case's input, made in a child process: this one stays small (a child forked
    from it starts with its peak: ``ru_maxrss`` counts the parent's resident set at the
    fork)."""
    out = subprocess.run([sys.executable, __file__, "--make", case], check=True,
                         stdout=subprocess.PIPE, text=True).stdout
    return Path(out.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    ap.add_argument("--make", choices=list(CASES), help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.make:  # (in a child process: see _input)
        print(CASES[a.make][0]())
        return
    print("| input | elements | estimate MiB | peak MiB | estimate / peak |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for case in a.cases:
            opts = CASES[case][1]
            path = _input(case)
            out = subprocess.run([sys.executable, "-c", CHILD, str(path), *opts, "-o",
                                  str(Path(tmp) / "out.seg")], capture_output=True, text=True)
            try:
                r = json.loads(out.stdout.strip().splitlines()[-1])
            except (ValueError, IndexError):
                print(f"| {case} | failed: {out.stderr.strip().splitlines()[-1:]} | | | |")
                continue
            mib = 2 ** 20
            print(f"| {case} | {r['n']:,} | {r['estimate'] / mib:,.0f} | "
                  f"{r['peak'] / mib:,.0f} | {r['estimate'] / max(r['peak'], 1):.2f} |",
                  flush=True)
    print(f"\nnew process each; {os.cpu_count()} cores; Python {sys.version.split()[0]}")


if __name__ == "__main__":
    main()
