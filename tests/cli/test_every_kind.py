"""Every command takes every kind of input: meshes, point clouds (every format 'segment'
reads) and tetrahedral meshes, where the command has something to do with it."""

from __future__ import annotations

import csv
import json
import re

import numpy as np
import pytest

from superfacets.cli import main

laspy = pytest.importorskip("laspy")


def _laz(path, n=3000, seed=0):
    rng = np.random.default_rng(seed)
    las = laspy.create(point_format=3, file_version="1.4")
    las.header.scales = [0.01] * 3
    xy = rng.random((n, 2)) * [40.0, 20.0]
    las.x, las.y = xy.T
    las.z = np.where(xy[:, 0] > 20, 2.0, 0.0) + 0.5 * np.sin(xy[:, 1])
    las.classification = np.where(xy[:, 0] > 20, 6, 2).astype(np.uint8)
    las.write(str(path))
    return path


def _tets(path):
    meshio = pytest.importorskip("meshio")
    from scipy.spatial import Delaunay

    p = np.random.default_rng(0).random((300, 3))
    meshio.write(str(path), meshio.Mesh(p, [("tetra", Delaunay(p).simplices)]))
    return path


def test_render_and_html_draw_clouds_and_tetrahedral_meshes(tmp_path, capsys):
    pytest.importorskip("pyvista")
    laz = _laz(tmp_path / "tile.laz")
    assert main(["render", str(laz), "-k", "12", "-o", str(tmp_path / "t.png"),
                 "--size", "320x240"]) == 0
    said = capsys.readouterr().out
    assert "3,000 points" in said and "up axis z" in said
    vol = _tets(tmp_path / "v.vtu")
    assert main(["render", str(vol), "-k", "6", "-o", str(tmp_path / "v.png"),
                 "--size", "320x240"]) == 0
    assert "tetrahedra" in capsys.readouterr().out
    assert main(["html", str(vol), "-k", "6", "-o", str(tmp_path / "v.html")]) == 0
    assert (tmp_path / "v.html").stat().st_size > 1000
    labels = tmp_path / "v.seg"  # labels of the tetrahedra, from a file
    assert main(["segment", str(vol), "-k", "6", "-o", str(labels), "-q"]) == 0
    assert main(["html", str(vol), str(labels), "-o", str(tmp_path / "w.html")]) == 0
    # labels that fit no kind of the input: one line saying what is needed
    (tmp_path / "bad.seg").write_text("0\n1\n")
    assert main(["render", str(laz), str(tmp_path / "bad.seg"), "-o",
                 str(tmp_path / "x.png")]) == 2
    assert "2 labels, but" in capsys.readouterr().err and not (tmp_path / "x.png").exists()




def test_segment_writes_a_volume_s_graph_levels_and_page(tmp_path, capsys):
    """``segment VOLUME --graph --levels --html`` as on a mesh: the graph of the
    superfacets of tetrahedra (their learning layout, the levels' parents and labels), the
    page of the volume cut in half as ``html`` draws it; what a volume cannot take is
    refused before the run, the options it does take are not silently dropped."""
    pytest.importorskip("pyvista")
    from superfacets import segment
    from superfacets.io.tetmeshes import read_volume

    vol = _tets(tmp_path / "v.vtu")
    graph, page = tmp_path / "g.npz", tmp_path / "v.html"
    assert main(["segment", str(vol), "-k", "12", "--graph", str(graph), "--levels", "6,3",
                 "--html", str(page), "-o", str(tmp_path / "v.seg")]) == 0
    said = capsys.readouterr().out
    assert "superfacet graph, levels 6,3" in said and "page of the volume" in said
    arrays = np.load(graph)
    labels = np.loadtxt(tmp_path / "v.seg", dtype=np.int64)
    data = read_volume(vol)
    assert np.array_equal(arrays["labels"], labels)
    assert np.array_equal(labels, segment(data, 12).labels)
    assert list(arrays["levels"]) == [6, 3] and arrays["x"].shape[0] == 12
    assert len(np.unique(arrays["labels_0"])) == 6 and len(np.unique(arrays["labels_1"])) == 3
    # each level's labels are the parents of the finer ones
    assert np.array_equal(arrays["labels_0"], arrays["parent_0"][labels])
    from superfacets.elements.cells import cell_graph

    pairs = {(min(i, j), max(i, j)) for i, j in arrays["edge_index"].T.tolist()}
    g = cell_graph(data)
    a, b = labels[g.pairs[:, 0]], labels[g.pairs[:, 1]]
    touching = {(min(x, y), max(x, y)) for x, y in zip(a.tolist(), b.tolist()) if x != y}
    assert pairs == touching  # the graph's edges: the superfacets sharing a triangle
    assert b"<html" in page.read_bytes()[:2000].lower()
    # the options that need more than a count, or a surface, say so; nothing is written
    for extra, words in ((["-k", "12", "--levels", "4", "-o", str(tmp_path / "x.seg")],
                          "--graph"),
                         (["--seed-resolution", "0.2", "-o", str(tmp_path / "x.seg")],
                          "takes a count"),
                         (["-k", "12", "--level-cost", "planarity", "-o",
                           str(tmp_path / "x.seg")], "--levels"),
                         (["-k", "12", "--graph", str(tmp_path / "x.npz"), "--levels", "20"],
                          "at most")):
        assert main(["segment", str(vol), *extra]) == 2, extra
        assert words in capsys.readouterr().err, extra
        assert not (tmp_path / "x.seg").exists() and not (tmp_path / "x.npz").exists()


