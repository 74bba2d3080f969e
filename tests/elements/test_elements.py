import numpy as np
import pytest

from superfacets import Mesh, ParameterError, paper_weights, segment, shlafman_weights
from superfacets.elements import build_face_graph, face_graph
from superfacets.method.weights import edge_weights


def fold(z: float) -> Mesh:
    """Two right triangles sharing the edge (0,0,0)-(0,1,0); the far vertex of the
    second is at (1, 0.5, z). Normals up (+z) for the first face."""
    v = np.array([[0, 0, 0], [0, 1, 0], [-1, 0.5, 0], [1, 0.5, z]], float)
    f = np.array([[0, 1, 2], [1, 0, 3]])
    return Mesh(v, f)


def hand_weight(z, alpha, eta_convex, concave):
    c0 = np.array([-1 / 3, 0.5, 0])
    c1 = np.array([1 / 3, 0.5, z / 3])
    mid = np.array([0, 0.5, 0])
    geo = np.linalg.norm(c0 - mid) + np.linalg.norm(mid - c1)
    theta = np.arctan2(abs(z), 1.0)  # angle between the two normals
    eta = 1.0 if concave else eta_convex
    ang = eta * 1.0 * theta / np.pi  # shared edge length 1
    d = np.linalg.norm(np.array([1, 1, abs(z)]) - np.array([-1, 0, 0]))  # bbox diagonal
    return (geo + alpha * ang) / d, geo, np.cos(theta)


@pytest.mark.parametrize("z, concave", [(0.7, True), (-0.7, False)])
def test_paper_weight_matches_hand_computation(z, concave):
    m = fold(z)
    assert face_graph(m).n_edges == 1
    w = paper_weights(m, alpha=200, eta_convex=0.2)
    expected, _, _ = hand_weight(z, 200, 0.2, concave)
    assert w[0] == pytest.approx(expected, rel=1e-12)


def test_concave_fold_costs_more_than_convex():
    wc = paper_weights(fold(0.7), alpha=200)[0]
    wx = paper_weights(fold(-0.7), alpha=200)[0]
    assert wc > 2 * wx


def test_flat_pair_weight_is_geodesic_only_and_alpha_free():
    m = fold(0.0)
    w0 = paper_weights(m, alpha=0)
    w1 = paper_weights(m, alpha=1000)
    np.testing.assert_allclose(w0, w1)
    _, geo, _ = hand_weight(0.0, 0, 0.2, False)
    assert w0[0] * m.diagonal == pytest.approx(geo)


def test_shlafman_weight_matches_hand_computation():
    z = 0.7
    _, geo, cos = hand_weight(z, 0, 0.2, True)
    w = shlafman_weights(fold(z), alpha=0.3)
    assert w[0] == pytest.approx(0.7 * geo + 0.3 * (1 - cos**2), rel=1e-12)


def test_weights_invariant_to_scale_and_translation(sphere):
    w = paper_weights(sphere, alpha=200)
    moved = Mesh(sphere.vertices * 37.5 + [3, -2, 8], sphere.faces)
    np.testing.assert_allclose(paper_weights(moved, alpha=200), w, rtol=1e-9)


@pytest.mark.parametrize("kwargs, match", [
    (dict(alpha=-1), r"alpha must be a finite number in \[0, 1e\+12\]"),
    (dict(alpha=np.nan), r"alpha must be a finite number in \[0, 1e\+12\]"),
    (dict(eta_convex=-0.1), r"eta_convex must be a finite number in \[0, 1e\+12\]"),
    (dict(alpha="x"), "alpha must be a number"),
])
def test_paper_weight_parameter_errors(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        paper_weights(fold(0.5), **kwargs)


def test_shlafman_alpha_range_and_unknown_weighting():
    with pytest.raises(ParameterError, match=r"\[0, 1\]"):
        shlafman_weights(fold(0.5), alpha=1.5)
    with pytest.raises(ParameterError, match="weighting must be"):
        edge_weights(fold(0.5), "cosine")


def test_non_manifold_edge_joins_every_pair():
    # three triangles on the edge (0,1) plus one ordinary neighbour
    v = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -1, 0], [0.5, 0, 1], [1.5, 1, 0]], float)
    f = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4], [1, 5, 2]])
    g = face_graph(Mesh(v, f))
    pairs = {tuple(p) for p in g.pairs.tolist()}
    assert pairs == {(0, 1), (0, 2), (1, 2), (0, 3)}
    # CSR is symmetric and consistent with the pairs
    for i, j in pairs:
        assert j in g.indices[g.indptr[i]:g.indptr[i + 1]]
        assert i in g.indices[g.indptr[j]:g.indptr[j + 1]]
    assert g.indices.dtype == np.int32


def test_duplicate_faces_degenerate_edges_and_boundary():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    # face 1 duplicates face 0; face 2 has a collapsed edge (2, 2)
    f = np.array([[0, 1, 2], [0, 1, 2], [2, 2, 3], [1, 3, 2]])
    g = face_graph(Mesh(v, f))
    pairs = {tuple(p) for p in g.pairs.tolist()}
    assert (0, 1) in pairs and len([p for p in g.pairs.tolist() if p == [0, 1]]) == 1
    assert all(i != j for i, j in pairs)
    # boundary edges of a 2-triangle square: 4, each used by exactly one face
    sq = face_graph(Mesh(v, [[0, 1, 2], [1, 3, 2]]))
    assert sq.boundary_edges.shape == (4, 2) and sq.n_edges == 1


def test_closed_mesh_has_three_neighbours_per_face(sphere):
    g = face_graph(sphere)
    assert (np.diff(g.indptr) == 3).all()
    assert g.boundary_edges.shape[0] == 0
    assert g.n_edges == sphere.n_faces * 3 // 2


