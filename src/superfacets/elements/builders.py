"""From what the user gives to the element graph the method runs on.

:func:`elements_of` is the one place that decides what the elements of an
input are: the faces of a mesh (the paper), its vertices, or the points of a
cloud. It validates the input, builds (or takes from the input's cache) the
graph, and keeps the map from elements back to the input's rows, so labels
come back one per face, vertex or point, in input order.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np

from .._runtime.arrays import gather
from .graph import ElementGraph, cached_on
from .points import DEFAULT_NEIGHBORS as _N_NEIGHBORS

__all__ = ["ElementInput", "Builder", "BUILDERS", "as_element_graph", "elements_of",
           "is_cloud", "kind_for", "prepared", "register_builder", "features_of", "per_element",
           "check_count"]

from .._runtime import memory
from ..checks import check_int, check_n_segments
from ..errors import ParameterError
from ..inputs.cloud import PointCloud, as_cloud, is_point_table
from ..inputs.convert import as_mesh
from ..inputs.mesh import Mesh
from ..inputs.tetmesh import TetMesh
from . import faces, points, vertices
from .cells import cell_graph
from .faces import distinct_faces
from .features import features_of, per_element  # noqa: E402,F401 (re-exported)
from .kinds import kind_of


def check_count(n_segments, n: int, rows: int, kind: str) -> int:
    """``n_segments`` checked against the ``n`` elements of an input of ``rows`` rows: where
    rows are not elements (points at an earlier point's position or at none, vertices of no
    face), the message counts them, since the elements alone read as a miscount of the
    user's rows.

    Parameters
    ----------
    n_segments : int
    n, rows : int
        The elements, and the input's rows (faces, vertices, points with invalid ones).
    kind : str

    Returns
    -------
    int

    Raises
    ------
    ParameterError
        If ``n_segments`` is not an integer in ``1..n``.

    Examples
    --------
    >>> check_count(5, 50, 52, "points")
    5
    """
    if rows <= n or check_int("n_segments", n_segments, lo=1) <= n:
        return check_n_segments(n_segments, n, kind)
    one = rows - n == 1
    why = (("repeats an earlier point's position or has none" if one else
            "repeat an earlier point's position or have none") if kind_of(kind).cloud else
           f"{'is' if one else 'are'} used by no face")
    raise ParameterError(f"n_segments ({n_segments:,}) is larger than the number of {kind} "
                         f"({n:,}: {rows - n:,} of the input's {rows:,} {why})")


class ElementInput(NamedTuple):
    """An input ready for the method.

    Attributes
    ----------
    graph : ElementGraph
    index : (N,) int32 or int64 ndarray, or None
        Element of each input row (vertex or point), -1 for rows that are not
        elements (vertices used by no face, invalid points); None when the
        elements are the rows themselves (faces).
    source : Mesh or PointCloud
        The validated input.

    Examples
    --------
    >>> src = elements_of(np.random.default_rng(0).random((50, 3)))
    >>> src.graph.kind, src.n_rows, src.to_rows(np.zeros(src.graph.n_elements, int)).shape
    ('points', 50, (50,))
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
        index = self.index
        if index.shape[0] and int(index.min()) >= 0:  # every row an element: one gather
            return gather(np.asarray(labels), index)
        out = np.full(index.shape[0], -1, dtype=labels.dtype)
        ok = index >= 0
        out[ok] = labels[index[ok]]
        return out

    def colors(self) -> np.ndarray | None:
        """(N, 3) float64: the RGB of each input row (face, vertex or point) in ``[0, 1]``,
        None where the input has no colours
        (:meth:`superfacets.inputs.mesh.Mesh.colors_of_faces`)."""
        if isinstance(self.source, Mesh):
            return (self.source.colors_of_faces() if self.graph.kind == "faces"
                    else self.source.colors_of_vertices())
        return getattr(self.source, "colors", None)

    def first_rows(self, elements: np.ndarray) -> np.ndarray:
        """The first input row of each of ``elements`` (the row a center stands for)."""
        if self.index is None:
            return elements
        elements = np.asarray(elements)
        n = self.graph.n_elements
        if 8 * elements.size < n:  # a few (the centers): the rows of those alone
            wanted = np.zeros(n + 1, dtype=bool)  # (the last: rows of no element, -1)
            wanted[elements] = True
            rows = np.flatnonzero(wanted[self.index])
            rows = rows[self.index[rows] >= 0]
        else:
            rows = np.flatnonzero(self.index >= 0)
        first = np.full(n, -1, dtype=np.int64)
        first[self.index[rows][::-1]] = rows[::-1]
        return first[elements]


