"""Speed of superpoints: vertices, a million points, the real RGB-D scans.

Usage: python benchmarks/superpoints.py [--repeat 3] [--million 1000000] [--content]

Rows (the fastest of ``--repeat`` runs; each row in a fresh process, so peak
memory is its own):

- bunny vertices (35,947), k = 150: superfacets' vertex mode and the ScanNet
  Segmentator's method (graph segmentation, its defaults kThresh = 0.01,
  segMinVerts = 20) in the same process, each from a freshly read mesh (the
  vertex graph included);
- ``--million`` points sampled uniformly on the horse, k = 500, end to end
  in process (point graph, normals, the method); with ``--content`` also the
  same with content-sensitive sizes (``density=0.5, roughness=1``);
- each real scan of ``../shared/data/clouds``: the command line
  ``superfacets segment SCAN.pcd -k 150 -o OUT.seg`` in a new process
  (start-up and reading included), and in process.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("SUPERFACETS_SHARED", ROOT.parent / "shared")) / "data"


def _peak_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def row_bunny(repeat: int) -> dict:
    from superfacets import read_mesh, segment
    from superfacets.evaluation.baselines.graph_segmentation import graph_segmentation

    best = {}
    for _ in range(repeat):
        mesh = read_mesh(SHARED / "meshes" / "bunny.tri.xz")
        t = time.perf_counter()
        r = segment(mesh, 150, elements="vertices")
        sf = time.perf_counter() - t
        mesh = read_mesh(SHARED / "meshes" / "bunny.tri.xz")
        t = time.perf_counter()
        fh = graph_segmentation(mesh)
        gs = time.perf_counter() - t
        if not best or sf < best["superfacets_s"]:
            best["superfacets_s"] = sf
        if "segmentator_s" not in best or gs < best["segmentator_s"]:
            best["segmentator_s"] = gs
    return dict(row="bunny vertices", elements=mesh.n_vertices, segments=r.n_segments,
                iterations=r.n_iter, segmentator_segments=int(fh.max()) + 1,
                peak_mib=_peak_mib(), **best)


def row_million(n: int, repeat: int, content: bool = False) -> dict:
    from superfacets import read_mesh, superpoints
    from superfacets.evaluation.datasets.sampling import sample_points

    pts, _ = sample_points(read_mesh(SHARED / "meshes" / "horse.tri.xz"), n, seed=0)
    best = None
    for _ in range(repeat):
        t = time.perf_counter()
        labels = superpoints(pts, 500, **(dict(density=0.5, roughness=1.0) if content else {}))
        s = time.perf_counter() - t
        best = s if best is None else min(best, s)
    return dict(row=f"{n:,} points (horse)" + (", content" if content else ""), elements=n,
                segments=int(labels.max()) + 1,
                superfacets_s=best, peak_mib=_peak_mib())


def row_scan(path: Path, repeat: int) -> dict:
    from superfacets import read_cloud, segment

    best, r = None, None
    for _ in range(repeat):
        t = time.perf_counter()
        r = segment(read_cloud(path), 150)
        s = time.perf_counter() - t
        best = s if best is None else min(best, s)
    cli = []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(repeat):
            t = time.perf_counter()
            subprocess.run([sys.executable, "-m", "superfacets", "segment", str(path), "-k", "150",
                            "-o", str(Path(tmp) / "out.seg"), "-q"], check=True)
            cli.append(time.perf_counter() - t)
    return dict(row=path.stem, elements=int((r.labels >= 0).sum()), segments=r.n_segments,
                iterations=r.n_iter, superfacets_s=best, cli_s=min(cli), peak_mib=_peak_mib())


def child(args) -> None:
    kind, _, arg = args.one.partition(":")
    if kind == "bunny":
        out = row_bunny(args.repeat)
    elif kind in ("million", "content"):
        out = row_million(int(arg), args.repeat, kind == "content")
    else:
        out = row_scan(Path(arg), args.repeat)
    print(json.dumps(out))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--million", type=int, default=1_000_000)
    ap.add_argument("--content", action="store_true",
                    help="also the million points with density=0.5, roughness=1")
    ap.add_argument("--one", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        return child(args)
    jobs = ["bunny", f"million:{args.million}"]
    jobs += [f"content:{args.million}"] if args.content else []
    jobs += [f"scan:{p}" for p in sorted((SHARED / "clouds").glob("*.pcd"))]
    rows = []
    for job in jobs:
        cmd = [sys.executable, __file__, "--one", job, "--repeat", str(args.repeat)]
        out = subprocess.run(cmd, check=True, capture_output=True, text=True)
        rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
    print(f"{'input':34} {'elements':>10} {'segments':>8} {'in process s':>12} "
          f"{'CLI new process s':>17} {'Segmentator s':>13} {'peak MiB':>9}")
    for r in rows:
        cli = f"{r['cli_s']:.2f}" if "cli_s" in r else "-"
        gs = (f"{r['segmentator_s']:.3f} ({r['segmentator_segments']})"
              if "segmentator_s" in r else "-")
        print(f"{r['row']:34} {r['elements']:>10,} {r['segments']:>8} "
              f"{r['superfacets_s']:>12.2f} {cli:>17} {gs:>13} {r['peak_mib']:>9.0f}")


if __name__ == "__main__":
    main()
