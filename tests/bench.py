"""A script of ``benchmarks/`` loaded as a module, for the tests of its helpers."""

import importlib.util
from pathlib import Path


def benchmark(name: str):
    """``benchmarks/<name>.py`` as a module (the folder is not a package)."""
    path = Path(__file__).resolve().parents[1] / "benchmarks" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
