"""The one search the baselines share: a parameter for a number of segments."""

from __future__ import annotations

from typing import Callable

import numpy as np


def search_count(run: Callable[[float], np.ndarray], n_segments: int, lo: float, hi: float,
                 max_runs: int, method: str = "the baseline") -> np.ndarray:
    """Bisection in ``log10`` of a parameter whose growth lowers the segment count.

    ``run(value)`` returns dense labels; ``lo`` and ``hi`` bound ``log10(value)``.
    Stops within 2 % of ``n_segments``, else after ``max_runs``; returns the labels
    whose count came nearest, with a ``RuntimeWarning`` naming ``method`` where that count
    is more than 10 % from ``n_segments`` (:func:`count_missed`).

    Examples
    --------
    >>> import warnings
    >>> at_most_5 = lambda v: np.arange(100) % min(5, max(1, int(100 / v)))
    >>> with warnings.catch_warnings(record=True) as seen:
    ...     warnings.simplefilter("always")
    ...     int(search_count(at_most_5, 10, -2.0, 2.0, 8, "a test").max()) + 1
    5
    >>> print(seen[0].message)
    a test gave 5 segments for n_segments=10: the nearest count its parameter reaches on this input
    """
    a, b = lo, hi
    best = None
    for _ in range(max_runs):
        mid = 0.5 * (a + b)
        lab = run(10.0 ** mid)
        count = int(lab.max()) + 1
        if best is None or abs(count - n_segments) < abs(best[0] - n_segments):
            best = (count, lab)
        if abs(count - n_segments) <= 0.02 * n_segments:
            break
        if count > n_segments:
            a = mid
        else:
            b = mid
    count_missed(method, best[0], n_segments)
    return best[1]


#: The start of the warning's message after the count (``warnings.filterwarnings`` matches
#: messages from their start: ``".*" + COUNT_MISSED``)
COUNT_MISSED = " segments for n_segments="


def count_missed(method: str, count: int, n_segments: int) -> None:
    """Warn (``RuntimeWarning``) where a baseline's count search ended more than 10 % from
    the ``n_segments`` asked for (a flat noise-free plane is one segment to the
    Segmentator's method at any threshold): a comparison at equal counts should know."""
    if abs(count - n_segments) > 0.1 * n_segments:
        import warnings

        warnings.warn(f"{method} gave {count}{COUNT_MISSED}{n_segments}: the "
                      "nearest count its parameter reaches on this input", RuntimeWarning,
                      stacklevel=3)
