"""The ``superfacets`` command line: one module per command group.

- :mod:`.segmenting`: ``segment`` (superfacets of a mesh file, as a ``.seg``
  label file and/or a coloured PLY), ``baseline`` (any registered method),
  ``demo`` (a built-in procedural mesh, no data needed);
- :mod:`.evaluating`: ``evaluate`` (the metrics of a result against ground
  truths: faces, vertices or a labelled scan's points);
- :mod:`.batching`: ``batch`` (many files with the same options, resumable, a
  manifest; on a local or a running Dask cluster);
- :mod:`.experiments`: ``experiment`` (methods x parameters over the
  Princeton benchmark, resumable) and ``report`` (figures and tables);
- :mod:`.pictures`: ``render`` (PNG, off-screen), ``panel`` (settings side by
  side), ``view`` (a window) and ``html`` (a self-contained web page);
- :mod:`.options`: the options they share.

Bad input (missing, unreadable or malformed files, invalid parameters) ends
with one line ``superfacets: error: ...`` on stderr and exit status 2; no
output file is written unless the whole run succeeded.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

__all__ = ["main", "build_parser"]


class _Version(argparse.Action):
    """``--version``: the version, and the kernels a run uses (the compiled ones, with the
    threads they may take; or why they cannot run)."""

    def __init__(self, option_strings, version, dest=argparse.SUPPRESS,
                 default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest, default=default, nargs=0, help=help)
        self.version = version

    def __call__(self, parser, namespace, values, option_string=None):
        from .._kernels import native

        if native.available():
            cxx = native.require()
            kernels = (f"compiled kernels: C++ ({cxx.compiler}), up to {cxx.threads()} "
                       "threads")
        else:
            kernels = f"no kernels: the compiled ones are {native.missing_because()}"
        print(f"{self.version} ({kernels})")
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every command (each sub-parser sets ``func``)."""
    from .._version import __version__
    from . import batching, evaluating, experiments, pictures, segmenting

    parser = _Parser(
        prog="superfacets",
        description="Over-segment meshes (triangles or polygons), point clouds and "
                    "tetrahedral meshes into superfacets and superpoints (Simari, Picciau, "
                    "De Floriani, 'Fast and Scalable Mesh Superfacets', 2014).")
    parser.add_argument("--version", action=_Version, version=f"superfacets {__version__}",
                        help="show the version and whether the compiled kernels are built")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    segmenting.add_parsers(sub)
    evaluating.add_parsers(sub)
    batching.add_parsers(sub)
    experiments.add_parsers(sub)
    pictures.add_parsers(sub)
    return parser


