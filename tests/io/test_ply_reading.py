"""Binary PLY triangles read by plyfile's memory map (``superfacets.io.ply.read_ply_triangles``):
the arrays trimesh's parser gives, None (the general readers) for anything else."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import trimesh
from plyfile import PlyData, PlyElement

from superfacets import MeshFormatError, read_mesh
from superfacets.io.meshes import _load_trimesh
from superfacets.io.ply import read_ply_triangles


def _sphere():
    return trimesh.creation.icosphere(subdivisions=2)


def _write(path, vertex_fields, faces, index="<i4", count="u1", byte_order="<", face_extra=(),
           more=()):
    m = _sphere()
    v = np.empty(len(m.vertices), dtype=vertex_fields)
    for c, _ in vertex_fields:  # coordinates, and colours of many values
        v[c] = m.vertices[:, "xyz".index(c)] if c in "xyz" else np.arange(len(v)) * 7 % 256
    f = np.empty(len(faces), dtype=[("vertex_indices", index, (faces.shape[1],))]
                 + list(face_extra))
    f["vertex_indices"] = faces
    for name, _ in face_extra:
        f[name] = np.arange(len(faces)) * 5 % 256
    elements = [PlyElement.describe(v, "vertex"),
                PlyElement.describe(f, "face", len_types={"vertex_indices": count})]
    PlyData(elements + list(more), byte_order=byte_order).write(str(path))
    return path


XYZ = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")]


@pytest.mark.parametrize("case", ["float", "double big-endian", "uint indices",
                                  "vertex colours", "face colours", "uint count"])
def test_binary_triangles_give_the_arrays_of_trimesh(tmp_path, case):
    faces = _sphere().faces
    kw = {}
    fields = XYZ
    if case == "double big-endian":
        fields, kw = [(c, ">f8") for c in "xyz"], dict(byte_order=">", index=">i4")
    elif case == "uint indices":
        kw = dict(index="<u4")
    elif case == "vertex colours":
        fields = XYZ + [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    elif case == "face colours":
        kw = dict(face_extra=[("red", "u1"), ("green", "u1"), ("blue", "u1")])
    elif case == "uint count":
        kw = dict(count="u4")
    path = _write(tmp_path / "m.ply", fields, faces, **kw)
    data = path.read_bytes()
    got = read_ply_triangles(path, data)
    assert got is not None
    want = _load_trimesh(data, "ply", path)
    np.testing.assert_array_equal(got[0], want[0])
    assert got[0].dtype == np.float64
    assert not any(isinstance(a, np.memmap) or isinstance(a.base, np.memmap)
                   for a in got if a is not None)  # copies: the file is not held
    np.testing.assert_array_equal(got[1], want[1])
    assert got[1].dtype == (np.int64 if case == "uint indices" else np.int32)
    for a, b in zip(got[2:], want[2:]):
        assert (a is None) == (b is None)
        if a is not None:
            np.testing.assert_array_equal(a, b)
    assert (got[2] is not None) == (case == "vertex colours")
    assert (got[3] is not None) == (case == "face colours")
    # read_mesh gives the same mesh through either reader
    mesh = read_mesh(path)
    np.testing.assert_array_equal(mesh.faces, faces)


def test_anything_else_goes_to_the_general_readers(tmp_path):
    m = _sphere()
    ascii_path = tmp_path / "a.ply"
    ascii_path.write_bytes(trimesh.exchange.ply.export_ply(m, encoding="ascii"))
    quads = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])
    quad_path = _write(tmp_path / "q.ply", XYZ, quads)
    extra = PlyElement.describe(np.zeros(2, dtype=[("a", "<i4")]), "edge")
    extra_path = _write(tmp_path / "e.ply", XYZ, m.faces, more=[extra])
    wide = _write(tmp_path / "c16.ply", XYZ + [("red", "<u2"), ("green", "<u2"),
                                               ("blue", "<u2")], m.faces)
    for path in (ascii_path, quad_path, extra_path, wide):
        assert read_ply_triangles(path, path.read_bytes()) is None, path.name
    assert read_mesh(ascii_path).n_faces == len(m.faces)
    assert read_mesh(quad_path).face_sizes.tolist() == [4, 4]  # polygons, as before
    assert read_mesh(extra_path).n_faces == len(m.faces)
    assert read_mesh(wide).colors is not None


def test_mixed_sizes_and_short_files_are_not_misread(tmp_path):
    """A file of triangles with one quad among them, and one cut short: not read as
    triangles (the count of every face is checked; the map needs the whole file)."""
    m = _sphere()
    path = _write(tmp_path / "t.ply", XYZ, m.faces)
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    at = end + 12 * len(m.vertices)  # the first face's count byte
    mixed = bytearray(data)
    mixed[at] = 4
    bad = tmp_path / "mixed.ply"
    bad.write_bytes(bytes(mixed))
    assert read_ply_triangles(bad, bytes(mixed)) is None
    short = tmp_path / "short.ply"
    short.write_bytes(data[:-7])
    assert read_ply_triangles(short, data[:-7]) is None
    with pytest.raises(MeshFormatError):
        read_mesh(short)


def test_reading_binary_triangles_imports_no_trimesh(tmp_path):
    path = _write(tmp_path / "m.ply", XYZ, _sphere().faces)
    code = ("import sys; from superfacets import read_mesh; "
            f"m = read_mesh({str(path)!r}); "
            "print(m.n_faces, 'trimesh' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == [str(len(_sphere().faces)), "False"]


def test_binary_triangles_are_mapped_not_read_whole(tmp_path, monkeypatch):
    """The common PLY's header is read (its first 64 KiB), its arrays mapped: the file is
    never read whole (a 6.8M-face file was read into memory, 169 MB, only to be mapped);
    an ASCII PLY still is, by the general readers."""
    from pathlib import Path

    m = _sphere()
    path = _write(tmp_path / "m.ply", XYZ, m.faces)
    ascii_path = tmp_path / "a.ply"
    ascii_path.write_bytes(trimesh.exchange.ply.export_ply(m, encoding="ascii"))
    whole = []
    real = Path.read_bytes
    monkeypatch.setattr(Path, "read_bytes", lambda self: whole.append(self.name) or real(self))
    got = read_mesh(path)
    assert whole == [] and got.n_faces == len(m.faces)
    np.testing.assert_array_equal(got.faces, m.faces)
    assert read_mesh(ascii_path).n_faces == len(m.faces) and whole == ["a.ply"]
    empty = tmp_path / "empty.ply"
    empty.write_bytes(b"")
    with pytest.raises(MeshFormatError, match="empty"):
        read_mesh(empty)


@pytest.mark.parametrize("byte_order", ["<", ">"])
def test_a_binary_ply_of_points_is_read_whole_as_plyfile_reads_it(tmp_path, byte_order):
    """Known answer: a PLY cloud (positions, normals, 8-bit colours, an extra element),
    binary or ASCII, read by arrays (read_ply_scalars) gives plyfile's values, compressed
    or not; a short body is left to plyfile (None)."""
    import gzip

    from plyfile import PlyData, PlyElement

    from superfacets import read_cloud
    from superfacets.io.ply import read_ply_scalars

    rng = np.random.default_rng(2)
    n = 500
    v = np.empty(n, dtype=[("x", "f4"), ("y", "f4"), ("z", "f8"), ("nx", "f4"), ("ny", "f4"),
                           ("nz", "f4"), ("red", "u1"), ("green", "u1"), ("blue", "u1")])
    for name in v.dtype.names[:3]:
        v[name] = rng.normal(size=n)
    nrm = rng.normal(size=(n, 3))
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    v["nx"], v["ny"], v["nz"] = nrm.T
    for name in ("red", "green", "blue"):
        v[name] = rng.integers(0, 256, n)
    extra = np.zeros(3, dtype=[("t", "i4")])
    ply = PlyData([PlyElement.describe(v, "vertex"), PlyElement.describe(extra, "camera")],
                  byte_order=byte_order)
    path = tmp_path / "c.ply"
    ply.write(str(path))
    (tmp_path / "c.ply.gz").write_bytes(gzip.compress(path.read_bytes()))
    got = read_ply_scalars(path.read_bytes())
    assert set(got) == {"vertex", "camera"} and got["camera"].count == 3
    for name in v.dtype.names:
        np.testing.assert_array_equal(got["vertex"][name], v[name])
    for f in (path, tmp_path / "c.ply.gz"):
        c = read_cloud(f)
        np.testing.assert_array_equal(c.points, np.c_[v["x"], v["y"], v["z"]].astype(float))
        np.testing.assert_allclose(c.normals, nrm, atol=1e-6)
        np.testing.assert_array_equal(np.round(c.colors * 255), np.c_[v["red"], v["green"],
                                                                      v["blue"]])
    PlyData([PlyElement.describe(v, "vertex")], text=True).write(str(tmp_path / "a.ply"))
    text = read_ply_scalars((tmp_path / "a.ply").read_bytes())["vertex"]
    ref = PlyData.read(str(tmp_path / "a.ply"))["vertex"]
    for name in v.dtype.names:
        np.testing.assert_array_equal(text[name], ref[name])
    assert read_ply_scalars(path.read_bytes()[:-1]) is None  # a body one byte short
