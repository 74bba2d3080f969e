"""Voronoi cells of seeds in the weighted element graph (private kernel of
:mod:`superfacets.method.coarse_to_fine`): one multi-source shortest-path search with the
bucket queue of :func:`.expand.expand`."""

import numpy as np
from numba import njit

from .exact import search_buckets


@njit(cache=True, error_model="numpy", nogil=True)
def nearest_seed(indptr, indices, weights, seeds, first, dist, label, queue, inv_width):
    """Label every element with its nearest seed (index into ``seeds``) and
    that distance, by a label-correcting multi-source search from
    ``seeds[first:]`` (:func:`.exact.search_buckets`).

    ``dist``/``label`` must hold ``inf``/-1, except where an earlier call
    from ``seeds[:first]`` (in other connected components) already labelled.

    The distances are exact (those of Dijkstra's algorithm, see
    :func:`.expand.expand`); on ties an element takes the seed listed first
    (``(distance, seed)`` pairs compared lexicographically: the result does not
    depend on the order of the search, so the compiled kernel searches by blocks
    on threads).
    Elements no seed reaches keep ``label = -1``, ``dist = inf``.
    ``queue = (qface, qdist, qnext, head)`` as in :func:`.expand.expand`.
    Returns 0, or :data:`.expand.QUEUE_FULL` (grow ``queue`` and call again).
    """
    todo = np.empty(seeds.shape[0] - first, dtype=np.int64)
    n = 0
    for s in range(first, seeds.shape[0]):
        f = seeds[s]
        if dist[f] == 0.0:
            continue
        dist[f] = 0.0
        label[f] = s
        todo[n] = f
        n += 1
    qlab = np.empty(queue[0].shape[0], dtype=np.int64)
    return search_buckets(indptr, indices, weights, dist, label, todo[:n], queue, qlab,
                          inv_width, True)


@njit(cache=True, error_model="numpy")
def first_in_cells(positions, lo, h, dims, cap):
    """The lowest-index element of each occupied cell of pitch ``h`` from ``lo``
    (``dims`` cells per axis, their product below ``2**62``), ascending (the compiled
    kernel fills one table on threads: its slots' order is not its inputs').

    An open-addressing hash table of ``cap`` slots (a power of two); returns
    an empty array when more than half of them would fill (call again with a
    larger ``cap``).
    """
    keys = np.full(cap, -1, dtype=np.int64)
    first = np.empty(cap, dtype=np.int64)
    mask = np.uint64(cap - 1)
    mult = np.uint64(11400714819323198485)  # Fibonacci hashing
    count = 0
    for t in range(positions.shape[0]):
        cx = np.int64(np.floor((positions[t, 0] - lo[0]) / h))
        cy = np.int64(np.floor((positions[t, 1] - lo[1]) / h))
        cz = np.int64(np.floor((positions[t, 2] - lo[2]) / h))
        k = (cx * dims[1] + cy) * dims[2] + cz
        s = ((np.uint64(k) * mult) >> np.uint64(20)) & mask
        while True:
            i = np.int64(s)
            if keys[i] == k:
                break
            if keys[i] < 0:
                keys[i] = k
                first[i] = t
                count += 1
                if 2 * count > cap:
                    return np.empty(0, dtype=np.int64)
                break
            s = (s + np.uint64(1)) & mask
    out = np.empty(count, dtype=np.int64)
    j = 0
    for i in range(cap):
        if keys[i] >= 0:
            out[j] = first[i]
            j += 1
    out.sort()
    return out


