"""Whole-array passes over a large input's columns and indices (private kernels): the
columns' bounds and means, the finite rows, integer gathers. The compiled kernels of the same names
run them on threads from 65,536 rows (``superfacets.inputs.bounds``,
``superfacets._runtime.arrays``)."""

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", nogil=True)
def column_bounds(a, lo, hi):
    """``lo[c]``, ``hi[c]``: the least and greatest value of column ``c`` of the ``(n, d)``
    ``a`` (``n >= 1``), as ``a[:, c].min()`` and ``.max()`` give them: NaN where the
    column has one; of equal values (signed zeros) the first row's."""
    for c in range(a.shape[1]):
        lo[c] = a[0, c]
        hi[c] = a[0, c]
    for r in range(1, a.shape[0]):
        for c in range(a.shape[1]):
            x = a[r, c]
            if x < lo[c] or x != x:
                lo[c] = x
            if x > hi[c] or x != x:
                hi[c] = x


@njit(cache=True, nogil=True)
def column_means(a, out):
    """``out[c]``: the mean of column ``c`` of the ``(n, d)`` ``a`` (``n >= 1``) as
    ``a.mean(axis=0)`` makes it: the rows added in order, then divided by ``n``."""
    for c in range(a.shape[1]):
        out[c] = 0.0
    for r in range(a.shape[0]):
        for c in range(a.shape[1]):
            out[c] += a[r, c]
    for c in range(a.shape[1]):
        out[c] = out[c] / a.shape[0]


@njit(cache=True, nogil=True)
def finite_rows(a, out):
    """``out[r]``: whether every value of row ``r`` of ``a`` is finite, as
    ``np.isfinite(a).all(axis=1)``."""
    for r in range(a.shape[0]):
        ok = True
        for c in range(a.shape[1]):
            ok = ok and np.isfinite(a[r, c])
        out[r] = ok


@njit(cache=True, nogil=True)
def gather(values, index, out):
    """``out[i] = values[index[i]]`` for each index in range (``0 <= index[i] <
    len(values)``; others leave ``out[i]`` as it was); returns how many were not."""
    n = values.shape[0]
    bad = 0
    for i in range(index.shape[0]):
        j = index[i]
        if j < 0 or j >= n:
            bad += 1
        else:
            out[i] = values[j]
    return bad


@njit(cache=True, nogil=True)
def nearest_row(a, point):
    """The first row ``r`` of the ``(n, 3)`` ``a`` of least ``(dx dx + dy dy) + dz dz``
    to ``point`` (``np.argmin(((a - point) ** 2).sum(axis=1))``); -1 where a distance
    is NaN (numpy's argmin then takes the first NaN)."""
    best = np.inf
    at = -1
    for r in range(a.shape[0]):
        dx = a[r, 0] - point[0]
        dy = a[r, 1] - point[1]
        dz = a[r, 2] - point[2]
        d = dx * dx + dy * dy + dz * dz
        if d != d:
            return -1
        if d < best or at < 0:
            best = d
            at = r
    return at
