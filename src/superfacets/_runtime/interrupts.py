"""Ctrl-C caught and handled: the one flag the command line's SIGINT handler reads.

The command line (:mod:`superfacets.cli`) raises Ctrl-C's KeyboardInterrupt
again every 0.2 s until the run has unwound, since some libraries swallow it.
Code that catches it to stop in order (a batch writing its manifest, an
experiment its last rows) calls :func:`caught` first, so that its clean-up is
not interrupted in turn; nothing else changes.
"""

from __future__ import annotations

import threading

__all__ = ["caught", "was_caught", "reset"]

_caught = threading.Event()


def caught() -> None:
    """Say that a KeyboardInterrupt was caught and the run is stopping in order."""
    _caught.set()


def was_caught() -> bool:
    """Whether :func:`caught` was called since the last :func:`reset`."""
    return _caught.is_set()


def reset() -> None:
    """Forget an earlier :func:`caught` (a new command in the same process)."""
    _caught.clear()
