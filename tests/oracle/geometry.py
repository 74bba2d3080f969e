"""Per-face geometry of a triangle mesh in one pass (private kernel)."""

import numpy as np
from numba import njit, prange


@njit(cache=True, error_model="numpy", nogil=True)
def face_geometry(vertices, faces, centroids, areas, normals):
    """Centroids, areas and unit normals of all faces in one pass.

    The same floating-point operations, in the same order, as the numpy
    expressions they replace: centroid ``(v0 + v1 + v2) / 3``; cross product
    ``(v1 - v0) x (v2 - v0)`` written out as ``np.cross`` computes it; norm
    ``sqrt((x*x + y*y) + z*z)`` as ``np.linalg.norm(axis=1)``; area half of
    it; normal the cross product divided by the norm, zero for a degenerate
    face. Writes the three (m, 3) / (m,) outputs.
    """
    for f in range(faces.shape[0]):
        i = faces[f, 0]
        j = faces[f, 1]
        k = faces[f, 2]
        for t in range(3):
            centroids[f, t] = (vertices[i, t] + vertices[j, t] + vertices[k, t]) / 3.0
        a0 = vertices[j, 0] - vertices[i, 0]
        a1 = vertices[j, 1] - vertices[i, 1]
        a2 = vertices[j, 2] - vertices[i, 2]
        b0 = vertices[k, 0] - vertices[i, 0]
        b1 = vertices[k, 1] - vertices[i, 1]
        b2 = vertices[k, 2] - vertices[i, 2]
        c0 = a1 * b2 - a2 * b1
        c1 = a2 * b0 - a0 * b2
        c2 = a0 * b1 - a1 * b0
        areas[f] = 0.5 * store_unit(normals, f, c0, c1, c2)


@njit(cache=True, error_model="numpy", inline="always")
def store_unit(out, i, x, y, z):
    """``out[i] = (x, y, z) / norm``, zero where the norm is not positive; returns the
    norm, ``sqrt((x*x + y*y) + z*z)`` as ``np.linalg.norm(axis=1)``."""
    norm = np.sqrt(x * x + y * y + z * z)
    if norm > 0:
        out[i, 0] = x / norm
        out[i, 1] = y / norm
        out[i, 2] = z / norm
    else:
        out[i, 0] = 0.0
        out[i, 1] = 0.0
        out[i, 2] = 0.0
    return norm


@njit(cache=True, error_model="numpy", inline="always")
def _edge(vertices, p, q, ox, oy, oz):
    """The positions of vertices ``p`` and ``q`` relative to ``(ox, oy, oz)``."""
    return (vertices[p, 0] - ox, vertices[p, 1] - oy, vertices[p, 2] - oz,
            vertices[q, 0] - ox, vertices[q, 1] - oy, vertices[q, 2] - oz)


