"""The superfacet method's public functions (paper section 3; ``docs/notes/method.md``).

``superfacets(data, ...)`` returns one label per face; ``segment(data, ...)``
takes the same arguments and returns a :class:`SegmentationResult` with the
labels and the details (centers, iterations, convergence, time per stage);
``superpoints(points, ...)`` is the same method on a point cloud. Each
validates its parameters before any work and runs :func:`pipeline`
(:mod:`superfacets.method.pipeline`: the method step by step).
"""

from __future__ import annotations

import inspect
import os
import warnings

import numpy as np

from ..errors import ParameterError
from ..inputs.cloud import as_cloud
from ..method.params import DEFAULTS, PARAMETERS, resolve
from ..method.pipeline import pipeline
from .levels import START, adaptive_segment
from .result import SegmentationResult

__all__ = ["superfacets", "superpoints", "segment", "pipeline", "SegmentationResult"]

_D = DEFAULTS
#: ``data`` not given (the input may come as the keyword ``mesh`` of before)
_NO_INPUT = object()


def superfacets(data=_NO_INPUT, n_segments: int | None = _D.n_segments, *, features=None,
                **params) -> np.ndarray:
    """Over-segment a mesh (its faces or vertices) or a point cloud into superfacets.

    The k-means-style method of Simari, Picciau and De Floriani (2014):
    initialize centers, then alternate a classification (bounded Dijkstra
    expansions over the weighted face graph) and a center update until no
    center moves or ``max_iter`` passes have run.

    Parameters
    ----------
    data : Mesh, trimesh.Trimesh or tuple of ((n, 3) float, (m, 3) int) ndarray, or a point cloud
        Triangle or polygon mesh. Degenerate faces, unreferenced vertices,
        non-manifold edges and several connected components are accepted (each
        component gets its own superfacets); copies of a face (the same vertices, in
        any order) are one element and share its label. Or a point
        cloud (see :func:`superpoints`), or the path of a file of either (str or
        ``os.PathLike``, read by :func:`superfacets.io.read_input`). (Named ``mesh``
        before: ``mesh=`` still works, with a ``FutureWarning``.)
    n_segments : int, default 150
        Desired number of superfacets ``k``, ``1 <= k <= m``. The radius is
        then ``r = sqrt(A / (k pi))`` (section 3.1). Ignored, and must be left
        at its default or None, when ``radius`` is given.
    radius : float, optional
        Desired superfacet radius as a fraction of the bounding-box diagonal
        ``d`` (``r = radius * d``), ``> 0``. With ``init='farthest'`` the
        number of centers is then ``round(A / (pi r^2))``.
    alpha : float, default 200
        Weight of the angular (concavity) term, eq. 3; ``>= 0``. 0 gives the
        most compact superfacets, larger values follow concavities more.
        With ``weighting='shlafman'`` it must lie in ``[0, 1]`` (eq. 6).
    eta_convex : float, default 0.2
        Factor of the angular term on convex edges (concave edges: 1), eq. 2.
    window : float, default 2
        Expansion multiple: an expansion only reaches faces whose centroid is
        within ``window * r`` of its center's centroid (section 3.1).
    init : {'farthest', 'flood', 'grid'}, optional
        Initialization: iterative farthest point (default when ``radius`` is
        not given), flood (default when it is) or regular grid of cell ``2 r``.
    max_iter : int, default 50
        Maximum number of classification passes (``>= 1``).
    weighting : {'paper', 'shlafman'}, default 'paper'
        Edge weights: the paper's eqs. 1-3 or Shlafman et al.'s eq. 6.
    assignment : {'bounded', 'exact'}, optional
        ``'bounded'``: the paper's classification, one window-bounded
        Dijkstra per center, a face keeping the smallest distance seen.
        ``'exact'``: one multi-source search from all centers, no window, so
        every element goes to its nearest center along the graph (ties: the
        center listed first; the bounded version differs only where the
        shortest path to the nearest center leaves that center's window, and
        may leave orphans; after the first pass it searches again only the
        cells of the centers that moved, with the same result). Default
        (None): ``'exact'`` on vertices (with the paper's weighting, unless
        ``paper``) and in content-sensitive runs (``density`` or
        ``roughness`` above 0, the automatic density included), ``'bounded'``
        otherwise (:func:`~superfacets.method.params.assignment_of`;
        ``docs/notes/cleanup.md``). In content-sensitive runs the bounded windows
        are scaled per center (:func:`superfacets.elements.density.window_factors`).
    enforce_connectivity : bool, default True
        Merge stray pieces of a superfacet into the neighbour with which they
        share the longest boundary, so each superfacet is face-connected.
    cleanup : bool, optional
        Boundary clean-up after the iteration
        (:func:`superfacets.method.cleanup.clean_boundaries`): each boundary between
        two superfacets is re-placed within a third of a radius by a minimum
        graph cut that prefers short boundaries along creases; the number of
        superfacets does not change and each stays connected. Default: on
        for faces and vertices with the paper's weighting; off for points
        (not better on undersegmentation error there), with
        ``weighting='shlafman'`` and with ``paper=True``. Not in the paper
        (``docs/notes/cleanup.md``).
    split_merge : bool, optional
        K-preserving swaps (:mod:`superfacets.method.splitmerge`): a superfacet
        that straddles a crease (a high energy ``sum(size * d ** 4)`` in the
        paper's distance) is split in two while two neighbours elsewhere are
        merged, then the iteration runs again from the new centers. With
        ``tol > 0`` one round comes once a pass changes at most 20 % of the
        area, and at most 1 pass follows on faces (2 on vertices and
        points); with ``tol = 0`` up to 3 rounds, each iterated to
        convergence. Same number of superfacets. Default as ``cleanup``.
        Both on (the default on faces) against the paper on the 300
        benchmark meshes at ``k = 150``: undersegmentation error -7.8 %,
        compactness -15.5 %, boundary recall 0.805 (paper 0.802), for 0.88
        of its time (``docs/notes/cleanup.md``, "One pass after the swaps").
    paper : bool, default False
        The paper's method as published (Simari, Picciau, De Floriani 2014,
        section 3): its stopping rule (``tol=0``, no center tolerance, no
        coarse-to-fine), no clean-up, no split-and-merge; its labels bit for
        bit (tested against a straightforward implementation of the paper).
        Raises :class:`~superfacets.errors.ParameterError` with
        ``cleanup=True``, ``split_merge=True``, ``tol``, ``center_tol``,
        ``coarsen``, ``beta``, ``min_elements``, ``density``, ``roughness`` or
        ``merge_from`` above 1.
    beta : float or None, default None
        Weight of the feature (colour) term (not in the paper): ``beta * |e_ij| *
        max(0, ||f_i - f_j|| - floor)`` joins eq. 3's numerator, so crossing a colour
        (feature) edge costs as crossing a crease does; the clean-up prefers such
        edges for boundaries likewise. ``floor`` is the features' noise, the difference
        90 % of neighbouring elements stay under. None (the default) reads ``beta`` from the data
        where the input has colours or ``features`` are given: the term then weighs,
        on average over the adjacencies, as much as distance and angle together
        (:func:`superfacets.method.weights.feature_scale`); 0 without colours. 0
        gives the weights of the paper bit for bit (``docs/notes/method.md``,
        "Features"). The run's value is ``result.params["beta"]``.
    features : (N, d) float ndarray, optional
        One feature per input row (face, vertex or point), for ``beta > 0``.
        Default: the input's colours (a point cloud read from PLY, PCD or LAS
        with RGB, or ``PointCloud(colors=...)``).
    min_elements : int, default 1
        Smallest superfacet, in elements (not in the paper; as the ScanNet
        Segmentator's ``segMinVerts`` and scikit-image's ``min_size_factor``):
        at the end, a superfacet of fewer elements is merged into the
        neighbour it shares the longest border with
        (:func:`~superfacets.method.connectivity.enforce_connectivity`), so ``K``
        falls by the number merged. On a LiDAR sweep, whose sparse far range
        holds superpoints of one or two points, 3 merges 5-16 % of the superpoints at
        ``n_segments`` = 300-3,000 (``docs/notes/superpoints.md``, "Superpoints
        of one point"). 1 merges none; needs ``enforce_connectivity``.
    density : float or None, default None
        Content-sensitive sizes (not in the paper; :mod:`superfacets.elements.density`):
        exponent ``q`` in ``[0, 1]`` by which superfacets follow the density of
        the elements: 0 gives superfacets of equal area (the paper), 1 of equal
        numbers of elements (points), between them ``a_i^(1-q)`` times the
        median size's ``q``-th power as each element's size; the first centers
        are placed by farthest points with distances stretched to match.
        None: 0.5 on a point cloud whose density is uneven (the log of its
        point sizes spreads beyond 0.7: LiDAR sweeps, RGB-D frames), 0 on even
        clouds (every cloud sampled from the benchmark), meshes and with
        ``paper=True`` (:func:`superfacets.elements.density.density_for`); the value
        used is in ``result.params``.
    roughness : float, default 0
        Content-sensitive sizes (not in the paper): each element's length
        scale multiplied by ``1 + roughness * rho``, ``rho`` the mean angle in
        radians between neighbouring normals there (smoothed), so rough places
        (vegetation, clutter, folds) get more, smaller superfacets. On real
        scans ``density=0.5, roughness=1`` lowered the undersegmentation error
        by 6-34 % in all 15 settings measured (``docs/notes/superpoints.md``,
        "Content-sensitive superpoints").
    merge_from : int or None, default None
        Many superpoints first, merged to ``n_segments`` at the end (not in the
        paper; :mod:`superfacets.method.merges`): the run segments ``merge_from``
        times ``n_segments`` (at most one per 12 elements, or where that is under twice
        ``n_segments``, twice, at most one per 4), then merges adjacent ones,
        first those whose union stays flat to within the input's noise (walls,
        floors, ground, the flat faces of objects), then the cheapest by Ward's
        cost with the crease factor, down to exactly ``n_segments``. 1 merges
        nothing. None: 5 on point clouds (with ``merge_cost='auto'`` only where their
        density is even), 20 on scenes (a cloud with an up direction,
        ``PointCloud.up``: LAS, LAZ and E57 files, RGB-D frames) with the default cost,
        1 on meshes, with ``paper=True`` and in the tiles of a tiled run
        (:func:`superfacets.method.rules.merge_from_of`). On two
        ScanNet rooms it lowered the undersegmentation error by 13-26 % at
        ``n_segments`` = 300-3,000, below the ScanNet Segmentator's; on the 300
        benchmark meshes sampled to clouds by 5.9 % at 150
        (``docs/notes/superpoints-defaults.md``).
    max_size_ratio : float, optional
        With merges to the count (``merge_from`` above 1): no merge makes a
        superpoint of more than this many times the mean count of elements
        (``n / n_segments``) while other neighbours can merge, so flat ground, a
        roof or a wall becomes several superpoints, not one holding a large share of
        the scan (not in the paper). ``>= 1``; 0: no bound. Default (None): 4 on a
        scene (a cloud with an up direction: on 27 labelled scans at ``n_segments`` =
        100-3,000 against the Segmentator 98 of 108 targets met instead of 91, mean
        boundary recall +0.016, mean undersegmentation error +1.9 %), 16 elsewhere
        (``docs/notes/superpoints.md``, "A scene's superpoints at most 4 times the
        mean"); 2 gives more even sizes still.
    merge_cost : {'noise', 'auto', 'scene'}, default 'noise'
        With merges to the count (not in the paper). ``'noise'``: after the flat
        merges, the pair of least ``(w rise / u + ward / r^2)`` times the crease factor
        merges first: the plane's rise of the union in units ``u`` of the scan's noise
        ``s`` (or of the neighbourhoods' own residual, where larger), weighted by
        ``w = min(1, s / v)``, the noise's share of the first superpoints' median
        residual per point ``v`` (:func:`superfacets.method.merges.rise_weight`: 1 on
        flat ground and walls, small among vegetation or an object's fine detail), plus
        Ward's term in units of the superpoint's size; where the noise reads 0 (a
        surface sampled from a mesh) ``'auto'``'s merges, label for label. It merges on
        every cloud, uneven density too (``merge_from`` 5, a scene's 20, unless given).
        ``'auto'`` (the default before 2026-11-30): the plane's rise where the flat
        regions hold most of the points, else Ward's cost with the crease factor; no
        merges on clouds of uneven density. ``'scene'``: ``'noise'`` with ``w = 1``
        everywhere. On 27 labelled scans ``'noise'`` met the Segmentator's targets in 70 of
        108 settings against ``'auto'``'s 61 (``'scene'`` 78, but the 300 benchmark clouds'
        UE 11-20 % higher); on the 300 benchmark clouds UE +0.1 to +0.4 % against
        ``'auto'``; it takes 1.07 times ``'auto'``'s time over the 27 scans, up to 1.5 times
        on LiDAR sweeps at ``n_segments`` of 1,000 and more
        (``docs/notes/superpoints-defaults.md``).
    up_weight : float, optional
        A point cloud's up coordinate (along its ``up``: a LAS, LAZ or E57 file's z)
        multiplied by this in the method's distances, its neighbours, normals and merges
        (not in the paper; :func:`superfacets.inputs.cloud.up_weighted`), in ``(0, 100]``;
        1: none. Above 1, what an airborne scan stacks in height (ground, low vegetation,
        canopy, roofs) is kept apart. None (the default): read off a scene's planar
        neighbourhoods (:func:`superfacets.inputs.cloud.surface_up_weight`: 1 to 8, the
        more they lie level; 2.8-7.9 on airborne tiles, 1.6-2 on LiDAR sweeps, 1 in rooms,
        whose walls a stretch cuts in bands), 1 on other inputs and with ``paper``.
        On 30 labelled scans at ``n_segments`` = 100-3,000 against 1: the Segmentator's
        targets met in 111 against 109 of 120 settings (113 against 104 at half density),
        airborne undersegmentation error 28 % lower, oracle mIoU 0.035 higher, 1.20 times
        the time (``docs/notes/superpoints.md``, "The up weight's power").
        ``result.params["up_weight"]`` gives the weight used. Labels,
        :meth:`SegmentationResult.graph` and ``learning_graph`` are of
        the cloud as given; ``mesh_radius`` is the weighed cloud's. One run holds a weighed
        copy of the points (24 bytes a point); a tiled run reads every position weighed.
    step_weight : float, optional
        A step off a point cloud's surface (the part of a neighbour's offset ``d`` along
        the normals) weighed this many times, in ``[1, 100]`` (not in the paper): each
        point's neighbours are those of its 20 nearest with the least ``|d|^2 + (S^2 - 1)
        (n . d)^2`` (:func:`superfacets.elements.points.surface_neighbours`), and the
        distances between neighbours are ``sqrt(|d|^2 + (S^2 - 1) off^2)``. A roof and the
        ground under it, a table and the floor, are then two surfaces however close.
        Default (None): 4 on a scene (a cloud with an up direction), 1 elsewhere and with
        ``paper``; on 27 labelled scans at ``n_segments`` = 100-3,000 against the
        Segmentator 91 of 108 targets met instead of 88, mean undersegmentation error
        -6.6 %, oracle mIoU +0.020, in 1.19 times the time; on objects it left the
        compactness 0.7-1.5 % worse, so they keep 1 (``docs/notes/superpoints.md``,
        "Neighbours along the surface"). A tiled run's tiles read the same neighbours.
    tol : float, default 0.001
        Convergence tolerance in ``[0, 1]``: also stop once a classification
        changes the superfacet of at most this fraction of the surface area
        (as SLIC stops on its residual). 0 is the paper's rule (stop when no
        center moves, else at ``max_iter``; with ``paper=True`` its labels bit
        for bit). The default stops
        about a quarter of the passes earlier with undersegmentation error and
        compactness within 0.05 % of ``tol=0`` on the 300 benchmark meshes
        (``docs/notes/benchmarks.md``). ``tol=0`` also turns ``center_tol`` and
        ``coarsen`` off unless they are given.
    center_tol : float, optional
        In ``[0, 1]``: a center that the update would move by less than
        ``center_tol * r`` (``r`` the superfacet radius) stays where it is.
        Default: 0.05 when ``tol > 0``, else 0 (within 0.25 % of ``tol=0``
        on the 300 benchmark meshes, ``docs/notes/benchmarks.md``).
    coarsen : int, optional
        Coarse-to-fine (``superfacets.method.coarse_to_fine``): first run on clusters of
        about ``coarsen`` elements (Voronoi cells in the weighted graph), then
        on every element from the centers found there; capped at ``n / (8
        k)``; 1 turns it off. Default: when ``tol > 0`` and a superfacet holds
        at least 4,000 elements, what leaves about 1,000 clusters per
        superfacet (6.8M faces at ``k=150``: 45), else off.
    progress : bool, default False
        Show a progress bar on stderr: the set-up stages by name (face graph,
        weights, init), then the iterations.
    n_threads : int, optional
        Threads of the run (``>= 1``; default: ``SUPERFACETS_NUM_THREADS``
        where set, else the number of cores this process may use): the graph build
        and the weights' terms it triggers, the expansions, the split-and-merge
        searches, the clean-up's cuts and every compiled kernel (a limit of the
        process while the run lasts). The labels do not depend on it.
    elements : {'faces', 'vertices', 'points'}, optional
        What is segmented: the faces of a mesh (the paper; default for a
        mesh), its vertices (one label per vertex, on the graph of mesh
        edges; ``superfacets.elements.vertices``) or the points of a cloud
        (the default, and the only choice, for a cloud;
        ``superfacets.elements.points``).
    n_neighbors : int, default 10
        Points: nearest neighbours of each point in the point graph (1..100).
    neighbor_radius : float, optional
        Points: drop neighbours farther than this fraction of ``d``.

    Returns
    -------
    labels : (m,) int64 ndarray
        Superfacet of each face (vertex, point), dense ``0..K-1``. ``K`` may differ from
        ``n_segments``: faces no center reached within its window seed extra
        superfacets, and centers left without faces reduce it. Every
        separate piece of the graph gets a center from the start (more
        pieces than ``n_segments``: one superfacet each); with ``paper=True``
        a piece the farthest points missed seeds one from its orphans, beyond
        the count. Vertices used by no face and invalid points of a cloud get -1.

    Raises
    ------
    TypeError
        If ``data`` is not a mesh or cloud (or is not given), or ``faces`` not integer.
    InvalidMeshError
        If the mesh is empty, has NaN/inf coordinates, out-of-range indices,
        zero extent or zero area.
    ParameterError
        If a parameter is out of range (``n_segments`` < 1 or > m, negative
        ``alpha``, both ``n_segments`` and ``radius``, unknown ``init``, ...).
        Every parameter is checked before any work on the mesh.

    See Also
    --------
    segment : same arguments, returns the labels with the run's details.

    References
    ----------
    .. [1] G. Simari, G. Picciau, L. De Floriani, "Fast and Scalable Mesh
       Superfacets", Computer Graphics Forum 33(7) (Pacific Graphics), 2014;
       section 3.1 (the iteration), eqs. 1-3 (weights). ``docs/notes/method.md``.

    Examples
    --------
    >>> from superfacets import superfacets
    >>> mesh = trimesh.creation.icosphere(subdivisions=3)
    >>> labels = superfacets(mesh, n_segments=20)
    >>> labels.shape, int(labels.max()) + 1
    ((1280,), 20)
    """
    data = _the_input(data, params, "superfacets")
    return segment(data, n_segments, features=features, **params).labels


