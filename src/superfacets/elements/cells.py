"""The cell graph of a tetrahedral mesh: tetrahedra adjacent through shared triangles.

The paper's section 6 names tetrahedral meshes as a direction. Each
tetrahedron is an element:

- adjacency: two tetrahedra sharing a triangle (a triangle shared by more
  than two, which a conforming mesh never has, joins each pair of them);
- size: the volume, so superfacets balance volume as they balance area on
  a surface (``r = (3 V / (4 pi k))^(1/3)``);
- position: the centroid; border length of an adjacency: the shared
  triangle's area (connectivity, compactness ``area / volume^(2/3)``);
- geodesic term (eq. 1's analogue): ``|c_i - m_ij| + |m_ij - c_j|``, ``m_ij``
  the centroid of the shared triangle;
- the angular term has no analogue inside a solid (no surface normal
  between two tetrahedra): ``theta = 0``, so the paper's weights reduce to the
  geodesic term, and what a concave crease is on a surface is a *material
  jump* in a volume. It enters through the feature term (``beta``, the
  materials one-hot by default), in the form of eq. 2: ``beta * |c_i - c_j| *
  ||f_i - f_j||``. ``docs/notes/method.md``, "Tetrahedral meshes".
"""

from __future__ import annotations

import numpy as np

from ..inputs.tetmesh import TET_FACES
from .graph import ElementGraph, adjacency_csr, cached_on

__all__ = ["cell_graph"]


def cell_graph(mesh) -> ElementGraph:
    """The cell graph of a :class:`~superfacets.inputs.tetmesh.TetMesh` (module notes),
    built once and kept with the mesh.

    Returns
    -------
    ElementGraph
        ``kind = "cells"``.

    Examples
    --------
    >>> from superfacets.inputs.tetmesh import TetMesh
    >>> t = TetMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]],
    ...             [[0, 1, 2, 3], [1, 2, 3, 4]])
    >>> g = cell_graph(t)
    >>> g.pairs.tolist(), round(float(g.lengths[0]), 6)   # the triangle 1-2-3
    ([[0, 1]], 0.866025)
    """
    return cached_on(mesh, "_cell_graph", lambda: _build(mesh))


def _build(mesh) -> ElementGraph:
    m = mesh.n_tets
    v = mesh.vertices
    tri = np.sort(mesh.tets[:, TET_FACES].reshape(-1, 3), axis=1)
    owner = np.repeat(np.arange(m), 4)
    order = np.lexsort((tri[:, 2], tri[:, 1], tri[:, 0]))
    tri, owner = tri[order], owner[order]
    new = np.ones(tri.shape[0], dtype=bool)
    new[1:] = (tri[1:] != tri[:-1]).any(axis=1)
    starts = np.flatnonzero(new)
    count = np.diff(np.r_[starts, tri.shape[0]])
    area = 0.5 * np.linalg.norm(np.cross(v[tri[starts, 1]] - v[tri[starts, 0]],
                                         v[tri[starts, 2]] - v[tri[starts, 0]]), axis=1)
    mid = v[tri[starts]].mean(axis=1)
    # pairs: each two tetrahedra of one triangle
    lo_l, hi_l, grp_l = [], [], []
    for c in np.unique(count[count >= 2]):
        gs = np.flatnonzero(count == c)
        members = owner[starts[gs][:, None] + np.arange(c)[None, :]]
        for x in range(c):
            for y in range(x + 1, c):
                lo_l.append(members[:, x])
                hi_l.append(members[:, y])
                grp_l.append(gs)
    if lo_l:
        a, b, grp = np.concatenate(lo_l), np.concatenate(hi_l), np.concatenate(grp_l)
    else:
        a = b = grp = np.zeros(0, dtype=np.int64)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    key = lo * m + hi
    o = np.argsort(key, kind="stable")
    key, grp = key[o], grp[o]
    keep = np.r_[True, key[1:] != key[:-1]] if key.size else np.zeros(0, bool)
    lo, hi, grp = key[keep] // m, key[keep] % m, grp[keep]
    # two tetrahedra sharing several triangles (only in a degenerate mesh): the first
    indptr, indices, dual_edge = adjacency_csr(lo, hi, m)
    c = mesh.centroids
    lengths = area[grp]
    spans = np.linalg.norm(c[hi] - c[lo], axis=1)
    geo = np.linalg.norm(c[lo] - mid[grp], axis=1) + np.linalg.norm(mid[grp] - c[hi], axis=1)
    once = count == 1
    used = v[np.unique(mesh.tets)]  # as meshes: vertices of no tetrahedron do not count
    lower, upper = used.min(axis=0), used.max(axis=0)
    return ElementGraph(
        kind="cells", positions=np.ascontiguousarray(c), sizes=mesh.volumes,
        normals=np.zeros((m, 3)), centroid=used.mean(axis=0),
        lower=lower, diagonal=float(np.linalg.norm(upper - lower)),
        pairs=np.stack([lo, hi], axis=1), indptr=indptr, indices=indices,
        dual_edge=dual_edge, lengths=lengths, boundary_elements=owner[starts[once]],
        boundary_lengths=area[once], spans=spans,
        terms_of=lambda g, sl, geo=geo: (geo[sl], np.ones(geo[sl].shape[0]),
                                         np.zeros(geo[sl].shape[0], dtype=bool)))
