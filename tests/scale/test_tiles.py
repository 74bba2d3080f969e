"""Tiled runs of one input (superfacets.scale.tiling, superfacets.scale.runner.tiles,
superfacets.io.regions):
known answers on synthetic inputs, invariants on several tiles, streamed reading, errors."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

from superfacets import Mesh, ParameterError, segment
from superfacets.elements.faces import face_graph
from superfacets.errors import MeshFormatError
from superfacets.inputs.cloud import PointCloud
from superfacets.io.regions import RegionReader
from superfacets.method.connectivity import label_components
from superfacets.method.params import resolve
from superfacets.scale.runner import buckets as buckets_module
from superfacets.scale.runner.buckets import bucket
from superfacets.scale.runner.tiles import segment_tiled
from superfacets.scale.tile_layout import balanced_tiles, tile_box, tile_grid, tile_of, trim_centers
from superfacets.scale.tiling import tile_labels


def _bumpy(subdivisions: int = 5) -> Mesh:
    """A sphere with folds (creases, concave and convex), about 20k faces."""
    m = trimesh.creation.icosphere(subdivisions=subdivisions)
    v = m.vertices
    v = v * (1 + 0.15 * np.sin(4 * v[:, :1]) * np.cos(3 * v[:, 1:2]))
    return Mesh(v, m.faces)


def _bumpy_cloud(n: int):
    """``n`` points sampled on :func:`_bumpy` (no normals, no viewpoint)."""
    from superfacets import PointCloud
    from superfacets.evaluation.datasets.sampling import sample_points

    return PointCloud(sample_points(_bumpy(4), n, seed=0)[0])


def _write_ply_mesh(path, vertices, faces, counts=None):
    v = np.array([tuple(x) for x in vertices], dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    if counts is None:
        f = np.empty(len(faces), dtype=[("vertex_indices", "i4", (3,))])
        f["vertex_indices"] = faces
    else:  # faces of other sizes
        f = np.empty(len(faces), dtype=[("vertex_indices", object)])
        f["vertex_indices"] = [np.asarray(x, dtype=np.int32) for x in faces]
    from plyfile import PlyData, PlyElement

    PlyData([PlyElement.describe(v, "vertex"), PlyElement.describe(f, "face")]).write(str(path))


# ---------------------------------------------------------------- the grid
def test_tile_grid_is_the_most_cubic_split():
    assert tile_grid([0, 0, 0], [4, 2, 1], 8).shape == (4, 2, 1)
    assert tile_grid([0, 0, 0], [1, 1, 1], (2, 3, 1)).shape == (2, 3, 1)
    flat = tile_grid([0, 0, 0], [6, 3, 0], 4)  # no split along a zero extent
    assert flat.shape[2] == 1 and flat.shape[0] * flat.shape[1] == 4
    assert tile_grid([0, 0, 0], [5, 0, 0], 7).shape == (7, 1, 1)  # a prime count on a line


def test_grid_tiles_are_its_cells_numbered_x_fastest():
    """Tile i + nx (j + ny k) is the cell (i, j, k): a position on an inner edge goes to
    the cell above it, one on the outer bounds (or past them) to the last cell."""
    g = tile_grid([0, 0, 0], [3, 2, 2], (3, 2, 2))
    assert g.n_tiles == 12
    pts = np.array([[0.5, 0.5, 0.5], [1.0, 0.5, 0.5], [2.5, 1.5, 1.5], [3.0, 2.0, 2.0],
                    [-1.0, 0.5, 7.0], [0.5, 1.0, 1.0]])
    assert tile_of(pts, g).tolist() == [0, 1, 11, 11, 6, 9]
    lo, hi = tile_box(g, 11, 0.25)
    np.testing.assert_allclose(lo, [1.75, 0.75, 0.75])
    np.testing.assert_allclose(hi, [3.25, 2.25, 2.25])


def test_balanced_tiles_hold_equal_shares_of_an_uneven_input():
    """A dense corner and a sparse rest: the grid's busiest tile holds most of the
    input, balanced tiles each about n / N (the same as the sample's quantiles), and
    they cover the box without overlap."""
    rng = np.random.default_rng(3)
    pts = np.r_[rng.random((45000, 3)) * 0.2, rng.random((5000, 3))]
    lo, hi = pts.min(0), pts.max(0)
    grid = np.bincount(tile_of(pts, tile_grid(lo, hi, 8)), minlength=8)
    assert grid.max() > 0.8 * pts.shape[0]
    for n in (1, 2, 5, 8, 13):
        b = balanced_tiles(pts, lo, hi, n)
        counts = np.bincount(tile_of(pts, b), minlength=n)
        assert b.n_tiles == n and b.shape is None
        assert counts.sum() == pts.shape[0]
        assert counts.max() - counts.min() <= 1
        # an even sample (every 10th position: ~385 a tile at n = 13) gives shares
        # within its sampling noise, the grid's busiest tile ~7x the mean
        counts = np.bincount(tile_of(pts, balanced_tiles(pts[::10], lo, hi, n)), minlength=n)
        assert counts.max() <= 1.15 * pts.shape[0] / n
        # the boxes tile [lo, hi]: volumes add up, each position lies in its own box
        assert np.isclose(np.prod(b.hi - b.lo, axis=1).sum(), np.prod(hi - lo))
        t = tile_of(pts, b)
        assert ((pts >= b.lo[t]) & (pts <= b.hi[t])).all()


def test_balanced_tiles_of_degenerate_samples():
    """Every position in one place, or no sample at all: boxes split in the middle."""
    same = np.ones((100, 3))
    b = balanced_tiles(same, [0, 0, 0], [2, 1, 1], 4)
    assert b.n_tiles == 4 and np.isclose(np.prod(b.hi - b.lo, axis=1).sum(), 2.0)
    e = balanced_tiles(np.zeros((0, 3)), [0, 0, 0], [4, 1, 1], 4)
    np.testing.assert_allclose(np.sort(e.lo[:, 0]), [0, 1, 2, 3])
    assert tile_of(np.array([[np.nan, 0, 0], [0.5, 0.5, 0.5]]), e).tolist()[0] == -1
    with pytest.raises(ParameterError, match="tiles must"):
        balanced_tiles(same, [0, 0, 0], [1, 1, 1], 0)


@pytest.mark.parametrize("bad", [0, -2, 2.5, True, (1, 2), (1, 0, 1), "4"])
def test_tile_grid_refuses_bad_counts(bad, tmp_path, monkeypatch):
    with pytest.raises(ParameterError, match="tiles must"):
        tile_grid([0, 0, 0], [1, 1, 1], bad)
    # a tiled run refuses them before it reads the file
    np.save(tmp_path / "p.npy", np.random.default_rng(0).random((50, 3)))
    monkeypatch.setattr(RegionReader, "survey", lambda self: pytest.fail("file read"))
    with pytest.raises(ParameterError, match="tiles must"):
        segment_tiled(tmp_path / "p.npy", 5, tiles=bad)


@pytest.mark.parametrize("layout", [tile_grid, balanced_tiles])
def test_every_position_has_one_tile_and_boxes_hold_them(layout):
    rng = np.random.default_rng(0)
    pts = rng.random((5000, 3)) * [3, 2, 1]
    args = (pts.min(0), pts.max(0), 6)
    tiles = tile_grid(*args) if layout is tile_grid else balanced_tiles(pts, *args)
    t = tile_of(pts, tiles)
    assert t.min() >= 0 and t.max() < 6 and np.bincount(t).min() > 0
    for k in range(6):
        lo, hi = tile_box(tiles, k)
        inside = ((pts >= lo) & (pts <= hi)).all(1)
        assert inside[t == k].all()
    assert tile_of(np.array([[np.nan, 0, 0]]), tiles)[0] == -1


@pytest.mark.parametrize("n_tiles", [1, 2, 3, 7, 16])
def test_a_tiles_core_holds_exactly_the_positions_of_that_tile(n_tiles):
    """``Tiles.holds(p, t)`` (the splits on the way to ``t`` only) is ``of(p) == t``,
    non-finite positions in no core, on a split in the tile above it."""
    rng = np.random.default_rng(n_tiles)
    pts = rng.normal(size=(6000, 3))
    tiles = balanced_tiles(pts, pts.min(0), pts.max(0), n_tiles)
    pts[::97] = np.nan
    pts[5::101, 1] = np.inf
    pts[7::103, tiles.axis[0] if tiles.axis.size else 0] = tiles.value[0] if \
        tiles.axis.size else 0.0  # (on the first split)
    of = tiles.of(pts)
    for t in range(tiles.n_tiles):
        np.testing.assert_array_equal(tiles.holds(pts, t), of == t)
    grid = tile_grid(np.zeros(3), np.ones(3), (2, 3, 1))
    cells = rng.random((3000, 3))
    for t in range(6):
        np.testing.assert_array_equal(grid.holds(cells, t), grid.of(cells) == t)


def test_trim_keeps_k_and_drops_the_most_crowded():
    pos = np.array([[0, 0, 0], [10, 0, 0], [20, 0, 0], [20.1, 0, 0], [30, 0, 0.]])
    keep = trim_centers(pos, 4)
    assert keep.sum() == 4 and not keep[3] and keep[2]
    assert trim_centers(pos, 9).all()


# ---------------------------------------------------------------- streamed reading
def test_ply_mesh_box_is_the_faces_whose_centroid_lies_in_it(tmp_path):
    mesh = _bumpy(3)
    path = tmp_path / "m.ply"
    _write_ply_mesh(path, mesh.vertices, mesh.faces)
    reader = RegionReader.open(path, chunk=97)  # many chunks
    assert (reader.kind, reader.n_rows) == ("faces", mesh.n_faces)
    v32 = np.asarray(mesh.vertices, dtype=np.float32).astype(np.float64)
    cent = v32[np.asarray(mesh.faces)].mean(axis=1)
    lo, hi = np.array([-0.3, -2, -2]), np.array([0.5, 2, 0.2])
    rows, pos, part = reader.read_box(lo, hi)
    want = np.flatnonzero(((cent >= lo) & (cent <= hi)).all(1))
    np.testing.assert_array_equal(rows, want)
    np.testing.assert_allclose(pos, cent[want])
    np.testing.assert_allclose(np.asarray(part.vertices)[np.asarray(part.faces)],
                               v32[np.asarray(mesh.faces)[want]])
    s = reader.survey()
    assert s.n_elements == mesh.n_faces
    assert math.isclose(s.size, float(face_graph(Mesh(v32, mesh.faces)).area), rel_tol=1e-9)


def test_points_from_ply_npy_and_las_read_by_box(tmp_path):
    rng = np.random.default_rng(1)
    pts = rng.random((3000, 3))
    rgb = (rng.random((3000, 3)) * 255).astype(np.uint8)
    from plyfile import PlyData, PlyElement

    v = np.empty(3000, dtype=[("x", "f8"), ("y", "f8"), ("z", "f8"), ("red", "u1"),
                              ("green", "u1"), ("blue", "u1")])
    for i, c in enumerate("xyz"):
        v[c] = pts[:, i]
    for i, c in enumerate(("red", "green", "blue")):
        v[c] = rgb[:, i]
    PlyData([PlyElement.describe(v, "vertex")]).write(str(tmp_path / "p.ply"))
    with_nan = pts.copy()
    with_nan[5] = np.nan
    np.save(tmp_path / "p.npy", with_nan)
    laspy = pytest.importorskip("laspy")
    las = laspy.create(point_format=2)
    las.header.scales = [1e-4] * 3
    las.x, las.y, las.z = pts[:, 0], pts[:, 1], pts[:, 2]
    las.red, las.green, las.blue = (rgb.astype(np.uint16) * 257).T
    las.write(tmp_path / "p.las")
    lo, hi = np.array([0.2, 0.1, 0.0]), np.array([0.7, 0.9, 0.5])
    want = np.flatnonzero(((pts >= lo) & (pts <= hi)).all(1))
    for name in ("p.ply", "p.npy", "p.las"):
        reader = RegionReader.open(tmp_path / name, chunk=500)
        assert reader.kind == "points" and reader.n_rows == 3000
        rows, pos, cloud = reader.read_box(lo, hi)
        near = np.abs(pts[rows] - pos).max() < 1e-3  # LAS: scaled integers
        expect = want[want != 5] if name == "p.npy" else want  # row 5: NaN in the .npy
        assert near and set(rows) ^ set(expect) <= set(np.flatnonzero(
            (np.abs(pts - lo) < 1e-3).any(1) | (np.abs(pts - hi) < 1e-3).any(1)))
        if name != "p.npy":
            np.testing.assert_allclose(cloud.colors, rgb[rows] / 255.0, atol=1e-6)
    assert 5 not in RegionReader.open(tmp_path / "p.npy").read_box([-9] * 3, [9] * 3)[0]


def _same_box(a, b):
    for x, y in zip(a[:2], b[:2]):
        np.testing.assert_array_equal(x, y)
    if a[2] is None or b[2] is None:
        assert a[2] is None and b[2] is None
    elif isinstance(a[2], Mesh):
        np.testing.assert_array_equal(a[2].vertices, b[2].vertices)
        np.testing.assert_array_equal(a[2].faces, b[2].faces)
    else:
        for n in ("points", "colors", "normals"):
            x, y = getattr(a[2], n), getattr(b[2], n)
            assert (x is None) == (y is None)
            if x is not None:
                np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("kind", ["ply-mesh", "npy-points", "spilled-cloud", "balanced"])
def test_buckets_read_every_box_as_the_file_does(tmp_path, kind):
    """One pass sorts the input into tiles; any box (across tiles, on their edges, empty)
    then reads the same rows, positions and input as a pass over the file."""
    rng = np.random.default_rng(4)
    if kind == "ply-mesh":
        mesh = _bumpy(3)
        _write_ply_mesh(tmp_path / "m.ply", mesh.vertices, mesh.faces)
        reader = RegionReader.open(tmp_path / "m.ply", chunk=333)
    elif kind in ("npy-points", "balanced"):
        pts = np.round(rng.random((4000, 3)), 2)  # many positions exactly on tile edges
        pts[7] = np.nan  # an invalid point, as a spilled organized scan holds them
        np.save(tmp_path / "p.npy", pts)
        from dataclasses import replace

        reader = replace(RegionReader.open(tmp_path / "p.npy", chunk=333), invalid_ok=True)
    else:
        from superfacets import PointCloud

        pts = rng.random((3000, 3))
        nrm = rng.normal(size=(3000, 3))
        cloud = PointCloud(pts, nrm / np.linalg.norm(nrm, axis=1, keepdims=True),
                           colors=rng.random((3000, 3)), viewpoint=np.array([0, 0, 5.0]))
        reader = RegionReader.spill(cloud, tmp_path / "spill", chunk=333)
    s = reader.survey()
    assert s.sample.shape == (s.n_elements, 3)  # small inputs: every position sampled
    edges = (balanced_tiles(s.sample, s.lo, s.hi, 12) if kind == "balanced"
             else tile_grid(s.lo, s.hi, (3, 2, 2)))
    buckets = bucket(reader, edges, tmp_path / "b")
    assert buckets.counts.sum() == s.n_elements and (buckets.counts > 0).sum() >= 10
    assert sorted(p.name for p in (tmp_path / "b").iterdir()) == sorted(
        f"tile-{t}.bin" for t in np.flatnonzero(buckets.counts))
    boxes = [(s.lo, s.hi), (s.lo - 1, s.lo - 0.5)]  # everything; nothing
    for t in (0, 5, 11):
        boxes.append(tile_box(edges, t))  # exactly a tile: its edges included
        boxes.append(tile_box(edges, t, 0.13))  # with a halo into its neighbours
    boxes += [tuple(np.sort(rng.uniform(s.lo, s.hi, (2, 3)), axis=0)) for _ in range(5)]
    for lo, hi in boxes:
        _same_box(buckets.read_box(lo, hi, name="b"), reader.read_box(lo, hi, name="b"))
    again = bucket(reader, edges, tmp_path / "b")  # a second bucketing replaces the first
    np.testing.assert_array_equal(again.counts, buckets.counts)
    _same_box(again.read_box(s.lo, s.hi), reader.read_box(s.lo, s.hi))
    if kind == "spilled-cloud":
        np.testing.assert_array_equal(buckets.read_box(s.lo, s.hi)[2].viewpoint, [0, 0, 5.0])


def test_a_kept_box_is_read_back_whole_and_only_for_the_same_box(tmp_path):
    """A tile's later phases read its box from the one file its first phase kept: the same
    rows, positions and cloud; another box is read from the tiles; a changed file refused."""
    from superfacets import PointCloud
    from superfacets.errors import SuperfacetsError

    rng = np.random.default_rng(3)
    cloud = PointCloud(rng.random((4000, 3)), colors=rng.random((4000, 3)))
    reader = RegionReader.spill(cloud, tmp_path / "spill", chunk=500)
    s = reader.survey()
    buckets = bucket(reader, balanced_tiles(s.sample, s.lo, s.hi, 6), tmp_path / "b")
    keep = tmp_path / "box-0"
    lo, hi = np.full(3, 0.2), np.full(3, 0.7)
    first = buckets.read_box(lo, hi, keep=keep)
    for name in [f"tile-{t}.bin" for t in range(6)]:  # read again: from the kept file alone
        (tmp_path / "b" / name).rename(tmp_path / f"away-{name}")
    _same_box(buckets.read_box(lo, hi, keep=keep), first)
    _same_box(first, reader.read_box(lo, hi))
    with pytest.raises(FileNotFoundError):  # another box: not the kept one
        buckets.read_box(lo, hi + 0.1, keep=keep)
    data = bytearray((tmp_path / "box-0.npy").read_bytes())
    data[-1] ^= 1
    (tmp_path / "box-0.npy").write_bytes(bytes(data))
    with pytest.raises(SuperfacetsError, match="changed since this run wrote it"):
        buckets.read_box(lo, hi, keep=keep)


def test_tiles_read_the_whole_clouds_area_on_the_graphs_they_keep(monkeypatch, tmp_path):
    """The areas of a cloud's tiles are read on the graphs they build once (boxes sized by
    the survey's sample): the radius is one run's; a sample that asks for too narrow a
    halo has the graphs dropped and built again on the halo the radius asks for."""
    import superfacets.scale.runner.tiles as rt
    from superfacets.elements.points import point_graph

    cloud = _bumpy_cloud(20000)
    area = float(point_graph(cloud, 10).graph.sizes.sum())
    seen, real = [], rt.tile_graph
    monkeypatch.setattr(rt, "tile_graph", lambda *a: seen.append(real(*a)) or seen[-1])
    res = segment_tiled(cloud, 60, tiles=4, workdir=tmp_path)
    fine = 60 * res.params["merge_from"]  # (an even cloud: superpoints merged to the count)
    assert res.mesh_radius == pytest.approx(math.sqrt(area / (fine * math.pi)), rel=1e-9)
    assert seen.count("built") == 4 and res.halo >= 3 * 2 * res.mesh_radius
    monkeypatch.setattr(rt, "GRAPH_SLACK", 0.5)  # the sample's halo too narrow
    seen.clear()
    narrow = segment_tiled(cloud, 60, tiles=4, workdir=tmp_path)
    assert seen.count("built") == 8 and narrow.halo == pytest.approx(6 * narrow.mesh_radius)
    assert narrow.mesh_radius == pytest.approx(res.mesh_radius, rel=1e-12)
    monkeypatch.setattr(rt, "graph_folder", lambda *a: None)
    np.testing.assert_array_equal(segment_tiled(cloud, 60, tiles=4).labels, narrow.labels)


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
    res = segment_tiled(path, 40, tiles=(2, 2, 2), halo=1, workdir=tmp_path / "work")
    assert len(passes) == 2 and res.timings["bucket"] > 0
    (folder, files), = written
    assert len(files) == 8 and folder.parent.parent == (tmp_path / "work").resolve()
    assert list((tmp_path / "work").iterdir()) == []  # the run's own folder, removed
    # halo 1 leaves pieces: the connect phase ran on the stitched labels read from a file
    assert res.disagreements > 0 and res.repaired > 0
    passes.clear()
    monkeypatch.setattr(buckets_module, "bucket", lambda reader, *a, **k: reader)
    each = segment_tiled(path, 40, tiles=(2, 2, 2), halo=1)
    assert len(passes) > 8 * 3  # every task of every phase read the file
    np.testing.assert_array_equal(res.labels, each.labels)
    assert res.repaired == each.repaired and res.disagreements == each.disagreements


def test_the_surveys_sample_names_its_rows(tmp_path, monkeypatch):
    """Every ``ceil(n / SAMPLE)``-th finite row, over chunks whose starts are not
    multiples of the stride: ``sample == positions[sample_rows]``."""
    from superfacets.io import regions

    monkeypatch.setattr(regions, "SAMPLE", 1000)
    monkeypatch.setattr(regions, "CHUNK", 777)
    pts = np.random.default_rng(0).random((10_001, 3))
    np.save(tmp_path / "c.npy", pts)
    survey = RegionReader.open(tmp_path / "c.npy").survey()
    np.testing.assert_array_equal(survey.sample_rows, np.arange(0, 10_001, 11))
    np.testing.assert_array_equal(survey.sample, pts[survey.sample_rows])


def test_a_clouds_tiles_start_from_centers_found_on_the_sample(monkeypatch):
    """On a cloud the tiles' centers phase is replaced by one run on the survey's
    sample (thinned to a quarter of the cloud here); the refine round starts from its
    centers, the labels phase from theirs; the same count; ``refine=0`` keeps the
    centers phase (where no round follows to run the passes on every point)."""
    from superfacets.scale import tiling

    seen = []
    real = tiling.sample_start

    def start(sample, rows, *args, **kw):
        out = real(sample, rows, *args, **kw)
        seen.append((sample, rows, out))
        return out

    monkeypatch.setattr(tiling, "sample_start", start)
    monkeypatch.setattr(tiling, "START_MIN_POINTS", 1000)
    cloud = _bumpy_cloud(20_000)
    res = segment_tiled(cloud, 30, tiles=4, merge_from=1)
    (sample, rows, (found, pos)), = seen
    np.testing.assert_array_equal(sample[rows], cloud.points)  # (the whole cloud here)
    assert 30 <= found.size and (np.diff(found) > 0).all() and found.max() < 20_000
    assert (found % 4 == 0).all()  # on every 4th point: a quarter of the cloud
    np.testing.assert_array_equal(pos, cloud.points[found])
    assert res.n_segments == 30 and "start" in res.timings and "centers" not in res.timings
    assert sum(t["centers"] for t in res.tiles) >= 30
    assert all(t["peak_mib"] is None or t["peak_mib"] >= t["labels_peak_mib"]
               for t in res.tiles)
    assert all("refine_seconds" in t and "labels_seconds" in t for t in res.tiles)
    plain = segment_tiled(cloud, 30, tiles=4, merge_from=1, refine=0)
    assert "centers" in plain.timings and "start" not in plain.timings and len(seen) == 1


@pytest.mark.parametrize("options", [dict(n_segments=100), dict(n_segments=None,
                                                                radius=0.004)])
def test_a_sample_too_small_for_the_centers_leaves_them_to_the_tiles(options, tmp_path,
                                                                     monkeypatch):
    """A survey's sample of 16 points a center or fewer (a huge count on a huge cloud),
    or of fewer points than the radius asks centers, starts no run: each tile samples its
    own centers, as on a mesh."""
    from superfacets.io import regions

    monkeypatch.setattr(regions, "SAMPLE", 500)  # every 40th of 20,000 points
    np.save(tmp_path / "c.npy", _bumpy_cloud(20_000).points)
    res = segment_tiled(tmp_path / "c.npy", tiles=4, merge_from=1, **options)
    assert "centers" in res.timings and all(t["centers_seconds"] >= 0 for t in res.tiles)
    assert res.n_segments >= (100 if options["n_segments"] else 2000)


def test_a_tiled_run_shows_every_stage_and_redraws_while_a_tile_runs(monkeypatch, capsys):
    """With ``progress`` each stage shows a line (the phases a bar of tiles), redrawn
    every TICK seconds while it runs: no stage is silent on a terminal."""
    from conftest import slowed

    from superfacets.scale import tiling

    slowed(monkeypatch, tiling, "tile_refine", 0.3)  # (a tile that takes a while)
    res = segment_tiled(_bumpy_cloud(20_000), 30, tiles=2, progress=True)
    err = capsys.readouterr().err
    for name in ("survey", "orientation", "areas", "start", "refine", "labels", "stitch",
                 "merges"):
        assert f"tiles: {name}" in err and name in res.timings
    assert err.count("tiles: refine") >= 10  # redrawn while the two slow tiles ran


def test_streamed_reading_errors_are_clear(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such file"):
        RegionReader.open(tmp_path / "missing.ply")
    (tmp_path / "a.off").write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    with pytest.raises(MeshFormatError, match="not read in chunks"):
        RegionReader.open(tmp_path / "a.off")
    trimesh.creation.box().export(tmp_path / "ascii.ply", encoding="ascii")
    with pytest.raises(MeshFormatError, match="ASCII PLY"):
        RegionReader.open(tmp_path / "ascii.ply")
    _write_ply_mesh(tmp_path / "quad.ply", np.eye(4, 3), [[0, 1, 2], [0, 1, 2, 3]], counts=True)
    with pytest.raises(MeshFormatError, match="reads triangles.*row 1"):
        RegionReader.open(tmp_path / "quad.ply").survey()
    good = tmp_path / "m.ply"
    _write_ply_mesh(good, *(lambda m: (m.vertices, m.faces))(trimesh.creation.icosphere(2)))
    (tmp_path / "cut.ply").write_bytes(good.read_bytes()[:-100])
    with pytest.raises(MeshFormatError, match="cannot read PLY"):
        RegionReader.open(tmp_path / "cut.ply")
    np.save(tmp_path / "flat.npy", np.zeros((4, 2)))
    with pytest.raises(MeshFormatError, match=r"shape \(N, 3\)"):
        RegionReader.open(tmp_path / "flat.npy")


# ---------------------------------------------------------------- the method
def test_core_classification_is_the_whole_inputs_from_the_same_centers():
    """Known answer: with a halo of 2 window * r, each tile labels its core as one run over
    the whole input does from the same centers (paper's classification, no post-step)."""
    mesh = _bumpy(4)
    p = resolve(n_segments=60, paper=True, enforce_connectivity=False)
    g = face_graph(mesh)
    r = math.sqrt(g.area / (60 * math.pi))
    centers = np.sort(segment(mesh, 60, paper=True).centers)
    whole = tile_labels(mesh, centers, p, r, g.diagonal)
    edges = tile_grid(g.positions.min(0), g.positions.max(0), 4)
    tiles = tile_of(g.positions, edges)
    seen = 0
    for t in range(4):
        lo, hi = tile_box(edges, t, 2 * p.window * r)
        rows = np.flatnonzero(((g.positions >= lo) & (g.positions <= hi)).all(1))
        used, local = np.unique(np.asarray(mesh.faces)[rows], return_inverse=True)
        part = Mesh(np.asarray(mesh.vertices)[used], local.reshape(-1, 3))
        at = np.searchsorted(rows, centers)
        ok = (at < rows.size) & (rows[np.minimum(at, rows.size - 1)] == centers)
        named = tile_labels(part, at[ok], p, r, g.diagonal)
        core = tiles[rows] == t
        np.testing.assert_array_equal(rows[named[core]], whole[rows[core]])
        seen += core.sum()
    assert seen == mesh.n_faces


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


def test_every_tile_orients_points_like_the_whole_cloud(tmp_path):
    """Points with no normals and no viewpoint: each tile's pieces are turned like the
    oriented sample the survey keeps, so a tile holding the inside of a torus's ring
    (concave seen from its own mean) gets the whole cloud's normals, not their opposite."""
    from scipy.spatial import cKDTree

    from superfacets.elements.points import point_graph
    from superfacets.scale.tiling import orientation_reference

    torus = trimesh.creation.torus(major_radius=1.0, minor_radius=0.4, major_sections=64,
                                   minor_sections=32)
    pts, _ = trimesh.sample.sample_surface_even(torus, 20000, seed=2)
    np.save(tmp_path / "t.npy", np.asarray(pts, dtype=np.float64))
    reader = RegionReader.open(tmp_path / "t.npy")
    s = reader.survey()
    assert not s.normals and reader.viewpoint is None
    whole = point_graph(PointCloud(pts)).graph
    reference = orientation_reference(s.sample, 10)
    layout = tile_grid(s.lo, s.hi, (3, 3, 1))  # the middle tile (+0.3): the ring's inner side
    agree = {}
    for use in (False, True):
        for t in range(layout.n_tiles):
            lo, hi = layout.box(t, 0.3)
            _, pos, cloud = reader.read_box(lo, hi)
            if use:
                inside = ((reference[0] >= lo - 0.1) & (reference[0] <= hi + 0.1)).all(1)
                cloud = PointCloud(cloud.points, orient_like=(reference[0][inside],
                                                              reference[1][inside]))
            g = point_graph(cloud).graph
            _, j = cKDTree(whole.positions).query(g.positions)
            agree[use, t] = (np.einsum("ij,ij->i", g.normals, whole.normals[j]) > 0).mean()
    assert agree[False, 4] < 0.01  # turned outwards from its own mean: all inverted
    assert min(agree[True, t] for t in range(9)) > 0.99


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


def test_a_failing_tile_names_itself(tmp_path):
    path = tmp_path / "quad.ply"
    _write_ply_mesh(path, np.eye(4, 3), [[0, 1, 2], [0, 1, 2, 3]], counts=True)
    with pytest.raises(MeshFormatError, match="reads triangles"):
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
    from superfacets.scale import tile_layout

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


def test_a_meshs_merges_from_its_tiles_sums_are_one_runs_wards_merges():
    """A tiled mesh merges its few extra superfacets from the tiles' sums (no noise read:
    no flat merges) as one run's exact count merges the same labels on the whole graph."""
    from superfacets.method.finish import exact_count
    from superfacets.method.stages import resolve_rules
    from superfacets.scale.tile_merges import merge_names, tile_merge_stats

    mesh = _bumpy(4)
    g = face_graph(mesh)
    labels = np.asarray(segment(mesh, 60).labels, dtype=np.int64)
    names = np.arange(60, dtype=np.int64) * 7 + 3  # (the centers' rows, in a tiled run)
    south = g.positions[:, 1] < np.median(g.positions[:, 1])
    stats = [tile_merge_stats(g, labels, names, core, np.arange(g.n_elements), 0)
             for core in (south, ~south)]
    assert all(s["noise"].size == 0 for s in stats)
    p = resolve(n_segments=40)
    got, merged, flat, fewest = merge_names(stats, 40, p.alpha, p.eta_convex)
    assert flat == 60 and fewest == 40 and np.unique(merged).size == 40
    want, _ = exact_count(g, labels, resolve_rules(g, p))
    tiled = np.searchsorted(got, merged)[labels]  # each face's merged superfacet
    assert np.unique(want * 1000 + tiled).size == 40  # the same partition



def test_a_tile_whose_clean_up_leaves_a_piece_alone_names_it_by_a_center_of_its_own():
    """The clean-up makes a piece left with no neighbour a superfacet of its own (one
    tile of the bunny in 4, at 109 superfacets): the tile names it by a center in it, as
    one run does (it stopped the run with an IndexError), and the run gives exactly k."""
    from conftest import MESHES, need

    from superfacets.io import read_input
    from superfacets.scale import tiling

    seen = []
    real = tiling.clean_up

    def spy(graph, labels, kept, *a):
        out = real(graph, labels, kept, *a)
        seen.append(int(out.max()) + 1 - len(kept))
        return out

    mesh = read_input(need(MESHES / "bunny.tri.xz"))
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(tiling, "clean_up", spy)
        res = segment_tiled(mesh, 100, tiles=4)
    assert max(seen) >= 1  # the case: a superfacet more than centers
    assert res.n_segments == 100 and (res.labels >= 0).all()
    pieces = label_components(face_graph(mesh), res.labels)
    assert np.unique(pieces).size == 100

def test_a_tiled_mesh_with_merge_from_1_keeps_its_tiles_own_superfacets():
    mesh = _bumpy(4)
    res = segment_tiled(mesh, 60, tiles=4, merge_from=1)
    plain = segment_tiled(mesh, 60, tiles=4)
    assert res.params["merged_from"] is None and res.n_segments <= 60
    assert plain.n_segments == 60 and plain.params["merged_from"] >= 60


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


def test_a_scans_viewpoint_reaches_every_tile(tmp_path):
    from superfacets import PointCloud

    rng = np.random.default_rng(2)
    cloud = PointCloud(rng.random((500, 3)), viewpoint=np.array([0.5, 0.5, 5.0]))
    reader = RegionReader.spill(cloud, tmp_path)
    assert reader.viewpoint == (0.5, 0.5, 5.0)
    _, _, part = reader.read_box([0, 0, 0], [0.5, 0.5, 1])
    np.testing.assert_array_equal(part.viewpoint, [0.5, 0.5, 5.0])


def test_a_scans_viewpoint_reaches_the_start_on_its_sample(monkeypatch):
    """The sample a tiled scan starts from faces its scanner, as every tile does."""
    from superfacets.scale import tiling

    seen = []
    real = tiling.pipeline

    def pipeline(cloud, *args, **kw):
        seen.append(cloud.viewpoint)
        return real(cloud, *args, **kw)

    monkeypatch.setattr(tiling, "pipeline", pipeline)
    cloud = _bumpy_cloud(20_000)
    scan = PointCloud(cloud.points, viewpoint=np.array([0.0, 0.0, 9.0]))
    res = segment_tiled(scan, 30, tiles=4, merge_from=1)
    assert "start" in res.timings
    np.testing.assert_array_equal(seen[0], [0.0, 0.0, 9.0])  # (the start runs first)


def _lattice_cloud(n: int = 40, seed: int = 3):
    """A wavy sheet on an integer lattice, positions rounded to millimetres: the many
    equal distances of a quantized RGB-D scan."""
    from superfacets import PointCloud

    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    z = np.round(3 * np.sin(x / 6) * np.cos(y / 7), 0)
    rng = np.random.default_rng(seed)
    pts = np.c_[x.ravel(), y.ravel(), z.ravel()][rng.permutation(n * n)]
    return PointCloud(pts, viewpoint=np.array([n / 2, n / 2, 100.0]))


def test_equal_distances_give_a_tile_the_whole_clouds_neighbours():
    """Invariant: ties at the k-th distance go to the lowest index (the Z-order in the
    cloud's frame), so a box of the cloud given the whole cloud's frame (as a tiled run
    gives its tiles) has the whole cloud's neighbours away from its edge."""
    from superfacets import PointCloud
    from superfacets.elements.points import point_graph

    cloud = _lattice_cloud()
    whole = point_graph(cloud, 10).graph
    frame = np.array([cloud.points.min(axis=0), cloud.points.max(axis=0)])
    box = ((cloud.points[:, 0] >= 3) & (cloud.points[:, 0] < 28) & (cloud.points[:, 1] < 30))
    part = point_graph(PointCloud(cloud.points[box], frame=frame), 10).graph

    def neighbours(g):
        pos = g.positions
        return {tuple(pos[i]): {tuple(pos[j]) for j in g.indices[g.indptr[i]:g.indptr[i + 1]]}
                for i in range(g.n_elements)}

    a, b = neighbours(whole), neighbours(part)
    inner = [p for p in b if 8 <= p[0] < 23 and p[1] < 25]
    assert len(inner) == 375
    assert all(a[p] == b[p] for p in inner)
    assert any(len(a[p]) != 10 for p in inner)  # ties were in play (degrees vary)


def test_tile_connect_joins_stray_pieces_of_its_own_superfacets():
    """Known answer on a strip of 10 faces x 2: the stray piece of an owned label joins
    the neighbour it shares the longest border with; other labels' pieces are left."""
    from superfacets.scale.tiling import tile_connect

    v = np.array([[x, y, 0.0] for y in (0, 1) for x in range(11)])
    faces = []
    for x in range(10):
        a, b, c, d = x, x + 1, 11 + x, 12 + x
        faces += [[a, b, d], [a, d, c]]
    mesh = Mesh(v, np.array(faces))
    labels = np.repeat([100, 200, 100, 300, 300], 4).astype(np.int64)  # 100 in two pieces
    p = resolve(n_segments=3)
    fixed = tile_connect(mesh, labels, np.array([100]), np.array([0]), p)
    np.testing.assert_array_equal(fixed, np.repeat([100, 200, 200, 300, 300], 4))
    # not owned here (its center is in another tile's core): left as it is
    assert tile_connect(mesh, labels, np.array([200, 300]), np.array([4, 12]), p) is None
    # the center's piece keeps the name, wherever it is
    fixed = tile_connect(mesh, labels, np.array([100]), np.array([9]), p)
    np.testing.assert_array_equal(fixed, np.repeat([200, 200, 100, 300, 300], 4))


def test_tile_connect_on_points_reads_an_unoriented_graph_of_the_same_adjacency(monkeypatch):
    """The repair reads the adjacency, sizes and border lengths: on points it builds the
    graph without orienting the normals (a third of the build), and repairs as with the
    oriented graph."""
    from superfacets.elements import points
    from superfacets.inputs.cloud import PointCloud
    from superfacets.scale.tiling import tile_connect

    rng = np.random.default_rng(3)
    xyz = rng.normal(size=(4000, 3))
    xyz /= np.linalg.norm(xyz, axis=1, keepdims=True)
    cloud = PointCloud(xyz)
    u = points.point_graph(cloud, oriented=False).graph
    g = points.point_graph(cloud).graph
    assert u is not g and points.point_graph(cloud, oriented=False).graph is g  # (built)
    for name in ("indptr", "indices", "sizes", "border_shares", "lengths"):
        np.testing.assert_array_equal(getattr(u, name), getattr(g, name), err_msg=name)
    cos = (np.asarray(g.normals, float) * np.asarray(u.normals, float)).sum(axis=1)
    np.testing.assert_allclose(np.abs(cos), 1.0, atol=1e-5)
    assert (cos < 0).any()  # PCA's signs, not turned outwards
    labels = (xyz[:, 0] > 0).astype(np.int64) * 7 + 3  # two halves, names 3 and 10
    labels[(xyz[:, 0] < -0.6) & (xyz[:, 1] > 0.5)] = 10  # a stray piece of 10
    p = resolve(n_segments=2)
    center = np.array([int(np.argmax(xyz[:, 0]))])
    fixed = tile_connect(PointCloud(xyz), labels, np.array([10]), center, p)
    assert fixed is not None and (fixed[labels == 10] != 10).sum() > 0
    built = points.point_graph
    monkeypatch.setattr(points, "point_graph",
                        lambda *a, oriented=True, **k: built(*a, **k))  # oriented anyway
    np.testing.assert_array_equal(
        tile_connect(PointCloud(xyz), labels, np.array([10]), center, p), fixed)


def test_a_tile_graph_read_back_is_the_graph_built(tmp_path):
    """What the later phases of a tile read is what the first built: every array, the
    pairs' type, and the cloud's points given back bit for bit."""
    from superfacets.elements.points import point_graph
    from superfacets.inputs.cloud import PointCloud
    from superfacets.scale.tile_graphs import tile_graph

    xyz = np.random.default_rng(5).normal(size=(3000, 3))
    xyz[10] = xyz[11]  # a duplicate point: two rows, one element
    assert tile_graph(PointCloud(xyz.copy()), tmp_path / "tile-0", 10) == "built"
    assert not (tmp_path / "tile-0.part").exists()
    built = point_graph(PointCloud(xyz.copy()), 10)
    again = PointCloud(xyz.copy())
    assert tile_graph(again, tmp_path / "tile-0", 10) == "read"
    read = point_graph(again, 10)  # the graph read back, kept with the cloud
    for name in ("positions", "sizes", "normals", "indptr", "indices", "centroid", "lower",
                 "pairs", "lengths", "border_shares"):
        a, b = getattr(read.graph, name), getattr(built.graph, name)
        assert a.dtype == b.dtype and np.array_equal(a, b), name
    assert read.graph.diagonal == built.graph.diagonal
    np.testing.assert_array_equal(read.index, built.index)
    assert np.array_equal(again.points.view(np.uint64), xyz.view(np.uint64))
    # a half-written graph (a task stopped while saving) is not read: built again
    (tmp_path / "tile-1").mkdir()
    np.save(tmp_path / "tile-1" / "positions.npy", xyz)
    assert tile_graph(PointCloud(xyz.copy()), tmp_path / "tile-1", 10) != "read"


@pytest.mark.parametrize("change", ["indices", "indptr", "index", "positions", "meta"])
def test_a_tile_graph_changed_between_phases_is_refused(tmp_path, change):
    """Work files changed between phases went to the compiled kernels unchecked: an
    index of 2**62, an indptr entry past the end or a row of 2**30 crashed the process
    (SIGSEGV), other positions gave another cloud's labels. Each file's SHA-256 is kept
    with the graph and checked before anything reads it: one line."""
    from superfacets.errors import SuperfacetsError
    from superfacets.inputs.cloud import PointCloud
    from superfacets.scale.tile_graphs import tile_graph

    xyz = np.random.default_rng(5).normal(size=(2000, 3))
    folder = tmp_path / "tile-0"
    assert tile_graph(PointCloud(xyz.copy()), folder, 10) == "built"
    if change == "meta":  # a graph.json without the digests (or of another writer)
        (folder / "graph.json").write_text('{"pair_dtype": "int32"}')
    else:
        a = np.load(folder / f"{change}.npy")
        if change == "positions":
            a = a + 1e-9  # valid, but not the cloud's
        else:
            a.flat[len(a) // 2] = 2**30 if a.dtype.itemsize == 4 else 2**62
        np.save(folder / f"{change}.npy", a)
    with pytest.raises(SuperfacetsError, match="changed since this run wrote it"):
        tile_graph(PointCloud(xyz.copy()), folder, 10)


def test_tiles_that_keep_their_graphs_label_as_those_that_build_them(monkeypatch, tmp_path):
    """A cloud's tiles build their graphs once and read them in the later phases: the
    same labels as building them every phase, and the work folder left without them."""
    import superfacets.scale.runner.tiles as rt

    cloud = _bumpy_cloud(20000)
    seen, real = [], rt.tile_graph
    monkeypatch.setattr(rt, "tile_graph", lambda *a: seen.append(real(*a)) or seen[-1])
    kept = segment_tiled(cloud, 60, tiles=4, halo=1, workdir=tmp_path)
    assert seen.count("built") == 4 and seen.count("read") >= 8  # refine, labels (connect)
    assert not (tmp_path / "graphs").exists()
    monkeypatch.setattr(rt, "graph_folder", lambda *a: None)
    seen.clear()
    built = segment_tiled(cloud, 60, tiles=4, halo=1)
    assert seen == [] and kept.disagreements > 0  # (the connect phase ran too)
    np.testing.assert_array_equal(kept.labels, built.labels)


def test_a_quantized_scan_in_tiles_has_no_cut_superpoint():
    from superfacets.elements.points import point_graph

    cloud = _lattice_cloud(60)
    res = segment_tiled(cloud, 40, tiles=4)
    g = point_graph(cloud, 10)
    el = res.labels[np.argsort(g.index)]  # distinct points: one row per element
    assert np.unique(label_components(g.graph, el)).size == res.n_segments
    assert res.disagreements == 0 and res.repaired == 0


def test_the_connect_pass_repairs_pieces_left_by_a_thin_halo():
    """A halo of one expansion's reach makes tiles disagree at their borders; the pass
    after stitching leaves every superfacet in one piece."""
    mesh = _bumpy(5)  # how many pieces a thin halo leaves depends on the method: 72 here
    res = segment_tiled(mesh, 40, tiles=(2, 2, 2), halo=1)
    assert res.disagreements > 0 and res.repaired > 0 and "connect" in res.timings
    pieces = label_components(face_graph(mesh), res.labels)
    assert np.unique(pieces).size == res.n_segments


def test_the_connect_pass_looks_again_near_what_a_repair_moved(monkeypatch):
    """Tiles repair at once, from the same stitched labels: a piece one tile moves can be
    left apart by another's repair (seen on a 5M-point cloud in 16 tiles: 4 points).
    Here one tile's first repair also moves one face into a superfacet it does not
    touch; the tiles whose boxes hold that face look again, and every superfacet ends in
    one piece; then nothing moves, and the pass stops."""
    from superfacets.scale import tiling

    mesh = _bumpy(5)
    plain = segment_tiled(mesh, 40, tiles=(2, 2, 2), halo=1)  # 1 repair round suffices
    real, calls, spoiled = tiling.tile_connect, [], []

    def connect(inp, labels, owned, owned_rows, params):
        fixed = real(inp, labels, owned, owned_rows, params)
        calls.append(len(owned))
        if not spoiled and fixed is not None:  # one face of a far superfacet's, once
            out = fixed.copy()
            g = face_graph(inp)
            lab = np.asarray(out)
            for e in range(lab.size):
                near = set(lab[g.indices[g.indptr[e]:g.indptr[e + 1]]].tolist())
                far = [x for x in owned.tolist() if x not in near and x != lab[e]]
                if lab[e] in owned and far and (lab == lab[e]).sum() > 1:
                    out[e] = far[0]
                    spoiled.append(e)
                    return out
        return fixed

    monkeypatch.setattr(tiling, "tile_connect", connect)
    res = segment_tiled(mesh, 40, tiles=(2, 2, 2), halo=1)
    assert spoiled and len(calls) > 8  # a second round, on the tiles near the face
    assert len(calls) < 3 * 8  # not every tile every round: then nothing moved
    pieces = label_components(face_graph(mesh), res.labels)
    assert np.unique(pieces).size == res.n_segments
    assert res.repaired == plain.repaired + 2  # the face moved away, and back


def test_the_work_folder_is_the_runs_own(tmp_path, capsys):
    """A tiled run removed a user's W/graphs/ with its files, unlinked W/.lock and
    overwrote W/orientation.npy (exit 0): it now works in a folder of its own that it
    makes inside --workdir and removes at its end, nothing else there touched; two runs
    share a folder; the leftovers of a killed run are removed, and said, by the next."""
    import fcntl

    mesh = _bumpy(3)
    work = tmp_path / "work"
    (work / "graphs").mkdir(parents=True)
    mine = {work / "graphs" / "keep.txt": b"mine", work / "orientation.npy": b"not an array",
            work / ".lock": b"lock of mine"}
    for path, data in mine.items():
        path.write_bytes(data)
    live = work / "superfacets-tiles-live"  # another run, still going: its lock held
    live.mkdir()
    (live / "tile-0.npy").write_bytes(b"its work")
    held = open(live / "run.lock", "w")
    fcntl.flock(held, fcntl.LOCK_EX)
    dead = work / "superfacets-tiles-dead"  # a killed run's leftovers: lock released
    dead.mkdir()
    (dead / "run.lock").write_bytes(b"")
    (dead / "tile-0.npy").write_bytes(b"stale")
    try:
        res = segment_tiled(mesh, 20, tiles=2, workers=1, workdir=work)
        assert res.labels.shape == (mesh.n_faces,)
        assert all(path.read_bytes() == data for path, data in mine.items())
        assert (live / "tile-0.npy").read_bytes() == b"its work"  # the live run's, kept
        assert not dead.exists() and f"removed {dead}" in capsys.readouterr().err
        assert sorted(p.name for p in work.iterdir()) == [
            ".lock", "graphs", "orientation.npy", "superfacets-tiles-live"]
        # a folder inside a run's own folder: that run's end would remove it
        with pytest.raises(ParameterError, match="inside the work folder of a tiled run"):
            segment_tiled(mesh, 20, tiles=2, workers=1, workdir=live / "graphs")
    finally:
        held.close()
    with pytest.raises(ParameterError, match="empty path"):
        segment_tiled(mesh, 20, tiles=2, workers=1, workdir="")
    with pytest.raises(ParameterError, match="not a folder"):
        segment_tiled(mesh, 20, tiles=2, workers=1, workdir=work / ".lock")
    same = segment_tiled(mesh, 20, tiles=2, workers=1)  # a temporary folder: the same labels
    np.testing.assert_array_equal(same.labels, res.labels)


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
    with pytest.raises(InvalidMeshError, match="non-finite"):
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


def test_a_killed_tiled_run_leaves_nothing_for_long(tmp_path, monkeypatch, capsys):
    """A SIGKILLed tiled run left its temporary folder (about 14 times the input)
    forever: without --workdir the runs work in the system's temporary folder the same
    way, and the next run removes what a killed one left (its lock released)."""
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    dead = tmp_path / "superfacets-tiles-killed"
    dead.mkdir()
    (dead / "run.lock").write_bytes(b"")
    (dead / "buckets").mkdir()
    other = tmp_path / "superfacets-tiles-not-ours"  # no lock file: not a run's, kept
    other.mkdir()
    res = segment_tiled(_bumpy(3), 20, tiles=2, workers=1)
    assert res.n_segments > 0 and not dead.exists() and other.exists()
    assert f"removed {dead}" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["superfacets-tiles-not-ours"]


def test_option_extremes_are_refused_before_any_work(tmp_path, monkeypatch):
    """--tiles 1000,1000,1000 built the layout of a billion tiles (exit 134 after 55 s and
    3.7 GiB) before the count was checked; 1,1,99999999999999999999 and a 400-digit count
    were tracebacks; --refine and -j had no bound (-j 1000 started 1,000 processes). Each
    is one line now, before the tile layout (none is built) and before any worker."""
    import superfacets.scale.tile_layout as layouts
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


def test_a_tile_file_changed_before_it_is_read_is_refused(tmp_path, monkeypatch):
    """A changed row number in a tile's file (the input sorted by tile, in the work
    folder) was a traceback, and changed positions gave other elements' labels: each
    file's SHA-256 is kept and checked before a task reads it."""
    from superfacets.errors import SuperfacetsError

    mesh = _bumpy(4)
    path = tmp_path / "m.ply"
    _write_ply_mesh(path, mesh.vertices, mesh.faces)
    real = buckets_module.bucket

    def tampered(reader, tiles, folder, **kw):
        out = real(reader, tiles, folder, **kw)
        tile = sorted(Path(folder).glob("tile-*.bin"))[0]
        data = bytearray(tile.read_bytes())
        data[3] ^= 0x40  # the first record's row number
        tile.write_bytes(bytes(data))
        return out

    monkeypatch.setattr(buckets_module, "bucket", tampered)
    with pytest.raises(SuperfacetsError, match="changed since this run wrote it"):
        segment_tiled(path, 20, tiles=2, workers=1, workdir=tmp_path / "work")


def test_a_full_disk_under_the_work_folder_says_so(tmp_path, monkeypatch):
    """A full disk under the work folder said only '50000 requested and 48256 written'
    (numpy's short write): it names the folder and the room the tiles' files need."""
    import builtins

    mesh = _bumpy(3)
    path = tmp_path / "m.ply"
    _write_ply_mesh(path, mesh.vertices, mesh.faces)

    class Full:
        def __init__(self, *a, **k):
            pass

        def __enter__(self):
            raise OSError("50000 requested and 48256 written")

        def __exit__(self, *a):
            return False

    real_open = builtins.open
    monkeypatch.setattr(buckets_module, "open",
                        lambda p, mode="r", *a, **k: Full() if str(p).endswith(".bin")
                        and "a" in mode else real_open(p, mode, *a, **k), raising=False)
    with pytest.raises(OSError, match=r"the tiles' files of the input could not be written "
                                      r"\(50000 requested.*needs about the input's size free"):
        segment_tiled(path, 20, tiles=2, workers=1, workdir=tmp_path / "work")
    assert list((tmp_path / "work").iterdir()) == []  # (the run's own folder, removed)


def test_a_sample_of_fewer_than_three_distinct_points_gives_no_reference():
    """The survey's sample is oriented only where it holds three distinct points (a pass
    per point found, as ``np.unique`` over its rows counted them): one or two distinct
    points, repeated, give empty arrays; a third anywhere in the sample gives normals."""
    from superfacets.scale.tiling import _three_distinct, orientation_reference

    rng = np.random.default_rng(11)
    a, b, c = np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 1.0, 0])
    for rows, want in (([a], False), ([a, a, a], False), ([a, b, a, b, b], False),
                       ([a, b, c], True), ([b, b, b, b, a, a, c], True),
                       ([a, -0.0 * a, b], False)):
        pts = np.array(rows, dtype=np.float64)
        assert _three_distinct(pts) == want == (np.unique(pts, axis=0).shape[0] >= 3)
    for _ in range(20):
        pts = rng.integers(0, 2, (rng.integers(1, 9), 3)).astype(np.float64)
        assert _three_distinct(pts) == (np.unique(pts, axis=0).shape[0] >= 3)
    positions, normals = orientation_reference(np.array([a, b] * 50), 10)
    assert positions.shape == normals.shape == (0, 3)


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
