"""Content-sensitive sizes (``density``, ``roughness``): superpoints follow the points."""

import numpy as np
import pytest

from superfacets import segment
from superfacets.elements.density import (
    AUTO_DENSITY,
    AUTO_SPREAD,
    adapted_graph,
    content_scale,
    density_for,
    roughness_of,
    size_spread,
    window_factors,
)
from superfacets.elements.points import point_graph
from superfacets.errors import ParameterError
from superfacets.inputs.cloud import PointCloud


def two_density_plane(seed=0):
    """A unit square in z = 0: 6,000 points on its left half, 750 on its right."""
    rng = np.random.default_rng(seed)
    left = rng.random((6000, 2)) * [0.5, 1.0]
    right = rng.random((750, 2)) * [0.5, 1.0] + [0.5, 0.0]
    xy = np.r_[left, right]
    return np.c_[xy, np.zeros(len(xy))]


def bumpy_plane(seed=0):
    """A square of 8,000 uniform points, flat for x < 0.5, rippled for x > 0.5."""
    rng = np.random.default_rng(seed)
    xy = rng.random((8000, 2))
    z = np.where(xy[:, 0] > 0.5, 0.03 * np.sin(40 * xy[:, 0]) * np.sin(40 * xy[:, 1]), 0.0)
    return np.c_[xy, z]


def test_scale_is_one_without_options_and_equalises_sizes_with_density_one():
    g = point_graph(PointCloud(two_density_plane())).graph
    assert np.array_equal(content_scale(g), np.ones(g.n_elements))
    a = adapted_graph(g, 1.0, 0.0)
    # q = 1: every element the median size (equal point counts), up to rounding
    np.testing.assert_allclose(a.sizes, np.median(g.sizes), rtol=1e-12)
    np.testing.assert_allclose(a.scale2, np.median(g.sizes) / g.sizes, rtol=1e-12)
    half = adapted_graph(g, 0.5, 0.0)
    np.testing.assert_allclose(half.sizes, np.sqrt(g.sizes * np.median(g.sizes)), rtol=1e-12)
    assert g.scale2 is None and a.positions is g.positions  # the cached graph is untouched


def test_roughness_is_zero_on_a_plane_and_the_crease_angle_on_a_box():
    import trimesh

    from superfacets.elements.builders import as_element_graph

    flat = point_graph(PointCloud(two_density_plane())).graph
    assert np.abs(roughness_of(flat)).max() < 1e-6
    box = trimesh.creation.box()
    rho = roughness_of(as_element_graph((box.vertices, box.faces)), rounds=0)
    # each triangle: one coplanar neighbour, two across a right angle
    np.testing.assert_allclose(rho, np.pi / 3)


def test_weighted_farthest_points_blocked_equal_plain():
    from oracle.farthest import farthest_point, farthest_point_blocked, spatial_blocks

    rng = np.random.default_rng(3)
    c = rng.random((3000, 3))
    scale2 = rng.random(3000) * 4 + 0.1
    plain = np.empty(200, np.int64)
    farthest_point(c, 200, 0, plain, scale2)
    order, bstart, bcenter, bradius = spatial_blocks(c, 8)
    s2 = np.ascontiguousarray(scale2[order])
    blocked = np.empty(200, np.int64)
    farthest_point_blocked(c, 200, 0, blocked, order, bstart, bcenter, bradius, s2,
                           np.maximum.reduceat(s2, bstart[:-1]))
    assert np.array_equal(plain, blocked)
    unweighted = np.empty(200, np.int64)
    farthest_point(c, 200, 0, unweighted)
    assert not np.array_equal(plain, unweighted)
    # the weighted samples crowd where the scale is large
    assert scale2[plain].mean() > scale2.mean() * 1.2


def superpoints_on_left(labels, pts, k):
    centroid_x = np.bincount(labels, weights=pts[:, 0]) / np.bincount(labels)
    return int((centroid_x < 0.5).sum())


