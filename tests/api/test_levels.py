"""Content-adaptive levels: the planarity cost on points (each point weighs one) and its
``extent_weight`` term, known answers against brute force and the automatic choice."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import grid_mesh

from superfacets import segment
from superfacets.errors import ParameterError
from superfacets.graph.adjacency import superfacet_graph
from superfacets.graph.hierarchy import (
    AUTO_EXTENT_WEIGHT,
    hierarchy,
    level_extent_weight,
    planarity_graph,
)


def _bumpy_cloud(n=1500, seed=0):
    rng = np.random.default_rng(seed)
    xy = rng.random((n, 2))
    z = 0.3 * np.exp(-((xy - 0.5) ** 2).sum(axis=1) / 0.02) + 0.2 * (xy[:, 0] > 0.7) * xy[:, 0]
    return np.c_[xy, z]


def _plane_rise(points, a, b):
    """Least-squares plane residual (sum of squared distances) of a U b, minus a's and b's."""
    def resid(p):
        d = p - p.mean(axis=0)
        return max(np.linalg.eigvalsh(d.T @ d)[0], 0.0)
    return resid(np.r_[points[a], points[b]]) - resid(points[a]) - resid(points[b])


def test_points_weigh_one_each_in_the_planarity_graph():
    pts = _bumpy_cloud()
    r = segment(pts, 30)
    g = r.elements.graph
    sg = planarity_graph(g, r.element_labels)
    lab = r.element_labels
    np.testing.assert_array_equal(sg.area, np.bincount(lab))
    for s in (0, 7, 29):
        p = pts[r.elements.first_rows(np.flatnonzero(lab == s))]
        np.testing.assert_allclose(sg.centroid[s], p.mean(axis=0), rtol=1e-12)
        d = p - p.mean(axis=0)
        np.testing.assert_allclose(sg.scatter[s], d.T @ d, rtol=1e-9, atol=1e-15)
    assert not np.allclose(superfacet_graph(g, lab).area, sg.area)  # estimated areas differ
    # faces keep their areas
    mesh = grid_mesh(10, 10, height=lambda x, y: x * y)
    rf = segment(mesh, 8)
    np.testing.assert_array_equal(planarity_graph(rf.elements.graph, rf.element_labels).area,
                                  rf.graph().area)


@pytest.mark.parametrize("compactness", [0.0, 0.3])
def test_merges_are_the_cheapest_pairs_by_brute_force(compactness):
    # an unevenly sampled cloud (estimated areas far from equal per point): ten greedy
    # merges replayed with numpy's least-squares planes of the points themselves
    pts = _bumpy_cloud()
    pts = pts[(pts[:, 0] < 0.5) | (np.arange(pts.shape[0]) % 4 == 0)]
    r = segment(pts, 30)
    lab = r.element_labels
    p = pts[r.elements.first_rows(np.arange(lab.size))]
    edges = planarity_graph(r.elements.graph, lab).edge_index.T
    levels = list(range(29, 19, -1))
    h = r.hierarchy(levels, cost="planarity", extent_weight=compactness)
    group = np.arange(30)
    for i, level in enumerate(levels):
        best, pair = np.inf, None
        for a, b in {(min(group[a], group[b]), max(group[a], group[b])) for a, b in edges
                     if group[a] != group[b]}:
            ia, ib = group[lab] == a, group[lab] == b
            ward = ia.sum() * ib.sum() / (ia.sum() + ib.sum()) * \
                np.sum((p[ia].mean(axis=0) - p[ib].mean(axis=0)) ** 2)
            cost = max(_plane_rise(p, ia, ib), 0.0) + compactness * ward
            if cost < best:
                best, pair = cost, (a, b)
        group[group == pair[1]] = pair[0]
        got = h.of_superfacets(i)
        # the same partition of the 30 superpoints
        assert np.unique(np.c_[got, group], axis=0).shape[0] == level == np.unique(got).size


def test_the_extent_weight_keeps_flat_segments_compact():
    # a flat square: every plane rise is zero, so without the term the merges follow
    # rounding noise; with it they are Ward's, whatever its weight
    rng = np.random.default_rng(1)
    pts = np.c_[rng.random((3000, 2)), np.zeros(3000)]
    r = segment(pts, 120)

    def spread(labels):
        return sum(((pts[labels == s] - pts[labels == s].mean(axis=0)) ** 2).sum()
                   for s in np.unique(labels))

    loose = r.hierarchy([8], cost="planarity", extent_weight=0).labels(0, r.labels)
    tight = r.hierarchy([8], cost="planarity", extent_weight=0.01).labels(0, r.labels)
    heavy = r.hierarchy([8], cost="planarity", extent_weight=10).labels(0, r.labels)
    np.testing.assert_array_equal(tight, heavy)
    assert spread(tight) < 0.8 * spread(loose)


def test_the_extent_weight_is_left_to_the_method_by_the_scans_density():
    even = _bumpy_cloud(2000)
    rng = np.random.default_rng(2)
    far = np.c_[rng.random((400, 2)) * [1, 3] + [1.2, 0], np.zeros(400)]  # sparse, beside
    uneven = np.r_[even, far]
    re, ru = segment(even, 40), segment(uneven, 40)
    assert level_extent_weight(re.elements.graph) == 0.0
    assert level_extent_weight(ru.elements.graph) == AUTO_EXTENT_WEIGHT
    np.testing.assert_array_equal(ru.hierarchy([10], cost="planarity").parents[0],
                                  ru.hierarchy([10], cost="planarity",
                                               extent_weight=AUTO_EXTENT_WEIGHT).parents[0])
    assert level_extent_weight(segment(grid_mesh(30, 30), 10).elements.graph) == 0.0  # faces
    with pytest.raises(ParameterError, match="extent_weight is a term of cost='planarity'"):
        re.hierarchy([10], extent_weight=0.1)
    with pytest.raises(ParameterError, match="extent_weight"):
        hierarchy(planarity_graph(re.elements.graph, re.element_labels), [10],
                  cost="planarity", extent_weight=-1)


def test_adaptive_and_cli_take_the_extent_weight(tmp_path, capsys):
    from superfacets import adaptive_superpoints
    from superfacets.cli import main

    pts = _bumpy_cloud(2000)
    r = segment(pts, 60, merge_from=1)  # the level's own superpoints (merge_from: 1)
    want = r.hierarchy([12], cost="planarity", extent_weight=0.05).labels(0, r.labels)
    np.testing.assert_array_equal(adaptive_superpoints(pts, 12, start=5, extent_weight=0.05),
                                  want)
    with pytest.raises(ParameterError, match="extent_weight"):
        adaptive_superpoints(pts, 12, extent_weight=-0.1)
    path = tmp_path / "c.xyz"
    np.savetxt(path, pts)
    assert main(["segment", str(path), "-k", "12", "--adaptive", "5", "--extent-weight",
                 "0.05", "-o", str(tmp_path / "c.seg")]) == 0
    np.testing.assert_array_equal(np.loadtxt(tmp_path / "c.seg", dtype=np.int64), want)
    said = capsys.readouterr().out
    assert "12 content-adaptive superpoints (merged from 5 times as many)" in said
    assert "--min-elements" not in said  # the start's hints do not apply to the level
    # a start beyond the points: the count the start made, not "10**9 times as many"
    assert main(["segment", str(path), "-k", "12", "--adaptive", "1000000000", "-o",
                 str(tmp_path / "c.seg")]) == 0
    assert "12 content-adaptive superpoints (merged from 2,000)" in capsys.readouterr().out
    for bad in (["--extent-weight", "0.1"],
                ["--adaptive", "--extent-weight", "-1"],
                ["--graph", str(tmp_path / "g.npz"), "--levels", "5",
                 "--extent-weight", "0.1"]):
        assert main(["segment", str(path), "-k", "12", *bad, "-o",
                     str(tmp_path / "x.seg")]) == 2
        assert "--extent-weight takes a number >= 0" in capsys.readouterr().err
    assert not (tmp_path / "x.seg").exists() and not (tmp_path / "g.npz").exists()


def test_the_registry_runs_the_adaptive_level():
    from superfacets import adaptive_superpoints
    from superfacets.evaluation.methods import get_method

    method = get_method("adaptive")
    pts = _bumpy_cloud(2000)
    cfg = dict(method.defaults, start=5, extent_weight="0.05")
    run = method.run(pts, 12, cache={}, seed=0, elements="points", **cfg)
    np.testing.assert_array_equal(run.labels,
                                  adaptive_superpoints(pts, 12, start=5, extent_weight=0.05))
    auto = method.run(pts, 12, cache={}, seed=0, elements="points", **method.defaults)
    np.testing.assert_array_equal(auto.labels, adaptive_superpoints(pts, 12))
    assert method.defaults["start"] == 10 and "points" in method.elements
    # a parameter may not take a metric's column of the results file
    from superfacets.evaluation.methods import register_method

    with pytest.raises(ParameterError, match="reserved by the runner"):
        register_method("x", method.run, defaults={"compactness": 0.1})


def test_batch_writes_content_adaptive_superpoints(tmp_path, capsys):
    from superfacets import adaptive_superpoints
    from superfacets.cli import main
    from superfacets.scale.runner.batch import run_batch

    corpus = tmp_path / "in"
    corpus.mkdir()
    clouds = {name: _bumpy_cloud(1500, seed) for seed, name in enumerate(("a", "b"))}
    for name, pts in clouds.items():
        np.savetxt(corpus / f"{name}.xyz", pts)
    out = tmp_path / "out"
    s = run_batch([str(corpus)], out, 10, adaptive=4, extent_weight=0.05, workers=1,
                  progress=False)
    assert s.ok == 2
    for name, pts in clouds.items():
        np.testing.assert_array_equal(np.loadtxt(out / f"{name}.seg", dtype=np.int64),
                                      adaptive_superpoints(pts, 10, start=4, extent_weight=0.05))
    with pytest.raises(ParameterError, match=r"adaptive.start 4 -> 5"):  # never mixed
        run_batch([str(corpus)], out, 10, adaptive=5, workers=1, progress=False)
    with pytest.raises(ParameterError, match=r"adaptive \(--adaptive\) takes n_segments"):
        run_batch([str(corpus)], tmp_path / "o2", 10, adaptive=4, per_object=True, workers=1)
    with pytest.raises(ParameterError, match=r"extent_weight \(--extent-weight\) goes with"):
        run_batch([str(corpus)], tmp_path / "o2", 10, extent_weight=0.1, workers=1)
    # the command line: the same labels
    assert main(["batch", str(corpus), "-o", str(tmp_path / "o3"), "-k", "10", "--adaptive",
                 "4", "--extent-weight", "0.05", "--workers", "1", "-q"]) == 0
    np.testing.assert_array_equal(np.loadtxt(tmp_path / "o3" / "a.seg", dtype=np.int64),
                                  np.loadtxt(out / "a.seg", dtype=np.int64))
    assert not (tmp_path / "o2").exists()


def test_the_old_names_are_gone():
    """``compactness=``, ``level_compactness``, ``--level-compactness`` and
    ``result.radius`` (renamed before any release) are not kept."""
    from superfacets.cli import build_parser

    r = segment(grid_mesh(20, 20), 30)
    with pytest.raises(TypeError):
        r.hierarchy([5], cost="planarity", compactness=0.2)
    assert not hasattr(r, "radius")
    with pytest.raises(SystemExit):
        build_parser().parse_args(["segment", "m.off", "--adaptive", "--level-compactness",
                                   "0.2"])


def test_the_adaptive_level_is_a_parameter_of_segment_and_superpoints():
    """One front door: ``segment(cloud, k, adaptive=True)`` (was "unknown parameter(s)
    adaptive") and ``superpoints(..., adaptive=START)`` give the adaptive level's labels;
    ``extent_weight`` alone is refused."""
    from superfacets import superpoints
    from superfacets.api.levels import adaptive_segment

    rng = np.random.default_rng(0)
    xyz = rng.normal(size=(3000, 3))
    xyz /= np.linalg.norm(xyz, axis=1, keepdims=True)
    level = adaptive_segment(xyz, 12, start=4)
    r = segment(xyz, 12, adaptive=4)
    assert np.array_equal(r.labels, level.labels) and r.params["start"] == 4
    assert segment(xyz, 12, adaptive=True).params["start"] == 10
    assert np.array_equal(superpoints(xyz, 12, adaptive=4), level.labels)
    with pytest.raises(ParameterError, match="extent_weight is a term of the adaptive"):
        segment(xyz, 12, extent_weight=0.1)
    with pytest.raises(ParameterError, match="adaptive takes n_segments"):
        segment(xyz, None, radius=0.1, adaptive=True)
