"""The engine that runs independent tasks: in this process, or on Dask.

One engine serves ``superfacets batch`` (:mod:`.batch`) and ``superfacets
experiment`` (:mod:`.experiment`). A task is a small picklable dict naming its
input by path (never an array), so the scheduler never holds meshes; its
function returns a small result (a row or a list of rows) and writes any
large output itself.

- One worker and no scheduler: the tasks run one after the other in this
  process (no Dask needed, no start-up cost).
- Otherwise ``dask.distributed`` (the ``distributed`` extra): by default a
  :class:`~distributed.LocalCluster` of single-threaded worker processes,
  one per core; or an existing cluster given by its scheduler's address
  (``scheduler=``, or Dask's ``DASK_SCHEDULER_ADDRESS``), whose workers
  must see the same files (a shared filesystem) and have ``superfacets``
  installed.

A worker that dies (killed, out of memory, a crash in native code) is
restarted by its nanny and its task is run again elsewhere, up to Dask's
``distributed.scheduler.allowed-failures`` times; after that the task ends
through ``on_lost`` (a failed row), never a lost run.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import traceback
import uuid
from pathlib import Path
from typing import Callable, Iterable, Iterator

from ..._runtime import extras
from ...checks import max_threads
from ...errors import ParameterError

__all__ = ["Engine", "PeakMemory", "default_workers", "error_text", "LOST_WORKER",
           "QUIET_CLUSTER", "check_memory_limit", "MIN_WORKER_MEMORY"]

#: The least memory a local worker may be given: a worker process holds about 100 MiB
#: before any task (Python, NumPy, Dask); under that it is killed or paused at once
#: (1 KB: a batch that never ended; 50 MiB: every input failed).
MIN_WORKER_MEMORY = 128 * 2**20

#: The error text of a task whose worker died each time it ran it.
LOST_WORKER = "worker process died (killed, e.g. out of memory, or crashed)"

#: Environment of local worker processes: one thread each (the engine runs one task per core).
_WORKER_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
               "SUPERFACETS_NUM_THREADS": "1", "SUPERFACETS_KERNEL_THREADS": "1"}
#: Dask settings of the engine's own local cluster that cut its CPU while tasks run, none
#: of which a run reads: the workers' statistical profiler (a stack sample every 10 ms, for
#: the dashboard's profile page, off), the event loop's tick (20 ms -> 200 ms: it only
#: warns of a blocked loop) and the system monitor (0.5 s -> 2 s: the dashboard's plots;
#: the nanny's memory limit has its own monitor). Two idle workers and their scheduler
#: used 7.7 s of CPU over 30 s with Dask's defaults, 5.7 s with these (this 2-core machine).
QUIET_CLUSTER = {"distributed.worker.profile.enabled": False,
                 "distributed.admin.tick.interval": "200ms",
                 "distributed.admin.system-monitor.interval": "2s"}

#: With ``exact_memory``: glibc gives arrays of 64 KiB and more back to the system when
#: freed, so each task's peak resident memory is its own, not hidden by memory kept from an
#: earlier task. It costs time (fresh pages for every array: about +15 % on the benchmark's
#: meshes), so only the experiments, which report memory, ask for it.
_EXACT_MEMORY_ENV = {"MALLOC_MMAP_THRESHOLD_": "65536", "MALLOC_TRIM_THRESHOLD_": "65536"}


def check_memory_limit(memory_limit):
    """``memory_limit`` of local workers, checked: ``'auto'``, or ``None`` or 0 (no limit),
    or a float in ``(0, 1]`` (Dask's share of the machine's memory), as given; else a size
    (``'4GiB'``, ``'500MB'``, bytes) of at least :data:`MIN_WORKER_MEMORY`, in bytes.

    Raises
    ------
    ParameterError
        On a value that is no size, or a size under :data:`MIN_WORKER_MEMORY`.

    Examples
    --------
    >>> check_memory_limit("1GiB"), check_memory_limit("auto")
    (1073741824, 'auto')
    """
    import numbers

    if memory_limit is None or memory_limit == "auto" or (
            isinstance(memory_limit, numbers.Real) and not isinstance(memory_limit, bool)
            and memory_limit == 0):
        return memory_limit
    said = (f"memory_limit must be a size such as 4GiB or 500MB (or auto), got "
            f"{memory_limit!r}")
    if isinstance(memory_limit, str):
        size = _bytes_of(memory_limit.strip())
        if size is None:
            raise ParameterError(said)
    elif isinstance(memory_limit, numbers.Real) and not isinstance(memory_limit, bool):
        size = float(memory_limit)
        if isinstance(memory_limit, float) and 0 < size <= 1:  # (Dask's share of the memory)
            return size
    else:
        raise ParameterError(said)
    if size == 0:  # (Dask's "no limit")
        return 0
    if not math.isfinite(size):
        raise ParameterError(said)
    if size < MIN_WORKER_MEMORY:
        raise ParameterError(f"memory_limit {memory_limit!r} is below what a worker process "
                             f"takes before any work: give at least "
                             f"{MIN_WORKER_MEMORY // 2**20} MiB")
    return int(size)


def _bytes_of(text: str) -> float | None:
    """Bytes of a size in Dask's syntax (``dask.utils.parse_bytes``: ``'4GiB'``, ``'500
    MB'``, ``'1e9'``), None where it is not one."""
    try:
        from dask.utils import parse_bytes
    except ImportError:  # (no Dask: a plain number of bytes)
        try:
            return float(text)
        except ValueError:
            return None
    try:
        return float(parse_bytes(text))
    except (ValueError, TypeError):
        return None


