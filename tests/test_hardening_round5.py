"""The faults of the fifth attack (options that a command took and then did nothing with,
or crashed on, on a labelled scan): each case fails without its fix."""

from __future__ import annotations

import json

import numpy as np
import pytest

from superfacets import PointCloud
from superfacets.cli import main
from superfacets.elements.points import point_graph
from superfacets.errors import ParameterError
from superfacets.io import read_labels
from superfacets.scale.runner.engine import MIN_WORKER_MEMORY, Engine, check_memory_limit


@pytest.fixture
def scan(tmp_path):
    """A small classified airborne tile (ground and a roof) as LAS, and its labels."""
    laspy = pytest.importorskip("laspy")
    rng = np.random.default_rng(0)
    xy = rng.uniform(0, 30, (3000, 2))
    roof = ((xy > 10) & (xy < 20)).all(axis=1)
    z = np.where(roof, 8.0, 0.0) + rng.normal(0, 0.02, 3000)
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.scales = [0.001] * 3
    las = laspy.LasData(header)
    las.x, las.y, las.z = xy[:, 0], xy[:, 1], z
    las.classification = np.where(roof, 6, 2).astype(np.uint8)
    path = tmp_path / "tile.las"
    las.write(path)
    labels = tmp_path / "tile.seg"
    assert main(["segment", str(path), "-k", "20", "-o", str(labels)]) == 0
    return path, labels


def _one_line_error(capsys, *says):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("superfacets: error:"), err
    assert all(s in err[0] for s in says), err[0]


@pytest.mark.parametrize("n, says", [("-2", ">= 1"), ("0", ">= 1"), ("101", "<= 100")])
def test_evaluate_refuses_a_neighbourhood_the_point_graph_cannot_have(scan, capsys, n, says):
    # (-2: a traceback from the tree; 0: every metric computed on a graph of no edge, a
    # boundary precision of 1.0 and a compactness of 0; 101: more than segment allows)
    path, labels = scan
    assert main(["evaluate", str(path), str(labels), "--ground-truth-field",
                 "classification", "--neighbors", n]) == 2
    _one_line_error(capsys, "n_neighbors", says)


@pytest.mark.parametrize("kwargs", [dict(n_neighbors=0), dict(n_neighbors=2.5),
                                    dict(n_neighbors=True), dict(neighbor_radius=-1.0),
                                    dict(neighbor_radius=float("nan"))])
def test_the_point_graph_checks_its_neighbourhood_itself(kwargs):
    cloud = PointCloud(np.random.default_rng(1).random((200, 3)))
    with pytest.raises(ParameterError, match="n_neighbors|neighbor_radius"):
        point_graph(cloud, **kwargs)
    assert point_graph(cloud, 4).graph.n_elements == 200  # (and a good one still builds)


@pytest.mark.parametrize("args, says", [
    (["--tiles", "2", "--levels", "5,10"], "--levels of a tiled run go into --graph OUT.npz"),
    (["--tiles", "2", "--level-cost", "planarity"], "give --levels too"),  # (was ignored)
    (["--tiles", "2", "--extent-weight", "2"], "give --levels too"),
    (["--tiles", "2", "--view", "top"], "--view chooses the camera of --picture OUT.png"),
    (["--level-cost", "planarity"], "--level-cost is the merge cost of --levels"),
    (["--view", "top"], "--view chooses the camera of --picture"),
    (["--up", "z"], "--up sets the up axis of --picture"),
])
def test_an_option_that_would_do_nothing_is_refused(scan, tmp_path, capsys, args, says):
    path, _ = scan
    out = tmp_path / "out.seg"
    assert main(["segment", str(path), "-k", "20", *args, "-o", str(out)]) == 2
    _one_line_error(capsys, says)
    assert not out.exists()


def test_the_options_still_work_where_they_belong(scan, tmp_path):
    path, _ = scan
    graph = tmp_path / "g.npz"
    assert main(["segment", str(path), "-k", "20", "--levels", "5,10", "--level-cost",
                 "planarity", "--graph", str(graph), "-q"]) == 0
    assert {"labels_0", "labels_1"} <= set(np.load(graph).files)
    assert main(["segment", str(path), "-k", "20", "--up", "z", "--view", "top",
                 "--html", str(tmp_path / "p.html"), "-q"]) == 0


