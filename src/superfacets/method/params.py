"""Defaults, choices and validation of every parameter, defined once.

The API (:func:`superfacets.superfacets`, :func:`superfacets.segment`), the
command line, the method registry and the docs read the values here;
:func:`resolve` checks every parameter of a segmentation before any work that
grows with the mesh (the element graph is the memory peak of a run). The
``check_*`` helpers are the package's only argument checks: each raises
:class:`~superfacets.errors.ParameterError` (a ``ValueError``) naming the
parameter and the bad value.

See ``docs/notes/method.md`` for what each parameter means in the method.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, make_dataclass, replace
from typing import Callable

from ..checks import (
    check_bool,
    check_choice,
    check_int,
    check_n_segments,
    check_nonneg,
    check_number,
    check_positive,
    check_threads,
    max_threads,
)
from ..elements.kinds import KINDS, kind_of
from ..elements.points import DEFAULT_NEIGHBORS, MAX_NEIGHBORS  # noqa: F401 (re-exported)
from ..errors import ParameterError
from .rules import assignment_of, better_method, superfacet_measure, superfacet_size  # noqa: F401

__all__ = ["SegmentParams", "DEFAULTS", "Parameter", "PARAMETERS", "PARAMETER", "ALL_KINDS",
           "INITS", "ASSIGNMENTS", "WEIGHTINGS", "ELEMENTS", "MERGE_COSTS",
           "WEIGHTING_ALPHA", "DEFAULT_CENTER_TOL", "COARSE_MIN_PER_SEGMENT",
           "COARSE_MIN_PER_SEGMENT_POINTS", "COARSE_PER_SEGMENT_POINTS",
           "COARSE_PER_SEGMENT", "DEFAULT_N_SEGMENTS", "DEFAULT_ALPHAS", "resolve", "check_int",
           "check_number", "check_positive", "check_nonneg", "check_choice", "check_radius",
           "check_n_segments", "check_threads", "check_bool", "max_threads", "superfacet_size",
           "better_method", "assignment_of", "superfacet_measure"]

#: Names accepted by ``init=``: iterative farthest point, flood, regular grid.
INITS = ("farthest", "flood", "grid")
#: Names accepted by ``assignment=``: the paper's window-bounded expansions, or
#: the exact nearest center by one multi-source Dijkstra.
ASSIGNMENTS = ("bounded", "exact")
#: Names accepted by ``weighting=``: the paper's eqs. 1-3, Shlafman et al.'s eq. 6.
WEIGHTINGS = ("paper", "shlafman")
#: The merges' costs to the count (``merge_cost``): ``'auto'`` the plane's rise where the
#: flat regions hold most of the points, else Ward's; ``'scene'`` one cost on every input
#: (:func:`superfacets.method.merges.scene_merge_nodes`); ``'noise'`` that cost with its
#: rise weighted by the noise's share of the superpoints' residual
#: (:func:`superfacets.method.merges.rise_weight`).
MERGE_COSTS = ("auto", "scene", "noise")
#: Names accepted by ``elements=``: the faces of a mesh, its vertices, the points of a cloud
#: (the kinds of surface elements of :data:`~superfacets.elements.kinds.KINDS`).
ELEMENTS = tuple(name for name, kind in KINDS.items() if kind.dim == 2)
#: Default ``alpha`` of each weighting, and its valid range ``(low, high)``.
WEIGHTING_ALPHA = {"paper": (200.0, (0.0, math.inf)), "shlafman": (0.5, (0.0, 1.0))}
#: Largest alpha and eta_convex (beyond, the angular term alone decides anyway; infinite
#: weights would stall the expansions) and largest window (beyond, every window holds
#: the whole mesh).
MAX_WEIGHT_FACTOR = 1e12
MAX_WINDOW = 1e3
#: Largest radius, a fraction of the bounding-box diagonal (beyond 1 a superfacet is the
#: whole input; far beyond, its area overflows a float).
MAX_RADIUS = 1e3
#: Largest ``up_weight`` (beyond, a cloud's points are layers apart whatever their spacing).
MAX_UP_WEIGHT = 100.0


def check_radius(value) -> float:
    """``radius`` (a fraction of the bounding-box diagonal) as a float in
    ``(0, MAX_RADIUS]``.

    Parameters
    ----------
    value : object
        A number, or a string of one.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        If it is not a finite number in that range.

    Examples
    --------
    >>> check_radius(0.05)
    0.05
    """
    return check_number("radius", value, 0.0, MAX_RADIUS, lo_open=True)


#: The paper's sweep (Fig. 4): numbers of superfacets and alphas.
DEFAULT_N_SEGMENTS = (50, 100, 150, 200, 250, 300)
DEFAULT_ALPHAS = (0.0, 100.0, 200.0, 500.0, 1000.0)
#: ``center_tol`` when ``tol > 0`` and none is given (fraction of the superfacet radius).
DEFAULT_CENTER_TOL = 0.05
#: Automatic coarse-to-fine (``coarsen=None``, ``tol > 0``): the faces' (and vertices')
#: thresholds and the points', from the table of kinds (:mod:`superfacets.elements.kinds`:
#: ``coarse_min_per_segment``, ``coarse_per_segment``). On points, clusters of at most
#: ``n_neighbors // 2`` (the error kept in less time: docs/notes/superpoints.md).
COARSE_MIN_PER_SEGMENT = kind_of("faces").coarse_min_per_segment
COARSE_PER_SEGMENT = kind_of("faces").coarse_per_segment
COARSE_MIN_PER_SEGMENT_POINTS = kind_of("points").coarse_min_per_segment
COARSE_PER_SEGMENT_POINTS = kind_of("points").coarse_per_segment


#: Every kind of element (:data:`~superfacets.elements.kinds.KINDS`), cells too.
ALL_KINDS = tuple(KINDS)


@dataclass(frozen=True)
class Parameter:
    """The declaration of one parameter of the method: the one place that says it.

    :class:`SegmentParams` (its fields and defaults), :func:`resolve` (its check),
    the command line's options, the method registry and the Parameters section of
    :func:`superfacets.superfacets` come from :data:`PARAMETERS` or are tested
    against it (``tests/method/test_params.py``).

    Attributes
    ----------
    name : str
        The keyword of :func:`superfacets.segment` (and the field of
        :class:`SegmentParams`).
    default : object
        Its default; ``None`` where the method decides (an automatic rule,
        resolved once per run by :func:`superfacets.method.pipeline.resolve_rules`).
    type : str
        The type, as the docstrings write it (``'int'``, ``'float'``, ``'bool'``,
        ``'str'``; ``' or None'`` where None is accepted).
    doc : str
        One line: what it is, its range and unit.
    check : callable or None
        ``check(value) -> value``: the validated value (raises
        :class:`~superfacets.errors.ParameterError`); None where the check needs
        another parameter (done by :func:`resolve`).
    kinds : tuple of str
        The kinds of element it applies to.
    cli : str or None
        The command line's option (``segment``), or None.
    choices : tuple of str
        The values a string parameter takes (its option's choices), else empty.
    auto : bool
        None is resolved by ``check`` itself (``n_threads``: ``SUPERFACETS_NUM_THREADS`` or the
        cores).

    Examples
    --------
    >>> p = PARAMETER["alpha"]
    >>> p.default, p.cli, p.check is None
    (200.0, '--alpha', True)
    >>> PARAMETER["n_neighbors"].kinds, PARAMETER["radius"].optional
    (('points',), True)
    """

    name: str
    default: object
    type: str
    doc: str
    check: Callable[[object], object] | None = field(default=None, repr=False, compare=False)
    kinds: tuple = ALL_KINDS
    cli: str | None = None
    auto: bool = False
    choices: tuple = ()

    @property
    def optional(self) -> bool:
        """Whether None is accepted (the method then decides)."""
        return self.type.endswith("or None")


def _declare() -> tuple[Parameter, ...]:
    P, num, integer, flag = Parameter, check_number, check_int, check_bool
    big = MAX_WEIGHT_FACTOR
    return (
        P("n_segments", 150, "int or None", "number of superfacets k, 1 <= k <= elements "
          "(paper section 3.1); None with radius", None, cli="--n-segments"),
        P("radius", None, "float or None", "superfacet radius, a fraction of the bounding-box "
          "diagonal, in (0, 1000] (instead of n_segments)",
          lambda v: check_radius(v), cli="--radius"),
        P("alpha", WEIGHTING_ALPHA["paper"][0], "float", "weight of the angular (concavity) "
          "term, eq. 3, >= 0; in [0, 1] with weighting='shlafman' (eq. 6)", None, cli="--alpha"),
        P("eta_convex", 0.2, "float", "factor of the angular term on convex edges, eq. 2, >= 0",
          lambda v: num("eta_convex", v, 0.0, big), cli="--eta-convex"),
        P("window", 2.0, "float", "expansion window, a multiple of the radius, > 0 "
          "(section 3.1)", lambda v: num("window", v, 0.0, MAX_WINDOW, lo_open=True),
          cli="--window"),
        P("init", None, "str or None", "initialization: " + ", ".join(INITS) + " (default "
          "farthest with n_segments, flood with radius)",
          lambda v: check_choice("init", v, INITS), cli="--init", choices=INITS),
        P("max_iter", 50, "int", "most classification passes, >= 1",
          lambda v: integer("max_iter", v, lo=1), cli="--max-iter"),
        P("weighting", "paper", "str", "edge weights: paper (eqs. 1-3) or shlafman (eq. 6)",
          lambda v: check_choice("weighting", v, WEIGHTINGS), cli="--weighting",
          choices=WEIGHTINGS),
        P("assignment", None, "str or None", "classification: bounded (the paper's windows) "
          "or exact (nearest center); None: by kind and content",
          lambda v: check_choice("assignment", v, ASSIGNMENTS), cli="--assignment",
          choices=ASSIGNMENTS),
        P("enforce_connectivity", True, "bool", "merge stray pieces so each superfacet is "
          "connected", lambda v: flag("enforce_connectivity", v), cli="--no-connectivity"),
        P("cleanup", None, "bool or None", "boundary clean-up after the iteration; None: by "
          "kind", lambda v: flag("cleanup", v), cli="--cleanup"),
        P("split_merge", None, "bool or None", "K-preserving split-and-merge swaps; None: by "
          "kind", lambda v: flag("split_merge", v), cli="--split-merge"),
        P("tol", 0.001, "float", "stop once a pass changes at most this fraction of the area, "
          "in [0, 1]; 0: the paper's rule", lambda v: num("tol", v, 0.0, 1.0), cli="--tol"),
        P("center_tol", None, "float or None", "a center moving less than this fraction of "
          "the radius stays, in [0, 1]; None: 0.05 with tol > 0, else 0",
          lambda v: num("center_tol", v, 0.0, 1.0), cli="--center-tol"),
        P("coarsen", None, "int or None", "coarse-to-fine: elements per cluster, >= 1 (1: "
          "off); None: by size and kind", lambda v: integer("coarsen", v, lo=1),
          cli="--coarsen"),
        P("progress", False, "bool", "a progress bar on stderr", bool, cli="--progress"),
        P("n_threads", None, "int or None", "threads of the run, 1..max_threads(); None: "
          "SUPERFACETS_NUM_THREADS or the cores", check_threads, cli="--threads", auto=True),
        P("elements", None, "str or None", "what is segmented: " + ", ".join(ALL_KINDS) +
          "; None: the input's default", lambda v: check_choice("elements", v, tuple(KINDS)),
          cli="--elements", choices=ELEMENTS),
        P("n_neighbors", DEFAULT_NEIGHBORS, "int", "nearest neighbours of each point in the "
          f"point graph, 1..{MAX_NEIGHBORS}",
          lambda v: integer("n_neighbors", v, lo=1, hi=MAX_NEIGHBORS), ("points",),
          cli="--neighbors"),
        P("neighbor_radius", None, "float or None", "drop neighbours farther than this "
          "fraction of the diagonal, > 0", lambda v: check_positive("neighbor_radius", v),
          ("points",), cli="--neighbor-radius"),
        P("paper", False, "bool", "the paper's method as published, its labels bit for bit",
          bool, cli="--paper"),
    )


def _declare_scan_parameters() -> tuple[Parameter, ...]:
    """The declarations of the colour term and of what scans add (sizes, merges, the
    vertical's weight), after the method's own."""
    P, num, integer = Parameter, check_number, check_int
    big = MAX_WEIGHT_FACTOR
    return (
        P("beta", None, "float or None", "weight of the feature (colour) term, >= 0; paper "
          "weighting only; None: read from the data where the input has colours or features "
          "are given, else 0", None, cli="--beta"),
        P("min_elements", 1, "int", "smallest superfacet in elements, >= 1; smaller ones "
          "merged at the end", lambda v: integer("min_elements", v, lo=1),
          cli="--min-elements"),
        P("density", None, "float or None", "content-sensitive sizes: exponent q in [0, 1] "
          "(0 equal areas, 1 equal counts); None: by kind and density",
          lambda v: num("density", v, 0.0, 1.0), cli="--density"),
        P("roughness", 0.0, "float", "content-sensitive sizes: smaller superfacets where "
          "normals turn, >= 0", lambda v: num("roughness", v, 0.0, big), cli="--roughness"),
        P("merge_from", None, "int or None", "segment this many times n_segments first (at "
          "least one per 100 elements), then merge neighbours down to n_segments, flat ones "
          "first, >= 1 (1: off); None: by kind, density and up direction (a scene's 20)",
          lambda v: integer("merge_from", v, lo=1), cli="--merge-from"),
        P("max_size_ratio", None, "float or None", "merges to n_segments (merge_from > 1): "
          "no superpoint of more than this many times the mean count of elements while "
          "other neighbours can merge, >= 1; 0: no bound; None: 4 on a scene (a cloud with "
          "an up direction), else 16", _size_ratio, cli="--max-size-ratio"),
        P("merge_cost", "noise", "str", "merges to n_segments (merge_from > 1): noise (the "
          "rise in noise units weighted by the noise's share, plus Ward's), auto (the rise "
          "where flat regions hold most points, else Ward's; the default before 2026-11-30) "
          "or scene (noise's, unweighted)", _merge_cost, cli="--merge-cost",
          choices=MERGE_COSTS),
        P("up_weight", None, "float or None", "weight of a point cloud's up coordinate in "
          "the method's distances (its up: a LAS, LAZ or E57 file's z), in (0, 100]; 1: none; "
          "None: read from a scene's surfaces (1 to 8, the more its planes lie level; "
          "inputs.cloud.surface_up_weight), else 1",
          lambda v: num("up_weight", v, 0.0, MAX_UP_WEIGHT, lo_open=True), ("points",),
          cli="--up-weight"),
        P("step_weight", None, "float or None", "weight of a step off a cloud's surface (the "
          "part of a neighbour's offset along the normals) in the choice of its neighbours "
          "and in the method's distances, in [1, 100]; 1: none; None: 4 on a scene (a cloud "
          "with an up direction), else 1",
          lambda v: num("step_weight", v, 1.0, MAX_UP_WEIGHT), ("points",),
          cli="--step-weight"),
    )


def _merge_cost(value) -> str:
    """``merge_cost``: one of :data:`MERGE_COSTS`."""
    return check_choice("merge_cost", value, MERGE_COSTS)


def _size_ratio(value) -> float | None:
    """``max_size_ratio``: None (by the input), 0 (no bound) or a number ``>= 1``."""
    if value is None:
        return None
    try:
        x = check_number("max_size_ratio", value, 0.0, MAX_WEIGHT_FACTOR)
    except ParameterError as e:  # (inf, nan, negative: say what means "no bound")
        raise ParameterError(f"{e}; 0 means no bound") from None
    if 0.0 < x < 1.0:
        raise ParameterError(f"max_size_ratio must be 0 (no bound) or at least 1 (a "
                             f"superpoint of the mean size), got {value!r}")
    return x


#: Every parameter of the method, declared once (:class:`Parameter`), in the order of
#: :func:`superfacets.superfacets`'s signature.
PARAMETERS: tuple[Parameter, ...] = _declare() + _declare_scan_parameters()
#: The declarations by name.
PARAMETER = {p.name: p for p in PARAMETERS}


def _as_dict(self) -> dict:
    """The parameters as a plain dict."""
    return asdict(self)


#: Every parameter of one segmentation, a frozen dataclass whose fields and defaults are
#: :data:`PARAMETERS` (see :func:`superfacets.superfacets`). ``DEFAULTS`` holds the
#: default of each; :func:`resolve` returns a validated instance with ``init`` resolved.
SegmentParams = make_dataclass(
    "SegmentParams", [(p.name, object, field(default=p.default)) for p in PARAMETERS],
    frozen=True, namespace={"as_dict": _as_dict, "__module__": __name__, "__doc__": (
        "Every parameter of one segmentation (see :func:`superfacets.superfacets`); its "
        "fields are declared in :data:`superfacets.method.params.PARAMETERS`.\n\n"
        "``DEFAULTS`` holds the default of each; :func:`superfacets.method.params.resolve` returns "
        "a validated instance with ``init`` resolved.\n\n"
        "Attributes\n----------\n" + "".join(
            f"{p.name} : {p.type}, default {p.default!r}\n    {p.doc}.\n" for p in PARAMETERS)
        + "\nExamples\n--------\n>>> DEFAULTS.alpha, DEFAULTS.n_segments\n(200.0, 150)\n")})

#: The default of every parameter.
DEFAULTS = SegmentParams()


def resolve(**params) -> SegmentParams:
    """Validate the parameters of a segmentation; return them with ``init`` resolved.

    Every check that does not need the input is done here, before any O(m) work:
    each parameter's own (:data:`PARAMETERS`), then those between parameters
    (``paper`` and what it excludes, ``n_segments`` or ``radius``, ``alpha`` and
    ``beta`` by ``weighting``, ``min_elements`` and ``enforce_connectivity``).
    ``n_segments`` is checked against the number of elements when the input is
    known, before its graph is built (:func:`superfacets.elements.builders.elements_of`).

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

    Examples
    --------
    >>> resolve(radius=0.05).init, resolve().init
    ('flood', 'farthest')
    >>> resolve(alpha=-1)
    Traceback (most recent call last):
    ...
    superfacets.errors.ParameterError: alpha must be a finite number in [0, 1e+12], got -1
    """
    unknown = set(params) - set(PARAMETER)
    if unknown:
        word = "parameter" if len(unknown) == 1 else "parameters"
        raise ParameterError(f"unknown {word} {', '.join(sorted(unknown))}")
    p = replace(DEFAULTS, **params)
    if check_bool("paper", p.paper):  # the paper's method as published, bit for bit
        extra = [name for name, on in (("cleanup", p.cleanup), ("split_merge", p.split_merge),
                                       ("tol", p.tol not in (0, DEFAULTS.tol)),
                                       ("center_tol", p.center_tol is not None),
                                       ("coarsen", p.coarsen not in (None, 1)),
                                       ("beta", p.beta not in (None, 0, 0.0)),
                                       ("min_elements", p.min_elements != 1),
                                       ("density", p.density not in (None, 0, 0.0)),
                                       ("roughness", p.roughness not in (0, 0.0)),
                                       ("merge_from", p.merge_from not in (None, 1)),
                                       ("up_weight", p.up_weight not in (None, 1)),
                                       ("step_weight", p.step_weight not in (None, 1))) if on]
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
    radius = None if p.radius is None else check_radius(p.radius)
    init = p.init if p.init is not None else ("farthest" if radius is None else "flood")
    check_choice("init", init, INITS)
    weighting = check_choice("weighting", p.weighting, WEIGHTINGS)
    if params.get("alpha") is None:  # the weighting's own default (Shlafman's: 0.5)
        p = replace(p, alpha=WEIGHTING_ALPHA[weighting][0])
    lo, hi = WEIGHTING_ALPHA[weighting][1]
    if weighting == "paper":
        alpha = check_number("alpha", p.alpha, 0.0, MAX_WEIGHT_FACTOR)
    else:
        try:
            alpha = check_number("alpha", p.alpha, lo, hi)
        except ParameterError:
            raise ParameterError(f"alpha of the Shlafman weighting must be in [0, 1], "
                                 f"got {p.alpha!r}") from None
    done = dict(n_segments=n_segments, radius=radius, alpha=alpha, init=init,
                weighting=weighting, beta=_beta(p.beta, weighting, p.paper),
                min_elements=min_elements)
    out = {}
    for decl in PARAMETERS:  # each parameter's own check, in the signature's order
        value = getattr(p, decl.name)
        if decl.name in done:
            out[decl.name] = done[decl.name]
        elif value is None and decl.optional and not decl.auto:
            out[decl.name] = None
        else:
            out[decl.name] = decl.check(value)
    return SegmentParams(**out)


def _beta(beta, weighting: str, paper: bool = False) -> float | None:
    if beta is None:  # read from the data (superfacets.method.stages.resolve_features)
        return 0.0 if paper or weighting != "paper" else None
    b = check_number("beta", beta, 0.0, MAX_WEIGHT_FACTOR)
    if b > 0 and weighting != "paper":
        raise ParameterError("beta (the feature term) goes with weighting='paper' only")
    return b