class _Parser(argparse.ArgumentParser):
    """An argument parser whose 'unrecognized arguments' error names the nearest
    options (``--k`` -> ``-k``, ``--n_segments`` -> ``--n-segments``), and which takes no
    abbreviated option: ``--seed 3`` was ``--seed-resolution 3`` (one superpoint per 9
    square units, said only in the summary), ``--labels b.seg`` was ``--labels-from
    b.seg``."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)  # (its sub-parsers are of this class)
        super().__init__(*args, **kwargs)

    def error(self, message: str):
        if message.startswith("unrecognized arguments:"):
            message += _did_you_mean(self, message.split(":", 1)[1].split())
        super().error(message)


def _did_you_mean(parser: argparse.ArgumentParser, unknown: list[str]) -> str:
    import difflib

    options = set()
    stack = [parser]
    argv = getattr(parser, "argv", None) or []
    while stack:
        p = stack.pop()
        for action in p._actions:
            options.update(action.option_strings)
            if isinstance(action, argparse._SubParsersAction):  # the command given, or all
                chosen = [action.choices[a] for a in argv if a in action.choices][:1]
                stack.extend(chosen or action.choices.values())
    hints = []
    for token in unknown:
        if not token.startswith("-"):
            continue
        name = token.split("=", 1)[0]
        near = [o for o in sorted(options) if o.startswith(name) and len(name) > 2][:3] or \
            difflib.get_close_matches(name.replace("_", "-"), sorted(options), n=2, cutoff=0.6)
        if near:
            hints.append(f"{name}: did you mean {' or '.join(near)}?")
    return ("; " + "; ".join(hints)) if hints else ""


def _scene_folder(args) -> None:
    """A scene folder given as the input (Pointcept's layout, ``scene0000_00/``) is its
    ``coord.npy`` (read with the ``color.npy`` and ``normal.npy`` beside it)."""
    given = getattr(args, "mesh", None)
    if isinstance(given, str) and Path(given).is_dir() and (Path(given) / "coord.npy").is_file():
        args.mesh = str(Path(given) / "coord.npy")


def _late_files(parser, args, extra: list) -> None:
    """Files named after an option (``evaluate scan.laz --labels-from ClusterID gt.seg``),
    which argparse leaves over once its optional positionals matched nothing: into the
    command's ``late_files`` (its optional LABELS first where empty, then its list);
    anything else left over is refused as ``parse_args`` refuses it."""
    slots = getattr(args, "late_files", None)
    if extra and slots and not any(e.startswith("-") and e != "-" for e in extra):
        first, rest = slots
        if getattr(args, first) is None:
            setattr(args, first, extra[0])
            extra = extra[1:]
        setattr(args, rest, [*getattr(args, rest), *extra])
        extra = []
    if extra:
        parser.error(f"unrecognized arguments: {' '.join(extra)}")


def _labels_option(parser, args) -> None:
    """``--labels FILE``, the commands' LABELS given by name (``render scan.laz --labels
    b.seg``): into LABELS, where evaluate's LABELS slot then held its first ground truth;
    evaluate's ``--ground-truth GT`` after its other ground truths."""
    if getattr(args, "ground_truth_files", None):
        args.ground_truths = [*args.ground_truths, *args.ground_truth_files]
    given = getattr(args, "labels_file", None)
    if given is None:
        return
    if args.labels is not None and not hasattr(args, "ground_truths"):
        parser.error(f"give the labels once: LABELS ({args.labels}) or --labels ({given})")
    if args.labels is not None:  # (evaluate INPUT --labels L GT...: GT read as LABELS)
        args.ground_truths = [args.labels, *args.ground_truths]
    args.labels = given


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
    from ..errors import NoDisplayError, SuperfacetsError

    restore = _terminate_cleanly()  # first: Ctrl-C during the imports too
    if argv is None and hasattr(sys.stdout, "reconfigure"):  # (a file's name in letters
        sys.stdout.reconfigure(errors="backslashreplace")  # the terminal's encoding lacks,
        # as stderr already writes them: not a traceback after the outputs are written)
    shown, warnings.showwarning = warnings.showwarning, _warning_line
    from .._runtime.memory import limit_arenas, limit_blas_threads

    limit_arenas()  # (before any thread starts: see its notes)
    limit_blas_threads()  # (before numpy loads its BLAS: under `ulimit -v`, one thread)
    try:
        parser = build_parser()
        parser.argv = list(sys.argv[1:] if argv is None else argv)  # for its error hints
        args, extra = parser.parse_known_args(_axis_values(parser.argv))
        _late_files(parser, args, extra)
        _labels_option(parser, args)
        _scene_folder(args)
        code = args.func(args)
        if getattr(restore, "state", {}).get("terminated"):  # a SIGTERM the run went on
            print("superfacets: terminated", file=sys.stderr)  # past (swallowed on the
            return 143  # way, or heard by a kernel that stopped in order): said, as 143
        return code
    except SystemError as exc:  # numba's dispatcher around a KeyboardInterrupt
        if not _interrupted(exc):
            raise
        print("superfacets: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `superfacets ... | head`: the reader left; end quietly
        _silence_stdout()
        return 0
    except (SuperfacetsError, OSError, NoDisplayError) as exc:
        msg = str(exc)
        if isinstance(exc, OSError) and exc.filename and (exc.strerror or
                                                          str(exc.filename) not in msg):
            msg = f"{exc.filename}: {exc.strerror or msg}"  # (not "[Errno 2] ...: 'x'")
        print(f"superfacets: error: {msg}", file=sys.stderr)
        return 2
    except MemoryError:  # what no estimate foresaw: one line, not a traceback
        print("superfacets: error: out of memory: the input needs more memory than this "
              "process may use; segment it in tiles (--tiles N) or on a larger machine",
              file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        if getattr(getattr(restore, "watch", None), "signum", 0) == 15 or getattr(
                restore, "state", {}).get("terminated"):  # SIGTERM, heard
            # by a compiled kernel, which stopped with a KeyboardInterrupt
            print("superfacets: terminated", file=sys.stderr)
            return 143
        print("superfacets: interrupted", file=sys.stderr)
        return 130
    except _Terminated:
        print("superfacets: terminated", file=sys.stderr)
        return 143
    finally:
        warnings.showwarning = shown
        restore()
        if argv is None:  # the program itself: its work is done, a late Ctrl-C is moot
            _quiet_exit()


def _warning_line(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning as the command line says it: one line on stderr, not Python's file, line
    number and source line."""
    print(f"superfacets: warning: {message}", file=sys.stderr if file is None else file)


#: Options whose values may start with a minus: an axis (``--up -y``, ``--seen-from -z``).
_AXIS_OPTIONS = ("--up", "--seen-from")


def _axis_values(argv: list[str]) -> list[str]:
    """``--up -y`` as ``--up=-y``: argparse takes a value that starts with a minus for an
    option of its own and refuses it, where the axis was meant.

    Examples
    --------
    >>> _axis_values(["render", "m.off", "--up", "-z", "-o", "m.png"])
    ['render', 'm.off', '--up=-z', '-o', 'm.png']
    """
    out, i = [], 0
    while i < len(argv):
        a = argv[i]
        if a in _AXIS_OPTIONS and i + 1 < len(argv) and argv[i + 1] in ("-x", "-y", "-z"):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


class _Terminated(BaseException):
    """SIGTERM, raised in the main thread so that temporary files are removed."""


def _interrupted(exc: BaseException) -> bool:
    """Whether ``exc`` is, or was raised while handling, a KeyboardInterrupt."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


#: Code that an exception must not cut through anywhere in the stack: Python's import
#: machinery (an interrupted module lock leaves the process hung) and numba's dispatcher
#: and compiler (they turn it into a SystemError with a long traceback).
_NEVER_IN = ("<frozen importlib", "/numba/", "/llvmlite/")
#: Code that juggles locks: an exception at the wrong line keeps a lock taken (a thread
#: pool's workers then wait for it forever); only its blocking waits are safe to cut.
_LOCKS_IN = ("/threading.py", "/concurrent/futures/", "/queue.py", "/multiprocessing/")


def _blocking_waits() -> set:
    """(code, line) of the blocking calls of threading's waits: a Condition's wait on
    its waiter lock, a thread's join."""
    import inspect
    import threading

    out = set()
    for fn in (threading.Condition.wait, threading.Thread._wait_for_tstate_lock):
        lines, start = inspect.getsourcelines(fn)
        out.update((fn.__code__, start + i) for i, text in enumerate(lines)
                   if "waiter.acquire(" in text or "lock.acquire(" in text)
    return out


def _in_machinery(frame, waits=None) -> bool:
    """Whether a KeyboardInterrupt raised in ``frame`` (the main thread's, at a signal)
    could hang the process or turn into a traceback."""
    inner = frame
    while frame is not None:
        if any(m in frame.f_code.co_filename for m in _NEVER_IN):
            return True
        frame = frame.f_back
    if inner is not None and any(m in inner.f_code.co_filename for m in _LOCKS_IN):
        waits = _blocking_waits() if waits is None else waits
        return (inner.f_code, inner.f_lineno) not in waits
    return False


def _terminate_cleanly():
    """Turn SIGTERM and Ctrl-C into exceptions that unwind the run (temporary files are
    removed); return a function that puts the previous handlers back.

    Ctrl-C's KeyboardInterrupt is raised only outside the import machinery and numba
    (where it hangs the process or becomes a long SystemError) and again every 0.2 s
    until the run unwinds: code that swallows it (a reader's ``except BaseException``, a
    finalizer) does not keep the run going. Nothing interrupts the unwinding itself.
    """
    import os
    import signal
    import threading

    from .._runtime import interrupts

    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    interrupts.reset()
    done = threading.Event()
    waits = _blocking_waits()

    def on_term(signum, frame):
        state["terminated"] = True  # (kept: the run ends 143 even where it was swallowed)
        if _interrupted(sys.exc_info()[1]):  # a compiled kernel heard it first: stopping
            return
        raise _Terminated()

    def repeat() -> None:  # the same Ctrl-C until the run has unwound
        while not done.wait(0.2):
            os.kill(os.getpid(), signal.SIGINT)

    state = {"repeater": None, "terminated": False}

    def on_int(signum, frame):
        if done.is_set() or interrupts.was_caught() or _interrupted(sys.exc_info()[1]) \
                or interrupts.outputs_written():
            return  # unwinding, stopping in order, or done already: let the run finish
        if state["repeater"] is None:
            state["repeater"] = threading.Thread(target=repeat, daemon=True,
                                                 name="superfacets-interrupt")
            state["repeater"].start()
        if interrupts.in_commit() or _in_machinery(frame, waits):
            interrupts.pending()  # raised at the next stage boundary, if not before
            return  # the repeater comes back in 0.2 s
        raise KeyboardInterrupt

    def unraisable(event) -> None:
        # a KeyboardInterrupt raised in a finalizer cannot unwind the run: say nothing
        # (the repeater interrupts again where it can); a SIGTERM that landed in one (a
        # callback of Dask's garbage collection took it) is sent again, once, to land
        # where it unwinds the run
        if isinstance(event.exc_value, _Terminated):
            if not done.is_set():
                threading.Timer(0.05, os.kill, (os.getpid(), signal.SIGTERM)).start()
            return
        if not _interrupted(event.exc_value):
            previous_hook(event)

    try:
        previous = signal.signal(signal.SIGTERM, on_term)
        previous_int = signal.signal(signal.SIGINT, on_int)
    except (ValueError, OSError):  # pragma: no cover - not settable here
        return lambda: None
    try:
        watch = interrupts.SignalWatch()  # the compiled kernels hear them too
    except (ValueError, OSError):  # pragma: no cover - no wakeup descriptor to be had
        watch = None
    previous_hook, sys.unraisablehook = sys.unraisablehook, unraisable

    def restore():
        if watch is not None:
            watch.close()
        done.set()
        if state["repeater"] is not None:  # no Ctrl-C of ours after the handlers go back
            state["repeater"].join()
        interrupts.reset()  # nothing pending for a later run in this process
        signal.signal(signal.SIGTERM, previous)
        signal.signal(signal.SIGINT, previous_int)
        sys.unraisablehook = previous_hook

    restore.watch = watch
    restore.state = state
    return restore


def _quiet_exit() -> None:
    """Ignore Ctrl-C while the interpreter exits (Dask's and numba's exit handlers would
    otherwise print a KeyboardInterrupt traceback after the run's last line); a SIGTERM
    then exits 143 (the outputs are whole), not by the signal."""
    import os
    import signal
    import threading

    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        # the outputs are whole by now: a SIGTERM ends the exit with 143, as during the run
        signal.signal(signal.SIGTERM, lambda signum, frame: os._exit(143))
        # a run interrupted may have left a thread of its kernels running (a Ctrl-C
        # between two of the waiting's bytecodes): wait for it here, where no Ctrl-C
        # lands, so that it never returns to an interpreter being finalized (an abort)
        from .._runtime.threads import wait_for_stragglers

        wait_for_stragglers()


def _silence_stdout() -> None:
    """Point stdout at /dev/null so that the interpreter's final flush stays quiet."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # pragma: no cover
        pass


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
