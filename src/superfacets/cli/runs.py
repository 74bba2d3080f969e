"""What one ``segment`` run checks and runs, whatever it segments: the sizes in the data's
units, the graph and its levels, the count, the run itself (surfaces and clouds in
:mod:`.segmenting`, tetrahedral meshes in :mod:`.tetmeshes`)."""

from __future__ import annotations

import sys

from ..elements.kinds import kind_of
from ..method.params import DEFAULTS
from .options import check_output, named_after


def check_units(args) -> None:
    """The sizes in the data's units against the options they replace (before reading)."""
    from ..errors import ParameterError

    if args.seed_resolution is not None and (args.n_segments is not None or
                                             args.radius is not None):
        raise ParameterError("--seed-resolution gives the count: not with -k or --radius")
    if args.neighbor_distance is not None and args.neighbor_radius is not None:
        raise ParameterError("give --neighbor-distance (data units) or --neighbor-radius "
                             "(a fraction of the diagonal), not both")
    for flag, v in (("--seed-resolution", args.seed_resolution),
                    ("--neighbor-distance", args.neighbor_distance)):
        if v is not None and not v > 0:
            raise ParameterError(f"{flag} must be a length > 0, got {v}")


def sizes_of(args, data, kind: str, kwargs: dict) -> tuple[dict, str]:
    """The count and the neighbour radius from the sizes in the data's units, or the
    count that grows with the input where none is given; and a line saying which."""
    from ..api.sizes import (
        POINTS_PER_SEGMENT,
        count_for_resolution,
        default_count,
        diagonal_fraction,
    )
    from ..io.units import length_unit
    from .notes import resolution_said

    if args.neighbor_distance is not None:
        if kind != "points":
            from ..errors import ParameterError

            raise ParameterError("--neighbor-distance is of a point cloud's graph")
        kwargs = dict(kwargs, neighbor_radius=diagonal_fraction(
            data, args.neighbor_distance, "--neighbor-distance"))
    segs = kind_of(kind).segment_word
    if args.seed_resolution is not None:
        options = {k: kwargs[k] for k in ("n_neighbors", "neighbor_radius") if k in kwargs}
        res = args.seed_resolution
        k, area = count_for_resolution(data, res, kind, **options)
        args.n_segments = k
        return kwargs, resolution_said(k, kind, res, area, length_unit(args.mesh))
    if args.n_segments is None and args.radius is None:
        k = default_count(data, kind, DEFAULTS.n_segments)
        args.n_segments = k
        if k != DEFAULTS.n_segments:
            why = (f"one per {POINTS_PER_SEGMENT:,} points" if k > DEFAULTS.n_segments else
                   "at most one per 12 elements of this small input")
            choose = "-k" if kind == "cells" else "-k or --seed-resolution"
            return kwargs, f"k = {k:,} {segs} by default ({why}; {choose} to choose)"
    return kwargs, ""


def say_geographic(args) -> None:
    """A note, before the run, where the input's coordinates are longitude and latitude
    (:func:`superfacets.io.units.geographic_note`); none with ``-q``."""
    from ..io.units import geographic_note

    note = "" if getattr(args, "quiet", False) else geographic_note(args.mesh)
    if note:
        print(f"note: {note}", file=sys.stderr)


def checked_graph(args, into_records: bool = False):
    """``--graph OUT.npz`` (a path or None) and ``--levels``, ``--level-cost``,
    ``--extent-weight``, ``--adaptive`` with what they need, before anything is read;
    ``into_records``: ``-o`` writes the scan's own records (where levels go too)."""
    from ..errors import ParameterError
    from ..graph.hierarchy import wanted_levels
    from ..io import input_kind

    check_levels(args)
    graph_out = check_output(args.graph, (".npz",), "the graph", inputs=(args.mesh,))
    if args.levels and graph_out is None and not into_records:
        records = (" or -o of the scan's own records (.las/.laz, .ply, .pcd: each level a "
                   "field ClusterID_N after the labels)" if input_kind(args.mesh) != "volume"
                   else "")
        raise ParameterError("--levels goes with --graph OUT.npz (the hierarchy is written "
                             f"there){records}")
    if args.levels:
        wanted_levels(args.levels, args.n_segments, ("--levels", "-k"))
    if args.level_cost is not None and not args.levels:
        raise ParameterError("--level-cost is the merge cost of --levels; give both")
    return graph_out


def check_levels(args) -> None:
    """``--per-object``, ``--adaptive`` and ``--extent-weight`` with what they need."""
    from ..errors import ParameterError

    if args.per_object and args.radius is not None:
        raise ParameterError("--per-object takes -k, not --radius")
    if args.extent_weight is not None and (
            args.extent_weight < 0 or (args.adaptive is None and (
                not args.levels or args.level_cost != "planarity"))):
        raise ParameterError("--extent-weight takes a number >= 0, with --adaptive or "
                             f"--levels and --level-cost planarity, got {args.extent_weight}")
    if args.adaptive is not None and args.adaptive < 1:
        raise ParameterError(f"--adaptive must be at least 1, got {args.adaptive}")
    if args.adaptive is not None and (args.per_object or args.radius is not None):
        raise ParameterError("--adaptive takes -k, on one segmentation (not --radius or "
                             "--per-object)")


def run_segment(args, data, kwargs):
    """The segmentation the options ask for: per object, content-adaptive or one run."""
    from ..api.scenes import segment_objects
    from ..api.segmentation import segment
    from ..errors import SuperfacetsError
    from ..viz.outputs import JoinedResult

    size = data.n_tets if hasattr(data, "n_tets") else \
        data.n_faces if hasattr(data, "faces") else data.n_total
    if args.progress is None:  # long runs show where they are
        kwargs = dict(kwargs, progress=size >= 500_000 and sys.stderr.isatty())
    k = args.n_segments or DEFAULTS.n_segments
    try:
        if args.per_object:
            return JoinedResult(*segment_objects(data, k, **kwargs))
        if args.adaptive is not None:  # (the API's one door: segment(..., adaptive=START))
            return segment(data, k, adaptive=args.adaptive, extent_weight=args.extent_weight,
                           **kwargs)
        return segment(data, args.n_segments, radius=args.radius, **kwargs)
    except SuperfacetsError as exc:
        raise named_after(args.mesh, exc) from None
