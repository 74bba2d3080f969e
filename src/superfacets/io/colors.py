"""Colours for superfacets (adjacent superfacets always differ clearly) and their boundaries.

The superfacet adjacency graph (two superfacets are adjacent when one of
their faces share a mesh edge) is coloured greedily, largest degree first
(Welsh-Powell), each superfacet taking the least used palette colour that no
coloured neighbour has. Twelve well-separated colours suffice in practice;
more are generated if a superfacet has more coloured neighbours. An element labelled
below 0 (unassigned, as DBSCAN's noise and the metrics read it) is drawn
:data:`UNASSIGNED` grey, not as a segment.
"""

from __future__ import annotations

import colorsys

import numpy as np

from ..elements import faces
from ..elements.labels import check_labels, relabel_dense

__all__ = ["PALETTE", "UNASSIGNED", "superfacet_colors", "labelled_colors", "face_colors",
           "superfacet_adjacency", "boundary_edges"]

#: The colour of an element labelled below 0: in no segment.
UNASSIGNED = np.array([200, 200, 200], dtype=np.uint8)

#: Base palette (RGB, uint8): well-separated, light enough to show shading.
PALETTE = np.array([
    [230, 25, 75], [60, 180, 75], [255, 225, 25], [0, 130, 200], [245, 130, 48],
    [145, 30, 180], [70, 240, 240], [240, 50, 230], [210, 245, 60], [250, 190, 212],
    [0, 128, 128], [170, 110, 40], [255, 250, 200], [128, 0, 0], [170, 255, 195],
    [128, 128, 0], [255, 215, 180], [0, 0, 128],
], dtype=np.uint8)


def _graph(mesh):
    """The face graph of a Mesh, or the element graph given."""
    if hasattr(mesh, "faces"):
        return faces.face_graph(mesh)
    return mesh


def _across(mesh, labels):
    """Labels on both sides of every adjacency, and which adjacencies cross superfacets.
    ``mesh`` is a Mesh (its face graph) or any element graph."""
    graph = _graph(mesh)
    pairs = graph.pairs
    labels = check_labels(labels, graph.n_elements, per=graph.element)
    a, b = labels[pairs[:, 0]], labels[pairs[:, 1]]
    return a, b, a != b


def superfacet_adjacency(mesh, labels: np.ndarray) -> np.ndarray:
    """Pairs of adjacent superfacets.

    Parameters
    ----------
    mesh : Mesh
    labels : (m,) int ndarray

    Returns
    -------
    pairs : (p, 2) int64 ndarray
        Unique ``(s, t)``, ``s < t``, of superfacets sharing a mesh edge.
    """
    a, b, cross = _across(mesh, labels)
    lo, hi = np.minimum(a[cross], b[cross]), np.maximum(a[cross], b[cross])
    if lo.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    return np.unique(np.stack([lo, hi], axis=1).astype(np.int64), axis=0)


def _extra_color(i: int) -> np.ndarray:
    h = (i * 0.618033988749895) % 1.0
    r, g, b = colorsys.hsv_to_rgb(h, 0.65, 0.95)
    return np.array([r * 255, g * 255, b * 255], dtype=np.uint8)


def superfacet_colors(mesh, labels: np.ndarray) -> np.ndarray:
    """One RGB colour per superfacet, different for adjacent superfacets.

    Parameters
    ----------
    mesh : Mesh or ElementGraph
        A mesh (its face graph), or the element graph the labels belong to.
    labels : (m,) int ndarray
        Dense labels ``0..K-1``, one per element.

    Returns
    -------
    colors : (K, 3) uint8 ndarray
    """
    labels = np.asarray(labels, dtype=np.int64)
    k = int(labels.max()) + 1
    adj = superfacet_adjacency(mesh, labels)
    nbrs: list[list[int]] = [[] for _ in range(k)]
    for s, t in adj.tolist():
        nbrs[s].append(t)
        nbrs[t].append(s)
    degree = np.array([len(n) for n in nbrs])
    color = np.full(k, -1, dtype=np.int64)
    palette = [c for c in PALETTE]
    used = np.zeros(len(palette), dtype=np.int64)
    for s in np.lexsort((np.arange(k), -degree)):
        taken = {int(color[t]) for t in nbrs[s] if color[t] >= 0}
        free = [c for c in range(len(palette)) if c not in taken]
        if not free:
            palette.append(_extra_color(len(palette)))
            used = np.r_[used, 0]
            free = [len(palette) - 1]
        best = min(free, key=lambda c: (used[c], c))
        color[s] = best
        used[best] += 1
    return np.asarray(palette, dtype=np.uint8)[color]


def labelled_colors(graph, labels: np.ndarray) -> np.ndarray:
    """Each element's colour: its segment's (:func:`superfacet_colors`), :data:`UNASSIGNED`
    grey where its label is below 0.

    Parameters
    ----------
    graph : Mesh or ElementGraph
        As :func:`superfacet_colors`.
    labels : (m,) int ndarray
        One per element (checked by the caller); any integers, negative ones unassigned.

    Returns
    -------
    (m, 3) uint8 ndarray

    Raises
    ------
    Never for one integer label per element.

    Examples
    --------
    >>> box = as_mesh(trimesh.creation.box())  # 12 triangles
    >>> rgb = labelled_colors(box, np.r_[[-1] * 2, np.arange(10)])
    >>> rgb[0].tolist(), bool((rgb[2:] != UNASSIGNED).any(axis=1).all())
    ([200, 200, 200], True)
    """
    labels = np.asarray(labels, dtype=np.int64)
    dense = relabel_dense(labels)
    out = superfacet_colors(graph, dense)[dense]
    out[labels < 0] = UNASSIGNED
    return out


def face_colors(mesh, labels: np.ndarray) -> np.ndarray:
    """Per-face RGB colours of a segmentation.

    Parameters
    ----------
    mesh : Mesh
    labels : (m,) int ndarray

    Returns
    -------
    (m, 3) uint8 ndarray
        :data:`UNASSIGNED` grey where a face's label is below 0.

    Raises
    ------
    ParameterError
        If ``labels`` is not one integer per face.
    """
    return labelled_colors(mesh, check_labels(labels, mesh.n_faces, per="face"))


def boundary_edges(mesh, labels: np.ndarray) -> np.ndarray:
    """Mesh edges separating two superfacets (the lines drawn between them).

    Parameters
    ----------
    mesh : Mesh
    labels : (m,) int ndarray

    Returns
    -------
    edges : (b, 2) int64 ndarray
        Vertex index pairs, each edge once.
    """
    cut = _across(mesh, labels)[2]
    e = np.sort(np.asarray(_graph(mesh).edges[cut], dtype=np.int64), axis=1)
    return np.unique(e, axis=0) if e.size else e.reshape(0, 2)
