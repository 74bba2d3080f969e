"""``segment INPUT --tiles N``: one large input tile by tile, on Dask or in this process."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from ..elements.density import AUTO_DENSITY, AUTO_SPREAD
from ..elements.kinds import kind_of
from .notes import fields_said, merges_said, records_said, resolution_said, scene_note, weights_said
from .options import (
    add_engine_options,
    check_drawings,
    check_labels_output,
    check_output,
    element_kwargs,
    method_kwargs,
    named_after,
    sizes_said,
)

#: The halos' share of a tiled run's work (``TiledResult.halo_ratio``) from which the
#: command says what they cost: from half again one run's work.
HALO_NOTE = 1.5


def tiles_arg(text: str):
    """``N`` (balanced tiles) or ``NX,NY,NZ`` (a regular grid)."""
    import argparse

    parts = text.split(",")
    try:
        vals = [int(p) for p in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected N or NX,NY,NZ (integers), got {text!r}") \
            from None
    if len(vals) not in (1, 3) or min(vals) < 1:
        raise argparse.ArgumentTypeError(f"expected N or NX,NY,NZ (integers >= 1), got {text!r}")
    return vals[0] if len(vals) == 1 else tuple(vals)


def add_tile_options(p) -> None:
    """``--tiles``, ``--halo``, ``-j/--workers``, ``--scheduler`` of ``segment``."""
    g = p.add_argument_group("tiles (one input larger than a machine)")
    g.add_argument("--tiles", type=tiles_arg, default=None, metavar="N|NX,NY,NZ",
                   help="cut the input into N spatial tiles with halos, one task each, "
                        "stitched so that no superfacet is cut by a tile border (N: boxes "
                        "holding about equal numbers of elements; NX,NY,NZ: a regular grid of "
                        "equal boxes); binary PLY, "
                        "LAS/LAZ and .npy are read in chunks, twice, and sorted into a file "
                        "per tile (labels: -o OUT.seg / .json; --picture, --html)")
    g.add_argument("--halo", type=float, default=None, metavar="H",
                   help="with --tiles: halo width in units of window * r (>= 1; default 3)")
    g.add_argument("--refine", type=int, default=None, metavar="N",
                   help="with --tiles: rounds of passes again on every tile from the gathered "
                        "centers (default 1; 0 is faster, and farther from one run)")
    g.add_argument("--tile-start", choices=("sample", "tiles"), default=None,
                   help="with --tiles: where the refine rounds start: the method once on an "
                        "even sample of the input (default; a mesh's face centroids), or "
                        "each tile's own centers on its box and halo (slower)")
    g.add_argument("--workdir", default=None, metavar="DIR",
                   help="with --tiles: folder for the work files (the input sorted by tile, "
                        "about its size; a cloud's tile graphs, about 120 bytes a point with "
                        "the halos), in a folder of the run's own made inside DIR and "
                        "removed at the end, nothing else in DIR touched (default: the "
                        "system's temporary folder); with --scheduler, one every worker "
                        "reaches, or each task reads INPUT whole")
    add_engine_options(g, sees="its workers must read INPUT by the same path",
                       prefix="with --tiles: ")


def segment_tiles(args) -> int:
    """``segment --tiles``: labels of a large input, written as ``-o`` says."""
    from .._runtime import interrupts
    from ..io.units import length_unit
    from .runs import check_units, say_geographic

    _refuse_one_run_options(args)
    drawings = check_drawings(args, (args.output,))
    if drawings[1] is not None:
        _check_page(args.mesh)
    seg_out = check_labels_output(args.output, args.mesh, records=True)
    graph_out = check_output(args.graph, (".npz",), "the graph", inputs=(args.mesh,))
    check_units(args)
    say_geographic(args)
    t0 = time.perf_counter()
    result, wanted = _tiled_run(args, graph_out is not None)
    elapsed = time.perf_counter() - t0
    interrupts.last_outputs()  # (once whole, a Ctrl-C no longer undoes the run)
    kept = _write_labels(seg_out, args.mesh, result, graph_out)
    report = sys.stderr if str(seg_out) == "-" else sys.stdout
    if not args.quiet:
        kind = result.params["elements"]
        peak = max((t.get("peak_mib") or 0 for t in result.tiles), default=0)
        what = kind_of(kind).segment_word
        k = args.n_segments
        asked = ("" if k is None or result.n_segments == k else
                 f" ({k} asked: tiles this small hold fewer centers; see docs/notes/tiles.md)"
                 if result.n_segments < k else f" ({k} asked)")
        first = result.params.get("merged_from")
        if first:
            what += merges_said(first, result.params, kind_of(kind).cloud,
                                scene=getattr(args, "merge_from", None) is None)
        what += weights_said(result.params)  # (as one run's summary says them)
        if result.n_segments > 1:
            what += sizes_said(result.labels, kind, result, length_unit(args.mesh))
        invalid = int((result.labels < 0).sum()) if kind == "points" else 0
        said = f" ({invalid:,} invalid)" if invalid else ""  # (as one run's summary says)
        print(f"{Path(args.mesh).name}: {result.labels.size:,} {kind}{said}, "
              f"{result.n_segments:,} "
              f"{what}{asked} in {len(result.tiles)} tiles "
              f"({result.layout.describe()}), {elapsed:.2f} s; largest tile "
              f"{max(t['rows'] for t in result.tiles):,} {kind} with its halo, peak "
              f"{peak:,.0f} MiB; {result.disagreements:,} border disagreements", file=report)
        count = _count_said(args, result, wanted)
        if count:
            print(count, file=report)
        if _uneven(args, result):
            print(f"note: the points' sizes spread {result.size_spread:.2f} (an uneven "
                  f"density): one run would size its superpoints by it (--density "
                  f"{AUTO_DENSITY:g}); tiles keep equal areas (see docs/guide/scale.md)",
                  file=sys.stderr)
        scene = result.params.get("up") is None and scene_note(
            None, kind, Path(args.mesh).name, extent=result.layout.hi.max(axis=0) -
            result.layout.lo.min(axis=0))
        if scene:
            print(f"note: {scene}", file=sys.stderr)
        if result.halo_ratio >= HALO_NOTE:
            print(f"note: with their halos the tiles ran over {result.halo_ratio:.2f} times "
                  f"the {kind}, about that many times one run's work: fewer tiles, or more "
                  f"{kind} per {kind_of(kind).segment_word[:-1]}, cost less", file=sys.stderr)
        if seg_out is not None and str(seg_out) != "-":
            levels = () if result.hierarchy is None else result.hierarchy.levels
            what = records_said(seg_out, args.mesh, kind, kept, levels) or \
                f"labels, one per {kind_of(kind).singular}"
            print(f"wrote {seg_out} ({what})", file=report)
        if graph_out is not None:
            print(f"wrote {graph_out} (superpoint graph, PyTorch Geometric's layout)",
                  file=report)
        if seg_out is None and graph_out is None and drawings == (None, None):
            print("note: nothing was saved: add -o OUT.seg", file=sys.stderr)
    if drawings != (None, None):
        _draw(args, result, *drawings)
    return 0


def _uneven(args, result) -> bool:
    """Whether one run of the same options would size the superpoints by the points'
    density, which a tiled run does not (:func:`superfacets.elements.density.density_for`:
    a spread above :data:`~superfacets.elements.density.AUTO_SPREAD`, left automatic)."""
    return (getattr(args, "density", None) is None and not getattr(args, "paper", False)
            and result.size_spread > AUTO_SPREAD)


def _refuse_one_run_options(args) -> None:
    """Refuse the options of ``segment`` that only one run gives."""
    from ..errors import ParameterError

    for flag, given in (("--colored-mesh", args.colored_mesh),
                        ("--per-object", args.per_object)):
        if given:
            raise ParameterError(f"{flag} needs the whole input in one process; not with "
                                 "--tiles (write -o OUT.seg, then view a part)")
    from ..io.records import scan_output

    if args.levels and scan_output(args.output, args.mesh) is None and args.graph is None:
        raise ParameterError("--levels of a tiled run go into --graph OUT.npz or -o of the "
                             "scan's own records (.las/.laz, .ply, .pcd): each level a field "
                             "ClusterID_N after the labels")
    if (args.level_cost is not None or args.extent_weight is not None) and not args.levels:
        raise ParameterError("--level-cost and --extent-weight are the options of --levels; "
                             "give --levels too")
    if getattr(args, "elements", None) == "vertices":
        raise ParameterError("--tiles segments faces or points, not vertices")
    units = [f for f, v in (("--seed-resolution", args.seed_resolution),
                            ("--neighbor-distance", args.neighbor_distance)) if v is not None]
    if units and getattr(args, "up_weight", None) not in (None, 1, 1.0):
        raise ParameterError(f"{' and '.join(units)} with --up-weight: the tiles measure the "
                             "weighed cloud; give -k and --neighbor-radius")
    if args.header:  # (its lines record one run's passes and time)
        raise ParameterError("--header records one run's parameters and passes; a tiled run "
                             "writes the labels alone (its summary says the rest)")


def _check_page(path) -> None:
    """Refuse ``--html`` of a mesh file whose triangles no page holds, before the run (a
    tiled mesh is of triangles; a cloud's page draws the survey's sample)."""
    from ..io.regions import RegionReader, streamed
    from ..viz.html import MAX_PAGE_TRIANGLES

    if not streamed(path):  # (a file read whole is checked once read, after the run)
        return
    reader = RegionReader.open(path)
    if reader.kind == "faces" and reader.n_rows > MAX_PAGE_TRIANGLES:
        from ..errors import ParameterError

        raise ParameterError(f"{path}: a page of {reader.n_rows:,} triangles would not open "
                             f"in a browser (at most {MAX_PAGE_TRIANGLES:,}); draw it with "
                             "--picture OUT.png")


def _drawn(args, result) -> tuple:
    """What a tiled run's picture and page draw: a cloud that streams (binary PLY,
    LAS/LAZ, ``.npy``) as the survey's even sample of it (at most about a million points,
    read again in one pass: the whole cloud need not fit), anything else read whole; with
    the drawn elements' labels."""
    from dataclasses import replace

    from ..inputs.cloud import PointCloud
    from ..io.regions import RegionReader, streamed
    from .options import read_usable

    source = _source(args)
    if result.params["elements"] == "points" and streamed(args.mesh):
        reader = source if isinstance(source, RegionReader) else RegionReader.open(args.mesh)
        survey = replace(reader, up_weight=1.0).survey()  # (the positions as in the file)
        data = PointCloud(survey.sample, viewpoint=reader.viewpoint, up=reader.up,
                          name=Path(args.mesh).name)
        return data, result.labels[survey.sample_rows]
    data = source if isinstance(source, PointCloud) else read_usable(args.mesh, clouds=True)
    return data, result.labels


