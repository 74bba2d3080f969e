"""The names every docstring example may use without importing them: the shared doctest
namespace (``tests/test_docstrings.py`` and ``tests/hostile_api.py`` run the examples in
it, the module's own names first). The API reference says so above its examples."""

from __future__ import annotations


def shared() -> dict:
    """numpy as ``np``, trimesh, and the package's most used names."""
    import numpy as np
    import trimesh

    from superfacets import Mesh, PointCloud, as_mesh, face_graph, segment
    from superfacets.elements.builders import as_element_graph
    from superfacets.elements.points import point_graph
    from superfacets.method.params import resolve
    from superfacets.method.pipeline import passes_example

    return dict(np=np, trimesh=trimesh, Mesh=Mesh, PointCloud=PointCloud, as_mesh=as_mesh,
                face_graph=face_graph, segment=segment, as_element_graph=as_element_graph,
                point_graph=point_graph, resolve=resolve,
                passes_example=passes_example)
