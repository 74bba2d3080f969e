"""The faults of the sixth attack (street scans' files no command read; options and files
that a command took and then got wrong): each case fails without its fix."""

from __future__ import annotations

import json

import numpy as np
import pytest

from superfacets import read_cloud, read_labels, write_labels
from superfacets.cli import main
from superfacets.errors import MeshFormatError, ParameterError


def _one_line_error(capsys, *says):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("superfacets: error:"), err
    assert all(s in err[0] for s in says), err[0]


def _nuscenes(folder, name="n015__LIDAR_TOP__1532402927647951"):
    """A nuScenes lidar sweep in miniature (float32 x y z intensity ring, z up): road, a
    wall and a car, with its lidarseg classes (one uint8 a point)."""
    from conftest import street_sweep

    xyz, part, rng = street_sweep(5, -1.8)
    level = rng.integers(0, 256, len(xyz))
    ring = rng.integers(0, 32, len(xyz))
    np.c_[xyz, level, ring].astype("<f4").tofile(folder / f"{name}.pcd.bin")
    cls = np.array([24, 28, 17], dtype=np.uint8)[part]
    cls.tofile(folder / f"{name}_lidarseg.bin")
    return folder / f"{name}.pcd.bin", folder / f"{name}_lidarseg.bin", xyz


