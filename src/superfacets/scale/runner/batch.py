"""Segment many files: ``superfacets batch``, resumable, on this machine or on Dask.

:func:`run_batch` segments every input with the same options as
``superfacets segment`` and writes, under one output folder:

- per input, its labels (``.seg``, or ScanNet's ``.json``) and optionally a
  coloured mesh or cloud, a picture and a page, each written atomically,
  named after the input's path relative to the inputs' common folder (so
  names cannot collide; :mod:`.inputs` finds the inputs and names them);
- ``manifest.parquet`` (``manifest.csv`` where pyarrow is missing): one row
  per input, with :data:`~.manifest.MANIFEST_COLUMNS` (:mod:`.manifest`);
- ``batch.json``: the options, so that a rerun with other options is refused
  rather than mixing results.

Each finished input is appended at once to a journal (``.manifest.jsonl``)
that the manifest is made from, so a run interrupted at any point (Ctrl-C,
``kill -9``, a power cut) loses nothing: a rerun skips every input done, runs
the rest, and runs the failed ones again on request (``retry_failed``).
The tasks go to :class:`~.engine.Engine` by path; a worker reads its input
and writes its outputs itself, so the scheduler never holds meshes.
"""

from __future__ import annotations

import contextlib
import json
import time
from dataclasses import dataclass, field, replace
from datetime import datetime, timezone
from pathlib import Path
from typing import Sequence

from ..._runtime import extras, interrupts
from ..._runtime.progress import new_bar, tick
from ..._runtime.warned import task_warnings
from ...api.levels import adaptive_segment
from ...api.scenes import segment_objects
from ...api.segmentation import segment
from ...api.sizes import count_for_resolution, default_count, diagonal_fraction
from ...checks import AXES
from ...elements.builders import kind_for
from ...elements.kinds import kind_of
from ...errors import ParameterError
from ...graph.hierarchy import wanted_levels
from ...inputs.cloud import PointCloud
from ...io import read_input
from ...io.clouds import is_cloud_file
from ...io.files import not_a_folder, split_suffix
from ...io.orientation import default_view, up_axis
from ...io.records import RECORD_FORMATS, records_kind
from ...method.params import (
    DEFAULTS,
    check_choice,
    check_int,
    check_nonneg,
    check_positive,
    resolve,
)
from ...viz.camera import check_camera
from ...viz.outputs import JoinedResult, write_result
from .collect import broken_link_reason, collect_inputs, no_inputs, output_names
from .engine import Engine, PeakMemory, check_memory_limit, error_text
from .manifest import (
    JOURNAL,
    MANIFEST_COLUMNS,
    FolderLock,
    check_options,
    read_manifest,
    record_options,
    write_manifest,
)

__all__ = ["run_batch", "collect_inputs", "output_names", "read_manifest", "BatchSummary",
           "MANIFEST_COLUMNS", "segment_file"]

_LABEL_SUFFIX = {"seg": ".seg", "json": ".json", "npy": ".npy", "records": None, "laz": None}


def _label_suffix(labels: str, source) -> str:
    """The suffix of an input's labels: ``.seg``, ``.json``, for ``records`` its own
    format where labels go into it (``.las``, ``.laz``, ``.ply``, NPY records'
    ``.npy``), for ``laz`` ``.laz``
    for every cloud; else ``.seg``."""

    if labels not in ("records", "laz"):
        return _LABEL_SUFFIX[labels]
    fmt = split_suffix(Path(source))[0]
    if labels == "laz":
        return ".laz" if _a_cloud(source) else ".seg"
    if fmt == "ply":  # a cloud's records are its points; a mesh's faces have none of theirs
        return ".ply" if _a_cloud(source) else ".seg"
    if fmt == "npy":  # NPY records (a structured array) as records; an array of points: .seg
        return ".npy" if records_kind("records.npy", source) == "npy" else ".seg"
    return f".{fmt}" if fmt in RECORD_FORMATS else ".seg"


def _a_cloud(source) -> bool:
    """Whether the file ``source`` holds a point cloud (an unreadable header: no, its
    task says why)."""
    try:
        return is_cloud_file(source)
    except Exception:  # noqa: BLE001 - an unreadable header: its task says why
        return False