def _soup(seed: int, n_faces: int, n_vertices: int) -> np.ndarray:
    # random triangles over few vertices: non-manifold edges (many faces per edge),
    # duplicate and flipped faces, collapsed edges, a high-valence vertex
    rng = np.random.default_rng(seed)
    f = rng.integers(0, n_vertices, size=(n_faces, 3))
    f[: n_faces // 10, 0] = 0  # vertex 0 in a tenth of the faces
    f[n_faces // 10: n_faces // 10 + 20] = f[:20][:, ::-1]  # flipped duplicates
    return f


def _graph_by_dicts(faces: np.ndarray):
    """The face graph spelled out with Python dicts: every pair of faces on an edge of
    at most 8, each face and the next (cyclically) on an edge of more."""
    on_edge = {}
    for f, tri in enumerate(faces.tolist()):
        for c in range(3):
            a, b = sorted((tri[c], tri[(c + 1) % 3]))
            if a != b:
                on_edge.setdefault((a, b), []).append(f)
    pairs = {}
    for edge in sorted(on_edge):
        fs = on_edge[edge]
        for x in range(len(fs)):
            for y in range(x + 1, len(fs)) if len(fs) <= 8 else [(x + 1) % len(fs)]:
                if fs[x] != fs[y]:
                    pairs.setdefault((min(fs[x], fs[y]), max(fs[x], fs[y])), edge)
    boundary = sorted((e, fs[0]) for e, fs in on_edge.items() if len(fs) == 1)
    return pairs, boundary


@pytest.mark.parametrize("seed, n_faces, n_vertices", [(0, 400, 60), (1, 3000, 25), (2, 200, 400)])
def test_graph_of_a_triangle_soup_matches_a_plain_construction(seed, n_faces, n_vertices):
    # random triangles over few vertices: non-manifold edges (up to dozens of faces),
    # duplicate and flipped faces, collapsed edges, a high-valence vertex
    rng = np.random.default_rng(seed)
    faces = rng.integers(0, n_vertices, size=(n_faces, 3))
    faces[: n_faces // 10, 0] = 0
    faces[n_faces // 10: n_faces // 10 + 20] = faces[:20][:, ::-1]
    g = build_face_graph(faces, n_vertices)
    pairs, boundary = _graph_by_dicts(faces)
    assert g.pairs.tolist() == [list(p) for p in sorted(pairs)]  # one per face pair, in order
    assert g.edges.tolist() == [list(pairs[p]) for p in sorted(pairs)]  # its smallest edge
    assert g.boundary_edges.tolist() == [list(e) for e, _ in boundary]
    assert g.boundary_faces.tolist() == [f for _, f in boundary]
    for f in range(n_faces):  # symmetric CSR, ascending rows, dual_edge consistent
        row = g.indices[g.indptr[f]:g.indptr[f + 1]]
        assert (np.diff(row) > 0).all()
        for nb, e in zip(row.tolist(), g.dual_edge[g.indptr[f]:g.indptr[f + 1]].tolist()):
            assert sorted(g.pairs[e].tolist()) == sorted([f, nb])
    if n_vertices < n_faces:
        assert np.diff(g.indptr).max() > 3  # non-manifold edges were exercised
    if seed == 1:  # edges of about 30 faces, each paired in a cycle: 2 neighbours an edge
        assert np.diff(g.indptr).max() <= 6 and (faces == 0).any(axis=1).sum() > 32


def _vertex_graph_by_numpy(mesh):
    """The vertex graph's arrays by plain numpy (np.unique of the edge keys, np.bincount
    over the corners): the construction the one-pass kernels replace."""
    corners, offsets = np.asarray(mesh.corners), np.asarray(mesh.offsets)
    sizes = np.diff(offsets)
    nxt = np.roll(corners, -1)
    nxt[offsets[1:] - 1] = corners[offsets[:-1]]
    owner = np.repeat(np.arange(mesh.n_faces), sizes)
    used = np.flatnonzero(mesh.referenced_vertices)
    index = np.full(mesh.n_vertices, -1)
    index[used] = np.arange(used.shape[0])
    n, ci, pos = used.shape[0], index[corners], mesh.vertices[used]
    area = np.bincount(ci, weights=np.repeat(mesh.areas / sizes, sizes), minlength=n)
    fn = mesh.normals * mesh.areas[:, None]
    normal = np.stack([np.bincount(ci, weights=fn[owner, c], minlength=n) for c in range(3)],
                      axis=1)
    norm = np.linalg.norm(normal, axis=1)
    normal[norm > 0] /= norm[norm > 0, None]
    normal[~(norm > 0)] = 0.0
    a, b = np.minimum(ci, index[nxt]), np.maximum(ci, index[nxt])
    keep = a != b
    a, b, own = a[keep], b[keep], owner[keep]
    uniq, inv, count = np.unique(a * n + b, return_inverse=True, return_counts=True)
    lo, hi = uniq // n, uniq % n
    dual = np.linalg.norm(mesh.centroids[own] - 0.5 * (pos[a] + pos[b]), axis=1)
    return dict(sizes=area, normals=normal, pairs=np.stack([lo, hi], axis=1),
                lengths=np.bincount(inv.ravel(), weights=dual, minlength=uniq.shape[0]),
                spans=np.linalg.norm(pos[lo] - pos[hi], axis=1), open=count == 1)


@pytest.mark.parametrize("seed, polygons", [(0, False), (1, False), (2, True)])
def test_vertex_graph_equals_the_numpy_construction_bit_for_bit(seed, polygons):
    # triangle (or polygon) soups over few vertices: non-manifold edges, flipped and
    # repeated faces, collapsed edges, unused vertices, a vertex on more than 32 edges
    from superfacets.elements.vertices import vertex_graph

    rng = np.random.default_rng(seed)
    n_vertices, n_faces = 80, 600
    size = 5 if polygons else 3
    faces = rng.integers(0, n_vertices - 5, size=(n_faces, size))
    faces[:60, 0] = 0  # a high-valence vertex: a bucket past the insertion sort
    faces[60:80] = faces[:20][:, ::-1]
    if polygons:
        faces[::3, 3:] = -1  # triangles among pentagons and quads
        faces[1::3, 4] = -1
    mesh = Mesh(rng.normal(size=(n_vertices, 3)), faces)
    g = vertex_graph(mesh).graph
    ref = _vertex_graph_by_numpy(mesh)
    for name in ("sizes", "normals", "pairs", "lengths", "spans"):
        np.testing.assert_array_equal(getattr(g, name), ref[name], err_msg=name)
    assert g.pairs.dtype == ref["pairs"].dtype and g.n_elements == n_vertices - 5
    lo, hi = ref["pairs"][ref["open"], 0], ref["pairs"][ref["open"], 1]
    np.testing.assert_array_equal(g.boundary_elements, np.concatenate([lo, hi]))
    half = 0.5 * ref["spans"][ref["open"]]
    np.testing.assert_array_equal(g.boundary_lengths, np.concatenate([half, half]))
    assert np.diff(g.indptr).max() > 32 and ref["open"].any() and not ref["open"].all()


def test_face_graph_caches_the_terms_of_the_weights(sphere):
    # the cached per-adjacency data equal the formulas of docs/notes/method.md, sections 1-2
    g = face_graph(sphere)
    assert g is face_graph(sphere) and g.kind == "faces" and g.n_elements == sphere.n_faces
    v, c, n = sphere.vertices, sphere.centroids, sphere.normals
    i, j = g.pairs[:, 0], g.pairs[:, 1]
    a, b = v[g.edges[:, 0]], v[g.edges[:, 1]]
    mid = (a + b) / 2
    np.testing.assert_allclose(g.lengths, np.linalg.norm(b - a, axis=1))
    np.testing.assert_allclose(g.terms.geo, np.linalg.norm(c[i] - mid, axis=1)
                               + np.linalg.norm(c[j] - mid, axis=1))
    np.testing.assert_allclose(g.terms.cos, np.clip((n[i] * n[j]).sum(1), -1, 1))
    assert not g.terms.concave.any()  # a sphere is convex everywhere
    assert g.terms is g.terms  # computed once
    assert g.area == pytest.approx(sphere.area)
    np.testing.assert_allclose(g.centroid, sphere.vertices.mean(axis=0), atol=1e-12)


def test_weights_and_metrics_take_the_graph_or_the_mesh(valley):
    from superfacets import superfacets
    from superfacets.evaluation.metrics import compactness

    g = face_graph(valley)
    np.testing.assert_array_equal(paper_weights(g, alpha=50), paper_weights(valley, alpha=50))
    labels = superfacets(valley, 12)
    assert compactness(g, labels) == compactness(valley, labels)
    concave = g.terms.concave
    assert concave.any() and (~concave).any()  # the valley's crease is concave, the rest flat


def test_vertex_and_point_terms_equal_the_numpy_expressions_bit_for_bit(valley):
    """The one-pass kernel of the vertex and point terms does the numpy expressions'
    floating-point operations in their order (docs/notes/method.md, sections 1-2)."""
    import trimesh

    from superfacets.elements.points import point_graph
    from superfacets.elements.vertices import vertex_graph
    from superfacets.inputs.cloud import PointCloud

    rng = np.random.default_rng(0)
    bumpy = trimesh.creation.icosphere(subdivisions=4)
    bumpy.vertices *= 1 + 0.1 * rng.random((len(bumpy.vertices), 1))
    pts = trimesh.sample.sample_surface(bumpy, 3000, seed=2)[0]
    graphs = [vertex_graph(valley).graph, vertex_graph(Mesh(bumpy.vertices, bumpy.faces)).graph,
              point_graph(PointCloud(pts)).graph]
    assert graphs[2].normals.dtype == np.float32  # points keep them in 4 bytes...
    for g in graphs:
        p, n = g.positions, g.normals.astype(np.float64)  # ... read in float64
        i, j = g.pairs[:, 0], g.pairs[:, 1]
        d = p[i] - p[j]
        np.testing.assert_array_equal(g.terms.geo, np.linalg.norm(d, axis=1))
        np.testing.assert_array_equal(
            g.terms.cos, np.clip(np.einsum("ij,ij->i", n[i], n[j]), -1.0, 1.0))
        np.testing.assert_array_equal(g.terms.concave,
                                      np.einsum("ij,ij->i", n[i] - n[j], d) < 0)
    assert graphs[0].terms.concave.any() and graphs[2].terms.concave.any()


def test_terms_of_a_slice_are_not_kept_and_equal_the_cached_ones(sphere):
    """The weights read the terms chunk by chunk: without the cache nothing is kept,
    and the values are those of the whole-graph terms, so the weights are the same."""
    from superfacets.elements.vertices import vertex_graph

    for g in (face_graph(sphere), vertex_graph(sphere).graph):
        g.release_terms()
        sl = slice(5, 40)
        part = g.terms_in(sl)
        w = paper_weights(g, alpha=100)
        assert "terms" not in g.__dict__  # computed per chunk, not cached
        whole = g.terms
        for a, b in zip(part, whole):
            np.testing.assert_array_equal(a, b[sl])
        np.testing.assert_array_equal(paper_weights(g, alpha=100), w)  # from the cache now
        np.testing.assert_array_equal(g.terms_in(sl).geo, whole.geo[sl])


def test_released_terms_come_back_the_same(sphere):
    from superfacets import segment

    g = face_graph(sphere)
    geo = g.terms.geo.copy()
    segment(sphere, 10, paper=True)  # without the clean-up, released once the weights are made
    assert "terms" not in g.__dict__
    np.testing.assert_array_equal(g.terms.geo, geo)


def _released_fields_come_back(g, mesh=None):
    names = ("normals", "pairs", "dual_edge", "lengths") + (() if g.spans is None else ("spans",))
    names += () if g.border_shares is None else ("border_shares",)
    before = {k: getattr(g, k).copy() for k in names}
    terms = g.terms
    g.release()
    g.release_terms()
    gone = [k for k in names if k not in g.__dict__]
    if mesh is not None:  # the mesh forgets its copy of the normals too
        assert mesh.__dict__["_geometry"][2] is None
    assert g.terms.geo.tolist() == terms.geo.tolist()  # rebuilt on the way, the same
    assert np.array_equal(g.terms.concave, terms.concave)
    for k, v in before.items():
        assert getattr(g, k).dtype == v.dtype, k
        np.testing.assert_array_equal(getattr(g, k), v, err_msg=k)
    if mesh is not None:
        assert g.normals is mesh.normals  # shared again, not two copies
    return gone


def _polygon_grid(nx: int, ny: int) -> Mesh:
    """Quads on a bent grid, the last row's split into triangles (rows padded with -1)."""
    x, y = np.meshgrid(np.arange(nx + 1.0), np.arange(ny + 1.0), indexing="ij")
    v = np.stack([x.ravel(), y.ravel(), 0.1 * (x * y).ravel()], axis=1)
    at = lambda i, j: i * (ny + 1) + j  # noqa: E731
    faces = []
    for i in range(nx):
        for j in range(ny):
            q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]
            faces += [q[:3] + [-1], [q[0], q[2], q[3], -1]] if j == ny - 1 else [q]
    return Mesh(v, np.array(faces))


def test_face_graph_releases_what_the_passes_do_not_read_and_rebuilds_it(sphere):
    for mesh in (sphere, _polygon_grid(5, 4)):  # triangles; quads and triangles
        g = face_graph(mesh)
        assert _released_fields_come_back(g, mesh) == ["normals", "pairs", "dual_edge",
                                                       "lengths"]


def test_a_triangle_meshs_edges_are_made_again_from_its_faces(sphere, valley):
    # the shared edge of each face pair, from the two triangles' vertices: the same as
    # built on closed, open and non-manifold meshes; not offered where a pair shares more
    # than one edge (duplicate faces; a degenerate face lists its edge twice) or polygons
    import trimesh

    v = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -1, 0], [0.5, 0, 1], [1.5, 1, 0],
                  [2, 0, 0]], float)
    fan = Mesh(v, [[0, 1, 2], [1, 0, 3], [0, 1, 4], [1, 5, 2], [6, 1, 5]])
    half = valley.faces[valley.centroids[:, 0] > 0]
    used = np.unique(half)
    remap = np.full(valley.n_vertices, -1)
    remap[used] = np.arange(used.shape[0])
    ball = trimesh.creation.icosphere(subdivisions=6)  # (normals made in several blocks)
    for mesh in (sphere, Mesh(valley.vertices[used], remap[half]), fan,
                 Mesh(ball.vertices, ball.faces)):
        g = face_graph(mesh)
        assert "edges" in g.rebuild
        built, normals = g.edges.copy(), g.normals.copy()
        g.release()
        assert "edges" not in g.__dict__ and mesh.__dict__["_geometry"][2] is None
        assert g.edges.dtype == built.dtype
        np.testing.assert_array_equal(g.edges, built)
        np.testing.assert_array_equal(g.normals, normals)
    dup = Mesh(v[:4], [[0, 1, 2], [0, 1, 2], [1, 3, 2]])  # a pair shares three vertices
    flat = Mesh(v, [[0, 1, 2], [1, 6, 6], [6, 1, 5]])  # (1, 6) twice in a degenerate face
    for mesh in (_polygon_grid(5, 4), dup, flat):
        g = face_graph(mesh)
        edges = g.edges
        g.release()
        assert "edges" not in g.rebuild and g.edges is edges


