"""The ``superfacets`` command line.

Sub-commands:

- ``superfacets segment MESH ...``: superfacets of a mesh file, written as a
  ``.seg`` label file and/or a coloured PLY;
- ``superfacets evaluate MESH LABELS.seg GT.seg...``: the metrics of a result;
- ``superfacets experiment``: a grid of methods x parameters over the
  Princeton benchmark, appended to a results CSV (resumable);
- ``superfacets report RESULTS``: figures (PNG, SVG) and Markdown tables;
- ``superfacets render MESH [LABELS.seg] -o OUT.png``: a picture, off-screen;
- ``superfacets panel MESH -o OUT.png``: several settings side by side (Fig. 2);
- ``superfacets view MESH [LABELS.seg]``: an interactive window;
- ``superfacets html MESH [LABELS.seg] -o OUT.html``: a self-contained web page;
- ``superfacets demo``: the same on a built-in procedural mesh, no data needed.

Bad input (missing, unreadable or malformed files, invalid parameters) ends
with one line ``superfacets: error: ...`` on stderr and exit status 2; no
output file is written unless the whole run succeeded.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

__all__ = ["main"]


def _int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    return v


def _float(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


def _add_method_options(p: argparse.ArgumentParser, with_size: bool = True) -> None:
    if with_size:
        size = p.add_mutually_exclusive_group()
        size.add_argument("-k", "--n-segments", type=_int, default=None, metavar="N",
                          help="number of superfacets k (default: 150 unless --radius is given)")
        size.add_argument("--radius", type=_float, default=None, metavar="R",
                          help="superfacet radius as a fraction of the bounding-box diagonal "
                               "(instead of -k; default init then 'flood')")
    p.add_argument("--alpha", type=_float, default=200.0, metavar="A",
                   help="weight of the concavity (angular) term, >= 0; 0 = most compact, "
                        "larger = follows concavities more (default: 200)")
    p.add_argument("--eta-convex", type=_float, default=0.2, metavar="E",
                   help="factor of the angular term on convex edges (concave: 1) (default: 0.2)")
    p.add_argument("--init", choices=("farthest", "flood", "grid"), default=None,
                   help="initialization (default: farthest with -k, flood with --radius)")
    p.add_argument("--window", type=_float, default=2.0, metavar="W",
                   help="expansion window, a multiple of the radius (default: 2)")
    p.add_argument("--max-iter", type=_int, default=50, metavar="N",
                   help="maximum number of iterations (default: 50)")
    p.add_argument("--weighting", choices=("paper", "shlafman"), default="paper",
                   help="edge weights: the paper's eqs. 1-3 or Shlafman's eq. 6 "
                        "(then --alpha in [0, 1]) (default: paper)")
    p.add_argument("--assignment", choices=("bounded", "exact"), default="bounded",
                   help="bounded: the paper's window-bounded expansion per center; "
                        "exact: nearest center by one multi-source Dijkstra (default: bounded)")
    p.add_argument("--no-connectivity", action="store_true",
                   help="keep superfacets split in several pieces (default: merge stray "
                        "pieces into the neighbour sharing the longest boundary)")
    p.add_argument("--threads", type=_int, default=None, metavar="N",
                   help="threads expanding centers at once (default: all cores; the labels "
                        "do not depend on it)")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar of the stages and iterations on stderr (default: on for "
                        "meshes of 500,000 faces or more when stderr is a terminal)")


def _build_parser() -> argparse.ArgumentParser:
    from . import __version__

    parser = argparse.ArgumentParser(
        prog="superfacets",
        description="Over-segment triangle meshes into superfacets (Simari, Picciau, "
                    "De Floriani, 'Fast and Scalable Mesh Superfacets', 2014).")
    parser.add_argument("--version", action="version", version=f"superfacets {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    p = sub.add_parser(
        "segment", help="compute the superfacets of a mesh file",
        description="Compute the superfacets of a mesh file (.off, .tri, .ply, .obj, .stl, "
                    "optionally .gz/.xz/.bz2) and write them as a .seg label file "
                    "(one label per face per line) and/or a coloured PLY.")
    p.add_argument("mesh", metavar="MESH", help="input mesh file")
    _add_method_options(p)
    p.add_argument("-o", "--output", metavar="OUT.seg", default=None,
                   help="write the labels here (one per face per line; default: none)")
    p.add_argument("--header", action="store_true",
                   help="start the .seg file with '#' lines recording parameters, "
                        "iterations and time (default: labels only, as the benchmark's files)")
    p.add_argument("--colored-mesh", metavar="OUT.ply", default=None,
                   help="write the mesh as a binary PLY with one colour per superfacet")

    bl = sub.add_parser(
        "baseline", help="segment a mesh file with a baseline (normalized cuts, VSA, ...)",
        description="Segment a mesh file with any method of the registry (see 'superfacets "
                    "experiment --list-methods'): the baselines of the paper's comparisons, "
                    "normalized cuts ('ncuts', O(m^2) memory: meshes over its memory limit "
                    "are refused before anything is allocated) and Variational Shape "
                    "Approximation ('vsa'), or 'shlafman'. Writes a .seg label file and/or a "
                    "coloured PLY, like 'segment'.")
    bl.add_argument("mesh", metavar="MESH", help="input mesh file")
    bl.add_argument("-m", "--method", required=True, metavar="NAME",
                    help="registered method: ncuts, vsa, shlafman, superfacets")
    bl.add_argument("-k", "--n-segments", type=_int, default=150, metavar="N",
                    help="number of segments (default: 150)")
    bl.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                    help="a method parameter, repeatable (e.g. metric=l2 init=incremental for "
                         "vsa; alpha=100 memory_limit_gib=8 for ncuts)")
    bl.add_argument("--seed", type=_int, default=0, help="seed of randomized methods (default 0)")
    bl.add_argument("-o", "--output", metavar="OUT.seg", default=None,
                    help="write the labels here (one per face per line)")
    bl.add_argument("--colored-mesh", metavar="OUT.ply", default=None,
                    help="write the mesh as a binary PLY with one colour per segment")
    bl.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")

    d = sub.add_parser(
        "demo", help="segment a built-in procedural mesh (no data needed)",
        description="Build a procedural four-legged creature (about 21,000 faces), compute "
                    "its superfacets and write the mesh, the labels and a coloured PLY.")
    d.add_argument("--output-dir", default="demo-output", metavar="DIR",
                   help="folder for the outputs, created if needed (default: demo-output)")
    d.add_argument("--resolution", type=_int, default=100, metavar="N",
                   help="marching-cubes grid resolution of the shape (default: 100)")
    d.add_argument("-k", "--n-segments", type=_int, default=150, metavar="N",
                   help="number of superfacets (default: 150)")
    _add_method_options(d, with_size=False)
    e = sub.add_parser(
        "evaluate", help="metrics of a segmentation against ground truths",
        description="Print the undersegmentation error (eq. 4), compactness (eq. 5), boundary "
                    "recall and achievable segmentation accuracy of a label file, each averaged "
                    "over the given ground-truth segmentations (area-weighted).")
    e.add_argument("mesh", metavar="MESH", help="the mesh file")
    e.add_argument("labels", metavar="LABELS.seg", help="superfacet labels, one per face")
    e.add_argument("ground_truths", metavar="GT.seg", nargs="+",
                   help="one or more ground-truth segmentations of the same mesh")
    e.add_argument("--tau", type=_float, default=0.05,
                   help="overlap tolerance of the undersegmentation error, a fraction of each "
                        "superfacet's area (default: 0.05)")
    x = sub.add_parser(
        "experiment", help="run methods x parameters over the Princeton benchmark",
        description="Run a grid of methods and parameters over the meshes of the Princeton "
                    "Mesh Segmentation Benchmark, in parallel worker processes, appending one "
                    "row per (mesh, method, parameters, k) with every metric to a CSV file. "
                    "Rerunning with the same file continues where it stopped; a failure on "
                    "one mesh is recorded and the run goes on. The defaults reproduce the "
                    "paper's sweep (k in 50..300, alpha in 0, 100, 200, 500, 1000).")
    x.add_argument("--psb", metavar="DIR", default=None,
                   help="unpacked benchmark folder holding off/ and seg/ (default: unpacked "
                        "once from ../shared/data/psb.tar.xz into ~/.cache/superfacets)")
    x.add_argument("-o", "--results", metavar="FILE.csv", default="results.csv",
                   help="results file, appended to (default: results.csv)")
    x.add_argument("-m", "--method", action="append", default=None, metavar="NAME",
                   help="method from the registry, repeatable (default: superfacets; "
                        "see --list-methods)")
    x.add_argument("-k", "--n-segments", type=_int, nargs="+", default=None, metavar="K",
                   help="numbers of superfacets (default: 50 100 150 200 250 300)")
    x.add_argument("--alpha", type=_float, nargs="+", default=None, metavar="A",
                   help="alpha values (default: each method's sweep; superfacets: "
                        "0 100 200 500 1000)")
    x.add_argument("--param", action="append", default=[], metavar="NAME=V1,V2",
                   help="values of another method parameter, repeatable (e.g. init=grid,flood)")
    x.add_argument("--ids", default=None, metavar="LIST",
                   help="mesh ids, e.g. 1-20,45 (default: all)")
    x.add_argument("--categories", default=None, metavar="LIST",
                   help="comma-separated categories, e.g. Human,Cup (default: all)")
    x.add_argument("--per-category", type=_int, default=None, metavar="N",
                   help="only the first N meshes (by id) of each category: a stratified subset")
    x.add_argument("-j", "--workers", type=_int, default=None, metavar="N",
                   help="worker processes (default: all cores)")
    x.add_argument("--tau", type=_float, default=0.05,
                   help="undersegmentation error tolerance (default: 0.05)")
    x.add_argument("--seed", type=_int, default=0, help="seed given to randomized methods")
    x.add_argument("--retry-failed", action="store_true",
                   help="run again the rows recorded as failed")
    x.add_argument("--list-methods", action="store_true",
                   help="list the registered methods and their parameters, and exit")
    x.add_argument("-q", "--quiet", action="store_true", help="no progress bar")

    r = sub.add_parser(
        "report", help="figures and tables from a results file",
        description="Draw the paper's Fig. 4 layout (undersegmentation error and compactness "
                    "against k, one curve per setting, mean over categories), the same per "
                    "category, and Markdown tables, from a file of 'superfacets experiment'.")
    r.add_argument("results", metavar="RESULTS.csv", nargs="+",
                   help="results file(s); rows of several files are pooled")
    r.add_argument("--series", action="append", default=None, metavar="NAME",
                   help="keep only this series, as named in the legend (e.g. "
                        "'superfacets α=200'), repeatable")
    r.add_argument("-o", "--output-dir", default=None, metavar="DIR",
                   help="folder for the figures and summary.md (default: beside the results "
                        "file, named after it)")
    r.add_argument("--k-focus", type=_int, default=150, metavar="K",
                   help="k of the per-category and all-metrics tables (default: 150)")
    _add_picture_parsers(sub)
    return parser


def _size_arg(text: str) -> tuple[int, int]:
    w, sep, h = text.lower().partition("x")
    try:
        return int(w), int(h)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, e.g. 1200x900, got {text!r}") \
            from None


def _view_arg(text: str):
    if "," in text:
        try:
            return tuple(float(t) for t in text.split(","))
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a name or x,y,z, got {text!r}") from None
    return text


def _add_camera_options(p, size: str) -> None:
    p.add_argument("--view", type=_view_arg, default=None, metavar="V",
                   help="camera: auto (default: along the mesh's thinnest axis), front, back, "
                        "left, right, top, bottom, or a direction x,y,z from the mesh")
    p.add_argument("--up", default="y", choices=("x", "y", "z", "-x", "-y", "-z"),
                   help="the mesh's up axis (default: y, as the benchmark's meshes)")
    if size:
        p.add_argument("--size", type=_size_arg, default=_size_arg(size), metavar="WxH",
                       help=f"image size in pixels (default: {size})")
        p.add_argument("--background", default="white", metavar="COLOR",
                       help="background colour: a name or #rrggbb (default: white)")
        p.add_argument("--no-boundaries", action="store_true",
                       help="do not draw the superfacet boundaries as dark lines")
        p.add_argument("--line-width", type=_float, default=1.0, metavar="PX",
                       help="boundary line width in pixels (default: 1)")
        p.add_argument("--zoom", type=_float, default=1.0, metavar="Z",
                       help="camera zoom factor, > 1 magnifies (default: 1)")


def _add_mesh_and_labels(p, plain: bool = True) -> None:
    p.add_argument("mesh", metavar="MESH", help="input mesh file")
    p.add_argument("labels", metavar="LABELS.seg", nargs="?", default=None,
                   help="superfacet labels, one per face (default: computed)")
    if plain:
        p.add_argument("--plain", action="store_true", help="draw the mesh without superfacets")


def _add_picture_parsers(sub) -> None:
    seg_note = ("Without LABELS.seg the mesh is segmented first with the method options "
                "below (default k = 150, alpha = 200); with --plain it is drawn grey.")
    r = sub.add_parser(
        "render", help="render a segmented mesh to a PNG, off-screen",
        description="Render a mesh off-screen (no display or GPU needed) to a PNG: flat "
                    "shaded, faces coloured by superfacet (adjacent superfacets in clearly "
                    "different colours), boundaries as dark lines. " + seg_note)
    _add_mesh_and_labels(r)
    r.add_argument("-o", "--output", metavar="OUT.png", required=True, help="PNG to write")
    r.add_argument("--title", default=None, help="text at the top (default: none)")
    _add_camera_options(r, "1200x900")
    _add_method_options(r)

    pn = sub.add_parser(
        "panel", help="render several settings side by side (the paper's Figs. 2, 3, 8)",
        description="Render one mesh at several settings side by side, with titles: every "
                    "combination of the given methods, -k values and --alpha values "
                    "(e.g. --alpha 0 200 1000 -k 150 is the paper's Fig. 2), or the given "
                    "label files (--labels).")
    pn.add_argument("mesh", metavar="MESH", help="input mesh file")
    pn.add_argument("-o", "--output", metavar="OUT.png", required=True, help="PNG to write")
    pn.add_argument("-m", "--method", nargs="+", default=["superfacets"], metavar="NAME",
                    help="registered methods (default: superfacets)")
    pn.add_argument("-k", "--n-segments", type=_int, nargs="+", default=[150], metavar="K",
                    help="numbers of superfacets (default: 150)")
    pn.add_argument("--alpha", type=_float, nargs="+", default=None, metavar="A",
                    help="alpha values (default: each method's default)")
    pn.add_argument("--param", action="append", default=[], metavar="NAME=V1,V2",
                    help="values of another parameter, for the methods that have it "
                         "(METHOD.NAME=... for one method only), repeatable "
                         "(e.g. --param vsa.metric=l21,l2 --param vsa.init=random,incremental)")
    pn.add_argument("--labels", nargs="+", default=None, metavar="LABELS.seg",
                    help="draw these label files instead of computing")
    pn.add_argument("--titles", nargs="+", default=None, metavar="TEXT",
                    help="panel titles (default: the settings or file names)")
    pn.add_argument("--columns", type=_int, default=None, metavar="N",
                    help="panels per row (default: up to 4)")
    _add_camera_options(pn, "600x500")

    v = sub.add_parser(
        "view", help="open an interactive 3D window",
        description="Open a window to rotate (drag) and zoom (wheel) the coloured result "
                    "(PyVista). Needs a display; without one, use 'render' or 'html'. "
                    + seg_note)
    _add_mesh_and_labels(v)
    _add_camera_options(v, "")
    _add_method_options(v)

    h = sub.add_parser(
        "html", help="write a self-contained interactive web page",
        description="Write one HTML file (no network needed to open it) showing the coloured "
                    "mesh interactively in a browser (WebGL), with its name, face count, "
                    "superfacet count and parameters. " + seg_note)
    _add_mesh_and_labels(h)
    h.add_argument("-o", "--output", metavar="OUT.html", required=True, help="page to write")
    h.add_argument("--title", default=None, help="page title (default: the file name)")
    h.add_argument("--background", default="#ffffff", metavar="COLOR",
                   help="page background, a CSS colour (default: #ffffff)")
    _add_camera_options(h, "")
    _add_method_options(h)


def _labels_for(args, mesh):
    """Labels from LABELS.seg, computed with the method options, or None (--plain)."""
    from .errors import SuperfacetsError
    from .io import read_labels
    from .segment import segment

    if args.plain:
        return None, {}
    if args.labels:
        return read_labels(args.labels, n_faces=mesh.n_faces), {"labels": Path(args.labels).name}
    kw = _method_kwargs(args)
    kw["progress"] = False
    try:
        r = segment(mesh, args.n_segments, radius=args.radius, **kw)
    except SuperfacetsError as exc:
        raise type(exc)(f"{args.mesh}: {exc}") from None
    info = {"k asked": r.params.get("n_segments"), "alpha": args.alpha,
            "iterations": f"{r.n_iter} ({'converged' if r.converged else 'max-iter'})",
            "seconds": f"{r.timings['total']:.2f}"}
    return r.labels, info


def _cmd_render(args) -> int:
    from .io import read_mesh
    from .render import render

    out = _check_output(args.output, (".png",), "the picture")
    mesh = read_mesh(args.mesh)
    labels, _ = _labels_for(args, mesh)
    t0 = time.perf_counter()
    render(mesh, labels, out, size=args.size, view=args.view, up=args.up,
           background=args.background, boundaries=not args.no_boundaries,
           line_width=args.line_width, title=args.title, zoom=args.zoom)
    if not args.quiet:
        print(f"wrote {out} ({args.size[0]}x{args.size[1]}, {mesh.n_faces} faces, "
              f"rendered in {time.perf_counter() - t0:.2f} s)")
    return 0


def _cmd_panel(args) -> int:
    from itertools import product as _product

    from .errors import ParameterError
    from .experiment import expand_grid, get_method
    from .io import read_labels, read_mesh
    from .render import render_panel

    out = _check_output(args.output, (".png",), "the picture")
    mesh = read_mesh(args.mesh)
    items = []
    if args.labels:
        for p in args.labels:
            items.append((mesh, read_labels(p, n_faces=mesh.n_faces), Path(p).stem))
    else:
        methods = [get_method(m) for m in args.method]
        extra = _param_values(args.param)
        def applies(name: str, method) -> str | None:
            scope, dot, pname = name.rpartition(".")
            if dot and scope != method.name:
                return None
            return pname if pname in method.defaults else None

        unused = [n for n in extra if not any(applies(n, m) for m in methods)]
        if unused:
            raise ParameterError(f"--param: no method given has {', '.join(sorted(unused))}")
        for method in methods:
            grid = {applies(n, method): v for n, v in extra.items() if applies(n, method)}
            if args.alpha and "alpha" in method.defaults:
                grid["alpha"] = args.alpha
            for cfg, k in _product(expand_grid(method.name, **grid), args.n_segments):
                params = cfg.kwargs
                try:
                    run = method.run(mesh, k, cache={}, seed=0, **params)
                except (ValueError, RuntimeError) as exc:
                    raise ParameterError(f"{args.mesh}: {method.name}: {exc}") from None
                n = len(np.unique(run.labels))
                shown = [f"{p} = {_fmt_value(params[p])}" for p in params if p in grid
                         or (p == "alpha" and len(methods) == 1 and not args.alpha)]
                title = ", ".join(([method.name] if len(methods) > 1 else []) + shown
                                  + [f"k = {k} ({n})"])
                items.append((mesh, run.labels, title))
    if args.titles:
        if len(args.titles) != len(items):
            raise ParameterError(f"--titles: {len(args.titles)} given for {len(items)} panels")
        items = [(m, lab, t) for (m, lab, _), t in zip(items, args.titles)]
    render_panel(items, out, ncols=args.columns, size=args.size, view=args.view, up=args.up,
                 background=args.background, boundaries=not args.no_boundaries,
                 line_width=args.line_width, zoom=args.zoom)
    print(f"wrote {out}: {len(items)} panels")
    return 0


def _fmt_value(v) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


def _cmd_view(args) -> int:
    from .io import read_mesh
    from .render import NoDisplayError, _has_display, show

    if not _has_display():  # say so before the (maybe long) segmentation
        raise NoDisplayError("no display available ($DISPLAY is not set): use "
                             "'superfacets render' for a PNG or 'superfacets html' for a page "
                             "to open in a browser")
    mesh = read_mesh(args.mesh)
    labels, _ = _labels_for(args, mesh)
    show(mesh, labels, title=Path(args.mesh).name, view=args.view, up=args.up)  # pragma: no cover
    return 0  # pragma: no cover


def _cmd_html(args) -> int:
    from .html import write_html
    from .io import read_mesh

    out = _check_output(args.output, (".html", ".htm"), "the page")
    mesh = read_mesh(args.mesh)
    labels, info = _labels_for(args, mesh)
    write_html(out, mesh, labels, title=args.title or Path(args.mesh).name, info=info,
               background=args.background, view=args.view, up=args.up)
    if not args.quiet:
        print(f"wrote {out} ({out.stat().st_size / 1e6:.1f} MB): open it in a browser")
    return 0


def _id_list(text: str) -> set[int]:
    from .errors import ParameterError

    out: set[int] = set()
    for part in text.split(","):
        part = part.strip()
        try:
            if "-" in part:
                a, b = part.split("-", 1)
                out |= set(range(int(a), int(b) + 1))
            elif part:
                out.add(int(part))
        except ValueError:
            raise ParameterError(f"--ids: expected ids or ranges like 1-20,45, got {part!r}") \
                from None
    return out


def _select_meshes(args):
    from .datasets.psb import list_meshes, psb_root
    from .errors import ParameterError

    root = Path(args.psb) if args.psb else psb_root()
    meshes = list_meshes(root)
    if args.ids:
        ids = _id_list(args.ids)
        meshes = [m for m in meshes if m.id in ids]
    if args.categories:
        wanted = {c.strip().lower() for c in args.categories.split(",") if c.strip()}
        known = {m.category.lower() for m in meshes}
        unknown = wanted - known
        if unknown:
            raise ParameterError(f"--categories: unknown {', '.join(sorted(unknown))}; "
                                 f"present: {', '.join(sorted(known))}")
        meshes = [m for m in meshes if m.category.lower() in wanted]
    if args.per_category is not None:
        if args.per_category < 1:
            raise ParameterError(f"--per-category must be >= 1, got {args.per_category}")
        seen: dict[str, int] = {}
        kept = []
        for m in meshes:
            if seen.get(m.category, 0) < args.per_category:
                kept.append(m)
                seen[m.category] = seen.get(m.category, 0) + 1
        meshes = kept
    if not meshes:
        raise ParameterError(f"{root}: no mesh selected")
    return meshes


def _param_values(items) -> dict[str, list[str]]:
    """``NAME=V1,V2`` options as {name: [values]}."""
    from .errors import ParameterError

    extra: dict[str, list[str]] = {}
    for item in items:
        name, sep, vals = item.partition("=")
        if not sep or not name.strip() or not vals.strip():
            raise ParameterError(f"--param: expected NAME=V1,V2, got {item!r}")
        extra[name.strip()] = [v.strip() for v in vals.split(",") if v.strip()]
    return extra


def _cmd_experiment(args) -> int:
    from .experiment import DEFAULT_N_SEGMENTS, METHODS, expand_grid, get_method, run_experiment

    if args.list_methods:
        for name, m in sorted(METHODS.items()):
            params = ", ".join(f"{k}={v}" for k, v in m.defaults.items())
            print(f"{name}: {m.description}\n    parameters: {params}")
            for k, v in m.sweep.items():
                print(f"    default sweep: {k} in {', '.join(map(str, v))}")
        return 0
    extra = _param_values(args.param)
    configs = []
    for name in args.method or ["superfacets"]:
        method = get_method(name)
        grid = {k: list(v) for k, v in method.sweep.items()}
        if args.alpha is not None:
            grid["alpha"] = args.alpha
        grid.update(extra)
        configs += expand_grid(name, **grid)
    meshes = _select_meshes(args)
    ks = args.n_segments or list(DEFAULT_N_SEGMENTS)
    out = Path(args.results)
    if not args.quiet:
        print(f"{len(meshes)} meshes x {len(configs)} settings x {len(ks)} values of k "
              f"-> {out}", file=sys.stderr)
    s = run_experiment(meshes, configs, out, ks, workers=args.workers, tau=args.tau,
                       seed=args.seed, retry_failed=args.retry_failed, progress=not args.quiet)
    print(f"{s.written} rows written ({s.ok} ok, {s.failed} failed, {s.skipped} skipped), "
          f"{s.done_before} already there, in {s.seconds:.1f} s -> {out}")
    if s.interrupted:
        print("interrupted: run the same command again to continue", file=sys.stderr)
        return 130
    if not args.quiet:
        print(f"next: superfacets report {out}")
    return 0


def _cmd_report(args) -> int:
    from .report import write_report

    res = [Path(p) for p in args.results]
    out = Path(args.output_dir) if args.output_dir else res[0].with_name(res[0].stem + "_report")
    files = write_report(res, out, k_focus=args.k_focus, series=args.series)
    print((out / "summary.md").read_text())
    print(f"wrote {len(files)} files to {out}: " + ", ".join(f.name for f in files))
    return 0


def _cmd_evaluate(args) -> int:
    from .errors import ParameterError
    from .io import read_labels, read_mesh
    from .metrics import evaluate

    if not (0 <= args.tau < 1):
        raise ParameterError(f"--tau must be in [0, 1), got {args.tau}")
    mesh = read_mesh(args.mesh)
    labels = read_labels(args.labels, n_faces=mesh.n_faces)
    gts = [read_labels(p, n_faces=mesh.n_faces) for p in args.ground_truths]
    m = evaluate(mesh, labels, gts, tau=args.tau)
    print(f"{Path(args.mesh).name}: {mesh.n_faces} faces, {len(np.unique(labels))} superfacets, "
          f"{len(gts)} ground truths")
    print(f"undersegmentation_error {m['undersegmentation_error']:.4f}  (lower is better)")
    print(f"compactness             {m['compactness']:.4f}  (lower is better; disk 3.545)")
    print(f"boundary_recall         {m['boundary_recall']:.4f}  (higher is better)")
    print(f"achievable_accuracy     {m['achievable_accuracy']:.4f}  (higher is better)")
    return 0


def _method_kwargs(args) -> dict:
    return dict(alpha=args.alpha, eta_convex=args.eta_convex, window=args.window,
                init=args.init, max_iter=args.max_iter, weighting=args.weighting,
                assignment=args.assignment, enforce_connectivity=not args.no_connectivity,
                progress=bool(args.progress), n_threads=args.threads)


def _header(mesh, result, source: str) -> dict:
    p = result.params
    return {
        "superfacets": f"labels of {source}",
        "faces": mesh.n_faces,
        "superfacets_count": result.n_segments,
        "parameters": " ".join(f"{k}={v}" for k, v in p.items()),
        "iterations": f"{result.n_iter} ({'converged' if result.converged else 'max_iter reached'})",
        "seconds": f"{result.timings['total']:.3f}",
    }


def _summary(name: str, mesh, result, seconds: float) -> str:
    state = "converged" if result.converged else "stopped at max-iter"
    return (f"{name}: {mesh.n_faces} faces, {result.n_segments} superfacets, "
            f"{result.n_iter} iterations ({state}), {seconds:.2f} s")


def _check_output(path: str | None, suffixes: tuple[str, ...], what: str) -> Path | None:
    from .errors import ParameterError

    if path is None:
        return None
    out = Path(path)
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise FileNotFoundError(f"{out}: output folder {parent} does not exist")
    if out.is_dir():
        raise IsADirectoryError(f"{out}: is a directory")
    if suffixes and not any(out.name.lower().endswith(s) for s in suffixes):
        raise ParameterError(f"{out}: {what} must end in {' or '.join(suffixes)}")
    return out


def _cmd_segment(args) -> int:
    from .errors import SuperfacetsError
    from .io import read_mesh, write_colored_mesh, write_labels
    from .segment import segment

    seg_out = _check_output(args.output, (), "label file")
    ply_out = _check_output(args.colored_mesh, (".ply",), "the coloured mesh")
    t0 = time.perf_counter()
    mesh = read_mesh(args.mesh)
    kwargs = _method_kwargs(args)
    if args.progress is None:  # long runs show where they are
        kwargs["progress"] = mesh.n_faces >= 500_000 and sys.stderr.isatty()
    try:
        result = segment(mesh, args.n_segments, radius=args.radius, **kwargs)
    except SuperfacetsError as exc:
        raise type(exc)(f"{args.mesh}: {exc}") from None
    elapsed = time.perf_counter() - t0
    if seg_out is not None:
        write_labels(seg_out, result.labels,
                     header=_header(mesh, result, Path(args.mesh).name) if args.header else None)
    if ply_out is not None:
        write_colored_mesh(ply_out, mesh, result.labels)
    if not args.quiet:
        print(_summary(Path(args.mesh).name, mesh, result, elapsed))
    return 0


def _cmd_baseline(args) -> int:
    from .errors import MemoryLimitError, ParameterError
    from .experiment import Skipped, get_method
    from .io import read_mesh, write_colored_mesh, write_labels

    method = get_method(args.method)
    given = _param_values(args.param)
    many = [n for n, v in given.items() if len(v) != 1]
    if many:
        raise ParameterError(f"--param: give one value for {', '.join(many)}")
    params = method.resolve({n: v[0] for n, v in given.items()})
    seg_out = _check_output(args.output, (), "label file")
    ply_out = _check_output(args.colored_mesh, (".ply",), "the coloured mesh")
    mesh = read_mesh(args.mesh)
    t0 = time.perf_counter()
    try:
        run = method.run(mesh, args.n_segments, cache={}, seed=args.seed, **params)
    except Skipped as exc:
        raise MemoryLimitError(f"{args.mesh}: {exc}") from None
    except ParameterError as exc:
        raise ParameterError(f"{args.mesh}: {exc}") from None
    elapsed = time.perf_counter() - t0
    labels = np.asarray(run.labels)
    if seg_out is not None:
        write_labels(seg_out, labels)
    if ply_out is not None:
        write_colored_mesh(ply_out, mesh, labels)
    if not args.quiet:
        shown = ", ".join(f"{k}={_fmt_value(v)}" for k, v in params.items())
        iters = "" if run.n_iter is None else (
            f", {run.n_iter} iterations" + ("" if run.converged is None else
                                            " (converged)" if run.converged else " (max)"))
        print(f"{Path(args.mesh).name}: {mesh.n_faces} faces, {method.name} ({shown}): "
              f"{int(labels.max()) + 1} segments{iters}, {elapsed:.2f} s")
    return 0


def _cmd_demo(args) -> int:
    from .io import write_colored_mesh, write_labels, write_mesh
    from .segment import segment
    from .shapes import creature

    out = Path(args.output_dir)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    mesh = creature(args.resolution)
    t_shape = time.perf_counter() - t0
    t0 = time.perf_counter()
    result = segment(mesh, args.n_segments, **_method_kwargs(args))
    elapsed = time.perf_counter() - t0
    write_mesh(out / "creature.off", mesh)
    write_labels(out / "creature.seg", result.labels, header=_header(mesh, result, "creature.off"))
    write_colored_mesh(out / "creature_superfacets.ply", mesh, result.labels)
    from .html import write_html

    write_html(out / "creature.html", mesh, result.labels, title="creature (demo)", up="z",
               info={"k asked": args.n_segments, "alpha": args.alpha})
    picture = ""
    try:
        from .render import render

        render(mesh, result.labels, out / "creature.png", size=(1000, 750), up="z",
               title=f"{result.n_segments} superfacets, alpha = {args.alpha:g}")
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


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``superfacets`` console script.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0 on success, 2 on bad input, 130 when interrupted.
    """
    from .errors import SuperfacetsError
    from .render import NoDisplayError

    parser = _build_parser()
    args = parser.parse_args(argv)
    try:
        if args.command == "segment":
            return _cmd_segment(args)
        if args.command == "evaluate":
            return _cmd_evaluate(args)
        if args.command == "experiment":
            return _cmd_experiment(args)
        if args.command == "report":
            return _cmd_report(args)
        if args.command in ("render", "panel", "view", "html", "baseline"):
            return globals()[f"_cmd_{args.command}"](args)
        return _cmd_demo(args)
    except (SuperfacetsError, OSError, NoDisplayError) as exc:
        msg = str(exc)
        if isinstance(exc, OSError) and exc.filename and str(exc.filename) not in msg:
            msg = f"{exc.filename}: {exc.strerror or msg}"
        print(f"superfacets: error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("superfacets: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
