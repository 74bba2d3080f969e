"""numba kernels: contiguous arrays and scalars in, preallocated arrays out.

Private. Glue modules (``seeding``, ``segment``) validate and prepare the
arrays; nothing here checks its input. The face graph is given as CSR arrays
``indptr`` (int64), ``indices`` (int32) and ``weights`` (float64, one per CSR
entry). Buffers are allocated once per run by the caller:

- ``local`` (m,) float64 and ``stamp`` (m,) int32: per-expansion tentative
  distances, valid only where ``stamp[f] == sid`` (the id of the current
  expansion), so no O(m) array is reset per center; ``stamp`` starts at -1
  and each expansion gets a fresh ``sid``;
- ``queue``: the bucket queue of :func:`expand` (node pool and bucket heads,
  sized to the frontier of one expansion, grown by the caller on demand);
- ``hkey`` (float64) / ``hval`` (int32 or int64): a binary min-heap with lazy
  deletion, for the multi-source search of :func:`classify_exact` (capacity
  ``len(indices) + m + 1``: a face is pushed again only on a strict decrease).
"""

import numpy as np
from numba import njit

_INF = np.inf


@njit(cache=True, error_model="numpy", inline="always")
def _push(hkey, hval, size, key, val):
    i = size
    while i > 0:
        p = (i - 1) >> 1
        if hkey[p] <= key:
            break
        hkey[i] = hkey[p]
        hval[i] = hval[p]
        i = p
    hkey[i] = key
    hval[i] = val
    return size + 1


@njit(cache=True, error_model="numpy", inline="always")
def _pop(hkey, hval, size):
    """Remove the root (read it before calling); return the new size."""
    size -= 1
    if size == 0:
        return 0
    key = hkey[size]
    val = hval[size]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= size:
            break
        if c + 1 < size and hkey[c + 1] < hkey[c]:
            c += 1
        if hkey[c] >= key:
            break
        hkey[i] = hkey[c]
        hval[i] = hval[c]
        i = c
    hkey[i] = key
    hval[i] = val
    return size


#: ``mode`` of :func:`expand`: label faces that get a strictly lower distance
MERGE = 0
#: ``mode`` of :func:`expand`: enter and label only faces without a label
UNLABELLED = 1
#: ``mode`` of :func:`expand`: touch neither ``dist`` nor ``label``, only record
RECORD = 2
#: status returned when the visit/record arrays are full
RECORD_FULL = -1
#: status returned when the queue is full
QUEUE_FULL = -2


