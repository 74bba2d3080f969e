"""Mesh validation and derived per-face geometry (``docs/method.md``, section 1).

A :class:`Mesh` holds C-contiguous ``(n, 3) float64`` vertices and
``(m, 3) int64`` faces, validated once. Derived quantities (centroids, unit
normals, areas, bounding-box diagonal, the face graph) are computed on first
use and cached, so the method, the metrics and the baselines share them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .errors import InvalidMeshError

__all__ = ["Mesh", "as_mesh"]


@dataclass(frozen=True, eq=False)
class Mesh:
    """A validated triangle mesh with cached derived geometry.

    Parameters
    ----------
    vertices : (n, 3) float ndarray
        Vertex positions. Any units; every result of this package is invariant
        to uniform scaling.
    faces : (m, 3) int ndarray
        Vertex indices of each triangle, 0-based. The face order is kept: it
        is the order of the labels.
    name : str, optional
        A name for messages and file headers (usually the file name).

    Raises
    ------
    InvalidMeshError
        If the arrays have the wrong shape, the mesh has no face, a face index
        is out of range, a coordinate is NaN or infinite, or the mesh has zero
        extent or zero total area.
    TypeError
        If ``faces`` is not an integer array.

    Notes
    -----
    Degenerate (zero-area) faces, duplicate faces, unreferenced vertices,
    several connected components and non-manifold edges are valid input.
    The arrays are stored as read-only views; the caller's arrays are never
    modified.
    """

    vertices: np.ndarray
    faces: np.ndarray
    name: str = field(default="")

    def __post_init__(self) -> None:
        vertices, faces = _validate_arrays(self.vertices, self.faces, self.name)
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "faces", faces)

    # ----------------------------------------------------------------- sizes
    @property
    def n_vertices(self) -> int:
        """Number of vertices ``n``."""
        return int(self.vertices.shape[0])

    @property
    def n_faces(self) -> int:
        """Number of faces ``m``."""
        return int(self.faces.shape[0])

    # ------------------------------------------------------ derived geometry
    @cached_property
    def _geometry(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        from ._kernels.geometry import face_geometry  # one pass: no (m, 3) temporaries

        m = self.n_faces
        centroids, areas, normals = np.empty((m, 3)), np.empty(m), np.empty((m, 3))
        face_geometry(np.ascontiguousarray(self.vertices),
                               np.ascontiguousarray(self.faces), centroids, areas, normals)
        return _readonly(centroids), _readonly(areas), _readonly(normals)

    @property
    def centroids(self) -> np.ndarray:
        """(m, 3) float64: mean of each face's three vertex positions."""
        return self._geometry[0]

    @property
    def areas(self) -> np.ndarray:
        """(m,) float64: face areas (0 for degenerate faces)."""
        return self._geometry[1]

    @property
    def normals(self) -> np.ndarray:
        """(m, 3) float64: unit face normals, right-hand rule on vertex order.

        Degenerate (zero-area) faces get the zero vector, so their dihedral
        angle with any neighbour is pi/2 and their edges count as convex.
        """
        return self._geometry[2]

    @cached_property
    def area(self) -> float:
        """Total surface area ``A`` (sum of face areas)."""
        return float(self.areas.sum())

    @cached_property
    def diagonal(self) -> float:
        """Length ``d`` of the diagonal of the axis-aligned bounding box of the
        vertices referenced by faces."""
        used = self.vertices[self.referenced_vertices]
        return float(np.linalg.norm(used.max(axis=0) - used.min(axis=0)))

    @cached_property
    def referenced_vertices(self) -> np.ndarray:
        """(n,) bool: True for vertices used by at least one face."""
        mask = np.zeros(self.n_vertices, dtype=bool)
        mask[self.faces.ravel()] = True
        return _readonly(mask)

    @cached_property
    def centroid(self) -> np.ndarray:
        """(3,) float64: mean position of the referenced vertices (the "mesh
        centroid" of the authors' implementation; the first center is the face
        nearest to it)."""
        return self.vertices[self.referenced_vertices].mean(axis=0)

    @cached_property
    def graph(self):
        """The face graph of this mesh, an :class:`~superfacets.elements.ElementGraph`
        (built on first use, then cached)."""
        from .elements.faces import face_graph

        return face_graph(self)

    def check_usable(self) -> None:
        """Raise :class:`InvalidMeshError` if the mesh cannot be segmented or measured.

        Segmenting needs a positive bounding-box diagonal (weights are divided
        by it) and a positive total area (the superfacet radius derives from
        it). The extent must also lie within ``1e-70 .. 1e70`` and coordinates
        within ``1e300`` in magnitude: face areas and normals square and
        square again the edge vectors, which would overflow or underflow
        double precision beyond that (the mesh must then be rescaled).
        """
        where = f"{self.name}: " if self.name else ""
        used = self.vertices[self.referenced_vertices]
        with np.errstate(over="ignore", invalid="ignore"):
            extent = float(np.max(used.max(axis=0) - used.min(axis=0)))
            size = float(np.abs(used).max())
        if not (np.isfinite(extent) and size <= _MAX_COORDINATE and extent <= _MAX_EXTENT):
            raise InvalidMeshError(
                f"{where}coordinates up to {size:.3g} spanning {extent:.3g}: the face geometry "
                f"would overflow double precision; rescale the mesh (e.g. to unit size)")
        if extent == 0:
            raise InvalidMeshError(f"{where}mesh has zero extent (all vertices coincide)")
        if extent < _MIN_EXTENT:
            raise InvalidMeshError(
                f"{where}the mesh spans only {extent:.3g}: face areas would underflow double "
                f"precision; rescale the mesh (e.g. to unit size)")
        if not self.diagonal > 0:
            raise InvalidMeshError(f"{where}mesh has zero extent (all vertices coincide)")
        if not self.area > 0:
            raise InvalidMeshError(f"{where}mesh has zero total area (every face is degenerate)")


