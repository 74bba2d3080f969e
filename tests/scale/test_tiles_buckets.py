"""Reading an input by boxes, and the tiles' buckets (superfacets.scale.tiles.buckets)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import trimesh
from tiled import _bumpy, _write_ply_mesh

from superfacets import Mesh
from superfacets.elements.faces import face_graph
from superfacets.errors import MeshFormatError
from superfacets.io.regions import RegionReader
from superfacets.scale.tiles import buckets as buckets_module
from superfacets.scale.tiles.buckets import bucket
from superfacets.scale.tiles.layout import (
    balanced_tiles,
    tile_box,
    tile_grid,
)
from superfacets.scale.tiles.run import segment_tiled


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


@pytest.mark.parametrize("in_memory", [True, False])
def test_a_ply_meshs_chunks_are_its_centroids_and_areas_bit_for_bit(tmp_path, monkeypatch,
                                                                    in_memory):
    """Each chunk's face centroids and areas are numpy's mean of the corners and half the
    norm of their cross product, bit for bit (the tiles' core membership reads them),
    whether the vertex positions are read into memory or gathered from the mapped file."""
    from superfacets.io import regions

    if not in_memory:
        monkeypatch.setattr(regions, "VERTEX_TABLE_BYTES", 0)
    mesh = _bumpy(3)
    path = tmp_path / "m.ply"
    _write_ply_mesh(path, mesh.vertices, mesh.faces)
    v32 = np.asarray(mesh.vertices, dtype=np.float32).astype(np.float64)
    corners = v32[np.asarray(mesh.faces)]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0],
                                         corners[:, 2] - corners[:, 0]), axis=1)
    chunks = list(RegionReader.open(path, chunk=97).chunks())
    assert isinstance(chunks[0][3][1], np.ndarray) == in_memory  # (the vertex table)
    for start, pos, size, _ in chunks:
        np.testing.assert_array_equal(pos, corners[start:start + 97].mean(axis=1))
        np.testing.assert_array_equal(size, area[start:start + 97])


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
    # a face's record leaves out its position (its corners' mean, computed again: the
    # positions read below are the file's bit for bit); a point's keeps it
    assert ("pos" in buckets.dtype.names) == (kind != "ply-mesh")
    if kind == "ply-mesh":
        assert buckets.dtype.itemsize == 8 + 24 + 72  # row, vertex indices, corners
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
    with pytest.raises(MeshFormatError, match="not a triangle.*row 1"):
        RegionReader.open(tmp_path / "quad.ply").survey()
    good = tmp_path / "m.ply"
    _write_ply_mesh(good, *(lambda m: (m.vertices, m.faces))(trimesh.creation.icosphere(2)))
    (tmp_path / "cut.ply").write_bytes(good.read_bytes()[:-100])
    with pytest.raises(MeshFormatError, match="cannot read PLY"):
        RegionReader.open(tmp_path / "cut.ply")
    np.save(tmp_path / "flat.npy", np.zeros((4, 2)))
    with pytest.raises(MeshFormatError, match=r"shape \(N, 3\)"):
        RegionReader.open(tmp_path / "flat.npy")


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


@pytest.mark.parametrize("colored", [False, True])
def test_a_mesh_box_written_from_what_was_read_reads_back_the_same(tmp_path, colored):
    """A held mesh tile's box is written only when the tile is let go, from its rows,
    positions and mesh (``mesh_records``): read back, the same rows, positions, vertices,
    faces and face colours as the box read from the tiles' files."""
    from superfacets.scale.tiles.buckets import keep_box, mesh_records

    mesh = _bumpy(3)
    rng = np.random.default_rng(5)
    colors = rng.random((mesh.faces.shape[0], 3)) if colored else None
    reader = RegionReader.spill(Mesh(mesh.vertices, mesh.faces, face_colors=colors),
                                tmp_path / "spill", chunk=333)
    s = reader.survey()
    buckets = bucket(reader, balanced_tiles(s.sample, s.lo, s.hi, 4), tmp_path / "b")
    lo, hi = tile_box(balanced_tiles(s.sample, s.lo, s.hi, 4), 1, 0.2)
    first = buckets.read_box(lo, hi)
    keep = tmp_path / "box-1"
    assert not buckets.kept(keep, lo, hi)
    keep_box(keep, mesh_records(buckets.dtype, *first), np.asarray(lo, float),
             np.asarray(hi, float))
    assert buckets.kept(keep, lo, hi) and not buckets.kept(keep, lo, hi + 0.1)
    for name in [p.name for p in (tmp_path / "b").iterdir()]:  # from the kept file alone
        (tmp_path / "b" / name).rename(tmp_path / f"away-{name}")
    again = buckets.read_box(lo, hi, keep=keep)
    _same_box(again, first)
    if colored:
        np.testing.assert_array_equal(again[2].face_colors, first[2].face_colors)
        assert again[2].face_colors is not None