@njit(cache=True, error_model="numpy", nogil=True)
def expand(indptr, indices, weights, centroids, src, lab, window_r2,
           dist, label, local, stamp, sid, queue, inv_width, mode,
           vis_face, vis_dist, pos, lim):
    """Bounded shortest-path expansion from face ``src`` with label ``lab``.

    Only faces whose centroid lies within ``sqrt(window_r2)`` of the centroid
    of ``src`` are reached; the distances are those of Dijkstra's algorithm
    on the faces of that window connected to ``src`` through it.

    The search is label-correcting with a bucket queue (sequential
    delta-stepping): a face waits in bucket ``floor(d * inv_width)`` of a
    circular array and the lowest non-empty bucket is processed in any
    order, a face being queued again whenever its distance strictly
    decreases. The result is exact for any bucket width: each distance is the
    minimum over the face's neighbours of ``d(neighbour) + w`` (the same
    floating-point sums as Dijkstra's), whatever the order. With a width
    below the typical edge weight almost no face is processed twice, and no
    heap is needed (Dijkstra's binary heap cost three quarters of the time).
    The circular array must have more than ``max(weights) * inv_width + 1``
    buckets, all empty (-1) on entry; they are empty again on return.

    Every face reached (inside the window, connected) is appended once to
    ``vis_face`` from index ``pos`` (below ``lim``), and, if ``vis_dist`` is
    not empty, its final distance to ``vis_dist``. Then, by ``mode``:
    :data:`MERGE`: a reached face takes ``lab`` and its distance when that
    distance is lower than ``dist[f]`` (strictly: earlier expansions win
    ties); :data:`UNLABELLED`: the expansion neither enters nor counts
    faces that already have a label (``label >= 0``) and labels the others
    ``lab``, ignoring ``dist``; :data:`RECORD`: neither ``dist`` nor
    ``label`` is read or written, so the expansion depends on its face alone.

    ``local``/``stamp``: per-face scratch, valid where ``stamp == sid``.
    ``queue = (qface, qdist, qnext, head)``: node pool and bucket heads.
    Returns the new ``pos``, or :data:`RECORD_FULL` / :data:`QUEUE_FULL`
    (the caller grows that array and starts over with a fresh ``sid``).
    """
    qface, qdist, qnext, head = queue
    qcap = qface.shape[0]
    nb = head.shape[0]
    bmask = nb - 1
    cx = centroids[src, 0]
    cy = centroids[src, 1]
    cz = centroids[src, 2]
    only_unlabelled = mode == UNLABELLED
    start = pos
    if pos >= lim:
        return RECORD_FULL
    stamp[src] = sid
    local[src] = 0.0
    vis_face[pos] = src
    pos += 1
    qface[0] = src
    qdist[0] = 0.0
    qnext[0] = -1
    head[0] = 0
    free = -1
    bump = 1
    live = 1
    cur = 0
    status = 0
    while live > 0:
        b = cur & bmask
        while head[b] < 0:
            cur += 1
            b = cur & bmask
        n = head[b]
        head[b] = qnext[n]
        f = qface[n]
        d = qdist[n]
        qnext[n] = free
        free = n
        live -= 1
        if d > local[f]:
            continue  # stale: queued again since with a lower distance
        for e in range(indptr[f], indptr[f + 1]):
            g = indices[e]
            nd = d + weights[e]
            if stamp[g] != sid:
                stamp[g] = sid
                dx = centroids[g, 0] - cx
                dy = centroids[g, 1] - cy
                dz = centroids[g, 2] - cz
                if dx * dx + dy * dy + dz * dz > window_r2 or (only_unlabelled and label[g] >= 0):
                    local[g] = -1.0  # outside this window: never entered
                    continue
                if pos >= lim:
                    status = RECORD_FULL
                    break
                vis_face[pos] = g
                pos += 1
            elif not nd < local[g]:  # local == -1 (outside) never passes
                continue
            local[g] = nd
            if free >= 0:
                n = free
                free = qnext[n]
            elif bump < qcap:
                n = bump
                bump += 1
            else:
                status = QUEUE_FULL
                break
            i = np.int64(nd * inv_width)
            if i < cur:
                i = cur
            b = i & bmask
            qface[n] = g
            qdist[n] = nd
            qnext[n] = head[b]
            head[b] = n
            live += 1
        if status != 0:
            for b in range(nb):
                head[b] = -1
            return status
    if vis_dist.shape[0] > 0:
        for j in range(start, pos):
            vis_dist[j] = local[vis_face[j]]
    if mode == MERGE:
        for j in range(start, pos):
            f = vis_face[j]
            d = local[f]
            if d < dist[f]:
                dist[f] = d
                label[f] = lab
    elif only_unlabelled:
        for j in range(start, pos):
            label[vis_face[j]] = lab
    return pos


@njit(cache=True, error_model="numpy", nogil=True)
def classify_bounded(indptr, indices, weights, centroids, centers, n_centers, window_r2,
                     dist, label, local, stamp, sid, queue, inv_width, vis):
    """Classification step of the paper (section 3.1) with orphan re-seeding.

    The straightforward version: runs :func:`expand` from
    ``centers[0:n_centers]`` in order (label = index of the center), then,
    scanning faces in index order, seeds a new center on each face still
    unlabelled (an orphan) and expands it, appending it to ``centers``.
    Returns ``(K, next_sid)``: the number of centers now in use and the next
    free expansion id; ``K`` is a negative status of :func:`expand` if
    ``queue`` or the visit buffer ``vis`` was too small.
    """
    m = label.shape[0]
    nod = np.empty(0)
    lim = vis.shape[0]
    for f in range(m):
        dist[f] = _INF
        label[f] = -1
    for s in range(n_centers):
        st = expand(indptr, indices, weights, centroids, centers[s], s, window_r2,
                    dist, label, local, stamp, sid, queue, inv_width, MERGE, vis, nod, 0, lim)
        sid += 1
        if st < 0:
            return st, sid
    k = n_centers
    for f in range(m):
        if label[f] < 0:
            centers[k] = f
            st = expand(indptr, indices, weights, centroids, f, k, window_r2,
                        dist, label, local, stamp, sid, queue, inv_width, MERGE, vis, nod, 0,
                        lim)
            sid += 1
            if st < 0:
                return st, sid
            k += 1
    return k, sid


