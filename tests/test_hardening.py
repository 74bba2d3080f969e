"""The smaller faults of the third attack on every command (issue 94, item 8): each a
known answer that failed before its fix."""

import numpy as np
import pytest

import superfacets
from superfacets.cli import main
from superfacets.errors import MeshFormatError, ParameterError
from superfacets.inputs.shapes import creature
from superfacets.method.params import PARAMETERS


def _run(capsys, *args) -> tuple[int, str]:
    capsys.readouterr()
    code = main([str(a) for a in args])
    return code, capsys.readouterr().err


def test_huge_integers_for_float_parameters_are_one_line():
    """10**400 for a float parameter raised OverflowError (10 parameters)."""
    mesh = creature(16)
    floats = [p.name for p in PARAMETERS if p.name in (
        "radius", "alpha", "eta_convex", "window", "tol", "center_tol", "neighbor_radius",
        "beta", "density", "roughness")]
    assert len(floats) == 10
    for name in floats:
        with pytest.raises(ParameterError, match=f"{name} must be a finite number.*"
                                                 "a 401-character int"):
            superfacets.segment(mesh, None if name == "radius" else 5, **{name: 10**400})
    with pytest.raises(ParameterError, match="n_threads must be an integer <= .* a 61-char"):
        superfacets.segment(mesh, 5, n_threads=10**60)


def test_a_batch_whose_output_folder_holds_the_inputs_says_so(tmp_path, capsys):
    """batch DIR -o DIR said only 'no input to segment'."""
    from superfacets.io import write_mesh

    write_mesh(tmp_path / "c.off", creature(16))
    code, err = _run(capsys, "batch", tmp_path, "-o", tmp_path, "-k", 5)
    assert code == 2 and "is or holds the output folder" in err and "-o" in err


def _pcd_header(points: int, data: str) -> bytes:
    return (f"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            f"WIDTH {points}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {points}\n"
            f"DATA {data}\n").encode()


@pytest.mark.parametrize("data", ["binary", "ascii", "binary_compressed"])
def test_a_pcd_declaring_more_points_than_it_holds_is_refused_unread(tmp_path, data):
    """A PCD declaring 10**12 points said 'cannot read PCD: MemoryError'."""
    pytest.importorskip("pypcd4")
    from superfacets import read_cloud

    body = b"" if data != "binary_compressed" else (
        (100).to_bytes(4, "little") + (4_000_000_000).to_bytes(4, "little") + b"\0" * 100)
    path = tmp_path / "big.pcd"
    path.write_bytes(_pcd_header(10**12, data) + body)
    with pytest.raises(MeshFormatError, match="declares 1,000,000,000,000 points"):
        read_cloud(path)
    good = tmp_path / "good.pcd"  # (a whole binary file still reads)
    good.write_bytes(_pcd_header(4, "binary") + np.arange(12, dtype="<f4").tobytes())
    assert read_cloud(good).points.shape == (4, 3)


