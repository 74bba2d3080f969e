"""What the tiled runs' tests share: bumpy meshes and clouds, a PLY mesh file."""

from __future__ import annotations

import numpy as np
import trimesh

from superfacets import Mesh


def _bumpy(subdivisions: int = 5) -> Mesh:
    """A sphere with folds (creases, concave and convex), about 20k faces."""
    m = trimesh.creation.icosphere(subdivisions=subdivisions)
    v = m.vertices
    v = v * (1 + 0.15 * np.sin(4 * v[:, :1]) * np.cos(3 * v[:, 1:2]))
    return Mesh(v, m.faces)


def _bumpy_cloud(n: int):
    """``n`` points sampled on :func:`_bumpy` (no normals, no viewpoint)."""
    from superfacets import PointCloud
    from superfacets.evaluation.datasets.sampling import sample_points

    return PointCloud(sample_points(_bumpy(4), n, seed=0)[0])


def _write_ply_mesh(path, vertices, faces, counts=None):
    v = np.array([tuple(x) for x in vertices], dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    if counts is None:
        f = np.empty(len(faces), dtype=[("vertex_indices", "i4", (3,))])
        f["vertex_indices"] = faces
    else:  # faces of other sizes
        f = np.empty(len(faces), dtype=[("vertex_indices", object)])
        f["vertex_indices"] = [np.asarray(x, dtype=np.int32) for x in faces]
    from plyfile import PlyData, PlyElement

    PlyData([PlyElement.describe(v, "vertex"), PlyElement.describe(f, "face")]).write(str(path))


def _lattice_cloud(n: int = 40, seed: int = 3):
    """A wavy sheet on an integer lattice, positions rounded to millimetres: the many
    equal distances of a quantized RGB-D scan."""
    from superfacets import PointCloud

    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    z = np.round(3 * np.sin(x / 6) * np.cos(y / 7), 0)
    rng = np.random.default_rng(seed)
    pts = np.c_[x.ravel(), y.ravel(), z.ravel()][rng.permutation(n * n)]
    return PointCloud(pts, viewpoint=np.array([n / 2, n / 2, 100.0]))