@njit(cache=True, error_model="numpy", inline="always")
def _merge_segment(a, n, s, rec_face, rec_dist, dist, label):
    """Faces of a record take label ``s`` where ``(d, s)`` is lexicographically
    below their ``(dist, label)``: the center of lowest index wins ties, so
    records may be merged in any order with the result of merging them in
    center order with a strict ``<``."""
    for e in range(a, a + n):
        f = rec_face[e]
        d = rec_dist[e]
        if d < dist[f] or (d == dist[f] and s < label[f]):
            dist[f] = d
            label[f] = s


@njit(cache=True, error_model="numpy", nogil=True)
def expand_many(indptr, indices, weights, centroids, srcs, labs, window_r2, local, stamp,
                sid0, queue, inv_width, rec_face, rec_dist, pos, lim, out_start, out_len,
                dist, label):
    """Record-only expansions (:data:`RECORD`) of the faces ``srcs``, each
    merged right after (while in cache) into ``dist``/``label`` with label
    ``labs[i]`` by the lexicographic rule of :func:`merge_some`.

    Expansion ``i`` gets id ``sid0 + i``; its settled faces and distances go
    to ``rec_face`` / ``rec_dist`` from ``out_start[i] = pos`` onwards
    (``out_len[i]`` entries), below ``lim``. Releases the GIL, so several
    threads may run it at once on disjoint record ranges with their own
    ``local``, ``stamp``, queue and ``dist``/``label``. Returns the end
    position, or a negative status of :func:`expand`.
    """
    nod = np.empty(0)
    nol = np.empty(0, dtype=np.int32)  # the type of the real labels: one compiled expand
    for i in range(srcs.shape[0]):
        out_start[i] = pos
        p = expand(indptr, indices, weights, centroids, srcs[i], 0, window_r2, nod, nol,
                   local, stamp, sid0 + i, queue, inv_width, RECORD, rec_face, rec_dist, pos,
                   lim)
        if p < 0:
            return p
        out_len[i] = p - pos
        _merge_segment(pos, p - pos, labs[i], rec_face, rec_dist, dist, label)
        pos = p
    return pos


@njit(cache=True, error_model="numpy", nogil=True)
def merge_some(labs, seg_start, seg_len, rec_face, rec_dist, dist, label):
    """Merge the records of the centers ``labs`` into ``dist``/``label``.

    Face ``f`` of the record of center ``s`` takes label ``s`` when ``(d, s)``
    is lexicographically below ``(dist[f], label[f])``. Since the center of
    lowest index wins ties, merging every record this way, in any order and
    split over any number of ``dist``/``label`` pairs combined by
    :func:`combine_merged`, gives the labelling of :func:`classify_bounded`
    (centers in order, strict ``<``).
    """
    for i in range(labs.shape[0]):
        s = labs[i]
        _merge_segment(seg_start[s], seg_len[s], s, rec_face, rec_dist, dist, label)


@njit(cache=True, error_model="numpy", nogil=True)
def reset_labels(dist, label):
    """``dist = inf``, ``label = -1`` (records have finite distances, so the
    label of an unreached face never takes part in a comparison)."""
    for f in range(dist.shape[0]):
        dist[f] = _INF
        label[f] = -1


@njit(cache=True, error_model="numpy", nogil=True)
def combine_merged(dist, label, dist2, label2, lo, hi):
    """Faces ``lo <= f < hi`` keep the lexicographic minimum of ``(dist, label)``
    and ``(dist2, label2)``."""
    for f in range(lo, hi):
        d = dist2[f]
        if d < dist[f] or (d == dist[f] and label2[f] < label[f]):
            dist[f] = d
            label[f] = label2[f]