def test_vertex_and_point_graphs_release_their_pairs(sphere):
    from superfacets.elements.builders import elements_of

    for kind, released in (("vertices", ["pairs", "dual_edge"]),
                           ("points", ["pairs", "dual_edge", "lengths", "spans",
                                       "border_shares"])):
        g = elements_of(sphere if kind == "vertices" else sphere.vertices, kind).graph
        assert _released_fields_come_back(g) == released
    assert g.pairs.dtype == np.int32  # points: 4-byte pairs, as built and rebuilt
    g.release(keep=("spans",))
    assert "spans" in g.__dict__ and "pairs" not in g.__dict__


def test_coarsening_reads_no_released_field(sphere):
    # the pipeline releases the pairs, dual edges and spans before the coarsening: it
    # reads the CSR layout and the weights per CSR entry instead, with the same result
    from superfacets.method.coarse_to_fine import COARSENING_READS, coarsen
    from superfacets.method.weights import csr_weights, paper_weights

    g = face_graph(sphere)
    w = csr_weights(g, paper_weights(g))
    kept = coarsen(g, w, 8)
    g.release(keep=COARSENING_READS)
    released = coarsen(g, w, 8)
    assert not {"pairs", "dual_edge"} & set(g.__dict__)
    for a, b in ((kept.graph.pairs, released.graph.pairs), (kept.weights, released.weights),
                 (kept.graph.lengths, released.graph.lengths), (kept.cluster, released.cluster)):
        np.testing.assert_array_equal(a, b)


def test_face_graph_rebuilds_its_normals_after_its_mesh_is_gone(sphere):
    import gc

    from superfacets.elements import as_element_graph

    g = as_element_graph((sphere.vertices, sphere.faces))  # its Mesh is dropped
    gc.collect()
    assert g.rebuild["normals"].mesh() is None
    _released_fields_come_back(g)


def test_runs_that_release_the_graph_give_the_same_labels(valley, monkeypatch):
    # the passes run without the released fields; what reads them after
    # (connectivity, clean-up, split and merge) finds them rebuilt, the same
    from superfacets import Mesh, segment
    from superfacets.method import pipeline

    trims = []
    monkeypatch.setattr(pipeline, "give_back_free_memory", lambda: trims.append(1))

    def run(release_min, **kw):
        monkeypatch.setattr(pipeline, "_RELEASE_MIN", release_min)
        mesh = Mesh(valley.vertices, valley.faces)
        r = segment(mesh, 12, **kw)
        g = face_graph(mesh)
        return r.labels, "pairs" in g.__dict__, "terms" in g.__dict__

    for kw in ({}, {"cleanup": True, "split_merge": True}, {"coarsen": 4}):
        del trims[:]
        kept, held, _ = run(1 << 60, **kw)
        assert held and not trims  # a small graph: nothing released, nothing trimmed
        released, _, _ = run(0, **kw)
        assert len(trims) == 2  # after the build, and before the passes
        np.testing.assert_array_equal(released, kept)


