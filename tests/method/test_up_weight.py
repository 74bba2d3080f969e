"""``up_weight``: a point cloud's up coordinate weighed more in the method's distances (not
in the paper): the labels of the stretched cloud, graphs in the data's units, clear
refusals."""

from __future__ import annotations

import numpy as np
import pytest

from superfacets import ParameterError, PointCloud, segment
from superfacets.elements.builders import elements_of
from superfacets.graph.adjacency import superfacet_graph
from superfacets.inputs.cloud import surface_up_weight, up_weighted


def _canopy(seed: int = 0):
    """Flat ground 20 m square and a flat layer 0.6 m above its middle (a canopy, a roof):
    points about 0.3 m apart, so that the point graph joins the two layers."""
    rng = np.random.default_rng(seed)
    ground = np.c_[rng.random((4000, 2)) * 20, 0.01 * rng.standard_normal(4000)]
    layer = np.c_[rng.random((1000, 2)) * 10 + 5, 0.6 + 0.01 * rng.standard_normal(1000)]
    classes = np.r_[np.zeros(4000, dtype=int), np.ones(1000, dtype=int)]
    return np.vstack([ground, layer]), classes


def _mixed(labels, classes) -> int:
    return sum(len(set(classes[labels == s])) > 1 for s in np.unique(labels))