@njit(cache=True, error_model="numpy", nogil=True)
def seed_orphans(indptr, indices, weights, centroids, centers, n_centers, window_r2,
                 dist, label, local, stamp, sid, queue, inv_width, rec_face, rec_dist, pos,
                 lim, seg_start, seg_len):
    """Orphan re-seeding of :func:`classify_bounded`, recording the expansions.

    Scanning faces in index order, seeds a center on each face still
    unlabelled, expands it (:data:`MERGE`) and records it from ``pos`` like
    :func:`expand_many` (``seg_start``/``seg_len`` indexed by center).
    Returns ``(status, K, next_sid)``: ``status`` is the end position or a
    negative status of :func:`expand`.
    """
    m = label.shape[0]
    k = n_centers
    for f in range(m):
        if label[f] < 0:
            centers[k] = f
            seg_start[k] = pos
            p = expand(indptr, indices, weights, centroids, f, k, window_r2, dist, label,
                       local, stamp, sid, queue, inv_width, MERGE, rec_face, rec_dist, pos, lim)
            sid += 1
            if p < 0:
                return p, k, sid
            seg_len[k] = p - pos
            pos = p
            k += 1
    return pos, k, sid


@njit(cache=True, error_model="numpy", nogil=True)
def compact_records(order, seg_start, seg_len, rec_face, rec_dist):
    """Move the given record segments to the front, in order of their start.

    ``order`` lists the segments by increasing start (``np.argsort`` of
    ``seg_start``); segments must not overlap. Updates ``seg_start`` in place
    and returns the end of the last one.
    """
    w = 0
    for j in range(order.shape[0]):
        i = order[j]
        a = seg_start[i]
        n = seg_len[i]
        if a != w:
            for e in range(n):  # w < a: a forward copy never overwrites unread data
                rec_face[w + e] = rec_face[a + e]
                rec_dist[w + e] = rec_dist[a + e]
        seg_start[i] = w
        w += n
    return w


@njit(cache=True, error_model="numpy")
def _multi_source(indptr, indices, weights, dist, label, hkey, hval, size):
    while size > 0:
        d = hkey[0]
        f = hval[0]
        size = _pop(hkey, hval, size)
        if d > dist[f]:
            continue
        lf = label[f]
        for e in range(indptr[f], indptr[f + 1]):
            g = indices[e]
            nd = d + weights[e]
            if nd < dist[g]:
                dist[g] = nd
                label[g] = lf
                size = _push(hkey, hval, size, nd, g)


@njit(cache=True, error_model="numpy")
def classify_exact(indptr, indices, weights, centers, n_centers, dist, label, hkey, hval):
    """Exact nearest-center assignment: one multi-source Dijkstra, no bound.

    Every face gets the label of the center at the smallest face-graph
    distance (ties: the center settled first). Faces of connected components
    without a center are re-seeded like orphans (first unreached face, in
    index order). Returns the number of centers ``K``.
    """
    m = label.shape[0]
    for f in range(m):
        dist[f] = _INF
        label[f] = -1
    size = 0
    for s in range(n_centers):
        c = centers[s]
        if dist[c] > 0.0:  # a second center on the same face stays empty
            dist[c] = 0.0
            label[c] = s
            size = _push(hkey, hval, size, 0.0, c)
    _multi_source(indptr, indices, weights, dist, label, hkey, hval, size)
    k = n_centers
    for f in range(m):
        if label[f] < 0:
            centers[k] = f
            dist[f] = 0.0
            label[f] = k
            size = _push(hkey, hval, 0, 0.0, f)
            _multi_source(indptr, indices, weights, dist, label, hkey, hval, size)
            k += 1
    return k