def _draw(args, result, png_out, html_out) -> None:
    """``--picture`` and ``--html`` of a tiled run, drawn once its labels are written
    (:func:`_drawn`); a picture's legend and a page's count from every label."""
    from ..io.orientation import default_view
    from ..viz.html import check_page_size, write_html
    from ..viz.render import PICTURE_SIZE, render, render_points
    from .options import said_up, up_of

    t0 = time.perf_counter()
    kind = result.params["elements"]
    data, labels = _drawn(args, result)
    up = up_of(args, data)
    name = Path(args.mesh).name
    style = dict(view=args.view if args.view is not None else default_view(data), up=up[0],
                 title=f"{name}: {result.n_segments} {kind_of(kind).segment_word}")
    cloud = kind == "points"
    n_all = int((result.labels >= 0).sum())
    if html_out is not None:
        if not cloud:
            check_page_size(data)
        info = {"drawn": f"{data.n_points:,} of {n_all:,} points (an even sample)"} \
            if cloud and data.n_points < n_all else None
        write_html(html_out, data, labels, info=info, **style)
    if png_out is not None:
        if cloud:
            render_points(data, labels, png_out, legend=result.labels, **style)
        else:
            render(data, labels, png_out, legend=True, elements=kind, **style)
    if args.quiet:
        return
    drawn = f", {min(data.n_points, PICTURE_SIZE[0] * PICTURE_SIZE[1]):,} of {n_all:,} " \
        "points drawn" if cloud else ""
    said = [(out, what) for out, what in ((png_out, f"picture, {said_up(up)}{drawn}"),
                                          (html_out, "page: open it in a browser"))
            if out is not None]
    for i, (out, what) in enumerate(said):
        took = f", both drawn in {time.perf_counter() - t0:.2f} s" if len(said) == 2 else \
            f", drawn in {time.perf_counter() - t0:.2f} s"
        print(f"wrote {out} ({what}{took if i == len(said) - 1 else ''})")


