"""Experiments over benchmark meshes: parameter grids, the results file, the runner."""

from .experiment import ExperimentSummary, PeakMemory, run_experiment
from .grid import Config, expand_grid, method_grid, parse_params
from .results import columns, read_results, row_key

__all__ = ["Config", "ExperimentSummary", "PeakMemory", "columns", "expand_grid",
           "method_grid", "parse_params", "read_results", "row_key", "run_experiment"]
