"""Element graphs: the elements a method segments and their adjacency.

An :class:`ElementGraph` is what every step after it works on (weights,
initialization, passes, connectivity, metrics): elements with a position,
a size and a normal, and a symmetric adjacency with, per adjacent pair, the
length of the border they share and the geometric terms of the weights.
Only the builders know what an element is: :func:`face_graph` makes the
face graph (dual graph) of a triangle mesh.
"""

from .faces import build_face_graph, face_graph
from .graph import AdjacencyTerms, ElementGraph, as_element_graph

__all__ = ["ElementGraph", "AdjacencyTerms", "as_element_graph", "face_graph",
           "build_face_graph"]
