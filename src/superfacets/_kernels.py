"""numba kernels: contiguous arrays and scalars in, preallocated arrays out.

Private. Glue modules (``seeding``, ``segment``) validate and prepare the
arrays; nothing here checks its input. The face graph is given as CSR arrays
``indptr`` (int64), ``indices`` (int32) and ``weights`` (float64, one per CSR
entry). Buffers are allocated once per run by the caller:

- ``local`` (m,) float64 and ``stamp`` (m,) int64: per-expansion tentative
  distances, valid only where ``stamp[f] == sid`` (the id of the current
  expansion), so no O(m) array is reset per center; ``stamp`` starts at -1
  and each expansion of a run gets a fresh ``sid``;
- ``hkey`` (float64) / ``hval`` (int64) of capacity ``len(indices) + m + 1``:
  a binary min-heap with lazy deletion (a face is pushed again only on a
  strict decrease of its tentative distance, which bounds the pushes).
"""

import numpy as np
from numba import njit

_INF = np.inf


@njit(cache=True, inline="always")
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


@njit(cache=True, inline="always")
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


@njit(cache=True)
def expand(indptr, indices, weights, centroids, src, lab, window_r2,
           dist, label, local, stamp, sid, hkey, hval, only_unlabelled,
           rec_face, rec_dist, pos):
    """Bounded Dijkstra expansion from face ``src`` with label ``lab``.

    Only faces whose centroid lies within ``sqrt(window_r2)`` of the centroid
    of ``src`` are reached (labelled and expanded); the expansion is an exact
    Dijkstra on the faces of that window connected to ``src`` through it.
    A settled face takes ``lab`` and its distance when that distance is lower
    than ``dist[f]`` (strictly: earlier expansions win ties). With
    ``only_unlabelled`` the expansion neither enters nor labels faces that
    already have a label (``label >= 0``) and ignores ``dist``.

    The traversal never reads ``dist``/``label`` (except with
    ``only_unlabelled``), so the expansion of a center depends on its face
    alone. Settled faces and their distances are appended to ``rec_face`` /
    ``rec_dist`` from index ``pos`` (pass empty arrays to record nothing).
    Returns the new ``pos``, or -1 if the record arrays are too small.
    """
    cx = centroids[src, 0]
    cy = centroids[src, 1]
    cz = centroids[src, 2]
    stamp[src] = sid
    local[src] = 0.0
    size = _push(hkey, hval, 0, 0.0, src)
    record = rec_face.shape[0] > 0
    cap = rec_face.shape[0]
    while size > 0:
        d = hkey[0]
        f = hval[0]
        size = _pop(hkey, hval, size)
        if d > local[f]:
            continue  # stale heap entry
        if record:
            if pos < 0 or pos >= cap:
                pos = -1
            else:
                rec_face[pos] = f
                rec_dist[pos] = d
                pos += 1
        if only_unlabelled:
            label[f] = lab
        elif d < dist[f]:
            dist[f] = d
            label[f] = lab
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
                local[g] = nd
                size = _push(hkey, hval, size, nd, g)
            elif nd < local[g]:  # local == -1 (outside) never passes
                local[g] = nd
                size = _push(hkey, hval, size, nd, g)
    return pos


@njit(cache=True)
def classify_bounded(indptr, indices, weights, centroids, centers, n_centers, window_r2,
                     dist, label, local, stamp, sid, hkey, hval):
    """Classification step of the paper (section 3.1) with orphan re-seeding.

    Runs :func:`expand` from ``centers[0:n_centers]`` in order (label = index
    of the center), then, scanning faces in index order, seeds a new center
    on each face still unlabelled (an orphan) and expands it, appending it to
    ``centers``. Returns ``(K, next_sid)``: the number of centers now in use
    and the next free expansion id.
    """
    m = label.shape[0]
    norec_f = np.empty(0, dtype=np.int32)
    norec_d = np.empty(0, dtype=np.float64)
    for f in range(m):
        dist[f] = _INF
        label[f] = -1
    for s in range(n_centers):
        expand(indptr, indices, weights, centroids, centers[s], s, window_r2,
               dist, label, local, stamp, sid, hkey, hval, False, norec_f, norec_d, 0)
        sid += 1
    k = n_centers
    for f in range(m):
        if label[f] < 0:
            centers[k] = f
            expand(indptr, indices, weights, centroids, f, k, window_r2,
                   dist, label, local, stamp, sid, hkey, hval, False, norec_f, norec_d, 0)
            sid += 1
            k += 1
    return k, sid