def segment(data=_NO_INPUT, n_segments: int | None = _D.n_segments, *, features=None,
            adaptive: bool | int | None = None, extent_weight: float | None = None,
            **params) -> SegmentationResult:
    """Superfacets with details: same parameters as :func:`superfacets`.

    Parameters
    ----------
    data : Mesh, trimesh.Trimesh, (vertices, faces), PointCloud, TetMesh, or a path
        The input (see :func:`superfacets`; a file's path is read by
        :func:`superfacets.io.read_input`; named ``mesh`` before, which still works as a
        keyword, with a ``FutureWarning``).
    n_segments : int, default 150
        Desired number of superfacets ``k``.
    features : (N, d) float ndarray, optional
        One feature per input row, for ``beta > 0``.
    adaptive : bool or int, optional
        The content-adaptive level (``--adaptive [START]``): segment ``START`` times
        ``n_segments`` (``True``: 10), then keep the level of ``n_segments`` that merges
        the flattest neighbours first (:func:`superfacets.api.levels.adaptive_segment`).
    extent_weight : float, optional
        With ``adaptive``: the weight of the segments' extent in the merges (default:
        0.01 on a scan of uneven density, else 0).
    **params
        Every other parameter of :func:`superfacets`, by keyword; declared once in
        :data:`superfacets.method.params.PARAMETERS` (the signature lists them all).

    Returns
    -------
    SegmentationResult
        ``.labels`` is what :func:`superfacets` returns; ``.centers``,
        ``.n_iter``, ``.converged``, ``.timings`` and ``.params`` describe
        the run.

    Raises
    ------
    TypeError, InvalidMeshError, ParameterError
        As :func:`superfacets`.

    Notes
    -----
    With ``assignment='bounded'`` a center that did not move since the
    previous pass is not expanded again: its recorded expansion is replayed
    (:class:`~superfacets.method.classify.BoundedReplay`, about ``12 * 5`` bytes per
    face), and a repeating cycle of center lists is jumped over
    (:mod:`superfacets.method.passes`). Labels, centers, ``n_iter`` and
    ``n_orphan_seeds`` are exactly those of expanding every center on every
    pass (``pipeline(..., replay=False, jump_cycles=False)``, tested), for
    any ``n_threads``; ``timings['passes']`` counts the passes run.

    Examples
    --------
    >>> r = segment(trimesh.creation.icosphere(subdivisions=3), n_segments=20)
    >>> r.n_segments, r.labels.dtype
    (20, dtype('int64'))
    """
    data = _the_input(data, params, "segment")
    if adaptive is not None and adaptive is not False:
        return _adaptive(data, n_segments, adaptive, extent_weight, features=features,
                         **params)
    if extent_weight is not None:
        raise ParameterError("extent_weight is a term of the adaptive level: give adaptive=")
    run = pipeline(data, resolve(n_segments=n_segments, **params), features=features)
    return SegmentationResult(**run.result_fields())


