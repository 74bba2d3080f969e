"""Linear-time sorts of the graph builds (private kernels of :mod:`superfacets.elements`).

Each is a counting sort on a first key with small integer range (a vertex or
an element index), then a sort of each bucket on the second key: insertion
sort for the usual few entries, a stable merge sort for a large bucket (a
vertex shared by thousands of faces). They give exactly the order a stable
``np.argsort`` of the combined key gives, without sorting ``3 m`` 64-bit keys.
"""

import numpy as np
from numba import njit, prange

_SMALL = 32  # buckets up to this size: insertion sort


#: Faces around one edge up to which every two are paired (the compiled kernel's)
MAX_FAN = 8


@njit(cache=True, error_model="numpy")
def _sort_bucket(order, lo, hi, key2):
    """Sort ``order[lo:hi]`` by ``key2[order[.]]``, stably."""
    if hi - lo <= _SMALL:
        for i in range(lo + 1, hi):
            x = order[i]
            kx = key2[x]
            j = i - 1
            while j >= lo and key2[order[j]] > kx:
                order[j + 1] = order[j]
                j -= 1
            order[j + 1] = x
    else:
        part = order[lo:hi].copy()
        o = np.argsort(key2[part], kind="mergesort")
        for i in range(hi - lo):
            order[lo + i] = part[o[i]]


@njit(cache=True, error_model="numpy", nogil=True)
def count_keys(key1, skip, lo, hi, counts):
    """``counts[v] +=`` the number of ``t`` in ``lo..hi-1`` with ``key1[t] == v``
    and not ``skip[t]`` (the first pass of a counting sort on ``key1``)."""
    for t in range(lo, hi):
        if not skip[t]:
            counts[key1[t]] += 1


@njit(cache=True, error_model="numpy", nogil=True)
def scatter_keys(key1, skip, lo, hi, fill, order):
    """Put each kept ``t`` in ``lo..hi-1`` at ``order[fill[key1[t]]]``, advancing
    ``fill`` (the second pass of a stable counting sort)."""
    for t in range(lo, hi):
        if not skip[t]:
            k = key1[t]
            order[fill[k]] = t
            fill[k] += 1


@njit(cache=True, error_model="numpy", nogil=True)
def sort_buckets(order, starts, key2, v0, v1):
    """Sort each bucket ``order[starts[v]:starts[v + 1]]``, ``v0 <= v < v1``, by
    ``key2``, stably."""
    for v in range(v0, v1):
        if starts[v + 1] - starts[v] > 1:
            _sort_bucket(order, starts[v], starts[v + 1], key2)


@njit(cache=True, error_model="numpy", inline="always")
def _sort_row(indices, dual_edge, s, f):
    """Sort the CSR row ``indices[s:f]`` (with its ``dual_edge``) by neighbour, stably."""
    if f - s <= _SMALL:
        for i in range(s + 1, f):
            x = indices[i]
            d = dual_edge[i]
            j = i - 1
            while j >= s and indices[j] > x:
                indices[j + 1] = indices[j]
                dual_edge[j + 1] = dual_edge[j]
                j -= 1
            indices[j + 1] = x
            dual_edge[j + 1] = d
    else:
        o = np.argsort(indices[s:f], kind="mergesort")
        ind = indices[s:f].copy()
        de = dual_edge[s:f].copy()
        for i in range(f - s):
            indices[s + i] = ind[o[i]]
            dual_edge[s + i] = de[o[i]]


@njit(cache=True, error_model="numpy")
def csr_of_pairs(lo, hi, n, indices, dual_edge):
    """Symmetric CSR of the pairs ``(lo[t], hi[t])``: fills ``indices``
    (neighbours ascending per row; a pair listed twice appears twice, in ``t``
    order) and ``dual_edge`` (the pair of each entry), both of length ``2 e``;
    returns ``indptr``."""
    e = lo.shape[0]
    indptr = np.zeros(n + 1, dtype=np.int64)
    for t in range(e):
        indptr[lo[t] + 1] += 1
        indptr[hi[t] + 1] += 1
    for v in range(n):
        indptr[v + 1] += indptr[v]
    fill = indptr[:n].copy()
    for t in range(e):
        a = lo[t]
        b = hi[t]
        p = fill[a]
        indices[p] = b
        dual_edge[p] = t
        fill[a] = p + 1
        p = fill[b]
        indices[p] = a
        dual_edge[p] = t
        fill[b] = p + 1
    for v in range(n):
        _sort_row(indices, dual_edge, indptr[v], indptr[v + 1])
    return indptr


