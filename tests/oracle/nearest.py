"""The k nearest neighbours of points of a cloud, in a tree of its Z-order (private kernels).

The cloud's points are in Z-order (:func:`superfacets.elements.points.distinct_points`),
so the points of each power-of-two cell of the Z-order keys are one range of rows.
:func:`tree_nodes` splits the rows at the first bit of the keys where the first and the
last row of a range differ (a binary radix tree over the sorted keys, as in Karras 2012's
linear BVH) until a range holds ``leaf`` points, and bounds each node by the box of its
points. No copy of the points and no permutation: a node is a range of rows and six
numbers.

:func:`nearest_in_tree` answers each query, itself one of the points, with its ``k``
nearest other points in the order of (squared distance, index): the ties that scipy's
KD-tree leaves to its own traversal go to the lowest index, so the answer is a function
of the points alone. The search starts in the query's own leaf and climbs, visiting each
sibling subtree nearest child first and skipping any box farther than the ``k``-th
candidate. Squared distances are ``(dx*dx + dy*dy) + dz*dz``, the reported distance its
square root, as scipy computes them.
"""

import numpy as np
from numba import njit, prange

from .normals import pca_normals

#: Depth bound of the tree: 189 key bits, then halving ranges of equal keys (64 levels).
STACK = 512
#: Queries per chunk of a thread.
CHUNK = 4096


