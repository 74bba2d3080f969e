"""The faults of the eleventh attack (scenes segmented object by object, a cloud's up
given by name): each case fails without its fix. The per-object levels and the coarse
run's orphan seeds have their own tests (tests/io/test_scan_inputs.py,
tests/method/test_multilevel.py)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from superfacets import PointCloud, segment_tiled
from superfacets.api.scenes import segment_objects
from superfacets.errors import InvalidCloudError, ParameterError


def _scene():
    return trimesh.Scene([trimesh.creation.icosphere(subdivisions=1),
                          trimesh.creation.box().apply_translation([3, 0, 0])])


def test_more_segments_than_a_scenes_faces_are_refused_as_one_run_refuses_them():
    """segment_objects(scene, 10**6) gave each object all its faces (92 superfacets, no
    word); 2**63 raised OverflowError from the shares' arithmetic."""
    for k in (10**6, 2**63):
        with pytest.raises(ParameterError, match=r"larger than the number of faces \(92\)"):
            segment_objects(_scene(), k)
    cloud = PointCloud(np.random.default_rng(0).random((50, 3)))
    with pytest.raises(ParameterError, match=r"larger than the number of points \(50\)"):
        segment_objects(cloud, 51)
    labels, parts = segment_objects(_scene(), 92)  # as many as faces: still allowed
    assert len(parts) == 2 and int(labels.max()) + 1 == sum(p.n_segments for p in parts)


def test_a_clouds_up_takes_an_axis_name_as_every_other_up():
    """PointCloud(up='z') raised numpy's "could not convert string to float" (the
    learning graph's and the CLI's up take axis names)."""
    pts = np.random.default_rng(1).random((400, 3))
    assert np.array_equal(PointCloud(pts, up="-y").up, [0.0, -1.0, 0.0])
    with pytest.raises(InvalidCloudError, match="up must be an axis"):
        PointCloud(pts, up="q")
    r = segment_tiled(PointCloud(pts * [4, 3, 0.3], up="z"), 12, tiles=2, workers=1,
                      graph=True)
    assert r.learning["x"].shape[0] == 12


def test_a_hierarchys_labels_are_checked():
    """Hierarchy.labels(i, labels) indexed its parents with whatever it was given: numpy's
    IndexError for a label past the superfacets, its ufunc error for strings."""
    from superfacets import segment

    r = segment(trimesh.creation.icosphere(subdivisions=3), 20)
    h = r.hierarchy([5, 2])
    assert np.array_equal(h.labels(1, np.array([-1, 0, 19])),
                          [-1, h.of_superfacets(1)[0], h.of_superfacets(1)[19]])
    for bad, says in ((np.arange(1280), r"lie in -1\.\.19"), (np.array([-2]), "lie in"),
                      (np.array(["a"]), "integers"), (None, "integers")):
        with pytest.raises(ParameterError, match=says):
            h.labels(0, bad)


def test_an_inputs_name_is_a_string_or_a_path():
    """A name that was neither (an array passed one argument too far) raised numpy's
    "truth value of an array is ambiguous"; a path is taken as its text."""
    from pathlib import Path

    from superfacets import Mesh

    box = trimesh.creation.box()
    assert Mesh(box.vertices, box.faces, name=Path("parts/box.ply")).name == "parts/box.ply"
    for make in (lambda n: Mesh(box.vertices, box.faces, n),
                 lambda n: PointCloud(box.vertices, None, n)):
        with pytest.raises(ParameterError, match="name must be a string, got ndarray"):
            make(np.zeros(3))


def test_a_tiled_graph_or_levels_with_an_up_weight_are_of_the_cloud_as_given(tmp_path):
    """segment_tiled(graph=True, up_weight=2) summed the weighed cloud: heights and
    elevations doubled against one run's learning graph of the same labels (which is of
    the cloud as given), without a word. Refused then; now of the cloud as given (the
    whole comparison: tests/method/test_up_weight.py)."""
    pts = np.random.default_rng(3).random((2000, 3)) * [4, 3, 1]
    cloud = PointCloud(pts, up="z")
    r = segment_tiled(cloud, 20, tiles=2, workers=1, up_weight=2, graph=True, levels=[5])
    assert r.n_segments == 20 and r.hierarchy.levels == (5,)
    assert 0 < r.learning["pos"][:, 2].max() < 1.0  # (the weighed cloud's heights reach 2)


def test_the_sizes_and_metrics_take_what_segment_takes():
    """count_for_resolution(trimesh, R) raised AttributeError ('Trimesh' has no n_faces),
    default_count of an array likewise; evaluate(mesh, labels, gt) with one array meant one
    ground truth and iterated over its numbers, a number raised "has no len()"."""
    from superfacets import Mesh, segment
    from superfacets.api.sizes import count_for_resolution, default_count, diagonal_fraction
    from superfacets.evaluation.metrics import evaluate

    ball = trimesh.creation.icosphere(subdivisions=3)
    mine = Mesh(ball.vertices, ball.faces)
    assert count_for_resolution(ball, 0.3) == count_for_resolution(mine, 0.3)
    assert diagonal_fraction(ball, 0.5) == diagonal_fraction(mine, 0.5)
    pts = np.random.default_rng(4).random((30000, 3))
    assert default_count(pts) == default_count(PointCloud(pts)) == 150
    with pytest.raises(ParameterError, match="finite length"):
        diagonal_fraction(ball, "far")
    truth = (ball.triangles_center[:, 0] > 0).astype(int)
    labels = segment(ball, 12).labels
    assert evaluate(ball, labels, truth) == evaluate(ball, labels, [truth])
    assert evaluate(ball, labels, list(truth)) == evaluate(ball, labels, [truth])
    for bad in (-1, "gt.seg", {}):
        with pytest.raises(ParameterError, match="sequence of label arrays"):
            evaluate(ball, labels, bad)
