"""One input larger than a machine: tiles with halos on Dask, stitched by center.

:func:`segment_tiled` cuts the input into tiles (:mod:`superfacets.scale.tiles.layout`:
balanced boxes, or a regular grid) and runs each tile as a task on :class:`~.engine.Engine`
(this process, a local Dask cluster or a running scheduler). A task gets the file's name
and its box, never data: it reads its tile and halo itself
(:class:`superfacets.io.regions.RegionReader`), so no process holds the whole input. The
phases (:mod:`superfacets.scale.tiles.phases`):

0. a survey of the file in chunks (bounds, total area) in this process, and a second pass
   that sorts its elements into one file per tile in the work folder
   (:func:`~superfacets.scale.tiles.buckets.bucket`): from then on a task reads the tiles
   its box overlaps; for a point cloud asked for ``n_segments``, one task per tile
   builds its point graph (kept for the later phases) and sums the points' areas on it
   (the radius needs the total; the halo it reads with comes from the survey's sample);
1. the start: the method once on the survey's even sample of the input (a cloud's
   points, a mesh's face centroids), or (``start='tiles'``, or a sample too thin for the
   count) per tile, the method on the tile and its halo, the centers of its core; then
   (``refine`` rounds) per tile, the method's passes again from all the centers within
   reach: the centers of its core;
2. per tile, labels from all the centers, kept for the core;
3. only where two tiles saw a border differently: per tile, the stitched labels of its
   box (read from a file in the work folder) made connected
   (:func:`~superfacets.scale.tiles.phases.tile_connect`), again on the tiles near what moved
   until nothing moves (:data:`CONNECT_ROUNDS` at most);
4. on a point cloud of even density (``merge_from``, as one run chooses it): the phases
   above make ``merge_from`` times the superpoints asked for, each tile sums what the
   merges read in phase 2, and this process merges them down to the count
   (:mod:`superfacets.scale.tiles.merges`); a mesh's tiles make a few more than asked
   (:data:`MESH_EXCESS`), merged to the count by Ward's merges alone.

A cloud's tile builds its point graph once, in the work folder
(:mod:`superfacets.scale.tiles.graphs`). Labels are named by their center's row, so a
superfacet crossing tile borders has one label on every side; they are made dense at the
end. Only the labels (8 bytes per element) and the centers are gathered here.
"""

from __future__ import annotations

import math
import re
import time
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path

import numpy as np

from ..._runtime.arrays import ranked
from ..._runtime.progress import new_bar, tick, waiting_bar
from ...api.result import TiledResult
from ...api.sizes import resolution_count
from ...checks import check_n_segments, check_nonneg, check_up, max_threads
from ...elements import points
from ...elements.density import AUTO_SPREAD
from ...elements.kinds import kind_of
from ...errors import ParameterError, SuperfacetsError
from ...graph.hierarchy import AUTO_EXTENT_WEIGHT, wanted_levels
from ...graph.learning import ground_axes, ground_frame
from ...inputs.bounds import check_extent, rows_in_box
from ...inputs.cloud import check_weighable, stretched_along
from ...io.clouds import dropped_normals_said
from ...io.files import user_path
from ...io.regions import RegionReader, streamed
from ...method.merges import NOISE_SAMPLE
from ...method.params import resolve, superfacet_size
from ...method.rules import SCENE_DEFAULTS, fine_count, scene_default_of, up_weight_of
from ..runner.engine import Engine, check_memory_limit
from . import buckets, phases
from .buckets import box_folder
from .graphs import drop_graphs, graph_folder
from .held import hold_from_env, release_held
from .layout import balanced_tiles, check_tiles, gathered_centers, in_box, tile_grid
from .merges import merged_labels, tiled_hierarchy, tiled_learning, tiled_merge_from
from .phases import HALO, check_tileable, halo_distance, point_areas, sample_cloud
from .task import tile_task
from .workdir import run_folder

#: Passes of the centers phase where refine rounds follow (they run the passes again
#: from the gathered centers): less time for the same tiled error (docs/notes/tiles.md).
CENTER_PASSES = 1

#: Most rounds of the connectivity pass: the first over the superfacets the border
#: disagreements name, each next over those the last moved elements to or from (tiles
#: repair at once, from the same stitched labels, and two repairs can leave a piece
#: apart again).
CONNECT_ROUNDS = 4

__all__ = ["segment_tiled", "TiledResult"]


#: The most refinement rounds (each runs the passes on every tile again; 1 is the default)
MAX_REFINE = 100


