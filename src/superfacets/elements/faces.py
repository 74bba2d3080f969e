"""The face graph (dual graph) of a mesh (``docs/notes/method.md``, sections 1-2).

One element per face (triangle or polygon) and one adjacency per pair of
faces that share a mesh edge (an edge of a polygon joins two consecutive
corners). Adjacency comes from our own grouping of the mesh edges by their
(sorted) vertex pair, not from trimesh, because trimesh's ``face_adjacency``
drops non-manifold edges:

- an edge with one face is an open boundary and gives no adjacency;
- an edge with two faces gives one adjacency;
- a **non-manifold** edge with ``3 <= s <= 8`` faces joins *every* pair of its
  faces (``s (s - 1) / 2`` adjacencies), so no face is cut off; beyond 8 (a fan of
  copies, a "book" of faces on one edge), each face is joined to the next around the
  edge and the last to the first (``s`` adjacencies: work in proportion to the faces);
- a collapsed edge (both ends the same vertex, in a degenerate face) joins
  nothing;
- two faces sharing more than one edge (duplicate faces) get a single
  adjacency, through the shared edge with the smallest vertex pair.
"""

from __future__ import annotations

import weakref
from functools import partial
from typing import NamedTuple

import numpy as np

from .._kernels import native
from .._runtime import memory, threads
from .._runtime.threads import split
from ..errors import MemoryLimitError
from ..inputs.mesh import Mesh
from . import graph as _graph
from .graph import ElementGraph, cached_on, pairs_from_csr
from .kinds import kind_of

__all__ = ["FaceAdjacency", "build_face_graph", "distinct_faces", "face_adjacency",
           "face_graph", "face_graph_from"]


class FaceAdjacency(NamedTuple):
    """Topology of the face graph (see :func:`build_face_graph`).

    Attributes
    ----------
    pairs : (e, 2) int32 ndarray (int64 from 2**31 faces on)
        The two faces ``(i, j)``, ``i < j``, of each adjacency, sorted.
    edges : (e, 2) int32 ndarray (int64 from 2**31 vertices or half-edges on)
        The shared mesh edge ``(a, b)``, ``a < b``, of each adjacency.
    indptr : (m + 1,) int64 ndarray
    indices : (2 e,) int32 ndarray
    dual_edge : (2 e,) int32 ndarray (int64 beyond 2**31 entries)
    boundary_edges : (b, 2) int64 ndarray
        Mesh edges used by exactly one face, ``a < b``.
    boundary_faces : (b,) int64 ndarray
        The face of each boundary edge.
    repeated : int
        Face pairs that share more than one edge (kept once): two triangles sharing two
        edges have the same three vertices, duplicates (:func:`distinct_faces`).
    """

    pairs: np.ndarray
    edges: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray
    dual_edge: np.ndarray
    boundary_edges: np.ndarray
    boundary_faces: np.ndarray
    repeated: int = 0


def face_graph(mesh) -> ElementGraph:
    """The face graph of a triangle or polygon mesh, with its geometry.

    Elements are faces (triangles or polygons): position = centroid, size =
    area, normal = unit face normal (:class:`~superfacets.inputs.mesh.Mesh`'s cached geometry,
    shared,
    not copied). Per adjacency: the length of the shared mesh edge, and the
    terms of the paper's weights (eqs. 1-3) from the edge midpoint ``m_ij``:
    ``geo = |c_i - m_ij| + |m_ij - c_j|``, the cosine of the dihedral angle
    and the concavity ``n_i . (c_j - c_i) > 0``.

    The graph is built on the first call and kept with the mesh: later calls
    on the same :class:`~superfacets.inputs.mesh.Mesh` (segmenting it again with
    other parameters, the metrics, the pictures) return the same object.

    Parameters
    ----------
    mesh : Mesh

    Returns
    -------
    ElementGraph
        ``kind = "faces"``; ``edges`` and ``boundary_edges`` hold mesh edges.

    Raises
    ------
    TypeError
        If ``mesh`` is not a :class:`~superfacets.inputs.mesh.Mesh` (use
        :func:`superfacets.as_mesh`, or :func:`superfacets.elements.as_element_graph`).

    Examples
    --------
    >>> box = trimesh.creation.box()
    >>> g = face_graph(Mesh(box.vertices, box.faces))
    >>> g.n_elements, g.n_edges
    (12, 18)
    """
    if not all(hasattr(mesh, a) for a in ("faces", "n_vertices", "is_triangular")):
        raise TypeError(f"face_graph needs a superfacets.Mesh, got {type(mesh).__name__} "
                        "(superfacets.as_mesh converts trimesh, Open3D and (V, F) pairs)")
    return cached_on(mesh, "_face_graph", lambda: _build_face_graph_of(mesh))


