"""Options shared by several commands, and the helpers that read them.

Defaults and choices come from :mod:`superfacets.method.params`, so the help texts
and the API never disagree. Nothing here imports numba: building the parser
(``--help``, argument errors) stays light.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..method.params import (
    ASSIGNMENTS,
    COARSE_MIN_PER_SEGMENT,
    COARSE_MIN_PER_SEGMENT_POINTS,
    COARSE_PER_SEGMENT,
    DEFAULTS,
    ELEMENTS,
    INITS,
    WEIGHTINGS,
)
from ..method.params import DEFAULT_CENTER_TOL as _D_CENTER_TOL
from .inputs import check_header, named_after, read_usable  # noqa: F401 (re-exported)

__all__ = ["int_arg", "float_arg", "size_arg", "view_arg", "add_method_options",
           "add_camera_options", "add_mesh_and_labels", "method_kwargs", "check_output",
           "labels_for", "fmt_value", "add_scan_options", "scan_cloud", "scan_fields",
           "point_arg"]

_D = DEFAULTS


def int_arg(text: str) -> int:
    """argparse type: an integer."""
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None


def levels_arg(text: str) -> list[int]:
    """argparse type: ``--levels 50,20``, positive integers."""
    try:
        out = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        out = []
    if not out or min(out) < 1:
        raise argparse.ArgumentTypeError(f"expected positive integers N1,N2,..., got {text!r}")
    return out


def float_arg(text: str) -> float:
    """argparse type: a number."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


def auto_float_arg(text: str) -> float | None:
    """argparse type: a number, or ``auto`` (None: the method decides)."""
    return None if text.strip().lower() == "auto" else float_arg(text)


def size_arg(text: str) -> tuple[int, int]:
    """argparse type: ``WIDTHxHEIGHT``."""
    w, _, h = text.lower().partition("x")
    try:
        return int(w), int(h)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, e.g. 1200x900, got {text!r}") \
            from None


def view_arg(text: str):
    """argparse type: a view name or a direction ``x,y,z``."""
    if "," in text:
        try:
            return tuple(float(t) for t in text.split(","))
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a name or x,y,z, got {text!r}") from None
    return text


def point_arg(text: str) -> tuple:
    """argparse type: three numbers ``x,y,z``."""
    try:
        out = tuple(float(t) for t in text.split(","))
    except ValueError:
        out = ()
    if len(out) != 3:
        raise argparse.ArgumentTypeError(f"expected x,y,z (three numbers), got {text!r}")
    return out


#: ``--seen-from`` axis names and their directions.
AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0),
        "-x": (-1.0, 0.0, 0.0), "-y": (0.0, -1.0, 0.0), "-z": (0.0, 0.0, -1.0)}


def add_scan_options(p: argparse.ArgumentParser) -> None:
    """How the estimated normals of a point cloud are oriented (scans)."""
    p.add_argument("--viewpoint", type=point_arg, default=None, metavar="X,Y,Z",
                   help="point clouds: the sensor's position; estimated normals face it "
                        "(default: a PCD's VIEWPOINT, else none)")
    p.add_argument("--seen-from", choices=tuple(AXES), default=None, metavar="AXIS",
                   help="point clouds of open surfaces (terrain, streets) without a "
                        "viewpoint: the side they were scanned from (x, y, z, -x, -y, -z); "
                        "each piece's normals are turned to agree with it (default: z for "
                        ".las/.laz, else outwards from each piece's mean)")


def scan_fields(args) -> dict:
    """The cloud fields :func:`add_scan_options` set: ``viewpoint`` and ``up`` (tuples)."""
    out = {}
    if getattr(args, "viewpoint", None) is not None:
        out["viewpoint"] = tuple(args.viewpoint)
    if getattr(args, "seen_from", None) is not None:
        out["up"] = AXES[args.seen_from]
    return out


