"""Iterative farthest-point sampling of element positions (private kernels)."""

import numpy as np
from numba import njit

_INF = np.inf


@njit(cache=True, error_model="numpy", inline="always")
def _nearest_so_far(centroids, mind, f, cx, cy, cz, scale2):
    """Lower ``mind[f]`` to the squared distance from the centroid of ``f`` to
    ``(cx, cy, cz)`` (times ``scale2[f]`` unless it is None) if nearer; return
    it (negative: ``f`` is a center)."""
    mf = mind[f]
    if mf < 0.0:
        return mf
    dx = centroids[f, 0] - cx
    dy = centroids[f, 1] - cy
    dz = centroids[f, 2] - cz
    d = dx * dx + dy * dy + dz * dz
    if scale2 is not None:
        d *= scale2[f]
    if d < mf:
        mind[f] = d
        return d
    return mf


@njit(cache=True, error_model="numpy")
def farthest_point(centroids, k, first, out, scale2=None):
    """Iterative farthest point sampling in O(m k) with a running minimum.

    ``out[0] = first``; each next entry is the face whose centroid has the
    largest Euclidean distance to its nearest chosen center (ties: lowest
    index), that distance multiplied by ``sqrt(scale2[f])`` when ``scale2``
    is given (content-sensitive sampling). A chosen face is never chosen again.
    """
    m = centroids.shape[0]
    mind = np.full(m, _INF)
    cur = first
    for t in range(k):
        out[t] = cur
        mind[cur] = -1.0
        cx = centroids[cur, 0]
        cy = centroids[cur, 1]
        cz = centroids[cur, 2]
        best = -1.0
        nxt = -1
        for f in range(m):
            mf = _nearest_so_far(centroids, mind, f, cx, cy, cz, scale2)
            if mf < 0.0:
                continue
            if mf > best:
                best = mf
                nxt = f
        cur = nxt


@njit(cache=True, error_model="numpy", nogil=True)
def spatial_blocks(centroids, cells_per_axis):
    """Group faces by the cell of a regular grid that holds their centroid.

    Returns ``(order, bstart, bcenter, bradius)``: ``order`` lists the faces
    cell by cell (ascending within a cell), non-empty cell ``b`` holds
    ``order[bstart[b]:bstart[b + 1]]``, and its faces' centroids lie within
    ``bradius[b]`` of ``bcenter[b]`` (the middle of their bounding box; the
    radius is enlarged by a relative 1e-9 against rounding).
    """
    m = centroids.shape[0]
    g = cells_per_axis
    lo = np.empty(3)
    span = 0.0
    for t in range(3):
        a = centroids[0, t]
        b = centroids[0, t]
        for f in range(m):
            x = centroids[f, t]
            if x < a:
                a = x
            if x > b:
                b = x
        lo[t] = a
        if b - a > span:
            span = b - a
    scale = g / span if span > 0 else 0.0
    cell = np.empty(m, dtype=np.int64)
    count = np.zeros(g * g * g + 1, dtype=np.int64)
    for f in range(m):
        key = 0
        for t in range(3):
            i = np.int64((centroids[f, t] - lo[t]) * scale)
            if i >= g:
                i = g - 1
            if i < 0:
                i = 0
            key = key * g + i
        cell[f] = key
        count[key + 1] += 1
    for i in range(g * g * g):
        count[i + 1] += count[i]
    order = np.empty(m, dtype=np.int64)
    fill = count[:-1].copy()
    for f in range(m):
        order[fill[cell[f]]] = f
        fill[cell[f]] += 1
    nb = 0
    for i in range(g * g * g):
        if count[i + 1] > count[i]:
            nb += 1
    bstart = np.empty(nb + 1, dtype=np.int64)
    b = 0
    for i in range(g * g * g):
        if count[i + 1] > count[i]:
            bstart[b] = count[i]
            b += 1
    bstart[nb] = m
    bcenter = np.empty((nb, 3))
    bradius = np.empty(nb)
    for b in range(nb):
        for t in range(3):
            a = np.inf
            z = -np.inf
            for j in range(bstart[b], bstart[b + 1]):
                x = centroids[order[j], t]
                if x < a:
                    a = x
                if x > z:
                    z = x
            bcenter[b, t] = 0.5 * (a + z)
        r2 = 0.0
        for j in range(bstart[b], bstart[b + 1]):
            f = order[j]
            d = 0.0
            for t in range(3):
                x = centroids[f, t] - bcenter[b, t]
                d += x * x
            if d > r2:
                r2 = d
        bradius[b] = np.sqrt(r2) * (1.0 + 1e-9)
    return order, bstart, bcenter, bradius