@njit(cache=True, error_model="numpy", nogil=True)
def polygon_geometry(vertices, corners, offsets, centroids, areas, normals):
    """Centroids, areas and unit normals of polygons of any size, in one pass.

    Polygon ``f`` has the vertices ``corners[offsets[f]:offsets[f + 1]]``, in
    order. Normal and area by Newell's method (the sum over the edges ``i ->
    j`` of ``(y_i - y_j)(z_i + z_j)``, and so on: exact for planar polygons,
    convex or not, and the projected-area normal of non-planar ones), taken
    around the polygon's first vertex for precision. Centroid: the mean of the
    centroids of the fan triangles ``(v0, v_i, v_i+1)`` weighted by their
    areas signed along the normal (right for non-convex polygons); the plain
    vertex mean when that area vanishes. Zero normal for a degenerate polygon.
    """
    for f in range(offsets.shape[0] - 1):
        a = offsets[f]
        k = offsets[f + 1] - a
        o = corners[a]
        ox = vertices[o, 0]
        oy = vertices[o, 1]
        oz = vertices[o, 2]
        nx = 0.0
        ny = 0.0
        nz = 0.0
        for i in range(k):
            px, py, pz, qx, qy, qz = _edge(vertices, corners[a + i], corners[a + (i + 1) % k],
                                           ox, oy, oz)
            nx += (py - qy) * (pz + qz)
            ny += (pz - qz) * (px + qx)
            nz += (px - qx) * (py + qy)
        norm = np.sqrt(nx * nx + ny * ny + nz * nz)
        areas[f] = 0.5 * norm
        if norm > 0:
            nx /= norm
            ny /= norm
            nz /= norm
        else:
            nx = 0.0
            ny = 0.0
            nz = 0.0
        normals[f, 0] = nx
        normals[f, 1] = ny
        normals[f, 2] = nz
        wsum = 0.0
        cx = 0.0
        cy = 0.0
        cz = 0.0
        for i in range(1, k - 1):
            px, py, pz, qx, qy, qz = _edge(vertices, corners[a + i], corners[a + i + 1],
                                           ox, oy, oz)
            w = (py * qz - pz * qy) * nx + (pz * qx - px * qz) * ny + (px * qy - py * qx) * nz
            wsum += w
            cx += w * (px + qx)
            cy += w * (py + qy)
            cz += w * (pz + qz)
        if wsum != 0.0 and norm > 0:
            centroids[f, 0] = ox + cx / (3.0 * wsum)
            centroids[f, 1] = oy + cy / (3.0 * wsum)
            centroids[f, 2] = oz + cz / (3.0 * wsum)
        else:
            sx = 0.0
            sy = 0.0
            sz = 0.0
            for i in range(k):
                p = corners[a + i]
                sx += vertices[p, 0]
                sy += vertices[p, 1]
                sz += vertices[p, 2]
            centroids[f, 0] = sx / k
            centroids[f, 1] = sy / k
            centroids[f, 2] = sz / k


@njit(cache=True, error_model="numpy", nogil=True)
def face_terms(vertices, centroids, normals, pairs, edges, lo, hi, geo, cos, concave):
    """The terms of the paper's weights for the face pairs ``lo:hi``, in one pass.

    The same floating-point operations, in the same order, as the numpy
    expressions of :func:`superfacets.elements.faces.face_graph`: edge
    midpoint ``0.5 * (v_a + v_b)``; ``geo = |c_i - m| + |m - c_j|`` with
    norms ``sqrt((x*x + y*y) + z*z)``; ``cos`` the dot product summed as
    ``np.einsum("ij,ij->i")`` sums three terms, ``(x_i x_j + z_i z_j) + y_i
    y_j``, clipped to ``[-1, 1]``; ``concave`` the sign of ``n_i . (c_j -
    c_i)``, summed the same way. Writes ``geo``, ``cos``, ``concave`` from
    index 0. (Tested bit for bit against the numpy expressions.)
    """
    for t in range(lo, hi):
        i = pairs[t, 0]
        j = pairs[t, 1]
        a = edges[t, 0]
        b = edges[t, 1]
        mx = 0.5 * (vertices[a, 0] + vertices[b, 0])
        my = 0.5 * (vertices[a, 1] + vertices[b, 1])
        mz = 0.5 * (vertices[a, 2] + vertices[b, 2])
        dx = centroids[i, 0] - mx
        dy = centroids[i, 1] - my
        dz = centroids[i, 2] - mz
        ex = mx - centroids[j, 0]
        ey = my - centroids[j, 1]
        ez = mz - centroids[j, 2]
        u = t - lo
        geo[u] = np.sqrt(dx * dx + dy * dy + dz * dz) + np.sqrt(ex * ex + ey * ey + ez * ez)
        c = (normals[i, 0] * normals[j, 0] + normals[i, 2] * normals[j, 2]) \
            + normals[i, 1] * normals[j, 1]
        cos[u] = min(max(c, -1.0), 1.0)
        s = (normals[i, 0] * (centroids[j, 0] - centroids[i, 0])
             + normals[i, 2] * (centroids[j, 2] - centroids[i, 2])) \
            + normals[i, 1] * (centroids[j, 1] - centroids[i, 1])
        concave[u] = s > 0


