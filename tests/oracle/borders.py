"""The superfacet graph's borders, in numba (private kernel of
:func:`superfacets.graph.adjacency.superfacet_graph`): the crossing adjacencies grouped
by the pair of labels they join.
"""

import numpy as np
from numba import njit

from .geometry import pair_terms


@njit(cache=True, error_model="numpy", nogil=True)
def label_pairs(labels, pairs, k, inv):
    """The distinct label pairs ``lo * k + hi`` (``lo < hi``, the labels of the two
    elements of each row of ``pairs``), ascending, returned; ``inv[c]``: the place of
    row ``c``'s among them. ``np.unique(lo * k + hi, return_inverse=True)``, by a
    counting sort on ``lo`` and each ``lo``'s distinct ``hi`` sorted."""
    m = pairs.shape[0]
    lo = np.empty(m, dtype=np.int64)
    hi = np.empty(m, dtype=np.int64)
    start = np.zeros(k + 1, dtype=np.int64)
    for c in range(m):
        a, b = labels[pairs[c, 0]], labels[pairs[c, 1]]
        if a > b:
            a, b = b, a
        lo[c] = a
        hi[c] = b
        start[a + 1] += 1
    for s in range(k):
        start[s + 1] += start[s]
    fill = start[:k].copy()
    order = np.empty(m, dtype=np.int64)
    for c in range(m):
        order[fill[lo[c]]] = c
        fill[lo[c]] += 1
    stamp = np.full(k, -1, dtype=np.int64)
    slot = np.empty(k, dtype=np.int64)
    seen = np.empty(k, dtype=np.int64)
    key = np.empty(m, dtype=np.int64)
    e = 0
    for s in range(k):
        ns = 0
        for t in range(start[s], start[s + 1]):
            h = hi[order[t]]
            if stamp[h] != s:
                stamp[h] = s
                seen[ns] = h
                ns += 1
        part = np.sort(seen[:ns])
        for j in range(ns):
            slot[part[j]] = e + j
            key[e + j] = s * k + part[j]
        e += ns
        for t in range(start[s], start[s + 1]):
            inv[order[t]] = slot[hi[order[t]]]
    return key[:e].copy()


@njit(cache=True, error_model="numpy", nogil=True)
def crossing_pairs(indptr, indices, labels):
    """The pairs ``(i, j)``, ``i < j``, of a symmetric CSR layout whose labels differ, in
    pair order (rows ascending, then ``j``): ``(m, 2)`` int64."""
    n = indptr.shape[0] - 1
    m = 0
    for i in range(n):
        for x in range(indptr[i], indptr[i + 1]):
            j = indices[x]
            if j > i and labels[j] != labels[i]:
                m += 1
    out = np.empty((m, 2), dtype=np.int64)
    m = 0
    for i in range(n):
        for x in range(indptr[i], indptr[i + 1]):
            j = indices[x]
            if j > i and labels[j] != labels[i]:
                out[m, 0] = i
                out[m, 1] = j
                m += 1
    return out


@njit(cache=True, error_model="numpy", nogil=True)
def label_pair_sums(indptr, indices, labels, k, positions, normals, shares):
    """The crossing adjacencies (:func:`crossing_pairs`) summed per pair of labels: the
    keys ``lo * k + hi`` ascending, and per key ``(border, border * angle, border *
    concave, crossings, angle, concave)`` added in pair order (a stable sort of the keys),
    each border the mean of the two points' border shares and each angle ``acos`` of
    :func:`~superfacets._kernels.geometry.pair_terms`' cosine: ``(E,)`` int64, ``(E, 6)``."""
    pairs = crossing_pairs(indptr, indices, labels)
    m = pairs.shape[0]
    key = np.empty(m, dtype=np.int64)
    for t in range(m):
        a, b = labels[pairs[t, 0]], labels[pairs[t, 1]]
        key[t] = min(a, b) * k + max(a, b)
    order = np.argsort(key, kind="mergesort")
    e = 0
    for u in range(m):
        if u == 0 or key[order[u]] != key[order[u - 1]]:
            e += 1
    keys = np.empty(e, dtype=np.int64)
    sums = np.zeros((e, 6))
    r = -1
    for u in range(m):
        t = order[u]
        if u == 0 or key[t] != key[order[u - 1]]:
            r += 1
            keys[r] = key[t]
        i, j = pairs[t, 0], pairs[t, 1]
        _, cs, concave = pair_terms(positions, normals, i, j)
        length = 0.5 * (shares[i] + shares[j])
        ang = np.arccos(cs)
        cc = 1.0 if concave else 0.0
        sums[r, 0] += length
        sums[r, 1] += length * ang
        sums[r, 2] += length * cc
        sums[r, 3] += 1.0
        sums[r, 4] += ang
        sums[r, 5] += cc
    return keys, sums
