"""NPY records (numpy structured arrays with fields ``x y z``, as ``ros_numpy`` makes of a
ROS ``PointCloud2``): read as clouds, their other fields as ground truths; a learning
pipeline's scene folder (Pointcept's ``coord.npy``, ``color.npy``, ``segment.npy``)."""

from __future__ import annotations

import numpy as np
import pytest

from superfacets import PointCloud, read_cloud, segment
from superfacets.cli import main
from superfacets.errors import MeshFormatError
from superfacets.inputs.cloud import InvalidCloudError
from superfacets.io.labels import read_field


def _terraces(n=1500, seed=0):
    rng = np.random.default_rng(seed)
    xy = rng.random((n, 2)) * [4.0, 3.0]
    z = np.where(xy[:, 0] > 2.0, 0.5, 0.0) + 0.002 * rng.standard_normal(n)
    return np.c_[xy, z], (xy[:, 0] > 2.0).astype(np.int32)


def _records(points, labels, *, rgb=None, names=("x", "y", "z")):
    fields = [(n, "f4") for n in names] + [("label", "i4"), ("intensity", "f4")]
    if rgb is not None:
        fields += [("r", "u1"), ("g", "u1"), ("b", "u1")]
    arr = np.zeros(len(points), dtype=fields)
    for c, n in enumerate(names):
        arr[n] = points[:, c]
    arr["label"] = labels
    if rgb is not None:
        arr["r"], arr["g"], arr["b"] = rgb.T
    return arr


def test_records_read_as_the_same_cloud_as_its_columns(tmp_path):
    pts, lab = _terraces()
    rgb = np.where(lab[:, None] == 1, [200, 40, 40], [40, 200, 40]).astype(np.uint8)
    np.save(tmp_path / "scan.npy", _records(pts, lab, rgb=rgb, names=("X", "Y", "Z")))
    cloud = read_cloud(tmp_path / "scan.npy")
    f32 = pts.astype(np.float32).astype(np.float64)
    assert np.array_equal(cloud.points, f32) and np.allclose(cloud.colors * 255, rgb)
    assert cloud.normals is None and cloud.shape is None
    same = segment(PointCloud(f32, colors=rgb / 255.0), 12)
    assert np.array_equal(segment(cloud, 12).labels, same.labels)
    assert np.array_equal(read_field(tmp_path / "scan.npy", "label"), lab)


def test_an_organized_record_frame_keeps_its_layout_holes_and_packed_colour(tmp_path):
    u, v = np.meshgrid(np.linspace(0, 4, 30), np.linspace(0, 3, 20))
    arr = np.zeros((20, 30), dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("rgb", "f4"),
                                    ("normal_x", "f4"), ("normal_y", "f4"),
                                    ("normal_z", "f4"), ("ring", "u2")])
    arr["x"], arr["y"], arr["z"], arr["normal_z"] = u, v, 0.1 * np.sin(u), 1.0
    for c in "xyz":
        arr[c][4, 7] = np.nan
    packed = np.full((20, 30), (255 << 16) | (128 << 8) | 3, dtype=np.uint32)
    arr["rgb"] = packed.view(np.float32)
    np.save(tmp_path / "frame.npy", arr)
    cloud = read_cloud(tmp_path / "frame.npy")
    assert cloud.shape == (20, 30) and cloud.n_points == 599
    assert np.allclose(cloud.colors[0] * 255, [255, 128, 3])
    assert np.allclose(cloud.normals[0], [0, 0, 1])
    labels = segment(cloud, 8).labels
    assert labels[4 * 30 + 7] == -1 and (np.delete(labels, 4 * 30 + 7) >= 0).all()