def segment_tiled(source, n_segments: int | None = None, *, tiles=4,
                  halo: float | None = None, workers: int | None = 1,
                  scheduler: str | None = None, memory_limit="auto", workdir=None,
                  progress: bool = False, refine: int = 1, start: str = "sample",
                  levels=None, level_cost: str = "ward", extent_weight: float | None = None,
                  graph: bool = False, seed_resolution: float | None = None,
                  neighbor_distance: float | None = None, **options) -> TiledResult:
    """Segment one large input tile by tile, on Dask or in this process.

    Parameters
    ----------
    source : str or os.PathLike, RegionReader, Mesh, PointCloud or array
        A binary PLY (triangle mesh or points), LAS/LAZ or ``.npy`` file (or
        its ``RegionReader``) is read in chunks by each task; anything
        else is read here once and written to ``.npy`` files in ``workdir``
        (it must then fit this machine). Triangle meshes and point clouds.
    n_segments : int, optional
        Superfacets over the whole input (``r = sqrt(A / (k pi))``, paper
        section 3.1); default 150, or none with ``radius`` or ``seed_resolution``. On a
        point cloud of even density the tiles make ``merge_from`` (5) times as many,
        merged down to exactly this count at the end
        (:mod:`superfacets.scale.tiles.merges`; ``merge_from=1``: none); on a mesh in
        several tiles, 5 % more and one a tile (:data:`MESH_EXCESS`), merged
        by Ward's merges to exactly this count (``merge_from=1``: none, the tiles' own
        count, which can fall short by a few).
    tiles : int or sequence of 3 int, default 4
        Number of balanced tiles (boxes split at the quantiles of the
        positions, so that each holds about ``n / tiles`` elements, however
        uneven the input: :func:`~superfacets.scale.tiles.layout.balanced_tiles`),
        or three integers: a regular grid of equal boxes, tiles along x, y, z.
    halo : float, optional
        Halo width in units of ``window * r``, ``>= 1``; default 3. From 2
        each core element's classification is that of a single run from the
        same centers; the third makes the clean-up near borders agree
        (:mod:`superfacets.scale.tiles.phases`).
    workers : int, default 1
        Local Dask worker processes; 1 runs the tiles one after another in
        this process. Ignored with ``scheduler``.
    scheduler : str, optional
        Address of a running Dask scheduler; its workers must reach
        ``source`` (and ``workdir``) by the same path.
    memory_limit : str or float, default 'auto'
        Memory limit of each local worker (Dask's syntax).
    workdir : str or os.PathLike, optional
        Folder for the work files: the input sorted into one file per tile
        (the file is read twice in all, then each task reads the tiles its box
        overlaps), the ``.npy`` copy of an input that is not streamed, the tiles' point
        graphs (:mod:`~superfacets.scale.tiles.graphs`), the stitched labels. The run
        works in a folder of its own that it makes inside ``workdir`` and removes at its
        end; nothing else there is touched, and two runs may share it
        (:mod:`~superfacets.scale.tiles.workdir`). Default: a temporary folder. With
        ``scheduler`` give a folder every worker reaches, or each task reads the whole
        file for its box.
    progress : bool, default False
        A progress bar per phase.
    refine : int, default 1
        Rounds in which every tile runs the method's passes again from the
        gathered centers within reach (so the centers near a border settle
        with their true neighbours), ``>= 0``. On 15 benchmark meshes in 8
        tiles, UE against one run: +5.8 % with 0, +1.2 % with 1 (docs/notes/tiles.md).
    start : {'sample', 'tiles'}, default 'sample'
        Where the refine rounds start from. ``'sample'``: the method once on the survey's
        even sample of the input (a cloud's points; a mesh's face centroids, as a cloud,
        with a mesh's split-and-merge swaps), with the whole input's radius
        (:func:`~superfacets.scale.tiles.phases.sample_start`). ``'tiles'``: each tile
        samples its own centers on its box and halo and runs one pass (a mesh's start
        before 2026-11-30; also where the sample holds too few elements a center, or
        ``refine=0``). On 15 benchmark meshes in four settings the sample's start gave a
        tiled UE 1.6 % under one run's on average (the tiles' own: 1.2 %) in about a
        third less time (docs/notes/tiles.md, "A mesh's start").
    levels : int or sequence of int, optional
        Also coarser, nested levels of these numbers of segments, each connected, merged
        from the tiles' sums as one run's :meth:`SegmentationResult.hierarchy` merges its
        superpoint graph (:func:`~superfacets.scale.tiles.merges.tiled_hierarchy`):
        ``result.hierarchy``; the same parents where the normals are the input's, and where
        they are estimated the crease factor reads the tiles' angles (each tile orients its
        own), so a merge can differ.
    level_cost : {'ward', 'planarity'}, default 'ward'
        Their merge cost (``'planarity'``: clouds only).
    extent_weight : float, optional
        With ``'planarity'``, as :meth:`SegmentationResult.hierarchy` (default: 0.01 on
        a cloud of uneven density, ``size_spread`` above
        :data:`~superfacets.elements.density.AUTO_SPREAD`, else 0).
    graph : bool, default False
        Also the superpoint graph in the layout learning pipelines read, from the tiles'
        sums (:func:`~superfacets.scale.tiles.merges.tiled_learning`): ``result.learning``,
        the arrays :meth:`SegmentationResult.learning_graph` gives of the same labels (the
        input's own up, else z; the ground's grid on the extent the survey reads along
        its axes), but for the edges' ``mean_angle`` and ``concave`` where the normals are
        estimated (each tile orients them like a sample, one run by its pieces; the
        planes' angle ``normal_angle`` reads no orientation). With ``up_weight``, the graph
        and the levels are of the cloud as given, as one run's result makes them (each tile
        also builds the point graph of its points stretched back; not with
        ``neighbor_radius``).
    seed_resolution : float, optional
        The count from a size in the data's units, as
        :func:`~superfacets.api.sizes.count_for_resolution` gives it for the whole input:
        its area (a mesh's from the survey, a cloud's point sizes summed over the tiles as
        one run sums them) over the square of this length; not with ``n_segments`` or
        ``radius``.
    neighbor_distance : float, optional
        A cloud's farthest neighbour in the data's units: ``neighbor_radius`` that
        distance over the survey's bounding-box diagonal, as
        :func:`~superfacets.api.sizes.diagonal_fraction` gives it for one run.
    **options
        Keyword arguments of :func:`superfacets.segment` (``alpha``,
        ``window``, ``cleanup``, ``paper``, ``beta``, ``n_neighbors``, ...).

    Returns
    -------
    TiledResult

    Raises
    ------
    ParameterError
        On a bad option, ``tiles``, ``halo`` or level (one above the count, before the
        run; below the superpoints' connected pieces, after it); or ``features`` (tiles
        read colours from the file).
    MeshFormatError, InvalidMeshError
        As the readers, or a tile's input.
    SuperfacetsError
        If a tile's task fails (its number and error in the message).

    Examples
    --------
    >>> m = trimesh.creation.icosphere(subdivisions=4)
    >>> r = segment_tiled((m.vertices, m.faces), 40, tiles=2)
    >>> r.labels.shape, r.n_segments, r.layout.n_tiles
    ((5120,), 40, 2)
    """
    params, halo, units = _checked_options(n_segments, options, tiles, halo, refine, workers,
                                           start, memory_limit,
                                           (seed_resolution, neighbor_distance))
    levels = _checked_levels(levels, level_cost, extent_weight, params, graph)
    t_start, timings = time.perf_counter(), {}
    stage = partial(_stage, timings, progress)  # (each stage timed, and shown as it runs)
    with run_folder(workdir) as tmp:  # the run's own folder, removed at its end
        with stage("survey"):
            reader, survey, params = _surveyed(source, tmp, tiles, params, graph, levels, units)
        _check_levels_of(levels, reader.kind)
        weight, (params, sample_area) = params.up_weight, _step_resolved(params, reader,
                                                                          survey, units)
        layout = (balanced_tiles(survey.sample, survey.lo, survey.hi, tiles)
                  if np.ndim(tiles) == 0 else tile_grid(survey.lo, survey.hi, tiles))
        grid, n_tiles = layout.shape or (layout.n_tiles,), layout.n_tiles
        target, merge_from, params = plan = _merge_plan(params, reader, survey, n_tiles)
        diagonal = float(np.linalg.norm(survey.hi - survey.lo))
        # a file per tile (a task reads its box's, not the file), where the workers share one
        shared = scheduler is None or workdir is not None
        up = getattr(reader, "up", None)  # (the buckets keep the viewpoint, not this)
        ground = _ground_of(up, survey)
        if shared and n_tiles > 1:
            with stage("bucket", bar=False):  # (a bar of its own)
                reader = buckets.bucket(reader, layout, Path(tmp) / "buckets", progress=progress)
        with stage("orientation"):
            reference, sample_area, sampled = _orientation(reader, survey, params, up,
                                                           shared and tmp, sample_area)
        graphs = graph_folder(tmp, survey.n_elements, reader.kind, shared and n_tiles > 1,
                              params)  # the tiles' point graphs, kept between phases
        boxes = box_folder(tmp, reader, survey.n_elements) if shared and n_tiles > 1 else None
        with Engine(workers=workers, scheduler=scheduler, memory_limit=memory_limit) as engine, \
                _holding(engine, tmp):
            sent = _Sent()  # (where each tile's box is held: .held)

            def run(phase, margin, extra=lambda t: {}, only=None):
                tasks = [dict(phase=phase, reader=reader, layout=layout, tile=t, margin=margin,
                              params=params, r=r, diagonal=diagonal, graphs=graphs,
                              boxes=boxes, floor=floor,
                              frame=_frame(reader, survey), **extra(t))
                         for t in (range(n_tiles) if only is None else only)]
                if reference is not None and (phase != "areas" or graphs is not None):
                    for task in tasks:
                        task["orient_like"] = reference if isinstance(reference, str) else \
                            in_box(reference, *layout.box(task["tile"], 1.5 * margin))
                return _gather(engine, tasks, phase, progress, sent)

            r, floor = math.nan, None
            with stage("areas", bar=False):  # (the phases' bars)
                r, margin, area, spread, (target, merge_from, params) = _sized(
                    run, layout, (reader, survey, units), plan, diagonal, halo,
                    (graphs, sample_area))
            merging = params.n_segments != target  # (the tiles make more: merged at the end)
            params, floor = _colour_term(run, margin, params, survey.colors, stage)
            found, done = _classified(run, layout, params, margin, params.window * r, dict(
                refine=refine, box_rows=not shared, frame=ground, n_noise=_noise_points(
                    merging or levels is not None or graph, merge_from if merging else 1,
                    n_tiles), unweighted=_unweighted(up, weight, graph or levels is not None),
                start=_sample_start(reader, survey, params, r, diagonal,
                    (refine, start), stage, (sampled, up))),
                timings)
            with stage("stitch"):
                labels, disagreements, suspects = _stitched(done, reader.n_rows)
            repaired = 0
            if disagreements:  # two tiles saw a border differently: pieces are possible
                with stage("connect", bar=False):
                    box = None if shared else {o["tile"]: o.pop("box_rows") for o in done}
                    repaired = _connected(run, labels, (margin, done), tmp, box, suspects)
            drop_graphs(graphs)
    labels, names, merged_from, tree, learning = _merged(
        labels, done, stage, (merging, target, params), (levels, ground), (spread, reader.kind))
    timings["total"] = time.perf_counter() - t_start
    resolved = dict(params.as_dict(), n_segments=int(names.size), radius=r / diagonal,
                    up_weight=weight, tiles=grid, halo=float(halo), elements=reader.kind,
                    up=None if up is None else tuple(map(float, _up_of(up))), merge_from=merge_from,
                    merged_from=merged_from, **({} if floor is None else {"feature_floor": floor}))
    return TiledResult(labels=labels, centers=names.astype(np.int64), mesh_radius=r, grid=grid,
                       layout=layout, halo=margin, disagreements=disagreements, repaired=repaired,
                       tiles=_tile_stats(found, done), timings=timings, params=resolved,
                       area=_data_area(area, weight, survey, up, params), size_spread=spread,
                       hierarchy=tree, learning=learning)