def _adaptive(obj, n_segments, adaptive, extent_weight, **options):
    """The content-adaptive level of ``n_segments`` (``adaptive``: True or its START)."""

    if n_segments is None:
        raise ParameterError("adaptive takes n_segments, not radius")
    start = START if adaptive is True else adaptive
    return adaptive_segment(obj, n_segments, start=start, extent_weight=extent_weight,
                            **options)


def _the_input(data, params: dict, name: str):
    """The input given as ``data``, or as the keyword ``mesh`` of before (taken out of
    ``params``, with a FutureWarning); a TypeError where there is none."""
    if "mesh" in params:
        given = params.pop("mesh")
        if data is not _NO_INPUT:
            raise TypeError(f"{name}() got the input twice (data and mesh=)")
        warnings.warn(f"{name}(mesh=...) is {name}(data=...) now (or the input first); "
                      "mesh= will be removed", FutureWarning, stacklevel=3)
        data = given
    if data is _NO_INPUT:
        raise TypeError(f"{name}() needs the input: a mesh, point cloud or tetrahedral mesh "
                        "(its first argument, data)")
    if isinstance(data, (str, os.PathLike)):  # a file: read as the command line reads it
        from ..io import read_input

        return read_input(data)
    return data


def _signature(returns, own=()) -> inspect.Signature:
    """``(data, n_segments=150, *, <every other parameter>, features=None, <own>)``: the
    keywords of :data:`superfacets.method.params.PARAMETERS` with their defaults, and the
    function's ``own`` keywords (each None by default)."""
    P = inspect.Parameter
    out = [P("data", P.POSITIONAL_OR_KEYWORD),
           P("n_segments", P.POSITIONAL_OR_KEYWORD, default=_D.n_segments)]
    out += [P(d.name, P.KEYWORD_ONLY, default=d.default) for d in PARAMETERS
            if d.name != "n_segments"]
    out += [P(name, P.KEYWORD_ONLY, default=None) for name in ("features", *own)]
    return inspect.Signature(out, return_annotation=returns)


