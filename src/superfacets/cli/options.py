"""Options shared by several commands, and the helpers that read them.

Defaults and choices come from :mod:`superfacets.method.params`, so the help texts
and the API never disagree. Nothing here imports numba: building the parser
(``--help``, argument errors) stays light.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..checks import AXES  # (``--seen-from`` axis names and their directions)
from ..elements.kinds import kind_of
from ..method.params import DEFAULTS, PARAMETERS
from .parameters import auto_float_arg, float_arg, int_arg  # noqa: F401 (re-exported)
from .reading import (  # noqa: F401 (re-exported)
    check_header,
    named_after,
    read_usable,
    shows_stages,
)

__all__ = ["int_arg", "float_arg", "size_arg", "view_arg", "add_method_options",
           "add_camera_options", "add_mesh_and_labels", "method_kwargs", "check_output",
           "labels_for", "fmt_value", "add_scan_options", "scan_cloud", "scan_fields",
           "point_arg"]

_D = DEFAULTS


def levels_arg(text: str) -> list[int]:
    """argparse type: ``--levels 50,20``, positive integers."""
    try:
        out = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        out = []
    if not out or min(out) < 1:
        raise argparse.ArgumentTypeError(f"expected positive integers N1,N2,..., got {text!r}")
    return out


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




def add_scan_options(p: argparse.ArgumentParser) -> None:
    """How the estimated normals of a point cloud are oriented (scans)."""
    p.add_argument("--viewpoint", type=point_arg, default=None, metavar="X,Y,Z",
                   help="point clouds: the sensor's position; estimated normals face it "
                        "(default: a PCD's VIEWPOINT, else none)")
    p.add_argument("--seen-from", choices=tuple(AXES), default=None, metavar="AXIS",
                   help="point clouds of open surfaces (terrain, streets) without a "
                        "viewpoint: the side they were scanned from (x, y, z, -x, -y, -z); "
                        "each piece's normals are turned to agree with it, a PCD's own "
                        "VIEWPOINT set aside (default: z for .las/.laz, else outwards from "
                        "each piece's mean)")


def add_unit_options(p) -> None:
    """Sizes in the data's units: ``--seed-resolution`` (instead of ``-k``) and
    ``--neighbor-distance`` (instead of ``--neighbor-radius``)."""
    p.add_argument("--seed-resolution", type=float_arg, default=None, metavar="R",
                   help="the size of a superpoint (superfacet) in the data's units (metres "
                        "for most scans), as VCCS's seed resolution: k = surface area / R^2 "
                        "(instead of -k or --radius)")
    p.add_argument("--neighbor-distance", type=float_arg, default=None, metavar="D",
                   help="point clouds: drop neighbours farther than D, in the data's units "
                        "(instead of --neighbor-radius, a fraction of the diagonal)")


def scan_fields(args) -> dict:
    """The cloud fields :func:`add_scan_options` set: ``viewpoint`` and ``up`` (tuples).
    ``--seen-from`` without ``--viewpoint`` sets the file's own viewpoint aside (a PCD's
    ``VIEWPOINT``, often PCL's default origin, which a georeferenced scan lies far from):
    the side named is the orientation asked for."""
    out = {}
    if getattr(args, "viewpoint", None) is not None:
        out["viewpoint"] = tuple(args.viewpoint)
    if getattr(args, "seen_from", None) is not None:
        out["up"] = AXES[args.seen_from]
        out.setdefault("viewpoint", None)
    return out


def scan_cloud(data, args):
    """``data`` with :func:`add_scan_options` applied (a point cloud; a mesh given either
    option is refused)."""
    from dataclasses import replace

    changes = scan_fields(args)
    if not changes:
        _far_viewpoint_note(data, args)
        return data
    if hasattr(data, "faces"):
        from ..errors import ParameterError

        raise ParameterError("--viewpoint and --seen-from orient point clouds; the input is "
                             "a mesh")
    return replace(data, **changes)


def _far_viewpoint_note(data, args) -> None:
    """A note on stderr where a cloud's own viewpoint (a PCD's ``VIEWPOINT``: PCL writes the
    origin by default) lies farther from its points than their bounding box is wide: no
    sensor sees that way, and the estimated normals face it (a georeferenced tile)."""
    import sys

    import numpy as np

    vp = getattr(data, "viewpoint", None)
    if vp is None or getattr(args, "quiet", False) or getattr(data, "normals", None) is not None:
        return
    pts = np.asarray(data.points, dtype=np.float64).reshape(-1, 3)
    pts = pts[np.isfinite(pts).all(axis=1)]
    if not pts.shape[0]:
        return
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    far = float(np.linalg.norm(np.maximum(lo - vp, 0) + np.maximum(vp - hi, 0)))
    if far > float(np.linalg.norm(hi - lo)):
        where = ", ".join(f"{v:g}" for v in vp)
        print(f"note: the file's viewpoint ({where}) lies {far:,.0f} units from the points, "
              "farther than they spread: the estimated normals face it; for an airborne or "
              "terrain tile give --seen-from z (or --viewpoint X,Y,Z)", file=sys.stderr)


def up_of(args, data, path=None) -> tuple[str, str]:
    """The pictures' up axis and what said so: ``--up``, else the input's own or its
    format's (:func:`superfacets.io.orientation.up_axis`), else y."""
    if getattr(args, "up", None):
        return args.up, "--up"
    if getattr(args, "seen_from", None) and hasattr(data, "valid"):  # (a cloud's, given)
        return args.seen_from, "--seen-from"
    from ..io.orientation import up_axis

    return up_axis(data, path if path is not None else getattr(args, "mesh", None))


