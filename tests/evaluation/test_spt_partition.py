"""The Superpoint Transformer partition baseline: its problem (features, graph, voxels)
with known answers, and the plumbing around the solver with a stand-in solver (the real
one, pycut-pursuit, is GPL-3 and installed by hand: its test skips without it)."""

from __future__ import annotations

import colorsys

import numpy as np
import pytest
from conftest import components_solver

pytest.importorskip("pgeof", reason="the baselines extra (pgeof)")
pytest.importorskip("sklearn", reason="the baselines extra (scikit-learn)")

from superfacets import ParameterError  # noqa: E402
from superfacets.evaluation.baselines import spt_partition as spt  # noqa: E402
from superfacets.inputs.cloud import PointCloud  # noqa: E402


def _room(n=4000, seed=0):
    """A floor (z = 0, grey) and a wall (x = 0, red) meeting along an edge, on a 2 cm grid."""
    rng = np.random.default_rng(seed)
    g = np.arange(0.0, 1.0, 0.02)
    a, b = (x.ravel() for x in np.meshgrid(g, g))
    floor = np.c_[a + 0.02, b, np.zeros_like(a)]
    wall = np.c_[np.zeros_like(a), b, a + 0.02]
    pts = np.r_[floor, wall] + rng.normal(0, 1e-4, (2 * a.size, 3))
    colors = np.r_[np.full((a.size, 3), 0.5), np.tile([0.9, 0.1, 0.1], (a.size, 1))]
    return PointCloud(pts, colors=colors), a.size