def default_workers() -> int:
    """The cores this process may run on (at least 1)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def _have_dask() -> bool:
    import importlib.util

    return importlib.util.find_spec("distributed") is not None


def _scheduler_from_config() -> str | None:
    try:
        import dask.config
    except ImportError:
        return os.environ.get("DASK_SCHEDULER_ADDRESS") or None
    return dask.config.get("scheduler-address", None) or None


@contextlib.contextmanager
def _sigint_held():
    """Keep Ctrl-C (SIGINT) from the worker processes started meanwhile, not from us.

    SIGINT is blocked in this thread while the cluster starts: the threads it starts
    (Dask's event loop, which starts the workers) and the worker processes (a new process
    inherits the signal mask) keep it blocked, so a Ctrl-C in the terminal, which reaches
    every process of the group, interrupts this process alone; it then closes the
    cluster, and the workers with it, without a traceback from each. A Ctrl-C meanwhile
    waits and comes once this thread unblocks it. multiprocessing's resource tracker is
    started first: starting it unblocks SIGINT in the thread that starts it.
    """
    import signal
    import threading
    from multiprocessing import resource_tracker

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    resource_tracker.ensure_running()
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def error_text(exc: BaseException) -> str:
    """One line (at most 500 characters) saying what went wrong; where an
    unexpected error came from."""
    text = f"{type(exc).__name__}: {exc}".replace("\n", " ").strip()
    if not isinstance(exc, (ValueError, OSError, MemoryError)) and \
            type(exc).__name__ != "Skipped":
        # an unexpected error: say where it came from
        tb = traceback.extract_tb(exc.__traceback__)
        if tb:
            text += f" (at {Path(tb[-1].filename).name}:{tb[-1].lineno})"
    return text[:500]


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

    def peak_mib(self, above_start: bool = True) -> float | None:
        """MiB of resident memory at the peak since creation: above the start, or (with
        ``above_start=False``) the whole process's (what a memory limit sees)."""
        if self.start is None:
            return None
        try:
            hwm = self._read("VmHWM")
        except OSError:
            return None
        if hwm is None:
            return None
        return max(0.0, hwm - self.start) if above_start else hwm