# the signature ``help()``, IDEs and the API reference show: one keyword per declaration
superfacets.__signature__ = _signature(np.ndarray)
segment.__signature__ = _signature(SegmentationResult, ("adaptive", "extent_weight"))


def superpoints(points, n_segments: int | None = _D.n_segments, *, normals=None,
                n_neighbors: int = _D.n_neighbors,
                neighbor_radius: float | None = _D.neighbor_radius, viewpoint=None,
                adaptive: bool | int | None = None, extent_weight: float | None = None,
                **options) -> np.ndarray:
    """Over-segment a point cloud into superpoints: the paper's method on the point graph.

    The point graph joins each point to its ``n_neighbors`` nearest (scipy's
    KD-tree, symmetric); each point stands for the surface area of the
    k-nearest-neighbour density estimate, so ``n_segments`` and ``radius``
    mean what they mean on a mesh; normals are estimated (PCA) and oriented
    consistently when not given; the weights are the paper's eqs. 1-3 with
    the distance between points as the geodesic term (``docs/notes/method.md``,
    section "Vertices and points"). Every superpoint is connected in the
    point graph; the result is deterministic. Where the points' density is
    uneven (a LiDAR sweep, an RGB-D frame: the log of the point sizes spreads
    beyond 0.7), superpoints follow it by default (``density=None``: 0.5 there,
    0 on even clouds; pass ``density=0`` for the paper's equal areas). Where it is
    even (rooms, aerial tiles, sampled surfaces), the run segments 5 times the
    superpoints (a scene with an up direction, a LAS file's: 20 times) and merges them
    to ``n_segments``, flat neighbours first
    (``merge_from=None``; ``merge_from=1`` for the method's own superpoints).

    Parameters
    ----------
    points : (N, 3) float ndarray, organized (H, W, 3) float ndarray, PointCloud,
        trimesh.PointCloud or open3d.geometry.PointCloud
        Coordinates, any units. An organized array may hold NaN points
        (missing measurements): they get the label -1.
    n_segments : int, default 150
        Desired number of superpoints ``k``, ``1 <= k <=`` distinct valid points.
    normals : (N, 3) float ndarray, optional
        Consistently oriented normals; estimated when omitted.
    n_neighbors : int, default 10
        Nearest neighbours of each point (1..100).
    neighbor_radius : float, optional
        Drop neighbours farther than this fraction of the bounding-box diagonal.
    viewpoint : (3,) float ndarray, optional
        Sensor position: estimated normals face it.
    adaptive : bool or int, optional
        Content-adaptive superpoints (``--adaptive [START]``): ``START`` times (``True``:
        10) the superpoints first, then the level of ``n_segments`` that merges the
        flattest neighbours first (as :func:`segment`).
    extent_weight : float, optional
        With ``adaptive``: the weight of the segments' extent in the merges.
    **options
        The other keyword arguments of :func:`superfacets` (``alpha``,
        ``radius``, ``init``, ``tol``, ...).

    Returns
    -------
    labels : (N,) or (H, W) int64 ndarray
        Superpoint of each point, dense ``0..K-1`` in input order; -1 for
        invalid points. Exact duplicate points share a label.

    Raises
    ------
    InvalidCloudError
        If the cloud is empty, has NaN/inf rows (unorganized input: the row
        is named), all points coincide or lie on one line.
    ParameterError
        If ``n_segments`` exceeds the distinct valid points, or another
        parameter is out of range (checked before any work).
    TypeError
        If ``points`` is not a point cloud.

    References
    ----------
    Simari, Picciau, De Floriani, "Fast and Scalable Mesh Superfacets", 2014
    (section 3.1, eqs. 1-3; point clouds named as future work, section 6).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> xyz = rng.normal(size=(2000, 3))
    >>> xyz /= np.linalg.norm(xyz, axis=1, keepdims=True)   # a sphere
    >>> labels = superpoints(xyz, 20)
    >>> labels.shape, int(labels.max()) + 1
    ((2000,), 20)
    """
    from dataclasses import replace


    if "elements" in options and options["elements"] not in (None, "points"):
        raise ParameterError("superpoints segments points; use superfacets() for meshes")
    options.pop("elements", None)
    params = resolve(n_segments=n_segments, n_neighbors=n_neighbors,
                     neighbor_radius=neighbor_radius, elements="points", **options)
    cloud = as_cloud(points, normals)
    if viewpoint is not None:  # the cloud's other fields (colours, up, ...) kept
        cloud = replace(cloud, viewpoint=viewpoint)
    if adaptive is not None and adaptive is not False:
        labels = _adaptive(cloud, n_segments, adaptive, extent_weight, elements="points",
                           n_neighbors=n_neighbors, neighbor_radius=neighbor_radius,
                           **options).labels
    elif extent_weight is not None:
        raise ParameterError("extent_weight is a term of the adaptive level: give adaptive=")
    else:
        labels = pipeline(cloud, params).labels
    return labels.reshape(cloud.shape) if cloud.shape is not None else labels
