"""Experiments over benchmark meshes and batches of files, on one engine.

:mod:`.engine` runs tasks in this process or on Dask; :mod:`.batch` segments
many files (``superfacets batch``); :mod:`.experiment` runs parameter grids
(:mod:`.grid`) over the benchmark into a results file (:mod:`.results`).
The names below are imported when first used, so that a command that fails on
its arguments does not pay for numba.
"""

from __future__ import annotations

import importlib

_WHERE = {"ExperimentSummary": "experiment", "run_experiment": "experiment",
          "PeakMemory": "engine", "Engine": "engine",
          "BatchSummary": "batch", "run_batch": "batch", "read_manifest": "batch",
          "Config": "grid", "expand_grid": "grid", "method_grid": "grid", "parse_params": "grid",
          "columns": "results", "read_results": "results", "row_key": "results"}

__all__ = sorted(_WHERE)


def __getattr__(name: str):
    if name in _WHERE:
        return getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_WHERE))