@njit(cache=True)
def classify_incremental(indptr, indices, weights, centroids, centers, n_centers, window_r2,
                         dist, label, local, stamp, sid, hkey, hval,
                         prev_centers, prev_off, prev_face, prev_dist, slot,
                         new_off, new_face, new_dist):
    """:func:`classify_bounded` with the expansions of unmoved centers replayed.

    Gives exactly the labels and distances of :func:`classify_bounded`: each
    center's expansion depends on its face only, so for a center whose face
    was also a center in the previous pass (``prev_centers``, with its
    settled faces in ``prev_face[prev_off[i]:prev_off[i + 1]]``) the recorded
    faces are replayed through the same strict ``<`` update, in the same
    center order; other centers (and orphans) are expanded anew. Every
    center's list is written to ``new_off`` / ``new_face`` / ``new_dist``
    for the next pass. ``slot`` is an (m,) int64 scratch array of -1, left
    as it was found.

    Returns ``(K, next_sid, n_expanded)``, or ``(-1, sid, 0)`` if the new
    record arrays are too small (the caller grows them and calls again).
    """
    m = label.shape[0]
    for f in range(m):
        dist[f] = _INF
        label[f] = -1
    for i in range(prev_centers.shape[0]):
        slot[prev_centers[i]] = i
    pos = 0
    n_expanded = 0
    new_off[0] = 0
    for s in range(n_centers):
        c = centers[s]
        i = slot[c]
        if i >= 0:
            a = prev_off[i]
            b = prev_off[i + 1]
            if pos + (b - a) > new_face.shape[0]:
                pos = -1
                break
            for e in range(a, b):
                f = prev_face[e]
                d = prev_dist[e]
                new_face[pos] = f
                new_dist[pos] = d
                pos += 1
                if d < dist[f]:
                    dist[f] = d
                    label[f] = s
        else:
            pos = expand(indptr, indices, weights, centroids, c, s, window_r2,
                         dist, label, local, stamp, sid, hkey, hval, False,
                         new_face, new_dist, pos)
            sid += 1
            n_expanded += 1
            if pos < 0:
                break
        new_off[s + 1] = pos
    for i in range(prev_centers.shape[0]):
        slot[prev_centers[i]] = -1
    if pos < 0:
        return -1, sid, 0
    k = n_centers
    for f in range(m):
        if label[f] < 0:
            if k + 1 >= new_off.shape[0]:
                return -1, sid, 0
            centers[k] = f
            pos = expand(indptr, indices, weights, centroids, f, k, window_r2,
                         dist, label, local, stamp, sid, hkey, hval, False,
                         new_face, new_dist, pos)
            sid += 1
            n_expanded += 1
            if pos < 0:
                return -1, sid, 0
            k += 1
            new_off[k] = pos
    return k, sid, n_expanded


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
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
            mf = mind[f]
            if mf < 0.0:
                continue
            dx = centroids[f, 0] - cx
            dy = centroids[f, 1] - cy
            dz = centroids[f, 2] - cz
            d = dx * dx + dy * dy + dz * dz
            if d < mf:
                mf = d
                mind[f] = d
            if mf > best:
                best = mf
                nxt = f
        cur = nxt


@njit(cache=True)
def flood(indptr, indices, weights, centroids, order, window_r2, label, local, stamp, sid,
          hkey, hval):
    """Flood initialization (authors' implementation).

    Faces are visited in ``order`` (by Euclidean distance to the first seed);
    each face still unlabelled starts a new region, grown by a bounded
    expansion that claims only unlabelled faces. Returns ``(n_regions,
    next_sid)``.
    """
    m = label.shape[0]
    for f in range(m):
        label[f] = -1
    dummy = np.empty(0)
    norec_f = np.empty(0, dtype=np.int32)
    norec_d = np.empty(0, dtype=np.float64)
    n = 0
    for i in range(order.shape[0]):
        f = order[i]
        if label[f] < 0:
            expand(indptr, indices, weights, centroids, f, n, window_r2,
                   dummy, label, local, stamp, sid, hkey, hval, True, norec_f, norec_d, 0)
            n += 1
            sid += 1
    return n, sid