def segment_file(task: dict) -> dict:
    """Read, segment and write one input; its manifest row (never raises).

    The worker function of :func:`run_batch` (a module-level function: Dask
    workers import it by reference).

    Parameters
    ----------
    task : dict
        ``input`` (absolute path), ``outdir``, ``name``, ``options`` (keyword
        arguments of :func:`superfacets.segment`), ``outputs`` (``labels``:
        'seg', 'json' or 'records' (a LAS/LAZ/PLY input's own records with
        ``ClusterID``, others .seg); ``header``, ``colored`` suffix or None, ``picture``,
        ``html``, ``vertex_colors``), ``per_object``.

    Returns
    -------
    dict
        A row with :data:`MANIFEST_COLUMNS`.
    """
    outs = task["outputs"]
    label_rel = task["name"] + _label_suffix(outs["labels"], task["input"])
    row = dict.fromkeys(MANIFEST_COLUMNS)
    row.update(input=task["input"], output=label_rel)
    probe = PeakMemory()
    t0 = time.perf_counter()
    with task_warnings() as said:  # (the row keeps them, named by its input: a worker's
        try:                           # printed warnings would not be)
            row.update(_segment_and_write(task, label_rel))
            row["status"] = "ok"
        except Exception as exc:  # noqa: BLE001 - a failed row; the batch goes on
            row.update(status="failed", error=error_text(exc))
        except MemoryError as exc:  # pragma: no cover - depends on the machine
            row.update(status="failed", error=error_text(exc))
    row["warnings"] = "\n".join(dict.fromkeys(said)) or None
    row["seconds"] = round(time.perf_counter() - t0, 4)
    peak = probe.peak_mib(above_start=False)
    row["peak_mib"] = None if peak is None else round(peak, 1)
    row["finished"] = datetime.now(timezone.utc).isoformat(timespec="seconds")
    return row


def _segment_and_write(task: dict, label_rel: str) -> dict:
    outs = task["outputs"]
    opts = dict(task["options"])
    base = Path(task["outdir"]) / task["name"]
    why = broken_link_reason(task["input"])
    if why is not None:
        raise ParameterError(f"{task['input']}: {why}")
    data = read_input(task["input"])
    if outs.get("seen_from") and isinstance(data, PointCloud):  # (meshes as they are)
        data = replace(data, up=outs["seen_from"], viewpoint=None)
    kind = kind_for(data, opts.get("elements"))
    if kind_of(kind).dim == 3 and outs["colored"]:
        raise ParameterError("tetrahedral meshes: batch writes their labels, graphs, pictures "
                             "and pages (cut in half); `superfacets segment VOLUME "
                             "--colored-mesh OUT.vtu` writes the labels as cell data")
    if not kind_of(kind).objects:
        if task["per_object"] and not (kind_of(kind).cloud and getattr(data, "objects", ())):
            raise ParameterError("--per-object segments the faces of a scene or the scans of "
                                 f"a multi-scan cloud (E57); not {kind}")
        if outs["colored"] not in (None, "ply"):
            raise ParameterError(f"coloured {kind} are written as .ply")
    opts = _sized(opts, outs.get("sizes") or {}, data, kind)
    if task["per_object"]:
        opts.pop("radius", None)
        k = opts.pop("n_segments", None)
        result = JoinedResult(*segment_objects(data, *(() if k is None else (k,)), **opts))
    elif task.get("adaptive"):
        opts.pop("radius", None)
        k = opts.pop("n_segments", None) or DEFAULTS.n_segments
        result = adaptive_segment(data, k, start=task["adaptive"]["start"],
                                  extent_weight=task["adaptive"]["compactness"], **opts)
    else:
        if opts.get("n_segments") is None and opts.get("radius") is None:
            opts["n_segments"] = default_count(data, kind)
        result = segment(data, **opts)
    n = kind_of(kind).n_rows(data)
    base.parent.mkdir(parents=True, exist_ok=True)
    picture = base.with_name(base.name + ".png") if outs["picture"] else None
    html = base.with_name(base.name + ".html") if outs["html"] else None
    colored = None
    if outs["colored"]:
        colored = base.with_name(base.name + "_superfacets." + outs["colored"])
    write_result(data, result, kind, Path(task["input"]).name,
                 labels=Path(task["outdir"]) / label_rel, header=outs["header"],
                 source_path=task["input"] if outs["labels"] in ("records", "laz") else None,
                 new_scan=outs["labels"] == "laz" and kind_of(kind).cloud
                 and split_suffix(Path(task["input"]))[0] not in ("las", "laz"),
                 colored=colored, vertex_colors=outs["vertex_colors"], picture=picture,
                 html=html, element_options={k: opts[k] for k in ("n_neighbors",
                                                                  "neighbor_radius")
                                             if k in opts},
                 up=outs.get("up") or up_axis(data, task["input"])[0],
                 view=outs.get("view") or default_view(data), levels=outs.get("levels"),
                 graph=base.with_name(base.name + ".npz") if outs.get("graph") else None)
    return {"elements": kind, "n_elements": int(n), "segments": int(result.n_segments),
            "passes": int(result.n_iter), "converged": bool(result.converged)}