@njit(cache=True, error_model="numpy", nogil=True)
def farthest_point_blocked(centroids, k, first, out, order, bstart, bcenter, bradius,
                           scale2=None, bscale2=None):
    """:func:`farthest_point`, skipping the blocks a new center cannot change.

    ``scale2`` (optional) is :func:`farthest_point`'s, listed in block order
    (``scale2[order]``), and ``bscale2`` its smallest value in each block (a block's
    bound on its elements' scaled distances then bounds each of them).

    Same output, ties included. Each face keeps the squared distance to its
    nearest chosen center; each block of :func:`spatial_blocks` keeps the
    largest of them and its lowest face index. A block is visited only when
    a lower bound of the squared distance from the new center to its faces
    (from the bounding sphere, minus a relative 1e-9 for rounding) is below
    that largest value: otherwise no face of it gets nearer. Near-linear in
    practice: a new center only changes the faces around it.
    """
    m = centroids.shape[0]
    nb = bstart.shape[0] - 1
    # positions and running minima in block order: a block's faces are contiguous in
    # memory (the same arithmetic, in the same order: the same output)
    pos = np.empty((m, 3))
    slot = np.empty(m, dtype=np.int64)  # place of each face in block order
    for j in range(m):
        f = order[j]
        slot[f] = j
        pos[j, 0] = centroids[f, 0]
        pos[j, 1] = centroids[f, 1]
        pos[j, 2] = centroids[f, 2]
    mind = np.full(m, _INF)
    bmax = np.full(nb, _INF)
    barg = np.empty(nb, dtype=np.int64)
    home = np.empty(m, dtype=np.int64)  # block of each face
    for b in range(nb):
        barg[b] = m
        for j in range(bstart[b], bstart[b + 1]):
            f = order[j]
            home[f] = b
            if f < barg[b]:
                barg[b] = f
    cur = first
    for t in range(k):
        out[t] = cur
        mind[slot[cur]] = -1.0
        cx = centroids[cur, 0]
        cy = centroids[cur, 1]
        cz = centroids[cur, 2]
        hb = home[cur]
        for b in range(nb):
            if b != hb:
                dx = bcenter[b, 0] - cx
                dy = bcenter[b, 1] - cy
                dz = bcenter[b, 2] - cz
                dc = np.sqrt(dx * dx + dy * dy + dz * dz)
                lb = dc - bradius[b] - 1e-9 * (dc + bradius[b])
                lb2 = lb * lb
                if scale2 is not None:
                    lb2 *= bscale2[b]
                if lb > 0.0 and lb2 >= bmax[b]:
                    continue  # every face is at least as near to an earlier center
            best = -1.0
            arg = m
            for j in range(bstart[b], bstart[b + 1]):
                mf = _nearest_so_far(pos, mind, j, cx, cy, cz, scale2)
                if mf < 0.0:
                    continue
                f = order[j]
                if mf > best or (mf == best and f < arg):
                    best = mf
                    arg = f
            bmax[b] = best
            barg[b] = arg
        best = -1.0
        nxt = -1
        for b in range(nb):
            if bmax[b] > best or (bmax[b] == best and barg[b] < nxt):
                best = bmax[b]
                nxt = barg[b]
        cur = nxt