def _merged(labels: np.ndarray, done: list, stage, plan: tuple, asked: tuple, of: tuple):
    """The stitched ``labels`` merged to the count where ``plan = (merging, target,
    params)`` says (:func:`~superfacets.scale.tiles.merges.merged_labels`), numbered
    densely, and what ``asked = (levels, ground)`` asks of the tiles' sums (None: nothing):
    the levels, and the superpoint graph in the learning layout on that ground's grid;
    ``of`` is the input's ``(size_spread, kind)``. Returns the labels, each one's name
    before, the count merged from (None: no merges), the hierarchy and the graph's arrays
    (each None where not asked)."""
    merging, target, params = plan
    levels, ground = asked
    fine = labels.copy() if asked != (None, None) else None
    merged_from = None
    if merging:
        with stage("merges"):
            merged_from = int(ranked(labels, labels.size)[0].size)
            labels = merged_labels(labels, [o["merge_stats"] for o in done], target, params)
    with stage("stitch", add=True):
        names = _numbered_densely(labels)
    learning = None
    given = [o["merge_stats"].get("unweighted", o["merge_stats"]) for o in done] \
        if asked != (None, None) else None  # (the cloud as given, where the run weighed it)
    if ground is not None:
        with stage("graph"):
            learning = tiled_learning(given, fine, labels, ground)
    if levels is None:
        return labels, names, merged_from, None, learning
    wanted, cost, weight = levels
    if weight is None:  # (as one run's: a planarity level of a cloud of uneven density
        weight = AUTO_EXTENT_WEIGHT if cost == "planarity" and of[0] > AUTO_SPREAD else 0.0
    with stage("levels"):
        tree = tiled_hierarchy(given, fine, labels, wanted,
                               alpha=params.alpha, eta_convex=params.eta_convex, cost=cost,
                               extent_weight=weight, cloud=kind_of(of[1]).cloud)
    return labels, names, merged_from, tree, learning


