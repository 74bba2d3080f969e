"""Cut pursuit on the point graph: the partition Superpoint Graph and its successors use.

Landrieu and Simonovsky's Superpoint Graph (CVPR 2018), and Superpoint
Transformer after it, take their superpoints from the l0 cut pursuit of
Landrieu and Obozinski: the piecewise-constant approximation of per-point
features ``f`` on the k-nearest-neighbour graph that minimises

``sum_i ||g_i - f_i||^2 + reg_strength * sum_(ij, g_i != g_j) w_ij``,

its superpoints being the connected pieces of constant ``g``. Here, as in
the Superpoint Graph's partition step:

- features: the four dimensionality features of each point's neighbourhood
  (its neighbours in the graph), from the eigenvalues
  ``l1 >= l2 >= l3`` of their covariance: linearity ``(l1 - l2) / l1``,
  planarity ``(l2 - l3) / l1``, scattering ``l3 / l1`` and verticality (the
  ``up`` component of the eigenvalue-weighted sum of the absolute
  eigenvectors, normalised), with RGB appended where given, and the point's
  position divided by the bounding-box diagonal and multiplied by
  ``spatial`` (as Superpoint Transformer's partition adds positions, so that
  superpoints stay compact where the other features are flat);
- edge weights ``1 / (1 + d_ij / mean(d))``, ``d`` the edge lengths;
- the graph: the package's point graph (or a mesh's vertex graph), so both
  methods see the same neighbours.

``reg_strength`` sets the number of superpoints only indirectly; given
``n_segments`` it is found by bisection in log scale. ``cut-pursuit-py``
1.0.12 ignores its ``reg_strength`` argument (measured: the same partition
from 1e-4 to 100), so it is applied by dividing the features by
``sqrt(reg_strength)`` and passing 1: minimising ``sum ||g - f / s||^2 +
sum w`` is the problem above with ``reg_strength = s^2``. The solver is
``cut-pursuit-py`` (MIT, an optional dependency: ``pip install
cut-pursuit-py``); the GPL ``pycut-pursuit`` is not used here.

This is Superpoint Graph's partition with the package's own graph, not the
strongest configuration: :mod:`.spt_partition` runs cut pursuit as
Superpoint Transformer does (voxels, elevation, its graph, a minimum
superpoint size, two levels), which the comparison tables use as well.

References
----------
L. Landrieu, G. Obozinski, "Cut Pursuit: fast algorithms to learn piecewise
constant functions on general weighted graphs", SIAM J. Imaging Sci. 10(4),
2017. L. Landrieu, M. Simonovsky, "Large-scale Point Cloud Semantic
Segmentation with Superpoint Graphs", CVPR 2018.
"""

from __future__ import annotations

import numpy as np

from ..._kernels import native
from ..._runtime import extras
from ...elements.builders import elements_of, is_cloud
from ...elements.labels import relabel_dense
from ...method.params import DEFAULTS, check_choice, check_int, check_nonneg, check_positive
from ._count import search_count

__all__ = ["cut_pursuit", "dimensionality_features"]


def dimensionality_features(graph, up: int = 2) -> np.ndarray:
    """Linearity, planarity, scattering and verticality of each element's neighbourhood.

    Parameters
    ----------
    graph : ElementGraph
        Its CSR neighbours form each neighbourhood.
    up : {0, 1, 2}, default 2
        The vertical axis of verticality.

    Returns
    -------
    (n, 4) float64 ndarray
        Each in ``[0, 1]`` (an element with a degenerate neighbourhood: zeros).
    """

    n = graph.n_elements
    cov = np.empty((n, 3, 3))
    native.kernel("baselines.csr_covariances")(
        np.ascontiguousarray(graph.indptr, dtype=np.int64), graph.indices,
        np.ascontiguousarray(graph.positions, dtype=np.float64), cov)
    lam, vec = np.linalg.eigh(cov)  # ascending
    lam = np.maximum(lam[:, ::-1], 0.0)  # l1 >= l2 >= l3
    vec = vec[:, :, ::-1]
    l1 = np.where(lam[:, 0] > 0, lam[:, 0], 1.0)
    out = np.zeros((n, 4))
    out[:, 0] = (lam[:, 0] - lam[:, 1]) / l1
    out[:, 1] = (lam[:, 1] - lam[:, 2]) / l1
    out[:, 2] = lam[:, 2] / l1
    unary = np.einsum("nj,nij->ni", lam, np.abs(vec))  # sum_j l_j |u_j|
    norm = np.linalg.norm(unary, axis=1)
    out[:, 3] = np.divide(unary[:, up], norm, out=np.zeros(n), where=norm > 0)
    out[lam[:, 0] <= 0] = 0.0
    return out


