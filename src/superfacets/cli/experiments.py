"""Commands over the benchmark: experiment (a grid of runs, resumable) and report."""

from __future__ import annotations

import sys
from pathlib import Path

from ..checks import AXES
from ..method.params import DEFAULT_N_SEGMENTS
from .options import add_engine_options, float_arg, int_arg
from .parameters import Joined, float_list_arg, int_list_arg

__all__ = ["add_parsers"]


def add_parsers(sub) -> None:
    """Add ``experiment`` and ``report`` to the sub-parsers."""
    x = sub.add_parser(
        "experiment", help="run methods x parameters over the Princeton benchmark",
        description="Run a grid of methods and parameters over the meshes of the Princeton "
                    "Mesh Segmentation Benchmark, in parallel worker processes, appending one "
                    "row per (mesh, method, parameters, k) with every metric to a CSV file. "
                    "Rerunning with the same file continues where it stopped; a failure on "
                    "one mesh is recorded and the run goes on. The defaults reproduce the "
                    "paper's sweep (k in 50..300, alpha in 0, 100, 200, 500, 1000).")
    x.add_argument("--psb", metavar="DIR", default=None,
                   help="the benchmark: a folder holding off/ and seg/, or an archive of "
                        "psb/off and psb/seg (default: $SUPERFACETS_PSB, else the copy "
                        "unpacked in ~/.cache/superfacets, else, in a source checkout, "
                        "../shared/data/psb.tar.xz)")
    x.add_argument("-o", "--results", metavar="FILE.csv", default="results.csv",
                   help="results file, appended to (default: results.csv)")
    x.add_argument("-m", "--method", action="append", default=None, metavar="NAME",
                   help="method from the registry, repeatable (default: superfacets; "
                        "see --list-methods)")
    x.add_argument("-k", "--n-segments", type=int_list_arg, nargs="+", action=Joined,
                   default=None, metavar="K",
                   help="numbers of superfacets (default: "
                        f"{' '.join(map(str, DEFAULT_N_SEGMENTS))})")
    x.add_argument("--alpha", type=float_list_arg, nargs="+", action=Joined,
                   default=None, metavar="A",
                   help="alpha values, for the methods that have alpha (default: each "
                        "method's sweep; superfacets: 0 100 200 500 1000)")
    x.add_argument("--param", action="append", default=[], metavar="NAME=V1,V2",
                   help="values of a method parameter, for each method that has it "
                        "(METHOD.NAME=... for one method), repeatable (e.g. init=grid,flood)")
    x.add_argument("--dataset", choices=("psb", "rooms", "files"), default=None,
                   help="psb: the Princeton benchmark's meshes (default); rooms: made-up "
                        "labelled rooms (S3DIS-like point clouds with colour, judged against "
                        "their classes; --elements points); files: your own (--inputs)")
    _add_inputs(x)
    x.add_argument("--rooms", type=int_arg, default=10, metavar="N",
                   help="with --dataset rooms: the first N rooms (default: 10)")
    x.add_argument("--ids", default=None, metavar="LIST",
                   help="mesh ids, e.g. 1-20,45 (default: all)")
    x.add_argument("--categories", default=None, metavar="LIST",
                   help="comma-separated categories, e.g. Human,Cup (default: all)")
    x.add_argument("--per-category", type=int_arg, default=None, metavar="N",
                   help="only the first N meshes (by id) of each category: a stratified subset")
    add_engine_options(x, sees="its workers must see the benchmark's files",
                       note="; at most 4 per core")
    x.add_argument("--elements", default=None, metavar="LIST",
                   help="element kinds, comma-separated: faces, vertices (ground truth: "
                        "majority of the incident faces), points (--points sampled per mesh, "
                        "ground truth of their face); vertices and points are evaluated "
                        "with equal weight per element; cells: a tetrahedral mesh's "
                        "(--inputs) (default: faces; with --inputs, each file's own: a "
                        "mesh's faces, a cloud's points, a volume's cells)")
    x.add_argument("--points", type=int_arg, default=20_000, metavar="N",
                   help="points sampled per mesh (uniform by area, fixed seed) for "
                        "--elements points (default: 20000)")
    x.add_argument("--tau", type=float_arg, default=0.05,
                   help="undersegmentation error tolerance (default: 0.05)")
    x.add_argument("--seed", type=int_arg, default=0, help="seed given to randomized methods")
    x.add_argument("--retry-failed", action="store_true",
                   help="run again the rows recorded as failed")
    x.add_argument("--list-methods", action="store_true",
                   help="list the registered methods and their parameters, and exit")
    x.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    x.set_defaults(func=cmd_experiment)

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
    r.add_argument("--k-focus", type=int_arg, default=150, metavar="K",
                   help="k of the per-category and all-metrics tables (default: 150)")
    r.set_defaults(func=cmd_report)


