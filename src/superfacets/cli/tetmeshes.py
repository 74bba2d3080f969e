"""``segment`` of a tetrahedral mesh (``.msh``, ``.vtk``, ``.vtu``, ``.mesh``)."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from .options import (
    check_drawings,
    check_labels_output,
    check_output,
    method_kwargs,
    named_after,
    refuse_neighbours,
    sizes_said,
)
from .runs import check_units, checked_graph, run_segment, sizes_of


def _checked(args) -> dict:
    """The outputs of a volume's run, and the options it refuses, before the read."""
    from ..errors import ParameterError

    for flag, given in (("--per-object", args.per_object),
                        ("--vertex-colors", args.vertex_colors)):
        if given:
            raise ParameterError(f"{flag} is not available for tetrahedral meshes")
    if getattr(args, "elements", None) not in (None, "cells"):
        raise ParameterError(f"--elements {args.elements}: a tetrahedral mesh is segmented by "
                             "its tetrahedra")
    refuse_neighbours(args.neighbors, args.neighbor_radius, "cells")
    check_units(args)
    for flag, given in (("--seed-resolution", args.seed_resolution),
                        ("--neighbor-distance", args.neighbor_distance)):
        if given is not None:
            raise ParameterError(f"{flag} is a size on a surface or in a point cloud's graph; "
                                 "a tetrahedral mesh takes a count (-k)")
    seg_out = check_labels_output(args.output, args.mesh)
    vol_out = check_output(args.colored_mesh, (".vtu", ".vtk", ".msh", ".mesh"),
                           "the labelled volume", inputs=(args.mesh,))
    graph_out = checked_graph(args)
    png_out, html_out = check_drawings(args, (seg_out, vol_out, graph_out))
    return dict(labels=seg_out, volume=vol_out, graph=graph_out, picture=png_out,
                html=html_out)


def segment_volume(args) -> int:
    """``segment`` of a tetrahedral mesh: labels per tetrahedron, the mesh with the labels
    as cell data (``--colored-mesh OUT.vtu``), the superfacet graph and its levels
    (``--graph``, ``--levels``), a picture and a page of it cut in half."""
    from ..io.tetmeshes import read_volume
    from ..method.params import resolve

    out = _checked(args)
    kwargs = dict(method_kwargs(args))
    resolve(n_segments=args.n_segments, radius=args.radius, **kwargs)
    t0 = time.perf_counter()
    data = read_volume(args.mesh)
    kwargs, size_note = sizes_of(args, data, "cells", kwargs)
    result = run_segment(args, data, kwargs)
    elapsed = time.perf_counter() - t0
    _write(args, data, result, out)
    report = sys.stderr if str(out["labels"]) == "-" else sys.stdout
    if not args.quiet:
        sizes = sizes_said(result.labels, "tetrahedra", result) if result.n_segments > 1 else ""
        print(f"{Path(args.mesh).name}: {data.n_tets:,} tetrahedra, {result.n_segments:,} "
              f"superfacets{sizes}, {result.n_iter} iterations, {elapsed:.2f} s", file=report)
        if size_note:
            print(size_note, file=report)
        what = (("labels", "labels, one per tetrahedron"),
                ("volume", "volume with cell data 'superfacet'"),
                ("graph", "superfacet graph" + (", levels " + ",".join(map(str, args.levels))
                                                if args.levels else "")),
                ("picture", "picture of the volume cut in half"),
                ("html", "page of the volume cut in half: open it in a browser"))
        written = [f"{out[k]} ({w})" for k, w in what if out[k] is not None
                   and str(out[k]) != "-"]
        print("wrote " + ", ".join(written) if written else
              "note: nothing was saved: add -o OUT.seg, --colored-mesh OUT.vtu, --graph "
              "OUT.npz, --picture OUT.png or --html OUT.html",
              file=report if written else sys.stderr)
        from .notes import count_note

        note = count_note(args, data, result, "cells")
        if note:
            print(f"note: {note}", file=sys.stderr)
    return 0


def _write(args, data, result, out: dict) -> None:
    """Every output of the run, all or nothing."""
    import numpy as np

    from ..errors import SuperfacetsError
    from ..io.files import Outputs
    from ..io.labels import write_labels
    from ..io.tetmeshes import write_volume_labels
    from ..viz.outputs import graph_arrays

    try:
        h = result.hierarchy(args.levels, cost=args.level_cost or "ward",
                             extent_weight=args.extent_weight) if args.levels else None
    except SuperfacetsError as exc:
        raise named_after(args.mesh, exc) from None
    with Outputs() as outputs:
        if out["labels"] is not None:
            write_labels(out["labels"], result.labels, outputs=outputs)
        if out["volume"] is not None:
            write_volume_labels(out["volume"], data, result.labels, outputs=outputs)
        if out["graph"] is not None:
            arrays = graph_arrays(result, h)
            outputs.write(out["graph"], lambda fh: np.savez_compressed(fh, **arrays))
        title = (f"{Path(args.mesh).name}: {result.n_segments} superfacets, cut at the "
                 "middle of x")  # (both draw the volume's cut)
        if out["picture"] is not None:
            from ..viz.render import render

            render(data, result.labels, out["picture"], outputs=outputs, up=args.up or "y",
                   view=args.view, title=title)
        if out["html"] is not None:
            from ..viz.html import write_html

            write_html(out["html"], data, result.labels, title=title, outputs=outputs,
                       up=args.up or "y", view=args.view)
