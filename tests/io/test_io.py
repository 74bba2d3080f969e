import bz2
import gzip
import lzma
import os

import numpy as np
import pytest
import trimesh
from conftest import MESHES, need

from superfacets import (
    InvalidMeshError,
    Mesh,
    MeshFormatError,
    read_labels,
    read_mesh,
    write_colored_mesh,
    write_labels,
    write_mesh,
)
from superfacets.elements import face_graph
from superfacets.io import atomic_write
from superfacets.io.colors import superfacet_adjacency


@pytest.fixture
def box():
    b = trimesh.creation.box()
    return Mesh(b.vertices, b.faces)


@pytest.mark.parametrize("suffix", [".off", ".tri", ".ply", ".obj", ".stl",
                                    ".off.gz", ".tri.xz", ".ply.bz2", ".obj.gz"])
def test_round_trip_keeps_faces_in_order(tmp_path, box, suffix):
    path = write_mesh(tmp_path / f"box{suffix}", box)
    m = read_mesh(path)
    assert m.n_faces == box.n_faces
    # the same triangles, in the same order (vertex ids may be renumbered)
    np.testing.assert_allclose(m.vertices[m.faces], box.vertices[box.faces], atol=1e-6)


def test_stl_vertices_are_merged(tmp_path, box):
    m = read_mesh(write_mesh(tmp_path / "box.stl", box))
    assert m.n_vertices == 8
    assert face_graph(m).n_edges == 18


def test_off_with_comments_counts_on_header_and_colors(tmp_path):
    p = tmp_path / "c.off"
    p.write_text("OFF 4 2 0\n# a comment\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n"
                 "3 0 1 2 255 0 0\n3 1 3 2 0 255 0\n")
    m = read_mesh(p)
    np.testing.assert_array_equal(m.faces, [[0, 1, 2], [1, 3, 2]])


def test_tri_format_as_documented(tmp_path):
    p = tmp_path / "t.tri"
    p.write_text("3\n0 0 0\n1 0 0\n0 1 0\n1\n0 1 2\n")
    m = read_mesh(p)
    assert m.n_faces == 1 and m.n_vertices == 3


@pytest.mark.parametrize("name, content, match", [
    ("trunc.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n", "expected 2 faces, found 1"),
    ("truncv.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n", "expected 4 vertices, found 2"),
    ("bad.off", "OFF\n3 1 0\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n", "malformed vertex lines"),
    ("line.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 1\n", "3 or more needed"),
    ("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "out of range"),
    ("nan.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", "NaN or infinite"),
    ("empty.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", "empty mesh"),
    ("nothing.off", "", "empty file"),
    ("magic.off", "PLY\n3 1 0\n", "not an OFF file"),
    ("counts.off", "OFF\nthree 1 0\n", "expected the vertex count"),
    ("trunc.tri", "3\n0 0 0\n1 0 0\n0 1 0\n2\n0 1 2\n", "expected 2 faces, found 1"),
    ("nofaces.tri", "3\n0 0 0\n1 0 0\n0 1 0\n", "no face count"),
    ("quad.tri", "4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n1\n0 1 2 3\n", "face lines have 4 indices"),
    ("mesh.xyz", "1 2 3\n", "unknown mesh format .xyz"),
    ("noext", "1 2 3\n", "unknown mesh format"),
    ("broken.off.gz", "not gzip data", "cannot decompress"),
])
def test_malformed_files(tmp_path, name, content, match):
    p = tmp_path / name
    p.write_text(content)
    with pytest.raises((MeshFormatError, InvalidMeshError), match=match) as info:
        read_mesh(p)
    assert str(p) in str(info.value) or p.name in str(info.value)


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such file"):
        read_mesh(tmp_path / "none.off")
    d = tmp_path / "dir.off"
    d.mkdir()
    with pytest.raises(IsADirectoryError):
        read_mesh(d)


def test_binary_data_in_text_format(tmp_path):
    p = tmp_path / "bin.off"
    p.write_bytes(b"OFF\n\xff\xfe\x00\x01")
    with pytest.raises(MeshFormatError, match="not a text file"):
        read_mesh(p)


def test_ply_and_obj_quads_are_read_as_quads(tmp_path):
    ply = tmp_path / "q.ply"
    ply.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\n"
                    b"property float y\nproperty float z\nelement face 2\n"
                    b"property list uchar int vertex_indices\nend_header\n"
                    b"0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n4 0 1 2 3\n3 1 4 2\n")
    m = read_mesh(ply)  # mixed sizes: trimesh would split and reorder them
    assert [p.tolist() for p in m.polygons()] == [[0, 1, 2, 3], [1, 4, 2]]
    obj = tmp_path / "q.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    assert read_mesh(obj).faces.tolist() == [[0, 1, 2, 3]]


