"""Label arrays: the one check every function taking labels uses, and dense relabelling."""

from __future__ import annotations

import numpy as np

from ..checks import check_unmasked
from ..errors import ParameterError

__all__ = ["check_labels", "relabel_dense", "size_summary"]


def check_labels(labels, n: int | None, what: str = "labels", per: str = "element") -> np.ndarray:
    """``labels`` as an ``(n,)`` int64 array, one integer per element.

    Parameters
    ----------
    labels : array_like
        One label per element (any integers).
    n : int or None
        Number of elements (faces of a mesh); None accepts any length.
    what : str, default 'labels'
        Name used in the error message.
    per : str, default 'element'
        What one label belongs to, for the message (``'face'``, ``'point'``).

    Returns
    -------
    (n,) int64 ndarray
        The labels, unchanged (not relabelled).

    Raises
    ------
    ParameterError
        If the array is not 1-D, not of length ``n`` or not of an integer dtype, is a
        run's result (its ``labels`` are meant) or a masked array with masked labels.

    Examples
    --------
    >>> check_labels([0, 1, 1], 3)
    array([0, 1, 1])
    """
    if not isinstance(labels, np.ndarray) and isinstance(getattr(labels, "labels", None),
                                                          np.ndarray):  # (a run's result)
        raise ParameterError(f"{what}: got a {type(labels).__name__}; pass its labels "
                             "(result.labels)")
    a = check_unmasked(labels, what)
    if a.ndim != 1 or (n is not None and a.shape[0] != n) \
            or not np.issubdtype(a.dtype, np.integer):
        count = "a 1-D array of integers" if n is None else f"{n} integers"
        raise ParameterError(f"{what} must be {count}, one per {per}; got shape "
                             f"{a.shape}, dtype {a.dtype}")
    return a.astype(np.int64, copy=False)


def relabel_dense(labels: np.ndarray) -> np.ndarray:
    """Map labels to ``0..K-1`` keeping their relative order.

    Parameters
    ----------
    labels : (m,) int ndarray

    Returns
    -------
    (m,) int64 ndarray

    Examples
    --------
    >>> relabel_dense(np.array([5, 2, 5, 9]))
    array([1, 0, 1, 2])
    """
    a = np.asarray(labels).ravel()
    if a.size and np.issubdtype(a.dtype, np.integer):
        lo, hi = int(a.min()), int(a.max())
        if lo >= 0 and hi <= 2 * a.size + 1024:  # small range: a table, no sort
            present = np.zeros(hi + 1, dtype=bool)
            present[a] = True
            rank = np.cumsum(present, dtype=np.int64) - 1
            return rank[a]
    _, inv = np.unique(a, return_inverse=True)
    return inv.astype(np.int64).ravel()


def size_summary(labels) -> dict:
    """The sizes of a partition's segments, in elements: ``size_min``, ``size_median``,
    ``size_max`` and ``size_histogram`` (counts of segments by size in powers of two:
    ``[1], [2, 3], [4, 7], ...``), labels below 0 left out.

    Parameters
    ----------
    labels : (n,) int ndarray

    Returns
    -------
    dict

    Raises
    ------
    ParameterError
        If no element has a label.

    Examples
    --------
    >>> s = size_summary(np.array([0, 0, 1, 1, 1, 1, 2]))
    >>> s["size_min"], s["size_median"], s["size_max"], s["size_histogram"]
    (1, 2.0, 4, [1, 1, 1])
    """
    lab = np.asarray(labels, dtype=np.int64)
    lab = lab[lab >= 0]
    if not lab.size:
        raise ParameterError("no labelled element")
    sizes = np.unique(lab, return_counts=True)[1]
    bins = np.floor(np.log2(sizes)).astype(np.int64)
    return {"size_min": int(sizes.min()), "size_median": float(np.median(sizes)),
            "size_max": int(sizes.max()),
            "size_histogram": np.bincount(bins).astype(int).tolist()}