class Engine:
    """Run tasks in this process or on a Dask cluster; results as they complete.

    Use as a context manager: entering starts (or connects to) the cluster,
    so that a bad address or a missing extra is one clear error before any
    work; leaving stops what was started.

    Parameters
    ----------
    workers : int, optional
        Local worker processes (default: one per core, or this process alone
        where ``distributed`` is not installed: see :attr:`note`). ``1`` with
        no scheduler runs the tasks in this process. Ignored with a scheduler.
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``); default
        Dask's ``scheduler-address`` setting (``DASK_SCHEDULER_ADDRESS``).
    memory_limit : str or float, default 'auto'
        Local workers: memory limit of each (Dask's syntax: ``'4GiB'``, bytes,
        or ``'auto'`` = the machine's memory shared out; at least
        :data:`MIN_WORKER_MEMORY`, :func:`check_memory_limit`); a worker passing 95 %
        of it is restarted and its task counts as a failure.
    connect_timeout : float, default 10
        Seconds to reach the scheduler.
    wait_workers : float, default 60
        Seconds to wait for an external cluster to have a worker.
    dask : bool, optional
        True: a local Dask cluster even for one worker (crash isolation, or to
        measure the engine's overhead); default: Dask unless one worker.
    exact_memory : bool, default False
        Local workers: each task's peak memory measured alone (glibc returns
        freed arrays to the system at once), at some cost in time.

    Raises
    ------
    ParameterError
        On a ``workers`` count or ``memory_limit`` out of range.
    MissingExtraError
        On entering, where Dask is needed and ``distributed`` is not installed.
    SchedulerError
        On entering, where the scheduler cannot be reached or has no worker, or where the
        local workers cannot start (a script that starts them outside
        ``if __name__ == "__main__":``).

    Examples
    --------
    >>> with Engine(workers=1) as engine:
    ...     sorted(engine.run(abs, [-2, 1], on_lost=lambda t, e: None))
    [1, 2]
    """

    def __init__(self, workers: int | None = None, scheduler: str | None = None, *,
                 memory_limit="auto", connect_timeout: float = 10.0,
                 wait_workers: float = 60.0, dask: bool | None = None,
                 exact_memory: bool = False) -> None:
        import numbers

        if workers is not None and (isinstance(workers, bool) or not isinstance(
                workers, numbers.Integral) or not 1 <= workers <= max_threads()):
            raise ParameterError(f"workers must be an integer in 1..{max_threads()} (at most "
                                 f"4 per core), got {workers!r}")
        self.scheduler = scheduler if scheduler else _scheduler_from_config()
        self.workers = default_workers() if workers is None else int(workers)
        #: a line for the user where the engine chose for them (no Dask: in this process)
        self.note = ""
        if workers is None and not self.scheduler and not dask and not _have_dask():
            self.workers = 1
            self.note = ("dask.distributed is not installed: running in this process; "
                         "pip install 'superfacets[distributed]' for one worker per core")
        self.memory_limit = check_memory_limit(memory_limit)
        self.connect_timeout = connect_timeout
        self.wait_workers = wait_workers
        self.force_dask = bool(dask)
        self.exact_memory = bool(exact_memory)
        self.client = None
        self._cluster = None
        self._saved_env: dict | None = None

    @property
    def local(self) -> bool:
        """True where the tasks run in this process."""
        return self.workers == 1 and not self.scheduler and not self.force_dask

    def describe(self) -> str:
        """A short line: where the tasks run."""
        if self.local:
            return "in this process" + (f" ({self.note})" if self.note else "")
        if self.scheduler:
            n = len(self.client.scheduler_info().get("workers", {})) if self.client else "?"
            return f"on the Dask cluster at {self.scheduler} ({n} workers)"
        return f"on a local Dask cluster of {self.workers} worker process" + (
            "es" if self.workers > 1 else "")

    def __enter__(self) -> "Engine":
        if self.local:
            return self

        extras.require("distributed", "running on Dask (--workers > 1, --scheduler)")
        import dask
        from distributed import Client

        from ...errors import SchedulerError

        if self.scheduler:
            try:
                self.client = Client(self.scheduler, timeout=f"{self.connect_timeout}s",
                                     set_as_default=False)
            except (OSError, TimeoutError, ValueError) as exc:
                raise SchedulerError(
                    f"cannot reach the Dask scheduler at {self.scheduler} "
                    f"({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})"
                ) from None
            try:
                self.client.wait_for_workers(1, timeout=self.wait_workers)
            except (TimeoutError, OSError):
                self.client.close()
                raise SchedulerError(f"the Dask scheduler at {self.scheduler} has no worker "
                                     f"after {self.wait_workers:g} s; start some with "
                                     f"'dask worker {self.scheduler}'") from None
            return self
        from distributed import LocalCluster

        mine = dict(_WORKER_ENV, **(_EXACT_MEMORY_ENV if self.exact_memory else {}))
        self._saved_env = {k: os.environ.get(k) for k in (*mine, *_EXACT_MEMORY_ENV)}
        env = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}), **mine)
        if not self.exact_memory:  # glibc's own (dynamic) thresholds: the fastest
            for k in _EXACT_MEMORY_ENV:
                env.pop(k, None)
                os.environ.pop(k, None)
        try:
            # worker-saturation 1: a worker holds only the task it runs, so when it dies no
            # other task is blamed (crash isolation: only a task that kills its worker each
            # time it runs fails)
            with dask.config.set({"distributed.nanny.pre-spawn-environ": env,
                                  "distributed.scheduler.worker-saturation": 1.0,
                                  "distributed.worker.daemon": True, **QUIET_CLUSTER}):
                with _sigint_held():  # the workers ignore Ctrl-C: it is ours alone
                    self._cluster = LocalCluster(
                        n_workers=self.workers, threads_per_worker=1, processes=True,
                        dashboard_address=None, memory_limit=self.memory_limit,
                        silence_logs=logging.CRITICAL,
                        # the scheduler's HTTP routes (no dashboard) on a free local port:
                        # its default, 8787, taken by another run, printed Dask's warning
                        scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
                self.client = Client(self._cluster, set_as_default=False)
        except RuntimeError as exc:  # (Dask: "Nanny failed to start.")
            self.__exit__(None, None, None)
            if "failed to start" not in str(exc):
                raise
            from ...errors import SchedulerError

            raise SchedulerError(
                f"the local Dask workers did not start ({exc}). In a script, run this under "
                "'if __name__ == \"__main__\":' (each worker is a new Python process that "
                "imports the script first); or use one worker (workers=1, -j 1)") from None
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc) -> None:
        # quiet shutdown: the nannies log closed connections as the cluster goes
        logging.getLogger("distributed").setLevel(logging.CRITICAL)
        try:
            if self.client is not None:
                self.client.close()
            if self._cluster is not None:
                self._cluster.close()
        except Exception:  # noqa: BLE001 - nothing to keep; the results are written  # pragma: no cover
            pass
        finally:
            self.client = self._cluster = None
            if self._saved_env is not None:  # Dask sets these in this process to spawn
                for k, v in self._saved_env.items():
                    if v is None:
                        os.environ.pop(k, None)
                    else:
                        os.environ[k] = v
                self._saved_env = None

    def run(self, fn: Callable, tasks: Iterable, on_lost: Callable,
            prefer: Callable | None = None) -> Iterator:
        """Yield ``fn(task)`` for every task, in the order they complete.

        Parameters
        ----------
        fn : callable
            A module-level function (workers import it by reference); it
            should catch its own errors and return them as its result.
        tasks : iterable
            Small picklable objects (paths and options, not arrays).
        on_lost : callable
            ``on_lost(task, error_text)`` makes the result of a task that
            raised, or whose worker died each time it ran it.
        prefer : callable, optional
            ``prefer(task)``: the address of the Dask worker to run it on where that
            worker is there and free (None: any; a tiled run sends a tile to the worker
            that holds its box from the phase before); another worker runs it if that
            one has gone.

        Yields
        ------
        object
            One result per task.
        """
        if self.local:
            for t in tasks:
                try:
                    yield fn(t)
                except Exception as exc:  # noqa: BLE001 - the run goes on
                    yield on_lost(t, error_text(exc))
            return
        yield from self._run_dask(fn, list(tasks), on_lost, prefer)

    def on_workers(self, fn: Callable, *args) -> None:
        """Run ``fn(*args)`` here and, on Dask, once in every worker (what a worker holds
        for a run let go at its end); a worker that fails it is left as it is."""
        fn(*args)
        if self.local or self.client is None:
            return
        try:
            self.client.run(fn, *args)
        except Exception:  # noqa: BLE001 - best effort: the workers let it go later  # pragma: no cover
            pass

    def _run_dask(self, fn, tasks: list, on_lost, prefer=None) -> Iterator:
        from distributed import as_completed

        client = self.client
        threads = sum(client.nthreads().values()) or 1
        window = max(4, 2 * threads)  # a bounded number in flight: the scheduler holds few
        tag = uuid.uuid4().hex[:8]
        name = getattr(fn, "__name__", "task")
        pending = list(reversed(list(enumerate(tasks))))
        owner: dict = {}  # key -> (future, task) of the tasks in flight

        def submit() -> None:
            i, t = pending.pop()
            where = prefer(t) if prefer is not None else None
            near = {} if where is None else {"workers": [where], "allow_other_workers": True}
            fut = client.submit(fn, t, key=f"{name}-{tag}-{i}", pure=False, **near)
            owner[fut.key] = (fut, t)
            done.add(fut)

        done = as_completed([], loop=client.loop, with_results=False)
        try:
            for _ in range(min(window, len(pending))):
                submit()
            for fut in done:
                t = owner.pop(fut.key)[1]
                if fut.status == "finished":
                    result = fut.result()
                else:
                    result = on_lost(t, _lost_text(fut))
                fut.release()
                if pending:
                    submit()
                yield result
        finally:
            if owner:  # interrupted: drop what has not finished
                try:
                    client.cancel([f for f, _ in owner.values()], force=True)
                except Exception:  # noqa: BLE001 - the cluster is going anyway  # pragma: no cover
                    pass


def _lost_text(fut) -> str:
    """The error text of a future that did not finish."""
    try:
        exc = fut.exception()
    except Exception as e:  # noqa: BLE001 - cancelled, or the connection went
        exc = e
    kind = type(exc).__name__
    if kind == "KilledWorker":
        return LOST_WORKER
    return f"{kind}: {exc}".replace("\n", " ")[:500]