def test_garbage_ply(tmp_path):
    p = tmp_path / "g.ply"
    p.write_bytes(b"this is not a ply file at all")
    with pytest.raises((MeshFormatError, InvalidMeshError), match="g.ply"):
        read_mesh(p)


def test_labels_round_trip_with_header(tmp_path):
    labels = np.array([3, 0, 2, 2, 1])
    p = write_labels(tmp_path / "x.seg", labels, header={"alpha": 200, "iterations": 7})
    text = p.read_text()
    assert text.startswith("# alpha: 200\n# iterations: 7\n3\n0\n")
    np.testing.assert_array_equal(read_labels(p, n_faces=5), labels)
    plain = write_labels(tmp_path / "y.seg", labels)
    assert plain.read_text() == "3\n0\n2\n2\n1\n"
    gz = write_labels(tmp_path / "z.seg.gz", labels)
    np.testing.assert_array_equal(read_labels(gz), labels)


def test_label_file_errors(tmp_path):
    p = tmp_path / "bad.seg"
    p.write_text("1\n2\nx\n")
    with pytest.raises(MeshFormatError, match="malformed label file"):
        read_labels(p)
    p.write_text("1\n2\n")
    with pytest.raises(MeshFormatError, match="has 2 labels but the input has 3 elements"):
        read_labels(p, n_faces=3)
    with pytest.raises(FileNotFoundError):
        read_labels(tmp_path / "none.seg")
    with pytest.raises(ValueError, match="1-D array of integers"):
        write_labels(tmp_path / "f.seg", np.array([0.5, 1.0]))


def test_atomic_write_leaves_nothing_on_failure(tmp_path):
    target = tmp_path / "out.seg"
    target.write_text("old content\n")

    def boom(fh):
        fh.write(b"partial")
        raise RuntimeError("interrupted")

    with pytest.raises(RuntimeError):
        atomic_write(target, boom)
    assert target.read_text() == "old content\n"
    assert os.listdir(tmp_path) == ["out.seg"]
    with pytest.raises(FileNotFoundError, match="does not exist"):
        atomic_write(tmp_path / "no" / "x.seg", b"1\n")


def test_colored_mesh_adjacent_superfacets_differ(tmp_path, sphere):
    from superfacets import superfacets

    labels = superfacets(sphere, 40, alpha=0)
    p = write_colored_mesh(tmp_path / "c.ply", sphere, labels)
    tm = trimesh.load(p, process=False)
    colors = np.asarray(tm.visual.face_colors)[:, :3]
    assert len(tm.faces) == sphere.n_faces
    # one colour per superfacet
    for s in range(labels.max() + 1):
        assert len(np.unique(colors[labels == s], axis=0)) == 1
    rep = np.array([colors[np.flatnonzero(labels == s)[0]] for s in range(labels.max() + 1)])
    for s, t in superfacet_adjacency(sphere, labels):
        assert not np.array_equal(rep[s], rep[t])


def test_compressed_inputs_match_plain(tmp_path, box):
    plain = write_mesh(tmp_path / "b.off", box).read_bytes()
    for ext, comp in ((".gz", gzip.compress), (".xz", lzma.compress), (".bz2", bz2.compress)):
        p = tmp_path / f"b.off{ext}"
        p.write_bytes(comp(plain))
        np.testing.assert_array_equal(read_mesh(p).faces, box.faces)


