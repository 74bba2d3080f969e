"""Colours of meshes (vertex and face RGB): read from files and libraries' objects, kept
through conversion, and what ``beta > 0`` uses on faces and vertices without ``features``."""

from __future__ import annotations

import pickle
import subprocess
import sys

import numpy as np
import pytest
import trimesh
from conftest import grid_mesh, minority

from superfacets import Mesh, segment
from superfacets.api.scenes import segment_objects
from superfacets.errors import InvalidMeshError, MeshFormatError, ParameterError
from superfacets.io import read_mesh

BLUE, RED = [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]


def _two_colour_grid(n=48, cut=0.37):
    """A flat grid whose vertices left of x = cut (in [-1, 1]) are blue, the rest red."""
    mesh = grid_mesh(n, n)
    left = mesh.vertices[:, 0] <= cut
    return Mesh(mesh.vertices, mesh.faces, colors=np.where(left[:, None], BLUE, RED)), left


def test_vertex_and_face_colours_carry_to_the_other_elements():
    v = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]
    f = [[0, 1, 2], [1, 3, 2]]
    m = Mesh(v, f, colors=[RED, [0, 1, 0], BLUE, [1, 1, 1]])
    np.testing.assert_allclose(m.colors_of_vertices(), m.colors)
    np.testing.assert_allclose(m.colors_of_faces(),
                               [[1 / 3, 1 / 3, 1 / 3], [1 / 3, 2 / 3, 2 / 3]])
    m = Mesh(v, f, face_colors=[RED, BLUE])
    np.testing.assert_allclose(m.colors_of_vertices(),
                               [RED, [0.5, 0, 0.5], [0.5, 0, 0.5], BLUE])
    np.testing.assert_allclose(m.colors_of_faces(), [RED, BLUE])
    assert Mesh(v, f).colors_of_faces() is None
    # both given: each element its own
    m = Mesh(v, f, colors=[RED] * 4, face_colors=[BLUE, BLUE])
    np.testing.assert_allclose(m.colors_of_faces(), [BLUE, BLUE])
    np.testing.assert_allclose(m.colors_of_vertices(), [RED] * 4)
    back = pickle.loads(pickle.dumps(m))
    np.testing.assert_array_equal(back.face_colors, m.face_colors)
    assert not back.colors.flags.writeable


def test_bad_colours_are_refused_with_the_row():
    v, f = [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]
    with pytest.raises(InvalidMeshError, match=r"m.ply: colour 1 is not in \[0, 1\]"):
        Mesh(v, f, name="m.ply", colors=[[0, 0, 0], [255, 0, 0], [0, 0, 0]])
    with pytest.raises(InvalidMeshError, match=r"face colour 0 is not finite"):
        Mesh(v, f, face_colors=[[np.nan, 0, 0]])
    with pytest.raises(InvalidMeshError, match=r"colours must have shape \(3, 3\)"):
        Mesh(v, f, colors=[[0, 0, 0]])
    with pytest.raises(TypeError, match="face colours must be numeric"):
        Mesh(v, f, face_colors=[["red", "green", "blue"]])


