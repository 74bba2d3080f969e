"""Normals of a cloud's points: PCA over each point's neighbours, and one orientation.

The PCA normal of a point is the direction of least variance of its neighbourhood (the
smallest eigenvector of their covariance); its sign is arbitrary, so the normals are
then oriented consistently (Hoppe et al. 1992; the module notes of
:mod:`superfacets.elements.points` give the rules): towards a known sensor, else by
propagation along a minimum spanning tree of flat steps, each connected piece turned
outwards or upwards (``up``); or each normal turned like the nearest normal of an oriented
reference sample (tiled runs).
"""

from __future__ import annotations

import numpy as np

from .._kernels import native

__all__ = ["estimate_normals", "normals_and_linearity", "orient_normals"]


def estimate_normals(points: np.ndarray, neighbors: np.ndarray) -> np.ndarray:
    """Unit PCA normals: the direction of least variance of each point's neighbourhood.

    Parameters
    ----------
    points : (n, 3) float64 ndarray
    neighbors : (n, K) int ndarray
        Each point's neighbourhood (itself included); int32 is read in place, other
        integer types are converted.

    Returns
    -------
    (n, 3) float64 ndarray
        Unit normals, signs arbitrary (see :func:`orient_normals`).
    """
    return normals_and_linearity(points, neighbors)[0]


def normals_and_linearity(points: np.ndarray, neighbors: np.ndarray
                           ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`estimate_normals`, and how much each neighbourhood is a line:
    ``(l1 - l2) / l1`` of its covariance's eigenvalues ``l1 >= l2 >= l3``.

    Parameters
    ----------
    points, neighbors
        As :func:`estimate_normals`.

    Returns
    -------
    normals : (n, 3) float64 ndarray
        Unit normals, signs arbitrary.
    linearity : (n,) float64 ndarray
        In ``[0, 1]``: 1 on a line (a scan line), about 0 on a surface.

    Examples
    --------
    >>> xyz = np.c_[np.arange(5.0), np.zeros(5), np.zeros(5)]   # a line
    >>> nbr = np.array([[i, (i + 1) % 5, (i - 1) % 5] for i in range(5)])
    >>> round(float(normals_and_linearity(xyz, nbr)[1][2]), 6)
    1.0
    """
    pca_normals = native.kernel("normals.pca_normals")

    out = np.empty((points.shape[0], 3))
    linearity = np.empty(points.shape[0])
    # int32 neighbours as given: a column slice of the neighbour lists is read in place
    # (a copy of 11 columns of 1M rows costs 0.25 s, row by row)
    if neighbors.dtype != np.int32:
        neighbors = np.asarray(neighbors, dtype=np.int32)
    pca_normals(np.ascontiguousarray(points, dtype=np.float64), neighbors, out, linearity)
    return out, linearity


def orient_normals(points: np.ndarray, normals: np.ndarray, indptr: np.ndarray,
                   indices: np.ndarray, viewpoint: np.ndarray | None = None,
                   reference: tuple | None = None, up: np.ndarray | None = None
                   ) -> np.ndarray:
    """Flip normals to a consistent orientation (see the module notes).

    Parameters
    ----------
    points, normals : (n, 3) float64 ndarray
    indptr, indices : CSR arrays of the neighbourhood graph
    viewpoint : (3,) float64 ndarray, optional
        Turn every normal towards it instead.
    reference : tuple of two (R, 3) float64 ndarray, optional
        ``(positions, normals)`` oriented elsewhere (a sample of the same
        surface), at least one: instead of the propagation, each normal is
        turned to agree with the reference normal nearest its point
        (``n_i . m_near(i) >= 0``; ties to the lower reference row), a rule
        of the point and the reference alone, so two tiles that both hold a
        point turn it alike.
    up : (3,) float64 ndarray, optional
        Without ``reference``: after the propagation, each connected piece is
        turned to agree with this direction (``sum s_i n_i . up >= 0``),
        instead of outwards from its mean (an open surface seen from that
        side: a terrain from above).

    Returns
    -------
    (n, 3) float64 ndarray
    """
    if viewpoint is not None:
        flip = np.einsum("ij,ij->i", normals, viewpoint[None, :] - points) < 0
        return np.where(flip[:, None], -normals, normals)
    if reference is not None and reference[0].shape[0]:
        return _turned_like(points, normals, reference)
    propagate_signs = native.kernel("orient.propagate_signs")
    turn_outwards = native.kernel("orient.turn_outwards")

    n = points.shape[0]
    sign = np.empty(n, dtype=np.int8)
    comp = np.empty(n, dtype=np.int64)
    n_comp = propagate_signs(indptr, indices, normals, sign, comp)
    out = np.empty_like(normals)
    turn_outwards(points, normals, sign, comp, n_comp, out)
    if up is not None and n:
        vote = np.bincount(comp, weights=out @ np.asarray(up, dtype=np.float64),
                           minlength=n_comp)
        out[(vote < 0)[comp]] *= -1.0
    return out


#: Points turned like the reference (:func:`orient_normals`) per block.
TURN_BLOCK = 1 << 20


def _turned_like(points: np.ndarray, normals: np.ndarray, reference: tuple) -> np.ndarray:
    """``normals`` each turned to agree with the reference normal nearest its point
    (:func:`orient_normals`' ``reference``), in blocks of :data:`TURN_BLOCK` points (the
    nearest rows are 8 bytes a point)."""
    from .neighbors import closest, point_tree

    tree = point_tree(np.asarray(reference[0], dtype=np.float64))
    ref_normals = np.asarray(reference[1], dtype=np.float64)
    out = np.array(normals, dtype=np.float64)
    for lo in range(0, points.shape[0], TURN_BLOCK):
        hi = min(lo + TURN_BLOCK, points.shape[0])
        near = closest(tree, points[lo:hi])
        flip = np.einsum("ij,ij->i", out[lo:hi], ref_normals[near]) < 0
        out[lo:hi][flip] *= -1.0
    return out
