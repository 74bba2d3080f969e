"""Text formats read in pieces: the same result whatever the piece size, faults named by
their line in the whole file, and a large text costing about its arrays (issue 110: a
small compressed file of one line repeated millions of times)."""

import gzip
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from superfacets.errors import MeshFormatError
from superfacets.io.columns import read_columns
from superfacets.io.meshes import read_mesh
from superfacets.io.obj import parse_obj

OBJ = (b"# a cube's corner\nmtllib m.mtl\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\n"
       b"vt 0 0\nvn 0 0 1\no first\nf 1/1/1 2/1/1 3/1/1\nv 0 0 1 1 1 1\n"
       b"f -4 -3 -1\no\nf\t1 3 4\nusemtl red\nf 2 3 4\n")


@pytest.mark.parametrize("size", [1, 7, 40, 1 << 23])
def test_obj_pieces_give_one_answer(size):
    v, f, objects, colors = parse_obj(OBJ, Path("m.obj"), size=size)
    assert v.shape == (4, 3) and colors.shape == (4, 3)
    assert f.tolist() == [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]
    assert objects == (("first", 0, 2), ("object1", 2, 4))


@pytest.mark.parametrize("size", [1, 16, 1 << 23])
def test_obj_polygons_and_faults_named_in_the_whole_file(size):
    quad = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 2 3 4\n"
    _, f, _, _ = parse_obj(quad, Path("q.obj"), size=size)
    assert f == [[0, 1, 2], [0, 1, 2, 3]]
    with pytest.raises(MeshFormatError, match="face 2: vertex index 0"):
        parse_obj(quad + b"f 0 1 2\n", Path("q.obj"), size=size)
    with pytest.raises(MeshFormatError, match="face 2: vertex index 9 out of range"):
        parse_obj(quad + b"f 1 2 9\n", Path("q.obj"), size=size)
    with pytest.raises(MeshFormatError, match="malformed vertex 4"):
        parse_obj(quad + b"v 1 x 0\nf 1 2 3\n", Path("q.obj"), size=size)


def test_an_index_may_name_a_later_vertex():
    _, f, _, _ = parse_obj(b"v 0 0 0\nf 1 2 3\nv 1 0 0\nv 0 1 0\n", Path("a.obj"), size=8)
    assert f.tolist() == [[0, 1, 2]]


def test_a_malformed_colour_counts_only_where_every_vertex_has_one():
    rows = b"v 0 0 0 1 0 0\nv 1 0 0 red 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n"
    with pytest.raises(MeshFormatError, match="malformed vertex colour 1"):
        parse_obj(rows, Path("c.obj"), size=4)
    _, _, _, colors = parse_obj(rows + b"v 1 1 1\n", Path("c.obj"), size=4)
    assert colors is None


@pytest.mark.parametrize("size", [1, 20, 1 << 23])
def test_columns_pieces_give_one_answer(size):
    text = (b"// X Y Z NX NY NZ\n# scanned\n0 0 1 0 0 1\n1,0,0,1,0,0\n\n"
            b"# a remark\n0;1;0;0;1;0\r\n2 2 2 0 0 1\n")
    out = read_columns(text, Path("p.xyz"), size=size)
    assert out["points"].tolist() == [[0, 0, 1], [1, 0, 0], [0, 1, 0], [2, 2, 2]]
    assert out["normals"][:, 2].tolist() == [1, 0, 0, 1]



