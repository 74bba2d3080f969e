"""Variational Shape Approximation (Cohen-Steiner, Alliez, Desbrun 2004).

The baseline of the paper's Figs. 7 and 8: a Lloyd-style partition of the
faces into regions, each approximated by a planar *proxy* ``(X, N)`` (a point
and a unit normal), minimizing a distortion:

- **L2,1** (normal deviation): ``E(T, P) = area(T) |n_T - N|^2``;
- **L2** (distance to the plane): ``E(T, P) = integral over T of
  ((x - X) . N)^2 dA = area/6 (d0^2 + d1^2 + d2^2 + d0 d1 + d1 d2 + d2 d0)``
  with ``d_i`` the signed distances of the three vertices.

One iteration: **flooding** from one seed face per proxy with a single
priority queue of (distortion, face, proxy) entries, the smallest popped
first; **fitting** of each proxy to its region (L2,1: area-weighted mean
normal; L2: normal of least variance of the exact, triangle-integrated
covariance, through the area centroid); **new seeds**, the face of each
region that its new proxy fits best. It stops when the partition no longer
changes, or after ``max_iter`` iterations.

Initialization:

- ``random``: ``k`` distinct faces drawn uniformly (``rng``);
- ``incremental``: one proxy on a random face; then, until there are ``k``,
  run ``insert_iter`` iterations and add a proxy on the worst face (largest
  distortion) of the region of largest total distortion (CSAD04, section
  3.5, "region insertion"). Proxies go where the surface is curved.

Every face-connected component of the mesh gets at least one proxy, so every
face is labelled; a mesh with more components than ``k`` gets more regions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..._kernels import native
from ...elements.faces import face_graph
from ...errors import ParameterError
from ...inputs.convert import as_mesh
from ...method.params import check_int, check_n_segments

__all__ = ["VSAResult", "variational_shape_approximation", "vsa", "METRICS", "INITS"]

#: Distortion metrics.
METRICS = ("l21", "l2")
#: Proxy initializations.
INITS = ("random", "incremental")


@dataclass(frozen=True, eq=False)
class VSAResult:
    """Result of :func:`variational_shape_approximation`.

    Attributes
    ----------
    labels : (m,) int64 ndarray
        Region of each face, dense ``0..K-1``.
    points : (K, 3) float64 ndarray
        ``X`` of each proxy (area centroid of its region), mesh units.
    normals : (K, 3) float64 ndarray
        Unit normal ``N`` of each proxy.
    seeds : (K,) int64 ndarray
        Seed face of each region for the next flooding.
    distortion : float
        Total distortion ``sum_T E(T, P(T))`` of the final partition against
        the final proxies: area units for L2,1, length^4 for L2.
    n_iter : int
        Iterations run after the initialization.
    converged : bool
        Whether the partition stopped changing before ``max_iter``.
    """

    labels: np.ndarray
    points: np.ndarray
    normals: np.ndarray
    seeds: np.ndarray
    distortion: float
    n_iter: int
    converged: bool


class _State:
    """Arrays of one VSA run; proxies grow in place up to ``capacity``."""

    def __init__(self, mesh, metric: int, capacity: int):
        g = face_graph(mesh)
        self.m = mesh.n_faces
        self.indptr = np.ascontiguousarray(g.indptr, dtype=np.int64)
        self.indices = np.ascontiguousarray(g.indices, dtype=np.int32)
        self.metric = metric
        self.areas = np.ascontiguousarray(mesh.areas)
        self.face_normals = np.ascontiguousarray(mesh.normals)
        self.centroids = np.ascontiguousarray(mesh.centroids)
        self.corners = np.ascontiguousarray(mesh.vertices[mesh.faces]) if metric == 1 \
            else np.zeros((1, 3, 3))
        self.X = np.zeros((capacity, 3))
        self.N = np.zeros((capacity, 3))
        self.seeds = np.zeros(capacity, dtype=np.int64)
        self.total = np.zeros(capacity)
        self.n = 0
        self.label = np.full(self.m, -1, dtype=np.int64)

    def add(self, face: int) -> None:
        """A proxy seeded at ``face``, fitted to that face alone."""
        p = self.n
        self.X[p] = self.centroids[face]
        self.N[p] = self.face_normals[face]
        self.seeds[p] = face
        self.n += 1

    def _proxies(self) -> tuple:
        """The arguments every VSA kernel takes after the labels (metric to ``N``)."""
        return (self.metric, self.areas, self.face_normals, self.centroids, self.corners,
                self.X, self.N)

    def step(self) -> bool:
        """Flood, fit, reseed; return True when the partition did not change."""

        old = self.label.copy()
        n = self.n
        native.kernel("baselines.vsa_partition")(
            self.indptr, self.indices, self.metric, self.areas, self.face_normals,
            self.corners, self.X, self.N, self.seeds, n, self.label)
        self.fit()
        native.kernel("baselines.vsa_assess")(self.label, n, *self._proxies(), self.seeds,
                                              self.total)
        return bool(np.array_equal(old, self.label))

    def fit(self) -> None:
        """Best proxy of each region (CSAD04, section 3.4), in place in ``X``, ``N``.

        L2,1: ``N`` = the normalized area-weighted mean normal. L2: ``N`` = the
        eigenvector of the smallest eigenvalue of the region's exact covariance
        (integrated over its triangles), turned like the mean normal. ``X`` = the area
        centroid in both cases. A region of zero area (or zero mean normal) keeps its
        previous proxy."""

        n = self.n
        area, nsum, csum = np.empty(n), np.empty((n, 3)), np.empty((n, 3))
        mom = np.empty((n, 3, 3))
        native.kernel("baselines.vsa_sums")(self.label, n, self.metric, self.areas,
                                            self.face_normals, self.centroids, self.corners,
                                            area, nsum, csum, mom)
        ok = area > 0.0
        X, N = self.X[:n], self.N[:n]
        X[ok] = csum[ok] / area[ok, None]
        if self.metric == 0:
            norm = np.sqrt(nsum[:, 0] ** 2 + nsum[:, 1] ** 2 + nsum[:, 2] ** 2)
            ok &= norm > 0.0
            N[ok] = nsum[ok] / norm[ok, None]
            return
        if not ok.any():
            return
        cov = mom[ok] - area[ok, None, None] * X[ok][:, :, None] * X[ok][:, None, :]
        v = np.linalg.eigh(cov)[1][:, :, 0]  # of the smallest eigenvalue
        sign = np.where(np.einsum("pi,pi->p", v, nsum[ok]) < 0.0, -1.0, 1.0)
        N[ok] = sign[:, None] * v  # (cosmetic: L2 ignores the sign)

    def insert(self) -> None:
        """Region insertion: a proxy on the worst non-seed face of the worst region."""

        n = self.n
        is_seed = np.zeros(self.m, dtype=np.bool_)
        is_seed[self.seeds[:n]] = True
        worst = np.empty(n, dtype=np.int64)
        native.kernel("baselines.vsa_worst_faces")(self.label, n, *self._proxies(),
                                                   self.seeds, is_seed, worst)
        totals = np.where(worst >= 0, self.total[:n], -np.inf)
        self.add(int(worst[int(np.argmax(totals))]))

    def snapshot(self) -> dict:
        n = self.n
        return {"n": n, "X": self.X[:n].copy(), "N": self.N[:n].copy(),
                "seeds": self.seeds[:n].copy(), "label": self.label.copy(),
                "total": self.total[:n].copy()}

    def restore(self, snap: dict) -> None:
        n = snap["n"]
        self.n = n
        self.X[:n] = snap["X"]
        self.N[:n] = snap["N"]
        self.seeds[:n] = snap["seeds"]
        self.label[:] = snap["label"]
        self.total[:n] = snap["total"]


def _component_seeds(mesh, chosen: np.ndarray) -> list[int]:
    """First face of every face-connected component holding no chosen face."""
    from scipy.sparse.csgraph import connected_components

    n_comp, comp = connected_components(face_graph(mesh).to_csr(), directed=False)
    if n_comp == 1:
        return []
    have = np.zeros(n_comp, dtype=bool)
    have[comp[chosen]] = True
    first = np.full(n_comp, -1, dtype=np.int64)
    order = np.arange(comp.shape[0])[::-1]
    first[comp[order]] = order  # smallest face index of each component wins
    return [int(first[c]) for c in range(n_comp) if not have[c]]


def variational_shape_approximation(mesh, n_segments: int = 150, *, metric: str = "l21",
                                    init: str = "random", max_iter: int = 30,
                                    insert_iter: int = 2, rng=None,
                                    cache: dict | None = None) -> VSAResult:
    """Partition a mesh into ``k`` planar-proxy regions (VSA, CSAD04).

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or tuple of ((n, 3) float, (m, 3) int) ndarray
    n_segments : int, default 150
        Number of proxies ``k``, ``1 <= k <= m``.
    metric : {'l21', 'l2'}, default 'l21'
        Distortion: normal deviation (L2,1) or squared distance to the plane (L2).
    init : {'random', 'incremental'}, default 'random'
        Proxy initialization (see the module notes).
    max_iter : int, default 30
        Maximum Lloyd iterations after the initialization, ``>= 1``.
    insert_iter : int, default 2
        Iterations between two insertions of the incremental initialization.
    rng : None, int or numpy.random.Generator
        Draws the random seeds (``random``) or the first seed (``incremental``).
    cache : dict, optional
        For ``incremental``: the state after each insertion phase is kept
        here and continued by a later call with a larger ``n_segments`` on
        the same mesh and options, with the same result as from scratch.

    Returns
    -------
    VSAResult

    Raises
    ------
    ParameterError
        If ``n_segments`` is not in ``1..m``, ``metric``/``init`` unknown,
        or ``max_iter``/``insert_iter`` not a valid count.
    InvalidMeshError, TypeError
        On a bad mesh.

    References
    ----------
    .. [1] D. Cohen-Steiner, P. Alliez, M. Desbrun, "Variational Shape
       Approximation", ACM Transactions on Graphics 23(3) (SIGGRAPH), 2004.

    Examples
    --------
    >>> from superfacets.evaluation.baselines import variational_shape_approximation
    >>> box = trimesh.creation.box().subdivide().subdivide()
    >>> r = variational_shape_approximation(box, 6, init="incremental", rng=0)
    >>> int(r.labels.max()) + 1, round(r.distortion, 9)
    (6, 0.0)
    """
    mesh = as_mesh(mesh)
    mesh.check_usable()
    if not mesh.is_triangular:
        raise ParameterError("VSA fits planes to triangles: give a triangle mesh (its L2 "
                             "metric integrates over triangles); superfacets take polygons")
    k = check_n_segments(n_segments, mesh.n_faces)
    if metric not in METRICS:
        raise ParameterError(f"metric must be one of {', '.join(METRICS)}; got {metric!r}")
    if init not in INITS:
        raise ParameterError(f"init must be one of {', '.join(INITS)}; got {init!r}")
    max_iter = check_int("max_iter", max_iter, 1)
    insert_iter = check_int("insert_iter", insert_iter, 0)
    gen = np.random.default_rng(rng)
    m = mesh.n_faces

    if init == "random":
        chosen = np.sort(gen.choice(m, size=k, replace=False)) if k < m else np.arange(m)
        extra = _component_seeds(mesh, chosen)
        st = _State(mesh, METRICS.index(metric), k + len(extra))
        for f in (*chosen.tolist(), *extra):
            st.add(f)
    else:
        first = int(gen.integers(m))
        extra = _component_seeds(mesh, np.array([first]))
        st = _State(mesh, METRICS.index(metric), k + len(extra))
        snap = None if cache is None else cache.get("vsa_incremental")
        if snap is not None and snap["first"] == first and snap["n"] <= k + len(extra):
            st.restore(snap)
        else:
            for f in (first, *extra):
                st.add(f)
            for _ in range(max(1, insert_iter)):
                if st.step():
                    break
        while st.n < k + len(extra):
            st.insert()
            for _ in range(insert_iter):
                if st.step():
                    break
        if cache is not None:
            cache["vsa_incremental"] = dict(st.snapshot(), first=first)

    converged = False
    it = 0
    while it < max_iter:
        it += 1
        if st.step():
            converged = True
            break

    n = st.n
    distortion = native.kernel("baselines.vsa_assess")(st.label, n, *st._proxies(),
                                                       st.seeds.copy(), st.total)
    used, labels = np.unique(st.label, return_inverse=True)
    return VSAResult(labels.astype(np.int64).ravel(), st.X[used].copy(), st.N[used].copy(),
                     st.seeds[used].copy(), float(distortion), it, converged)


def vsa(mesh, n_segments: int = 150, *, metric: str = "l21", init: str = "random",
        max_iter: int = 30, insert_iter: int = 2, rng=None) -> np.ndarray:
    """Labels of :func:`variational_shape_approximation` (same parameters).

    Returns
    -------
    labels : (m,) int64 ndarray
        Dense ``0..K-1``; each region is face-connected.

    Raises
    ------
    ParameterError, InvalidMeshError, TypeError
        As :func:`variational_shape_approximation`.
    """
    return variational_shape_approximation(mesh, n_segments, metric=metric, init=init,
                                           max_iter=max_iter, insert_iter=insert_iter,
                                           rng=rng).labels
