"""Coarse-to-fine (multilevel.py) and the center tolerance: known answers and invariants."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from conftest import grid_mesh
from scipy.sparse.csgraph import connected_components, dijkstra
from test_segmentation import check_invariants

from superfacets import Mesh, segment
from superfacets.api.segmentation import pipeline
from superfacets.elements import face_graph
from superfacets.errors import ParameterError
from superfacets.method.coarse_to_fine import coarse_ratio, coarsen, grid_seeds, voronoi_cells
from superfacets.method.params import resolve
from superfacets.method.passes import hold_small_moves
from superfacets.method.weights import csr_weights, paper_weights


def _sphere(subdivisions=4, radius=1.0, shift=0.0):
    s = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return s.vertices + shift, s.faces


def _weighted(mesh):
    g = face_graph(mesh)
    w = paper_weights(g)
    return g, w, csr_weights(g, w)


def test_voronoi_cells_are_exact_nearest_seeds_and_connected(sphere):
    g, w, wc = _weighted(sphere)
    seeds = grid_seeds(g.positions, g.area, 60)
    seeds2, cluster, dist = voronoi_cells(g, wc, seeds)
    np.testing.assert_array_equal(seeds2, seeds)  # one component: no seed added
    assert np.all(cluster >= 0) and np.all(np.isfinite(dist))
    # distances: exactly those of Dijkstra from the nearest seed (scipy)
    d = dijkstra(g.to_csr(w), indices=seeds, min_only=True)
    np.testing.assert_allclose(dist, d, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(dist[seeds], 0.0)
    # each cell is connected in the face graph (a shortest-path tree)
    csr = g.to_csr()
    for c in range(seeds.shape[0]):
        idx = np.flatnonzero(cluster == c)
        assert connected_components(csr[idx][:, idx], directed=False)[0] == 1


def test_components_without_a_seed_get_their_own():
    # two concentric spheres: every grid cell's first face lies on the outer one
    va, fa = _sphere(3, 1.0)
    vb, fb = _sphere(3, 0.98)
    mesh = Mesh(np.vstack([va, vb]), np.vstack([fa, fb + va.shape[0]]))
    g, w, wc = _weighted(mesh)
    seeds = grid_seeds(g.positions, g.area, 20)
    assert np.all(seeds < fa.shape[0])  # the inner sphere got no seed from the grid
    seeds2, cluster, dist = voronoi_cells(g, wc, seeds)
    assert seeds2.shape[0] > seeds.shape[0] and np.all(cluster >= 0)
    inner = cluster[fa.shape[0]:]
    assert np.all(inner >= seeds.shape[0])  # inner faces only in the added cells
    assert np.all(cluster[:fa.shape[0]] < seeds.shape[0])


def test_coarse_graph_weights_follow_the_fine_distances(sphere):
    g, w, wc = _weighted(sphere)
    co = coarsen(g, wc, 16)
    cg = co.graph
    assert 0.3 * g.n_elements / 16 < cg.n_elements < 3 * g.n_elements / 16
    np.testing.assert_allclose(cg.area, g.area)
    assert cg.kind == "faces" and cg.indptr[-1] == co.weights.shape[0]
    # two clusters are adjacent iff some of their faces are
    a, b = co.cluster[g.pairs[:, 0]], co.cluster[g.pairs[:, 1]]
    fine_pairs = {(min(x, y), max(x, y)) for x, y in zip(a.tolist(), b.tolist()) if x != y}
    assert fine_pairs == set(map(tuple, cg.pairs.tolist()))
    # a coarse edge is a path between the two seeds: never shorter than their distance
    d = dijkstra(g.to_csr(w), indices=co.seeds[cg.pairs[:50, 0]])
    direct = d[np.arange(50), co.seeds[cg.pairs[:50, 1]]]
    pair_w = np.empty(cg.n_edges)
    pair_w[cg.dual_edge] = co.weights
    assert np.all(pair_w[:50] >= direct - 1e-12)
    assert np.all(pair_w[:50] <= 3 * direct + 1e-9)  # and not much longer (no detours)


def test_coarse_pairs_equal_a_stable_sort_and_reduceat():
    """The cluster adjacency kernel: each cluster pair once, in (lo, hi) order, the
    minimum path and the summed border lengths (pairs joined by 1 to several hundred
    adjacencies, the large buckets sorted another way)."""
    from oracle.voronoi import coarse_pairs

    from superfacets._kernels import native
    from superfacets.elements.graph import adjacency_csr

    rng = np.random.default_rng(1)
    for n, n_c, e in ((3000, 2000, 9000), (3000, 10, 20000), (50, 1, 400), (10, 3, 2)):
        pairs = np.unique(np.sort(rng.integers(0, n, (e, 2)), axis=1), axis=0)
        pairs = pairs[pairs[:, 0] != pairs[:, 1]]  # a graph's pairs: distinct, sorted
        e = pairs.shape[0]
        cluster = rng.integers(0, n_c, n)
        dist, w = rng.random(n), rng.random(e)
        lengths = rng.random(e) * 10 ** rng.uniform(-3, 3, e)
        # read from the CSR layout: each entry's weight, the pairs' order
        indptr, indices, dual_edge = adjacency_csr(pairs[:, 0], pairs[:, 1], n)
        out, via, length = coarse_pairs(indptr, indices, cluster, dist, w[dual_edge], lengths,
                                        np.empty(0), n_c)
        assert out.dtype == np.int32  # 4-byte cluster pairs
        for c in (cluster, cluster.astype(np.int32)):  # compiled: 4- or 8-byte clusters
            got = native.kernel("voronoi.coarse_pairs")(indptr, indices, c, dist, w[dual_edge],
                                                        lengths, np.empty(0), n_c)
            assert got[0].dtype == np.int32
            for x, y in zip(got, (out, via, length)):
                np.testing.assert_array_equal(x, y)
        a, b = cluster[pairs[:, 0]], cluster[pairs[:, 1]]
        cross = a != b
        lo, hi = np.minimum(a, b)[cross], np.maximum(a, b)[cross]
        o = np.argsort(lo * n_c + hi, kind="stable")
        key = (lo * n_c + hi)[o]
        first = np.flatnonzero(np.r_[True, key[1:] != key[:-1]]) if key.size else key
        path = (dist[pairs[:, 0]] + w + dist[pairs[:, 1]])[cross][o]
        np.testing.assert_array_equal(out, np.c_[lo[o][first], hi[o][first]].reshape(-1, 2))
        if key.size:
            np.testing.assert_array_equal(via, np.minimum.reduceat(path, first))
            np.testing.assert_allclose(length, np.add.reduceat(lengths[cross][o], first),
                                       rtol=1e-12)
        if n_c == 10:
            assert np.diff(np.r_[first, key.size]).max() > 32  # the merge-sorted buckets
        # border shares per element (points): the same sums as their lengths per pair
        shares = rng.random(n)
        from_shares = 0.5 * (shares[pairs[:, 0]] + shares[pairs[:, 1]])
        np.testing.assert_array_equal(
            coarse_pairs(indptr, indices, cluster, dist, w[dual_edge], np.empty(0), shares,
                         n_c)[2],
            coarse_pairs(indptr, indices, cluster, dist, w[dual_edge], from_shares,
                         np.empty(0), n_c)[2])


def test_coarse_ratio_rule():
    assert coarse_ratio(100_000, 150) == 1  # ~670 faces per superfacet: no coarsening
    assert coarse_ratio(1_693_760, 150) == 11
    assert coarse_ratio(6_775_040, 150) == 45
    # points: from 1,200 per superpoint (clusters of 3 points at least: a coarse graph of
    # half the points saved no time), about 400 clusters each, at most n_neighbors // 2
    assert coarse_ratio(1_000_000, 1000, "points") == 1
    assert coarse_ratio(1_199_000, 1000, "points") == 1
    assert coarse_ratio(1_200_000, 1000, "points") == 3
    assert coarse_ratio(1_000_000, 500, "points") == 5
    assert coarse_ratio(10_000_000, 500, "points") == 5
    assert coarse_ratio(10_000_000, 500, "points", n_neighbors=16) == 8
    assert coarse_ratio(1_000_000, 500, "vertices") == 1  # vertices: the faces' rule


def test_hold_small_moves_known_answer():
    pos = np.array([[0, 0, 0], [0.1, 0, 0], [1, 0, 0], [2, 0, 0]], float)
    old = np.array([0, 2, 3, 1], dtype=np.int64)
    new = np.array([1, 3, 3, -1], dtype=np.int64)
    assert hold_small_moves(new, old, pos, 0.5) == 1
    np.testing.assert_array_equal(new, [0, 3, 3, -1])  # 0 -> 1 moved 0.1: held


def test_coarse_to_fine_puts_the_boundary_on_the_crease(valley):
    # a V valley: two flat halves meeting at a concave crease along x = 0
    fine = grid_mesh(120, 60, height=lambda x, y: np.abs(x))
    for mesh in (valley, fine):
        r = segment(mesh, 2, coarsen=8)
        assert r.timings["coarse_elements"] < mesh.n_faces / 4
        check_invariants(mesh, r.labels)
        side = mesh.centroids[:, 0] > 0
        # each superfacet is one side of the crease
        assert all(np.unique(r.labels[side == s]).size == 1 for s in (False, True))
        assert r.labels[side][0] != r.labels[~side][0]


def test_coarse_to_fine_invariants_and_determinism():
    s = trimesh.creation.icosphere(subdivisions=5)  # 20,480 faces
    mesh = Mesh(s.vertices * [1, 1, 0.6], s.faces)
    a = segment(mesh, 4)  # 5,120 faces per superfacet: coarse-to-fine by default
    assert a.params["coarsen"] == 5 and a.timings["coarse_elements"] < mesh.n_faces / 2
    assert a.params["center_tol"] == 0.05
    check_invariants(mesh, a.labels)
    assert a.n_segments == 4
    b = segment(mesh, 4, n_threads=1)
    np.testing.assert_array_equal(a.labels, b.labels)
    assert a.converged  # the refinement on every face settled
    plain = segment(mesh, 4, coarsen=1)
    assert "coarse_elements" not in plain.timings and plain.params["coarsen"] == 1


def test_tol_zero_turns_coarse_to_fine_and_center_tol_off():
    s = trimesh.creation.icosphere(subdivisions=5)
    mesh = Mesh(s.vertices * [1, 1, 0.6], s.faces)
    paper = segment(mesh, 4, tol=0)
    assert paper.params["coarsen"] == 1 and paper.params["center_tol"] == 0.0
    assert "coarse_elements" not in paper.timings
    plain = pipeline(mesh, resolve(n_segments=4, tol=0), replay=False, jump_cycles=False)
    np.testing.assert_array_equal(paper.labels, plain.labels)
    # given explicitly, they apply even with tol = 0
    forced = segment(mesh, 4, tol=0, coarsen=4, center_tol=0.1)
    assert forced.params["coarsen"] == 4 and "coarse_elements" in forced.timings


@pytest.mark.parametrize("kw, match", [(dict(center_tol=-0.1), "center_tol"),
                                       (dict(center_tol=2.0), "center_tol"),
                                       (dict(coarsen=0), "coarsen"),
                                       (dict(coarsen=2.5), "coarsen")])
def test_bad_values_are_refused(kw, match):
    with pytest.raises(ParameterError, match=match):
        segment(grid_mesh(4, 4), 2, **kw)


def test_coarsen_is_capped_to_keep_clusters_per_superfacet():
    mesh = grid_mesh(40, 40)  # 3,200 faces
    r = segment(mesh, 3, coarsen=10_000)  # capped at 3,200 // (8 * 3) = 133 faces per cluster
    assert r.params["coarsen"] == 133 and r.n_segments == 3
    check_invariants(mesh, r.labels)
    r = segment(mesh, 500, coarsen=10)  # 6 faces per superfacet: no room for clusters
    assert r.params["coarsen"] == 1 and "coarse_elements" not in r.timings


def test_too_few_clusters_for_k_falls_back(sphere):
    from superfacets.method.coarse_to_fine import coarse_centers

    g, w, wc = _weighted(sphere)
    kw = dict(init="farthest", window=2.0, assignment="bounded", max_iter=50, tol=0.001,
              min_move=0.0, n_threads=1)
    r = np.sqrt(g.area / (30 * np.pi))
    centers, info = coarse_centers(g, wc, 100, k=30, radius=r, **kw)  # ~60 clusters
    assert centers is None and info["coarse_elements"] < 4 * 30
    centers, info = coarse_centers(g, wc, 10, k=30, radius=r, **kw)  # ~500 clusters
    assert centers.shape[0] >= 30 and np.unique(centers).size == centers.shape[0]
    assert info["coarse_passes"] >= 1


def test_grid_seeds_known_answer():
    # a 20 x 20 lattice of unit spacing (area 400): pitch sqrt(400 / 100) = 2 puts one
    # seed in each 2 x 2 block, the block's lowest index
    xy = np.stack(np.meshgrid(np.arange(20.0), np.arange(20.0), indexing="ij"), -1).reshape(-1, 2)
    pos = np.c_[xy, np.zeros(400)]
    seeds = grid_seeds(pos, 400.0, 100)
    assert seeds.shape == (100,) and np.all(np.diff(seeds) > 0)
    assert np.all(pos[seeds, :2] % 2 == 0)
    assert grid_seeds(pos, 400.0, 400).shape == (400,)  # as many seeds as elements: all


def test_clusters_without_any_neighbour():
    # 40 separate triangles: every cluster is a component of its own, no coarse edge
    t = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    v = np.concatenate([t + [3.0 * i, 0, 0] for i in range(40)])
    mesh = Mesh(v, np.arange(120).reshape(40, 3))
    g, w, wc = _weighted(mesh)
    co = coarsen(g, wc, 2)
    assert co.graph.n_edges == 0 and co.graph.n_elements == 40
    r = segment(mesh, 4, coarsen=2)  # capped to 1 (40 faces, 4 superfacets): plain run
    check_invariants(mesh, r.labels)


def test_a_large_clouds_coarse_start_lets_its_weights_go_and_the_passes_read_them_again(
        monkeypatch):
    """On a large cloud the coarse start forgets the fine weights once its clusters'
    graph is made, and they are made again for the passes: the same labels as a run
    that keeps them, and they are made exactly once more."""
    import superfacets.method.pipeline as pl
    from superfacets.method.weights import HeldWeights

    rng = np.random.default_rng(3)
    u, v = rng.random((2, 300_000))  # a wavy sheet: 300,000 points, above the size
    pts = np.c_[u, v, 0.05 * np.sin(6 * u) * np.cos(4 * v)]  # where runs release
    made = []
    real = pl.held_weights

    def counted(*args, **kwargs):
        made.append(real(*args, **kwargs))
        return made[-1]

    monkeypatch.setattr(pl, "held_weights", counted)
    let_go = segment(pts, 40, merge_from=1)  # 40 superpoints (merges: 3,000, no coarse start)
    assert let_go.params["coarsen"] > 1 and [h.remade for h in made] == [1]
    monkeypatch.setattr(pl, "held_weights", lambda g, r, w, *a: HeldWeights(w))
    kept = segment(pts, 40, merge_from=1)
    np.testing.assert_array_equal(let_go.labels, kept.labels)


def test_a_coarse_graphs_lengths_are_made_when_read_the_fine_sums():
    """The clusters' border lengths are not made by the coarsening (the coarse run does
    not read them); read, they are the fine adjacencies' lengths summed per pair."""
    g, _, wc = _weighted(Mesh(*_sphere(4)))
    co = coarsen(g, wc, 8)
    assert "lengths" not in co.graph.__dict__
    pairs, lengths = co.graph.pairs, co.graph.lengths
    c = co.cluster[g.pairs]
    cross = c[:, 0] != c[:, 1]
    key = np.sort(c[cross], axis=1)
    expected = {}
    for (a, b), length in zip(map(tuple, key), g.lengths[cross]):
        expected[(a, b)] = expected.get((a, b), 0.0) + length
    assert len(expected) == pairs.shape[0]
    got = dict(zip(map(tuple, pairs), lengths))
    assert all(abs(got[p] - v) <= 1e-12 * max(1.0, v) for p, v in expected.items())


def test_the_coarse_runs_orphan_seeds_are_counted_and_said(tmp_path, capsys):
    """A window narrower than the radius leaves clusters of the coarse run that no center
    reaches: each seeds a superfacet of its own, as on every element. The run made 116
    superfacets for 12 and said nothing (n_orphan_seeds counted the fine passes' only)."""
    from superfacets.cli import main

    mesh = trimesh.creation.icosphere(subdivisions=6)
    r = segment(mesh, 12, window=0.5)
    assert r.params["coarsen"] > 1 and r.n_segments > 12
    assert r.n_orphan_seeds == r.timings["coarse_orphans"] > 0
    assert r.n_orphan_seeds >= r.n_segments - 12
    path = tmp_path / "sphere.ply"
    mesh.export(path)
    assert main(["segment", str(path), "-k", "12", "--window", "0.5",
                 "-o", str(tmp_path / "s.seg")]) == 0
    assert "regions that no center reached within its window" in capsys.readouterr().err
