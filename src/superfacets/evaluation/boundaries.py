"""Agreement of superfacet boundaries with ground-truth boundaries: recall and precision.

The two standard boundary measures of superpixel benchmarks (Martin, Fowlkes,
Malik, PAMI 2004; Stutz, Hermans, Leibe, CVIU 2018), on an element graph:
an element is *on a boundary* when one of its neighbours has another label,
and *near* one when it lies within ``tolerance`` rings of an element on it.

- boundary recall: the share of the ground-truth boundary near a superfacet
  boundary (higher is better: few true borders missed);
- boundary precision: the share of the superfacet boundary near a
  ground-truth boundary (higher is better: few borders where there is none).

Recall alone rewards long, wandering boundaries: a segmentation that puts a
boundary near every element recalls everything. Read the two together (or
their harmonic mean, the F-measure) when comparing methods whose superfacets
differ in shape (``docs/notes/superpoints.md``, "Boundary recall and precision").
"""

from __future__ import annotations

import numpy as np

from ..checks import check_int
from ..elements.builders import as_element_graph
from ..elements.labels import check_labels, relabel_dense

__all__ = ["boundary_recall", "boundary_precision", "near_boundary", "recall_lengths",
           "recall_elements"]


def _per_element(g, labels, what: str) -> np.ndarray:
    """One label per element, dense ``0..K-1``."""
    return relabel_dense(check_labels(labels, g.n_elements, what, per=g.element))


def boundary_recall(graph, labels, ground_truth, *, tolerance: int = 1) -> float:
    """Fraction of the ground-truth boundary found by the superfacet boundaries.

    A ground-truth boundary edge (shared by two faces of different segments)
    counts as recalled when one of its two faces lies within ``tolerance``
    face rings of a face touching a superfacet boundary; the result is the
    recalled length over the total length. In ``[0, 1]``, higher is better;
    1 when the boundaries coincide. A standard superpixel measure, beyond the
    paper.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    labels, ground_truth : (m,) int ndarray
    tolerance : int, default 1
        Face rings of slack (0: the edge's faces must touch a superfacet
        boundary themselves).

    Returns
    -------
    float
        1.0 if the ground truth has no boundary.
    """
    g = as_element_graph(graph)
    s = _per_element(g, labels, "labels")
    gt = _per_element(g, ground_truth, "ground_truth")
    return recall_lengths(g, near_boundary(g, s, tolerance), gt)


def near_boundary(g, s: np.ndarray, tolerance: int,
                  labelled: np.ndarray | None = None) -> np.ndarray:
    """(m,) bool: elements within ``tolerance`` rings of one on a boundary of ``s``
    (where ``labelled`` is given, adjacencies with an unlabelled end are no boundary);
    the rings stop growing once they cover every element they can reach."""
    tolerance = check_int("tolerance", tolerance, lo=0)
    i, j = g.pairs[:, 0], g.pairs[:, 1]
    near = np.zeros(g.n_elements, dtype=bool)
    cut = s[i] != s[j]
    if labelled is not None:
        cut &= labelled[i] & labelled[j]
    near[i[cut]] = True
    near[j[cut]] = True
    for _ in range(tolerance):
        grow = near.copy()
        grow[j[near[i]]] = True
        grow[i[near[j]]] = True
        if np.array_equal(grow, near):  # (a tolerance of 2**62 rings: as many as needed)
            break
        near = grow
    return near


def recall_lengths(g, near: np.ndarray, gt: np.ndarray,
                   labelled: np.ndarray | None = None) -> float:
    """Length share of the boundary of ``gt`` with an end ``near`` (adjacencies with an
    unlabelled end, where ``labelled`` is given, are no boundary). With the roles swapped
    (``near`` the truth's, ``gt`` the superfacets) it is the precision."""
    i, j = g.pairs[:, 0], g.pairs[:, 1]
    gt_edge = gt[i] != gt[j]
    if labelled is not None:
        gt_edge &= labelled[i] & labelled[j]
    if not gt_edge.any():
        return 1.0
    length = g.lengths[gt_edge]
    hit = near[i[gt_edge]] | near[j[gt_edge]]
    return float(length[hit].sum() / length.sum())


def recall_elements(g, near: np.ndarray, gt: np.ndarray,
                     labelled: np.ndarray | None = None) -> float:
    """Fraction of the elements on a boundary of ``gt`` that are ``near`` (adjacencies
    with an unlabelled end, where ``labelled`` is given, are no boundary). With the roles
    swapped it is the precision by elements."""
    i, j = g.pairs[:, 0], g.pairs[:, 1]
    cut = gt[i] != gt[j]
    if labelled is not None:
        cut &= labelled[i] & labelled[j]
    on = np.zeros(g.n_elements, dtype=bool)
    on[i[cut]] = True
    on[j[cut]] = True
    if not on.any():
        return 1.0
    return float(near[on].sum() / on.sum())


def boundary_precision(graph, labels, ground_truth, *, tolerance: int = 1) -> float:
    """Fraction of the superfacet boundaries that lies near a ground-truth boundary.

    A superfacet boundary edge (shared by two elements of different labels)
    counts as precise when one of its two elements lies within ``tolerance``
    rings of an element touching a ground-truth boundary; the result is the
    precise length over the total boundary length: the counterpart of
    :func:`boundary_recall` with the two segmentations' roles swapped.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    labels, ground_truth : (m,) int ndarray
    tolerance : int, default 1
        Rings of slack (0: the edge's elements must touch a ground-truth
        boundary themselves).

    Returns
    -------
    float
        In ``[0, 1]``, higher is better; 1.0 if the labels have no boundary
        (one superfacet).

    Raises
    ------
    ParameterError
        If a label array does not have one integer per element, or ``tolerance`` is not
        an integer >= 0.

    References
    ----------
    D. Martin, C. Fowlkes, J. Malik, "Learning to detect natural image
    boundaries using local brightness, color, and texture cues", PAMI 2004
    (boundary precision and recall with a distance tolerance).

    Examples
    --------
    >>> mesh = trimesh.creation.box()
    >>> labels = (mesh.triangles_center[:, 0] > 0).astype(int)
    >>> boundary_precision(mesh, labels, labels), boundary_recall(mesh, labels, labels)
    (1.0, 1.0)
    """
    g = as_element_graph(graph)
    s = _per_element(g, labels, "labels")
    gt = _per_element(g, ground_truth, "ground_truth")
    return recall_lengths(g, near_boundary(g, gt, tolerance), s)  # roles swapped