@pytest.mark.parametrize("name, faces", [("bunny", 69451), ("horse", 96966), ("hand_olivier",
                                                                              105860)])
def test_table1_meshes_load(name, faces):
    m = read_mesh(need(MESHES / f"{name}.tri.xz"))
    assert m.n_faces == faces


def test_obj_reader_follows_the_obj_rules(tmp_path):
    # relative (negative) indices count back from the vertices defined so far; tabs separate;
    # i/t/n keeps i; other statements are skipped; index 0 is an error
    p = tmp_path / "m.obj"
    p.write_text("# c\nv 0 0 0\nv\t1 0 0\nv 0 1 0\nvt 0 0\nf -3/1 -2/1 -1/1\no second\n"
                 "v 0 0 1\nf\t1//1 2//1 -1//1\nusemtl x\nf 4 2 3\n")
    m = read_mesh(p)
    assert m.faces.tolist() == [[0, 1, 2], [0, 1, 3], [3, 1, 2]]
    assert m.vertices.tolist()[3] == [0, 0, 1]
    p.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")
    with pytest.raises(MeshFormatError, match="index 0"):
        read_mesh(p)
    p.write_text("v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n")
    with pytest.raises(MeshFormatError, match="out of range"):
        read_mesh(p)


def test_outputs_are_all_or_nothing_and_follow_links(tmp_path):
    import os

    from superfacets.io.files import Outputs

    target = tmp_path / "real.seg"
    target.write_text("old\n")
    os.chmod(target, 0o600)
    link = tmp_path / "link.seg"
    link.symlink_to(target)
    with Outputs() as out:
        out.write(link, b"new\n")
    assert link.is_symlink() and target.read_text() == "new\n"
    assert (target.stat().st_mode & 0o777) == 0o600  # permissions kept

    def boom(fh):
        fh.write(b"partial")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        with Outputs() as out:
            out.write(tmp_path / "a.txt", b"a")
            out.write(tmp_path / "b.txt", boom)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.seg", "real.seg"]
    with Outputs() as out:  # a character device is written in place, never replaced
        out.write("/dev/null", b"x")
    assert os.path.exists("/dev/null") and not os.path.isfile("/dev/null")


def test_an_output_error_names_the_target_not_the_staged_file(tmp_path, monkeypatch):
    """A folder where no file can be made (``/proc``), or a write that fails (a full disk):
    the error names the file asked for, not the hidden temporary one, and none is left."""
    import errno

    from superfacets.io.files import Outputs

    with pytest.raises(OSError) as info:
        with Outputs() as out:
            out.write("/proc/x.las", b"x")
    assert info.value.filename == "/proc/x.las" and ".tmp" not in str(info.value)

    def full(fh):
        raise OSError(errno.ENOSPC, "No space left on device")

    with pytest.raises(OSError) as info:
        with Outputs() as out:
            out.write(tmp_path / "a.seg", full)
    assert info.value.filename == str(tmp_path / "a.seg")
    assert info.value.errno == errno.ENOSPC and list(tmp_path.iterdir()) == []