def scan_cloud(data, args):
    """``data`` with :func:`add_scan_options` applied (a point cloud; a mesh given either
    option is refused)."""
    from dataclasses import replace

    changes = scan_fields(args)
    if not changes:
        return data
    if hasattr(data, "faces"):
        from ..errors import ParameterError

        raise ParameterError("--viewpoint and --seen-from orient point clouds; the input is "
                             "a mesh")
    return replace(data, **changes)


def fmt_value(v) -> str:
    """A parameter value for messages and titles (floats without trailing zeros)."""
    return f"{v:g}" if isinstance(v, float) else str(v)


def add_method_options(p: argparse.ArgumentParser, with_size: bool = True) -> None:
    """The parameters of the method (``segment`` and the commands that segment)."""
    if with_size:
        size = p.add_mutually_exclusive_group()
        size.add_argument("-k", "--n-segments", type=int_arg, default=None, metavar="N",
                          help=f"number of superfacets k (default: {_D.n_segments} unless "
                               "--radius is given)")
        size.add_argument("--radius", type=float_arg, default=None, metavar="R",
                          help="superfacet radius as a fraction of the bounding-box diagonal "
                               "(instead of -k; default init then 'flood')")
    p.add_argument("--alpha", type=float_arg, default=_D.alpha, metavar="A",
                   help="weight of the concavity (angular) term, >= 0; 0 = most compact, "
                        f"larger = follows concavities more (default: {_D.alpha:g})")
    p.add_argument("--eta-convex", type=float_arg, default=_D.eta_convex, metavar="E",
                   help="factor of the angular term on convex edges (concave: 1) "
                        f"(default: {_D.eta_convex:g})")
    p.add_argument("--init", choices=INITS, default=_D.init,
                   help="initialization (default: farthest with -k, flood with --radius)")
    p.add_argument("--window", type=float_arg, default=_D.window, metavar="W",
                   help=f"expansion window, a multiple of the radius (default: {_D.window:g})")
    p.add_argument("--max-iter", type=int_arg, default=_D.max_iter, metavar="N",
                   help=f"maximum number of iterations (default: {_D.max_iter})")
    p.add_argument("--weighting", choices=WEIGHTINGS, default=_D.weighting,
                   help="edge weights: the paper's eqs. 1-3 or Shlafman's eq. 6 "
                        f"(then --alpha in [0, 1]) (default: {_D.weighting})")
    p.add_argument("--assignment", choices=ASSIGNMENTS, default=_D.assignment,
                   help="bounded: the paper's window-bounded expansion per center; "
                        "exact: nearest center by one multi-source search "
                        "(default: exact on vertices and points, bounded on faces; "
                        "--paper: bounded)")
    p.add_argument("--tol", type=float_arg, default=_D.tol, metavar="T",
                   help="also stop once a pass changes the superfacet of at most this fraction "
                        f"of the area (default: {_D.tol:g}; 0: the paper's rule: stop when no "
                        "center moves, and --center-tol 0 --coarsen 1 unless given; --paper "
                        "for the paper's labels bit for bit)")
    p.add_argument("--center-tol", type=float_arg, default=None, metavar="F",
                   help="a center the update would move by less than this fraction of the "
                        f"superfacet radius stays where it is (default: {_D_CENTER_TOL:g}, "
                        "0 with --tol 0)")
    p.add_argument("--coarsen", type=int_arg, default=None, metavar="N",
                   help="coarse-to-fine: first solve on clusters of about N elements, then "
                        "refine on all of them; 1: off (default: on where a superfacet holds "
                        f"at least {COARSE_MIN_PER_SEGMENT:,} elements, leaving about "
                        f"{COARSE_PER_SEGMENT:,} clusters per superfacet; for points from "
                        f"{COARSE_MIN_PER_SEGMENT_POINTS:,} points per superpoint, clusters of at "
                        "most n_neighbors / 2 points; off with --tol 0)")
    p.add_argument("--no-connectivity", action="store_true",
                   help="keep superfacets split in several pieces (default: merge stray "
                        "pieces into the neighbour sharing the longest boundary)")
    p.add_argument("--cleanup", action=argparse.BooleanOptionalAction, default=None,
                   help="boundary clean-up after the iteration: boundaries straightened and "
                        "moved onto nearby creases, same superfacets (default: on for faces "
                        "and vertices, off for points, --paper and --weighting shlafman)")
    p.add_argument("--split-merge", action=argparse.BooleanOptionalAction, default=None,
                   help="split superfacets that straddle a crease and merge as many pairs of "
                        "neighbours elsewhere, then iterate again; same number of superfacets "
                        "(default: on for faces and vertices, off for points, --paper and "
                        "--weighting shlafman)")
    p.add_argument("--beta", type=float_arg, default=_D.beta, metavar="B",
                   help="weight of the colour term: crossing a colour edge costs as crossing "
                        "a crease does (the input's RGB: PLY, PCD or LAS points); 0: off "
                        f"(default: {_D.beta:g})")
    p.add_argument("--min-elements", type=int_arg, default=_D.min_elements, metavar="N",
                   help="merge superfacets (superpoints) of fewer than N faces (vertices, "
                        "points) into a neighbour at the end; the count falls by those "
                        f"merged (default: {_D.min_elements}, none)")
    p.add_argument("--density", type=auto_float_arg, default=_D.density, metavar="Q",
                   help="content-sensitive sizes: 0 superfacets of equal area (the paper), "
                        "1 of equal numbers of elements; auto: 0.5 on point clouds of uneven "
                        "density (LiDAR sweeps, RGB-D frames), else 0 (default: auto)")
    p.add_argument("--roughness", type=float_arg, default=_D.roughness, metavar="C",
                   help="content-sensitive sizes: smaller superfacets where neighbouring "
                        "normals turn (C per radian of mean angle); 1 suits scans "
                        f"(default: {_D.roughness:g})")
    p.add_argument("--merge-from", type=int_arg, default=_D.merge_from, metavar="F",
                   help="segment F times -k superpoints first, then merge neighbours down to "
                        "-k, flat ones (within the noise) first; 1: off (default: 5 on point "
                        "clouds of even density, else 1)")
    p.add_argument("--paper", action="store_true",
                   help="the paper's method as published, its labels bit for bit: its "
                        "stopping rule (--tol 0), no clean-up, no split-and-merge (the "
                        "default on faces adds both: lower undersegmentation error and "
                        "more compact superfacets at the paper's speed)")
    p.add_argument("--threads", type=int_arg, default=None, metavar="N",
                   help="threads of the run: graph build, expansions, split-and-merge "
                        "searches, clean-up cuts (default: all cores; the labels do not "
                        "depend on it)")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar of the stages and iterations on stderr (default: on for "
                        "meshes of 500,000 faces or more when stderr is a terminal)")