def test_a_record_cloud_s_missing_point_is_nan_in_all_three(tmp_path):
    pts, lab = _terraces(200)
    arr = _records(pts, lab)
    for c in "xyz":
        arr[c][5] = np.nan
    np.save(tmp_path / "holes.npy", arr)
    assert read_cloud(tmp_path / "holes.npy").n_points == 199
    arr["z"][5], arr["x"][9] = 0.0, np.nan  # row 5 x and y NaN beside a number; row 9 x
    np.save(tmp_path / "torn.npy", arr)
    with pytest.raises(InvalidCloudError, match="point 5 "):
        read_cloud(tmp_path / "torn.npy")


@pytest.mark.parametrize("fields, match", [
    ([("x", "f4"), ("y", "f4"), ("height", "f4")], r"no z field \(they have: x, y, height\)"),
    ([("x", "f4"), ("y", "f4"), ("z", "c8")], r"field 'z' \(complex64\) is not one real"),
    ([("x", "f4"), ("y", "f4"), ("z", "f4", (2,))], "field 'z' .* not one real"),
])
def test_records_without_usable_coordinates_are_refused(tmp_path, fields, match):
    np.save(tmp_path / "bad.npy", np.zeros(10, dtype=fields))
    with pytest.raises(MeshFormatError, match=match):
        read_cloud(tmp_path / "bad.npy")


def test_a_field_of_records_is_a_ground_truth_and_plain_arrays_have_none(tmp_path, capsys):
    pts, lab = _terraces()
    arr = _records(pts, lab)
    np.save(tmp_path / "scan.npy", arr)
    np.save(tmp_path / "plain.npy", pts)
    assert main(["segment", str(tmp_path / "scan.npy"), "-k", "10", "-o",
                 str(tmp_path / "labels.npy")]) == 0
    capsys.readouterr()
    assert main(["evaluate", str(tmp_path / "scan.npy"), str(tmp_path / "labels.npy"),
                 "--ground-truth-field", "label", "--json"]) == 0
    by_field = capsys.readouterr().out
    np.save(tmp_path / "truth.npy", lab)
    assert main(["evaluate", str(tmp_path / "scan.npy"), str(tmp_path / "labels.npy"),
                 str(tmp_path / "truth.npy"), "--json"]) == 0
    assert capsys.readouterr().out == by_field
    with pytest.raises(MeshFormatError, match="it has: x, y, z, label, intensity"):
        read_field(tmp_path / "scan.npy", "class")
    with pytest.raises(MeshFormatError, match="plain numbers .* has no fields"):
        read_field(tmp_path / "plain.npy", "label")
    two = np.zeros(10, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("lab", "i4", (2,))])
    np.save(tmp_path / "two.npy", two)
    with pytest.raises(MeshFormatError, match="holds 2 values per point"):
        read_field(tmp_path / "two.npy", "lab")
    arr["intensity"] = 0.5  # not a whole number
    np.save(tmp_path / "scan.npy", arr)
    with pytest.raises(MeshFormatError, match="intensity"):
        read_field(tmp_path / "scan.npy", "intensity")


def test_tiles_read_records_as_one_run_does(tmp_path):
    from superfacets import segment_tiled

    pts, lab = _terraces(4000)
    np.save(tmp_path / "scan.npy", _records(pts, lab))
    tiled = segment_tiled(tmp_path / "scan.npy", 20, tiles=2, workdir=tmp_path / "work")
    assert tiled.labels.shape == (4000,) and tiled.labels.min() >= 0
    assert len(np.unique(tiled.labels)) == 20


def _scene(folder, seed):
    """A Pointcept scene folder: two terraces of two colours, -1 on the first 50 points."""
    pts, lab = _terraces(1500, seed)
    folder.mkdir()
    np.save(folder / "coord.npy", pts.astype(np.float32))
    rgb = np.where(lab[:, None] == 1, [200, 30, 30], [30, 200, 30]).astype(np.uint8)
    np.save(folder / "color.npy", rgb)
    normal = np.zeros((1500, 3), dtype=np.float32)
    normal[:, 2] = 1
    np.save(folder / "normal.npy", normal)
    segment_ = lab.astype(np.int16)
    segment_[:50] = -1
    np.save(folder / "segment.npy", segment_)
    return pts.astype(np.float32).astype(np.float64), rgb


