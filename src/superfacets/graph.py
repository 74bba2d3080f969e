"""Face graph (dual graph) and its edge weights (SPEC section 2, paper eqs. 1-3, 6).

The face graph has one node per face and one *dual edge* per pair of faces
that share a mesh edge. Adjacency comes from our own grouping of the mesh
edges by their (sorted) vertex pair, not from trimesh, because trimesh's
``face_adjacency`` drops non-manifold edges:

- an edge with one face is an open boundary and gives no dual edge;
- an edge with two faces gives one dual edge;
- a **non-manifold** edge with ``s >= 3`` faces joins *every* pair of its
  faces (``s (s - 1) / 2`` dual edges), so no face is cut off;
- a collapsed edge (both ends the same vertex, in a degenerate face) joins
  nothing;
- two faces sharing more than one edge (duplicate faces) get a single dual
  edge, through the shared edge with the smallest vertex pair.

The graph is stored once per mesh, as the list of dual edges and a symmetric
CSR structure (``indptr``, ``indices``, and ``dual_edge``: the dual edge of
each CSR entry), so any weighting is a per-dual-edge array mapped onto CSR
with ``weights[graph.dual_edge]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import ParameterError

__all__ = ["FaceGraph", "paper_weights", "shlafman_weights", "edge_weights"]


@dataclass(frozen=True, eq=False)
class FaceGraph:
    """Face adjacency of a triangle mesh.

    Attributes
    ----------
    n_faces : int
        Number of faces ``m`` (nodes).
    pairs : (e, 2) int64 ndarray
        The two faces ``(i, j)``, ``i < j``, of each dual edge, sorted.
    edges : (e, 2) int64 ndarray
        The shared mesh edge ``(a, b)``, ``a < b`` (vertex indices), of each
        dual edge.
    indptr : (m + 1,) int64 ndarray
        CSR row pointers: neighbours of face ``f`` are
        ``indices[indptr[f]:indptr[f + 1]]``.
    indices : (2 e,) int32 ndarray
        CSR column indices (neighbour faces), ascending within a row.
    dual_edge : (2 e,) int64 ndarray
        Index into ``pairs`` of each CSR entry.
    boundary_edges : (b, 2) int64 ndarray
        Mesh edges used by exactly one face (open boundary), ``a < b``.
    boundary_faces : (b,) int64 ndarray
        The face of each boundary edge.
    """

    n_faces: int
    pairs: np.ndarray
    edges: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray
    dual_edge: np.ndarray
    boundary_edges: np.ndarray
    boundary_faces: np.ndarray

    @property
    def n_edges(self) -> int:
        """Number of dual edges ``e``."""
        return int(self.pairs.shape[0])

    @classmethod
    def from_mesh(cls, mesh) -> "FaceGraph":
        """Build the face graph of a :class:`~superfacets.mesh.Mesh`."""
        return build_face_graph(mesh.faces, mesh.n_vertices)

    def to_csr(self, weights: np.ndarray | None = None):
        """Return the graph as a symmetric ``scipy.sparse.csr_array``.

        Parameters
        ----------
        weights : (e,) float ndarray, optional
            Per-dual-edge weights; 1 when omitted.
        """
        from scipy.sparse import csr_array

        data = np.ones(self.indices.shape[0]) if weights is None else weights[self.dual_edge]
        return csr_array((data, self.indices, self.indptr), shape=(self.n_faces, self.n_faces))


def build_face_graph(faces: np.ndarray, n_vertices: int) -> FaceGraph:
    """Group mesh edges and build the face graph (see the module notes).

    Parameters
    ----------
    faces : (m, 3) int64 ndarray
        Triangles, indices in ``[0, n_vertices)``.
    n_vertices : int
        Number of vertices.

    Returns
    -------
    FaceGraph
    """
    m = faces.shape[0]
    # 32-bit half-edge and vertex ids while they fit: the temporaries of the edge grouping
    # are the memory peak of a whole run on large meshes
    itype = np.int32 if max(int(n_vertices), 3 * m) < 2**31 - 1 else np.int64
    a = np.empty(3 * m, dtype=itype)  # half-edge h = 3 * face + corner, corner c joins
    b = np.empty(3 * m, dtype=itype)  # vertices (0, 1), (1, 2), (2, 0) of the face
    for c, (u, v) in enumerate(((0, 1), (1, 2), (2, 0))):
        np.minimum(faces[:, u], faces[:, v], out=a[c::3], casting="unsafe")
        np.maximum(faces[:, u], faces[:, v], out=b[c::3], casting="unsafe")
    valid = np.flatnonzero(a != b).astype(itype)  # collapsed edges join nothing
    key = a[valid].astype(np.int64)
    key *= np.int64(n_vertices)
    key += b[valid]
    order = np.argsort(key, kind="stable")
    skey = key[order]
    del key
    half = valid[order]  # half-edge ids, grouped by edge
    del valid, order
    sface = half // 3
    n_half = skey.shape[0]
    if n_half:
        brk = np.empty(n_half, dtype=bool)
        brk[0] = True
        np.not_equal(skey[1:], skey[:-1], out=brk[1:])
        starts = np.flatnonzero(brk)
        del brk
    else:
        starts = np.zeros(0, np.int64)
    del skey
    sizes = np.diff(np.r_[starts, n_half])

    # boundary edges: groups of size 1
    one = starts[sizes == 1]
    boundary_faces = sface[one].astype(np.int64)
    boundary_edges = np.stack([a[half[one]], b[half[one]]], axis=1).astype(np.int64)
    del one

    # pairs within every group of size >= 2 (all pairs for non-manifold edges)
    pi, pj, pe = [], [], []
    for s in np.unique(sizes[sizes >= 2]):
        st = starts[sizes == s]
        ii, jj = np.triu_indices(int(s), 1)
        pi.append(sface[st[:, None] + ii[None, :]].ravel())
        pj.append(sface[st[:, None] + jj[None, :]].ravel())
        pe.append(np.repeat(half[st], ii.size))
    del starts, sizes, sface, half
    if pi:
        fi = np.concatenate(pi)
        fj = np.concatenate(pj)
        he = np.concatenate(pe)
    else:
        fi = fj = he = np.zeros(0, itype)
    del pi, pj, pe
    lo = np.minimum(fi, fj)
    hi = np.maximum(fi, fj)
    del fi, fj
    keep = lo != hi  # a degenerate face sharing an edge with itself
    if not keep.all():
        lo, hi, he = lo[keep], hi[keep], he[keep]
    del keep
    # one dual edge per face pair: the first in edge-key order (smallest vertex pair)
    pkey = lo.astype(np.int64) * np.int64(m) + hi
    ekey = a[he].astype(np.int64) * np.int64(n_vertices) + b[he]
    o = np.lexsort((ekey, pkey))
    del ekey
    pkey, lo, hi, he = pkey[o], lo[o], hi[o], he[o]
    del o
    first = np.r_[True, pkey[1:] != pkey[:-1]] if pkey.size else np.zeros(0, bool)
    del pkey
    if not first.all():
        lo, hi, he = lo[first], hi[first], he[first]
    del first
    pairs = np.stack([lo, hi], axis=1).astype(np.int64)
    edges = np.stack([a[he], b[he]], axis=1).astype(np.int64)
    del a, b, he

    # symmetric CSR, neighbours ascending within each row
    e = pairs.shape[0]
    rows = np.concatenate([lo, hi])
    cols = np.concatenate([hi, lo])
    del lo, hi
    o = np.lexsort((cols, rows))
    indptr = np.zeros(m + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=m), out=indptr[1:])
    del rows
    indices = np.ascontiguousarray(cols[o], dtype=np.int32)
    del cols
    dual_edge = o.astype(np.int64)
    dual_edge[dual_edge >= e] -= e  # entry t of [lo->hi, hi->lo] is dual edge t mod e
    del o
    return FaceGraph(
        n_faces=m,
        pairs=pairs,
        edges=edges,
        indptr=indptr,
        indices=indices,
        dual_edge=dual_edge,
        boundary_edges=boundary_edges,
        boundary_faces=boundary_faces,
    )


_CHUNK = 1 << 18  # dual edges per chunk: bounds the temporaries of the weights


def _chunked(graph: FaceGraph, weight) -> np.ndarray:
    """``weight(sl)`` for consecutive slices of the dual edges, into one array."""
    e = graph.n_edges
    out = np.empty(e, dtype=np.float64)
    for s in range(0, e, _CHUNK):
        sl = slice(s, min(e, s + _CHUNK))
        out[sl] = weight(sl)
    return out


def _edge_terms(mesh, graph: FaceGraph, sl: slice = slice(None)):
    """Per dual edge (of slice ``sl``): geodesic term, cos of dihedral angle, concavity,
    edge length."""
    v = mesh.vertices
    c = mesh.centroids
    n = mesh.normals
    pairs, edges = graph.pairs[sl], graph.edges[sl]
    i, j = pairs[:, 0], pairs[:, 1]
    pa, pb = v[edges[:, 0]], v[edges[:, 1]]
    mid = 0.5 * (pa + pb)
    length = np.linalg.norm(pb - pa, axis=1)
    geo = np.linalg.norm(c[i] - mid, axis=1) + np.linalg.norm(mid - c[j], axis=1)
    cos = np.clip(np.einsum("ij,ij->i", n[i], n[j]), -1.0, 1.0)
    concave = np.einsum("ij,ij->i", n[i], c[j] - c[i]) > 0
    return geo, cos, concave, length


def _check_nonneg(name: str, value) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number, got {value!r}") from None
    if not np.isfinite(x) or x < 0:
        raise ParameterError(f"{name} must be a finite number >= 0, got {value!r}")
    return x


def paper_weights(mesh, graph: FaceGraph | None = None, *, alpha: float = 200.0,
                  eta_convex: float = 0.2) -> np.ndarray:
    """Edge weights of the paper (Simari et al. 2014, eqs. 1-3).

    For adjacent faces ``f_i, f_j`` with centroids ``c_i, c_j``, unit normals
    ``n_i, n_j``, shared edge ``e_ij`` of midpoint ``m_ij``:

    - ``geo = |c_i - m_ij| + |m_ij - c_j|`` (eq. 1);
    - ``theta = arccos(n_i . n_j)`` in ``[0, pi]``, the unsigned dihedral angle;
    - ``ang = eta * |e_ij| * theta / pi`` (eq. 2), with ``eta = 1`` on concave
      edges and ``eta_convex`` on convex ones; an edge is concave when
      ``n_i . (c_j - c_i) > 0`` (authors' implementation), ``i < j``;
    - ``w = (geo + alpha * ang) / d`` (eq. 3), ``d`` the bounding-box diagonal.

    Parameters
    ----------
    mesh : Mesh
        The mesh (its cached centroids, normals and diagonal are used).
    graph : FaceGraph, optional
        Precomputed face graph; ``mesh.graph`` when omitted.
    alpha : float, default 200
        Weight of the angular term, ``>= 0``.
    eta_convex : float, default 0.2
        Factor ``eta`` of convex edges, ``>= 0``.

    Returns
    -------
    weights : (e,) float64 ndarray
        One weight per dual edge (``graph.pairs`` order), unitless
        (fractions of ``d``), ``>= 0``. Invariant to uniform scaling and
        rigid motion of the mesh.

    Raises
    ------
    ParameterError
        If ``alpha`` or ``eta_convex`` is negative, NaN or infinite.
    """
    alpha = _check_nonneg("alpha", alpha)
    eta_convex = _check_nonneg("eta_convex", eta_convex)
    graph = mesh.graph if graph is None else graph

    def weight(sl):
        geo, cos, concave, length = _edge_terms(mesh, graph, sl)
        theta = np.arccos(cos)
        eta = np.where(concave, 1.0, eta_convex)
        ang = eta * length * theta / np.pi
        return (geo + alpha * ang) / mesh.diagonal

    return _chunked(graph, weight)


def shlafman_weights(mesh, graph: FaceGraph | None = None, *, alpha: float = 0.5) -> np.ndarray:
    """Edge weights of Shlafman, Tal and Katz, as written in the paper (eq. 6).

    ``w' = (1 - alpha) * geo + alpha * (1 - (n_i . n_j)^2)``, with ``geo`` of
    eq. 1. The roles of ``alpha`` and ``1 - alpha`` are swapped with respect
    to Shlafman et al. so that a higher ``alpha`` favours the angular term, as
    in the paper. Not scale invariant and blind to the concave/convex
    distinction: that is the point of the paper's comparison (Fig. 6).

    Parameters
    ----------
    mesh : Mesh
    graph : FaceGraph, optional
    alpha : float, default 0.5
        In ``[0, 1]``.

    Returns
    -------
    weights : (e,) float64 ndarray
        One weight per dual edge, in mesh units for the geodesic part.

    Raises
    ------
    ParameterError
        If ``alpha`` is outside ``[0, 1]``.
    """
    a = _check_nonneg("alpha", alpha)
    if a > 1:
        raise ParameterError(f"alpha of the Shlafman weighting must be in [0, 1], got {alpha!r}")
    graph = mesh.graph if graph is None else graph

    def weight(sl):
        geo, cos, _, _ = _edge_terms(mesh, graph, sl)
        return (1.0 - a) * geo + a * (1.0 - cos * cos)

    return _chunked(graph, weight)


def edge_weights(mesh, weighting: str = "paper", *, alpha: float = 200.0,
                 eta_convex: float = 0.2) -> np.ndarray:
    """Dispatch to :func:`paper_weights` or :func:`shlafman_weights` by name.

    Raises
    ------
    ParameterError
        If ``weighting`` is not ``"paper"`` or ``"shlafman"``.
    """
    if weighting == "paper":
        return paper_weights(mesh, alpha=alpha, eta_convex=eta_convex)
    if weighting == "shlafman":
        return shlafman_weights(mesh, alpha=alpha)
    raise ParameterError(f"weighting must be 'paper' or 'shlafman', got {weighting!r}")
