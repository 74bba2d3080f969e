"""Ctrl-C caught and handled: the one flag the command line's SIGINT handler reads.

The command line (:mod:`superfacets.cli`) raises Ctrl-C's KeyboardInterrupt
again every 0.2 s until the run has unwound, since some libraries swallow it.
Code that catches it to stop in order (a batch writing its manifest, an
experiment its last rows) calls :func:`caught` first, so that its clean-up is
not interrupted in turn; nothing else changes.
"""

from __future__ import annotations

import threading
from contextlib import contextmanager

__all__ = ["caught", "was_caught", "reset", "pending", "check", "SignalWatch", "last_outputs",
           "committing", "in_commit", "outputs_written"]

_caught = threading.Event()
_pending = threading.Event()
_last = threading.Event()  # the command's next commit writes its last outputs
_committing = threading.Event()  # staged outputs being renamed over their targets
_written = threading.Event()  # the command's last outputs are whole: its work is done


def caught() -> None:
    """Say that a KeyboardInterrupt was caught and the run is stopping in order."""
    _caught.set()


def was_caught() -> bool:
    """Whether :func:`caught` was called since the last :func:`reset`."""
    return _caught.is_set()


def reset() -> None:
    """Forget an earlier :func:`caught`, :func:`pending` or :func:`last_outputs` (a new
    command in the same process)."""
    for flag in (_caught, _pending, _last, _committing, _written):
        flag.clear()


def last_outputs() -> None:
    """Say that the command's next commit of staged outputs
    (:meth:`superfacets.io.files.Outputs.commit`) writes its last ones: once they are
    whole, a Ctrl-C no longer stops it (the command line's handler ignores it, and the
    command ends as it would have, its summary said), so that an interrupted command never
    leaves outputs behind and a finished one never reports an interruption."""
    _last.set()


@contextmanager
def committing():
    """Around the renames of a commit: a Ctrl-C in it waits for its end (all the files or
    none, never some), and after the last outputs' (:func:`last_outputs`) is ignored."""
    _committing.set()
    try:
        yield
    except BaseException:
        _committing.clear()
        raise
    _committing.clear()
    if _last.is_set():
        _written.set()


def in_commit() -> bool:
    """Whether a commit's renames are under way (:func:`committing`)."""
    return _committing.is_set()


def outputs_written() -> bool:
    """Whether the command's last outputs are whole (:func:`last_outputs`)."""
    return _written.is_set()


def pending() -> None:
    """Say that a Ctrl-C came where it could not be raised (the import machinery, numba's
    dispatcher): :func:`check` raises it at the next safe point."""
    _pending.set()


def check() -> None:
    """Raise the KeyboardInterrupt of a :func:`pending` Ctrl-C, once: called at the run's
    stage boundaries, so that a Ctrl-C during the start-up (imports, kernels loading)
    stops the run even when every repeat of it lands in such code again. Nothing
    happens outside the command line (no handler sets it)."""
    if _pending.is_set() and not _caught.is_set() and not _written.is_set():
        _pending.clear()
        raise KeyboardInterrupt



class SignalWatch:
    """While a run lasts, tell the compiled kernels at once that SIGINT or SIGTERM came.

    Python runs its signal handlers on the main thread between bytecodes, so a run
    inside a long compiled kernel heard nothing until the kernel returned (minutes on a
    large input). Python's own C-level handler also writes each signal's number to a
    wakeup file descriptor (:func:`signal.set_wakeup_fd`): a thread here reads it and
    sets the kernels' interrupt flag, and the kernels stop within milliseconds with a
    KeyboardInterrupt. :attr:`signum` is the signal that stopped the run (SIGTERM stays
    the reason once seen: the command line exits 143 for it, 130 for SIGINT). Made on
    the main thread; :meth:`close` puts the previous wakeup descriptor back and clears
    the flag.
    """

    def __init__(self):
        import signal
        import socket

        self.signum = 0
        self._read, self._write = socket.socketpair()
        self._write.setblocking(False)
        self._previous = signal.set_wakeup_fd(self._write.fileno(), warn_on_full_buffer=False)
        self._thread = threading.Thread(target=self._watch, daemon=True,
                                        name="superfacets-signals")
        self._thread.start()

    @staticmethod
    def _kernels():
        import sys  # (never imported from here: a kernel runs once the run loaded them)

        return sys.modules.get("superfacets._kernels._cxx")

    def _watch(self) -> None:
        import signal

        while True:
            try:
                got = self._read.recv(64)
            except OSError:
                return
            if not got:
                return
            for signum in got:
                if signum in (signal.SIGINT, signal.SIGTERM):
                    if self.signum != signal.SIGTERM:
                        self.signum = signum
                    kernels = self._kernels()
                    if kernels is not None:
                        kernels.interrupt(1)

    def close(self) -> None:
        import signal

        try:
            signal.set_wakeup_fd(self._previous)
        except ValueError:  # pragma: no cover - not the main thread
            pass
        self._write.close()
        self._read.shutdown(2)
        self._thread.join(1.0)
        self._read.close()
        kernels = self._kernels()
        if kernels is not None:
            kernels.interrupt(0)