def test_a_panel_of_a_tile_is_a_map_with_every_panel_drawn(tmp_path, capsys):
    """A LAS tile's panels are seen from above, as ``render`` draws it; eye-dome lighting
    (a whole window's pass) left all panels but the last blank."""
    pytest.importorskip("pyvista")
    from PIL import Image

    laz = _laz(tmp_path / "tile.laz")
    out = tmp_path / "p.png"
    assert main(["panel", str(laz), "-k", "10", "30", "-o", str(out), "--size", "300x200"]) == 0
    img = np.asarray(Image.open(out).convert("RGB")).astype(int)
    for half in (img[:, :300], img[:, 300:]):  # each panel: mostly points, not background
        assert (np.abs(half - 255).sum(axis=2) > 60).mean() > 0.3



def test_a_panel_draws_a_scan_s_own_fields_side_by_side(tmp_path, capsys, monkeypatch):
    """``panel SCAN --labels-from ClusterID ClusterID_3 classification``: the labels and
    levels ``segment -o`` wrote into the scan, and its classes, a panel each (it took label
    files only); a field it lacks, or a run's option beside them, is one line; nothing
    drawn."""
    pytest.importorskip("pyvista")
    import superfacets.viz.render as render_module

    laz, out = _laz(tmp_path / "tile.laz"), tmp_path / "with.laz"
    assert main(["segment", str(laz), "-k", "12", "--levels", "6,3", "-o", str(out), "-q"]) == 0
    drawn = []
    real = render_module.render_panel

    def spy(items, path, **kw):
        drawn.extend(items)
        return real(items, path, **kw)

    monkeypatch.setattr(render_module, "render_panel", spy)
    png = tmp_path / "p.png"
    assert main(["panel", str(out), "--labels-from", "ClusterID", "ClusterID_3",
                 "classification", "-o", str(png), "--size", "300x200"]) == 0
    assert "3 panels" in capsys.readouterr().out and png.stat().st_size > 0
    f = laspy.read(str(out))
    assert [t for _, _, t in drawn] == ["ClusterID", "ClusterID_3", "classification"]
    for (_, labels, _), field in zip(drawn, ("ClusterID", "ClusterID_3", "classification")):
        assert np.array_equal(labels, np.asarray(f[field]))
    assert len(np.unique(drawn[1][1])) == 3
    png.unlink()
    for extra, words in ((["--labels-from", "nope"], "no field 'nope'"),
                         (["--labels-from", "ClusterID", "-k", "5"], "leave them out")):
        assert main(["panel", str(out), *extra, "-o", str(png)]) == 2
        assert words in capsys.readouterr().err and not png.exists()


