"""Exact nearest-center classification: one multi-source search (private kernels).

Every element gets the smallest ``(distance, center index)`` pair over the
centers, pairs compared lexicographically: ties of distance go to the center
listed first, whatever order the search settles elements in (in exact
arithmetic; a tie that appears only after rounding may go either way, the
same way on every run). The search (:func:`search_buckets`, shared with the
Voronoi cells of coarse-to-fine, :mod:`.voronoi`) is label-correcting with the
bucket queue of the bounded expansions (:func:`.expand.expand`), about twice
as fast as a binary heap here. ``queue = (qface, qdist, qnext, head)`` as
there, ``qlab`` one label per queue node.
"""

import numpy as np
from numba import njit

from superfacets._kernels.codes import NOT_INCREMENTAL, QUEUE_FULL  # noqa: F401

from .expand import queue_node, queue_pop, queue_push

_INF = np.inf


@njit(cache=True, error_model="numpy", nogil=True)
def search_buckets(indptr, indices, weights, dist, label, seeds, queue, qlab, inv_width, lex):
    """Spread the labels of ``seeds`` (elements already holding their ``dist`` and
    ``label``, in increasing distance) over the graph: every element reached ends
    with the least ``dist + weight`` over its neighbours and that neighbour's label.

    With ``lex``, ``(distance, label)`` pairs are compared lexicographically (an
    equal distance with a smaller label wins: the result does not depend on the
    order of the work); without, only a strictly smaller distance wins (on ties
    an element keeps the label that reached it first: deterministic, but set by
    the order of the work). Label-correcting over the circular bucket queue of
    :func:`.expand.expand` (``head`` all -1 on entry and on return); seeds enter
    it once they lie within its span of the bucket being processed. Returns 0,
    or :data:`.expand.QUEUE_FULL` (grow ``queue`` and ``qlab`` and start again).
    """
    qface, qdist, qnext, head = queue
    qcap = qface.shape[0]
    nb = head.shape[0]
    bmask = nb - 1
    ns = seeds.shape[0]
    free = -1
    bump = 0
    live = 0
    sp = 0
    cur = 0
    while live > 0 or sp < ns:
        if live == 0:  # jump to the next seed
            b0 = np.int64(dist[seeds[sp]] * inv_width)
            if b0 > cur:
                cur = b0
        while sp < ns:  # the seeds within the circular array's span
            g = seeds[sp]
            if np.int64(dist[g] * inv_width) > cur + nb - 1:
                break
            sp += 1
            n, free, bump = queue_node(qnext, free, bump, qcap)
            if n < 0:
                for b in range(nb):
                    head[b] = -1
                return QUEUE_FULL
            queue_push(qface, qdist, qnext, head, bmask, n, g, dist[g], inv_width, cur)
            qlab[n] = label[g]
            live += 1
        f, d, free, cur = queue_pop(qface, qdist, qnext, head, bmask, cur, free)
        lf = qlab[free]  # the node just popped heads the free list
        live -= 1
        if d != dist[f] or lf != label[f]:
            continue  # stale: reached by a smaller pair since
        for e in range(indptr[f], indptr[f + 1]):
            g = indices[e]
            nd = d + weights[e]
            if nd < dist[g] or (lex and nd == dist[g] and lf < label[g]):
                dist[g] = nd
                label[g] = lf
                n, free, bump = queue_node(qnext, free, bump, qcap)
                if n < 0:
                    for b in range(nb):
                        head[b] = -1
                    return QUEUE_FULL
                queue_push(qface, qdist, qnext, head, bmask, n, g, nd, inv_width, cur)
                qlab[n] = lf
                live += 1
    return 0


@njit(cache=True, error_model="numpy")
def classify_exact(indptr, indices, weights, centers, n_centers, dist, label, queue, qlab,
                   inv_width):
    """Exact nearest-center assignment: one multi-source search, no bound.

    Every element gets the label of the center at the smallest graph
    distance (ties: the center listed first; a second center on the same
    element stays empty). Elements of connected pieces without a center are
    re-seeded like orphans (each piece its first unreached element, in index
    order, appended to ``centers``). Returns the number of centers ``K``, or
    :data:`.expand.QUEUE_FULL` (grow the queue and call again).
    """
    m = label.shape[0]
    for f in range(m):
        dist[f] = _INF
        label[f] = -1
    seeds = np.empty(n_centers, dtype=np.int64)
    ns = 0
    for s in range(n_centers):
        c = centers[s]
        if label[c] < 0:
            dist[c] = 0.0
            label[c] = s
            seeds[ns] = c
            ns += 1
    if search_buckets(indptr, indices, weights, dist, label, seeds[:ns], queue, qlab,
                      inv_width, True) != 0:
        return QUEUE_FULL
    return _seed_orphans(indptr, indices, weights, centers, n_centers, dist, label, queue, qlab,
                         inv_width)