def test_sigterm_removes_temporary_files(tmp_path):
    import subprocess
    import sys

    code = f"""
import os, signal, sys
from superfacets.cli import _terminate_cleanly, _Terminated
from superfacets.io.files import Outputs
_terminate_cleanly()
def content(fh):
    fh.write(b"half")
    os.kill(os.getpid(), signal.SIGTERM)
    fh.write(b"never")
try:
    with Outputs() as out:
        out.write({str(tmp_path / 'x.seg')!r}, content)
except _Terminated:
    sys.exit(143)
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 143, r.stderr
    assert list(tmp_path.iterdir()) == []


def test_labels_to_stdout_and_broken_pipe(tmp_path):
    import subprocess
    import sys

    from conftest import grid_mesh

    mesh = tmp_path / "g.off"
    write_mesh(mesh, grid_mesh(20, 20))
    r = subprocess.run([sys.executable, "-m", "superfacets", "segment", str(mesh), "-k", "10",
                        "-o", "-"], capture_output=True, text=True)
    assert r.returncode == 0 and len(r.stdout.split()) == 800  # the labels, one per face
    assert "800 faces" in r.stderr  # the summary goes to stderr then
    r = subprocess.run(f"{sys.executable} -m superfacets segment {mesh} -k 10 -o - | head -1",
                       shell=True, capture_output=True, text=True)
    assert r.stdout.strip().isdigit() and "Error" not in r.stderr and "Traceback" not in r.stderr


def test_a_full_device_as_output_is_named_in_the_error(tmp_path, capsys):
    """A device is written in place (it cannot be staged); its error names it."""
    from pathlib import Path

    from superfacets.cli import main

    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full on this system")
    mesh = tmp_path / "m.off"
    mesh.write_text("OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n")
    assert main(["segment", str(mesh), "-k", "1", "-o", "/dev/full"]) == 2
    err = capsys.readouterr().err
    assert "/dev/full" in err and "No space left" in err and "Traceback" not in err


def test_non_ascii_and_multiline_names_are_written(tmp_path):
    """Scenes whose objects are named ``Tür`` (OBJ ``o``, glTF nodes), an accented file
    name in a ``--header``, an OBJ coloured mesh named so: UTF-8 everywhere; a name with
    a line break stays on its header line, so the file reads back."""
    import trimesh

    from superfacets.cli import main

    box = trimesh.creation.box()
    lines = ["o Tür"] + [f"v {x} {y} {z}" for x, y, z in box.vertices] + [
        f"f {a + 1} {b + 1} {c + 1}" for a, b, c in box.faces[:6]] + ["o Straße"] + [
        f"f {a + 1} {b + 1} {c + 1}" for a, b, c in box.faces[6:]]
    obj = tmp_path / "Küche.obj"
    obj.write_text("\n".join(lines) + "\n", encoding="utf-8")
    seg = tmp_path / "Küche.seg"
    assert main(["segment", str(obj), "-k", "4", "-o", str(seg), "--header",
                 "--colored-mesh", str(tmp_path / "Küche_sf.obj"), "-q"]) == 0
    text = seg.read_text(encoding="utf-8")
    assert "# object Tür: faces 0-5" in text and "Küche.obj" in text
    assert "mtllib Küche_sf.mtl" in (tmp_path / "Küche_sf.obj").read_text(encoding="utf-8")
    assert main(["evaluate", str(obj), str(seg), str(seg)]) == 0
    scene = trimesh.Scene()
    scene.add_geometry(box, node_name="lid\nevil: 1", geom_name="lid\nevil: 1")
    scene.add_geometry(trimesh.creation.icosphere(), node_name="ball", geom_name="ball")
    glb = tmp_path / "scene.glb"
    scene.export(glb)
    seg = tmp_path / "scene.seg"
    assert main(["segment", str(glb), "-k", "6", "-o", str(seg), "-q"]) == 0
    head = [ln for ln in seg.read_text(encoding="utf-8").splitlines() if ln.startswith("#")]
    assert len(head) == 2 and all(ln.startswith("# object ") for ln in head)
    assert main(["evaluate", str(glb), str(seg), str(seg)]) == 0


@pytest.mark.parametrize("version", ["1.2", "1.4"])
def test_las_record_level_damage_is_refused_by_both_readers(tmp_path, version):
    """A file truncated at a record boundary, a point count larger than the data, a wrong
    point record length: a whole run read fewer or garbage points and exited 0, the tiled
    reader refused them. One check now serves both."""
    import struct

    laspy = pytest.importorskip("laspy")
    from superfacets import read_cloud
    from superfacets.errors import MeshFormatError
    from superfacets.io.regions import RegionReader

    header = laspy.LasHeader(point_format=3, version=version)
    header.scales = [0.001] * 3
    las = laspy.LasData(header)
    pts = np.random.default_rng(0).random((500, 3))
    las.x, las.y, las.z = pts.T
    good = tmp_path / "good.las"
    las.write(good)
    data = good.read_bytes()
    start = struct.unpack_from("<I", data, 96)[0]
    length = struct.unpack_from("<H", data, 105)[0]
    assert read_cloud(good).n_points == 500
    damaged = {
        "cut": data[:start + 400 * length],  # at a record boundary
        "count": data[:107] + struct.pack("<I", 600) + data[111:],
        "record": data[:105] + struct.pack("<H", length - 2) + data[107:],
        "short-record": data[:105] + struct.pack("<H", 20) + data[107:],
    }
    if version == "1.4":  # the 64-bit count is the one 1.4 readers use
        damaged["count"] = (data[:107] + struct.pack("<I", 0) + data[111:247] +
                            struct.pack("<Q", 600) + data[255:])
    for name, blob in damaged.items():
        path = tmp_path / f"{name}.las"
        path.write_bytes(blob)
        with pytest.raises(MeshFormatError, match="damaged LAS file"):
            read_cloud(path)
        with pytest.raises(MeshFormatError, match="damaged LAS file"):
            RegionReader.open(path)


def test_headers_that_claim_more_than_the_file_are_refused_unread(tmp_path):
    """A PLY header declaring billions of elements ended in a MemoryError traceback; the
    data after the header is checked against what it declares, before reading."""
    import trimesh

    from superfacets import read_cloud
    from superfacets.errors import MeshFormatError
    from superfacets.io.headers import header_counts

    good = tmp_path / "good.ply"
    trimesh.creation.icosphere(subdivisions=2).export(good)
    assert header_counts(good) == {"vertices": 162, "faces": 320}
    data = good.read_bytes()
    huge = tmp_path / "huge.ply"
    huge.write_bytes(data.replace(b"element face 320", b"element face 3000000000"))
    with pytest.raises(MeshFormatError, match="declares 162 vertex, 3,000,000,000 face"):
        read_mesh(huge)
    pts = tmp_path / "pts.ply"
    trimesh.PointCloud(np.random.default_rng(0).random((100, 3))).export(pts)
    pts.write_bytes(pts.read_bytes().replace(b"element vertex 100", b"element vertex 9999"))
    with pytest.raises(MeshFormatError, match="damaged PLY file"):
        read_cloud(pts)


def test_a_run_that_would_not_fit_is_refused_in_one_line(tmp_path, monkeypatch, capsys):
    """Under a memory limit a large mesh ended in a MemoryError traceback: the run's peak
    is estimated from the header (the command line) or the element count (the API)."""
    import trimesh

    from superfacets import MemoryLimitError, segment
    from superfacets._runtime import memory
    from superfacets.cli import main

    mesh = trimesh.creation.icosphere(subdivisions=4)  # 5,120 faces
    path = tmp_path / "ball.ply"
    mesh.export(path)
    monkeypatch.setattr(memory, "available_bytes", lambda: 100_000)  # 100 kB left
    with pytest.raises(MemoryLimitError, match=r"5,120 faces need about \d+ KiB .* may use "
                       r"97.7 KiB: .* larger machine \(SUPERFACETS_MEMORY_CHECK=off runs it "
                       r"anyway\)") as exc:
        segment(mesh, 10)
    assert "tiles" not in str(exc.value)  # (a tiled run of a mesh peaks higher)
    assert main(["segment", str(path), "-k", "10", "-o", str(tmp_path / "b.seg")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "superfacets: error:" in err and "larger machine" in err
    assert not (tmp_path / "b.seg").exists()
    # points: room for the tiled run's rows and a fifth of the run: tiles are named
    np.save(tmp_path / "p.npy", np.random.default_rng(0).random((20_000, 3)))
    from superfacets.elements.kinds import kind_of

    room = 20_000 * 100 + 20_000 * kind_of("points").peak_bytes // 4
    monkeypatch.setattr(memory, "resident_bytes", lambda: memory.BASE_BYTES)
    monkeypatch.setattr(memory, "available_bytes", lambda: room)
    assert main(["segment", str(tmp_path / "p.npy"), "-k", "10", "-o",
                 str(tmp_path / "p.seg")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "(--tiles 5," in err, err
    assert not (tmp_path / "p.seg").exists()
    monkeypatch.setenv("SUPERFACETS_MEMORY_CHECK", "off")  # the override
    assert segment(mesh, 10).n_segments == 10
    monkeypatch.delenv("SUPERFACETS_MEMORY_CHECK")
    monkeypatch.setattr(memory, "available_bytes", lambda: None)

    def oom(*args, **kwargs):
        raise MemoryError

    import superfacets.api.segmentation as api

    monkeypatch.setattr(api, "pipeline", oom)  # what no estimate foresaw
    assert main(["segment", str(path), "-k", "10", "-o", str(tmp_path / "b.seg")]) == 2
    assert "superfacets: error: out of memory" in capsys.readouterr().err


def test_label_files_are_written_in_blocks_with_the_same_text(tmp_path):
    """Labels are formatted a block at a time (10M labels as one list of str held 1.3 GB):
    the file is the one-line-per-label text all the same, across block borders."""
    from superfacets.io.labels import _BLOCK, write_labels

    rng = np.random.default_rng(0)
    for labels in (np.zeros(0, np.int64), np.array([7]), rng.integers(-1, 10**6, 2 * _BLOCK + 3)):
        path = write_labels(tmp_path / "x.seg", labels, {"k": 3})
        want = "# k: 3\n" + "".join(f"{int(v)}\n" for v in labels)
        assert path.read_text() == want
        np.testing.assert_array_equal(read_labels(path), labels)


def test_segindices_are_written_in_blocks_as_json_writes_them(tmp_path):
    """The ScanNet-style JSON's labels are formatted a block at a time: the bytes are
    json.dumps' all the same (empty, one label, across block borders, non-ASCII names)."""
    import json

    from superfacets.io.labels import _BLOCK, write_segindices

    rng = np.random.default_rng(1)
    for labels in (np.zeros(0, np.int64), np.array([3]), rng.integers(-1, 10**6, 2 * _BLOCK + 5)):
        path = write_segindices(tmp_path / "s.json", labels, {"k": np.int64(3), "n": "Tür"},
                                "scène")
        want = json.dumps({"params": {"k": 3, "n": "Tür"}, "sceneId": "scène",
                           "segIndices": labels.tolist()}, separators=(",", ":"),
                          ensure_ascii=False).encode("utf-8") + b"\n"
        assert path.read_bytes() == want