def test_view_opens_clouds_meshes_and_volumes(tmp_path, monkeypatch, sphere):
    """``view`` read meshes alone ("unknown mesh format .laz"); a cloud is drawn as its
    points, a volume as its cut. (The window replaced by an off-screen picture.)"""
    pv = pytest.importorskip("pyvista")
    import superfacets.viz.render as render
    from superfacets import write_mesh

    shown = []
    real = render._pyvista
    monkeypatch.setattr(render, "has_display", lambda: True)
    monkeypatch.setattr(render, "_pyvista", lambda off_screen: real(True))
    monkeypatch.setattr(pv.Plotter, "__init__", _off_screen_init(pv.Plotter.__init__))
    monkeypatch.setattr(pv.Plotter, "show", lambda self, *a, **k: shown.append(
        self.screenshot(return_img=True)))
    write_mesh(tmp_path / "ball.off", sphere)
    for path in (_laz(tmp_path / "tile.laz"), tmp_path / "ball.off", _tets(tmp_path / "v.vtu")):
        assert main(["view", str(path), "-k", "8"]) == 0, path
        img = shown[-1]
        assert img.ndim == 3 and (img.reshape(-1, 3).std(axis=0) > 5).any(), path
    assert len(shown) == 3


def _off_screen_init(init):
    def off_screen(self, *args, **kwargs):
        kwargs["off_screen"] = True
        init(self, *args, **kwargs)
    return off_screen