def test_a_large_graph_holds_no_terms_through_the_passes(valley, monkeypatch):
    # the clean-up's adjacency terms are made again after the passes, the same values
    from superfacets import Mesh, segment
    from superfacets.method import pipeline, stages

    seen = {}
    iterate = stages.iterate_passes

    def spy(graph, *args, **kw):
        seen["terms"] = "terms" in graph.__dict__
        return iterate(graph, *args, **kw)

    monkeypatch.setattr(pipeline, "iterate_passes", spy)
    for release_min, held in ((1 << 60, True), (0, False)):
        monkeypatch.setattr(pipeline, "_RELEASE_MIN", release_min)
        segment(Mesh(valley.vertices, valley.faces), 12, cleanup=True)
        assert seen["terms"] is held


def test_point_runs_that_release_the_graph_give_the_same_labels(monkeypatch):
    # points release their pairs and spans once the weights are made, before the
    # coarse-to-fine run's clusters (20,000 points, k = 8: 5 points per cluster)
    from superfacets import segment
    from superfacets.method import pipeline

    rng = np.random.default_rng(3)
    xy = rng.random((20_000, 2))
    cloud = np.c_[xy, 0.2 * np.sin(6 * xy[:, 0]) * np.cos(4 * xy[:, 1])]

    def run(release_min):
        monkeypatch.setattr(pipeline, "_RELEASE_MIN", release_min)
        r = segment(cloud, 8, merge_from=1)  # 2,500 points per superpoint: coarse-to-fine
        return r.labels, r.timings.get("coarse_elements")

    (kept, coarse), (released, _) = run(1 << 60), run(0)
    assert coarse is not None and coarse < 20_000 // 3
    np.testing.assert_array_equal(released, kept)


def test_graph_and_geometry_on_threads_equal_one_thread(monkeypatch):
    # ranges of half-edges and faces on three threads: the cuts move to edge starts,
    # so non-manifold runs, duplicates and collapsed edges come out as from one call
    from superfacets._runtime import threads as _threads

    rng = np.random.default_rng(1)
    faces = rng.integers(0, 25, size=(3000, 3))
    faces[:300, 0] = 0
    vertices = rng.random((25, 3))
    one = build_face_graph(faces, 25)
    geo_one = Mesh(vertices, faces)._geometry
    monkeypatch.setattr(_threads, "MIN_PER_THREAD", 100)
    monkeypatch.setattr(_threads, "default_threads", lambda: 3)
    assert len(_threads.split(9000)) == 4
    three = build_face_graph(faces, 25)
    for name in one._fields:
        a, b = np.asarray(getattr(one, name)), np.asarray(getattr(three, name))
        assert a.dtype == b.dtype and np.array_equal(a, b), name
    for a, b in zip(geo_one, Mesh(vertices, faces)._geometry):
        assert np.array_equal(a, b)


def test_weights_and_cut_costs_by_chunks_on_threads_equal_one_thread(sphere, monkeypatch):
    # the per-adjacency arrays in chunks of 64 on three threads, from a graph whose
    # pairs and normals were released (made again before the threads start): the same
    # arrays as the chunks one after the other, and the plain numpy expressions
    from superfacets._runtime import threads as _threads
    from superfacets.elements import graph as _graph
    from superfacets.method.cleanup import cut_costs

    def arrays(n_threads):
        monkeypatch.setattr(_threads, "default_threads", lambda: n_threads)
        g = face_graph(sphere)
        g.release()
        made = []
        compute = _graph.chunked

        def spy(n, fn, dtype=np.float64):
            made.append(n)
            return compute(n, fn, dtype)

        monkeypatch.setattr("superfacets.method.weights.chunked", spy)
        monkeypatch.setattr("superfacets.method.cleanup.chunked", spy)
        out = (paper_weights(g, alpha=200, beta=0.5, features=sphere.centroids),
               shlafman_weights(g, alpha=0.3), cut_costs(g, alpha=200))
        assert made == [g.n_edges] * 3
        return out, g

    monkeypatch.setattr(_graph, "CHUNK", 64)
    one, g = arrays(1)
    assert g.n_edges > 6 * 64  # several chunks a thread
    three, _ = arrays(3)
    for a, b in zip(one, three):
        assert np.array_equal(a, b)
    t = g.terms
    theta = np.arccos(t.cos)
    jump = np.linalg.norm(sphere.centroids[g.pairs[:, 0]] - sphere.centroids[g.pairs[:, 1]],
                          axis=1)
    want = (t.geo + 200 * np.where(t.concave, 1.0, 0.2) * g.span * theta / np.pi
            + 0.5 * g.span * jump) / g.diagonal
    np.testing.assert_allclose(three[0], want, rtol=1e-12)
    np.testing.assert_allclose(three[1], 0.7 * t.geo + 0.3 * (1 - t.cos**2), rtol=1e-12)


