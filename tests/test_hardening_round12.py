"""The faults of the twelfth attack (every command on every kind of input, and labels
read back from the fields they were written into): each case fails without its fix. The
volume's options (``segment VOLUME --levels``, ``--seed-resolution``, ``--graph``,
``--html``) and ``panel --labels-from`` have their own tests
(tests/cli/test_every_kind.py)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from superfacets import PointCloud, segment
from superfacets.cli import main
from superfacets.evaluation.metrics import evaluate_rows


def _two_pieces(n=600, seed=0):
    """Two flat patches 50 apart, a class each: no point's ten neighbours cross the gap."""
    xy = np.random.default_rng(seed).random((n, 2)) * 10
    right = np.arange(n) >= n // 2
    pts = np.c_[xy, np.zeros(n)]
    pts[right, 0] += 60
    return pts, right.astype(np.int64)


def test_a_truth_whose_classes_never_neighbour_is_said_not_to_judge_borders(tmp_path,
                                                                          capsys):
    """Classes on separate pieces of the point graph (a LAS whose classes are 50 m
    apart): evaluate printed boundary recall 1.0000 and precision 0.0000 without a word,
    as if the superpoints had found every border and placed none."""
    pts, truth = _two_pieces()
    labels = segment(PointCloud(pts), 12).labels
    m = evaluate_rows(PointCloud(pts), labels, [truth], precision=True)
    assert m["borderless_truths"] == 1
    assert m["boundary_recall"] == 1.0 and m["boundary_precision"] == 0.0
    near = truth.copy()  # the same classes, one border inside the left piece
    near[(pts[:, 0] < 5)] = 2
    assert evaluate_rows(PointCloud(pts), labels, [near, truth])["borderless_truths"] == 1
    assert evaluate_rows(PointCloud(pts), labels, [near])["borderless_truths"] == 0
    np.save(tmp_path / "c.npy", pts)
    np.savetxt(tmp_path / "l.seg", labels, fmt="%d")
    np.savetxt(tmp_path / "gt.seg", truth, fmt="%d")
    np.savetxt(tmp_path / "near.seg", near, fmt="%d")
    assert main(["evaluate", str(tmp_path / "c.npy"), str(tmp_path / "l.seg"),
                 str(tmp_path / "gt.seg")]) == 0
    out = capsys.readouterr().out
    assert "boundary_recall         1.0000" in out
    assert "no two neighbouring points differ in 1 of the ground truths" in out
    assert main(["evaluate", str(tmp_path / "c.npy"), str(tmp_path / "l.seg"),
                 str(tmp_path / "near.seg")]) == 0
    assert "neighbouring" not in capsys.readouterr().out
    assert main(["evaluate", str(tmp_path / "c.npy"), str(tmp_path / "l.seg"),
                 str(tmp_path / "gt.seg"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["borderless_truths"] == 1


def test_a_volume_is_drawn_by_its_cut_and_refused_in_words_where_a_surface_is_needed(
        tmp_path):
    """render(volume, labels) and html_page(volume, labels) said "mesh must be a
    superfacets.Mesh, ..., got TetMesh" (the commands drew its cut); they draw the cut at
    the middle of x as the commands do. Where a surface is needed (a coloured mesh, a
    scene's objects, a tiled run) the error says what takes a volume."""
    from scipy.spatial import Delaunay

    from superfacets import TetMesh, segment_tiled, write_colored_mesh
    from superfacets.api.scenes import segment_objects
    from superfacets.inputs.tetmesh import as_drawn, cut_surface
    from superfacets.viz.html import html_page

    p = np.random.default_rng(3).random((250, 3))
    vol = TetMesh(p, Delaunay(p).simplices)
    labels = segment(vol, 7).labels
    surface, face_labels = cut_surface(vol, labels, axis=0, at=0.5)
    assert html_page(vol, labels) == html_page(surface, face_labels)
    drawn, drawn_labels, cut = as_drawn(vol, labels)
    assert cut and np.array_equal(drawn_labels, face_labels)
    assert as_drawn(surface, face_labels)[2] is False
    pytest.importorskip("pyvista")
    from superfacets.viz.render import render

    a = render(vol, labels, size=(200, 150))
    b = render(surface, face_labels, size=(200, 150))
    assert np.array_equal(a, b)
    for call in (lambda: write_colored_mesh(tmp_path / "v.ply", vol, labels),
                 lambda: segment_objects(vol, 3), lambda: segment_tiled(vol, 5, tiles=2)):
        with pytest.raises(TypeError, match="not a tetrahedral mesh: segment\\(volume, k\\)"):
            call()
    assert not (tmp_path / "v.ply").exists()