def _add_inputs(x) -> None:
    """``--inputs`` and ``--ground-truth-field``: an experiment on the user's own files."""
    x.add_argument("--inputs", nargs="+", default=None, metavar="PATH",
                   help="your own meshes, point clouds and tetrahedral meshes (files, "
                        "folders, globs, @list.txt; every format 'segment' reads): --dataset "
                        "files. A cloud's points are segmented, a volume's cells; a mesh's "
                        "--elements")
    x.add_argument("--ground-truth-field", metavar="NAME", default=None,
                   help="with --inputs: each file's ground truth, a field of its own (a "
                        "LAS/LAZ classification, a PLY vertex label, a PCD label, an NPY "
                        "record's field, a text cloud's named column, a "
                        "volume's gmsh:physical); without it, rows have the "
                        "compactness alone")
    x.add_argument("--ground-truths", metavar="PATTERN", default=None,
                   help="with --inputs: each file's ground truth, a label file named by "
                        "PATTERN from the file's folder, {stem} its name without suffix "
                        "(SemanticKITTI: '../labels/{stem}.label'; a .seg beside each: "
                        "'{stem}.seg'), or a list file (.csv, .tsv, .txt) of INPUT "
                        "GROUND_TRUTH lines")
    x.add_argument("--ignore-label", type=int_arg, default=None, metavar="L",
                   help="with --inputs and a ground truth: its value L marks unlabelled "
                        "elements, left out of the metrics (SemanticKITTI: 0)")
    x.add_argument("--seen-from", choices=tuple(AXES), default=None, metavar="AXIS",
                   help="with --inputs: the side the point clouds were scanned from (x, y, "
                        "z, -x, -y, -z), as segment --seen-from: each segmented as a scan "
                        "with that up direction; the rows record it (default: each file's "
                        "own: z for .las/.laz)")


def _id_list(text: str) -> set[int]:
    from ..errors import ParameterError

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


def _check_dataset_options(args, dataset: str) -> None:
    """Refuse the options of another dataset than the one run (taken, they would change
    nothing): the benchmark's selection and sampling on rooms or files, ``--rooms`` on
    another dataset, ``--tau`` where no ground truth judges the rows."""
    from ..errors import ParameterError

    psb_only = [f for f, on in (("--ids", getattr(args, "ids", None)),
                                ("--categories", getattr(args, "categories", None)),
                                ("--per-category", getattr(args, "per_category", None)
                                 is not None)) if on]
    sampled = "points" in (getattr(args, "elements", None) or "faces").split(",")
    if getattr(args, "points", 20_000) != 20_000:
        if dataset != "psb":
            psb_only.append("--points")
        elif not sampled:
            raise ParameterError("--points samples each benchmark mesh for --elements points; "
                                 "add it")
    if psb_only and dataset != "psb":
        verbs = "selects or samples" if len(psb_only) == 1 else "select or sample"
        raise ParameterError(f"{', '.join(psb_only)} {verbs} the benchmark's meshes; not "
                             f"with --dataset {dataset}")
    if getattr(args, "rooms", 10) != 10 and dataset != "rooms":
        raise ParameterError("--rooms goes with --dataset rooms")
    truth = getattr(args, "ground_truth_field", None) or getattr(args, "ground_truths", None)
    if getattr(args, "tau", 0.05) != 0.05 and dataset == "files" and not truth:
        raise ParameterError("--tau judges against a ground truth: with --inputs give "
                             "--ground-truth-field NAME or --ground-truths PATTERN")
    if getattr(args, "ignore_label", None) is not None and not (dataset == "files" and truth):
        raise ParameterError("--ignore-label marks a ground truth's unlabelled elements: it "
                             "goes with --inputs and --ground-truth-field or --ground-truths")


def select_meshes(args):
    """The benchmark meshes chosen by ``--psb``, ``--ids``, ``--categories``, ``--per-category``."""
    from ..errors import ParameterError
    from ..evaluation.datasets.psb import first_per_category, list_meshes, psb_root

    dataset = getattr(args, "dataset", None) or (
        "files" if getattr(args, "inputs", None) else "psb")
    if (dataset == "files") != bool(getattr(args, "inputs", None)):
        raise ParameterError("--inputs PATH ... goes with --dataset files (its default)")
    for name in ("ground_truth_field", "ground_truths", "seen_from"):
        if getattr(args, name, None) and dataset != "files":
            raise ParameterError(f"--{name.replace('_', '-')} goes with --inputs")
    _check_dataset_options(args, dataset)
    if dataset == "files":
        from ..scale.runner.collect import file_entries

        return file_entries(args.inputs, args.ground_truth_field,
                            truths=getattr(args, "ground_truths", None))
    if dataset == "rooms":
        from ..evaluation.datasets.rooms import room_entries

        if "points" not in (args.elements or "faces").split(","):
            raise ParameterError("--dataset rooms holds point clouds: add --elements points")
        return room_entries(args.rooms)
    root = psb_root(args.psb)
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
        meshes = first_per_category(meshes, args.per_category)
    if not meshes:
        raise ParameterError(f"{root}: no mesh selected")
    return meshes


