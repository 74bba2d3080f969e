"""What the command line says about a run beside its summary: why the count of segments
differs from the ``-k`` asked for, and how to come closer to it."""

from __future__ import annotations

from ..elements.kinds import kind_of
from ..method.params import DEFAULTS
from ..method.rules import SCENE_MERGE_FROM

__all__ = ["count_note", "duplicates_note", "merges_said", "resolution_said", "scene_note",
           "COST_SAID"]

#: What a summary adds for the merges' cost to the count (``--merge-cost``), beyond the
#: default's.
COST_SAID = {"scene": "; the scene's cost, its rise unweighted",
             "auto": "; by the plane's rise or Ward's cost (--merge-cost auto)"}


def resolution_said(k: int, kind: str, resolution: float, area: float,
                    unit: str | None = None) -> str:
    """Where a count from ``--seed-resolution`` came from (one run's or a tiled run's): the
    surface's area over the resolution squared, in the file's ``unit`` where it names one
    (:func:`superfacets.io.units.length_unit`), and the floor of elements per segment where
    it decided."""
    import numpy as np

    from ..api.sizes import MIN_ELEMENTS_PER_SEGMENT

    with np.errstate(over="ignore", under="ignore", divide="ignore"):
        capped = not np.float64(area) / np.float64(resolution) / np.float64(resolution) < \
            k + 0.5
    square = (f"{unit}^2 / ({resolution:g} {unit})^2" if unit else
              f"square units / {resolution:g}^2")
    return (f"k = {k:,} {kind_of(kind).segment_word} from --seed-resolution {resolution:g}: "
            f"a surface of {area:,.4g} {square}"
            + (f", at most one per {MIN_ELEMENTS_PER_SEGMENT} {kind}" if capped else ""))


def merges_said(first: int, params: dict, cloud: bool = True, scene: bool = False) -> str:
    """The summary's words for merges to the count from ``first`` superpoints (one run's
    or a tiled run's): how they merged, the size bound and a cost other than the
    default's; a tiled mesh's are Ward's merges. ``scene``: the run chose its
    ``merge_from`` itself (not given), and took a scene's
    (:data:`~superfacets.method.rules.SCENE_MERGE_FROM`: the input has an up direction)."""
    if not cloud:
        return f" (merged from {first:,} finer ones, Ward's merges; --merge-from 1: no merging)"
    bound = params.get("max_size_ratio") or 0
    most = f", none above {bound:g} times the mean" if bound else ""
    why = ""
    if scene and params.get("merge_from") == SCENE_MERGE_FROM:
        why = f", {SCENE_MERGE_FROM} times -k as on a scene (the input's up direction)"
        k = params.get("n_segments") or 0
        if k and first < SCENE_MERGE_FROM * k:  # (superfacets.method.rules.fine_count)
            why += " where its points allow"
    return (f" (merged from {first:,} finer ones{why}, flat neighbours first{most}"
            f"{COST_SAID.get(params.get('merge_cost'), '')}; --merge-from 1: no merging)")


def fields_said(kept: list) -> str:
    """The values a new file of the points kept, for the summary's "wrote" line (" with
    their intensity and ring"; "" for none)."""
    if not kept:
        return ""
    names = f"{', '.join(kept[:-1])} and {kept[-1]}" if len(kept) > 1 else kept[0]
    return f" with their {names}"


def records_said(output, source, rows: str, kept: str = "", levels=()) -> str:
    """What ``-o OUTPUT`` holds where it writes a scan's records (a copy of the input's, or
    a new file of its ``rows`` whose kept values ``kept`` says, :func:`fields_said`): the
    field the labels are in (a PLY's ``scalar_`` name and CloudCompare's), the levels'
    (``levels``: their numbers of segments) and a COPC input's index left out; ``""`` where
    ``-o`` writes a label file."""
    from ..io.records import LABEL_FIELD, copc_said, level_field, ply_field_name, scan_output

    into = scan_output(output, source)
    if into is None:
        return ""
    ply = str(output).lower().endswith(".ply")
    field = (f"{ply_field_name(LABEL_FIELD)}, CloudCompare's scalar field {LABEL_FIELD}"
             if ply else LABEL_FIELD)
    if levels:
        field += ", levels as " + ", ".join((ply_field_name if ply else str)(level_field(n))
                                            for n in sorted(set(levels), reverse=True))
    if into == "new":
        return f"a new file of the input's {rows}{kept}, labels as {field}"
    return f"the input's {rows}, every field kept, labels as {field}{copc_said(source)}"


def weights_said(params: dict) -> str:
    """The summary's words for what a run's weights read besides the geometry (one run's or
    a tiled run's): the colour term, the up coordinate's weight, a scene's steps."""
    said = ""
    if params.get("feature_floor") is not None and params.get("beta"):  # colour weighed
        said += f", following colour (beta {params['beta']:.3g}; --beta 0: off)"
    if params.get("up_weight", 1) != 1:
        said += f", heights weighed {params['up_weight']:g} times (--up-weight 1: off)"
    if (params.get("step_weight") or 1) != 1:
        said += (f", neighbours along the surfaces (steps weighed {params['step_weight']:g} "
                 "times; --step-weight 1: off)")
    return said


