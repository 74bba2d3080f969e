"""Run an experiment: methods x parameters x benchmark meshes, evaluated, resumable.

:func:`run_experiment` runs a grid of configurations (:mod:`.grid`) of
registered methods (:mod:`superfacets.evaluation.methods`) over benchmark meshes in
worker processes (:class:`.engine.Engine`: a local Dask cluster, or a
running one) and appends one tidy row per (mesh, method, parameters,
``n_segments``) to a CSV file (:mod:`.results`) as results arrive; rerunning
with the same file skips every row already there, so an interrupted run
continues where it stopped. A failure on one mesh is recorded as a row with
its error and does not stop the run; a worker that dies is replaced.
``superfacets batch`` (:mod:`.batch`) runs on the same engine.
"""

from __future__ import annotations

import csv
import re
import time
from dataclasses import dataclass, field, replace
from functools import lru_cache
from itertools import product
from pathlib import Path
from typing import Sequence

import numpy as np

from ..._runtime import interrupts
from ..._runtime.progress import new_bar, tick
from ..._runtime.warned import task_warnings
from ...checks import AXES
from ...elements import face_graph
from ...elements.builders import elements_of
from ...elements.kinds import KINDS, kind_of
from ...errors import ParameterError
from ...evaluation.baselines._count import COUNT_MISSED
from ...evaluation.datasets.psb import BenchmarkMesh
from ...evaluation.datasets.rooms import load_room
from ...evaluation.datasets.sampling import sample_points, vertex_ground_truth
from ...evaluation.methods import Skipped, get_method
from ...evaluation.metrics import compactness, evaluate, has_border, oracle_miou
from ...evaluation.results import columns, fmt_value, prepare_file, row_key
from ...inputs.cloud import PointCloud
from ...io import read_input
from ...io.files import not_a_folder
from ...io.labels import read_field, read_labels
from ...method.params import DEFAULT_N_SEGMENTS, ELEMENTS, check_choice, check_int, max_threads
from .engine import Engine, PeakMemory, error_text
from .grid import Config

__all__ = ["run_experiment", "ExperimentSummary", "PeakMemory"]


@lru_cache(maxsize=2)
def _load(path: str, seg_paths: tuple):
    bm = BenchmarkMesh(0, "", Path(path), tuple(Path(p) for p in seg_paths))
    mesh = bm.load()
    return mesh, bm.ground_truths(mesh.n_faces)


@lru_cache(maxsize=2)
def _prepared(path: str, seg_paths: tuple, elements: str, n_points: int, seed: int):
    """The input of one element kind, its evaluation graph and ground truths per element.

    Faces: the mesh and its ground truths. Vertices: the mesh, ground truth by
    area-weighted majority of the incident faces. Points: ``n_points`` sampled
    uniformly by area (fixed seed), each with its face's ground truth.
    """

    mesh, gts = _load(path, seg_paths)
    truth = kind_of(elements).face_truth
    if truth == "same":
        return mesh, face_graph(mesh), None, gts
    if truth == "vote":
        obj = mesh
        rows = [vertex_ground_truth(mesh, gt) for gt in gts]
    else:
        pts, faces = sample_points(mesh, n_points, seed)
        obj = PointCloud(pts, name=Path(path).name)
        rows = [gt[faces] for gt in gts]
    source = elements_of(obj, elements)
    to_el = _element_values(source)
    return obj, source.graph, to_el, [to_el(r) for r in rows]


@lru_cache(maxsize=2)
def _room(name: str):
    """A made-up room (:mod:`superfacets.evaluation.datasets.rooms`) as :func:`_prepared`
    gives an input: its cloud, point graph, per-element values and its classes."""

    scan = load_room(name)
    source = elements_of(scan.cloud, "points")
    to_el = _element_values(source)
    return scan.cloud, source.graph, to_el, [to_el(scan.ground_truth)]


