"""Argument checks every layer uses: each raises
:class:`~superfacets.errors.ParameterError` (a ``ValueError``) naming the parameter
and the bad value, never ``TypeError``, never an ``assert``.

:mod:`superfacets.method.params` declares the method's parameters with these checks; the
other modules check their own arguments with them.

Examples
--------
>>> check_int("n", 3, lo=1), check_positive("r", "0.5")
(3, 0.5)
"""

from __future__ import annotations

import math

import numpy as np

from .errors import ParameterError

__all__ = ["check_int", "check_number", "check_positive", "check_nonneg", "check_bool",
           "check_choice", "check_n_segments", "check_threads", "max_threads",
           "threads_from_env", "not_real", "check_real", "check_unmasked", "counted",
           "check_up", "check_name", "AXES"]

#: Named axes (an up direction, a side to see from) and their directions.
AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0),
        "-x": (-1.0, 0.0, 0.0), "-y": (0.0, -1.0, 0.0), "-z": (0.0, 0.0, -1.0)}


def counted(n: int, one: str, many: str | None = None) -> str:
    """``n`` and its noun, in the singular for one: ``counted(1, "piece")`` is ``"1 piece"``,
    ``counted(3, "piece")`` ``"3 pieces"``, thousands separated (``"5,120 faces"``).

    Parameters
    ----------
    n : int
    one : str
        The noun in the singular.
    many : str, optional
        Its plural, where it is not ``one + "s"``.

    Returns
    -------
    str

    Raises
    ------
    ValueError
        If ``n`` is not a number (the format's).

    Examples
    --------
    >>> counted(1, "connected piece"), counted(2, "vertex", "vertices")
    ('1 connected piece', '2 vertices')
    """
    return f"{n:,} {one if n == 1 else (many or one + 's')}"


def not_real(dtype, what: str) -> str:
    """Why an array of ``dtype`` cannot hold coordinates: "" for real numbers (integers,
    floats); the one sentence every door (the API, each reader, the tiled readers,
    :class:`~superfacets.TetMesh`) gives for the others (complex: casting would drop the
    imaginary part; objects, strings, booleans, records).

    Parameters
    ----------
    dtype : numpy.dtype or str
        The array's element type.
    what : str
        What the array holds, for the sentence (``"points"``).

    Returns
    -------
    str
        "" where ``dtype`` is an integer or floating type, else the sentence.

    Raises
    ------
    TypeError
        Never for a dtype; if ``dtype`` is not one (numpy's own error).

    Examples
    --------
    >>> not_real(np.dtype("complex128"), "points")
    'points must be real numbers, got dtype complex128'
    >>> not_real(np.dtype("float32"), "points")
    ''
    """
    dtype = np.dtype(dtype)
    if dtype.names is None and (np.issubdtype(dtype, np.integer)
                                or np.issubdtype(dtype, np.floating)):
        return ""
    return f"{what} must be real numbers, got dtype {dtype}"


def check_name(value, what: str = "name") -> str:
    """An input's name: a string or a path (a file's name, shown in messages).

    Parameters
    ----------
    value : str or os.PathLike
    what : str, default 'name'
        The parameter's name, for the message.

    Returns
    -------
    str

    Raises
    ------
    ParameterError
        If ``value`` is neither.

    Examples
    --------
    >>> from pathlib import Path
    >>> check_name("bunny.ply"), check_name(Path("scans/site.e57"))
    ('bunny.ply', 'scans/site.e57')
    """
    import os

    if isinstance(value, os.PathLike):
        value = os.fspath(value)
    if not isinstance(value, str):
        raise ParameterError(f"{what} must be a string, got {type(value).__name__}")
    return value


def check_real(dtype, what: str) -> None:
    """Refuse coordinates of any ``dtype`` but integers and floats (:func:`not_real`).

    Parameters
    ----------
    dtype : numpy.dtype or str
    what : str
        What the array holds, with the input's name where it has one.

    Returns
    -------
    None

    Raises
    ------
    TypeError
        With :func:`not_real`'s sentence.

    Examples
    --------
    >>> check_real(np.dtype("int32"), "faces")
    """
    if not_real(dtype, what):
        raise TypeError(not_real(dtype, what))