def _lost_row(task: dict, error: str) -> dict:
    row = dict.fromkeys(MANIFEST_COLUMNS)
    row.update(input=task["input"], output=task["name"] + _label_suffix(
        task["outputs"]["labels"], task["input"]),
               status="failed", error=error[:500],
               finished=datetime.now(timezone.utc).isoformat(timespec="seconds"))
    return row


# --- the run ------------------------------------------------------------------------------

@dataclass
class BatchSummary:
    """Counts of one :func:`run_batch` call.

    Attributes
    ----------
    manifest : pathlib.Path
    inputs : int
        Inputs matched.
    done_before : int
        Inputs already done (ok, or failed and not retried): not run again.
    failed_before : int
        Of those, the failed ones (``retry_failed`` runs them again).
    ok, failed : int
        Inputs run by this call, by outcome.
    seconds : float
    interrupted : bool
    engine : str
        Where the tasks ran.
    failures : list of (str, str)
        (input, error) of the inputs that failed in this call.
    warned : list of (str, str)
        (input, warning) of this call's inputs whose run warned (each warning once).
    skipped : list of (str, str)
        (folder, reason) of the sub-folders that could not be read.
    passed : list of (str, str)
        (file, reason) of the files of the searched folders that are not inputs.
    """

    manifest: Path
    inputs: int = 0
    done_before: int = 0
    failed_before: int = 0
    ok: int = 0
    failed: int = 0
    seconds: float = 0.0
    interrupted: bool = False
    engine: str = ""
    failures: list = field(default_factory=list)
    warned: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    passed: list = field(default_factory=list)


