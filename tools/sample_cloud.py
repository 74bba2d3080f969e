"""Write a large point cloud sampled on a mesh's surface as a binary PLY, in parallel.

Usage: python tools/sample_cloud.py MESH N OUT.ply [--processes P] [--seed S]

``N`` points (float32 ``x y z``) sampled uniformly on the surface of ``MESH`` (any format
``superfacets.read_mesh`` reads), in ``P`` processes of ``N / P`` points each (seeds ``S``,
``S + 1``, ...; default: one per CPU), written part by part into one file. For the many-core
measurements (``tools/many_cores.sh``): one process samples about 10M points in 7 s here.
"""

from __future__ import annotations

import argparse
import os
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np


def _part(args: tuple) -> np.ndarray:
    mesh, n, seed = args
    import trimesh

    from superfacets.io import read_mesh

    m = read_mesh(mesh)
    t = trimesh.Trimesh(np.asarray(m.vertices), np.asarray(m.faces), process=False)
    return trimesh.sample.sample_surface(t, n, seed=seed)[0].astype(np.float32)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("mesh")
    p.add_argument("n", type=int)
    p.add_argument("out")
    p.add_argument("--processes", type=int, default=os.cpu_count() or 1)
    p.add_argument("--seed", type=int, default=0)
    a = p.parse_args()
    parts = max(1, min(a.processes, a.n))
    sizes = [a.n * (i + 1) // parts - a.n * i // parts for i in range(parts)]
    header = (f"ply\nformat binary_{'little' if np.little_endian else 'big'}_endian 1.0\n"
              f"element vertex {a.n}\nproperty float x\nproperty float y\nproperty float z\n"
              "end_header\n").encode("ascii")
    out = Path(a.out)
    tmp = out.with_name(out.name + ".part")
    with open(tmp, "wb") as f, ProcessPoolExecutor(parts) as pool:
        f.write(header)
        jobs = [(a.mesh, s, a.seed + i) for i, s in enumerate(sizes)]
        for pts in pool.map(_part, jobs):
            f.write(np.ascontiguousarray(pts).tobytes())
    os.replace(tmp, out)  # (whole or not at all)
    print(f"{a.n:,} points -> {out}")


if __name__ == "__main__":
    main()
