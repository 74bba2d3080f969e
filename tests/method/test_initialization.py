import numpy as np
import pytest
from conftest import grid_mesh, slab_and_beads

from superfacets import Mesh, ParameterError, PointCloud
from superfacets.elements import face_graph
from superfacets.elements.points import point_graph
from superfacets.method.connectivity import label_components
from superfacets.method.initialization import (
    farthest_point_centers,
    first_center,
    flood_labels,
    grid_labels,
)
from superfacets.method.weights import paper_weights


def strip(n: int) -> Mesh:
    """n separate small triangles along the x axis, centroids at x = 0..n-1."""
    v, f = [], []
    for i in range(n):
        v += [[i - 0.1, 0, 0], [i + 0.1, 0, 0], [i, 0.2, 0]]
        f.append([3 * i, 3 * i + 1, 3 * i + 2])
    return Mesh(np.array(v, float), np.array(f))


def test_first_center_is_nearest_to_mesh_centroid():
    m = strip(5)
    assert first_center(m) == 2


def test_farthest_point_known_order():
    m = strip(9)  # first: middle (4); then an end (0, lowest index on ties); then 8; then 2 ...
    c = farthest_point_centers(m, 4)
    assert c.tolist() == [4, 0, 8, 2]
    assert len(set(farthest_point_centers(m, 9).tolist())) == 9


def test_farthest_point_matches_brute_force(sphere):
    k = 25
    c = farthest_point_centers(sphere, k)
    x = sphere.centroids
    chosen = [first_center(sphere)]
    for _ in range(k - 1):
        d = np.min(((x[:, None, :] - x[chosen][None]) ** 2).sum(-1), axis=1)
        d[chosen] = -1
        chosen.append(int(np.argmax(d)))
    assert c.tolist() == chosen


@pytest.mark.parametrize("source", ["grid", "bunny", "noisy"])
def test_blocked_farthest_point_equals_the_plain_loop(source, monkeypatch):
    # the grid has many exactly tied distances; the cell-skipping version must break
    # them the same way (lowest face index) and skip only cells it cannot change
    from conftest import MESHES, need
    from oracle.farthest import farthest_point, farthest_point_blocked, spatial_blocks

    from superfacets import read_mesh

    if source == "grid":
        mesh = grid_mesh(120, 90)
    elif source == "bunny":
        mesh = read_mesh(need(MESHES / "bunny.tri.xz"))
    else:
        rng = np.random.default_rng(3)
        base = grid_mesh(100, 80)
        mesh = Mesh(base.vertices + rng.normal(0, 1e-3, base.vertices.shape), base.faces)
    c = np.ascontiguousarray(mesh.centroids)
    for k in (1, 7, 150, 1000):
        plain = np.empty(k, np.int64)
        farthest_point(c, k, first_center(mesh), plain)
        for g in (1, 5, 40):
            blocked = np.empty(k, np.int64)
            farthest_point_blocked(c, k, first_center(mesh), blocked, *spatial_blocks(c, g))
            assert blocked.tolist() == plain.tolist()
    from superfacets.method import initialization

    monkeypatch.setattr(initialization, "_BLOCKED_MIN_WORK", 0)  # the public function, blocked path
    np.testing.assert_array_equal(farthest_point_centers(mesh, 1000), plain)


def test_content_sensitive_farthest_points_equal_the_plain_loop(monkeypatch):
    """Known answer: with a scale per element (a content-sensitive run), the blocked
    sampling picks the plain loop's centers (a block bounded by its largest scale skipped
    blocks whose elements would have got nearer: 828 of 1,500 centers differed)."""
    from superfacets._kernels import native
    from superfacets.method import initialization

    rng = np.random.default_rng(8)
    x, y = np.meshgrid(np.arange(120.0), np.arange(100.0))
    pts = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)] + rng.normal(0, 0.05, (x.size, 3))
    graph = point_graph(PointCloud(pts), 8).graph
    scale = rng.random(graph.n_elements) * 4 + 0.1
    graph = graph.replaced(scale2=scale)
    plain = np.empty(600, np.int64)
    native.kernel("farthest.farthest_point")(np.ascontiguousarray(graph.positions), 600,
                                              first_center(graph), plain, scale)
    monkeypatch.setattr(initialization, "_BLOCKED_MIN_WORK", 0)  # the blocked path
    np.testing.assert_array_equal(farthest_point_centers(graph, 600), plain)


@pytest.mark.parametrize("k, match", [(0, ">= 1"), (10**6, "larger than the number of faces"),
                                      (2.5, "integer"), (True, "integer")])
def test_farthest_point_bad_k(sphere, k, match):
    with pytest.raises(ParameterError, match=match):
        farthest_point_centers(sphere, k)


def test_grid_labels_known_cells():
    m = grid_mesh(8, 8, size=1.0)  # [-1, 1]^2, cells of 2r = 0.5 -> 4 x 4 cells
    labels = grid_labels(m, radius=0.25)
    assert labels.max() + 1 == 16
    cell = np.floor((m.centroids[:, :2] + 1) / 0.5).astype(int)
    for s in range(16):
        assert len(np.unique(cell[labels == s], axis=0)) == 1