def test_render_refuses_a_negative_line_width_on_a_cloud_too(scan, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    path, labels = scan
    out = tmp_path / "p.png"
    assert main(["render", str(path), str(labels), "-o", str(out), "--line-width", "-3"]) == 2
    _one_line_error(capsys, "line_width")
    assert not out.exists()


@pytest.mark.parametrize("value, says", [("lots", "a size such as 4GiB"), ([1], "a size"),
                                         ("inf", "a size"), (True, "a size"),
                                         ("1KB", "at least 128 MiB"), (-1, "at least 128")])
def test_a_worker_memory_limit_is_a_size_a_worker_can_live_in(value, says):
    with pytest.raises(ParameterError, match=says):
        check_memory_limit(value)
    with pytest.raises(ParameterError, match=says):
        Engine(workers=2, memory_limit=value)


def test_memory_limits_dask_takes_pass_through():
    assert check_memory_limit("auto") == "auto" and check_memory_limit(None) is None
    assert check_memory_limit(0) == 0 and check_memory_limit("0") == 0  # (no limit)
    assert check_memory_limit(0.5) == 0.5  # (a share of the machine's memory)
    assert check_memory_limit("2 GiB") == 2 * 2**30
    assert check_memory_limit(MIN_WORKER_MEMORY) == MIN_WORKER_MEMORY


def test_segment_tiled_refuses_a_bad_memory_limit_before_reading(tmp_path):
    from superfacets import segment_tiled

    missing = tmp_path / "not-read.ply"  # (not there: the limit is refused first)
    with pytest.raises(ParameterError, match="memory_limit"):
        segment_tiled(missing, 10, tiles=2, memory_limit="10MiB")


def test_batch_segments_an_e57_s_scans_one_by_one_as_segment_does(tmp_path):
    pye57 = pytest.importorskip("pye57")
    rng = np.random.default_rng(0)
    path = tmp_path / "site.e57"
    e57 = pye57.E57(str(path), mode="w")
    for i in range(2):
        floor = np.c_[rng.random((1500, 2)) * 10 - 5, np.zeros(1500)]
        wall = np.c_[rng.random(1500) * 10 - 5, np.full(1500, 5.0), rng.random(1500) * 3]
        p = np.vstack([floor, wall])
        e57.write_scan_raw({"cartesianX": p[:, 0], "cartesianY": p[:, 1],
                            "cartesianZ": p[:, 2]}, name=f"station {i}",
                           translation=np.array([20.0 * i, 0, 0]),
                           rotation=np.array([1.0, 0, 0, 0]))
    e57.close()
    one = tmp_path / "one.seg"
    assert main(["segment", str(path), "-k", "16", "--per-object", "-o", str(one), "-q"]) == 0
    # (batch refused it: "--per-object segments the faces of a scene; not points")
    assert main(["batch", str(path), "-o", str(tmp_path / "b"), "-k", "16", "--per-object",
                 "--workers", "1", "-q"]) == 0
    got = read_labels(tmp_path / "b" / "site.seg")
    assert np.array_equal(got, read_labels(one)) and len(np.unique(got)) == 16


def test_write_colored_mesh_takes_a_cloud_as_colored_mesh_does(tmp_path):
    from superfacets import read_labels, segment, write_colored_mesh

    cloud = PointCloud(np.c_[np.random.default_rng(2).random((600, 2)), np.zeros(600)])
    labels = segment(cloud, 6).labels
    # (it said "mesh must be ... (a point cloud: a PointCloud or an (N, 3) array), got
    # PointCloud")
    for given, name in ((cloud, "a.ply"), (cloud.points, "b.ply")):
        out = write_colored_mesh(tmp_path / name, given, labels)
        assert np.array_equal(read_labels(out), labels)
    assert (tmp_path / "a.ply").read_bytes() == (tmp_path / "b.ply").read_bytes()
    with pytest.raises(ParameterError, match="600 integers, one per point"):
        write_colored_mesh(tmp_path / "c.ply", cloud, labels[:5])
    assert not (tmp_path / "c.ply").exists()


@pytest.mark.parametrize("method, param, says", [
    ("superfacets", "alpha=0,-1", "alpha must be"),  # (a failed row each, after the others)
    ("superfacets", "window=0", "window must be"),
    ("shlafman", "alpha=2", "Shlafman weighting must be in [0, 1]"),
    ("adaptive", "start=0", "start must be"),
])
def test_experiment_refuses_a_setting_its_method_refuses_before_any_work(scan, tmp_path,
                                                                         capsys, method,
                                                                         param, says):
    path, _ = scan
    out = tmp_path / "r.csv"
    assert main(["experiment", "--dataset", "files", "--inputs", str(path),
                 "--ground-truth-field", "classification", "-k", "10", "-m", method,
                 "--param", param, "--elements", "points", "-o", str(out), "-j", "1",
                 "-q"]) == 2
    _one_line_error(capsys, f"method {method!r}", says)
    assert not out.exists()


def test_experiment_says_why_its_rows_failed(scan, tmp_path, capsys):
    path, _ = scan
    out = tmp_path / "r.csv"
    assert main(["experiment", "--dataset", "files", "--inputs", str(path),
                 "--ground-truth-field", "nosuch", "-k", "10", "--alpha", "0", "200",
                 "-o", str(out), "-j", "1", "-q"]) == 0
    captured = capsys.readouterr()
    assert "0 ok, 2 failed" in captured.out
    said = [ln for ln in captured.err.splitlines() if ln.startswith("failed:")]
    assert len(said) == 1 and said[0].startswith("failed: 2 rows: MeshFormatError:")
    assert "no field 'nosuch'" in said[0]


def test_report_refuses_a_focus_that_is_no_count(scan, tmp_path, capsys):
    path, _ = scan
    rows = tmp_path / "r.csv"
    assert main(["experiment", "--dataset", "files", "--inputs", str(path),
                 "--ground-truth-field", "classification", "-k", "10", "--alpha", "200",
                 "-o", str(rows), "-j", "1", "-q"]) == 0
    capsys.readouterr()  # (the roof floats 8 above the ground: no border, a warning says)
    assert main(["report", str(rows), "--k-focus", "-3", "-o", str(tmp_path / "rep")]) == 2
    _one_line_error(capsys, "k_focus")
    assert not (tmp_path / "rep").exists()


def _sphere_faces():
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=3)  # (1,280 faces: past 4 KiB of text)
    return m.vertices, m.faces