def test_layers_stacked_in_height_are_kept_apart():
    """Without the weight (and no step weight), superpoints hold ground and the layer above
    it alike (10, 15 and 24 of 10, 20 and 40); a scene's step weight alone mixes fewer (4,
    2, 3); weighing the up coordinate twice, none; the default reads a weight off the
    level surfaces (7.9 here) and mixes none either."""
    pts, classes = _canopy()
    cloud = PointCloud(pts, up=np.array([0.0, 0.0, 1.0]))
    for k in (10, 20, 40):
        assert _mixed(segment(cloud, k, step_weight=1, up_weight=1).labels, classes) >= \
            k // 2, k
        assert 0 < _mixed(segment(cloud, k, up_weight=1).labels, classes) <= max(4, k // 8), k
        r = segment(cloud, k, up_weight=2)
        assert _mixed(r.labels, classes) == 0 and r.n_segments == k, k
        assert r.params["up_weight"] == 2.0
        auto = segment(cloud, k)
        assert _mixed(auto.labels, classes) == 0 and auto.n_segments == k, k
        assert auto.params["up_weight"] == surface_up_weight(pts, (0, 0, 1)) > 7.5


def _box_room(n: int = 6000, seed: int = 0):
    """A room's surfaces: floor, ceiling and four walls of a 6 x 4 x 3 m box, sampled
    evenly by area (walls hold 60 of its 108 square metres)."""
    rng = np.random.default_rng(seed)
    faces = [((0, 0, 0), (6, 0, 0), (0, 4, 0)), ((0, 0, 3), (6, 0, 0), (0, 4, 0)),
             ((0, 0, 0), (6, 0, 0), (0, 0, 3)), ((0, 4, 0), (6, 0, 0), (0, 0, 3)),
             ((0, 0, 0), (0, 4, 0), (0, 0, 3)), ((6, 0, 0), (0, 4, 0), (0, 0, 3))]
    area = np.array([np.linalg.norm(np.cross(a, b)) for _, a, b in faces])
    counts = np.floor(n * area / area.sum()).astype(int)
    return np.vstack([np.asarray(o) + rng.random((c, 1)) * a + rng.random((c, 1)) * b
                      for (o, a, b), c in zip(faces, counts, strict=True)])


def test_the_weight_read_off_the_surfaces():
    """(2 m)^3 where m > 1/2, else 1, m the mean |n . up| of the planar neighbourhoods:
    level ground 8, a plane sloping at 60 degrees (m = 1/2 + 1/2 of it level: 0.75) about
    3.4, the same surface standing up 1, a sphere's surface (every way alike: m = 1/2) 1, a
    box room (walls 60 of 108 square metres: m about 0.44) 1; rows not finite are
    skipped, small or degenerate inputs read 1; objects and the paper keep 1."""
    rng = np.random.default_rng(1)
    ground = np.c_[rng.random((3000, 2)) * 50, 0.02 * rng.standard_normal(3000)]
    assert surface_up_weight(ground, (0, 0, 1)) == 8.0
    assert surface_up_weight(ground, (0, 0, -5)) == 8.0  # (the up's length and sign)
    assert surface_up_weight(ground[:, [2, 0, 1]], (0, 0, 1)) == 1.0
    c, s = np.cos(np.pi / 3), np.sin(np.pi / 3)  # (its normal 60 degrees off up: |n.up| 1/2)
    slope = ground @ np.array([[1, 0, 0], [0, c, s], [0, -s, c]])
    half = np.vstack([ground, slope + [0, 0, 100]])  # (half level, half sloping: m = 3/4)
    assert abs(surface_up_weight(half, (0, 0, 1)) - 1.5 ** 3) < 0.1
    sphere = rng.standard_normal((8000, 3))
    sphere /= np.linalg.norm(sphere, axis=1, keepdims=True)
    assert surface_up_weight(sphere, (0, 0, 1)) <= 1.05
    room = _box_room()
    assert surface_up_weight(room, (0, 0, 1)) == 1.0
    with_holes = np.vstack([ground, np.full((5, 3), np.nan)])
    assert surface_up_weight(with_holes, (0, 0, 1)) == 8.0
    assert surface_up_weight(ground[:5], (0, 0, 1)) == 1.0
    assert surface_up_weight(np.zeros((50, 3)), (0, 0, 1)) == 1.0  # (no plane at all)
    with pytest.raises(ValueError, match="finite non-zero"):
        surface_up_weight(ground, (0, 0, 0))
    assert segment(PointCloud(ground), 10).params["up_weight"] == 1.0  # (no up)
    assert segment(PointCloud(room, up=np.array([0.0, 0.0, 1.0])), 10).params[
        "up_weight"] == 1.0
    paper = segment(PointCloud(ground, up=np.array([0.0, 0.0, 1.0])), 10, paper=True)
    assert paper.params["up_weight"] == 1.0
    # on any number of threads the same (the queries and the compiled kernels split rows)
    from superfacets._runtime.threads import using

    weights = []
    for n in (1, 2, 3):
        with using(n):
            weights.append(surface_up_weight(half, (0, 0, 1)))
    assert len(set(weights)) == 1 and abs(weights[0] - 1.5 ** 3) < 0.1


@pytest.mark.parametrize("up", [(0.0, 0.0, 1.0), (0.0, 0.6, 0.8)])
def test_the_labels_are_those_of_the_cloud_stretched_along_its_up(up):
    pts, _ = _canopy(1)
    u = np.asarray(up)
    pts = pts @ np.linalg.qr(np.c_[u, np.eye(3)[:, :2]])[0].T if up[1] else pts
    cloud = PointCloud(pts, up=u)
    stretched = PointCloud(pts + (3.0 - 1.0) * (pts @ u)[:, None] * u, up=u)
    np.testing.assert_allclose(up_weighted(cloud, 3.0).points, stretched.points, atol=1e-12)
    np.testing.assert_array_equal(segment(cloud, 25, up_weight=3).labels,
                                  segment(up_weighted(cloud, 3.0), 25, up_weight=1).labels)


def test_graphs_are_in_the_data_s_units():
    """The run's graph is of the weighed cloud; the result's graphs are of the cloud as
    given: centroids and areas equal to those of its own point graph (a scene's: with its
    neighbours along the surface, as the run's)."""
    pts, _ = _canopy(2)
    cloud = PointCloud(pts, up=np.array([0.0, 0.0, 1.0]))
    r = segment(cloud, 20, up_weight=4)
    e = elements_of(cloud, "points", step_weight=r.params["step_weight"])
    want = superfacet_graph(e.graph, r.labels[e.first_rows(np.arange(e.graph.n_elements))],
                            None)
    g = r.graph()
    np.testing.assert_allclose(g.centroid, want.centroid)
    np.testing.assert_allclose(g.area, want.area)
    assert g.centroid[:, 2].max() < 0.7  # (the weighed cloud's layer stands at 2.4)
    np.testing.assert_allclose(r.learning_graph()["pos"], want.centroid)
    assert r.hierarchy([5], cost="planarity").levels == (5,)
    # pickled, the result leaves the cloud as given behind: its graphs unstretch the run's
    import pickle

    again = pickle.loads(pickle.dumps(r)).graph()
    np.testing.assert_allclose(again.centroid, want.centroid, atol=1e-12)
    np.testing.assert_allclose(again.area, want.area, rtol=1e-12)
    # the content-adaptive level is made from a start run of the same weighed cloud, whose
    # graph was asked first: the level's graph is of the level's 20, not the start's 200
    a = segment(cloud, 20, up_weight=4, adaptive=True)
    assert a.n_segments == 20 == a.graph().n_segments


def test_a_tiled_run_reads_the_cloud_weighed_as_one_run_does():
    """Every position a tiled run reads is stretched (its survey, boxes and tiles, which run
    unweighted): the layers stay apart, and the borders agree."""
    from superfacets.scale.tiles.run import segment_tiled

    pts, classes = _canopy(4)
    cloud = PointCloud(pts, up=np.array([0.0, 0.0, 1.0]))
    plain = segment_tiled(cloud, 30, tiles=4, workers=1, step_weight=1, up_weight=1)
    r = segment_tiled(cloud, 30, tiles=4, workers=1, up_weight=2)
    assert _mixed(plain.labels, classes) >= 10 and _mixed(r.labels, classes) == 0
    assert r.n_segments == 30 and r.disagreements == 0 and r.params["up_weight"] == 2.0
    # the default: the weight one run reads off the points, read off the survey's sample
    auto = segment_tiled(cloud, 30, tiles=4, workers=1)
    assert auto.params["up_weight"] == segment(cloud, 30).params["up_weight"] > 1.9
    assert _mixed(auto.labels, classes) == 0 and auto.n_segments == 30
    # a graph asked for with a neighbour radius is built of the cloud unweighed: none read
    fixed = segment_tiled(cloud, 30, tiles=4, workers=1, graph=True, neighbor_radius=0.05)
    assert fixed.params["up_weight"] == 1.0 and fixed.learning is not None


def test_what_cannot_be_weighed_is_refused_in_words(tmp_path, capsys):
    import trimesh

    from superfacets.cli import main
    from superfacets.scale.tiles.run import segment_tiled

    pts, _ = _canopy(3)
    with pytest.raises(ParameterError, match="this cloud has no up"):
        segment(PointCloud(pts), 10, up_weight=2)
    with pytest.raises(ParameterError, match="this input's elements are faces"):
        segment(trimesh.creation.icosphere(), 10, up_weight=2)
    said = r"up_weight must be a finite number in \(0, 100\]"
    for bad in (0, -1, 101, float("nan")):
        with pytest.raises(ParameterError, match=said):
            segment(PointCloud(pts, up=np.array([0.0, 0.0, 1.0])), 10, up_weight=bad)
    with pytest.raises(ParameterError, match="not go with up_weight"):
        segment(PointCloud(pts, up=np.array([0.0, 0.0, 1.0])), 10, up_weight=2, paper=True)
    with pytest.raises(ParameterError, match="this cloud has no up"):
        segment_tiled(PointCloud(pts), 10, tiles=2, workers=1, up_weight=2)
    with pytest.raises(ParameterError, match="this input's elements are faces"):
        segment_tiled(trimesh.creation.icosphere(3), 10, tiles=2, workers=1, up_weight=2)
    np.save(tmp_path / "c.npy", pts)
    out = tmp_path / "c.seg"
    assert main(["segment", str(tmp_path / "c.npy"), "-k", "10", "--up-weight", "2",
                 "-o", str(out)]) == 2 and not out.exists()
    assert main(["segment", str(tmp_path / "c.npy"), "-k", "10", "--up-weight", "2",
                 "--seen-from", "z", "-o", str(out)]) == 0
    assert len(np.unique(np.loadtxt(out))) == 10
    assert "heights weighed 2 times (--up-weight 1: off)" in capsys.readouterr().out


def test_a_tiled_runs_graph_and_levels_are_of_the_cloud_as_given():
    """With up_weight a tiled run's superpoint graph (learning layout) and levels are those
    one run's result makes of the same labels on the cloud as given (its own point graph,
    as :meth:`SegmentationResult.graph` builds it), not of the weighed cloud: the features
    to float32's rounding (the tiles read the points stretched and stretch them back), the
    edges the same, and the levels' parents the same where the normals are the file's (with
    estimated ones each tile orients its own, and the levels' crease factor reads their
    angles: parents differed in 10 of 16 runs of eight such clouds)."""
    from superfacets.graph.hierarchy import hierarchy
    from superfacets.graph.learning import learning_arrays
    from superfacets.scale.tiles.run import segment_tiled

    pts, _ = _canopy(5)
    cloud = PointCloud(pts, up=np.array([0.0, 0.0, 1.0]))
    r = segment_tiled(cloud, 30, tiles=3, workers=1, up_weight=3, graph=True, levels=[10, 4])
    step = r.params["step_weight"]
    e = elements_of(cloud, "points", step_weight=step)
    per = r.labels[e.first_rows(np.arange(e.graph.n_elements))]
    sg = superfacet_graph(e.graph, per, None)
    want = learning_arrays(sg, e.graph.positions, per, r.labels)
    got = r.learning
    for key in ("edge_index", "super_index"):
        np.testing.assert_array_equal(got[key], want[key], err_msg=key)
    np.testing.assert_allclose(got["x"], want["x"], rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(got["pos"], want["pos"], atol=1e-9)
    assert got["pos"][:, 2].max() < 0.7  # (the weighed cloud's layer stands at 1.8)
    given = PointCloud(pts, normals=np.tile([0.0, 0.0, 1.0], (pts.shape[0], 1)),
                       up=np.array([0.0, 0.0, 1.0]))
    r = segment_tiled(given, 30, tiles=3, workers=1, up_weight=3, levels=[10, 4])
    e = elements_of(given, "points", step_weight=step)
    per = r.labels[e.first_rows(np.arange(e.graph.n_elements))]
    tree = hierarchy(superfacet_graph(e.graph, per, None), [10, 4])
    for a, b in zip(r.hierarchy.parents, tree.parents):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ParameterError, match="not with neighbor_radius"):
        segment_tiled(cloud, 30, tiles=3, workers=1, up_weight=3, graph=True,
                      neighbor_radius=0.05)


def test_the_summary_says_widths_in_the_data_s_units(tmp_path, capsys):
    """A street (ground and two facades as tall as it is wide) with its heights weighed
    twice: the summary's median width is the cloud's as given (within 5 % of its
    superpoint graph's, in the data's units), not the stretched cloud's (the facades'
    superpoints twice as large there); level areas keep their size, walls' halve."""
    from superfacets.cli import main
    from superfacets.inputs.cloud import unweighed_area_factor

    rng = np.random.default_rng(6)
    ground = np.c_[rng.random((6000, 2)) * [40, 20], np.zeros(6000)]
    walls = [np.c_[rng.random(6000) * 40, np.full(6000, y), rng.random(6000) * 20]
             for y in (0.0, 20.0)]
    pts = np.vstack([ground, *walls]) + 0.005 * rng.standard_normal((18000, 3))
    np.save(tmp_path / "street.npy", pts)
    assert main(["segment", str(tmp_path / "street.npy"), "-k", "60", "--seen-from", "z",
                 "--up-weight", "2", "-o", str(tmp_path / "s.seg")]) == 0
    said = capsys.readouterr().out
    wide = float(said.split("about ")[1].split(" wide")[0])
    r = segment(PointCloud(pts, up=np.array([0.0, 0.0, 1.0])), 60, up_weight=2)
    want = 2 * np.sqrt(np.median(r.graph().area) / np.pi)
    assert abs(wide / want - 1) < 0.05, (wide, want)
    np.testing.assert_allclose(unweighed_area_factor(
        np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, 1.0, 0.0]]), (0, 0, 2), 2.0),
        [1.0, np.sqrt(0.64 + 0.36 / 4), 0.5])


def test_runs_of_one_cloud_share_its_weighed_copy():
    """The weight read off a scene and its weighed copy (with its point graph) are kept with
    the cloud: a second count reads neither again, as an unweighed cloud's graph is kept;
    a pickled cloud leaves them behind."""
    import pickle

    pts, _ = _canopy(7)
    cloud = PointCloud(pts, up=np.array([0.0, 0.0, 1.0]))
    a, b = segment(cloud, 10), segment(cloud, 30)
    assert a.params["up_weight"] == b.params["up_weight"] > 7.5
    assert a.elements.source is b.elements.source is not cloud
    assert a.elements.graph is b.elements.graph
    c = segment(cloud, 30, up_weight=3)  # (another weight: another copy)
    assert c.elements.source is not a.elements.source
    again = pickle.loads(pickle.dumps(cloud))
    assert not any(k.startswith(("up_weighted", "surface_up_weight")) for k in again.__dict__)
    np.testing.assert_array_equal(segment(again, 30).labels, b.labels)
