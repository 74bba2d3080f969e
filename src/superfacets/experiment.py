"""Experiment runner: methods x parameters x meshes, evaluated, resumable.

A *method* is anything that labels the faces of a mesh given a number of
segments. Methods are looked up by name in one registry (:data:`METHODS`,
:func:`register_method`), so new ones (the baselines) plug in without any
change to the runner. :func:`run_experiment` runs a grid of them over a set of
benchmark meshes in worker processes and appends one tidy row per
(mesh, method, parameters) to a CSV file as results arrive; rerunning with
the same file skips every row already there, so an interrupted run continues
where it stopped. A failure on one mesh is recorded as a row with its error
and does not stop the run.

Row columns (:func:`columns`): ``mesh``, ``mesh_id``, ``category``,
``n_faces``, ``method``, ``n_segments`` (asked), one column per method
parameter (empty where a method does not have it), ``seed``, ``status``
(``ok``, ``failed`` or ``skipped``), ``superfacets`` (produced), ``iterations``,
``converged``, ``seconds`` (the method only, not reading or metrics, including
work reused from an earlier ``n_segments``), ``peak_mib`` (peak resident memory
above the start of the call, Linux only), the
metrics of :data:`superfacets.metrics.METRICS` averaged over the mesh's
ground truths, ``n_ground_truths`` and ``error``.
"""

from __future__ import annotations

import csv
import io
import math
import os
import time
import traceback
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from functools import lru_cache
from itertools import product
from pathlib import Path
from typing import Callable, Iterable, Sequence

import numpy as np

from .errors import ParameterError
from .metrics import METRICS

__all__ = ["Method", "MethodRun", "Skipped", "METHODS", "register_method", "get_method",
           "expand_grid", "Config", "run_experiment", "ExperimentSummary", "read_results",
           "columns", "DEFAULT_N_SEGMENTS", "DEFAULT_ALPHAS"]

#: The paper's sweep (SPEC section 4, Fig. 4).
DEFAULT_N_SEGMENTS = (50, 100, 150, 200, 250, 300)
DEFAULT_ALPHAS = (0.0, 100.0, 200.0, 500.0, 1000.0)


class Skipped(Exception):
    """Raised by a method that declines a mesh (e.g. it would not fit in memory).

    The runner records the row with status ``skipped`` and the message.
    """


@dataclass
class MethodRun:
    """What a method returns for one mesh and one number of segments.

    Attributes
    ----------
    labels : (m,) int ndarray
        One label per face.
    n_iter : int, optional
        Iterations run, where the method iterates.
    converged : bool, optional
    reused_seconds : float, default 0
        Seconds of work done by an earlier call and reused from ``cache``
        (e.g. the embedding of normalized cuts). The runner adds them to the
        row's ``seconds``, so ``seconds`` is the cost of one segmentation
        from scratch, and takes the row's ``peak_mib`` as the largest of the
        calls so far on that mesh and setting.
    """

    labels: np.ndarray
    n_iter: int | None = None
    converged: bool | None = None
    reused_seconds: float = 0.0


@dataclass(frozen=True)
class Method:
    """A segmentation method in the registry.

    Attributes
    ----------
    name : str
    run : callable
        ``run(mesh, n_segments, *, cache, seed, **params) -> MethodRun``.
        ``cache`` is a dict shared by the calls for one mesh and one setting
        of ``params`` over every ``n_segments`` (for work that does not depend
        on it, e.g. a distance matrix); ``seed`` an int for methods that draw
        random numbers. May raise :class:`Skipped`.
    defaults : dict
        Every parameter (besides ``n_segments``) and its default; a value
        given to the runner is converted to the type of the default.
    sweep : dict
        Default values swept by ``superfacets experiment`` per parameter.
    description : str
    """

    name: str
    run: Callable[..., MethodRun]
    defaults: dict
    sweep: dict = field(default_factory=dict)
    description: str = ""

    def resolve(self, params: dict) -> dict:
        """``defaults`` updated with ``params``, converted to the defaults' types.

        Raises
        ------
        ParameterError
            On an unknown parameter or a value of the wrong type.
        """
        out = dict(self.defaults)
        for k, v in params.items():
            if k not in self.defaults:
                raise ParameterError(f"method {self.name!r} has no parameter {k!r} "
                                     f"(it has: {', '.join(sorted(self.defaults)) or 'none'})")
            kind = type(self.defaults[k])
            try:
                out[k] = kind(v) if kind is not bool or isinstance(v, bool) else _bool(v)
            except (TypeError, ValueError):
                raise ParameterError(f"method {self.name!r}: {k} must be "
                                     f"{kind.__name__}, got {v!r}") from None
        return out


