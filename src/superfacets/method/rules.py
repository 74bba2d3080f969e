"""The automatic rules of a run that depend on the kind of element: whether the clean-up
and split-and-merge run, which classification, and the superfacet size (paper section
3.1). Each reads the table of kinds (:mod:`superfacets.elements.kinds`); the run resolves
them once (:func:`superfacets.method.stages.resolve_rules`).
"""

from __future__ import annotations

import math

from ..checks import check_n_segments
from ..elements.graph import cached_on
from ..elements.kinds import kind_of
from ..errors import ParameterError
from ..inputs.cloud import surface_up_weight

__all__ = ["better_method", "assignment_of", "superfacet_size", "superfacet_measure",
           "merge_from_of", "fine_count", "MIN_FINE_ELEMENTS", "FINE_ELEMENTS",
           "MERGE_CHOICE", "FEWEST_FINE_ELEMENTS", "SCENE_MERGE_FROM", "SCENE_STEP_WEIGHT",
           "MAX_SIZE_RATIO", "SCENE_MAX_SIZE_RATIO", "SCENE_DEFAULTS", "scene_default_of",
           "up_weight_of"]

#: The fewest elements per superpoint, on average, of the many superpoints a run with
#: ``merge_from > 1`` segments first: fewer leave their planes to a few points and cost
#: time for nothing (``docs/notes/superpoints-defaults.md``).
MIN_FINE_ELEMENTS = 12
#: Where that floor leaves fewer first superpoints than this many times the count (a
#: count near a tenth of the points), the first run goes below it, down to
#: :data:`FEWEST_FINE_ELEMENTS` elements each, so that the merges still choose which
#: borders to keep: at the floor alone such a run was the plain run, its superpoints of
#: about 11 points straddling the ground's border (``docs/notes/superpoints-defaults.md``,
#: "Twice the count where the floor binds").
MERGE_CHOICE = 2
FEWEST_FINE_ELEMENTS = 4
#: The most elements per superpoint, on average, of those first superpoints: on a large
#: scan at a small ``k`` (an airborne tile of 700,000 points at k = 100: 1,400 points
#: each at 5 times) they are too large to keep to one surface, and the merges cannot
#: undo what they join (``docs/notes/superpoints-defaults.md``).
FINE_ELEMENTS = 100


