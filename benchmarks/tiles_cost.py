"""What a tiled run costs against one run: wall and CPU seconds, a new process each.

Usage: ``python benchmarks/tiles_cost.py [--points 10000000] [-k 2000] [--tiles 2 4 16]
[--workers 2] [--before DIR] [--repeat 2]``

Points are sampled on PSB mesh 281 (the benchmark's, from ``../shared``; ``--seed``) and
written to a binary PLY once. Each run is a new process: one run (``superfacets.segment``
on the file read whole) and ``segment_tiled`` with each ``--tiles`` count on
``--workers`` local Dask workers. Its CPU seconds are the process's and its waited-for
children's (the Dask workers: user + system time), so a tiled run's is the total over
its workers. ``--before DIR`` runs the same, alternating, against a built copy of another
version (``benchmarks/_versions.py``). Prints a table: the median of ``--repeat`` runs,
and each tiled run's CPU seconds over one run's of the same version.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _versions import run_code  # noqa: E402

CODE = """
import json, resource, sys, time
def cpu():
    a = resource.getrusage(resource.RUSAGE_SELF)
    b = resource.getrusage(resource.RUSAGE_CHILDREN)
    return a.ru_utime + a.ru_stime + b.ru_utime + b.ru_stime
def main():
    path, k, tiles, workers = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
    t, c = time.perf_counter(), cpu()
    if tiles == 0:
        from superfacets import segment
        from superfacets.io import read_cloud
        n = segment(read_cloud(path), k).n_segments
    else:
        from superfacets.scale.tiles.run import segment_tiled
        n = segment_tiled(path, k, tiles=tiles, workers=workers).n_segments
    print(json.dumps(dict(wall=time.perf_counter() - t, cpu=cpu() - c, n=int(n))))
if __name__ == "__main__":
    main()
"""


def _cloud(n: int, seed: int, folder: Path) -> Path:
    import numpy as np
    import trimesh
    from plyfile import PlyData, PlyElement

    from superfacets.evaluation.datasets.psb import list_meshes
    from superfacets.io import read_mesh

    m = read_mesh(next(b for b in list_meshes() if b.id == 281).path)
    pts, _ = trimesh.sample.sample_surface(
        trimesh.Trimesh(np.asarray(m.vertices), np.asarray(m.faces), process=False), n,
        seed=seed)
    v = np.empty(n, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    v["x"], v["y"], v["z"] = pts.T
    path = folder / f"psb281_{n}.ply"
    PlyData([PlyElement.describe(v, "vertex")]).write(str(path))
    return path


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--points", type=int, default=10_000_000)
    p.add_argument("-k", type=int, default=2000)
    p.add_argument("--tiles", type=int, nargs="+", default=[2, 4, 16])
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--repeat", type=int, default=1)
    p.add_argument("--before", default=None, help="a built copy of another version")
    a = p.parse_args()
    versions = ["installed"] + ([a.before] if a.before else [])
    runs: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        path = _cloud(a.points, a.seed, Path(tmp))
        for _ in range(a.repeat):
            for tiles in [0, *a.tiles]:
                for v in versions:  # alternating
                    out = run_code(v, CODE, str(path), str(a.k), str(tiles), str(a.workers))
                    if out.returncode:
                        raise SystemExit(out.stderr[-2000:])
                    runs.setdefault((v, tiles), []).append(
                        json.loads(out.stdout.strip().splitlines()[-1]))
    print(f"{a.points:,} points on PSB 281 (seed {a.seed}), k = {a.k}, {a.workers} workers; "
          f"median of {a.repeat}, a new process each")
    print("| version | run | wall s | CPU s | CPU / one run's | superpoints |")
    print("|---|---|---|---|---|---|")
    for v in versions:
        one = statistics.median(r["cpu"] for r in runs[(v, 0)])
        for tiles in [0, *a.tiles]:
            rs = runs[(v, tiles)]
            wall, cpu = (statistics.median(r[f] for r in rs) for f in ("wall", "cpu"))
            name = "one run" if tiles == 0 else f"{tiles} tiles"
            print(f"| {'this' if v == 'installed' else Path(v).name} | {name} | {wall:.1f} | "
                  f"{cpu:.1f} | {cpu / one:.2f} | {rs[0]['n']} |")


if __name__ == "__main__":
    main()