def is_cloud(obj) -> bool:
    """Whether ``obj`` is a point cloud (a PointCloud, a bare (N, 3) or (H, W, 3) array or
    a list of rows of 3 numbers, a trimesh or Open3D point cloud, a pandas DataFrame of
    ``x y z`` columns) rather than a mesh.

    Parameters
    ----------
    obj : object

    Returns
    -------
    bool

    Raises
    ------
    TypeError
        Never: anything that is not a cloud is answered False.

    Examples
    --------
    >>> is_cloud(np.zeros((10, 3))), is_cloud((np.zeros((3, 3)), [[0, 1, 2]]))
    (True, False)
    """

    if isinstance(obj, PointCloud) or is_point_table(obj):
        return True
    if isinstance(obj, list) and obj:  # (rows of 3 numbers; a (V, F) pair is a tuple)
        try:
            obj = np.asarray(obj, dtype=np.float64)
        except (TypeError, ValueError):
            return False
    if isinstance(obj, np.ndarray):
        return obj.ndim in (2, 3) and obj.shape[-1] == 3
    mod = type(obj).__module__ or ""
    return type(obj).__name__ == "PointCloud" and mod.split(".")[0] in ("trimesh", "open3d")


class Builder(NamedTuple):
    """How the element graph of one kind is built (a row of :data:`BUILDERS`).

    Attributes
    ----------
    accepts : callable
        ``accepts(obj) -> bool``: whether ``obj`` is an input of this kind's
        family (a mesh, a point cloud, a tetrahedral mesh).
    default : bool
        This kind is the default for the inputs it accepts.
    prepare : callable
        ``prepare(obj) -> input``: the validated input (a ``Mesh``, ``PointCloud``
        or ``TetMesh``), before any graph.
    count : callable
        ``count(input) -> int``: the number of elements, or a bound on it from
        above, without the graph (``n_segments`` is checked against it first).
    build : callable
        ``build(input, n_neighbors, neighbor_radius) -> ElementInput``: build (or
        take from the input's cache) the graph.
    needs : str
        What the kind needs, for the error when the input does not fit.

    Examples
    --------
    >>> BUILDERS["faces"].needs
    "a mesh; a point cloud has elements='points'"
    """

    accepts: Callable[[object], bool]
    default: bool
    prepare: Callable[[object], object]
    count: Callable[[object], int]
    build: Callable[..., ElementInput]
    needs: str


def _is_volume(obj) -> bool:
    return isinstance(obj, TetMesh)


def _is_mesh(obj) -> bool:
    return not is_cloud(obj) and not _is_volume(obj)


def _usable(obj):
    obj.check_usable()
    return obj


def _usable_cloud(obj):
    return _usable(as_cloud(obj))


def _usable_mesh(obj):
    return _usable(as_mesh(obj))


def _cells(volume, n_neighbors, neighbor_radius) -> ElementInput:
    return ElementInput(cell_graph(volume), None, volume)


def _points(cloud, n_neighbors, neighbor_radius) -> ElementInput:
    g, index = points.point_graph(cloud, n_neighbors, neighbor_radius)
    return ElementInput(g, index, cloud)


def _vertices(mesh, n_neighbors, neighbor_radius) -> ElementInput:
    g, index = vertices.vertex_graph(mesh)
    return ElementInput(g, index, mesh)


def _faces(mesh, n_neighbors, neighbor_radius) -> ElementInput:
    found = distinct_faces(mesh)
    if found is None:
        return ElementInput(faces.face_graph(mesh), None, mesh)
    # copies of a face are one element: the graph of the distinct faces, kept with the mesh
    first, index = found
    return cached_on(mesh, "_distinct_faces_input",
                     lambda: ElementInput(faces.face_graph(_faces_of(mesh, first)), index, mesh))


