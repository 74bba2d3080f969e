"""The ``superfacets`` command line: one module per command group.

- :mod:`.segmenting`: ``segment`` (superfacets of a mesh file, as a ``.seg``
  label file and/or a coloured PLY), ``baseline`` (any registered method),
  ``demo`` (a built-in procedural mesh, no data needed) and ``evaluate``
  (the metrics of a result against ground truths);
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

__all__ = ["main", "build_parser"]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every command (each sub-parser sets ``func``)."""
    from .._version import __version__
    from . import batching, experiments, pictures, segmenting

    parser = argparse.ArgumentParser(
        prog="superfacets",
        description="Over-segment triangle meshes into superfacets (Simari, Picciau, "
                    "De Floriani, 'Fast and Scalable Mesh Superfacets', 2014).")
    parser.add_argument("--version", action="version", version=f"superfacets {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    segmenting.add_parsers(sub)
    batching.add_parsers(sub)
    experiments.add_parsers(sub)
    pictures.add_parsers(sub)
    return parser


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

    args = build_parser().parse_args(argv)
    restore = _terminate_cleanly()
    try:
        return args.func(args)
    except BrokenPipeError:  # `superfacets ... | head`: the reader left; end quietly
        _silence_stdout()
        return 0
    except (SuperfacetsError, OSError, NoDisplayError) as exc:
        msg = str(exc)
        if isinstance(exc, OSError) and exc.filename and str(exc.filename) not in msg:
            msg = f"{exc.filename}: {exc.strerror or msg}"
        print(f"superfacets: error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("superfacets: interrupted", file=sys.stderr)
        return 130
    except _Terminated:
        print("superfacets: terminated", file=sys.stderr)
        return 143
    finally:
        restore()


class _Terminated(BaseException):
    """SIGTERM, raised in the main thread so that temporary files are removed."""


def _terminate_cleanly():
    """Turn SIGTERM into an exception (unwinding removes temporary files); return a
    function that puts the previous handler back."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return lambda: None

    def handler(signum, frame):
        raise _Terminated()

    try:
        previous = signal.signal(signal.SIGTERM, handler)
    except (ValueError, OSError):  # pragma: no cover - not settable here
        return lambda: None
    return lambda: signal.signal(signal.SIGTERM, previous)


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