_MAX_COORDINATE = 1e300  # sums of three coordinates stay finite
_MAX_EXTENT = 1e70  # (edge length)^4 stays finite: areas and normals
_MIN_EXTENT = 1e-70  # (edge length)^4 stays a normal number


def _readonly(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


def _validate_arrays(vertices, faces, name: str = "") -> tuple[np.ndarray, np.ndarray]:
    where = f"{name}: " if name else ""
    try:
        v = np.asarray(vertices)
        f = np.asarray(faces)
    except Exception as exc:  # ragged lists and the like
        raise InvalidMeshError(f"{where}vertices/faces are not arrays: {exc}") from None
    if v.ndim != 2 or v.shape[1] != 3:
        raise InvalidMeshError(f"{where}vertices must have shape (n, 3), got {v.shape}")
    if f.ndim != 2:
        raise InvalidMeshError(f"{where}faces must have shape (m, 3), got {f.shape}")
    if f.shape[0] == 0:
        raise InvalidMeshError(f"{where}empty mesh: no faces")
    if f.shape[1] != 3:
        raise InvalidMeshError(
            f"{where}only triangle faces are supported, got faces of shape {f.shape} "
            f"({f.shape[1]} vertices per face)"
        )
    if not np.issubdtype(v.dtype, np.number) or np.issubdtype(v.dtype, np.complexfloating):
        raise TypeError(f"{where}vertices must be a real numeric array, got dtype {v.dtype}")
    if not np.issubdtype(f.dtype, np.integer):
        raise TypeError(f"{where}faces must be an integer array, got dtype {f.dtype}")
    v = np.ascontiguousarray(v, dtype=np.float64)
    f = np.ascontiguousarray(f, dtype=np.int64)
    bad = ~np.isfinite(v).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InvalidMeshError(
            f"{where}{int(bad.sum())} vertices have NaN or infinite coordinates "
            f"(first: vertex {i} = {v[i].tolist()})"
        )
    n = v.shape[0]
    lo, hi = int(f.min()), int(f.max())
    if lo < 0 or hi >= n:
        badf = np.flatnonzero(((f < 0) | (f >= n)).any(axis=1))
        i = int(badf[0])
        raise InvalidMeshError(
            f"{where}{badf.size} faces have vertex indices out of range 0..{n - 1} "
            f"(first: face {i} = {f[i].tolist()})"
        )
    # read-only views: the caller's arrays stay writable and untouched
    v = v.view()
    f = f.view()
    v.setflags(write=False)
    f.setflags(write=False)
    return v, f


def as_mesh(mesh, name: str = "") -> Mesh:
    """Turn a mesh given in any accepted form into a validated :class:`Mesh`.

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or tuple of (vertices, faces)
        ``vertices`` is ``(n, 3)`` float, ``faces`` is ``(m, 3)`` int.
        A :class:`Mesh` is returned as is (its caches are reused).
    name : str, optional
        Name used in error messages.

    Returns
    -------
    Mesh

    Raises
    ------
    TypeError
        If ``mesh`` is none of the accepted forms.
    InvalidMeshError
        If the arrays are invalid (see :class:`Mesh`).
    """
    if isinstance(mesh, Mesh):
        return mesh
    if isinstance(mesh, (tuple, list)) and len(mesh) == 2:
        return Mesh(mesh[0], mesh[1], name=name)
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):  # trimesh.Trimesh and alike
        return Mesh(np.asarray(mesh.vertices), np.asarray(mesh.faces), name=name)
    raise TypeError(
        "mesh must be a superfacets.Mesh, a trimesh.Trimesh or a (vertices, faces) pair, "
        f"got {type(mesh).__name__}"
    )