def test_a_scene_folder_s_coord_npy_reads_its_colour_and_normals(tmp_path, capsys):
    import csv

    from superfacets import segment_tiled

    pts, rgb = _scene(tmp_path / "scene0000_00", 0)
    _scene(tmp_path / "scene0001_00", 1)
    coord = tmp_path / "scene0000_00" / "coord.npy"
    cloud = read_cloud(coord)
    assert np.array_equal(cloud.points, pts) and np.allclose(cloud.colors * 255, rgb)
    assert np.allclose(cloud.normals, [0, 0, 1]) and np.allclose(cloud.up, [0, 0, 1])
    one = segment(cloud, 12, beta=1.0)
    tiled = segment_tiled(coord, 12, tiles=2, workdir=tmp_path / "work", beta=1.0)
    assert len(np.unique(tiled.labels)) == 12 and tiled.labels.min() >= 0
    assert np.array_equal(segment(PointCloud(pts, colors=rgb / 255, normals=cloud.normals,
                                             up=(0, 0, 1)), 12, beta=1.0).labels, one.labels)
    # each scene judged against the segment.npy beside it, -1 left out
    out = tmp_path / "rows.csv"
    assert main(["experiment", "--inputs", str(tmp_path / "*" / "coord.npy"),
                 "--ground-truths", "segment.npy", "--ignore-label", "-1", "-m",
                 "superfacets", "-k", "10", "--alpha", "0", "-o", str(out), "-q"]) == 0
    rows = list(csv.DictReader(out.open()))
    assert sorted(r["mesh"] for r in rows) == ["scene0000_00", "scene0001_00"]
    assert all(r["status"] == "ok" and float(r["undersegmentation_error"]) < 0.05
               for r in rows)
    # the folder itself is the scene, for every command of one input
    assert main(["segment", str(tmp_path / "scene0000_00"), "-k", "12", "--beta", "1", "-o",
                 str(tmp_path / "sp.npy")]) == 0
    assert np.array_equal(np.load(tmp_path / "sp.npy"), one.labels)
    # one file for every input is refused; so is a colour file of another length
    assert main(["experiment", "--inputs", str(tmp_path / "*" / "coord.npy"),
                 "--ground-truths", "../scene0000_00/segment.npy", "-k", "10", "-o",
                 str(tmp_path / "no.csv")]) == 2
    assert "2 inputs (" in capsys.readouterr().err and not (tmp_path / "no.csv").exists()
    np.save(tmp_path / "scene0001_00" / "color.npy", rgb[:10])
    with pytest.raises(MeshFormatError, match=r"color.npy: the scene's color should be "
                                              r"\(1,500, 3\)"):
        read_cloud(tmp_path / "scene0001_00" / "coord.npy")


def test_a_folder_of_scene_folders_gives_each_coord_npy_once(tmp_path):
    # (batch on a Pointcept tree read color.npy as a cloud of colours, segment.npy as an error)
    from superfacets.scale.runner.collect import collect_inputs

    for name in ("scene0000_00", "scene0001_00"):
        _scene(tmp_path / name, 0)
    np.save(tmp_path / "loose.npy", np.zeros((10, 3)))  # (not a scene: an input)
    passed = []
    found = collect_inputs([str(tmp_path)], passed=passed)
    assert sorted(p.relative_to(tmp_path).as_posix() for p in found) == [
        "loose.npy", "scene0000_00/coord.npy", "scene0001_00/coord.npy"]
    assert len(passed) == 6 and all("Pointcept" in why for _, why in passed)
    # each scene's outputs named by its folder (labels in scene0000_00.npy, not coord.npy)
    from superfacets.scale.runner.collect import output_names

    assert sorted(output_names(found).values()) == ["loose", "scene0000_00", "scene0001_00"]
    one = tmp_path / "scene0000_00" / "coord.npy"
    assert output_names([one]) == {one: "scene0000_00"}