def said_up(up: tuple[str, str]) -> str:
    """``up axis z (STL's convention)``, for messages; the default names ``--up``."""
    axis, source = up
    if source == "--up":
        return f"up axis {axis}"
    hint = "; --up z for a z-up mesh" if source == "the default" else ""
    return f"up axis {axis} ({source}{hint})"


def fmt_value(v) -> str:
    """A parameter value for messages and titles (floats without trailing zeros)."""
    return f"{v:g}" if isinstance(v, float) else str(v)


def add_method_options(p: argparse.ArgumentParser, with_size: bool = True) -> None:
    """The parameters of the method (``segment`` and the commands that segment), made
    from their declarations (:mod:`superfacets.cli.parameters`), and ``-q``."""
    from .parameters import GROUPS, add_parameters

    add_parameters(p, _method_names(with_size))
    run = next((g for g in p._action_groups if g.title == GROUPS["run"]), p)
    run.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")


def _method_names(with_size: bool = True) -> tuple[str, ...]:
    from .parameters import ELEMENT_PARAMETERS

    size = ("n_segments", "radius")
    return tuple(q.name for q in PARAMETERS if q.name not in ELEMENT_PARAMETERS and
                 (with_size or q.name not in size))


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
    """What is segmented: faces, vertices or points, and the point graph's neighbourhood
    (from their declarations, :mod:`superfacets.cli.parameters`)."""
    from .parameters import ELEMENT_PARAMETERS, add_parameters

    add_parameters(p, ELEMENT_PARAMETERS)


def element_kwargs(args) -> dict:
    """Keyword arguments of :func:`superfacets.segment` from :func:`add_element_options`."""
    from .parameters import ELEMENT_PARAMETERS, parameter_kwargs

    return parameter_kwargs(args, ELEMENT_PARAMETERS)


def method_kwargs(args) -> dict:
    """Keyword arguments of :func:`superfacets.segment` from the method options (the size,
    ``-k`` or ``--radius``, apart)."""
    from .parameters import parameter_kwargs

    return parameter_kwargs(args, _method_names(with_size=False))


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
                   help="the input's up axis (default: the file's own, e.g. a LAS "
                        "cloud's z or an RGB-D scan's sensor up, else its format's: STL z, "
                        "glTF y, else y; the picture commands say which they used)")
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
    """``INPUT [LABELS]``, ``--labels-from`` and ``--plain``."""
    p.add_argument("mesh", metavar="INPUT",
                   help="a mesh, a point cloud (every format 'segment' reads) or a "
                        "tetrahedral mesh")
    p.add_argument("labels", metavar="LABELS", nargs="?", default=None,
                   help="labels, one per face, vertex, point or tetrahedron: a .seg file, a "
                        "segIndices .json, a PLY, PCD or LAS/LAZ written by 'segment -o' "
                        "(default: computed)")
    p.add_argument("--labels", metavar="LABELS", dest="labels_file", default=None,
                   help="LABELS given by name (the same file)")
    p.add_argument("--labels-from", metavar="FIELD", default=None,
                   help="take the labels from a field of the input itself: a LAS/LAZ "
                        "dimension, a PCD field or a PLY vertex property (ClusterID, as "
                        "'segment -o OUT.laz' writes it; scalar_ClusterID is found as "
                        "ClusterID)")
    if plain:
        p.add_argument("--plain", action="store_true", help="draw the input without labels")


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
        from ..io.files import not_a_folder

        raise FileNotFoundError(f"{out}: output folder {parent} {not_a_folder(parent)}")
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


