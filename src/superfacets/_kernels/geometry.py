"""Per-face geometry of a triangle mesh in one pass (private kernel)."""

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", nogil=True)
def face_geometry(vertices, faces, centroids, areas, normals):
    """Centroids, areas and unit normals of all faces in one pass.

    The same floating-point operations, in the same order, as the numpy
    expressions they replace: centroid ``(v0 + v1 + v2) / 3``; cross product
    ``(v1 - v0) x (v2 - v0)`` written out as ``np.cross`` computes it; norm
    ``sqrt((x*x + y*y) + z*z)`` as ``np.linalg.norm(axis=1)``; area half of
    it; normal the cross product divided by the norm, zero for a degenerate
    face. Writes the three (m, 3) / (m,) outputs.
    """
    for f in range(faces.shape[0]):
        i = faces[f, 0]
        j = faces[f, 1]
        k = faces[f, 2]
        for t in range(3):
            centroids[f, t] = (vertices[i, t] + vertices[j, t] + vertices[k, t]) / 3.0
        a0 = vertices[j, 0] - vertices[i, 0]
        a1 = vertices[j, 1] - vertices[i, 1]
        a2 = vertices[j, 2] - vertices[i, 2]
        b0 = vertices[k, 0] - vertices[i, 0]
        b1 = vertices[k, 1] - vertices[i, 1]
        b2 = vertices[k, 2] - vertices[i, 2]
        c0 = a1 * b2 - a2 * b1
        c1 = a2 * b0 - a0 * b2
        c2 = a0 * b1 - a1 * b0
        norm = np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
        areas[f] = 0.5 * norm
        if norm > 0:
            normals[f, 0] = c0 / norm
            normals[f, 1] = c1 / norm
            normals[f, 2] = c2 / norm
        else:
            normals[f, 0] = 0.0
            normals[f, 1] = 0.0
            normals[f, 2] = 0.0
