"""Multi-million-face inputs made reproducibly from the real meshes, cached as binary PLY.

Usage: python benchmarks/large_meshes.py [--levels 1 2 3 4] [--base hand_olivier]
       python benchmarks/large_meshes.py --psb LEVEL [--per-category N]

Each level is one midpoint subdivision (every triangle into four, trimesh)
of the previous one followed by one step of Laplacian smoothing of the new
vertices (each moves half-way to the mean of its neighbours), so the surface
is not piecewise flat. From ``hand_olivier`` (105,860 faces): level 1 gives
0.42M faces, 2 gives 1.7M, 3 gives 6.8M (the paper's largest, the Dragon,
has 7.2M) and 4 gives 27M. Files go to
``$SUPERFACETS_CACHE/large/<base>_x<4^level>.ply`` (default
``~/.cache/superfacets``), outside the repository, and are reused.

``--psb LEVEL`` makes the Princeton benchmark at a finer resolution: each
mesh (the first ``--per-category`` of each category, or all) subdivided
``LEVEL`` times the same way, with every human segmentation carried to the
child faces, in ``<cache>/psb_x<4^LEVEL>/{off,seg}`` (a folder
``superfacets experiment --psb`` takes). It judges what only acts on fine
meshes (coarse-to-fine, ``center_tol``) against the ground truth.
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
    from superfacets.evaluation.datasets.psb import default_archive

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


def subdivide(mesh, level: int):
    """``mesh`` subdivided ``level`` times (as :func:`make`); also the original
    face of each new face."""
    import trimesh

    v, f = mesh.vertices, mesh.faces
    parent = np.arange(f.shape[0])
    for _ in range(level):
        n_old = v.shape[0]
        v, f2, index = trimesh.remesh.subdivide(v, f, return_index=True)
        child_parent = np.empty(f2.shape[0], dtype=np.int64)
        for old, new in index.items():
            child_parent[new] = old
        v = _smooth_new(np.asarray(v, dtype=np.float64), np.asarray(f2), n_old)
        f = np.asarray(f2)
        parent = parent[child_parent]
    return v, f, parent


def make_psb(level: int, per_category: int | None, cache: Path) -> Path:
    """The benchmark subdivided ``level`` times, in ``cache/psb_x<4^level>``."""
    from superfacets import Mesh, read_mesh, write_mesh
    from superfacets.evaluation.datasets.psb import first_per_category, list_meshes
    from superfacets.io.labels import read_labels

    out = cache / f"psb_x{4 ** level}"
    meshes = list_meshes()
    if per_category:
        meshes = first_per_category(meshes, per_category)  # list_meshes: sorted by id
    for bm in meshes:
        off = out / "off" / f"{bm.id}.off"
        if off.exists():
            continue
        mesh = read_mesh(bm.path)
        v, f, parent = subdivide(mesh, level)
        segdir = out / "seg" / "Benchmark" / str(bm.id)
        segdir.mkdir(parents=True, exist_ok=True)
        for sp in bm.seg_paths:
            gt = read_labels(sp, n_faces=mesh.n_faces)
            np.savetxt(segdir / sp.name, gt[parent], fmt="%d")
        off.parent.mkdir(parents=True, exist_ok=True)
        tmp = off.with_suffix(".tmp.off")
        write_mesh(tmp, Mesh(v, f.astype(np.int64)))
        tmp.replace(off)
        print(f"{off}: {f.shape[0]:,} faces", file=sys.stderr)
    return out


def main() -> int:
    from superfacets.evaluation.datasets.psb import default_cache

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", type=int, nargs="+", default=[1, 2, 3, 4])
    ap.add_argument("--base", default="hand_olivier")
    ap.add_argument("--psb", type=int, metavar="LEVEL",
                    help="make the benchmark subdivided LEVEL times instead")
    ap.add_argument("--per-category", type=int, metavar="N",
                    help="with --psb: only the first N meshes of each category")
    args = ap.parse_args()
    if args.psb:
        print(make_psb(args.psb, args.per_category, default_cache()))
        return 0
    for level in args.levels:
        print(make(args.base, level, default_cache() / "large"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
