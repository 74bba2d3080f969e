"""The faults of the thirteenth attack (scans written back into their own formats, every
kind through experiment, batch and the tiled run): each case fails without its fix."""

from __future__ import annotations

import csv

import numpy as np
from plyfile import PlyData, PlyElement

from superfacets.cli import main
from superfacets.elements.points import point_graph
from superfacets.evaluation.metrics import has_border


def _ply_cloud(path, pts, fields: dict) -> None:
    """A binary PLY of points with more vertex properties (``fields``: name -> values)."""
    dtype = [("x", "f8"), ("y", "f8"), ("z", "f8")] + [(k, np.asarray(v).dtype.str)
                                                      for k, v in fields.items()]
    v = np.empty(len(pts), dtype=dtype)
    v["x"], v["y"], v["z"] = pts.T
    for k, values in fields.items():
        v[k] = values
    PlyData([PlyElement.describe(v, "vertex")]).write(str(path))


def test_experiment_leaves_the_recall_empty_where_the_truth_has_no_border(tmp_path, capsys):
    """Two classes 50 apart (no point's neighbours cross the gap): experiment wrote a
    boundary recall of 1.0 in every row, which the report then averaged as if every
    border had been found."""
    rng = np.random.default_rng(0)
    n = 800
    right = np.arange(n) >= n // 2
    pts = np.c_[rng.random((n, 2)) * 10, np.zeros(n)]
    pts[right, 0] += 60
    g = point_graph(pts).graph
    assert not has_border(g, right.astype(int)) and has_border(g, (pts[:, 0] > 5) * 1)
    _ply_cloud(tmp_path / "far.ply", pts, {"label": right.astype(np.int32)})
    near = (pts[:, 0] > 5) + 2 * right  # a border inside the left piece too
    _ply_cloud(tmp_path / "near.ply", pts, {"label": near.astype(np.int32)})
    out = tmp_path / "exp.csv"
    assert main(["experiment", "--dataset", "files", "--inputs", str(tmp_path / "far.ply"),
                 str(tmp_path / "near.ply"), "--ground-truth-field", "label", "-k", "8",
                 "--alpha", "200", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "far: the boundary recall is left empty: no two neighbouring elements" in err
    assert "near:" not in err
    rows = {r["mesh"]: r for r in csv.DictReader(out.open())}
    assert rows["far"]["status"] == "ok" and rows["far"]["boundary_recall"] == ""
    assert rows["far"]["undersegmentation_error"] != ""
    assert 0 < float(rows["near"]["boundary_recall"]) <= 1


def test_a_tiled_run_does_not_say_it_follows_colour_it_weighs_at_zero(tmp_path, capsys):
    """Points of one colour: --beta auto reads no colour edge (beta 0); the tiled run's
    summary said "following colour (beta 0; --beta 0: off)", one run's nothing."""
    rng = np.random.default_rng(1)
    n = 3000
    pts = np.c_[rng.random((n, 2)) * 20, np.zeros(n)]
    grey = np.full(n, 128, np.uint8)
    _ply_cloud(tmp_path / "grey.ply", pts, {"red": grey, "green": grey, "blue": grey})
    for extra in ([], ["--tiles", "2"]):
        assert main(["segment", str(tmp_path / "grey.ply"), "-k", "20", "-o",
                     str(tmp_path / "g.seg"), *extra]) == 0
        said = capsys.readouterr().out
        assert "superpoints" in said and "colour" not in said, said
    pts[:, 2] = 0
    colours = np.where(pts[:, 0] > 10, 250, 5).astype(np.uint8)
    _ply_cloud(tmp_path / "two.ply", pts, {"red": colours, "green": grey, "blue": grey})
    assert main(["segment", str(tmp_path / "two.ply"), "-k", "20", "-o",
                 str(tmp_path / "g.seg"), "--tiles", "2", "--beta", "1"]) == 0
    assert "following colour (beta 1" in capsys.readouterr().out


def test_a_cloud_format_o_does_not_write_names_those_that_hold_the_labels(tmp_path, capsys):
    """``-o out.e57`` (or a .pcd of a text cloud): refused, naming only a label file, where
    a LAS/LAZ or PLY of the points with their labels was one name away."""
    rng = np.random.default_rng(2)
    np.savetxt(tmp_path / "c.xyz", rng.random((400, 3)))
    _ply_cloud(tmp_path / "c.ply", rng.random((400, 3)), {})
    for source, out, names in (("c.xyz", "o.e57", "o.las, o.laz or o.ply"),
                               ("c.xyz", "o.pcd", "o.las, o.laz or o.ply"),
                               ("c.ply", "o.e57", "o.ply")):
        assert main(["segment", str(tmp_path / source), "-k", "5", "-o",
                     str(tmp_path / out)]) == 2
        err = capsys.readouterr().err
        assert f"the points with their labels as a field: {names}" in err, err
        assert not (tmp_path / out).exists()
        suggested = names.split(", ")[0].split(" or ")[0]
        assert main(["segment", str(tmp_path / source), "-k", "5", "-o",
                     str(tmp_path / suggested)]) == 0
        assert (tmp_path / suggested).stat().st_size > 0
        capsys.readouterr()
