"""The tiles one large input is cut into: axis-aligned boxes, a regular grid or balanced.

A tiled run (:mod:`superfacets.scale.tiles.phases`, :mod:`superfacets.scale.tiles.run`) gives
every element to the *core* of one tile, the box holding its position, and
reads each tile with a halo around that box. The tiles are the leaves of a
binary tree of axis-aligned splits (the cells of a k-d tree) covering the
input's bounding box:

- :func:`balanced_tiles` (``tiles=N``, the default): each box is split
  across its longest side at the quantile of the elements' positions that
  gives its two halves their share of the ``N`` tiles (PDAL's "chipper" and
  the k-d tree's median split do the same). Every tile then holds about
  ``n / N`` elements whatever the density: an uneven scan, or a shape whose
  bounding box is mostly empty, makes no tile several times the others,
  and a task's memory follows ``n / N``. The quantiles come from a sample of
  the positions that one pass over the file collects
  (:meth:`superfacets.io.regions.RegionReader.survey`).
- :func:`tile_grid` (``tiles=(nx, ny, nz)``): the regular grid of equal
  boxes, as splits at its edges; the tile ``t`` is the cell ``(i, j, k)``
  with ``t = i + nx (j + ny k)``.

A position on a split belongs to the box above it; positions outside the
bounding box go to the nearest box along each split (so every finite
position has one tile); a non-finite one has none (-1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...checks import check_int
from ...errors import ParameterError
from ...inputs.bounds import finite_rows, rows_in_box

__all__ = ["Tiles", "tile_grid", "balanced_tiles", "tile_of", "tile_box", "check_tiles",
           "trim_centers"]


@dataclass(frozen=True)
class Tiles:
    """Axis-aligned tiles covering a box: the leaves of a tree of splits.

    Attributes
    ----------
    axis : (s,) int64 ndarray
        Axis (0, 1, 2) of each split node.
    value : (s,) float64 ndarray
        Position of each split: below it to ``left``, at or above it to ``right``.
    left, right : (s,) int64 ndarray
        Children of each split: a node index ``>= 0``, or ``-1 - t`` for tile ``t``.
    lo, hi : (T, 3) float64 ndarray
        The core box of each tile.
    shape : tuple of 3 int or None
        Tiles along x, y and z for a regular grid (:func:`tile_grid`); None
        for balanced tiles.
    """

    axis: np.ndarray
    value: np.ndarray
    left: np.ndarray
    right: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    shape: tuple | None = None

    @property
    def n_tiles(self) -> int:
        """Number of tiles ``T``."""
        return int(self.lo.shape[0])

    def of(self, positions: np.ndarray) -> np.ndarray:
        """The tile of each position, ``(n,)`` int64; -1 for a non-finite one."""
        p = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        out = np.full(p.shape[0], -1, dtype=np.int64)
        rows = np.flatnonzero(finite_rows(p))
        if self.axis.size == 0:  # one tile
            out[rows] = 0
            return out
        node = np.zeros(rows.size, dtype=np.int64)
        while rows.size:
            up = p[rows, self.axis[node]] >= self.value[node]
            node = np.where(up, self.right[node], self.left[node])
            leaf = node < 0
            out[rows[leaf]] = -1 - node[leaf]
            rows, node = rows[~leaf], node[~leaf]
        return out

    def holds(self, positions: np.ndarray, t: int) -> np.ndarray:
        """Whether each position lies in tile ``t``'s core, ``(n,)`` bool: ``self.of(
        positions) == t``, tested on the splits from the root to ``t`` only (a column
        compared per split, no walk of every position down the tree)."""
        p = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        inside = finite_rows(p)
        for node, above in self._path(t):
            column = p[:, self.axis[node]]
            inside &= (column >= self.value[node]) if above else (column < self.value[node])
        return inside

    def _path(self, t: int) -> list:
        """The splits from the root to tile ``t``: (node, whether ``t`` lies above it)."""
        parent = {}
        for node in range(self.axis.size):
            for child, above in ((self.left[node], False), (self.right[node], True)):
                parent[int(child)] = (node, above)
        path, at = [], -1 - int(t)
        while at in parent:
            node, above = parent[at]
            path.append((node, above))
            at = node
        return path[::-1]

    def box(self, t: int, margin: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """The core box ``(lo, hi)`` of tile ``t``, grown by ``margin`` on every side."""
        return self.lo[t] - margin, self.hi[t] + margin

    def min_side(self) -> float:
        """The shortest positive side of any tile (0 if the tiles are all flat points)."""
        side = self.hi - self.lo
        side = side[side > 0]
        return float(side.min()) if side.size else 0.0

    def describe(self) -> str:
        """``'2x2x2 grid'`` or ``'balanced'``, for messages."""
        return "x".join(map(str, self.shape)) + " grid" if self.shape else "balanced"


class _Builder:
    """Nodes and leaves of a :class:`Tiles`, appended as the splits are made."""

    def __init__(self):
        self.axis, self.value, self.left, self.right = [], [], [], []
        self.boxes: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def split(self, axis: int, value: float) -> int:
        self.axis.append(axis)
        self.value.append(value)
        self.left.append(0)
        self.right.append(0)
        return len(self.axis) - 1

    def leaf(self, t: int, lo, hi) -> int:
        self.boxes[t] = (np.array(lo, dtype=np.float64), np.array(hi, dtype=np.float64))
        return -1 - t

    def done(self, shape=None) -> Tiles:
        n = len(self.boxes)
        lo = np.array([self.boxes[t][0] for t in range(n)]).reshape(n, 3)
        hi = np.array([self.boxes[t][1] for t in range(n)]).reshape(n, 3)
        return Tiles(np.array(self.axis, dtype=np.int64), np.array(self.value, dtype=np.float64),
                     np.array(self.left, dtype=np.int64), np.array(self.right, dtype=np.int64),
                     lo, hi, shape)


def tile_grid(lo, hi, tiles) -> Tiles:
    """A regular grid of equal tiles over the box ``[lo, hi]``.

    Parameters
    ----------
    lo, hi : (3,) float ndarray
        Bounds of the input's element positions.
    tiles : int or sequence of 3 int
        Number of tiles (split into the most cubic grid of that many) or the
        tiles along x, y and z.

    Returns
    -------
    Tiles
        ``shape`` the tiles along each axis; tile ``i + nx (j + ny k)`` is the
        cell ``(i, j, k)``.

    Raises
    ------
    ParameterError
        If ``tiles`` is not a positive integer or three of them.

    Examples
    --------
    >>> tile_grid([0, 0, 0], [4, 2, 0], 8).shape
    (4, 2, 1)
    """
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    counts = _grid_counts(np.maximum(hi - lo, 0.0), tiles)
    edges = [np.linspace(lo[i], hi[i], int(counts[i]) + 1) for i in range(3)]
    b = _Builder()

    def build(a0, a1):  # cells a0[i] .. a1[i] - 1 along each axis
        axis = next((i for i in range(3) if a1[i] - a0[i] > 1), None)
        if axis is None:
            t = a0[0] + counts[0] * (a0[1] + counts[1] * a0[2])
            return b.leaf(int(t), [edges[i][a0[i]] for i in range(3)],
                          [edges[i][a0[i] + 1] for i in range(3)])
        mid = (a0[axis] + a1[axis]) // 2
        node = b.split(axis, float(edges[axis][mid]))
        lower, upper = list(a1), list(a0)
        lower[axis] = upper[axis] = mid
        b.left[node] = build(a0, lower)
        b.right[node] = build(upper, a1)
        return node

    build([0, 0, 0], [int(c) for c in counts])
    return b.done(tuple(int(c) for c in counts))


def balanced_tiles(sample, lo, hi, n_tiles: int) -> Tiles:
    """``n_tiles`` tiles over ``[lo, hi]`` holding about equal shares of ``sample``.

    Each box is split across its longest side (the lower axis on a tie) at
    the quantile of the sample's positions inside it that gives each half
    its share of the tiles (``n // 2`` below, the rest above); a box whose
    sample is empty, or whose quantile falls on its side, is split in its
    middle. Deterministic: the same sample gives the same tiles.

    Parameters
    ----------
    sample : (s, 3) float ndarray
        Finite element positions (all of them, or an even sample of them).
    lo, hi : (3,) float ndarray
        Bounds of all the positions.
    n_tiles : int
        Number of tiles, ``>= 1``.

    Returns
    -------
    Tiles
        ``shape`` None.

    Raises
    ------
    ParameterError
        If ``n_tiles`` is not a positive integer.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> pts = np.r_[rng.random((900, 3)) * 0.1, rng.random((100, 3))]  # dense corner
    >>> t = balanced_tiles(pts, pts.min(0), pts.max(0), 4)
    >>> np.bincount(t.of(pts)).tolist()
    [250, 250, 250, 250]
    """
    n = _positive_int(n_tiles)
    s = np.asarray(sample, dtype=np.float64).reshape(-1, 3)
    s = s[np.isfinite(s).all(axis=1)]
    b = _Builder()
    count = [0]

    def build(pts, box_lo, box_hi, m):
        if m == 1:
            count[0] += 1
            return b.leaf(count[0] - 1, box_lo, box_hi)
        ext = box_hi - box_lo
        axis = int(np.argmax(ext))
        below = m // 2
        value = 0.5 * (box_lo[axis] + box_hi[axis])
        if pts.shape[0]:
            x = np.sort(pts[:, axis])
            q = x[min(x.size - 1, int(round(x.size * below / m)))]
            if box_lo[axis] < q < box_hi[axis]:
                value = float(q)
        node = b.split(axis, value)
        up = pts[:, axis] >= value
        mid_hi, mid_lo = box_hi.copy(), box_lo.copy()
        mid_hi[axis] = mid_lo[axis] = value
        b.left[node] = build(pts[~up], box_lo, mid_hi, below)
        b.right[node] = build(pts[up], mid_lo, box_hi, m - below)
        return node

    build(s, np.asarray(lo, dtype=np.float64).copy(), np.asarray(hi, dtype=np.float64).copy(), n)
    return b.done(None)


def tile_of(positions: np.ndarray, tiles: Tiles) -> np.ndarray:
    """The tile of each position (:meth:`Tiles.of`); -1 for a non-finite one."""
    return tiles.of(positions)


def tile_box(tiles: Tiles, t: int, margin: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The core box of tile ``t``, grown by ``margin`` on every side (:meth:`Tiles.box`)."""
    return tiles.box(t, margin)


#: Fewest elements a tile holds on average: below, the tiles' halos and tasks cost more
#: than the method (200 tiles of a 5,000-face mesh took 20 s; 10,000 never ended).
MIN_PER_TILE = 50
#: The most tiles a run takes (a million: 50M elements per tile would be 50 trillion)
MAX_TILES = 1 << 20


def check_tiles(tiles, n_elements: int | None = None) -> None:
    """Refuse a ``tiles`` that is neither a positive integer nor three of them, or that
    leaves fewer than :data:`MIN_PER_TILE` elements per tile of an input of
    ``n_elements``.

    Raises
    ------
    ParameterError
        Naming the bad value (and the most tiles the input takes).

    Examples
    --------
    >>> check_tiles((2, 2, 1), 1000)
    >>> check_tiles(10000, 5000)
    Traceback (most recent call last):
    ...
    superfacets.errors.ParameterError: tiles=10000 leaves 0.5 elements per tile ...
    """
    if n_elements is not None:
        check_tiles(tiles)
        n = math.prod(int(t) for t in np.ravel(tiles))
        if n > 1 and n_elements < n * MIN_PER_TILE:
            most = n_elements // MIN_PER_TILE
            raise ParameterError(
                f"tiles={tiles!r} leaves {n_elements / n:.2g} elements per tile of this input "
                f"({n_elements:,} elements); " + (f"give at most {most} tiles" if most > 1 else
                                                  "run it whole, without tiles"))
        return
    if np.ndim(tiles) == 0:
        _positive_int(tiles)
    elif len(tiles) != 3:
        raise ParameterError(f"tiles must be an integer or three integers, got {tiles!r}")
    else:
        for t in tiles:
            _positive_int(t)
        if math.prod(int(t) for t in tiles) > MAX_TILES:
            raise ParameterError(f"tiles={tuple(int(t) for t in tiles)!r} makes more than "
                                 f"{MAX_TILES:,} tiles")


def _grid_counts(ext: np.ndarray, tiles) -> np.ndarray:
    if np.ndim(tiles) == 0:
        n = _positive_int(tiles)
        best = None
        for a, b in _factor_pairs(n):  # (a, b ascending, a * b dividing n)
            counts = np.array([a, b, n // (a * b)])
            if (counts[ext <= 0] > 1).any():
                continue
            side = ext / counts
            side = side[ext > 0]
            score = (side.max() / side.min()) if side.size else 1.0
            if best is None or score < best[0] - 1e-12:
                best = (score, counts)
        if best is None:  # a flat input: a prime count along one axis
            counts = np.ones(3, dtype=np.int64)
            counts[int(np.argmax(ext))] = n
            return counts
        return best[1]
    check_tiles(tiles)
    return np.array([int(t) for t in tiles])


def _divisors(n: int) -> list[int]:
    small = [d for d in range(1, math.isqrt(n) + 1) if n % d == 0]
    return sorted(set(small + [n // d for d in small]))


def _factor_pairs(n: int):
    """The pairs ``(a, b)``, ``a * b`` dividing ``n``, in the order of a loop over
    ``a`` then ``b`` from 1 to ``n`` (in time of the divisors, not of ``n**2``)."""
    for a in _divisors(n):
        for b in _divisors(n // a):
            yield a, b


def _positive_int(v) -> int:
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)) or v < 1:
        raise ParameterError(f"tiles must be positive integers, got {v!r}")
    if v > MAX_TILES:
        shown = str(v) if len(str(v)) < 30 else f"a {len(str(v))}-digit number"
        raise ParameterError(f"tiles must be at most {MAX_TILES:,}, got {shown}")
    return int(v)


def trim_centers(positions: np.ndarray, k: int) -> np.ndarray:
    """Which of the tiles' centers to keep so that at most ``k`` remain.

    Each tile's core holds its share of ``k`` centers when the passes start,
    but the passes move centers across tile borders, where two tiles' runs
    can each keep one: the gathered count runs 0-10 % over ``k`` (measured on
    benchmark meshes). The most crowded go, one at a time: the center whose
    nearest other center is closest (the later row on a tie), until ``k``
    remain.

    Returns
    -------
    (c,) bool ndarray

    Raises
    ------
    ParameterError
        If ``k`` is not an integer >= 0.
    """
    from scipy.spatial import cKDTree

    k = check_int("k", k, lo=0)

    keep = np.ones(positions.shape[0], dtype=bool)
    while keep.sum() > k:
        idx = np.flatnonzero(keep)
        d, j = cKDTree(positions[idx]).query(positions[idx], 2)
        d, j = d[:, 1], j[:, 1]
        excess = int(keep.sum()) - k
        # a pair counts once: drop the later of each closest pair, closest pairs first
        order = np.lexsort((-idx, d))
        gone = np.zeros(idx.size, dtype=bool)
        for a in order:
            if excess == 0:
                break
            if gone[a] or gone[j[a]]:
                continue
            gone[max(a, j[a])] = True
            excess -= 1
            if d[a] > d[order[0]] * 4:  # the rest after the neighbours are recomputed
                break
        keep[idx[gone]] = False
    return keep


def any_in_box(positions: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> bool:
    """Whether any of ``positions`` ((m, 3)) lies in the box ``[lo, hi]``."""
    return bool(rows_in_box(positions, lo, hi).any())


def in_box(reference: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The rows (position, normal) of ``reference`` (R, 6) whose position lies in the box."""
    inside = rows_in_box(reference[:, :3], lo, hi)
    return np.asarray(reference[inside], dtype=np.float64)


def gathered_centers(outs: list, params) -> tuple[np.ndarray, np.ndarray]:
    """The tiles' centers (rows, positions) in row order, trimmed to ``n_segments``."""
    rows = np.concatenate([o["centers"] for o in outs])
    pos = np.concatenate([o["positions"] for o in outs])
    order = np.argsort(rows, kind="stable")
    rows, pos = rows[order], pos[order]
    if params.radius is None and params.init == "farthest":
        keep = trim_centers(pos, params.n_segments)
        return rows[keep], pos[keep]
    return rows, pos
