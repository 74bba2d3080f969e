"""Run a piece of code in a new process against one version of the package.

A version is ``"installed"`` (the package this environment imports, an editable install
included) or a folder holding a built copy of another version, made with::

    git worktree add /tmp/before <commit>
    pip install --no-build-isolation --no-deps --target /tmp/before-site /tmp/before

(the folder is put first on the path, and an editable install's import hook, which
would otherwise come first, is set aside). The child's own children (a tiled run's Dask
workers) import the same version: a ``sitecustomize`` on their ``PYTHONPATH`` does the
same at their start (without it they imported the installed package: a tiled run of
another version measured that version's driver with this one's tasks).
"""

from __future__ import annotations

import atexit
import functools
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

PRELUDE = """import os, sys
if os.environ.get("SUPERFACETS_BENCH_VERSION"):
    sys.path.insert(0, os.environ["SUPERFACETS_BENCH_VERSION"])
    sys.meta_path = [f for f in sys.meta_path if "editable" not in type(f).__module__]
"""


def version_env(version: str) -> dict:
    """The environment of a child process that imports ``version`` (with :data:`PRELUDE`
    run first; see the module notes)."""
    env = dict(os.environ)
    env.pop("SUPERFACETS_BENCH_VERSION", None)
    if version != "installed":
        folder = Path(version).resolve()
        if not (folder / "superfacets" / "_kernels").is_dir() or not any(
                (folder / "superfacets" / "_kernels").glob("_cxx*")):
            raise SystemExit(f"{folder}: no built package there (see benchmarks/_versions.py)")
        env["SUPERFACETS_BENCH_VERSION"] = str(folder)
        env["PYTHONPATH"] = os.pathsep.join(
            [_site_folder(), str(folder)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH")
                                             else []))
    return env


@functools.cache
def _site_folder() -> str:
    """A folder holding a ``sitecustomize`` that runs :data:`PRELUDE` in every process
    started with it on the path (removed when this process ends)."""
    folder = tempfile.mkdtemp(prefix="superfacets-bench-site-")
    atexit.register(shutil.rmtree, folder, True)
    Path(folder, "sitecustomize.py").write_text(PRELUDE, encoding="utf-8")
    return folder


def run_code(version: str, code: str, *args: str, timeout: float | None = None
             ) -> subprocess.CompletedProcess:
    """``python -c code args`` against ``version`` (see the module notes); raises
    ``subprocess.TimeoutExpired`` past ``timeout`` seconds."""
    env = version_env(version)
    return subprocess.run([sys.executable, "-c", PRELUDE + code, *args], env=env,
                          capture_output=True, text=True, check=False, timeout=timeout)
