"""The contingency table of a segmentation and a ground truth: the area of every
non-empty intersection of a superfacet and a ground-truth segment, shared by the
undersegmentation error and the achievable accuracy (:mod:`superfacets.evaluation.metrics`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..elements.builders import as_element_graph
from ..elements.labels import check_labels

__all__ = ["Contingency", "contingency", "dense_labels"]


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

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=3)
    >>> octants = (ball.triangles_center > 0) @ [4, 2, 1]      # eight segments
    >>> t = contingency(ball, octants, octants // 4)           # the truth: two halves
    >>> t.s_area.shape, t.g_area.shape, bool(np.isclose(t.area.sum(), t.s_area.sum()))
    ((8,), (2,), True)
    """

    s: np.ndarray
    g: np.ndarray
    area: np.ndarray
    s_area: np.ndarray
    g_area: np.ndarray


def dense_labels(g, labels, what: str) -> np.ndarray:
    """One label per element, made dense ``0..K-1``.

    Parameters
    ----------
    g : ElementGraph
    labels : (n,) int ndarray
    what : str
        The array's name, for the message.

    Returns
    -------
    (n,) int64 ndarray

    Raises
    ------
    ParameterError
        If ``labels`` is not one integer per element.

    Examples
    --------
    >>> g = as_element_graph(trimesh.creation.box())
    >>> dense_labels(g, [5] * 6 + [9] * 6, "labels").tolist()
    [0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1]
    """
    _, dense = np.unique(check_labels(labels, g.n_elements, what, per=g.element),
                         return_inverse=True)
    return dense.ravel().astype(np.int64)


def contingency(graph, labels, ground_truth) -> Contingency:
    """Area-weighted contingency table of superfacets against a ground truth.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    labels : (m,) int ndarray
        Superfacet of each face (any integers; made dense internally).
    ground_truth : (m,) int ndarray
        Ground-truth segment of each face.

    Returns
    -------
    Contingency

    Raises
    ------
    ParameterError
        If either label array does not have one integer per element.

    Raises
    ------
    ParameterError
        If the labels or the ground truth are not one integer per element.

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=3)
    >>> quarters = (ball.triangles_center[:, :2] > 0) @ [2, 1]
    >>> t = contingency(ball, quarters, (ball.triangles_center[:, 2] > 0).astype(int))
    >>> int(t.s.max()) + 1, int(t.g.max()) + 1, t.s.shape    # 4 x 2 overlaps
    (4, 2, (8,))
    """
    graph = as_element_graph(graph)
    s = dense_labels(graph, labels, "labels")
    g = dense_labels(graph, ground_truth, "ground_truth")
    n_g = int(g.max()) + 1
    key = s * n_g + g
    uniq, inv = np.unique(key, return_inverse=True)
    area = np.bincount(inv.ravel(), weights=graph.sizes)
    s_area = np.bincount(s, weights=graph.sizes)
    g_area = np.bincount(g, weights=graph.sizes, minlength=n_g)
    return Contingency(s=uniq // n_g, g=uniq % n_g, area=area, s_area=s_area, g_area=g_area)
