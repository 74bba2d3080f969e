"""Bounded expansions over the element graph and the merging of their records.

Private kernels of :mod:`superfacets.method.classify` (and :mod:`superfacets.method.initialization`
for the flood). The element graph is given as CSR arrays ``indptr`` (int64),
``indices`` (int32) and ``weights`` (float64, one per CSR entry). Buffers are
allocated once per run by the caller (:mod:`superfacets.method.expansion`):

- ``local`` (n,) float64: per-expansion tentative distances, stored negated
  (``-d``: the sign bit marks an element this expansion reached, ``-0.0`` its
  source), ``+0.0`` on every element between expansions (each expansion puts
  back ``+0.0`` on the elements it reached, which it lists anyway, so no O(n)
  array is reset per center and no per-element expansion id is kept). Zero
  bits between expansions: a buffer of zeros costs memory only where written,
  and its pages may be handed back between passes;
- ``queue``: the bucket queue of :func:`expand` (node pool and bucket heads,
  sized to the frontier of one expansion, grown by the caller on demand).

Nothing here checks its input.
"""

import numpy as np
from numba import njit

from superfacets._kernels.codes import MERGE, QUEUE_FULL, RECORD, RECORD_FULL, UNLABELLED  # noqa: F401

_INF = np.inf


@njit(cache=True, error_model="numpy", inline="always")
def queue_pop(qface, qdist, qnext, head, bmask, cur, free):
    """Take a node from the lowest non-empty bucket at or after ``cur``; it
    joins the free list. Returns ``(face, distance, node, cur)``."""
    b = cur & bmask
    while head[b] < 0:
        cur += 1
        b = cur & bmask
    n = head[b]
    head[b] = qnext[n]
    qnext[n] = free
    return qface[n], qdist[n], n, cur


@njit(cache=True, error_model="numpy", inline="always")
def queue_node(qnext, free, bump, qcap):
    """A node for a push: from the free list, else the next unused one.
    Returns ``(node, free, bump)``; node -1 when the pool is full."""
    if free >= 0:
        return free, qnext[free], bump
    if bump < qcap:
        return bump, free, bump + 1
    return -1, free, bump


@njit(cache=True, error_model="numpy", inline="always")
def queue_push(qface, qdist, qnext, head, bmask, n, g, nd, inv_width, cur):
    """Put node ``n`` (face ``g`` at distance ``nd``) in its bucket (never below ``cur``)."""
    i = np.int64(nd * inv_width)
    if i < cur:
        i = cur
    b = i & bmask
    qface[n] = g
    qdist[n] = nd
    qnext[n] = head[b]
    head[b] = n


@njit(cache=True, error_model="numpy", inline="always")
def window_of(window_r2, wscale, f):
    """The squared window of an expansion from face ``f``: ``window_r2``, times
    ``wscale[f]`` where ``wscale`` is not empty (content-sensitive runs: a
    center's window scaled by ``1 / s^2`` of its element, :mod:`superfacets.elements.density`)."""
    if wscale.shape[0] > 0:
        return window_r2 * wscale[f]
    return window_r2


@njit(cache=True, error_model="numpy", nogil=True)
def expand(indptr, indices, weights, centroids, src, lab, window_r2,
           dist, label, local, queue, inv_width, mode, vis_face, vis_dist, pos, lim):
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

    ``local``: per-face scratch, ``+0.0`` everywhere on entry and again on
    return, ``-distance`` (sign bit set, ``-0.0`` for the source) for the faces this
    expansion reached (a face is first reached when its ``local`` has no sign bit; a face
    outside the window, or labelled in ``UNLABELLED`` mode, is tested again
    each time it is reached and never entered).
    ``queue = (qface, qdist, qnext, head)``: node pool and bucket heads.
    Returns the new ``pos``, or :data:`RECORD_FULL` / :data:`QUEUE_FULL`
    (the caller grows that array and starts over).
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
    local[src] = -0.0
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
        f, d, free, cur = queue_pop(qface, qdist, qnext, head, bmask, cur, free)
        live -= 1
        if d > -local[f]:
            continue  # stale: queued again since with a lower distance
        for e in range(indptr[f], indptr[f + 1]):
            g = indices[e]
            nd = d + weights[e]
            lg = local[g]
            if not np.signbit(lg):  # not reached yet by this expansion
                dx = centroids[g, 0] - cx
                dy = centroids[g, 1] - cy
                dz = centroids[g, 2] - cz
                if dx * dx + dy * dy + dz * dz > window_r2 or (only_unlabelled and label[g] >= 0):
                    continue  # outside this window: never entered
                if pos >= lim:
                    status = RECORD_FULL
                    break
                vis_face[pos] = g
                pos += 1
            elif not nd < -lg:
                continue
            local[g] = -nd
            n, free, bump = queue_node(qnext, free, bump, qcap)
            if n < 0:
                status = QUEUE_FULL
                break
            queue_push(qface, qdist, qnext, head, bmask, n, g, nd, inv_width, cur)
            live += 1
        if status != 0:
            for b in range(nb):
                head[b] = -1
            for j in range(start, pos):
                local[vis_face[j]] = 0.0
            return status
    if vis_dist.shape[0] > 0:
        for j in range(start, pos):
            vis_dist[j] = -local[vis_face[j]]
    if mode == MERGE:
        for j in range(start, pos):
            f = vis_face[j]
            d = -local[f]
            if d < dist[f]:
                dist[f] = d
                label[f] = lab
    elif only_unlabelled:
        for j in range(start, pos):
            label[vis_face[j]] = lab
    for j in range(start, pos):
        local[vis_face[j]] = 0.0
    return pos


