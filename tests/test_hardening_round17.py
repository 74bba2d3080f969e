"""Round 17 of hardening: faults an attack on the readers and the command line found, each
with its test.

- A PCD header whose SIZE, TYPE or COUNT gives fewer values than FIELDS names fields was
  "cannot read PCD: tuple index out of range"; now the line and both counts are named.
- A PLY whose vertex coordinates are declared as lists (``property list uchar float x``,
  one value a row, as some writers do and trimesh reads) was numpy's "setting an array
  element with a sequence"; now a list of one value reads as that value, and a row of
  another length is named.
- A text cloud, label file, OBJ or OFF saved as UTF-16 (Windows PowerShell's ``>``) was "not
  a text file"; now it is read.
- ``evaluate --ground-truth-field X`` (a coordinate, or the intensity, read as classes)
  judged against thousands of "classes" without a word; now a warning says the field is a
  measurement.
- ``-k`` above the points at distinct positions said "larger than the number of points
  (14406)" of a file of 14,408 points; now the repeated points are counted in the message.
- An output under a path that is a file said its "folder does not exist"; it says it is a
  file. ``report -o`` given the results file itself said "File exists".
- ``render`` of vertex labels said "642 vertexs"; ``evaluate`` of a tetrahedral mesh's
  labels "2,418 cells": each kind's plural now comes from the kinds' table.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from superfacets import ParameterError, read_cloud, read_mesh, segment
from superfacets.cli import main
from superfacets.errors import MeshFormatError
from superfacets.io import read_labels
from superfacets.io.labels import read_field

_PCD = ("VERSION .7\nFIELDS x y z\nSIZE {}\nTYPE {}\nCOUNT {}\nWIDTH 3\nHEIGHT 1\n"
        "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n0 0 0\n1 0 0\n0 1 0\n")


def test_a_pcd_header_line_of_fewer_values_than_fields_is_named(tmp_path):
    good = tmp_path / "good.pcd"
    good.write_text(_PCD.format("4 4 4", "F F F", "1 1 1"))
    assert read_cloud(good).points.shape == (3, 3)
    for name, line, said in (("size", ("4 4", "F F F", "1 1 1"), "SIZE gives 2 values"),
                             ("type", ("4 4 4", "F F F F", "1 1 1"), "TYPE gives 4 values"),
                             ("count", ("4 4 4", "F F F", "1"), "COUNT gives 1 value ")):
        path = tmp_path / f"{name}.pcd"
        path.write_text(_PCD.format(*line))
        with pytest.raises(MeshFormatError, match=f"FIELDS names 3 fields \\(x y z\\), {said}"):
            read_cloud(path)


def _ply(path, rows, faces=""):
    head = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty list uchar float x\n"
            "property float y\nproperty float z\n")
    if faces:
        head += "element face 1\nproperty list uchar int vertex_indices\n"
    path.write_text(head + "end_header\n" + rows + faces)
    return path


def test_ply_coordinates_declared_as_lists_of_one_value_are_read(tmp_path):
    rows = "1 0.5 0 0\n1 1 0 0\n1 0 1 0\n"
    cloud = read_cloud(_ply(tmp_path / "lists.ply", rows))
    assert cloud.points.tolist() == [[0.5, 0, 0], [1, 0, 0], [0, 1, 0]]
    mesh = read_mesh(_ply(tmp_path / "mesh.ply", rows, "3 0 1 2\n"))  # (as trimesh reads it)
    assert mesh.vertices.tolist() == cloud.points.tolist()
    with pytest.raises(MeshFormatError, match="vertex property x is a list, of 2 values in "
                                              "row 1: one number is expected"):
        read_cloud(_ply(tmp_path / "two.ply", "1 0 0 0\n2 1 3 0 0\n1 0 1 0\n"))


def test_utf16_text_inputs_are_read(tmp_path):
    rng = np.random.default_rng(0)
    pts = rng.random((200, 3))
    text = "\n".join(" ".join(f"{v:.6f}" for v in p) for p in pts)
    for encoding in ("utf-16", "utf-16-be"):  # (the byte-order mark of each: "utf-16" LE)
        xyz = tmp_path / f"{encoding}.xyz"
        xyz.write_bytes(("\ufeff" + text).encode(encoding))
        assert np.allclose(read_cloud(xyz).points, pts, atol=1e-6)
    seg = tmp_path / "labels.seg"
    seg.write_text("\n".join(str(i % 3) for i in range(200)), encoding="utf-16")
    assert read_labels(seg, n_faces=200).tolist() == [i % 3 for i in range(200)]
    for name, body in (("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
                       ("tri.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")):
        (tmp_path / name).write_text(body, encoding="utf-16")
        assert read_mesh(tmp_path / name).faces.tolist() == [[0, 1, 2]]
    bad = tmp_path / "bad.xyz"
    bad.write_bytes(b"\xff\xfe\x00\xd8")  # (a lone surrogate: no UTF-16)
    with pytest.raises(MeshFormatError, match="begins as UTF-16 text, and is not"):
        read_cloud(bad)


def test_a_measured_field_read_as_labels_is_said(tmp_path, capsys):
    laspy = pytest.importorskip("laspy")
    las = laspy.LasData(laspy.LasHeader(point_format=3, version="1.2"))
    rng = np.random.default_rng(1)
    xyz = rng.random((300, 3)) * [10, 10, 0.1]
    las.x, las.y, las.z = xyz.T
    las.classification = (xyz[:, 0] > 5).astype(np.uint8) + 1
    las.intensity = rng.integers(0, 1000, 300).astype(np.uint16)
    path = tmp_path / "scan.las"
    las.write(path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert set(read_field(path, "classification").tolist()) == {1, 2}
    for name, what in (("X", "a coordinate"), ("intensity", "the return's intensity")):
        with pytest.warns(UserWarning, match=f"field '{name}' is {what} measured at each "
                                             "point, not a class or a segment"):
            read_field(path, name)
    labels = tmp_path / "scan.seg"
    assert main(["segment", str(path), "-k", "5", "-o", str(labels), "-q"]) == 0
    capsys.readouterr()
    assert main(["evaluate", str(path), str(labels), "--ground-truth-field", "X"]) == 0
    assert "field 'X' is a coordinate" in capsys.readouterr().err


def test_more_segments_than_distinct_points_counts_the_repeated_ones(tmp_path):
    pts = np.random.default_rng(2).random((50, 3))
    cloud = np.r_[pts, pts[:2]]  # (two points at an earlier one's position)
    with pytest.raises(ParameterError, match=r"n_segments \(51\) is larger than the number "
                                             r"of points \(50: 2 of the input's 52 repeat "
                                             "an earlier point's position or have none\\)"):
        segment(cloud, 51)
    with pytest.raises(ParameterError, match=r"number of points \(50\)$"):
        segment(pts, 51)  # (every row a point: the count alone)
    assert segment(cloud, 50).n_segments == 50
    # a mesh's vertices used by no face, the same way
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [5, 5, 5.0]])
    with pytest.raises(ParameterError, match=r"number of vertices \(4: 1 of the input's 5 is "
                                             r"used by no face\)"):
        segment((v, np.array([[0, 1, 2], [1, 3, 2]])), 5, elements="vertices")


def test_an_output_under_a_file_says_the_folder_is_a_file(tmp_path, capsys):
    pts = tmp_path / "pts.xyz"
    np.savetxt(pts, np.random.default_rng(3).random((100, 3)))
    (tmp_path / "afile").write_text("")
    for argv in (["segment", str(pts), "-k", "3", "-o", str(tmp_path / "afile" / "o.seg")],
                 ["batch", str(pts), "-k", "3", "-o", str(tmp_path / "afile" / "out")],
                 ["experiment", "--inputs", str(pts), "-k", "3", "-o",
                  str(tmp_path / "afile" / "r.csv")]):
        assert main(argv) != 0
        assert "afile is a file, not a folder" in capsys.readouterr().err


def test_a_report_into_a_file_says_so(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    pts = tmp_path / "pts.xyz"
    np.savetxt(pts, np.random.default_rng(4).random((300, 3)))
    rows = tmp_path / "rows.csv"
    assert main(["experiment", "--inputs", str(pts), "-k", "5", "-m", "superfacets",
                 "--alpha", "200", "-o", str(rows), "-j", "1", "-q"]) == 0
    (tmp_path / "afile").write_text("")
    for out, said in ((rows, "rows.csv: exists and is not a folder (the report writes a "
                             "folder"),
                      (tmp_path / "afile" / "x" / "y", "afile is a file, not a folder")):
        capsys.readouterr()
        assert main(["report", str(rows), "-o", str(out)]) != 0
        assert said in capsys.readouterr().err
    assert rows.read_text().startswith("mesh,")  # (untouched)
    assert main(["report", str(rows), "-o", str(tmp_path / "new" / "deep")]) == 0
    assert (tmp_path / "new" / "deep" / "summary.md").is_file()


def test_every_kind_is_counted_in_its_own_plural(tmp_path, capsys):
    from superfacets.elements.kinds import kind_of

    assert [kind_of(k).counted(n) for k, n in (("faces", 1), ("vertices", 642),
                                                ("points", 3000), ("cells", 2418))] == [
        "1 face", "642 vertices", "3,000 points", "2,418 tetrahedra"]
    meshio = pytest.importorskip("meshio")
    from scipy.spatial import Delaunay

    pts = np.random.default_rng(5).random((200, 3))
    tets = Delaunay(pts).simplices
    vol = tmp_path / "vol.vtu"
    meshio.write(vol, meshio.Mesh(pts, [("tetra", tets)]))
    labels = tmp_path / "vol.seg"
    assert main(["segment", str(vol), "-k", "5", "-o", str(labels), "-q"]) == 0
    capsys.readouterr()
    assert main(["evaluate", str(vol), str(labels)]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"vol.vtu: {len(tets):,} tetrahedra, 5 superfacets") and \
        "tetrahedra (min / median / max" in out and "cells" not in out