def add_adaptive_options(p: argparse.ArgumentParser, levels: bool = True) -> None:
    """``--adaptive [START]`` and ``--extent-weight C`` (of ``segment`` and ``batch``)."""
    p.add_argument("--adaptive", nargs="?", const=10, default=None, type=int_arg,
                   metavar="START",
                   help="content-adaptive superpoints: segment START (default 10) times -k, "
                        "then keep the level of -k that merges the flattest neighbours first "
                        "(rooms, aerial tiles; on LiDAR sweeps at small -k only)")
    p.add_argument("--extent-weight", type=float, default=None,
                   metavar="C", dest="extent_weight",
                   help=("planarity levels and " if levels else "") + "--adaptive: weight of "
                        "the segments' extent (default: 0.01 on a scan of uneven density, "
                        "else 0)")


def add_element_options(p: argparse.ArgumentParser) -> None:
    """What is segmented: faces, vertices or points, and the point graph's neighbourhood."""
    p.add_argument("--elements", choices=ELEMENTS, default=None,
                   help="segment the faces of a mesh (the paper), its vertices (one label per "
                        "vertex, like the ScanNet Segmentator) or the points of a cloud "
                        "(default: points for a point cloud, faces for a mesh)")
    p.add_argument("--neighbors", type=int_arg, default=_D.n_neighbors, metavar="N",
                   help=f"point clouds: nearest neighbours of each point (default: "
                        f"{_D.n_neighbors})")
    p.add_argument("--neighbor-radius", type=float_arg, default=None, metavar="R",
                   help="point clouds: drop neighbours farther than this fraction of the "
                        "bounding-box diagonal (default: none)")


