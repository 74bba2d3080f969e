"""Ground truth for vertices and points: benchmark meshes sampled for the superpoint benchmark.

- :func:`sample_points`: a fixed number of points on a mesh, uniform by area
  (faces drawn with probability proportional to their area, a uniform point
  in each; fixed seed), each point carrying its face, so its ground truth is
  its face's label;
- :func:`vertex_ground_truth`: the label of a vertex is the majority label of
  its incident faces, weighted by their area (ties: the smallest label).
"""

from __future__ import annotations

import numpy as np

from ...elements.labels import check_labels
from ...errors import InvalidMeshError
from ...method.params import check_int

__all__ = ["sample_points", "vertex_ground_truth", "DEFAULT_POINTS"]

#: Points sampled per mesh by default (the benchmark meshes have 2,682 to 55,644 faces).
DEFAULT_POINTS = 20_000


def sample_points(mesh, n_points: int = DEFAULT_POINTS, seed: int = 0
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Points uniform on the surface of a mesh, with the face of each.

    Parameters
    ----------
    mesh : Mesh
        Triangles or polygons (polygons through their fan triangles).
    n_points : int, default 20000
    seed : int, default 0

    Returns
    -------
    points : (n_points, 3) float64 ndarray
    faces : (n_points,) int64 ndarray
        The face each point lies on.

    Raises
    ------
    ParameterError
        If ``n_points < 1``.
    InvalidMeshError
        If the mesh has no area.

    Examples
    --------
    >>> box = trimesh.creation.box()
    >>> p, f = sample_points(Mesh(box.vertices, box.faces), 100)
    >>> p.shape, bool(np.all(np.abs(p) <= 0.5 + 1e-12))
    ((100, 3), True)
    """

    n_points = check_int("n_points", n_points, lo=1)
    tri, owner = mesh.triangulated()
    v = mesh.vertices
    a, b, c = v[tri[:, 0]], v[tri[:, 1]], v[tri[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    total = area.sum()
    if not total > 0:
        raise InvalidMeshError("mesh has zero total area: no point to sample")
    rng = np.random.default_rng(seed)
    t = rng.choice(tri.shape[0], size=n_points, p=area / total)
    r1, r2 = rng.random(n_points), rng.random(n_points)
    s = np.sqrt(r1)
    pts = (1 - s)[:, None] * a[t] + (s * (1 - r2))[:, None] * b[t] + (s * r2)[:, None] * c[t]
    return pts, np.asarray(owner)[t].astype(np.int64)


def vertex_ground_truth(mesh, face_labels) -> np.ndarray:
    """The area-weighted majority label of each vertex's incident faces.

    Parameters
    ----------
    mesh : Mesh
    face_labels : (m,) int ndarray

    Returns
    -------
    (n_vertices,) int64 ndarray
        -1 for vertices used by no face.
    """

    labels = check_labels(face_labels, mesh.n_faces, "ground truth", per="face")
    corners = np.asarray(mesh.corners)
    owner = np.repeat(np.arange(mesh.n_faces), mesh.face_sizes)
    _, dense = np.unique(labels, return_inverse=True)
    dense = dense.ravel()
    uniq = np.unique(labels)
    k = uniq.shape[0]
    key = corners.astype(np.int64) * k + dense[owner]
    weight = mesh.areas[owner] + 1e-300  # degenerate faces still vote
    ukey, inv = np.unique(key, return_inverse=True)
    votes = np.bincount(inv.ravel(), weights=weight)
    vert, lab = ukey // k, ukey % k
    order = np.lexsort((lab, -votes, vert))  # per vertex: most votes, then smallest label
    vert, lab = vert[order], lab[order]
    first = np.r_[True, vert[1:] != vert[:-1]]
    out = np.full(mesh.n_vertices, -1, dtype=np.int64)
    out[vert[first]] = uniq[lab[first]]
    return out