def face_adjacency(mesh) -> FaceAdjacency:
    """The topology of a mesh's face graph (:func:`build_face_graph` of its faces); a
    tiled run keeps it for a tile's later phases (:func:`face_graph_from`)."""
    return (build_face_graph(mesh.faces, mesh.n_vertices) if mesh.is_triangular else
            build_face_graph(np.asarray(mesh.corners), mesh.n_vertices, np.asarray(mesh.offsets)))


def face_graph_from(mesh, topo: FaceAdjacency) -> ElementGraph:
    """The face graph of ``mesh`` (as :func:`face_graph`, kept with the mesh) from its
    topology ``topo``, given: :func:`face_adjacency` of the same faces, made before (a
    tile's box, read again by a tiled run's later phases). A graph the mesh already keeps
    is returned as it is.

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=2)
    >>> m = Mesh(ball.vertices, ball.faces)
    >>> g = face_graph_from(m, face_adjacency(Mesh(ball.vertices, ball.faces)))
    >>> g is face_graph(m), g.n_edges
    (True, 480)
    """
    return cached_on(mesh, "_face_graph", lambda: _build_face_graph_of(mesh, topo))


def _build_face_graph_of(mesh, topo: FaceAdjacency | None = None) -> ElementGraph:
    topo = face_adjacency(mesh) if topo is None else topo
    mesh.__dict__["_repeated_face_pairs"] = topo.repeated  # (for distinct_faces)
    v = mesh.vertices

    def edge_length(edges):  # |v_b - v_a| as np.linalg.norm(axis=1), in one kernel pass
        edge_lengths = native.kernel("geometry.edge_lengths")

        out = np.empty(edges.shape[0])
        edge_lengths(v, edges, out)
        return out

    def terms_of(g: ElementGraph, sl: slice):
        # one pass of a kernel; the same operations as the numpy expressions
        #   mid = 0.5 * (v[a] + v[b]); geo = |c_i - mid| + |mid - c_j|,
        #   cos = clip(n_i . n_j, -1, 1), concave = n_i . (c_j - c_i) > 0
        face_terms = native.kernel("geometry.face_terms")

        pairs = g.pairs
        lo, hi = sl.indices(pairs.shape[0])[:2]
        geo, cos = np.empty(hi - lo), np.empty(hi - lo)
        concave = np.empty(hi - lo, dtype=bool)
        face_terms(v, g.positions, g.normals, pairs, g.edges, lo, hi, geo, cos, concave)
        return geo, cos, concave

    csr_pairs = partial(pairs_from_csr, pair_dtype=topo.pairs.dtype)
    rebuild = {"normals": _MeshNormals(mesh), "pairs": csr_pairs, "dual_edge": csr_pairs,
               "lengths": lambda g: {"lengths": edge_length(g.edges)}}
    if _SharedEdges.fits(mesh, topo):
        rebuild["edges"] = _SharedEdges(mesh, topo.edges.dtype)
    return ElementGraph(
        kind="faces", positions=mesh.centroids, sizes=mesh.areas, normals=mesh.normals,
        centroid=mesh.centroid, lower=mesh._bounds[0].copy(), diagonal=mesh.diagonal,
        pairs=topo.pairs, indptr=topo.indptr, indices=topo.indices, dual_edge=topo.dual_edge,
        lengths=edge_length(topo.edges),
        boundary_elements=topo.boundary_faces,
        boundary_lengths=edge_length(topo.boundary_edges),
        edges=topo.edges, boundary_edges=topo.boundary_edges, terms_of=terms_of,
        rebuild=rebuild)