def element_kwargs(args) -> dict:
    """Keyword arguments of :func:`superfacets.segment` from :func:`add_element_options`."""
    return dict(elements=args.elements, n_neighbors=args.neighbors,
                neighbor_radius=args.neighbor_radius)


def method_kwargs(args) -> dict:
    """Keyword arguments of :func:`superfacets.segment` from the method options."""
    return dict(alpha=args.alpha, eta_convex=args.eta_convex, window=args.window,
                init=args.init, max_iter=args.max_iter, weighting=args.weighting,
                assignment=args.assignment, enforce_connectivity=not args.no_connectivity,
                cleanup=args.cleanup, split_merge=args.split_merge, tol=args.tol,
                center_tol=args.center_tol,
                coarsen=args.coarsen, progress=bool(args.progress), n_threads=args.threads,
                paper=args.paper, beta=args.beta, min_elements=args.min_elements,
                density=args.density, roughness=args.roughness, merge_from=args.merge_from)


def add_engine_options(p, *, sees: str, note: str = "", prefix: str = "") -> None:
    """``-j/--workers`` and ``--scheduler``: where the tasks of ``batch``, ``experiment``
    and ``segment --tiles`` run (:class:`superfacets.scale.runner.engine.Engine`)."""
    p.add_argument("-j", "--workers", type=int_arg, default=None, metavar="N",
                   help=f"{prefix}worker processes of a local Dask cluster (default: one per "
                        f"core{note}; 1: in this process)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help=f"{prefix}run on a running Dask cluster (tcp://host:8786); {sees} "
                        "(default: DASK_SCHEDULER_ADDRESS where set)")


def add_camera_options(p, size: str) -> None:
    """View, up axis and (for pictures) size, background, boundary lines and zoom."""
    p.add_argument("--view", type=view_arg, default=None, metavar="V",
                   help="camera: auto (default: along the mesh's thinnest axis), front, back, "
                        "left, right, top, bottom, or a direction x,y,z from the mesh")
    p.add_argument("--up", default=None, choices=("x", "y", "z", "-x", "-y", "-z"),
                   help="the mesh's up axis (default: y, as the benchmark's meshes; the "
                        "picture commands say which they used)")
    if size:
        p.add_argument("--size", type=size_arg, default=size_arg(size), metavar="WxH",
                       help=f"image size in pixels (default: {size})")
        p.add_argument("--background", default="white", metavar="COLOR",
                       help="background colour: a name or #rrggbb (default: white)")
        p.add_argument("--no-boundaries", action="store_true",
                       help="do not draw the superfacet boundaries as dark lines")
        p.add_argument("--line-width", type=float_arg, default=1.0, metavar="PX",
                       help="boundary line width in pixels (default: 1)")
        p.add_argument("--zoom", type=float_arg, default=1.0, metavar="Z",
                       help="camera zoom factor, > 1 magnifies (default: 1)")


def add_mesh_and_labels(p, plain: bool = True) -> None:
    """``MESH [LABELS.seg]`` and ``--plain``."""
    p.add_argument("mesh", metavar="MESH", help="input mesh file")
    p.add_argument("labels", metavar="LABELS.seg", nargs="?", default=None,
                   help="superfacet labels, one per face (default: computed)")
    if plain:
        p.add_argument("--plain", action="store_true", help="draw the mesh without superfacets")


def check_output(path: str | None, suffixes: tuple[str, ...], what: str,
                 stdout: bool = False, inputs: tuple = ()) -> Path | None:
    """The output path, checked before any work: its folder exists, it is no folder,
    and it ends in one of ``suffixes`` (when given). ``-`` (standard output) is
    accepted where ``stdout`` is True. A link is checked where it points. An
    output that is one of ``inputs`` (the same file) is refused: nothing is lost.

    Raises
    ------
    FileNotFoundError, IsADirectoryError, ParameterError
    """
    from ..errors import ParameterError

    if path is None:
        return None
    if path == "-":
        if not stdout:
            raise ParameterError(f"-: {what} cannot go to standard output; give a file name")
        return Path("-")
    out = Path(path)
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise FileNotFoundError(f"{out}: output folder {parent} does not exist")
    if out.is_dir():
        raise IsADirectoryError(f"{out}: is a directory")
    if suffixes and not any(out.name.lower().endswith(s) for s in suffixes):
        raise ParameterError(f"{out}: {what} must end in {' or '.join(suffixes)}")
    flat = [x for src in inputs for x in (src if isinstance(src, (list, tuple)) else [src])]
    for src in flat:
        if src and Path(src).exists() and out.exists() and out.samefile(src):
            raise ParameterError(f"{out}: is an input of this command; writing {what} there "
                                 "would overwrite it")
    return out


def check_labels_output(path: str | None, source: str) -> Path | None:
    """``-o``: a label file (``.seg`` or any text name, ``.json`` for segIndices, ``-``).

    A name that says mesh, cloud, picture or page (``x.ply``, ``x.png``, ...) is
    refused: ``-o`` writes text labels there, which no viewer would open; the
    message names the option that writes such a file.
    """
    from ..errors import ParameterError
    from ..io import CLOUD_FORMATS, MESH_FORMATS
    from ..io.files import split_suffix

    out = check_output(path, (), "label file", stdout=True, inputs=(source,))
    if out is None or str(out) == "-":
        return out
    fmt = split_suffix(out)[0]
    option = {"png": "--picture", "html": "--html", "htm": "--html"}.get(
        fmt, "--colored-mesh" if fmt in ("ply", "glb", "obj") else None)
    if fmt != "txt" and (fmt in MESH_FORMATS or fmt in CLOUD_FORMATS or option):
        raise ParameterError(
            f"{out}: -o writes the labels as text (one per line; .json for segIndices), not a "
            f".{fmt} file" + (f"; for that use {option} {out.name}" if option else "")
            + "; name the labels e.g. " + out.name.split(".")[0] + ".seg")
    return out


def labels_for(args, mesh):
    """Labels from LABELS.seg, computed with the method options, or None (--plain);
    a dict describing them for titles and pages; and what they label: ``'faces'``, or
    ``'vertices'`` for a file of one label per vertex (``segment --elements vertices``)."""
    from ..api.segmentation import segment
    from ..errors import MeshFormatError, SuperfacetsError
    from ..io import read_labels

    if args.plain:
        return None, {}, "faces"
    if args.labels:
        labels = read_labels(args.labels)
        info = {"labels": Path(args.labels).name}
        if labels.shape[0] == mesh.n_faces:
            return labels, info, "faces"
        if labels.shape[0] == mesh.n_vertices:
            return labels, info, "vertices"
        raise MeshFormatError(f"{args.labels}: {labels.shape[0]} labels, but {args.mesh} has "
                              f"{mesh.n_faces} faces and {mesh.n_vertices} vertices (one "
                              "label per face or per vertex is needed)")
    kw = method_kwargs(args)
    kw["progress"] = False
    try:
        r = segment(mesh, args.n_segments, radius=args.radius, **kw)
    except SuperfacetsError as exc:
        raise named_after(args.mesh, exc) from None
    info = {"k asked": r.params.get("n_segments"), "alpha": args.alpha,
            "iterations": f"{r.n_iter} ({_describe_stop(r)})",
            "seconds": f"{r.timings['total']:.2f}"}
    return r.labels, info, "faces"


def _describe_stop(result) -> str:
    from ..api.result import describe_stop

    return describe_stop(result)