def _unweighted(up, weight: float, asked: bool) -> tuple | None:
    """What the tiles' labels phase stretches back, where the run weighs the up coordinate
    and its graph or levels are asked (of the cloud as given): ``(up, weight)``, else None."""
    return (up, weight) if weight != 1 and asked else None


def _ground_of(up, survey) -> tuple | None:
    """The ground's grid of the learning layout's elevation (None: no graph asked): on the
    input's extent along the grid's axes, which the survey read as one run reads it."""
    if survey.extent_along is None:
        return None
    return ground_frame(None, _up_of(up), extent=survey.extent_along)


def _up_of(up) -> np.ndarray:
    """The input's own up, else z."""
    return check_up((0.0, 0.0, 1.0) if up is None else up)


def _check_levels_of(levels, kind: str) -> None:
    """Refuse planarity levels of a mesh's faces, once its kind is known."""
    if levels is not None and levels[1] == "planarity" and not kind_of(kind).cloud:
        raise ParameterError("a tiled mesh's levels merge by Ward's cost (planarity levels "
                             "of faces weigh their areas, which tiles do not sum)")


def _classified(run, layout, params, margin: float, ring: float, how: dict,
                timings: dict):
    """The centers phase (or, given ``how['start']``, the centers it gives),
    ``how['refine']`` refinements, then the labels phase: the tiles' outputs of the first
    phase run and of the last (each tile its own core's)."""
    found = None
    if how.get("start") is not None:
        rows, pos = how["start"]
    else:
        t = time.perf_counter()
        # where refine rounds follow, they run the passes: the centers phase gives each
        # tile's start and one pass (its passes to the end were run again by the round)
        passes = CENTER_PASSES if how["refine"] else None
        found = [o for o in run("centers", margin, lambda t: dict(passes=passes))
                 if o["core"]]
        timings["centers"] = time.perf_counter() - t
        rows, pos = gathered_centers(found, params)

    def reach(t):
        lo, hi = layout.box(t, margin)
        inside = rows_in_box(pos, lo, hi)
        return dict(centers=rows[inside], ring=ring, box_rows=how["box_rows"])

    for _ in range(how["refine"]):
        t = time.perf_counter()
        again = [o for o in run("refine", margin, reach) if o["core"]]
        timings["refine"] = timings.get("refine", 0.0) + time.perf_counter() - t
        rows, pos = gathered_centers(again, params)
        found = again if found is None else found
    t = time.perf_counter()
    done = [o for o in run("labels", margin, lambda t: dict(
        reach(t), n_noise=how["n_noise"], frame_of_ground=how.get("frame"),
        unweighted=how.get("unweighted"))) if o["core"]]
    timings["labels"] = time.perf_counter() - t
    return found, done


def _colour_term(run, margin: float, params, colors: bool, stage):
    """The colour term of every tile, read once over all of them (a stage of its own, where
    the input has ``colors`` and ``beta`` is not 0): ``params`` with its ``beta`` a number
    (the one given, else read) and the floor (:func:`superfacets.method.weights.scale_of` on
    the tiles' samples together, :func:`~superfacets.scale.tiles.phases.tile_colour_sample`;
    None: no colour term). Each tile reading its own made two tiles weigh their border
    differently. No colour read (no tile with finite colours): the term off."""
    from ...method.weights import scale_of

    if not colors or (params.beta is not None and params.beta <= 0):
        return params, None
    with stage("colours", bar=False):
        samples = [o["colour_sample"] for o in run("colours", margin)
                   if o.get("colour_sample") is not None]
    if not samples:
        return replace(params, beta=0.0), None
    beta, floor = scale_of(np.concatenate([s[0] for s in samples]),
                           np.concatenate([s[1] for s in samples]))
    return replace(params, beta=beta if params.beta is None else params.beta), floor


def _noise_points(merging: bool, merge_from: int, n_tiles: int) -> int | None:
    """Points of each tile's core to read the noise on for the merges to the count (a
    cloud's flat merges; 0: a mesh's, Ward's merges only), or None: no merges."""
    if not merging:
        return None
    return NOISE_SAMPLE // n_tiles + 1 if merge_from > 1 else 0


def _sample_start(reader, survey, params, r: float, diagonal: float, how: tuple,
                  stage, sampled: tuple):
    """The centers the refine rounds start from, found on the survey's sample (a cloud's
    points, a mesh's face centroids: :func:`~superfacets.scale.tiles.phases.sample_start`;
    ``sampled``: a cloud's orientation sample as a cloud, or None, and the cloud's up
    direction); None where the tiles' centers phase gives them (``refine=0``, where no
    round follows to run the passes on every element, or ``start='tiles'``; a sample too
    small for the centers: :func:`~superfacets.scale.tiles.phases.sample_start` says so).
    ``how``: the run's ``refine`` and ``start``."""

    sample, (refine, start) = survey.sample, how
    if refine < 1 or start != "sample" or sample is None \
            or survey.sample_rows is None or sample.shape[0] < 3:
        return None
    with stage("start"):  # (timed and shown: :func:`_stage`)
        return phases.sample_start(sample, survey.sample_rows, reader.n_rows, params, r, diagonal,
                            *sampled, viewpoint=reader.viewpoint, kind=reader.kind)


def _frame(reader, survey) -> np.ndarray | None:
    """The whole cloud's box, whose frame numbers every tile's points (None: a mesh)."""
    return np.array([survey.lo, survey.hi]) if kind_of(reader.kind).cloud else None