@njit(cache=True, error_model="numpy")
def update_centers(label, k, areas, centroids, old_centers, new_centers):
    """Center update of the paper (section 3.1).

    For each superfacet ``s < k``: the area-weighted mean of its face
    centroids (plain mean if its area is zero), then the face of ``s`` whose
    centroid is nearest to that mean; the old center stays on ties, else the
    lowest face index wins. Writes ``new_centers[s]``, -1 for an empty
    superfacet.
    """
    m = label.shape[0]
    sums = np.zeros((k, 3))
    plain = np.zeros((k, 3))
    wsum = np.zeros(k)
    cnt = np.zeros(k, dtype=np.int64)
    for f in range(m):
        s = label[f]
        a = areas[f]
        for t in range(3):
            sums[s, t] += a * centroids[f, t]
            plain[s, t] += centroids[f, t]
        wsum[s] += a
        cnt[s] += 1
    for s in range(k):
        if wsum[s] > 0.0:
            for t in range(3):
                sums[s, t] /= wsum[s]
        elif cnt[s] > 0:
            for t in range(3):
                sums[s, t] = plain[s, t] / cnt[s]
    best = np.full(k, _INF)
    for s in range(k):
        new_centers[s] = -1
        c = old_centers[s]
        if c >= 0 and label[c] == s:
            d = 0.0
            for t in range(3):
                x = centroids[c, t] - sums[s, t]
                d += x * x
            best[s] = d
            new_centers[s] = c
    for f in range(m):
        s = label[f]
        d = 0.0
        for t in range(3):
            x = centroids[f, t] - sums[s, t]
            d += x * x
        if d < best[s]:
            best[s] = d
            new_centers[s] = f


@njit(cache=True, error_model="numpy", inline="always")
def _nearest_so_far(centroids, mind, f, cx, cy, cz):
    """Lower ``mind[f]`` to the squared distance from the centroid of ``f`` to
    ``(cx, cy, cz)`` if nearer; return it (negative: ``f`` is a center)."""
    mf = mind[f]
    if mf < 0.0:
        return mf
    dx = centroids[f, 0] - cx
    dy = centroids[f, 1] - cy
    dz = centroids[f, 2] - cz
    d = dx * dx + dy * dy + dz * dz
    if d < mf:
        mind[f] = d
        return d
    return mf


@njit(cache=True, error_model="numpy")
def farthest_point(centroids, k, first, out):
    """Iterative farthest point sampling in O(m k) with a running minimum.

    ``out[0] = first``; each next entry is the face whose centroid has the
    largest Euclidean distance to its nearest chosen center (ties: lowest
    index). A chosen face is never chosen again.
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
            mf = _nearest_so_far(centroids, mind, f, cx, cy, cz)
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
def farthest_point_blocked(centroids, k, first, out, order, bstart, bcenter, bradius):
    """:func:`farthest_point`, skipping the blocks a new center cannot change.

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
        mind[cur] = -1.0
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
                if lb > 0.0 and lb * lb >= bmax[b]:
                    continue  # every face is at least as near to an earlier center
            best = -1.0
            arg = m
            for j in range(bstart[b], bstart[b + 1]):
                f = order[j]
                mf = _nearest_so_far(centroids, mind, f, cx, cy, cz)
                if mf < 0.0:
                    continue
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


@njit(cache=True, error_model="numpy", nogil=True)
def flood(indptr, indices, weights, centroids, order, window_r2, label, local, stamp, sid,
          queue, inv_width, vis):
    """Flood initialization (authors' implementation).

    Faces are visited in ``order`` (by Euclidean distance to the first seed);
    each face still unlabelled starts a new region, grown by a bounded
    expansion that claims only unlabelled faces. Returns ``(n_regions,
    next_sid)``; ``n_regions`` is a negative status of :func:`expand` if
    ``queue`` or the visit buffer ``vis`` was too small.
    """
    m = label.shape[0]
    for f in range(m):
        label[f] = -1
    dummy = np.empty(0)
    n = 0
    for i in range(order.shape[0]):
        f = order[i]
        if label[f] < 0:
            st = expand(indptr, indices, weights, centroids, f, n, window_r2, dummy, label,
                        local, stamp, sid, queue, inv_width, UNLABELLED, vis, dummy, 0,
                        vis.shape[0])
            sid += 1
            if st < 0:
                return st, sid
            n += 1
    return n, sid


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
        norm = np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
        areas[f] = 0.5 * norm
        if norm > 0:
            normals[f, 0] = c0 / norm
            normals[f, 1] = c1 / norm
            normals[f, 2] = c2 / norm
        else:
            normals[f, 0] = 0.0
            normals[f, 1] = 0.0
            normals[f, 2] = 0.0