def _faces_of(mesh, first):
    """The mesh of the faces ``first`` of ``mesh`` (its vertices, colours and name)."""

    face_colors = None if mesh.face_colors is None else mesh.face_colors[first]
    return Mesh(mesh.vertices, mesh.faces[first], name=mesh.name, colors=mesh.colors,
                face_colors=face_colors)


def _used_vertices(mesh) -> int:
    return int(np.count_nonzero(np.bincount(np.asarray(mesh.corners).ravel(),
                                            minlength=mesh.n_vertices)))


_MESH = "a mesh; a point cloud has elements='points'"

#: The element-graph builder of each kind (the kinds' rules are in
#: :data:`superfacets.elements.kinds.KINDS`); the first kind marked ``default`` that
#: accepts an input is its default.
BUILDERS: dict[str, Builder] = {
    "cells": Builder(_is_volume, True, _usable, lambda v: v.n_tets, _cells,
                     "a tetrahedral mesh (superfacets.read_volume)"),
    "points": Builder(is_cloud, True, _usable_cloud, lambda c: c.n_points, _points,
                      "a point cloud (a mesh has faces and vertices: elements='faces' "
                      "or 'vertices')"),
    "faces": Builder(_is_mesh, True, _usable_mesh, lambda m: m.n_faces, _faces, _MESH),
    "vertices": Builder(_is_mesh, False, _usable_mesh, _used_vertices, _vertices, _MESH),
}


def register_builder(kind: str, builder: Builder) -> None:
    """Add (or replace) the builder of a kind of element.

    The kind must have a row in :data:`superfacets.elements.kinds.KINDS`.

    Parameters
    ----------
    kind : str
    builder : Builder

    Raises
    ------
    ValueError
        If ``kind`` has no row in the table of kinds.

    Examples
    --------
    >>> register_builder("faces", BUILDERS["faces"])  # as it is

    Returns
    -------
    None
    """

    kind_of(kind)
    BUILDERS[kind] = builder


def kind_for(obj, elements: str | None = None) -> str:
    """The kind of element a run on ``obj`` segments: ``elements`` if given and
    ``obj`` fits it, else the input's default kind.

    Parameters
    ----------
    obj : Mesh, PointCloud, TetMesh, or what they are made from
    elements : str, optional

    Returns
    -------
    str

    Raises
    ------
    ParameterError
        If ``elements`` is unknown or does not fit the input.

    Examples
    --------
    >>> kind_for(trimesh.creation.box()), kind_for(np.zeros((5, 3)))
    ('faces', 'points')
    """

    if elements is None:
        for kind, b in BUILDERS.items():
            if b.default and b.accepts(obj):
                return kind
        raise ParameterError(f"no kind of element accepts a {type(obj).__name__}")
    builder = BUILDERS.get(elements)
    if builder is None:
        raise ParameterError(f"elements must be one of {', '.join(BUILDERS)}; got {elements!r}")
    if not builder.accepts(obj):
        if elements == "cells" or not _is_volume(obj):
            raise ParameterError(f"elements={elements!r} needs {builder.needs}")
        raise ParameterError(f"a tetrahedral mesh has elements='cells', not {elements!r}")
    return elements


