import numpy as np
import pytest
import trimesh

from superfacets import InvalidMeshError, Mesh, as_mesh
from superfacets.elements import face_graph

V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
F = np.array([[0, 1, 2], [0, 3, 1]])


def test_derived_geometry_known_values():
    m = Mesh(V, F)
    np.testing.assert_allclose(m.centroids[0], [1 / 3, 1 / 3, 0])
    np.testing.assert_allclose(m.normals[0], [0, 0, 1])
    np.testing.assert_allclose(m.normals[1], [0, 1, 0])  # (0,0,1) x (1,0,0)
    np.testing.assert_allclose(m.areas, [0.5, 0.5])
    assert m.area == pytest.approx(1.0)
    assert m.diagonal == pytest.approx(np.sqrt(3))
    assert m.n_faces == 2 and m.n_vertices == 4


def test_degenerate_face_has_zero_normal_and_area():
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], float)
    m = Mesh(v, [[0, 1, 2], [0, 1, 3]])
    np.testing.assert_array_equal(m.normals[0], 0)
    assert m.areas[0] == 0
    assert np.isfinite(m.normals).all()


def test_accepts_trimesh_and_pair_and_keeps_caller_arrays_writable():
    tm = trimesh.creation.box()
    m = as_mesh(tm)
    assert m.n_faces == len(tm.faces)
    v, f = V.copy(), F.copy()
    m2 = as_mesh((v, f))
    assert v.flags.writeable and f.flags.writeable
    assert not m2.vertices.flags.writeable
    assert as_mesh(m2) is m2


def test_unreferenced_vertices_do_not_change_diagonal():
    v = np.vstack([V, [[100.0, 100.0, 100.0]]])
    assert Mesh(v, F).diagonal == pytest.approx(np.sqrt(3))


@pytest.mark.parametrize("vertices, faces, match", [
    (V, np.zeros((0, 3), int), "empty mesh"),
    (V[:, :2], F, r"vertices must have shape \(n, 3\)"),
    (V, np.array([[0, 1]]), "at least 3 vertices"),
    (V, np.array([[0, 1, 4]]), "out of range"),
    (V, np.array([[0, 1, -1]]), "out of range"),
    (np.array([[0, 0, 0], [1, np.nan, 0], [0, 1, 0]]), np.array([[0, 1, 2]]), "NaN or infinite"),
    (np.array([[0, 0, 0], [1, np.inf, 0], [0, 1, 0]]), np.array([[0, 1, 2]]), "NaN or infinite"),
])
def test_invalid_arrays(vertices, faces, match):
    with pytest.raises(InvalidMeshError, match=match):
        Mesh(vertices, faces)


def test_float_faces_and_bad_types():
    with pytest.raises(TypeError, match="integer"):
        Mesh(V, F.astype(float))
    with pytest.raises(TypeError, match="mesh must be"):
        as_mesh("not a mesh")
    # what is wrong with an array or a list of points is said
    with pytest.raises(TypeError, match=r"got an array of shape \(5, 4\)"):
        as_mesh(np.zeros((5, 4)))
    with pytest.raises(TypeError, match=r"\(N, 3\) array or list.*got list of 5 items"):
        as_mesh(np.zeros((5, 3)).tolist())  # (segment takes it: a cloud)


def test_check_usable():
    v = np.zeros((3, 3))
    with pytest.raises(InvalidMeshError, match="zero extent"):
        Mesh(v, [[0, 1, 2]]).check_usable()
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], float)
    with pytest.raises(InvalidMeshError, match="zero total area"):
        Mesh(v, [[0, 1, 2]]).check_usable()


def test_one_pass_geometry_equals_the_numpy_expressions_bit_for_bit():
    # random triangles (some degenerate: repeated or collinear vertices) of very
    # different sizes; the kernel must repeat numpy's operations exactly
    rng = np.random.default_rng(7)
    v = rng.normal(size=(300, 3)) * rng.choice([1e-6, 1.0, 1e4], size=(300, 1))
    v[250:] = v[:50] * 0.5 + v[50:100] * 0.5  # midpoints: collinear triangles
    f = rng.integers(0, 300, size=(2000, 3))
    f[:40, 2] = f[:40, 1]  # repeated vertex
    f[40:80] = np.stack([np.arange(40), np.arange(250, 290), np.arange(50, 90)], axis=1)
    mesh = Mesh(v, f)
    v0, v1, v2 = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    cross = np.cross(v1 - v0, v2 - v0)
    norm = np.linalg.norm(cross, axis=1)
    normals = np.zeros_like(cross)
    ok = norm > 0
    normals[ok] = cross[ok] / norm[ok, None]
    np.testing.assert_array_equal(mesh.centroids, (v0 + v1 + v2) / 3.0)
    np.testing.assert_array_equal(mesh.areas, 0.5 * norm)
    np.testing.assert_array_equal(mesh.normals, normals)
    assert (~ok).sum() >= 40 and not mesh.centroids.flags.writeable


