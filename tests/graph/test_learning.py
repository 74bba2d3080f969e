"""The superpoint graph for learning pipelines: both directions of each edge, and the
handcrafted features checked on shapes whose answers are known."""

from __future__ import annotations

import numpy as np
import pytest

from superfacets import ParameterError, PointCloud, segment
from superfacets.graph.learning import EDGE_FEATURES, NODE_FEATURES


def _column(a, name):
    return a["x"][:, list(a["node_features"]).index(name)]


def _scene(seed=0):
    """A flat ground (20 m by 20 m) with a thin vertical pole 3 m tall, z up."""
    rng = np.random.default_rng(seed)
    ground = np.c_[rng.random((8000, 2)) * 20, np.zeros(8000)]
    t = rng.random(600) * 3.0
    angle = rng.random(600) * 2 * np.pi
    pole = np.c_[10 + 0.03 * np.cos(angle), 10 + 0.03 * np.sin(angle), 0.2 + t]
    return ground, pole


def test_a_square_plane_is_planar_and_level_a_pole_linear_and_upright():
    ground, pole = _scene()
    plane = segment(PointCloud(ground), 1).learning_graph()
    assert _column(plane, "planarity")[0] > 0.95 and _column(plane, "linearity")[0] < 0.05
    assert _column(plane, "verticality")[0] < 0.01 and _column(plane, "scattering")[0] < 0.01
    stick = segment(PointCloud(pole), 1).learning_graph()
    assert _column(stick, "linearity")[0] > 0.95 and _column(stick, "verticality")[0] > 0.95
    tilted = segment(PointCloud(ground[:, [0, 2, 1]]), 1).learning_graph()  # a wall
    assert _column(tilted, "planarity")[0] > 0.95 and _column(tilted, "verticality")[0] > 0.99


def test_an_up_is_an_axis_or_a_direction_and_nothing_else():
    """``up`` may name an axis (``'y'``: the wall above is level seen with y up); a zero
    vector gave NaN features with a RuntimeWarning, a word or two numbers numpy's errors."""
    ground, _ = _scene()
    r = segment(PointCloud(ground[:, [0, 2, 1]]), 1)
    for up in ("y", "-y", (0, 5, 0)):
        assert _column(r.learning_graph(up=up), "verticality")[0] < 0.01, up
    for bad in (np.zeros(3), "q", [0, 1], (0, np.nan, 1)):
        with pytest.raises(ParameterError, match="up must be an axis"):
            r.learning_graph(up=bad)


def test_the_normal_is_the_best_planes_in_the_up_half_space():
    """Each superpoint's normal is its points' best plane's, turned to the side of ``up``
    (Superpoint Transformer's convention), whichever way the points' own normals face: a
    tilted plane given normals all facing down, or half of them up, reads the same."""
    rng = np.random.default_rng(3)
    uv = rng.random((3000, 2)) * 10
    n = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])
    e1 = np.cross(n, [1.0, 0, 0])
    e1 /= np.linalg.norm(e1)
    pts = uv[:, :1] * e1 + uv[:, 1:] * np.cross(n, e1)
    down = np.tile(-n, (3000, 1))
    mixed = np.where((np.arange(3000) % 2 == 0)[:, None], down, -down)
    got = []
    for normals in (down, mixed):
        r = segment(PointCloud(pts, normals=normals), 6, merge_from=1)
        a = r.learning_graph()
        got.append(a["x"][:, [list(a["node_features"]).index(f"normal_{c}") for c in "xyz"]])
        assert np.allclose(got[-1], n, atol=1e-4)
        flipped = r.learning_graph(up="-z")  # the other half-space
        assert np.allclose(flipped["x"][:, 7:10], -n, atol=1e-4)
    np.testing.assert_array_equal(got[0], got[1])


def test_a_scene_s_superpoints_read_as_ground_and_pole():
    ground, pole = _scene()
    r = segment(PointCloud(np.vstack([ground, pole]), up=(0, 0, 1)), 12, merge_from=1)
    a = r.learning_graph()
    pole_sp = np.unique(r.labels[len(ground):])
    ground_sp = np.setdiff1d(np.unique(r.labels[:len(ground)]), pole_sp)
    assert ground_sp.size >= 8
    assert (_column(a, "scattering")[ground_sp] < 0.05).all()  # flat, whatever its outline
    assert (_column(a, "verticality")[ground_sp] < 0.05).all()
    assert (np.abs(_column(a, "elevation")[ground_sp]) < 0.05).all()
    top = pole_sp[np.argmax(a["pos"][pole_sp, 2])]  # the pole's upper part
    assert _column(a, "linearity")[top] > 0.9
    assert _column(a, "verticality")[top] > 0.9
    assert _column(a, "elevation")[top] > 1.0  # above the ground beneath it
    feats = np.c_[_column(a, "linearity"), _column(a, "planarity"), _column(a, "scattering")]
    assert np.allclose(feats.sum(axis=1), 1.0, atol=1e-5) and (feats >= -1e-6).all()
    counts = np.bincount(r.labels, minlength=r.n_segments)
    assert np.allclose(_column(a, "log_count"), np.log1p(counts), atol=1e-5)