def _numbered_densely(labels: np.ndarray) -> np.ndarray:
    """Number the labels (>= 0; -1 stays) 0..K-1 in place, in the order of their values;
    returns the values (each superfacet's name before)."""
    names, labels[:] = ranked(labels, labels.size)  # (each names a row of the input)
    return names


#: A tiled mesh asks its tiles for this share more superfacets than the count, and one
#: more a tile, merged down to exactly the count by Ward's merges at the end: its tiles'
#: cores end with fewer centers than their shares (a center the passes carry across a
#: border can leave both tiles' cores), 0-5 % on 15 benchmark meshes in 8 tiles and up
#: to a third at 1-2 superfacets a tile (docs/notes/tiles.md, "Exactly k on meshes").
MESH_EXCESS = 0.05


def _checked_units(seed_resolution, neighbor_distance, n_segments, options) -> dict:
    """The sizes in the data's units given (each a length ``> 0``), against the options
    they replace and ``up_weight`` (the tiles measure the weighed cloud)."""
    units = {}
    if seed_resolution is not None:
        resolution_count(1.0, seed_resolution, 1)  # (a finite length > 0, or the error)
        if n_segments is not None or options.get("radius") is not None:
            raise ParameterError("seed_resolution gives the count: not with n_segments or "
                                 "radius")
        units["seed_resolution"] = float(seed_resolution)
    if neighbor_distance is not None:
        try:
            d = float(neighbor_distance)
        except (TypeError, ValueError):
            d = math.nan
        if not (math.isfinite(d) and d > 0):
            raise ParameterError(f"neighbor_distance must be a finite length > 0, got "
                                 f"{neighbor_distance!r}")
        if options.get("neighbor_radius") is not None:
            raise ParameterError("give neighbor_distance (data units) or neighbor_radius "
                                 "(a fraction of the diagonal), not both")
        units["neighbor_distance"] = d
    if units and options.get("up_weight") not in (None, 1, 1.0):
        raise ParameterError("sizes in the data's units with up_weight: the tiles measure the "
                             "weighed cloud; give n_segments and neighbor_radius")
    return units


def _in_units(params, reader, survey, units: dict) -> tuple:
    """The parameters with the sizes in the data's units resolved where the survey
    suffices: ``neighbor_radius`` (the distance over the survey's diagonal), a mesh's
    count (its area over the resolution squared); a cloud's count from its even sample's
    area (the areas phase gives the exact one: :func:`_sized`), with that area."""
    sample_area = None
    if "neighbor_distance" in units:
        if not kind_of(reader.kind).cloud:
            raise ParameterError("neighbor_distance is of a point cloud's graph")
        diagonal = float(np.linalg.norm(survey.hi - survey.lo))
        if not diagonal > 0:
            raise ParameterError("neighbor_distance: the input has no extent to measure it "
                                 "against")
        params = replace(params, neighbor_radius=units["neighbor_distance"] / diagonal)
    if "seed_resolution" in units:
        area = survey.size
        if kind_of(reader.kind).cloud:
            sample = survey.sample
            area = sample_area = point_areas(sample, np.ones(sample.shape[0], dtype=bool),
                                             params.n_neighbors) if sample is not None \
                and sample.shape[0] > 1 else 0.0
        params = replace(params, n_segments=resolution_count(
            area, units["seed_resolution"], survey.n_elements))
    return params, sample_area


def _merge_plan(params, reader, survey, n_tiles: int):
    """The count asked for, the factor of the superpoints made before the merges down to
    it (1: none; a mesh's few more: :data:`MESH_EXCESS`), and the parameters of the tiles'
    runs (their count that many times), for the input ``reader`` reads (its kind, and
    whether it has an up direction: a scene's ``merge_from``, as one run's)."""
    n_elements, kind = survey.n_elements, reader.kind
    target, merge_from = params.n_segments, tiled_merge_from(
        params, kind, scene=getattr(reader, "up", None) is not None)
    if merge_from > 1:  # merge_from times the superpoints, merged to the count at the end
        fine = fine_count(target, merge_from, n_elements)
        merge_from = merge_from if fine > target else 1
        params = replace(params, n_segments=fine)
    elif (not kind_of(kind).cloud and target is not None and params.radius is None
          and n_tiles > 1 and params.merge_from is None):  # a few more, merged to the count
        fine = min(n_elements, target + math.ceil(MESH_EXCESS * target) + n_tiles)
        params = replace(params, n_segments=max(fine, target))
    return target, merge_from, params


def _orientation(reader, survey, params, up, folder, area=None):
    """The normals' orientation reference of a cloud with neither normals nor viewpoint
    (from the survey's sample, thinned as the start thins it: :func:`~superfacets.scale.
    tiles.phases.start_step`; saved in ``folder`` where the tasks share one, and then its
    path), else None; the sample's area where its graph was built (else ``area``); and the
    sample as a cloud with that graph (else None: :func:`~superfacets.scale.tiles.phases.
    sample_start` reads it, not building its own)."""

    if not kind_of(reader.kind).cloud or survey.normals or reader.viewpoint is not None:
        return None, area, None
    step = phases.start_step(survey.sample.shape[0], reader.n_rows, params.n_segments)
    cloud = sample_cloud(survey.sample[::step], params.n_neighbors, up)
    if cloud is None:
        return np.zeros((0, 6)), area, None
    graph = points.point_graph(cloud, params.n_neighbors).graph  # (kept with the cloud)
    reference = np.hstack([graph.positions, graph.normals.astype(np.float64)])
    area = float(graph.sizes.sum())
    if folder:  # read by the tasks from the work folder, not shipped with each
        np.save(Path(folder) / "orientation.npy", reference)
        return str(Path(folder) / "orientation.npy"), area, cloud
    return reference, area, cloud


#: How much wider than the halo its estimate gives the boxes of the graphs built with the
#: areas are (the radius read on the survey's sample is within a few per cent of the
#: whole cloud's; a narrower halo than asked is never used: the graphs are then built again).
GRAPH_SLACK = 1.02


