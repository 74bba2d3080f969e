"""The faults of the seventh attack (files written by this package and others read back):
each case fails without its fix."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from plyfile import PlyData, PlyElement

from superfacets import read_labels
from superfacets.cli import main
from superfacets.errors import MeshFormatError
from superfacets.io.labels import read_field


def _ply_cloud(path, n, **fields):
    """A PLY of ``n`` points with the given vertex properties (name: array)."""
    rng = np.random.default_rng(0)
    dtype = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")] + [(k, v.dtype.str) for k, v in
                                                          fields.items()]
    data = np.zeros(n, dtype=dtype)
    for i, c in enumerate("xyz"):
        data[c] = rng.random(n)
    for k, v in fields.items():
        data[k] = v
    PlyData([PlyElement.describe(data, "vertex")]).write(str(path))
    return path


@pytest.mark.parametrize("values, said", [
    (np.full(6, 2**63, dtype=np.uint64), "label 0 is 9223372036854775808 (uint64)"),
    (np.r_[np.zeros(5), 1e19], "label 5 is 1e+19 (float64)"),
    (np.r_[np.zeros(4), np.nan, 0.0], "label 4 is nan (float64)"),
    (np.r_[0.0, 1.5, np.zeros(4)], "label 1 is 1.5 (float64)"),
])
def test_npy_labels_beyond_int64_or_not_whole_are_named_not_wrapped(tmp_path, values, said):
    # (an unsigned 2**63 wrapped to -2**63: "every label is below 0"; a NaN was "values
    # that are not")
    np.save(tmp_path / "l.npy", values)
    with pytest.raises(MeshFormatError, match=r"whole numbers within int64; " +
                       said.replace("(", r"\(").replace(")", r"\)").replace("+", r"\+")):
        read_labels(tmp_path / "l.npy")
    np.save(tmp_path / "ok.npy", np.array([0.0, 3.0, -1.0]))
    assert read_labels(tmp_path / "ok.npy").tolist() == [0, 3, -1]


def test_a_ply_scalar_field_saved_as_floats_is_read_and_a_nan_named(tmp_path):
    # (CloudCompare saves a scalar field as float32: a NaN, its "no value", was cast to
    # -2**63 with a numpy warning, 2.7 truncated to 2)
    labels = np.arange(40) % 3
    good = _ply_cloud(tmp_path / "cc.ply", 40, scalar_ClusterID=labels.astype(np.float32))
    assert np.array_equal(read_labels(good), labels)
    bad = labels.astype(np.float32)
    bad[7] = np.nan
    _ply_cloud(tmp_path / "nan.ply", 40, scalar_ClusterID=bad)
    with pytest.raises(MeshFormatError, match=r"nan.ply: vertex property 'scalar_ClusterID': "
                       r"labels must be whole numbers within int64; label 7 is nan"):
        read_labels(tmp_path / "nan.ply")
    bad[7] = 2.7
    _ply_cloud(tmp_path / "part.ply", 40, classification=bad)
    with pytest.raises(MeshFormatError, match=r"field 'classification': .* label 7 is 2.7"):
        read_field(tmp_path / "part.ply", "classification")


def test_evaluate_says_one_segment_in_the_singular(tmp_path, capsys):
    # ("500 points, 1 superpoints"; counts without thousands separators; a frame's invalid
    # points, left out of the metrics, not said)
    pts = np.random.default_rng(1).random((1500, 3))
    np.savetxt(tmp_path / "c.xyz", pts)
    np.savetxt(tmp_path / "one.txt", np.zeros(1500, dtype=int), fmt="%d")
    assert main(["evaluate", str(tmp_path / "c.xyz"), str(tmp_path / "one.txt")]) == 0
    assert "c.xyz: 1,500 points, 1 superpoint, no ground truths" in capsys.readouterr().out
    frame = pts.reshape(30, 50, 3)
    frame[0, :7] = np.nan
    np.save(tmp_path / "f.npy", frame)
    assert main(["evaluate", str(tmp_path / "f.npy"), str(tmp_path / "one.txt")]) == 0
    assert "f.npy: 1,500 points (7 invalid, not measured), 1 superpoint" in \
        capsys.readouterr().out


@pytest.mark.parametrize("sep, header", [("\t", ""), (" ", ""), ("\t", "X\tY\tZ\n")])
def test_decimal_commas_in_tab_or_space_separated_columns(tmp_path, sep, header):
    # (a spreadsheet's tab-separated text in a European locale, "1,5\t2,25\t0,5", was read
    # as six columns, x = 1 and y = 5: every point wrong, silently)
    from superfacets import read_cloud

    pts = np.round(np.random.default_rng(4).random((200, 3)) * 10, 4)
    rows = "".join(sep.join(f"{v:.4f}".replace(".", ",") for v in r) + "\n" for r in pts)
    (tmp_path / "c.txt").write_text(header + rows)
    assert np.allclose(read_cloud(tmp_path / "c.txt").points, pts)
    (tmp_path / "ints.csv").write_text("1, 2, 3\n4, 5, 6\n7, 8, 1\n")  # (still a CSV)
    assert read_cloud(tmp_path / "ints.csv").points.tolist()[1] == [4.0, 5.0, 6.0]


def test_a_copc_tile_gets_its_labels_in_a_plain_laz_copy(tmp_path, capsys):
    # (a COPC file, as 3DEP and LiDAR HD tiles come: "NotImplementedError: Writing COPC is
    # not supported", a traceback, nothing written)
    laspy = pytest.importorskip("laspy")
    rng = np.random.default_rng(5)
    las = laspy.create(point_format=6, file_version="1.4")
    las.header.scales = [0.001] * 3
    xy = rng.random((1500, 2)) * 30
    las.x, las.y = xy[:, 0], xy[:, 1]
    las.z = np.where(xy[:, 0] > 15, 1.0, 0.0) + rng.normal(0, 0.01, 1500)
    # (the index of a COPC file: its info VLR first, the hierarchy as an EVLR)
    las.vlrs.insert(0, laspy.VLR(user_id="copc", record_id=1, record_data=bytes(160)))
    las.header.evlrs = laspy.vlrs.vlrlist.VLRList([
        laspy.VLR(user_id="copc", record_id=1000, record_data=bytes(32)),
        laspy.VLR(user_id="someone", record_id=7, record_data=b"kept")])
    src = tmp_path / "tile.copc.laz"
    las.write(str(src), laz_backend=laspy.LazBackend.Lazrs)
    assert isinstance(laspy.read(str(src)).vlrs[0], laspy.copc.CopcInfoVlr)
    for extra in ([], ["--tiles", "2"]):
        out = tmp_path / f"out{len(extra)}.laz"
        assert main(["segment", str(src), "-k", "12", "-o", str(out), *extra]) == 0
        assert "its COPC index left out" in capsys.readouterr().out
        back = laspy.read(str(out))
        assert not [v for v in back.vlrs if v.user_id == "copc"]
        assert [(v.user_id, v.record_data) for v in back.header.evlrs] == [("someone", b"kept")]
        assert np.array_equal(back.X, laspy.read(str(src)).X)
        assert np.array_equal(read_labels(out), read_labels(tmp_path / "out0.laz")) or extra
        assert len(np.unique(back.ClusterID)) == 12


def _two_pieces(folder):
    """A cloud of two patches far apart: one superpoint cannot span them (a warning)."""
    rng = np.random.default_rng(6)
    a = np.c_[rng.random((300, 2)), np.zeros(300)]
    np.savetxt(folder / "two.xyz", np.r_[a, a + [50.0, 0, 0]])
    np.savetxt(folder / "one.xyz", a)


def test_a_batch_names_each_warning_s_input_and_keeps_it_in_the_manifest(tmp_path, capsys):
    # (a worker's warning came out as Python prints one, its source line and no input's
    # name: in a batch of many files, no telling whose)
    from superfacets.scale.runner.manifest import read_manifest

    folder = tmp_path / "in"
    folder.mkdir()
    _two_pieces(folder)
    assert main(["batch", str(folder), "-o", str(tmp_path / "out"), "-k", "1", "-j", "1"]) == 0
    err = capsys.readouterr().err
    assert f"warning: {folder / 'two.xyz'}: 2 superpoints for n_segments=1" in err
    assert "RuntimeWarning" not in err and "one.xyz" not in err
    rows = {Path(r["input"]).name: r for r in read_manifest(tmp_path / "out")}
    assert rows["two.xyz"]["warnings"].startswith("2 superpoints for n_segments=1")
    assert rows["one.xyz"]["warnings"] is None


def test_an_experiment_counts_its_warnings_by_input(tmp_path, capsys):
    folder = tmp_path / "in"
    folder.mkdir()
    _two_pieces(folder)
    assert main(["experiment", "--inputs", str(folder), "-m", "superfacets", "-k", "1",
                 "--alpha", "200", "-o", str(tmp_path / "rows.csv"), "-j", "1"]) == 0
    err = capsys.readouterr().err
    assert "warning: 1 row: two: 2 superpoints for n_segments=1" in err
    assert "RuntimeWarning" not in err and "warnings" not in \
        (tmp_path / "rows.csv").read_text().splitlines()[0]


def test_a_folder_s_nuscenes_sweeps_are_inputs_its_other_bin_files_not(tmp_path):
    # (a folder of nuScenes sweeps gave "a .bin in a folder is not read as a cloud")
    from superfacets.scale.runner.collect import collect_inputs

    (tmp_path / "n015__LIDAR_TOP__1.pcd.bin").write_bytes(bytes(20))
    (tmp_path / "weights.bin").write_bytes(bytes(20))
    (tmp_path / "n015__LIDAR_TOP__1_lidarseg.bin").write_bytes(bytes(1))
    found = [p.name for p in collect_inputs([str(tmp_path)])]
    assert found == ["n015__LIDAR_TOP__1.pcd.bin"]


def test_a_copc_name_is_not_given_to_a_plain_laz(tmp_path, capsys):
    # (`-o out.copc.laz` wrote a plain LAZ under a name PDAL reads with readers.copc; a
    # batch named a COPC tile's copy tile.copc.laz, a nuScenes sweep's labels sweep.pcd.seg)
    from superfacets.scale.runner.collect import output_names

    np.savetxt(tmp_path / "c.xyz", np.random.default_rng(7).random((300, 3)))
    out = tmp_path / "c.copc.laz"
    assert main(["segment", str(tmp_path / "c.xyz"), "-k", "5", "-o", str(out)]) == 2
    assert "not a COPC file (PDAL reads a .copc.laz as one): name it NAME.laz" in \
        capsys.readouterr().err and not out.exists()
    names = output_names([Path("/d/tile.copc.laz"), Path("/d/n015.pcd.bin"),
                          Path("/d/x.copc"), Path("/d/.pcd.bin")])
    assert sorted(names.values()) == [".pcd", "n015", "tile", "x"]


def test_a_vertex_no_face_uses_is_refused_by_tiles_as_by_one_run(tmp_path):
    # (one run refused a NaN vertex that no face uses; a tiled run segmented the mesh)
    import trimesh

    from superfacets import segment, segment_tiled
    from superfacets.errors import InvalidMeshError

    sphere = trimesh.creation.icosphere(3)
    v = np.r_[sphere.vertices, [[np.nan] * 3]]
    trimesh.Trimesh(v, sphere.faces, process=False).export(tmp_path / "m.ply")
    said = r"m.ply: 1 vertex has NaN or infinite coordinates \(first: vertex 642 = \[nan"
    for run in (lambda p: segment(p, 10), lambda p: segment_tiled(p, 10, tiles=2)):
        with pytest.raises(InvalidMeshError, match=said):
            run(tmp_path / "m.ply")


def test_an_unknown_suffix_or_standard_input_names_every_format_read(tmp_path, capsys):
    # (`segment scan.foo` and `segment -` said "unknown mesh format", naming meshes only,
    # to users of clouds and volumes)
    np.savetxt(tmp_path / "scan.foo", np.random.default_rng(8).random((50, 3)))
    for name in (str(tmp_path / "scan.foo"), "-"):
        assert main(["segment", name, "-k", "5"]) == 2
        err = capsys.readouterr().err
        assert "meshes: .off" in err and "point clouds: .pcd" in err and ".laz" in err \
            and "tetrahedral meshes: .msh" in err and "mesh format" not in err
        assert ("standard input is not read" in err) == (name == "-")


def test_an_experiment_tells_apart_files_of_one_name_in_two_folders(tmp_path, capsys):
    # (SemanticKITTI's sequences/00/velodyne/000000.bin and sequences/01/velodyne/000000.bin
    # were both rows of "000000": a resumed run took the second for done, a report merged
    # them)
    import csv

    rng = np.random.default_rng(9)
    for seq in ("00", "01"):
        (tmp_path / seq).mkdir()
        np.savetxt(tmp_path / seq / "000000.xyz", rng.random((400, 3)))
    out = tmp_path / "rows.csv"
    for _ in range(2):
        assert main(["experiment", "--inputs", str(tmp_path / "*" / "*.xyz"), "-k", "10",
                     "--alpha", "200", "-m", "superfacets", "-o", str(out), "-j", "1"]) == 0
    assert "0 rows written (0 ok, 0 failed, 0 skipped), 2 already there" in \
        capsys.readouterr().out
    assert sorted(r["mesh"] for r in csv.DictReader(out.open())) == ["00/000000", "01/000000"]
