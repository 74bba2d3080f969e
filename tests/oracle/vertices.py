"""The vertex graph of a mesh in two passes (private kernels of
:mod:`superfacets.elements.vertices`).

:func:`vertex_cells` sums each vertex's barycentric area and normal over its
faces; :func:`mesh_edges` lists the mesh edges once each, in ``(lo, hi)``
order, with their dual lengths, by the counting sort of :mod:`.adjacency`.
Both do the floating-point operations of the numpy expressions they replace,
in their order (``np.bincount`` over the corners, ``np.linalg.norm(axis=1)``),
so the graph is the same bit for bit.
"""

import numpy as np
from numba import njit

from .adjacency import count_keys, scatter_keys, sort_buckets
from .geometry import store_unit


@njit(cache=True, error_model="numpy", nogil=True)
def vertex_cells(corners, offsets, index, areas, normals, area, normal):
    """Barycentric area and unit area-weighted normal of every vertex element.

    Face ``f`` (corners ``corners[offsets[f]:offsets[f + 1]]``, element of a
    corner ``index[corners[c]]``) gives ``areas[f] / s`` to each of its ``s``
    corners and ``normals[f] * areas[f]`` to each corner's normal; sums in
    corner order (as ``np.bincount`` over the corners), then each normal made
    unit, ``sqrt((x*x + y*y) + z*z)`` as ``np.linalg.norm(axis=1)``, zero where
    that is not positive. ``area`` and ``normal`` are zeroed here.
    """
    n = area.shape[0]
    for i in range(n):
        area[i] = 0.0
        normal[i, 0] = 0.0
        normal[i, 1] = 0.0
        normal[i, 2] = 0.0
    for f in range(offsets.shape[0] - 1):
        s = offsets[f]
        e = offsets[f + 1]
        share = areas[f] / (e - s)
        fx = normals[f, 0] * areas[f]
        fy = normals[f, 1] * areas[f]
        fz = normals[f, 2] * areas[f]
        for c in range(s, e):
            i = index[corners[c]]
            area[i] += share
            normal[i, 0] += fx
            normal[i, 1] += fy
            normal[i, 2] += fz
    for i in range(n):
        store_unit(normal, i, normal[i, 0], normal[i, 1], normal[i, 2])


@njit(cache=True, error_model="numpy")
def mesh_edges(corners, offsets, index, n, positions, centroids):
    """The edges of a mesh's vertex elements, their dual lengths and uses.

    Polygon ``f``'s edges join its consecutive corners (the last to the
    first); an edge's elements are ``index`` of its two vertices, lower first;
    a collapsed edge (one element) is skipped. The edges come out once each,
    ordered by ``(lo, hi)`` (the order of ``np.unique`` of ``lo * n + hi``),
    with ``uses`` (the half-edges on each) and ``lengths``: over its half-edges
    in corner order, the sum of ``|centroid of the face - (p_lo + p_hi) / 2|``
    (``0.5 * (p_lo + p_hi)``, the norm as ``np.linalg.norm(axis=1)``), the same
    additions as ``np.bincount``; ``spans``, the edge's length ``|p_lo - p_hi|``.
    A counting sort on ``lo``, then each bucket sorted stably on ``hi``.

    Returns
    -------
    lo, hi : (e,) int64 ndarray
    lengths, spans : (e,) float64 ndarray
    uses : (e,) int64 ndarray
    """
    nh = corners.shape[0]
    a = np.empty(nh, dtype=np.int64)
    b = np.empty(nh, dtype=np.int64)
    owner = np.empty(nh, dtype=np.int64)
    skip = np.empty(nh, dtype=np.bool_)
    for f in range(offsets.shape[0] - 1):
        s = offsets[f]
        e = offsets[f + 1]
        for c in range(s, e):
            u = index[corners[c]]
            v = index[corners[c + 1 if c + 1 < e else s]]
            a[c] = min(u, v)
            b[c] = max(u, v)
            owner[c] = f
            skip[c] = u == v
    starts = np.zeros(n + 1, dtype=np.int64)
    count_keys(a, skip, 0, nh, starts[1:])
    for v in range(n):
        starts[v + 1] += starts[v]
    order = np.empty(starts[n], dtype=np.int64)
    fill = starts[:n].copy()
    scatter_keys(a, skip, 0, nh, fill, order)
    sort_buckets(order, starts, b, 0, n)
    m = order.shape[0]
    ne = 0
    for t in range(m):
        if t == 0 or a[order[t]] != a[order[t - 1]] or b[order[t]] != b[order[t - 1]]:
            ne += 1
    lo = np.empty(ne, dtype=np.int64)
    hi = np.empty(ne, dtype=np.int64)
    lengths = np.zeros(ne, dtype=np.float64)
    spans = np.empty(ne, dtype=np.float64)
    uses = np.zeros(ne, dtype=np.int64)
    k = -1
    for t in range(m):
        h = order[t]
        p = a[h]
        q = b[h]
        if t == 0 or p != a[order[t - 1]] or q != b[order[t - 1]]:
            k += 1
            lo[k] = p
            hi[k] = q
            dx = positions[p, 0] - positions[q, 0]
            dy = positions[p, 1] - positions[q, 1]
            dz = positions[p, 2] - positions[q, 2]
            spans[k] = np.sqrt(dx * dx + dy * dy + dz * dz)
        f = owner[h]
        dx = centroids[f, 0] - 0.5 * (positions[p, 0] + positions[q, 0])
        dy = centroids[f, 1] - 0.5 * (positions[p, 1] + positions[q, 1])
        dz = centroids[f, 2] - 0.5 * (positions[p, 2] + positions[q, 2])
        lengths[k] += np.sqrt(dx * dx + dy * dy + dz * dz)
        uses[k] += 1
    return lo, hi, lengths, spans, uses