@lru_cache(maxsize=2)
def _file(path: str, field: str | None, elements: str, truths: tuple = (),
          seen_from: str | None = None):
    """A user's file (:func:`superfacets.scale.runner.collect.file_entries`) as :func:`_prepared`
    gives an input: the mesh or cloud, its element graph, per-element values and its
    ground truths (the file's ``field``, the label files ``truths``; none without); a
    cloud seen from the axis ``seen_from`` where given (as ``segment --seen-from``)."""

    if field is not None and kind_of(elements).objects:
        raise ParameterError(f"{Path(path).name}: a field ({field}) holds one value per "
                             "vertex or point: judge a mesh's vertices (--elements vertices)")
    data = read_input(path)
    if seen_from is not None and isinstance(data, PointCloud):
        data = replace(data, up=AXES[seen_from], viewpoint=None)
    source = elements_of(data, elements)
    to_el = _element_values(source)
    gts = [] if field is None else [to_el(read_field(path, field))]
    n = kind_of(elements).n_rows(data)
    gts += [to_el(read_labels(t, n_faces=n)) for t in truths]
    return data, source.graph, to_el, gts


def _element_values(source):
    """Per-row values -> per-element values (the first row of each element)."""
    first = source.first_rows(np.arange(source.graph.n_elements))
    return lambda values: np.asarray(values)[first]


#: How a row's warning begins where no ground truth has a border (:func:`_borderless`).
BORDERLESS_EMPTY = "the boundary recall is left empty"


def _borderless(graph, gts: list, ignore_label) -> str:
    """What a row says of its ground truths that have no border on ``graph`` (their
    recall 1 by convention, :func:`~superfacets.evaluation.metrics.has_border`): none
    with a border, the recall is left empty (the report's means leave it out); ``""``
    where every ground truth has one."""
    without = sum(not has_border(graph, gt, ignore_label) for gt in gts)
    if not without:
        return ""
    why = "(their classes lie on separate pieces of the graph, or there is one class)"
    if without == len(gts):
        return (f"{BORDERLESS_EMPTY}: no two neighbouring elements differ in the ground "
                f"truth {why}")
    return (f"no two neighbouring elements differ in {without} of its {len(gts)} ground "
            f"truths {why}: the boundary recall counts 1 for each of them")


def _run_task(task: dict) -> list[dict]:
    """Run one config over a list of n_segments on one mesh; one row each."""

    base = dict(task["base"])
    run = task["run"]
    params = dict(task["params"])
    rows = []
    kind = task.get("elements", "faces")
    try:
        if task.get("room"):  # a made-up room: points with their classes
            data, graph, to_el, gts = _room(task["path"])
        elif task.get("file"):  # a user's file: judged against its own field, if named
            data, graph, to_el, gts = _file(task["path"], task.get("field"), kind,
                                            task["seg_paths"], task.get("seen_from"))
        else:
            base["n_faces"] = _load(task["path"], task["seg_paths"])[0].n_faces
            data, graph, to_el, gts = _prepared(task["path"], task["seg_paths"], kind,
                                                task.get("n_points", 0), task["seed"])
        base["n_elements"] = graph.n_elements
        n_rows = graph.n_elements if to_el is None else (
            kind_of(kind).n_rows(data))
        extra = {"elements": kind} if task.get("takes_elements") else {}
    except Exception as exc:  # noqa: BLE001 - recorded, the run goes on
        return [dict(base, n_segments=k, status="failed", error=error_text(exc))
                for k in task["ks"]]
    cache: dict = {}
    task_peak = 0.0
    borderless = _borderless(graph, gts, task.get("ignore_label"))
    for k in task["ks"]:
        row = dict(base, n_segments=k)
        try:
            probe = PeakMemory()
            t0 = time.perf_counter()
            # (told by the summary, named by input, not from a worker; a baseline's count
            # far from k is said by its row's `segments`)
            with task_warnings(ignore=(re.escape(COUNT_MISSED),)) as said:
                out = run(data, k, cache=cache, seed=task["seed"], **params, **extra)
            row["warnings"] = list(dict.fromkeys(said))
            seconds = time.perf_counter() - t0
            peak = probe.peak_mib()
            row["seconds"] = round(seconds + float(out.reused_seconds), 4)
            if peak is not None:
                task_peak = max(task_peak, peak)
                row["peak_mib"] = round(task_peak if out.reused_seconds else peak, 1)
            labels = np.asarray(out.labels)
            if labels.shape != (n_rows,):
                raise RuntimeError(f"method returned {labels.shape} labels for "
                                   f"{n_rows} {kind}")
            if to_el is not None:
                labels = to_el(labels)
            row.update(status="ok", segments=int(np.unique(labels).size),
                       iterations=out.n_iter, converged=out.converged,
                       n_ground_truths=len(gts))
            if gts:
                equal = kind_of(kind).equal_weight
                row.update({m: round(v, 6) for m, v in
                            evaluate(graph, labels, gts, tau=task["tau"], equal_weight=equal,
                                     ignore_label=task.get("ignore_label")).items()})
                weights = None if equal else graph.sizes  # (each class's share, as the UE's)
                row["oracle_miou"] = round(float(np.mean(
                    [oracle_miou(labels, gt, weights=weights,
                                 ignore_label=task.get("ignore_label"))[0] for gt in gts])), 6)
                if borderless:
                    row["warnings"].append(borderless)
                    if borderless.startswith(BORDERLESS_EMPTY):
                        row["boundary_recall"] = None
            else:  # (no ground truth: the shapes alone, as `evaluate` measures them)
                row["compactness"] = round(compactness(graph, labels), 6)
        except Skipped as exc:
            row.update(status="skipped", error=str(exc)[:500], seconds=None)
        except Exception as exc:  # noqa: BLE001 - recorded, the run goes on
            row.update(status="failed", error=error_text(exc), seconds=None)
        rows.append(row)
    return rows


