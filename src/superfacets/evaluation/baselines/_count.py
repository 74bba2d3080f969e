"""The one search the baselines share: a parameter for a number of segments."""

from __future__ import annotations

from typing import Callable

import numpy as np


def search_count(run: Callable[[float], np.ndarray], n_segments: int, lo: float, hi: float,
                 max_runs: int) -> np.ndarray:
    """Bisection in ``log10`` of a parameter whose growth lowers the segment count.

    ``run(value)`` returns dense labels; ``lo`` and ``hi`` bound ``log10(value)``.
    Stops within 2 % of ``n_segments``, else after ``max_runs``; returns the labels
    whose count came nearest.
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
    return best[1]