def run_batch(inputs: Sequence[str], outdir, n_segments: int | None = None, *,
              radius: float | None = None, labels: str = "seg", header: bool = False,
              colored_mesh: str | None = None, vertex_colors: bool = False,
              picture: bool = False, html: bool = False, graph: bool = False, up=None,
              view=None, per_object: bool = False, adaptive: int | None = None,
              extent_weight: float | None = None, levels: Sequence[int] | None = None,
              seed_resolution: float | None = None, neighbor_distance: float | None = None,
              seen_from: str | None = None, workers: int | None = None,
              scheduler: str | None = None, memory_limit="auto", retry_failed: bool = False,
              progress: bool = True, n_threads: int = 1, dask: bool | None = None,
              **options) -> BatchSummary:
    """Segment every input with the same options; resumable; on this machine or on Dask.

    Parameters
    ----------
    inputs : sequence of str
        Files, folders (recursively), globs, ``@list.txt`` (:func:`collect_inputs`).
    outdir : path
        Output folder, created if missing (its parent must exist).
    n_segments, radius : optional
        As :func:`superfacets.segment` (default k = 150).
    labels : {'seg', 'json', 'npy', 'records', 'laz'}, default 'seg'
        Label file of each input: one label per line, ScanNet's ``segIndices``, a NumPy
        ``int64`` array (``.npy``, as learning pipelines load labels), a LAS/LAZ,
        PLY or PCD cloud's own records with ``ClusterID`` (``records``; others ``.seg``), or
        a ``.laz`` for every cloud (``laz``: a LAS/LAZ input's records, any other cloud's
        points as a new file: :func:`superfacets.io.records.write_cloud_with_labels`;
        meshes ``.seg``).
    header : bool, default False
        ``.seg`` files start with ``#`` lines (parameters, passes, time).
    colored_mesh : {'ply', 'glb', 'obj'}, optional
        Also write each input coloured by superfacet (vertices, points: ``ply``).
    vertex_colors : bool, default False
        PLY: colours per vertex.
    picture, html : bool, default False
        Also write a PNG (``render`` extra) / an interactive page per input
        (faces, vertices or points).
    graph : bool, default False
        Also write ``NAME.npz`` per input: the superfacet (superpoint) graph in PyTorch
        Geometric's layout, with the element labels and, given ``levels``, the hierarchy
        (:func:`superfacets.viz.outputs.graph_arrays`: what ``segment --graph`` writes).
        Not with ``per_object``.
    up, view : optional
        The pictures' and pages' camera (:func:`superfacets.viz.camera.view_frame`;
        default: each input's up axis, :func:`superfacets.io.orientation.up_axis`, the
        view automatic).
    per_object : bool, default False
        Scenes: each object segmented on its own (k shared out by area).
    adaptive : int, optional
        Content-adaptive superpoints (:func:`superfacets.adaptive_superpoints`)
        with this ``start`` (``>= 1``; with ``n_segments``, not ``radius`` or
        ``per_object``).
    extent_weight : float, optional
        Their ``extent_weight`` (default: left to the method).
    levels : sequence of int, optional
        With ``labels='records'`` or ``'laz'``: each cloud's coarser levels of these
        numbers of segments, each a field after the labels (``ClusterID_<n>``,
        :func:`superfacets.io.records.level_field`); a mesh's ``.seg`` holds its labels
        alone; with ``graph``, in each input's ``.npz`` (any ``labels``); with
        ``per_object``, each object's own levels
        (:func:`superfacets.api.scenes.objects_hierarchy`). An input whose superpoints cannot
        make a level (fewer than it asks, more connected pieces, or fewer than one per
        object) fails with the reason.
    seed_resolution, neighbor_distance : float, optional
        Sizes in each input's own units, as ``segment --seed-resolution`` and
        ``--neighbor-distance`` read them: its count ``k`` (its surface area over the
        square of the size, :func:`superfacets.api.sizes.count_for_resolution`; not with
        ``n_segments`` or ``radius``) and a cloud's farthest neighbour (not with
        ``neighbor_radius``; a mesh fails). Each ``> 0``.
    seen_from : {'x', 'y', 'z', '-x', '-y', '-z'}, optional
        Point clouds: the side they were scanned from, as ``segment --seen-from`` reads
        it: each cloud's up direction (segmented as a scan: neighbours along its
        surfaces, merged from 20 times ``k``; a LAS file's own is z) and its normals turned
        towards it; meshes as they are.
    workers : int, optional
        Local worker processes (default: one per core); 1 runs in this process.
    scheduler : str, optional
        A running Dask scheduler's address (default: ``DASK_SCHEDULER_ADDRESS``).
    memory_limit : default 'auto'
        Per local worker (:class:`~.engine.Engine`).
    retry_failed : bool, default False
        Run again the inputs that failed before.
    progress : bool, default True
        A progress bar on stderr.
    n_threads : int, default 1
        Threads of each segmentation (one task per core already).
    dask : bool, optional
        True: a Dask cluster even for one worker (a worker process that dies
        fails only its input); default: Dask unless ``workers=1``.
    **options
        The other keyword arguments of :func:`superfacets.segment` (``alpha``,
        ``elements``, ``tol``, ``cleanup``, ...).

    Returns
    -------
    BatchSummary

    Raises
    ------
    ParameterError
        Bad options, no input, an output folder made with other options or
        in use by another batch (before any work).
    FileNotFoundError, NotADirectoryError
        An input that matches nothing; an output folder that is a file or
        whose parent is missing.
    MissingExtraError, SchedulerError
        Dask or the render extra missing where needed; an unreachable scheduler.

    Examples
    --------
    >>> s = run_batch(["meshes/"], "out", 150, workers=2)   # doctest: +SKIP
    >>> s.ok, s.failed, s.manifest                          # doctest: +SKIP
    (12, 0, PosixPath('out/manifest.parquet'))
    """

    outdir = Path(outdir)
    if outdir.exists() and not outdir.is_dir():
        raise NotADirectoryError(f"{outdir}: exists and is not a folder")
    parent = outdir.parent if str(outdir.parent) else Path(".")
    if not parent.is_dir():
        raise FileNotFoundError(f"{outdir}: its folder {parent} {not_a_folder(parent)}")
    check_choice("labels", labels, tuple(_LABEL_SUFFIX))
    if vertex_colors and colored_mesh != "ply":  # (as segment refuses it)
        raise ParameterError("vertex_colors (--vertex-colors) colours a PLY's vertices: give "
                             "colored_mesh='ply' (--colored-mesh ply)")
    if header and labels != "seg":  # (its '#' lines would go nowhere, silently)
        raise ParameterError(f"header (--header) starts each .seg with '#' lines; labels "
                             f"{labels!r} (--labels {labels}) writes none")
    if colored_mesh is not None:
        check_choice("colored_mesh", colored_mesh, ("ply", "glb", "obj"))
    if per_object and radius is not None:
        raise ParameterError("per_object (--per-object) takes n_segments (-k), not radius "
                             "(--radius)")
    adaptive, extent_weight = _checked_adaptive(adaptive, extent_weight, per_object, radius)
    sizes = _checked_sizes(seed_resolution, neighbor_distance, n_segments, radius, options)
    if graph and per_object:
        raise ParameterError("graph (--graph) is of one segmentation; not with per_object "
                             "(--per-object)")
    levels = _checked_levels(levels, labels, graph)
    if levels:
        wanted_levels(levels, n_segments, ("levels (--levels)", "n_segments (-k)"))
    if workers is not None:
        check_int("workers", workers, lo=1)
    memory_limit = check_memory_limit(memory_limit)  # (before any input is looked at)
    if (up is not None or view is not None) and not (picture or html):
        raise ParameterError("up and view (--up, --view) set the camera of the pictures and "
                             "pages: give picture or html (--picture, --html)")
    n_threads = check_int("n_threads", n_threads, lo=1)
    seg_opts = dict(options, n_segments=n_segments, radius=radius, n_threads=n_threads)
    resolved = resolve(**seg_opts).as_dict()  # every option checked before any work
    if picture or html:
        check_camera(view, up or "y")
    if picture:
        extras.require("pyvista", "pictures (--picture)")
    skipped: list = []
    passed: list = []
    files = collect_inputs(inputs, exclude=outdir if outdir.exists() else None,
                           skipped=skipped, passed=passed)
    if not files:
        raise no_inputs(inputs, outdir)
    outputs = {"labels": labels, "header": bool(header), "colored": colored_mesh,
               "picture": bool(picture), "html": bool(html), "vertex_colors": bool(vertex_colors)}
    if picture or html:  # recorded only where drawn (folders of earlier runs resume)
        outputs.update(up=up, view=list(view) if isinstance(view, (tuple, list)) else view)
    if levels:  # (likewise)
        outputs["levels"] = levels
    if graph:  # (likewise)
        outputs["graph"] = True
    if sizes:  # (likewise: each input's own count and neighbours, read by its task)
        outputs["sizes"] = sizes
    if seen_from is not None:  # (likewise)
        outputs["seen_from"] = check_choice("seen_from", seen_from, tuple(AXES))
    recorded = {"segment": _jsonable({k: v for k, v in resolved.items()  # defaults filled
                                      if k not in ("n_threads", "progress")}),
                "outputs": outputs, "per_object": bool(per_object)}
    level = None
    if adaptive is not None:  # recorded only where on (folders of earlier runs resume)
        level = {"start": adaptive, "compactness": extent_weight}  # the key folders hold
        recorded["adaptive"] = level
    known = check_options(outdir, recorded)  # before the engine starts: a quick refusal
    work = bool(_todo(files, read_manifest(outdir) if known else [], retry_failed))
    # the engine (a cluster to start or reach) only where there is work, before any is done
    with (Engine(workers, scheduler, memory_limit=memory_limit, dask=dask) if work else
          contextlib.nullcontext()) as engine:
        outdir.mkdir(exist_ok=True)
        with FolderLock(outdir):
            if not known and not check_options(outdir, recorded):
                record_options(outdir, recorded)
            summary = _run(files, outdir, seg_opts, outputs, per_object, level, engine,
                           retry_failed, progress)
    summary.skipped = skipped
    summary.passed = passed
    return summary