def check_unmasked(values, what: str, error: type = ParameterError):
    """``values`` as an array, refused where it is a masked array with masked entries:
    ``numpy.asarray`` would drop the mask and keep the values under it, which the caller
    meant to leave out (a silent wrong answer).

    Parameters
    ----------
    values : array_like
        Coordinates or labels, possibly a ``numpy.ma.MaskedArray``.
    what : str
        What the array holds, with the input's name where it has one (``"points"``).
    error : type, default ParameterError
        The exception raised (``InvalidCloudError``, ``InvalidMeshError``).

    Returns
    -------
    ndarray
        ``numpy.asarray(values)``; a masked array with no masked entry gives its data.

    Raises
    ------
    error
        Naming how many rows hold masked entries, and what to do instead.

    Examples
    --------
    >>> a = np.ma.masked_array([[0.0, 1, 2], [3, 4, 5]], mask=[[0, 0, 0], [0, 1, 0]])
    >>> check_unmasked(a, "points")
    Traceback (most recent call last):
    ...
    superfacets.errors.ParameterError: points: a masked array with 1 row of masked values: ...
    """
    if np.ma.isMaskedArray(values) and np.ma.getmaskarray(values).any():
        mask = np.ma.getmaskarray(values)
        if mask.ndim > 1:
            rows = int(mask.reshape(mask.shape[0], -1).any(axis=1).sum())
            held, out = f"{counted(rows, 'row')} of masked values", "a[~a.mask.any(axis=1)]"
            fill = "a.filled(value)"
        else:
            held, out = counted(int(mask.sum()), "masked value"), "a[~a.mask]"
            fill = "a.filled(value); a ground truth's with the value given as ignore_label"
        raise error(f"{what}: a masked array with {held}: leave them out ({out}) or fill "
                    f"them ({fill}); the mask is not read")
    return np.asarray(values)


def _is_int(value) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def check_int(name: str, value, lo: int | None = None, hi: int | None = None) -> int:
    """``value`` as an int in ``[lo, hi]``; booleans and floats are refused.

    Parameters
    ----------
    name : str
        The parameter's name, for the message.
    value : object
    lo, hi : int, optional
        The bounds, included.

    Returns
    -------
    int

    Raises
    ------
    ParameterError
        If ``value`` is not an integer (``True`` and ``2.0`` are not) or out of range.

    Examples
    --------
    >>> check_int("k", 5, lo=1)
    5
    >>> check_int("k", 0, lo=1)
    Traceback (most recent call last):
    ...
    superfacets.errors.ParameterError: k must be an integer >= 1, got 0
    """
    if not _is_int(value):
        raise ParameterError(f"{name} must be an integer, got {_shown(value)}")
    v = int(value)
    if lo is not None and v < lo:
        raise ParameterError(f"{name} must be an integer >= {lo}, got {_shown(v)}")
    if hi is not None and v > hi:
        raise ParameterError(f"{name} must be an integer <= {hi}, got {_shown(v)}")
    return v


def check_number(name: str, value, lo: float = -math.inf, hi: float = math.inf, *,
                 lo_open: bool = False) -> float:
    """``value`` as a finite float in ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``).

    Parameters
    ----------
    name : str
        The parameter's name, for the message.
    value : object
        A number, or a string of one.
    lo, hi : float
        The bounds (``hi`` included; ``lo`` included unless ``lo_open``).
    lo_open : bool, default False

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        If ``value`` is not a finite number in range (booleans are refused).

    Examples
    --------
    >>> check_number("tol", "0.5", 0.0, 1.0)
    0.5
    """
    shown = _shown(value)
    if isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name} must be a number, got {shown}")
    low = f"> {lo:g}" if lo_open else f">= {lo:g}"
    rng = low if hi == math.inf else f"in {'(' if lo_open else '['}{lo:g}, {hi:g}]"
    try:
        x = float(value)
    except OverflowError:  # an integer past float64's range (10**400)
        raise ParameterError(f"{name} must be a finite number {rng}, got {shown}") from None
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number, got {shown}") from None
    if not math.isfinite(x) or (x <= lo if lo_open else x < lo) or x > hi:
        raise ParameterError(f"{name} must be a finite number {rng}, got {shown}")
    return x


def _shown(value) -> str:
    """``repr(value)``, a number of many digits named by its length instead."""
    text = repr(value)
    return text if len(text) <= 40 else f"a {len(text)}-character {type(value).__name__}"


def check_positive(name: str, value) -> float:
    """A finite number ``> 0``.

    Parameters
    ----------
    name : str
    value : object

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        If ``value`` is not a finite number above 0.

    Examples
    --------
    >>> check_positive("radius", 0.05)
    0.05
    """
    return check_number(name, value, 0.0, lo_open=True)


def check_nonneg(name: str, value) -> float:
    """A finite number ``>= 0``.

    Parameters
    ----------
    name : str
    value : object

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        If ``value`` is not a finite number of at least 0.

    Examples
    --------
    >>> check_nonneg("alpha", 0)
    0.0
    """
    return check_number(name, value, 0.0)


def check_bool(name: str, value) -> bool:
    """``True`` or ``False`` (numpy booleans accepted).

    Parameters
    ----------
    name : str
    value : object

    Returns
    -------
    bool

    Raises
    ------
    ParameterError
        If ``value`` is not a boolean (``1`` is not).

    Examples
    --------
    >>> check_bool("paper", True)
    True
    """
    if not isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name} must be True or False, got {_shown(value)}")
    return bool(value)