def check_drawings(args, others: tuple = ()) -> tuple:
    """``--picture OUT.png`` and ``--html OUT.html`` of a command, checked before its run:
    their paths, ``--view`` and ``--up`` without either, no two outputs on one file (with
    the run's ``others``), the drawing extra; each a path or None."""
    from .._runtime.extras import require
    from ..errors import ParameterError

    png_out = check_output(args.picture, (".png",), "the picture", inputs=(args.mesh,))
    html_out = check_output(args.html, (".html", ".htm"), "the page", inputs=(args.mesh,))
    for flag, given, what in (("--view", args.view is not None, "chooses the camera"),
                              ("--up", args.up, "sets the up axis")):
        if given and png_out is None and html_out is None:
            raise ParameterError(f"{flag} {what} of --picture OUT.png and --html OUT.html; "
                                 "give one of them")
    named = [str(x) for x in (*others, png_out, html_out) if x is not None]
    if len(set(named)) < len(named):
        raise ParameterError("two outputs go to the same file")
    if png_out is not None:
        require("pyvista", "drawing pictures")  # (before the run, not after it)
    return png_out, html_out


#: Data files ``-o`` does not write, by suffix: a name of one is refused, not given text.
CONTAINERS = {"npz": "NumPy's archive", "h5": "HDF5", "hdf5": "HDF5", "hdf": "HDF5",
              "pt": "PyTorch", "pth": "PyTorch", "pkl": "pickle", "pickle": "pickle",
              "parquet": "Parquet", "feather": "Feather", "arrow": "Arrow", "mat": "MATLAB",
              "zip": "zip", "tar": "tar", "7z": "7-Zip", "zarr": "Zarr",
              "tfrecord": "TFRecord", "xlsx": "Excel", "xls": "Excel"}


def check_labels_output(path: str | None, source: str, records: bool = False) -> Path | None:
    """``-o``: a label file (``.seg`` or any text name, ``.json`` for segIndices, ``-``),
    or, where ``records`` is True, a copy of a LAS/LAZ, PLY or PCD input with the labels in its
    records (:func:`superfacets.io.records.write_labels_into`), or a new LAS/LAZ or PLY of
    the points of a cloud whose own file takes no field (:func:`superfacets.io.records.
    write_cloud_with_labels`).

    Any other name that says mesh, cloud, picture or page (``x.pcd``, ``x.png``, ...) is
    refused: ``-o`` writes text labels there, which no viewer would open; the
    message names the option that writes such a file.
    """
    from ..errors import ParameterError
    from ..io import CLOUD_FORMATS, MESH_FORMATS, VOLUME_FORMATS
    from ..io.files import split_suffix
    from ..io.records import scan_output

    out = check_output(path, (), "the labels", stdout=True, inputs=(source,))
    if out is None or str(out) == "-":
        return out
    if records and scan_output(out, source) is not None:  # (a mismatch: refused there)
        return out
    fmt = split_suffix(out)[0]
    if fmt == "npy":  # (the labels as a NumPy array, as learning pipelines load them)
        return out
    if fmt == "label":  # (read back as SemanticKITTI's binary classes: refused, not misread)
        raise ParameterError(f"{out}: a .label file is SemanticKITTI's binary classes; name "
                             f"the labels e.g. {out.name.split('.')[0]}.seg")
    if fmt in CONTAINERS:  # (text there would not load where such a file is read)
        stem = out.name.split(".")[0]
        raise ParameterError(f"{out}: -o writes the labels as text or as a NumPy array, not a "
                             f".{fmt} file ({CONTAINERS[fmt]}); name them {stem}.npy (np.load) or "
                             f"{stem}.seg" + ("; --graph NAME.npz writes the superpoint "
                                              "graph with its labels" if fmt == "npz" else ""))
    option = {"png": "--picture", "html": "--html", "htm": "--html"}.get(
        fmt, "--colored-mesh" if fmt in ("ply", "glb", "obj", *VOLUME_FORMATS) else None)
    if fmt != "txt" and (fmt in MESH_FORMATS or fmt in CLOUD_FORMATS or option):
        raise ParameterError(
            f"{out}: -o writes the labels as text (one per line; .json for segIndices), not a "
            f".{fmt} file" + (f"; for that use {option} {out.name}" if option else "")
            + "; name the labels e.g. " + out.name.split(".")[0] + ".seg"
            + ("" if not records or fmt not in ("las", "laz", "ply", "pcd") else
               f" (a .{fmt} takes the labels into a copy of a "
               f"{'LAS/LAZ' if fmt in ('las', 'laz') else fmt.upper()} input's records)")
            + _converted_said(out, source, records))
    return out


