"""Bounding boxes of positions, and the extents double precision can take.

Face areas and normals square and square again the edge vectors (point
normals the neighbour offsets): an input is refused, with a message that says
to rescale it, before any of them would overflow or underflow.
"""

from __future__ import annotations

import numpy as np

from .._kernels import native
from .._runtime.arrays import COMPILED_MIN
from ..errors import InvalidCloudError, InvalidMeshError

__all__ = ["check_extent", "column_bounds", "column_means", "finite_rows", "nearest_row",
           "rows_in_box", "along"]

_MAX_COORDINATE = 1e300  # sums of three coordinates stay finite
_MAX_EXTENT = 1e70  # (edge length)^4 stays finite: areas and normals
_MIN_EXTENT = 1e-70  # (edge length)^4 stays a normal number
_COMPILED_MIN = COMPILED_MIN  # rows from which the compiled passes are used


def check_extent(lo, hi, where: str = "", what: str = "mesh") -> float:
    """The extent (longest side of the bounding box ``[lo, hi]``) of a mesh or
    cloud, once it is known that its geometry fits double precision.

    Face areas and normals square and square again the edge vectors (point
    normals the neighbour offsets), which overflow or underflow beyond an
    extent of ``1e70`` or below ``1e-70``; sums of coordinates overflow beyond
    ``1e300``.

    Parameters
    ----------
    lo, hi : (3,) float ndarray
        The lowest and highest finite coordinates.
    where : str, default ''
        Prefix of the message (the input's name and ``': '``).
    what : {'mesh', 'cloud'}, default 'mesh'
        The input's kind, as the message names it; also chooses the error.

    Returns
    -------
    float
        The extent, in the input's units (0 when every position coincides:
        the caller says what that means).

    Raises
    ------
    InvalidMeshError
        (:class:`~superfacets.errors.InvalidCloudError` for a cloud) If the
        coordinates or the extent lie beyond those limits.

    Examples
    --------
    >>> check_extent(np.zeros(3), np.array([2.0, 1.0, 0.0]))
    2.0
    >>> check_extent(np.zeros(3), np.full(3, 1e-80), "tiny.off: ")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    superfacets.errors.InvalidMeshError: tiny.off: the mesh spans only 1e-80: its geometry ...
    """
    error = InvalidCloudError if what == "cloud" else InvalidMeshError
    with np.errstate(over="ignore", invalid="ignore"):
        extent = float(np.max(np.asarray(hi) - np.asarray(lo)))
        size = float(max(np.abs(lo).max(), np.abs(hi).max()))
    if not (np.isfinite(extent) and size <= _MAX_COORDINATE and extent <= _MAX_EXTENT):
        raise error(f"{where}coordinates up to {size:.3g} spanning {extent:.3g}: its geometry "
                    f"would overflow double precision; rescale the {what} (e.g. to unit size)")
    if 0 < extent < _MIN_EXTENT:
        raise error(f"{where}the {what} spans only {extent:.3g}: its geometry would underflow "
                    "double precision; rescale it (e.g. to unit size)")
    return extent


def column_bounds(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lowest and highest value of each column of an ``(n, d)`` array, as
    ``a.min(axis=0), a.max(axis=0)`` (the same values: min and max are exact; of a
    column's zeros of both signs, either). Large float64 arrays in one compiled pass on
    threads, others column by column: a strided
    1-D reduction is several times faster than an ``axis=0`` one over short rows."""
    if (_COMPILED_MIN <= a.shape[0] and a.ndim == 2 and 1 <= a.shape[1] <= 16
            and a.dtype == np.float64 and a.flags.c_contiguous):
        lo, hi = np.empty(a.shape[1]), np.empty(a.shape[1])
        native.kernel("columns.column_bounds")(a, lo, hi)
        return lo, hi
    return (np.array([a[:, j].min() for j in range(a.shape[1])], dtype=a.dtype),
            np.array([a[:, j].max() for j in range(a.shape[1])], dtype=a.dtype))


def column_means(a: np.ndarray) -> np.ndarray:
    """``a.mean(axis=0)`` of an ``(n, d)`` float64 array (the same values: numpy adds the
    rows in order over the outer axis). Large C-contiguous arrays in one compiled pass
    (numpy loops over three columns per row)."""
    if (_COMPILED_MIN <= a.shape[0] and a.ndim == 2 and 1 <= a.shape[1] <= 16
            and a.dtype == np.float64 and a.flags.c_contiguous):
        out = np.empty(a.shape[1])
        native.kernel("columns.column_means")(a, out)
        return out
    return a.mean(axis=0)


def nearest_row(a: np.ndarray, point: np.ndarray) -> int:
    """``np.argmin(((a - point) ** 2).sum(axis=1))`` of an ``(n, 3)`` array, ``n >= 1``:
    the first row nearest ``point`` (the same squared distances, added in that order).
    Large C-contiguous float64 arrays in one compiled pass on threads, without the
    three temporaries of ``n`` rows."""
    p = np.ascontiguousarray(point, dtype=np.float64)
    if (_COMPILED_MIN <= a.shape[0] and a.ndim == 2 and a.shape[1] == 3 and p.shape == (3,)
            and a.dtype == np.float64 and a.flags.c_contiguous):
        r = int(native.kernel("columns.nearest_row")(a, p))
        if r >= 0:
            return r
    return int(np.argmin(((a - point) ** 2).sum(axis=1)))


def rows_in_box(a: np.ndarray, lo, hi) -> np.ndarray:
    """``((a >= lo) & (a <= hi)).all(axis=1)`` of an ``(n, d)`` array (a row with a NaN is
    outside), column by column: no ``(n, d)`` temporaries and no reduction over short rows
    (2M points: several times faster).

    Examples
    --------
    >>> rows_in_box(np.array([[0.5, 0.5], [2.0, 0.5], [np.nan, 0.0]]), [0, 0], [1, 1]).tolist()
    [True, False, False]
    """
    inside = (a[:, 0] >= lo[0]) & (a[:, 0] <= hi[0])
    for j in range(1, a.shape[1]):
        inside &= a[:, j] >= lo[j]
        inside &= a[:, j] <= hi[j]
    return inside


def finite_rows(a: np.ndarray) -> np.ndarray:
    """``np.isfinite(a).all(axis=1)`` of an ``(n, d)`` array: large float64 arrays in one
    compiled pass on threads."""
    if (_COMPILED_MIN <= a.shape[0] and a.ndim == 2 and a.dtype == np.float64
            and a.flags.c_contiguous):
        out = np.empty(a.shape[0], dtype=bool)
        native.kernel("columns.finite_rows")(a, out)
        return out
    return np.isfinite(a).all(axis=1)


def along(positions: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """``positions @ axis`` summed in one order for every row, so that a row's value does
    not depend on the rows read with it (a tile's or a chunk's against the whole input's).

    Parameters
    ----------
    positions : (n, 3) float64 ndarray
    axis : (3,) float64 ndarray

    Returns
    -------
    (n,) float64 ndarray

    Raises
    ------
    Never.

    Examples
    --------
    >>> along(np.array([[1.0, 2, 3]]), np.array([0.0, 1, 0])).tolist()
    [2.0]
    """
    p = np.asarray(positions, dtype=np.float64)
    return p[:, 0] * axis[0] + p[:, 1] * axis[1] + p[:, 2] * axis[2]
