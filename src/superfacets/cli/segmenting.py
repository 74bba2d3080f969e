"""Commands that segment one mesh or judge one result: segment, baseline, demo, evaluate."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from ..checks import counted
from ..elements.kinds import kind_of
from ..method.params import DEFAULTS
from .notes import (
    count_note,
    duplicates_note,
    fields_said,
    merges_said,
    records_said,
    scene_note,
    weights_said,
)
from .options import (
    add_adaptive_options,
    add_camera_options,
    add_element_options,
    add_method_options,
    add_scan_options,
    add_unit_options,
    check_drawings,
    check_header_option,
    check_labels_output,
    check_output,
    element_kwargs,
    fmt_value,
    int_arg,
    levels_arg,
    method_kwargs,
    read_usable,
    refuse_neighbours,
    said_up,
    scan_cloud,
    shows_stages,
    sizes_said,
    up_of,
)
from .runs import check_units, checked_graph, run_segment, say_geographic, sizes_of

__all__ = ["add_parsers"]


def add_parsers(sub) -> None:
    """Add ``segment``, ``baseline`` and ``demo`` to the sub-parsers."""
    _add_segment(sub)
    _add_baseline(sub)
    _add_demo(sub)


def _add_segment(sub) -> None:
    p = sub.add_parser(
        "segment", help="compute the superfacets of a mesh or a point cloud file",
        description="Compute the superfacets of a mesh file (.off, .tri, .ply, .obj, .stl, "
                    ".glb, .gltf, optionally .gz/.xz/.bz2; triangles or polygons, one label "
                    "per face in file order; the objects of a scene joined in order), or "
                    "of its vertices (--elements vertices), or the superpoints of a point "
                    "cloud (.ply without faces, .pcd, .xyz/.pts/.txt, .npy, .las/.laz, .e57, "
                    "KITTI's .bin, nuScenes' .pcd.bin; one "
                    "label per point in file order, -1 for invalid points), and write them "
                    "as a .seg label file (one label per line), a ScanNet-style .json "
                    "(segIndices) and/or a coloured mesh or cloud.")
    inp = p.add_argument_group("input")
    inp.add_argument("mesh", metavar="INPUT",
                     help="a mesh (.off, .tri, .ply, .obj, .stl, .glb, .gltf), a point cloud "
                          "(.ply without faces, .pcd, .xyz/.pts/.txt, .npy, .las/.laz, .e57, "
                          "KITTI's velodyne .bin, nuScenes' .pcd.bin) or a "
                          "tetrahedral mesh (.msh, .vtk, .vtu, .mesh), optionally "
                          ".gz/.xz/.bz2")
    add_scan_options(inp)
    add_method_options(p)
    add_element_options(p)
    add_unit_options(p.add_argument_group("sizes in the data's units"))
    out = p.add_argument_group("outputs")
    out.add_argument("-o", "--output", metavar="OUT.seg", default=None,
                     help="write the labels here: one per face, vertex or point per line, or "
                          "{'segIndices': [...], 'params': ...} when it ends in .json "
                          "('-': standard output; default: none); a .las/.laz, .ply or .pcd "
                          "of a scan of that format (a .npy of NPY records): a copy of its "
                          "records with the labels as the field ClusterID; a .npy of a "
                          ".npy of positions: the labels (int64); a .las/.laz or .ply of a "
                          "cloud whose "
                          "file takes no field (.xyz, .npy, .bin, .e57, ...): a new file "
                          "of its points with that field")
    out.add_argument("--header", action="store_true",
                     help="start the .seg file with '#' lines recording parameters, "
                          "iterations and time (default: labels only, as the benchmark's "
                          "files)")
    out.add_argument("--colored-mesh", metavar="OUT.ply", default=None,
                     help="write the mesh coloured by superfacet: .ply (polygons kept, face "
                          "colours and an int32 face property 'label'), .glb (for Blender, "
                          "three.js, model viewers) or .obj (a material per colour, with "
                          ".mtl)")
    out.add_argument("--vertex-colors", action="store_true",
                     help="PLY: colours per vertex (each face its own vertices) instead of "
                          "per face, for tools that show only vertex colours")
    out.add_argument("--graph", metavar="OUT.npz", default=None,
                     help="write the superfacet (superpoint) adjacency graph: edge_index, "
                          "border_length, mean_angle, concave, area, centroid, normal, "
                          "feature (mean colour), labels (numpy .npz)")
    levels = p.add_argument_group("levels (coarser, nested segmentations)")
    levels.add_argument("--levels", type=levels_arg, default=None, metavar="N1,N2,...",
                        help="also a nested hierarchy of coarser levels of N1, N2, ... "
                             "segments, each connected: with --graph, parent_<i> and "
                             "labels_<i> in the .npz; with -o of the scan's records "
                             "(.las/.laz, .ply, .pcd), each level a field ClusterID_N after "
                             "the labels")
    add_adaptive_options(levels)
    levels.add_argument("--level-cost", choices=("ward", "planarity"), default=None,
                        help="the levels' merge cost: ward (compact segments, the default) "
                             "or planarity (flat regions merged first: with -k several times "
                             "the level, content-adaptive superpoints)")
    levels.add_argument("--per-object", action="store_true",
                        help="segment each object of a scene (each scan of an E57 file) on "
                             "its own (-k shared out by area, or points); labels stay unique "
                             "over the scene")
    pics = p.add_argument_group("pictures")
    pics.add_argument("--picture", metavar="OUT.png", default=None,
                      help="also render a picture (faces or points coloured by label; needs "
                           "the render extra)")
    pics.add_argument("--html", metavar="OUT.html", default=None,
                      help="also write an interactive page (open in a browser)")
    add_camera_options(pics, "")  # --view, --up of --picture and --html
    from .tiles import add_tile_options

    add_tile_options(p)
    p.set_defaults(func=cmd_segment)


def _add_baseline(sub) -> None:
    bl = sub.add_parser(
        "baseline", help="segment a mesh or a point cloud with a baseline (normalized cuts, "
                         "VSA, cut pursuit, ...)",
        description="Segment a mesh or a point cloud with any method of the registry (see "
                    "'superfacets experiment --list-methods'): the baselines of the paper's "
                    "comparisons, normalized cuts ('ncuts', O(m^2) memory: meshes over its "
                    "memory limit are refused before anything is allocated) and Variational "
                    "Shape Approximation ('vsa'), or 'shlafman'; on point clouds the "
                    "Segmentator's graph segmentation, cut pursuit, Superpoint Transformer's "
                    "partition ('spt_partition') and VCCS. Writes a .seg label file (or the "
                    "input's records: -o OUT.laz) and/or a coloured PLY, like 'segment'.")
    bl.add_argument("mesh", metavar="INPUT",
                    help="a mesh or a point cloud (every format 'segment' reads)")
    bl.add_argument("-m", "--method", required=True, metavar="NAME",
                    help="registered method (superfacets experiment --list-methods): ncuts, "
                         "vsa, shlafman on faces; graph_segmentation (the ScanNet "
                         "Segmentator's), cut_pursuit, spt_partition, vccs on points")
    bl.add_argument("--elements", choices=("faces", "vertices", "points"), default=None,
                    help="what to segment of a mesh (default: faces; a cloud's points)")
    bl.add_argument("-k", "--n-segments", type=int_arg, default=DEFAULTS.n_segments,
                    metavar="N", help=f"number of segments (default: {DEFAULTS.n_segments})")
    bl.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                    help="a method parameter, repeatable (e.g. metric=l2 init=incremental for "
                         "vsa; alpha=100 memory_limit_gib=8 for ncuts)")
    bl.add_argument("--seed", type=int_arg, default=0,
                    help="seed of randomized methods (default 0)")
    bl.add_argument("-o", "--output", metavar="OUT.seg", default=None,
                    help="write the labels here (one per face per line)")
    bl.add_argument("--colored-mesh", metavar="OUT.ply", default=None,
                    help="write the mesh as a binary PLY with one colour per segment")
    bl.add_argument("--picture", metavar="OUT.png", default=None,
                    help="also render a picture, as segment does (the render extra)")
    bl.add_argument("--html", metavar="OUT.html", default=None,
                    help="also write an interactive page (open in a browser)")
    add_camera_options(bl, "")  # --view, --up of --picture and --html
    add_scan_options(bl)  # (a scan's up and its normals' side, as segment reads them)
    bl.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    bl.set_defaults(func=cmd_baseline)


def _add_demo(sub) -> None:
    d = sub.add_parser(
        "demo", help="segment a built-in procedural mesh (no data needed)",
        description="Build a procedural four-legged creature (about 22,000 faces), compute "
                    "its superfacets and write the mesh, the labels and a coloured PLY.")
    d.add_argument("--output-dir", default="demo-output", metavar="DIR",
                   help="folder for the outputs, created if needed (default: demo-output)")
    d.add_argument("--resolution", type=int_arg, default=58, metavar="N",
                   help="grid samples along the shape's longest axis, 16..300 (default: 58)")
    d.add_argument("-k", "--n-segments", type=int_arg, default=DEFAULTS.n_segments, metavar="N",
                   help=f"number of superfacets (default: {DEFAULTS.n_segments})")
    add_method_options(d, with_size=False)
    d.set_defaults(func=cmd_demo)


def _summary(name: str, mesh, result, seconds: float, elements: str = "faces",
             density_given: bool = True, merge_given: bool = True,
             unit: str | None = None) -> str:
    from ..api.result import describe_stop

    state = describe_stop(result)
    if elements == "points":
        invalid = mesh.n_total - mesh.n_points
        what = counted(mesh.n_total, "point") + (f" ({invalid:,} invalid)" if invalid else "")
        segs = "superpoints"
        if not density_given and ((getattr(result, "params", None) or {}).get("density") or 0):
            segs += " sized by the points' uneven density (auto; --density 0: equal areas)"
        merged = (getattr(result, "params", None) or {}).get("merge_from") or 1
        first = (getattr(result, "params", None) or {}).get("n_init_centers") or 0
        if merged > 1 and first > result.n_segments:
            segs += merges_said(first, getattr(result, "params", None) or {},
                                scene=not merge_given)
    else:
        kind = "" if mesh.is_triangular else " (polygons)"
        objs = f" in {len(mesh.objects)} objects" if len(mesh.objects) > 1 else ""
        faces = counted(mesh.n_faces, "face")
        what = (f"{faces}{kind}{objs}" if elements == "faces" else
                f"{counted(mesh.n_vertices, 'vertex', 'vertices')} ({faces}{kind})")
        segs = kind_of(elements).segment_word
    params = getattr(result, "params", None) or {}
    segs += weights_said(params)
    start = params.get("start")
    if start:  # --adaptive: the iterations and the hints are of the start's segmentation
        first = params.get("n_init_centers") or 0
        segs = f"content-adaptive {segs} (merged from " + (
            f"{first:,}" if first and first < start * result.n_segments else
            f"{start} times as many") + ")"
    t = getattr(result, "timings", None) or {}
    coarse = (f", after {t['coarse_passes']} on {t['coarse_elements']:,} clusters "
              f"(coarse-to-fine)" if t.get("coarse_elements") and "coarse_passes" in t else "")
    swaps = f", {_count(t['swaps'], 'split-and-merge swap')}" if "swaps" in t else ""
    if result.n_segments == 1:  # (one superfacet, one superpoint)
        segs = segs.replace("superfacets", "superfacet", 1).replace("superpoints", "superpoint", 1)
    else:  # how even they are: the smallest, the largest and the median
        segs += sizes_said(result.labels, elements, result, unit)
    return (f"{name}: {what}, {result.n_segments} {segs}, "
            f"{_count(result.n_iter, 'iteration')} ({state}){coarse}{swaps}, {seconds:.2f} s"
            f"{_tiny_hint(result) if elements == 'points' and not start else ''}")


def _count(n: int, word: str) -> str:
    """``n`` and ``word``, plural unless ``n`` is 1 ("1 iteration", "3 iterations")."""
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


def _tiny_hint(result) -> str:
    """``'; N of them of 1 or 2 points ...'`` where at least 1 % of the superpoints are
    that small (a LiDAR sweep's sparse far range) and ``min_elements`` was not given;
    it names the option that merges them and, unless given, ``--density``."""
    labels = getattr(result, "element_labels", None)
    if labels is None or (getattr(result, "params", None) or {}).get("min_elements", 1) > 1:
        return ""
    n = int((np.bincount(labels) < 3).sum())
    if n == 0 or n < 0.01 * result.n_segments:
        return ""
    density = "" if ((result.params or {}).get("density") or 0) > 0 else \
        "; --density 0.5 sizes superpoints by the points' density"
    return f"; {n} of them of 1 or 2 points (--min-elements 3 merges them{density})"



def cmd_segment(args) -> int:
    from .._runtime import interrupts
    from ..method.params import resolve

    if Path(args.mesh).is_dir():
        raise IsADirectoryError(f"{args.mesh}: is a directory; to segment every mesh or cloud "
                                f"in it: superfacets batch {args.mesh} -o OUTDIR")
    elsewhere = _other_command(args)  # a tetrahedral mesh, tiles
    if elsewhere is not None:
        return elsewhere()
    outputs = _checked_outputs(args)
    check_units(args)
    say_geographic(args)
    kwargs = dict(method_kwargs(args), **element_kwargs(args))
    resolve(n_segments=args.n_segments, radius=args.radius, **kwargs)  # before the read
    t0 = time.perf_counter()
    with _reading_bar(args):
        data = scan_cloud(read_usable(args.mesh, clouds=True), args)
    interrupts.check()  # a Ctrl-C during the start-up and the reading
    kind = _kind_of_run(args, data, outputs["colored"])
    if outputs["html"] is not None and not kind_of(kind).cloud:  # (before the run)
        from ..inputs.mesh import Mesh
        from ..viz.html import check_page_size

        if isinstance(data, Mesh):  # (a volume's page draws its cut)
            check_page_size(data)
    kwargs, size_note = sizes_of(args, data, kind, kwargs)
    result = run_segment(args, data, kwargs)
    elapsed = time.perf_counter() - t0
    interrupts.last_outputs()  # (once they are whole, a Ctrl-C no longer undoes the run)
    _write_and_say(args, data, result, kind, outputs, elapsed, size_note)
    return 0


def _reading_bar(args):
    """A bar naming the file while it is read, its elapsed time going on, where the run
    shows progress (``--progress``, or a file that reads long on a terminal without
    ``-q``: :func:`~superfacets.cli.reading.reads_long`; not with ``--no-progress``)."""
    from .._runtime.progress import waiting_bar

    path = Path(args.mesh)
    size = path.stat().st_size if path.is_file() else 0
    show = args.progress if args.progress is not None else shows_stages(args, path=path)
    return waiting_bar(f"reading {path.name} ({size / 2**20:,.0f} MiB)", bool(show))


def _other_command(args):
    """The command that takes this input instead (a tetrahedral mesh, ``--tiles``), as a
    function of no argument; None where it is this one (then no tile option is given)."""
    from ..errors import ParameterError
    from ..io import input_kind

    if input_kind(args.mesh) == "volume":
        if args.tiles is not None:
            raise ParameterError("--tiles takes triangle meshes and point clouds, not "
                                 "tetrahedral meshes")
        from .tetmeshes import segment_volume

        return lambda: segment_volume(args)
    if args.tiles is not None:
        if args.adaptive is not None:
            raise ParameterError("--adaptive merges levels of the whole input; not with --tiles")
        from .tiles import segment_tiles

        return lambda: segment_tiles(args)
    for flag, given in (("--halo", args.halo), ("--workers", args.workers),
                        ("--scheduler", args.scheduler), ("--refine", args.refine),
                        ("--tile-start", args.tile_start), ("--workdir", args.workdir)):
        if given is not None:
            raise ParameterError(f"{flag} goes with --tiles")
    return None


def _checked_outputs(args) -> dict:
    """The output paths of ``segment``, checked against each other and the options that
    go with them, before anything is read (one line each)."""
    from ..errors import ParameterError

    seg_out = check_labels_output(args.output, args.mesh, records=True)
    ply_out = check_output(args.colored_mesh, (".ply", ".glb", ".obj"), "the coloured mesh",
                           inputs=(args.mesh,))
    if seg_out is not None and ply_out is not None and str(seg_out) == str(ply_out):
        raise ParameterError(f"{seg_out}: the labels and the coloured mesh cannot both go there")
    if args.vertex_colors and (ply_out is None or not ply_out.name.lower().endswith(".ply")):
        raise ParameterError("--vertex-colors goes with --colored-mesh OUT.ply")
    check_header_option(args.header, seg_out, args.mesh)
    graph_out = checked_graph(args, _into_records(seg_out, args.mesh))
    png_out, html_out = check_drawings(args, (seg_out, ply_out, graph_out))
    if graph_out is not None and args.per_object:
        raise ParameterError("--graph is of one segmentation; not with --per-object")
    return dict(labels=seg_out, colored=ply_out, picture=png_out, html=html_out,
                graph=graph_out)


def _kind_of_run(args, data, ply_out) -> str:
    """The elements segmented, checked against the options that need faces."""
    from ..errors import ParameterError

    kind = "points" if not hasattr(data, "faces") else (args.elements or "faces")
    refuse_neighbours(args.neighbors, args.neighbor_radius, kind)
    if kind == "faces" and _into_records(args.output, args.mesh):
        raise ParameterError(f"{args.output}: a PLY's records are its vertices: -o OUT.ply "
                             "takes the labels of --elements vertices; the labels of faces go "
                             "in a label file (-o NAME.seg) or as the coloured mesh's face "
                             "property 'label' (--colored-mesh OUT.ply)")
    objects = len(getattr(data, "objects", ()) or ()) or 1
    if args.per_object and args.levels and min(args.levels) < objects:
        raise ParameterError(f"--levels with --per-object: each level holds at least one "
                             f"segment per object ({objects}), got {min(args.levels)}")
    if not kind_of(kind).objects:
        if args.per_object and not (kind == "points" and getattr(data, "objects", ())):
            raise ParameterError("--per-object segments the faces of a scene or the scans of "
                                 "a multi-scan cloud (E57); not with "
                                 f"{kind}")
        if ply_out is not None and not ply_out.name.lower().endswith(".ply"):
            raise ParameterError(f"{ply_out}: coloured {kind} are written as .ply")
    return kind


def _into_records(output, source) -> bool:
    """Whether ``-o`` writes the labels into a scan's file: a copy of the input's records,
    or a new LAS/LAZ or PLY of a cloud's points."""
    from ..io.records import scan_output

    return scan_output(output, source) is not None


def _write_and_say(args, data, result, kind, outputs, elapsed, size_note: str = "") -> None:
    """Write the outputs, then the summary, what was written and the notes."""
    from ..io.orientation import default_view
    from ..io.units import length_unit
    from ..viz.outputs import write_result

    up = up_of(args, data)  # (a LAS cloud is upright with z up, an STL mesh too)
    view = args.view if args.view is not None else default_view(data)  # (a scan's own)
    with _writing_bar(args, data, outputs):
        write_result(data, result, kind, Path(args.mesh).name, labels=outputs["labels"],
                     source_path=args.mesh,
                     header=args.header, colored=outputs["colored"],
                     vertex_colors=args.vertex_colors, picture=outputs["picture"],
                     html=outputs["html"], element_options=dict(
                         n_neighbors=args.neighbors, neighbor_radius=args.neighbor_radius),
                     up=up[0], view=view, graph=outputs["graph"],
                     levels=args.levels, level_cost=args.level_cost or "ward",
                     extent_weight=args.extent_weight)
    if args.quiet:
        return
    seg_out = outputs["labels"]
    report = sys.stderr if str(seg_out) == "-" else sys.stdout  # stdout holds the labels
    print(_summary(Path(args.mesh).name, data, result, elapsed, kind,
                   getattr(args, "density", None) is not None,
                   getattr(args, "merge_from", None) is not None,
                   length_unit(args.mesh)), file=report)
    if size_note:
        print(size_note, file=report)
    _say_what_was_written(seg_out, outputs["colored"], outputs["picture"], outputs["html"],
                          report, up, outputs["graph"], _labels_what(args, kind, data), kind,
                          drawn=_drawn_share(data, kind))
    for note in (duplicates_note(args, data, kind), count_note(args, data, result, kind),
                 scene_note(data, kind, Path(args.mesh).name)):
        if note:
            print(f"note: {note}", file=sys.stderr)


def _writing_bar(args, data, outputs):
    """A bar naming the files being written, its elapsed time going on (a picture and a
    page of millions of faces take seconds), where the run showed progress (``--progress``,
    or 500,000 elements or more on a terminal without ``-q``; not with ``--no-progress``)."""
    from .._runtime.progress import waiting_bar

    names = [Path(str(outputs[k])).name for k in ("labels", "colored", "picture", "html",
                                                   "graph") if outputs[k] not in (None, "-")]
    size = data.n_faces if hasattr(data, "faces") else data.n_total
    show = args.progress if args.progress is not None else shows_stages(args, size)
    return waiting_bar(f"writing {', '.join(names)}", bool(show and names))


def _labels_what(args, kind: str, data=None) -> str:
    """What ``-o`` holds, said in the summary: labels, or the input's records with them (a
    new file's: with the values of the input ``data`` kept, named)."""
    from ..io.records import kept_fields, scan_output

    kept = []
    if data is not None and scan_output(args.output, args.mesh) == "new":
        kept = kept_fields(args.output, data)
    return records_said(args.output, args.mesh, "vertices" if kind == "vertices" else "points",
                        fields_said(kept), getattr(args, "levels", None) or ()) or "labels"


def _drawn_share(data, kind: str) -> str:
    """``', 1,080,000 of 5,000,000 points drawn'`` where a picture draws a share of a
    cloud's points (:func:`superfacets.viz.render.drawn_share`), else ``''``."""
    if not kind_of(kind).cloud or kind == "vertices":
        return ""
    from ..viz.render import PICTURE_SIZE

    pixels, n = PICTURE_SIZE[0] * PICTURE_SIZE[1], int(data.n_points)
    return f", {pixels:,} of {n:,} points drawn" if n > pixels else ""


def _say_what_was_written(seg_out, ply_out, png_out, html_out, report, up,
                          graph_out=None, labels_what: str = "labels",
                          kind: str = "faces", drawn: str = "") -> None:
    axis = said_up(up) + drawn
    colored = "coloured cloud" if kind == "points" else "coloured mesh"
    graph = "superpoint graph" if kind_of(kind).segment_word == "superpoints" else \
        "superfacet graph"
    written = [f"{path} ({what})" for path, what in
               ((seg_out, labels_what), (ply_out, colored), (png_out, f"picture, {axis}"),
                (html_out, "page: open it in a browser"), (graph_out, graph))
               if path is not None and str(path) != "-"]
    if written:
        print("wrote " + ", ".join(written), file=report)
    elif seg_out is None:
        print("note: nothing was saved: add -o OUT.seg (or -o - for standard output), "
              "--colored-mesh OUT.ply, --picture OUT.png or --html OUT.html", file=sys.stderr)


def cmd_baseline(args) -> int:
    from .._runtime.progress import waiting_bar
    from ..errors import MemoryLimitError, ParameterError
    from ..evaluation.methods import Skipped, get_method
    from ..scale.runner.grid import method_grid, parse_params

    method = get_method(args.method)
    given = method_grid([method], parse_params(args.param))[method.name]
    many = [n for n, v in given.items() if len(v) != 1]
    if many:
        raise ParameterError(f"--param: give one value for {', '.join(many)}")
    params = method.resolve({n: v[0] for n, v in given.items()})
    seg_out = check_labels_output(args.output, args.mesh, records=True)
    ply_out = check_output(args.colored_mesh, (".ply", ".glb", ".obj"), "the coloured mesh",
                           inputs=(args.mesh,))
    drawings = check_drawings(args, (seg_out, ply_out))
    data = scan_cloud(read_usable(args.mesh, clouds=True), args)
    kind = _baseline_kind(args, data, method, ply_out)
    t0 = time.perf_counter()
    show = not args.quiet and sys.stderr.isatty()
    extra = {"progress": show} if method.progress else {}
    if method.elements != ("faces",):
        extra["elements"] = kind
    n = kind_of(kind).n_rows(data)
    size = f"{n:,} {kind if n != 1 else kind_of(kind).singular}"
    try:  # (a method without bars of its own: one line, its elapsed time going on)
        with waiting_bar(f"{Path(args.mesh).name}: {size}, running {method.name}",
                         show and not method.progress):
            run = method.run(data, args.n_segments, cache={}, seed=args.seed, **params,
                             **extra)
    except Skipped as exc:
        raise MemoryLimitError(f"{args.mesh}: {exc}") from None
    except ParameterError as exc:
        raise ParameterError(f"{args.mesh}: {exc}") from None
    elapsed = time.perf_counter() - t0
    labels = np.asarray(run.labels)
    from ..io.orientation import default_view

    up = up_of(args, data)
    _write_baseline(args, data, kind, labels, (seg_out, ply_out, *drawings),
                    dict(up=up[0], view=args.view if args.view is not None else
                         default_view(data), title=f"{Path(args.mesh).name}: "
                         f"{counted(int(np.unique(labels[labels >= 0]).size), 'segment')} "
                         f"({method.name})"))
    if not args.quiet:
        shown = ", ".join(f"{k}={fmt_value(v)}" for k, v in params.items())
        iters = "" if run.n_iter is None else (
            f", {run.n_iter} iterations" + ("" if run.converged is None else
                                            " (converged)" if run.converged else " (max)"))
        n_segs = int(np.unique(labels[labels >= 0]).size)
        report = sys.stderr if str(seg_out) == "-" else sys.stdout
        print(f"{Path(args.mesh).name}: {size}, {method.name} ({shown}): "
              f"{counted(n_segs, 'segment')}{iters}, {elapsed:.2f} s", file=report)
        written = [f"{p} ({what})" for p, what in (
            (seg_out, _labels_what(args, kind, data)), (ply_out, f"coloured {kind}"),
            (drawings[0], f"picture, {said_up(up)}{_drawn_share(data, kind)}"),
            (drawings[1], "page: open it in a browser"))
            if p is not None and str(p) != "-"]  # (as segment says what it wrote)
        if written:
            print("wrote " + ", ".join(written), file=report)
    return 0


def check_method_elements(method, kind: str) -> dict:
    """The keywords that run a registered ``method`` on elements of ``kind`` (``elements=``
    where it takes more than faces); a ParameterError naming the methods that do, where it
    does not."""
    from ..errors import ParameterError
    from ..evaluation.methods import METHODS

    if kind not in method.elements:
        able = ", ".join(n for n, m in METHODS.items() if kind in m.elements)
        raise ParameterError(f"{method.name} segments {' and '.join(method.elements)}, not "
                             f"{kind}; " + (f"methods that segment {kind}: {able}" if able else
                                            f"'superfacets segment' segments {kind} (its "
                                            "labels drawn with --labels)"))
    return {"elements": kind} if method.takes_elements else {}


def _baseline_kind(args, data, method, ply_out) -> str:
    """The elements a baseline segments: a cloud's points, a mesh's faces (or
    ``--elements vertices``); refused in one line where the method does not segment them."""
    from ..errors import ParameterError

    if hasattr(data, "tets"):
        raise ParameterError(f"{args.mesh}: the baselines segment surfaces and point clouds, "
                             "not tetrahedra; 'superfacets segment' segments a tetrahedral "
                             "mesh")
    kind = "points" if not hasattr(data, "faces") else (args.elements or "faces")
    if kind == "points" and args.elements not in (None, "points"):
        raise ParameterError(f"{args.mesh} is a point cloud: its elements are points, not "
                             f"{args.elements}")
    check_method_elements(method, kind)
    if kind == "faces" and _into_records(args.output, args.mesh):
        raise ParameterError(f"{args.output}: a PLY's records are its vertices: -o OUT.ply "
                             "takes the labels of --elements vertices")
    if kind != "faces" and ply_out is not None and not ply_out.name.lower().endswith(".ply"):
        raise ParameterError(f"{ply_out}: coloured {kind} are written as .ply")
    return kind


def _write_baseline(args, data, kind, labels, outs: tuple, camera: dict) -> None:
    """A baseline's files, all or nothing: labels (a label file, or the input's records),
    a coloured mesh or cloud, a picture and a page (``outs``: their paths or None;
    ``camera``: ``up``, ``view`` and ``title`` of the last two)."""
    from ..elements.builders import elements_of
    from ..io import write_colored_mesh, write_labels
    from ..io.export import write_colored_elements
    from ..io.files import Outputs
    from ..io.records import write_scan_labels

    seg_out, ply_out, png_out, html_out = outs
    with Outputs() as outputs:  # all or nothing
        if seg_out is not None and _into_records(args.output, args.mesh):
            write_scan_labels(seg_out, args.mesh, labels, outputs=outputs,
                              cloud=data if kind == "points" else None)
        elif seg_out is not None:
            write_labels(seg_out, labels, outputs=outputs)
        if ply_out is not None and kind == "faces":
            write_colored_mesh(ply_out, data, labels, outputs=outputs)
        elif ply_out is not None:
            write_colored_elements(ply_out, elements_of(data, kind), labels, outputs=outputs)
        _draw_baseline(data, kind, labels, (png_out, html_out), camera, outputs)


def _draw_baseline(data, kind: str, labels, outs: tuple, camera: dict, outputs) -> None:
    """A baseline's picture and page (``outs``), as segment draws a run's."""
    png_out, html_out = outs
    drawn = {} if kind_of(kind).cloud else {"elements": kind}  # faces or vertices
    if html_out is not None:
        from ..viz.html import write_html

        write_html(html_out, data, labels, outputs=outputs, **camera, **drawn)
    if png_out is not None:
        from ..viz.render import render, render_points

        draw = render_points if kind_of(kind).cloud else render
        draw(data, labels, png_out, outputs=outputs, legend=True, **camera, **drawn)


def cmd_demo(args) -> int:
    from ..api.segmentation import segment
    from ..inputs.shapes import creature
    from ..io import write_colored_mesh, write_labels, write_mesh
    from ..io.files import Outputs
    from ..method.params import check_int, resolve
    from ..viz.html import write_html
    from ..viz.outputs import result_header

    check_int("--resolution", args.resolution, lo=16, hi=300)
    resolve(n_segments=args.n_segments, **method_kwargs(args))  # every option, before work
    out = Path(args.output_dir)
    if out.exists() and not out.is_dir():
        raise NotADirectoryError(f"{out}: exists and is not a folder")
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    mesh = creature(args.resolution)
    t_shape = time.perf_counter() - t0
    t0 = time.perf_counter()
    result = segment(mesh, args.n_segments, **method_kwargs(args))
    elapsed = time.perf_counter() - t0
    picture = ""
    with Outputs() as outputs:  # all or nothing (the picture is a bonus)
        write_mesh(out / "creature.off", mesh, outputs=outputs)
        write_labels(out / "creature.seg", result.labels, outputs=outputs,
                     header=result_header(mesh, result, "creature.off"))
        write_colored_mesh(out / "creature_superfacets.ply", mesh, result.labels,
                           outputs=outputs)
        write_html(out / "creature.html", mesh, result.labels, title="creature (demo)",
                   up="z", info={"k asked": args.n_segments, "alpha": result.params["alpha"]},
                   outputs=outputs)
        try:
            from ..viz.render import render

            render(mesh, result.labels, out / "creature.png", size=(1000, 750), up="z",
                   title=f"{result.n_segments} superfacets, alpha = {result.params['alpha']:g}",
                   outputs=outputs, legend=True)
            picture = f", {out / 'creature.png'} (picture)"
        except Exception as exc:  # noqa: BLE001 - the picture is a bonus; say why it is missing
            print(f"note: no picture rendered ({type(exc).__name__}: {exc})", file=sys.stderr)
    if not args.quiet:
        print(f"built the demo mesh in {t_shape:.2f} s")
        print(_summary("creature", mesh, result, elapsed))
        print(f"wrote {out / 'creature.off'} (mesh), {out / 'creature.seg'} (labels), "
              f"{out / 'creature_superfacets.ply'} (open in MeshLab or Blender), "
              f"{out / 'creature.html'} (open in a browser){picture}")
    return 0