@njit(cache=True, error_model="numpy")
def triangle_half_edges(faces, a, b, skip):
    """The half-edges of triangles: half-edge ``3 f + c`` joins corners ``(0, 1)``,
    ``(1, 2)``, ``(2, 0)`` of face ``f`` for ``c = 0, 1, 2``; ``a`` / ``b`` get its
    lower / higher vertex (in their dtype), ``skip`` whether they coincide."""
    for f in range(faces.shape[0]):
        for c in range(3):
            u = faces[f, c]
            v = faces[f, 0 if c == 2 else c + 1]
            h = 3 * f + c
            a[h] = min(u, v)
            b[h] = max(u, v)
            skip[h] = u == v


@njit(cache=True, error_model="numpy", nogil=True)
def group_pairs(half, owner, a, b):
    """The edges of sorted half-edges and the face pairs that share them.

    ``half`` holds half-edge ids ordered by their vertices ``(a[h], b[h])``;
    the face of half-edge ``h`` is ``owner[h]``, or ``h // 3`` (triangles)
    when ``owner`` is empty. A run of equal ``(a, b)`` is one
    edge: of one half-edge, an open boundary; of ``2 <= s <= MAX_FAN``, each of the
    ``s (s - 1) / 2`` pairs of its faces (``i < j`` within the run; a face
    paired with itself left out) is a face pair across that edge; of ``s > MAX_FAN``
    (a fan of copies, a "book"), each face with the next in the run, the last with the
    first: ``s`` pairs, so the pairs stay in proportion to the faces.

    Returns
    -------
    boundary : (b,) int64 ndarray
        Index into ``half`` of each open-boundary edge, in order.
    lo, hi : (p,) ndarrays of ``half``'s dtype
        The two faces of each pair, ``lo < hi``, runs in order, then ``(i, j)``.
    ea, eb : (p,) ndarrays of ``a``'s dtype
        The vertices ``(a, b)`` of the edge of each pair.
    """
    n = half.shape[0]
    new = np.empty(n + 1, dtype=np.bool_)  # half[i] starts a run (and a sentinel)
    new[n] = True
    n_bound = 0
    n_pairs = 0
    run = 0
    for i in range(n):  # one read of each half-edge's vertices: mark runs, count
        h = half[i]
        if i == 0 or a[h] != a[half[i - 1]] or b[h] != b[half[i - 1]]:
            new[i] = True
            if i > 0:
                if run == 1:
                    n_bound += 1
                else:
                    n_pairs += run * (run - 1) // 2 if run <= MAX_FAN else run
            run = 1
        else:
            new[i] = False
            run += 1
    if n:
        if run == 1:
            n_bound += 1
        else:
            n_pairs += run * (run - 1) // 2 if run <= MAX_FAN else run
    boundary = np.empty(n_bound, dtype=np.int64)
    lo = np.empty(n_pairs, dtype=half.dtype)
    hi = np.empty(n_pairs, dtype=half.dtype)
    tri = owner.shape[0] == 0
    ea = np.empty(n_pairs, dtype=a.dtype)
    eb = np.empty(n_pairs, dtype=a.dtype)
    nb = 0
    p = 0
    i = 0
    while i < n:  # fill
        j = i + 1
        while not new[j]:
            j += 1
        if j - i == 1:
            boundary[nb] = i
            nb += 1
        else:
            va = a[half[i]]
            vb = b[half[i]]
            for x in range(i, j):
                if j - i <= MAX_FAN:  # every later face
                    y0, y1 = x + 1, j
                else:  # the next face, the last with the first
                    y0 = x + 1 if x + 1 < j else i
                    y1 = y0 + 1
                for y in range(y0, y1):
                    f = half[x] // 3 if tri else owner[half[x]]
                    g = half[y] // 3 if tri else owner[half[y]]
                    if f != g:
                        lo[p] = min(f, g)
                        hi[p] = max(f, g)
                        ea[p] = va
                        eb[p] = vb
                        p += 1
        i = j
    if p < n_pairs:
        return boundary, lo[:p].copy(), hi[:p].copy(), ea[:p].copy(), eb[:p].copy()
    return boundary, lo, hi, ea, eb


