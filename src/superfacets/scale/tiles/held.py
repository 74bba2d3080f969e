"""A tile's box, element graph and weights held in its worker's memory between phases.

Each phase of a tiled run reads its tile's box and kept graph from the work folder
(:mod:`.graphs`: a cloud's point graph, a mesh's kept box and face graph topology), and the
later phases each made the box's adjacency weights again: at 10M points in 4 tiles, 4.4 s
of a 57 s run (in process, one thread) went to reading and weighing what the phase before
had in memory. A worker now holds the last tiles it ran (the box's rows, positions and
input, its element graph, and the weights the graph was given:
:func:`superfacets.method.stages.weigh` keeps them where the graph carries a
``weights_kept`` dictionary), within a quarter of the
memory it may still use, and the run sends each tile's next phase to the worker that holds
it (:meth:`superfacets.scale.runner.engine.Engine.run`, ``prefer``); anything not held is
read from the work folder as before. What a held tile's phases made for its later phases
(its graph, its refine round's last classification, a mesh's box and face topology) is
written to the work folder only when the tile is let go while the run goes on (``write``,
given to :func:`hold_box`), or at once where it cannot be held: a run whose tiles stay held
writes none of it. The same arrays either way, so the same labels.

``SUPERFACETS_TILE_HOLD_MIB`` sets the budget in MiB (0: nothing held).
"""

from __future__ import annotations

import os
import threading
from collections import OrderedDict
from pathlib import Path

import numpy as np

from ..._runtime.memory import available_bytes
from ...errors import ParameterError

__all__ = ["held_box", "hold_box", "release_held", "hold_budget", "hold_from_env",
           "worker_address", "HOLD_SHARE"]

#: The share of the memory a worker may still use (its Dask memory limit, and the
#: machine's available memory) that its held tiles may take.
HOLD_SHARE = 0.25

#: The held tiles of this process, oldest first: key -> (value, bytes, write).
_HELD: OrderedDict = OrderedDict()
#: (two runs in one process's threads share the held tiles)
_LOCK = threading.RLock()


def hold_budget() -> int:
    """Bytes this process may hold tiles in: :data:`HOLD_SHARE` of what it may still use
    (the held tiles counted as usable), or ``SUPERFACETS_TILE_HOLD_MIB``.

    Examples
    --------
    >>> hold_budget() >= 0
    True
    """
    given = hold_from_env()
    if given is not None:
        return given
    with _LOCK:
        held = sum(b for _, b, _ in _HELD.values())
    avail = available_bytes()
    room = None if avail is None else avail + held
    limit = _worker_limit()
    if limit:
        room = limit if room is None else min(room, limit)
    return 0 if room is None else int(HOLD_SHARE * room)


def hold_from_env() -> int | None:
    """``SUPERFACETS_TILE_HOLD_MIB`` in bytes: a whole number of MiB, 0 or more; None where
    it is not set (or empty).

    Raises
    ------
    ParameterError
        If it is set to anything else, naming it (a tiled run checks it before it starts).

    Examples
    --------
    >>> os.environ["SUPERFACETS_TILE_HOLD_MIB"] = "512"
    >>> hold_from_env() == 512 * 2**20
    True
    >>> del os.environ["SUPERFACETS_TILE_HOLD_MIB"]
    """
    raw = os.environ.get("SUPERFACETS_TILE_HOLD_MIB", "").strip()
    if not raw:
        return None
    if not (raw.isascii() and raw.isdigit()) or len(raw) > 9:
        raise ParameterError(f"SUPERFACETS_TILE_HOLD_MIB={raw[:40]!r}: give a whole number of "
                             "MiB (0: no tile held between phases), or unset it")
    return int(raw) * 2**20


def _worker_limit() -> int | None:
    """The Dask worker's memory limit, where this runs in one that has one."""
    try:
        from distributed import get_worker

        return int(get_worker().memory_manager.memory_limit or 0) or None
    except (ImportError, ValueError, AttributeError):
        return None


def worker_address() -> str | None:
    """The address of the Dask worker this runs in (None: not in one)."""
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError, AttributeError):
        return None


def held_box(key: tuple):
    """What :func:`hold_box` holds under ``key`` (None: nothing), marked as the newest."""
    with _LOCK:
        _forget_gone()
        got = _HELD.get(key)
        if got is None:
            return None
        _HELD.move_to_end(key)
        return got[0]


def hold_box(key: tuple, value, arrays, write=None) -> bool:
    """Hold ``value`` under ``key`` (its first item the run's folder, whose removal ends
    the hold), counted as the bytes of ``arrays``; the oldest held tiles go where the
    budget needs their room. ``write`` (called with no argument, optional): writes what
    the tile's later phases would read from the work folder, called when it is let go
    while the run goes on, or here where it is not held. Returns whether it is held."""
    size = sum(int(a.nbytes) for a in arrays if isinstance(a, np.ndarray))
    with _LOCK:
        _HELD.pop(key, None)
        budget = hold_budget()
        if size > budget:  # (the others stay: this one never comes in)
            _written(write)
            return False
        while _HELD and sum(b for _, b, _ in _HELD.values()) + size > budget:
            _written(_HELD.popitem(last=False)[1][2])
        _HELD[key] = (value, size, write)
        return True


def _written(write) -> None:
    """Run a let-go tile's ``write`` (:func:`hold_box`); a full disk leaves its later
    phases to make it again (a graph built again is the same graph)."""
    if write is not None:
        try:
            write()
        except OSError:
            pass


def release_held(folder=None) -> int:
    """Let go of the tiles held under ``folder`` (a run's folder, at its end: nothing
    written), or of all (a tile that does not fit beside them: the task runs again
    without them, each first writing what its later phases read); how many."""
    top = None if folder is None else Path(folder)
    with _LOCK:
        gone = [k for k in _HELD
                if top is None or top == Path(k[0]) or top in Path(k[0]).parents]
        for key in gone:
            write = _HELD.pop(key)[2]
            if top is None:
                _written(write)
    return len(gone)


def _forget_gone() -> None:
    """Let go of the tiles whose graph folder is gone (their run ended)."""
    for key in [k for k in _HELD if not Path(k[0]).exists()]:
        del _HELD[key]