def distinct_faces(mesh) -> tuple[np.ndarray, np.ndarray] | None:
    """The first of each set of duplicate faces (the same vertices, in any order or
    orientation), and the distinct face of every face; None where every face is distinct.

    A segmentation takes each distinct face once (:func:`superfacets.segment`): copies of
    a face share its element, and so its label. Found from the face graph (cached with the
    mesh): only where two faces share more than one edge are the faces compared, so a
    mesh without duplicates costs nothing more.

    Parameters
    ----------
    mesh : Mesh

    Returns
    -------
    (first, index) : ((d,) int64 ndarray, (m,) int64 ndarray), or None
        ``first``: the distinct faces, by their first copy, ascending; ``index[f]``: the
        row of ``first`` that face ``f`` is a copy of (``first[index[f]]`` has its
        vertices).

    Examples
    --------
    >>> m = Mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2], [2, 1, 0]])
    >>> first, index = distinct_faces(m)
    >>> first.tolist(), index.tolist()
    ([0, 1], [0, 1, 0])
    """
    face_graph(mesh)  # (built once: it counts the faces sharing more than one edge)
    if not mesh.__dict__.get("_repeated_face_pairs", 0):
        return None
    _, first, inverse = np.unique(np.sort(mesh.faces, axis=1), axis=0, return_index=True,
                                  return_inverse=True)
    if first.shape[0] == mesh.n_faces:
        return None
    order = np.argsort(first, kind="stable")  # the distinct faces in the input's order
    rank = np.empty_like(order)
    rank[order] = np.arange(order.shape[0])
    return first[order].astype(np.int64), rank[inverse.ravel()].astype(np.int64)


class _SharedEdges:
    """``rebuild["edges"]`` of a triangle mesh's face graph: the edge each pair of faces
    shares, from the faces' vertices (``adjacency.shared_edges``: the two distinct
    vertices both triangles have), the same as built.

    Only where that is so (:meth:`fits`): a triangle mesh whose face pairs share exactly
    their one edge (no duplicate faces), checked once against the edges as built (about
    0.07 s on 6.8M faces). Polygons keep their edges (two polygons may share more than
    one edge, or corners that are not an edge).
    """

    def __init__(self, mesh, dtype) -> None:
        self.faces, self.dtype = mesh.faces, dtype

    @staticmethod
    def fits(mesh, topo: FaceAdjacency) -> bool:
        """Whether the edges made again from the faces are the built ones."""
        if not mesh.is_triangular or topo.repeated:
            return False
        shared_edges = native.kernel("adjacency.shared_edges")
        faces = np.ascontiguousarray(mesh.faces)
        return shared_edges(faces, topo.pairs, topo.edges, True) == 0

    def __call__(self, graph: ElementGraph) -> dict[str, np.ndarray]:
        shared_edges = native.kernel("adjacency.shared_edges")
        pairs = graph.pairs
        edges = np.empty(pairs.shape, dtype=self.dtype)
        if shared_edges(np.ascontiguousarray(self.faces), pairs, edges, False):
            raise RuntimeError("the face pairs no longer share one edge each")  # (a defect)
        return {"edges": edges}


class _MeshNormals:
    """``rebuild["normals"]`` of a face graph: the normals its mesh caches.

    The mesh is held by a weak reference (it holds the graph); once it is
    gone, a new :class:`~superfacets.inputs.mesh.Mesh` of the same arrays computes
    them, the same. :meth:`release` makes the mesh forget its copy too.
    """

    def __init__(self, mesh):
        self.mesh = weakref.ref(mesh)
        self.vertices, self.faces = mesh.vertices, mesh.faces

    def __call__(self, graph: ElementGraph) -> dict[str, np.ndarray]:
        mesh = self.mesh()
        if mesh is None:
            mesh = Mesh(self.vertices, self.faces)
        return {"normals": mesh.normals}

    def release(self) -> None:
        mesh = self.mesh()
        if mesh is not None:
            mesh._release_normals()


