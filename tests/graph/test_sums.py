"""What the merges read, as sums (``superfacets.graph.sums``): known answers against the
superfacet graph made from scratch."""

from __future__ import annotations

import numpy as np
import trimesh

from superfacets.elements import face_graph
from superfacets.elements.points import point_graph
from superfacets.graph.adjacency import crossing_adjacencies, superfacet_graph
from superfacets.graph.sums import border_sums, grouped_graph, grouped_planes, pair_sums, point_sums
from superfacets.inputs.cloud import PointCloud
from superfacets.inputs.convert import as_mesh


def _graphs_and_labels():
    """A point graph (its one-pass kernel) and a mesh's face graph (every pair), each with
    fine labels (strips) and a coarsening of them (a union of fine labels each)."""
    rng = np.random.default_rng(11)
    xyz = rng.random((5000, 3)) * [3, 2, 0.3]
    for g in (point_graph(PointCloud(xyz)).graph,
              face_graph(as_mesh(trimesh.creation.icosphere(subdivisions=4)))):
        fine = (g.positions[:, 0] * 9).astype(np.int64) * 7 + \
            (g.positions[:, 1] * 6.5).astype(np.int64) % 7
        fine = np.unique(fine, return_inverse=True)[1].astype(np.int64)
        k = int(fine.max()) + 1
        top = np.unique(rng.integers(0, 6, k), return_inverse=True)[1].astype(np.int64)
        yield g, fine, k, top


def test_the_pairs_sums_are_the_crossing_adjacencies_summed():
    for g, fine, k, _ in _graphs_and_labels():
        pc, length, cos, concave = crossing_adjacencies(g, fine)
        want = pair_sums(fine[pc[:, 0]], fine[pc[:, 1]], length,
                         np.arccos(np.clip(cos, -1.0, 1.0)), concave.astype(float))
        got = border_sums(g, fine, k)
        np.testing.assert_array_equal(got["edges"], want["edges"])
        for name in want:
            np.testing.assert_allclose(got[name], want[name], rtol=1e-12, err_msg=name)
        assert got["crossings"].sum() == pc.shape[0]


def test_a_grouping_of_the_sums_is_the_graph_of_the_grouped_labels():
    """Summed once over the fine labels and added up per group, the sums give the graph
    superfacet_graph makes from the coarse labels (their area-weighted centroids, the
    border-weighted angles and concave shares), and the points' planes by Chan's rule."""
    for g, fine, k, top in _graphs_and_labels():
        coarse = top[fine]
        pairs = border_sums(g, fine, k)
        nodes = point_sums(fine, k, g.positions, g.normals, g.sizes)
        groups = int(top.max()) + 1
        area = np.bincount(top, weights=nodes["area"], minlength=groups)
        mean = np.stack([np.bincount(top, weights=nodes["area"] * nodes["area_mean"][:, c])
                         for c in range(3)], 1) / area[:, None]
        got = grouped_graph(top, pairs["edges"], pairs, area, mean)
        want = superfacet_graph(g, coarse)
        np.testing.assert_array_equal(got.edge_index, want.edge_index)
        for name in ("border_length", "mean_angle", "concave", "area", "centroid"):
            np.testing.assert_allclose(getattr(got, name), getattr(want, name), rtol=1e-9,
                                       atol=1e-12, err_msg=name)
        count, centre, scatter = grouped_planes(top, nodes["count"], nodes["mean"],
                                                nodes["scatter"])
        np.testing.assert_array_equal(count, np.bincount(coarse))
        for s in range(groups):
            d = g.positions[coarse == s] - g.positions[coarse == s].mean(axis=0)
            np.testing.assert_allclose(centre[s], g.positions[coarse == s].mean(axis=0),
                                       atol=1e-12)
            np.testing.assert_allclose(scatter[s], d.T @ d, rtol=1e-9, atol=1e-12)


def test_pair_sums_of_names_too_large_for_one_key_are_the_same(monkeypatch):
    from superfacets.graph import sums

    rng = np.random.default_rng(0)
    a, b = rng.integers(0, 50, 5000) * 1_000_003, rng.integers(0, 50, 5000) * 1_000_003
    w = [rng.random(5000) for _ in range(3)]
    one = sums.pair_sums(a, b, *w)
    monkeypatch.setattr(sums, "_ONE_KEY", 0)  # every pair by a sort of rows
    rows = sums.pair_sums(a, b, *w)
    assert one.keys() == rows.keys()
    for key in one:
        np.testing.assert_array_equal(one[key], rows[key])
    e = one["edges"]
    assert (e[:, 0] <= e[:, 1]).all()
    assert (np.lexsort((e[:, 1], e[:, 0])) == np.arange(len(e))).all()  # in the pairs' order


def test_the_pairs_sums_are_the_same_on_any_number_of_threads(monkeypatch):
    """The compiled pass lists each chunk's crossings on threads and adds them on one, in
    pair order: one thread or three give the same sums, bit for bit (a cloud of two chunks
    of rows, each split among the threads; labels of superpoints of about 12 points, so
    most adjacencies cross, and of 40 strips)."""
    rng = np.random.default_rng(4)
    xyz = np.c_[rng.random((140_000, 2)) * [40, 30], 0.02 * rng.standard_normal(140_000)]
    g = point_graph(PointCloud(xyz)).graph
    cells = (g.positions[:, 0] * 10).astype(np.int64) * 300 + (g.positions[:, 1] * 10).astype(
        np.int64)
    for labels in (np.unique(cells, return_inverse=True)[1].astype(np.int64),
                   (g.positions[:, 0]).astype(np.int64)):
        k = int(labels.max()) + 1
        got = {}
        for threads in ("1", "3"):
            monkeypatch.setenv("SUPERFACETS_KERNEL_THREADS", threads)
            got[threads] = border_sums(g, labels, k)
        assert got["1"]["edges"].shape[0] >= k - 1  # (every neighbour pair of labels)
        for name, a in got["1"].items():
            b = got["3"][name]
            assert a.dtype == b.dtype and np.array_equal(a, b), name