@dataclass
class ExperimentSummary:
    """Counts of one :func:`run_experiment` call.

    Attributes
    ----------
    path : pathlib.Path
        The results file.
    done_before : int
        Rows found in the file and skipped.
    ok, failed, skipped : int
        Rows written by this call, by status.
    seconds : float
        Wall-clock time of this call.
    interrupted : bool
    note : str
        Where the engine chose for the user (no Dask installed: in this process).
    failures : dict
        The failed rows' errors, each with how many rows it ended, in the order first met.
    warned : dict
        The runs' warnings (each with its input's name), each with how many rows it came
        from, in the order first met; not in the results file.
    """

    path: Path
    done_before: int = 0
    ok: int = 0
    failed: int = 0
    skipped: int = 0
    seconds: float = 0.0
    interrupted: bool = False
    note: str = ""
    failures: dict = field(default_factory=dict)
    warned: dict = field(default_factory=dict)

    @property
    def written(self) -> int:
        return self.ok + self.failed + self.skipped


def _tasks(meshes, configs, kinds, ks, done, common: dict) -> list[dict]:
    """One task per mesh, configuration and kind with rows still to run (its counts
    ``ks`` not in ``done``); ``common``: seed, tau, n_points, ignore_label and seen_from
    of every task."""
    tasks = []
    for bm, cfg, kind in product(meshes, configs, kinds):
        method = get_method(cfg.method)
        room = getattr(bm, "room", False)
        file = getattr(bm, "file", False)
        if not _applies(method, bm, kind):
            continue
        base = {"mesh": getattr(bm, "name", "") or Path(bm.path).stem, "mesh_id": bm.id,
                "category": bm.category,
                "method": cfg.method, "elements": kind, "seed": common["seed"],
                "seen_from": common["seen_from"] if file and KINDS[kind].cloud else None,
                **{k: fmt_value(v) for k, v in cfg.params}}
        todo = [k for k in ks if row_key({**base, "n_segments": k}) not in done]
        if todo:
            tasks.append({"base": base, "run": method.run, "params": cfg.params,
                          "path": str(bm.path), "seg_paths": tuple(str(p) for p in bm.seg_paths),
                          "ks": todo, "elements": kind, "room": room, "file": file,
                          "field": getattr(bm, "field", None),
                          "takes_elements": method.takes_elements, **common})
    return tasks


def _applies(method, bm, kind: str) -> bool:
    """Whether ``method`` segments input ``bm``'s elements of ``kind``."""
    room, file = getattr(bm, "room", False), getattr(bm, "file", False)
    cloud = room or (file and bm.category == "cloud")
    volume = file and bm.category == "volume"  # (its elements: cells alone)
    return kind in method.elements and not (cloud and not KINDS[kind].cloud) and not (
        file and not cloud and KINDS[kind].cloud) and volume == (KINDS[kind].dim == 3)