@njit(cache=True, error_model="numpy", nogil=True)
def take_pairs(first, lo, hi, ka, kb, pairs, edges):
    """``pairs[t] = (lo[first[t]], hi[first[t]])`` and ``edges[t] = (ka[first[t]],
    kb[first[t]])``: the kept face pairs and their edges, in one pass (``pairs`` and
    ``edges`` are ``(len(first), 2)``)."""
    for t in range(first.shape[0]):
        u = first[t]
        pairs[t, 0] = lo[u]
        pairs[t, 1] = hi[u]
        edges[t, 0] = ka[u]
        edges[t, 1] = kb[u]


@njit(cache=True, error_model="numpy")
def shared_edges(faces, pairs, edges, check):
    """The mesh edge ``(a, b)``, ``a < b``, each pair of triangles ``pairs[t]`` shares:
    the two distinct vertices of the first face that the second has too, written to
    ``edges[t]`` (with ``check``: compared with it). Returns the pairs that do not share
    exactly two distinct vertices, or (``check``) whose edge differs."""
    bad = 0
    got = np.empty(3, dtype=np.int64)
    for t in range(pairs.shape[0]):
        i, j = pairs[t, 0], pairs[t, 1]
        k = 0
        for c in range(3):
            v = faces[i, c]
            twice = False
            for u in range(k):
                if got[u] == v:
                    twice = True
            if not twice and (faces[j, 0] == v or faces[j, 1] == v or faces[j, 2] == v):
                got[k] = v
                k += 1
        if k != 2:
            bad += 1
            continue
        a, b = min(got[0], got[1]), max(got[0], got[1])
        if check:
            if edges[t, 0] != a or edges[t, 1] != b:
                bad += 1
        else:
            edges[t, 0] = a
            edges[t, 1] = b
    return bad


