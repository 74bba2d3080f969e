"""Progress bars that go on while a compiled stage runs."""

from __future__ import annotations

import threading

__all__ = ["TICK", "tick", "waiting_bar"]

#: Seconds between two redraws of a bar while a stage runs
TICK = 0.5


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
            from tqdm import tqdm

            self.bar = tqdm(total=None, desc=self.desc, bar_format="{desc} [{elapsed}]",
                            leave=False)
            self.bar.refresh()
            self.stop = tick(self.bar)
        return self

    def __exit__(self, *exc) -> None:
        if self.stop is not None:
            self.stop.set()
        if self.bar is not None:
            self.bar.close()
