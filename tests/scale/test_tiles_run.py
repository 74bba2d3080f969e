"""Tiled runs end to end (superfacets.scale.tiles.run): labels as one run's, options,
Dask, the command line, errors."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh
from tiled import _bumpy, _bumpy_cloud, _lattice_cloud, _write_ply_mesh

from superfacets import Mesh, ParameterError, segment
from superfacets.elements.faces import face_graph
from superfacets.errors import MeshFormatError
from superfacets.io.meshes import read_mesh
from superfacets.io.regions import RegionReader, streamed
from superfacets.method.connectivity import label_components
from superfacets.scale.tiles import buckets as buckets_module
from superfacets.scale.tiles.layout import (
    tile_of,
)
from superfacets.scale.tiles.run import segment_tiled


def test_a_tiled_run_reads_the_file_twice_and_gives_the_same_labels(tmp_path, monkeypatch):
    """After the survey and the bucketing no task reads the file; the labels are those of
    tasks that each read the file (the path a remote scheduler without workdir takes)."""
    mesh = _bumpy(5)  # (at k = 40 a halo of 1 leaves 72 pieces to repair)
    path = tmp_path / "m.ply"
    _write_ply_mesh(path, mesh.vertices, mesh.faces)
    passes = []
    chunks = RegionReader.chunks

    def counted(self, *args):
        passes.append(1)
        yield from chunks(self, *args)

    monkeypatch.setattr(RegionReader, "chunks", counted)
    written, real_bucket = [], buckets_module.bucket

    def bucket(reader, tiles, folder, **kw):  # (the tile files, seen before the run ends)
        out = real_bucket(reader, tiles, folder, **kw)
        written.append((Path(folder), sorted(p.name for p in Path(folder).glob("tile-*.bin"))))
        return out

    monkeypatch.setattr(buckets_module, "bucket", bucket)
    res = segment_tiled(path, 40, tiles=(2, 2, 2), halo=1, workdir=tmp_path / "work",
                        start="tiles")  # (the tiles' own start: pieces for the connect phase)
    assert len(passes) == 2 and res.timings["bucket"] > 0
    (folder, files), = written
    assert len(files) == 8 and folder.parent.parent == (tmp_path / "work").resolve()
    assert list((tmp_path / "work").iterdir()) == []  # the run's own folder, removed
    # halo 1 leaves pieces: the connect phase ran on the stitched labels read from a file
    assert res.disagreements > 0 and res.repaired > 0
    passes.clear()
    monkeypatch.setattr(buckets_module, "bucket", lambda reader, *a, **k: reader)
    each = segment_tiled(path, 40, tiles=(2, 2, 2), halo=1, start="tiles")
    assert len(passes) > 8 * 3  # every task of every phase read the file
    np.testing.assert_array_equal(res.labels, each.labels)
    assert res.repaired == each.repaired and res.disagreements == each.disagreements


def test_a_tiled_run_shows_every_stage_and_redraws_while_a_tile_runs(monkeypatch, capsys):
    """With ``progress`` each stage shows a line (the phases a bar of tiles), redrawn
    every TICK seconds while it runs: no stage is silent on a terminal."""
    from conftest import slowed

    from superfacets.scale.tiles import phases as tiling

    slowed(monkeypatch, tiling, "tile_refine", 0.3)  # (a tile that takes a while)
    res = segment_tiled(_bumpy_cloud(20_000), 30, tiles=2, progress=True)
    err = capsys.readouterr().err
    for name in ("survey", "orientation", "areas", "start", "refine", "labels", "stitch",
                 "merges"):
        assert f"tiles: {name}" in err and name in res.timings
    assert err.count("tiles: refine") >= 10  # redrawn while the two slow tiles ran


@pytest.mark.parametrize("extra", [dict(paper=True), {}], ids=["paper", "default"])
def test_one_tile_gives_the_single_runs_partition(extra):
    mesh = _bumpy(4)
    single = segment(mesh, 50, **extra)
    tiled = segment_tiled(mesh, 50, tiles=1, refine=0, **extra)
    assert tiled.n_segments == single.n_segments == 50
    pairs = np.unique(single.labels * 1000 + tiled.labels)
    assert pairs.size == 50  # the same partition, labels aside


@pytest.mark.parametrize("extra, tiles", [(dict(paper=True), (2, 2, 2)), ({}, 8),
                                          (dict(paper=True), 8)],
                         ids=["paper-grid", "default-balanced", "paper-balanced"])
def test_several_tiles_stitch_without_cutting_a_superfacet(extra, tiles):
    mesh = _bumpy(5)
    res = segment_tiled(mesh, 150, tiles=tiles, **extra)
    labels = res.labels
    assert labels.shape == (mesh.n_faces,) and labels.min() == 0
    assert np.unique(labels).size == res.n_segments == labels.max() + 1
    # the tiles make a few more than asked (their cores end with fewer than their shares),
    # merged by Ward's merges to exactly the count
    assert res.n_segments == 150 and res.params["merged_from"] >= 150
    # every superfacet one connected piece of the face graph: none cut by a tile border
    pieces = label_components(face_graph(mesh), labels)
    assert np.unique(pieces).size == res.n_segments
    g = face_graph(mesh)
    assert res.layout.n_tiles == 8
    t = tile_of(g.positions, res.layout)
    if res.layout.shape is None:
        assert res.grid == (8,)
        counts = np.bincount(t, minlength=8)  # balanced: about equal cores (ties on a split)
        assert counts.max() <= 1.05 * counts.mean()
    else:
        assert res.grid == (2, 2, 2)
    crossing = np.unique(labels[t == 0])
    assert np.isin(crossing, labels[t != 0]).any()  # some do cross a border
    assert res.centers.shape == (res.n_segments,)
    np.testing.assert_array_equal(labels[res.centers], np.arange(res.n_segments))
    assert len(res.tiles) == 8 and sum(t["core"] for t in res.tiles) == mesh.n_faces
    if extra:  # the paper's classification is exact from halo 2; faces no window
        # reached seed superfacets in each tile's own order (a few elements can differ)
        assert res.disagreements <= 0.001 * mesh.n_faces
        if res.layout.shape:
            assert res.disagreements == 0


def test_tiled_points_with_invalid_rows(tmp_path):
    """An organized scan's holes are invalid points (-1) in tiles as in a whole run; a
    ``.npy`` file with NaN rows is refused, as a whole run refuses it."""
    from superfacets.inputs.cloud import InvalidCloudError

    mesh = trimesh.creation.icosphere(4)
    pts, _ = trimesh.sample.sample_surface_even(mesh, 6000, seed=0)
    pts = np.asarray(pts, dtype=np.float64)
    pts[[3, 77]] = np.nan
    np.save(tmp_path / "c.npy", pts)
    with pytest.raises(InvalidCloudError, match="point 3 has a non-finite coordinate"):
        segment_tiled(tmp_path / "c.npy", 40, tiles=4)
    organized = pts[: pts.shape[0] // 100 * 100].reshape(-1, 100, 3)
    res = segment_tiled(organized, 40, tiles=4)
    assert res.labels[3] == res.labels[77] == -1
    ok = res.labels >= 0
    assert ok.sum() == pts.shape[0] - 2 and res.labels[ok].max() + 1 == res.n_segments
    assert 35 <= res.n_segments <= 40 and res.params["elements"] == "points"


def test_dask_workers_give_the_same_labels(tmp_path):
    pytest.importorskip("distributed")
    mesh = _bumpy(4)
    path = tmp_path / "m.ply"
    _write_ply_mesh(path, mesh.vertices, mesh.faces)
    here = segment_tiled(path, 60, tiles=4, workers=1)
    there = segment_tiled(path, 60, tiles=4, workers=2)
    np.testing.assert_array_equal(here.labels, there.labels)


def test_where_the_refine_rounds_start(monkeypatch):
    """A tiled run's rounds start by default from one run on the survey's sample (a
    mesh's face centroids, as a cloud, with the mesh's swaps); ``start='tiles'``: each
    tile samples its own centers instead. Either way the count is exact and no
    superfacet is cut."""
    from superfacets.scale.tiles import phases as tiling

    mesh = _bumpy(5)
    g = face_graph(mesh)
    starts, real = [], tiling.pipeline

    def recorded(obj, p, **kw):  # (the start's run: a whole run on a cloud; a tile's
        if type(obj).__name__ == "PointCloud" and kw.get("finished", True):  # is unfinished)
            starts.append((obj.points.shape[0], p.split_merge))
        return real(obj, p, **kw)

    monkeypatch.setattr(tiling, "pipeline", recorded)
    sampled = segment_tiled(mesh, 60, tiles=4)
    assert "start" in sampled.timings and "centers" not in sampled.timings
    assert starts == [(mesh.n_faces // 2, True)]  # every second face's centroid (thinned
    # to at most a quarter of the rows where 10,000 remain: start_step); a mesh's swaps
    own = segment_tiled(mesh, 60, tiles=4, start="tiles")
    assert "centers" in own.timings and "start" not in own.timings and len(starts) == 1
    for res in (own, sampled):
        assert res.n_segments == 60
        assert np.unique(label_components(g, res.labels)).size == 60
    assert not np.array_equal(own.labels, sampled.labels)
    cloud = segment_tiled(_bumpy_cloud(20_000), 30, tiles=2)
    assert "start" in cloud.timings and starts[1][1] is False  # (points: no swaps)
    cloud = segment_tiled(_bumpy_cloud(20_000), 30, tiles=2, start="tiles")
    assert "centers" in cloud.timings and "start" not in cloud.timings and len(starts) == 2


def test_bad_options_are_refused_before_any_work(tmp_path):
    mesh = _bumpy(2)
    with pytest.raises(ParameterError, match="halo must be"):
        segment_tiled(mesh, 10, halo=0.5)
    with pytest.raises(ParameterError, match="refine must be"):
        segment_tiled(mesh, 10, refine=-1)
    with pytest.raises(ParameterError, match="workers must be"):
        segment_tiled(mesh, 10, workers=0)
    with pytest.raises(ParameterError, match="features"):
        segment_tiled(mesh, 10, features=np.zeros((mesh.n_faces, 3)))
    with pytest.raises(ParameterError, match="faces or points"):
        segment_tiled(mesh, 10, elements="vertices")
    with pytest.raises(ParameterError, match="larger than the number of"):
        segment_tiled(mesh, mesh.n_faces + 1)
    with pytest.raises(ParameterError, match="unknown parameter"):
        segment_tiled(mesh, 10, colour=1)
    with pytest.raises(ParameterError, match="start must be 'sample' or 'tiles'"):
        segment_tiled(mesh, 10, start="coarse")


def test_a_failing_tile_names_itself(tmp_path):
    path = tmp_path / "quad.ply"
    _write_ply_mesh(path, np.eye(4, 3), [[0, 1, 2], [0, 1, 2, 3]], counts=True)
    with pytest.raises(MeshFormatError, match="has polygons"):
        segment_tiled(path, 1, tiles=2)
    np.save(tmp_path / "flat.npy", np.zeros((5, 3)))
    with pytest.raises(ParameterError, match="zero extent"):
        segment_tiled(tmp_path / "flat.npy", 1, tiles=2)


def test_damaged_and_unusable_inputs_of_a_tiled_run_get_clear_errors(tmp_path):
    """The errors of the whole-input run, from the survey and the chunked readers."""
    from superfacets import InvalidMeshError

    pts = np.random.default_rng(0).random((300, 3))
    huge = pts.copy()
    huge[7] = 1e200  # beyond what areas and normals can square in double precision
    np.save(tmp_path / "huge.npy", huge)
    with pytest.raises(InvalidMeshError, match="huge.npy: coordinates up to 1e.200.*rescale "
                                               "the cloud"):
        segment_tiled(tmp_path / "huge.npy", 5, tiles=2)
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=1, version="1.2")
    header.scales = [0.001] * 3
    las = laspy.LasData(header)
    las.x, las.y, las.z = pts.T
    las.write(tmp_path / "whole.las")
    (tmp_path / "cut.las").write_bytes((tmp_path / "whole.las").read_bytes()[:-30])
    # one check of the header against the data, before either reader reads a point
    with pytest.raises(MeshFormatError, match=r"cut.las: damaged LAS file: the header "
                                              r"declares 300 points, the file holds 298"):
        segment_tiled(tmp_path / "cut.las", 5, tiles=2)
    from superfacets import read_cloud

    with pytest.raises(MeshFormatError, match=r"declares 300 points, the file holds 298"):
        read_cloud(tmp_path / "cut.las")


def test_a_tiled_run_on_dask_starts_quietly_beside_another_cluster(tmp_path, recwarn):
    """Dask's scheduler serves HTTP routes on port 8787 by default, and warned when
    another run held it; the engine's scheduler takes a free local port."""
    import socket

    pytest.importorskip("distributed")
    held = socket.socket()
    try:
        held.bind(("127.0.0.1", 8787))
        held.listen(1)
    except OSError:
        pass  # already held by something else: the case to test all the same
    try:
        pts = np.random.default_rng(1).random((2000, 3)) * [1, 1, 0.1]
        res = segment_tiled(pts, 20, tiles=2, workers=2)
    finally:
        held.close()
    assert res.n_segments == 20
    assert not [w for w in recwarn if "already in use" in str(w.message)]