def _sized(run, layout, read: tuple, plan: tuple, diagonal: float, halo: float, kept):
    """The radius ``r`` of the run, the margin its tiles are read with, the input's area
    (a cloud's points' summed sizes; NaN for a cloud sized by ``radius``), the spread
    of a cloud's point sizes (:func:`superfacets.elements.density.size_spread`, added up
    over the tiles' cores; NaN where not read), and the merge ``plan`` (the count, the
    merges' factor, the tiles' parameters: :func:`_merge_plan`), made again from a cloud's
    measured area where a seed resolution gives its count; ``read``:
    the reader, its survey and the sizes in the data's units.

    A cloud sized by ``n_segments`` sums its tiles' point areas, read on boxes whose halo
    comes from the radius the survey's sample gives (``kept[1]``, its area, else read
    here), widened by :data:`GRAPH_SLACK`; where the tiles keep their point graphs
    (``kept[0]``, the graphs' folder), on the graphs each tile builds there. The phases then
    read the same boxes, so the graphs are built once (and a run that keeps none labels
    alike). If the halo the exact radius asks for is wider, the graphs are dropped, and
    the phases read that halo and build them."""

    graphs, sample_area = kept
    (reader, survey, units), params = read, plan[2]
    n, window, kind = survey.n_elements, params.window, reader.kind
    if not kind_of(kind).cloud or params.radius is not None:
        r = superfacet_size(params, survey.size, diagonal, n, kind)[1]
        return r, halo_distance(halo, window, r), \
            math.nan if kind_of(kind).cloud else survey.size, math.nan, plan
    wide, sample = None, survey.sample
    if sample is not None and sample.shape[0] > 1:
        if sample_area is None:
            sample_area = point_areas(sample, np.ones(sample.shape[0], dtype=bool),
                                      params.n_neighbors)
        if sample_area:  # (each point of the even sample sized by its sparser neighbours)
            rough = superfacet_size(params, sample_area, diagonal, n, kind)[1]
            wide = GRAPH_SLACK * halo_distance(halo, window, rough)
    asked = "seed_resolution" in units
    outs = run("areas", 0.25 * layout.min_side() if wide is None else wide,
               lambda t: dict(graph_area=wide is not None and graphs is not None,
                              surface_area=asked))
    area = sum(o.get("area", 0.0) for o in outs)
    if area <= 0:
        raise ParameterError("the points are too few or too sparse to size superpoints by "
                             "n_segments; give radius instead")
    if asked:  # (the count from the area measured, not estimated; with steps weighed, the
        # surface's area by the points' nearest neighbours, as one run's count reads it)
        surface = sum(o.get("surface_area", o.get("area", 0.0)) for o in outs)
        plan = _merge_plan(replace(params, n_segments=resolution_count(
            surface, units["seed_resolution"], n)), reader, survey, 1)
        params = plan[2]
    r = superfacet_size(params, area, diagonal, n, kind)[1]  # (the run's graph's sizes)
    area = surface if asked else area  # (the result's: the area its count read)
    margin = halo_distance(halo, window, r)
    spread = _spread([o["size_moments"] for o in outs if "size_moments" in o])
    if wide is not None and margin <= wide:
        return r, wide, area, spread, plan  # the boxes the graphs were built on (kept or not)
    drop_graphs(graphs)  # (too narrow: the phases build them on their boxes)
    return r, margin, area, spread, plan


def _spread(moments: list) -> float:
    """The standard deviation of the log point sizes from the tiles' ``(n, sum, sum of
    squares)`` (:func:`~superfacets.scale.tiles.phases.size_moments`); NaN under two."""
    n, s1, s2 = (sum(m[i] for m in moments) for i in range(3))
    if n < 2:
        return math.nan
    mean = s1 / n
    return float(math.sqrt(max(s2 / n - mean * mean, 0.0)))


def _stitched(done: list, n_rows: int):
    """Each row's label from the tile whose core holds it, how many rows of the tiles'
    rings another tile labelled otherwise, and the superfacets those rows name (either
    label: the only ones the stitching can have left in pieces)."""
    labels = np.full(n_rows, -1, dtype=np.int64)
    for o in done:
        labels[o["core_rows"]] = o["core_labels"]
    disagreements, named = 0, [np.zeros(0, dtype=np.int64)]
    for o in done:
        differ = labels[o["ring_rows"]] != o["ring_labels"]
        disagreements += int(differ.sum())
        named += [labels[o["ring_rows"][differ]], o["ring_labels"][differ]]
    suspects = np.unique(np.concatenate(named))
    return labels, disagreements, suspects[suspects >= 0]


def _checked_levels(levels, cost: str, extent_weight, params, graph: bool) -> tuple | None:
    """``(levels, cost, extent_weight)`` of a run's hierarchy, checked before any pass
    over the input (None: no levels); with ``up_weight`` the graph and levels are of the
    cloud as given, its point graph built by ``n_neighbors`` (not ``neighbor_radius``)."""
    if (graph or levels is not None) and params.up_weight not in (None, 1) and \
            params.neighbor_radius is not None:
        raise ParameterError("the superpoint graph and the levels of a tiled run with "
                             "up_weight are of the cloud as given, built with "
                             "n_neighbors alone: not with neighbor_radius")
    n_segments = params.n_segments
    if levels is None:
        if cost != "ward" or extent_weight is not None:
            raise ParameterError("level_cost and extent_weight are the levels' options: "
                                 "give levels too")
        return None
    wanted = wanted_levels(levels, n_segments)
    if cost not in ("ward", "planarity"):
        raise ParameterError(f"level_cost must be 'ward' or 'planarity', got {cost!r}")
    if extent_weight is not None and cost != "planarity":
        raise ParameterError("extent_weight is a term of level_cost='planarity'")
    weight = None if extent_weight is None else check_nonneg("extent_weight", extent_weight)
    return wanted, cost, weight


