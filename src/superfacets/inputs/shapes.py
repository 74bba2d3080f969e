"""Procedural test and demo shapes, made by the package itself (no data needed)."""

from __future__ import annotations

from itertools import permutations

import numpy as np

from ..checks import check_int
from .mesh import Mesh

__all__ = ["creature"]


def _capsule_sdf(p, a, b, r):
    ab = b - a
    t = np.clip(((p - a) @ ab) / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[..., None] * ab), axis=-1) - r


def _smooth_min(a, b, k):
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b * (1 - h) + a * h - k * h * (1 - h)


def contour(sdf: np.ndarray, origin, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Triangulate the zero level set of a sampled signed distance (marching tetrahedra).

    Each grid cell is split into the six tetrahedra of its Kuhn subdivision
    (all sharing the cell's main diagonal), which match across neighbouring
    cells, so the surface is watertight wherever it stays inside the grid.
    A tetrahedron with one (or three) corners inside gives one triangle, with
    two a quadrilateral split in two; each vertex lies on a grid edge at the
    linearly interpolated zero, and is shared by every triangle using that
    edge. Triangles face outwards (towards positive values).

    Parameters
    ----------
    sdf : (nx, ny, nz) float ndarray
        Signed distance samples, negative inside.
    origin : (3,) float
        Position of sample ``[0, 0, 0]``.
    spacing : float
        Distance between neighbouring samples.

    Returns
    -------
    vertices : (n, 3) float64 ndarray
    faces : (m, 3) int64 ndarray

    Examples
    --------
    >>> g = np.mgrid[-1:1:21j, -1:1:21j, -1:1:21j]
    >>> v, f = contour(np.sqrt((g ** 2).sum(0)) - 0.6, (-1, -1, -1), 0.1)
    >>> bool(np.allclose(np.linalg.norm(v, axis=1), 0.6, atol=0.02))
    True
    """
    sdf = np.asarray(sdf, dtype=np.float64)
    shape = np.array(sdf.shape)
    strides = np.array([shape[1] * shape[2], shape[2], 1])
    cells = np.arange(sdf.size).reshape(sdf.shape)[:-1, :-1, :-1].ravel()
    tets = []
    for perm in permutations(range(3)):  # the path 000 -> ... -> 111 through the cell
        steps = np.cumsum([0] + [strides[a] for a in perm])
        tets.append(cells[:, None] + steps[None, :])
    tets = np.concatenate(tets)
    val = sdf.ravel()[tets]
    inside = val < 0
    n_in = inside.sum(axis=1)
    tets, val, inside, n_in = (a[(n_in > 0) & (n_in < 4)] for a in (tets, val, inside, n_in))
    # order each tet's corners: the odd one (alone on its side) or the inside pair first
    order = np.argsort(~inside, axis=1, kind="stable")  # inside corners first
    three = n_in == 3
    order[three] = np.argsort(inside[three], axis=1, kind="stable")  # the outside one first
    c = np.take_along_axis(tets, order, axis=1)
    one = n_in != 2
    e = []  # triangles as triples of grid edges (p, q)
    a, b, d, f = (c[one, i] for i in range(4))
    e.append(np.stack([np.stack(pq, 1) for pq in ((a, b), (a, d), (a, f))], 1))
    a, b, d, f = (c[~one, i] for i in range(4))  # a, b inside; d, f outside
    e.append(np.stack([np.stack(pq, 1) for pq in ((a, d), (a, f), (b, f))], 1))
    e.append(np.stack([np.stack(pq, 1) for pq in ((a, d), (b, f), (b, d))], 1))
    tri_edges = np.concatenate(e)  # (t, 3, 2) grid point ids
    lo, hi = tri_edges.min(axis=2), tri_edges.max(axis=2)
    keys, faces = np.unique(lo * sdf.size + hi, return_inverse=True)
    faces = faces.reshape(-1, 3).astype(np.int64)
    p, q = keys // sdf.size, keys % sdf.size
    vp, vq = sdf.ravel()[p], sdf.ravel()[q]
    def grid(i):
        return np.stack(np.unravel_index(i, sdf.shape), axis=1) * spacing
    t = (vp / (vp - vq))[:, None]
    vertices = grid(p) + t * (grid(q) - grid(p)) + np.asarray(origin, dtype=np.float64)
    # outwards: along the sum of the triangle's grid edges taken from inside to outside
    ins = np.where(sdf.ravel()[tri_edges[:, :, 0]] < 0, tri_edges[:, :, 0], tri_edges[:, :, 1])
    out = np.where(sdf.ravel()[tri_edges[:, :, 0]] < 0, tri_edges[:, :, 1], tri_edges[:, :, 0])
    away = (grid(out.ravel()) - grid(ins.ravel())).reshape(-1, 3, 3).sum(axis=1)
    v0, v1, v2 = (vertices[faces[:, i]] for i in range(3))
    flip = np.einsum("ij,ij->i", np.cross(v1 - v0, v2 - v0), away) < 0
    faces[flip] = faces[flip][:, ::-1]
    return vertices, faces


def creature(resolution: int = 72) -> Mesh:
    """A four-legged creature: body, head, neck, legs and tail blended smoothly.

    An implicit surface (capsules joined with a smooth minimum, so every limb
    meets the body in a clear concave crease) triangulated by :func:`contour`.
    Deterministic; watertight; outward normals.

    Parameters
    ----------
    resolution : int, default 72
        Grid samples along the longest axis; faces grow as its square
        (72 gives about 40,000 faces).

    Returns
    -------
    Mesh
        Named ``"creature"``.

    Raises
    ------
    ParameterError
        If ``resolution`` is not an integer in ``16..300``.
    """
    resolution = check_int("resolution", resolution, lo=16, hi=300)
    P = np.array
    parts = [
        (P([-0.55, 0.0, 0.0]), P([0.55, 0.0, 0.0]), 0.32),    # body
        (P([0.55, 0.0, 0.05]), P([0.85, 0.0, 0.45]), 0.14),   # neck
        (P([0.85, 0.0, 0.50]), P([1.10, 0.0, 0.45]), 0.20),   # head
        (P([-0.55, 0.0, 0.05]), P([-1.25, 0.0, 0.35]), 0.07),  # tail
    ]
    for x in (-0.42, 0.42):
        for y in (-0.18, 0.18):
            parts.append((P([x, y, -0.1]), P([x * 1.08, y * 1.5, -0.85]), 0.1))  # legs
    lo = np.array([-1.45, -0.55, -1.05])
    hi = np.array([1.4, 0.55, 0.8])
    h = (hi - lo).max() / resolution
    axes = [np.arange(lo[i], hi[i] + h, h) for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    sdf = None
    for a, b, r in parts:
        d = _capsule_sdf(grid, a, b, r)
        sdf = d if sdf is None else _smooth_min(sdf, d, 0.06)
    verts, faces = contour(sdf, lo, h)
    return Mesh(verts, faces, name="creature")
