"""Progress bars that go on while a compiled stage runs."""

from __future__ import annotations

import os
import sys
import threading

__all__ = ["TICK", "new_bar", "tick", "waiting_bar"]

#: Seconds between two redraws of a bar while a stage runs
TICK = 0.5
#: The size of the screen a bar is drawn for on a terminal that reports none
NO_SIZE = (80, 24)


def new_bar(iterable=None, **kwargs):
    """A tqdm bar on stderr, drawn for a screen of :data:`NO_SIZE` (columns, lines) where
    stderr is a terminal that reports no size (a pseudo-terminal opened without one, as
    some remote shells and CI runners open them): tqdm draws nothing on a screen of 0
    columns, and hides a bar below its 0 lines.

    Examples
    --------
    >>> bar = new_bar(total=3, disable=True)
    >>> bar.update(3); bar.close()
    """
    from tqdm import tqdm

    size = _stderr_size()
    if size is not None:
        if size[0] == 0 and "ncols" not in kwargs:
            kwargs.pop("dynamic_ncols", None)
            kwargs["ncols"] = NO_SIZE[0]
        if size[1] == 0 and "nrows" not in kwargs:
            kwargs["nrows"] = NO_SIZE[1]
    return tqdm(iterable, **kwargs)


def _stderr_size() -> tuple[int, int] | None:
    """The columns and lines of the terminal stderr is (0: reports none), or None."""
    try:
        return tuple(os.get_terminal_size(sys.stderr.fileno()))
    except (OSError, ValueError, AttributeError):  # (not a terminal, or no descriptor)
        return None


def tick(bar) -> threading.Event:
    """Redraw ``bar`` (a tqdm bar) every :data:`TICK` seconds on a daemon thread, until
    the returned event is set: its elapsed time goes on while a compiled stage runs
    (they release the interpreter), so no stage is silent on a terminal.

    Examples
    --------
    >>> from tqdm import tqdm
    >>> bar = tqdm(total=None, disable=True)
    >>> stop = tick(bar)
    >>> stop.set(); bar.close()
    """
    stop = threading.Event()

    def run() -> None:
        while not stop.wait(TICK):
            try:
                bar.refresh()
            except Exception:  # noqa: BLE001 - a bar closed meanwhile: nothing to draw
                return

    threading.Thread(target=run, name="superfacets-progress", daemon=True).start()
    return stop


class waiting_bar:
    """A bar of one line, ``desc`` and the time elapsed, redrawn while the ``with`` block
    runs (reading a file); nothing where ``show`` is False.

    Examples
    --------
    >>> with waiting_bar("reading", show=False):
    ...     pass
    """

    def __init__(self, desc: str, show: bool = True) -> None:
        self.desc, self.show = desc, show
        self.bar = self.stop = None

    def __enter__(self):
        if self.show:
            self.bar = new_bar(total=None, desc=self.desc, bar_format="{desc} [{elapsed}]",
                               leave=False)
            self.bar.refresh()
            self.stop = tick(self.bar)
        return self

    def __exit__(self, *exc) -> None:
        if self.stop is not None:
            self.stop.set()
        if self.bar is not None:
            self.bar.close()
