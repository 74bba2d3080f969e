"""``segment`` of a tetrahedral mesh (``.msh``, ``.vtk``, ``.vtu``, ``.mesh``)."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from .options import check_labels_output, check_output, method_kwargs, named_after


def segment_volume(args) -> int:
    """``segment`` of a tetrahedral mesh: labels per tetrahedron, the mesh with the labels
    as cell data (``--colored-mesh OUT.vtu``), a picture of it cut in half."""
    from ..api.segmentation import segment
    from ..errors import ParameterError, SuperfacetsError
    from ..io.files import Outputs
    from ..io.labels import write_labels
    from ..io.tetmeshes import read_volume, write_volume_labels
    from ..method.params import resolve

    for flag, given in (("--html", args.html), ("--graph", args.graph),
                        ("--per-object", args.per_object),
                        ("--vertex-colors", args.vertex_colors)):
        if given:
            raise ParameterError(f"{flag} is not available for tetrahedral meshes")
    if getattr(args, "elements", None) not in (None, "cells"):
        raise ParameterError(f"--elements {args.elements}: a tetrahedral mesh is segmented by "
                             "its tetrahedra")
    seg_out = check_labels_output(args.output, args.mesh)
    vol_out = check_output(args.colored_mesh, (".vtu", ".vtk", ".msh", ".mesh"),
                           "the labelled volume", inputs=(args.mesh,))
    png_out = check_output(args.picture, (".png",), "the picture", inputs=(args.mesh,))
    kwargs = dict(method_kwargs(args))
    resolve(n_segments=args.n_segments, radius=args.radius, **kwargs)
    t0 = time.perf_counter()
    data = read_volume(args.mesh)
    try:
        result = segment(data, args.n_segments, radius=args.radius, **kwargs)
    except SuperfacetsError as exc:
        raise named_after(args.mesh, exc) from None
    elapsed = time.perf_counter() - t0
    with Outputs() as outputs:
        if seg_out is not None:
            write_labels(seg_out, result.labels, outputs=outputs)
        if vol_out is not None:
            write_volume_labels(vol_out, data, result.labels, outputs=outputs)
        if png_out is not None:
            from ..inputs.tetmesh import cut_surface
            from ..viz.render import render

            surface, face_labels = cut_surface(data, result.labels, axis=0, at=0.5)
            render(surface, face_labels, png_out, outputs=outputs, up=args.up or "y",
                   view=args.view, title=f"{Path(args.mesh).name}: {result.n_segments} "
                                         "superfacets, cut at the middle of x")
    report = sys.stderr if str(seg_out) == "-" else sys.stdout
    if not args.quiet:
        print(f"{Path(args.mesh).name}: {data.n_tets} tetrahedra, {result.n_segments} "
              f"superfacets, {result.n_iter} iterations, {elapsed:.2f} s", file=report)
        written = [f"{p} ({w})" for p, w in ((seg_out, "labels, one per tetrahedron"),
                                             (vol_out, "volume with cell data 'superfacet'"),
                                             (png_out, "picture of the volume cut in half"))
                   if p is not None and str(p) != "-"]
        print("wrote " + ", ".join(written) if written else
              "note: nothing was saved: add -o OUT.seg, --colored-mesh OUT.vtu or --picture "
              "OUT.png", file=report if written else sys.stderr)
        from .notes import count_note

        note = count_note(args, data, result, "cells")
        if note:
            print(f"note: {note}", file=sys.stderr)
    return 0