def test_problem_features_graph_and_weights():
    cloud, half = _room()
    settings = spt.replace(spt.PRESETS["scannet"], voxel=0.0)
    p = spt.spt_problem(cloud, settings)
    n = 2 * half
    assert p.feature_names == spt.PRESETS["scannet"].features
    assert p.observations.shape == (n, 3 + 3 + 5) and p.observations.dtype == np.float32
    np.testing.assert_allclose(p.coor_weights, [0.1] * 3 + [1.0] * 8)
    np.testing.assert_allclose(p.observations[:, :3].mean(axis=0), 0.0, atol=1e-6)  # centred
    rgb, geo, elev = p.observations[:, 3:6], p.observations[:, 6:10], p.observations[:, 10]
    np.testing.assert_allclose(rgb[:half], 0.5, atol=1e-6)
    floor = slice(half // 4, half)  # away from the edge
    assert np.median(geo[floor, 1]) > 0.8 and np.median(geo[floor, 2]) < 0.05  # planar
    assert np.median(geo[floor, 3]) < 0.05  # a horizontal plane: not vertical
    assert np.median(geo[half + half // 4:, 3]) > 1.0  # a wall: vertical, doubled
    # elevation: the height above the floor (RANSAC's plane), divided by the ground scale
    z = cloud.points[:, 2]
    np.testing.assert_allclose(elev, z / 4.0, atol=1e-3)
    # the graph: each undirected edge once, lo < hi, weights 1 / (1 + d / mean d)
    lo = np.repeat(np.arange(n), np.diff(p.first_edge.astype(np.int64)))
    hi = p.adj_vertices.astype(np.int64)
    assert p.first_edge[-1] == hi.size and np.all(lo < hi)
    assert np.unique(lo * n + hi).size == hi.size
    assert np.all((p.edge_weights > 0) & (p.edge_weights < 1))
    # every voxel has an edge; each is one of its 10 nearest
    assert np.union1d(lo, hi).size == n
    assert hi.size >= 5 * n  # 10 nearest of each, shared pairs counted once


def test_voxels_average_and_map_back():
    rng = np.random.default_rng(2)
    centres = (np.unique(rng.integers(0, 40, (3000, 3)), axis=0) + 0.5) * 0.05
    pts = np.r_[centres, centres + rng.uniform(-0.01, 0.01, centres.shape)]
    colors = np.r_[np.zeros_like(centres), np.ones_like(centres)]
    p = spt.spt_problem(PointCloud(pts, colors=colors),
                        spt.replace(spt.PRESETS["scannet"], voxel=0.05))
    n = centres.shape[0]
    assert p.observations.shape[0] == n  # each pair in one voxel
    np.testing.assert_array_equal(p.voxel_of[:n], p.voxel_of[n:])
    np.testing.assert_allclose(p.observations[:, 3:6], 0.5, atol=1e-6)  # colours averaged
    # no colours: the colour features are left out
    p = spt.spt_problem(centres, "kitti360")
    assert "hsv" not in p.feature_names and p.feature_names[0] == "linearity"


def test_hsv_is_colorsys():
    rgb = np.random.default_rng(1).random((200, 3))
    rgb[:5] = [[0, 0, 0], [1, 1, 1], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0.2]]
    ref = np.array([colorsys.rgb_to_hsv(*c) for c in rgb])
    np.testing.assert_allclose(spt._hsv(rgb), ref, atol=1e-12)


def test_partition_plumbing_with_a_stand_in_solver(monkeypatch):
    from superfacets._runtime import extras

    real = extras.require
    monkeypatch.setattr(extras, "require", lambda m, f: components_solver()
                        if m == "pycut_pursuit.cp_d0_dist" else real(m, f))
    cloud, half = _room()
    rows = np.r_[cloud.points[:10], np.full((1, 3), np.nan), cloud.points[10:]]
    cloud = PointCloud(rows, colors=np.r_[cloud.colors[:11], cloud.colors[10:]],
                       allow_invalid=True)
    own = spt.spt_partition(cloud)  # the preset's level 1
    assert own.shape == (2 * half + 1,) and own[10] == -1
    n_first = int(own.max()) + 1
    for level in (1, 2, "auto"):
        labels = spt.spt_partition(cloud, max(2, n_first // 4), level=level)
        assert labels[10] == -1 and labels.min() == -1
        used = np.unique(labels[labels >= 0])
        np.testing.assert_array_equal(used, np.arange(used.size))  # dense
    # level 2 merges level-1 superpoints: each level-1 superpoint lies in one of level 2
    two = spt.spt_partition(cloud, max(2, n_first // 4), level=2)
    ok = own >= 0
    assert all(np.unique(two[ok][own[ok] == s]).size == 1 for s in range(n_first))
    with pytest.raises(ParameterError, match="unknown Superpoint Transformer preset"):
        spt.spt_partition(cloud, 10, preset="nope")
    with pytest.raises(ParameterError, match="unknown setting"):
        spt.spt_partition(cloud, 10, voxels=0.1)
    with pytest.raises(ParameterError, match="level"):
        spt.spt_partition(cloud, 10, level=3)


def test_partition_with_pycut_pursuit():
    try:
        import pycut_pursuit.cp_d0_dist  # noqa: F401
    except ImportError:
        pytest.skip("pycut-pursuit (GPL-3) is installed by hand (docs/guide/install.md)")
    cloud, half = _room()
    labels = spt.spt_partition(cloud, 20)
    k = int(labels.max()) + 1
    assert abs(k - 20) <= 4
    np.testing.assert_array_equal(labels, spt.spt_partition(cloud, 20))  # deterministic
    floor = np.arange(2 * half) < half
    a, b = np.bincount(labels, floor, k), np.bincount(labels, ~floor, k)
    assert np.minimum(a, b).sum() < 0.03 * 2 * half  # superpoints keep to floor or wall
    assert np.bincount(labels).min() >= 10  # the cut-off: no superpoint under 10 voxels


def test_a_voxelized_cloud_is_used_as_given():
    """Points a voxel apart already (a cloud voxelized at 3 cm, with its own grid) are not
    voxelized again at a shifted grid (41,568 points became 27,571)."""
    g = np.arange(0, 1.5, 0.03)
    rng = np.random.default_rng(1)
    pts = np.stack(np.meshgrid(g, g, [0.0]), axis=-1).reshape(-1, 3) + 0.029  # its own grid
    pts[:, :2] += rng.uniform(-0.002, 0.002, (pts.shape[0], 2))  # (means, not centres)
    keys = np.floor(pts / 0.03)
    assert np.unique(keys, axis=0).shape[0] < pts.shape[0]  # voxelized again: merged
    xyz, _, voxel_of = spt._voxels(pts, None, 0.03)
    assert xyz.shape[0] == pts.shape[0] and np.array_equal(voxel_of, np.arange(len(pts)))
    dense = np.r_[pts, pts + 0.004]  # two points a voxel: averaged
    assert spt._voxels(dense, None, 0.03)[0].shape[0] < dense.shape[0]


def test_the_ground_fit_stands_a_low_outlier():
    """A sweep whose lowest point is an outlier 8.6 m under the ground: RANSAC raised a
    ValueError (nothing within the threshold of that point); the ground is found."""
    rng = np.random.default_rng(0)
    ground = np.c_[rng.random((3000, 2)) * 20, rng.normal(0, 0.01, 3000)]
    wall = np.c_[rng.random((500, 1)) * 20, np.zeros((500, 1)), rng.random((500, 1)) * 3]
    xyz = np.r_[ground, wall, [[5.0, 5.0, -8.6]]]
    h = spt._elevation(xyz, threshold=0.5, scale=1.0)
    assert abs(np.median(h[:3000])) < 0.02 and h[-1] < -8


def test_the_missing_solver_names_a_command_that_works(monkeypatch):
    from superfacets._runtime import extras
    from superfacets.errors import MissingExtraError

    real = extras.require

    def require(module, feature):
        if module == "pycut_pursuit.cp_d0_dist":
            raise MissingExtraError(f"{feature} needs pycut-pursuit; pip install it")
        return real(module, feature)

    monkeypatch.setattr(extras, "require", require)
    cloud, _ = _room()
    with pytest.raises(MissingExtraError, match=r"pycut-pursuit==0\.1\.3.*install\.md"):
        spt.spt_partition(cloud)