def fine_count(k: int, merge_from: int, n_elements: int) -> int:
    """The superpoints a run with ``merge_from > 1`` segments before merging them down to
    ``k``: ``merge_from`` times ``k``, at least one per :data:`FINE_ELEMENTS` elements,
    at most one per :data:`MIN_FINE_ELEMENTS`, or where that is fewer than
    :data:`MERGE_CHOICE` times ``k``, that many, at most one per
    :data:`FEWEST_FINE_ELEMENTS` elements (and never fewer than ``k``).

    Parameters
    ----------
    k : int
        The count asked for, ``>= 1``.
    merge_from : int
        ``>= 1`` (:func:`merge_from_of`).
    n_elements : int
        The input's elements.

    Returns
    -------
    int
        ``>= k``.

    Raises
    ------
    TypeError
        Never for integers: nothing is checked (the run has checked ``k``).

    Examples
    --------
    >>> fine_count(300, 5, 20_000), fine_count(100, 5, 700_000), fine_count(3000, 5, 81_000)
    (1500, 7000, 6750)
    >>> fine_count(1000, 5, 20_000), fine_count(3000, 5, 34_000), fine_count(3000, 5, 7_500)
    (2000, 6000, 3000)
    """
    most = max(k, n_elements // MIN_FINE_ELEMENTS,
               min(MERGE_CHOICE * k, n_elements // FEWEST_FINE_ELEMENTS))
    return min(max(k * merge_from, n_elements // FINE_ELEMENTS), most)


def better_method(params, kind: str) -> tuple[bool, bool]:
    """``(cleanup, split_merge)`` of a run on elements ``kind``: as given, else (None)
    on for faces and vertices with the paper's weighting (unless ``paper``), off
    for points, tetrahedral cells (not measured) and with another weighting.

    On faces both beat the paper at every k from 50 to 300 at its speed
    (``docs/notes/cleanup.md``, "The default" and "Swap energies"); on vertices, with the
    clean-up's crease weight and band of that kind (:mod:`superfacets.method.cleanup`)
    and the exact classification (:func:`assignment_of`), they lower the
    undersegmentation error and the compactness. On points they lower the compactness
    but not the undersegmentation error, so points keep the paper's method unless asked
    (``docs/notes/cleanup.md``, "Vertices and points").

    Parameters
    ----------
    params : SegmentParams
    kind : str
        The kind of element (a row of :data:`superfacets.elements.kinds.KINDS`).

    Returns
    -------
    (bool, bool)
        ``(cleanup, split_merge)``.

    Raises
    ------
    ValueError
        For an unknown kind.

    Examples
    --------
    >>> from superfacets.method.params import DEFAULTS
    >>> better_method(DEFAULTS, "faces"), better_method(DEFAULTS, "points")
    ((True, True), (False, False))
    """
    auto = kind_of(kind).better_method and params.weighting == "paper" and not params.paper
    return (auto if params.cleanup is None else bool(params.cleanup),
            auto if params.split_merge is None else bool(params.split_merge))


def assignment_of(params, kind: str) -> str:
    """The classification of a run on elements ``kind``: as given, else (None)
    ``'exact'`` on vertices and points with the paper's weighting (unless ``paper``)
    and in content-sensitive runs (``density`` or ``roughness``), the paper's
    ``'bounded'`` everywhere else.

    The exact nearest-center search (one multi-source search per pass, every
    element settled once, where the bounded windows settle each about 4.4 times;
    compiled, by blocks of elements on threads) gives the windows' quality in less
    time. On vertices, a third of their time with the default's few passes: that is
    what brings the better method to the paper's time there (``docs/notes/cleanup.md``,
    "The default on vertices, at the paper's speed"); on points, the same error in
    less than half the passes' time (``docs/notes/superpoints-defaults.md``, "The exact
    search on every cloud"). On faces the windows' bound on a superfacet's extent keeps them
    more compact. Content-sensitive superfacets differ in extent by design; on the
    five labelled scans the exact search gave the lower undersegmentation error than
    windows scaled to each center's extent in 11 of 15 settings
    (``docs/notes/superpoints.md``).

    Parameters
    ----------
    params : SegmentParams
    kind : str

    Returns
    -------
    str
        ``'bounded'`` or ``'exact'``.

    Raises
    ------
    ValueError
        For an unknown kind.

    Examples
    --------
    >>> from superfacets.method.params import DEFAULTS
    >>> assignment_of(DEFAULTS, "points"), assignment_of(DEFAULTS, "faces")
    ('exact', 'bounded')
    """
    if params.assignment is not None:
        return params.assignment
    auto = kind_of(kind).exact_assignment and params.weighting == "paper" and not params.paper
    content = (params.density or 0.0) > 0 or params.roughness > 0
    return "exact" if auto or content else "bounded"


def superfacet_size(params, area: float, diagonal: float,
                    n_elements: int, kind: str = "faces") -> tuple[int | None, float]:
    """The number of centers ``k`` and the radius ``r`` (mesh units) of a run.

    With ``n_segments``: ``r = sqrt(A / (k pi))`` (paper section 3.1); on
    tetrahedra (``kind = "cells"``, ``A`` a volume) ``r = (3 A / (4 pi k))^(1/3)``. With
    ``radius`` (a fraction of ``d``): ``r = radius * d``, and for the
    farthest-point initialization ``k = round(A / (pi r^2))`` clamped to
    ``1..n``; ``k`` is None for flood and grid.


    Parameters
    ----------
    params : SegmentParams
    area : float
        Total size of the elements (an area; a volume on cells).
    diagonal : float
        The bounding-box diagonal ``d``.
    n_elements : int
    kind : str, default 'faces'

    Returns
    -------
    k : int or None
    r : float
        In the input's units.

    Raises
    ------
    ParameterError
        If ``n_segments`` exceeds the number of elements, or ``radius`` is so
        small that a superfacet's area (volume) is 0 in double precision.

    Examples
    --------
    >>> k, r = superfacet_size(resolve(n_segments=4), 4 * 3.141592653589793, 10.0, 100)
    >>> k, round(r, 6)
    (4, 1.0)
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


    Parameters
    ----------
    r : float
        The radius, in the input's units.
    dim : int, default 2
        2 for surfaces, 3 for tetrahedra.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        Never: no argument is checked here (:func:`superfacet_size` checks them).

    Examples
    --------
    >>> round(superfacet_measure(1.0), 4), round(superfacet_measure(1.0, 3), 4)
    (3.1416, 4.1888)
    """
    return 4.0 / 3.0 * math.pi * r ** 3 if dim == 3 else math.pi * r * r


#: ``merge_from`` (None) of a scene: a cloud with an up direction (``PointCloud.up``: LAS,
#: LAZ and E57 files, an RGB-D camera's PCD frame, ``--seen-from``), whose labels are
#: classes meeting at steps and bends, where the merges take the noise's cost (the
#: default): they choose from this many times the count. 27 labelled scans: 78 -> 88 of
#: 108 targets, 1.05 times the time; objects (no up direction), whose parts follow
#: Ward's compact merges, keep the kind's 5 (``docs/notes/superpoints-defaults.md``,
#: "Scenes merge from 20 times the count").
SCENE_MERGE_FROM = 20


#: ``step_weight`` (None) of a scene: a cloud with an up direction, whose classes meet at
#: steps (a roof over the ground, a kerb, a table on the floor). Its neighbours are chosen,
#: and its distances read, with the part of each offset along the normals weighed this
#: many times: on 27 labelled scans 88 -> 91 of 108 targets, mean UE -7 % (airborne -9 %,
#: street -3 %, rooms +4 %); objects (no up direction) keep 1, as their compactness
#: would worsen by 1 %
#: (``docs/notes/superpoints.md``, "A step off the surface").
SCENE_STEP_WEIGHT = 4.0


#: ``max_size_ratio`` (None) of an object: the merges to the count make no superpoint of
#: more than 16 times the mean while another pair may merge (flat faces left nearly whole).
MAX_SIZE_RATIO = 16.0
#: ``max_size_ratio`` (None) of a scene (a cloud with an up direction): 4 times the mean,
#: so the count goes where the surface changes and large flat pieces (ground, floors,
#: roofs) cannot take in the low things on them. On 27 labelled scans at k = 100-3,000
#: against the Segmentator: 91 -> 98 of 108 targets, mean boundary recall +0.016, mean UE
#: +1.9 %, oracle mIoU the same (16: 91, 6: 93, 3: 95, 2: 93;
#: ``docs/notes/superpoints.md``, "A scene's superpoints at most 4 times the mean").
SCENE_MAX_SIZE_RATIO = 4.0


#: The parameters whose default (None) a scene resolves otherwise: name -> (the value on
#: the points of a scene, a cloud with an up direction; the value elsewhere and with
#: ``paper``).
SCENE_DEFAULTS = {"step_weight": (SCENE_STEP_WEIGHT, 1.0),
                  "max_size_ratio": (SCENE_MAX_SIZE_RATIO, MAX_SIZE_RATIO)}


def scene_default_of(params, name: str, kind: str, scene: bool = False) -> float:
    """The value of parameter ``name`` (one of :data:`SCENE_DEFAULTS`) in a run: as given,
    else (None) its scene's value on the points of a ``scene`` (a cloud with an up
    direction), its other value elsewhere and with ``paper``.

    Parameters
    ----------
    params : SegmentParams
    name : str
        ``"step_weight"`` or ``"max_size_ratio"``.
    kind : str
        The kind of element.
    scene : bool, default False
        The input has an up direction (``PointCloud.up``).

    Returns
    -------
    float

    Raises
    ------
    KeyError
        For a parameter a scene does not resolve.
    ValueError
        For an unknown kind.

    Examples
    --------
    >>> from dataclasses import replace
    >>> from superfacets.method.params import DEFAULTS
    >>> [scene_default_of(DEFAULTS, name, "points", scene=True) for name in SCENE_DEFAULTS]
    [4.0, 4.0]
    >>> [scene_default_of(DEFAULTS, name, "points") for name in SCENE_DEFAULTS]
    [1.0, 16.0]
    >>> scene_default_of(DEFAULTS, "max_size_ratio", "faces", scene=True)
    16.0
    >>> scene_default_of(replace(DEFAULTS, max_size_ratio=0), "max_size_ratio", "points", True)
    0.0
    """
    on_scene, elsewhere = SCENE_DEFAULTS[name]
    given = getattr(params, name)
    if given is not None:
        return float(given)
    if params.paper or not scene or not kind_of(kind).cloud:
        return elsewhere
    return on_scene


def up_weight_of(params, kind: str, up=None, points=None, owner=None) -> float:
    """``up_weight`` of a run: as given, else (None) read off a scene's surfaces
    (:func:`superfacets.inputs.cloud.surface_up_weight`: 1 to 8, the more its planar
    neighbourhoods lie level), 1 on other inputs and with ``paper``.

    On 30 labelled scans at ``n_segments`` = 100-3,000 against the Segmentator (this
    machine, 2026-12-02; against a weight of 1): 109 -> 111 of 120 targets at full
    density, 104 -> 113 at half density (every 2nd point), airborne UE -28 %, oracle
    mIoU +0.035; the ScanNet rooms read 1 and stay as they were
    (``docs/notes/superpoints.md``, "The up weight's power").

    Parameters
    ----------
    params : SegmentParams
    kind : str
        The kind of element.
    up : (3,) float array-like, optional
        The input's up direction (None: not a scene).
    points : (n, 3) float ndarray, optional
        The positions the weight is read from (with ``up``; every point or an even
        sample in the input's order).
    owner : Mesh or PointCloud, optional
        The input ``points`` are of: the weight read is kept with it
        (:func:`~superfacets.elements.graph.cached_on`) and not read again.

    Returns
    -------
    float

    Raises
    ------
    ValueError
        For an unknown kind.

    Examples
    --------
    >>> import numpy as np
    >>> from dataclasses import replace
    >>> from superfacets.method.params import DEFAULTS
    >>> flat = np.c_[np.random.default_rng(0).random((500, 2)), np.zeros(500)]
    >>> up_weight_of(DEFAULTS, "points", (0, 0, 1), flat)    # level ground
    8.0
    >>> up_weight_of(DEFAULTS, "points", None, flat)         # no up: not a scene
    1.0
    >>> up_weight_of(replace(DEFAULTS, up_weight=1.5), "points", (0, 0, 1), flat)
    1.5
    """
    if params.up_weight is not None:
        return float(params.up_weight)
    if params.paper or up is None or points is None or not kind_of(kind).cloud:
        return 1.0
    if owner is None:
        return surface_up_weight(points, up)
    return cached_on(owner, "surface_up_weight", lambda: surface_up_weight(points, up))


def merge_from_of(params, kind: str, tiled: bool = False, scene: bool = False) -> int:
    """``merge_from`` of a run: as given, else (None) the kind's
    (:attr:`~superfacets.elements.kinds.ElementKind.merge_from`: 5 on points) where
    the merges take the scene's cost (``merge_cost`` ``'noise'``, the default, or
    ``'scene'``: measured with merges on every scan, uneven density too) or the
    superpoints have equal areas (``density`` resolved to 0: clouds of even density), 1
    elsewhere (``'auto'`` on LiDAR sweeps), with ``paper`` and in the tiles of a tiled run;
    on a ``scene`` (a cloud with an up direction) with ``merge_cost='noise'``,
    :data:`SCENE_MERGE_FROM`.

    On the even-density clouds measured (two ScanNet rooms, an airborne tile, the 300
    benchmark meshes sampled) merging 5 times the superpoints down to ``k``, flat
    neighbours first, lowered the undersegmentation error at every k; on LiDAR sweeps
    ``'auto'``'s merges lost to the density term, the scene's cost did not
    (``docs/notes/superpoints-defaults.md``).

    Parameters
    ----------
    params : SegmentParams
        With ``density`` resolved (:func:`superfacets.method.stages.build_graph`).
    kind : str
        The kind of element.
    tiled : bool, default False
        A tile of a tiled run (its count is the whole run's share).
    scene : bool, default False
        The input has an up direction (``PointCloud.up``).

    Returns
    -------
    int
        ``>= 1``; 1 segments ``k`` superpoints directly.

    Raises
    ------
    ValueError
        For an unknown kind.

    Examples
    --------
    >>> from dataclasses import replace
    >>> from superfacets.method.params import DEFAULTS
    >>> merge_from_of(replace(DEFAULTS, density=0.0), "points")
    5
    >>> merge_from_of(replace(DEFAULTS, density=0.5), "points"), merge_from_of(DEFAULTS, "faces")
    (5, 1)
    >>> merge_from_of(replace(DEFAULTS, density=0.5, merge_cost="auto"), "points")
    1
    >>> merge_from_of(DEFAULTS, "points", scene=True), merge_from_of(DEFAULTS, "faces", scene=True)
    (20, 1)
    """
    if params.merge_from is not None:
        return int(params.merge_from)
    if params.paper or tiled:
        return 1
    if (params.density or 0.0) > 0 and params.merge_cost not in ("scene", "noise"):
        return 1
    ratio = kind_of(kind).merge_from
    if scene and ratio > 1 and params.merge_cost == "noise":
        return max(ratio, SCENE_MERGE_FROM)
    return ratio