def test_the_edges_go_both_ways_with_their_offsets():
    ground, pole = _scene(1)
    r = segment(PointCloud(np.vstack([ground, pole])), 15)
    a, g = r.learning_graph(), r.graph()
    e = a["edge_index"]
    assert e.shape == (2, 2 * g.n_edges)
    assert {tuple(p) for p in e.T} == {tuple(p) for p in e[::-1].T}  # symmetric
    assert len({tuple(p) for p in e.T}) == e.shape[1] and (e[0] != e[1]).all()
    attr = a["edge_attr"]
    assert attr.shape == (e.shape[1], len(EDGE_FEATURES))
    off = attr[:, [EDGE_FEATURES.index(c) for c in ("offset_x", "offset_y", "offset_z")]]
    assert np.allclose(off, a["pos"][e[1]] - a["pos"][e[0]], atol=1e-4)
    half = g.n_edges  # j -> i carries the attributes of i -> j, its offset reversed
    assert np.allclose(attr[:half, :3], attr[half:, :3])
    assert np.array_equal(a["super_index"], r.labels)
    assert list(a["node_features"][:len(NODE_FEATURES)]) == list(NODE_FEATURES)


def test_colours_join_the_node_features():
    rng = np.random.default_rng(2)
    xyz = rng.random((3000, 3)) * (10, 10, 0.01)
    rgb = np.where(xyz[:, :1] > 5, [1.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    a = segment(PointCloud(xyz, colors=rgb), 10).learning_graph()
    names = list(a["node_features"])
    assert names[-3:] == ["red", "green", "blue"]
    red, blue = a["x"][:, names.index("red")], a["x"][:, names.index("blue")]
    assert np.allclose(red + blue, 1.0, atol=1e-5) and ((red > 0.99) | (red < 0.01)).all()
    assert 0 < (red > 0.5).sum() < 10  # superpoints of either colour, none mixed


def test_to_pyg_where_torch_geometric_is_installed():
    pytest.importorskip("torch_geometric", reason="torch_geometric is an optional extra "
                        "(pip install 'superfacets[pyg]')")
    ground, pole = _scene(3)
    r = segment(PointCloud(np.vstack([ground, pole])), 10)
    data = r.to_pyg()
    assert tuple(data.edge_index.shape) == (2, 2 * r.graph().n_edges)
    assert data.is_undirected() and data.num_nodes == 10


def test_the_planes_angle_of_an_edge_is_its_ridges_whatever_the_normals_orientation():
    """Two planes meeting at a ridge 40 degrees apart: the edge's ``normal_angle`` is 40
    degrees in radians both ways, whether the points' normals face one side or flip from
    point to point (the mean angle reads them; the planes' angle does not); a box's
    sides meet at right angles."""
    import trimesh

    from superfacets.elements.builders import elements_of
    from superfacets.graph.adjacency import superfacet_graph
    from superfacets.graph.learning import learning_arrays

    rng = np.random.default_rng(7)
    uv = rng.random((6000, 2)) * [8.0, 4.0] - [4.0, 0.0]
    slope = np.tan(np.radians(40.0))
    pts = np.c_[uv, np.where(uv[:, 0] > 0, uv[:, 0] * slope, 0.0)]
    n_b = np.array([-np.sin(np.radians(40.0)), 0.0, np.cos(np.radians(40.0))])
    normals = np.where((uv[:, :1] > 0), n_b, [0.0, 0.0, 1.0])
    flip = np.where(np.arange(6000)[:, None] % 2 == 0, -normals, normals)
    col = EDGE_FEATURES.index("normal_angle")
    angles = []
    for given in (normals, flip):
        src = elements_of(PointCloud(pts, normals=given), "points")
        lab = np.full(src.graph.n_elements, -1)
        lab[src.index] = (pts[:, 0] > 0).astype(np.int64)
        a = learning_arrays(superfacet_graph(src.graph, lab, None), src.graph.positions, lab,
                            lab[src.index])
        assert a["edge_attr"].shape == (2, len(EDGE_FEATURES))
        angles.append(a["edge_attr"][:, col])
    np.testing.assert_allclose(angles[0], np.radians(40.0), atol=1e-4)
    np.testing.assert_array_equal(angles[0], angles[1])
    box = trimesh.creation.box().subdivide()
    sides = np.unique(box.face_normals.round(6), axis=0, return_inverse=True)[1].ravel()
    g = elements_of(box, "faces").graph
    a = learning_arrays(superfacet_graph(g, sides, None), g.positions, sides, sides)
    assert a["edge_attr"].shape[0] == 24  # twelve edges of the box, both ways
    np.testing.assert_allclose(a["edge_attr"][:, col], np.pi / 2, atol=1e-6)