def test_weight_terms_equal_the_numpy_expressions_bit_for_bit():
    # the face graph's terms come from a kernel that must repeat numpy exactly
    rng = np.random.default_rng(3)
    v = rng.normal(size=(200, 3)) * rng.choice([1e-6, 1.0, 1e4], size=(200, 1))
    f = rng.integers(0, 200, size=(3000, 3))  # random triangles: many shared edges
    mesh = Mesh(v, f)
    g = face_graph(mesh)
    c, n = mesh.centroids, mesh.normals
    # 32-bit face and vertex ids while they fit (the graph's memory on large meshes)
    assert g.pairs.dtype == np.int32 and g.edges.dtype == np.int32
    i, j = g.pairs[:, 0], g.pairs[:, 1]
    mid = 0.5 * (v[g.edges[:, 0]] + v[g.edges[:, 1]])
    geo = np.linalg.norm(c[i] - mid, axis=1) + np.linalg.norm(mid - c[j], axis=1)
    cos = np.clip(np.einsum("ij,ij->i", n[i], n[j]), -1.0, 1.0)
    concave = np.einsum("ij,ij->i", n[i], c[j] - c[i]) > 0
    assert g.n_edges > 1000
    np.testing.assert_array_equal(g.terms.geo, geo)
    np.testing.assert_array_equal(g.terms.cos, cos)
    np.testing.assert_array_equal(g.terms.concave, concave)
    np.testing.assert_array_equal(g.lengths, np.linalg.norm(v[g.edges[:, 1]] - v[g.edges[:, 0]],
                                                            axis=1))


def test_a_mesh_with_its_caches_pickles_and_segments_the_same(sphere):
    # the face graph holds functions; a mesh sent to another process (a pool, Dask)
    # carries its arrays and names only, and gives the same results there
    import pickle

    from superfacets import segment

    before = segment(sphere, 12).labels  # graph, geometry and weights cached now
    copy = pickle.loads(pickle.dumps(sphere))
    assert "graph" not in copy.__dict__ and copy.name == sphere.name
    assert not copy.vertices.flags.writeable and not copy.faces.flags.writeable
    np.testing.assert_array_equal(copy.faces, sphere.faces)
    np.testing.assert_array_equal(segment(copy, 12).labels, before)


def test_int32_faces_stay_int32_and_give_what_int64_faces_give(sphere):
    # a file's reader gives int32 faces (half the memory); the geometry, the graph and
    # the labels are those of the same faces in int64, bit for bit
    from superfacets import segment

    v, f = np.asarray(sphere.vertices), np.asarray(sphere.faces)
    wide, narrow = Mesh(v, f.astype(np.int64)), Mesh(v, f.astype(np.int32))
    assert wide.faces.dtype == np.int64 and narrow.faces.dtype == np.int32
    assert Mesh(v, f.astype(np.uint16)).faces.dtype == np.int64  # other types: int64
    for name in ("centroids", "areas", "normals", "referenced_vertices"):
        assert getattr(narrow, name).tobytes() == getattr(wide, name).tobytes(), name
    assert narrow.corners.dtype == np.int64
    np.testing.assert_array_equal(narrow.corners, wide.corners)
    held = [k for k, a in narrow.__dict__.items() if getattr(a, "dtype", None) == np.int64]
    assert held == []  # the int64 corners of int32 triangles are not kept with the mesh
    gw, gn = face_graph(wide), face_graph(narrow)
    np.testing.assert_array_equal(gn.pairs, gw.pairs)
    np.testing.assert_array_equal(gn.indices, gw.indices)
    for elements in ("faces", "vertices"):
        a = segment(wide, 20, elements=elements)
        b = segment(narrow, 20, elements=elements)
        np.testing.assert_array_equal(b.labels, a.labels)



def test_narrow_faces_only_where_every_index_fits():
    from superfacets.inputs.mesh import narrow_faces

    assert narrow_faces(F, 4).dtype == np.int32
    np.testing.assert_array_equal(narrow_faces(F, 4), F)
    big = np.array([[0, 1, 2**31]])
    assert narrow_faces(big, 4) is big  # out of range stays so, for the mesh's check
    assert narrow_faces(np.array([[0, 1, -2]]), 4).dtype == np.int64
    ragged = [[0, 1, 2], [0, 1, 2, 3]]
    assert narrow_faces(ragged, 4) is ragged
    assert narrow_faces(F, 2**31).dtype == np.int64  # too many vertices for int32


def test_read_meshes_have_int32_faces_and_out_of_range_indices_are_named(tmp_path):
    from superfacets import read_mesh
    from superfacets.errors import InvalidMeshError

    good = tmp_path / "tri.off"
    good.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    assert read_mesh(good).faces.dtype == np.int32
    bad = tmp_path / "far.off"
    bad.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3000000000\n")
    with pytest.raises(InvalidMeshError, match="3000000000"):
        read_mesh(bad)
