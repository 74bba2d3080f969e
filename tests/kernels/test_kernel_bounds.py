"""The compiled kernels stay inside their arrays whatever they are given (issue 94).

Every kernel checks, at its entry and before any work, the indices it will follow: an
index array's entries against the length they index, a compressed-row layout (``indptr``
from 0 or above, never falling, ending within its indices), the lengths of the arrays it
writes. A mismatch is ``OutOfRange`` (a ``ValueError`` naming the argument), never a read
or a write past an array. Tested on the arguments of real calls, each integer array
spoilt in turn, in a process of its own (a kernel that strayed would end it).
"""

from __future__ import annotations

import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import superfacets
from superfacets._kernels import native
from superfacets.inputs.shapes import creature

#: Kernels that follow no index an argument gives (coordinates, keys, counts only)
NO_INDICES = {"column_bounds", "column_means", "finite_rows", "nearest_row", "key_window",
              "sort_keys", "local_morton_keys", "spatial_blocks",
              "tree_nodes",
              "first_in_cells", "combine_weights", "interrupt", "set_thread_limit",
              "threads", "border_shares", "gather"}


def _sampled(n: int) -> np.ndarray:
    mesh = creature(30)
    rng = np.random.default_rng(1)
    face = rng.choice(mesh.n_faces, n, p=mesh.areas / mesh.areas.sum())
    a, b = rng.random((2, n, 1))
    flip = (a + b) > 1
    a, b = np.where(flip, 1 - a, a), np.where(flip, 1 - b, b)
    v = mesh.vertices[mesh.faces[face]]
    return v[:, 0] + a * (v[:, 1] - v[:, 0]) + b * (v[:, 2] - v[:, 0])


def _recorded_calls(monkeypatch) -> dict:
    """The first call of each compiled kernel (copies of its arguments) in small runs of
    every kind and option that reaches a kernel."""
    from test_native import _quad_cube

    from superfacets._runtime import arrays
    from superfacets.elements.builders import elements_of
    from superfacets.evaluation.baselines.cut_pursuit import dimensionality_features
    from superfacets.evaluation.baselines.graph_segmentation import graph_segmentation
    from superfacets.evaluation.baselines.vsa import vsa
    from superfacets.graph.adjacency import superfacet_graph
    from superfacets.graph.hierarchy import hierarchy
    from superfacets.inputs.cloud import PointCloud, as_cloud
    from superfacets.method.coarse_to_fine import coarsen
    from superfacets.method.weights import csr_weights, paper_weights

    calls: dict = {}
    plain = native.kernel

    def copy(x):
        if isinstance(x, np.ndarray):
            return x.copy()
        return tuple(map(copy, x)) if isinstance(x, tuple) else x

    def kernel(path):
        run = plain(path)

        def recorded(*args, **kwargs):
            if path not in calls:
                calls[path] = ([copy(a) for a in args], {k: copy(v) for k, v in kwargs.items()})
            return run(*args, **kwargs)
        return recorded

    monkeypatch.setattr(native, "kernel", kernel)
    monkeypatch.setattr(arrays, "COMPILED_MIN", 16)  # (the large arrays' kernels too)
    mesh, pts = creature(24), _sampled(6000)
    for data, k, params in [
            (mesh, 30, {}), (mesh, 30, {"cleanup": False, "split_merge": False}),
            (mesh, None, {"radius": 0.08, "init": "flood"}), (mesh, 40, {"roughness": 1.0}),
            (_quad_cube(8), 20, {}), (creature(40), 3, {}),
            (mesh, 30, {"elements": "vertices"}),
            (as_cloud(np.r_[pts, pts[:50]]), 30, {}), (as_cloud(pts), 3, {"merge_from": 1}),
            (as_cloud(pts), 30, {"window": 1.0, "assignment": "bounded"}),
            (as_cloud(pts), 30, {"roughness": 1.0}),
            (as_cloud(np.r_[pts, pts + [50.0, 0, 0]]), 20, {}),
            (PointCloud(pts, colors=np.c_[pts[:, :1] > 0, pts[:, 1:] > 0] * 0.5), 30, {}),
            (PointCloud(pts[:3000], orient_like=(pts[::7], np.tile([0.0, 0, 1], (858, 1)))),
             20, {})]:
        superfacets.segment(data, k, n_threads=1, **params)
    labels = superfacets.segment(mesh, 30, n_threads=1).labels
    hierarchy(superfacet_graph(elements_of(mesh, "faces").graph, labels, None), [20, 5])
    graph_segmentation(mesh, n_segments=30)
    vsa(mesh, 12, metric="l21", init="incremental", rng=0)
    dimensionality_features(elements_of(pts, "points").graph)
    cloud_labels = superfacets.segment(as_cloud(pts), 30, n_threads=1).labels
    superfacet_graph(elements_of(pts, "points").graph, cloud_labels)  # (pairs listed)
    g = elements_of(mesh, "faces").graph
    coarsen(g, csr_weights(g, paper_weights(g)), 8).graph.lengths  # noqa: B018 (made if read)
    return calls