def test_density_puts_the_superpoints_where_the_points_are():
    pts = two_density_plane()
    area = segment(PointCloud(pts), 40, density=0, merge_from=1)  # no flat merges
    count = segment(PointCloud(pts), 40, density=1.0, merge_from=1)  # the density term alone
    assert area.n_segments == 40 and count.n_segments == 40
    assert count.params["density"] == 1.0 and count.params["assignment"] == "exact"
    # equal areas: about half on each half; equal point counts: about 8 in 9 on the left
    assert 15 <= superpoints_on_left(area.labels, pts, 40) <= 25
    assert superpoints_on_left(count.labels, pts, 40) >= 30
    sizes = np.bincount(count.labels)
    assert sizes.max() < 3 * np.median(sizes)  # about equal point counts


def test_automatic_density_follows_uneven_clouds_only():
    # the default (density=None) sizes superpoints by density where a cloud's density
    # is uneven (the plane's halves differ 8-fold), not on an even cloud, a mesh or
    # the paper's method; the value used is in the result's parameters
    import trimesh

    pts = two_density_plane()
    auto = segment(PointCloud(pts), 40)
    assert auto.params["density"] == AUTO_DENSITY == 0.5
    np.testing.assert_array_equal(auto.labels,
                                  segment(PointCloud(pts), 40, density=0.5).labels)
    assert superpoints_on_left(auto.labels, pts, 40) >= 28
    assert segment(PointCloud(pts), 40, paper=True).params["density"] == 0.0
    g = point_graph(PointCloud(pts), 10).graph
    assert size_spread(g) > AUTO_SPREAD and density_for(g) == 0.5 and density_for(g, True) == 0
    even = bumpy_plane()
    assert size_spread(point_graph(PointCloud(even), 10).graph) < 0.5
    assert segment(PointCloud(even), 40).params["density"] == 0.0
    sphere = trimesh.creation.icosphere(3)
    big = sphere.vertices[:, 2] > 0.5  # faces of very different sizes: still equal areas
    mesh = trimesh.Trimesh(sphere.vertices, sphere.faces).subdivide(
        np.flatnonzero(big[sphere.faces].all(axis=1)))
    assert segment((mesh.vertices, mesh.faces), 20).params["density"] == 0.0


def test_bounded_windows_follow_the_scale():
    """With the paper's windows each center's window is scaled by its superpoint's
    extent, so the count asked comes back, placed by density (with one window for
    all, points no window reached seeded 17 superpoints beyond it: 57 for 40)."""
    pts = two_density_plane()
    r = segment(PointCloud(pts), 40, density=1.0, assignment="bounded")
    assert r.params["assignment"] == "bounded" and r.n_segments == 40
    assert superpoints_on_left(r.labels, pts, 40) >= 30


def test_window_factors_are_the_smoothed_inverse_squared_scale():
    g = point_graph(PointCloud(two_density_plane()), 8).graph
    assert window_factors(g).shape == (0,)
    a = adapted_graph(g, 1.0, 0.0)
    assert np.allclose(window_factors(a, rounds=0), 1.0 / a.scale2)
    w = window_factors(a)
    left = g.positions[:, 0] < 0.45
    right = g.positions[:, 0] > 0.55
    # equal point counts: the sparse half's superpoints span sqrt(8) times as far
    assert 5 < np.median(w[right]) / np.median(w[left]) < 11
    assert w[left].std() < (1.0 / a.scale2[left]).std()  # smoothed


def test_roughness_puts_more_superpoints_on_the_rough_half():
    pts = bumpy_plane()
    plain = segment(PointCloud(pts), 40, merge_from=1)  # equal areas: no flat merges
    rough = segment(PointCloud(pts), 40, roughness=3.0, merge_from=1)
    assert rough.n_segments == 40
    assert superpoints_on_left(plain.labels, pts, 40) >= 15
    assert superpoints_on_left(rough.labels, pts, 40) <= 12  # the flat half gets fewer


