"""The tiles' layout (superfacets.scale.tiles.layout): grids, balanced tiles, cores and boxes."""

from __future__ import annotations

import numpy as np
import pytest

from superfacets import ParameterError
from superfacets.io.regions import RegionReader
from superfacets.scale.tiles.layout import (
    balanced_tiles,
    tile_box,
    tile_grid,
    tile_of,
    trim_centers,
)
from superfacets.scale.tiles.run import segment_tiled


def test_tile_grid_is_the_most_cubic_split():
    assert tile_grid([0, 0, 0], [4, 2, 1], 8).shape == (4, 2, 1)
    assert tile_grid([0, 0, 0], [1, 1, 1], (2, 3, 1)).shape == (2, 3, 1)
    flat = tile_grid([0, 0, 0], [6, 3, 0], 4)  # no split along a zero extent
    assert flat.shape[2] == 1 and flat.shape[0] * flat.shape[1] == 4
    assert tile_grid([0, 0, 0], [5, 0, 0], 7).shape == (7, 1, 1)  # a prime count on a line


def test_grid_tiles_are_its_cells_numbered_x_fastest():
    """Tile i + nx (j + ny k) is the cell (i, j, k): a position on an inner edge goes to
    the cell above it, one on the outer bounds (or past them) to the last cell."""
    g = tile_grid([0, 0, 0], [3, 2, 2], (3, 2, 2))
    assert g.n_tiles == 12
    pts = np.array([[0.5, 0.5, 0.5], [1.0, 0.5, 0.5], [2.5, 1.5, 1.5], [3.0, 2.0, 2.0],
                    [-1.0, 0.5, 7.0], [0.5, 1.0, 1.0]])
    assert tile_of(pts, g).tolist() == [0, 1, 11, 11, 6, 9]
    lo, hi = tile_box(g, 11, 0.25)
    np.testing.assert_allclose(lo, [1.75, 0.75, 0.75])
    np.testing.assert_allclose(hi, [3.25, 2.25, 2.25])


def test_balanced_tiles_hold_equal_shares_of_an_uneven_input():
    """A dense corner and a sparse rest: the grid's busiest tile holds most of the
    input, balanced tiles each about n / N (the same as the sample's quantiles), and
    they cover the box without overlap."""
    rng = np.random.default_rng(3)
    pts = np.r_[rng.random((45000, 3)) * 0.2, rng.random((5000, 3))]
    lo, hi = pts.min(0), pts.max(0)
    grid = np.bincount(tile_of(pts, tile_grid(lo, hi, 8)), minlength=8)
    assert grid.max() > 0.8 * pts.shape[0]
    for n in (1, 2, 5, 8, 13):
        b = balanced_tiles(pts, lo, hi, n)
        counts = np.bincount(tile_of(pts, b), minlength=n)
        assert b.n_tiles == n and b.shape is None
        assert counts.sum() == pts.shape[0]
        assert counts.max() - counts.min() <= 1
        # an even sample (every 10th position: ~385 a tile at n = 13) gives shares
        # within its sampling noise, the grid's busiest tile ~7x the mean
        counts = np.bincount(tile_of(pts, balanced_tiles(pts[::10], lo, hi, n)), minlength=n)
        assert counts.max() <= 1.15 * pts.shape[0] / n
        # the boxes tile [lo, hi]: volumes add up, each position lies in its own box
        assert np.isclose(np.prod(b.hi - b.lo, axis=1).sum(), np.prod(hi - lo))
        t = tile_of(pts, b)
        assert ((pts >= b.lo[t]) & (pts <= b.hi[t])).all()


def test_balanced_tiles_of_degenerate_samples():
    """Every position in one place, or no sample at all: boxes split in the middle."""
    same = np.ones((100, 3))
    b = balanced_tiles(same, [0, 0, 0], [2, 1, 1], 4)
    assert b.n_tiles == 4 and np.isclose(np.prod(b.hi - b.lo, axis=1).sum(), 2.0)
    e = balanced_tiles(np.zeros((0, 3)), [0, 0, 0], [4, 1, 1], 4)
    np.testing.assert_allclose(np.sort(e.lo[:, 0]), [0, 1, 2, 3])
    assert tile_of(np.array([[np.nan, 0, 0], [0.5, 0.5, 0.5]]), e).tolist()[0] == -1
    with pytest.raises(ParameterError, match="tiles must"):
        balanced_tiles(same, [0, 0, 0], [1, 1, 1], 0)


@pytest.mark.parametrize("bad", [0, -2, 2.5, True, (1, 2), (1, 0, 1), "4"])
def test_tile_grid_refuses_bad_counts(bad, tmp_path, monkeypatch):
    with pytest.raises(ParameterError, match="tiles must"):
        tile_grid([0, 0, 0], [1, 1, 1], bad)
    # a tiled run refuses them before it reads the file
    np.save(tmp_path / "p.npy", np.random.default_rng(0).random((50, 3)))
    monkeypatch.setattr(RegionReader, "survey", lambda self: pytest.fail("file read"))
    with pytest.raises(ParameterError, match="tiles must"):
        segment_tiled(tmp_path / "p.npy", 5, tiles=bad)


@pytest.mark.parametrize("layout", [tile_grid, balanced_tiles])
def test_every_position_has_one_tile_and_boxes_hold_them(layout):
    rng = np.random.default_rng(0)
    pts = rng.random((5000, 3)) * [3, 2, 1]
    args = (pts.min(0), pts.max(0), 6)
    tiles = tile_grid(*args) if layout is tile_grid else balanced_tiles(pts, *args)
    t = tile_of(pts, tiles)
    assert t.min() >= 0 and t.max() < 6 and np.bincount(t).min() > 0
    for k in range(6):
        lo, hi = tile_box(tiles, k)
        inside = ((pts >= lo) & (pts <= hi)).all(1)
        assert inside[t == k].all()
    assert tile_of(np.array([[np.nan, 0, 0]]), tiles)[0] == -1


@pytest.mark.parametrize("n_tiles", [1, 2, 3, 7, 16])
def test_a_tiles_core_holds_exactly_the_positions_of_that_tile(n_tiles):
    """``Tiles.holds(p, t)`` (the splits on the way to ``t`` only) is ``of(p) == t``,
    non-finite positions in no core, on a split in the tile above it."""
    rng = np.random.default_rng(n_tiles)
    pts = rng.normal(size=(6000, 3))
    tiles = balanced_tiles(pts, pts.min(0), pts.max(0), n_tiles)
    pts[::97] = np.nan
    pts[5::101, 1] = np.inf
    pts[7::103, tiles.axis[0] if tiles.axis.size else 0] = tiles.value[0] if \
        tiles.axis.size else 0.0  # (on the first split)
    of = tiles.of(pts)
    for t in range(tiles.n_tiles):
        np.testing.assert_array_equal(tiles.holds(pts, t), of == t)
    grid = tile_grid(np.zeros(3), np.ones(3), (2, 3, 1))
    cells = rng.random((3000, 3))
    for t in range(6):
        np.testing.assert_array_equal(grid.holds(cells, t), grid.of(cells) == t)


def test_trim_keeps_k_and_drops_the_most_crowded():
    pos = np.array([[0, 0, 0], [10, 0, 0], [20, 0, 0], [20.1, 0, 0], [30, 0, 0.]])
    keep = trim_centers(pos, 4)
    assert keep.sum() == 4 and not keep[3] and keep[2]
    assert trim_centers(pos, 9).all()
