"""The superfacet graph and the hierarchy: known answers on synthetic inputs, invariants."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from conftest import grid_mesh

from superfacets import segment
from superfacets.elements import face_graph
from superfacets.errors import ParameterError
from superfacets.graph.adjacency import superfacet_graph
from superfacets.graph.hierarchy import hierarchy
from superfacets.inputs.convert import as_mesh
from superfacets.method.connectivity import label_components


def test_box_sides_known_answer():
    box = as_mesh(trimesh.creation.box(extents=(1.0, 2.0, 3.0)))
    g = face_graph(box)
    sides = np.argmax(np.abs(box.normals), axis=1) * 2 + (box.normals.sum(axis=1) > 0)
    labels = np.unique(sides, return_inverse=True)[1]
    sg = superfacet_graph(g, labels)
    assert (sg.n_segments, sg.n_edges) == (6, 12)
    assert (sg.edge_index[0] < sg.edge_index[1]).all()
    np.testing.assert_allclose(sg.mean_angle, np.pi / 2)  # every box edge is a right angle
    np.testing.assert_allclose(sg.concave, 0.0)  # all convex
    np.testing.assert_allclose(sg.area.sum(), 2 * (2 + 3 + 6))
    # the border of two sides is the box edge they share: 1, 2 or 3 long
    assert sorted(np.round(sg.border_length, 9).tolist()) == [1.0] * 4 + [2.0] * 4 + [3.0] * 4
    for s in range(6):  # centroids are the face centers, normals the axes
        assert np.isclose(np.abs(sg.normal[s]).max(), 1.0)
        assert np.isclose(np.abs(sg.centroid[s]).max(), np.abs(sg.centroid[s] @ sg.normal[s]))
    m = sg.to_scipy()
    assert (m != m.T).nnz == 0 and m.nnz == 24
    assert m[sg.edge_index[0, 0], sg.edge_index[1, 0]] == sg.border_length[0]


def test_concave_border_and_features():
    # a V-shaped valley: two flanks meeting in a concave crease along x = 0
    mesh = grid_mesh(20, 10, height=lambda x, y: 0.5 * np.abs(x))
    x = mesh.centroids[:, 0]
    labels = (x > 0).astype(np.int64)
    feat = np.c_[labels * 1.0, np.ones(mesh.n_faces)]
    sg = superfacet_graph(face_graph(mesh), labels, feat)
    assert sg.n_edges == 1
    assert sg.concave[0] == pytest.approx(1.0)
    assert sg.mean_angle[0] == pytest.approx(2 * np.arctan(0.5), rel=1e-6)
    np.testing.assert_allclose(sg.feature, [[0, 1], [1, 1]])
    with pytest.raises(ParameterError, match="features"):
        superfacet_graph(face_graph(mesh), labels, feat[:-1])
    with pytest.raises(ParameterError, match="every value"):
        superfacet_graph(face_graph(mesh), labels * 2)


def test_result_graph_and_networkx(tmp_path):
    nx = pytest.importorskip("networkx")
    mesh = as_mesh(trimesh.creation.icosphere(subdivisions=4))
    r = segment(mesh, 30)
    sg = r.graph()
    assert sg.n_segments == r.n_segments
    np.testing.assert_allclose(sg.area.sum(), mesh.area)
    # each adjacency of the face graph across two labels is in the graph, and only those
    g = face_graph(mesh)
    a, b = r.labels[g.pairs[:, 0]], r.labels[g.pairs[:, 1]]
    cross = {(min(p, q), max(p, q)) for p, q in zip(a, b) if p != q}
    assert cross == set(map(tuple, sg.edge_index.T.tolist()))
    G = sg.to_networkx()
    assert G.number_of_nodes() == 30 and G.number_of_edges() == sg.n_edges
    assert nx.is_connected(G)
    sg.save(tmp_path / "g.npz")
    with np.load(tmp_path / "g.npz") as z:
        np.testing.assert_array_equal(z["edge_index"], sg.edge_index)


def test_hierarchy_is_nested_connected_and_follows_creases():
    # two flat plates joined by a sharp concave crease: the coarsest level of two
    # segments splits at the crease, not across it
    mesh = grid_mesh(40, 20, height=lambda x, y: 1.0 * np.abs(x))
    r = segment(mesh, 24)
    h = r.hierarchy([12, 6, 2])
    assert h.levels == (12, 6, 2)
    g = face_graph(mesh)
    previous = r.labels
    for i, n in enumerate(h.levels):
        lab = h.labels(i, r.labels)
        assert int(lab.max()) + 1 == n and np.unique(lab).size == n
        assert np.unique(label_components(g, lab)).size == n  # each segment connected
        # nested: every segment of the level below lies in one segment of this one
        pairs = np.unique(np.c_[previous, lab], axis=0)
        assert np.unique(pairs[:, 0]).size == pairs.shape[0]
        previous = lab
    top = h.labels(2, r.labels)
    x = mesh.centroids[:, 0]
    assert np.unique(top[x < -0.05]).size == 1 and np.unique(top[x > 0.05]).size == 1
    assert top[x < -0.05][0] != top[x > 0.05][0]


def test_hierarchy_levels_are_checked():
    mesh = grid_mesh(10, 10)
    r = segment(mesh, 8)
    k = r.n_segments
    with pytest.raises(ParameterError, match=rf"levels must lie in \[1, {k}\]"):
        r.hierarchy([k + 1])
    with pytest.raises(ParameterError, match="levels"):
        r.hierarchy([])
    with pytest.raises(ParameterError, match="levels"):
        r.hierarchy([0])
    with pytest.raises(ParameterError, match="levels must be a number of segments or a "
                                             "sequence of them, got None"):
        r.hierarchy(None)
    with pytest.raises(ParameterError, match="beta"):
        hierarchy(r.graph(), [2], beta=1.0)
    assert r.hierarchy(k).parents[0].tolist() == list(range(k))  # K itself: the identity


def test_hierarchy_of_two_pieces_stops_at_two():
    a = trimesh.creation.icosphere(subdivisions=3)
    b = a.copy()
    b.apply_translation([5, 0, 0])
    both = as_mesh(trimesh.util.concatenate([a, b]))
    r = segment(both, 20)
    h = r.hierarchy([2])
    top = h.labels(0, r.labels)
    half = both.n_faces // 2
    assert np.unique(top[:half]).size == 1 and np.unique(top[half:]).size == 1
    with pytest.raises(ParameterError, match="2 connected piece"):
        r.hierarchy([1])


def test_superpoint_graph_of_a_cloud_keeps_rows():
    rng = np.random.default_rng(0)
    pts = rng.random((3000, 3)) * [1, 1, 0.01]
    pts[5] = np.nan
    from superfacets.inputs.cloud import PointCloud

    cloud = PointCloud(pts, allow_invalid=True)
    r = segment(cloud, 10)
    assert r.labels[5] == -1
    sg = r.graph(features=np.c_[pts[:, :1]])  # a NaN row that is not an element is skipped
    assert sg.n_segments == r.n_segments and sg.feature.shape == (r.n_segments, 1)
    h = r.hierarchy([3])
    top = h.labels(0, r.labels)
    assert top[5] == -1 and set(np.unique(top[top >= 0])) == {0, 1, 2}


def test_cli_writes_the_graph_and_the_levels(tmp_path, capsys):
    from superfacets.cli import main
    from superfacets.io import write_mesh

    mesh = grid_mesh(30, 30, height=lambda x, y: np.abs(x))
    path = tmp_path / "v.off"
    write_mesh(path, mesh)
    out = tmp_path / "g.npz"
    assert main(["segment", str(path), "-k", "20", "--graph", str(out), "--levels", "8,3",
                 "-o", str(tmp_path / "v.seg")]) == 0
    assert "g.npz (superfacet graph)" in capsys.readouterr().out
    with np.load(out) as z:
        k = int(z["labels"].max()) + 1
        assert z["edge_index"].shape[0] == 2 and z["area"].shape == (k,)
        e = z["edge_index"]  # PyTorch Geometric's layout: each edge both ways
        assert {tuple(p) for p in e.T} == {tuple(p) for p in e[::-1].T}
        assert z["x"].shape == (k, len(z["node_features"]))
        assert z["edge_attr"].shape == (e.shape[1], len(z["edge_features"]))
        np.testing.assert_array_equal(z["super_index"], z["labels"])
        assert z["levels"].tolist() == [8, 3]
        assert z["parent_0"].shape == (k,) and z["parent_1"].shape == (8,)
        np.testing.assert_array_equal(z["labels_1"], z["parent_1"][z["parent_0"]][z["labels"]])
    # a level beyond K: one clear error, nothing written
    bad = tmp_path / "bad.npz"
    assert main(["segment", str(path), "-k", "20", "--graph", str(bad), "--levels", "500",
                 "-o", str(tmp_path / "bad.seg")]) == 2
    said = "--levels must each be at most the 20 segments they merge (-k)"
    assert said in capsys.readouterr().err
    assert not bad.exists() and not (tmp_path / "bad.seg").exists()
    assert main(["segment", str(path), "--radius", "0.3", "--graph", str(bad), "--levels",
                 "500", "-o", str(tmp_path / "bad.seg")]) == 2  # (a count known after the run)
    assert "levels must lie in" in capsys.readouterr().err
    assert not bad.exists() and not (tmp_path / "bad.seg").exists()
    assert main(["segment", str(path), "--levels", "5"]) == 2
    assert "--levels goes with --graph" in capsys.readouterr().err
    # the planarity cost: the API's levels
    flat = tmp_path / "flat.npz"
    assert main(["segment", str(path), "-k", "20", "--graph", str(flat), "--levels", "8,3",
                 "--level-cost", "planarity", "-o", str(tmp_path / "f.seg")]) == 0
    r = segment(mesh, 20)
    with np.load(flat) as z:
        np.testing.assert_array_equal(z["labels"], r.labels)
        np.testing.assert_array_equal(z["labels_0"], r.hierarchy([8, 3], cost="planarity")
                                      .labels(0, r.labels))


def test_scatter_is_the_area_weighted_spread_about_the_centroid():
    mesh = grid_mesh(12, 12, height=lambda x, y: 0.3 * x * y)
    g = face_graph(mesh)
    labels = (mesh.centroids[:, 0] > 0).astype(np.int64)
    sg = superfacet_graph(g, labels)
    for s in range(2):
        m = labels == s
        d = mesh.centroids[m] - sg.centroid[s]
        want = (mesh.areas[m, None, None] * d[:, :, None] * d[:, None, :]).sum(axis=0)
        np.testing.assert_allclose(sg.scatter[s], want, rtol=1e-10, atol=1e-14)
    box = as_mesh(trimesh.creation.box())  # flat sides: no spread off their planes
    sides = np.unique(np.round(box.normals, 6), axis=0, return_inverse=True)[1].ravel()
    flat = superfacet_graph(face_graph(box), sides)
    assert np.abs(np.linalg.eigvalsh(flat.scatter)[:, 0]).max() < 1e-12


def test_planarity_levels_merge_the_flat_floor_first():
    # a floor with a bump in the middle: Ward's cost keeps segments of even size, so most
    # lie on the floor; the planarity cost merges the floor first and keeps the bump's
    mesh = grid_mesh(60, 60, height=lambda x, y: 0.5 * np.exp(-(x ** 2 + y ** 2) / 0.04))
    r = segment(mesh, 80)
    floor = mesh.centroids[:, 2] < 1e-4
    flat = r.hierarchy([12], cost="planarity").labels(0, r.labels)
    even = r.hierarchy([12]).labels(0, r.labels)
    assert np.unique(flat).size == np.unique(even).size == 12
    assert np.unique(flat[floor]).size <= 2 < 6 <= np.unique(even[floor]).size
    assert np.unique(flat[~floor]).size >= 10
    assert np.unique(label_components(face_graph(mesh), flat)).size == 12  # each connected
    with pytest.raises(ParameterError, match="cost must be 'ward' or 'planarity'"):
        r.hierarchy([12], cost="plane")


def test_closed_form_plane_distance_is_numpys_smallest_eigenvalue():
    from oracle.hierarchy import _plane

    rng = np.random.default_rng(0)
    for i in range(500):
        a = rng.normal(size=(3, 3))
        m = a @ a.T * rng.uniform(1e-3, 1e3)
        if i % 3 == 0:  # nearly flat: one direction 10^6 times thinner
            m[2] *= 1e-6
            m[:, 2] *= 1e-6
        want = max(np.linalg.eigvalsh(m)[0], 0.0)
        got = _plane(m[0, 0], m[1, 1], m[2, 2], m[0, 1], m[0, 2], m[1, 2])
        assert abs(got - want) <= 1e-12 * np.abs(m).max()
    assert _plane(2.0, 2.0, 2.0, 0.0, 0.0, 0.0) == 2.0  # a multiple of the identity


def test_adaptive_superpoints_spend_the_count_off_the_floor():
    from superfacets import adaptive_superpoints

    # a floor with a bump, sampled as points: the level keeps the floor in few pieces
    mesh = grid_mesh(60, 60, height=lambda x, y: 0.5 * np.exp(-(x ** 2 + y ** 2) / 0.04))
    pts = mesh.centroids
    floor = pts[:, 2] < 1e-4
    plain = segment(pts, 12, merge_from=1).labels  # the method's equal areas
    labels = adaptive_superpoints(pts, 12, start=8)
    assert labels.shape == (pts.shape[0],) and np.unique(labels).size == 12
    assert np.unique(labels[floor]).size <= 2 < np.unique(plain[floor]).size
    # the same as the two steps, and start=1 is the method's own superpoints
    r = segment(pts, 96, merge_from=1)
    np.testing.assert_array_equal(labels, r.hierarchy([12], cost="planarity")
                                  .labels(0, r.labels))
    np.testing.assert_array_equal(adaptive_superpoints(pts, 12, start=1), plain)
    # more than the elements: it starts from all of them
    small = grid_mesh(4, 4)
    assert np.unique(adaptive_superpoints(small, 5)).size == 5
    with pytest.raises(ParameterError, match="start"):
        adaptive_superpoints(pts, 12, start=0)
    with pytest.raises(ParameterError, match="n_segments"):
        adaptive_superpoints(small, 100)


def test_cli_adaptive_writes_the_levels_labels(tmp_path, capsys):
    from superfacets.api.levels import adaptive_segment
    from superfacets.cli import main
    from superfacets.io import write_mesh

    mesh = grid_mesh(40, 40, height=lambda x, y: 0.5 * np.exp(-(x ** 2 + y ** 2) / 0.04))
    path = tmp_path / "b.off"
    write_mesh(path, mesh)
    assert main(["segment", str(path), "-k", "10", "--adaptive", "6", "-o",
                 str(tmp_path / "b.seg")]) == 0
    want = adaptive_segment(mesh, 10, start=6)
    np.testing.assert_array_equal(np.loadtxt(tmp_path / "b.seg", dtype=np.int64), want.labels)
    assert (want.labels[want.centers] == np.arange(10)).all()  # each center in its segment
    assert want.graph().n_segments == 10 and want.params["start"] == 6
    for bad, message in ((["--adaptive", "0"], "at least 1"),
                         (["--adaptive", "--per-object"], "--adaptive takes -k"),
                         (["--adaptive", "--tiles", "2"], "not with --tiles")):
        assert main(["segment", str(path), "-k", "10", *bad, "-o",
                     str(tmp_path / "x.seg")]) == 2
        assert message in capsys.readouterr().err
    assert not (tmp_path / "x.seg").exists()


def test_superpoint_graph_of_a_lazy_point_graph_reads_only_its_crossings():
    """A default point graph never builds its pairs and terms (about 60 bytes per
    adjacency): its superpoint graph comes from the crossing adjacencies alone, equal to
    the one made from every pair, and leaves the pairs and terms unbuilt."""
    from superfacets.elements.points import point_graph
    from superfacets.inputs.cloud import PointCloud

    rng = np.random.default_rng(6)
    xyz = rng.random((4000, 3)) * [3, 2, 0.2]
    pe = point_graph(PointCloud(xyz))
    g = pe.graph
    labels = np.empty(g.n_elements, dtype=np.int64)
    labels[pe.index] = segment(PointCloud(xyz), 25).labels  # (a new cloud: its own graph)
    lean = superfacet_graph(g, labels)
    assert not {"pairs", "terms", "lengths"} & set(g.__dict__)
    g.pairs, g.terms  # noqa: B018 (built: the path over every pair)
    full = superfacet_graph(g, labels)
    for name, a in lean.arrays().items():
        np.testing.assert_array_equal(a, full.arrays()[name], err_msg=name)
    assert lean.n_edges > 25