@pytest.mark.parametrize("options, message", [
    (dict(density=1.5), "density must be a finite number in"),
    (dict(density=-0.1), "density must be"),
    (dict(roughness=-1.0), "roughness must be"),
    (dict(density=0.5, paper=True), "does not go with density"),
    (dict(roughness=1.0, paper=True), "does not go with roughness"),
])
def test_bad_content_settings_are_refused(options, message):
    with pytest.raises(ParameterError, match=message):
        segment(PointCloud(bumpy_plane()), 20, **options)


def test_cli_density_and_roughness(tmp_path, capsys):
    from superfacets.cli import main
    from superfacets.io import read_labels

    np.save(tmp_path / "plane.npy", two_density_plane())
    out = tmp_path / "plane.seg"
    assert main(["segment", str(tmp_path / "plane.npy"), "-k", "40", "--density", "1",
                 "--roughness", "0.5", "-o", str(out)]) == 0
    labels = read_labels(out)
    expected = segment(PointCloud(two_density_plane()), 40, density=1.0, roughness=0.5).labels
    assert np.array_equal(labels, expected)
    assert main(["segment", str(tmp_path / "plane.npy"), "-k", "40", "--density", "2",
                 "-o", str(tmp_path / "bad.seg")]) == 2
    assert "density must be" in capsys.readouterr().err
    assert main(["segment", str(tmp_path / "plane.npy"), "-k", "20", "--density", "0.5",
                 "--tiles", "2", "-o", str(tmp_path / "t.seg")]) == 2
    assert "density: not available in a tiled run" in capsys.readouterr().err
    assert not (tmp_path / "bad.seg").exists() and not (tmp_path / "t.seg").exists()
    # auto (the default) and 0 as asked; a tiled run takes the default (tiles: 0)
    for flag, q in ((["--density", "auto"], 0.5), ([], 0.5), (["--density", "0"], 0.0)):
        out = tmp_path / f"auto{len(flag)}{q}.seg"
        assert main(["segment", str(tmp_path / "plane.npy"), "-k", "40", *flag,
                     "-o", str(out)]) == 0
        expected = segment(PointCloud(two_density_plane()), 40, density=q).labels
        assert np.array_equal(read_labels(out), expected)
        said = capsys.readouterr().out  # the summary says when the automatic density acted
        assert ("40 superpoints sized by the points' uneven density (auto; --density 0: "
                "equal areas)" in said) == (flag != ["--density", "0"])
    assert main(["segment", str(tmp_path / "plane.npy"), "-k", "20", "--tiles", "2",
                 "-o", str(tmp_path / "t.seg")]) == 0
    with pytest.raises(SystemExit) as stop:  # argparse: usage and one line, exit 2
        main(["segment", str(tmp_path / "plane.npy"), "-k", "20", "--density", "high",
              "-o", str(tmp_path / "bad.seg")])
    assert stop.value.code == 2
    assert "expected a number, got 'high'" in capsys.readouterr().err


def test_neighbour_means_come_from_the_csr_layout_as_from_the_pairs():
    """Known answer: the windows' neighbour averaging reads the CSR layout (a point graph
    then never builds its pairs) and gives np.bincount's sums over the pairs bit for
    bit, on values spread over six orders of magnitude."""
    from superfacets.elements.density import _neighbour_mean
    from superfacets.elements.points import point_graph
    from superfacets.inputs.cloud import PointCloud

    rng = np.random.default_rng(7)
    g = point_graph(PointCloud(rng.random((5000, 3)) ** 3)).graph
    v = rng.random(g.n_elements) * 10 ** rng.uniform(-3, 3, g.n_elements)
    got = _neighbour_mean(g, v)
    assert "pairs" not in g.__dict__
    lo, hi, n = g.pairs[:, 0], g.pairs[:, 1], g.n_elements
    want = (v + np.bincount(lo, weights=v[hi], minlength=n)
            + np.bincount(hi, weights=v[lo], minlength=n)) / (
        1.0 + np.bincount(g.pairs.ravel(), minlength=n))
    np.testing.assert_array_equal(got, want)