def _bool(v) -> bool:
    t = str(v).strip().lower()
    if t in ("1", "true", "yes"):
        return True
    if t in ("0", "false", "no"):
        return False
    raise ValueError(v)


#: The registry: method name -> :class:`Method`.
METHODS: dict[str, Method] = {}


def register_method(name: str, run: Callable[..., MethodRun], *, defaults: dict,
                    sweep: dict | None = None, description: str = "") -> Method:
    """Add (or replace) a method in :data:`METHODS`.

    Parameters
    ----------
    name : str
        Registry key; letters, digits, ``_`` and ``-``.
    run : callable
        ``run(mesh, n_segments, *, cache, seed, **params) -> MethodRun``. It
        is sent to the worker processes by reference, so it must be a
        module-level function of an importable module (not a lambda).
    defaults : dict
        Parameter names and default values (int, float, str or bool).
    sweep : dict, optional
        Default sweep per parameter, e.g. ``{"alpha": (0, 200)}``.
    description : str, optional

    Returns
    -------
    Method
    """
    if not name or not all(c.isalnum() or c in "_-" for c in name):
        raise ParameterError(f"invalid method name {name!r}")
    clash = set(defaults) & {"n_segments", "seed", "cache"}
    if clash:
        raise ParameterError(f"parameter name(s) reserved by the runner: {sorted(clash)}")
    m = Method(name, run, dict(defaults), dict(sweep or {}), description)
    METHODS[name] = m
    return m


def get_method(name: str) -> Method:
    """The registered method ``name``.

    Raises
    ------
    ParameterError
        Naming the registered methods, if there is none of that name.
    """
    try:
        return METHODS[name]
    except KeyError:
        raise ParameterError(f"unknown method {name!r}; registered: "
                             f"{', '.join(sorted(METHODS))}") from None


# --- the built-in methods -------------------------------------------------------------


def _run_superfacets(mesh, n_segments, *, cache, seed, weighting="paper", **params):
    from .segment import segment

    r = segment(mesh, n_segments, weighting=weighting, **params)
    return MethodRun(r.labels, r.n_iter, r.converged)


def _run_shlafman(mesh, n_segments, *, cache, seed, **params):
    return _run_superfacets(mesh, n_segments, cache=cache, seed=seed, weighting="shlafman",
                            **params)


def _run_ncuts(mesh, n_segments, *, cache, seed, components, memory_limit_gib, **params):
    from .baselines.ncuts import ncut_embedding, normalized_cuts
    from .errors import MemoryLimitError

    emb = cache.get("ncut_embedding")
    reused = 0.0
    if emb is None or emb.n_components < min(n_segments, mesh.n_faces):
        limit = int(memory_limit_gib * 2**30) if memory_limit_gib > 0 else None
        try:
            emb = ncut_embedding(mesh, max(components, n_segments), memory_limit=limit,
                                 rng=seed, **params)
        except MemoryLimitError as exc:
            raise Skipped(str(exc)) from None
        cache["ncut_embedding"] = emb
    else:
        reused = emb.total_seconds
    return MethodRun(normalized_cuts(mesh, n_segments, embedding=emb, rng=seed),
                     reused_seconds=reused)


def _run_vsa(mesh, n_segments, *, cache, seed, **params):
    from .baselines.vsa import variational_shape_approximation

    r = variational_shape_approximation(mesh, n_segments, rng=seed, cache=cache, **params)
    return MethodRun(r.labels, r.n_iter, r.converged)


