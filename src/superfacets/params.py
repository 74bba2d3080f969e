"""Defaults, choices and validation of every parameter, defined once.

The API (:func:`superfacets.superfacets`, :func:`superfacets.segment`), the
command line, the method registry and the docs read the values here;
:func:`resolve` checks every parameter of a segmentation before any work that
grows with the mesh (the element graph is the memory peak of a run). The
``check_*`` helpers are the package's only argument checks: each raises
:class:`~superfacets.errors.ParameterError` (a ``ValueError``) naming the
parameter and the bad value.

See ``docs/method.md`` for what each parameter means in the method.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from .elements.kinds import KINDS, kind_of
from .errors import ParameterError

__all__ = ["SegmentParams", "DEFAULTS", "INITS", "ASSIGNMENTS", "WEIGHTINGS", "ELEMENTS",
           "WEIGHTING_ALPHA", "DEFAULT_CENTER_TOL", "COARSE_MIN_PER_SEGMENT",
           "COARSE_MIN_PER_SEGMENT_POINTS", "COARSE_PER_SEGMENT_POINTS",
           "COARSE_PER_SEGMENT", "DEFAULT_N_SEGMENTS", "DEFAULT_ALPHAS", "resolve", "check_int",
           "check_number", "check_positive", "check_nonneg", "check_choice",
           "check_n_segments", "check_threads", "check_bool", "max_threads", "superfacet_size",
           "better_method", "assignment_of", "superfacet_measure"]

#: Names accepted by ``init=``: iterative farthest point, flood, regular grid.
INITS = ("farthest", "flood", "grid")
#: Names accepted by ``assignment=``: the paper's window-bounded expansions, or
#: the exact nearest center by one multi-source Dijkstra.
ASSIGNMENTS = ("bounded", "exact")
#: Names accepted by ``weighting=``: the paper's eqs. 1-3, Shlafman et al.'s eq. 6.
WEIGHTINGS = ("paper", "shlafman")
#: Names accepted by ``elements=``: the faces of a mesh, its vertices, the points of a cloud.
ELEMENTS = ("faces", "vertices", "points")
#: Largest number of nearest neighbours of the point graph.
MAX_NEIGHBORS = 100
#: Default ``alpha`` of each weighting, and its valid range ``(low, high)``.
WEIGHTING_ALPHA = {"paper": (200.0, (0.0, math.inf)), "shlafman": (0.5, (0.0, 1.0))}
#: Largest alpha and eta_convex (beyond, the angular term alone decides anyway; infinite
#: weights would stall the expansions) and largest window (beyond, every window holds
#: the whole mesh).
MAX_WEIGHT_FACTOR = 1e12
MAX_WINDOW = 1e3
#: The paper's sweep (Fig. 4): numbers of superfacets and alphas.
DEFAULT_N_SEGMENTS = (50, 100, 150, 200, 250, 300)
DEFAULT_ALPHAS = (0.0, 100.0, 200.0, 500.0, 1000.0)
def better_method(params: "SegmentParams", kind: str) -> tuple[bool, bool]:
    """``(cleanup, split_merge)`` of a run on elements ``kind``: as given, else (None)
    on for faces and vertices with the paper's weighting (unless ``paper``), off
    for points, tetrahedral cells (not measured) and with another weighting.

    On faces both beat the paper at every k from 50 to 300 (UE -6 to -11 %,
    compactness -14 to -19 %) and in every category of the 300 benchmark meshes
    but Cup at k = 50 and 150, at its speed at the default k (``docs/cleanup.md``,
    "The default" and "Swap energies"); on vertices, with the clean-up's
    crease weight and band of that kind (:mod:`superfacets.cleanup`) and the exact
    classification (:func:`assignment_of`), they lower the undersegmentation
    error by 4-8 % and the compactness by 5-7 % at k = 50, 150, 300. On points they lower the compactness by 18-25 %
    but not the undersegmentation error at k = 150 (+0.3 %), so points keep
    the paper's method unless asked (``docs/cleanup.md``, "Vertices and points").
    """
    auto = kind_of(kind).better_method and params.weighting == "paper" and not params.paper
    return (auto if params.cleanup is None else bool(params.cleanup),
            auto if params.split_merge is None else bool(params.split_merge))


def assignment_of(params: "SegmentParams", kind: str) -> str:
    """The classification of a run on elements ``kind``: as given, else (None)
    ``'exact'`` on vertices with the paper's weighting (unless ``paper``) and in
    content-sensitive runs (``density`` or ``roughness``), the paper's
    ``'bounded'`` everywhere else.

    On vertices the exact nearest-center search (one multi-source search per
    pass, every element settled once, where the bounded windows settle each
    about 4.4 times) gives the same quality as the windows with the default's
    few passes, for about a third of their time; that is what brings the
    better method to the paper's time there. On faces the windows' bound on a
    superfacet's extent keeps them more compact (``docs/cleanup.md``, "The
    default on vertices, at the paper's speed"). Content-sensitive superfacets
    differ in extent by design; the windows follow it (each center's scaled by
    :func:`superfacets.adaptive.window_factors`) and are about 1.6 times faster
    on a million points, but on the five labelled scans the exact search gave
    the lower undersegmentation error in 11 of 15 settings (``docs/superpoints.md``).

    Examples
    --------
    >>> assignment_of(DEFAULTS, "vertices"), assignment_of(DEFAULTS, "faces")
    ('exact', 'bounded')
    """
    if params.assignment is not None:
        return params.assignment
    auto = kind_of(kind).exact_assignment and params.weighting == "paper" and not params.paper
    content = (params.density or 0.0) > 0 or params.roughness > 0
    return "exact" if auto or content else "bounded"


#: ``center_tol`` when ``tol > 0`` and none is given (fraction of the superfacet radius).
DEFAULT_CENTER_TOL = 0.05
#: Automatic coarse-to-fine (``coarsen=None``, ``tol > 0``): the faces' (and vertices')
#: thresholds and the points', from the table of kinds (:mod:`superfacets.elements.kinds`:
#: ``coarse_min_per_segment``, ``coarse_per_segment``). On points, clusters of at most
#: ``n_neighbors // 2`` (15 benchmark meshes sampled with 200,000 points: clusters of 5
#: keep UE, k = 50: +0.5 %, k = 100: -2.2 %, and take 42 % off the time;
#: docs/superpoints.md).
COARSE_MIN_PER_SEGMENT = kind_of("faces").coarse_min_per_segment
COARSE_PER_SEGMENT = kind_of("faces").coarse_per_segment
COARSE_MIN_PER_SEGMENT_POINTS = kind_of("points").coarse_min_per_segment
COARSE_PER_SEGMENT_POINTS = kind_of("points").coarse_per_segment


@dataclass(frozen=True)
class SegmentParams:
    """Every parameter of one segmentation (see :func:`superfacets.superfacets`).

    ``DEFAULTS`` holds the default of each; :func:`resolve` returns a
    validated instance with ``init`` resolved.
    """

    n_segments: int | None = 150
    radius: float | None = None
    alpha: float = WEIGHTING_ALPHA["paper"][0]
    eta_convex: float = 0.2
    window: float = 2.0
    init: str | None = None
    max_iter: int = 50
    weighting: str = "paper"
    assignment: str | None = None
    enforce_connectivity: bool = True
    cleanup: bool | None = None
    split_merge: bool | None = None
    tol: float = 0.001
    center_tol: float | None = None
    coarsen: int | None = None
    progress: bool = False
    n_threads: int | None = None
    elements: str | None = None
    n_neighbors: int = 10
    neighbor_radius: float | None = None
    paper: bool = False
    beta: float = 0.0
    min_elements: int = 1
    density: float | None = None
    roughness: float = 0.0

    def as_dict(self) -> dict:
        """The parameters as a plain dict."""
        return asdict(self)


#: The default of every parameter.
DEFAULTS = SegmentParams()


def _is_int(value) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def check_int(name: str, value, lo: int | None = None, hi: int | None = None) -> int:
    """``value`` as an int in ``[lo, hi]``; booleans and floats are refused.

    Raises
    ------
    ParameterError
    """
    if not _is_int(value):
        raise ParameterError(f"{name} must be an integer, got {value!r}")
    v = int(value)
    if lo is not None and v < lo:
        raise ParameterError(f"{name} must be an integer >= {lo}, got {v}")
    if hi is not None and v > hi:
        raise ParameterError(f"{name} must be an integer <= {hi}, got {v}")
    return v


def check_number(name: str, value, lo: float = -math.inf, hi: float = math.inf, *,
                 lo_open: bool = False) -> float:
    """``value`` as a finite float in ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``).

    Raises
    ------
    ParameterError
    """
    if isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name} must be a number, got {value!r}")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number, got {value!r}") from None
    low = f"> {lo:g}" if lo_open else f">= {lo:g}"
    rng = low if hi == math.inf else f"in {'(' if lo_open else '['}{lo:g}, {hi:g}]"
    if not math.isfinite(x) or (x <= lo if lo_open else x < lo) or x > hi:
        raise ParameterError(f"{name} must be a finite number {rng}, got {value!r}")
    return x


def check_positive(name: str, value) -> float:
    """A finite number ``> 0``."""
    return check_number(name, value, 0.0, lo_open=True)


def check_nonneg(name: str, value) -> float:
    """A finite number ``>= 0``."""
    return check_number(name, value, 0.0)


def check_bool(name: str, value) -> bool:
    """``True`` or ``False`` (numpy booleans accepted)."""
    if not isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def check_choice(name: str, value, choices) -> str:
    """One of ``choices``.

    Raises
    ------
    ParameterError
        Listing the choices.
    """
    if not isinstance(value, str) or value not in choices:
        raise ParameterError(f"{name} must be one of {', '.join(choices)}; got {value!r}")
    return value


def check_n_segments(n_segments, m: int, kind: str = "faces") -> int:
    """A number of segments ``k`` in ``1..m`` (``m`` the number of elements, of ``kind``).

    Raises
    ------
    ParameterError
        If ``n_segments`` is not an integer in ``1..m``.
    """
    k = check_int("n_segments", n_segments, lo=1)
    if k > m:
        raise ParameterError(f"n_segments ({k}) is larger than the number of {kind} ({m})")
    return k


def max_threads() -> int:
    """The most threads a run may use: 4 per core, at least 16 (each thread keeps
    about 12 bytes per element of buffers)."""
    import os

    return max(16, 4 * (os.cpu_count() or 1))


def check_threads(n_threads) -> int:
    """Resolve ``n_threads``: None gives numba's thread count (``NUMBA_NUM_THREADS``).

    Raises
    ------
    ParameterError
        If it is not an integer in ``1..max_threads()``.
    """
    if n_threads is None:
        import os
        import sys

        # numba's setting once numba is imported; while another thread (the
        # warm-up) is still importing it, its config may not be there yet
        config = getattr(sys.modules.get("numba"), "config", None)
        value = getattr(config, "NUMBA_NUM_THREADS", None)
        if value is not None:
            return int(value)
        # numba's own rule, without importing numba (checking arguments stays light)
        try:
            return max(1, int(os.environ["NUMBA_NUM_THREADS"]))
        except (KeyError, ValueError):
            try:
                return max(1, len(os.sched_getaffinity(0)))
            except AttributeError:  # pragma: no cover - not Linux
                return max(1, os.cpu_count() or 1)
    return check_int("n_threads", n_threads, lo=1, hi=max_threads())


def resolve(**params) -> SegmentParams:
    """Validate the parameters of a segmentation; return them with ``init`` resolved.

    Every check that does not need the mesh is done here, before any
    O(m) work. ``n_segments`` is checked against the number of elements later
    (:func:`check_n_segments`).

    Parameters
    ----------
    **params
        Fields of :class:`SegmentParams`; the others take their default.

    Returns
    -------
    SegmentParams

    Raises
    ------
    ParameterError
        On an unknown name or a value out of range; ``TypeError`` never.
    """
    unknown = set(params) - set(DEFAULTS.as_dict())
    if unknown:
        raise ParameterError(f"unknown parameter(s) {', '.join(sorted(unknown))}")
    p = replace(DEFAULTS, **params)
    if check_bool("paper", p.paper):  # the paper's method as published, bit for bit
        extra = [name for name, on in (("cleanup", p.cleanup), ("split_merge", p.split_merge),
                                       ("tol", p.tol not in (0, DEFAULTS.tol)),
                                       ("center_tol", p.center_tol is not None),
                                       ("coarsen", p.coarsen not in (None, 1)),
                                       ("beta", p.beta not in (0, 0.0)),
                                       ("min_elements", p.min_elements != 1),
                                       ("density", p.density not in (None, 0, 0.0)),
                                       ("roughness", p.roughness not in (0, 0.0))) if on]
        if extra:
            raise ParameterError(f"paper=True is the paper's method as published; it does not "
                                 f"go with {', '.join(extra)}")
        p = replace(p, tol=0.0)
    min_elements = check_int("min_elements", p.min_elements, lo=1)
    if min_elements > 1 and not check_bool("enforce_connectivity", p.enforce_connectivity):
        raise ParameterError("min_elements merges small superfacets as the connectivity step "
                             "merges stray pieces; it goes with enforce_connectivity=True")
    if p.radius is not None and p.n_segments not in (None, DEFAULTS.n_segments):
        raise ParameterError("give either n_segments or radius, not both")
    n_segments = None if p.radius is not None else (
        check_int("n_segments", DEFAULTS.n_segments if p.n_segments is None else p.n_segments,
                  lo=1))
    radius = None if p.radius is None else check_positive("radius", p.radius)
    init = p.init if p.init is not None else ("farthest" if radius is None else "flood")
    check_choice("init", init, INITS)
    weighting = check_choice("weighting", p.weighting, WEIGHTINGS)
    lo, hi = WEIGHTING_ALPHA[weighting][1]
    if weighting == "paper":
        alpha = check_number("alpha", p.alpha, 0.0, MAX_WEIGHT_FACTOR)
    else:
        try:
            alpha = check_number("alpha", p.alpha, lo, hi)
        except ParameterError:
            raise ParameterError(f"alpha of the Shlafman weighting must be in [0, 1], "
                                 f"got {p.alpha!r}") from None
    return SegmentParams(
        n_segments=n_segments, radius=radius, alpha=alpha,
        eta_convex=check_number("eta_convex", p.eta_convex, 0.0, MAX_WEIGHT_FACTOR),
        window=check_number("window", p.window, 0.0, MAX_WINDOW, lo_open=True), init=init,
        max_iter=check_int("max_iter", p.max_iter, lo=1), weighting=weighting,
        assignment=None if p.assignment is None else check_choice("assignment", p.assignment,
                                                                  ASSIGNMENTS),
        enforce_connectivity=check_bool("enforce_connectivity", p.enforce_connectivity),
        cleanup=None if p.cleanup is None else check_bool("cleanup", p.cleanup),
        split_merge=None if p.split_merge is None else check_bool("split_merge", p.split_merge),
        tol=check_number("tol", p.tol, 0.0, 1.0),
        center_tol=None if p.center_tol is None else check_number("center_tol", p.center_tol,
                                                                  0.0, 1.0),
        coarsen=None if p.coarsen is None else check_int("coarsen", p.coarsen, lo=1),
        progress=bool(p.progress),
        n_threads=check_threads(p.n_threads),
        elements=None if p.elements is None else check_choice("elements", p.elements,
                                                              tuple(KINDS)),
        n_neighbors=check_int("n_neighbors", p.n_neighbors, lo=1, hi=MAX_NEIGHBORS),
        neighbor_radius=None if p.neighbor_radius is None else check_positive(
            "neighbor_radius", p.neighbor_radius),
        paper=bool(p.paper), beta=_beta(p.beta, weighting), min_elements=min_elements,
        density=None if p.density is None else check_number("density", p.density, 0.0, 1.0),
        roughness=check_number("roughness", p.roughness, 0.0, MAX_WEIGHT_FACTOR))


def _beta(beta, weighting: str) -> float:
    b = check_number("beta", beta, 0.0, MAX_WEIGHT_FACTOR)
    if b > 0 and weighting != "paper":
        raise ParameterError("beta (the feature term) goes with weighting='paper' only")
    return b


def superfacet_size(params: SegmentParams, area: float, diagonal: float,
                    n_elements: int, kind: str = "faces") -> tuple[int | None, float]:
    """The number of centers ``k`` and the radius ``r`` (mesh units) of a run.

    With ``n_segments``: ``r = sqrt(A / (k pi))`` (paper section 3.1); on
    tetrahedra (``kind = "cells"``, ``A`` a volume) ``r = (3 A / (4 pi k))^(1/3)``. With
    ``radius`` (a fraction of ``d``): ``r = radius * d``, and for the
    farthest-point initialization ``k = round(A / (pi r^2))`` clamped to
    ``1..n``; ``k`` is None for flood and grid.

    Raises
    ------
    ParameterError
        If ``n_segments`` exceeds the number of elements, or ``radius`` is so
        small that a superfacet's area (volume) is 0 in double precision.
    """
    profile = kind_of(kind)  # ``area`` is a volume on cells: r of a ball of volume V / k
    if params.radius is not None:
        r = params.radius * diagonal
        each = superfacet_measure(r, profile.dim)
        if not each > 0:
            raise ParameterError(f"radius {params.radius:g} of the diagonal ({r:.3g} in the "
                                 "input's units) is too small: a superfacet's "
                                 f"{profile.size_word} would be 0")
        k = None
        if params.init == "farthest":
            k = int(min(n_elements, max(1, round(area / each))))
        return k, r
    k = check_n_segments(params.n_segments, n_elements, profile.name)
    if profile.dim == 3:
        return k, (3.0 * area / (4.0 * math.pi * k)) ** (1.0 / 3.0)
    return k, math.sqrt(area / (k * math.pi))


def superfacet_measure(r: float, dim: int = 2) -> float:
    """The size of one superfacet of radius ``r``: a disc's area ``pi r^2`` (paper
    section 3.1) on surfaces (``dim = 2``), a ball's volume ``4/3 pi r^3`` on
    tetrahedra (``dim = 3``).

    Examples
    --------
    >>> round(superfacet_measure(1.0), 4), round(superfacet_measure(1.0, 3), 4)
    (3.1416, 4.1888)
    """
    return 4.0 / 3.0 * math.pi * r ** 3 if dim == 3 else math.pi * r * r