def _checked_adaptive(adaptive, extent_weight, per_object: bool, radius) -> tuple:
    """``adaptive`` and its ``extent_weight``, checked against the options they exclude."""
    if adaptive is not None:
        adaptive = check_int("adaptive", adaptive, lo=1)
        if per_object or radius is not None:
            raise ParameterError("adaptive (--adaptive) takes n_segments (-k), on one "
                                 "segmentation: not with radius (--radius) or per_object "
                                 "(--per-object)")
    if extent_weight is not None:
        if adaptive is None:
            raise ParameterError("extent_weight (--extent-weight) goes with adaptive "
                                 "(--adaptive)")
        extent_weight = check_nonneg("extent_weight", extent_weight)
    return adaptive, extent_weight


def _checked_sizes(seed_resolution, neighbor_distance, n_segments, radius,
                   options: dict) -> dict:
    """The sizes in the data's units given (``> 0``), against the options they replace."""
    sizes = {}
    for name, v, instead in (("seed_resolution", seed_resolution, (n_segments, radius)),
                             ("neighbor_distance", neighbor_distance,
                              (options.get("neighbor_radius"),))):
        if v is None:
            continue
        v = check_positive(name, v)
        if any(o is not None for o in instead):
            raise ParameterError(f"{name} (--{name.replace('_', '-')}) is given in the data's "
                                 "units instead of " + ("n_segments (-k) or radius (--radius)"
                                                        if name == "seed_resolution" else
                                                        "neighbor_radius (--neighbor-radius)"))
        sizes[name] = v
    return sizes


