"""From what the user gives to the element graph the method runs on.

:func:`elements_of` is the one place that decides what the elements of an
input are: the faces of a mesh (the paper), its vertices, or the points of a
cloud. It validates the input, builds (or takes from the input's cache) the
graph, and keeps the map from elements back to the input's rows, so labels
come back one per face, vertex or point, in input order.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .graph import ElementGraph

__all__ = ["ElementInput", "as_element_graph", "elements_of", "is_cloud"]


class ElementInput(NamedTuple):
    """An input ready for the method.

    Attributes
    ----------
    graph : ElementGraph
    index : (N,) int64 ndarray or None
        Element of each input row (vertex or point), -1 for rows that are not
        elements (vertices used by no face, invalid points); None when the
        elements are the rows themselves (faces).
    source : Mesh or PointCloud
        The validated input.
    """

    graph: ElementGraph
    index: np.ndarray | None
    source: object

    @property
    def n_rows(self) -> int:
        """Number of labels to return (faces, vertices or points of the input)."""
        return self.graph.n_elements if self.index is None else int(self.index.shape[0])

    def to_rows(self, labels: np.ndarray) -> np.ndarray:
        """Per-element values -> per-row values (-1 for rows that are not elements)."""
        if self.index is None:
            return labels
        out = np.full(self.index.shape[0], -1, dtype=labels.dtype)
        ok = self.index >= 0
        out[ok] = labels[self.index[ok]]
        return out

    def colors(self) -> np.ndarray | None:
        """(N, 3) float64: the RGB of each input row (face, vertex or point) in ``[0, 1]``,
        None where the input has no colours (:meth:`superfacets.mesh.Mesh.element_colors`)."""
        if hasattr(self.source, "element_colors"):
            return self.source.element_colors("faces" if self.index is None else "vertices")
        return getattr(self.source, "colors", None)

    def first_rows(self, elements: np.ndarray) -> np.ndarray:
        """The first input row of each of ``elements`` (the row a center stands for)."""
        if self.index is None:
            return elements
        rows = np.flatnonzero(self.index >= 0)
        first = np.full(self.graph.n_elements, -1, dtype=np.int64)
        first[self.index[rows][::-1]] = rows[::-1]
        return first[elements]


def is_cloud(obj) -> bool:
    """Whether ``obj`` is a point cloud (a PointCloud, a bare (N, 3) or (H, W, 3) array,
    a trimesh or Open3D point cloud) rather than a mesh."""
    from ..cloud import PointCloud

    if isinstance(obj, PointCloud):
        return True
    if isinstance(obj, np.ndarray):
        return obj.ndim in (2, 3) and obj.shape[-1] == 3
    mod = type(obj).__module__ or ""
    return type(obj).__name__ == "PointCloud" and mod.split(".")[0] in ("trimesh", "open3d")


def elements_of(obj, elements: str | None = None, *, n_neighbors: int = 10,
                neighbor_radius: float | None = None) -> ElementInput:
    """Validate an input and give its element graph.

    Parameters
    ----------
    obj : Mesh, PointCloud, or what :func:`~superfacets.convert.as_mesh` or
        :func:`~superfacets.cloud.as_cloud` accept
    elements : {'faces', 'vertices', 'points', 'cells'}, optional
        Default: ``'points'`` for a point cloud, ``'cells'`` for a
        :class:`~superfacets.volume.TetMesh` (its tetrahedra), else ``'faces'``.
    n_neighbors, neighbor_radius
        The point graph's neighbourhood (points only).

    Returns
    -------
    ElementInput

    Raises
    ------
    ParameterError
        If ``elements`` does not fit the input (points of a mesh, faces of a cloud).
    InvalidMeshError, InvalidCloudError, TypeError
        As the input's validation.
    """
    from ..errors import ParameterError
    from ..volume import TetMesh

    if isinstance(obj, TetMesh):  # its tetrahedra
        if elements not in (None, "cells"):
            raise ParameterError(f"a tetrahedral mesh has elements='cells', not {elements!r}")
        obj.check_usable()
        from .cells import cell_graph

        return ElementInput(cell_graph(obj), None, obj)
    if elements == "cells":
        raise ParameterError("elements='cells' needs a tetrahedral mesh "
                             "(superfacets.read_volume)")
    cloud = is_cloud(obj)
    if elements is None:
        elements = "points" if cloud else "faces"
    if elements == "points":
        if not cloud:
            raise ParameterError("elements='points' needs a point cloud (a mesh has faces "
                                 "and vertices: elements='faces' or 'vertices')")
        from ..cloud import as_cloud

        c = as_cloud(obj)
        c.check_usable()
        from .points import point_graph

        g, index = point_graph(c, n_neighbors, neighbor_radius)
        return ElementInput(g, index, c)
    if cloud:
        raise ParameterError(f"elements={elements!r} needs a mesh; a point cloud has "
                             "elements='points'")
    from ..convert import as_mesh

    mesh = as_mesh(obj)
    mesh.check_usable()
    if elements == "vertices":
        from .vertices import vertex_graph

        g, index = vertex_graph(mesh)
        return ElementInput(g, index, mesh)
    from .faces import face_graph

    return ElementInput(face_graph(mesh), None, mesh)


def as_element_graph(obj) -> ElementGraph:
    """The element graph of ``obj``: itself, or the face graph of a mesh.

    Parameters
    ----------
    obj : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)

    Returns
    -------
    ElementGraph

    Raises
    ------
    TypeError, InvalidMeshError
        As :func:`superfacets.convert.as_mesh`.
    """
    if isinstance(obj, ElementGraph):
        return obj
    from ..convert import as_mesh
    from .faces import face_graph

    return face_graph(as_mesh(obj))
