"""Evaluation metrics of an over-segmentation (paper section 4, SPEC section 4).

Pure functions of (mesh, labels[, ground truth]). Areas are sums of face
areas, so every metric is independent of the sampling density and invariant
to uniform scaling. A shared, area-weighted contingency table
(:func:`contingency`) makes the overlap-based metrics fast.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from .mesh import as_mesh

__all__ = ["Contingency", "contingency", "undersegmentation_error", "compactness",
           "achievable_segmentation_accuracy", "boundary_recall", "mean_over_ground_truths",
           "evaluate", "METRICS"]

#: The names of the metrics :func:`evaluate` returns, and whether lower is better.
METRICS = {"undersegmentation_error": True, "compactness": True,
           "boundary_recall": False, "achievable_accuracy": False}


@dataclass(frozen=True)
class Contingency:
    """Area of every non-empty intersection of a superfacet and a ground-truth segment.

    Attributes
    ----------
    s, g : (q,) int64 ndarray
        Superfacet index and ground-truth segment index of each intersection
        (dense indices, ``0..K-1`` and ``0..G-1``).
    area : (q,) float64 ndarray
        ``A(s_j ∩ g_i)``.
    s_area : (K,) float64 ndarray
        ``A(s_j)``.
    g_area : (G,) float64 ndarray
        ``A(g_i)``.
    """

    s: np.ndarray
    g: np.ndarray
    area: np.ndarray
    s_area: np.ndarray
    g_area: np.ndarray


def _labels(mesh, labels, what: str) -> np.ndarray:
    labels = np.asarray(labels)
    if labels.shape != (mesh.n_faces,) or not np.issubdtype(labels.dtype, np.integer):
        raise ValueError(f"{what} must be an integer array of shape ({mesh.n_faces},), "
                         f"got shape {labels.shape}, dtype {labels.dtype}")
    _, dense = np.unique(labels, return_inverse=True)
    return dense.ravel().astype(np.int64)


def contingency(mesh, labels, ground_truth) -> Contingency:
    """Area-weighted contingency table of superfacets against a ground truth.

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or (vertices, faces)
    labels : (m,) int ndarray
        Superfacet of each face (any integers; made dense internally).
    ground_truth : (m,) int ndarray
        Ground-truth segment of each face.

    Returns
    -------
    Contingency

    Raises
    ------
    ValueError
        If either label array does not have one integer per face.
    """
    mesh = as_mesh(mesh)
    s = _labels(mesh, labels, "labels")
    g = _labels(mesh, ground_truth, "ground_truth")
    n_g = int(g.max()) + 1
    key = s * n_g + g
    uniq, inv = np.unique(key, return_inverse=True)
    area = np.bincount(inv.ravel(), weights=mesh.areas)
    s_area = np.bincount(s, weights=mesh.areas)
    g_area = np.bincount(g, weights=mesh.areas, minlength=n_g)
    return Contingency(s=uniq // n_g, g=uniq % n_g, area=area, s_area=s_area, g_area=g_area)


def undersegmentation_error(mesh, labels, ground_truth, *, tau: float = 0.05,
                            table: Contingency | None = None) -> float:
    """Undersegmentation error (paper eq. 4).

    ``UE = sum_i sum_{j : A(s_j ∩ g_i) > tau A(s_j)} A(s_j \\ g_i) / sum_i A(g_i)``:
    for each ground-truth segment, the area that the superfacets overlapping
    it by more than ``tau`` of their own area leak outside it.

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or (vertices, faces)
    labels, ground_truth : (m,) int ndarray
    tau : float, default 0.05
        Overlap tolerance as a fraction of each superfacet's area.
    table : Contingency, optional
        Precomputed :func:`contingency` of the same arrays.

    Returns
    -------
    float
        ``>= 0``; 0 when every superfacet lies inside one segment. Lower is
        better. (Can exceed 1 when superfacets straddle many segments.)

    References
    ----------
    Simari, Picciau, De Floriani, "Fast and Scalable Mesh Superfacets", 2014, eq. 4.
    """
    t = table if table is not None else contingency(mesh, labels, ground_truth)
    sa = t.s_area[t.s]
    counted = t.area > tau * sa
    return float((sa[counted] - t.area[counted]).sum() / t.g_area.sum())


def achievable_segmentation_accuracy(mesh, labels, ground_truth, *,
                                     table: Contingency | None = None) -> float:
    """Achievable segmentation accuracy: ``sum_j max_i A(s_j ∩ g_i) / A``.

    The fraction of the area labelled correctly when every superfacet takes
    its best ground-truth segment. In ``[0, 1]``, higher is better. A
    standard superpixel measure (Liu et al., CVPR 2011), beyond the paper.

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or (vertices, faces)
    labels, ground_truth : (m,) int ndarray
    table : Contingency, optional

    Returns
    -------
    float
    """
    t = table if table is not None else contingency(mesh, labels, ground_truth)
    best = np.zeros(t.s_area.shape[0])
    np.maximum.at(best, t.s, t.area)
    return float(best.sum() / t.s_area.sum())


def _edge_lengths(mesh, edges: np.ndarray) -> np.ndarray:
    v = mesh.vertices
    return np.linalg.norm(v[edges[:, 1]] - v[edges[:, 0]], axis=1)


def compactness(mesh, labels) -> float:
    """Compactness (paper eq. 5): mean over superfacets of perimeter / sqrt(area).

    The perimeter of a superfacet is the total length of the mesh edges on
    its boundary: edges shared with a face of another label, and open
    boundary edges. (A non-manifold edge counts once per pair of its faces
    that have different labels.) Superfacets of zero area are skipped.

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or (vertices, faces)
    labels : (m,) int ndarray

    Returns
    -------
    float
        Unitless, scale invariant; lower is better. A flat disk gives
        ``2 sqrt(pi) ≈ 3.545``, a square 4.

    References
    ----------
    Simari, Picciau, De Floriani, 2014, eq. 5.
    """
    mesh = as_mesh(mesh)
    s = _labels(mesh, labels, "labels")
    g = mesh.graph
    k = int(s.max()) + 1
    a, b = s[g.pairs[:, 0]], s[g.pairs[:, 1]]
    cut = a != b
    length = _edge_lengths(mesh, g.edges)[cut]
    perim = np.zeros(k)
    perim += np.bincount(a[cut], weights=length, minlength=k)
    perim += np.bincount(b[cut], weights=length, minlength=k)
    perim += np.bincount(s[g.boundary_faces], weights=_edge_lengths(mesh, g.boundary_edges),
                         minlength=k)
    area = np.bincount(s, weights=mesh.areas, minlength=k)
    ok = area > 0
    return float(np.mean(perim[ok] / np.sqrt(area[ok])))


def boundary_recall(mesh, labels, ground_truth, *, tolerance: int = 1) -> float:
    """Fraction of the ground-truth boundary found by the superfacet boundaries.

    A ground-truth boundary edge (shared by two faces of different segments)
    counts as recalled when one of its two faces lies within ``tolerance``
    face rings of a face touching a superfacet boundary; the result is the
    recalled length over the total length. In ``[0, 1]``, higher is better;
    1 when the boundaries coincide. A standard superpixel measure, beyond the
    paper.

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or (vertices, faces)
    labels, ground_truth : (m,) int ndarray
    tolerance : int, default 1
        Face rings of slack (0: the edge's faces must touch a superfacet
        boundary themselves).

    Returns
    -------
    float
        1.0 if the ground truth has no boundary.
    """
    mesh = as_mesh(mesh)
    s = _labels(mesh, labels, "labels")
    gt = _labels(mesh, ground_truth, "ground_truth")
    return _recall(mesh, _near_boundary(mesh, s, tolerance), gt)


def _near_boundary(mesh, s: np.ndarray, tolerance: int) -> np.ndarray:
    """(m,) bool: faces within ``tolerance`` rings of a face on a boundary of ``s``."""
    g = mesh.graph
    i, j = g.pairs[:, 0], g.pairs[:, 1]
    near = np.zeros(mesh.n_faces, dtype=bool)
    cut = s[i] != s[j]
    near[i[cut]] = True
    near[j[cut]] = True
    for _ in range(int(tolerance)):
        grow = near.copy()
        grow[j[near[i]]] = True
        grow[i[near[j]]] = True
        near = grow
    return near


def _recall(mesh, near: np.ndarray, gt: np.ndarray) -> float:
    g = mesh.graph
    i, j = g.pairs[:, 0], g.pairs[:, 1]
    gt_edge = gt[i] != gt[j]
    if not gt_edge.any():
        return 1.0
    length = _edge_lengths(mesh, g.edges)[gt_edge]
    hit = near[i[gt_edge]] | near[j[gt_edge]]
    return float(length[hit].sum() / length.sum())


def mean_over_ground_truths(metric: Callable[..., float], mesh, labels,
                            ground_truths: Sequence[np.ndarray], **kwargs) -> float:
    """Average a metric over the several human segmentations of one mesh.

    Parameters
    ----------
    metric : callable
        ``metric(mesh, labels, ground_truth, **kwargs) -> float``.
    mesh : Mesh
    labels : (m,) int ndarray
    ground_truths : sequence of (m,) int ndarray
    **kwargs
        Passed to ``metric``.

    Returns
    -------
    float

    Raises
    ------
    ValueError
        If ``ground_truths`` is empty.
    """
    if len(ground_truths) == 0:
        raise ValueError("no ground-truth segmentation given")
    return float(np.mean([metric(mesh, labels, gt, **kwargs) for gt in ground_truths]))


def evaluate(mesh, labels, ground_truths: Sequence[np.ndarray], *, tau: float = 0.05,
             tolerance: int = 1) -> dict:
    """Every metric of one segmentation, averaged over the ground truths.

    Computes one contingency table per ground truth (shared by the
    undersegmentation error and the achievable accuracy) and the superfacet
    boundary mask once, so it is several times faster than calling each
    metric through :func:`mean_over_ground_truths`, with identical results.

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or (vertices, faces)
    labels : (m,) int ndarray
        Superfacet of each face.
    ground_truths : sequence of (m,) int ndarray
        Human segmentations of the same mesh (at least one).
    tau : float, default 0.05
        Overlap tolerance of :func:`undersegmentation_error` (eq. 4).
    tolerance : int, default 1
        Face rings of slack of :func:`boundary_recall`.

    Returns
    -------
    dict of str to float
        ``undersegmentation_error`` (eq. 4, lower is better), ``compactness``
        (eq. 5, lower is better; independent of the ground truths),
        ``boundary_recall`` and ``achievable_accuracy`` (higher is better);
        the keys of :data:`METRICS`.

    Raises
    ------
    ValueError
        If ``ground_truths`` is empty or a label array does not have one
        integer per face.
    """
    if len(ground_truths) == 0:
        raise ValueError("no ground-truth segmentation given")
    mesh = as_mesh(mesh)
    s = _labels(mesh, labels, "labels")
    near = _near_boundary(mesh, s, tolerance)
    ue, br, asa = [], [], []
    for gt in ground_truths:
        t = contingency(mesh, s, gt)
        ue.append(undersegmentation_error(mesh, s, gt, tau=tau, table=t))
        asa.append(achievable_segmentation_accuracy(mesh, s, gt, table=t))
        br.append(_recall(mesh, near, _labels(mesh, gt, "ground_truth")))
    return {"undersegmentation_error": float(np.mean(ue)),
            "compactness": compactness(mesh, s),
            "boundary_recall": float(np.mean(br)),
            "achievable_accuracy": float(np.mean(asa))}