#: Distinct errors of failed rows that ``experiment`` prints.
FAILURES_SAID = 5


def cmd_experiment(args) -> int:
    from ..evaluation.methods import METHODS, get_method
    from ..scale.runner import expand_grid, method_grid, parse_params, run_experiment

    if args.list_methods:
        for name, m in sorted(METHODS.items()):
            params = ", ".join(f"{k}={v}" for k, v in m.defaults.items())
            print(f"{name}: {m.description}\n    parameters: {params}")
            for k, v in m.sweep.items():
                print(f"    default sweep: {k} in {', '.join(map(str, v))}")
        return 0
    methods = [get_method(name) for name in args.method or ["superfacets"]]
    given = method_grid(methods, parse_params(args.param))
    configs = []
    for method in methods:
        grid = {k: list(v) for k, v in method.sweep.items()}
        if args.alpha is not None and "alpha" in method.defaults:
            grid["alpha"] = args.alpha
        grid.update(given[method.name])
        configs += expand_grid(method.name, **grid)
    meshes = select_meshes(args)
    ks = args.n_segments or list(DEFAULT_N_SEGMENTS)
    out = Path(args.results)
    if not args.quiet:
        what = ("inputs" if getattr(meshes[0], "file", False) else
                "rooms" if getattr(meshes[0], "room", False) else "meshes")
        print(f"{len(meshes)} {what} x {len(configs)} settings x {len(ks)} values of k "
              f"-> {out}", file=sys.stderr)
    files = getattr(meshes[0], "file", False)
    kinds = [e.strip() for e in (args.elements or ("faces,points,cells" if files else "faces"))
             .split(",") if e.strip()]
    if files:
        _say_left_out(meshes, kinds)
    s = run_experiment(meshes, configs, out, ks, workers=args.workers, tau=args.tau,
                       ignore_label=args.ignore_label,
                       seed=args.seed, retry_failed=args.retry_failed,
                       progress=not args.quiet and sys.stderr.isatty(),
                       elements=kinds, n_points=args.points, scheduler=args.scheduler,
                       seen_from=getattr(args, "seen_from", None))
    if s.note:
        print(f"note: {s.note}", file=sys.stderr)
    print(f"{s.written} rows written ({s.ok} ok, {s.failed} failed, {s.skipped} skipped), "
          f"{s.done_before} already there, in {s.seconds:.1f} s -> {out}")
    for said, n in list(s.warned.items())[:FAILURES_SAID]:
        print(f"warning: {n} row{'s' if n != 1 else ''}: {said}", file=sys.stderr)
    if len(s.warned) > FAILURES_SAID:
        print(f"... and {len(s.warned) - FAILURES_SAID} more warnings", file=sys.stderr)
    for error, n in list(s.failures.items())[:FAILURES_SAID]:  # (every row's in the file)
        print(f"failed: {n} row{'s' if n != 1 else ''}: {error}", file=sys.stderr)
    if len(s.failures) > FAILURES_SAID:
        print(f"... and {len(s.failures) - FAILURES_SAID} more errors (see {out}'s error "
              "column)", file=sys.stderr)
    if s.interrupted:
        print("superfacets: interrupted: run the same command again to continue",
              file=sys.stderr)
        return 130
    if not args.quiet:
        print(f"next: superfacets report {out}")
    return 0


def _say_left_out(entries, kinds) -> None:
    """One line for each of the user's files that no element kind asked for fits (a cloud
    without ``points``, a mesh with ``points`` alone): it gets no row."""
    from ..elements.kinds import KINDS

    for e in entries:
        cloud, volume = e.category == "cloud", e.category == "volume"
        if not any(k in KINDS and KINDS[k].cloud == cloud and (KINDS[k].dim == 3) == volume
                   for k in kinds):
            fits, what = (("points", "point cloud") if cloud else ("cells", "tetrahedral mesh")
                          if volume else ("faces or vertices", "mesh"))
            print(f"left out: {e.path} (a {what}: --elements {fits})", file=sys.stderr)


def cmd_report(args) -> int:
    from .._runtime.progress import waiting_bar
    from ..evaluation.report import write_report

    res = [Path(p) for p in args.results]
    out = Path(args.output_dir) if args.output_dir else res[0].with_name(res[0].stem + "_report")
    from ..errors import ParameterError

    try:
        with waiting_bar(f"writing the report to {out}", sys.stderr.isatty()):  # (seconds)
            files = write_report(res, out, k_focus=args.k_focus, series=args.series)
    except ParameterError as exc:
        if "the results file" in str(exc):  # (which one: several may be given)
            raise ParameterError(f"{', '.join(map(str, res))}: {exc}") from None
        raise
    print((out / "summary.md").read_text())
    print(f"wrote {len(files)} file{'s' if len(files) != 1 else ''} to {out}: "
          + ", ".join(f.name for f in files))
    return 0