def test_integer_text_is_pythons_decimal_text():
    from superfacets.io.labels import integer_text

    rng = np.random.default_rng(5)
    info = np.iinfo(np.int64)
    cases = [np.array([], dtype=np.int64), np.array([0]), np.array([-1, 9, 10, -10, 99, 100]),
             np.array([info.min, info.max, 2**32 - 1, 2**32, -(2**32), 10**18, 10**19 // 2]),
             rng.integers(-1, 3000, 50_000), rng.integers(-(10**12), 10**12, 5_000)]
    for values in cases:
        for end in (b"\n", b","):
            want = "".join(f"{v}{end.decode()}" for v in values.tolist()).encode()
            assert integer_text(values, end) == want
    assert integer_text(np.array([7], dtype=np.int32), b"\n") == b"7\n"


def test_labels_file_text_across_blocks(tmp_path, monkeypatch):
    from superfacets.io import labels as module

    monkeypatch.setattr(module, "_BLOCK", 1000)
    labels = np.random.default_rng(2).integers(0, 12_000, 3_500)
    path = write_labels(tmp_path / "l.seg", labels)
    assert path.read_bytes() == "".join(f"{v}\n" for v in labels.tolist()).encode()
    np.testing.assert_array_equal(read_labels(path), labels)


def test_the_memory_check_counts_the_face_pairs_of_a_fan_and_sends_it_not_to_tiles(
        monkeypatch):
    """Copies of one triangle make three face pairs a face, not one and a half: the
    estimate counts them; tiles cannot help (one edge's pairs are in one tile)."""
    from superfacets import MemoryLimitError, segment
    from superfacets._runtime import memory

    n = 6000
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5]])
    faces = np.r_[np.tile([[0, 1, 2]], (n, 1)), [[1, 3, 2]]]
    monkeypatch.setattr(memory, "resident_bytes", lambda: memory.BASE_BYTES)
    from superfacets.elements.kinds import kind_of

    faces_only = memory.estimated_peak(n + 1, kind_of("faces").peak_bytes,
                                       held=memory.BASE_BYTES)
    monkeypatch.setattr(memory, "available_bytes", lambda: faces_only + 1000)
    with pytest.raises(MemoryLimitError, match=r"6,001 faces with 18,001 face pairs") as exc:
        segment((vertices, faces), 2)
    assert "tiles" not in str(exc.value)
    monkeypatch.setattr(memory, "available_bytes", lambda: None)
    assert segment((vertices, faces), 2).labels.shape == (n + 1,)


