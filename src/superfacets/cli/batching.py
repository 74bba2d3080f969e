"""``superfacets batch``: segment many files, resumable, on this machine or on Dask."""

from __future__ import annotations

import sys

from ..checks import AXES
from .options import (
    add_adaptive_options,
    add_camera_options,
    add_element_options,
    add_engine_options,
    add_method_options,
    add_unit_options,
    element_kwargs,
    levels_arg,
    method_kwargs,
)

__all__ = ["add_parsers"]


def add_parsers(sub) -> None:
    """Add ``batch`` to the sub-parsers."""
    b = sub.add_parser(
        "batch", help="segment many mesh or point-cloud files (resumable; on Dask)",
        description="Segment every INPUT with the same options as 'segment' and write, under "
                    "OUTDIR, one label file per input (named after its path relative to the "
                    "inputs' common folder) and a manifest (manifest.parquet, or manifest.csv "
                    "without pyarrow) with one row per input: path, status (ok, failed, "
                    "skipped), elements, segments, passes, seconds, peak memory, error. "
                    "Running it again skips what is done. Runs on a local Dask cluster of one "
                    "worker process per core (the 'distributed' extra), on a running cluster "
                    "(--scheduler), or in this process (--workers 1). Exit status 0 when "
                    "every input is ok, 1 when some failed, 2 on bad options.")
    b.add_argument("inputs", metavar="INPUT", nargs="+",
                   help="a file, a folder (searched recursively for every format 'segment' "
                        "reads; .txt files only when named), a glob ('scans/**/*.ply', quoted) "
                        "or @LIST.txt (one of these per line)")
    b.add_argument("-o", "--output-dir", required=True, metavar="OUTDIR",
                   help="output folder, created if missing")
    add_method_options(b)
    add_element_options(b)
    add_unit_options(b)  # (each input's own count and neighbours, in its units)
    for action in b._actions:  # one task per core already: one thread each by default
        if action.dest == "threads":
            action.default = 1
            action.help = "threads of each segmentation (default: 1; the labels do not " \
                          "depend on it)"
    b.add_argument("--labels", choices=("seg", "json", "npy", "records", "laz"),
                   default="seg",
                   help="label file per input: one label per line (.seg), ScanNet's "
                        "segIndices (.json), a NumPy int64 array (.npy), records: each "
                        "LAS/LAZ, PLY, PCD or NPY-records cloud's own records with a "
                        "ClusterID field "
                        "(.seg for the others), or laz: a .laz with ClusterID for every "
                        "cloud (a LAS/LAZ input's records, any other cloud's points; "
                        "meshes .seg) (default: seg)")
    b.add_argument("--header", action="store_true",
                   help="start each .seg file with '#' lines (parameters, passes, time)")
    b.add_argument("--colored-mesh", choices=("ply", "glb", "obj"), default=None,
                   help="also write each input coloured by superfacet (NAME_superfacets.EXT; "
                        "vertices and points: ply)")
    b.add_argument("--vertex-colors", action="store_true",
                   help="PLY: colours per vertex instead of per face")
    b.add_argument("--picture", action="store_true",
                   help="also render NAME.png per input (the render extra)")
    b.add_argument("--html", action="store_true",
                   help="also write NAME.html per input, an interactive page")
    add_camera_options(b, "")  # --view, --up of --picture and --html
    b.add_argument("--seen-from", choices=tuple(AXES), default=None, metavar="AXIS",
                   help="point clouds: the side they were scanned from (x, y, z, -x, -y, "
                        "-z), as segment --seen-from: each cloud segmented as a scan with "
                        "that up direction (default: a LAS file's z, else none); meshes as "
                        "they are")
    b.add_argument("--graph", action="store_true",
                   help="also write NAME.npz per input: the superfacet (superpoint) graph in "
                        "PyTorch Geometric's layout, as segment --graph writes it (with "
                        "--levels, the hierarchy too)")
    b.add_argument("--per-object", action="store_true",
                   help="scenes: segment each object on its own (-k shared out by area)")
    add_engine_options(b, sees="its workers read the inputs and write OUTDIR, so both "
                                "must be on a shared filesystem")
    add_adaptive_options(b, levels=False)
    b.add_argument("--levels", type=levels_arg, default=None, metavar="N1,N2,...",
                   help="with --labels records or laz: each cloud's coarser, nested levels of "
                        "N1, N2, ... segments, each a field ClusterID_N after the labels; "
                        "with --graph, in each NAME.npz")
    b.add_argument("--memory-limit", default="auto", metavar="SIZE",
                   help="memory of each local worker, e.g. 4GiB; a worker going over is "
                        "restarted and its input fails after Dask's retries (default: auto, "
                        "the machine's memory shared out)")
    b.add_argument("--retry-failed", action="store_true",
                   help="run again the inputs that failed in an earlier run")
    b.set_defaults(func=cmd_batch)