def test_colours_are_read_from_ply_off_obj_and_glb(tmp_path):
    tm = trimesh.creation.icosphere(subdivisions=2)
    rgb = np.random.default_rng(0).integers(0, 256, (len(tm.vertices), 3)).astype(np.uint8)
    frgb = np.random.default_rng(1).integers(0, 256, (len(tm.faces), 3)).astype(np.uint8)
    tm.visual.vertex_colors = np.c_[rgb, np.full(len(rgb), 255, np.uint8)]
    tm.export(tmp_path / "v.ply")
    m = read_mesh(tmp_path / "v.ply")
    np.testing.assert_allclose(m.colors, rgb / 255.0)
    assert m.face_colors is None
    tf = trimesh.Trimesh(tm.vertices, tm.faces, process=False)
    tf.visual.face_colors = np.c_[frgb, np.full(len(frgb), 255, np.uint8)]
    tf.export(tmp_path / "f.ply")
    m = read_mesh(tmp_path / "f.ply")
    np.testing.assert_allclose(m.face_colors, frgb / 255.0)
    assert m.colors is None
    # the libraries' objects keep theirs
    from superfacets.inputs.convert import as_mesh

    np.testing.assert_allclose(as_mesh(tm).colors, rgb / 255.0)
    np.testing.assert_allclose(as_mesh(tf).face_colors, frgb / 255.0)
    assert as_mesh(trimesh.creation.box()).colors is None

    class FakeOpen3d:  # open3d.geometry.TriangleMesh's attributes: colours in [0, 1]
        __module__ = "open3d.cpu.pybind.geometry"
        vertices = np.eye(3)
        triangles = np.array([[0, 1, 2]])
        vertex_colors = np.array([RED, BLUE, RED])

    np.testing.assert_allclose(as_mesh(FakeOpen3d()).colors, [RED, BLUE, RED])
    FakeOpen3d.vertex_colors = np.zeros((0, 3))  # Open3D without colours: an empty vector
    assert as_mesh(FakeOpen3d()).colors is None
    # a PLY of quads (read with plyfile), both kinds of colour
    from plyfile import PlyData, PlyElement

    vert = np.zeros(4, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("red", "u1"),
                              ("green", "u1"), ("blue", "u1")])
    vert["x"], vert["y"] = [0, 1, 1, 0], [0, 0, 1, 1]
    vert["red"] = [255, 0, 0, 51]
    face = np.zeros(1, dtype=[("vertex_indices", "i4", (4,)), ("red", "u1"), ("green", "u1"),
                              ("blue", "u1")])
    face["vertex_indices"][0] = [0, 1, 2, 3]
    face["green"] = 255
    PlyData([PlyElement.describe(vert, "vertex"), PlyElement.describe(face, "face")]
            ).write(str(tmp_path / "q.ply"))
    q = read_mesh(tmp_path / "q.ply")
    assert q.faces.shape == (1, 4)
    np.testing.assert_allclose(q.colors[:, 0], [1, 0, 0, 0.2])
    np.testing.assert_allclose(q.face_colors, [[0, 1, 0]])
    # COFF (8-bit), CNOFF (normals first), OBJ "v x y z r g b" (floats)
    (tmp_path / "c.off").write_text("COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n"
                                    "0 1 0 0 0 51 255\n3 0 1 2\n")
    np.testing.assert_allclose(read_mesh(tmp_path / "c.off").colors,
                               [RED, [0, 1, 0], [0, 0, 0.2]])
    (tmp_path / "n.off").write_text("CNOFF\n3 1 0\n0 0 0 0 0 1 1 0 0 1\n1 0 0 0 0 1 0 1 0 1\n"
                                    "0 1 0 0 0 1 0 0 1 1\n3 0 1 2\n")
    np.testing.assert_allclose(read_mesh(tmp_path / "n.off").colors, [RED, [0, 1, 0], BLUE])
    (tmp_path / "c.obj").write_text("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 0.5\nf 1 2 3\n")
    np.testing.assert_allclose(read_mesh(tmp_path / "c.obj").colors,
                               [RED, [0, 1, 0], [0, 0, 0.5]])
    (tmp_path / "p.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    assert read_mesh(tmp_path / "p.obj").colors is None
    # a glTF binary scene of two coloured objects: the colours joined in object order
    scene = trimesh.Scene([tm, tm.copy()])
    (tmp_path / "s.glb").write_bytes(scene.export(file_type="glb"))
    s = read_mesh(tmp_path / "s.glb")
    assert s.colors is not None and s.colors.shape == (s.n_vertices, 3)
    np.testing.assert_allclose(s.colors[:len(rgb)], rgb / 255.0, atol=1 / 255)


def test_malformed_colour_columns_are_one_clear_error(tmp_path):
    (tmp_path / "short.off").write_text("COFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    with pytest.raises(MeshFormatError, match="COFF vertex lines need 6 numbers"):
        read_mesh(tmp_path / "short.off")
    (tmp_path / "bad.obj").write_text("v 0 0 0 1 0 0\nv 1 0 0 red 1 0\nv 0 1 0 0 0 1\n"
                                      "f 1 2 3\n")
    with pytest.raises(MeshFormatError, match="malformed vertex colour 1"):
        read_mesh(tmp_path / "bad.obj")
    (tmp_path / "range.obj").write_text("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 -1\n"
                                        "f 1 2 3\n")
    m = read_mesh(tmp_path / "range.obj")  # clipped, as every reader's colours
    assert m.colors.min() == 0


def _colors(mesh, elements):
    return mesh.colors_of_faces() if elements == "faces" else mesh.colors_of_vertices()


@pytest.mark.parametrize("elements", ["faces", "vertices"])
def test_a_colour_edge_on_a_flat_mesh_becomes_a_border(elements):
    # geometry says nothing on a flat grid; the mesh's own colours say where the edge is
    mesh, _ = _two_colour_grid()
    blue = _colors(mesh, elements)[:, 2]
    pure = (blue == 0) | (blue == 1)  # faces across the edge have a mixed colour: left out
    side = blue[pure] == 1
    blind = segment(mesh, 16, elements=elements, beta=0)
    seeing = segment(mesh, 16, elements=elements, beta=400)
    assert minority(blind.labels[pure], side) > 20
    assert minority(seeing.labels[pure], side) < 0.2 * minority(blind.labels[pure], side)
    auto = segment(mesh, 16, elements=elements)  # the default reads the mesh's colours
    assert minority(auto.labels[pure], side) < 0.2 * minority(blind.labels[pure], side)
    # the same as passing the colours as features
    given = segment(Mesh(mesh.vertices, mesh.faces), 16, elements=elements, beta=400,
                    features=_colors(mesh, elements))
    np.testing.assert_array_equal(given.labels, seeing.labels)
    # the superfacet graph's mean feature is the mean colour
    g = seeing.graph()
    assert g.feature.shape == (seeing.n_segments, 3)
    np.testing.assert_array_equal(g.feature, seeing.graph(_colors(mesh, elements)).feature)
    assert ((g.feature[:, 2] < 0.1) | (g.feature[:, 2] > 0.9)).mean() >= 0.8  # one colour each


def test_per_object_runs_keep_each_objects_colours():
    mesh, _ = _two_colour_grid(16)
    half = mesh.n_faces // 2
    joined = Mesh(mesh.vertices, mesh.faces, colors=mesh.colors,
                  objects=(("a", 0, half), ("b", half, mesh.n_faces)))
    labels, results = segment_objects(joined, 8, beta=100)
    assert len(results) == 2 and labels.max() + 1 == sum(r.n_segments for r in results)
    with pytest.raises(ParameterError, match="beta > 0 needs features"):
        segment_objects(Mesh(mesh.vertices, mesh.faces), 8, beta=100)


def test_cli_reads_a_coloured_mesh_for_beta(tmp_path):
    mesh, _ = _two_colour_grid(24)
    tm = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    tm.visual.vertex_colors = np.c_[np.round(mesh.colors * 255), np.full(mesh.n_vertices,
                                                                          255)].astype(np.uint8)
    tm.export(tmp_path / "g.ply")
    out = tmp_path / "g.seg"
    run = subprocess.run([sys.executable, "-m", "superfacets", "segment", str(tmp_path / "g.ply"),
                          "-k", "8", "--beta", "300", "-o", str(out)],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    labels = np.loadtxt(out, dtype=np.int64)
    want = segment(read_mesh(tmp_path / "g.ply"), 8, beta=300).labels
    np.testing.assert_array_equal(labels, want)
    plain = tmp_path / "plain.off"
    plain.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    run = subprocess.run([sys.executable, "-m", "superfacets", "segment", str(plain), "-k", "1",
                          "--beta", "5", "-o", str(tmp_path / "p.seg")],
                         capture_output=True, text=True)
    assert run.returncode != 0 and "Traceback" not in run.stderr
    assert "vertex or face colours" in run.stderr


def test_tiled_mesh_runs_read_the_colours(tmp_path):
    from superfacets.scale.tiles.run import segment_tiled

    mesh, _ = _two_colour_grid(60)
    blue = mesh.colors_of_faces()[:, 2]
    pure = (blue == 0) | (blue == 1)
    side = blue[pure] == 1
    blind = segment_tiled(mesh, 16, tiles=2, beta=0)
    seeing = segment_tiled(mesh, 16, tiles=2, beta=400)  # spilled: the faces' colours
    assert minority(seeing.labels[pure], side) < 0.2 * minority(blind.labels[pure], side)
    auto = segment_tiled(mesh, 16, tiles=2)  # each tile reads the term from its colours
    assert minority(auto.labels[pure], side) < 0.2 * minority(blind.labels[pure], side)
    # a binary PLY read in chunks: each face the mean of its vertices' 8-bit colours
    tm = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    tm.visual.vertex_colors = np.c_[np.round(mesh.colors * 255),
                                    np.full(mesh.n_vertices, 255)].astype(np.uint8)
    tm.export(tmp_path / "g.ply")  # binary, positions in float32
    streamed = segment_tiled(tmp_path / "g.ply", 16, tiles=2, beta=400)
    spilled = segment_tiled(read_mesh(tmp_path / "g.ply"), 16, tiles=2, beta=400)
    np.testing.assert_array_equal(streamed.labels, spilled.labels)
    assert minority(streamed.labels[pure], side) < 0.2 * minority(blind.labels[pure], side)
    with pytest.raises(ParameterError, match="beta > 0 needs colours, and this input has none"):
        segment_tiled(Mesh(mesh.vertices, mesh.faces), 16, tiles=2, beta=400)


def test_library_point_clouds_keep_their_colours():
    from superfacets.inputs.cloud import as_cloud

    xyz = np.random.default_rng(3).random((50, 3))
    rgba = np.tile(np.array([255, 0, 51, 255], np.uint8), (50, 1))
    c = as_cloud(trimesh.PointCloud(xyz, colors=rgba))
    np.testing.assert_allclose(c.colors, np.tile([1.0, 0.0, 0.2], (50, 1)))
    assert as_cloud(trimesh.PointCloud(xyz)).colors is None

    class FakeOpen3dCloud:  # open3d.geometry.PointCloud's attributes
        __module__ = "open3d.cpu.pybind.geometry"
        points = xyz
        colors = np.tile(BLUE, (50, 1))

        def has_normals(self):
            return False

    np.testing.assert_allclose(as_cloud(FakeOpen3dCloud()).colors, np.tile(BLUE, (50, 1)))
    FakeOpen3dCloud.colors = np.zeros((0, 3))
    assert as_cloud(FakeOpen3dCloud()).colors is None


def test_pyvista_colour_arrays_are_read():
    pv = pytest.importorskip("pyvista")
    from superfacets.inputs.convert import as_mesh

    sphere = pv.Sphere()
    rgb = np.random.default_rng(4).integers(0, 256, (sphere.n_points, 3)).astype(np.uint8)
    sphere.point_data["RGB"] = rgb
    m = as_mesh(sphere)
    np.testing.assert_allclose(m.colors, rgb / 255.0)
    assert m.face_colors is None
    sphere.cell_data["colors"] = np.tile(BLUE, (sphere.n_cells, 1))
    np.testing.assert_allclose(as_mesh(sphere).face_colors, np.tile(BLUE, (sphere.n_cells, 1)))
    assert as_mesh(pv.Sphere()).colors is None  # its normals are no colours


def test_a_tiled_run_scales_a_files_colours_alike_in_every_chunk(tmp_path):
    # 16-bit colours whose first chunk is dark (no value above 255): read alone, that chunk
    # would pass for 8-bit; the survey decides one divisor for the whole file
    from dataclasses import replace

    from plyfile import PlyData, PlyElement

    from superfacets.io.regions import RegionReader

    n = 300
    v = np.zeros(n, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("red", "u2"),
                           ("green", "u2"), ("blue", "u2")])
    rng = np.random.default_rng(5)
    v["x"], v["y"] = rng.random(n), rng.random(n)
    raw = np.where(np.arange(n)[:, None] < 100, rng.integers(0, 256, (n, 3)),
                   rng.integers(0, 65536, (n, 3))).astype(np.uint16)
    v["red"], v["green"], v["blue"] = raw.T
    PlyData([PlyElement.describe(v, "vertex")]).write(str(tmp_path / "p.ply"))
    reader = RegionReader.open(tmp_path / "p.ply", chunk=100)
    survey = reader.survey()
    assert survey.colors and survey.color_top == 65535.0

    def colours(r):
        return np.concatenate([extra[0] for _, _, _, extra in r.chunks()])

    np.testing.assert_allclose(colours(replace(reader, color_top=survey.color_top)),
                               raw / 65535.0)
    np.testing.assert_allclose(colours(reader)[:100], raw[:100] / 255.0)  # chunk by chunk
    from superfacets.io import read_cloud

    np.testing.assert_allclose(read_cloud(tmp_path / "p.ply").colors, raw / 65535.0)