@njit(cache=True, error_model="numpy", nogil=True)
def classify_bounded(indptr, indices, weights, centroids, centers, n_centers, window_r2,
                     dist, label, local, queue, inv_width, vis, wscale):
    """Classification step of the paper (section 3.1) with orphan re-seeding.

    The straightforward version: runs :func:`expand` from
    ``centers[0:n_centers]`` in order (label = index of the center), then,
    scanning faces in index order, seeds a new center on each face still
    unlabelled (an orphan) and expands it, appending it to ``centers``.
    Returns ``K``, the number of centers now in use, or a negative status of
    :func:`expand` if ``queue`` or the visit buffer ``vis`` was too small.
    ``wscale``: per-face window factors (:func:`window_of`), or empty.
    """
    m = label.shape[0]
    nod = np.empty(0)
    lim = vis.shape[0]
    for f in range(m):
        dist[f] = _INF
        label[f] = -1
    for s in range(n_centers):
        st = expand(indptr, indices, weights, centroids, centers[s], s,
                    window_of(window_r2, wscale, centers[s]),
                    dist, label, local, queue, inv_width, MERGE, vis, nod, 0, lim)
        if st < 0:
            return st
    k = n_centers
    for f in range(m):
        if label[f] < 0:
            centers[k] = f
            st = expand(indptr, indices, weights, centroids, f, k, window_of(window_r2, wscale, f),
                        dist, label, local, queue, inv_width, MERGE, vis, nod, 0, lim)
            if st < 0:
                return st
            k += 1
    return k


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
def expand_many(indptr, indices, weights, centroids, srcs, labs, window_r2, local, queue,
                inv_width, rec_face, rec_dist, pos, lim, out_start, out_len, dist, label,
                wscale):
    """Record-only expansions (:data:`RECORD`) of the faces ``srcs``, each
    merged right after (while in cache) into ``dist``/``label`` with label
    ``labs[i]`` by the lexicographic rule of :func:`merge_some`.

    The settled faces and distances of expansion ``i`` go to ``rec_face`` /
    ``rec_dist`` from ``out_start[i] = pos`` onwards
    (``out_len[i]`` entries), below ``lim``. Releases the GIL, so several
    threads may run it at once on disjoint record ranges with their own
    ``local``, queue and ``dist``/``label``. Empty ``dist``/``label``: records
    only, merged later (:func:`merge_some`). ``wscale``: per-face window
    factors (:func:`window_of`), or empty. Returns the end
    position, or a negative status of :func:`expand`.
    """
    nod = np.empty(0)
    nol = np.empty(0, dtype=np.int32)  # the type of the real labels: one compiled expand
    for i in range(srcs.shape[0]):
        out_start[i] = pos
        p = expand(indptr, indices, weights, centroids, srcs[i], 0,
                   window_of(window_r2, wscale, srcs[i]), nod, nol,
                   local, queue, inv_width, RECORD, rec_face, rec_dist, pos, lim)
        if p < 0:
            return p
        out_len[i] = p - pos
        if dist.shape[0]:
            _merge_segment(pos, p - pos, labs[i], rec_face, rec_dist, dist, label)
        pos = p
    return pos


@njit(cache=True, error_model="numpy", nogil=True)
def merge_some(labs, seg_start, seg_len, rec_face, rec_dist, dist, label):
    """Merge the records of the centers ``labs`` into ``dist``/``label``.

    Face ``f`` of the record of center ``s`` takes label ``s`` when ``(d, s)``
    is lexicographically below ``(dist[f], label[f])``. Since the center of
    lowest index wins ties, merging every record this way, in any order,
    gives the labelling of :func:`classify_bounded`
    (centers in order, strict ``<``).
    """
    for i in range(labs.shape[0]):
        s = labs[i]
        _merge_segment(seg_start[s], seg_len[s], s, rec_face, rec_dist, dist, label)


@njit(cache=True, error_model="numpy", nogil=True)
def unset_owned(labs, seg_start, seg_len, rec_face, dist, label):
    """Unlabel (``dist = inf``, ``label = -1``) every face that the record of
    center ``s`` (for ``s`` in ``labs``) labels ``s``: the faces that lose their
    center when ``s`` moves."""
    for i in range(labs.shape[0]):
        s = labs[i]
        for e in range(seg_start[s], seg_start[s] + seg_len[s]):
            f = rec_face[e]
            if label[f] == s:
                dist[f] = _INF
                label[f] = -1


@njit(cache=True, error_model="numpy", nogil=True)
def reset_labels(dist, label):
    """``dist = inf``, ``label = -1`` (records have finite distances, so the
    label of an unreached face never takes part in a comparison)."""
    for f in range(dist.shape[0]):
        dist[f] = _INF
        label[f] = -1


@njit(cache=True, error_model="numpy", nogil=True)
def seed_orphans(indptr, indices, weights, centroids, centers, n_centers, window_r2,
                 dist, label, local, queue, inv_width, rec_face, rec_dist, pos, lim,
                 seg_start, seg_len, wscale):
    """Orphan re-seeding of :func:`classify_bounded`, recording the expansions.

    Scanning faces in index order, seeds a center on each face still
    unlabelled, expands it (:data:`MERGE`) and records it from ``pos`` like
    :func:`expand_many` (``seg_start``/``seg_len`` indexed by center).
    Returns ``(status, K)``: ``status`` is the end position or a negative
    status of :func:`expand`.
    """
    m = label.shape[0]
    k = n_centers
    for f in range(m):
        if label[f] < 0:
            centers[k] = f
            seg_start[k] = pos
            p = expand(indptr, indices, weights, centroids, f, k, window_of(window_r2, wscale, f),
                       dist, label, local, queue, inv_width, MERGE, rec_face, rec_dist, pos, lim)
            if p < 0:
                return p, k
            seg_len[k] = p - pos
            pos = p
            k += 1
    return pos, k


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