@pytest.mark.parametrize("n", [1, 2, 60, 3000])
def test_an_stls_vertices_merge_as_numpy_unique_merges_them(n):
    """Known answer: STL's merged vertices (a sort of the columns) are
    ``np.unique(axis=0)``'s arrays, signed zeros as one, on rows with many repeats."""
    from superfacets.io.meshes import _merged_rows

    rng = np.random.default_rng(n)
    v = np.round(rng.normal(size=(n, 3)), 1)
    v[::5] *= -0.0
    want, want_inv = np.unique(v, axis=0, return_inverse=True)
    got, inv = _merged_rows(v)
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(inv, want_inv.ravel())


def test_the_memory_check_counts_an_input_it_holds_once(monkeypatch):
    """After the read, the input's own arrays are held already, and counted in the bytes
    per element: the check does not count them twice (6.8M faces were estimated at 1.44
    times their peak)."""
    import trimesh

    from superfacets import segment
    from superfacets._runtime import memory
    from superfacets.elements.builders import _array_bytes
    from superfacets.elements.kinds import kind_of
    from superfacets.inputs.convert import as_mesh

    mesh = as_mesh(trimesh.creation.icosphere(subdivisions=4))
    seen = []
    check = memory.check_memory
    monkeypatch.setattr(memory, "check_memory",
                        lambda n, bpe, what, **kw: seen.append(kw) or check(n, bpe, what, **kw))
    own = _array_bytes(mesh)  # (before the run: it keeps its graph with the mesh)
    segment(mesh, 10)
    assert own == mesh.vertices.nbytes + mesh.faces.nbytes
    # the input's arrays and what its check computed of them (areas, normals, centroids)
    held = seen[0]["held_input"]
    assert own + mesh.areas.nbytes + mesh.normals.nbytes <= held <= _array_bytes(mesh)
    n, bpe = mesh.n_faces, kind_of("faces").peak_bytes
    assert memory.estimated_peak(n, bpe, held=0, input_bytes=held) == (
        memory.BASE_BYTES + n * bpe - held)


