"""The stray-piece merge of :func:`superfacets.method.connectivity.enforce_connectivity`
(private kernel: a union-find over the pieces' adjacency)."""

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", inline="always")
def find(parent, x):
    """The root of ``x`` in the union-find forest ``parent``, compressing its path."""
    root = x
    while parent[root] != root:
        root = parent[root]
    while parent[x] != root:  # path compression
        nxt = parent[x]
        parent[x] = root
        x = nxt
    return root


@njit(cache=True, error_model="numpy", nogil=True)
def merge_strays(strays, nb_indptr, nb_indices, nb_data, n_pieces, count, tiny, min_elements):
    """The piece each piece ends in: every stray (in the order given) joins the
    region (pieces merged so far) with which it shares the longest boundary,
    ``nb_data`` summed per region in the order of the stray's row of the
    pieces' adjacency ``nb_*`` (as ``np.bincount`` sums), ties to the lowest
    region id; a stray with no other neighbouring region stays, and so does a
    ``tiny`` one (a superfacet's own piece) whose region earlier strays have grown to
    ``min_elements`` elements (``count`` per piece); a tiny one joins a tiny region
    still below that size where it touches one. Returns the root
    (``(n_pieces,)`` int64) of each piece."""
    parent = np.arange(n_pieces)
    held = count.copy()
    total = np.zeros(n_pieces)
    seen = np.zeros(n_pieces, dtype=np.bool_)
    touched = np.empty(n_pieces, dtype=np.int64)
    for i in range(strays.shape[0]):
        p = strays[i]
        rp = find(parent, p)
        if tiny[p] and held[rp] >= min_elements:
            continue
        m = 0
        for e in range(nb_indptr[p], nb_indptr[p + 1]):
            q = find(parent, nb_indices[e])
            if q == rp:
                continue
            if not seen[q]:
                seen[q] = True
                touched[m] = q
                m += 1
            total[q] += nb_data[e]
        if m == 0:
            continue
        target = -1
        best = 0.0
        small_target = False  # a tiny piece joins a region still small first
        for j in range(m):
            q = touched[j]
            small = tiny[p] and tiny[q] and held[q] < min_elements
            if target < 0 or (small and not small_target) or (
                    small == small_target and (total[q] > best or (total[q] == best
                                                                   and q < target))):
                target = q
                best = total[q]
                small_target = small
            total[q] = 0.0
            seen[q] = False
        parent[rp] = target
        held[target] += held[rp]
    root = np.empty(n_pieces, dtype=np.int64)
    for q in range(n_pieces):
        root[q] = find(parent, q)
    return root


@njit(cache=True, error_model="numpy", nogil=True)
def stray_borders(indptr, indices, piece, is_main, lengths, shares):
    """The entries ``(a, b, length)`` of the pieces' adjacency whose row ``a`` is a
    stray piece: first ``(piece[i], piece[j])`` over adjacencies ``(i, j)``, ``i < j``,
    in order, then ``(piece[j], piece[i])`` (the order of the whole matrix's entries).
    The adjacencies are the CSR entries ``(i, j)``, ``j > i``, row by row (the pair
    order); the length of pair ``t`` is ``lengths[t]``, or with ``shares`` not empty
    ``0.5 * (shares[i] + shares[j])``."""
    n = indptr.shape[0] - 1
    m = 0
    for i in range(n):
        for x in range(indptr[i], indptr[i + 1]):
            j = indices[x]
            if j > i:
                p, q = piece[i], piece[j]
                if p != q:
                    m += (not is_main[p]) + (not is_main[q])
    a = np.empty(m, dtype=np.int64)
    b = np.empty(m, dtype=np.int64)
    w = np.empty(m)
    u = 0
    for side in range(2):
        t = 0
        for i in range(n):
            for x in range(indptr[i], indptr[i + 1]):
                j = indices[x]
                if j > i:
                    p, q = (piece[i], piece[j]) if side == 0 else (piece[j], piece[i])
                    if p != q and not is_main[p]:
                        a[u] = p
                        b[u] = q
                        if shares.shape[0]:
                            w[u] = 0.5 * (shares[i] + shares[j])
                        else:
                            w[u] = lengths[t]
                        u += 1
                    t += 1
    return a, b, w


@njit(cache=True, error_model="numpy")
def same_label_components(indptr, indices, labels):
    """Connected pieces of each label: ``comp[f]`` numbers the piece of ``f``,
    pieces numbered in the order of their lowest element (the numbering of
    ``scipy.sparse.csgraph.connected_components``). Returns ``comp`` (int64)."""
    n = labels.shape[0]
    comp = np.full(n, -1, dtype=np.int64)
    stack = np.empty(n, dtype=np.int64)
    c = 0
    for s in range(n):
        if comp[s] >= 0:
            continue
        lab = labels[s]
        comp[s] = c
        top = 0
        stack[0] = s
        top = 1
        while top > 0:
            top -= 1
            f = stack[top]
            for e in range(indptr[f], indptr[f + 1]):
                g = indices[e]
                if comp[g] < 0 and labels[g] == lab:
                    comp[g] = c
                    stack[top] = g
                    top += 1
        c += 1
    return comp