def test_a_nuscenes_sweep_and_its_lidarseg_classes_are_read(tmp_path, capsys):
    # (refused before: "a .pcd.bin (nuScenes: five float32 values a point) is not read")
    scan, truth, xyz = _nuscenes(tmp_path)
    cloud = read_cloud(scan)
    assert np.allclose(cloud.points, xyz.astype(np.float32)) and cloud.viewpoint is None
    assert np.allclose(cloud.up, [0, 0, 1])  # (seen from above, as a KITTI sweep)
    assert np.array_equal(np.unique(read_labels(truth, 12500)), [17, 24, 28])
    out = tmp_path / "sweep.seg"
    assert main(["segment", str(scan), "-k", "60", "-o", str(out), "-q"]) == 0
    assert main(["evaluate", str(scan), str(out), str(truth), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["segments"] == 60 and got["oracle_miou"] > 0.9
    # text in a .bin would be read back as binary classes: refused, as a .label is
    assert main(["segment", str(scan), "-k", "6", "-o", str(tmp_path / "x_lidarseg.bin")]) == 2
    _one_line_error(capsys, "not a .bin file")
    with pytest.raises(ParameterError, match="name the labels .seg"):
        write_labels(tmp_path / "y.bin", [0, 1])
    assert not (tmp_path / "y.bin").exists()


def test_labels_in_a_bin_other_than_lidarseg_are_refused(tmp_path):
    # (read before as text: "malformed label file", or numbers out of bytes)
    path = tmp_path / "semantic_mask.bin"
    np.arange(10, dtype=np.int64).tofile(path)
    with pytest.raises(MeshFormatError, match=r"named \*_lidarseg.bin"):
        read_labels(path)


@pytest.mark.parametrize("content, says", [
    (b"\0" * 21, "not a whole number of points"),
    # a KITTI sweep named .pcd.bin: 16 bytes a point (five of them read as four)
    (np.c_[np.ones((50, 3)), np.full(50, 0.5)].astype("<f4").tobytes(), "not a nuScenes"),
    (np.c_[np.ones((50, 3)), np.full(50, 9.0), np.full(50, 2.5)].astype("<f4").tobytes(),
     "ring 2.5"),
    (np.c_[np.ones((50, 3)), np.full(50, 300.0), np.full(50, 2.0)].astype("<f4").tobytes(),
     "intensity is 300.0"),
])
def test_a_pcd_bin_that_is_no_nuscenes_sweep_is_refused(tmp_path, capsys, content, says):
    (tmp_path / "x.pcd.bin").write_bytes(content)
    assert main(["segment", str(tmp_path / "x.pcd.bin"), "-k", "3", "-o",
                 str(tmp_path / "x.seg")]) == 2
    _one_line_error(capsys, says)
    assert not (tmp_path / "x.seg").exists()


def test_a_page_too_large_to_open_is_refused_before_the_run(tmp_path, capsys, monkeypatch):
    # (a mesh of more than ~33M triangles gave a page no browser opens, after the whole run)
    import trimesh

    import superfacets.api.segmentation as segmentation
    from superfacets.viz import html

    ball = trimesh.creation.icosphere(subdivisions=3)  # 1,280 triangles
    path = tmp_path / "ball.ply"
    ball.export(path)
    monkeypatch.setattr(html, "MAX_PAGE_TRIANGLES", 1000)

    def never(*a, **k):
        raise AssertionError("the run started")

    monkeypatch.setattr(segmentation, "segment", never)
    for elements in ("faces", "vertices"):
        assert main(["segment", str(path), "-k", "10", "--elements", elements,
                     "-o", str(tmp_path / "b.seg"), "--html", str(tmp_path / "b.html")]) == 2
        _one_line_error(capsys, "1,280 triangles would not open", "--picture")
    assert not list(tmp_path.glob("b.*"))
    with pytest.raises(ParameterError, match="would not open"):
        html.html_page(ball)
    monkeypatch.undo()
    (tmp_path / "b.seg").write_text("\n".join(["0"] * 1280))
    monkeypatch.setattr(html, "MAX_PAGE_TRIANGLES", 1000)
    assert main(["html", str(path), str(tmp_path / "b.seg"), "-o",
                 str(tmp_path / "b.html")]) == 2
    _one_line_error(capsys, "would not open")
    assert not (tmp_path / "b.html").exists()


def _organized_pcd(path, normals_nan_at_valid=False):
    """A 20 x 20 organized frame (a tilted plane) with PCL's normal fields; its first row
    invalid (NaN positions, NaN normals, as PCL writes them)."""
    u, v = np.meshgrid(np.arange(20.0), np.arange(20.0))
    xyz = np.c_[u.ravel() * 0.01, v.ravel() * 0.01, 1 + 0.005 * u.ravel()]
    nrm = np.tile([-0.5, 0.0, -1.0] / np.linalg.norm([0.5, 0, 1.0]), (400, 1))
    xyz[:20] = nrm[:20] = np.nan
    if normals_nan_at_valid:
        nrm[57] = np.nan
    head = ("VERSION 0.7\nFIELDS x y z normal_x normal_y normal_z\nSIZE 4 4 4 4 4 4\n"
            "TYPE F F F F F F\nCOUNT 1 1 1 1 1 1\nWIDTH 20\nHEIGHT 20\n"
            "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 400\nDATA ascii\n")
    body = "\n".join(" ".join("nan" if np.isnan(x) else f"{x:.6f}" for x in row)
                     for row in np.c_[xyz, nrm])
    path.write_text(head + body + "\n")
    return nrm


def test_a_pcd_s_normals_nan_at_its_invalid_points_are_read(tmp_path, recwarn):
    # (dropped before, silently, for any NaN: even only at the frame's invalid points,
    # where every other reader keeps them)
    path = tmp_path / "frame.pcd"
    nrm = _organized_pcd(path)
    cloud = read_cloud(path)
    assert cloud.normals is not None and not recwarn.list
    assert np.allclose(cloud.normals[20:], nrm[20:], atol=1e-6)
    # a NaN normal at a valid point (PCL could not estimate it): all estimated, said
    _organized_pcd(path, normals_nan_at_valid=True)
    with pytest.warns(UserWarning, match="1 of its 380 normals are zero or not finite"):
        assert read_cloud(path).normals is None


def _surface(n=3000):
    rng = np.random.default_rng(0)
    xy = rng.uniform(0, 10, (n, 2))
    return np.c_[xy, np.sin(xy[:, 0]) * 0.5]


def test_text_clouds_with_decimal_commas_or_quoted_fields_are_read(tmp_path, capsys):
    # ("the header names 3 columns (x y z), the lines have 6"; "point line 1 is not
    # numbers": a spreadsheet's CSV in a European locale, and a CSV of quoted fields)
    pts = _surface()
    plain = tmp_path / "plain.xyz"
    np.savetxt(plain, pts, fmt="%.5f")
    body = "".join(f"{a:.5f};{b:.5f};{c:.5f}\n".replace(".", ",") for a, b, c in pts)
    (tmp_path / "eu.csv").write_text("X;Y;Z\n" + body)
    (tmp_path / "eu_plain.txt").write_text(body)  # (no header either)
    (tmp_path / "quoted.csv").write_text('"x","y","z","Intensity"\n' + "".join(
        f'"{a:.5f}","{b:.5f}","{c:.5f}","5"\n' for a, b, c in pts))
    want = read_cloud(plain).points
    for name in ("eu.csv", "eu_plain.txt", "quoted.csv"):
        assert np.array_equal(read_cloud(tmp_path / name).points, want), name
    # a semicolon file of decimal points, a comma file: as before
    (tmp_path / "semi.csv").write_text("".join(f"{a:.5f};{b:.5f};{c:.5f}\n" for a, b, c in pts))
    assert np.array_equal(read_cloud(tmp_path / "semi.csv").points, want)
    labels = tmp_path / "eu.seg"
    assert main(["segment", str(tmp_path / "eu.csv"), "-k", "20", "-o", str(labels), "-q"]) == 0
    assert main(["segment", str(plain), "-k", "20", "-o", str(tmp_path / "p.seg"), "-q"]) == 0
    assert labels.read_text() == (tmp_path / "p.seg").read_text()


def test_obj_and_off_files_of_vertices_alone_are_point_clouds(tmp_path, capsys):
    # ("empty mesh: no faces": MeshLab saves a cloud as an OBJ or OFF of vertices)
    from superfacets import read_input, read_mesh
    from superfacets.errors import InvalidMeshError

    pts = _surface()
    rgb = np.tile([200, 100, 50], (len(pts), 1))
    (tmp_path / "c.obj").write_text("# cloud\n" + "".join(
        f"v {a:.5f} {b:.5f} {c:.5f} 0.8 0.4 0.2\n" for a, b, c in pts))
    (tmp_path / "c.off").write_text(f"COFF\n{len(pts)} 0 0\n" + "".join(
        f"{a:.5f} {b:.5f} {c:.5f} 200 100 50 255\n" for a, b, c in pts))
    (tmp_path / "n.off").write_text(f"NOFF {len(pts)} 0 0\n" + "".join(
        f"{a:.5f} {b:.5f} {c:.5f} 0 0 1\n" for a, b, c in pts))
    want = np.round(pts, 5)
    for name in ("c.obj", "c.off", "n.off"):
        cloud = read_input(tmp_path / name)
        assert type(cloud).__name__ == "PointCloud", name
        assert np.allclose(cloud.points, want), name
    assert np.allclose(read_input(tmp_path / "c.off").colors * 255, rgb)
    assert np.allclose(read_input(tmp_path / "c.obj").colors, [0.8, 0.4, 0.2])
    assert np.allclose(read_input(tmp_path / "n.off").normals, [0, 0, 1])
    assert main(["segment", str(tmp_path / "c.obj"), "-k", "20", "-o",
                 str(tmp_path / "c.seg"), "-q"]) == 0
    assert len((tmp_path / "c.seg").read_text().split()) == len(pts)
    # a mesh stays a mesh (its faces after its vertices, or indented), and a file of
    # neither vertices nor faces is still refused as an empty mesh
    tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
    for name, text in (("m.obj", tri + "f 1 2 3\n"), ("i.obj", tri + "  f\t1 2 3\n")):
        (tmp_path / name).write_text(text)
        assert type(read_input(tmp_path / name)).__name__ == "Mesh", name
    (tmp_path / "e.obj").write_text("# nothing\n")
    with pytest.raises(InvalidMeshError, match="no faces"):
        read_input(tmp_path / "e.obj")
    with pytest.raises(InvalidMeshError, match="no faces"):
        read_mesh(tmp_path / "c.off")


def test_spreadsheet_and_survey_csv_files_are_read(tmp_path):
    # (a BOM: "point line 1 is not numbers: '\ufeffx y z'"; a header in a Windows code
    # page: "not a text file (binary data)"; Easting, Northing, Elevation: "not numbers")
    pts = _surface()
    body = "".join(f"{a:.5f},{b:.5f},{c:.5f},1\n" for a, b, c in pts)
    (tmp_path / "bom.csv").write_text("x,y,z,i\n" + body, encoding="utf-8-sig")
    (tmp_path / "cp.csv").write_bytes("x,y,z,Höhe\n".encode("cp1252") + body.encode())
    (tmp_path / "survey.csv").write_text("Easting,Northing,Elevation,Code\n" + body)
    (tmp_path / "both.csv").write_text("Height,X,Y,Z\n" + "".join(
        f"9,{a:.5f},{b:.5f},{c:.5f}\n" for a, b, c in pts))  # (z named: height is not z)
    want = np.round(pts, 5)
    for name in ("bom.csv", "cp.csv", "survey.csv", "both.csv"):
        assert np.allclose(read_cloud(tmp_path / name).points, want, atol=1e-9), name
    # binary data in a text format is still refused as such
    (tmp_path / "bin.xyz").write_bytes(b"\x00\xff\x10" * 50)
    with pytest.raises(MeshFormatError, match="not a text file"):
        read_cloud(tmp_path / "bin.xyz")


def test_evaluate_with_no_ground_truth_measures_the_shapes(tmp_path, capsys):
    # (refused before: "give a ground truth", though the compactness and the sizes, what a
    # user with an unlabelled scan can know of a result, need none)
    from superfacets.evaluation.metrics import evaluate_rows, shape_rows

    pts = _surface()
    path = tmp_path / "s.xyz"
    np.savetxt(path, pts)
    labels = tmp_path / "s.seg"
    assert main(["segment", str(path), "-k", "20", "-o", str(labels), "-q"]) == 0
    truth = (pts[:, 0] > 5).astype(int)
    full = evaluate_rows(read_cloud(path), read_labels(labels), [truth])
    shapes = shape_rows(read_cloud(path), read_labels(labels))
    assert shapes["compactness"] == full["compactness"] and shapes["segments"] == 20
    assert all(shapes[k] == full[k] for k in ("size_min", "size_median", "size_max"))
    capsys.readouterr()
    assert main(["evaluate", str(path), str(labels)]) == 0
    out = capsys.readouterr().out
    assert "20 superpoints, no ground truths" in out
    assert f"compactness             {full['compactness']:.4f}" in out
    assert "undersegmentation_error" not in out and "only the shapes are measured" in out
    assert main(["evaluate", str(path), str(labels), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["undersegmentation_error"] is None and got["ground_truths"] == 0
    assert got["compactness"] == pytest.approx(full["compactness"])
    assert main(["evaluate", str(path), str(labels), "--csv"]) == 0
    assert capsys.readouterr().out.splitlines()[1].count(",,") >= 1


def test_a_leica_pts_file_s_colours_are_read(tmp_path):
    # (its seven columns, x y z intensity r g b, were read as positions alone)
    import gzip

    pts = _surface(500)
    rgb = np.random.default_rng(1).integers(0, 256, (500, 3))
    text = f"{len(pts)}\n" + "".join(f"{a:.5f} {b:.5f} {c:.5f} -1200 {r} {g} {bl}\n"
                                     for (a, b, c), (r, g, bl) in zip(pts, rgb))
    (tmp_path / "scan.pts").write_text(text)
    (tmp_path / "scan.pts.gz").write_bytes(gzip.compress(text.encode()))
    for name in ("scan.pts", "scan.pts.gz"):
        cloud = read_cloud(tmp_path / name)
        assert np.allclose(cloud.colors * 255, rgb) and np.allclose(cloud.points, pts,
                                                                    atol=1e-5), name
    # seven columns of something else (not whole numbers in 0..255), or an .xyz: positions
    (tmp_path / "other.pts").write_text("".join(f"{a:.5f} {b:.5f} {c:.5f} 1 0.1 0.2 0.3\n"
                                                for a, b, c in pts))
    assert read_cloud(tmp_path / "other.pts").colors is None
    # (in another text file the same layout, its intensity signed: test_hardening_round8)


def test_tiles_take_an_organized_npy_and_one_with_normals(tmp_path):
    # ("a tiled run reads NPY points of shape (N, 3)": one run takes (H, W, 3) and (N, 6))
    from superfacets import segment, segment_tiled

    rng = np.random.default_rng(0)
    u, v = np.meshgrid(np.linspace(0, 4, 60), np.linspace(0, 3, 45))
    frame = np.dstack([u, v, 0.2 * np.sin(3 * u)])
    frame[rng.random((45, 60)) < 0.05] = np.nan
    np.save(tmp_path / "frame.npy", frame)
    holes = np.isnan(frame.reshape(-1, 3)).any(axis=1)
    tiled = segment_tiled(tmp_path / "frame.npy", 20, tiles=2)
    assert tiled.labels.shape == (2700,) and np.array_equal(tiled.labels < 0, holes)
    assert tiled.n_segments == 20 and tiled.disagreements == 0
    pts = frame.reshape(-1, 3)[~holes]
    np.save(tmp_path / "normals.npy", np.c_[pts, np.tile([0.0, 0.0, 1.0], (len(pts), 1))])
    assert segment_tiled(tmp_path / "normals.npy", 20, tiles=2).n_segments == 20
    assert segment(tmp_path / "normals.npy", 20).n_segments == 20


@pytest.mark.parametrize("when", ["during the commit", "after the commit"])
def test_a_ctrl_c_once_the_outputs_are_written_does_not_report_an_interruption(
        tmp_path, monkeypatch, when):
    # (CI, 2026-11-30: a Ctrl-C landing between the last rename and the command's summary
    # exited 130, "interrupted", with its outputs written; one during the renames could
    # leave some of them written and not the others)
    import os
    import signal

    import superfacets.cli.segmenting as segmenting
    from superfacets.io.files import Outputs

    def ctrl_c():
        os.kill(os.getpid(), signal.SIGINT)

    if when == "during the commit":
        commit = Outputs._commit

        def interrupted(self):
            ctrl_c()
            commit(self)

        monkeypatch.setattr(Outputs, "_commit", interrupted)
    else:
        say = segmenting._say_what_was_written
        monkeypatch.setattr(segmenting, "_say_what_was_written",
                            lambda *a, **k: (ctrl_c(), say(*a, **k)))
    path = tmp_path / "s.xyz"
    np.savetxt(path, _surface(800))
    argv = ["segment", str(path), "-k", "8", "-o", str(tmp_path / "s.seg"),
            "--colored-mesh", str(tmp_path / "s.ply")]
    assert main(argv) == 0
    assert len(read_labels(tmp_path / "s.seg")) == 800 and (tmp_path / "s.ply").is_file()


def test_labels_to_a_full_standard_output_say_so_in_one_line(tmp_path):
    # ("[Errno 28] No space left on device": `segment ... -o - > file` on a full disk)
    import os
    import subprocess
    import sys

    if not os.path.exists("/dev/full"):
        pytest.skip("/dev/full not found (Linux's always-full device)")
    path = tmp_path / "s.xyz"
    np.savetxt(path, _surface(500))
    with open("/dev/full", "w") as full:
        run = subprocess.run([sys.executable, "-m", "superfacets", "segment", str(path), "-k",
                              "5", "-o", "-"], stdout=full, stderr=subprocess.PIPE, text=True,
                             timeout=120)
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [
        "superfacets: error: standard output: No space left on device"]


def test_labels_as_numpy_arrays_are_written_and_read(tmp_path, capsys):
    # (-o x.npy: "-o writes the labels as text ..., not a .npy file"; a ground truth kept
    # as a learning pipeline's .npy: "not a text file (binary data in a text format)")
    pts = _surface(600)
    path = tmp_path / "s.xyz"
    np.savetxt(path, pts)
    assert main(["segment", str(path), "-k", "6", "-o", str(tmp_path / "s.npy"), "-q"]) == 0
    assert main(["segment", str(path), "-k", "6", "-o", str(tmp_path / "s.seg"), "-q"]) == 0
    got = np.load(tmp_path / "s.npy")
    assert got.dtype == np.int64 and np.array_equal(got, read_labels(tmp_path / "s.seg"))
    truth = (pts[:, 0] > 5).astype(np.int32)
    for name, arr in (("flat", truth), ("column", truth[:, None]),
                      ("grid", truth.reshape(20, 30)), ("float", truth.astype(float))):
        np.save(tmp_path / f"{name}.npy", arr)
        assert np.array_equal(read_labels(tmp_path / f"{name}.npy", 600), truth), name
    assert main(["evaluate", str(path), str(tmp_path / "s.npy"), str(tmp_path / "flat.npy"),
                 "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["segments"] == 6
    for arr, says in ((np.full(600, 0.5), "whole numbers"), (pts, "one integer per element"),
                      (np.array(["a"] * 600), "must be integers")):
        np.save(tmp_path / "bad.npy", arr)
        with pytest.raises(MeshFormatError, match=says):
            read_labels(tmp_path / "bad.npy")
    assert main(["batch", str(path), "-o", str(tmp_path / "b"), "-k", "6", "--labels", "npy",
                 "--workers", "1", "-q"]) == 0
    assert np.array_equal(np.load(tmp_path / "b" / "s.npy"), got)


@pytest.mark.parametrize("args, says", [
    (["-o", "{d}/h.json"], "h.json holds none"),
    (["-o", "{d}/h.npy"], "h.npy holds none"),
    (["-o", "{d}/h.laz"], "h.laz holds none"),
    (["--picture", "{d}/h.png"], "give -o OUT.seg"),
    (["-o", "{d}/h.seg", "--tiles", "2"], "a tiled run writes the labels alone"),
])
def test_header_where_no_text_label_file_is_written_is_refused(tmp_path, capsys, args, says):
    # (taken and ignored: no '#' line anywhere)
    path = tmp_path / "s.xyz"
    np.savetxt(path, _surface(400))
    argv = ["segment", str(path), "-k", "5", "--header",
            *[a.replace("{d}", str(tmp_path)) for a in args]]
    assert main(argv) == 2
    _one_line_error(capsys, says)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.xyz"]


def test_a_batch_header_with_labels_other_than_text_is_refused(tmp_path, capsys):
    path = tmp_path / "s.xyz"
    np.savetxt(path, _surface(400))
    assert main(["batch", str(path), "-o", str(tmp_path / "b"), "-k", "5", "--labels", "npy",
                 "--header"]) == 2
    _one_line_error(capsys, "--labels npy) writes none")
    assert main(["batch", str(path), "-o", str(tmp_path / "c"), "-k", "5", "--header",
                 "--workers", "1", "-q"]) == 0
    assert (tmp_path / "c" / "s.seg").read_text().startswith("#")


@pytest.mark.parametrize("cmd, args, says", [
    ("segment", ["--neighbors", "12"], "--neighbors shapes a point cloud's graph"),
    ("segment", ["--neighbor-radius", "0.1"], "elements are faces"),
    ("segment", ["--elements", "vertices", "--neighbors", "4"], "elements are vertices"),
    ("evaluate", ["--neighbors", "5"], "--neighbors shapes"),
])
def test_a_cloud_s_neighbourhood_given_for_a_mesh_is_refused(tmp_path, capsys, cmd, args,
                                                             says):
    # (taken and ignored: a mesh's faces and vertices have its edges for a graph)
    import trimesh

    path = tmp_path / "ball.off"
    trimesh.creation.icosphere(subdivisions=2).export(path)
    labels = tmp_path / "b.seg"
    assert main(["segment", str(path), "-k", "6", "-o", str(labels), "-q"]) == 0
    argv = ["segment", str(path), "-k", "6", "-o", str(tmp_path / "c.seg")] \
        if cmd == "segment" else ["evaluate", str(path), str(labels), str(labels)]
    assert main(argv + args) == 2
    _one_line_error(capsys, says)
    assert not (tmp_path / "c.seg").exists()


@pytest.mark.parametrize("cmd, args, says", [
    ("render", ["{d}/b.seg", "--alpha", "300"], "--alpha segments the input"),
    ("render", ["{d}/b.seg", "-k", "40"], "-k segments the input"),
    ("render", ["--plain", "--tol", "0.1"], "--tol segments"),
    ("html", ["{d}/b.seg", "--no-connectivity"], "--no-connectivity segments"),
    ("render", ["{d}/b.seg", "--no-boundaries", "--line-width", "3"], "not with --no-bound"),
    ("panel", ["--labels", "{d}/b.seg", "--alpha", "300"], "--alpha chooses the runs"),
    ("panel", ["--labels", "{d}/b.seg", "-k", "9", "12"], "-k chooses the runs"),
])
def test_options_a_drawing_of_given_labels_would_ignore_are_refused(tmp_path, capsys, cmd,
                                                                    args, says):
    # (taken and ignored: the labels given were drawn as they were)
    import trimesh

    path = tmp_path / "ball.off"
    trimesh.creation.icosphere(subdivisions=2).export(path)
    assert main(["segment", str(path), "-k", "6", "-o", str(tmp_path / "b.seg"), "-q"]) == 0
    out = tmp_path / ("p.html" if cmd == "html" else "p.png")
    if cmd != "html":
        pytest.importorskip("pyvista")
    argv = [cmd, str(path), *[a.replace("{d}", str(tmp_path)) for a in args], "-o", str(out)]
    assert main(argv) == 2
    _one_line_error(capsys, says)
    assert not out.exists()


def test_options_of_what_is_not_written_are_refused(tmp_path, capsys):
    # (taken and ignored: `evaluate --tau` or `--ignore-label` with no ground truth, whose
    # shapes alone are measured; `batch --vertex-colors` with no coloured PLY)
    path = tmp_path / "s.xyz"
    np.savetxt(path, _surface(400))
    labels = tmp_path / "s.seg"
    assert main(["segment", str(path), "-k", "5", "-o", str(labels), "-q"]) == 0
    for extra, says in ((["--tau", "0.1"], "--tau judges"),
                        (["--ignore-label", "0"], "--ignore-label judges")):
        assert main(["evaluate", str(path), str(labels), *extra]) == 2
        _one_line_error(capsys, says, "give GT.seg files")
    assert main(["batch", str(path), "-o", str(tmp_path / "b"), "-k", "5",
                 "--vertex-colors"]) == 2
    _one_line_error(capsys, "--colored-mesh ply")
    assert not (tmp_path / "b").exists()


@pytest.mark.parametrize("extra, says", [
    (["--rooms", "3"], "--rooms goes with --dataset rooms"),
    (["--ids", "1-3"], "--ids selects or samples the benchmark's meshes"),
    (["--categories", "Human", "--per-category", "2"], "--categories, --per-category"),
    (["--points", "5000"], "not with --dataset files"),
    (["--tau", "0.1"], "--tau judges against a ground truth"),
])
def test_an_experiment_on_files_refuses_other_datasets_options(tmp_path, capsys, extra, says):
    # (taken and ignored: the benchmark's selection and sampling, the rooms' count, a
    # tolerance with no ground truth)
    folder = tmp_path / "in"
    folder.mkdir()
    np.savetxt(folder / "s.xyz", _surface(400))
    out = tmp_path / "rows.csv"
    assert main(["experiment", "--inputs", str(folder), "-k", "5", "--alpha", "200", "-o",
                 str(out), "-j", "1", "-q", *extra]) == 2
    _one_line_error(capsys, says)
    assert not out.exists()


def test_labels_saved_by_numpy_savetxt_s_default_are_read(tmp_path):
    # ("could not convert string '0.000000000000000000e+00' to int64": np.savetxt(labels)
    # writes floats unless told otherwise)
    truth = np.arange(30) % 4
    np.savetxt(tmp_path / "gt.txt", truth)
    assert np.array_equal(read_labels(tmp_path / "gt.txt", 30), truth)
    (tmp_path / "half.txt").write_text("1.5\n2\n")
    with pytest.raises(MeshFormatError, match="malformed label file"):
        read_labels(tmp_path / "half.txt")
