"""The warnings one task told, on whichever thread it runs.

A batch or an experiment keeps each input's warnings in its row (named by the input, not
printed by a worker). :class:`warnings.catch_warnings` cannot do that on a Dask worker of
several threads (``dask worker --nthreads 4``, a user's cluster): it swaps the module's
filters and its ``showwarning`` for the whole process, so one task's warnings went into
another's row, and two tasks ending out of order left the process's warnings recorded
into a list no one reads. Here one process-wide hook hands each warning to the list of
the task running on its thread, or shows it as before where none runs.
"""

from __future__ import annotations

import re
import threading
import warnings
from contextlib import contextmanager
from typing import Iterator

__all__ = ["task_warnings"]

_local = threading.local()
_lock = threading.Lock()
_shown = {"before": None}


def _show(message, category, filename, lineno, file=None, line=None) -> None:
    """``warnings.showwarning`` while installed: to this thread's task, else as before."""
    sinks = getattr(_local, "sinks", None)
    if sinks:
        said, ignore = sinks[-1]
        text = str(message).strip()
        if not any(p.search(text) for p in ignore):
            said.append(text)
        return
    before = _shown["before"] or warnings._showwarning_orig  # noqa: SLF001 - its default
    before(message, category, filename, lineno, file, line)


def _install() -> None:
    with _lock:
        if warnings.showwarning is not _show:
            _shown["before"] = warnings.showwarning
            warnings.showwarning = _show
            # (last, below the user's filters: a warning of this package is told again by
            # each task that meets it, not once per process)
            warnings.filterwarnings("always", module=r"superfacets(\.|$)", append=True)


@contextmanager
def task_warnings(ignore: tuple = ()) -> Iterator[list]:
    """Collect the warnings of the code run inside, on this thread only.

    Parameters
    ----------
    ignore : tuple of str
        Regular expressions: a warning whose text one matches is dropped.

    Yields
    ------
    list of str
        The warnings' texts, in order, as they come (repeats kept).

    Raises
    ------
    re.error
        If a pattern of ``ignore`` is not a regular expression.

    Examples
    --------
    >>> with task_warnings(ignore=("dull",)) as said:
    ...     warnings.warn("a dull one"); warnings.warn("kept", RuntimeWarning)
    >>> said
    ['kept']
    """
    patterns = tuple(re.compile(p) for p in ignore)
    _install()
    sinks = getattr(_local, "sinks", None)
    if sinks is None:
        sinks = _local.sinks = []
    said: list = []
    sinks.append((said, patterns))
    try:
        yield said
    finally:
        sinks.pop()
