import numpy as np
import pytest
from conftest import grid_mesh

from superfacets import enforce_connectivity
from superfacets.elements import face_graph
from superfacets.elements.labels import relabel_dense
from superfacets.method.connectivity import label_components


def cell_labels(mesh, fn):
    c = mesh.centroids
    return np.array([fn(x, y) for x, y in c[:, :2]], dtype=np.int64)


def test_stray_piece_joins_neighbour_with_longest_boundary():
    mesh = grid_mesh(12, 12)  # [-1, 1]^2
    # left half label 0, right half label 1; an island of label 1 inside the left half,
    # touching only label 0 -> it must become 0
    labels = cell_labels(mesh, lambda x,
                         y: 1 if x > 0 or (-0.6 < x < -0.3 and -0.2 < y < 0.2) else 0)
    assert label_components(face_graph(mesh), labels).max() + 1 == 3
    out = enforce_connectivity(mesh, labels)
    expected = cell_labels(mesh, lambda x, y: 1 if x > 0 else 0)
    np.testing.assert_array_equal(out, expected)


def test_longest_shared_boundary_wins():
    mesh = grid_mesh(12, 12)
    # three labels: 0 left, 1 right-top, 2 right-bottom; a stray of label 0 sitting in
    # the right part, mostly inside label 2 -> joins 2
    def f(x, y):
        if 0.3 < x < 0.8 and -0.5 < y < 0.05:
            return 0
        if x < 0:
            return 0
        return 1 if y > 0 else 2
    labels = cell_labels(mesh, f)
    out = enforce_connectivity(mesh, labels)
    c = mesh.centroids
    stray = (c[:, 0] > 0.3) & (c[:, 0] < 0.8) & (c[:, 1] > -0.5) & (c[:, 1] < 0.05)
    bottom = (c[:, 0] > 0) & (c[:, 1] < 0) & ~stray
    assert len(np.unique(out[stray])) == 1
    assert out[stray][0] == out[bottom][0]
    assert label_components(face_graph(mesh), out).max() + 1 == out.max() + 1 == 3


def test_center_piece_keeps_label_even_if_smaller():
    mesh = grid_mesh(10, 10)
    labels = cell_labels(mesh, lambda x, y: 0 if x < -0.5 or x > 0.4 else 1)
    # label 0 has two pieces: left (small) and right (larger); center in the left one
    left_face = int(np.flatnonzero(mesh.centroids[:, 0] < -0.5)[0])
    mid_face = int(np.flatnonzero(labels == 1)[0])
    out = enforce_connectivity(mesh, labels, centers=np.array([left_face, mid_face]))
    assert out[left_face] != out[mid_face]
    right = mesh.centroids[:, 0] > 0.4
    assert (out[right] == out[mid_face]).all()


def test_already_connected_is_just_relabelled():
    mesh = grid_mesh(6, 6)
    labels = cell_labels(mesh, lambda x, y: 7 if x < 0 else 3)
    out = enforce_connectivity(mesh, labels)
    np.testing.assert_array_equal(out, relabel_dense(labels))
    assert set(out.tolist()) == {0, 1}


def test_pieces_are_numbered_as_scipy_numbers_components(sphere):
    # the kernel's pieces against scipy's connected components of the same-label subgraph
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import connected_components

    g = face_graph(sphere)
    n = g.n_elements
    i, j = g.pairs[:, 0], g.pairs[:, 1]
    for labels in (np.random.default_rng(1).integers(0, 4, n), np.zeros(n, dtype=np.int64),
                   (sphere.centroids[:, 0] > 0).astype(np.int64)):
        same = labels[i] == labels[j]
        adj = coo_array((np.ones(int(same.sum()), dtype=np.int8), (i[same], j[same])),
                        shape=(n, n))
        ref = connected_components(adj.tocsr(), directed=False)[1]
        np.testing.assert_array_equal(label_components(g, labels), ref)


def test_summed_csr_equals_scipy_coo_to_csr():
    from scipy.sparse import coo_array

    from superfacets.method.connectivity import _summed_csr

    rng = np.random.default_rng(5)
    for n in (1, 7, 300):
        rows = rng.integers(0, n, 900)
        cols = rng.integers(0, n, 900)  # many duplicates
        vals = rng.random(900)
        indptr, indices, data = _summed_csr(rows, cols, vals, n)
        ref = coo_array((vals, (rows, cols)), shape=(n, n)).tocsr()
        ref.sort_indices()
        assert np.array_equal(indptr, ref.indptr) and np.array_equal(indices, ref.indices)
        np.testing.assert_allclose(data, ref.data, rtol=1e-12)


def test_min_elements_merges_tiny_superfacets_into_their_neighbours():
    mesh = grid_mesh(12, 12)  # 288 faces, [-1, 1]^2
    halves = cell_labels(mesh, lambda x, y: 1 if x > 0 else 0)
    labels = halves.copy()
    # two connected superfacets of one and of two faces inside the left half
    g = face_graph(mesh)
    ring = lambda f: g.indices[g.indptr[f]:g.indptr[f + 1]]  # noqa: E731
    inner = np.flatnonzero((np.abs(mesh.centroids[:, :2]) < 0.8).all(axis=1) & (halves == 0))
    one = int(inner[0])
    nbr = int(ring(one)[0])
    labels[one] = 2
    a = int(inner[-1])
    pair = np.array([a, int(ring(a)[0])])
    assert halves[pair[1]] == 0 and not set(pair) & {one, *ring(one)}
    labels[pair] = 3
    centers = np.array([0, int(np.flatnonzero(halves == 1)[0]), one, int(pair[0])])
    # min_elements = 1 (the default): only connectivity, all four kept
    np.testing.assert_array_equal(enforce_connectivity(mesh, labels, centers), labels)
    # 2: the single face joins the half around it, the pair stays
    two = enforce_connectivity(mesh, labels, centers, min_elements=2)
    assert np.unique(two).size == 3 and two[one] == two[nbr] and two[pair[0]] == two[pair[1]]
    # 3: both merge away, the halves are back
    np.testing.assert_array_equal(enforce_connectivity(mesh, labels, centers, min_elements=3),
                                  halves)