@njit(cache=True, error_model="numpy", inline="always")
def pair_terms(positions, normals, i, j):
    """``(geo, cos, concave)`` of the elements ``i < j``, points with normals: ``d = p_i -
    p_j``, ``geo = sqrt((x*x + y*y) + z*z)``, ``cos`` clipped to ``[-1, 1]`` and
    ``concave = (n_i - n_j) . d < 0``, each dot product summed as ``(x + z) + y``; float32
    normals are read as float64 (the values of a float64 copy)."""
    dx = positions[i, 0] - positions[j, 0]
    dy = positions[i, 1] - positions[j, 1]
    dz = positions[i, 2] - positions[j, 2]
    ix, iy, iz = np.float64(normals[i, 0]), np.float64(normals[i, 1]), np.float64(normals[i, 2])
    jx, jy, jz = np.float64(normals[j, 0]), np.float64(normals[j, 1]), np.float64(normals[j, 2])
    c = (ix * jx + iz * jz) + iy * jy
    s = ((ix - jx) * dx + (iz - jz) * dz) + (iy - jy) * dy
    return np.sqrt(dx * dx + dy * dy + dz * dz), min(max(c, -1.0), 1.0), s < 0


@njit(cache=True, error_model="numpy", nogil=True)
def point_terms(positions, normals, pairs, lo, hi, geo, cos, concave):
    """The terms of the paper's weights for pairs ``lo:hi`` of elements that are points
    with normals (mesh vertices, cloud points), in one pass.

    The same floating-point operations, in the same order, as the numpy
    expressions ``d = p_i - p_j``, ``geo = np.linalg.norm(d, axis=1)``
    (``sqrt((x*x + y*y) + z*z)``), ``cos = clip(einsum(n_i, n_j), -1, 1)`` and
    ``concave = einsum(n_i - n_j, d) < 0``, the three terms of each ``einsum``
    summed as ``(x + z) + y`` (as :func:`face_terms`; :func:`pair_terms`). Writes from
    index 0. (Tested bit for bit against the numpy expressions.)
    """
    for t in range(lo, hi):
        u = t - lo
        geo[u], cos[u], concave[u] = pair_terms(positions, normals, pairs[t, 0], pairs[t, 1])


@njit(cache=True, error_model="numpy", nogil=True)
def edge_lengths(vertices, edges, out):
    """``out[t] = |v[edges[t, 1]] - v[edges[t, 0]]|``, as ``np.linalg.norm(axis=1)``
    computes it: ``sqrt((x*x + y*y) + z*z)``."""
    for t in range(edges.shape[0]):
        a = edges[t, 0]
        b = edges[t, 1]
        x = vertices[b, 0] - vertices[a, 0]
        y = vertices[b, 1] - vertices[a, 1]
        z = vertices[b, 2] - vertices[a, 2]
        out[t] = np.sqrt(x * x + y * y + z * z)


@njit(cache=True, inline="always")
def _spread21(x):
    """The low 21 bits of ``x`` moved to every third bit (bit b -> bit 3b)."""
    x &= np.uint64(0x1FFFFF)
    x = (x | (x << np.uint64(32))) & np.uint64(0x1F00000000FFFF)
    x = (x | (x << np.uint64(16))) & np.uint64(0x1F0000FF0000FF)
    x = (x | (x << np.uint64(8))) & np.uint64(0x100F00F00F00F00F)
    x = (x | (x << np.uint64(4))) & np.uint64(0x10C30C30C30C30C3)
    x = (x | (x << np.uint64(2))) & np.uint64(0x1249249249249249)
    return x


