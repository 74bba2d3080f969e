"""Element graphs: the elements a method segments and their adjacency.

An :class:`ElementGraph` is what every step after it works on (weights,
initialization, passes, connectivity, metrics): elements with a position,
a size and a normal, and a symmetric adjacency with, per adjacent pair, the
length of the border they share and the geometric terms of the weights.
Only the builders know what an element is: :func:`face_graph` makes the
face graph (dual graph) of a triangle or polygon mesh,
:func:`~superfacets.elements.vertices.vertex_graph` the graph of its vertices and
:func:`~superfacets.elements.points.point_graph` the k-nearest-neighbour graph of
a point cloud. Each keeps what it builds with its input (one build per mesh or
cloud, and per neighbourhood): the inputs know nothing of graphs.

The rules that differ by kind are in one table, :mod:`superfacets.elements.kinds`
(read before any graph is built: importing it imports no builder).
"""

import importlib

__all__ = ["ElementGraph", "AdjacencyTerms", "as_element_graph", "face_graph",
           "build_face_graph"]

_WHERE = {"ElementGraph": "graph", "AdjacencyTerms": "graph", "as_element_graph": "builders",
          "face_graph": "faces", "build_face_graph": "faces"}


def __getattr__(name):  # lazy: ``elements.kinds`` is read before any builder is imported
    if name in _WHERE:
        return getattr(importlib.import_module(f"{__name__}.{_WHERE[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + __all__)