@njit(cache=True, error_model="numpy")
def _seed_orphans(indptr, indices, weights, centers, n_centers, dist, label, queue, qlab,
                  inv_width):
    """Each element still unlabelled, in index order, becomes a center appended to
    ``centers`` and spreads its label over its connected piece. Returns ``K``."""
    m = label.shape[0]
    k = n_centers
    one = np.empty(1, dtype=np.int64)
    for f in range(m):
        if label[f] < 0:
            centers[k] = f
            dist[f] = 0.0
            label[f] = k
            one[0] = f
            if search_buckets(indptr, indices, weights, dist, label, one, queue, qlab,
                              inv_width, True) != 0:
                return QUEUE_FULL
            k += 1
    return k


#: :func:`reclassify_exact` found the previous labels unusable: classify from scratch.


@njit(cache=True, error_model="numpy")
def reclassify_exact(indptr, indices, weights, centers, n_centers, dist, label, queue, qlab,
                     inv_width, prev, first, border_mark):
    """:func:`classify_exact` of ``centers[:n_centers]``, updated from the previous
    pass's result instead of searched again from scratch: the same labels and
    distances, bit for bit.

    ``dist``/``label`` hold the result of :func:`classify_exact` (or of this
    function) for the centers ``prev`` (orphans included). A center of ``prev``
    whose element is again a center keeps its cell: its elements keep their
    distance, under the center's new index. The other elements (those of
    centers that moved or left) are cleared and reached again by one search
    seeded with the moved centers (distance 0) and with the kept elements
    bordering the cleared ones (their distances): each kept element's pair is
    already the least over the kept centers, so the search's least fixed point
    is the one the search from scratch reaches. Ties keep their rule when the
    kept centers keep their order; else (or with labels out of range) this
    returns :data:`NOT_INCREMENTAL` having changed nothing. ``first`` (int64,
    one per element) and ``border_mark`` (bool) are scratch: all -1 / False on
    entry and again on return. Returns ``K`` or :data:`.expand.QUEUE_FULL`.
    """
    m = label.shape[0]
    for s in range(n_centers):
        c = centers[s]
        if first[c] < 0:
            first[c] = s
    kp = prev.shape[0]
    remap = np.empty(kp, dtype=np.int64)
    last = -1
    usable = True
    for j in range(kp):
        i = first[prev[j]]
        remap[j] = i
        if i >= 0:
            if i <= last:
                usable = False  # the kept centers changed order: ties could go otherwise
            last = i
    if usable:
        for f in range(m):
            lab = label[f]
            if lab < 0 or lab >= kp:
                usable = False
                break
    if not usable:
        for s in range(n_centers):
            first[centers[s]] = -1
        return NOT_INCREMENTAL
    n_clear = 0
    for f in range(m):
        i = remap[label[f]]
        if i < 0:
            dist[f] = _INF
            label[f] = -1
            n_clear += 1
        else:
            label[f] = i
    seeds = np.empty(n_centers, dtype=np.int64)
    ns = 0
    for s in range(n_centers):
        c = centers[s]
        if first[c] == s and (label[c] < 0 or dist[c] > 0.0 or label[c] > s):
            dist[c] = 0.0
            label[c] = s
            seeds[ns] = c
            ns += 1
    for s in range(n_centers):
        first[centers[s]] = -1
    # kept elements next to cleared ones, in increasing distance
    border = np.empty(min(n_clear * 8 + 16, m), dtype=np.int64)
    nb = 0
    for f in range(m):
        if label[f] >= 0:
            continue
        for e in range(indptr[f], indptr[f + 1]):
            g = indices[e]
            if label[g] >= 0 and not border_mark[g]:
                border_mark[g] = True
                if nb == border.shape[0]:
                    grown = np.empty(2 * nb + 16, dtype=np.int64)
                    grown[:nb] = border[:nb]
                    border = grown
                border[nb] = g
                nb += 1
    for t in range(nb):
        border_mark[border[t]] = False
    border = border[:nb]
    order = np.argsort(dist[border], kind="mergesort")
    all_seeds = np.empty(ns + nb, dtype=np.int64)
    all_seeds[:ns] = seeds[:ns]
    for t in range(nb):
        all_seeds[ns + t] = border[order[t]]
    if search_buckets(indptr, indices, weights, dist, label, all_seeds, queue, qlab,
                      inv_width, True) != 0:
        return QUEUE_FULL
    return _seed_orphans(indptr, indices, weights, centers, n_centers, dist, label, queue, qlab,
                         inv_width)