def _converted_said(out: Path, source: str, records: bool) -> str:
    """Where ``-o`` names a cloud format it does not write (an E57, a PCD of a LAS): the
    names that take the labels with the input's points (a copy of its records, or a new
    LAS/LAZ or PLY of its points), or ``""``."""
    from ..errors import ParameterError
    from ..io.records import scan_output

    if not records:
        return ""
    stem = out.name.split(".")[0]
    taken = []
    for fmt in ("las", "laz", "ply", "pcd"):
        try:
            if fmt != out.suffix.lower()[1:] and scan_output(out.with_name(f"{stem}.{fmt}"),
                                                             source) is not None:
                taken.append(f"{stem}.{fmt}")
        except ParameterError:  # (a copy of another format's records: refused there)
            continue
    if not taken:
        return ""
    names = ", ".join(taken[:-1]) + " or " + taken[-1] if len(taken) > 1 else taken[0]
    return f"; the points with their labels as a field: {names}"


def _segmenting_options(args) -> list[str]:
    """The method's options given to a command that draws labels (those whose values are
    not the defaults, and ``-k``/``--radius``), as ``--name``."""
    from ..method.params import DEFAULTS, PARAMETERS

    given = [f for f, v in (("-k", getattr(args, "n_segments", None)),
                            ("--radius", getattr(args, "radius", None))) if v is not None]
    try:
        kwargs = method_kwargs(args)
    except AttributeError:  # (a command without the method's options)
        return given
    flags = {p.name: p.cli for p in PARAMETERS if p.cli}
    for k, v in kwargs.items():
        if k != "progress" and v is not None and v != getattr(DEFAULTS, k, v):
            flag = flags.get(k, f"--{k.replace('_', '-')}")
            given.append(f"--no-{flag[2:]}" if v is False and not flag.startswith("--no-")
                         else flag)
    return given


def check_header_option(header: bool, labels, source) -> None:
    """Refuse ``--header`` where no label file of text is written (none, a ``.json``, a
    ``.npy``, a scan's records): its ``#`` lines would go nowhere, silently.

    Raises
    ------
    ParameterError
        Naming the output that holds no header.
    """
    from ..errors import ParameterError
    from ..io.records import scan_output

    if not header:
        return
    if labels is None:
        raise ParameterError("--header starts the label file with '#' lines: give -o OUT.seg")
    name = str(labels).lower()
    if name.endswith((".json", ".npy")) or scan_output(labels, source) is not None:
        raise ParameterError(f"--header starts a label file of text with '#' lines; "
                             f"{Path(str(labels)).name} holds none (name the labels .seg)")


def refuse_neighbours(n_neighbors, neighbor_radius, kind: str) -> None:
    """Refuse ``--neighbors`` (other than the default) and ``--neighbor-radius`` where the
    elements are not a cloud's points: a mesh's faces and vertices have the mesh's edges
    for a graph, and would take them and change nothing.

    Raises
    ------
    ParameterError
        Naming the elements.
    """
    from ..errors import ParameterError
    from ..method.params import DEFAULTS

    if kind_of(kind).cloud:
        return
    given = [f for f, on in (("--neighbors", n_neighbors not in (None, DEFAULTS.n_neighbors)),
                             ("--neighbor-radius", neighbor_radius is not None)) if on]
    if given:
        raise ParameterError(f"{' and '.join(given)} shape{'s' if len(given) == 1 else ''} "
                             f"a point cloud's graph; this input's elements are {kind}, "
                             "whose graph is the mesh's edges")


def elements_of_input(data) -> str:
    """What an input's elements are by default: ``'faces'`` (a mesh), ``'points'`` (a
    cloud) or ``'cells'`` (a tetrahedral mesh)."""
    if hasattr(data, "tets"):
        return "cells"
    return "faces" if hasattr(data, "faces") else "points"


def _counts(data) -> dict:
    """The number of each kind of element an input has, by kind."""
    kind = elements_of_input(data)
    if kind == "points":
        return {"points": data.n_total}
    if kind == "cells":
        return {"cells": data.n_tets}
    return {"faces": data.n_faces, "vertices": data.n_vertices}


