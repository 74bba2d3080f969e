"""Array operations numpy makes slow for the arrays a run holds."""

from __future__ import annotations

import numpy as np

from .._kernels import native

__all__ = ["gather", "real_rows", "sorted_unique", "ranked", "row_table"]

#: Rows from which the whole-array passes run compiled, on threads (numpy below): the
#: gathers here, the columns' bounds and means, a point graph's shares and sort window.
COMPILED_MIN = 1 << 16
#: Indices from which :func:`gather` runs compiled (numpy's ``take`` below).
GATHER_MIN = COMPILED_MIN


def sorted_unique(values: np.ndarray) -> np.ndarray:
    """``np.unique(values)`` (the distinct values, ascending) by a sort.

    numpy 2.x finds the distinct values of a plain ``np.unique`` call in a hash table,
    which is many times slower than sorting on the wide integer keys a run makes
    (pairs of elements as ``a * n + b``; ``docs/notes/code-measurements.md``). The same
    values in the same order.

    Parameters
    ----------
    values : ndarray
        Any shape (flattened), any dtype numpy sorts (NaN is kept once at the end, as
        ``np.unique`` keeps it).

    Returns
    -------
    (u,) ndarray
        Of the dtype of ``values``.

    Raises
    ------
    Nothing of its own.

    Examples
    --------
    >>> sorted_unique(np.array([5, 1, 5, 3, 1])).tolist()
    [1, 3, 5]
    """
    a = np.sort(np.asarray(values), axis=None)
    if a.size == 0 or a.dtype.kind in "fc":  # (NaN: np.unique's own rule)
        return np.unique(a) if a.size else a
    keep = np.empty(a.shape, dtype=bool)
    keep[0] = True
    np.not_equal(a[1:], a[:-1], out=keep[1:])
    return a[keep]


def row_table(names: np.ndarray, upper: int) -> np.ndarray:
    """Where each of ``upper`` values stands in ``names`` (distinct values in ``0..upper-1``):
    ``table[v]`` is ``v``'s position, ``-1`` for a value not named, and ``table[-1]`` (one
    entry past ``upper``) is ``-1``, so that ``table[labels]`` reads ``-1`` for a label of
    ``-1``. A lookup in place of ``np.searchsorted`` on labels named by rows: 4 bytes per
    value (8 past 2**31 names), one gather instead of a binary search per label.

    Parameters
    ----------
    names : (K,) int ndarray
        Distinct, in ``0..upper-1``.
    upper : int
        The values' bound.

    Returns
    -------
    (upper + 1,) int32 or int64 ndarray

    Examples
    --------
    >>> row_table(np.array([7, 2]), 9)[np.array([2, 7, 3, -1])].tolist()
    [1, 0, -1, -1]
    """
    names = np.asarray(names)
    table = np.full(int(upper) + 1, -1, dtype=np.int32 if names.size < 2**31 else np.int64)
    table[names] = np.arange(names.size, dtype=table.dtype)
    return table


def ranked(labels: np.ndarray, upper: int) -> tuple[np.ndarray, np.ndarray]:
    """The distinct values of ``labels`` (``-1`` aside) ascending, and each label's rank
    among them (``-1`` stays): ``np.unique(labels[labels >= 0], return_inverse=True)`` by a
    table of ``upper`` entries instead of a sort (5 bytes per value of the table against
    24 per label).

    Parameters
    ----------
    labels : (n,) int ndarray
        Each in ``-1..upper-1``.
    upper : int
        The labels' bound.

    Returns
    -------
    names : (K,) int64 ndarray
    ranks : (n,) int64 ndarray

    Raises
    ------
    ValueError
        If a label lies outside ``-1..upper-1``.

    Examples
    --------
    >>> names, ranks = ranked(np.array([9, -1, 4, 9]), 10)
    >>> names.tolist(), ranks.tolist()
    ([4, 9], [1, -1, 0, 1])
    """
    labels = np.asarray(labels)
    if labels.size and (labels.min() < -1 or labels.max() >= upper):
        raise ValueError(f"labels must lie in -1..{upper - 1}")
    present = np.zeros(int(upper) + 1, dtype=bool)
    present[labels] = True  # (-1: the entry past upper)
    present[-1] = False
    names = np.flatnonzero(present)
    return names, row_table(names, upper)[labels].astype(np.int64)


def real_rows(values: np.ndarray) -> np.ndarray:
    """``values`` as the compiled kernels read real arrays: C-contiguous float32 or
    float64 as they are (a point cloud's normals stay float32: the kernels read each as
    float64, the values a float64 copy would hold), anything else as float64.

    Parameters
    ----------
    values : ndarray
        Any shape.

    Returns
    -------
    ndarray
        ``values`` itself where it already is such an array.

    Examples
    --------
    >>> a = np.zeros((2, 3), dtype=np.float32)
    >>> real_rows(a) is a, real_rows(a.astype(np.int64)).dtype.name
    (True, 'float64')
    """
    a = np.asarray(values)
    if a.dtype == np.float32 or a.dtype == np.float64:
        return np.ascontiguousarray(a)
    return np.ascontiguousarray(a, dtype=np.float64)


def gather(values: np.ndarray, index: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``values[index]`` of 1-D integer arrays (labels, their numbers), as ``np.take``.

    numpy's ``take`` runs on one thread, and a run gathers its labels every pass;
    65,536 indices or more of int32 or int64 values and indices, C-contiguous,
    are gathered by a compiled pass on threads. Anything else goes to ``np.take``.

    Parameters
    ----------
    values : (n,) int32 or int64 ndarray
    index : (m,) int32 or int64 ndarray
        Each in ``0 .. n - 1``.
    out : (m,) ndarray, optional
        Of the dtype of ``values``; written and returned.

    Returns
    -------
    (m,) ndarray
        Of the dtype of ``values``.

    Raises
    ------
    IndexError
        If an index is out of range (``out`` may then be partly written).

    Examples
    --------
    >>> gather(np.array([10, 20, 30]), np.array([2, 0, 2])).tolist()
    [30, 10, 30]
    """
    ints = (np.int32, np.int64)
    if (index.shape[0] < GATHER_MIN or values.ndim != 1 or index.ndim != 1
            or values.dtype not in ints or index.dtype not in ints
            or not (values.flags.c_contiguous and index.flags.c_contiguous)
            or (out is not None and (out.dtype != values.dtype or not out.flags.c_contiguous
                                     or not out.flags.writeable))):
        return np.take(values, index, out=out)

    if out is None:
        out = np.empty(index.shape[0], dtype=values.dtype)
    bad = native.kernel("columns.gather")(values, index, out)
    if bad:
        raise IndexError(f"{bad} of {index.shape[0]} indices out of range for "
                         f"{values.shape[0]} values")
    return out