def test_tiny_tiles_of_one_point_each(monkeypatch):
    from superfacets.scale.tiles import layout as tile_layout

    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.]])
    with pytest.raises(ParameterError, match="elements per tile"):  # refused by default
        segment_tiled(pts, None, radius=0.3, tiles=(2, 2, 1), n_neighbors=2)
    monkeypatch.setattr(tile_layout, "MIN_PER_TILE", 0)  # the machinery, on tiny tiles
    res = segment_tiled(pts, None, radius=0.3, tiles=(2, 2, 1), n_neighbors=2)
    np.testing.assert_array_equal(np.sort(res.labels), [0, 1, 2])
    # sized by n_segments: each tile's box reaches as far as the halo the survey's sample
    # asks for, so the tiny tiles read the points' areas as one run does
    tiled = segment_tiled(pts, 2, tiles=(2, 2, 1), n_neighbors=2)
    np.testing.assert_array_equal(tiled.labels, segment(pts, 2, n_neighbors=2).labels)


def test_cli_tiles_writes_labels_and_refuses_whole_input_outputs(tmp_path):
    mesh = _bumpy(3)
    path = tmp_path / "m.ply"
    _write_ply_mesh(path, mesh.vertices, mesh.faces)
    run = [sys.executable, "-m", "superfacets", "segment", str(path), "-k", "30"]
    out = subprocess.run(run + ["--tiles", "2,1,1", "-j", "1", "-o", str(tmp_path / "m.seg"),
                                "--workdir", str(tmp_path / "work")],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "2 tiles (2x1x1 grid)" in out.stdout
    assert "30 superfacets (merged from " in out.stdout and "Ward's merges" in out.stdout
    labels = np.loadtxt(tmp_path / "m.seg", dtype=int)
    assert labels.shape == (mesh.n_faces,) and np.unique(labels).size == labels.max() + 1 == 30
    assert list((tmp_path / "work").iterdir()) == []  # (the run's own folder, removed)
    bad = subprocess.run(run + ["--tiles", "2", "--colored-mesh", str(tmp_path / "c.ply")],
                         capture_output=True, text=True)
    assert bad.returncode != 0 and "not with --tiles" in bad.stderr
    assert not (tmp_path / "c.ply").exists()
    bad = subprocess.run(run + ["--halo", "2"], capture_output=True, text=True)
    assert bad.returncode != 0 and "--halo goes with --tiles" in bad.stderr
    bad = subprocess.run(run + ["--workdir", str(tmp_path)], capture_output=True, text=True)
    assert bad.returncode != 0 and "--workdir goes with --tiles" in bad.stderr
    bad = subprocess.run(run + ["--tile-start", "tiles"], capture_output=True, text=True)
    assert bad.returncode != 0 and "--tile-start goes with --tiles" in bad.stderr
    out = subprocess.run(run + ["--tiles", "2,1,1", "--tile-start", "tiles", "-o",
                                str(tmp_path / "own.seg")], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    own = np.loadtxt(tmp_path / "own.seg", dtype=int)
    assert np.unique(own).size == 30 and not np.array_equal(own, labels)


def test_a_tiled_run_draws_its_picture_from_an_even_sample_of_the_file(tmp_path, capsys,
                                                                       monkeypatch):
    """``--picture`` and ``--html`` with ``--tiles`` (refused before: "needs the whole
    input in one process"): a cloud that streams is drawn from the survey's even sample of
    its rows (read again in one pass: the whole cloud need not fit), its legend from every
    label; a mesh is drawn whole; ``--view`` names the drawings it is for."""
    pytest.importorskip("pyvista")
    from PIL import Image

    from superfacets.cli import main
    from superfacets.io.labels import read_labels
    from superfacets.viz import render as rendering

    pts = _bumpy_cloud(3000).points
    np.save(tmp_path / "c.npy", pts)
    sized = []
    real = rendering.size_legend

    def legend(img, lab, *args):
        sized.append(np.asarray(lab))
        return real(img, lab, *args)

    monkeypatch.setattr(rendering, "size_legend", legend)
    assert main(["segment", str(tmp_path / "c.npy"), "-k", "30", "--tiles", "2", "-j", "1",
                 "-o", str(tmp_path / "c.seg"), "--picture", str(tmp_path / "c.png"),
                 "--view", "top", "--html", str(tmp_path / "c.html")]) == 0
    out = capsys.readouterr().out
    assert "3,000 of 3,000 points drawn" in out and "both drawn in" in out
    assert '"points": 3000' in (tmp_path / "c.html").read_text()
    img = np.asarray(Image.open(tmp_path / "c.png").convert("RGB"))
    assert (np.abs(img.astype(int) - 255).sum(-1) > 90).mean() > 0.05
    assert np.unique(img.reshape(-1, 3), axis=0).shape[0] > 30  # (coloured by superpoint)
    assert np.array_equal(sized[-1], read_labels(tmp_path / "c.seg"))
    with monkeypatch.context() as patch:  # (a survey's sample of 1,000 points)
        patch.setattr("superfacets.io.regions.SAMPLE", 1000)
        assert main(["segment", str(tmp_path / "c.npy"), "-k", "30", "--tiles", "2", "-j", "1",
                     "--picture", str(tmp_path / "s.png"), "--html",
                     str(tmp_path / "s.html")]) == 0
    assert "1,000 of 3,000 points drawn" in capsys.readouterr().out
    assert "1,000 of 3,000 points (an even sample)" in (tmp_path / "s.html").read_text()
    assert sized[-1].shape == (3000,)  # (the legend: every point's label)
    mesh = _bumpy(3)
    _write_ply_mesh(tmp_path / "m.ply", mesh.vertices, mesh.faces)
    assert main(["segment", str(tmp_path / "m.ply"), "-k", "20", "--tiles", "2", "-j", "1",
                 "--picture", str(tmp_path / "m.png"), "-q"]) == 0
    assert Image.open(tmp_path / "m.png").size == (1200, 900)
    assert sized[-1].shape == (mesh.n_faces,)
    assert main(["segment", str(tmp_path / "c.npy"), "-k", "30", "--tiles", "2",
                 "--picture", str(tmp_path / "c.seg"), "-o", str(tmp_path / "c.seg")]) == 2
    assert main(["segment", str(tmp_path / "c.npy"), "-k", "30", "--tiles", "2",
                 "--picture", str(tmp_path / "d.png"), "-o", str(tmp_path / "d.png")]) == 2
    assert "two outputs go to the same file" in capsys.readouterr().err


def test_the_cli_says_when_tiles_give_fewer_superpoints_than_asked(tmp_path, capsys):
    """Each tile's core takes its share of the centers, so a few hundred points in two
    tiles may end with fewer superpoints than asked: the summary says so."""
    from superfacets.cli import main

    np.save(tmp_path / "c.npy", np.random.default_rng(0).random((400, 3)))
    assert main(["segment", str(tmp_path / "c.npy"), "-k", "6", "--tiles", "2",
                 "-o", str(tmp_path / "c.seg")]) == 0
    got = int(np.loadtxt(tmp_path / "c.seg").max()) + 1
    line = capsys.readouterr().out.splitlines()[0]
    assert f", {got} superpoints" in line
    assert ("(6 asked: tiles this small hold fewer centers" in line) == (got < 6)
    assert got <= 6


def test_a_tiled_summary_says_the_merges_as_one_runs_does(tmp_path, capsys):
    """The merges to the count are said in the same words in one run and in tiles: the size
    bound, and the cost where it is not the default's."""
    from superfacets.cli import main

    np.save(tmp_path / "p.npy", np.c_[np.random.default_rng(3).random((6000, 2)),
                                      np.zeros(6000)])
    words = []
    for extra in ([], ["--tiles", "2"], ["--merge-cost", "auto"],
                  ["--merge-cost", "auto", "--tiles", "2"]):
        assert main(["segment", str(tmp_path / "p.npy"), "-k", "10", *extra, "-o",
                     str(tmp_path / "p.seg")]) == 0
        line = capsys.readouterr().out.splitlines()[0]
        words.append(line[line.index("finer ones"):line.index("no merging)")])
    assert words[0] == words[1] and words[2] == words[3] != words[0]
    assert ", none above 16 times the mean" in words[1]
    assert "(--merge-cost auto)" in words[3] and "cost" not in words[1]


def test_a_tiled_run_measures_the_input_s_area_and_says_the_superpoints_width(tmp_path,
                                                                              capsys):
    """A tiled run's summary gave sizes in elements alone: it now says how wide a
    superpoint is on average in the data's units, from the input's area, which the tiles
    measure as one run does (a mesh's faces; a cloud's points sized by their graph)."""
    from superfacets.cli import main

    mesh = _bumpy(3)
    r = segment_tiled(mesh, 20, tiles=2, workers=1)
    assert r.area == pytest.approx(mesh.area, rel=1e-9)
    cloud = _bumpy_cloud(3000)
    one = segment(cloud, 20)
    tiled = segment_tiled(cloud, 20, tiles=2, workers=1)
    assert tiled.area == pytest.approx(float(one.elements.graph.sizes.sum()), rel=1e-6)
    assert np.isnan(segment_tiled(cloud, radius=0.1, tiles=2, workers=1).area)
    side = 2.0  # a flat square of side 2: 16 superpoints about 2 * sqrt(4 / 16 / pi) wide
    xy = np.random.default_rng(3).random((8000, 2)) * side
    np.save(tmp_path / "p.npy", np.c_[xy, np.zeros(8000)])
    assert main(["segment", str(tmp_path / "p.npy"), "-k", "16", "--tiles", "2", "-o",
                 str(tmp_path / "p.seg")]) == 0
    line = capsys.readouterr().out.splitlines()[0]
    wide = float(line.split("about ")[1].split(" wide on average")[0])
    assert wide == pytest.approx(2 * np.sqrt(side ** 2 / 16 / np.pi), rel=0.05)


def test_the_cli_says_what_the_halos_cost_where_they_are_wide(tmp_path, capsys):
    """Every phase runs over the tiles' boxes, so the elements they hold over their cores'
    is what the halos add to the work: the summary says so where it is half again one run's
    or more (small tiles for their superpoints), not where the tiles are large."""
    from superfacets import segment_tiled
    from superfacets.cli import main

    rng = np.random.default_rng(1)
    small = rng.random((400, 3))
    flat = np.c_[rng.random((20000, 2)), np.zeros(20000)]
    for name, pts, k in (("small", small, 6), ("flat", flat, 400)):
        np.save(tmp_path / f"{name}.npy", pts)
        res = segment_tiled(pts, k, tiles=2)
        rows, core = (sum(t[f] for t in res.tiles) for f in ("rows", "core"))
        assert core == len(pts) and res.halo_ratio == rows / core
        assert main(["segment", str(tmp_path / f"{name}.npy"), "-k", str(k), "--tiles", "2",
                     "-o", str(tmp_path / f"{name}.seg")]) == 0
        err = capsys.readouterr().err
        said = f"the tiles ran over {res.halo_ratio:.2f} times the points" in err
        assert said == (res.halo_ratio >= 1.5), (name, res.halo_ratio, err)
    assert res.halo_ratio < 1.5 < segment_tiled(small, 6, tiles=2).halo_ratio


def test_a_scans_viewpoint_reaches_every_tile(tmp_path):
    from superfacets import PointCloud

    rng = np.random.default_rng(2)
    cloud = PointCloud(rng.random((500, 3)), viewpoint=np.array([0.5, 0.5, 5.0]))
    reader = RegionReader.spill(cloud, tmp_path)
    assert reader.viewpoint == (0.5, 0.5, 5.0)
    _, _, part = reader.read_box([0, 0, 0], [0.5, 0.5, 1])
    np.testing.assert_array_equal(part.viewpoint, [0.5, 0.5, 5.0])


def test_a_quantized_scan_in_tiles_has_no_cut_superpoint():
    from superfacets.elements.points import point_graph

    cloud = _lattice_cloud(60)
    res = segment_tiled(cloud, 40, tiles=4)
    g = point_graph(cloud, 10)
    el = res.labels[np.argsort(g.index)]  # distinct points: one row per element
    assert np.unique(label_components(g.graph, el)).size == res.n_segments
    assert res.disagreements == 0 and res.repaired == 0


def test_tiled_runs_refuse_what_whole_runs_refuse(tmp_path):
    """NaN coordinates (a mesh, a .npy cloud) gave -1 labels and exit 0 in tiles; a tile
    count that leaves a handful of elements per tile never ended."""
    from superfacets.errors import InvalidMeshError
    from superfacets.inputs.cloud import InvalidCloudError

    mesh = _bumpy(3)
    v = mesh.vertices.copy()
    v[5] = np.nan
    with pytest.raises(InvalidMeshError, match="NaN"):
        segment(Mesh(v, mesh.faces), 20)  # the whole run
    with pytest.raises(InvalidMeshError, match="NaN"):
        segment_tiled(Mesh(v, mesh.faces), 20, tiles=2, workers=1)
    path = tmp_path / "m.ply"
    _write_ply_mesh(path, v, mesh.faces)
    with pytest.raises(InvalidMeshError, match="1 vertex has NaN or infinite coordinates"):
        segment_tiled(path, 20, tiles=2, workers=1)
    pts = np.random.default_rng(0).random((3000, 3))
    pts[7] = np.nan
    np.save(tmp_path / "p.npy", pts)
    with pytest.raises(InvalidCloudError, match="point 7 has a non-finite coordinate"):
        segment_tiled(str(tmp_path / "p.npy"), 20, tiles=2, workers=1)
    organized = np.random.default_rng(1).random((60, 50, 3))
    organized[:3] = np.nan  # an organized scan's holes stay invalid points (-1)
    res = segment_tiled(organized, 20, tiles=2, workers=1)
    assert (res.labels.reshape(-1)[:150] == -1).all() and (res.labels[150:] >= 0).all()
    with pytest.raises(ParameterError, match="elements per tile of this input"):
        segment_tiled(mesh, 20, tiles=10000, workers=1)
    with pytest.raises(ParameterError, match="give at most 25 tiles"):
        segment_tiled(mesh, 20, tiles=(8, 8, 1), workers=1)
    with pytest.raises(ParameterError, match="4 elements.*run it whole, without tiles"):
        segment_tiled(np.eye(4, 3), 3, tiles=2, workers=1)  # (not "give at most 1 tiles")
    # more superfacets than faces: said as one run says it (a face's centroid has no
    # extent: the tiles said "nothing to tile")
    with pytest.raises(ParameterError, match=r"n_segments \(3\) is larger than the number "
                       r"of faces \(1\)"):
        segment_tiled(Mesh(np.eye(3), np.array([[0, 1, 2]])), 3, tiles=2, workers=1)


def test_option_extremes_are_refused_before_any_work(tmp_path, monkeypatch):
    """--tiles 1000,1000,1000 built the layout of a billion tiles (exit 134 after 55 s and
    3.7 GiB) before the count was checked; 1,1,99999999999999999999 and a 400-digit count
    were tracebacks; --refine and -j had no bound (-j 1000 started 1,000 processes). Each
    is one line now, before the tile layout (none is built) and before any worker."""
    import superfacets.scale.tiles.layout as layouts
    from superfacets.cli import main
    from superfacets.scale.runner.engine import Engine

    mesh = _bumpy(3)
    monkeypatch.setattr(layouts, "balanced_tiles", lambda *a: pytest.fail("a layout built"))
    monkeypatch.setattr(layouts, "tile_grid", lambda *a: pytest.fail("a layout built"))
    for tiles, said in (((1000, 1000, 1000), "makes more than 1,048,576 tiles"),
                        ((1, 1, 10**20), "at most 1,048,576, got 100000000000000000000"),
                        (10**400, "a 401-digit number"),
                        (500, "elements per tile of this input")):
        with pytest.raises(ParameterError, match=said):
            segment_tiled(mesh, 20, tiles=tiles, workers=1)
    with pytest.raises(ParameterError, match=r"refine must be an integer in 0\.\.100"):
        segment_tiled(mesh, 20, tiles=2, workers=1, refine=10**9)
    with pytest.raises(ParameterError, match=r"workers must be an integer in 1\.\."):
        segment_tiled(mesh, 20, tiles=2, workers=1000)
    with pytest.raises(ParameterError, match="workers must be an integer"):
        Engine(workers=1000)
    path = tmp_path / "m.ply"
    _write_ply_mesh(path, mesh.vertices, mesh.faces)
    for args in (["--tiles", "1,1," + "9" * 400], ["--tiles", "1000,1000,1000"],
                 ["--tiles", "2", "--refine", "1000000000"], ["--tiles", "2", "-j", "1000"]):
        assert main(["segment", str(path), "-k", "20", "-o", str(tmp_path / "x.seg"),
                     *args]) == 2, args
        assert not (tmp_path / "x.seg").exists()


def test_grid_tiles_whose_boxes_hold_no_point_are_skipped_on_a_cloud():
    """A regular grid over two patches 10 apart leaves its middle tiles without a point,
    halo included: their tasks failed with a TypeError (the orientation reference given to
    an empty box); they are skipped, and the patches are segmented as with balanced
    tiles: every point labelled, exactly k, no superpoint on both patches."""
    rng = np.random.default_rng(0)
    patch = rng.random((3000, 3)) * [1, 1, 0.01]
    pts = np.vstack([patch, patch + [10, 0, 0]])
    r = segment_tiled(pts, 20, tiles=(5, 1, 1), workers=1)
    assert r.n_segments == 20 and (r.labels >= 0).all()
    assert [t["core"] for t in r.tiles] == [3000, 3000]
    assert not set(r.labels[:3000]) & set(r.labels[3000:])


def test_every_tile_weighs_colour_alike(monkeypatch):
    """The colour term's weight and floor are read once over every tile (as one run reads
    them over the whole cloud), so two tiles weigh their border alike: on a cloud whose
    colours are rougher on one side, the tiles reading their own disagree on dozens of
    border points, the run's on none; the result says the weight and floor used."""
    from superfacets import PointCloud
    from superfacets.scale.tiles import run as tiled

    rng = np.random.default_rng(0)
    xy = rng.random((40_000, 2)) * [4, 2]
    board = np.where(((xy[:, 0] * 3).astype(int) + (xy[:, 1] * 3).astype(int)) % 2, 0.6, 0.3)
    rough = np.where(xy[:, 0] < 2, 0.08, 0.01)[:, None]
    colors = np.clip(board[:, None] + rough * rng.standard_normal((40_000, 3)), 0, 1)
    cloud = PointCloud(np.c_[xy, 0.1 * np.sin(3 * xy[:, 0]) * np.cos(2 * xy[:, 1])],
                       colors=colors)
    once = segment_tiled(cloud, 100, tiles=4, workers=1)
    assert once.disagreements == 0 and once.params["beta"] > 0
    one = segment(cloud, 100)  # the same term as one run's, within the tiles' sampling
    assert abs(once.params["feature_floor"] / one.params["feature_floor"] - 1) < 0.1
    monkeypatch.setattr(tiled, "_colour_term", lambda run, margin, params, *_: (params, None))
    assert segment_tiled(cloud, 100, tiles=4, workers=1).disagreements > 20  # each its own


def test_every_tile_turns_a_normal_alike(monkeypatch):
    """A cloud without normals, ground and scattered shrubs (rough, thin parts where a
    propagation of the normals' signs over each tile's own box goes its own way): each
    normal turned like the nearest normal of the one oriented sample of the whole cloud
    (``orient_like``), so no two tiles label a border point differently; with each tile
    orienting its box alone (no sample), they disagree."""
    from superfacets import PointCloud
    from superfacets.elements import normals, points

    rng = np.random.default_rng(0)
    xy = rng.random((30_000, 2)) * [4, 2]
    z = np.zeros(30_000)
    shrub = rng.random(30_000) < 0.4
    z[shrub] = rng.random(shrub.sum()) * 0.5
    cloud = PointCloud(np.c_[xy, z + 0.005 * rng.standard_normal(30_000)])
    assert segment_tiled(cloud, 100, tiles=4, workers=1).disagreements == 0

    def own_box(pts, nrm, indptr, indices, viewpoint=None, reference=None, up=None):
        return normals.orient_normals(pts, nrm, indptr, indices, viewpoint, None, up)

    monkeypatch.setattr(points, "orient_normals", own_box)
    assert segment_tiled(cloud, 100, tiles=4, workers=1).disagreements > 20


def test_files_not_read_in_chunks_are_tiled_whole_and_polygons_refused_with_advice(tmp_path):
    """An ASCII PLY and a binary PLY whose faces carry colours are not read in chunks: a
    tiled run reads them whole (as an OBJ), with the labels of the same run on the mesh
    read from the file; a polygon mesh is refused, the message saying what to do (it named
    ``RegionReader.spill`` to a command line user, and a face-coloured PLY was refused)."""
    from plyfile import PlyData, PlyElement

    from superfacets.cli import main

    mesh = _bumpy(4)
    ascii_ply, coloured, triangles = (tmp_path / n for n in ("a.ply", "c.ply", "t.ply"))
    trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).export(ascii_ply,
                                                                    encoding="ascii")
    _write_ply_mesh(triangles, mesh.vertices, mesh.faces)
    v = PlyData.read(str(triangles))["vertex"].data
    f = np.empty(len(mesh.faces), dtype=[("vertex_indices", "i4", (3,)), ("red", "u1")])
    f["vertex_indices"], f["red"] = mesh.faces, np.arange(len(mesh.faces)) % 2 * 255
    PlyData([PlyElement.describe(v, "vertex"), PlyElement.describe(f, "face")]).write(
        str(coloured))
    assert [streamed(p) for p in (ascii_ply, coloured, triangles)] == [False, False, True]
    for path in (ascii_ply, coloured):
        r = segment_tiled(path, 20, tiles=2, workers=1)
        same = segment_tiled(read_mesh(path), 20, tiles=2, workers=1)
        assert r.n_segments == 20 and np.array_equal(r.labels, same.labels), path
        out = tmp_path / f"{path.stem}.seg"
        assert main(["segment", str(path), "-k", "20", "--tiles", "2", "-o", str(out)]) == 0
        assert np.loadtxt(out, dtype=np.int64).shape == (len(mesh.faces),)
    _write_ply_mesh(tmp_path / "quad.ply", np.eye(4, 3), [[0, 1, 2], [0, 1, 2, 3]], counts=True)
    assert not streamed(tmp_path / "quad.ply")
    with pytest.raises(MeshFormatError, match="has polygons: segment it without tiles"):
        segment_tiled(tmp_path / "quad.ply", 2, tiles=2, workers=1)


def test_a_tiled_page_of_more_triangles_than_a_page_holds_is_refused_before_the_run(
        tmp_path, capsys, monkeypatch):
    from superfacets.cli import main

    mesh = _bumpy(3)
    _write_ply_mesh(tmp_path / "m.ply", mesh.vertices, mesh.faces)
    monkeypatch.setattr("superfacets.viz.html.MAX_PAGE_TRIANGLES", mesh.n_faces - 1)
    out = tmp_path / "m.seg"
    assert main(["segment", str(tmp_path / "m.ply"), "-k", "20", "--tiles", "2", "-o", str(out),
                 "--html", str(tmp_path / "m.html")]) == 2
    assert "would not open in a browser" in capsys.readouterr().err
    assert not out.exists() and not (tmp_path / "m.html").exists()


def test_a_tiled_run_reads_the_spread_of_point_sizes_and_notes_an_uneven_density(tmp_path,
                                                                                 capsys):
    """One run sizes the superpoints of a cloud of uneven density by it (``density``
    automatic), which tiles cannot (the median size is the whole cloud's): the tiles add up
    the spread of the point sizes over their cores, equal to one run's, and the command
    notes the difference where one run would have followed the density."""
    from superfacets.cli import main
    from superfacets.elements.density import AUTO_SPREAD, size_spread

    rng = np.random.default_rng(0)
    r = 0.2 * np.exp(rng.random(6000) * np.log(40))  # (density falling as the range squared)
    t = rng.random(6000) * 2 * np.pi
    uneven = np.c_[r * np.cos(t), r * np.sin(t), 0.05 * np.sin(r)]
    even = np.c_[rng.random((6000, 2)) * 8, np.zeros(6000)]
    for xyz, above in ((uneven, True), (even, False)):
        one = segment(xyz, 30)
        tiled = segment_tiled(xyz, 30, tiles=3, workers=1)
        spread = size_spread(one.elements.graph)
        assert tiled.size_spread == pytest.approx(spread, rel=1e-6)
        assert (spread > AUTO_SPREAD) is above
        assert (one.params["density"] > 0) is above
        np.save(tmp_path / "c.npy", xyz)
        assert main(["segment", str(tmp_path / "c.npy"), "-k", "30", "--tiles", "3", "-o",
                     str(tmp_path / "c.seg")]) == 0
        assert ("one run would size its superpoints by it" in capsys.readouterr().err) \
            is above
    assert np.isnan(segment_tiled(_bumpy(3), 20, tiles=2, workers=1).size_spread)


def test_a_tiled_run_writes_the_superpoint_graph_as_one_run_does(tmp_path, capsys):
    """``segment --tiles N --graph OUT.npz`` (refused before): the arrays one run's
    ``--graph`` writes, the levels with them, the labels those of ``-o``; all or nothing."""
    from superfacets.cli import main
    from superfacets.io.labels import read_labels

    np.save(tmp_path / "c.npy", _bumpy_cloud(3000).points)
    one, tiled = tmp_path / "one.npz", tmp_path / "tiled.npz"
    assert main(["segment", str(tmp_path / "c.npy"), "-k", "30", "--graph", str(one),
                 "--levels", "10,4", "-q"]) == 0
    assert main(["segment", str(tmp_path / "c.npy"), "-k", "30", "--tiles", "2", "-j", "1",
                 "--graph", str(tiled), "--levels", "10,4", "-o", str(tmp_path / "t.seg")]) == 0
    assert f"wrote {tiled} (superpoint graph" in capsys.readouterr().out
    a, b = np.load(one), np.load(tiled)
    assert sorted(a.files) == sorted(b.files)
    labels = read_labels(tmp_path / "t.seg")
    np.testing.assert_array_equal(b["super_index"], labels)
    np.testing.assert_array_equal(b["labels"], labels)
    assert b["x"].shape == (30, a["x"].shape[1]) and b["levels"].tolist() == [10, 4]
    assert len(np.unique(b["labels_1"])) == 4 and b["edge_index"].shape[0] == 2
    bad = tmp_path / "bad.npz"  # (a level the superpoints cannot make: nothing written)
    assert main(["segment", str(tmp_path / "c.npy"), "-k", "30", "--tiles", "2", "-j", "1",
                 "--graph", str(bad), "--levels", "31", "-o", str(tmp_path / "b.seg")]) == 2
    assert not bad.exists() and not (tmp_path / "b.seg").exists()


def test_sizes_in_the_data_s_units_give_one_run_s_count(tmp_path, capsys):
    """segment --tiles --seed-resolution R --neighbor-distance D (refused before: "measures
    the whole input"): the count one run gives (its area summed over the tiles; a mesh's
    from the survey), the neighbours the same fraction of the diagonal; the count a tiled
    run takes given none is one run's too (150 before, on a cloud one run gives 1 per
    1,000 points); with -k or --up-weight refused before any work."""
    from superfacets import PointCloud
    from superfacets.api.sizes import count_for_resolution, default_count, diagonal_fraction
    from superfacets.cli import main

    rng = np.random.default_rng(5)
    xy = rng.random((24000, 2)) * [60.0, 30.0]
    pts = np.c_[xy, 0.4 * np.sin(xy[:, 0] / 4)]
    path = tmp_path / "c.npy"
    np.save(path, pts)
    cloud = PointCloud(pts)
    for res, dist in ((1.5, None), (4.0, 2.0)):
        opts = {} if dist is None else {"neighbor_radius": diagonal_fraction(cloud, dist)}
        k, area = count_for_resolution(cloud, res, **opts)
        r = segment_tiled(str(path), tiles=3, seed_resolution=res, neighbor_distance=dist)
        assert r.n_segments == k and abs(r.area - area) <= 1e-6 * area
        if dist is not None:
            assert r.params["neighbor_radius"] == pytest.approx(opts["neighbor_radius"])
    out = tmp_path / "t.seg"
    assert main(["segment", str(path), "--tiles", "3", "--seed-resolution", "1.5", "-o",
                 str(out)]) == 0
    k, _ = count_for_resolution(cloud, 1.5)
    assert f"k = {k:,} superpoints from --seed-resolution 1.5" in capsys.readouterr().out
    assert len(np.unique(np.loadtxt(out))) == k
    mesh = _bumpy(3)
    mpath = tmp_path / "m.ply"
    _write_ply_mesh(mpath, mesh.vertices, mesh.faces)
    km, _ = count_for_resolution(mesh, 0.15)
    assert segment_tiled(str(mpath), tiles=2, seed_resolution=0.15).n_segments == km
    big = tmp_path / "big.npy"  # (one run's default: one per 1,000 points, not 150)
    np.save(big, np.c_[rng.random((240000, 2)) * 100, np.zeros(240000)])
    assert main(["segment", str(big), "--tiles", "2", "-o", str(out)]) == 0
    assert "k = 240 superpoints by default" in capsys.readouterr().out
    assert len(np.unique(np.loadtxt(out))) == 240 == default_count(np.load(big))
    for extra, words in ((["-k", "9"], "not with -k"), (["--up-weight", "2"], "--up-weight")):
        assert main(["segment", str(path), "--tiles", "3", "--seed-resolution", "1.5",
                     *extra, "-o", str(tmp_path / "x.seg")]) == 2
        assert words in capsys.readouterr().err and not (tmp_path / "x.seg").exists()
    with pytest.raises(ParameterError, match="not with n_segments"):
        segment_tiled(str(path), 20, seed_resolution=1.0)
    with pytest.raises(ParameterError, match="point cloud's graph"):
        segment_tiled(str(mpath), neighbor_distance=0.1)


def test_a_scenes_count_from_a_seed_resolution_is_one_runs(tmp_path, capsys):
    """A scan with an up direction weighs steps off its surface (``step_weight`` 4): its
    points' sizes on that graph add up to more than the surface's area, and the tiles
    summed them for the count (458 superpoints against one run's 362 on PDAL's crop);
    the count now reads the area by the nearest neighbours, as one run's does."""
    laspy = pytest.importorskip("laspy")
    from superfacets.cli import main
    from superfacets.scale.tiles.phases import point_sizes

    rng = np.random.default_rng(8)
    ground = np.c_[rng.random((12000, 2)) * 40.0, 0.05 * rng.standard_normal(12000)]
    shrubs = rng.random((6000, 3)) * [40.0, 40.0, 1.5]  # (a layer of scattered vegetation)
    pts = np.r_[ground, shrubs]
    every = np.ones(len(pts), dtype=bool)
    weighed, plain = (point_sizes(pts, every, 10, step).sum() for step in (4.0, 1.0))
    assert weighed > 1.1 * plain  # (the sizes the steps' graph reads are not the area)
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales, header.offsets = [0.001] * 3, [0.0] * 3
    las = laspy.LasData(header)
    las.x, las.y, las.z = pts.T
    path = tmp_path / "scene.las"
    las.write(str(path))
    said = []
    for tiles in ([], ["--tiles", "3"]):
        out = tmp_path / "s.seg"
        assert main(["segment", str(path), "--seed-resolution", "2", *tiles, "-o",
                     str(out)]) == 0
        said.append(next(line for line in capsys.readouterr().out.splitlines()
                         if line.startswith("k = ")))
        assert len(np.unique(np.loadtxt(out))) == int(said[-1].split()[2].replace(",", ""))
    assert said[0] == said[1], said
