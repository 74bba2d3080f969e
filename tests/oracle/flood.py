"""The flood initialization (authors' implementation), a numba kernel (private)."""

import numpy as np
from numba import njit

from .expand import UNLABELLED, expand


@njit(cache=True, error_model="numpy", nogil=True)
def flood(indptr, indices, weights, centroids, order, window_r2, label, local, queue,
          inv_width, vis):
    """Flood initialization (authors' implementation).

    Faces are visited in ``order`` (by Euclidean distance to the first seed);
    each face still unlabelled starts a new region, grown by a bounded
    expansion that claims only unlabelled faces. Returns the number of
    regions, or a negative status of :func:`expand` if ``queue`` or the
    visit buffer ``vis`` was too small. ``local``: :func:`expand`'s scratch, ``+0.0``
    on entry and on return (reached elements hold their distance negated meanwhile).
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
                        local, queue, inv_width, UNLABELLED, vis, dummy, 0, vis.shape[0])
            if st < 0:
                return st
            n += 1
    return n