def test_an_ascii_stl_in_capitals_is_read_as_text(tmp_path):
    from superfacets import read_mesh

    v, f = _sphere_faces()
    lines = ["solid  part  "]
    for tri in f:
        lines += ["  FACET NORMAL 0 0 0", "\tOUTER LOOP"]
        lines += [f"    VERTEX {x:.6e} {y:.6e} {z:.6e}" for x, y, z in v[tri]]
        lines += ["\tENDLOOP", "  ENDFACET"]
    path = tmp_path / "part.stl"
    path.write_text("\n".join(lines + ["ENDSOLID part"]) + "\n")
    # (it was read as binary: "truncated binary STL: 808,281,400 triangles declared")
    assert read_mesh(path).n_faces == len(f)


def test_an_obj_line_continued_by_a_backslash_is_one_line(tmp_path):
    from superfacets import read_mesh

    v, f = _sphere_faces()
    text = "".join(f"v {x} {y} {z}\n" for x, y, z in v)
    text += "".join(f"f {a + 1}//1 {b + 1}//1 \\\n{c + 1}//1\n" for a, b, c in f[::2])
    text += "".join(f"f {a + 1} {b + 1} {c + 1}\r\n" for a, b, c in f[1::2])
    path = tmp_path / "long.obj"
    path.write_text("vn 0 0 1\n" + text)
    # (it said "face 0: malformed vertex index '\\'")
    mesh = read_mesh(path)
    assert mesh.n_faces == len(f)
    assert np.array_equal(np.asarray(mesh.faces), np.r_[f[::2], f[1::2]])


@pytest.mark.parametrize("faces", [False, True])
def test_a_ply_with_x_y_z_in_capitals_reads_as_with_x_y_z(tmp_path, faces):
    from plyfile import PlyData, PlyElement

    if faces:
        v, f = _sphere_faces()
    else:
        v = np.c_[np.random.default_rng(4).random((3000, 2)) * 5, np.zeros(3000)]
    for case, name in ((str.upper, "upper.ply"), (str.lower, "lower.ply")):
        vert = np.zeros(len(v), dtype=[(case(c), "f8") for c in "xyz"])
        for i, c in enumerate("xyz"):
            vert[case(c)] = v[:, i]
        elements = [PlyElement.describe(vert, "vertex")]
        if faces:
            rec = np.zeros(len(f), dtype=[("vertex_indices", "i4", (3,))])
            rec["vertex_indices"] = f
            elements.append(PlyElement.describe(rec, "face"))
        PlyData(elements).write(str(tmp_path / name))
    # (PDAL names its dimensions X, Y, Z; such a file was refused: "the vertex element has
    # no x, y, z property (it has: X, Y, Z)")
    for extra in ([], ["--tiles", "2", "--workers", "1"]):
        outs = []
        for name in ("upper.ply", "lower.ply"):
            out = tmp_path / f"{name}{len(extra)}.seg"
            assert main(["segment", str(tmp_path / name), "-k", "10", *extra, "-o", str(out),
                         "-q"]) == 0
            outs.append(out.read_bytes())
        assert outs[0] == outs[1]


