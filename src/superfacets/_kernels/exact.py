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

from .expand import QUEUE_FULL, queue_node, queue_pop, queue_push

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