def labels_for(args, data):
    """Labels from LABELS (a file) or ``--labels-from FIELD`` (the input's own), computed
    with the method options, or None (``--plain``); a dict describing them for titles and
    pages; and what they label: ``'faces'``, ``'vertices'`` (one label per vertex, as
    ``segment --elements vertices`` writes), ``'points'`` or ``'cells'``."""
    from ..api.segmentation import segment
    from ..errors import MeshFormatError, ParameterError, SuperfacetsError
    from ..io import read_labels
    from ..io.labels import read_field

    counts = _counts(data)
    first = next(iter(counts))
    field = getattr(args, "labels_from", None)
    given = _segmenting_options(args)
    if given and (args.labels or field or getattr(args, "plain", False)):
        raise ParameterError(f"{', '.join(given)} segment{'s' if len(given) == 1 else ''} the "
                             "input; with LABELS, --labels-from or --plain nothing is "
                             "segmented: leave them out")
    if getattr(args, "plain", False):
        if args.labels or field:
            raise ParameterError("--plain draws no labels: not with LABELS or --labels-from")
        return None, {}, first
    if field and args.labels:
        raise ParameterError("give the labels once: LABELS or --labels-from FIELD")
    if args.labels or field:
        labels = read_field(args.mesh, field) if field else read_labels(args.labels)
        info = {"labels": f"{Path(args.mesh).name}: {field}" if field else
                Path(args.labels).name}
        for kind, n in counts.items():
            if labels.shape[0] == n:
                return labels, info, kind
        said = " and ".join(kind_of(k).counted(n) for k, n in counts.items())
        raise MeshFormatError(f"{field or args.labels}: {labels.shape[0]:,} labels, but "
                              f"{args.mesh} has {said} (one label per "
                              f"{' or per '.join(kind_of(k).singular for k in counts)} "
                              "is needed)")
    kw = method_kwargs(args)
    size = next(iter(counts.values()))
    kw["progress"] = shows_stages(args, size)  # (a large input: its bars)
    try:
        r = segment(data, args.n_segments, radius=args.radius, **kw)
    except SuperfacetsError as exc:
        raise named_after(args.mesh, exc) from None
    info = {"k asked": r.params.get("n_segments"), "alpha": r.params.get("alpha"),
            "iterations": f"{r.n_iter} ({_describe_stop(r)})",
            "seconds": f"{r.timings['total']:.2f}"}
    return r.labels, info, first


def _describe_stop(result) -> str:
    from ..api.result import describe_stop

    return describe_stop(result)


def sizes_said(labels, elements: str, result=None, unit: str | None = None) -> str:
    """``', 12 to 480 points each (median 130)'``: the segments' sizes in elements; with a
    run's ``result``, also how wide the median one is in the data's units (the diameter of
    a disc of its area: ``', ... (median 130, about 1.9 wide in the data's units)'``; a
    tiled run's, the mean one's, from the input's area: ``'about 2.1 wide on average'``);
    with the file's ``unit`` (:func:`superfacets.io.units.length_unit`), in it: ``'about
    1.9 m wide'``."""
    import numpy as np

    from ..elements.labels import size_summary

    lab = np.asarray(labels)
    if not (lab >= 0).any():
        return ""
    s = size_summary(lab)
    wide, said = _median_width(result), "wide"
    area = getattr(result, "area", None)  # (a tiled run's: the input's, not each element's)
    if wide is None and area is not None and np.isfinite(area) and area > 0:
        wide, said = 2.0 * np.sqrt(area / np.unique(lab[lab >= 0]).size / np.pi), \
            "wide on average"
    return (f", {s['size_min']:,} to {s['size_max']:,} {elements} each "
            f"(median {s['size_median']:,.0f}"
            + (f", about {wide:.3g} {unit} {said}" if wide and unit else
               f", about {wide:.3g} {said} in the data's units" if wide else "") + ")")


def _median_width(result) -> float | None:
    """The diameter of a disc of the median segment's area (its elements' sizes summed; of
    tetrahedra, of a ball of its volume), in the input's units (a run that weighed the up
    coordinate: each point's area on its tangent plane stretched back,
    :func:`superfacets.inputs.cloud.unweighed_area_factor`); None where the result holds
    no element graph."""
    import numpy as np

    from ..inputs.cloud import unweighed_area_factor

    try:
        graph, labels = result.elements.graph, np.asarray(result.element_labels)
    except AttributeError:
        return None
    keep = labels >= 0
    sizes = np.asarray(graph.sizes, dtype=np.float64)
    weight = (getattr(result, "params", None) or {}).get("up_weight", 1.0)
    up = getattr(getattr(result.elements, "source", None), "up", None)
    if weight != 1 and up is not None and graph.normals is not None:  # (the weighed cloud's)
        sizes = sizes * unweighed_area_factor(graph.normals, up, weight)
    area = np.bincount(labels[keep], weights=sizes[keep])
    area = area[area > 0]
    if not area.size:
        return None
    if graph.kind == "cells":  # (a volume: a ball's diameter)
        return float(np.cbrt(6.0 * np.median(area) / np.pi))
    return float(2.0 * np.sqrt(np.median(area) / np.pi))