def order_by_two_keys(key1: np.ndarray, key2: np.ndarray, n_key1: int,
                      skip: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Indices ``t`` (where ``skip[t]`` is False) ordered by ``(key1[t], key2[t], t)``.

    ``key1`` in ``0..n_key1-1``. The same as a stable ``np.argsort`` of
    ``key1 * K + key2`` over the kept entries: a stable counting sort on
    ``key1`` (ranges of ``t`` counted and scattered on threads, each range
    after the ones before it), then each bucket sorted on ``key2`` (ranges of
    buckets on threads), so the order is the same for any number of threads.

    Returns
    -------
    order : (n_kept,) ndarray of ``key1``'s dtype (which must hold ``len(key1)``)
    starts : (n_key1 + 1,) int64 ndarray
        Entries with ``key1 == v`` are ``order[starts[v]:starts[v + 1]]``.
    """
    count_keys = native.kernel("adjacency.count_keys")
    scatter_keys = native.kernel("adjacency.scatter_keys")
    sort_buckets = native.kernel("adjacency.sort_buckets")

    bounds = split(key1.shape[0])
    part = {a: i for i, a in enumerate(bounds[:-1])}
    counts = np.zeros((len(bounds) - 1, n_key1), dtype=np.int64)
    threads.run_ranges(lambda a, b: count_keys(key1, skip, a, b, counts[part[a]]), bounds)
    starts = np.zeros(n_key1 + 1, dtype=np.int64)
    np.cumsum(counts.sum(axis=0), out=starts[1:])
    fill = starts[:-1].copy()
    for i in range(counts.shape[0]):  # range i starts after ranges 0..i-1 in every bucket
        fill, counts[i] = fill + counts[i], fill
    order = np.empty(int(starts[-1]), dtype=key1.dtype)  # indices below n: key1's width
    threads.run_ranges(lambda a, b: scatter_keys(key1, skip, a, b, counts[part[a]], order), bounds)
    threads.run_ranges(lambda v0, v1: sort_buckets(order, starts, key2, v0, v1), split(n_key1))
    return order, starts


def _group_pairs_on_threads(group_pairs, half, owner, a, b):
    """``group_pairs`` (the compiled kernel cuts ``half`` into ranges of whole edges on
    threads itself); int32 half-edge and vertex ids only: a mesh of 2**31 half-edges or
    more is refused in one line."""
    if half.dtype != np.int32 or a.dtype != np.int32:
        raise MemoryLimitError(
            f"{half.shape[0]:,} half-edges: one run takes meshes of fewer than 2**31 "
            "half-edges (about 715M triangles); cut larger ones into tiles (--tiles)")
    return group_pairs(half, owner, a, b)


#: Memory of each face pair of the graph beyond a manifold mesh's 1.5 a face: its two CSR
#: entries, adjacency number, pair, edge, weights and terms, bytes
_PAIR_BYTES = 100


def _check_pairs(m: int, n_pairs: int) -> None:
    """Refuse, before the graph is built, a mesh whose edges shared by more than two faces
    make far more face pairs than its faces (a manifold mesh has 1.5 a face): the memory
    check counts them (:func:`superfacets._runtime.memory.check_memory`); tiles cannot
    help (the pairs of one edge are in one tile)."""
    extra = n_pairs - 3 * m // 2
    if extra > m // 2:
        per_face = kind_of("faces").peak_bytes + -(-extra * _PAIR_BYTES // max(m, 1))
        memory.check_memory(m, per_face, f"{m:,} faces with {n_pairs:,} face pairs (edges of "
                     "more than two faces)")


def build_face_graph(faces: np.ndarray, n_vertices: int, offsets: np.ndarray | None = None
                     ) -> FaceAdjacency:
    """Group mesh edges and build the face graph (see the module notes).

    Parameters
    ----------
    faces : (m, 3) int64 ndarray, or (c,) int64 ndarray with ``offsets``
        Triangles; or the corners of polygons of any sizes, face after face.
    n_vertices : int
        Number of vertices.
    offsets : (m + 1,) int64 ndarray, optional
        With polygons: face ``f`` has the corners ``faces[offsets[f]:offsets[f + 1]]``,
        and its edges join consecutive corners, the last to the first.

    Returns
    -------
    FaceAdjacency
    """
    csr_of_face_pairs = native.kernel("adjacency.csr_of_face_pairs")
    group_pairs = native.kernel("adjacency.group_pairs")
    triangle_half_edges = native.kernel("adjacency.triangle_half_edges")

    if offsets is None:  # triangles: half-edge h = 3 * face + corner
        m = faces.shape[0]
        n_half_edges = 3 * m
    else:
        m = offsets.shape[0] - 1
        n_half_edges = faces.shape[0]
    # 32-bit half-edge and vertex ids while they fit: the temporaries of the edge grouping
    # are the memory peak of a whole run on large meshes
    itype = np.int32 if max(int(n_vertices), n_half_edges) < 2**31 - 1 else np.int64
    a = np.empty(n_half_edges, dtype=itype)  # the two vertices of each half-edge, a <= b
    b = np.empty(n_half_edges, dtype=itype)
    if offsets is None:  # corner c joins vertices (0, 1), (1, 2), (2, 0) of the face
        collapsed = np.empty(n_half_edges, dtype=bool)
        triangle_half_edges(faces, a, b, collapsed)
        owner = np.empty(0, dtype=itype)  # the face of h is h // 3
    else:  # corner i of a polygon joins it to the next corner, the last to the first
        nxt = np.roll(faces, -1)
        nxt[offsets[1:] - 1] = faces[offsets[:-1]]
        np.minimum(faces, nxt, out=a, casting="unsafe")
        np.maximum(faces, nxt, out=b, casting="unsafe")
        del nxt
        collapsed = a == b
        owner = np.repeat(np.arange(m, dtype=itype), np.diff(offsets))
    # half-edges grouped by edge, in (a, b) order, collapsed edges (a == b) left out:
    # a counting sort on a, then b within each vertex's few half-edges
    half, _ = order_by_two_keys(a, b, int(n_vertices), collapsed)
    del collapsed
    # edges (runs of equal (a, b)): open boundaries, and the face pairs across each,
    # all pairs for non-manifold edges, a degenerate face paired with itself left out
    one, lo, hi, ea, eb = _group_pairs_on_threads(group_pairs, half, owner, a, b)
    _check_pairs(m, lo.shape[0])
    h_one = half[one]
    boundary_faces = (h_one // 3 if offsets is None else owner[h_one]).astype(np.int64)
    boundary_edges = np.stack([a[h_one], b[h_one]], axis=1).astype(np.int64)
    del one, h_one, half, a, b, owner
    # one dual edge per face pair: the first in edge order (smallest vertex pair);
    # pairs in (lo, hi) order and their CSR, in one counting sort
    n_max = 2 * lo.shape[0]
    indices = np.empty(n_max, dtype=np.int32)
    dual_edge = np.empty(n_max, dtype=_graph.adjacency_dtype(n_max))
    indptr, first = csr_of_face_pairs(lo, hi, ea, eb, m, indices, dual_edge)
    n_csr = 2 * first.shape[0]
    if n_csr < n_max:  # repeated pairs dropped: shrink to fit
        indices = indices[:n_csr].copy()
        dual_edge = dual_edge[:n_csr].astype(_graph.adjacency_dtype(n_csr))
    # 32-bit while the ids fit (24 bytes per face less, kept for the whole run)
    pairs = np.empty((first.shape[0], 2), dtype=np.int32 if m < 2**31 - 1 else np.int64)
    edges = np.empty((first.shape[0], 2), dtype=ea.dtype)
    native.kernel("adjacency.take_pairs")(first, lo, hi, ea, eb, pairs, edges)
    del lo, hi, ea, eb, first
    return FaceAdjacency(
        pairs=pairs,
        edges=edges,
        indptr=indptr,
        indices=indices,
        dual_edge=dual_edge,
        boundary_edges=boundary_edges,
        boundary_faces=boundary_faces,
        repeated=(n_max - n_csr) // 2,
    )
