"""Commands that make pictures: render (PNG), panel (side by side), view (window), html."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from .._runtime.progress import waiting_bar
from ..elements.kinds import kind_of
from ..io.orientation import default_view
from .options import (
    add_camera_options,
    add_mesh_and_labels,
    add_method_options,
    add_scan_options,
    check_output,
    fmt_value,
    int_arg,
    labels_for,
    read_usable,
    said_up,
    scan_cloud,
    shows_stages,
    up_of,
)
from .parameters import Joined, float_list_arg, int_list_arg

__all__ = ["add_parsers"]


def _read(args, clouds: bool = False):
    """The command's mesh (or, with ``clouds``, any input: a mesh, a point cloud or a
    tetrahedral mesh), read under a line naming it where reading takes long; a cloud to be
    segmented here with ``--viewpoint`` / ``--seen-from`` applied (:func:`scan_cloud`)."""
    with waiting_bar(f"reading {Path(args.mesh).name}", shows_stages(args, path=args.mesh)):
        data = read_usable(args.mesh, clouds=clouds)
    given = any(getattr(args, f, None) for f in ("labels", "labels_from", "plain"))
    return scan_cloud(data, args) if clouds and not given else data


def _drawn(data, labels, elements: str):
    """What a picture or page draws of an input: a tetrahedral mesh as the surface of its
    tetrahedra cut at the middle of x (each triangle its tetrahedron's label), else the
    input itself; with the labels and what they label."""
    from ..inputs.tetmesh import as_drawn

    data, labels, cut = as_drawn(data, labels)
    return data, labels, "faces" if cut else elements


def drawn_said(n_points: int, size) -> str:
    """``' (1,080,000 of them drawn)'`` where a picture of ``size`` pixels draws a share of
    a cloud's ``n_points`` valid points (:func:`superfacets.viz.render.drawn_share`), else
    ``''``."""
    pixels = int(size[0]) * int(size[1])
    return f" ({pixels:,} of them drawn)" if n_points > pixels else ""


def _size_said(data, elements: str) -> str:
    """``'69,451 faces'``, ``'3,000 points'``, ... for the summary line."""
    kind = kind_of(elements)
    return kind.counted(kind.n_rows(data))


def add_parsers(sub) -> None:
    """Add ``render``, ``panel``, ``view`` and ``html`` to the sub-parsers."""
    seg_note = ("Without LABELS (or --labels-from FIELD) the input is segmented first with "
                "the method options below (default k = 150, alpha = 200); with --plain it "
                "is drawn grey.")
    r = sub.add_parser(
        "render", help="render a segmented mesh or point cloud to a PNG, off-screen",
        description="Render a mesh, a point cloud or a tetrahedral mesh (cut at the middle "
                    "of x) off-screen (no display or GPU needed) to a PNG: flat shaded, faces "
                    "or points coloured by superfacet or superpoint (adjacent ones in clearly "
                    "different colours), boundaries as dark lines; an airborne tile drawn "
                    "from above, north up, a sensor's frame from its sensor. " + seg_note)
    add_mesh_and_labels(r)
    r.add_argument("-o", "--output", metavar="OUT.png", required=True, help="PNG to write")
    r.add_argument("--title", default=None, help="text at the top (default: none)")
    r.add_argument("--no-legend", action="store_true",
                   help="do not draw the segments' count and sizes (min, median, max and a "
                        "histogram) in the lower left corner")
    add_camera_options(r, "1200x900")
    add_method_options(r)
    add_scan_options(r)
    r.set_defaults(func=cmd_render)

    pn = sub.add_parser(
        "panel", help="render several settings side by side (the paper's Figs. 2, 3, 8)",
        description="Render one mesh, point cloud or tetrahedral mesh (cut at the middle of "
                    "x) at several settings side by side, with titles: every "
                    "combination of the given methods, -k values and --alpha values "
                    "(e.g. --alpha 0 200 1000 -k 150 is the paper's Fig. 2), or the given "
                    "label files (--labels).")
    pn.add_argument("mesh", metavar="INPUT", help="input mesh, point-cloud or volume file")
    add_scan_options(pn)  # (a scan's up and its normals' side, as segment reads them)
    pn.add_argument("-o", "--output", metavar="OUT.png", required=True, help="PNG to write")
    pn.add_argument("-m", "--method", nargs="+", default=["superfacets"], metavar="NAME",
                    help="registered methods (default: superfacets)")
    pn.add_argument("-k", "--n-segments", type=int_list_arg, nargs="+", action=Joined,
                    default=[150], metavar="K",
                    help="numbers of superfacets (default: 150)")
    pn.add_argument("--alpha", type=float_list_arg, nargs="+", action=Joined,
                    default=None, metavar="A",
                    help="alpha values (default: each method's default)")
    pn.add_argument("--param", action="append", default=[], metavar="NAME=V1,V2",
                    help="values of a method parameter, for each method that has it "
                         "(METHOD.NAME=... for one method), repeatable "
                         "(e.g. --param vsa.metric=l21,l2 --param vsa.init=random,incremental)")
    pn.add_argument("--labels", nargs="+", default=None, metavar="LABELS.seg",
                    help="draw these label files instead of computing")
    pn.add_argument("--labels-from", nargs="+", default=None, metavar="FIELD",
                    help="draw these fields of the input instead of computing, a panel each "
                         "(a scan's labels and levels: --labels-from ClusterID ClusterID_50)")
    pn.add_argument("--titles", nargs="+", default=None, metavar="TEXT",
                    help="panel titles (default: the settings or file names)")
    pn.add_argument("--columns", type=int_arg, default=None, metavar="N",
                    help="panels per row (default: up to 4)")
    add_camera_options(pn, "600x500")
    pn.set_defaults(func=cmd_panel)

    v = sub.add_parser(
        "view", help="open an interactive 3D window",
        description="Open a window to rotate (drag) and zoom (wheel) the coloured result "
                    "(PyVista). Needs a display; without one, use 'render' or 'html'. "
                    + seg_note)
    add_mesh_and_labels(v)
    add_camera_options(v, "")
    add_method_options(v)
    v.set_defaults(func=cmd_view)

    h = sub.add_parser(
        "html", help="write a self-contained interactive web page",
        description="Write one HTML file (no network needed to open it) showing the coloured "
                    "mesh, point cloud or tetrahedral mesh (cut at the middle of x) "
                    "interactively in a browser (WebGL), with its name, element count, "
                    "segment count and parameters. " + seg_note)
    add_mesh_and_labels(h)
    h.add_argument("-o", "--output", metavar="OUT.html", required=True, help="page to write")
    h.add_argument("--title", default=None, help="page title (default: the file name)")
    h.add_argument("--background", default="#ffffff", metavar="COLOR",
                   help="page background, a CSS colour (default: #ffffff)")
    add_camera_options(h, "")
    add_method_options(h)
    add_scan_options(h)
    h.set_defaults(func=cmd_html)


def cmd_render(args) -> int:
    from ..checks import check_number
    from ..viz.render import render, render_points

    check_number("line_width", args.line_width, 0.0, 100.0, lo_open=True)  # (a cloud's
    # picture draws no border lines, but a bad width is refused on every input alike)
    if args.no_boundaries and args.line_width != 1.0:
        from ..errors import ParameterError

        raise ParameterError("--line-width is the boundaries' width; not with --no-boundaries")
    out = check_output(args.output, (".png",), "the picture",
                       inputs=(args.mesh, getattr(args, "labels", None)))
    data = _read(args, clouds=True)
    labels, _, elements = labels_for(args, data)
    said = _size_said(data, elements)
    t0 = time.perf_counter()
    up = up_of(args, data)
    view = args.view if args.view is not None else default_view(data)
    data, labels, elements = _drawn(data, labels, elements)
    style = dict(size=args.size, view=view, up=up[0], background=args.background,
                 title=args.title, zoom=args.zoom, legend=not args.no_legend)
    with waiting_bar(f"rendering {out.name}", shows_stages(args, len(labels) if labels
                                                           is not None else 0)):
        if elements == "points":
            render_points(data, labels, out, class_names=_named_classes(args), **style)
            said += drawn_said(data.n_points, args.size)
        else:
            render(data, labels, out, boundaries=not args.no_boundaries,
                   line_width=args.line_width, elements=elements, **style)
    if not args.quiet:
        print(f"wrote {out} ({args.size[0]}x{args.size[1]}, {said}, {said_up(up)}, "
              f"rendered in {time.perf_counter() - t0:.2f} s)")
    return 0


def _named_classes(args) -> dict | None:
    """The class names of ``--labels-from FIELD`` where the format names them (a LAS file's
    ``classification``: the ASPRS classes), for the picture's legend; else None."""
    from ..io.labels import class_names

    field = getattr(args, "labels_from", None)
    return (class_names(args.mesh, field) or None) if field else None


def _field_labels(path, field: str, n: int, kind: str):
    """The labels a field of the input holds (``ClusterID``), one per element, or one line
    saying how many it has against how many are needed."""
    from ..errors import MeshFormatError
    from ..io.labels import read_field

    labels = read_field(path, field)
    if labels.shape[0] != n:
        raise MeshFormatError(f"{path}: field {field} has {labels.shape[0]:,} values, but the "
                              f"input has {kind_of(kind).counted(n)}")
    return labels


def cmd_panel(args) -> int:
    from itertools import product as _product

    from ..elements.builders import kind_for
    from ..errors import ParameterError
    from ..evaluation.methods import get_method
    from ..io import read_labels
    from ..scale.runner.grid import expand_grid, method_grid, parse_params
    from ..viz.render import render_panel
    from .segmenting import check_method_elements

    out = check_output(args.output, (".png",), "the picture",
                       inputs=(args.mesh, getattr(args, "labels", None)))
    given = [f for f, on in (("-m", args.method != ["superfacets"]),
                             ("-k", args.n_segments != [150]), ("--alpha", bool(args.alpha)),
                             ("--param", bool(args.param))) if on]
    drawn = args.labels or args.labels_from
    if drawn and given:  # (the label files and fields are drawn as they are)
        raise ParameterError(f"{', '.join(given)} choose{'s' if len(given) == 1 else ''} the "
                             "runs a panel segments; with --labels or --labels-from nothing "
                             "is segmented: leave them out")
    mesh = _read(args, clouds=True)
    kind = kind_for(mesh)  # (faces, points or cells: what the labels are of)
    items = []
    if drawn:
        n = kind_of(kind).n_rows(mesh)
        for p in args.labels or ():
            items.append((mesh, read_labels(p, n_faces=n), Path(p).stem))
        for field in args.labels_from or ():
            items.append((mesh, _field_labels(args.mesh, field, n, kind), field))
    else:
        methods = [get_method(m) for m in args.method]
        given = method_grid(methods, parse_params(args.param))
        extra = {m.name: check_method_elements(m, kind) for m in methods}
        for method in methods:
            grid = dict(given[method.name])
            if args.alpha and "alpha" in method.defaults:
                grid["alpha"] = args.alpha
            for cfg, k in _product(expand_grid(method.name, **grid), args.n_segments):
                params = cfg.kwargs
                try:
                    run = method.run(mesh, k, cache={}, seed=0, **params,
                                     **extra[method.name])
                except (ValueError, RuntimeError) as exc:
                    raise ParameterError(f"{args.mesh}: {method.name}: {exc}") from None
                n = len(np.unique(run.labels))
                shown = [f"{p} = {fmt_value(params[p])}" for p in params if p in grid
                         or (p == "alpha" and len(methods) == 1 and not args.alpha)]
                title = ", ".join(([method.name] if len(methods) > 1 else []) + shown
                                  + [f"k = {k} ({n})"])
                items.append((mesh, run.labels, title))
    if args.titles:
        if len(args.titles) != len(items):
            raise ParameterError(f"--titles: {len(args.titles)} given for {len(items)} panels")
        items = [(m, lab, t) for (m, lab, _), t in zip(items, args.titles)]
    items = [(*_drawn(m, lab, kind)[:2], t) for m, lab, t in items]  # (a volume: its cut)
    up = up_of(args, mesh)
    view = args.view if args.view is not None else default_view(mesh)  # (a tile: a map)
    render_panel(items, out, ncols=args.columns, size=args.size, view=view, up=up[0],
                 background=args.background, boundaries=not args.no_boundaries,
                 line_width=args.line_width, zoom=args.zoom)
    print(f"wrote {out}: {len(items)} panel{'s' if len(items) != 1 else ''}, {said_up(up)}")
    return 0


def cmd_view(args) -> int:
    from ..viz.render import VIEW_POINTS, has_display, no_display, show

    if not has_display():  # say so before the (maybe long) segmentation
        raise no_display()
    data = _read(args, clouds=True)
    labels, _, elements = labels_for(args, data)
    up = up_of(args, data)[0]
    view = args.view if args.view is not None else default_view(data)  # (a tile: a map)
    if elements == "vertices":
        from ..viz.render import faces_to_draw

        data, labels = faces_to_draw(data, labels, elements)
    data, labels, _ = _drawn(data, labels, elements)  # (a volume: its cut)
    n = data.n_points if elements == "points" else 0
    if n > VIEW_POINTS and not getattr(args, "quiet", False):
        print(f"drawing {VIEW_POINTS:,} of {n:,} points (an even share; a window of all "
              "would not turn)", file=sys.stderr)
    show(data, labels, title=Path(args.mesh).name, view=view, up=up, max_points=VIEW_POINTS)
    return 0  # pragma: no cover


def cmd_html(args) -> int:
    from ..viz.html import MAX_PAGE_POINTS, write_html

    out = check_output(args.output, (".html", ".htm"), "the page",
                       inputs=(args.mesh, args.labels))
    data = _read(args, clouds=True)
    labels, info, elements = labels_for(args, data)
    view = args.view if args.view is not None else default_view(data)
    up = up_of(args, data)[0]
    data, labels, elements = _drawn(data, labels, elements)
    drawn = {} if elements == "points" else {"elements": elements}
    with waiting_bar(f"writing {out.name}", shows_stages(args, len(labels) if labels
                                                         is not None else 0)):
        write_html(out, data, labels, title=args.title or Path(args.mesh).name, info=info,
                   background=args.background, view=view, up=up, **drawn,
                   class_names=_named_classes(args) if elements == "points" else None)
    if not args.quiet:
        n = data.n_points if elements == "points" else 0
        share = (f"; {MAX_PAGE_POINTS:,} of {n:,} points drawn: a page of all would not open"
                 if n > MAX_PAGE_POINTS else "")
        print(f"wrote {out} ({out.stat().st_size / 1e6:.1f} MB{share}): open it in a browser")
    return 0
