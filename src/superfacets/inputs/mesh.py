"""Mesh validation and derived per-face geometry (``docs/notes/method.md``, section 1).

A :class:`Mesh` holds C-contiguous ``(n, 3) float64`` vertices and
``(m, k) int64`` faces (``int32`` where given so: the mesh readers give them so while
they fit; triangles: ``k = 3``; polygons of any size, each
row padded with -1 after its vertices), validated once. Derived quantities (centroids, unit
normals, areas, bounding-box diagonal) are computed on first use and cached, so
the method, the metrics and the baselines share them. The mesh knows nothing of
graphs: :func:`superfacets.elements.face_graph` builds the face graph and keeps
it with the mesh (one build per mesh), and :func:`superfacets.inputs.convert.as_mesh`
turns the libraries' objects into a :class:`Mesh`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .._kernels import native
from .._runtime import threads
from .._runtime.threads import split
from ..checks import check_name, check_real, check_unmasked, counted
from ..errors import InvalidMeshError
from .bounds import check_extent, column_bounds
from .rgb import check_colors, face_means, vertex_means

__all__ = ["Mesh"]


@dataclass(frozen=True, eq=False)
class Mesh:
    """A validated triangle or polygon mesh with cached derived geometry.

    Parameters
    ----------
    vertices : (n, 3) float ndarray
        Vertex positions. Any units; every result of this package is invariant
        to uniform scaling.
    faces : (m, k) int ndarray, or a sequence of vertex index sequences
        Vertex indices of each face, 0-based, in order around it: triangles
        (``k = 3``), quads, or polygons of any sizes (a list of sequences, or
        an array whose rows end with -1 padding). The face order is kept: it
        is the order of the labels. Stored as ``int32`` when given as int32 (the
        mesh readers give them so while every index fits: half the memory), as
        ``int64`` otherwise.
    name : str, optional
        A name for messages and file headers (usually the file name).
    objects : tuple of (str, int, int), optional
        Named face ranges ``(name, start, stop)`` when the mesh joins several
        objects (a scene), in face order.
    colors : (n, 3) float ndarray, optional
        RGB of each vertex in ``[0, 1]`` (the readers scale 8-bit colours).
    face_colors : (m, 3) float ndarray, optional
        RGB of each face in ``[0, 1]``. Either or both: what ``beta > 0`` of
        :func:`superfacets.segment` reads when no ``features`` are given
        (:meth:`colors_of_faces`, :meth:`colors_of_vertices`).

    Raises
    ------
    InvalidMeshError
        If the arrays have the wrong shape, the mesh has no face, a face index
        is out of range, a coordinate is NaN or infinite, a colour is outside
        ``[0, 1]``, or the mesh has zero extent or zero total area.
    TypeError
        If ``faces`` is not an integer array.

    Notes
    -----
    Degenerate (zero-area) faces, duplicate faces (one element: ``distinct_faces``),
    unreferenced vertices, several components and non-manifold edges are valid input;
    so are non-planar and non-convex polygons (their area and normal come
    from Newell's method). The arrays are stored as read-only views; the
    caller's arrays are never modified.

    Examples
    --------
    >>> quad = Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2, 3]])
    >>> quad
    Mesh(4 vertices, 1 face: polygons of 4 vertices)
    >>> float(quad.areas[0])
    1.0
    """

    vertices: np.ndarray
    faces: np.ndarray
    name: str = field(default="")
    objects: tuple = field(default=(), repr=False)
    colors: np.ndarray | None = field(default=None, repr=False)
    face_colors: np.ndarray | None = field(default=None, repr=False)

    def __repr__(self) -> str:
        sizes = self.face_sizes
        lo, hi = int(sizes.min()), int(sizes.max())
        kind = ("triangles" if hi == 3 else f"polygons of {lo} vertices" if lo == hi
                else f"polygons of {lo} to {hi} vertices")
        name = f", name={self.name!r}" if self.name else ""
        objs = f", {len(self.objects)} objects" if len(self.objects) > 1 else ""
        return (f"Mesh({counted(self.n_vertices, 'vertex', 'vertices')}, "
                f"{counted(self.n_faces, 'face')}: {kind}{objs}{name})")

    def __post_init__(self) -> None:
        object.__setattr__(self, "name", check_name(self.name))  # (in every message)
        vertices, faces = _validate_arrays(self.vertices, self.faces, self.name)
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "faces", faces)
        where = f"{self.name}: " if self.name else ""
        for attr, n, what in (("colors", vertices.shape[0], "colour"),
                              ("face_colors", faces.shape[0], "face colour")):
            if getattr(self, attr) is not None:
                col = check_colors(getattr(self, attr), n, what, where, InvalidMeshError)
                object.__setattr__(self, attr, readonly(col))

    def __getstate__(self) -> dict:
        # the arrays and names only: the cached geometry and graphs are computed again
        # where the mesh is unpickled (the face graph holds functions, which pickle cannot)
        return {name: self.__dict__[name] for name in ("vertices", "faces", "name", "objects",
                                                        "colors", "face_colors")}

    def __setstate__(self, state: dict) -> None:
        state.setdefault("colors", None)
        state.setdefault("face_colors", None)
        for name in ("vertices", "faces", "colors", "face_colors"):
            if state[name] is not None:
                state[name].setflags(write=False)
        self.__dict__.update(state)

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
    @property
    def is_triangular(self) -> bool:
        """True when every face is a triangle (``faces`` is then ``(m, 3)``)."""
        return self.faces.shape[1] == 3

    @cached_property
    def face_sizes(self) -> np.ndarray:
        """(m,) int64: number of vertices of each face (3 for triangles)."""
        if self.is_triangular:
            return readonly(np.full(self.n_faces, 3, dtype=np.int64))
        return readonly((self.faces >= 0).sum(axis=1).astype(np.int64))

    @cached_property
    def offsets(self) -> np.ndarray:
        """(m + 1,) int64: face ``f`` has the vertices ``corners[offsets[f]:offsets[f + 1]]``."""
        out = np.zeros(self.n_faces + 1, dtype=np.int64)
        np.cumsum(self.face_sizes, out=out[1:])
        return readonly(out)

    @property
    def corners(self) -> np.ndarray:
        """(c,) int64: the vertex indices of every face in order, face after face (of
        int32 triangles a new copy each time: not held with the mesh)."""
        if self.is_triangular:
            return readonly(self.faces.ravel().astype(np.int64, copy=False))
        if "_corners" not in self.__dict__:
            self.__dict__["_corners"] = readonly(self.faces[self.faces >= 0].astype(np.int64))
        return self.__dict__["_corners"]

    def triangulated(self) -> tuple[np.ndarray, np.ndarray]:
        """The faces as triangles, for drawing and triangle-only formats.

        Each polygon is split into the fan ``(v0, v_i, v_i+1)``; triangles stay.

        Returns
        -------
        triangles : (t, 3) int64 ndarray
        face_of_triangle : (t,) int64 ndarray
            The face each triangle comes from (labels map with ``labels[face_of_triangle]``).
        """
        if self.is_triangular:
            return np.asarray(self.faces), np.arange(self.n_faces, dtype=np.int64)
        sizes = self.face_sizes
        owner = np.repeat(np.arange(self.n_faces, dtype=np.int64), sizes - 2)
        start = np.asarray(self.offsets)[:-1][owner]
        first = np.arange(owner.size) - np.repeat(np.cumsum(sizes - 2) - (sizes - 2), sizes - 2)
        c = np.asarray(self.corners)
        tri = np.stack([c[start], c[start + first + 1], c[start + first + 2]], axis=1)
        return tri, owner

    def colors_of_faces(self) -> np.ndarray | None:
        """(m, 3) float64: the RGB of each face in ``[0, 1]``, None without colours; a
        face without a colour of its own takes the mean of its vertices'
        (:func:`superfacets.inputs.rgb.face_means`).

        Examples
        --------
        >>> m = Mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]],
        ...          colors=[[1, 0, 0], [0, 1, 0], [0, 0, 1]])
        >>> m.colors_of_faces().round(3).tolist()
        [[0.333, 0.333, 0.333]]
        """
        if self.face_colors is not None or self.colors is None:
            return self.face_colors
        return face_means(self.colors, np.asarray(self.corners), np.asarray(self.offsets))

    def colors_of_vertices(self) -> np.ndarray | None:
        """(n, 3) float64: the RGB of each vertex in ``[0, 1]``, None without colours; a
        vertex without a colour of its own takes the mean of its faces'
        (:func:`superfacets.inputs.rgb.vertex_means`).

        Examples
        --------
        >>> m = Mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], face_colors=[[1, 0, 0]])
        >>> m.colors_of_vertices().tolist()[0]
        [1.0, 0.0, 0.0]
        """
        if self.colors is not None or self.face_colors is None:
            return self.colors
        return vertex_means(self.face_colors, np.asarray(self.corners),
                            np.asarray(self.offsets), self.n_vertices)

    def polygons(self) -> list[np.ndarray]:
        """The faces as a list of vertex index arrays (one per face, any size)."""
        return np.split(np.asarray(self.corners), self.offsets[1:-1])

    @cached_property
    def _geometry(self) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        return self._compute_geometry()

    def _release_normals(self) -> None:
        """Forget the cached normals (24 bytes per face; the face graph's
        :meth:`~superfacets.elements.ElementGraph.release`); they are computed
        again, the same, on next use."""
        geometry = self.__dict__.get("_geometry")
        if geometry is not None:
            self.__dict__["_geometry"] = (geometry[0], geometry[1], None)

    def _compute_geometry(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        m = self.n_faces
        centroids, areas, normals = np.empty((m, 3)), np.empty(m), np.empty((m, 3))
        v = np.ascontiguousarray(self.vertices)
        if self.is_triangular:  # one pass: no (m, 3) temporaries; ranges of faces on threads
            f = np.ascontiguousarray(self.faces)
            face_geometry = native.kernel("geometry.face_geometry")
            threads.run_ranges(lambda a, b: face_geometry(v, f[a:b], centroids[a:b], areas[a:b],
                                                  normals[a:b]), split(m))
        else:
            polygon_geometry = native.kernel("geometry.polygon_geometry")
            polygon_geometry(v, np.ascontiguousarray(self.corners), np.asarray(self.offsets),
                             centroids, areas, normals)
        return readonly(centroids), readonly(areas), readonly(normals)

    def _compute_normals(self) -> np.ndarray:
        """The normals alone, as :meth:`_compute_geometry` makes them: the triangles' in
        blocks, each block's centroids and areas written to scratch and let go (the
        normals of a large mesh are made again after being released, while the graph
        holds the centroids and areas already)."""
        if not self.is_triangular:
            return self._compute_geometry()[2]

        m, block = self.n_faces, 1 << 15
        normals = np.empty((m, 3))
        v, f = np.ascontiguousarray(self.vertices), np.ascontiguousarray(self.faces)
        face_geometry = native.kernel("geometry.face_geometry")

        def part(a: int, b: int) -> None:
            centroids, areas = np.empty((min(block, b - a), 3)), np.empty(min(block, b - a))
            for s in range(a, b, block):
                t = min(b, s + block)
                face_geometry(v, f[s:t], centroids[:t - s], areas[:t - s], normals[s:t])

        threads.run_ranges(part, split(m))
        return readonly(normals)

    @property
    def centroids(self) -> np.ndarray:
        """(m, 3) float64: face centroids (triangles: mean of the three vertex positions;
        polygons: area-weighted centroid of their fan triangles)."""
        return self._geometry[0]

    @property
    def areas(self) -> np.ndarray:
        """(m,) float64: face areas (0 for degenerate faces; polygons: by Newell's method)."""
        return self._geometry[1]

    @property
    def normals(self) -> np.ndarray:
        """(m, 3) float64: unit face normals, right-hand rule on vertex order.

        Degenerate (zero-area) faces get the zero vector, so their dihedral
        angle with any neighbour is pi/2 and their edges count as convex.
        """
        geometry = self._geometry
        if geometry[2] is None:  # released: computed again (the same kernel, the same values)
            geometry = (geometry[0], geometry[1], self._compute_normals())
            self.__dict__["_geometry"] = geometry
        return geometry[2]

    @cached_property
    def area(self) -> float:
        """Total surface area ``A`` (sum of face areas)."""
        return float(self.areas.sum())

    @cached_property
    def diagonal(self) -> float:
        """Length ``d`` of the diagonal of the axis-aligned bounding box of the
        vertices referenced by faces."""
        lo, hi = self._bounds
        return float(np.linalg.norm(hi - lo))

    @cached_property
    def _bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(3,) lowest and (3,) highest coordinates of the referenced vertices."""
        return column_bounds(self._used_vertices())

    def _used_vertices(self) -> np.ndarray:
        """The referenced vertices' rows (the array itself when all are referenced)."""
        mask = self.referenced_vertices
        if mask.all() and self.vertices.flags.c_contiguous:
            return self.vertices  # the same values and layout as the masked copy
        return self.vertices[mask]

    @cached_property
    def referenced_vertices(self) -> np.ndarray:
        """(n,) bool: True for vertices used by at least one face."""
        mask, f = np.zeros(self.n_vertices, dtype=bool), self.faces  # (not an int64 copy)
        mask[f.ravel() if self.is_triangular else f[f >= 0]] = True
        return readonly(mask)

    @cached_property
    def centroid(self) -> np.ndarray:
        """(3,) float64: mean position of the referenced vertices (the "mesh
        centroid" of the authors' implementation; the first center is the face
        nearest to it)."""
        return self._used_vertices().mean(axis=0)

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
        extent = check_extent(*self._bounds, where, "mesh")
        if extent == 0:
            raise InvalidMeshError(f"{where}mesh has zero extent (all vertices coincide)")
        if not self.diagonal > 0:
            raise InvalidMeshError(f"{where}mesh has zero extent (all vertices coincide)")
        if not self.area > 0:
            raise InvalidMeshError(f"{where}mesh has zero total area (every face is degenerate)")


def readonly(a: np.ndarray) -> np.ndarray:
    """``a`` made read-only in place (the inputs' arrays and cached geometry), and returned.

    Examples
    --------
    >>> readonly(np.zeros(3)).flags.writeable
    False
    """
    a.setflags(write=False)
    return a


def narrow_faces(faces: np.ndarray, n_vertices: int) -> np.ndarray:
    """``faces`` as int32 where every index fits (for arrays no one else holds: a file
    just read), else unchanged; indices out of range stay so, for the mesh's check.

    Examples
    --------
    >>> [narrow_faces(np.array([[0, 1, i]]), 3).dtype.name for i in (2, 2**40)]
    ['int32', 'int64']
    """
    f = faces
    if (not isinstance(f, np.ndarray) or f.dtype == np.int32
            or not np.issubdtype(f.dtype, np.integer) or f.size == 0
            or n_vertices >= 2**31 - 1):
        return faces
    if int(f.max()) >= 2**31 or int(f.min()) < -1:
        return faces
    return f.astype(np.int32)


def _index_row(row) -> np.ndarray:
    """One face's vertex indices as an array: a row of Python ints in an object array is
    read as the integers it holds (an object row of anything else stays as it is, for the
    caller's message)."""
    r = np.asarray(row).ravel()
    if r.dtype == object and r.size and all(isinstance(x, (int, np.integer)) and
                                            not isinstance(x, bool) for x in r.tolist()):
        values = r.tolist()
        if all(-2**63 <= x < 2**63 for x in values):
            return np.array(values, dtype=np.int64)
    return r


def _faces_array(faces, where: str) -> np.ndarray:
    """Faces as an (m, k) int64 array, polygons of fewer than k vertices padded with -1."""
    if isinstance(faces, np.ndarray) and faces.dtype != object:
        f = faces
    else:
        try:
            f = np.asarray(faces)
        except (ValueError, TypeError):  # a ragged list of polygons
            f = None
        if f is None or f.dtype == object:
            try:
                rows = [_index_row(r) for r in faces]
            except TypeError:
                raise InvalidMeshError(f"{where}faces must be an (m, k) array or a list of "
                                       "vertex index sequences") from None
            if not rows:
                raise InvalidMeshError(f"{where}empty mesh: no faces")
            for i, r in enumerate(rows):
                if r.size and not np.issubdtype(r.dtype, np.integer):
                    raise TypeError(f"{where}faces must hold integers, face {i} is {r.tolist()}")
            width = max(r.size for r in rows)
            f = np.full((len(rows), width), -1, dtype=np.int64)
            for i, r in enumerate(rows):
                if r.size < 3:
                    raise InvalidMeshError(f"{where}face {i} has {r.size} vertices (at least 3 "
                                           f"are needed): {r.tolist()}")
                if (r < 0).any():
                    raise InvalidMeshError(f"{where}face {i} has a negative vertex index: "
                                           f"{r.tolist()}")
                f[i, :r.size] = r
            return f
    if f.ndim != 2:
        raise InvalidMeshError(f"{where}faces must have shape (m, k), got {f.shape}")
    if f.shape[0] == 0:
        raise InvalidMeshError(f"{where}empty mesh: no faces")
    if f.shape[1] < 3:
        raise InvalidMeshError(f"{where}faces need at least 3 vertices, got faces of shape "
                               f"{f.shape}")
    if not np.issubdtype(f.dtype, np.integer):
        raise TypeError(f"{where}faces must be an integer array, got dtype {f.dtype}")
    return f


def check_finite_vertices(vertices, where: str = "", first_row: int = 0,
                          total: int | None = None) -> None:
    """Refuse vertices with a NaN or infinite coordinate, used by a face or not (a mesh's
    whole run and its tiled run alike).

    Parameters
    ----------
    vertices : (n, 3) float ndarray
    where : str, optional
        ``"NAME: "``, the start of the message.
    first_row : int, default 0
        The file's row of ``vertices[0]`` (a chunk of a file read in parts).
    total : int, optional
        How many vertices of the whole file are not finite, where ``vertices`` is a chunk
        of it (None: this array's count).

    Returns
    -------
    None

    Raises
    ------
    InvalidMeshError
        If a vertex has a NaN or infinite coordinate: how many, and the first.

    Examples
    --------
    >>> check_finite_vertices(np.zeros((4, 3)))
    """
    bad = ~np.isfinite(np.asarray(vertices, dtype=np.float64)).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        n = int(bad.sum()) if total is None else total
        raise InvalidMeshError(
            f"{where}{counted(n, 'vertex', 'vertices')} {'has' if n == 1 else 'have'} NaN or "
            f"infinite coordinates (first: vertex {first_row + i} = "
            f"{np.asarray(vertices[i]).tolist()})")


def _validate_arrays(vertices, faces, name: str = "") -> tuple[np.ndarray, np.ndarray]:
    where = f"{name}: " if name else ""
    try:
        v = check_unmasked(vertices, where + "vertices", InvalidMeshError)
    except InvalidMeshError:
        raise
    except Exception as exc:  # ragged lists and the like
        raise InvalidMeshError(f"{where}vertices are not an array: {exc}") from None
    if v.ndim != 2 or v.shape[1] != 3:
        raise InvalidMeshError(f"{where}vertices must have shape (n, 3), got {v.shape}")
    check_real(v.dtype, where + "vertices")
    f = _faces_array(faces, where)
    if f.dtype.kind == "u" and f.size and int(f.max()) >= v.shape[0]:  # (before a cast
        rows = np.flatnonzero((f >= v.shape[0]).any(axis=1))  # to int64 could wrap it)
        raise InvalidMeshError(
            f"{where}{rows.size} faces have vertex indices out of range 0..{v.shape[0] - 1} "
            f"(first: face {int(rows[0])} = {f[int(rows[0])].tolist()})")
    v = np.ascontiguousarray(v, dtype=np.float64)
    # int32 faces stay int32 (the readers': :func:`narrow_faces`), other types int64
    f = np.ascontiguousarray(f, dtype=np.int32 if f.dtype == np.int32 and v.shape[0] < 2**31 - 1
                             else np.int64)
    check_finite_vertices(v, where)
    n = v.shape[0]
    padded = f.shape[1] > 3 and bool((f[:, 3:] < 0).any())
    if padded:  # polygons of several sizes: -1 pads each row after its vertices
        valid = f >= 0
        sizes = valid.sum(axis=1)
        if not (valid == (np.arange(f.shape[1]) < sizes[:, None])).all() or (sizes < 3).any():
            i = int(np.flatnonzero((sizes < 3) | (valid != (np.arange(f.shape[1])
                                                             < sizes[:, None])).any(axis=1))[0])
            raise InvalidMeshError(f"{where}face {i} is not a polygon of 3 or more vertices "
                                   f"(-1 may only pad the end of a row): {f[i].tolist()}")
        out = f >= n
        lo, hi = 0, int(f.max())
    else:
        lo, hi = int(f.min()), int(f.max())
        out = (f < 0) | (f >= n)
    if lo < 0 or hi >= n:
        badf = np.flatnonzero(out.any(axis=1))
        i = int(badf[0])
        raise InvalidMeshError(
            f"{where}{badf.size} faces have vertex indices out of range 0..{n - 1} "
            f"(first: face {i} = {[x for x in f[i].tolist() if x >= 0 or not padded]})"
        )
    # read-only views: the caller's arrays stay writable and untouched
    v = v.view()
    f = f.view()
    v.setflags(write=False)
    f.setflags(write=False)
    return v, f