@njit(cache=True, error_model="numpy", nogil=True)
def _first_bit(keys, a, b, start):
    """The first bit from ``start`` of the 189-bit key strings (63 per word) at which rows
    ``a`` and ``b`` differ, or -1."""
    for w in range(start // 63, 3):
        x = keys[a, w] ^ keys[b, w]
        if w == start // 63:  # only the bits from start on
            x &= (np.uint64(1) << np.uint64(63 - (start - w * 63))) - np.uint64(1)
        if x != 0:
            top = 62
            while (x >> np.uint64(top)) & np.uint64(1) == 0:
                top -= 1
            return w * 63 + (62 - top)
    return -1


@njit(cache=True, error_model="numpy", nogil=True)
def _bit(keys, r, bit):
    w = bit // 63
    return (keys[r, w] >> np.uint64(62 - (bit - w * 63))) & np.uint64(1)


@njit(cache=True, error_model="numpy", nogil=True)
def tree_nodes(pts, keys, leaf, start, end, left, boxes):
    """Build the tree over ``pts`` ((n, 3) float64, sorted by their Z-order ``keys``,
    (n, 3) uint64): node 0 the root, node ``v`` the rows ``start[v]:end[v]``, its children
    ``left[v]`` and ``left[v] + 1`` (-1: a leaf of at most ``leaf`` rows), ``boxes[v]``
    the lower then upper corner of its points. Returns the number of nodes, or -1 when
    the arrays are too short (at most ``2 n - 1`` nodes are made)."""
    n = pts.shape[0]
    cap = start.shape[0]
    if cap < 1:
        return -1
    stack = np.empty((STACK, 2), dtype=np.int64)
    start[0] = 0
    end[0] = n
    nn = 1
    stack[0, 0] = 0
    stack[0, 1] = 0
    sp = 1
    while sp > 0:
        sp -= 1
        v = stack[sp, 0]
        b = stack[sp, 1]
        s = start[v]
        e = end[v]
        left[v] = -1
        if e - s <= leaf:
            continue
        m = s
        while True:
            bit = _first_bit(keys, s, e - 1, b)
            if bit < 0:  # equal keys: halves
                m = (s + e) // 2
                b = 189
                break
            lo = s
            hi = e - 1  # the first row with the bit set
            while lo < hi:
                mid = (lo + hi) // 2
                if _bit(keys, mid, bit):
                    hi = mid
                else:
                    lo = mid + 1
            b = bit + 1
            if s < lo < e:
                m = lo
                break
        if nn + 2 > cap:
            return -1
        left[v] = nn
        start[nn] = s
        end[nn] = m
        start[nn + 1] = m
        end[nn + 1] = e
        stack[sp, 0] = nn + 1
        stack[sp, 1] = b
        stack[sp + 1, 0] = nn
        stack[sp + 1, 1] = b
        sp += 2
        nn += 2
    for v in range(nn - 1, -1, -1):  # children after their parent: boxes bottom up
        c = left[v]
        for a in range(3):
            if c < 0:
                lo = np.inf
                hi = -np.inf
                for t in range(start[v], end[v]):
                    x = pts[t, a]
                    if x < lo:
                        lo = x
                    if x > hi:
                        hi = x
            else:
                lo = min(boxes[c, a], boxes[c + 1, a])
                hi = max(boxes[c, 3 + a], boxes[c + 1, 3 + a])
            boxes[v, a] = lo
            boxes[v, 3 + a] = hi
    return nn


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _gap2(lo, hi, q):
    """Squared distance from ``q`` to the interval ``[lo, hi]``."""
    g = lo - q
    if g <= 0.0:
        g = q - hi
        if g < 0.0:
            g = 0.0
    return g * g


@njit(cache=True, error_model="numpy", nogil=True)
def _box_distance(boxes, v, qx, qy, qz):
    """Squared distance from the query to node ``v``'s box (0 inside): never more than the
    computed squared distance to any point in it (rounding is monotone)."""
    return (_gap2(boxes[v, 0], boxes[v, 3], qx) + _gap2(boxes[v, 1], boxes[v, 4], qy)
            + _gap2(boxes[v, 2], boxes[v, 5], qz))


@njit(cache=True, error_model="numpy", nogil=True)
def _children(boxes, c, qx, qy, qz):
    """The children of an inner node whose first child is ``c``, nearer first: ``(near,
    far, d0, d1)``, ``d0 <= d1`` their boxes' squared distances from the query."""
    d0 = _box_distance(boxes, c, qx, qy, qz)
    d1 = _box_distance(boxes, c + 1, qx, qy, qz)
    if d1 < d0:
        return c + 1, c, d1, d0
    return c, c + 1, d0, d1


@njit(cache=True, error_model="numpy", nogil=True)
def _query(pts, start, end, left, boxes, ids, i, k, bd, bi, stack, sd, sib):
    """The ``k`` nearest points other than row ``i`` into ``bd`` (squared distances) and
    ``bi`` (their ids, ``ids[row]``), by (squared distance, id); returns how many were
    found."""
    qx = pts[i, 0]
    qy = pts[i, 1]
    qz = pts[i, 2]
    cnt = 0
    ns = 0
    v = 0
    while left[v] >= 0:  # down to the query's own leaf, noting the siblings
        c = left[v]
        if i < end[c]:
            sib[ns] = c + 1
            v = c
        else:
            sib[ns] = c
            v = c + 1
        ns += 1
    stack[0] = v
    sd[0] = 0.0
    sp = 1
    while True:
        while sp > 0:
            sp -= 1
            v = stack[sp]
            if cnt == k and sd[sp] > bd[k - 1]:
                continue
            c = left[v]
            if c < 0:
                for t in range(start[v], end[v]):
                    if t == i:
                        continue
                    dx = pts[t, 0] - qx
                    dy = pts[t, 1] - qy
                    dz = pts[t, 2] - qz
                    d = dx * dx + dy * dy + dz * dz
                    u = ids[t] if ids.shape[0] else t
                    if cnt < k:
                        p = cnt
                        cnt += 1
                    elif d < bd[k - 1] or (d == bd[k - 1] and u < bi[k - 1]):
                        p = k - 1
                    else:
                        continue
                    while p > 0 and (bd[p - 1] > d or (bd[p - 1] == d and bi[p - 1] > u)):
                        bd[p] = bd[p - 1]
                        bi[p] = bi[p - 1]
                        p -= 1
                    bd[p] = d
                    bi[p] = u
            else:
                near, far, d0, d1 = _children(boxes, c, qx, qy, qz)
                if not (cnt == k and d1 > bd[k - 1]):
                    stack[sp] = far
                    sd[sp] = d1
                    sp += 1
                stack[sp] = near
                sd[sp] = d0
                sp += 1
        if ns == 0:
            break
        ns -= 1
        stack[0] = sib[ns]
        sd[0] = _box_distance(boxes, sib[ns], qx, qy, qz)
        sp = 1
    return cnt


@njit(cache=True, error_model="numpy", nogil=True, parallel=True)
def nearest_in_tree(pts, start, end, left, boxes, ids, own, k, limit, nbr, kth, within):
    """For each query ``r`` (the row ``own[r]`` of ``pts``, the rows in the tree's order,
    ``ids[row]`` each one's point, none: the rows are the points): ``nbr[r, 0] =
    ids[own[r]]``, then the ids of its ``k`` nearest other rows by (distance, id);
    ``kth[r]`` the distance to the last of them; where ``within`` is not empty ((0, k):
    not asked for), ``within[r, j]``: the ``j + 1``-th lies within ``limit``. ``nbr``:
    (m, k + 1); ``within``: (m, k); ``k < n``."""
    m = own.shape[0]
    flag = within.shape[0] != 0
    for ch in prange((m + CHUNK - 1) // CHUNK):
        bd = np.empty(max(k, 1))
        bi = np.empty(max(k, 1), dtype=np.int64)
        stack = np.empty(STACK, dtype=np.int64)
        sd = np.empty(STACK)
        sib = np.empty(STACK, dtype=np.int64)
        for r in range(ch * CHUNK, min(m, ch * CHUNK + CHUNK)):
            i = own[r]
            got = _query(pts, start, end, left, boxes, ids, i, k, bd, bi, stack, sd, sib)
            nbr[r, 0] = ids[i] if ids.shape[0] else i
            for j in range(got):
                nbr[r, j + 1] = bi[j]
            kth[r] = np.sqrt(bd[got - 1]) if got > 0 else 0.0
            if flag:
                for j in range(k):
                    within[r, j] = j < got and np.sqrt(bd[j]) <= limit


@njit(cache=True, error_model="numpy", nogil=True)
def _closest(pts, start, end, left, boxes, ids, qx, qy, qz, stack, sd):
    """The id (``ids[row]``, none: the row) of the point nearest ``(qx, qy, qz)`` by
    (squared distance, id): depth first, the nearer child first, a node skipped when its
    box lies farther than the best found; -1 where the query is not finite."""
    best = np.inf
    bid = -1
    stack[0] = 0
    sd[0] = _box_distance(boxes, 0, qx, qy, qz)
    sp = 1
    while sp > 0:
        sp -= 1
        v = stack[sp]
        if sd[sp] > best:
            continue
        c = left[v]
        if c < 0:
            for t in range(start[v], end[v]):
                dx = pts[t, 0] - qx
                dy = pts[t, 1] - qy
                dz = pts[t, 2] - qz
                d = dx * dx + dy * dy + dz * dz
                u = ids[t] if ids.shape[0] else t
                if d < best or (d == best and u < bid):
                    best = d
                    bid = u
        else:
            near, far, d0, d1 = _children(boxes, c, qx, qy, qz)
            if d1 <= best:
                stack[sp] = far
                sd[sp] = d1
                sp += 1
            if d0 <= best:
                stack[sp] = near
                sd[sp] = d0
                sp += 1
    return bid


@njit(cache=True, error_model="numpy", nogil=True, parallel=True)
def closest_in_tree(pts, start, end, left, boxes, ids, queries, out):
    """For each query position ``r`` (``queries``: (m, 3)): ``out[r]``, the id of the tree's
    nearest point (ties: the lower id; ``ids[row]`` each row's point, none: the rows are the
    points), -1 where the query is not finite."""
    m = queries.shape[0]
    for ch in prange((m + CHUNK - 1) // CHUNK):
        stack = np.empty(STACK, dtype=np.int64)
        sd = np.empty(STACK)
        for r in range(ch * CHUNK, min(m, ch * CHUNK + CHUNK)):
            out[r] = _closest(pts, start, end, left, boxes, ids, queries[r, 0],
                              queries[r, 1], queries[r, 2], stack, sd)


@njit(cache=True, error_model="numpy", nogil=True)
def surface_select(pts, cand, k, step, nbr, kth, pick):
    """Of each point's candidates (``cand``: itself, then its ``kc`` nearest by (distance,
    id)), the ``k`` whose offset ``d`` has the least ``|d|^2 + (step^2 - 1) (n . d)^2``
    (ties: the lower id), ``n`` the PCA normal of ``cand``'s first ``k + 1`` (as
    ``normals.pca_normals``), in that order, into ``nbr`` (itself first); the distance to
    the farthest of them into ``kth``; where ``pick`` is not empty, the column of ``cand``
    each came from. (The compiled kernel stops at the first candidate farther than the
    ``k``-th key, as the order of ``cand`` allows: the same choice.)"""
    kc = cand.shape[1] - 1
    normals = np.empty((pts.shape[0], 3))
    linearity = np.empty(pts.shape[0])
    pca_normals(pts, np.ascontiguousarray(cand[:, :k + 1]), normals, linearity)
    grow = step * step - 1.0
    key = np.empty(kc)
    d2 = np.empty(kc)
    for r in range(pts.shape[0]):
        i = cand[r, 0]
        for c in range(kc):
            j = cand[r, c + 1]
            dx = pts[j, 0] - pts[i, 0]
            dy = pts[j, 1] - pts[i, 1]
            dz = pts[j, 2] - pts[i, 2]
            off = (dx * normals[r, 0] + dy * normals[r, 1]) + dz * normals[r, 2]
            d2[c] = (dx * dx + dy * dy) + dz * dz
            key[c] = d2[c] + grow * (off * off)
        order = np.argsort(cand[r, 1:], kind="mergesort")  # the ids, then the keys, stably
        order = order[np.argsort(key[order], kind="mergesort")]
        nbr[r, 0] = cand[r, 0]
        far = 0.0
        for m in range(k):
            c = order[m]
            nbr[r, m + 1] = cand[r, c + 1]
            far = max(far, d2[c])
            if pick.shape[0] != 0:
                pick[r, m] = c + 1
        kth[r] = np.sqrt(far)