def elements_of(obj, elements: str | None = None, *, n_neighbors: int = _N_NEIGHBORS,
                neighbor_radius: float | None = None,
                n_segments: int | None = None, step_weight: float = 1.0) -> ElementInput:
    """Validate an input and give its element graph.

    Parameters
    ----------
    obj : Mesh, PointCloud, TetMesh, or what :func:`~superfacets.inputs.convert.as_mesh` or
        :func:`~superfacets.inputs.cloud.as_cloud` accept
    elements : {'faces', 'vertices', 'points', 'cells'}, optional
        Default: ``'points'`` for a point cloud, ``'cells'`` for a
        :class:`~superfacets.inputs.tetmesh.TetMesh` (its tetrahedra), else ``'faces'``
        (:func:`kind_for`; the builders: :data:`BUILDERS`).
    n_neighbors, neighbor_radius
        The point graph's neighbourhood (points only).
    n_segments : int, optional
        Checked against the number of elements (or a bound on it known from the
        input, :attr:`Builder.count`) before the graph is built.
    step_weight : float, default 1
        Points only: ``> 1`` chooses each point's neighbours along its surface
        (:func:`~superfacets.elements.points.point_graph`'s ``step``).

    Returns
    -------
    ElementInput

    Raises
    ------
    ParameterError
        If ``elements`` does not fit the input (points of a mesh, faces of a cloud), or
        ``n_segments`` exceeds the elements, or ``step_weight`` is not 1 on elements that
        are not points.
    InvalidMeshError, InvalidCloudError, TypeError
        As the input's validation.

    Examples
    --------
    >>> src = elements_of(trimesh.creation.box(), "vertices")
    >>> src.graph.kind, src.graph.n_elements, src.n_rows
    ('vertices', 8, 8)
    """
    kind, data = prepared(obj, elements, n_segments=n_segments)
    if step_weight != 1:  # (the neighbours along the surface: a cloud's own graph)
        if not kind_of(kind).cloud:
            raise ParameterError(f"step_weight weighs steps off a point cloud's surface; "
                                 f"this input's elements are {kind}")
        g, index = points.point_graph(data, n_neighbors, neighbor_radius, step=step_weight)
        return ElementInput(g, index, data)
    return BUILDERS[kind].build(data, n_neighbors, neighbor_radius)


def prepared(obj, elements: str | None = None, *, n_segments: int | None = None):
    """The kind of element and the validated input, before any graph.

    Parameters
    ----------
    obj, elements
        As :func:`elements_of`.
    n_segments : int, optional
        Checked against the input's elements (:attr:`Builder.count`).

    Returns
    -------
    kind : str
    data : Mesh, PointCloud or TetMesh

    Raises
    ------
    ParameterError, InvalidMeshError, InvalidCloudError, TypeError
        As :func:`elements_of`.

    Examples
    --------
    >>> kind, mesh = prepared(trimesh.creation.box(), n_segments=12)
    >>> kind, mesh.n_faces
    ('faces', 12)
    """

    kind = kind_for(obj, elements)
    builder = BUILDERS[kind]
    data = builder.prepare(obj)
    n = builder.count(data)
    rows = max(n, int(kind_of(kind).n_rows(data)))  # (invalid points are held too)
    if n_segments is not None:  # before the graph, the memory peak of a run
        check_count(n_segments, n, rows, kind)

    memory.check_memory(rows, kind_of(kind).peak_bytes,
                 f"{getattr(data, 'name', '') or 'the input'}: {n:,} {kind}",
                 tiles_help=kind_of(kind).tiled_bytes is not None,
                 input_bytes=kind_of(kind).tiled_bytes or 0, held_input=_array_bytes(data))
    return kind, data


def _array_bytes(data) -> int:
    """The bytes of an input's own arrays (its vertices, faces, points, colours) and of
    what it keeps computed from them (a mesh's areas, centroids and normals, which its
    check made and the graph reads)."""
    total = 0
    for v in getattr(data, "__dict__", {}).values():
        for a in (v if isinstance(v, tuple) else (v,)):
            if isinstance(a, np.ndarray):
                total += a.nbytes
    return int(total)


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
        As :func:`superfacets.inputs.convert.as_mesh`; for a point cloud or a tetrahedral
        mesh, naming what reads them (:func:`superfacets.evaluation.metrics.evaluate_rows`,
        one label per row as ``superfacets evaluate`` reads them, or their graph,
        ``elements_of(obj).graph``): a mesh's metrics weigh faces by area, a cloud's each
        point alike.

    Examples
    --------
    >>> as_element_graph(trimesh.creation.box()).n_elements
    12
    """
    if isinstance(obj, ElementGraph):
        return obj
    if not _is_mesh(obj):
        what = "a tetrahedral mesh" if _is_volume(obj) else "a point cloud"
        raise TypeError(
            f"this takes a mesh or an element graph, not {what}: superfacets.evaluation."
            "metrics.evaluate_rows(input, labels, ground_truths) scores one label per row as "
            "`superfacets evaluate` does, each element weighing one; or pass its graph, "
            "superfacets.elements.builders.elements_of(input).graph")
    return faces.face_graph(as_mesh(obj))