def check_choice(name: str, value, choices) -> str:
    """One of ``choices``.

    Parameters
    ----------
    name : str
    value : object
    choices : sequence of str

    Returns
    -------
    str

    Raises
    ------
    ParameterError
        Listing the choices.

    Examples
    --------
    >>> check_choice("init", "grid", ("farthest", "flood", "grid"))
    'grid'
    """
    if not isinstance(value, str) or value not in choices:
        raise ParameterError(f"{name} must be one of {', '.join(choices)}; got {_shown(value)}")
    return value


def check_n_segments(n_segments, m: int, kind: str = "faces") -> int:
    """A number of segments ``k`` in ``1..m`` (``m`` the number of elements, of ``kind``).

    Parameters
    ----------
    n_segments : int
    m : int
        The number of elements.
    kind : str, default 'faces'
        Their kind, for the message.

    Returns
    -------
    int

    Raises
    ------
    ParameterError
        If ``n_segments`` is not an integer in ``1..m``.

    Examples
    --------
    >>> check_n_segments(10, 12)
    10
    """
    k = check_int("n_segments", n_segments, lo=1)
    if k > m:
        raise ParameterError(f"n_segments ({k}) is larger than the number of {kind} ({m})")
    return k


def max_threads() -> int:
    """The most threads a run may use: 4 per core, at least 16 (each thread keeps about
    12 bytes per element of buffers).

    Returns
    -------
    int

    Raises
    ------
    ParameterError
        Never (no argument to check); listed for the convention.

    Examples
    --------
    >>> max_threads() >= 16
    True
    """
    import os

    return max(16, 4 * (os.cpu_count() or 1))


def check_threads(n_threads) -> int:
    """Resolve ``n_threads``: None gives ``SUPERFACETS_NUM_THREADS`` where set, else the
    CPUs this process may run on.

    Parameters
    ----------
    n_threads : int or None

    Returns
    -------
    int

    Raises
    ------
    ParameterError
        If it is not an integer in ``1..max_threads()``.

    Examples
    --------
    >>> check_threads(2), check_threads(None) >= 1
    (2, True)
    """
    if n_threads is None:
        import os

        given = threads_from_env()
        if given is not None:
            return given
        try:
            return max(1, len(os.sched_getaffinity(0)))
        except AttributeError:  # pragma: no cover - not Linux
            return max(1, os.cpu_count() or 1)
    return check_int("n_threads", n_threads, lo=1, hi=max_threads())


def threads_from_env() -> int | None:
    """``SUPERFACETS_NUM_THREADS`` read by the rule ``--threads`` follows: a whole number
    from 1 to :func:`max_threads`; None where it is not set (or empty).

    Returns
    -------
    int or None

    Raises
    ------
    ParameterError
        If it is set to anything else (``1e3``, ``2.5``, ``0``, ``2**63``), naming it.

    Examples
    --------
    >>> import os
    >>> os.environ["SUPERFACETS_NUM_THREADS"] = "2"
    >>> threads_from_env()
    2
    >>> del os.environ["SUPERFACETS_NUM_THREADS"]
    """
    import os

    raw = os.environ.get("SUPERFACETS_NUM_THREADS", "").strip()
    if not raw:
        return None
    hi = max_threads()
    if not (raw.isascii() and raw.isdigit()) or not 1 <= int(raw) <= hi:
        raise ParameterError(f"SUPERFACETS_NUM_THREADS={raw[:40]!r}: give a whole number of "
                             f"threads from 1 to {hi} (as --threads), or unset it")
    return int(raw)


def check_up(value, name: str = "up") -> np.ndarray:
    """A direction as a unit vector: an axis name of :data:`AXES` or 3 finite numbers, not
    all zero.

    Parameters
    ----------
    value : str or (3,) array-like
    name : str
        The parameter's name, for the message.

    Returns
    -------
    (3,) float64 ndarray
        Of length 1.

    Raises
    ------
    ParameterError
        On an unknown axis name, or anything but 3 finite numbers not all zero.

    Examples
    --------
    >>> check_up("-y").tolist(), check_up([0, 0, 2]).tolist()
    ([0.0, -1.0, 0.0], [0.0, 0.0, 1.0])
    """
    if isinstance(value, str):
        if value not in AXES:
            raise ParameterError(f"{name} must be an axis ({', '.join(AXES)}) or 3 numbers, "
                                 f"got {value!r}")
        return np.array(AXES[value], dtype=np.float64)
    try:
        v = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        v = np.zeros(0)
    length = float(np.linalg.norm(v)) if v.shape == (3,) and np.isfinite(v).all() else 0.0
    if not length > 0 or not math.isfinite(length):
        raise ParameterError(f"{name} must be an axis ({', '.join(AXES)}) or 3 finite "
                             f"numbers, not all zero, got {value!r}")
    return v / length