@njit(cache=True, nogil=True, parallel=True)
def local_morton_keys(pts, lo, scale, keys):
    """Z-order keys in a local frame: each coordinate as the integer
    ``min(floor((x - lo) * scale), 2**62)`` (0 below ``lo`` and for NaN), its top bit set,
    interleaved x, y, z from the top: ``keys[i, 0]`` holds the top 21 bits of each,
    ``keys[i, 1]`` the next 21, ``keys[i, 2]`` the next 21."""
    top = np.uint64(1) << np.uint64(63)
    cap = 4611686018427387904.0
    for i in prange(pts.shape[0]):
        o0 = np.uint64(0)
        o1 = np.uint64(0)
        o2 = np.uint64(0)
        for a in range(3):
            q = np.floor((pts[i, a] - lo[a]) * scale)
            if not q > 0.0:
                q = 0.0
            if q > cap:
                q = cap
            b = np.uint64(q) | top
            if a == 0:
                o0 = b
            elif a == 1:
                o1 = b
            else:
                o2 = b
        for w in range(3):
            s = np.uint64(43 - 21 * w)
            keys[i, w] = (_spread21(o0 >> s) << np.uint64(2)) | (
                _spread21(o1 >> s) << np.uint64(1)) | _spread21(o2 >> s)


@njit(cache=True, nogil=True, parallel=True)
def distinct_in_order(p, order, out, inverse):
    """The rows of ``p`` taken in ``order``, each run of equal positions once, into
    ``out`` (from 0); ``inverse[order[i]]`` the place in ``out`` of row ``order[i]``.
    Returns the number of distinct positions. (``-0.0 == 0.0``, as numpy compares.)
    The runs are found and the rows moved in parallel (the gathers dominate), their
    places numbered by a prefix sum in between: the same arrays as one pass in order."""
    n = order.shape[0]
    place = np.empty(n, dtype=np.int64)
    for q in prange(n):  # 1 where a new run starts
        i = np.int64(q)
        if i == 0:
            place[i] = 1
        else:
            row = order[i]
            prev = order[i - 1]
            new = p[row, 0] != p[prev, 0] or p[row, 1] != p[prev, 1] \
                or p[row, 2] != p[prev, 2]
            place[i] = 1 if new else 0
    m = 0
    for i in range(n):  # the place in out of each run
        m += place[i]
        place[i] = m - 1
    for q in prange(n):
        i = np.int64(q)
        row = order[i]
        j = place[i]
        if i == 0 or place[i - 1] != j:
            out[j, 0] = p[row, 0]
            out[j, 1] = p[row, 1]
            out[j, 2] = p[row, 2]
        inverse[row] = j
    return m


@njit(cache=True, error_model="numpy", nogil=True)
def label_sums(labels, weights, positions, normals, area, wpos, wnrm):
    """Per label, added to the zeroed ``area`` (k,), ``wpos`` and ``wnrm`` (k, 3): the
    weights, and the weighted positions and normals, element by element in order, as
    ``np.bincount(labels, weights=w * x[:, c])`` adds them (the product rounded first);
    float32 normals are read as float64."""
    for i in range(labels.shape[0]):
        s = labels[i]
        w = weights[i]
        area[s] += w
        for c in range(3):
            wpos[s, c] += w * positions[i, c]
        for c in range(3):
            wnrm[s, c] += w * np.float64(normals[i, c])


@njit(cache=True, error_model="numpy", nogil=True)
def label_scatter(labels, weights, positions, centroid, scatter):
    """Per label, added to the zeroed ``scatter`` (k, 9): ``(w * d_a) * d_b`` at ``3 a +
    b``, ``d = position - centroid[label]``, element by element in order, as
    ``np.bincount(labels, weights=w * d[:, a] * d[:, b])`` adds them."""
    for i in range(labels.shape[0]):
        s = labels[i]
        w = weights[i]
        d0 = positions[i, 0] - centroid[s, 0]
        d1 = positions[i, 1] - centroid[s, 1]
        d2 = positions[i, 2] - centroid[s, 2]
        scatter[s, 0] += w * d0 * d0
        scatter[s, 1] += w * d0 * d1
        scatter[s, 2] += w * d0 * d2
        scatter[s, 3] += w * d1 * d0
        scatter[s, 4] += w * d1 * d1
        scatter[s, 5] += w * d1 * d2
        scatter[s, 6] += w * d2 * d0
        scatter[s, 7] += w * d2 * d1
        scatter[s, 8] += w * d2 * d2


