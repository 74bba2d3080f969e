"""Polygon meshes, scenes and library types (issue 14): known answers and invariants."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from conftest import MESHES, need

from superfacets import (
    InvalidMeshError,
    Mesh,
    MeshFormatError,
    ParameterError,
    read_labels,
    read_mesh,
    segment,
    superfacets,
    write_colored_mesh,
    write_mesh,
)
from superfacets.cli import main
from superfacets.elements import face_graph
from superfacets.method.connectivity import label_components


def voxel_surface(filled: np.ndarray, size: float = 1.0) -> Mesh:
    """The closed quad surface of a set of voxels (faces outwards, vertices shared)."""
    filled = np.pad(filled.astype(bool), 1)
    shape = np.array(filled.shape) + 1
    def pid(p):
        return (p[..., 0] * shape[1] + p[..., 1]) * shape[2] + p[..., 2]
    quads = []
    for axis in range(3):
        a, b = [(axis + 1) % 3, (axis + 2) % 3]
        diff = np.diff(filled.astype(np.int8), axis=axis)  # +1: empty -> filled, -1: out
        for sign in (1, -1):
            cells = np.argwhere(diff == sign)
            base = cells.copy()
            base[:, axis] += 1  # the face between cell i and i + 1 along axis
            ea, eb = np.eye(3, dtype=int)[a], np.eye(3, dtype=int)[b]
            corners = np.stack([base, base + ea, base + ea + eb, base + eb], axis=1)
            if sign == 1:  # outward normal along -axis: reverse the order
                corners = corners[:, ::-1]
            quads.append(pid(corners))
    f = np.concatenate(quads)
    used, inv = np.unique(f, return_inverse=True)
    v = np.stack(np.unravel_index(used, shape), axis=1).astype(float) * size
    return Mesh(v, inv.reshape(-1, 4))


@pytest.fixture
def l_prism() -> Mesh:
    """An L-shaped prism of 4 x 4 x 2 unit voxels (one 2 x 2 corner missing), in quads:
    one concave edge line, at the inner corner."""
    filled = np.ones((8, 8, 4), dtype=bool)
    filled[4:, 4:, :] = False
    return voxel_surface(filled, 0.25)


def test_voxel_quads_make_a_closed_outward_surface(l_prism):
    g = face_graph(l_prism)
    assert l_prism.faces.shape[1] == 4 and g.boundary_elements.size == 0
    vol = np.einsum("ij,ij->i", l_prism.centroids, l_prism.normals) @ l_prism.areas / 3
    assert vol == pytest.approx(2 * 2 * 1 - 1 * 1 * 1)  # the L's volume: normals outwards
    concave = g.terms.concave
    assert concave.sum() == 4 and g.lengths[concave].sum() == pytest.approx(1.0)


def test_concave_edge_of_a_quad_prism_is_a_boundary_at_high_alpha(l_prism):
    g = face_graph(l_prism)
    crease = g.terms.concave
    for alpha, expect_cut in ((1000, True),):
        labels = superfacets(l_prism, 6, alpha=alpha)
        cut = labels[g.pairs[:, 0]] != labels[g.pairs[:, 1]]
        assert cut[crease].all() == expect_cut
    assert label_components(g, labels).max() + 1 == labels.max() + 1


def test_triangulated_copy_gives_similar_superfacets(l_prism):
    from superfacets.evaluation.metrics import compactness

    tri, owner = l_prism.triangulated()
    copy = Mesh(l_prism.vertices, tri)
    a = superfacets(l_prism, 12, alpha=1000, paper=True)
    b = superfacets(copy, 12, alpha=1000, paper=True)
    ca, cb = compactness(l_prism, a), compactness(copy, b)
    assert abs(ca - cb) / ca < 0.25
    # the crease is cut in both; on the shared (quad) edges the boundaries mostly agree
    gq, gt = face_graph(l_prism), face_graph(copy)
    for g, lab in ((gq, a), (gt, b)):
        assert (lab[g.pairs[g.terms.concave, 0]] != lab[g.pairs[g.terms.concave, 1]]).all()


def test_polygon_geometry_newell_and_area_weighted_centroid():
    # a non-convex L hexagon, and a non-planar quad
    hexagon = Mesh([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]],
                   [[0, 1, 2, 3, 4, 5]])
    assert hexagon.areas[0] == pytest.approx(3.0)
    np.testing.assert_allclose(hexagon.normals[0], [0, 0, 1])
    np.testing.assert_allclose(hexagon.centroids[0], [2.5 / 3, 2.5 / 3, 0])
    saddle = Mesh([[0, 0, 0], [1, 0, 0.2], [1, 1, 0], [0, 1, 0.2]], [[0, 1, 2, 3]])
    assert np.linalg.norm(saddle.normals[0]) == pytest.approx(1)
    assert saddle.normals[0][2] > 0.95
    mixed = Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]], [[0, 1, 2, 3], [1, 4, 2]])
    assert mixed.face_sizes.tolist() == [4, 3] and mixed.faces.shape == (2, 4)
    assert face_graph(mixed).n_edges == 1 and face_graph(mixed).lengths[0] == pytest.approx(1.0)
    assert repr(mixed) == "Mesh(5 vertices, 2 faces: polygons of 3 to 4 vertices)"


@pytest.mark.parametrize("faces, match", [([[0, 1]], "at least 3"), ([[0, 1, 2], [0, 1]],
                                                                     "at least 3 are needed"),
                                          ([[0, 1, 2, 9]], "out of range"),
                                          ([[0, 1, -1, 2], [0, 1, 2, -1]], "-1 may only pad")])
def test_bad_polygons_are_refused(faces, match):
    with pytest.raises(InvalidMeshError, match=match):
        Mesh(np.eye(4, 3), np.array(faces) if "pad" in match else faces)


def test_polygon_files_round_trip_in_order(tmp_path):
    m = Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0.3], [3, 0, 0]],
             [[0, 1, 2, 3], [1, 4, 5, 2], [4, 6, 5]])
    for ext in ("off", "ply", "obj", "off.gz"):
        write_mesh(tmp_path / f"m.{ext}", m)
        back = read_mesh(tmp_path / f"m.{ext}")
        assert [p.tolist() for p in back.polygons()] == [p.tolist() for p in m.polygons()]
        np.testing.assert_allclose(back.vertices, m.vertices)
    with pytest.raises(MeshFormatError, match="triangles only"):
        write_mesh(tmp_path / "m.tri", m)


def test_colored_outputs_carry_the_labels(tmp_path):
    quad = read_mesh(need(MESHES / "horse_quad.obj.xz"))
    r = segment(quad, 50)
    write_colored_mesh(tmp_path / "c.ply", quad, r.labels)
    np.testing.assert_array_equal(read_labels(tmp_path / "c.ply"), r.labels)
    back = read_mesh(tmp_path / "c.ply")
    assert back.n_faces == 2398 and back.faces.shape[1] == 4
    write_colored_mesh(tmp_path / "v.ply", quad, r.labels, vertex_colors=True)
    np.testing.assert_array_equal(read_labels(tmp_path / "v.ply"), r.labels)
    write_colored_mesh(tmp_path / "c.glb", quad, r.labels)
    glb = trimesh.load(tmp_path / "c.glb", force="mesh")
    assert glb.faces.shape[0] == 2 * 2398
    write_colored_mesh(tmp_path / "c.obj", quad, r.labels)
    assert (tmp_path / "c.mtl").read_text().count("newmtl") >= 4
    with pytest.raises(MeshFormatError):
        write_colored_mesh(tmp_path / "c.stl", quad, r.labels)


def test_cli_on_the_real_quad_mesh(tmp_path):
    src = need(MESHES / "horse_quad.obj.xz")
    seg, ply, glb = tmp_path / "o.seg", tmp_path / "o.ply", tmp_path / "o.glb"
    assert main(["segment", str(src), "-k", "50", "-o", str(seg), "--colored-mesh", str(ply),
                 "-q"]) == 0
    labels = read_labels(seg)
    mesh = read_mesh(src)
    assert labels.shape == (2398,) and label_components(mesh, labels).max() == labels.max()
    np.testing.assert_array_equal(read_labels(ply), labels)
    assert read_mesh(ply).faces.shape == (2398, 4)
    assert main(["segment", str(src), "-k", "50", "--colored-mesh", str(glb), "-q"]) == 0
    assert trimesh.load(glb, force="mesh").faces.shape[0] == 4796
    assert main(["html", str(src), str(seg), "-o", str(tmp_path / "p.html"), "-q"]) == 0
    assert '"faces": 2398' in (tmp_path / "p.html").read_text()


def test_library_types_give_the_same_labels():
    pv = pytest.importorskip("pyvista")
    from superfacets import as_mesh
    from superfacets.io import to_pyvista, to_trimesh

    plane = pv.Plane(i_resolution=24, j_resolution=20).rotate_x(20, inplace=False)
    m = as_mesh(plane)
    assert m.faces.shape == (480, 4)
    a = superfacets(plane, 12)
    np.testing.assert_array_equal(a, superfacets((np.asarray(plane.points), m.polygons()), 12))
    tri = plane.triangulate()
    np.testing.assert_array_equal(superfacets(tri, 12),
                                  superfacets((tri.points, tri.faces.reshape(-1, 4)[:, 1:]), 12))
    p = to_pyvista(m, a)
    assert p.n_cells == 480 and (np.asarray(p.cell_data["label"]) == a).all()
    t = to_trimesh(m, a)
    assert t.faces.shape == (960, 3) and (t.face_attributes["label"] == a[t.metadata[
        "face_of_triangle"]]).all()
    with pytest.raises(InvalidMeshError, match="no polygons"):
        as_mesh(pv.PolyData(np.random.default_rng(0).random((10, 3))))

    class FakeOpen3d:  # the attributes of open3d.geometry.TriangleMesh
        __module__ = "open3d.cpu.pybind.geometry"
        vertices = np.eye(3)
        triangles = np.array([[0, 1, 2]])

    assert as_mesh(FakeOpen3d()).n_faces == 1


def test_scenes_join_objects_and_segment_per_object(tmp_path):
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.icosphere(subdivisions=3), node_name="ball")
    scene.add_geometry(trimesh.creation.box(extents=(3, 1, 1)), node_name="bar",
                       transform=trimesh.transformations.translation_matrix([4, 0, 0]))
    path = tmp_path / "s.glb"
    path.write_bytes(scene.export(file_type="glb"))
    mesh = read_mesh(path)
    assert len(mesh.objects) == 2 and mesh.objects[-1][2] == mesh.n_faces
    assert mesh.vertices[:, 0].max() > 5  # the node's transform is applied
    seg = tmp_path / "s.seg"
    assert main(["segment", str(path), "-k", "30", "--per-object", "-o", str(seg), "-q"]) == 0
    text = seg.read_text()
    assert text.count("# object ") == 2
    labels = read_labels(seg)
    for name, a, b in mesh.objects:  # no superfacet crosses objects; labels globally unique
        other = np.r_[labels[:a], labels[b:]]
        assert not set(labels[a:b]) & set(other)
    assert np.unique(labels).size == labels.max() + 1
    # a scene of lines alone holds nothing to segment (one of points is a cloud)
    lines = tmp_path / "lines.gltf"
    buffer = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0]], dtype="<f4").tobytes()
    import base64
    import json

    lines.write_text(json.dumps({
        "asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 1}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
        "bufferViews": [{"buffer": 0, "byteLength": len(buffer)}],
        "buffers": [{"byteLength": len(buffer), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(buffer).decode()}]}))
    assert main(["segment", str(lines)]) == 2


def test_vsa_refuses_polygons_clearly():
    from superfacets.evaluation.baselines import vsa

    quad = Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2, 3]])
    with pytest.raises(ParameterError, match="triangle mesh"):
        vsa(quad, 1)


def test_pictures_and_metrics_work_on_polygons(l_prism):
    pytest.importorskip("pyvista")
    from superfacets.evaluation.metrics import evaluate
    from superfacets.viz.html import html_page
    from superfacets.viz.render import render

    labels = superfacets(l_prism, 8, alpha=1000)
    img = render(l_prism, labels, size=(200, 160))
    assert img.std() > 10
    page = html_page(l_prism, labels)
    assert f'"faces": {l_prism.n_faces}' in page and f'"nFaces": {2 * l_prism.n_faces}' in page
    m = evaluate(l_prism, labels, [np.zeros(l_prism.n_faces, int), labels])
    assert m["undersegmentation_error"] == pytest.approx(0.0) and m["compactness"] > 3
