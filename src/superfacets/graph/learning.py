"""The superpoint graph in the layout learning pipelines read.

PyTorch Geometric's ``Data`` holds ``x`` (node features), ``pos``, ``edge_index``
with each edge in both directions and ``edge_attr`` per directed edge; Superpoint
Transformer (Robert et al., CVPR 2023) adds ``super_index`` (each point's superpoint)
and describes each superpoint by the handcrafted features of its points' covariance
(Demantke et al. 2011, as Superpoint Graph, Landrieu and Simonovsky 2018, computes
them): with ``s1 >= s2 >= s3`` the square roots of its eigenvalues,

- linearity ``(s1 - s2) / s1``, planarity ``(s2 - s3) / s1``, scattering ``s3 / s1``
  (they add up to 1: a pole is linear, a wall or the ground planar, a bush scattered);
- verticality ``1 - |n . up|`` of the normal ``n`` of the best plane (0 on the ground,
  1 on a wall or a pole);
- elevation: the centroid's height above the ground, in the data's units: a quadratic
  surface fitted to the lowest element of each cell of a grid (:data:`GROUND_CELLS`
  along the longer horizontal side), refitted to the lower half of the cells
  (:data:`GROUND_FITS` times) so that roofs and canopies do not lift it; a coarse model
  of a gently rolling ground, as a tile's;
- size: its element count and area; its normal, the best plane's, turned into the half-space
  of ``up`` (as Superpoint Transformer states it: the orientation of the elements' own
  normals does not enter, so a tiled run's equals one run's); its mean colour (where given).

Per edge: its border length, mean angle, concave share (:class:`SuperfacetGraph`),
the offset between the two centroids (``pos[j] - pos[i]`` of ``i -> j``) and the angle
between the two best planes, ``arccos |n_i . n_j|`` in radians (``[0, pi/2]``: the
planes' orientation-free angle, Superpoint Transformer's ``|n_i . n_j|``; a tiled run's
equals one run's however each tile orients estimated normals, which the mean angle and
the concave share read).
"""

from __future__ import annotations

import numpy as np

from ..checks import check_up
from ..inputs.bounds import along
from .adjacency import SuperfacetGraph

__all__ = ["shape_features", "learning_arrays", "learning_layout", "ground_axes",
           "ground_frame", "ground_cells", "elevation", "GROUND_CELLS", "GROUND_FITS",
           "NODE_FEATURES", "EDGE_FEATURES", "LINE_SPREAD"]

#: The ground beneath the superpoints: a quadratic surface fitted to the lowest element
#: of each cell of a grid of this many cells along the input's longer horizontal side ...
GROUND_CELLS = 64
#: ... fitted again this many times to the lower half of the cells, so that roofs and
#: canopies (cells with no ground) do not lift it.
GROUND_FITS = 3

#: A superpoint whose second spread (square root of its scatter's middle eigenvalue) is at
#: most this share of its first lies on a line: its plane is any turn about it, so its normal
#: is the direction across it closest to up (a numerical tolerance, not a shape's).
LINE_SPREAD = 1e-6

#: The columns of ``x``, in order (``red green blue`` follow where there are colours).
NODE_FEATURES = ("linearity", "planarity", "scattering", "verticality", "elevation",
                 "log_count", "log_area", "normal_x", "normal_y", "normal_z")

#: The columns of ``edge_attr``, in order.
EDGE_FEATURES = ("border_length", "mean_angle", "concave", "offset_x", "offset_y",
                 "offset_z", "normal_angle")


