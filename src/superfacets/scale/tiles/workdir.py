"""A tiled run's own work folder, inside the folder the user names (``--workdir``).

A run never writes, replaces or removes a path it did not create: it makes a new
folder ``superfacets-tiles-XXXXXXXX`` inside ``workdir`` (so that two runs can share a
work folder, and a user's files there are never touched), holds a lock on the file
``run.lock`` in it while it runs, and removes that folder, and nothing else, when it
ends. A run killed before its end (SIGKILL, a power cut) leaves its folder behind with
its lock released: the next run in the same ``workdir`` (or, without one, in the
system's temporary folder) removes it and says so. A
``workdir`` inside a run's own folder is refused (the end of that run would remove it
from under the other).
"""

from __future__ import annotations

import contextlib
import shutil
import sys
import tempfile
from pathlib import Path

from ...errors import ParameterError

__all__ = ["run_folder", "PREFIX"]

#: The name of every run's own folder starts so
PREFIX = "superfacets-tiles-"
_LOCK = "run.lock"


def _held(folder: Path) -> bool:
    """Whether a live run holds ``folder`` (its ``run.lock`` locked by another process)."""
    import fcntl

    try:
        with open(folder / _LOCK, "a") as f:
            try:
                fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                return True
            fcntl.flock(f, fcntl.LOCK_UN)
            return False
    except OSError:  # no lock file we may open: not ours to judge, so never removed
        return True


def _is_run_folder(path: Path) -> bool:
    return path.name.startswith(PREFIX) and (path / _LOCK).is_file()


def _remove_leftovers(work: Path) -> list[Path]:
    """The folders of runs that ended without removing theirs (their lock released),
    removed; returns them."""
    gone = []
    for child in sorted(work.glob(PREFIX + "*")):
        if child.is_dir() and not child.is_symlink() and _is_run_folder(child) \
                and not _held(child):
            shutil.rmtree(child, ignore_errors=True)
            gone.append(child)
    return gone


@contextlib.contextmanager
def run_folder(workdir):
    """The run's own folder: a new folder inside ``workdir`` (made if missing; None: the
    system's temporary folder), locked while the run lasts and removed at its end;
    yields its path (str). The leftovers of runs killed in the same folder are removed
    first.

    Raises
    ------
    ParameterError
        If ``workdir`` is empty, is not a folder, or lies inside another run's folder.
    """
    if workdir is None:
        workdir = tempfile.gettempdir()
    if not str(workdir).strip():
        raise ParameterError("workdir is an empty path: name a folder for the work files")
    work = Path(workdir).expanduser().resolve()
    for parent in (work, *work.parents):
        if _is_run_folder(parent):
            raise ParameterError(f"{workdir}: inside the work folder of a tiled run "
                                 f"({parent}); give a folder of its own")
    if work.exists() and not work.is_dir():
        raise ParameterError(f"{workdir}: exists and is not a folder")
    work.mkdir(parents=True, exist_ok=True)
    for old in _remove_leftovers(work):
        print(f"note: removed {old}, the work files of a tiled run that did not finish",
              file=sys.stderr)
    own = Path(tempfile.mkdtemp(prefix=PREFIX, dir=work))
    import fcntl
    import os

    # locked before it takes its name: another run never sees it unheld
    lock = open(own / (_LOCK + ".new"), "w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX)
        os.replace(own / (_LOCK + ".new"), own / _LOCK)
        yield str(own)
    finally:
        lock.close()
        shutil.rmtree(own, ignore_errors=True)
