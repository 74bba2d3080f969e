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
"""

from .faces import build_face_graph, face_graph
from .graph import AdjacencyTerms, ElementGraph
from .inputs import as_element_graph

__all__ = ["ElementGraph", "AdjacencyTerms", "as_element_graph", "face_graph",
           "build_face_graph"]