def test_evaluate_prints_json_and_csv_for_scripts(tmp_path, capsys):
    laz = _laz(tmp_path / "tile.laz")
    seg = tmp_path / "t.seg"
    assert main(["segment", str(laz), "-k", "20", "-o", str(seg), "-q"]) == 0
    assert main(["evaluate", str(laz), str(seg), "--ground-truth-field", "classification",
                 "--csv"]) == 0
    rows = list(csv.DictReader(capsys.readouterr().out.splitlines()))
    assert len(rows) == 1 and rows[0]["elements"] == "points"
    assert int(rows[0]["n_elements"]) == 3000 and int(rows[0]["segments"]) == 20
    assert main(["evaluate", str(laz), str(seg), "--ground-truth-field", "classification",
                 "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["undersegmentation_error"] == pytest.approx(
        float(rows[0]["undersegmentation_error"]))
    # two terraces, two classes, 20 superpoints: the majority labelling is nearly exact
    assert got["oracle_miou"] > 0.9 and set(got["oracle_iou_per_class"]) == {"2", "6"}
    assert got["size_min"] <= got["size_median"] <= got["size_max"]
    assert sum(got["size_histogram"]) == 20 and got["unassigned"] == 0
    # labels below 0 (DBSCAN's noise): counted as segments by the metrics and the sizes
    # alike (the sizes left them out: 5 segments, a histogram of 4), and said
    noisy = tmp_path / "noisy.seg"
    noisy.write_text("\n".join(str(i % 5 - 1) for i in range(3000)) + "\n")
    assert main(["evaluate", str(laz), str(noisy), "--ground-truth-field", "classification",
                 "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["segments"] == 5 == sum(got["size_histogram"]) and got["unassigned"] == 600
    assert main(["evaluate", str(laz), str(noisy), "--ground-truth-field",
                 "classification"]) == 0
    assert "note: 600 points labelled below 0 (unassigned)" in capsys.readouterr().out
    with pytest.raises(SystemExit) as stop:  # one of them (argparse says so)
        main(["evaluate", str(laz), str(seg), "--json", "--csv"])
    assert stop.value.code == 2 and "not allowed with" in capsys.readouterr().err


def test_baseline_runs_the_point_methods_on_a_laz(tmp_path, capsys):
    laz = _laz(tmp_path / "tile.laz")
    for method in ("graph_segmentation", "cut_pursuit"):
        out = tmp_path / f"{method}.laz"
        assert main(["baseline", str(laz), "-m", method, "-k", "15", "-o", str(out)]) == 0
        said = capsys.readouterr().out
        assert "3,000 points" in said  # (and its segments), and what it wrote, as segment
        assert f"wrote {out} (the input's points, every field kept, labels as ClusterID)" \
            in said
        labels = np.asarray(laspy.read(out).ClusterID)
        assert 10 <= len(np.unique(labels)) <= 20
    assert main(["baseline", str(laz), "-m", "vsa", "-k", "15"]) == 2
    err = capsys.readouterr().err
    assert "vsa segments faces, not points" in err and "cut_pursuit" in err


def test_baseline_draws_its_result_as_segment_does(tmp_path, capsys, sphere):
    """``baseline`` wrote labels and a coloured mesh only ("unrecognized arguments:
    --picture"): its picture and page now, checked before the run as segment's."""
    pytest.importorskip("pyvista")
    from PIL import Image

    from superfacets import write_mesh

    laz = _laz(tmp_path / "tile.laz")
    png, page = tmp_path / "g.png", tmp_path / "g.html"
    assert main(["baseline", str(laz), "-m", "graph_segmentation", "-k", "15", "--picture",
                 str(png), "--html", str(page), "--view", "top"]) == 0
    said = capsys.readouterr().out
    assert f"{png} (picture, up axis z" in said and f"{page} (page" in said
    img = np.asarray(Image.open(png).convert("RGB"))
    assert np.unique(img.reshape(-1, 3), axis=0).shape[0] > 15  # (coloured by segment)
    assert '"points": 3000' in page.read_text()
    write_mesh(tmp_path / "ball.off", sphere)
    assert main(["baseline", str(tmp_path / "ball.off"), "-m", "vsa", "-k", "6", "--picture",
                 str(tmp_path / "v.png"), "-q"]) == 0
    assert Image.open(tmp_path / "v.png").size == (1200, 900)
    for extra, says in ((["--view", "top"], "--view chooses the camera of --picture"),
                        (["--picture", str(png), "--colored-mesh", str(png)],
                         "must end in .ply")):
        assert main(["baseline", str(laz), "-m", "graph_segmentation", *extra]) == 2
        assert says in capsys.readouterr().err


def test_experiment_runs_on_a_user_s_files(tmp_path, capsys, sphere):
    from superfacets import write_mesh

    laz = _laz(tmp_path / "tile.laz")
    write_mesh(tmp_path / "ball.off", sphere)
    out = tmp_path / "rows.csv"
    assert main(["experiment", "--inputs", str(laz), "--ground-truth-field", "classification",
                 "-m", "superfacets", "-m", "graph_segmentation", "-k", "10", "30",
                 "--alpha", "200", "--elements", "points", "-o", str(out), "-j", "1",
                 "-q"]) == 0
    rows = list(csv.DictReader(out.open()))
    assert {(r["method"], r["n_segments"]) for r in rows} == {
        (m, k) for m in ("superfacets", "graph_segmentation") for k in ("10", "30")}
    assert all(r["status"] == "ok" and r["elements"] == "points" for r in rows)
    assert all(0 <= float(r["undersegmentation_error"]) < 1 for r in rows)
    assert all(0.9 < float(r["oracle_miou"]) <= 1 for r in rows)  # two terraces, two classes
    mesh_rows = tmp_path / "mesh.csv"
    assert main(["experiment", "--inputs", str(tmp_path / "ball.off"), "-k", "12",
                 "--alpha", "200", "-o", str(mesh_rows), "-j", "1", "-q"]) == 0
    (row,) = list(csv.DictReader(mesh_rows.open()))
    assert row["status"] == "ok" and row["elements"] == "faces" and row["segments"] == "12"
    capsys.readouterr()
    assert main(["experiment", "--ground-truth-field", "x", "-o", str(out)]) == 2
    assert "goes with --inputs" in capsys.readouterr().err



def test_evaluate_names_a_las_file_s_asprs_classes(tmp_path, capsys):
    """Against a LAS file's ``classification`` each class's IoU is named as the ASPRS
    table names it (ground, building); another field's classes are numbers alone."""
    laz = _laz(tmp_path / "tile.laz")
    labels = tmp_path / "tile.seg"
    assert main(["segment", str(laz), "-k", "20", "-o", str(labels), "-q"]) == 0
    capsys.readouterr()
    assert main(["evaluate", str(laz), str(labels), "--ground-truth-field",
                 "classification"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"class 2 +ground +IoU [01]\.\d{4}", out), out
    assert re.search(r"class 6 +building +IoU [01]\.\d{4}", out), out
    assert main(["evaluate", str(laz), str(labels), "--ground-truth-field",
                 "classification", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["class_names"] == {"2": "ground",
                                                                   "6": "building"}
    assert main(["evaluate", str(laz), str(labels), "--ground-truth-field",
                 "point_source_id"]) == 0  # (every point 0: one class, unnamed)
    assert re.search(r"class 0 +IoU 1\.0000", capsys.readouterr().out)  # (no name)


def test_an_experiment_segments_a_scan_as_seen_from_an_axis(tmp_path, capsys):
    """``experiment --inputs --seen-from z``: each cloud run as ``segment --seen-from z`` runs
    it (the same error as ``evaluate`` of those labels), the rows saying so; another axis or
    none into the same file adds rows, the same one again none."""
    rng = np.random.default_rng(0)
    x, y = rng.random((2, 4000)) * [[40], [10]]
    z = np.where(x > 20, 0.15, 0.0) + 0.01 * rng.standard_normal(4000)  # a curb, two classes
    street = tmp_path / "street.xyz"
    np.savetxt(street, np.c_[x, y, z, (x > 20) + 1], fmt="%.4f %.4f %.4f %d",
               header="x y z classification", comments="// ")
    out = tmp_path / "rows.csv"
    for side, written in ((["--seen-from", "z"], 1), ([], 1), (["--seen-from", "z"], 0)):
        assert main(["experiment", "--inputs", str(street), "--ground-truth-field",
                     "classification", "-m", "superfacets", "--alpha", "200", "-k", "30",
                     "-o", str(out), "-j", "1", "-q", *side]) == 0
        assert capsys.readouterr().out.startswith(f"{written} rows written")
    rows = {r["seen_from"]: r for r in csv.DictReader(out.open())}
    assert sorted(rows) == ["", "z"] and len(list(csv.DictReader(out.open()))) == 2
    for side, row in rows.items():
        labels = tmp_path / f"labels{side}.seg"
        assert main(["segment", str(street), "-k", "30", "--alpha", "200", "-o", str(labels),
                     "-q", *(["--seen-from", side] if side else [])]) == 0
        capsys.readouterr()
        assert main(["evaluate", str(street), str(labels), "--ground-truth-field",
                     "classification", "--json"]) == 0
        said = json.loads(capsys.readouterr().out)
        assert float(row["undersegmentation_error"]) == said["undersegmentation_error"]
    assert rows["z"]["undersegmentation_error"] != rows[""]["undersegmentation_error"]
    from superfacets.evaluation.report import load_results

    assert sorted(load_results(out)["series"]) == ["superfacets seen_from=file",
                                                   "superfacets seen_from=z"]
    assert main(["experiment", "--seen-from", "z", "-o", str(out)]) == 2
    assert "--seen-from goes with --inputs" in capsys.readouterr().err


def test_an_experiment_reads_each_file_s_ground_truth_from_a_label_file(tmp_path, capsys):
    # SemanticKITTI's layout: sequences/00/velodyne/000000.bin beside labels/000000.label
    from conftest import street_sweep

    velodyne, labels = tmp_path / "00" / "velodyne", tmp_path / "00" / "labels"
    velodyne.mkdir(parents=True)
    labels.mkdir()
    for i in range(2):
        xyz, part, rng = street_sweep(5 + i, -1.7)
        np.c_[xyz, rng.random(len(xyz))].astype("<f4").tofile(velodyne / f"{i:06d}.bin")
        classes = np.array([40, 50, 10], dtype=np.uint32)[part]
        classes[::7] = 0  # (SemanticKITTI's "unlabelled", scattered)
        classes.tofile(labels / f"{i:06d}.label")
    miou = {}
    for extra in ([], ["--ignore-label", "0"]):
        out = tmp_path / f"rows{len(extra)}.csv"
        assert main(["experiment", "--inputs", str(velodyne / "*.bin"), "--ground-truths",
                     "../labels/{stem}.label", "-m", "superfacets", "-k", "30", "--alpha",
                     "200", "-o", str(out), "-j", "1", "-q", *extra]) == 0
        rows = list(csv.DictReader(out.open()))
        assert sorted(r["mesh"] for r in rows) == ["000000", "000001"]
        assert all(r["status"] == "ok" and r["n_ground_truths"] == "1" for r in rows)
        miou[len(extra)] = [float(r["oracle_miou"]) for r in rows]
    # the scattered unlabelled points are a class no superpoint holds, until left out
    assert all(m < 0.8 for m in miou[0]) and all(m > 0.8 for m in miou[2])  # road, wall, car
    # the report speaks of inputs and superpoints, and gives the oracle mIoU
    # (it said "2 meshes, 1 categories", "number of superfacets", no mIoU)
    pytest.importorskip("matplotlib")
    assert main(["report", str(out), "-o", str(tmp_path / "rep")]) == 0
    summary = (tmp_path / "rep" / "summary.md").read_text()
    assert summary.startswith("Results: 2 inputs, 2 rows") and "mean over 2 inputs" in summary
    assert "by number of superpoints k" in summary and "| oracle mIoU |" in summary
    assert f"{np.mean(miou[2]):.3f}" in summary and "| elements (median) |" in summary
    (labels / "000001.label").unlink()  # refused before any run, the file named
    for pattern, says in (("../labels/{stem}.label", "000001.label: no such ground truth "
                           "(--ground-truths ../labels/{stem}.label); 1 of 2 inputs have none"),
                          ("../labels/{name}.label", "name each file's ground truth with "
                           "{stem}"), ("{stem", "name each file's ground truth")):
        assert main(["experiment", "--inputs", str(velodyne / "*.bin"), "--ground-truths",
                     pattern, "-k", "30", "-o", str(tmp_path / "no.csv")]) == 2
        assert says in capsys.readouterr().err
    assert main(["experiment", "--inputs", str(velodyne / "*.bin"), "--ignore-label", "0",
                 "-k", "30", "-o", str(tmp_path / "no.csv")]) == 2
    assert "--ignore-label marks a ground truth's unlabelled elements" in \
        capsys.readouterr().err
    assert not (tmp_path / "no.csv").exists()


def test_an_experiment_s_ground_truths_from_a_list_file(tmp_path, capsys):
    """``--ground-truths LIST.csv``: Open3D-ML's ``X_points.npy`` / ``X_labels.npy``, names no
    ``{stem}`` pattern makes, judged as a pattern's would be."""
    import csv

    rng = np.random.default_rng(0)
    for name in ("000700", "000750"):
        xy = rng.random((1500, 2)) * 10
        np.save(tmp_path / f"{name}_points.npy", np.c_[xy, np.where(xy[:, 0] > 5, 1.0, 0.0)])
        np.save(tmp_path / f"{name}_labels.npy",
                (xy[:, 0] > 5).astype(np.int32) + 1)
    (tmp_path / "gt.csv").write_text("input,ground_truth\n000700_points.npy,000700_labels.npy"
                                     "\n000750_points.npy,000750_labels.npy\n")
    out = tmp_path / "rows.csv"
    assert main(["experiment", "--inputs", str(tmp_path / "*_points.npy"), "--ground-truths",
                 str(tmp_path / "gt.csv"), "-m", "superfacets", "-k", "10", "--alpha", "0",
                 "-o", str(out), "-j", "1", "-q"]) == 0
    rows = list(csv.DictReader(out.open()))
    assert sorted(r["mesh"] for r in rows) == ["000700_points", "000750_points"]
    assert all(r["status"] == "ok" and r["n_ground_truths"] == "1" for r in rows)
    assert all(float(r["undersegmentation_error"]) < 0.05 for r in rows)  # two terraces
    # a list of spaces, one input missing; a line of one path; no such list
    (tmp_path / "one.txt").write_text("# Open3D-ML\n000700_points.npy  000700_labels.npy\n")
    (tmp_path / "bad.tsv").write_text("000700_points.npy\n")
    for listed, says in (("one.txt", "000750_points.npy: no line of "),
                         ("bad.tsv", "line 1 is not an input and its ground truth (2 paths)"),
                         ("none.csv", "none.csv: no such list of ground truths")):
        assert main(["experiment", "--inputs", str(tmp_path / "*_points.npy"),
                     "--ground-truths", str(tmp_path / listed), "-k", "10", "-o",
                     str(tmp_path / "no.csv")]) == 2
        assert says in capsys.readouterr().err, listed
    assert not (tmp_path / "no.csv").exists()


def test_an_experiment_on_a_folder_of_clouds_and_meshes_runs_each_on_its_own_elements(
        tmp_path, capsys, sphere):
    """``experiment --inputs FOLDER`` ran faces only: its clouds got no row, and nothing said
    so ("6 inputs", 4 in the file); by default each file is run on its own elements, a file
    no asked kind fits is named, and ``report`` of rows without ground truth (the
    compactness alone) writes its summary instead of failing in matplotlib's legend."""
    from superfacets import write_mesh

    folder = tmp_path / "in"
    folder.mkdir()
    _laz(folder / "tile.laz")
    write_mesh(folder / "ball.off", sphere)
    out = tmp_path / "rows.csv"
    assert main(["experiment", "--inputs", str(folder), "-k", "10", "--alpha", "200",
                 "-o", str(out), "-j", "1", "-q"]) == 0
    rows = list(csv.DictReader(out.open()))
    assert sorted((r["mesh"], r["elements"], r["status"]) for r in rows) == [
        ("ball", "faces", "ok"), ("tile", "points", "ok")]
    capsys.readouterr()
    faces = tmp_path / "faces.csv"
    assert main(["experiment", "--inputs", str(folder), "-k", "10", "--alpha", "200",
                 "--elements", "faces", "-o", str(faces), "-j", "1", "-q"]) == 0
    assert f"left out: {folder / 'tile.laz'} (a point cloud: --elements points)" in \
        capsys.readouterr().err
    assert [r["mesh"] for r in csv.DictReader(faces.open())] == ["ball"]
    pytest.importorskip("matplotlib")
    assert main(["report", str(out), "-o", str(tmp_path / "rep")]) == 0
    summary = (tmp_path / "rep" / "summary.md").read_text()
    assert "Not drawn, the rows holding no value to draw" in summary
    # (no ground truth: the compactness alone, which needs none, is drawn)
    assert all(float(r["compactness"]) > 3 and r["undersegmentation_error"] == ""
               for r in rows)
    assert (tmp_path / "rep" / "fig4.png").exists() and "per_category_undersegmentation_error" \
        in summary
    assert "mean over 2 inputs, each of the 2 kinds (cloud, mesh) weighing the same" in \
        summary and "by number of segments k" in summary


def test_an_axis_value_may_start_with_a_minus(tmp_path, capsys, sphere):
    """``--up -y`` was refused by argparse (a value starting with a minus read as an
    option); only ``--up=-y`` worked."""
    from superfacets import write_mesh

    path = tmp_path / "ball.off"
    write_mesh(path, sphere)
    for flag in ("--up", "--up="):
        argv = ["html", str(path), "-k", "5", "-o", str(tmp_path / "b.html")]
        argv += [flag + "-z"] if flag.endswith("=") else [flag, "-z"]
        assert main(argv) == 0, capsys.readouterr().err
    page = (tmp_path / "b.html").read_text()
    np.save(tmp_path / "p.npy", np.random.default_rng(0).random((500, 3)) * [1, 1, 0.01])
    assert main(["segment", str(tmp_path / "p.npy"), "-k", "5", "--seen-from", "-z", "-o",
                 str(tmp_path / "p.seg"), "-q"]) == 0
    assert "superfacets" in page


def test_seen_from_sets_a_pcds_own_viewpoint_aside(tmp_path, capsys):
    """A georeferenced PCD carries PCL's default VIEWPOINT (the origin, thousands of
    kilometres away): its normals faced it, and ``--seen-from z`` was ignored. Now the
    option sets the file's viewpoint aside: the labels are those of the cloud seen from
    above; without it the file's viewpoint still orients the normals, and a note says
    that it lies farther than the points spread (not for a camera's cloud)."""
    pypcd4 = pytest.importorskip("pypcd4")
    from dataclasses import replace

    from superfacets import segment
    from superfacets.io import read_cloud

    rng = np.random.default_rng(0)
    xy = rng.random((6000, 2)) * 40
    roofs = (np.abs(xy[:, 0] - 12) < 5) & (np.abs(xy[:, 1] - 20) < 8)
    z = 0.05 * rng.standard_normal(6000) + np.where(roofs, 6.0, 0.0)
    pts = (np.c_[xy, z] + [512_700.0, 5_403_550.0, 300.0]).astype(np.float32)
    path = tmp_path / "tile.pcd"
    pypcd4.PointCloud.from_xyz_points(pts).save(path)
    cloud = read_cloud(path)
    assert cloud.viewpoint is not None  # (the file's: the origin)
    for extra, expect in ((["--seen-from", "z"], replace(cloud, viewpoint=None, up=(0, 0, 1))),
                          ([], cloud)):
        out = tmp_path / "t.seg"
        capsys.readouterr()
        assert main(["segment", str(path), "-k", "20", "-o", str(out), *extra]) == 0
        np.testing.assert_array_equal(np.loadtxt(out, dtype=np.int64),
                                      segment(expect, 20).labels)
        # a viewpoint farther than the points spread is named, with what to give instead
        assert ("--seen-from z" in capsys.readouterr().err) == (not extra)
    # the pictures that segment take the option too (no note: the viewpoint set aside)
    assert main(["html", str(path), "-k", "20", "--seen-from", "z", "-o",
                 str(tmp_path / "t.html")]) == 0
    assert "viewpoint" not in capsys.readouterr().err
    assert main(["html", str(path), "-k", "20", "-o", str(tmp_path / "t.html")]) == 0
    assert "--seen-from z" in capsys.readouterr().err
    near = pts - pts.min(axis=0) + [-20.0, -20.0, 0.5]  # (a camera's cloud: in front of it)
    pypcd4.PointCloud.from_xyz_points(near.astype(np.float32)).save(path)
    assert main(["segment", str(path), "-k", "20", "-o", str(tmp_path / "t.seg")]) == 0
    assert "viewpoint" not in capsys.readouterr().err
    seen = segment(replace(cloud, viewpoint=None, up=(0, 0, 1)), 20).labels
    assert not np.array_equal(seen, segment(cloud, 20).labels)  # (the orientation matters)


def _two_blocks(path):
    """Two blocks of tetrahedra apart (a gap of a block's width), each a region of Gmsh's
    ``gmsh:physical`` (1 and 2): no superfacet can hold both."""
    meshio = pytest.importorskip("meshio")
    from scipy.spatial import Delaunay

    rng = np.random.default_rng(3)
    parts, tets, regions = [], [], []
    for i in range(2):
        p = rng.random((250, 3)) + [2.0 * i, 0, 0]
        tets.append(Delaunay(p).simplices + 250 * i)
        parts.append(p)
        regions.append(np.full(len(tets[-1]), i + 1))
    meshio.write(str(path), meshio.Mesh(np.vstack(parts), [("tetra", np.vstack(tets))],
                                        cell_data={"gmsh:physical": [np.concatenate(regions)],
                                                   "gmsh:geometrical": [np.concatenate(
                                                       regions)]}),
                 file_format="gmsh22", binary=False)
    return path, np.concatenate(regions)


def test_the_method_runs_on_tetrahedra_in_experiment_panel_and_evaluate(tmp_path, capsys):
    """A tetrahedral mesh goes through ``experiment --inputs`` (its cells, judged against its
    ``gmsh:physical`` regions), ``panel`` (the method, not only label files) and
    ``evaluate --ground-truth-field``; its regions are read as ``read_field`` reads a
    scan's classes."""
    from superfacets.io.labels import read_field

    vol, regions = _two_blocks(tmp_path / "blocks.msh")
    np.testing.assert_array_equal(read_field(vol, "gmsh:physical"), regions)
    folder = tmp_path / "in"
    folder.mkdir()
    _laz(folder / "tile.laz", n=800)
    (folder / "blocks.msh").write_bytes(vol.read_bytes())
    out = tmp_path / "rows.csv"
    assert main(["experiment", "--inputs", str(folder), "--ground-truth-field",
                 "gmsh:physical", "-k", "2", "6", "--alpha", "200", "-o", str(out), "-j", "1",
                 "-q"]) == 0
    rows = [r for r in csv.DictReader(out.open()) if r["mesh"] == "blocks"]
    assert [(r["elements"], r["category"], r["status"]) for r in rows] == [
        ("cells", "volume", "ok")] * 2
    for r in rows:  # two blocks apart: every superfacet in one region
        assert r["segments"] == r["n_segments"]
        assert float(r["undersegmentation_error"]) == 0.0 and float(r["oracle_miou"]) == 1.0
    capsys.readouterr()
    assert main(["experiment", "--inputs", str(folder), "-k", "4", "--elements", "points",
                 "-o", str(tmp_path / "p.csv"), "-j", "1", "-q"]) == 0
    assert "(a tetrahedral mesh: --elements cells)" in capsys.readouterr().err
    seg = tmp_path / "b.seg"
    assert main(["segment", str(vol), "-k", "6", "-o", str(seg), "-q"]) == 0
    assert main(["evaluate", str(vol), str(seg), "--ground-truth-field", "gmsh:physical",
                 "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["undersegmentation_error"] == 0.0
    assert main(["evaluate", str(vol), str(seg), "--ground-truth-field", "material"]) == 2
    assert "no field 'material'; it has: gmsh:physical" in capsys.readouterr().err
    pytest.importorskip("pyvista")
    assert main(["panel", str(vol), "-k", "2", "6", "-o", str(tmp_path / "p.png"),
                 "--size", "320x240"]) == 0
    assert "wrote" in capsys.readouterr().out and (tmp_path / "p.png").stat().st_size > 1000