_SF_DEFAULTS = dict(alpha=200.0, eta_convex=0.2, init="farthest", window=2.0, max_iter=50)
register_method(
    "superfacets", _run_superfacets, defaults=_SF_DEFAULTS,
    sweep={"alpha": DEFAULT_ALPHAS},
    description="the paper's method: bounded Dijkstra k-means, weights of eqs. 1-3")
register_method(
    "shlafman", _run_shlafman, defaults=dict(_SF_DEFAULTS, alpha=0.5),
    sweep={"alpha": (0.0, 0.25, 0.5, 0.75, 1.0)},
    description="the same k-means with Shlafman et al.'s weights (eq. 6), alpha in [0, 1]")
register_method(
    "ncuts", _run_ncuts,
    defaults=dict(alpha=100.0, eta_convex=0.2, bandwidth=1.0, components=300,
                  memory_limit_gib=0.0),
    sweep={"alpha": (0.0, 100.0, 200.0)},
    description="normalized cuts: dense all-pairs distances (same weights), Gaussian affinity, "
                "k-way spectral cut (Shi-Malik / Yu-Shi); O(m^2) memory, refuses meshes over "
                "memory_limit_gib (0: 40% of RAM)")
register_method(
    "vsa", _run_vsa, defaults=dict(metric="l21", init="random", max_iter=30, insert_iter=2),
    sweep={"metric": ("l21", "l2"), "init": ("random", "incremental")},
    description="Variational Shape Approximation (Cohen-Steiner et al. 2004): planar proxies, "
                "L2,1 or L2 metric, random or incremental proxy initialization")


# --- grid ------------------------------------------------------------------------------


@dataclass(frozen=True)
class Config:
    """One method with all its parameters resolved (``n_segments`` excepted)."""

    method: str
    params: tuple  # sorted (name, value) pairs

    @property
    def kwargs(self) -> dict:
        return dict(self.params)

    def label(self) -> str:
        return self.method + "".join(f" {k}={_fmt(v)}" for k, v in self.params)


def expand_grid(method: str, **values) -> list[Config]:
    """Every combination of the given parameter values for one method.

    Parameters
    ----------
    method : str
        A registered method name.
    **values : sequence or scalar
        Values per parameter; parameters not given take their default.

    Returns
    -------
    list of Config

    Raises
    ------
    ParameterError
        On an unknown method or parameter, or an empty list of values.

    Examples
    --------
    >>> [c.label() for c in expand_grid("superfacets", alpha=[0, 200])][:1]
    ['superfacets alpha=0.0 eta_convex=0.2 init=farthest max_iter=50 window=2.0']
    """
    m = get_method(method)
    names = sorted(values)
    lists = []
    for n in names:
        v = values[n]
        v = list(v) if isinstance(v, (list, tuple, np.ndarray)) else [v]
        if not v:
            raise ParameterError(f"no values given for {n}")
        lists.append(v)
    out = []
    for combo in product(*lists):
        p = m.resolve(dict(zip(names, combo)))
        out.append(Config(method, tuple(sorted(p.items()))))
    return list(dict.fromkeys(out))


# --- results file ------------------------------------------------------------------------

_HEAD = ["mesh", "mesh_id", "category", "n_faces", "method", "n_segments"]
_TAIL = ["seed", "status", "superfacets", "iterations", "converged", "seconds", "peak_mib",
         *METRICS, "n_ground_truths", "error"]


def _param_names(configs: Iterable[Config] = ()) -> list[str]:
    names = {k for m in METHODS.values() for k in m.defaults}
    names |= {k for c in configs for k, _ in c.params}
    return sorted(names)


def columns(configs: Iterable[Config] = ()) -> list[str]:
    """Column names of a results file: fixed ones and one per method parameter."""
    return _HEAD + _param_names(configs) + _TAIL


def _fmt(v) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else str(v)
    return str(v)


def _row_key(row: dict, method: Method | None) -> tuple:
    names = sorted(method.defaults) if method is not None else []
    return (row["mesh"], row["method"], str(row["n_segments"]), str(row.get("seed", "")),
            tuple((n, str(row.get(n, ""))) for n in names))