def _tiled_run(args, graph: bool) -> tuple:
    """The tiled run the options ask for, and the count it was asked for (None: a radius
    or a seed resolution gives it)."""
    from ..errors import SuperfacetsError
    from ..scale.tiles.run import segment_tiled

    kwargs = dict(method_kwargs(args), **element_kwargs(args))
    kwargs.pop("progress", None)
    source = _source(args)
    wanted = args.n_segments if args.n_segments is not None or args.radius is not None \
        or args.seed_resolution is not None else _default_count(source)
    try:
        return segment_tiled(source, wanted, radius=args.radius, tiles=args.tiles,
                             halo=args.halo, workers=args.workers, scheduler=args.scheduler,
                             refine=1 if args.refine is None else args.refine,
                             start=args.tile_start or "sample",
                             workdir=args.workdir, levels=args.levels,
                             level_cost=args.level_cost or "ward",
                             extent_weight=args.extent_weight, graph=graph,
                             seed_resolution=args.seed_resolution,
                             neighbor_distance=args.neighbor_distance,
                             progress=not args.quiet and sys.stderr.isatty(), **kwargs), wanted
    except SuperfacetsError as exc:
        raise named_after(args.mesh, exc) from None


def _count_said(args, result, k) -> str:
    """Where the count of a tiled run came from, as one run's summary says it: the seed
    resolution and the area the tiles measured, or the default that grows with a cloud."""
    from ..api.sizes import POINTS_PER_SEGMENT, resolution_count
    from ..io.units import length_unit
    from ..method.params import DEFAULTS

    segs = kind_of(result.params["elements"]).segment_word
    res = args.seed_resolution
    if res is not None:  # (the count asked: the input's pieces may have made more)
        n = resolution_count(result.area, res, int(result.labels.size))
        return resolution_said(n, result.params["elements"], res, result.area,
                               length_unit(args.mesh))
    if args.n_segments is None and args.radius is None and k != DEFAULTS.n_segments:
        return (f"k = {k:,} {segs} by default (one per {POINTS_PER_SEGMENT:,} points; -k or "
                "--seed-resolution to choose)")
    return ""


