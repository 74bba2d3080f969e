"""Multi-million-face inputs made reproducibly from the real meshes, cached as binary PLY.

Usage: python benchmarks/large_meshes.py [--levels 1 2 3 4] [--base hand_olivier]

Each level is one midpoint subdivision (every triangle into four, trimesh)
of the previous one followed by one step of Laplacian smoothing of the new
vertices (each moves half-way to the mean of its neighbours), so the surface
is not piecewise flat. From ``hand_olivier`` (105,860 faces): level 1 gives
0.42M faces, 2 gives 1.7M, 3 gives 6.8M (the paper's largest, the Dragon,
has 7.2M) and 4 gives 27M. Files go to
``$SUPERFACETS_CACHE/large/<base>_x<4^level>.ply`` (default
``~/.cache/superfacets``), outside the repository, and are reused.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _smooth_new(v: np.ndarray, f: np.ndarray, n_old: int) -> np.ndarray:
    """Move the vertices created by the subdivision half-way to their neighbours' mean."""
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    n = v.shape[0]
    deg = np.bincount(e[:, 0], minlength=n).astype(np.float64)
    mean = np.empty_like(v)
    for c in range(3):
        mean[:, c] = np.bincount(e[:, 0], weights=v[e[:, 1], c], minlength=n)
    mean /= np.maximum(deg, 1)[:, None]
    out = v.copy()
    out[n_old:] = 0.5 * v[n_old:] + 0.5 * mean[n_old:]
    return out


def make(base: str, level: int, cache: Path) -> Path:
    """The cached file of ``base`` subdivided ``level`` times (made if missing)."""
    import trimesh

    from superfacets import Mesh, read_mesh, write_mesh
    from superfacets.datasets.psb import default_archive

    out = cache / f"{base}_x{4 ** level}.ply"
    if out.exists():
        return out
    prev = make(base, level - 1, cache) if level > 1 else None
    src = prev or default_archive().parent / "meshes" / f"{base}.tri.xz"
    mesh = read_mesh(src)
    t = time.perf_counter()
    v, f = trimesh.remesh.subdivide(mesh.vertices, mesh.faces)
    v = _smooth_new(np.asarray(v, dtype=np.float64), np.asarray(f), mesh.n_vertices)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_mesh(out, Mesh(v, f.astype(np.int64)))
    print(f"{out}: {f.shape[0]:,} faces in {time.perf_counter() - t:.1f} s", file=sys.stderr)
    return out


def main() -> int:
    from superfacets.datasets.psb import default_cache

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", type=int, nargs="+", default=[1, 2, 3, 4])
    ap.add_argument("--base", default="hand_olivier")
    args = ap.parse_args()
    for level in args.levels:
        print(make(args.base, level, default_cache() / "large"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