def cmd_batch(args) -> int:
    from ..scale.runner.batch import run_batch

    if args.per_object and args.radius is not None:
        from ..errors import ParameterError

        raise ParameterError("--per-object takes -k, not --radius")
    kwargs = dict(method_kwargs(args), **element_kwargs(args))
    kwargs.pop("progress")
    s = run_batch(args.inputs, args.output_dir, args.n_segments, radius=args.radius,
                  labels=args.labels, header=args.header, colored_mesh=args.colored_mesh,
                  vertex_colors=args.vertex_colors, picture=args.picture, html=args.html,
                  graph=args.graph, up=args.up, view=args.view,
                  per_object=args.per_object, adaptive=args.adaptive,
                  extent_weight=args.extent_weight, levels=args.levels,
                  seed_resolution=args.seed_resolution,
                  neighbor_distance=args.neighbor_distance, seen_from=args.seen_from,
                  workers=args.workers,
                  scheduler=args.scheduler,
                  memory_limit=args.memory_limit, retry_failed=args.retry_failed,
                  progress=not args.quiet and (sys.stderr.isatty() if args.progress is None
                                               else args.progress), **kwargs)
    if not args.quiet:
        ran = s.ok + s.failed
        print(f"batch: {_count(s.inputs, 'input')}: {s.ok} ok, {s.failed} failed, "
              f"{s.done_before} already "
              f"done" + (f", {s.inputs - ran - s.done_before} not run" if s.interrupted else "")
              + (f"; {ran} run {s.engine} in {s.seconds:.1f} s" if ran else "")
              + f" -> {s.manifest}")
        if args.picture or args.html:
            print("pictures and pages drawn with up axis " + (
                args.up or "of each input's file or format (else y; --up for another)"))
        for path, said in s.warned[:10]:
            print(f"warning: {path}: {said}", file=sys.stderr)
        if len(s.warned) > 10:
            print(f"... and {len(s.warned) - 10} more warnings (the manifest's 'warnings')",
                  file=sys.stderr)
        for path, error in s.failures[:10]:
            print(f"failed: {path}: {error}", file=sys.stderr)
        if len(s.failures) > 10:
            print(f"... and {len(s.failures) - 10} more failed (see the manifest)",
                  file=sys.stderr)
        _say_passed(s.passed)
        for folder, reason in s.skipped:
            print(f"note: {folder}: not read ({reason}); its files are not inputs",
                  file=sys.stderr)
        if s.failed_before:
            print(f"note: {_count(s.failed_before, 'input')} failed in an earlier run; "
                  "--retry-failed runs them again", file=sys.stderr)
    if s.interrupted:
        print("superfacets: interrupted: run the same command again to continue",
              file=sys.stderr)
        return 130
    return 1 if s.failed or s.failed_before else 0


def _count(n: int, word: str) -> str:
    """``1 input``, ``2 inputs``."""
    return f"{n} {word}" + ("" if n == 1 else "s")


#: Files not inputs listed one by one; past this many, the rest are counted by reason.
LISTED = 20


def _say_passed(passed: list) -> None:
    """Each file of the searched folders that is not an input, with the reason (past
    :data:`LISTED`, the rest counted by reason)."""
    for path, reason in passed[:LISTED]:
        print(f"skipped: {path} ({reason})", file=sys.stderr)
    rest: dict = {}
    for _, reason in passed[LISTED:]:
        rest[reason] = rest.get(reason, 0) + 1
    for reason, n in rest.items():
        print(f"skipped: {_count(n, 'more file')} ({reason})", file=sys.stderr)