def test_flood_labels_cover_mesh_with_connected_regions_within_window(sphere):
    w = paper_weights(sphere, alpha=200)[face_graph(sphere).dual_edge]
    r = 0.2
    labels = flood_labels(sphere, w, r, window=2.0)
    assert labels.min() == 0 and (labels >= 0).all()
    k = labels.max() + 1
    assert 10 <= k <= 150  # ideal packing: 4 pi / (pi (2 r)^2) = 25 regions
    # each region is connected and within 2r of its seed: diameter <= 4r
    assert label_components(face_graph(sphere), labels).max() + 1 == k
    for s in range(k):
        pts = sphere.centroids[labels == s]
        span = np.sqrt(((pts[:, None] - pts[None]) ** 2).sum(-1)).max()
        assert span <= 4 * r + 1e-9


def test_every_piece_gets_a_center_within_the_count(sphere):
    from superfacets.method.initialization import piece_seeds

    # connected: the paper's centers exactly
    np.testing.assert_array_equal(farthest_point_centers(sphere, 40, every_piece=True),
                                  farthest_point_centers(sphere, 40))
    m, n, nb = slab_and_beads()
    seeds = piece_seeds(m)
    assert seeds[0] == first_center(m) and seeds[0] < n <= seeds[1] < n + nb <= seeds[2]
    # the paper's farthest points miss both beads (near the slab's middle) up to 10
    # centers; with every_piece: the paper's first k - 2, then a seed in each bead
    for k in (4, 10):
        paper = farthest_point_centers(m, k)
        assert (paper >= n).sum() == 0
        c = farthest_point_centers(m, k, every_piece=True)
        assert c.tolist() == paper[:k - 2].tolist() + seeds[1:].tolist()
    # at 40 the farthest points reach one bead: the first 39 and one seed, in the other
    paper = farthest_point_centers(m, 40)
    hit = paper[paper >= n]
    assert len(hit) == 1
    c = farthest_point_centers(m, 40, every_piece=True)
    assert c[:39].tolist() == paper[:39].tolist() and hit[0] in c[:39]
    assert c[39] == seeds[1 if hit[0] >= n + nb else 2]
    # more pieces than centers: one each
    assert farthest_point_centers(m, 2, every_piece=True).tolist() == seeds.tolist()


def test_a_shorter_farthest_run_on_the_same_graph_is_the_longer_ones_prefix(monkeypatch):
    """The farthest points a graph was sampled for are kept with it, and a run for fewer
    reads their prefix (a tiled run's tile samples its core's share, then starts from
    it): the same centers as a fresh graph's run, and a content-sensitive graph (another
    scale) is sampled again."""
    from superfacets._kernels import native
    from superfacets.method import initialization

    pts = np.random.default_rng(5).random((20000, 3)) * [1, 1, 0.05]
    graph = point_graph(PointCloud(pts), 8).graph
    longer = farthest_point_centers(graph, 900)
    calls = []
    real = native.kernel
    monkeypatch.setattr(native, "kernel", lambda name: calls.append(name) or real(name))
    shorter = farthest_point_centers(graph, 300)
    assert calls == []  # read from the longer run
    fresh = farthest_point_centers(point_graph(PointCloud(pts.copy()), 8).graph, 300)
    np.testing.assert_array_equal(shorter, fresh)
    np.testing.assert_array_equal(shorter, longer[:300])
    shorter[0] = -1  # (a copy: the kept run is not changed through it)
    np.testing.assert_array_equal(farthest_point_centers(graph, 300), fresh)
    scaled = graph.replaced(scale2=np.linspace(0.5, 2.0, graph.n_elements))
    calls.clear()
    monkeypatch.setattr(initialization, "_BLOCKED_MIN_WORK", 0)
    farthest_point_centers(scaled, 300)
    assert any(c.startswith("farthest.") for c in calls)  # sampled again


def test_the_pieces_farthest_points_seed_are_found_once_per_graph(monkeypatch):
    """Known answer: two separate sheets get a center each, and a second run on the same
    graph reads the pieces and their seeds found by the first (no components kernel)."""
    from superfacets._kernels import native

    rng = np.random.default_rng(2)
    sheet = rng.random((3000, 3)) * [1, 1, 0.01]
    graph = point_graph(PointCloud(np.r_[sheet, sheet + [0, 0, 5]]), 8).graph
    first = farthest_point_centers(graph, 2, every_piece=True)
    assert sorted((graph.positions[first, 2] > 2).tolist()) == [False, True]
    calls = []
    real = native.kernel
    monkeypatch.setattr(native, "kernel", lambda name: calls.append(name) or real(name))
    np.testing.assert_array_equal(farthest_point_centers(graph, 2, every_piece=True), first)
    assert not any(c.startswith("connectivity.") for c in calls)


def test_each_pieces_seed_is_its_element_nearest_its_mean_ties_to_the_lowest():
    """The seed of each piece is its element of least squared distance to the piece's
    mean, the lowest index among equals: what sorting every element by piece, distance and
    index gives (the rule before), on many pieces with many equal distances."""
    from superfacets.method.initialization import _nearest_per_piece

    rng = np.random.default_rng(3)
    n, n_pieces = 20_000, 700
    piece = rng.integers(0, n_pieces, n)
    piece[:n_pieces] = np.arange(n_pieces)  # (every piece holds an element)
    d2 = rng.integers(0, 6, n).astype(np.float64)  # (ties everywhere)
    order = np.lexsort((np.arange(n), d2, piece))
    want = order[np.searchsorted(piece[order], np.arange(n_pieces))]
    np.testing.assert_array_equal(_nearest_per_piece(piece, d2, n_pieces), want)
    assert (d2[want] == 0).sum() > 500  # (most pieces choose among several at 0)