def read_results(path) -> list[dict]:
    """Rows of a results file, as dicts of strings (a torn last line is dropped).

    Parameters
    ----------
    path : path

    Returns
    -------
    list of dict

    Raises
    ------
    FileNotFoundError
    superfacets.MeshFormatError
        If the file has no header row with the runner's columns.
    """
    from .errors import MeshFormatError

    text = Path(path).read_text()
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]  # a row torn by a hard kill
    rows = list(csv.DictReader(io.StringIO(text)))
    if text.strip() and (not rows and "method" not in text.splitlines()[0]
                         or rows and not {"mesh", "method", "status"} <= set(rows[0])):
        raise MeshFormatError(f"{path}: not a superfacets results file "
                              f"(no mesh/method/status columns)")
    return rows


def _prepare_file(path: Path, cols: list[str]) -> tuple[list[str], list[dict]]:
    """Existing rows, the file's columns (extended if needed), torn line repaired."""
    from .io import atomic_write

    if not path.exists() or path.stat().st_size == 0:
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(cols)
        atomic_write(path, buf.getvalue().encode())
        return cols, []
    raw = path.read_text()
    rows = read_results(path)
    header = next(csv.reader(io.StringIO(raw)))
    merged = header + [c for c in cols if c not in header]
    if merged != header or not raw.endswith("\n"):
        buf = io.StringIO()
        w = csv.DictWriter(buf, merged, restval="", lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
        atomic_write(path, buf.getvalue().encode())
    return merged, rows


# --- the worker -------------------------------------------------------------------------


@lru_cache(maxsize=2)
def _load(path: str, seg_paths: tuple):
    from .datasets.psb import BenchmarkMesh

    bm = BenchmarkMesh(0, "", Path(path), tuple(Path(p) for p in seg_paths))
    mesh = bm.load()
    return mesh, bm.ground_truths(mesh.n_faces)


def _error_text(exc: BaseException) -> str:
    text = f"{type(exc).__name__}: {exc}".replace("\n", " ").strip()
    if not isinstance(exc, (ValueError, OSError, MemoryError, Skipped)):
        # an unexpected error: say where it came from
        tb = traceback.extract_tb(exc.__traceback__)
        if tb:
            text += f" (at {Path(tb[-1].filename).name}:{tb[-1].lineno})"
    return text[:500]


def _run_task(task: dict) -> list[dict]:
    """Run one config over a list of n_segments on one mesh; one row each."""
    from .metrics import evaluate

    base = dict(task["base"])
    run = task["run"]
    params = dict(task["params"])
    rows = []
    try:
        mesh, gts = _load(task["path"], task["seg_paths"])
        base["n_faces"] = mesh.n_faces
    except Exception as exc:  # noqa: BLE001 - recorded, the run goes on
        return [dict(base, n_segments=k, status="failed", error=_error_text(exc))
                for k in task["ks"]]
    cache: dict = {}
    task_peak = 0.0
    for k in task["ks"]:
        row = dict(base, n_segments=k)
        try:
            probe = PeakMemory()
            t0 = time.perf_counter()
            out = run(mesh, k, cache=cache, seed=task["seed"], **params)
            seconds = time.perf_counter() - t0
            peak = probe.peak_mib()
            row["seconds"] = round(seconds + float(out.reused_seconds), 4)
            if peak is not None:
                task_peak = max(task_peak, peak)
                row["peak_mib"] = round(task_peak if out.reused_seconds else peak, 1)
            labels = np.asarray(out.labels)
            if labels.shape != (mesh.n_faces,):
                raise RuntimeError(f"method returned {labels.shape} labels for "
                                   f"{mesh.n_faces} faces")
            row.update(status="ok", superfacets=int(np.unique(labels).size),
                       iterations=out.n_iter, converged=out.converged,
                       n_ground_truths=len(gts))
            if gts:
                row.update({m: round(v, 6) for m, v in
                            evaluate(mesh, labels, gts, tau=task["tau"]).items()})
        except Skipped as exc:
            row.update(status="skipped", error=str(exc)[:500], seconds=None)
        except Exception as exc:  # noqa: BLE001 - recorded, the run goes on
            row.update(status="failed", error=_error_text(exc), seconds=None)
        rows.append(row)
    return rows


class PeakMemory:
    """Peak resident memory of this process since creation, above its start.

    Linux only: resets the kernel's high-water mark (``/proc/self/clear_refs``)
    and reads ``VmHWM`` / ``VmRSS`` from ``/proc/self/status``. Elsewhere
    :meth:`peak_mib` returns None.
    """

    def __init__(self) -> None:
        self.start = None
        try:
            with open("/proc/self/clear_refs", "w") as f:
                f.write("5")
            self.start = self._read("VmRSS")
        except OSError:
            pass

    @staticmethod
    def _read(field: str) -> float | None:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1]) / 1024.0  # kB -> MiB
        return None

    def peak_mib(self) -> float | None:
        """MiB of resident memory at the peak since creation, above the start."""
        if self.start is None:
            return None
        try:
            hwm = self._read("VmHWM")
        except OSError:
            return None
        return None if hwm is None else max(0.0, hwm - self.start)