def cut_pursuit(obj, n_segments: int | None = None, *, reg_strength: float = 0.1,
                elements: str | None = None, colors=None, up: int = 2,
                spatial: float = 1.0,
                n_neighbors: int = DEFAULTS.n_neighbors,
                neighbor_radius: float | None = None) -> np.ndarray:
    """Superpoints by l0 cut pursuit of dimensionality features (module notes).

    Parameters
    ----------
    obj : point cloud or mesh
        As :func:`superfacets.segment` accepts.
    n_segments : int, optional
        Search ``reg_strength`` (bisection in log scale, 16 runs at most) for
        the count nearest this one. The count can jump as ``reg_strength``
        varies (cut pursuit starts from one piece and may not split at all:
        on a plane and a separate line, from about 140 straight to 1), so
        the nearest count reached is returned.
    reg_strength : float, default 0.1
        The regularisation (larger: fewer superpoints), ``> 0``; ignored with
        ``n_segments``.
    elements : {'points', 'vertices'}, optional
        Default: points for a cloud, vertices for a mesh.
    colors : (N, 3) float ndarray, optional
        RGB in ``[0, 1]`` per input row, appended to the features (default:
        the cloud's colours, if any).
    up : {0, 1, 2}, default 2
        Vertical axis of the verticality feature.
    spatial : float, default 1
        Weight of the positions among the features (``>= 0``; 0: none).
    n_neighbors, neighbor_radius
        The point graph's neighbourhood.

    Returns
    -------
    labels : (N,) int64 ndarray
        Dense, one per point or vertex (-1 for invalid points and unused vertices).

    Raises
    ------
    MissingExtraError
        If ``cut-pursuit-py`` is not installed.
    ParameterError
        On a parameter out of range.

    Examples
    --------
    >>> xyz = np.random.default_rng(0).normal(size=(3000, 3))
    >>> xyz /= np.linalg.norm(xyz, axis=1, keepdims=True)
    >>> labels = cut_pursuit(xyz, 20)           # doctest: +SKIP
    """

    cp = extras.require("cut_pursuit_py", "the cut pursuit baseline")
    if elements is None:
        elements = "points" if is_cloud(obj) else "vertices"
    check_choice("elements", elements, ("points", "vertices"))
    up = check_int("up", up, lo=0, hi=2)
    source = elements_of(obj, elements, n_neighbors=n_neighbors,
                         neighbor_radius=neighbor_radius)
    g = source.graph
    feats = dimensionality_features(g, up)
    spatial = check_nonneg("spatial", spatial)
    if spatial > 0:
        pos = np.asarray(g.positions, dtype=np.float64)
        feats = np.c_[feats, spatial * (pos - pos.mean(axis=0)) / g.diagonal]
    if colors is None:
        colors = source.colors()
    if colors is not None:
        rows = source.first_rows(np.arange(g.n_elements))
        feats = np.c_[feats, np.asarray(colors, dtype=np.float64)[rows]]
    feats = np.ascontiguousarray(feats, dtype=np.float32)
    lo = np.ascontiguousarray(g.pairs[:, 0], dtype=np.uint32)
    hi = np.ascontiguousarray(g.pairs[:, 1], dtype=np.uint32)
    span = np.asarray(g.span, dtype=np.float64)
    mean = float(span.mean()) if span.size and span.mean() > 0 else 1.0
    w = (1.0 / (1.0 + span / mean)).astype(np.float32)

    def run(reg: float) -> np.ndarray:
        scaled = np.ascontiguousarray(feats / np.float32(np.sqrt(reg)), dtype=np.float32)
        out = cp.perform_cut_pursuit(reg_strength=1.0, D=int(feats.shape[1]),
                                     pc_vec=scaled, edge_weights=w, Eu=lo, Ev=hi,
                                     verbose=False)
        return relabel_dense(np.asarray(out, dtype=np.int64))

    if n_segments is None:
        labels = run(check_positive("reg_strength", reg_strength))
    else:
        n_segments = check_int("n_segments", n_segments, lo=1, hi=g.n_elements)

        # log10 of reg_strength
        labels = search_count(run, n_segments, -8.0, 2.0, 16, "cut pursuit")
    return source.to_rows(labels)
