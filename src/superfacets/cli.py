"""The ``superfacets`` command line.

Sub-commands:

- ``superfacets segment MESH ...``: superfacets of a mesh file, written as a
  ``.seg`` label file and/or a coloured PLY;
- ``superfacets evaluate MESH LABELS.seg GT.seg...``: the metrics of a result;
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
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")
    p.add_argument("--progress", action="store_true", help="show a progress bar of the iterations")


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
    return parser


def _cmd_evaluate(args) -> int:
    from .errors import ParameterError
    from .io import read_labels, read_mesh
    from .metrics import (achievable_segmentation_accuracy, boundary_recall, compactness,
                          mean_over_ground_truths, undersegmentation_error)

    if not (0 <= args.tau < 1):
        raise ParameterError(f"--tau must be in [0, 1), got {args.tau}")
    mesh = read_mesh(args.mesh)
    labels = read_labels(args.labels, n_faces=mesh.n_faces)
    gts = [read_labels(p, n_faces=mesh.n_faces) for p in args.ground_truths]
    ue = mean_over_ground_truths(undersegmentation_error, mesh, labels, gts, tau=args.tau)
    br = mean_over_ground_truths(boundary_recall, mesh, labels, gts)
    asa = mean_over_ground_truths(achievable_segmentation_accuracy, mesh, labels, gts)
    print(f"{Path(args.mesh).name}: {mesh.n_faces} faces, {len(np.unique(labels))} superfacets, "
          f"{len(gts)} ground truths")
    print(f"undersegmentation_error {ue:.4f}  (lower is better)")
    print(f"compactness             {compactness(mesh, labels):.4f}  (lower is better; disk 3.545)")
    print(f"boundary_recall         {br:.4f}  (higher is better)")
    print(f"achievable_accuracy     {asa:.4f}  (higher is better)")
    return 0


def _method_kwargs(args) -> dict:
    return dict(alpha=args.alpha, eta_convex=args.eta_convex, window=args.window,
                init=args.init, max_iter=args.max_iter, weighting=args.weighting,
                assignment=args.assignment, enforce_connectivity=not args.no_connectivity,
                progress=args.progress)


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
    try:
        result = segment(mesh, args.n_segments, radius=args.radius, **_method_kwargs(args))
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
    if not args.quiet:
        print(f"built the demo mesh in {t_shape:.2f} s")
        print(_summary("creature", mesh, result, elapsed))
        print(f"wrote {out / 'creature.off'} (mesh), {out / 'creature.seg'} (labels), "
              f"{out / 'creature_superfacets.ply'} (open in MeshLab or Blender)")
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

    parser = _build_parser()
    args = parser.parse_args(argv)
    try:
        if args.command == "segment":
            return _cmd_segment(args)
        if args.command == "evaluate":
            return _cmd_evaluate(args)
        return _cmd_demo(args)
    except (SuperfacetsError, OSError) as exc:
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
