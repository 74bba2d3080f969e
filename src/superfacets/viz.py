"""Colours for superfacets: adjacent superfacets always differ clearly.

The superfacet adjacency graph (two superfacets are adjacent when one of
their faces share a mesh edge) is coloured greedily, largest degree first
(Welsh-Powell), each superfacet taking the least used palette colour that no
coloured neighbour has. Twelve well-separated colours suffice in practice;
more are generated if a superfacet has more coloured neighbours.
"""

from __future__ import annotations

import colorsys

import numpy as np

__all__ = ["PALETTE", "superfacet_colors", "face_colors", "superfacet_adjacency",
           "boundary_edges", "view_frame"]

#: Base palette (RGB, uint8): well-separated, light enough to show shading.
PALETTE = np.array([
    [230, 25, 75], [60, 180, 75], [255, 225, 25], [0, 130, 200], [245, 130, 48],
    [145, 30, 180], [70, 240, 240], [240, 50, 230], [210, 245, 60], [250, 190, 212],
    [0, 128, 128], [170, 110, 40], [255, 250, 200], [128, 0, 0], [170, 255, 195],
    [128, 128, 0], [255, 215, 180], [0, 0, 128],
], dtype=np.uint8)


def _across(mesh, labels):
    """Labels on both sides of every face-graph edge, and which edges cross superfacets."""
    pairs = mesh.graph.pairs
    labels = np.asarray(labels)
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
    mesh : Mesh
    labels : (m,) int ndarray
        Dense labels ``0..K-1``.

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


def face_colors(mesh, labels: np.ndarray) -> np.ndarray:
    """Per-face RGB colours of a segmentation.

    Parameters
    ----------
    mesh : Mesh
    labels : (m,) int ndarray

    Returns
    -------
    (m, 3) uint8 ndarray

    Raises
    ------
    ValueError
        If ``labels`` does not have one entry per face.
    """
    labels = np.asarray(labels)
    if labels.shape != (mesh.n_faces,):
        raise ValueError(f"labels must have shape ({mesh.n_faces},), got {labels.shape}")
    from .connectivity import relabel_dense

    dense = relabel_dense(labels)
    return superfacet_colors(mesh, dense)[dense]


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
    e = np.sort(np.asarray(mesh.graph.edges[cut], dtype=np.int64), axis=1)
    return np.unique(e, axis=0) if e.size else e.reshape(0, 2)


_VIEWS = {"front": (0, 0, 1), "back": (0, 0, -1), "left": (-1, 0, 0), "right": (1, 0, 0),
          "top": (0, 1, 0), "bottom": (0, -1, 0)}


_AXES = {"x": (1, 0, 0), "y": (0, 1, 0), "z": (0, 0, 1),
         "-x": (-1, 0, 0), "-y": (0, -1, 0), "-z": (0, 0, -1)}


def view_frame(mesh, view=None, elevation: float = 20.0,
               up="y") -> tuple[np.ndarray, np.ndarray]:
    """A camera direction and up vector that show a mesh well.

    Automatic (``view=None``): look along the principal axis of least
    area-weighted spread of the face centroids (so the widest silhouette
    faces the camera), tilted up by ``elevation`` degrees. Up is the ``up``
    axis made perpendicular to the view, or the principal axis of largest
    spread when ``up`` is along the view.

    Parameters
    ----------
    mesh : Mesh
    view : str or (3,) float, optional
        ``'auto'``, ``'front'`` (+z), ``'back'``, ``'left'``, ``'right'``,
        ``'top'`` (+y), ``'bottom'``, or a direction from the mesh to the camera.
    elevation : float, default 20
        Degrees of upward tilt of an automatic or named view.
    up : {'y', 'z', 'x', '-y', '-z', '-x'} or (3,) float, default 'y'
        The mesh's up direction (most benchmark meshes: +y).

    Returns
    -------
    direction : (3,) float64 ndarray
        Unit vector from the mesh center to the camera.
    up : (3,) float64 ndarray
        Unit up vector, perpendicular to ``direction``.

    Raises
    ------
    ValueError
        On an unknown view name or a zero/non-finite direction.
    """
    c = mesh.centroids
    w = mesh.areas / max(mesh.area, 1e-300)
    mean = w @ c
    cov = (c - mean).T @ ((c - mean) * w[:, None])
    evals, evecs = np.linalg.eigh(cov)
    if isinstance(up, str):
        if up not in _AXES:
            raise ValueError(f"unknown up axis {up!r}; use one of {', '.join(_AXES)}")
        up_axis = np.array(_AXES[up], dtype=float)
    else:
        up_axis = np.asarray(up, dtype=float).reshape(3)
        if not np.all(np.isfinite(up_axis)) or np.linalg.norm(up_axis) == 0:
            raise ValueError(f"up must be a non-zero finite 3-vector, got {up!r}")
        up_axis = up_axis / np.linalg.norm(up_axis)
    if view is None or (isinstance(view, str) and view == "auto"):
        d = evecs[:, 0]  # the axis of least spread: the widest silhouette
        # face the camera from the positive side of the dominant world axis of d
        if d[np.argmax(np.abs(d))] < 0:
            d = -d
    elif isinstance(view, str):
        if view not in _VIEWS:
            raise ValueError(f"unknown view {view!r}; use auto, {', '.join(_VIEWS)} or x,y,z")
        d = np.array(_VIEWS[view], dtype=float)
    else:
        d = np.asarray(view, dtype=float).reshape(3)
        if not np.all(np.isfinite(d)) or np.linalg.norm(d) == 0:
            raise ValueError(f"view direction must be a non-zero finite 3-vector, got {view!r}")
        elevation = 0.0 if view is not None else elevation
    d = d / np.linalg.norm(d)
    up = up_axis.copy()
    if abs(up @ d) > 0.95:  # looking along y: use the longest principal axis
        up = evecs[:, 2] if abs(evecs[:, 2] @ d) < 0.95 else np.array([0.0, 0.0, -1.0])
    up = up - (up @ d) * d
    up /= np.linalg.norm(up)
    if elevation:
        t = np.radians(elevation)
        d, up = np.cos(t) * d + np.sin(t) * up, np.cos(t) * up - np.sin(t) * d
    return d / np.linalg.norm(d), up / np.linalg.norm(up)