def _checked_options(n_segments, options, tiles, halo, refine, workers, start="sample",
                     memory_limit="auto", units=(None, None)):
    """The run's parameters and halo, and the sizes in the data's units given
    (:func:`_checked_units`), every option checked before any pass over the input."""
    units = _checked_units(*units, n_segments, options)

    if "features" in options:
        raise ParameterError("a tiled run reads colours from the file; features= is not taken")
    params = resolve(n_segments=n_segments, **options)
    if params.elements not in (None, "faces", "points"):
        raise ParameterError(f"a tiled run segments faces or points, not {params.elements!r}")
    check_tileable(params)
    check_tiles(tiles)  # before any pass over the file
    hold_from_env()  # (the workers read it: refused here, not in each task)
    check_memory_limit(memory_limit)  # (the engine's, made after the survey)
    halo = HALO if halo is None else halo
    halo_distance(halo, params.window, 1.0)  # validated before any work
    for name, v, low, high in (("refine", refine, 0, MAX_REFINE),
                               ("workers", workers, 1, max_threads())):
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, np.integer))
                              or not low <= v <= high):
            raise ParameterError(f"{name} must be an integer in {low}..{high}, got {v!r}")
    if start not in ("sample", "tiles"):
        raise ParameterError(f"start must be 'sample' or 'tiles', got {start!r}")
    return params, halo, units


def _step_resolved(params, reader, survey, units: dict) -> tuple:
    """The tiles' parameters: ``up_weight`` 1 (every position is read weighed),
    ``step_weight`` and ``max_size_ratio`` resolved once from the reader (a scene's
    neighbours along its surfaces and size bound, as one run's: every tile reads them),
    the sizes in the data's units resolved as far as the survey goes (:func:`_in_units`);
    and a cloud's area estimated on the survey's sample where that was read."""
    if not kind_of(reader.kind).cloud and params.step_weight not in (None, 1):
        raise ParameterError(f"step_weight weighs steps off a point cloud's surface; this "
                             f"input's elements are {reader.kind}")
    scene = getattr(reader, "up", None) is not None
    return _in_units(replace(params, up_weight=1.0,
                             **{name: scene_default_of(params, name, reader.kind, scene)
                                for name in SCENE_DEFAULTS}), reader, survey, units)


def _surveyed(source, tmp, tiles, params, graph: bool = False, levels=None, units=None):
    """The input's reader (streamed from its file, or spilled to the work folder; its
    points read weighed with ``up_weight``, its colours divided by the survey's one
    divisor), its survey (bounds, counts, a sample; with ``graph``, the extent along
    the ground grid's horizontal axes), checked against the tiles and the parameters,
    and the parameters with ``up_weight`` resolved (None: read off a scene's survey
    sample, as one run reads it off its points; 1 with sizes in the data's ``units``, and
    where a graph or ``levels`` are asked for with ``neighbor_radius``: what a weighed
    tiled run does not measure or build, as ``up_weight`` given is refused with them)."""

    if isinstance(source, (str, Path)):  # (~/scan.laz: the home's, read by every worker)
        source = user_path(source)
    if isinstance(source, RegionReader):  # opened by the caller (its viewpoint, up)
        reader = source
    elif isinstance(source, (str, Path)) and streamed(source):
        reader = RegionReader.open(source)
    else:  # (an object, or a file not read in chunks: an ASCII PLY, an OBJ, ...)
        reader = RegionReader.spill(source, tmp)
    if params.up_weight not in (None, 1):  # every position read stretched (tiles: W = 1)
        reader = _up_weighted(reader, params.up_weight)
    axes = ground_axes(_up_of(getattr(reader, "up", None)))[1:] if graph else None
    survey = reader.survey(axes)
    if params.up_weight is None:  # (a scene's, read off the sample as one run's points)
        unweighed = bool(units) or ((graph or levels is not None) and
                                    params.neighbor_radius is not None)
        weight = 1.0 if unweighed else up_weight_of(
            params, reader.kind, getattr(reader, "up", None), survey.sample)
        params = replace(params, up_weight=weight)
        if weight != 1:
            reader = _up_weighted(reader, weight)
            survey = _weighed_survey(survey, reader, axes)
    if params.n_segments is not None and params.radius is None:  # (as one run says it, not
        check_n_segments(params.n_segments, survey.n_elements, reader.kind)  # "no extent")
    if check_extent(survey.lo, survey.hi, f"{reader.path}: ",
                    "cloud" if kind_of(reader.kind).cloud else "mesh") == 0:
        raise ParameterError("the input has zero extent: nothing to tile")
    check_tiles(tiles, survey.n_elements)  # a handful of elements per tile: refused
    check_tileable(params, survey.colors)
    if survey.color_top is not None:  # one divisor for the whole file's colours
        reader = replace(reader, color_top=survey.color_top)
    if survey.dropped_normals:  # (unusable normals: all estimated, as one run's reader)
        warnings.warn(dropped_normals_said(reader.path, *survey.dropped_normals), stacklevel=2)
        reader = replace(reader, normals_given=False)
    return reader, survey, params


def _data_area(area: float, weight: float, survey, up, params) -> float:
    """The input's area in the data's units: ``area`` (the tiles' points' summed sizes)
    where the heights are not weighed, else its even sample's area (the survey's sample
    stretched back), as a seed resolution's count reads it first; NaN where none."""
    sample = survey.sample
    if weight == 1 or not np.isfinite(area) or sample is None or sample.shape[0] < 2:
        return area if weight == 1 else math.nan
    up = np.asarray(up, dtype=np.float64)
    flat = stretched_along(sample, up / np.linalg.norm(up), 1.0 / weight)
    return point_areas(flat, np.ones(flat.shape[0], dtype=bool), params.n_neighbors)


def _weighed_survey(survey, reader, axes):
    """The survey of ``reader`` (read weighed) from the unweighed one: its sample and box
    stretched where ``up`` is a coordinate axis (a LAS file's z: the box's corners move
    alone; the extent along the ground's axes, across ``up``, does not), else read again."""
    up = np.asarray(reader.up, dtype=np.float64)
    if np.count_nonzero(up) != 1:
        return reader.survey(axes)
    lo, hi = (stretched_along(b, up, reader.up_weight) for b in (survey.lo, survey.hi))
    return replace(survey, lo=np.minimum(lo, hi), hi=np.maximum(lo, hi),
                   sample=stretched_along(survey.sample, up, reader.up_weight))


