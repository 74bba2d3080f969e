"""NPY records (numpy structured arrays with fields ``x y z``, as ``ros_numpy`` makes of a
ROS ``PointCloud2``): read as clouds, their other fields as ground truths."""

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