def test_a_work_files_digest_is_taken_in_memory_and_checked_on_reading(tmp_path):
    """A work file's digest (CRC-32 of its dtype, shape and bytes) is taken from the array
    as written and checked on the array read back: a changed byte, dtype or shape, a
    truncated raw file or an unreadable header is refused in one line."""
    import zlib

    from superfacets.errors import SuperfacetsError
    from superfacets.io.files import array_digest, load_checked

    a = np.arange(12, dtype=np.int32).reshape(4, 3)
    np.save(tmp_path / "a.npy", a)
    np.testing.assert_array_equal(load_checked(tmp_path / "a.npy", array_digest(a)), a)
    for other in (a.reshape(3, 4), a.astype(np.int64), a.astype(np.float32), a[:3]):
        assert array_digest(other) != array_digest(a)
    data = bytearray((tmp_path / "a.npy").read_bytes())
    data[-1] ^= 1
    (tmp_path / "b.npy").write_bytes(bytes(data))
    (tmp_path / "c.npy").write_bytes(b"\x93NUMPY garbage")
    header = (tmp_path / "a.npy").read_bytes()  # a shape asking for 3 TB: refused unread
    (tmp_path / "d.npy").write_bytes(header.replace(b"(4, 3)", b"(400000000000, 3)"))
    assert (tmp_path / "d.npy").read_bytes() != header
    for name, digest in (("b", array_digest(a)), ("c", array_digest(a)), ("a", None),
                         ("d", array_digest(a))):
        with pytest.raises(SuperfacetsError, match="changed since this run wrote it"):
            load_checked(tmp_path / f"{name}.npy", digest)
    rec = np.zeros(5, dtype=[("row", "<i8"), ("pos", "<f8", (3,))])
    rec["row"] = np.arange(5)
    crc = 0
    for block in (rec[:2], rec[2:]):  # as the tiles' files are written, block by block
        with open(tmp_path / "r.bin", "ab") as f:
            block.tofile(f)
        crc = zlib.crc32(block.view(np.uint8), crc)
    assert f"{crc:08x}" == array_digest(rec, described=False)
    got = load_checked(tmp_path / "r.bin", f"{crc:08x}", rec.dtype)
    assert got.dtype == rec.dtype and np.array_equal(got, rec)
    mapped = load_checked(tmp_path / "r.bin", f"{crc:08x}", rec.dtype, mapped=True)
    assert np.array_equal(mapped, rec) and not mapped.flags.writeable  # (not copied)
    del mapped
    (tmp_path / "e.bin").write_bytes(b"")  # an empty file: nothing to map, nothing in it
    assert load_checked(tmp_path / "e.bin", f"{0:08x}", rec.dtype, mapped=True).size == 0
    (tmp_path / "r.bin").write_bytes((tmp_path / "r.bin").read_bytes()[:-8])
    for mapped in (False, True):  # (mapped: its size no longer whole records)
        with pytest.raises(SuperfacetsError, match="changed since this run wrote it"):
            load_checked(tmp_path / "r.bin", f"{crc:08x}", rec.dtype, mapped=mapped)