def _default_count(source) -> int:
    """The count of a tiled run given none, as one run's
    (:func:`superfacets.api.sizes.default_count`): one superpoint per
    :data:`~superfacets.api.sizes.POINTS_PER_SEGMENT` points of a cloud (its rows: a
    streamed file's header), at least 150; a mesh's 150."""
    from ..api.sizes import default_count_of
    from ..io.regions import RegionReader, streamed

    if not isinstance(source, (str, Path)):
        reader = source
    elif streamed(source):
        reader = RegionReader.open(source)
    else:
        from .options import read_usable

        reader = read_usable(source, clouds=True)
    cloud = getattr(reader, "kind", "points" if hasattr(reader, "n_points") else "faces")
    n = getattr(reader, "n_rows", None) or getattr(reader, "n_points", None) or reader.n_faces
    return default_count_of(int(n), kind_of(cloud).cloud)


def _source(args):
    """The input of a tiled run: its path, or with ``--viewpoint``/``--seen-from`` its
    streamed reader (or, for a file that is not streamed, the cloud) carrying them."""
    from .options import read_usable, scan_cloud, scan_fields

    changes = scan_fields(args)
    if not changes:
        return args.mesh
    from dataclasses import replace

    from ..errors import ParameterError
    from ..io.regions import RegionReader, streamed

    if not streamed(args.mesh):
        return scan_cloud(read_usable(args.mesh, clouds=True), args)
    reader = RegionReader.open(args.mesh)
    if reader.kind != "points":
        raise ParameterError("--viewpoint and --seen-from orient point clouds; the input is "
                             "a mesh")
    return replace(reader, **changes)


def _write_labels(seg_out, source, result, graph_out=None) -> str:
    """``-o``'s file of a tiled run: the input's records or a new scan file with the labels
    (:func:`superfacets.io.records.write_scan_labels`), segIndices, or a label file; a new
    file's kept values, said (``" with their intensity and ring"``; else "")."""
    from ..io.clouds import read_cloud
    from ..io.files import Outputs
    from ..io.labels import write_labels, write_segindices
    from ..io.records import kept_fields, level_field, scan_output, write_scan_labels

    kept = []
    with Outputs() as outputs:
        if graph_out is not None:  # (the keys one run's --graph writes)
            arrays = dict(result.learning, labels=result.labels)
            h = result.hierarchy
            if h is not None:
                arrays.update(h.arrays(), **{f"labels_{i}": h.labels(i, result.labels)
                                             for i in range(len(h.levels))})
            outputs.write(graph_out, lambda fh: np.savez_compressed(fh, **arrays))
        if seg_out is not None:
            into = scan_output(seg_out, source)
            if into is not None:  # (a new file: the input read once more)
                cloud = read_cloud(source) if into == "new" else None
                kept = [] if cloud is None else kept_fields(seg_out, cloud)
                h = result.hierarchy
                levels = {} if h is None else {level_field(n): h.labels(i, result.labels)
                                               for i, n in enumerate(h.levels)}
                write_scan_labels(seg_out, source, result.labels, cloud=cloud, levels=levels,
                                  outputs=outputs)
            elif str(seg_out).lower().endswith(".json"):
                write_segindices(seg_out, result.labels, result.params, outputs=outputs)
            else:
                write_labels(seg_out, result.labels, outputs=outputs)
    return fields_said(kept)
