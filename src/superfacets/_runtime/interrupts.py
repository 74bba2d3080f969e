"""Ctrl-C caught and handled: the one flag the command line's SIGINT handler reads.

The command line (:mod:`superfacets.cli`) raises Ctrl-C's KeyboardInterrupt
again every 0.2 s until the run has unwound, since some libraries swallow it.
Code that catches it to stop in order (a batch writing its manifest, an
experiment its last rows) calls :func:`caught` first, so that its clean-up is
not interrupted in turn; nothing else changes.
"""

from __future__ import annotations

import threading

__all__ = ["caught", "was_caught", "reset", "pending", "check"]

_caught = threading.Event()
_pending = threading.Event()


def caught() -> None:
    """Say that a KeyboardInterrupt was caught and the run is stopping in order."""
    _caught.set()


def was_caught() -> bool:
    """Whether :func:`caught` was called since the last :func:`reset`."""
    return _caught.is_set()


def reset() -> None:
    """Forget an earlier :func:`caught` or :func:`pending` (a new command in the same
    process)."""
    _caught.clear()
    _pending.clear()


def pending() -> None:
    """Say that a Ctrl-C came where it could not be raised (the import machinery, numba's
    dispatcher): :func:`check` raises it at the next safe point."""
    _pending.set()


def check() -> None:
    """Raise the KeyboardInterrupt of a :func:`pending` Ctrl-C, once: called at the run's
    stage boundaries, so that a Ctrl-C during the start-up (imports, kernels loading)
    stops the run even when every repeat of it lands in such code again. Nothing
    happens outside the command line (no handler sets it)."""
    if _pending.is_set() and not _caught.is_set():
        _pending.clear()
        raise KeyboardInterrupt
