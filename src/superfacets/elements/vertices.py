"""The vertex graph of a mesh: one element per vertex, one adjacency per mesh edge.

Superpoints on mesh vertices (the elements of the ScanNet Segmentator and of
most scene-understanding pipelines). Each vertex stands for its barycentric
cell: a third of every incident triangle (``1/s`` of an ``s``-gon), so the
sizes add up to the surface area and ``k`` and ``radius`` keep their meaning.

- position: the vertex; size: its barycentric area; normal: the
  area-weighted mean of the incident face normals, made unit (zero where
  undefined);
- adjacency: every mesh edge (polygon edges join consecutive corners; an edge
  used by several faces, non-manifold included, counts once; collapsed edges
  join nothing);
- border length of an adjacency: the dual edge between the two cells (from
  the edge midpoint to the centroid of each incident face), so the
  compactness of a vertex segmentation is that of its cells on the surface;
  an open-boundary edge gives half its length to each end;
- weight terms (the paper's eqs. 1-3 in the vertex analogue): the geodesic
  term is the edge length ``|v_i - v_j|``; the angle is that of the vertex
  normals, the angular term scaled by the edge length (a path crossing a
  crease then pays about what the face graph charges: ``alpha |e| theta / pi``);
  the edge is concave when ``(n_i - n_j) . (v_i - v_j) < 0``, the symmetric
  test (on a sphere with outward normals it is ``|v_i - v_j|^2 / R > 0``: convex).

Vertices used by no face are not elements (they have no area and no
neighbour); :class:`VertexElements` maps the elements back to the vertices.
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import numpy as np

from .._kernels import native
from .._runtime.arrays import real_rows
from ..inputs.bounds import column_bounds
from .graph import ElementGraph, adjacency_csr, cached_on, pairs_from_csr

__all__ = ["vertex_graph", "VertexElements", "symmetric_terms"]

#: ``ElementGraph.rebuild`` of the vertex and point graphs: their pairs (int64) follow
#: from the CSR layout; the other fields are kept.
REBUILD_PAIRS = dict.fromkeys(("pairs", "dual_edge"), partial(pairs_from_csr, pair_dtype=np.int64))


class VertexElements(NamedTuple):
    """The vertex graph of a mesh and the vertex of each element.

    Attributes
    ----------
    graph : ElementGraph
        ``kind = "vertices"``, one element per referenced vertex.
    index : (n_vertices,) int64 ndarray
        Element of each mesh vertex, -1 for a vertex used by no face.
    """

    graph: ElementGraph
    index: np.ndarray


def symmetric_terms(graph: ElementGraph, sl: slice):
    """The weight terms of elements that are points with normals (vertices, cloud points),
    for the slice ``sl`` of ``graph.pairs`` (``terms_of`` of those graphs).

    Returns ``(geo, cos, concave)``: ``geo = |p_i - p_j|``, ``cos = n_i . n_j``
    (clipped), ``concave = (n_i - n_j) . (p_i - p_j) < 0``.
    """
    point_terms = native.kernel("geometry.point_terms")

    lo, hi = sl.indices(graph.pairs.shape[0])[:2]
    geo, cos = np.empty(hi - lo), np.empty(hi - lo)
    concave = np.empty(hi - lo, dtype=bool)
    point_terms(graph.positions, real_rows(graph.normals),
                graph.pairs, lo, hi, geo, cos, concave)  # (points keep float32 normals)
    return geo, cos, concave


def vertex_graph(mesh) -> VertexElements:
    """The vertex graph of a triangle or polygon mesh (see the module notes).

    Built on the first call and kept with the mesh (later calls return the
    same object).

    Parameters
    ----------
    mesh : Mesh

    Returns
    -------
    VertexElements
        The graph (``kind = "vertices"``) and the element of each vertex.

    Examples
    --------
    >>> box = trimesh.creation.box()
    >>> g = vertex_graph(Mesh(box.vertices, box.faces)).graph
    >>> g.n_elements, g.n_edges, round(g.area, 6)
    (8, 18, 6.0)
    """
    return cached_on(mesh, "_vertex_graph", lambda: _build_vertex_graph_of(mesh))


def _build_vertex_graph_of(mesh) -> VertexElements:
    mesh_edges = native.kernel("vertices.mesh_edges")
    vertex_cells = native.kernel("vertices.vertex_cells")

    n_v = mesh.n_vertices
    corners = np.asarray(mesh.corners)
    offsets = np.asarray(mesh.offsets)
    index = np.full(n_v, -1, dtype=np.int64)
    used = np.flatnonzero(mesh.referenced_vertices)
    index[used] = np.arange(used.shape[0])
    n = used.shape[0]
    pos = mesh.vertices[used]

    # per element: barycentric area and unit area-weighted normal
    area = np.empty(n)
    normal = np.empty((n, 3))
    vertex_cells(corners, offsets, index, mesh.areas, mesh.normals, area, normal)

    # mesh edges (element ids, lo < hi), once each; the dual length summed over their faces
    lo, hi, lengths, spans, uses = mesh_edges(corners, offsets, index, n, pos, mesh.centroids)
    pairs = np.stack([lo, hi], axis=1)
    indptr, indices, dual_edge = adjacency_csr(lo, hi, n)
    open_ = uses == 1  # an open-boundary edge: half of it to each end
    half_len = 0.5 * spans[open_]
    graph = ElementGraph(
        kind="vertices", positions=pos, sizes=area, normals=normal, centroid=mesh.centroid,
        lower=column_bounds(pos)[0], diagonal=mesh.diagonal, pairs=pairs, indptr=indptr,
        indices=indices, dual_edge=dual_edge, lengths=lengths,
        boundary_elements=np.concatenate([lo[open_], hi[open_]]),
        boundary_lengths=np.concatenate([half_len, half_len]), spans=spans,
        terms_of=symmetric_terms, rebuild=REBUILD_PAIRS)
    return VertexElements(graph, index)