def _sized(opts: dict, sizes: dict, data, kind: str) -> dict:
    """A task's options with its sizes in the data's units read on its input."""
    if sizes.get("neighbor_distance") is not None:
        if not kind_of(kind).cloud:
            raise ParameterError("neighbor_distance (--neighbor-distance) is of a point "
                                 f"cloud's graph, not of {kind}")
        opts = dict(opts, neighbor_radius=diagonal_fraction(
            data, sizes["neighbor_distance"], "--neighbor-distance"))
    if sizes.get("seed_resolution") is not None:
        near = {k: opts[k] for k in ("n_neighbors", "neighbor_radius") if k in opts}
        opts = dict(opts, n_segments=count_for_resolution(data, sizes["seed_resolution"],
                                                          kind, **near)[0])
    return opts


def _checked_levels(levels, labels: str, graph: bool = False) -> list | None:
    """``levels`` as distinct positive integers, largest first, where the label files
    (a cloud's own records) or the graphs take them, else refused in words; None where not
    given."""
    if levels is None:
        return None
    wanted = wanted_levels(levels)
    if labels not in ("records", "laz") and not graph:
        raise ParameterError(f"levels (--levels) go into each cloud's own file, a field "
                             f"ClusterID_N each: labels='records' or 'laz' (--labels records "
                             f"or laz), not {labels!r}; or into each input's graph (--graph)")
    return wanted


def _done(row, retry_failed: bool) -> bool:
    return row is not None and (row["status"] == "ok" or
                                (row["status"] == "failed" and not retry_failed))


def _todo(files: list, rows, retry_failed: bool) -> list:
    """The inputs to run: those without an ok row (or a failed one, unless retried)."""
    by_input = rows if isinstance(rows, dict) else {r["input"]: r for r in rows}
    return [f for f in files if not _done(by_input.get(str(f)), retry_failed)]