@njit(cache=True, error_model="numpy")
def csr_of_face_pairs(lo, hi, ka, kb, n, indices, dual_edge):
    """The distinct pairs among ``(lo[t], hi[t])`` (``lo < hi < n``, repeats
    allowed) and their symmetric CSR, in one counting sort.

    Of a pair listed several times, the entry of smallest ``(ka[t], kb[t])``
    (then smallest ``t``) is kept. ``indices`` and ``dual_edge`` have room
    for ``2 len(lo)`` entries; the first ``2 e`` are filled (neighbours
    ascending per row, and the pair of each entry).

    Returns
    -------
    indptr : (n + 1,) int64 ndarray
    keep : (e,) int64 ndarray
        The entry ``t`` kept for each distinct pair, in ``(lo, hi)`` order
        (as a stable ``np.lexsort((kb, ka, lo * n + hi))`` keeping the first
        of each pair).
    """
    # every listed pair in both rows, rows by neighbour, stably (repeats adjacent, in t
    # order); then one entry per neighbour (the best t), compacted
    indptr = csr_of_pairs(lo, hi, n, indices, dual_edge)
    out = 0
    for v in range(n):
        s = indptr[v]
        f = indptr[v + 1]
        indptr[v] = out
        i = s
        while i < f:
            g = indices[i]
            best = dual_edge[i]
            j = i + 1
            while j < f and indices[j] == g:
                u = dual_edge[j]
                if ka[u] < ka[best] or (ka[u] == ka[best] and kb[u] < kb[best]):
                    best = u
                j += 1
            indices[out] = g
            dual_edge[out] = best
            out += 1
            i = j
    indptr[n] = out
    keep = np.empty(out // 2, dtype=np.int64)
    number_pairs(indptr, indices, n, dual_edge, keep, np.empty((0, 2), dtype=np.int64))
    return indptr, keep


@njit(cache=True, error_model="numpy")
def number_pairs(indptr, indices, n, dual_edge, keep, pairs):
    """Number the pairs of a symmetric CSR (rows ascending) in ``(lo, hi)`` order.

    Pair ``t`` is the ``t``-th entry ``(v, g)``, ``g > v``, in CSR order; both
    of its entries get ``dual_edge = t``. The mirror entries of a row (its
    neighbours below it) come first and ascending, in the order ids are given.
    If ``keep`` is not empty, ``keep[t]`` receives the value ``dual_edge`` had
    at the entry ``(v, g)``; if ``pairs`` is not empty, ``pairs[t] = (v, g)``.
    """
    mirror = indptr[:n].copy()
    nid = 0
    for v in range(n):
        for i in range(indptr[v], indptr[v + 1]):
            g = indices[i]
            if g > v:
                if keep.shape[0]:
                    keep[nid] = dual_edge[i]
                if pairs.shape[0]:
                    pairs[nid, 0] = v
                    pairs[nid, 1] = g
                dual_edge[i] = nid
                q = mirror[g]
                dual_edge[q] = nid
                mirror[g] = q + 1
                nid += 1


@njit(cache=True, error_model="numpy", parallel=True)
def knn_csr(nbr, keep, indptr, rows, more, more_keep):
    """The symmetric graph of k-nearest-neighbour lists: ``i ~ j`` when ``j`` is in
    ``nbr[i]`` (where ``keep``; everywhere when ``keep`` has no rows) or ``i`` in
    ``nbr[j]``, and likewise for the longer lists ``more[t]`` (where ``more_keep``) of the
    distinct points ``rows[t]`` (none: ``rows`` of length 0). Fills ``indptr`` (n + 1);
    returns a buffer whose first ``indptr[n]`` entries are ``indices`` (int32, ascending
    per row; the rest is undefined: the caller shrinks the buffer to them, in place where
    it can, once it has let the lists go): the layout :func:`csr_of_pairs` gives from the
    sorted distinct pairs (whose pairs and dual-edge map :func:`number_pairs` numbers
    from it). A point listed as its own neighbour is no edge."""
    n, k = nbr.shape
    all_kept = keep.shape[0] == 0
    count = np.zeros(n + 1, dtype=np.int64)
    for i in range(n):
        for c in range(k):
            if (all_kept or keep[i, c]) and nbr[i, c] != i:
                count[i + 1] += 1
                count[nbr[i, c] + 1] += 1
    for t in range(rows.shape[0]):
        for c in range(more.shape[1]):
            if more_keep[t, c] and more[t, c] != rows[t]:
                count[rows[t] + 1] += 1
                count[more[t, c] + 1] += 1
    for i in range(n):
        count[i + 1] += count[i]
    raw = np.empty(count[n], dtype=np.int32)
    fill = count[:n].copy()
    for i in range(n):
        for c in range(k):
            if (all_kept or keep[i, c]) and nbr[i, c] != i:
                j = nbr[i, c]
                raw[fill[i]] = j
                fill[i] += 1
                raw[fill[j]] = i
                fill[j] += 1
    for t in range(rows.shape[0]):
        i = rows[t]
        for c in range(more.shape[1]):
            if more_keep[t, c] and more[t, c] != i:
                j = more[t, c]
                raw[fill[i]] = j
                fill[i] += 1
                raw[fill[j]] = i
                fill[j] += 1
    kept = np.empty(n, dtype=np.int64)
    for i in prange(n):  # sort each row, drop repeats, in place (rows apart: in parallel)
        s, f = count[i], count[i + 1]
        for a in range(s + 1, f):
            x = raw[a]
            b = a - 1
            while b >= s and raw[b] > x:
                raw[b + 1] = raw[b]
                b -= 1
            raw[b + 1] = x
        m = 0
        for a in range(s, f):
            if m == 0 or raw[s + m - 1] != raw[a]:
                raw[s + m] = raw[a]
                m += 1
        kept[i] = m
    indptr[0] = 0
    for i in range(n):
        indptr[i + 1] = indptr[i] + kept[i]
    for i in range(n):  # rows moved left in place (indptr[i] <= count[i])
        s = count[i]
        for a in range(indptr[i + 1] - indptr[i]):
            raw[indptr[i] + a] = raw[s + a]
    return raw
