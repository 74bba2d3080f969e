"""Tetrahedral meshes: validated vertices and tetrahedra (the paper's section 6 future work).

A :class:`TetMesh` holds ``(n, 3) float64`` vertices and ``(m, 4) int64``
tetrahedra in input order, and optionally one integer material (region) per
tetrahedron, as Gmsh's physical groups or a ``medit:ref`` give them. Its
elements for the method are the tetrahedra (:func:`superfacets.elements.cells.cell_graph`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..checks import check_int, check_name, check_number, check_real, check_unmasked
from ..errors import InvalidMeshError, ParameterError
from .bounds import check_extent, column_bounds
from .mesh import Mesh, readonly

__all__ = ["TetMesh", "TET_FACES", "cut_surface", "as_drawn"]

#: The four triangles of a tetrahedron ``(a, b, c, d)``, each opposite one corner.
TET_FACES = np.array([[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]])


@dataclass(frozen=True, eq=False)
class TetMesh:
    """A validated tetrahedral mesh.

    Parameters
    ----------
    vertices : (n, 3) float ndarray
    tets : (m, 4) int ndarray
        Vertex indices of each tetrahedron, ``0 <= i < n``, four distinct.
    materials : (m,) int ndarray, optional
        A region id per tetrahedron (e.g. Gmsh's physical group).
    name : str, optional
        For messages.

    Raises
    ------
    InvalidMeshError
        On a wrong shape, a non-finite coordinate, an index out of range, a
        tetrahedron with a repeated vertex, no tetrahedron, or materials that
        are not one integer per tetrahedron.

    Examples
    --------
    >>> t = TetMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 1, 2, 3]])
    >>> float(t.volumes[0]) == 1 / 6
    True
    """

    vertices: np.ndarray
    tets: np.ndarray
    materials: np.ndarray | None = None
    name: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "name", check_name(self.name))  # (in every message)
        where = f"{self.name}: " if self.name else ""
        v = check_unmasked(self.vertices, where + "vertices", InvalidMeshError)
        check_real(v.dtype, where + "vertices")
        v = np.ascontiguousarray(v, dtype=np.float64)
        if v.ndim != 2 or v.shape[1] != 3:
            raise InvalidMeshError(f"{where}vertices must have shape (n, 3), got {v.shape}")
        bad = ~np.isfinite(v).all(axis=1)
        if bad.any():
            raise InvalidMeshError(f"{where}vertex {int(np.flatnonzero(bad)[0])} has a "
                                   "non-finite coordinate")
        t = np.asarray(self.tets)
        if t.size == 0:
            raise InvalidMeshError(f"{where}no tetrahedron")
        if not np.issubdtype(t.dtype, np.integer):
            if not np.issubdtype(t.dtype, np.floating) or not np.all(np.mod(t, 1) == 0):
                raise InvalidMeshError(f"{where}tetrahedra must hold integer vertex indices")
        t = np.ascontiguousarray(t, dtype=np.int64)
        if t.ndim != 2 or t.shape[1] != 4:
            raise InvalidMeshError(f"{where}tetrahedra must have shape (m, 4), got {t.shape}")
        out = (t < 0) | (t >= v.shape[0])
        if out.any():
            row = int(np.flatnonzero(out.any(axis=1))[0])
            raise InvalidMeshError(f"{where}tetrahedron {row} refers to vertex "
                                   f"{int(t[row][out[row]][0])}, but there are "
                                   f"{v.shape[0]} vertices")
        s = np.sort(t, axis=1)
        rep = (s[:, 1:] == s[:, :-1]).any(axis=1)
        if rep.any():
            raise InvalidMeshError(f"{where}tetrahedron {int(np.flatnonzero(rep)[0])} repeats "
                                   "a vertex")
        object.__setattr__(self, "vertices", readonly(v))
        object.__setattr__(self, "tets", readonly(t))
        if self.materials is not None:
            mat = np.asarray(self.materials).reshape(-1)
            if mat.shape[0] != t.shape[0] or not np.issubdtype(mat.dtype, np.integer):
                raise InvalidMeshError(f"{where}materials must be one integer per "
                                       f"tetrahedron ({t.shape[0]}), got {mat.shape} "
                                       f"{mat.dtype}")
            object.__setattr__(self, "materials", readonly(mat.astype(np.int64)))

    def __repr__(self) -> str:
        extra = "" if self.materials is None else \
            f", {np.unique(self.materials).size} materials"
        return f"TetMesh({self.vertices.shape[0]} vertices, {self.n_tets} tetrahedra{extra})"

    @property
    def n_tets(self) -> int:
        """Number of tetrahedra ``m``."""
        return int(self.tets.shape[0])

    @cached_property
    def volumes(self) -> np.ndarray:
        """(m,) float64: the volume of each tetrahedron (0 for a flat one)."""
        p = self.vertices[self.tets]
        a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
        return readonly(np.abs(np.einsum("ij,ij->i", a, np.cross(b, c))) / 6.0)

    @cached_property
    def centroids(self) -> np.ndarray:
        """(m, 3) float64: the mean of each tetrahedron's four vertices."""
        return readonly(self.vertices[self.tets].mean(axis=1))

    @cached_property
    def volume(self) -> float:
        """Total volume."""
        return float(self.volumes.sum())

    def check_usable(self) -> None:
        """Raise :class:`InvalidMeshError` unless the tetrahedra enclose a volume whose
        geometry fits double precision (:func:`superfacets.inputs.bounds.check_extent`)."""
        where = f"{self.name}: " if self.name else ""
        check_extent(*column_bounds(self.vertices[np.unique(self.tets)]), where)
        if not self.volume > 0:
            raise InvalidMeshError(f"{where}every tetrahedron is flat: no volume to segment")

    def boundary(self, keep: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The triangles on the surface of the tetrahedra ``keep`` (default: all).

        Returns
        -------
        triangles : (b, 3) int64 ndarray
            Vertex indices, turned outwards.
        owner : (b,) int64 ndarray
            The tetrahedron each triangle belongs to.
        """
        idx = np.arange(self.n_tets) if keep is None else np.flatnonzero(keep)
        t = self.tets[idx]
        tri = t[:, TET_FACES].reshape(-1, 3)
        owner = np.repeat(idx, 4)
        key = np.sort(tri, axis=1)
        _, inv, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        once = count[inv.ravel()] == 1
        tri, owner = tri[once], owner[once]
        # outwards: away from the owner's centroid
        p = self.vertices
        n = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])
        inward = np.einsum("ij,ij->i", n, self.centroids[owner] - p[tri[:, 0]]) > 0
        tri[inward] = tri[inward][:, [0, 2, 1]]
        return tri, owner


def cut_surface(mesh: TetMesh, labels=None, *, axis: int = 0, at: float = 0.5):
    """The surface of the tetrahedra on the low side of a cutting plane, to picture a volume.

    Parameters
    ----------
    mesh : TetMesh
    labels : (m,) int ndarray, optional
        One label per tetrahedron.
    axis : {0, 1, 2}, default 0
        The plane's normal axis.
    at : float, default 0.5
        Where the plane cuts the bounding box along ``axis``, a fraction in ``[0, 1]``
        (1 keeps every tetrahedron: the outer surface).

    Returns
    -------
    surface : Mesh
        The triangles bounding the kept tetrahedra (the cut face included), outwards.
    face_labels : (b,) int64 ndarray or None
        The label of the tetrahedron under each triangle.

    Raises
    ------
    ParameterError
        If ``axis`` or ``at`` is out of range, no tetrahedron is kept, or ``labels`` is not
        one integer per tetrahedron.

    Examples
    --------
    >>> from scipy.spatial import Delaunay
    >>> p = np.random.default_rng(0).random((200, 3))
    >>> t = TetMesh(p, Delaunay(p).simplices)
    >>> surface, face_labels = cut_surface(t, np.zeros(t.n_tets, dtype=int))
    >>> surface.n_faces == face_labels.shape[0]
    True
    """

    axis = check_int("axis", axis, lo=0, hi=2)
    at = check_number("at", at, 0.0, 1.0)
    if labels is not None:
        given = np.asarray(labels)
        if given.shape != (mesh.n_tets,) or given.dtype.kind not in "iu":
            raise ParameterError(f"labels: one integer per tetrahedron ({mesh.n_tets:,}) is "
                                 f"needed, got shape {given.shape}, dtype {given.dtype}")
    c = mesh.centroids[:, axis]
    lo, hi = float(mesh.vertices[:, axis].min()), float(mesh.vertices[:, axis].max())
    keep = c <= lo + at * (hi - lo) + 1e-12 * max(1.0, abs(hi - lo))
    if not keep.any():
        raise ParameterError(f"no tetrahedron lies below {at:g} of the extent along axis {axis}")
    tri, owner = mesh.boundary(keep)
    surface = Mesh(mesh.vertices, tri, name=mesh.name)
    lab = None if labels is None else np.asarray(labels, dtype=np.int64)[owner]
    return surface, lab


def as_drawn(data, labels=None) -> tuple:
    """What a picture or a page draws of ``data``: a tetrahedral mesh's cut at the middle
    of x (:func:`cut_surface`, each triangle its tetrahedron's label), anything else
    itself.

    Parameters
    ----------
    data : TetMesh or any input
    labels : (m,) int ndarray, optional
        Per tetrahedron for a volume; else passed on as given.

    Returns
    -------
    data : Mesh or the input
    labels : ndarray or None
    cut : bool
        Whether ``data`` was a volume, now its cut (its labels per face).

    Raises
    ------
    ParameterError
        As :func:`cut_surface`.

    Examples
    --------
    >>> from scipy.spatial import Delaunay
    >>> p = np.random.default_rng(0).random((200, 3))
    >>> surface, face_labels, cut = as_drawn(TetMesh(p, Delaunay(p).simplices))
    >>> cut, face_labels is None, surface.n_faces > 0
    (True, True, True)
    """
    if not isinstance(data, TetMesh):
        return data, labels, False
    surface, face_labels = cut_surface(data, labels, axis=0, at=0.5)
    return surface, face_labels, True