def _say_idle(meshes, configs, kinds) -> None:
    """Warn, once per method, where a method of the grid segments none of the inputs (VSA
    asked of point clouds): it has no rows, and would otherwise have none silently."""
    import warnings

    for name in dict.fromkeys(c.method for c in configs):
        method = get_method(name)
        if not any(_applies(method, bm, k) for bm in meshes for k in kinds):
            warnings.warn(f"{name} segments {' and '.join(method.elements)}, which no input "
                          "here has (as the elements asked for): no rows for it", stacklevel=3)


def run_experiment(meshes: Sequence, configs: Sequence[Config], results,
                   n_segments: Sequence[int] = DEFAULT_N_SEGMENTS, *, workers: int | None = None,
                   tau: float = 0.05, seed: int = 0, retry_failed: bool = False,
                   progress: bool = True, elements: Sequence[str] = ("faces",),
                   n_points: int = 20_000, scheduler: str | None = None,
                   ignore_label: int | None = None,
                   seen_from: str | None = None) -> ExperimentSummary:
    """Run every config at every ``n_segments`` on every mesh, appending rows.

    Parameters
    ----------
    meshes : sequence of BenchmarkMesh or RoomEntry
        Meshes with their ground truths (:func:`superfacets.evaluation.datasets.psb.list_meshes`);
        a mesh without ground truths gets rows without metrics. Or made-up rooms
        (:func:`superfacets.evaluation.datasets.rooms.room_entries`: points, against their
        classes; run where ``elements`` has ``'points'``).
    configs : sequence of Config
        From :func:`expand_grid`.
    results : path
        CSV file, created if missing, appended to otherwise. Rows already
        there (same mesh, method, parameters, ``n_segments`` and ``seed``)
        are not run again.
    n_segments : sequence of int, default (50, 100, ..., 300)
    workers : int, optional
        Worker processes of a local Dask cluster (default: one per core; the
        ``distributed`` extra); 1 runs in this process. A worker that dies
        (killed, out of memory, a crash in native code) is replaced; its task
        runs again elsewhere up to Dask's ``allowed-failures`` times, then
        its rows are recorded as failed.
    tau : float, default 0.05
        Overlap tolerance of the undersegmentation error.
    ignore_label : int, optional
        A ground-truth value meaning *unlabelled* (SemanticKITTI's 0): those elements are
        left out of every metric but the compactness
        (:func:`superfacets.evaluation.metrics.evaluate`).
    seed : int, default 0
        Passed to every method (for those that draw random numbers).
    retry_failed : bool, default False
        Run again the rows recorded as ``failed`` (the new row is appended;
        :func:`superfacets.evaluation.report.load_results` keeps the last one).
    progress : bool, default True
        Show a progress bar (rows) on stderr.
    elements : sequence of {'faces', 'vertices', 'points', 'cells'}, default ('faces',)
        Element kinds to run each method on (where it supports them; cells: the
        tetrahedra of a user's volume mesh).
        Vertices: ground truth by area-weighted majority of the incident
        faces; points: ``n_points`` sampled uniformly by area (seed ``seed``),
        each with its face's ground truth; both evaluated with equal weight
        per element (:func:`superfacets.evaluation.metrics.evaluate`).
    n_points : int, default 20000
        Points sampled per mesh for ``'points'``.
    scheduler : str, optional
        Address of a running Dask scheduler to run on instead (default:
        ``DASK_SCHEDULER_ADDRESS`` where set); its workers must see the
        benchmark's files.
    seen_from : {'x', 'y', 'z', '-x', '-y', '-z'}, optional
        The side the user's point clouds (``meshes`` from
        :func:`~superfacets.scale.runner.collect.file_entries`) were scanned from: each is
        segmented as a scan with that up direction (neighbours along its surfaces, merged
        as a scene's), as ``segment --seen-from`` does, its own viewpoint set aside; the
        rows record it (``seen_from``), so that another axis or none into the same file
        adds rows. Meshes, rooms and the benchmark are run as they are.

    Returns
    -------
    ExperimentSummary

    Raises
    ------
    ParameterError
        On an empty grid, a bad ``n_segments``, ``workers``, ``tau`` or ``seen_from``, or
        a setting's value its method refuses (:attr:`~superfacets.evaluation.methods.Method.check`).
    MissingExtraError, SchedulerError
        Dask needed and missing; a scheduler that cannot be reached.
    """
    if not configs:
        raise ParameterError("no method configuration to run")
    ks = sorted({int(k) for k in n_segments})
    if not ks or ks[0] < 1:
        raise ParameterError(f"n_segments must be positive integers, got {list(n_segments)}")
    if not (0 <= tau < 1):
        raise ParameterError(f"tau must be in [0, 1), got {tau}")

    workers = None if workers is None else check_int("workers", workers, lo=1,
                                                     hi=max_threads())
    for c in configs:  # (each setting's values, before any work: not a failed row each)
        check = get_method(c.method).check
        try:
            if check is not None:
                check(**c.kwargs)
        except ParameterError as exc:
            raise ParameterError(f"method {c.method!r}: {exc}") from None
    path = Path(results)
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a directory")
    if not path.parent.is_dir():
        raise FileNotFoundError(f"{path}: folder {path.parent} {not_a_folder(path.parent)}")
    cols, old = prepare_file(path, columns(configs))
    done = {row_key(r) for r in old if not (retry_failed and r.get("status") == "failed")}

    kinds = [check_choice("elements", e, (*ELEMENTS, "cells")) for e in elements]
    if not kinds:
        raise ParameterError("no element kind to run")
    n_points = check_int("n_points", n_points, lo=1)
    if seen_from is not None:
        check_choice("seen_from", seen_from, tuple(AXES))
    tasks = _tasks(meshes, configs, kinds, ks, done,
                   dict(seed=seed, tau=tau, n_points=n_points, ignore_label=ignore_label,
                        seen_from=seen_from))
    if not any(k in get_method(c.method).elements for c in configs for k in kinds):
        raise ParameterError(f"no method of the grid segments {', '.join(kinds)}")
    _say_idle(meshes, configs, kinds)
    # the longest tasks first (the mesh's file size x its rows), so that no worker is left
    # with a large mesh at the end while the others wait; a mesh's tasks stay together
    tasks.sort(key=lambda t: _file_size(t["path"]) * len(t["ks"]), reverse=True)
    summary = ExperimentSummary(path, done_before=len(done))
    total = sum(len(t["ks"]) for t in tasks)
    t0 = time.perf_counter()
    bar = None
    if progress and total:  # (its elapsed time redrawn while a mesh runs)
        bar = new_bar(total=total, unit="row", desc="experiment", dynamic_ncols=True)
        ticking = tick(bar)

    with open(path, "a", newline="") as f:
        writer = csv.DictWriter(f, cols, restval="", extrasaction="ignore", lineterminator="\n")

        def record(rows: list[dict]) -> None:
            for r in rows:
                writer.writerow({k: fmt_value(v) for k, v in r.items()})
                setattr(summary, r["status"], getattr(summary, r["status"]) + 1)
                if r["status"] == "failed":
                    summary.failures[r["error"]] = summary.failures.get(r["error"], 0) + 1
                for w in r.get("warnings") or ():
                    w = f"{r['mesh']}: {w}"
                    summary.warned[w] = summary.warned.get(w, 0) + 1
            f.flush()
            if bar is not None:
                bar.update(len(rows))
                bar.set_postfix(failed=summary.failed, skipped=summary.skipped, refresh=False)

        try:
            with Engine(workers if len(tasks) > 1 else 1, scheduler,
                        exact_memory=True) as engine:  # rows report peak memory
                summary.note = engine.note
                for rows in engine.run(_run_task, tasks, _failed_rows):
                    record(rows)
        except KeyboardInterrupt:
            interrupts.caught()  # stopping in order: the rows so far are kept
            summary.interrupted = True
        finally:
            if bar is not None:
                ticking.set()
                bar.close()
    summary.seconds = time.perf_counter() - t0
    return summary


def _file_size(path: str) -> int:
    try:
        return Path(path).stat().st_size
    except OSError:
        return 0


def _failed_rows(task: dict, error: str) -> list[dict]:
    return [dict(task["base"], n_segments=k, status="failed", error=error) for k in task["ks"]]