def test_min_elements_keeps_a_tiny_superfacet_with_no_neighbour():
    # two separate pieces: a 288-face grid and one triangle far away
    mesh = grid_mesh(12, 12)
    v = np.vstack([mesh.vertices, [[5, 5, 0], [6, 5, 0], [5, 6, 0]]])
    f = np.vstack([mesh.faces, [[len(mesh.vertices) + i for i in range(3)]]])
    labels = np.r_[np.zeros(mesh.n_faces, np.int64), 1]
    out = enforce_connectivity((v, f), labels, min_elements=5)
    np.testing.assert_array_equal(out, labels)
    with pytest.raises(ValueError, match="min_elements"):
        enforce_connectivity((v, f), labels, min_elements=0)


def sparse_strip_cloud():
    """A dense unit square of points and, beside it, a strip of 60 points spaced
    about 0.35 apart: the strip's superpoints hold one or two points each (the
    far range of a LiDAR sweep, in small)."""
    rng = np.random.default_rng(0)
    dense = np.c_[rng.random((5000, 2)), np.zeros(5000)]
    strip = np.c_[5 + 20 * rng.random((60, 1)), rng.random((60, 1)), np.zeros(60)]
    return np.r_[dense, strip]


def test_segment_min_elements_merges_small_superpoints_at_the_end():
    from superfacets import segment
    from superfacets.method.passes import final_centers

    xyz = sparse_strip_cloud()
    plain = segment(xyz, 200, density=0, merge_from=1)  # equal areas, no merges
    small = np.bincount(plain.labels) < 3
    assert small.sum() > 40  # the premise: the strip's superpoints are tiny
    auto = segment(xyz, 200)
    assert auto.params["density"] == 0.5 and (np.bincount(auto.labels) < 3).sum() < small.sum()
    with pytest.warns(RuntimeWarning, match="superpoints for n_segments=200: min_elements=3 "
                      "merged those of fewer elements"):
        merged = segment(xyz, 200, min_elements=3, density=0, merge_from=1)
    sizes = np.bincount(merged.labels)
    assert sizes.min() >= 3
    assert np.unique(merged.labels).tolist() == list(range(merged.n_segments))
    assert merged.n_segments < plain.n_segments == 200
    # exactly the default run's labels with the merge applied after it
    g = plain.elements.graph
    centers = plain.elements.index[plain.centers]
    expected = enforce_connectivity(g, plain.element_labels, centers, min_elements=3)
    np.testing.assert_array_equal(merged.element_labels, expected)
    np.testing.assert_array_equal(
        merged.centers, plain.elements.first_rows(
            final_centers(expected, centers, g.sizes, g.positions)))
    assert merged.params["min_elements"] == 3 and plain.params["min_elements"] == 1
    # a superpoint of 3 points or more keeps its points together (others join it)
    big = ~small[plain.labels]
    pairs = np.unique(np.c_[plain.labels[big], merged.labels[big]], axis=0)
    assert np.unique(pairs[:, 0]).size == pairs.shape[0] == np.unique(pairs[:, 1]).size


@pytest.mark.parametrize("options, message", [
    (dict(min_elements=0), "min_elements must be an integer >= 1"),
    (dict(min_elements=3, enforce_connectivity=False), "enforce_connectivity=True"),
    (dict(min_elements=3, paper=True), "does not go with min_elements"),
])
def test_segment_min_elements_bad_settings_are_refused(options, message):
    from superfacets import segment
    from superfacets.errors import ParameterError

    with pytest.raises(ParameterError, match=message):
        segment(sparse_strip_cloud(), 20, **options)


def test_cli_min_elements(tmp_path, capsys):
    from superfacets.cli import main
    from superfacets.io import read_labels

    np.save(tmp_path / "strip.npy", sparse_strip_cloud())
    out = tmp_path / "strip.seg"
    assert main(["segment", str(tmp_path / "strip.npy"), "-k", "200", "--density", "0",
                 "-o", str(out)]) == 0
    hint = capsys.readouterr().out  # equal areas: names the tiny superpoints and the options
    assert "200 superpoints" in hint and ("of 1 or 2 points (--min-elements 3 merges them; "
                                          "--density 0.5 sizes superpoints") in hint
    assert main(["segment", str(tmp_path / "strip.npy"), "-k", "200", "-o", str(out)]) == 0
    hint = capsys.readouterr().out  # the automatic density is on: only --min-elements
    assert "(--min-elements 3 merges them)" in hint
    assert main(["segment", str(tmp_path / "strip.npy"), "-k", "200", "--min-elements", "3",
                 "--merge-from", "1", "-o", str(out)]) == 0  # (no merges to the count)
    labels = read_labels(out)
    assert labels.shape == (5060,) and np.bincount(labels).min() >= 3
    assert labels.max() + 1 < 200
    assert "--min-elements" not in capsys.readouterr().out
    assert main(["segment", str(tmp_path / "strip.npy"), "-k", "20", "--min-elements", "3",
                 "--tiles", "2", "-o", str(tmp_path / "t.seg")]) == 2
    assert "not available in a tiled run" in capsys.readouterr().err
    assert not (tmp_path / "t.seg").exists()
