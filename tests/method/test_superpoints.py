"""Superpoints: the method on mesh vertices and on point clouds, readers, CLI, baseline."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from conftest import SHARED, grid_mesh, need
from oracle import reference
from scipy.sparse.csgraph import connected_components

from superfacets import Mesh, segment
from superfacets.api.segmentation import superpoints
from superfacets.cli import main
from superfacets.elements.builders import elements_of
from superfacets.elements.points import point_graph
from superfacets.elements.vertices import vertex_graph
from superfacets.errors import MeshFormatError, ParameterError
from superfacets.evaluation.baselines.graph_segmentation import graph_segmentation
from superfacets.evaluation.datasets.sampling import sample_points, vertex_ground_truth
from superfacets.evaluation.metrics import evaluate
from superfacets.inputs.cloud import InvalidCloudError, PointCloud, up_weighted
from superfacets.io import read_cloud, read_input, read_labels


def _implementation(which: str):
    """The compiled kernel (``"kernel"``) or its numba reference (``"reference"``)."""
    from superfacets._kernels import native

    return native.kernel if which == "kernel" else reference


def connected(graph, labels) -> bool:
    """Every label is one connected piece of the element graph."""
    i, j = graph.pairs[:, 0], graph.pairs[:, 1]
    same = labels[i] == labels[j]
    from scipy.sparse import coo_matrix

    n = graph.n_elements
    adj = coo_matrix((np.ones(same.sum()), (i[same], j[same])), shape=(n, n))
    n_pieces, _ = connected_components(adj, directed=False)
    return n_pieces == np.unique(labels).size


def sphere_points(n=3000, seed=0):
    x = np.random.default_rng(seed).normal(size=(n, 3))
    return x / np.linalg.norm(x, axis=1, keepdims=True)


# ------------------------------------------------------------------ vertex graph
def test_vertex_graph_of_a_box_and_an_open_square():
    box = trimesh.creation.box()
    g = elements_of(Mesh(box.vertices, box.faces), "vertices").graph
    assert (g.n_elements, g.n_edges) == (8, 18)
    assert g.area == pytest.approx(6.0)
    assert g.boundary_elements.size == 0
    assert (np.einsum("ij,ij->i", g.normals, g.positions) > 0.5).all()  # outwards
    assert (g.terms.concave == 0).all()  # a box is convex everywhere
    sq = Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    g = elements_of(sq, "vertices").graph
    assert g.boundary_lengths.sum() == pytest.approx(4.0)  # the perimeter, half per end
    assert g.sizes.tolist() == pytest.approx([1 / 3, 1 / 6, 1 / 3, 1 / 6])
    # the diagonal's dual edge: from its midpoint to both triangle centroids
    diag = np.flatnonzero((g.pairs == [0, 2]).all(axis=1))[0]
    assert g.lengths[diag] == pytest.approx(2 * np.sqrt(2) / 6)


def test_vertex_mode_labels_every_vertex_and_marks_unused_ones(sphere):
    v = np.vstack([sphere.vertices, [[5.0, 5.0, 5.0]]])  # one vertex used by no face
    mesh = Mesh(v, sphere.faces)
    r = segment(mesh, 40, elements="vertices")
    assert r.labels.shape == (mesh.n_vertices,)
    assert r.labels[-1] == -1 and (r.labels[:-1] >= 0).all()
    assert np.unique(r.labels[:-1]).tolist() == list(range(r.n_segments))
    g = vertex_graph(mesh).graph
    assert connected(g, r.labels[:-1])
    assert r.params["elements"] == "vertices"
    assert np.array_equal(segment(mesh, 40, elements="vertices").labels, r.labels)
    assert np.array_equal(segment(mesh, 40, elements="vertices", n_threads=1).labels, r.labels)


def test_vertex_mode_follows_a_concave_crease(valley):
    labels = segment(valley, 2, elements="vertices", alpha=1000).labels
    x = valley.vertices[:, 0]
    left, right = labels[x < -0.05], labels[x > 0.05]
    assert np.unique(left).size == 1 and np.unique(right).size == 1
    assert left[0] != right[0]
    assert elements_of(valley, "vertices").graph.terms.concave.sum() > 0


# ------------------------------------------------------------------- point graph
def test_point_normals_are_estimated_and_turned_outwards_on_a_closed_surface():
    pts = sphere_points()
    g = elements_of(PointCloud(pts), "points").graph
    outward = np.einsum("ij,ij->i", g.normals, g.positions)
    assert (outward > 0.9).mean() > 0.99
    assert (~g.terms.concave).mean() > 0.95  # a sphere bends convexly everywhere
    # sizes add up to about the area of the unit sphere
    assert g.area == pytest.approx(4 * np.pi, rel=0.25)


@pytest.mark.parametrize("source", ["kernel", "reference"])
def test_orientation_follows_the_minimum_spanning_tree_with_ties_broken_by_ends(source):
    """The sign propagation follows the minimum spanning forest of ``1 - |n_u . n_v|``
    with ties broken by the edges' ends (lower, then higher): the same signs and
    components as Kruskal's algorithm over every edge sorted, walked from the lowest
    element of each tree, on normals quantized so that many keys tie, in two
    components (the compiled kernel and numba's)."""
    from scipy.sparse import coo_array


    propagate_signs = _implementation(source)("orient.propagate_signs")
    rng = np.random.default_rng(3)
    n = 400
    normals = np.round(rng.normal(size=(n, 3)), 0)
    normals[(normals == 0).all(axis=1)] = [0.0, 0.0, 1.0]
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    half = n // 2  # two pieces: no edge between the halves
    i = np.r_[rng.integers(0, half, 1200), rng.integers(half, n, 1200)]
    j = np.r_[rng.integers(0, half, 1200), rng.integers(half, n, 1200)]
    keep = i != j
    a = coo_array((np.ones(keep.sum()), (i[keep], j[keep])), shape=(n, n)).tocsr()
    a = (a + a.T).tocsr()
    a.sort_indices()
    indptr, indices = a.indptr.astype(np.int64), a.indices.astype(np.int32)

    sign, comp = np.empty(n, dtype=np.int8), np.empty(n, dtype=np.int64)
    n_comp = propagate_signs(indptr, indices, normals, sign, comp)

    rows = np.repeat(np.arange(n), np.diff(indptr))
    lo, hi = rows[rows < indices], indices[rows < indices].astype(np.int64)
    d = normals[lo, 0] * normals[hi, 0] + normals[lo, 1] * normals[hi, 1] \
        + normals[lo, 2] * normals[hi, 2]
    key = 1.0 - np.abs(d)
    assert np.unique(key).shape[0] < key.shape[0] // 10  # many ties
    up = list(range(n))

    def find(x):
        while up[x] != x:
            x = up[x]
        return x

    tree = [[] for _ in range(n)]
    for e in np.lexsort((hi, lo, key)):  # Kruskal's algorithm
        x, y = find(lo[e]), find(hi[e])
        if x != y:
            up[x] = y
            tree[lo[e]].append(hi[e])
            tree[hi[e]].append(lo[e])
    ref_sign, ref_comp = np.zeros(n, dtype=np.int8), np.full(n, -1)
    c = 0
    for s in range(n):
        if ref_comp[s] >= 0:
            continue
        ref_sign[s], ref_comp[s] = 1, c
        todo = [s]
        while todo:
            u = todo.pop()
            for v in tree[u]:
                if ref_comp[v] < 0:
                    ref_comp[v] = c
                    dot = normals[u, 0] * normals[v, 0] + normals[u, 1] * normals[v, 1] \
                        + normals[u, 2] * normals[v, 2]
                    ref_sign[v] = ref_sign[u] if dot >= 0 else -ref_sign[u]
                    todo.append(v)
        c += 1
    assert n_comp == c >= 2
    assert np.array_equal(comp, ref_comp) and np.array_equal(sign, ref_sign)


def test_a_piece_cut_from_a_closed_surface_orients_like_a_reference():
    """The inner half of a torus is concave seen from its own mean: turned "outwards" from
    it, every normal points into the solid. Oriented like a sample of the whole torus
    (``orient_like``), every one points out, as in the whole cloud (what tiles rely on)."""
    from scipy.spatial import cKDTree

    big, small = 1.0, 0.4
    torus = trimesh.creation.torus(major_radius=big, minor_radius=small, major_sections=64,
                                   minor_sections=32)
    pts, _ = trimesh.sample.sample_surface_even(torus, 20000, seed=1)
    rho = np.hypot(pts[:, 0], pts[:, 1])
    axis = np.c_[pts[:, :2] / rho[:, None] * big, np.zeros(len(pts))]
    out = (pts - axis) / np.linalg.norm(pts - axis, axis=1, keepdims=True)  # true normals

    def outward(cloud, which):
        g = point_graph(cloud).graph
        _, j = cKDTree(pts[which]).query(g.positions)
        return (np.einsum("ij,ij->i", g.normals, out[which][j]) > 0).mean()

    everything = np.ones(len(pts), dtype=bool)
    whole = point_graph(PointCloud(pts)).graph
    assert outward(PointCloud(pts), everything) == 1.0
    inner = rho < big
    assert outward(PointCloud(pts[inner]), inner) == 0.0  # its own mean turns it inwards
    reference = (np.array(whole.positions[::7]), np.array(whole.normals[::7]))
    assert outward(PointCloud(pts[inner], orient_like=reference), inner) == 1.0
    # a viewpoint wins over the reference: every normal faces it
    g = point_graph(PointCloud(pts[inner], viewpoint=[0.0, 0.0, -5.0],
                               orient_like=reference)).graph
    assert (np.einsum("ij,ij->i", g.normals, [0.0, 0.0, -5.0] - g.positions) >= 0).all()
    with pytest.raises(InvalidCloudError, match="orient_like"):
        PointCloud(pts, orient_like=(pts, pts[:10]))


def test_each_normal_turns_like_the_reference_normal_nearest_its_point():
    """Known answer: a plane whose reference normals point up on its left half and down on
    its right turns each point's normal like the reference nearest it (not one side per
    connected piece), and a box cut from it (a tile) turns every point it holds alike;
    on a sphere's cap the whole sphere's inward normals turn every normal inwards,
    against the cap's own outward rule."""
    from scipy.spatial import cKDTree

    rng = np.random.default_rng(3)
    pts = np.c_[rng.random((4000, 2)), 0.002 * rng.standard_normal(4000)]
    ref_pos = np.c_[rng.random((700, 2)), np.zeros(700)]
    ref_nrm = np.where(ref_pos[:, :1] < 0.5, 1.0, -1.0) * [0.0, 0.0, 1.0]
    _, near = cKDTree(ref_pos).query(pts)
    g = point_graph(PointCloud(pts, orient_like=(ref_pos, ref_nrm))).graph
    order = cKDTree(g.positions).query(pts)[1]  # (the graph's points in its own order)
    up = np.asarray(g.normals)[order, 2] > 0
    np.testing.assert_array_equal(up, ref_nrm[near, 2] > 0)
    assert 0.3 < up.mean() < 0.7
    box = (pts[:, 0] > 0.3) & (pts[:, 0] < 0.8)
    cut = point_graph(PointCloud(pts[box], orient_like=(ref_pos, ref_nrm))).graph
    cut_up = np.asarray(cut.normals)[cKDTree(cut.positions).query(pts[box])[1], 2] > 0
    np.testing.assert_array_equal(cut_up, up[box])

    d = rng.normal(size=(6000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    cap = d[d[:, 2] > 0.2]
    g = point_graph(PointCloud(cap, orient_like=(d[::5], -d[::5]))).graph
    assert (np.einsum("ij,ij->i", g.normals, g.positions) < 0).all()
    own = point_graph(PointCloud(cap)).graph  # (outwards from its mean, by default)
    assert (np.einsum("ij,ij->i", own.normals, own.positions) > 0).all()


def _terrain_with_a_block(seed=4):
    """A shallow valley ``z = 0.1 r^2`` around (2, 2) on [0, 4]^2 with a 1 x 1 x 0.5
    block standing in its middle (top and four walls), points about 0.04 apart: an
    airborne scan's scene in miniature. Returns the points and each one's part
    (0 ground, 1 top, 2 wall)."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 4, (10000, 2))
    xy = xy[~((np.abs(xy[:, 0] - 2) < 0.5) & (np.abs(xy[:, 1] - 2) < 0.5))]
    ground = np.c_[xy, 0.1 * ((xy - 2) ** 2).sum(axis=1)]
    top = np.c_[rng.uniform(1.5, 2.5, (625, 2)), np.full(625, 0.5)]
    walls = []
    for axis in (0, 1):
        for side in (1.5, 2.5):
            w = np.c_[rng.uniform(1.5, 2.5, 320), rng.uniform(0.05, 0.5, 320)]
            p = np.empty((320, 3))
            p[:, axis], p[:, 1 - axis], p[:, 2] = side, w[:, 0], w[:, 1]
            walls.append(p)
    pts = np.vstack([ground, top, *walls])
    return pts, np.repeat([0, 1, 2], [len(ground), len(top), 4 * 320])


def test_an_open_surface_seen_from_above_orients_up_and_its_foot_is_concave():
    """Turned "outwards" from its own mean, a valley's normals point down (into the
    ground), and the foot of a block standing in it reads as convex. With ``up`` (what
    LAS files carry) every piece agrees with the sky: the ground's normals point up and
    the foot is concave."""
    pts, part = _terrain_with_a_block()

    def graph(cloud):
        g, index = elements_of(cloud, "points")[:2]
        kind = np.empty(g.n_elements, np.int64)
        kind[index] = part
        return g, kind

    g, kind = graph(PointCloud(pts))
    assert (g.normals[kind == 0, 2] < 0).mean() > 0.99  # the defect `up` removes
    a, b = g.pairs[:, 0], g.pairs[:, 1]
    foot = ((kind[a] == 0) & (kind[b] == 2)) | ((kind[a] == 2) & (kind[b] == 0))
    assert foot.sum() > 20 and g.terms.concave[foot].mean() < 0.2
    g, kind = graph(PointCloud(pts, up=[0, 0, 2.0]))
    assert (g.normals[kind == 0, 2] > 0).mean() > 0.99
    assert g.terms.concave[foot].mean() > 0.8
    # a viewpoint wins over up
    g, kind = graph(PointCloud(pts, up=[0, 0, 1], viewpoint=[2.0, 2.0, -10.0]))
    assert (g.normals[kind == 0, 2] < 0).all()
    assert np.allclose(PointCloud(pts, up=[0, 0, 2.0]).up, [0, 0, 1])
    for bad in ([0, 0, 0], [0, np.nan, 1], [1, 2]):
        with pytest.raises(InvalidCloudError, match="up must be"):
            PointCloud(pts, up=bad)


def test_a_frame_must_be_a_box():
    pts = np.random.default_rng(0).random((50, 3))
    assert PointCloud(pts, frame=[[0, 0, 0], [1, 1, 1]]).frame.shape == (2, 3)
    for bad in ([0, 0, 0], [[0, 0, 0], [1, np.nan, 1]], [[1, 0, 0], [0, 1, 1]]):
        with pytest.raises(InvalidCloudError, match="frame must be a box"):
            PointCloud(pts, frame=bad)


def test_a_las_scan_is_oriented_up(tmp_path):
    laspy = pytest.importorskip("laspy")
    from superfacets.io.regions import RegionReader
    from superfacets.scale.tiles.phases import orientation_reference

    pts, part = _terrain_with_a_block()
    header = laspy.LasHeader(point_format=1, version="1.2")
    header.scales = [0.0001] * 3
    las = laspy.LasData(header)
    las.x, las.y, las.z = pts[:, 0], pts[:, 1], pts[:, 2]
    las.write(tmp_path / "terrain.las")
    cloud = read_cloud(tmp_path / "terrain.las")
    np.testing.assert_array_equal(cloud.up, [0, 0, 1])
    g, index = elements_of(cloud, "points")[:2]
    assert (g.normals[index[part == 0], 2] > 0).mean() > 0.99
    # tiled runs: the streamed reader and a spilled copy keep it, and the survey's
    # orientation sample (which every tile follows) is turned up with it
    assert RegionReader.open(tmp_path / "terrain.las").up == (0.0, 0.0, 1.0)
    assert RegionReader.spill(cloud, tmp_path / "spill").up == (0.0, 0.0, 1.0)
    low = pts[part == 0]
    for up, sign in (((0.0, 0.0, 1.0), 1), (None, -1)):
        positions, normals = orientation_reference(low, 10, up=up)
        assert (sign * normals[:, 2] > 0).mean() > 0.99


def test_point_normals_face_the_viewpoint_and_a_valley_crease_is_concave(valley):
    pts, _ = sample_points(valley, 6000, seed=1)
    cloud = PointCloud(pts, viewpoint=[0.0, 0.0, 10.0])
    g = elements_of(cloud, "points").graph
    assert (g.normals[:, 2] > 0).all()
    p = g.positions
    across = np.sign(p[g.pairs[:, 0], 0]) != np.sign(p[g.pairs[:, 1], 0])
    assert g.terms.concave[across].mean() > 0.9
    labels = superpoints(pts, 2, viewpoint=[0.0, 0.0, 10.0], alpha=1000)
    x = pts[:, 0]
    assert np.unique(labels[x < -0.1]).size == 1 and np.unique(labels[x > 0.1]).size == 1
    assert labels[x < -0.1][0] != labels[x > 0.1][0]


def test_superpoints_are_dense_connected_and_deterministic():
    pts = sphere_points(4000)
    labels = superpoints(pts, 30)
    assert labels.shape == (4000,) and labels.dtype == np.int64
    assert np.unique(labels).tolist() == list(range(30))
    g, index = elements_of(PointCloud(pts), "points")[:2]
    per_element = np.empty(g.n_elements, np.int64)
    per_element[index] = labels
    assert connected(g, per_element)
    assert np.array_equal(superpoints(pts, 30), labels)
    assert np.array_equal(superpoints(pts, 30, n_threads=1), labels)
    given = superpoints(pts, 30, normals=pts)  # exact outward normals
    assert np.unique(given).size == 30


def test_organized_cloud_keeps_its_layout_and_marks_invalid_points():
    xs, ys = np.meshgrid(np.linspace(0, 1, 40), np.linspace(0, 1, 30))
    grid = np.stack([xs, ys, 0.1 * np.sin(3 * xs)], axis=-1)
    grid[5, 7] = np.nan
    grid[10:12, :] = np.nan
    labels = superpoints(grid, 12)
    assert labels.shape == (30, 40)
    invalid = ~np.isfinite(grid).all(axis=-1)
    assert (labels[invalid] == -1).all() and (labels[~invalid] >= 0).all()
    assert np.unique(labels[~invalid]).size == labels.max() + 1


def test_duplicate_points_share_a_label():
    pts = sphere_points(2000)
    dup = np.vstack([pts, pts[:50]])
    labels = superpoints(dup, 20)
    assert np.array_equal(labels[2000:], labels[:50])


@pytest.mark.parametrize("points, message", [
    (np.zeros((0, 3)), "no valid point"),
    (np.ones((10, 3)), "all 10 points coincide"),
    (np.ones((1, 3)), "one point alone: no surface"),  # (not "all 1 points coincide")
    (np.c_[np.arange(10.0), 2 * np.arange(10.0), np.zeros(10)], "one line"),
    (np.r_[np.random.default_rng(0).random((9, 3)), [[np.nan, 0, 0]]], "point 9 has a "
                                                                         "non-finite"),
    (np.r_[np.random.default_rng(0).random((9, 3)), [[np.inf, 0, 0]]], "point 9"),
    (np.zeros((5, 2)), r"shape \(N, 3\)"),
    # a scanner's stray point far enough away that the rest look like one line beside it
    (np.r_[np.random.default_rng(0).random((40, 3)), [[0, 3e12, 0]]],
     r"1 of 41 points lies over 10000 times farther .*row 40 at 3e\+12.*remove such stray"),
    (np.r_[[[0, 3e12, 0]], np.arange(20.0)[:, None] * [1, 1, 1], [[0, -3e12, 0]]],
     "all 22 points lie on one line"),  # the rest is a line too: the plain message
])
def test_bad_clouds_are_refused_clearly(points, message):
    with pytest.raises(InvalidCloudError, match=message):
        superpoints(points, 1)


def test_the_line_test_of_a_large_cloud_asks_a_sample_first(monkeypatch):
    """Known answer: a large cloud's line test settles by a strided sample only where
    the sample proves a second direction; it answers as the pass over every point on
    lines thickened around the test's bound (1e-12 of the scatter), with one point off
    the line that the sample misses, and on a plane (settled by the sample)."""
    from superfacets.inputs import cloud

    rng = np.random.default_rng(3)
    n = 1 << 16
    t = rng.random(n)
    line = np.c_[t, 2 * t, 3 * t]
    cases = {}
    for amp in (0.0, 1e-9, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3):  # (1e-6: a line, by 0.85e-12)
        cases[f"line {amp:g}"] = line + amp * rng.standard_normal((n, 3))
    alone = line.copy()
    alone[7] += [0.0, 0.0, 1e-3]  # (row 7 is not in the sample of every 16th row)
    cases["one point off"] = alone
    cases["plane"] = np.c_[t, rng.random(n), np.zeros(n)]
    calls = []
    full = cloud.np.linalg.svd

    def svd(a, compute_uv=True):
        calls.append(1)
        return full(a, compute_uv=compute_uv)

    monkeypatch.setattr(cloud.np.linalg, "svd", svd)
    for name, p in cases.items():
        extent = float(np.ptp(p, axis=0).max())
        calls.clear()
        fast = cloud._on_a_line(p, extent)
        sampled_only = len(calls) == 1 and not fast
        with monkeypatch.context() as m:
            m.setattr(cloud, "_SAMPLE", n)  # (4 n > n: no sample)
            slow = cloud._on_a_line(p, extent)
        assert fast == slow, name
        assert sampled_only == (name in ("line 0.0001", "line 0.001", "plane")), name
    assert cloud._on_a_line(cases["line 1e-06"], 3.0)
    assert not cloud._on_a_line(cases["line 1e-05"], 3.0)
    assert not cloud._on_a_line(cases["one point off"], 3.0)


def test_more_superpoints_than_points_and_bad_options_are_refused():
    pts = sphere_points(50)
    with pytest.raises(ParameterError, match="larger than the number of points"):
        superpoints(pts, 51)
    with pytest.raises(ParameterError, match="n_neighbors"):
        superpoints(pts, 5, n_neighbors=0)
    with pytest.raises(ParameterError, match="neighbor_radius"):
        superpoints(pts, 5, neighbor_radius=-1.0)
    with pytest.raises(ParameterError, match="needs a point cloud"):
        segment(trimesh.creation.box(), 2, elements="points")
    with pytest.raises(ParameterError, match="needs a mesh"):
        segment(pts, 2, elements="faces")
    with pytest.raises(TypeError, match="real numbers"):
        PointCloud(np.array([["a", "b", "c"]]))


# ------------------------------------------------------------------------ readers
def write_ply_points(path, pts, normals=None):
    from plyfile import PlyData, PlyElement

    fields = [("x", "f8"), ("y", "f8"), ("z", "f8")]
    if normals is not None:
        fields += [("nx", "f8"), ("ny", "f8"), ("nz", "f8")]
    rec = np.empty(len(pts), dtype=fields)
    rec["x"], rec["y"], rec["z"] = pts.T
    if normals is not None:
        rec["nx"], rec["ny"], rec["nz"] = normals.T
    PlyData([PlyElement.describe(rec, "vertex")]).write(str(path))


def test_readers_of_every_cloud_format(tmp_path):
    pts = sphere_points(300)
    write_ply_points(tmp_path / "a.ply", pts, pts)
    c = read_input(tmp_path / "a.ply")
    assert isinstance(c, PointCloud) and np.allclose(c.points, pts)
    assert np.allclose(c.normals, pts)
    (tmp_path / "b.xyz").write_text("\n".join(" ".join(map(repr, p)) + " 0.5"
                                             for p in pts.tolist()))
    assert np.allclose(read_cloud(tmp_path / "b.xyz").points, pts)
    (tmp_path / "c.txt").write_text("# x y z nx ny nz\n" + "\n".join(
        ",".join(map(repr, p + p)) for p in pts.tolist()))
    c = read_cloud(tmp_path / "c.txt")
    assert np.allclose(c.points, pts) and np.allclose(c.normals, pts)
    (tmp_path / "d.pts").write_text(f"{len(pts)}\n" + "\n".join(
        " ".join(map(repr, p)) + " 10 1 2 3" for p in pts.tolist()))
    assert read_cloud(tmp_path / "d.pts").n_total == 300
    np.save(tmp_path / "e.npy", np.c_[pts, pts])
    assert read_cloud(tmp_path / "e.npy").normals is not None
    np.save(tmp_path / "f.npy", pts.reshape(15, 20, 3))
    assert read_cloud(tmp_path / "f.npy").shape == (15, 20)


@pytest.mark.parametrize("encoding", ["ascii", "binary", "binary_compressed"])
def test_pcd_files_with_invalid_points(tmp_path, encoding):
    pypcd4 = pytest.importorskip("pypcd4")
    pts = sphere_points(400).astype(np.float32)
    pts[17] = np.nan
    pc = pypcd4.PointCloud.from_xyz_points(pts)
    pc.save(tmp_path / "s.pcd", encoding=pypcd4.Encoding(encoding))
    c = read_cloud(tmp_path / "s.pcd")
    assert c.n_total == 400 and c.n_points == 399 and not c.valid[17]
    labels = segment(c, 10).labels
    assert labels[17] == -1 and (np.delete(labels, 17) >= 0).all()


def test_las_files(tmp_path):
    laspy = pytest.importorskip("laspy")
    pts = sphere_points(500) * 10
    las = laspy.create(point_format=0, file_version="1.2")
    las.header.scales = [0.001] * 3
    las.x, las.y, las.z = pts.T
    las.write(tmp_path / "s.las")
    c = read_cloud(tmp_path / "s.las")
    assert np.allclose(c.points, pts, atol=1e-3)


@pytest.mark.parametrize("name, text, message", [
    ("nan.xyz", "0 0 0\n1 0 0\nnan 1 0\n0 1 1\n", "point 2 has a non-finite"),
    ("cols.xyz", "# a b c\n0 0 0\n1 0 0\n0 1 0\n", "unknown columns"),
    ("ragged.xyz", "0 0 0\n1 0\n", "line 2 of the points has 2 columns"),
    ("words.txt", "0 0 0\n1 zero 0\n", "point line 2 is not numbers"),
    ("two.xyz", "0 0\n1 1\n", "need 3 columns"),
    ("count.pts", "10\n0 0 0\n", "declares 10 points"),
    ("empty.xyz", "", "empty file"),
])
def test_malformed_cloud_files(tmp_path, name, text, message):
    (tmp_path / name).write_text(text)
    with pytest.raises((MeshFormatError, InvalidCloudError), match=message):
        read_cloud(tmp_path / name)


# ------------------------------------------------------------------------------ CLI
def test_cli_segments_a_ply_of_points_one_label_per_point(tmp_path, capsys):
    pts = sphere_points(2000)
    write_ply_points(tmp_path / "c.ply", pts)
    out = tmp_path / "c.seg"
    assert main(["segment", str(tmp_path / "c.ply"), "-k", "25", "-o", str(out),
                 "--colored-mesh", str(tmp_path / "col.ply")]) == 0
    labels = read_labels(out)
    assert labels.shape == (2000,) and labels.max() + 1 == 25
    assert "2,000 points, 25 superpoints" in capsys.readouterr().out
    colored = read_cloud(tmp_path / "col.ply")
    assert np.allclose(colored.points, pts)
    assert np.array_equal(read_labels(tmp_path / "col.ply" if False else out), labels)


def test_cli_vertex_mode_writes_seg_and_segindices_json(tmp_path, sphere):
    from superfacets import write_mesh

    write_mesh(tmp_path / "s.off", sphere)
    assert main(["segment", str(tmp_path / "s.off"), "--elements", "vertices", "-k", "30",
                 "-o", str(tmp_path / "s.json"), "-q"]) == 0
    doc = json.loads((tmp_path / "s.json").read_text())
    assert len(doc["segIndices"]) == sphere.n_vertices and doc["sceneId"] == "s"
    assert doc["params"]["elements"] == "vertices" and doc["params"]["n_segments"] == 30
    assert main(["segment", str(tmp_path / "s.off"), "--elements", "vertices", "-k", "30",
                 "-o", str(tmp_path / "s.seg"), "-q"]) == 0
    assert np.array_equal(read_labels(tmp_path / "s.seg"), doc["segIndices"])
    assert np.array_equal(read_labels(tmp_path / "s.json"), doc["segIndices"])


def test_cli_bad_cloud_input_writes_nothing(tmp_path, capsys):
    (tmp_path / "bad.xyz").write_text("0 0 0\n1 0 0\n0 1 0\nnan 0 1\n")
    out = tmp_path / "o.seg"
    assert main(["segment", str(tmp_path / "bad.xyz"), "-k", "2", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "point 3 has a non-finite" in err and "Traceback" not in err
    assert not out.exists()
    pts = sphere_points(30)
    np.save(tmp_path / "few.npy", pts)
    assert main(["segment", str(tmp_path / "few.npy"), "-k", "31", "-o", str(out)]) == 2
    assert "larger than the number of points" in capsys.readouterr().err
    assert main(["segment", str(tmp_path / "few.npy"), "--elements", "faces", "-o",
                 str(out)]) == 2
    assert "needs a mesh" in capsys.readouterr().err and not out.exists()


def test_cli_orients_a_scan_by_viewpoint_or_side(tmp_path, capsys):
    """``--seen-from z`` on an open terrain gives the labels of ``PointCloud(up=z)``, and
    ``--viewpoint`` those of ``PointCloud(viewpoint=...)``; bad values and ``--tiles`` are
    refused in one line, writing nothing."""
    pts, _ = _terrain_with_a_block()
    np.save(tmp_path / "t.npy", pts)
    out = tmp_path / "t.seg"
    for flags, cloud in ((["--seen-from", "z"], PointCloud(pts, up=[0, 0, 1])),
                         (["--viewpoint", "2,2,30"], PointCloud(pts, viewpoint=[2, 2, 30])),
                         ([], PointCloud(pts))):
        assert main(["segment", str(tmp_path / "t.npy"), "-k", "12", "-o", str(out), "-q",
                     *flags]) == 0
        np.testing.assert_array_equal(read_labels(out), segment(cloud, 12).labels)
    # tiled: the same orientation reaches every tile (a streamed .npy; 2 tiles)
    for flags, cloud in ((["--seen-from", "z"], PointCloud(pts, up=[0, 0, 1])),
                         (["--viewpoint", "2,2,30"], PointCloud(pts, viewpoint=[2, 2, 30]))):
        assert main(["segment", str(tmp_path / "t.npy"), "-k", "12", "-o", str(out), "-q",
                     "--tiles", "2", *flags]) == 0
        from superfacets.scale.tiles.run import segment_tiled

        np.testing.assert_array_equal(read_labels(out), segment_tiled(cloud, 12, tiles=2).labels)
        assert (read_labels(out) != segment_tiled(PointCloud(pts), 12, tiles=2).labels).any()
    from superfacets import write_mesh

    write_mesh(tmp_path / "m.off", Mesh(*_grid_xy()))
    for flags, msg in ((["--viewpoint", "1,2"], "expected x,y,z"),
                       (["--seen-from", "up"], "invalid choice")):
        out.unlink(missing_ok=True)
        code = None
        try:
            code = main(["segment", str(tmp_path / "t.npy"), "-k", "12", "-o", str(out),
                         *flags])
        except SystemExit as exc:  # argparse
            code = exc.code
        assert code == 2 and not out.exists()
        err = capsys.readouterr().err
        assert msg in err and "Traceback" not in err
    for tiles in ([], ["--tiles", "2"]):
        assert main(["segment", str(tmp_path / "m.off"), "-k", "4", "-o", str(out),
                     "--seen-from", "z", *tiles]) == 2
        assert "orient point clouds" in capsys.readouterr().err and not out.exists()


def _grid_xy():
    """A flat 10 x 10 grid mesh: (vertices, triangles)."""
    x, y = np.meshgrid(np.arange(11.0), np.arange(11.0))
    v = np.c_[x.ravel(), y.ravel(), np.zeros(121)]
    i = np.arange(121).reshape(11, 11)
    a, b, c, d = i[:-1, :-1].ravel(), i[:-1, 1:].ravel(), i[1:, 1:].ravel(), i[1:, :-1].ravel()
    return v, np.r_[np.c_[a, b, c], np.c_[a, c, d]]


def test_superpoints_viewpoint_keeps_the_clouds_colours():
    pts = sphere_points(3000)
    colors = (pts[:, :1] > 0) * np.array([[1.0, 0.0, 0.0]]) + 0.0
    cloud = PointCloud(pts, colors=colors)
    with_vp = superpoints(cloud, 20, viewpoint=[0, 0, 0], beta=200)
    direct = segment(PointCloud(pts, colors=colors, viewpoint=[0, 0, 0]), 20, beta=200).labels
    np.testing.assert_array_equal(with_vp, direct)


# ----------------------------------------------------------------- the baseline
def test_graph_segmentation_splits_at_a_crease_and_keeps_flat_parts_whole(valley):
    labels = graph_segmentation(valley)
    x = valley.vertices[:, 0]
    assert np.unique(labels[x < -0.05]).size == 1 and np.unique(labels[x > 0.05]).size == 1
    assert labels[x < -0.05][0] != labels[x > 0.05][0]
    assert np.unique(graph_segmentation(grid_mesh(20, 20))).size == 1
    bumpy = trimesh.creation.icosphere(4)
    bumpy.vertices *= 1 + 0.05 * np.random.default_rng(0).random((len(bumpy.vertices), 1))
    counted = graph_segmentation(bumpy, n_segments=60)
    assert abs(np.unique(counted).size - 60) <= 6
    cloud = graph_segmentation(sphere_points(3000), n_segments=40)
    assert cloud.shape == (3000,) and abs(np.unique(cloud).size - 40) <= 4
    with pytest.raises(ParameterError, match="k_thresh"):
        graph_segmentation(valley, k_thresh=0)


# ------------------------------------------------------------ benchmark helpers
def test_sampling_and_vertex_ground_truth():
    mesh = grid_mesh(10, 10)
    pts, faces = sample_points(mesh, 5000, seed=3)
    assert np.array_equal(sample_points(mesh, 5000, seed=3)[0], pts)
    # each point lies in its face's triangle (the bounding box of its corners)
    tri = mesh.vertices[mesh.faces[faces]]
    assert ((pts >= tri.min(axis=1) - 1e-12) & (pts <= tri.max(axis=1) + 1e-12)).all()
    gt = (mesh.centroids[:, 0] > 0).astype(np.int64)
    vgt = vertex_ground_truth(mesh, gt)
    x = mesh.vertices[:, 0]
    assert (vgt[x < -0.01] == 0).all() and (vgt[x > 0.01] == 1).all()


def test_equal_weight_metrics_count_elements():
    mesh = grid_mesh(8, 8)
    g = elements_of(mesh, "vertices").graph
    gt = (g.positions[:, 0] > 0).astype(np.int64)
    perfect = evaluate(g, gt, [gt], equal_weight=True)
    assert perfect["undersegmentation_error"] == 0 and perfect["boundary_recall"] == 1
    one = evaluate(g, np.zeros(g.n_elements, np.int64), [gt], equal_weight=True)
    # one segment over both halves leaks each half's complement: (n1 + n0) / n = 1
    assert one["undersegmentation_error"] == pytest.approx(1.0)
    assert one["boundary_recall"] == 0
    quarter = (g.positions[:, 0] > 0.5).astype(np.int64)  # splits one half in two
    q = evaluate(g, quarter, [gt], equal_weight=True)
    # the superpoint x <= 0.5 holds all of half 0 and part of half 1: it leaks into both
    left = quarter == 0
    expect = ((left & (gt == 1)).sum() + (left & (gt == 0)).sum()) / g.n_elements
    assert q["undersegmentation_error"] == pytest.approx(expect)


# --------------------------------------------------------------------- real scans
@pytest.mark.parametrize("name", ["table_scene_mug_stereo_textured",
                                  "milk_cartoon_all_small_clorox"])
def test_real_rgbd_scans(name):
    pytest.importorskip("pypcd4")
    path = need(SHARED / "data" / "clouds" / f"{name}.pcd")
    cloud = read_cloud(path)
    assert cloud.shape == (480, 640) and 0 < cloud.n_points < cloud.n_total
    r = segment(cloud, 150)
    assert r.labels.shape == (307200,)
    assert (r.labels[~cloud.valid] == -1).all() and (r.labels[cloud.valid] >= 0).all()
    # each superpoint in one piece of the graph the run read (a scene's: its neighbours
    # along the surfaces, step_weight 4; its heights along the camera's up weighed as its
    # surfaces say: the table's level top, 2.34-2.42)
    assert r.params["step_weight"] == 4.0 and 2.2 < r.params["up_weight"] < 2.6
    g, index = r.elements.graph, r.elements.index
    want = point_graph(up_weighted(cloud, r.params["up_weight"]), step=4.0).graph
    np.testing.assert_array_equal(g.indices, want.indices)
    np.testing.assert_array_equal(g.positions, want.positions)
    per_element = np.empty(g.n_elements, np.int64)
    per_element[index[cloud.valid]] = r.labels[cloud.valid]
    assert connected(g, per_element)
    assert 140 <= r.n_segments <= 200


def test_a_run_asked_for_k_superpoints_returns_exactly_k():
    """Regions no window reached (the paper's windows, which the exact search by default
    does not have) seeded superpoints of their own (420 for 200 here): the count is now
    exactly k, the extra ones merged cheapest first, each still connected; the paper's
    method keeps its count; separate pieces beyond k: the fewest, warned."""
    import warnings

    from superfacets.method.connectivity import label_components

    rng = np.random.default_rng(0)
    x = rng.normal(size=(20000, 3))
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    r = segment(x, 200, window=1.0, assignment="bounded")
    assert r.n_segments == 200 and r.n_orphan_seeds > 0
    assert np.array_equal(np.unique(r.labels), np.arange(200))
    pieces = label_components(r.elements.graph, r.element_labels)
    assert pieces.max() + 1 == 200  # every superpoint connected
    assert segment(x, 200, window=1.0, paper=True).n_segments > 200
    two = np.r_[rng.random((500, 3)), rng.random((500, 3)) + [5, 0, 0]]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert segment(two, 1).n_segments == 2
    assert any("2 separate pieces" in str(w.message) for w in caught)


def test_complex_coordinates_are_refused():
    x = np.random.default_rng(0).random((300, 3)).astype(complex)
    with pytest.raises(TypeError, match="must be real numbers, got dtype complex128"):
        segment(x, 5)


def _creature_cloud(n: int = 6000):
    import trimesh

    from superfacets.inputs.shapes import creature

    m = creature(30)
    return trimesh.sample.sample_surface(trimesh.Trimesh(m.vertices, m.faces, process=False),
                                         n, seed=1)[0]


def test_a_cycle_on_a_cloud_is_settled_and_the_passes_converge(monkeypatch):
    """Known case: 6,000 points of the creature at k = 120 fall into a cycle of 4 center
    lists (50 passes, stopped on the cycle, when it is jumped over as the paper's passes
    run). Settled (the default on points): the cycle's pass of lowest energy, the centers
    that moved in it held, the passes converge in a few more, with as many superpoints."""
    from dataclasses import replace

    from superfacets.api.result import describe_stop
    from superfacets.elements import kinds

    pts = _creature_cloud()
    settled = segment(pts, 120)
    monkeypatch.setitem(kinds.KINDS, "points", replace(kinds.KINDS["points"],
                                                       settle_cycles=False))
    jumped = segment(pts, 120)
    assert jumped.stop_reason == "cycle" and jumped.n_iter == 50
    assert settled.converged and settled.stop_reason in ("converged", "tolerance")
    assert 0 < settled.timings["settled"] < 120 and settled.n_iter < 20
    assert settled.n_segments == jumped.n_segments == 120
    assert "oscillating centers frozen" in describe_stop(settled)


def test_settling_holds_the_centers_that_moved_at_the_cycles_best_pass():
    """Known answer of the settling step: of a cycle of three center lists, the one of
    lowest energy is restored and its centers that some list of the cycle lacked held."""
    from superfacets.method.passes import _settle

    states = [np.array([1, 5, 9]), np.array([1, 6, 9]), np.array([2, 6, 9])]
    energies = [3.0, 2.0, 4.0]
    centers = np.zeros(12, dtype=np.int64)
    held = np.zeros(12, dtype=bool)
    assert _settle(centers, states, energies, 0, held) == 3
    assert centers[:3].tolist() == [1, 6, 9] and np.flatnonzero(held).tolist() == [1, 6]


def test_a_center_sent_back_to_one_of_its_recent_places_is_held():
    """Known answer: superfacet 0's center goes 5 -> 6 -> 5 (held at 6 when sent back),
    superfacet 1's moves on; a compaction drops a dead superfacet's past."""
    from superfacets.method.passes import _Recent

    held = np.zeros(20, dtype=bool)
    recent = _Recent()
    used, moved = np.array([5, 10]), np.array([6, 11])
    recent.hold(used, moved, held)
    assert moved.tolist() == [6, 11] and not held.any()
    used, moved = np.array([6, 11]), np.array([5, 12])
    recent.hold(used, moved, held)
    assert np.flatnonzero(held).tolist() == [6]
    recent.compact(np.array([False, True]))
    assert recent.rows.shape[0] == 1 and 10 in recent.rows[0] and 11 in recent.rows[0]


@pytest.mark.parametrize("n", [1, 7, 8, 130, 1001, 65_536, 65_537, 300_001])
def test_the_passes_energy_is_numpys_sum_bit_for_bit(n, monkeypatch):
    """The energy sums the products in blocks, in numpy's own pairwise order: the same
    bits as ``(sizes * dist).sum()`` (the passes' stopping rules compare energies), and
    the elements no center reached are left out."""
    from superfacets.method import passes

    rng = np.random.default_rng(n)
    sizes = rng.random(n) * 10.0 ** rng.integers(-4, 4, n)
    dist = rng.random(n) ** 3
    for block in (128, 1000, passes.ENERGY_BLOCK):  # (numpy's own blocks: 128)
        monkeypatch.setattr(passes, "ENERGY_BLOCK", block)
        assert passes._energy(sizes, dist) == float((sizes * dist).sum())
    dist[::3] = np.inf
    keep = np.isfinite(dist)
    assert passes._energy(sizes, dist) == float((sizes[keep] * dist[keep]).sum())