def shape_features(graph: SuperfacetGraph, up=(0.0, 0.0, 1.0)) -> dict[str, np.ndarray]:
    """Linearity, planarity, scattering and verticality of each superpoint.

    Parameters
    ----------
    graph : SuperfacetGraph
        With its ``scatter`` (as :func:`~superfacets.graph.adjacency.superfacet_graph`
        makes it).
    up : (3,) float or {'x', 'y', 'z', '-x', '-y', '-z'}, default (0, 0, 1)
        The vertical direction (z for scans read from LAS/LAZ or E57).

    Returns
    -------
    dict of (K,) float64 ndarray
        ``linearity``, ``planarity``, ``scattering`` (in ``[0, 1]``, adding up to 1;
        all 0 for a superpoint of one point) and ``verticality`` (in ``[0, 1]``); and
        ``normal`` (K, 3): the best plane's unit normal with ``normal . up >= 0`` (a
        superpoint of one point, or of coincident ones: its mean normal, turned alike; of
        points on a line, a line's plane being any turn about it: the direction across the
        line closest to ``up``).

    Raises
    ------
    ValueError
        If the graph has no ``scatter``.
    ParameterError
        If ``up`` is neither an axis nor 3 finite numbers not all zero.

    Examples
    --------
    >>> plane = trimesh.creation.box(extents=(4, 4, 0.001)).subdivide().subdivide()
    >>> g = segment(plane, 4).graph()
    >>> f = shape_features(g)
    >>> bool((f["scattering"] < 0.01).all()), f["linearity"].shape  # flat: no scatter
    (True, (4,))
    """
    if graph.scatter is None:
        raise ValueError("the graph has no scatter of its elements: build it with "
                         "superfacet_graph")
    area = np.maximum(graph.area, 1e-300)
    cov = graph.scatter / area[:, None, None]
    evals, evecs = np.linalg.eigh(cov)  # ascending
    sigma = np.sqrt(np.clip(evals, 0.0, None))
    s3, s2, s1 = sigma[:, 0], sigma[:, 1], sigma[:, 2]
    ok = s1 > 0
    safe = np.where(ok, s1, 1.0)
    u = check_up(up)
    normal = np.where(ok[:, None], evecs[:, :, 0], np.asarray(graph.normal, dtype=np.float64))
    normal = _line_normals(normal, evecs[:, :, 2], ok & (s2 <= LINE_SPREAD * s1), u)
    normal = np.where((normal @ u < 0)[:, None], -normal, normal)  # (the up half-space)
    return {"linearity": np.where(ok, (s1 - s2) / safe, 0.0),
            "planarity": np.where(ok, (s2 - s3) / safe, 0.0),
            "scattering": np.where(ok, s3 / safe, 0.0),
            "verticality": np.where(ok, 1.0 - np.abs(normal @ u), 0.0), "normal": normal}


def _line_normals(normal: np.ndarray, along: np.ndarray, line: np.ndarray,
                  u: np.ndarray) -> np.ndarray:
    """``normal``, but for the superpoints whose points lie on a line (``line``, direction
    ``along``), whose plane any turn about the line fits: the direction closest to ``u``
    across the line (a level line's is ``u``), where the line is not along ``u``."""
    across = u[None, :] - (along @ u)[:, None] * along
    size = np.linalg.norm(across, axis=1)
    use = line & (size > 1e-6)
    normal = normal.copy()
    normal[use] = across[use] / size[use, None]
    return normal


def ground_axes(up) -> np.ndarray:
    """The vertical ``u`` and two horizontal axes ``e1``, ``e2`` of the ground's grid.

    Parameters
    ----------
    up : (3,) float ndarray
        Not all zero.

    Returns
    -------
    (3, 3) float64 ndarray
        Rows ``u``, ``e1``, ``e2``, orthonormal.

    Raises
    ------
    Never for a finite ``up`` not all zero.

    Examples
    --------
    >>> ground_axes(np.array([0.0, 0, 2])).tolist()
    [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]
    """
    u = np.asarray(up, dtype=np.float64) / np.linalg.norm(up)
    a = np.eye(3)[int(np.argmin(np.abs(u)))]
    e1 = np.cross(u, a)
    e1 /= np.linalg.norm(e1)
    return np.stack([u, e1, np.cross(u, e1)])


def ground_frame(positions: np.ndarray, up, extent: tuple | None = None) -> tuple:
    """The grid the ground is read on: the vertical ``u``, two horizontal axes ``e1``,
    ``e2`` (:func:`ground_axes`), and the lowest corner ``lo`` and side ``span`` of the
    elements' extent along them (:data:`GROUND_CELLS` cells along it).

    Parameters
    ----------
    positions : (n, 3) float64 ndarray or None
        The elements' positions (None with ``extent``).
    up : (3,) float ndarray
        Not all zero.
    extent : tuple of two (2,) float64 ndarray, optional
        The least and greatest of :func:`along` the two horizontal axes over the elements,
        instead of ``positions`` (a tiled run's survey reads them as it passes).

    Returns
    -------
    tuple
        ``(u, e1, e2, lo, span)``.

    Raises
    ------
    Never for a finite ``up`` not all zero.

    Examples
    --------
    >>> u, e1, e2, lo, span = ground_frame(np.array([[0.0, 0, 0], [4, 2, 1]]),
    ...                                    np.array([0.0, 0, 1]))
    >>> float(span), u.tolist()
    (4.0, [0.0, 0.0, 1.0])
    """
    u, e1, e2 = ground_axes(up)
    if extent is None:
        flat = np.c_[along(positions, e1), along(positions, e2)]
        extent = flat.min(axis=0), flat.max(axis=0)
    lo, hi = (np.asarray(v, dtype=np.float64) for v in extent)
    return u, e1, e2, lo, max(float((hi - lo).max()), 1e-300)