def _splats(path, n=3000, normals=0.0):
    """A 3D Gaussian splatting PLY in miniature: positions, the zero normals such files
    carry, colour coefficients, opacity, scales and rotations."""
    from plyfile import PlyData, PlyElement

    names = ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2", "opacity",
             "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"]
    g = np.zeros(n, dtype=[(c, "<f4") for c in names])
    p = np.c_[np.random.default_rng(6).random((n, 2)) * 5, np.zeros(n)]
    g["x"], g["y"], g["z"] = p.T
    g["nz"] = normals
    PlyData([PlyElement.describe(g, "vertex")]).write(str(path))
    return path


def test_a_splat_file_s_zero_normals_are_estimated_one_run_and_tiles(tmp_path, capsys):
    path = _splats(tmp_path / "splats.ply")
    # (it said "normal 0 is zero or not finite ...; leave normals out to have them
    # estimated", which no option does)
    for extra in ([], ["--tiles", "2", "--workers", "1"]):
        out = tmp_path / f"s{len(extra)}.seg"
        assert main(["segment", str(path), "-k", "10", *extra, "-o", str(out), "-q"]) == 0
        assert "its normals are all zero or not finite" in capsys.readouterr().err
        assert len(np.unique(np.loadtxt(out))) == 10
    # the same labels as a file without normals, one run
    from plyfile import PlyData, PlyElement

    v = PlyData.read(str(path))["vertex"].data[["x", "y", "z"]]
    PlyData([PlyElement.describe(np.array(v.tolist(), dtype=[(c, "<f4") for c in "xyz"]),
                                 "vertex")]).write(str(tmp_path / "bare.ply"))
    assert main(["segment", str(tmp_path / "bare.ply"), "-k", "10", "-o",
                 str(tmp_path / "bare.seg"), "-q"]) == 0
    assert (tmp_path / "bare.seg").read_bytes() == (tmp_path / "s0.seg").read_bytes()


@pytest.mark.parametrize("tiles", [[], ["--tiles", "2", "--workers", "1"]])
def test_a_file_with_some_unusable_normals_has_them_all_estimated(tmp_path, capsys, tiles):
    path = _splats(tmp_path / "mixed.ply", normals=1.0)
    from plyfile import PlyData, PlyElement

    data = PlyData.read(str(path))["vertex"].data.copy()
    data["nz"][5] = 0.0  # (PCL's normal estimation leaves NaN where it cannot tell)
    data["nz"][9] = np.nan
    PlyData([PlyElement.describe(data, "vertex")]).write(str(path))
    # (it was refused: "normal 5 is zero or not finite; leave normals out", no option does)
    out = tmp_path / "m.seg"
    assert main(["segment", str(path), "-k", "10", *tiles, "-o", str(out), "-q"]) == 0
    err = capsys.readouterr().err
    assert "2 of its 3,000 normals are zero or not finite (the first: point 5)" in err
    assert len(np.unique(np.loadtxt(out))) == 10


@pytest.mark.parametrize("tiles", [[], ["--tiles", "2", "--workers", "1"]])
def test_a_ply_of_no_vertex_element_names_what_it_has(tmp_path, capsys, tiles):
    from plyfile import PlyData, PlyElement

    v = np.zeros(100, dtype=[(c, "<f4") for c in "xyz"])
    PlyData([PlyElement.describe(v, "point")]).write(str(tmp_path / "p.ply"))
    assert main(["segment", str(tmp_path / "p.ply"), "-k", "5", *tiles, "-o",
                 str(tmp_path / "p.seg")]) == 2
    _one_line_error(capsys, "no vertex element (it has: point)")  # (it said "'vertex'")


