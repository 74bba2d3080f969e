"""The k nearest neighbours of the point graph (superfacets.elements.neighbors): exact,
in the order of (distance, index), whatever the order of the points or their ties."""

import numpy as np
import pytest

from superfacets.elements.neighbors import closest, nearest, point_tree
from superfacets.elements.points import distinct_points


def _brute(pts: np.ndarray, k: int, own: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each query itself, then its k nearest other points by (squared distance, index),
    the squared distance ``(dx*dx + dy*dy) + dz*dz``; and their distances."""
    nbr = np.empty((own.size, k + 1), dtype=np.int64)
    dist = np.zeros((own.size, k + 1))
    for r, i in enumerate(own):
        d = pts - pts[i]
        d2 = (d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]) + d[:, 2] * d[:, 2]
        d2[i] = -1.0  # itself first
        order = np.lexsort((np.arange(pts.shape[0]), d2))[:k + 1]
        nbr[r] = order
        dist[r, 1:] = np.sqrt(d2[order[1:]])
    return nbr, dist


def _grid() -> np.ndarray:
    """A quantized scan: a 25 x 18 grid of step 1 on a tilted plane, rounded to 0.5, so
    that nearly every point has several neighbours at each equal distance."""
    xy = np.stack(np.meshgrid(np.arange(25.0), np.arange(18.0)), -1).reshape(-1, 2)
    return np.c_[xy, np.round(0.3 * xy[:, 0] + 0.1 * xy[:, 1])]


@pytest.mark.parametrize("shuffle", [False, True])
def test_neighbours_are_the_nearest_by_distance_then_index_with_ties(shuffle):
    pts = _grid()
    if shuffle:  # any order of the rows: the same answers (the tree only runs slower)
        pts = pts[np.random.default_rng(3).permutation(pts.shape[0])]
    else:
        pts = distinct_points(pts)[0]
    own = np.arange(pts.shape[0])
    for k in (1, 4, 10, 23):
        tree = point_tree(pts, leaf=4)
        nbr, kth, within = nearest(tree, k, limit=1.5)
        want, dist = _brute(pts, k, own)
        np.testing.assert_array_equal(nbr, want)
        np.testing.assert_array_equal(kth, dist[:, k])
        np.testing.assert_array_equal(within, dist[:, 1:] <= 1.5)
    some = np.array([5, 0, 77, 449, 5])  # a subset of queries, in any order, repeated
    nbr, kth, _ = nearest(point_tree(pts), 9, some)
    np.testing.assert_array_equal(nbr, _brute(pts, 9, some)[0])


def test_duplicates_and_equal_keys_split_by_halves():
    # 300 copies of 3 positions: the Z-order keys cannot split them; ties at distance 0
    # go to the lowest index
    rng = np.random.default_rng(0)
    pts = np.repeat(rng.random((3, 3)), 100, axis=0)
    tree = point_tree(pts, leaf=8)
    assert tree.start.size > 2 * 300 // 8 - 1  # split down to leaves of 8 all the same
    nbr, kth, _ = nearest(tree, 12)
    np.testing.assert_array_equal(nbr, _brute(pts, 12, np.arange(300))[0])
    assert not kth.any()


def test_untied_neighbours_and_distances_are_scipys_bit_for_bit():
    from scipy.spatial import cKDTree

    rng = np.random.default_rng(1)
    pts = distinct_points(rng.normal(size=(5000, 3)) * [3.0, 1.0, 0.01])[0]
    nbr, kth, _ = nearest(point_tree(pts), 10)
    dist, idx = cKDTree(pts).query(pts, k=11)
    np.testing.assert_array_equal(nbr, idx)
    np.testing.assert_array_equal(kth, dist[:, 10])


@pytest.mark.parametrize("shuffle", [False, True])
def test_the_closest_point_to_any_position_with_ties_to_the_lower_index(shuffle):
    """Known answer: queries anywhere (on the quantized grid's points, halfway between
    them, far outside), each the nearest point by (squared distance, index) as a brute
    search finds it; the points in any order; refused: a non-finite query, no points."""
    pts = _grid()
    if shuffle:
        pts = pts[np.random.default_rng(4).permutation(pts.shape[0])]
    rng = np.random.default_rng(5)
    queries = np.r_[pts[::7], pts[::11] + [0.5, 0.0, 0.0], pts[::13] + [0.5, 0.5, 0.25],
                    rng.uniform(-5, 30, (200, 3)), [[1e6, -1e6, 3.0]]]
    d = queries[:, None, :] - pts[None, :, :]
    d2 = (d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1]) + d[..., 2] * d[..., 2]
    want = np.array([np.lexsort((np.arange(pts.shape[0]), row))[0] for row in d2])
    assert (np.sort(d2, axis=1)[:, 0] == np.sort(d2, axis=1)[:, 1]).sum() > 50  # ties
    for leaf in (1, 4, 16):
        np.testing.assert_array_equal(closest(point_tree(pts, leaf=leaf), queries), want)
    assert closest(point_tree(pts), np.zeros((0, 3))).shape == (0,)
    with pytest.raises(ValueError, match="finite"):
        closest(point_tree(pts), [[0.0, np.nan, 0.0]])
    with pytest.raises(ValueError, match="no points"):
        closest(point_tree(np.zeros((0, 3))), [[0.0, 0.0, 0.0]])


def test_no_neighbours_asked_and_too_many_asked():
    pts = np.eye(3)
    nbr, kth, within = nearest(point_tree(pts), 0, limit=1.0)
    assert nbr.tolist() == [[0], [1], [2]] and not kth.any() and within.shape == (3, 0)
    with pytest.raises(ValueError, match="need 0 <= k < 3"):
        nearest(point_tree(pts), 3)


@pytest.mark.parametrize("shift", [(0.0, 0.0, 0.0), (0.0, 0.0, -1000.0),
                                   (500_000.0, 5_000_000.0, 0.0)])
def test_the_tree_is_the_same_wherever_the_cloud_sits(shift):
    """The tree splits space in the cloud's own frame: a floor of centimetre noise at
    z = 0 (where the bits of the floats span many binades), or in survey coordinates, gets
    the very tree the same floor gets at z = 10 (the points, exact multiples of 2**-10,
    move exactly), and the same neighbours by position."""
    rng = np.random.default_rng(8)
    n = 5000
    base = np.c_[rng.integers(0, 60 * 1024, (n, 2)), rng.integers(-10, 11, n)] / 1024.0
    base = distinct_points(base)[0]

    def tree_and_neighbours(p):
        tree = point_tree(p)
        nbr, kth, _ = nearest(tree, 6)
        return tree, p[nbr], kth  # (neighbours by position: the rows' order may differ)

    ref_tree, ref_pos, ref_kth = tree_and_neighbours(base + [0.0, 0.0, 10.0])
    moved = distinct_points(base + np.array(shift))[0]
    tree, pos, kth = tree_and_neighbours(moved)
    for name in ("start", "end", "left"):
        assert np.array_equal(getattr(tree, name), getattr(ref_tree, name)), name
    back = moved - np.array(shift)
    order = np.lexsort(back.T[::-1])
    ref_order = np.lexsort((base).T[::-1])
    assert np.array_equal(back[order], base[ref_order])
    assert np.array_equal(kth[order], ref_kth[ref_order])
    assert np.array_equal(pos[order] - np.array(shift), ref_pos[ref_order] - [0.0, 0.0, 10.0])


def test_a_cloud_wider_than_the_largest_float_is_one_cell():
    """A side past the largest float (1e308 on both sides of 0) has no frame: every point in
    one cell, the tree split by halves, the answers by (distance, index) still."""
    pts = np.array([[1e308, 0, 0], [-1e308, 0, 0], [0, 0, 0.0], [1.0, 0, 0]])
    with np.errstate(over="ignore"):
        want, _ = _brute(pts, 2, np.arange(4))
    nbr, _, _ = nearest(point_tree(pts), 2)
    assert nbr.tolist() == want.tolist()


@pytest.mark.parametrize("shift", [(0.0, 0.0, -10.0), (0.0, 0.0, -1010.0),
                                   (500_000.0, 5_000_000.0, -10.0)])
def test_a_cloud_moved_exactly_keeps_its_order_and_its_labels(shift):
    """The elements are numbered in the cloud's own frame: a floor at z = 10 moved to
    z = 0, to z = -1,000 and into survey coordinates (exactly: its coordinates are
    multiples of 2**-10) lists its points in the same order and gets the same labels."""
    from superfacets import segment

    rng = np.random.default_rng(9)
    n = 4000
    floor = np.c_[rng.integers(0, 20 * 1024, (n, 2)), rng.integers(-10, 11, n)] / 1024.0
    floor[:, 2] += 10.0
    moved = floor + np.array(shift)
    a, inv_a = distinct_points(floor)
    b, inv_b = distinct_points(moved)
    assert np.array_equal(b - np.array(shift), a) and np.array_equal(inv_a, inv_b)
    assert np.array_equal(segment(floor, 40).labels, segment(moved, 40).labels)