def ground_cells(positions: np.ndarray, frame: tuple) -> tuple:
    """The lowest height of the elements in each cell of the ground's grid that holds one.

    Parameters
    ----------
    positions : (n, 3) float64 ndarray
    frame : tuple
        :func:`ground_frame`'s.

    Returns
    -------
    keys : (m, 2) int64 ndarray
        The cells, in lexicographic order.
    low : (m,) float64 ndarray
        The lowest height in each (along ``u``).

    Raises
    ------
    Never.

    Examples
    --------
    >>> pts = np.array([[0.0, 0, 3], [0, 0, 1], [4, 2, 5]])  # two in one cell
    >>> keys, low = ground_cells(pts, ground_frame(pts, np.array([0.0, 0, 1])))
    >>> low.tolist()
    [1.0, 5.0]
    """
    u, e1, e2, lo, span = frame
    flat = np.c_[along(positions, e1), along(positions, e2)]
    ij = np.floor((flat - lo) / (span / GROUND_CELLS)).astype(np.int64)
    side = GROUND_CELLS + 1  # (a cell's index in 0..GROUND_CELLS: one key, in row order)
    low = np.full(side * side, np.inf)
    np.minimum.at(low, ij[:, 0] * side + ij[:, 1], along(positions, u))
    cells = np.flatnonzero(low < np.inf)
    return np.stack([cells // side, cells % side], 1), low[cells]


def elevation(centroid: np.ndarray, frame: tuple, keys: np.ndarray,
              low: np.ndarray) -> np.ndarray:
    """Each centroid's height above the ground: a quadratic surface fitted to the lowest
    element of each grid cell (:func:`ground_cells`), refitted :data:`GROUND_FITS` times to
    the lower half of them (the cells whose lowest element is a roof or a canopy stand
    above it).

    Parameters
    ----------
    centroid : (K, 3) float64 ndarray
    frame : tuple
        :func:`ground_frame`'s.
    keys, low
        :func:`ground_cells`' (a tiled run: each cell's lowest over the tiles).

    Returns
    -------
    (K,) float64 ndarray
        In the data's units.

    Raises
    ------
    Never.

    Examples
    --------
    >>> xy = np.stack(np.meshgrid(np.arange(8.0), np.arange(8.0)), -1).reshape(-1, 2)
    >>> pts = np.c_[xy, np.zeros(64)]
    >>> frame = ground_frame(pts, np.array([0.0, 0, 1]))
    >>> elevation(np.array([[3.0, 3, 2]]), frame, *ground_cells(pts, frame)).round(6).tolist()
    [2.0]
    """
    u, e1, e2, lo, span = frame
    centres = (keys + 0.5) * (span / GROUND_CELLS) / span  # in [0, 1]: a conditioned fit

    def design(xy):
        x, y = xy[:, 0], xy[:, 1]
        return np.c_[np.ones_like(x), x, y, x * x, x * y, y * y]

    keep = np.ones(keys.shape[0], dtype=bool)
    coef = np.zeros(6)
    for _ in range(GROUND_FITS):
        if keep.sum() < 6:
            break
        coef = np.linalg.lstsq(design(centres[keep]), low[keep], rcond=None)[0]
        residual = low - design(centres) @ coef
        keep = residual <= np.median(residual[keep])
    at = (np.c_[centroid @ e1, centroid @ e2] - lo) / span
    return centroid @ u - design(at) @ coef


def learning_arrays(graph: SuperfacetGraph, positions: np.ndarray, element_labels,
                    row_labels, up=(0.0, 0.0, 1.0)) -> dict[str, np.ndarray]:
    """The superpoint graph as PyTorch Geometric lays it out, as numpy arrays.

    Parameters
    ----------
    graph : SuperfacetGraph
        Of ``element_labels``.
    positions : (n, 3) float ndarray
        The elements' positions (face centroids, vertices, points).
    element_labels : (n,) int ndarray
        Each element's superpoint.
    row_labels : (N,) int ndarray
        Each input row's superpoint (``-1``: an invalid point), as ``super_index``.
    up : (3,) float or {'x', 'y', 'z', '-x', '-y', '-z'}, default (0, 0, 1)

    Returns
    -------
    dict
        ``x`` (K, F) float32 (:data:`NODE_FEATURES`, then ``red green blue`` where the
        graph has a 3-column ``feature``), ``pos`` (K, 3) float64 centroids,
        ``edge_index`` (2, 2E) int64, each edge in both directions (``i -> j`` then
        ``j -> i``), ``edge_attr`` (2E, 7) float32 (:data:`EDGE_FEATURES`),
        ``super_index`` (N,) int64, ``node_features`` and ``edge_features`` (the
        column names, as arrays of str).

    Raises
    ------
    ValueError
        If the graph has no ``scatter`` (:func:`shape_features`).
    ParameterError
        If ``up`` is neither an axis nor 3 finite numbers not all zero.

    Examples
    --------
    >>> r = segment(trimesh.creation.icosphere(subdivisions=3), 12)
    >>> a = r.learning_graph()
    >>> a["x"].shape, a["edge_index"].shape[1] == 2 * r.graph().n_edges
    ((12, 10), True)
    """
    u = check_up(up)
    lab = np.asarray(element_labels, dtype=np.int64)
    count = np.bincount(lab[lab >= 0], minlength=graph.n_segments).astype(np.float64)
    pos = np.asarray(positions, dtype=np.float64)
    frame = ground_frame(pos, u)
    return learning_layout(graph, count, elevation(graph.centroid, frame,
                                                   *ground_cells(pos, frame)), row_labels, u)


def learning_layout(graph: SuperfacetGraph, count: np.ndarray, height: np.ndarray,
                    row_labels, up) -> dict[str, np.ndarray]:
    """:func:`learning_arrays` from each superpoint's element ``count`` and ``height``
    above the ground (:func:`elevation`), as a tiled run sums them.

    Parameters
    ----------
    graph : SuperfacetGraph
    count, height : (K,) float64 ndarray
    row_labels : (N,) int ndarray
    up : (3,) float ndarray
        The vertical (checked by the caller).

    Returns
    -------
    dict
        As :func:`learning_arrays`.

    Raises
    ------
    ValueError
        If the graph has no ``scatter``.

    Examples
    --------
    >>> r = segment(trimesh.creation.icosphere(subdivisions=3), 12)
    >>> a = learning_layout(r.graph(), np.ones(12), np.zeros(12), r.labels, np.eye(3)[2])
    >>> a["x"].shape
    (12, 10)
    """
    u = np.asarray(up, dtype=np.float64)
    shape = shape_features(graph, u)
    cols = [shape["linearity"], shape["planarity"], shape["scattering"], shape["verticality"],
            height, np.log1p(count), np.log1p(graph.area), *shape["normal"].T]
    names = list(NODE_FEATURES)
    if graph.feature is not None and graph.feature.shape[1] == 3:
        cols += list(graph.feature.T)
        names += ["red", "green", "blue"]
    a, b = graph.edge_index
    both = np.stack([np.r_[a, b], np.r_[b, a]])
    offset = graph.centroid[both[1]] - graph.centroid[both[0]]
    per_pair = np.c_[graph.border_length, graph.mean_angle, graph.concave]
    normal = shape["normal"]
    cos = np.abs(np.einsum("ij,ij->i", normal[a], normal[b])).clip(0.0, 1.0)
    planes = np.arccos(cos)
    edge_attr = np.c_[np.r_[per_pair, per_pair], offset, np.r_[planes, planes]]
    return {"x": np.stack(cols, axis=1).astype(np.float32), "pos": graph.centroid,
            "edge_index": both.astype(np.int64), "edge_attr": edge_attr.astype(np.float32),
            "super_index": np.asarray(row_labels, dtype=np.int64),
            "node_features": np.array(names), "edge_features": np.array(EDGE_FEATURES)}