@pytest.mark.parametrize("seed", [0, 1])
def test_knn_layout_is_the_csr_of_the_distinct_symmetric_pairs(seed):
    """Known answer: the point graph's kernel gives the layout of the sorted distinct
    pairs (i, j), j listed by i or i by j, as adjacency_csr builds it."""
    from oracle.adjacency import knn_csr

    from superfacets.elements.graph import adjacency_csr

    rng = np.random.default_rng(seed)
    n, k = 300, 6
    nbr = np.stack([rng.choice(np.r_[:i, i + 1:n], k, replace=False) for i in range(n)])
    keep = rng.random((n, k)) < 0.8
    # longer lists for some rows (the point graph's widened neighbourhoods)
    rows = np.sort(rng.choice(n, 40, replace=False))
    more = np.stack([rng.choice(np.r_[:i, i + 1:n], 2 * k, replace=False) for i in rows])
    more_keep = rng.random(more.shape) < 0.9
    indptr = np.empty(n + 1, dtype=np.int64)
    indices = knn_csr(nbr, keep, indptr, rows, more, more_keep)[:indptr[-1]]
    dual_edge, pairs = _numbered(indptr, indices)
    src = np.r_[np.repeat(np.arange(n), k).reshape(n, k)[keep],
                np.repeat(rows, 2 * k).reshape(-1, 2 * k)[more_keep]]
    dst = np.r_[nbr[keep], more[more_keep]]
    key = np.unique(np.minimum(src, dst) * n + np.maximum(src, dst))
    np.testing.assert_array_equal(pairs, np.c_[key // n, key % n])
    want = adjacency_csr(key // n, key % n, n)
    for got, ref in zip((indptr, indices, dual_edge), want):
        np.testing.assert_array_equal(got, ref)
    assert indices.dtype == np.int32 and dual_edge.dtype == np.int32


def _numbered(indptr, indices):
    """The dual-edge map and pairs of a CSR layout (as the point graph builds them when
    read: ``pairs_from_csr``)."""
    from oracle.adjacency import number_pairs

    pairs = np.empty((indices.shape[0] // 2, 2), dtype=np.int32)
    dual_edge = np.empty(indices.shape[0], dtype=np.int32)
    number_pairs(indptr, indices, indptr.shape[0] - 1, dual_edge, np.empty(0, np.int64), pairs)
    return dual_edge, pairs


def test_a_point_listed_as_its_own_neighbour_is_no_edge():
    """The kernel once left a pair slot unwritten (garbage indices) for a self entry."""
    from oracle.adjacency import knn_csr

    rng = np.random.default_rng(2)
    n, k = 50, 4
    nbr = np.stack([rng.choice(np.r_[:i, i + 1:n], k, replace=False) for i in range(n)])
    keep = np.ones((n, k), dtype=bool)
    rows, more = np.array([3, 7]), np.stack([np.arange(8), np.arange(8) + 1])
    empty = (np.zeros(0, dtype=np.int64), np.zeros((0, 1), dtype=np.int64),
             np.zeros((0, 1), dtype=bool))
    indptr = np.empty(n + 1, dtype=np.int64)
    want = _numbered(indptr, knn_csr(nbr, keep, indptr, *empty)[:indptr[-1]])
    selfish = nbr.copy()
    selfish[[5, 9], 2] = [5, 9]  # two points list themselves instead of a neighbour
    keep2 = keep.copy()
    keep2[[5, 9], 2] = True
    indptr = np.empty(n + 1, dtype=np.int64)
    indices = knn_csr(selfish, keep2, indptr, rows, more, np.ones(more.shape, dtype=bool))
    indices = indices[:indptr[-1]]
    _, pairs = _numbered(indptr, indices)
    assert (pairs[:, 0] < pairs[:, 1]).all() and pairs.max() < n
    assert not any(i in indices[indptr[i]:indptr[i + 1]] for i in range(n))
    ok = keep.copy()
    ok[[5, 9], 2] = False  # the same graph as leaving those entries out
    ref_indptr = np.empty(n + 1, dtype=np.int64)
    ref = knn_csr(nbr, ok, ref_indptr, rows, more, np.ones(more.shape, dtype=bool))
    ref = ref[:ref_indptr[-1]]
    np.testing.assert_array_equal(pairs, _numbered(ref_indptr, ref)[1])
    np.testing.assert_array_equal(indices, ref)
    assert want[1].shape[0] > 0


def test_points_closer_than_the_squared_distance_can_hold_are_two_points():
    """Two distinct points 4e-312 apart are at distance 0 for the KD-tree, which may
    list the other first: each is still its own first neighbour, and no point is its
    own neighbour in the graph (the graph held uninitialized pairs before)."""
    from superfacets.elements.points import point_graph
    from superfacets.inputs.cloud import PointCloud

    pts = np.random.default_rng(0).random((400, 3))
    pts[274] = [3.98616432e-312, 0, 0]
    pts[275] = [0, 0, 0]
    g = point_graph(PointCloud(pts)).graph
    assert g.n_elements == 400
    assert (g.pairs[:, 0] < g.pairs[:, 1]).all() and g.pairs.max() < 400
    rows = np.repeat(np.arange(g.n_elements), np.diff(g.indptr))
    assert not (rows == g.indices).any()
    labels = segment(pts, 5).labels
    assert labels.min() == 0 and labels.max() == 4


def test_points_are_indexed_along_a_z_order_curve():
    """Known answer: points of a box are listed along the Z-order curve of their
    coordinates as integers from its lower corner (the cube of the least power of two
    above its largest side, halved), x the major bit."""
    from superfacets.elements.points import distinct_points

    i, j = np.meshgrid(np.arange(4), np.arange(4), indexing="ij")
    p = np.c_[1 + i.ravel() / 4, 1 + j.ravel() / 4, np.ones(16)]
    rng = np.random.default_rng(0)
    s, inverse = distinct_points(p[rng.permutation(16)])
    got = [(int((x - 1) * 4), int((y - 1) * 4)) for x, y, _ in s]
    assert got == [(0, 0), (0, 1), (1, 0), (1, 1), (0, 2), (0, 3), (1, 2), (1, 3),
                   (2, 0), (2, 1), (3, 0), (3, 1), (2, 2), (2, 3), (3, 2), (3, 3)]


@pytest.mark.parametrize("seed", [0, 1])
def test_distinct_points_of_a_box_keep_the_whole_clouds_order(seed):
    """Invariant: the order of the distinct points depends on the positions and the
    frame alone, so a box of a cloud (a tile) given the whole cloud's frame lists its
    points in the whole cloud's relative order; each input row maps to its own position;
    -0.0 and 0.0 are one point."""
    from superfacets.elements.neighbors import local_frame
    from superfacets.elements.points import distinct_points

    rng = np.random.default_rng(seed)
    p = rng.normal(size=(5000, 3)) * rng.choice([1e-3, 1.0, 50.0], size=(5000, 1))
    p[:200] = np.round(p[:200], 1)  # duplicates, zeros
    p[200:300] = p[rng.integers(0, 5000, 100)]
    p[300] = [-0.0, 0.0, 0.0]
    p[301] = [0.0, -0.0, 0.0]
    s, inverse = distinct_points(p)
    np.testing.assert_array_equal(s[inverse], p)
    assert s.shape[0] == np.unique(p, axis=0).shape[0] == np.unique(s, axis=0).shape[0]
    for lo, hi in (([-0.5, -2, -1], [3, 0.7, 9]), ([-1e9] * 3, [0, 0, 1e9]), ([0] * 3, [1] * 3)):
        box = ((p >= lo) & (p <= hi)).all(axis=1)
        sub, _ = distinct_points(p[box], local_frame(p))
        inside = ((s >= lo) & (s <= hi)).all(axis=1)
        np.testing.assert_array_equal(sub, s[inside])


def _scan_lines(n_lines=6, radius=5.0, step=0.05, gap=0.4):
    """Points on concentric rings (a LiDAR's scan lines far from it): ``step`` apart
    along a ring, ``gap`` across."""
    rings = []
    for j in range(n_lines):
        r = radius + j * gap
        t = np.arange(int(2 * np.pi * r / step)) * step / r
        rings.append(np.c_[r * np.cos(t), r * np.sin(t), np.zeros(t.size)])
    return np.concatenate(rings)


def test_points_on_scan_lines_reach_the_next_line(monkeypatch):
    """Known answer: 10 neighbours of a point on such a ring all lie on its own ring (5
    steps of 0.05 on each side), so the plain k-nearest-neighbour graph is one piece per
    ring; a neighbourhood that is a line is widened to 2 k, which reaches the next ring
    (0.4 away; 10 steps on each side reach 0.5): one piece."""
    from scipy.sparse.csgraph import connected_components

    from superfacets.elements import points as P
    from superfacets.inputs.cloud import PointCloud

    pts = _scan_lines()
    monkeypatch.setattr(P, "WIDEN", 1)  # the plain graph
    plain = P.point_graph(PointCloud(pts), 10).graph
    monkeypatch.undo()
    wide = P.point_graph(PointCloud(pts), 10).graph
    assert connected_components(plain.to_csr(), directed=False)[0] == 6
    assert connected_components(wide.to_csr(), directed=False)[0] == 1
    # every adjacency of the plain graph is kept; the new ones join neighbouring lines
    old = set(map(tuple, plain.pairs.tolist()))
    new = set(map(tuple, wide.pairs.tolist()))
    assert old < new
    across = np.array(sorted(new - old))
    radial = np.linalg.norm(wide.positions[:, :2], axis=1)  # (the graph's own order)
    dr = np.abs(radial[across[:, 0]] - radial[across[:, 1]])
    assert np.all(dr < 0.4 + 1e-6) and np.any(dr > 0.39)  # to the next ring, no farther
    np.testing.assert_array_equal(wide.sizes, plain.sizes)  # sizes: the k-th distance


def test_a_surface_graph_is_not_widened(monkeypatch):
    """Points spread over a surface have no line-like neighbourhood: the graph is the
    plain k-nearest-neighbour graph, to the bit."""
    from superfacets.elements import points as P
    from superfacets.inputs.cloud import PointCloud

    rng = np.random.default_rng(3)
    uv = rng.random((3000, 2))
    pts = np.c_[uv, 0.1 * np.sin(3 * uv[:, 0])]
    wide = P.point_graph(PointCloud(pts), 10).graph
    monkeypatch.setattr(P, "WIDEN", 1)
    plain = P.point_graph(PointCloud(pts), 10).graph
    for name in ("indptr", "indices", "pairs", "lengths", "normals", "sizes"):
        np.testing.assert_array_equal(getattr(wide, name), getattr(plain, name))


def test_linearity_of_a_line_a_plane_and_a_ball():
    from oracle.normals import pca_linearity

    rng = np.random.default_rng(0)
    line = np.c_[np.arange(11.0), np.zeros(11), np.zeros(11)]
    plane = np.c_[rng.random((11, 2)), np.zeros(11)]
    ball = rng.normal(size=(11, 3))
    for pts, lo, hi in ((line, 0.999, 1.0), (plane, 0.0, 0.9), (ball, 0.0, 0.9)):
        out = np.empty(1)
        pca_linearity(pts, np.arange(11)[None, :], out)
        assert lo <= out[0] <= hi


def test_superpoints_on_scan_lines_are_the_same_for_any_thread_count():
    """The widened rows go through the same kernels: labels equal on 1 and 2 threads, one
    label per point; the count asked for (the plain graph, one piece per ring, gives 64
    superpoints for 12, each on one ring), superpoints spanning several rings."""
    from superfacets import PointCloud, segment

    pts = _scan_lines()
    one = segment(PointCloud(pts), 12, n_threads=1)
    two = segment(PointCloud(pts), 12, n_threads=2)
    np.testing.assert_array_equal(one.labels, two.labels)
    assert one.labels.shape == (pts.shape[0],) and one.labels.min() >= 0
    assert one.n_segments == 12
    ring = np.rint((np.linalg.norm(pts[:, :2], axis=1) - 5.0) / 0.4).astype(int)
    rings_per_label = [np.unique(ring[one.labels == s]).size for s in range(one.n_segments)]
    assert max(rings_per_label) > 1


def test_point_graph_is_the_same_on_any_number_of_threads(monkeypatch):
    # the tree is queried in one compiled loop whose ranges the threads take in turn
    # (4-byte neighbours, the k-th distance and the radius's mask kept): one thread or
    # three give the same graph, bit for bit, with ties at the k-th distance (a quantized
    # grid) and scan lines joined wider (a line)
    from superfacets.elements.points import point_graph
    from superfacets.inputs.cloud import PointCloud

    xy = np.stack(np.meshgrid(np.arange(150.0), np.arange(100.0)), -1).reshape(-1, 2)
    grid = np.c_[xy, 0.05 * (xy[:, 0] % 3)]
    line = np.c_[np.linspace(0, 149, 400), np.full(400, 125.0), np.zeros(400)]
    pts = np.concatenate([grid, line])

    def graph(threads, radius=None):
        monkeypatch.setenv("SUPERFACETS_KERNEL_THREADS", threads)
        return point_graph(PointCloud(pts), 6, radius).graph

    for radius in (None, 0.008):
        one, three = graph("1", radius), graph("3", radius)
        for name in ("pairs", "indptr", "indices", "sizes", "normals", "spans", "lengths"):
            a, b = getattr(one, name), getattr(three, name)
            assert a.dtype == b.dtype and np.array_equal(a, b), name
        assert one.pairs.dtype == np.int32 and one.n_edges > 0
    # (the radius, about 1.6 grid steps, masks the neighbours beyond it: fewer pairs)
    assert graph("1", 0.008).n_edges < graph("1").n_edges


def test_a_point_graph_builds_its_pairs_spans_and_lengths_only_when_read():
    """A default run on points reads the CSR layout and the border shares alone: the
    pairs, dual-edge map, spans and border lengths (about 180 bytes per point) are never
    built; read, they are the sorted distinct pairs and the module's formulas."""
    from superfacets.elements.points import point_graph
    from superfacets.inputs.cloud import PointCloud
    from superfacets.method.connectivity import enforce_connectivity

    rng = np.random.default_rng(4)
    xyz = rng.normal(size=(3000, 3))
    xyz /= np.linalg.norm(xyz, axis=1, keepdims=True)
    cloud = PointCloud(xyz)
    g = point_graph(cloud).graph
    lazy = ("pairs", "dual_edge", "lengths", "spans")
    labels = segment(cloud, 40).labels
    assert not any(name in g.__dict__ for name in lazy)
    assert g.n_edges == g.indices.shape[0] // 2
    # read: the distinct pairs (i, j), i < j, in CSR order, and the formulas
    row = np.repeat(np.arange(g.n_elements), np.diff(g.indptr))
    up = g.indices > row
    np.testing.assert_array_equal(g.pairs, np.c_[row[up], g.indices[up]])
    np.testing.assert_array_equal(g.pairs[g.dual_edge].min(axis=1),
                                  np.minimum(row, g.indices))
    share = 2.0 * np.sqrt(np.pi * g.sizes) / np.diff(g.indptr)
    lo, hi = g.pairs[:, 0], g.pairs[:, 1]
    np.testing.assert_array_equal(g.lengths, 0.5 * (share[lo] + share[hi]))
    np.testing.assert_array_equal(g.spans, np.linalg.norm(g.positions[hi] - g.positions[lo],
                                                          axis=1))
    # the kernels that sum border lengths give the same sums from the shares
    assert np.array_equal(g.border_shares, share)
    copy = g.replaced(sizes=g.sizes)  # a copy with the lengths built: read per pair
    lengths_only = copy.replaced(border_shares=None)
    pieces = labels.copy()
    pieces[rng.choice(g.n_elements, 30, replace=False)] = 7  # strays to merge
    np.testing.assert_array_equal(enforce_connectivity(g, pieces),
                                  enforce_connectivity(lengths_only, pieces))
    # replaced() leaves unbuilt fields unbuilt
    fresh = point_graph(PointCloud(xyz)).graph.replaced(sizes=np.ones(g.n_elements))
    assert not any(name in fresh.__dict__ for name in lazy) and fresh.area == g.n_elements
    # the shares, released (the passes do not read them), come back from the sizes as
    # built, also in a copy whose sizes were stretched (adaptive density)
    fresh.release()
    assert "border_shares" not in fresh.__dict__
    np.testing.assert_array_equal(fresh.border_shares, share)


def test_weights_from_the_csr_layout_equal_the_weights_per_pair():
    """Known answer: csr_point_weights is csr_weights(paper_weights(...)) bit for bit, on
    points and on mesh vertices, in float64 and float32 (np.arccos as paper_weights
    calls it)."""
    import trimesh

    from superfacets.elements.points import point_graph
    from superfacets.elements.vertices import vertex_graph
    from superfacets.inputs.cloud import PointCloud
    from superfacets.method.weights import csr_point_weights, csr_weights

    rng = np.random.default_rng(5)
    cloud = PointCloud(rng.random((5000, 3)) * [4, 2, 1])
    ball = trimesh.creation.icosphere(subdivisions=4)
    for g in (point_graph(cloud).graph, vertex_graph(Mesh(ball.vertices, ball.faces)).graph):
        for alpha, eta in ((200.0, 0.2), (37.5, 0.9)):
            ref = paper_weights(g, alpha=alpha, eta_convex=eta)
            for dtype in (np.float64, np.float32):
                got = csr_point_weights(g, alpha=alpha, eta_convex=eta, dtype=dtype)
                assert got.dtype == dtype
                np.testing.assert_array_equal(got, csr_weights(g, ref, dtype))


def test_distinct_positions_found_in_parallel_equal_one_pass_in_order():
    """Known answer: distinct_in_order (its runs and moves in parallel) gives the arrays
    of one pass in order: each run of equal rows once, -0.0 equal to 0.0, the first
    row's values kept; on empty, single and many-duplicate inputs."""
    from oracle.geometry import distinct_in_order

    rng = np.random.default_rng(8)
    for n in (0, 1, 2, 7, 50_000):
        p = rng.integers(-2, 3, (n, 3)).astype(np.float64)
        p[::5, 1] *= -0.0 if n else 1.0  # zeros of both signs
        order = np.lexsort((p[:, 2], p[:, 1], p[:, 0]))
        out, inverse = np.empty_like(p), np.empty(n, dtype=np.int64)
        m = distinct_in_order(p, order, out, inverse)
        want_out, want_inv, prev = [], np.empty(n, dtype=np.int64), None
        for row in order:
            if prev is None or (p[row] != p[prev]).any():
                want_out.append(p[row].copy())
            want_inv[row] = len(want_out) - 1
            prev = row
        assert m == len(want_out)
        np.testing.assert_array_equal(out[:m], np.array(want_out).reshape(-1, 3))
        np.testing.assert_array_equal(np.signbit(out[:m]), np.signbit(
            np.array(want_out).reshape(-1, 3)))
        np.testing.assert_array_equal(inverse, want_inv)


@pytest.mark.parametrize("threads", ["1", "2", "3"])
def test_the_z_order_sorts_by_the_whole_keys_then_the_positions(monkeypatch, threads):
    """Known answer: distinct_points' order (a sort of each key's first 64 varying bits,
    then equal ones by the whole keys and the coordinates, on threads where compiled) is
    numpy's stable lexsort of the whole keys and the coordinates: points closer than the
    first 64 bits tell apart, duplicates, -0.0 beside 0.0 (the lowest row's kept)."""
    from oracle.geometry import distinct_in_order

    from superfacets._kernels import native
    from superfacets.elements.neighbors import local_frame, local_keys
    from superfacets.elements.points import distinct_points

    rng = np.random.default_rng(3)
    near = 1.0 + rng.integers(0, 4, (30_000, 3)) * 1e-13  # equal in the first 64 bits
    grid = rng.integers(-3, 4, (40_000, 3)).astype(np.float64)  # duplicates, zeros
    grid[rng.random(grid.shape) < 0.3] *= -1.0  # -0.0 and 0.0 in the same runs
    p = np.r_[near, grid, rng.random((30_000, 3)) * 1e3, [[-1e5, 2e5, 7.0]]]
    p = p[rng.permutation(p.shape[0])]
    keys = local_keys(p, local_frame(p))
    order = np.lexsort((p[:, 2], p[:, 1], p[:, 0], keys[:, 2], keys[:, 1], keys[:, 0]))
    want, want_inv = np.empty_like(p), np.empty(p.shape[0], dtype=np.int64)
    m = distinct_in_order(p, order, want, want_inv)
    with monkeypatch.context() as mp:
        if native.available():  # (the compiled kernels' threads; numba's as configured)
            mp.setenv("SUPERFACETS_KERNEL_THREADS", threads)
        out, inverse = distinct_points(p)
    assert out.shape[0] == m < 60_000
    assert out.tobytes() == want[:m].tobytes()  # -0.0 or 0.0 as the lowest row has it
    np.testing.assert_array_equal(inverse, want_inv)


def test_the_z_orders_shared_leading_bits_are_those_no_point_changes():
    """Known answer: the leading bits of the 189-bit key strings that every point shares
    (the Z-order sorts from the first one that varies): found by or/and reductions, they
    are the bits up to the highest one where some key differs from the first, in a cloud
    in a small box far from the origin, a cloud in a slab (its frame's upper z bits
    shared), one point, and a spread one."""
    from superfacets.elements.neighbors import local_frame, local_keys, shared_prefix

    rng = np.random.default_rng(5)
    slab = np.c_[rng.random((5_000, 2)) * 60.0, rng.normal(0.0, 0.01, 5_000)]
    for p in (1e6 + rng.random((5_000, 3)) * 1e-3, np.array([[1.0, 2.0, 3.0]]), slab,
              rng.normal(size=(5_000, 3)) * 1e3, np.full((4, 3), 7.0)):
        keys = local_keys(p, local_frame(p))
        shared = shared_prefix(keys)
        want = 0
        for w in range(3):
            vary = 0
            for x in keys[:, w]:
                vary |= int(x) ^ int(keys[0, w])
            if vary:
                want += 63 - vary.bit_length()
                break
            want += 63
        assert shared == want
    same = np.full((4, 3), 7.0)
    assert shared_prefix(local_keys(same, local_frame(same))) == 189


def _owned(a: np.ndarray) -> np.ndarray:
    """A copy of ``a`` that nothing else holds (as a cloud read from a file)."""
    return np.array(a, copy=True)


def test_a_cloud_lends_its_points_to_its_graph_and_gets_them_back_bit_for_bit():
    """A cloud that alone holds its points lets them go once its graph holds the distinct
    points (24 bytes per point of a run's peak), and gives them back on first use bit for
    bit: duplicates, -0.0 merged with 0.0, invalid rows of an organized cloud."""
    import pickle

    from superfacets.elements.points import point_graph
    from superfacets.inputs.cloud import PointCloud

    rng = np.random.default_rng(5)
    xyz = rng.random((2000, 3))
    xyz[10] = xyz[20]  # an exact duplicate: one element
    xyz[30] = [0.0, 0.5, 0.5]
    xyz[31] = [-0.0, 0.5, 0.5]  # the same point: its row is kept as it was
    xyz[40:43] = [np.nan, np.inf, -np.inf]  # invalid rows
    original = xyz.copy()
    cloud = PointCloud(_owned(xyz), allow_invalid=True)
    point_graph(cloud)
    assert "points" in cloud.__dict__  # not checked usable yet: kept
    cloud = PointCloud(_owned(xyz), allow_invalid=True)
    labels = segment(cloud, 20).labels
    assert "points" not in cloud.__dict__  # lent (freed), and not asked back by the run
    assert point_graph(cloud).graph.n_elements == 2000 - 3 - 2
    assert cloud.n_total == 2000 and "points" not in cloud.__dict__
    back = cloud.points
    assert back.view(np.uint64).tolist() == original.view(np.uint64).tolist()
    assert not back.flags.writeable and "_lent" not in cloud.__dict__
    assert labels[10] == labels[20] and labels[30] == labels[31] and (labels[40:43] == -1).all()
    # a second graph (other neighbours) lends them again once the caller lets go of
    # them; a pickled cloud has them
    point_graph(cloud, 6)
    assert "points" in cloud.__dict__
    del back
    point_graph(cloud, 7)
    assert "points" not in cloud.__dict__
    again = pickle.loads(pickle.dumps(cloud))
    assert again.points.view(np.uint64).tolist() == original.view(np.uint64).tolist()


def test_a_cloud_keeps_points_its_caller_also_holds():
    from superfacets.elements.points import point_graph
    from superfacets.inputs.cloud import PointCloud

    xyz = np.random.default_rng(6).random((500, 3))
    cloud = PointCloud(xyz)
    cloud.check_usable()
    point_graph(cloud)
    assert cloud.__dict__["points"] is xyz  # the caller's array: freeing it frees nothing
    # a view of an array the caller holds is kept too; the view alone is lent
    base = np.random.default_rng(6).random((1000, 3))
    view_cloud = PointCloud(base[:500])
    view_cloud.check_usable()
    point_graph(view_cloud)
    assert "points" in view_cloud.__dict__
    alone = PointCloud(_owned(base).reshape(-1)[:1500].reshape(500, 3))
    alone.check_usable()
    point_graph(alone)
    assert "points" not in alone.__dict__
    np.testing.assert_array_equal(alone.points, base.reshape(-1)[:1500].reshape(500, 3))


def test_rows_of_elements_with_invalid_and_repeated_rows():
    """Known answers: the labels of a cloud's rows (-1 where a row is no point) and the
    first row of each point, asked for a few points (the centers) or all of them."""
    from superfacets.elements.builders import elements_of

    rng = np.random.default_rng(3)
    p = rng.random((4000, 3))
    p = np.r_[p, p[rng.integers(0, 4000, 500)]]  # repeated positions: one point each
    nan = p.copy()
    nan[rng.integers(0, 4500, 60)] = np.nan  # rows that are no point (an organized cloud)
    for cloud in (p, nan.reshape(45, 100, 3)):
        src = elements_of(cloud, "points")
        index, n = src.index, src.graph.n_elements
        brute = np.array([np.flatnonzero(index == e)[0] for e in range(n)])
        for elements in (np.arange(n), rng.choice(n, 50, replace=False), np.array([7, 7, 3])):
            np.testing.assert_array_equal(src.first_rows(elements), brute[elements])
        labels = rng.integers(0, 9, n).astype(np.int32)
        rows = src.to_rows(labels)
        assert rows.dtype == np.int32
        np.testing.assert_array_equal(rows, np.where(index >= 0, labels[index], -1))
        assert (rows < 0).sum() == (0 if cloud is p else np.isnan(nan).any(axis=1).sum())


def test_a_mesh_of_2_31_half_edges_is_refused_in_one_line():
    """int64 half-edge ids (from 2**31 half-edges, about 715M triangles) are refused
    before the compiled grouping, which takes int32 ids, is called."""
    from superfacets.elements.faces import _group_pairs_on_threads
    from superfacets.errors import MemoryLimitError

    wide = np.zeros(6, dtype=np.int64)
    with pytest.raises(MemoryLimitError, match=r"2\*\*31 half-edges.*--tiles"):
        _group_pairs_on_threads(None, wide, np.empty(0, dtype=np.int64), wide, wide)


def test_faces_around_one_edge_are_paired_in_proportion_to_them():
    """Every two faces around an edge were paired: 10,000 copies of one triangle (78 KiB)
    took 94 s and 9.1 GiB, 20,000 the whole machine. Up to 8 faces around an edge every
    two are still paired (the labels of any mesh of such edges unchanged); beyond, each
    face with the next around the edge, the last with the first."""
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    copies = face_graph(Mesh(v, np.tile([0, 1, 2], (10_000, 1))))
    assert copies.pairs.shape[0] == 10_000  # one cycle (the three edges give the same)
    assert np.diff(copies.indptr).max() == 2
    for n, pairs in ((3, 3), (8, 28), (9, 9), (6_000, 6_000)):  # a "book" on one edge
        ang = np.linspace(0, 2 * np.pi, n, endpoint=False)
        verts = np.vstack([[0, 0, 0], [0, 0, 1], np.c_[np.cos(ang), np.sin(ang), ang * 0]])
        book = Mesh(verts, np.c_[np.zeros(n, int), np.ones(n, int), np.arange(2, n + 2)])
        assert face_graph(book).pairs.shape[0] == pairs, n
    labels = segment(Mesh(v, np.tile([0, 1, 2], (10_000, 1))), 1).labels
    assert labels.shape == (10_000,) and not labels.any()  # (copies: one element)


def test_the_fan_rule_is_the_reference_kernels():
    """The compiled grouping and the reference's, on fans of every size around 8."""
    from oracle import reference

    from superfacets._kernels import native

    rng = np.random.default_rng(3)
    for n in (2, 7, 8, 9, 40):
        a = np.zeros(3 * n, dtype=np.int32)
        b = np.ones(3 * n, dtype=np.int32)
        a[1::3], b[1::3] = 1, 2 + rng.permutation(n)  # (other edges: open boundaries)
        a[2::3], b[2::3] = 0, 2 + rng.permutation(n)
        order = np.lexsort((b, a)).astype(np.int32)
        owner = np.empty(0, dtype=np.int32)
        got = native.kernel("adjacency.group_pairs")(order, owner, a, b)
        want = reference("adjacency.group_pairs")(order, owner, a, b)
        for x, y in zip(got, want):
            assert x.dtype == y.dtype and np.array_equal(x, y), n


def test_copies_of_a_face_are_one_element_and_share_its_label(capsys, tmp_path):
    """Duplicate faces (the same vertices, in any order) were elements of their own, each
    copy free to take another label: they are merged into their first copy's element, and
    the command line says how many."""
    import trimesh

    from superfacets.cli import main
    from superfacets.elements.builders import elements_of
    from superfacets.elements.faces import distinct_faces
    from superfacets.inputs.shapes import creature

    body = creature(30)
    assert distinct_faces(body) is None  # (none: nothing merged, nothing computed)
    extra = np.r_[body.faces[:400], body.faces[1000:1100, ::-1], body.faces[:50, [1, 2, 0]]]
    mesh = Mesh(body.vertices, np.r_[body.faces, extra])
    first, index = distinct_faces(mesh)
    assert first.tolist() == list(range(body.n_faces))
    assert np.array_equal(np.sort(mesh.faces[first[index]], axis=1), np.sort(mesh.faces, axis=1))
    src = elements_of(mesh)
    assert src.graph.n_elements == body.n_faces and src.n_rows == mesh.n_faces
    r = segment(mesh, 40)
    m = body.n_faces
    assert np.array_equal(r.labels[:m], segment(body, 40).labels)  # the same run
    assert np.array_equal(r.labels[m:m + 400], r.labels[:400])
    assert np.array_equal(r.labels[m + 400:m + 500], r.labels[1000:1100])
    assert np.array_equal(r.labels[m + 500:], r.labels[:50])
    path = tmp_path / "copies.off"
    trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).export(path)
    assert main(["segment", str(path), "-k", "40", "-o", str(tmp_path / "c.seg")]) == 0
    assert "note: 550 faces are copies of an earlier face" in capsys.readouterr().err
    pts = np.random.default_rng(0).random((2000, 3))
    np.save(tmp_path / "p.npy", np.r_[pts, pts[:30]])
    assert main(["segment", str(tmp_path / "p.npy"), "-k", "20", "-o",
                 str(tmp_path / "p.seg")]) == 0
    assert ("note: 30 points are at the position of an earlier point and share its label"
            in capsys.readouterr().err)


def test_no_stage_before_the_passes_makes_again_what_it_declared(valley, monkeypatch):
    # the one place that forgets (Hooks.before) keeps what the stages up to the passes
    # declare (stage_reads); the passes hold none of the fields; only the stages after
    # them make fields again
    from superfacets import Mesh, segment
    from superfacets.elements import face_graph
    from superfacets.method import pipeline

    monkeypatch.setattr(pipeline, "_RELEASE_MIN", 0)
    log, held = [], {}
    before, iterate = pipeline.Hooks.before, pipeline.iterate_passes

    def spy_before(hooks, stage):
        log.append(stage)
        if len(log) == 1:  # the graph's rebuilds wrapped, to log which stage made them
            g = hooks.graph
            for name, make in list(g.rebuild.items()):
                g.rebuild[name] = (lambda make=make, name=name:
                                   lambda graph: log.append(f"made {name}") or make(graph))()
        before(hooks, stage)

    def spy_passes(graph, *args, **kw):
        held["fields"] = sorted((set(graph.rebuild) | {"terms"}) & set(graph.__dict__))
        return iterate(graph, *args, **kw)

    monkeypatch.setattr(pipeline.Hooks, "before", spy_before)
    monkeypatch.setattr(pipeline, "iterate_passes", spy_passes)
    for kw in ({"coarsen": 4}, {"cleanup": True, "split_merge": True}):
        log.clear()
        mesh = Mesh(valley.vertices, valley.faces)
        segment(mesh, 12, **kw)
        assert held["fields"] == []  # (a triangle mesh's edges too: made again from faces)
        assert "edges" in face_graph(mesh).rebuild
        stages = [s for s in log if not s.startswith("made")]
        assert stages[-2:] == ["clean-up", "cuts"] and "passes" in stages
        assert ("coarsening" in stages) == ("coarsen" in kw)
        made_early = [s for s in log[:log.index("clean-up")] if s.startswith("made")]
        assert made_early == [], log
        assert {s for s in log[log.index("clean-up"):] if s.startswith("made")} <= {
            "made normals", "made pairs", "made dual_edge", "made lengths", "made edges"}
        # the cuts read none of them: the graph holds none after the run (on a large one)
        assert not (set(face_graph(mesh).rebuild) | {"terms"}) & set(face_graph(mesh).__dict__)


def test_point_graph_takes_what_as_cloud_takes_and_refuses_the_rest_in_words():
    """An (N, 3) array is a cloud of its own (the same graph as its PointCloud's); a word
    is a TypeError that names what it takes, not an AttributeError from inside."""
    from superfacets.elements.points import point_graph
    from superfacets.inputs.cloud import PointCloud

    pts = np.random.default_rng(3).random((200, 3))
    from_array = point_graph(pts, 6).graph
    from_cloud = point_graph(PointCloud(pts), 6).graph
    np.testing.assert_array_equal(from_array.indptr, from_cloud.indptr)
    np.testing.assert_array_equal(from_array.indices, from_cloud.indices)
    with pytest.raises(TypeError, match="expected a point cloud"):
        point_graph("scan.ply")