def _init_worker() -> None:  # pragma: no cover - runs in the workers
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C


# --- the runner -------------------------------------------------------------------------


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
    """

    path: Path
    done_before: int = 0
    ok: int = 0
    failed: int = 0
    skipped: int = 0
    seconds: float = 0.0
    interrupted: bool = False

    @property
    def written(self) -> int:
        return self.ok + self.failed + self.skipped


def _default_workers() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def run_experiment(meshes: Sequence, configs: Sequence[Config], results,
                   n_segments: Sequence[int] = DEFAULT_N_SEGMENTS, *, workers: int | None = None,
                   tau: float = 0.05, seed: int = 0, retry_failed: bool = False,
                   progress: bool = True) -> ExperimentSummary:
    """Run every config at every ``n_segments`` on every mesh, appending rows.

    Parameters
    ----------
    meshes : sequence of BenchmarkMesh
        Meshes with their ground truths (:func:`superfacets.datasets.psb.list_meshes`);
        a mesh without ground truths gets rows without metrics.
    configs : sequence of Config
        From :func:`expand_grid`.
    results : path
        CSV file, created if missing, appended to otherwise. Rows already
        there (same mesh, method, parameters, ``n_segments`` and ``seed``)
        are not run again.
    n_segments : sequence of int, default (50, 100, ..., 300)
    workers : int, optional
        Worker processes (default: all cores available). 1 runs in this
        process.
    tau : float, default 0.05
        Overlap tolerance of the undersegmentation error.
    seed : int, default 0
        Passed to every method (for those that draw random numbers).
    retry_failed : bool, default False
        Run again the rows recorded as ``failed`` (the new row is appended;
        :func:`superfacets.report.load_results` keeps the last one).
    progress : bool, default True
        Show a progress bar (rows) on stderr.

    Returns
    -------
    ExperimentSummary

    Raises
    ------
    ParameterError
        On an empty grid, a bad ``n_segments``, ``workers`` or ``tau``.
    """
    if not configs:
        raise ParameterError("no method configuration to run")
    ks = sorted({int(k) for k in n_segments})
    if not ks or ks[0] < 1:
        raise ParameterError(f"n_segments must be positive integers, got {list(n_segments)}")
    if not (0 <= tau < 1):
        raise ParameterError(f"tau must be in [0, 1), got {tau}")
    workers = _default_workers() if workers is None else int(workers)
    if workers < 1:
        raise ParameterError(f"workers must be >= 1, got {workers}")
    path = Path(results)
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a directory")
    if not path.parent.is_dir():
        raise FileNotFoundError(f"{path}: folder {path.parent} does not exist")
    cols, old = _prepare_file(path, columns(configs))
    done = {_row_key(r, METHODS.get(r["method"])) for r in old
            if not (retry_failed and r.get("status") == "failed")}

    tasks = []
    for bm, cfg in product(meshes, configs):
        base = {"mesh": Path(bm.path).stem, "mesh_id": bm.id, "category": bm.category,
                "method": cfg.method, "seed": seed, **{k: _fmt(v) for k, v in cfg.params}}
        method = get_method(cfg.method)
        todo = [k for k in ks if _row_key({**base, "n_segments": k}, method) not in done]
        if todo:
            tasks.append({"base": base, "run": method.run, "params": cfg.params,
                          "path": str(bm.path), "seg_paths": tuple(str(p) for p in bm.seg_paths),
                          "ks": todo, "seed": seed, "tau": tau})
    summary = ExperimentSummary(path, done_before=len(done))
    total = sum(len(t["ks"]) for t in tasks)
    t0 = time.perf_counter()
    bar = None
    if progress and total:
        from tqdm import tqdm

        bar = tqdm(total=total, unit="row", desc="experiment", dynamic_ncols=True)

    with open(path, "a", newline="") as f:
        writer = csv.DictWriter(f, cols, restval="", extrasaction="ignore", lineterminator="\n")

        def record(rows: list[dict]) -> None:
            for r in rows:
                writer.writerow({k: _fmt(v) for k, v in r.items()})
                setattr(summary, r["status"], getattr(summary, r["status"]) + 1)
            f.flush()
            if bar is not None:
                bar.update(len(rows))
                bar.set_postfix(failed=summary.failed, skipped=summary.skipped, refresh=False)

        try:
            if workers == 1 or len(tasks) <= 1:
                for t in tasks:
                    record(_run_task(t))
            else:
                _run_pool(tasks, workers, record)
        except KeyboardInterrupt:
            summary.interrupted = True
        finally:
            if bar is not None:
                bar.close()
    summary.seconds = time.perf_counter() - t0
    return summary


def _failed_rows(task: dict, error: str) -> list[dict]:
    return [dict(task["base"], n_segments=k, status="failed", error=error) for k in task["ks"]]


def _run_pool(tasks: list[dict], workers: int, record) -> None:
    """Feed tasks to a process pool, a bounded number in flight; survive dead workers.

    When a worker dies (killed, out of memory, a crash in native code) the
    pool breaks and every task then in flight is suspect: each is run again
    alone in a fresh one-worker pool, so only the task that kills its worker
    on its own is recorded as failed.
    """
    import multiprocessing as mp

    env = {v: "1" for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                            "NUMBA_NUM_THREADS")}
    # glibc: arrays of 64 KiB and more get their own pages, returned to the system when
    # freed, so each call's peak resident memory (peak_mib) is its own, not hidden by
    # memory kept from an earlier call
    env["MALLOC_MMAP_THRESHOLD_"] = "65536"
    saved = {v: os.environ.get(v) for v in env}
    os.environ.update(env)  # one thread per worker process; inherited at spawn
    ctx = mp.get_context("spawn")
    queue = list(reversed(tasks))
    suspects: list[dict] = []

    def collect(fut, t) -> list[dict]:
        try:
            return fut.result()
        except BrokenProcessPool:
            raise
        except Exception as exc:  # noqa: BLE001 - e.g. a method that cannot be pickled
            return _failed_rows(t, _error_text(exc))

    try:
        while queue or suspects:
            if suspects:
                t = suspects.pop()
                with ProcessPoolExecutor(1, mp_context=ctx, initializer=_init_worker) as pool:
                    try:
                        rows = collect(pool.submit(_run_task, t), t)
                    except BrokenProcessPool:
                        rows = _failed_rows(t, "worker process died (killed, e.g. out of "
                                               "memory, or crashed)")
                record(rows)
                continue
            with ProcessPoolExecutor(workers, mp_context=ctx, initializer=_init_worker) as pool:
                running: dict = {}
                try:
                    while queue or running:
                        while queue and len(running) < 2 * workers:
                            t = queue.pop()
                            running[pool.submit(_run_task, t)] = t
                        finished, _ = wait(running, return_when=FIRST_COMPLETED)
                        try:
                            for fut in finished:
                                rows = collect(fut, running[fut])
                                del running[fut]
                                record(rows)
                        except BrokenProcessPool:
                            suspects.extend(running.values())
                            break
                except KeyboardInterrupt:
                    # drop what has not started; the tasks running finish (workers ignore SIGINT)
                    pool.shutdown(wait=True, cancel_futures=True)
                    raise
    finally:
        for v, old in saved.items():
            if old is None:
                os.environ.pop(v, None)
            else:
                os.environ[v] = old