@njit(cache=True, error_model="numpy")
def coarse_pairs(indptr, indices, cluster, dist, csr_w, lengths, shares, n_c):
    """The adjacency of clusters: every pair of clusters ``lo < hi`` that some
    adjacency ``t`` joins, in ``(lo, hi)`` order, with the shortest path between
    their seeds through such an adjacency (the minimum of ``dist[i] + w[t]
    + dist[j]``) and the summed ``lengths[t]`` (added in adjacency order; with
    ``shares`` not empty, the length of ``(i, j)`` is ``0.5 * (shares[i] + shares[j])``:
    :meth:`~superfacets.elements.graph.ElementGraph.border_arrays`).

    The adjacencies are read from the CSR layout: the entries ``(i, j)``, ``j > i``,
    row by row, are the pairs ``t = 0, 1, ...`` in order (the graphs list their pairs
    in ``(lo, hi)`` order), and ``csr_w`` holds each entry's weight; so neither the
    pairs nor a copy of the weights per pair is needed. The crossing adjacencies'
    ``hi`` are bucketed by ``lo`` (4 bytes each, no sort of all of them), each bucket
    sorted and made distinct: the cluster pairs; a second pass in adjacency order
    adds each adjacency into its pair (found by bisection in its bucket).
    Returns ``(pairs (m, 2) int32, via (m,), length (m,))``."""
    n = indptr.shape[0] - 1
    start = np.zeros(n_c + 1, dtype=np.int64)
    for i in range(n):
        a = cluster[i]
        for x in range(indptr[i], indptr[i + 1]):
            j = indices[x]
            if j > i and cluster[j] != a:
                start[min(a, cluster[j]) + 1] += 1
    for c in range(n_c):
        start[c + 1] += start[c]
    hi = np.empty(start[n_c], dtype=np.int32)  # clusters <= elements < 2**31 (int32 ids)
    fill = start[:n_c].copy()
    for i in range(n):  # bucket by lo
        a = cluster[i]
        for x in range(indptr[i], indptr[i + 1]):
            j = indices[x]
            if j > i and cluster[j] != a:
                b = cluster[j]
                hi[fill[min(a, b)]] = max(a, b)
                fill[min(a, b)] += 1
    first = np.zeros(n_c + 1, dtype=np.int64)  # each lo's first pair
    for c in range(n_c):  # each bucket sorted, its distinct values at its start
        s, f = start[c], start[c + 1]
        if f - s > 32:
            hi[s:f] = np.sort(hi[s:f])
        else:
            for x in range(s + 1, f):
                h = hi[x]
                y = x - 1
                while y >= s and hi[y] > h:
                    hi[y + 1] = hi[y]
                    y -= 1
                hi[y + 1] = h
        u = 0
        for x in range(s, f):
            if u == 0 or hi[s + u - 1] != hi[x]:
                hi[s + u] = hi[x]
                u += 1
        first[c + 1] = first[c] + u
    m = first[n_c]
    out = np.empty((m, 2), dtype=np.int32)  # clusters <= elements < 2**31 (as hi)
    w_c = np.full(m, np.inf)
    with_len = shares.shape[0] > 0 or lengths.shape[0] > 0
    len_c = np.zeros(m if with_len else 0)
    for c in range(n_c):
        for u in range(first[c + 1] - first[c]):
            out[first[c] + u, 0] = c
            out[first[c] + u, 1] = hi[start[c] + u]
    t = 0
    for i in range(n):  # in adjacency order: the lengths add up in that order
        a = cluster[i]
        for x in range(indptr[i], indptr[i + 1]):
            j = indices[x]
            if j > i:
                b = cluster[j]
                if a != b:
                    lo_, h = min(a, b), max(a, b)
                    s = start[lo_]
                    left, right = 0, first[lo_ + 1] - first[lo_]
                    while left < right:
                        mid = (left + right) >> 1
                        if hi[s + mid] < h:
                            left = mid + 1
                        else:
                            right = mid
                    g = first[lo_] + left
                    v = dist[i] + csr_w[x] + dist[j]
                    if v < w_c[g]:
                        w_c[g] = v
                    if not with_len:
                        pass
                    elif shares.shape[0]:
                        len_c[g] += 0.5 * (shares[i] + shares[j])
                    else:
                        len_c[g] += lengths[t]
                t += 1
    return out, w_c, len_c


def coarse_lengths(indptr, indices, cluster, pairs, lengths, shares, n_c):
    """The summed border lengths of the cluster pairs ``pairs`` (:func:`coarse_pairs`'
    pairs, in ``(lo, hi)`` order): its third output when given ``lengths`` or ``shares``
    (by definition: that output, the pairs checked to be its pairs)."""
    n = indptr.shape[0] - 1
    out, _, len_c = coarse_pairs(indptr, indices, cluster, np.zeros(n),
                                 np.zeros(indices.shape[0]), lengths, shares, n_c)
    assert np.array_equal(out, pairs)
    return len_c
