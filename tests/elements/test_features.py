"""The feature (colour) term: bit for bit off, known answers on synthetic inputs, colours read."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import SHARED, grid_mesh, minority, need

from superfacets import segment
from superfacets.elements import face_graph
from superfacets.errors import ParameterError
from superfacets.inputs.cloud import InvalidCloudError, PointCloud
from superfacets.io import read_cloud
from superfacets.method.weights import paper_weights


def _halves(n=20000, cut=0.37, seed=0):
    rng = np.random.default_rng(seed)
    xy = rng.random((n, 2))
    left = xy[:, 0] <= cut
    col = np.where(left[:, None], [0.1, 0.1, 0.9], [0.9, 0.1, 0.1])
    return np.c_[xy, np.zeros(n)], col, left


def test_beta_zero_is_the_paper_bit_for_bit():
    mesh = grid_mesh(20, 20, height=lambda x, y: 0.3 * np.abs(x))
    g = face_graph(mesh)
    f = np.random.default_rng(1).random((mesh.n_faces, 3))
    np.testing.assert_array_equal(paper_weights(g), paper_weights(g, features=f, beta=0.0))
    a = segment(mesh, 10, paper=True)
    b = segment(mesh, 10, paper=True, beta=0, features=f)
    np.testing.assert_array_equal(a.labels, b.labels)
    # beta > 0: each weight grows by beta * span * |f_i - f_j| / d exactly
    w = paper_weights(g, features=f, beta=5.0)
    jump = np.linalg.norm(f[g.pairs[:, 0]] - f[g.pairs[:, 1]], axis=1)
    np.testing.assert_allclose(w - paper_weights(g), 5.0 * g.span * jump / g.diagonal,
                               rtol=1e-12, atol=1e-15)


def test_colour_edge_on_a_flat_cloud_becomes_a_border():
    # a flat square, two colours split at x = 0.37: geometry says nothing, colour all
    pts, col, left = _halves()
    cloud = PointCloud(pts, colors=col)
    blind = segment(cloud, 20, beta=0)
    seeing = segment(cloud, 20, beta=200)
    assert minority(blind.labels, left) > 200  # the paper's weights cut across it
    assert minority(seeing.labels, left) == 0  # every superpoint one colour
    auto = segment(cloud, 20)  # the default reads the colours: the term's weight from them
    assert minority(auto.labels, left) == 0 and auto.params["beta"] > 0
    assert auto.params["feature_floor"] == 0  # (no noise: most neighbours the same colour)
    assert seeing.params["beta"] == 200
    # features given explicitly are the same as the cloud's colours
    same = segment(PointCloud(pts), 20, beta=200, features=col)
    np.testing.assert_array_equal(same.labels, seeing.labels)


def test_colour_edge_on_faces_with_the_default_clean_up():
    mesh = grid_mesh(60, 60)
    x = mesh.centroids[:, 0]
    left = x <= 0.37 * (x.max() - x.min()) + x.min()
    col = np.where(left[:, None], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    blind = segment(mesh, 16)  # no colours: no colour term
    assert blind.params["beta"] == 0
    seeing = segment(mesh, 16, beta=400, features=col)
    assert seeing.params["cleanup"] and seeing.params["split_merge"]
    assert minority(seeing.labels, left) < 0.2 * minority(blind.labels, left)


def test_feature_errors():
    mesh = grid_mesh(8, 8)
    with pytest.raises(ParameterError, match="beta > 0 needs features"):
        segment(mesh, 4, beta=1)
    with pytest.raises(ParameterError, match="one row per input row"):
        segment(mesh, 4, beta=1, features=np.zeros((3, 3)))
    bad = np.zeros((mesh.n_faces, 3))
    bad[5, 1] = np.nan
    with pytest.raises(ParameterError, match="face 5 are not finite"):
        segment(mesh, 4, beta=1, features=bad)
    with pytest.raises(ParameterError, match="beta"):
        segment(mesh, 4, beta=-1, features=bad)
    with pytest.raises(ParameterError, match="weighting='paper' only"):
        segment(mesh, 4, beta=1, weighting="shlafman", alpha=0.5, features=np.zeros((128, 1)))
    with pytest.raises(ParameterError, match="does not go with beta"):
        segment(mesh, 4, beta=1, paper=True)
    colors = np.full((10, 3), 0.5)
    colors[2, 1] = 300.0  # 8-bit, not scaled
    with pytest.raises(InvalidCloudError, match=r"colour 2 is not in \[0, 1\]"):
        PointCloud(np.random.default_rng(0).random((10, 3)), colors=colors)


def test_colours_are_read_from_ply_las_and_pcd(tmp_path):
    from plyfile import PlyData, PlyElement

    pts, col, _ = _halves(500)
    v = np.zeros(500, dtype=[("x", "f8"), ("y", "f8"), ("z", "f8"), ("red", "u1"),
                             ("green", "u1"), ("blue", "u1")])
    v["x"], v["y"], v["z"] = pts.T
    rgb = np.round(col * 255).astype(np.uint8)
    v["red"], v["green"], v["blue"] = rgb.T
    PlyData([PlyElement.describe(v, "vertex")]).write(str(tmp_path / "c.ply"))
    c = read_cloud(tmp_path / "c.ply")
    np.testing.assert_allclose(c.colors, rgb / 255.0)
    laspy = pytest.importorskip("laspy")
    las = laspy.create(point_format=2, file_version="1.2")
    las.header.scales = [0.001] * 3
    las.x, las.y, las.z = (pts * 100).T
    las.red, las.green, las.blue = (rgb.astype(np.uint16) * 257).T  # 16-bit colour
    las.write(tmp_path / "c.las")
    np.testing.assert_allclose(read_cloud(tmp_path / "c.las").colors, rgb / 255.0)


def test_real_rgbd_scan_has_colours_and_the_term_runs():
    path = need(SHARED / "data" / "clouds" / "table_scene_mug_stereo_textured.pcd")
    pytest.importorskip("pypcd4")
    c = read_cloud(path)
    assert c.colors is not None and c.colors.shape == (c.n_total, 3)
    ok = c.colors[c.valid]
    assert 0 <= ok.min() and ok.max() <= 1 and ok.std() > 0.05  # a real, textured scene
    # (the colour term alone: the plain graph, step_weight 1, in the three runs)
    r = segment(c, 60, beta=2000, step_weight=1)
    assert (r.labels[~c.valid] == -1).all() and (r.labels[c.valid] >= 0).all()
    # the superpoints are more uniform in colour than without the term, the default's too
    blind, auto = segment(c, 60, beta=0, step_weight=1), segment(c, 60, step_weight=1)

    def spread(labels):
        lab = labels[c.valid]
        k = int(lab.max()) + 1
        mean = np.stack([np.bincount(lab, ok[:, i], k) / np.bincount(lab, minlength=k)
                         for i in range(3)], 1)
        return float(np.mean(np.linalg.norm(ok - mean[lab], axis=1)))

    assert spread(r.labels) < 0.97 * spread(blind.labels)
    # a projected stereo texture: the colours' own noise, the floor, is large, and the
    # default's term weak (no less uniform than without it)
    assert auto.params["feature_floor"] > 0.1 and 0 < auto.params["beta"] < 200
    assert spread(auto.labels) <= 1.001 * spread(blind.labels)
