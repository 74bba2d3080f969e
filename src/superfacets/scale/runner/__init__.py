"""Experiments over benchmark meshes and batches of files, on one engine.

:mod:`.engine` runs tasks in this process or on Dask; :mod:`.batch` segments
many files (``superfacets batch``); :mod:`.experiment` runs parameter grids
(:mod:`.grid`) over the benchmark into a results file
(:mod:`superfacets.evaluation.results`). The names below are imported when first used,
so that a command that fails on its arguments does not pay for the imports.
"""

from __future__ import annotations

import importlib

_WHERE = {"ExperimentSummary": "experiment", "run_experiment": "experiment",
          "PeakMemory": "engine", "Engine": "engine",
          "BatchSummary": "batch", "run_batch": "batch", "read_manifest": "batch",
          "Config": "grid", "expand_grid": "grid", "method_grid": "grid", "parse_params": "grid",
          "columns": "...evaluation.results", "read_results": "...evaluation.results",
          "row_key": "...evaluation.results"}

__all__ = sorted(_WHERE)


def __getattr__(name: str):
    if name in _WHERE:
        where = _WHERE[name]
        return getattr(importlib.import_module(where if where.startswith(".") else f".{where}",
                                               __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_WHERE))