@pytest.mark.skipif(not native.available(), reason="the compiled kernels are not built")
def test_spoilt_indices_are_refused_at_the_kernels_entry(monkeypatch, tmp_path):
    calls = _recorded_calls(monkeypatch)
    indexed = {name for name in dir(native._cxx)
               if callable(getattr(native._cxx, name)) and name[0].islower()} - NO_INDICES
    missing = {n for n in indexed if not any(p.endswith("." + n) for p in calls)}
    assert missing <= {"classify_bounded", "pca_linearity", "rows_apart"}, missing
    (tmp_path / "calls.pkl").write_bytes(pickle.dumps(calls))
    script = Path(__file__).resolve().parents[1] / "hostile_calls.py"
    out = subprocess.run([sys.executable, str(script), str(tmp_path / "calls.pkl")],
                         capture_output=True, text=True, timeout=600)
    lines = out.stdout.splitlines()
    last = [x for x in lines if x.startswith("CASE")][-1:]
    assert out.returncode == 0 and lines[-1] == "DONE", (out.returncode, last,
                                                         out.stderr[-2000:])
    outcomes = [x.split()[1] for x in lines if x.startswith("RESULT")]
    assert set(outcomes) <= {"ok", "OutOfRange", "Mismatch"}, set(outcomes)
    assert outcomes.count("OutOfRange") > 300  # (most spoilt indices are followed)


@pytest.mark.skipif(not native.available(), reason="the compiled kernels are not built")
def test_spoilt_counts_and_bounds_are_refused_not_crashed_or_looped_on(monkeypatch, tmp_path):
    """Every scalar argument of every kernel spoilt (0, -1, 2**62, 2**31; NaN, +-inf, 0,
    -1) and every array inside a tuple argument emptied, each case in a forked child: a
    result or a refusal, never a crash or a hang (issue 110: 24 crashes, 30 hangs)."""
    calls = _recorded_calls(monkeypatch)
    (tmp_path / "calls.pkl").write_bytes(pickle.dumps(calls))
    script = Path(__file__).resolve().parents[1] / "hostile_calls.py"
    out = subprocess.run([sys.executable, str(script), str(tmp_path / "calls.pkl"), "scalars",
                          "30"], capture_output=True, text=True, timeout=900,
                         env={**__import__("os").environ, "SUPERFACETS_KERNEL_THREADS": "1"})
    lines = out.stdout.splitlines()
    assert out.returncode == 0 and lines[-1] == "DONE", (out.returncode, out.stderr[-2000:])
    cases = [x for x in lines if x.startswith("CASE")]
    outcomes = [x.split(" ", 1)[1] for x in lines if x.startswith("RESULT")]
    bad = [(c, o) for c, o in zip(cases, outcomes)
           if o not in ("ok", "OutOfRange", "Mismatch", "TypeError", "MemoryError",
                        "ValueError", "OverflowError")]
    assert not bad, bad
    assert len(cases) > 400 and outcomes.count("OutOfRange") > 50


@pytest.mark.skipif(not native.available(), reason="the compiled kernels are not built")
def test_a_compressed_row_layout_past_its_indices_is_named():
    from superfacets._kernels._cxx import OutOfRange

    neighbour_mean = native.kernel("terms.neighbour_mean")
    indptr = np.array([0, 2, 3, 4], dtype=np.int64)
    indices = np.array([1, 2, 0, 0], dtype=np.int32)
    x, out = np.arange(3.0), np.empty(3)
    neighbour_mean(indptr, indices, x, out)
    assert out.tolist() == [1.0, 0.5, 1.0]  # (x_i + its neighbours) / (1 + degree)
    for bad, says in [(np.array([0, 2, 3, 9]), "past the 4 entries"),
                      (np.array([0, 3, 2, 4]), "fall"), (np.array([-1, 2, 3, 4]), "negative")]:
        with pytest.raises(OutOfRange, match=says):
            neighbour_mean(bad.astype(np.int64), indices, x, out)
    with pytest.raises(OutOfRange, match="entry 1 is 1073741824, outside 0..2"):
        neighbour_mean(indptr, np.array([1, 2**30, 0, 0], dtype=np.int32), x, out)
    assert issubclass(OutOfRange, ValueError)