def duplicates_note(args, data, kind: str) -> str | None:
    """Copies of a face (the same vertices) and points at the same position are segmented
    as one element: say how many share a label with an earlier one."""
    if kind == "faces":
        from ..elements.faces import distinct_faces

        found = distinct_faces(data)  # (from the face graph kept with the mesh)
        copies = 0 if found is None else data.n_faces - found[0].shape[0]
        what = ("face is a copy" if copies == 1 else "faces are copies") + \
            " of an earlier face (the same vertices)"
    elif kind == "points":
        import numpy as np

        from ..elements.builders import elements_of

        src = elements_of(data, kind, n_neighbors=args.neighbors,
                          neighbor_radius=args.neighbor_radius)  # (kept with the input)
        copies = int(np.count_nonzero(src.index >= 0)) - src.graph.n_elements
        what = ("point is" if copies == 1 else "points are") + \
            " at the position of an earlier point"
    else:
        return None
    return f"{copies:,} {what} and share its label" if copies else None


#: What the starts other than the farthest point's place (:func:`count_note`).
STARTS_SAID = {"flood": "its centers about a radius apart over the surface (the paper's "
                        "start for --radius)",
               "grid": "a center in each cell of a grid sized for k that the surface "
                       "crosses"}
#: How far from k a run with such a start ends before :func:`count_note` says why.
START_SLACK = 0.05


def scene_note(data, kind: str, name: str, extent=None) -> str | None:
    """A cloud with no up direction is segmented as an object; where its box is thinnest
    along one axis by half (:func:`superfacets.io.orientation.thinnest_axis`), the option
    that segments it as a scan, as a LAS file is. ``data`` None: a tiled run's cloud of no
    up direction, its box's sides ``extent``."""
    from ..io.orientation import thinnest_axis

    axis = thinnest_axis(data, extent) if kind == "points" else None
    if axis is None:
        return None
    return (f"{name} names no up direction, so its superpoints are an object's; if it is a "
            f"scan seen along {axis} (its box is thinnest along {axis}: a street, a room, "
            f"terrain), --seen-from {axis} segments it as a scan, as a LAS file is (neighbours "
            f"along its surfaces, merged from {SCENE_MERGE_FROM} times -k)")


def count_note(args, data, result, kind: str) -> str | None:
    """Why a run asked for k made more superfacets: more separate pieces than k (a
    region cannot cross from one piece to another), or regions that no center reached
    (with ``--paper``, whole pieces), and how to keep k; or more or fewer than k by 5 %
    with the flood's or the grid's start, which do not place k centers."""
    asked = args.n_segments or DEFAULTS.n_segments
    extra = getattr(result, "n_orphan_seeds", 0)
    start = getattr(result, "params", {}).get("init")
    if args.radius is None and not args.per_object and start in STARTS_SAID and abs(
            result.n_segments - asked) > START_SLACK * asked:
        return (f"{result.n_segments} {kind_of(kind).segment_word} for -k {asked}: the "
                f"{start} start places {STARTS_SAID[start]}, not k of them; the default "
                "start (--init farthest) places k")
    if args.radius is not None or args.per_object or result.n_segments <= asked:
        return None
    import numpy as np

    from ..elements.builders import elements_of
    from ..method.connectivity import label_components

    graph = elements_of(data, kind, n_neighbors=args.neighbors,
                        neighbor_radius=args.neighbor_radius).graph  # kept with the input
    # the pieces from the graph's own CSR (scipy's copy of it with unit weights cost a
    # 2M-point scan of rings 650 MiB, twice the run's peak)
    one = np.zeros(graph.n_elements, dtype=np.int64)
    pieces = int(label_components(graph, one).max()) + 1 if graph.n_elements else 0
    what = kind_of(kind).segment_word
    if pieces >= asked:
        return (f"{result.n_segments} {what} for -k {asked}: the input has {pieces} separate "
                f"pieces and a region cannot cross from one piece to another, so each piece "
                f"is at least one of them ({pieces} is the fewest this input can have)")
    if not extra:
        return None
    if pieces <= 1:
        return (f"{result.n_segments} {what} for -k {asked}: {extra} regions that no center "
                f"reached within its window became {what} of their own; a larger --window "
                "keeps closer to k")
    fewer = max(pieces, asked - (result.n_segments - asked))
    hint = (" or --per-object to share k among the file's objects" if kind_of(kind).objects
            and len(getattr(data, "objects", ())) > 1 else "")
    why = ("a region cannot cross from one piece to another" if getattr(args, "paper", False)
           else "each piece has a center, but a center drawn near another piece can leave "
                "elements of its own out of every window")
    return (f"{result.n_segments} {what} for -k {asked}: the input has {pieces} separate "
            f"pieces, and the {extra} " + ("region" if extra == 1 else "regions") +
            f" that no center reached ({why}) became {what} of their own; ask for fewer "
            f"(about -k {fewer}){hint} to end near {asked}")