def test_a_work_file_found_as_written_is_not_summed_again_until_it_changes(tmp_path,
                                                                           monkeypatch):
    """A tile's file is read by each box that overlaps it: its digest is summed on the first
    reading in a process, and again only once the file is replaced, written or touched."""
    import os

    import superfacets.io.files as files
    from superfacets.errors import SuperfacetsError

    rec = np.arange(40, dtype=np.int64)
    rec.tofile(tmp_path / "t.bin")
    digest = files.array_digest(rec, described=False)
    sums = []
    real = files.array_digest
    monkeypatch.setattr(files, "array_digest", lambda a, d=True: sums.append(1) or real(a, d))
    for _ in range(3):
        assert np.array_equal(files.load_checked(tmp_path / "t.bin", digest, rec.dtype,
                                                 mapped=True), rec)
    assert len(sums) == 1
    with pytest.raises(SuperfacetsError, match="changed since"):  # another digest: summed
        files.load_checked(tmp_path / "t.bin", "00000000", rec.dtype, mapped=True)
    assert len(sums) == 2
    changed = rec.copy()
    changed[5] = -1  # the same size, written in place, its times set back: only the sum
    st = os.stat(tmp_path / "t.bin")  # tells (the change time moves all the same)
    with open(tmp_path / "t.bin", "r+b") as f:
        changed.tofile(f)
    os.utime(tmp_path / "t.bin", ns=(st.st_atime_ns, st.st_mtime_ns + 1))
    with pytest.raises(SuperfacetsError, match="changed since"):
        files.load_checked(tmp_path / "t.bin", digest, rec.dtype, mapped=True)
    (tmp_path / "t.bin").unlink()  # replaced by another file (its times not those read
    rec.tofile(tmp_path / "t.bin")  # before, even within the clock's tick): summed again
    os.utime(tmp_path / "t.bin", ns=(st.st_atime_ns, st.st_mtime_ns + 2))
    files.load_checked(tmp_path / "t.bin", digest, rec.dtype, mapped=True)
    assert len(sums) == 4
