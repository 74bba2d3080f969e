"""Exact nearest-center classification: one multi-source Dijkstra (private kernels).

``hkey`` (float64) / ``hval`` (int32 or int64): the binary heap of
:mod:`.heap`, capacity ``len(indices) + n + 1`` (an element is pushed again
only on a strict decrease).
"""

import numpy as np
from numba import njit

from .heap import pop_min, push

_INF = np.inf


@njit(cache=True, error_model="numpy")
def _multi_source(indptr, indices, weights, dist, label, hkey, hval, size):
    while size > 0:
        d, f, size = pop_min(hkey, hval, size)
        if d > dist[f]:
            continue
        lf = label[f]
        for e in range(indptr[f], indptr[f + 1]):
            g = indices[e]
            nd = d + weights[e]
            if nd < dist[g]:
                dist[g] = nd
                label[g] = lf
                size = push(hkey, hval, size, nd, g)


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
            size = push(hkey, hval, size, 0.0, c)
    _multi_source(indptr, indices, weights, dist, label, hkey, hval, size)
    k = n_centers
    for f in range(m):
        if label[f] < 0:
            centers[k] = f
            dist[f] = 0.0
            label[f] = k
            size = push(hkey, hval, 0, 0.0, f)
            _multi_source(indptr, indices, weights, dist, label, hkey, hval, size)
            k += 1
    return k