def _jsonable(d: dict) -> dict:
    return {k: (v if isinstance(v, (int, float, str, bool, type(None))) else str(v))
            for k, v in sorted(d.items())}


def _run(files, outdir, seg_opts, outputs, per_object, level, engine, retry_failed,
         progress) -> BatchSummary:
    rows = {r["input"]: r for r in read_manifest(outdir)}  # again, under the lock
    summary = BatchSummary(outdir / "manifest.parquet", inputs=len(files))
    keys = {f: str(f) for f in files}
    todo = _todo(files, rows, retry_failed)
    if todo and engine is None:  # pragma: no cover - another batch changed the folder
        raise ParameterError(f"{outdir}: changed by another batch meanwhile; run again")
    summary.done_before = len(files) - len(todo)
    summary.failed_before = sum(rows[keys[f]]["status"] == "failed" for f in files
                                if f not in set(todo))
    reserved = {r["output"].rsplit(".", 1)[0] for k, r in rows.items() if r.get("output")}
    earlier = {f: rows[keys[f]]["output"].rsplit(".", 1)[0] for f in todo
               if keys[f] in rows and rows[keys[f]].get("output")}
    names = dict(earlier)
    names.update(output_names([f for f in todo if f not in earlier], reserved))
    tasks = [{"input": keys[f], "outdir": str(outdir.resolve()), "name": names[f],
              "options": dict(seg_opts, progress=False), "outputs": outputs,
              "per_object": per_object, "adaptive": level} for f in _largest_first(todo)]
    t0 = time.perf_counter()
    journal_path = outdir / JOURNAL
    bar = None
    finished: set[str] = set()
    last_write = time.monotonic()
    summary.engine = engine.describe() if engine is not None else ""
    try:
        with open(journal_path, "a") as journal:
            if progress and tasks:  # (its elapsed time redrawn while an input runs)
                bar = new_bar(total=len(tasks), unit="input", desc="batch", dynamic_ncols=True)
                ticking = tick(bar)
            for row in (engine.run(segment_file, tasks, _lost_row) if tasks else ()):
                journal.write(json.dumps(row) + "\n")
                journal.flush()
                rows[row["input"]] = row
                finished.add(row["input"])
                summary.warned += [(row["input"], w) for w in
                                   (row.get("warnings") or "").splitlines()]
                if row["status"] == "ok":
                    summary.ok += 1
                else:
                    summary.failed += 1
                    summary.failures.append((row["input"], row["error"]))
                if bar is not None:
                    bar.update(1)
                    bar.set_postfix(failed=summary.failed, refresh=False)
                if time.monotonic() - last_write > 30:  # a manifest to look at, now and then
                    summary.manifest = write_manifest(outdir, _ordered(rows, files))
                    last_write = time.monotonic()
    except KeyboardInterrupt:
        interrupts.caught()  # stopping in order: the manifest is written below
        summary.interrupted = True
    finally:
        if bar is not None:
            ticking.set()
            bar.close()
        for t in tasks:
            if t["input"] not in finished and not _done(rows.get(t["input"]), retry_failed):
                r = _lost_row(t, "not run: the batch stopped before it")
                r["status"] = "skipped"
                rows[t["input"]] = r
        summary.manifest = write_manifest(outdir, _ordered(rows, files))
        journal_path.unlink(missing_ok=True)  # all in the manifest now
    summary.seconds = time.perf_counter() - t0
    return summary


def _largest_first(files: list) -> list:
    """The inputs by decreasing file size: the longest tasks start first, so that no worker
    is left with a large input at the end while the others wait (the manifest keeps the
    inputs' order)."""
    def size(f) -> int:
        try:
            return f.stat().st_size
        except OSError:
            return 0
    return sorted(files, key=size, reverse=True)


def _ordered(rows: dict, files: list) -> list[dict]:
    """This run's inputs in order, then rows of earlier runs' other inputs."""
    keys = [str(f) for f in files]
    mine = set(keys)
    return [rows[k] for k in keys if k in rows] + [r for k, r in rows.items() if k not in mine]
