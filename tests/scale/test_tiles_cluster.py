"""A tiled run on a Dask cluster of separate processes, started as users start one: a
scheduler and workers from the command line (``dask scheduler``, ``dask worker``), the
run from ``superfacets segment --tiles N --scheduler ADDRESS``: the same labels as the
run in one process."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import numpy as np
import pytest
from tiled import _bumpy_cloud

pytest.importorskip("distributed")


def _start(args, log):
    """A process of ``python -m dask ARGS`` in its own session, its output in ``log``."""
    return subprocess.Popen([sys.executable, "-m", "dask", *args], stdout=log,
                            stderr=subprocess.STDOUT, start_new_session=True)


def _address(scheduler_file, processes, seconds=60.0):
    """The scheduler's address, once its file is written (its first line says it)."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if scheduler_file.exists():
            try:
                return json.loads(scheduler_file.read_text())["address"]
            except (ValueError, KeyError):
                pass  # (being written)
        if any(p.poll() is not None for p in processes):
            break
        time.sleep(0.2)
    pytest.fail(f"the Dask scheduler did not start within {seconds:.0f} s")


def _workers_up(address, n, seconds=60.0):
    from distributed import Client

    with Client(address, timeout=seconds) as client:
        client.wait_for_workers(n, timeout=seconds)


def _prefixes(address):
    """The names of the functions the scheduler has run tasks of."""
    from distributed import Client

    with Client(address, timeout=30) as client:
        return client.run_on_scheduler(lambda dask_scheduler: sorted(dask_scheduler.task_prefixes))


def test_a_cluster_started_from_the_command_line_runs_the_tiles_as_one_process_does(tmp_path):
    from plyfile import PlyData, PlyElement

    from superfacets.scale.tiles.run import segment_tiled

    pts = np.asarray(_bumpy_cloud(6000).points, dtype=np.float32)
    cloud = tmp_path / "cloud.ply"
    vertex = np.array([tuple(p) for p in pts], dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    PlyData([PlyElement.describe(vertex, "vertex")]).write(str(cloud))
    expected = segment_tiled(str(cloud), 30, tiles=4, workers=1).labels

    scheduler_file = tmp_path / "scheduler.json"
    env_dir = tmp_path / "dask"
    env_dir.mkdir()
    with open(tmp_path / "cluster.log", "wb") as log:
        procs = [_start(["scheduler", "--host", "127.0.0.1", "--port", "0",
                         "--no-dashboard", "--scheduler-file", str(scheduler_file)], log)]
        try:
            address = _address(scheduler_file, procs)
            procs.append(_start(["worker", address, "--nworkers", "2", "--nthreads", "1",
                                 "--no-dashboard", "--local-directory", str(env_dir)], log))
            _workers_up(address, 2)
            labels = tmp_path / "cloud.seg"
            run = subprocess.run(
                [sys.executable, "-m", "superfacets", "segment", str(cloud), "-k", "30",
                 "--tiles", "4", "--scheduler", address, "--workdir", str(tmp_path),
                 "-o", str(labels), "-q"],
                capture_output=True, text=True, timeout=300,
                env={**os.environ, "PYTHONWARNINGS": "ignore"})
            assert run.returncode == 0, run.stderr
            np.testing.assert_array_equal(np.loadtxt(labels, dtype=np.int64), expected)
            assert "tile_task" in _prefixes(address)  # (the cluster's workers ran the tiles)
        finally:
            for p in reversed(procs):  # the workers first, then the scheduler
                try:
                    os.killpg(p.pid, 15)
                except ProcessLookupError:
                    pass
            for p in procs:
                try:
                    p.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    os.killpg(p.pid, 9)
                    p.wait()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith("superfacets-tiles")] == []
