"""RGB colours of an input: file values scaled to ``[0, 1]``, validated, and carried
between a mesh's vertices and its faces.

Point clouds carry one colour per point (:class:`~superfacets.inputs.cloud.PointCloud`),
meshes one per vertex, one per face, or both (:class:`~superfacets.inputs.mesh.Mesh`):
what ``beta > 0`` of :func:`superfacets.segment` reads when no ``features``
are given (``docs/notes/method.md``, "Features"). A face's colour, where the file
gives only vertex colours, is the mean of its vertices' colours; a vertex's,
where the file gives only face colours, the mean of its faces' colours.
"""

from __future__ import annotations

import numpy as np

from ..checks import check_unmasked

__all__ = ["unit_colors", "color_top", "check_colors", "face_means", "vertex_means"]


def unit_colors(rgb: np.ndarray, top: float | None = None) -> np.ndarray:
    """RGB of a file in ``[0, 1]``.

    8-bit integers are divided by 255, 16-bit ones by 65535 (or by 255 where
    no value exceeds 255: LAS writers that store 8 bits in 16), floats kept
    (divided by 255 where one exceeds 1: floats holding 0..255), then clipped
    to ``[0, 1]``; NaN is kept (an invalid point's colour), and an infinity (damage, which
    the cloud or mesh then refuses).

    Parameters
    ----------
    rgb : (N, 3) int or float ndarray
    top : float, optional
        The divisor of integer colours, decided for a whole file (:func:`color_top`)
        when ``rgb`` is a part of it: a dark part of a 16-bit file must not be
        read as 8-bit.

    Returns
    -------
    (N, 3) float64 ndarray

    Examples
    --------
    >>> unit_colors(np.array([[255, 0, 51]], dtype=np.uint8)).tolist()
    [[1.0, 0.0, 0.2]]
    """
    a = np.asarray(rgb)
    if np.issubdtype(a.dtype, np.integer):
        if top is None:
            top = color_top(a.dtype.itemsize, int(a.max()) if a.size else 0)
        return np.clip(a.astype(np.float64) / top, 0.0, 1.0)
    a = a.astype(np.float64)
    if np.isfinite(a).any() and np.nanmax(np.where(np.isinf(a), np.nan, a)) > 1.0:
        # floats holding 0..255 (NaN and infinities are checked by the cloud)
        a = a / 255.0
    return np.where(np.isinf(a), a, np.clip(a, 0.0, 1.0))  # (an infinity is damage: kept)


def color_top(itemsize: int, largest: int) -> float:
    """The divisor of integer colours of ``itemsize`` bytes whose largest value is
    ``largest``: 255 for 8 bits, and for 16 bits that hold no value above 255; else
    65535.

    Examples
    --------
    >>> color_top(1, 200), color_top(2, 200), color_top(2, 4000)
    (255.0, 255.0, 65535.0)
    """
    return 255.0 if itemsize == 1 or largest <= 255 else 65535.0


def check_colors(colors, n: int, what: str, where: str, error: type,
                 valid: np.ndarray | None = None) -> np.ndarray:
    """``colors`` as a C-contiguous ``(n, 3) float64`` array in ``[0, 1]``, or ``error``.

    Parameters
    ----------
    colors : (n, 3) float ndarray
        RGB in ``[0, 1]`` (the readers scale 8- and 16-bit colours:
        :func:`unit_colors`).
    n : int
        Rows expected.
    what, where : str
        For the messages: one row's name (``"colour"``, ``"face colour"``) and
        the input's (``"mesh.ply: "``).
    error : type
        The exception raised (``InvalidMeshError``, ``InvalidCloudError``).
    valid : (n,) bool ndarray, optional
        Rows checked (an invalid point's colour may be anything).

    Raises
    ------
    TypeError
        If ``colors`` is not numeric.
    error
        On another shape, or a colour outside ``[0, 1]`` or not finite (naming
        the first such row; a file's broken colours stop its reading, as its
        broken coordinates do).

    Examples
    --------
    >>> check_colors([[0, 0.5, 1]], 1, "colour", "", ValueError).tolist()
    [[0.0, 0.5, 1.0]]
    """
    arr = check_unmasked(colors, f"{where}{what}s", error)
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.number) or arr.dtype == bool):
        raise TypeError(f"{where}{what}s must be numeric, got dtype {arr.dtype}")
    if np.issubdtype(arr.dtype, np.complexfloating):  # (a cast would drop the imaginary part)
        raise TypeError(f"{where}{what}s must be real numbers, got dtype {arr.dtype}")
    if arr.shape != (n, 3):
        raise error(f"{where}{what}s must have shape ({n}, 3), got {arr.shape}")
    col = np.ascontiguousarray(arr, dtype=np.float64)
    rows = col if valid is None else col[valid]
    bad = ~(np.isfinite(rows).all(axis=1) & (rows >= 0).all(axis=1) & (rows <= 1).all(axis=1))
    if bad.any():
        row = int(np.flatnonzero(bad)[0] if valid is None
                  else np.flatnonzero(valid)[np.flatnonzero(bad)[0]])
        if not np.isfinite(col[row]).all():
            raise error(f"{where}{what} {row} is not finite ({col[row].tolist()})")
        raise error(f"{where}{what} {row} is not in [0, 1] ({col[row].tolist()}); scale "
                    "8-bit colours by 1/255")
    return col


def face_means(colors: np.ndarray, corners: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """(m, 3) float64: each face's mean of its vertices' ``colors``.

    ``corners`` and ``offsets`` as :attr:`superfacets.inputs.mesh.Mesh.corners` and
    :attr:`~superfacets.inputs.mesh.Mesh.offsets` (face ``f`` has the vertices
    ``corners[offsets[f]:offsets[f + 1]]``).

    Examples
    --------
    >>> face_means(np.eye(3), np.array([0, 1, 2]), np.array([0, 3])).round(3).tolist()
    [[0.333, 0.333, 0.333]]
    """
    sums = np.add.reduceat(colors[corners], offsets[:-1], axis=0)
    return sums / np.diff(offsets)[:, None]


def vertex_means(face_colors: np.ndarray, corners: np.ndarray, offsets: np.ndarray,
                 n_vertices: int) -> np.ndarray:
    """(n, 3) float64: each vertex's mean of its faces' ``face_colors`` (0 for a vertex
    of no face).

    Examples
    --------
    >>> vertex_means(np.array([[1.0, 0, 0], [0, 0, 1.0]]), np.array([0, 1, 2, 1, 2, 3]),
    ...              np.array([0, 3, 6]), 4)[1].tolist()
    [0.5, 0.0, 0.5]
    """
    owner = np.repeat(np.arange(offsets.size - 1), np.diff(offsets))
    sums = np.zeros((n_vertices, face_colors.shape[1]))
    np.add.at(sums, corners, face_colors[owner])
    count = np.bincount(corners, minlength=n_vertices).astype(np.float64)
    return sums / np.maximum(count, 1.0)[:, None]