def _up_weighted(reader, weight: float):
    """``reader`` reading its points' positions (and sensor) stretched along its up
    (``up_weight``: :func:`superfacets.inputs.cloud.up_weighted`, as one run's)."""
    check_weighable(kind_of(reader.kind).cloud, reader.kind, reader.up)
    vp = reader.viewpoint
    return replace(reader, up_weight=float(weight), viewpoint=None if vp is None else tuple(
        stretched_along(np.asarray(vp, dtype=np.float64), reader.up, weight).tolist()))


def _connected(run, labels, tiling, tmp, box, suspects) -> int:
    """Repair the pieces two tiles' different views of a border left, in ``labels`` (in
    place), a few rounds; returns the rows moved. Only the ``suspects`` (the superfacets
    the disagreeing rows name: every other one is its owner tile's, whole, and connected)
    are looked at, each by the tile whose core holds its center; then those that each
    round moved rows to or from. ``tiling``: the margin and the labels phase's outputs
    (each tile's core rows); ``box``: each tile's rows where the tasks are not sharing a
    folder."""
    margin, done = tiling
    repaired = 0
    for _ in range(CONNECT_ROUNDS):
        only = [o["tile"] for o in done if _holds_any(o["core_rows"], suspects)]
        if not only:
            break
        if box is None:  # the tasks read their boxes' labels from one file
            np.save(Path(tmp) / "stitched.npy", labels)
            fixes = run("connect", margin, lambda t: dict(
                labels=str(Path(tmp) / "stitched.npy"), suspects=suspects), only)
        else:
            fixes = run("connect", margin, lambda t: dict(labels=labels[box.get(t, [])],
                                                          suspects=suspects), only)
        moved = [o for o in fixes if o.get("moved_rows") is not None and o["moved_rows"].size]
        if not moved:
            break
        # tiles repair at once: a piece one moved can border a piece another moved away,
        # so the superfacets that gained or lost rows are looked at again
        rows = np.concatenate([o["moved_rows"] for o in moved])
        given = np.concatenate([o["moved_labels"] for o in moved])
        suspects = np.unique(np.concatenate([labels[rows], given]))
        labels[rows] = given
        repaired += int(rows.size)
    return repaired


def _holds_any(sorted_rows: np.ndarray, names: np.ndarray) -> bool:
    """Whether any of ``names`` (rows) is among ``sorted_rows`` (increasing)."""
    at = np.searchsorted(sorted_rows, names)
    ok = at < sorted_rows.size
    return bool((sorted_rows[at[ok]] == names[ok]).any())


def _tile_stats(found: list, done: list) -> list[dict]:
    """Each tile's core and rows, the centers in its core after the first phase that
    finds them (the centers phase, or the first refine round after a sample start), and
    the seconds and peak memory of that phase and of the labels phase (``peak_mib``: the
    larger)."""
    stats = {o["tile"]: dict(tile=o["tile"], core=o["core"], rows=o["rows"]) for o in found}
    for outs in (found, done):
        for o in outs:
            phase, peak = o["phase"], o["peak_mib"]
            stats[o["tile"]].update({f"{phase}_seconds": round(o["seconds"], 3),
                                     f"{phase}_peak_mib": peak})
            if peak is not None:
                stats[o["tile"]]["peak_mib"] = max(peak, stats[o["tile"]].get("peak_mib", 0))
            if outs is found:
                stats[o["tile"]]["centers"] = int(o["centers"].size)
    return [stats[k] for k in sorted(stats)]


@contextmanager
def _holding(engine: Engine, folder):
    """The run's tiles held in its workers' memory between phases (:mod:`.held`, each
    under a folder of the run's ``folder``: a cloud's graphs, a mesh's boxes), let go at
    its end, however it ends."""
    try:
        yield
    finally:
        engine.on_workers(release_held, str(folder))


@dataclass
class _Sent:
    """Where a run's phases send its tiles: each to the worker of its phase before (which
    holds its box: :mod:`.held`), and every other phase in the reverse order (the tiles a
    worker ran last, those it still holds where it cannot hold them all, first)."""

    at: dict = field(default_factory=dict)
    phases: int = 0


def _gather(engine: Engine, tasks: list, phase: str, progress: bool,
            sent: _Sent | None = None) -> list:
    """Run one phase's tasks; raise the first tile's error."""
    def lost(task, text):
        return {"tile": task["tile"], "phase": phase, "error": text}

    sent = _Sent() if sent is None else sent
    sent.phases += 1
    at = sent.at
    results, stop = engine.run(tile_task, tasks[::-1] if sent.phases % 2 == 0 else tasks,
                               on_lost=lost, prefer=lambda task: at.get(task["tile"])), None
    if progress:  # (its elapsed time redrawn while a tile runs: never silent)
        results = new_bar(results, total=len(tasks), desc=f"tiles: {phase}", unit="tile",
                          leave=False)
        stop = tick(results)
    out = []
    try:
        for o in results:
            if "error" in o:
                # (a tile's memory check speaks of that tile: more of them, not "N tiles")
                why = re.sub(r"segment it in \d+ tiles \(--tiles \d+, "
                             r"superfacets\.segment_tiled\)",
                             "segment it in more tiles (--tiles)", o["error"])
                raise SuperfacetsError(f"tile {o['tile']} ({phase}): {why}")
            if o.get("worker"):
                at[o["tile"]] = o["worker"]
            out.append(o)
    finally:
        if stop is not None:
            stop.set()
    return sorted(out, key=lambda o: o["tile"])


@contextmanager
def _stage(timings: dict, progress: bool, name: str, bar: bool = True, add: bool = False):
    """Time a stage of the run into ``timings[name]`` (added to what is there with
    ``add``), showing a line with its elapsed time while it runs where ``progress`` and
    ``bar`` (stages that show bars of their own pass ``bar=False``)."""
    t = time.perf_counter()
    with waiting_bar(f"tiles: {name}", show=progress and bar):
        yield
    timings[name] = (timings.get(name, 0.0) if add else 0.0) + time.perf_counter() - t
