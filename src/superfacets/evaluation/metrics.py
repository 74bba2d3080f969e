"""Evaluation metrics of an over-segmentation (paper section 4; ``docs/notes/method.md``,
section 4).

Pure functions of (element graph, labels[, ground truth]); a mesh stands for
its cached face graph. Areas are sums of element sizes (face areas) and
lengths sums of the cached border lengths, so every metric is independent of
the sampling density and invariant to uniform scaling. A shared, area-weighted
contingency table (:func:`contingency`, like scikit-image's ``table=``) makes
the overlap-based metrics fast.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable, Sequence

import numpy as np

from ..elements.builders import as_element_graph, elements_of
from ..elements.kinds import kind_of
from ..elements.labels import check_labels, size_summary
from ..errors import InvalidMeshError, ParameterError
from ..method.params import DEFAULTS
from .boundaries import (
    boundary_precision,
    boundary_recall,
    near_boundary,
    recall_elements,
    recall_lengths,
)
from .contingency import Contingency, contingency, dense_labels  # noqa: F401 (re-exported)

__all__ = ["Contingency", "contingency", "undersegmentation_error",
           "undersegmentation_error_np", "compactness",
           "achievable_segmentation_accuracy", "boundary_recall", "boundary_precision",
           "mean_over_ground_truths", "ground_truth_list",
           "evaluate", "evaluate_rows", "shape_rows", "oracle_miou", "size_summary",
           "has_border", "METRICS"]

#: The names of the metrics :func:`evaluate` returns, and whether lower is better.
METRICS = {"undersegmentation_error": True, "undersegmentation_error_np": True,
           "compactness": True, "boundary_recall": False, "achievable_accuracy": False}


def undersegmentation_error(graph, labels, ground_truth, *, tau: float = 0.05,
                            table: Contingency | None = None) -> float:
    """Undersegmentation error (paper eq. 4).

    ``UE = sum_i sum_{j : A(s_j ∩ g_i) > tau A(s_j)} A(s_j \\ g_i) / sum_i A(g_i)``:
    for each ground-truth segment, the area that the superfacets overlapping
    it by more than ``tau`` of their own area leak outside it.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
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

    Raises
    ------
    ParameterError
        If the labels or the ground truth are not one integer per element.

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=3)
    >>> halves = (ball.triangles_center[:, 2] > 0).astype(int)
    >>> undersegmentation_error(ball, halves, halves)             # inside the truth: no leak
    0.0
    >>> round(undersegmentation_error(ball, np.zeros(1280, int), halves), 3)  # one: leaks
    1.0
    """
    t = table if table is not None else contingency(graph, labels, ground_truth)
    sa = t.s_area[t.s]
    counted = t.area > tau * sa
    return float((sa[counted] - t.area[counted]).sum() / t.g_area.sum())


def undersegmentation_error_np(graph, labels, ground_truth, *,
                               table: Contingency | None = None) -> float:
    """Neubert and Protzel's undersegmentation error: each overlap charged its smaller part.

    ``UE_NP = sum_j sum_i min(A(s_j ∩ g_i), A(s_j \\ g_i)) / sum_i A(g_i)`` over the
    pairs that overlap. The paper's error (:func:`undersegmentation_error`, eq. 4) charges
    a superfacet that reaches into a segment by more than ``tau`` of its area with all of
    its area outside that segment: one that misses a border by a band costs its whole
    size, while one that holds several small segments, each below ``tau`` of it, costs its
    outside part once. Here both cost what lies on the wrong side. Lower is better; 0 when
    every superfacet lies inside one segment.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    labels, ground_truth : (m,) int ndarray
    table : Contingency, optional
        Precomputed :func:`contingency` of the same arrays.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        If the labels or the ground truth are not one integer per element.

    References
    ----------
    Neubert, Protzel, "Superpixel benchmark and comparison", Forum Bildverarbeitung 2012;
    the undersegmentation error of Stutz, Hermans, Leibe, "Superpixels: an evaluation of
    the state-of-the-art", CVIU 2018.

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=3)
    >>> z = ball.triangles_center[:, 2]
    >>> halves, band = (z > 0).astype(int), (z > -0.2).astype(int)   # a border missed
    >>> round(undersegmentation_error(ball, band, halves), 2)   # the upper half, the band
    0.6
    >>> round(undersegmentation_error_np(ball, band, halves), 2)   # the band's area, twice
    0.22
    """
    t = table if table is not None else contingency(graph, labels, ground_truth)
    inside = t.area
    return float(np.minimum(inside, t.s_area[t.s] - inside).sum() / t.g_area.sum())


def achievable_segmentation_accuracy(graph, labels, ground_truth, *,
                                     table: Contingency | None = None) -> float:
    """Achievable segmentation accuracy: ``sum_j max_i A(s_j ∩ g_i) / A``.

    The fraction of the area labelled correctly when every superfacet takes
    its best ground-truth segment. In ``[0, 1]``, higher is better. A
    standard superpixel measure (Liu et al., CVPR 2011), beyond the paper.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    labels, ground_truth : (m,) int ndarray
    table : Contingency, optional

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        If the labels or the ground truth are not one integer per element.

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=3)
    >>> octants = (ball.triangles_center > 0) @ [4, 2, 1]
    >>> achievable_segmentation_accuracy(ball, octants, octants // 4)  # each in one half
    1.0
    """
    t = table if table is not None else contingency(graph, labels, ground_truth)
    best = np.zeros(t.s_area.shape[0])
    np.maximum.at(best, t.s, t.area)
    return float(best.sum() / t.s_area.sum())


def compactness(graph, labels) -> float:
    """Compactness (paper eq. 5): mean over superfacets of perimeter / sqrt(area).

    The perimeter of a superfacet is the total length of the mesh edges on
    its boundary: edges shared with a face of another label, and open
    boundary edges. (A non-manifold edge counts once per pair of its faces
    that have different labels.) Superfacets of zero area are skipped.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    labels : (m,) int ndarray

    Returns
    -------
    float
        Unitless, scale invariant; lower is better. A flat disk gives
        ``2 sqrt(pi) ≈ 3.545``, a square 4. On tetrahedra (a cell graph):
        surface area / volume^(2/3), a ball ``(36 pi)^(1/3) ≈ 4.836``, a cube 6.

    References
    ----------
    Simari, Picciau, De Floriani, 2014, eq. 5.

    Raises
    ------
    ParameterError
        If the labels are not one integer per element.

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=3)
    >>> 3.5 < compactness(ball, segment(ball, 12).labels) < 10
    True
    """
    g = as_element_graph(graph)
    s = dense_labels(g, labels, "labels")
    k = int(s.max()) + 1
    a, b = s[g.pairs[:, 0]], s[g.pairs[:, 1]]
    cut = a != b
    length = g.lengths[cut]
    perim = np.zeros(k)
    perim += np.bincount(a[cut], weights=length, minlength=k)
    perim += np.bincount(b[cut], weights=length, minlength=k)
    perim += np.bincount(s[g.boundary_elements], weights=g.boundary_lengths, minlength=k)
    area = np.bincount(s, weights=g.sizes, minlength=k)
    ok = area > 0
    dim = kind_of(g.kind).dim  # a volume: area / volume^(2/3)
    power = 2.0 / 3.0 if dim == 3 else 0.5
    return float(np.mean(perim[ok] / area[ok] ** power))



def mean_over_ground_truths(metric: Callable[..., float], graph, labels,
                            ground_truths: Sequence[np.ndarray], **kwargs) -> float:
    """Average a metric over the several human segmentations of one mesh.

    Parameters
    ----------
    metric : callable
        ``metric(graph, labels, ground_truth, **kwargs) -> float``.
    graph : ElementGraph or Mesh
    labels : (m,) int ndarray
    ground_truths : sequence of (m,) int ndarray
    **kwargs
        Passed to ``metric``.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        If ``ground_truths`` is empty.

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=3)
    >>> x, y, z = ((ball.triangles_center[:, j] > 0).astype(int) for j in range(3))
    >>> round(mean_over_ground_truths(achievable_segmentation_accuracy, ball, x, [x, y, z]), 3)
    0.676
    """
    if len(ground_truths) == 0:
        raise ParameterError("no ground-truth segmentation given")
    return float(np.mean([metric(graph, labels, gt, **kwargs) for gt in ground_truths]))


def ground_truth_list(ground_truths) -> list:
    """The ground truths as a list of label arrays: one 1-D array (or list of integers)
    is one ground truth, as a user holding one means it.

    Parameters
    ----------
    ground_truths : sequence of (m,) int ndarray, or one (m,) int ndarray

    Returns
    -------
    list

    Raises
    ------
    ParameterError
        If it is neither (a number, a string, a dict).

    Examples
    --------
    >>> len(ground_truth_list(np.array([0, 1, 1]))), len(ground_truth_list([[0, 1], [1, 1]]))
    (1, 2)
    """
    if isinstance(ground_truths, np.ndarray):
        return [ground_truths] if ground_truths.ndim == 1 else list(ground_truths)
    if isinstance(ground_truths, (str, bytes, dict)) or not hasattr(ground_truths, "__len__"):
        raise ParameterError("ground_truths must be a sequence of label arrays (one per "
                             f"ground truth), got {type(ground_truths).__name__}")
    items = list(ground_truths)
    if items and all(isinstance(v, (int, np.integer)) for v in items):
        return [np.asarray(items)]  # (one ground truth given as a list of integers)
    return items


def evaluate(graph, labels, ground_truths: Sequence[np.ndarray], *, tau: float = 0.05,
             tolerance: int = 1, equal_weight: bool = False,
             ignore_label: int | None = None, precision: bool = False) -> dict:
    """Every metric of one segmentation, averaged over the ground truths.

    Computes one contingency table per ground truth (shared by the
    undersegmentation error and the achievable accuracy) and the superfacet
    boundary mask once, so it is several times faster than calling each
    metric through :func:`mean_over_ground_truths`, with identical results.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    labels : (m,) int ndarray
        Superfacet of each face.
    ground_truths : sequence of (m,) int ndarray
        Human segmentations of the same mesh (at least one).
    tau : float, default 0.05
        Overlap tolerance of :func:`undersegmentation_error` (eq. 4).
    tolerance : int, default 1
        Face rings of slack of :func:`boundary_recall`.
    equal_weight : bool, default False
        Weigh every element alike instead of by its size (vertices and
        points: the benchmark of superpoints): the undersegmentation error
        and the achievable accuracy count elements, and the boundary recall
        is the fraction of ground-truth boundary *elements* (those with a
        neighbour in another segment) within ``tolerance`` rings of a
        superfacet boundary. The compactness stays geometric (eq. 5 on the
        graph's sizes and border lengths).
    ignore_label : int, optional
        A ground-truth value meaning *unlabelled* (a scan's points that no
        annotator labelled, e.g. SemanticKITTI's class 0): those elements
        weigh nothing in the undersegmentation error and the achievable
        accuracy, and neither they nor their adjacencies count as ground-truth
        boundary. The superfacets themselves are left whole (their labelled
        part is what is measured). The compactness is unaffected.
    precision : bool, default False
        Also return ``boundary_precision``
        (:func:`~superfacets.evaluation.boundaries.boundary_precision`, by elements with
        ``equal_weight``, adjacencies with an unlabelled end left out): the
        counterpart of the recall, which alone rewards long boundaries.

    Returns
    -------
    dict of str to float
        ``undersegmentation_error`` (eq. 4, lower is better),
        ``undersegmentation_error_np`` (:func:`undersegmentation_error_np`, lower is
        better), ``compactness`` (eq. 5, lower is better; independent of the ground truths),
        ``boundary_recall`` and ``achievable_accuracy`` (higher is better);
        the keys of :data:`METRICS`, and ``boundary_precision`` (higher is
        better) with ``precision``.

    Raises
    ------
    ParameterError
        If ``ground_truths`` is empty or a label array does not have one
        integer per element.
    InvalidMeshError
        If the total area is zero.

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=3)
    >>> octants = (ball.triangles_center > 0) @ [4, 2, 1]      # eight segments, in halves
    >>> scores = evaluate(ball, octants, [octants // 4])
    >>> sorted(scores)[:3], scores["undersegmentation_error"], scores["boundary_recall"]
    (['achievable_accuracy', 'boundary_recall', 'compactness'], 0.0, 1.0)
    """
    ground_truths = ground_truth_list(ground_truths)
    if len(ground_truths) == 0:
        raise ParameterError("no ground-truth segmentation given")
    g = as_element_graph(graph)
    if not g.area > 0:
        raise InvalidMeshError("mesh has zero total area (every face is degenerate): the "
                               "metrics are area-weighted")
    s = dense_labels(g, labels, "labels")
    near = near_boundary(g, s, tolerance)
    counted = g.replaced(sizes=np.ones(g.n_elements)) if equal_weight else g
    ue, ue_np, br, asa, bp = [], [], [], [], []
    for gt in ground_truths:
        this = counted
        labelled = None
        if ignore_label is not None:
            labelled = check_labels(gt, g.n_elements, "ground_truth", per=g.element) \
                != ignore_label
            if not labelled.any():
                raise ParameterError(f"every element of a ground truth is unlabelled "
                                     f"(ignore_label={ignore_label})")
            this = replace(counted, sizes=np.where(labelled, counted.sizes, 0.0))
        t = contingency(this, s, gt)
        ue.append(undersegmentation_error(this, s, gt, tau=tau, table=t))
        ue_np.append(undersegmentation_error_np(this, s, gt, table=t))
        asa.append(achievable_segmentation_accuracy(this, s, gt, table=t))
        dense_gt = dense_labels(g, gt, "ground_truth")
        br.append(recall_elements(g, near, dense_gt, labelled) if equal_weight else
                  recall_lengths(g, near, dense_gt, labelled))
        if precision:
            near_truth = near_boundary(g, dense_gt, tolerance, labelled)
            # the precision: the recall with the two segmentations' roles swapped
            bp.append(recall_elements(g, near_truth, s, labelled) if equal_weight else
                      recall_lengths(g, near_truth, s, labelled))
    out = {"undersegmentation_error": float(np.mean(ue)),
           "undersegmentation_error_np": float(np.mean(ue_np)),
           "compactness": compactness(g, s),
           "boundary_recall": float(np.mean(br)),
           "achievable_accuracy": float(np.mean(asa))}
    if precision:
        out["boundary_precision"] = float(np.mean(bp))
    return out


def oracle_miou(labels, ground_truth, *, weights=None, ignore_label: int | None = None
                ) -> tuple[float, dict]:
    """The oracle mIoU of a partition: each segment given the majority class of its
    elements, the mean over the classes of the intersection over union of that labelling
    with the classes (the figure Superpoint Transformer and EZ-SP publish for their
    partitions: the best semantic segmentation the superpoints allow).

    Parameters
    ----------
    labels : (n,) int ndarray
        Each element's segment.
    ground_truth : (n,) int ndarray
        Each element's class; ``ignore_label`` marks unlabelled elements, left out.
    weights : (n,) float ndarray, optional
        Each element's weight (faces: their areas); default 1 each (points).
    ignore_label : int, optional

    Returns
    -------
    miou : float
        In ``[0, 1]``; the mean over the classes present among the labelled elements.
    per_class : dict
        Class -> its IoU.

    Raises
    ------
    ParameterError
        If the arrays differ in length, or no element is labelled.

    Examples
    --------
    >>> labels = np.array([0, 0, 0, 1, 1, 1])
    >>> truth = np.array([5, 5, 7, 7, 7, 7])  # segment 0 holds one element of class 7
    >>> miou, per_class = oracle_miou(labels, truth)
    >>> round(miou, 3), {k: round(v, 3) for k, v in per_class.items()}
    (0.708, {5: 0.667, 7: 0.75})
    """
    lab = np.asarray(labels, dtype=np.int64)
    gt = np.asarray(ground_truth, dtype=np.int64)
    if lab.shape != gt.shape or lab.ndim != 1:
        raise ParameterError(f"labels and ground truth must have one value per element, got "
                             f"{lab.shape} and {gt.shape}")
    w = np.ones(lab.shape[0]) if weights is None else np.asarray(weights, dtype=np.float64)
    if w.shape != lab.shape:
        raise ParameterError(f"weights must have one value per element ({lab.shape[0]}), "
                             f"got shape {w.shape}")
    keep = np.ones(lab.shape[0], dtype=bool) if ignore_label is None else gt != ignore_label
    if lab.size and not (lab >= 0).any():
        raise ParameterError("every label is below 0 (unassigned): no segment to measure "
                             "the oracle mIoU on")
    keep &= lab >= 0
    if not keep.any():
        raise ParameterError("no labelled element to measure the oracle mIoU on" + (
            f" (the ground truth is {ignore_label} wherever a label is 0 or more)"
            if lab.size else ""))
    lab, gt, w = lab[keep], gt[keep], w[keep]
    segs, seg = np.unique(lab, return_inverse=True)
    classes, cls = np.unique(gt, return_inverse=True)
    table = np.zeros((segs.size, classes.size))
    np.add.at(table, (seg, cls), w)
    best = table.argmax(axis=1)  # each segment's majority class (the lowest on a tie)
    predicted = best[seg]
    per_class = {}
    for c in range(classes.size):
        inter = w[(predicted == c) & (cls == c)].sum()
        union = w[(predicted == c) | (cls == c)].sum()
        per_class[int(classes[c])] = float(inter / union) if union > 0 else 0.0
    return float(np.mean(list(per_class.values()))), per_class


def evaluate_rows(obj, labels, ground_truths: Sequence[np.ndarray], *,
                  elements: str | None = None, n_neighbors: int = DEFAULTS.n_neighbors,
                  tau: float = 0.05,
                  tolerance: int = 1, ignore_label: int | None = None,
                  precision: bool = False) -> dict:
    """The metrics of labels given per input row: a mesh's faces or vertices, a cloud's points.

    What :func:`superfacets.segment` returns and label files hold is one
    label per face, per vertex or per point of the file (-1 for invalid
    points and unused vertices); this builds the element graph the method
    segments (:func:`superfacets.elements.builders.elements_of`), takes each
    element's value from its first row, and calls :func:`evaluate`, area
    weighted on faces and with every element weighing the same on vertices
    and points (the superpoint benchmark's convention).

    Parameters
    ----------
    obj : Mesh, PointCloud or what :func:`superfacets.segment` accepts
    labels : (N,) int ndarray
        One label per row (faces, vertices or points).
    ground_truths : sequence of (N,) int ndarray
        One class or segment per row; ``ignore_label`` marks unlabelled rows.
    elements : {'faces', 'vertices', 'points'}, optional
        Default: points for a cloud, faces for a mesh.
    n_neighbors : int, default 10
        The point graph's neighbours (points only).
    tau, tolerance, ignore_label, precision
        As in :func:`evaluate`.

    Returns
    -------
    dict
        :func:`evaluate`'s metrics, ``segments`` (distinct labels among the
        elements), ``oracle_miou`` (:func:`oracle_miou`, the mean over the ground
        truths) and ``oracle_iou_per_class`` (with one ground truth), the segments'
        sizes (:func:`size_summary`), ``unassigned``: the elements labelled below 0
        (DBSCAN's noise, say), each such label counted as one segment by every metric, and
        ``borderless_truths``: how many ground truths have no border on the element graph
        (no two neighbours of different labelled values: one class, or classes on separate
        pieces), where the recall is 1 and the precision 0 by convention.

    Raises
    ------
    ParameterError
        If an array does not have one integer per row, or no ground truth
        is given.

    Examples
    --------
    >>> xy = np.random.default_rng(0).random((2000, 2))
    >>> cloud = PointCloud(np.c_[xy, np.zeros(2000)])
    >>> truth = (xy[:, 0] > 0.5).astype(int)
    >>> m = evaluate_rows(cloud, segment(cloud, 20).labels, [truth])
    >>> 0 <= m["undersegmentation_error"] < 0.5, m["segments"]
    (True, 20)
    """

    ground_truths = ground_truth_list(ground_truths)
    if len(ground_truths) == 0:
        raise ParameterError("no ground-truth segmentation given (shape_rows measures the "
                             "segments' shapes alone)")
    g, rows, lab, n = _element_labels(obj, labels, elements, n_neighbors)
    gts = [check_labels(gt, n, "ground_truth", per=g.element)[rows] for gt in ground_truths]
    out = evaluate(g, lab, gts, tau=tau, tolerance=tolerance, precision=precision,
                   equal_weight=kind_of(g.kind).equal_weight, ignore_label=ignore_label)
    weights = None if kind_of(g.kind).equal_weight else g.sizes
    mious = [oracle_miou(lab, gt, weights=weights, ignore_label=ignore_label) for gt in gts]
    out["oracle_miou"] = float(np.mean([m for m, _ in mious]))
    out["oracle_iou_per_class"] = mious[0][1] if len(mious) == 1 else {}
    out["borderless_truths"] = sum(not has_border(g, gt, ignore_label) for gt in gts)
    out.update(_counted(lab))
    return out


def has_border(graph, ground_truth, ignore_label: int | None = None) -> bool:
    """Whether two neighbouring elements hold different labelled values of a ground truth:
    where none do (one class, or classes on separate pieces of the element graph) the
    boundary recall is 1 and the precision 0 by convention, and say nothing.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
        The element graph the labels are measured on (a mesh: its face graph).
    ground_truth : (n_elements,) int ndarray
        One class or segment per element.
    ignore_label : int, optional
        The value of unlabelled elements: an adjacency with such an end is no border.

    Returns
    -------
    bool

    Raises
    ------
    TypeError, InvalidMeshError
        As :func:`~superfacets.elements.builders.as_element_graph`, for what is not an
        element graph or a mesh.
    ParameterError
        If ``ground_truth`` is not one integer per element (or has masked values).

    Examples
    --------
    >>> g = as_element_graph(trimesh.creation.icosphere(subdivisions=2))
    >>> side = (g.positions[:, 0] > 0).astype(int)
    >>> has_border(g, side), has_border(g, np.zeros_like(side))
    (True, False)
    """
    g = as_element_graph(graph)
    gt = check_labels(ground_truth, g.n_elements, "ground_truth", per=g.element)
    a, b = gt[g.pairs[:, 0]], gt[g.pairs[:, 1]]
    cut = a != b
    if ignore_label is not None:
        cut &= (a != ignore_label) & (b != ignore_label)
    return bool(cut.any())


def shape_rows(obj, labels, *, elements: str | None = None,
               n_neighbors: int = DEFAULTS.n_neighbors) -> dict:
    """What can be measured of labels given per input row with no ground truth: the
    compactness (paper eq. 5) and the segments' count and sizes.

    Parameters
    ----------
    obj : Mesh, PointCloud or what :func:`superfacets.segment` accepts
    labels : (N,) int ndarray
        One label per row (faces, vertices or points).
    elements : {'faces', 'vertices', 'points'}, optional
        Default: points for a cloud, faces for a mesh.
    n_neighbors : int, default 10
        The point graph's neighbours (points only).

    Returns
    -------
    dict
        ``compactness`` (lower is better; a disk 3.545), ``segments``, ``unassigned`` and
        the sizes of :func:`size_summary`, as :func:`evaluate_rows` gives them.

    Raises
    ------
    ParameterError
        If ``labels`` does not have one integer per row.

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=3)
    >>> m = shape_rows(ball, segment(ball, 12).labels)
    >>> m["segments"], 3.5 < m["compactness"] < 10
    (12, True)
    """
    g, _, lab, _ = _element_labels(obj, labels, elements, n_neighbors)
    return {"compactness": compactness(g, dense_labels(g, lab, "labels")), **_counted(lab)}


def _element_labels(obj, labels, elements, n_neighbors: int) -> tuple:
    """The element graph the method segments (:func:`~superfacets.elements.builders.
    elements_of`), each element's first row, each element's label (its first row's) and
    the input's rows."""
    source = elements_of(obj, elements, n_neighbors=n_neighbors)
    g, n = source.graph, source.n_rows
    rows = source.first_rows(np.arange(g.n_elements))
    return g, rows, check_labels(labels, n, "labels", per=g.element)[rows], n


def _counted(lab: np.ndarray) -> dict:
    """The segments among the elements' labels ``lab``, those below 0 (unassigned: each
    counted as one segment) and the sizes (:func:`size_summary`)."""
    return {"segments": int(np.unique(lab).size), "unassigned": int((lab < 0).sum()),
            **size_summary(lab - min(int(lab.min()), 0) if lab.size else lab)}
