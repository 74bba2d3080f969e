"""Procedural test and demo shapes, made by the package itself (no data needed)."""

from __future__ import annotations

import numpy as np

from .mesh import Mesh

__all__ = ["creature"]


def _capsule_sdf(p, a, b, r):
    ab = b - a
    t = np.clip(((p - a) @ ab) / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[..., None] * ab), axis=-1) - r


def _smooth_min(a, b, k):
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b * (1 - h) + a * h - k * h * (1 - h)


def creature(resolution: int = 72) -> Mesh:
    """A four-legged creature: body, head, neck, legs and tail blended smoothly.

    An implicit surface (capsules joined with a smooth minimum, so every limb
    meets the body in a clear concave crease) meshed by marching cubes
    (scikit-image). Deterministic; watertight; outward normals.

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
    ValueError
        If ``resolution`` < 16.
    """
    from skimage.measure import marching_cubes

    if resolution < 16:
        raise ValueError(f"resolution must be >= 16, got {resolution}")
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
    verts, faces, _, _ = marching_cubes(sdf, level=0.0, spacing=(h, h, h))
    verts = verts + lo
    faces = faces.astype(np.int64)
    # orient outwards: positive signed volume
    v0, v1, v2 = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    if np.einsum("ij,ij->i", v0, np.cross(v1, v2)).sum() < 0:
        faces = faces[:, ::-1].copy()
    return Mesh(verts, faces, name="creature")
