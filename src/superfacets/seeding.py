"""Initializations of the iteration (paper section 3.1, SPEC section 3 step 1).

- :func:`farthest_point_centers`: ``k`` center faces, given the number of
  superfacets;
- :func:`flood_labels` and :func:`grid_labels`: initial regions, given the
  radius ``r`` (absolute units here; the public API takes it as a fraction
  of the bounding-box diagonal).
"""

from __future__ import annotations

import numpy as np

from . import _kernels
from ._workspace import Workspace, bucket_width, with_room
from .errors import ParameterError

__all__ = ["first_center", "farthest_point_centers", "flood_labels", "grid_labels", "INITS"]

_BLOCKED_MIN_WORK = 50_000_000  # faces x centers above which cells pay (< 0.1 s below)

#: Names accepted by ``init=``.
INITS = ("farthest", "flood", "grid")


def first_center(mesh) -> int:
    """The face whose centroid is closest to the mesh centroid.

    The mesh centroid is the mean of the referenced vertex positions, as in
    the authors' implementation (unreferenced vertices are ignored). Ties go
    to the lowest face index.

    Parameters
    ----------
    mesh : Mesh

    Returns
    -------
    int
        A face index.
    """
    d2 = ((mesh.centroids - mesh.center) ** 2).sum(axis=1)
    return int(np.argmin(d2))


def farthest_point_centers(mesh, n_segments: int) -> np.ndarray:
    """Iterative farthest-point initialization (paper section 3.1).

    The first center is :func:`first_center`; each next one is the face whose
    centroid has the largest Euclidean distance to its nearest chosen center.
    Runs in O(m k) time at worst and O(m) memory (a running minimum),
    instead of the paper's O(m k^2); in practice close to O(m log k): the
    faces are grouped in grid cells, and a new center visits only the cells
    where it can be nearer than the earlier centers (exactly the same
    centers, ties included, as the plain O(m k) loop; tested).

    Parameters
    ----------
    mesh : Mesh
    n_segments : int
        Number of centers ``k``, ``1 <= k <= m``.

    Returns
    -------
    centers : (k,) int64 ndarray
        Distinct face indices, in the order they were chosen.

    Raises
    ------
    ParameterError
        If ``n_segments`` is not in ``1..m``.
    """
    k = check_n_segments(n_segments, mesh.n_faces)
    out = np.empty(k, dtype=np.int64)
    c = np.ascontiguousarray(mesh.centroids)
    m = c.shape[0]
    if m * k < _BLOCKED_MIN_WORK:
        _kernels.farthest_point(c, k, first_center(mesh), out)
    else:  # same result; each new center visits only the grid cells it can change
        g = max(2, round(m ** (1 / 3)))  # g^3 ~ m cells: the count array stays O(m)
        _kernels.farthest_point_blocked(c, k, first_center(mesh), out,
                                        *_kernels.spatial_blocks(c, g))
    return out


def flood_labels(mesh, csr_weights: np.ndarray, radius: float, window: float = 2.0) -> np.ndarray:
    """Flood initialization (paper section 3.1; authors' implementation).

    Faces are ordered by Euclidean distance (of centroids) to the first seed,
    :func:`first_center`. The nearest face not yet labelled starts a new
    region, grown over the face graph by a bounded expansion that claims only
    unlabelled faces within ``window * radius`` (Euclidean, centroid to
    centroid) of the seed — the paper's "a face farther than 2r from the seed
    starts a new region" with the default ``window = 2``. Repeats until every
    face has a label.

    Parameters
    ----------
    mesh : Mesh
    csr_weights : (2 e,) float64 ndarray
        Edge weights per CSR entry of ``mesh.graph``.
    radius : float
        Superfacet radius ``r`` in mesh units, ``> 0``.
    window : float, default 2
        Expansion multiple.

    Returns
    -------
    labels : (m,) int64 ndarray
        Region of each face, dense ``0..R-1`` in order of creation.
    """
    g = mesh.graph
    c = np.ascontiguousarray(mesh.centroids)
    seed = first_center(mesh)
    order = np.argsort(((c - c[seed]) ** 2).sum(axis=1), kind="stable").astype(np.int64)
    m = mesh.n_faces
    labels = np.empty(m, dtype=np.int64)
    inv_width, n_buckets = bucket_width(csr_weights)
    ws = Workspace(m, n_buckets, g.indices.shape[0] + m + 1)
    with_room(ws, lambda ws: _kernels.flood(g.indptr, g.indices, csr_weights, c, order,
                                            float((window * radius) ** 2), labels, ws.local,
                                            ws.stamp, 0, ws.queue, inv_width, ws.vis))
    return labels


def grid_labels(mesh, radius: float) -> np.ndarray:
    """Regular-grid initialization (paper section 3.1).

    Each face centroid is integer-divided by ``2 r`` after subtracting the
    minimum corner of the bounding box of the (referenced) vertices, so the
    grid moves with the mesh (translation invariance); faces in the same cell
    of the 3D grid start in the same region. Cells are numbered in lexicographic order of their integer
    coordinates. O(m log m) (a sort stands in for the hash map).

    Parameters
    ----------
    mesh : Mesh
    radius : float
        Superfacet radius ``r`` in mesh units, ``> 0``.

    Returns
    -------
    labels : (m,) int64 ndarray
        Region of each face, dense ``0..R-1``.
    """
    origin = mesh.vertices[mesh.referenced_vertices].min(axis=0)
    cell = np.floor((mesh.centroids - origin) / (2.0 * radius)).astype(np.int64)
    dims = cell.max(axis=0) + 1
    key = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
    _, labels = np.unique(key, return_inverse=True)
    return labels.astype(np.int64).ravel()


def check_n_segments(n_segments, m: int) -> int:
    """Validate a number of superfacets against the number of faces ``m``.

    Raises
    ------
    ParameterError
        If ``n_segments`` is not an integer in ``1..m``.
    """
    if isinstance(n_segments, (bool, np.bool_)) or not isinstance(n_segments, (int, np.integer)):
        raise ParameterError(f"n_segments must be an integer, got {n_segments!r}")
    k = int(n_segments)
    if k < 1:
        raise ParameterError(f"n_segments must be >= 1, got {k}")
    if k > m:
        raise ParameterError(f"n_segments ({k}) is larger than the number of faces ({m})")
    return k