def test_a_dataframe_or_a_list_of_points_is_a_cloud():
    pd = pytest.importorskip("pandas")
    from superfacets import as_cloud, segment, superpoints

    base = np.c_[np.random.default_rng(7).random((2000, 2)), np.zeros(2000)]
    want = segment(base, 8).labels
    # (both were refused: "mesh must be ... (a point cloud: a PointCloud or an (N, 3)
    # array), got DataFrame" / "got list of 2000 items")
    assert np.array_equal(segment(base.tolist(), 8).labels, want)
    table = pd.DataFrame(base, columns=["X", "Y", "Z"])  # (PDAL's and laspy's names)
    assert np.array_equal(superpoints(table, 8), want)
    table["red"], table["green"], table["blue"] = 255, 0, 0
    table["intensity"] = 7
    cloud = as_cloud(table)
    assert np.allclose(cloud.colors, [1.0, 0.0, 0.0]) and cloud.normals is None
    with pytest.raises(TypeError, match="DataFrame of x, y, z columns.*columns a, b"):
        segment(pd.DataFrame({"a": [1.0], "b": [2.0]}), 1)
    # tiles too (their reader had a rule of its own)
    from superfacets import segment_tiled

    tiled = segment_tiled(base, 8, tiles=2, workers=1).labels
    for given in (table, base.tolist()):
        assert np.array_equal(segment_tiled(given, 8, tiles=2, workers=1).labels, tiled)


def _sweep(folder, name="000000"):
    """A KITTI velodyne sweep in miniature (float32 x y z reflectance, z up): road, a wall
    and a car, with its SemanticKITTI .label (class | instance << 16)."""
    from conftest import street_sweep

    xyz, part, rng = street_sweep(8, -1.7)
    np.c_[xyz, rng.random(len(xyz))].astype("<f4").tofile(folder / f"{name}.bin")
    cls = np.array([40, 50, 10], dtype=np.uint32)[part]
    (cls | (np.r_[np.zeros(11000), np.full(1500, 7)].astype(np.uint32) << 16)).astype(
        "<u4").tofile(folder / f"{name}.label")
    return folder / f"{name}.bin", folder / f"{name}.label", xyz


def test_a_kitti_sweep_and_its_semantickitti_labels_are_read(tmp_path, capsys):
    from superfacets import read_cloud, read_labels

    scan, truth, xyz = _sweep(tmp_path)
    cloud = read_cloud(scan)
    assert np.allclose(cloud.points, xyz.astype(np.float32)) and cloud.viewpoint is None
    assert np.allclose(cloud.up, [0, 0, 1])  # (seen from above, as a LAS tile)
    assert np.array_equal(np.unique(read_labels(truth)), [10, 40, 50])  # (the instance: out)
    out = tmp_path / "sweep.seg"
    assert main(["segment", str(scan), "-k", "60", "-o", str(out), "-q"]) == 0
    assert main(["evaluate", str(scan), str(out), str(truth), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["segments"] == 60 and got["oracle_miou"] > 0.9
    # labels as text in a .label would be read back as binary: refused
    assert main(["segment", str(scan), "-k", "6", "-o", str(tmp_path / "x.label")]) == 2
    _one_line_error(capsys, "SemanticKITTI's binary classes")


@pytest.mark.parametrize("content, says", [
    (b"\0" * 17, "not a whole number of points"),
    (np.c_[np.ones((50, 3)), np.full(50, 9.0)].astype("<f4").tobytes(), "fourth value is 9.0"),
])
def test_a_bin_that_is_no_kitti_sweep_is_refused(tmp_path, capsys, content, says):
    (tmp_path / "x.bin").write_bytes(content)
    assert main(["segment", str(tmp_path / "x.bin"), "-k", "3", "-o",
                 str(tmp_path / "x.seg")]) == 2
    _one_line_error(capsys, says)


def test_a_folder_s_bin_files_are_read_where_a_glob_names_them(tmp_path, capsys):
    (tmp_path / "velodyne").mkdir()
    for name in ("000000", "000001"):
        _sweep(tmp_path / "velodyne", name)
    assert main(["batch", str(tmp_path / "velodyne"), "-o", str(tmp_path / "a"), "-k", "20",
                 "--workers", "1", "-q"]) == 2
    _one_line_error(capsys, "4 other files", "name it (or a glob")  # (.bin, .label)
    assert main(["batch", str(tmp_path / "velodyne" / "*.bin"), "-o", str(tmp_path / "b"),
                 "-k", "20", "--workers", "1", "-q"]) == 0
    assert len(list((tmp_path / "b").rglob("*.seg"))) == 2