def test_a_truncated_stl_is_named_truncated(tmp_path):
    """A short STL (binary or ASCII) said 'empty mesh: no faces'."""
    import trimesh

    from superfacets import read_mesh

    sphere = trimesh.creation.icosphere(1)
    binary, ascii_ = tmp_path / "b.stl", tmp_path / "a.stl"
    sphere.export(binary)
    sphere.export(ascii_, file_type="stl_ascii")
    assert read_mesh(binary).n_faces == read_mesh(ascii_).n_faces == 80
    for path, said in ((binary, "truncated binary STL: 80 triangles declared"),
                       (ascii_, "truncated ASCII STL")):
        data = path.read_bytes()
        path.write_bytes(data[:len(data) // 2])
        with pytest.raises(MeshFormatError, match=said):
            read_mesh(path)
    path.write_bytes(b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n")
    with pytest.raises(MeshFormatError, match="truncated ASCII STL"):
        read_mesh(path)
    (tmp_path / "tiny.stl").write_bytes(b"\0" * 40)
    with pytest.raises(MeshFormatError, match="not even the 84"):
        read_mesh(tmp_path / "tiny.stl")


@pytest.mark.parametrize("dtype", ["complex128", "<U8", "object"])
def test_one_rule_for_numbers_at_every_door(tmp_path, capsys, dtype):
    """Complex .npy clouds (whole and tiled) and TetMesh's complex vertices were taken
    (numpy's ComplexWarning, the imaginary part dropped) where the API refused complex
    points: every door now gives the same sentence."""
    from scipy.spatial import Delaunay

    pts = np.random.default_rng(0).random((300, 3))
    odd = pts.astype(dtype)
    said = f"must be real numbers, got dtype {np.dtype(dtype)}"
    with pytest.raises(TypeError, match=said):
        superfacets.segment(odd, 5)
    with pytest.raises(TypeError, match=said):
        superfacets.TetMesh(odd, Delaunay(pts).simplices)
    with pytest.raises(TypeError, match=said):
        superfacets.Mesh(odd, [[0, 1, 2]])
    if dtype != "object":  # (np.save pickles objects: the reader refuses pickles first)
        np.save(tmp_path / "p.npy", odd)
        for extra in ([], ["--tiles", "2"]):
            code, err = _run(capsys, "segment", tmp_path / "p.npy", "-k", 5, "-o",
                             tmp_path / "p.seg", *extra)
            assert code == 2 and said in err and err.count("\n") == 1, (extra, err)
            assert not (tmp_path / "p.seg").exists()


def test_compressed_files_are_read_as_bounded_streams(tmp_path, capsys, monkeypatch):
    """Compressed inputs were decompressed whole before any check: a 2.5 MB .ply.gz
    declaring 100M faces took 97 s and 6.7 GB before it was refused. The header is read
    from the stream's start and checked first; the rest is decompressed a block at a
    time and refused past 256 bytes an element the header declares (or past half of
    what the process may use)."""
    import gzip

    from superfacets import read_mesh
    from superfacets.errors import MemoryLimitError
    from superfacets.io.headers import header_counts

    header = (b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
              b"property float y\nproperty float z\nelement face 100000000\n"
              b"property list uchar int vertex_indices\nend_header\n")
    declares = tmp_path / "declares.ply.gz"
    declares.write_bytes(gzip.compress(header + bytes(10**5)))
    assert header_counts(declares) == {"vertices": 3, "faces": 100_000_000}
    from superfacets._runtime import memory

    with monkeypatch.context() as m:  # (a machine of 16 GiB: 100M faces do not fit)
        m.setattr(memory, "available_bytes", lambda: 16 * 2**30)
        code, err = _run(capsys, "segment", declares, "-k", 2, "-o", tmp_path / "x.seg")
    assert code == 2 and "100,000,000 faces need about" in err
    bomb = tmp_path / "bomb.off.gz"  # 3 vertices and a face, then 64 MiB of spaces
    bomb.write_bytes(gzip.compress(b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
                                   + b" " * (64 << 20), compresslevel=1))
    assert bomb.stat().st_size < 1 << 20
    with pytest.raises(MemoryLimitError, match="decompresses to more than 66,560 bytes"):
        read_mesh(bomb)
    small = tmp_path / "small.off.gz"  # (a whole file still reads)
    small.write_bytes(gzip.compress(b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"))
    assert read_mesh(small).n_faces == 1


@pytest.mark.parametrize("quaternion, up", [("1 0 0 0", [0.0, -1.0, 0.0]),
                                            ("0 1 0 0", [0.0, 1.0, 0.0]),
                                            ("0.7071068 0 0 0.7071068", [1.0, 0.0, 0.0])])
def test_an_organized_pcd_stands_on_its_sensors_up(tmp_path, quaternion, up):
    """Pictures of an RGB-D frame came out upside down (up y; a camera's y points down)."""
    pytest.importorskip("pypcd4")
    from superfacets import read_cloud
    from superfacets.io.orientation import up_axis

    pts = np.random.default_rng(0).random((6, 3)).astype("<f4")
    header = (f"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
              f"WIDTH 3\nHEIGHT 2\nVIEWPOINT 0 0 0 {quaternion}\nPOINTS 6\nDATA binary\n")
    path = tmp_path / "frame.pcd"
    path.write_bytes(header.encode() + pts.tobytes())
    cloud = read_cloud(path)
    np.testing.assert_allclose(cloud.up, up, atol=1e-6)  # (its normals' side, as declared)
    assert up_axis(cloud, path)[1] == "the image's"  # a picture stands as the image does
    flat = tmp_path / "flat.pcd"  # not an image: no sensor frame is declared
    flat.write_bytes(header.replace("WIDTH 3\nHEIGHT 2", "WIDTH 6\nHEIGHT 1").encode()
                     + pts.tobytes())
    assert read_cloud(flat).up is None and up_axis(read_cloud(flat), flat) == ("y", "the default")