@njit(cache=True, nogil=True)
def border_shares(indptr, area, out):
    """``out = 2.0 * np.sqrt(np.pi * area) / np.maximum(np.diff(indptr), 1.0)``, each
    operation rounded as numpy's."""
    for i in range(area.shape[0]):
        deg = float(indptr[i + 1] - indptr[i])
        out[i] = 2.0 * np.sqrt(np.pi * area[i]) / (deg if deg > 1.0 else 1.0)


@njit(cache=True, nogil=True)
def key_window(keys, start, out):
    """``out[r]``: bits ``start .. start + 63`` (``0 <= start < 189``) of row ``r``'s
    189-bit key string (63 bits a word of ``keys``, the first bit the highest; zeros past
    its end), as one uint64."""
    j, o = start // 63, start % 63
    mask = np.uint64((1 << (63 - o)) - 1)
    left, right = np.uint64(o + 1), np.uint64(62 - o)
    for r in range(keys.shape[0]):
        x = (keys[r, j] & mask) << left
        if j < 2:
            x |= keys[r, j + 1] >> right
        out[r] = x


@njit(cache=True, nogil=True)
def sort_keys(keys, order, out):
    """``order``: the stable argsort of the uint64 ``keys`` (equal keys in the order of
    their rows); ``out``: ``keys[order]``."""
    by = np.argsort(keys, kind="mergesort")
    for i in range(by.shape[0]):
        order[i] = by[i]
        out[i] = keys[by[i]]


@njit(cache=True, nogil=True)
def rows_apart(bits, at, index, rows):
    """The rows ``i`` (ascending) where ``index[i] < 0`` or the three words of
    ``at[index[i]]`` differ from ``bits[i]``, written into ``rows``; returns their
    number, or -1 when there are more than ``rows`` holds (its first entries written)."""
    cap = rows.shape[0]
    m = 0
    for i in range(index.shape[0]):
        j = index[i]
        if j < 0 or at[j, 0] != bits[i, 0] or at[j, 1] != bits[i, 1] \
                or at[j, 2] != bits[i, 2]:
            if m == cap:
                return -1
            rows[m] = i
            m += 1
    return m


@njit(cache=True, nogil=True, inline="always")
def _key_less(keys, p, a, b):
    """Row ``a`` before row ``b``: by the whole keys, then the positions."""
    for w in range(3):
        if keys[a, w] != keys[b, w]:
            return keys[a, w] < keys[b, w]
    for w in range(3):
        if p[a, w] != p[b, w]:
            return p[a, w] < p[b, w]
    return False


@njit(cache=True, nogil=True)
def order_ties(order, ordered, keys, p):
    """Each run of equal keys in ``ordered`` (the sorted Z-order windows of the rows
    ``order``) put in the order of the rows' whole keys ``keys[row, 0..2]``, then their
    positions ``p[row]``, stably (rows equal in all keep their order): a merge sort of
    each run, in place in ``order``."""
    n = order.shape[0]
    tmp = np.empty(0, dtype=order.dtype)
    a = 0
    while a < n:
        b = a + 1
        while b < n and ordered[b] == ordered[a]:
            b += 1
        m = b - a
        if m > 1:
            if tmp.shape[0] < m:
                tmp = np.empty(m, dtype=order.dtype)
            width = 1
            while width < m:  # bottom-up: runs of `width` merged in pairs, left first
                for lo in range(a, b, 2 * width):
                    mid = min(lo + width, b)
                    hi = min(lo + 2 * width, b)
                    i, j, o = lo, mid, 0
                    while i < mid and j < hi:
                        if _key_less(keys, p, order[j], order[i]):
                            tmp[o] = order[j]
                            j += 1
                        else:
                            tmp[o] = order[i]
                            i += 1
                        o += 1
                    while i < mid:
                        tmp[o] = order[i]
                        i += 1
                        o += 1
                    while j < hi:
                        tmp[o] = order[j]
                        j += 1
                        o += 1
                    order[lo:hi] = tmp[:o]
                width *= 2
        a = b