@pytest.mark.parametrize("size", [1, 20, 1 << 23])
def test_a_csv_s_first_line_of_names_and_colour_columns(size, tmp_path):
    """A CSV's first line of names (no ``//`` or ``#``: "point line 1 is not numbers") picks
    the columns, and ``r g b`` / ``red green blue`` columns are the colours (they were
    dropped), 0-255 read as such; a ``.csv`` is a cloud file (it was "unknown mesh
    format"). A first line of words that names no x, y, z is still a fault."""
    from superfacets.io import read_cloud

    text = b"Z,Y,X,Red,Green,Blue,Intensity\n1,0,0,255,0,0,7\n0,1,0,0,255,51,7\n0,0,1,0,0,0,7\n"
    out = read_columns(text, Path("p.csv"), size=size)
    assert out["points"].tolist() == [[0, 0, 1], [0, 1, 0], [1, 0, 0]]
    np.testing.assert_allclose(out["colors"], [[1, 0, 0], [0, 1, 0.2], [0, 0, 0]])
    cc = read_columns(b"//X Y Z R G B\n0 0 0 0.5 0.25 1\n1 1 1 0 0 0\n", Path("p.txt"),
                      size=size)
    assert cc["colors"].tolist() == [[0.5, 0.25, 1], [0, 0, 0]]  # (floats in [0, 1]: kept)
    assert read_columns(b"x y z\n0 0 0\n", Path("p.xyz"), size=size)["colors"] is None
    quoted = read_columns(b'"x","y","z"\n1,2,3\n', Path("p.csv"), size=size)  # (a spreadsheet's)
    assert quoted["points"].tolist() == [[1, 2, 3]]
    with pytest.raises(MeshFormatError, match="point line 1 is not numbers: 'a b c'"):
        read_columns(b"a b c\n0 0 0\n", Path("p.xyz"), size=size)
    (tmp_path / "scan.csv").write_bytes(text)
    cloud = read_cloud(tmp_path / "scan.csv")
    assert cloud.n_points == 3 and cloud.colors is not None


@pytest.mark.parametrize("size", [1, 12, 1 << 23])
def test_columns_count_line_and_faults(size):
    pts = b"3\n0 0 0\n1 0 0\n0 1 0\nnot a point\n"
    assert len(read_columns(pts, Path("p.pts"), size=size)["points"]) == 3
    with pytest.raises(MeshFormatError, match="declares 5 points, the file has 3"):
        read_columns(b"5\n0 0 0\n1 0 0\n0 1 0\n", Path("p.pts"), size=size)
    with pytest.raises(MeshFormatError, match="line 3 of the points has 4 columns"):
        read_columns(b"0 0 0\n1 0 0\n0 1 0 7\n", Path("p.xyz"), size=size)
    with pytest.raises(MeshFormatError, match="point line 2 is not numbers"):
        read_columns(b"0 0 0\n1 y 0\n", Path("p.xyz"), size=size)


def test_a_long_header_is_shown_cut():
    with pytest.raises(MeshFormatError) as err:
        read_columns(b"# " + b"word " * 10_000 + b"\n0 0 0\n", Path("p.xyz"))
    assert "the lines have 3" in str(err.value) and len(str(err.value)) < 200


def test_a_large_text_costs_about_its_arrays():
    """One face line repeated: the lines are never all held as strings (read whole,
    they cost 7 times the text; in pieces 1.6)."""
    n = 200_000
    data = b"v 0 0 0\nv 1 0 0\nv 0 1 0\n" + b"f 1 2 3 # one face, many times\n" * n
    tracemalloc.start()
    try:
        _, f, _, _ = parse_obj(data, Path("m.obj"), size=1 << 18)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(f) == n and peak < 3 * len(data)
    data = b"1.250000 2.500000 3.750000\n" * n
    tracemalloc.start()
    try:
        pts = read_columns(data, Path("p.xyz"), size=1 << 18)["points"]
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(pts) == n and peak < 5 * len(data)  # (whole: 6.2 times)


def test_a_compressed_repeated_face_reads_whole(tmp_path):
    """A small .obj.gz of one face repeated (under the decompression bound): every face
    kept, one element."""
    path = tmp_path / "r.obj.gz"
    path.write_bytes(gzip.compress(b"v 0 0 0\nv 1 0 0\nv 0 1 0\n" + b"f 1 2 3\n" * 50_000))
    mesh = read_mesh(path)
    assert mesh.n_faces == 50_000 and np.unique(np.asarray(mesh.faces), axis=0).shape == (1, 3)
