"""One box of a large input at a time: streamed reading for tiled runs.

A :class:`RegionReader` holds a file's name and layout, never its data: it
is small and picklable, so it travels to Dask workers, and each worker reads
only the elements of its tile (:meth:`RegionReader.read_box`). Every read
goes through the file in chunks of :data:`CHUNK` rows, so no process holds
more than one chunk beyond the box it keeps.

Streamed formats:

- binary PLY triangle meshes (faces read through a fixed-size record: a
  face with other than 3 corners is an error naming it), the vertex
  positions memory-mapped;
- binary PLY point clouds (a ``vertex`` element without faces; colours
  ``red green blue`` kept), memory-mapped;
- LAS / LAZ point clouds (``laspy``'s chunk iterator; extra ``clouds``);
- ``.npy`` arrays of points ``(N, 3)``, memory-mapped.

Anything else (OBJ, OFF, ASCII PLY, PCD, arrays in memory) is read once by
:meth:`RegionReader.spill` and written to ``.npy`` files in a work folder,
which the workers then memory-map: that input must fit one machine.

The element of a face is its centroid, of a point the point; a box keeps
the elements whose position lies in it (bounds included). Non-finite
points lie in no box (their label stays -1).

A tiled run reads the file twice in all: once for its bounds
(:meth:`RegionReader.survey`) and once to sort its elements into one file
per tile (:func:`superfacets.scale.tiles.buckets.bucket`); every box is then read
from the files of the tiles it overlaps, not from the whole file.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._runtime import extras
from ..elements.kinds import kind_of
from ..errors import InvalidMeshError, MeshFormatError
from ..inputs.bounds import along, column_bounds, finite_rows, rows_in_box
from ..inputs.cloud import (
    InvalidCloudError,
    PointCloud,
    as_cloud,
    missing_points,
    stretched_along,
    stretched_normals,
)
from ..inputs.convert import as_mesh
from ..inputs.mesh import Mesh, check_finite_vertices
from ..inputs.rgb import color_top, unit_colors
from .clouds import (
    SCENE_ASSETS,
    SCENE_UP,
    is_cloud_file,
    read_cloud,
    unusable_normals,
    withheld_rows,
)
from .files import format_hint
from .headers import NotStreamedError, check_las, first_line, npy_mapped, ply_mapped, ply_names
from .meshes import read_mesh
from .ply import VertexView

__all__ = ["RegionReader", "Survey", "CHUNK", "STREAMED", "SAMPLE", "point_cloud_of",
           "face_centroids", "streamed"]

#: Rows read at once.
CHUNK = 1 << 18
#: Suffixes read in chunks without holding the file.
STREAMED = ("ply", "las", "laz", "npy")
#: A binary PLY's vertex positions are read into memory for a pass over its faces where
#: they take at most this (44M vertices); larger, each chunk gathers its faces' corners
#: from the mapped file.
VERTEX_TABLE_BYTES = 1 << 30
#: Positions kept by a survey, at most (every ``ceil(n_rows / SAMPLE)``-th row): 24 MiB.
SAMPLE = 1 << 20


def streamed(path) -> bool:
    """Whether :meth:`RegionReader.open` reads the file at ``path`` in chunks: one of
    :data:`STREAMED`, a PLY binary, with faces (if any) of one list property of three
    corners, an NPY of ``(N, 3)`` points. Any other file a tiled run reads whole
    (:meth:`RegionReader.spill`: an organized ``(H, W, 3)`` NPY, points and normals
    ``(N, 6)``, as one run reads them).

    Parameters
    ----------
    path : str or pathlib.Path

    Returns
    -------
    bool

    Raises
    ------
    MeshFormatError
        If a PLY's header is damaged.

    Examples
    --------
    >>> _ = trimesh.creation.box().export("box.ply")
    >>> streamed("box.ply"), streamed("box.obj")
    (True, False)
    """
    p = Path(path)
    suffix = p.suffix.lower().lstrip(".")
    if suffix not in STREAMED:
        return False
    if suffix not in ("ply", "npy") or not p.is_file():
        return True
    if suffix == "npy":
        try:
            arr = npy_mapped(p)
        except MeshFormatError:
            return False  # (read whole: the reader says what is wrong)
        assets = p.name == "coord.npy" and any((p.parent / f"{a}.npy").is_file()
                                                for a in SCENE_ASSETS)
        return arr.ndim == 2 and arr.shape[1] == 3 and not assets  # (a scene's: whole)
    try:
        ply = ply_mapped(p)
    except NotStreamedError:
        return False
    except MeshFormatError as exc:
        raise MeshFormatError(str(exc) + format_hint(p)) from None
    if "face" not in [e.name for e in ply.elements] or ply["face"].count == 0:
        return True
    face = ply["face"]
    return len(face.properties) == 1 and isinstance(face.data, np.memmap)


@dataclass(frozen=True)
class Survey:
    """What one pass over the input tells: bounds, total size, element count."""

    lo: np.ndarray
    hi: np.ndarray
    #: total area of the faces (the number of points for a cloud)
    size: float
    n_elements: int
    #: (s, 3) float64: the finite positions of every ``ceil(n_rows / SAMPLE)``-th row,
    #: for balanced tiles (:func:`superfacets.scale.tiles.layout.balanced_tiles`)
    sample: np.ndarray | None = None
    #: the points carry normals (a point cloud's file has them)
    normals: bool = False
    #: the elements carry colours (a point's, a face's own or its vertices' mean)
    colors: bool = False
    #: the divisor of the points' integer colours over the whole file (None: not integers)
    color_top: float | None = None
    #: (s,) int64: the row in the input of each position of ``sample``
    sample_rows: np.ndarray | None = None
    #: ``(unusable, normals, first row)`` where some of the file's normals are zero or not
    #: finite: then none is read (``normals`` is False), all are estimated, as one run does
    #: (:func:`superfacets.io.clouds.given_normals`); None: every one usable, or none given
    dropped_normals: tuple | None = None
    #: ``(least, greatest)``, each (a,) float64: the positions along the axes the survey was
    #: asked for (:func:`~superfacets.inputs.bounds.along`); None: none asked
    extent_along: tuple | None = None


@dataclass(frozen=True)
class RegionReader:
    """A large mesh or point cloud, read one axis-aligned box at a time.

    Use :meth:`open` (a file) or :meth:`spill` (anything the package reads,
    written to ``.npy`` files first).

    Attributes
    ----------
    path : str
        The file read (for spilled inputs, the folder of ``.npy`` files).
    kind : {'faces', 'points'}
    layout : str
        ``'ply-mesh'``, ``'ply-points'``, ``'las'``, ``'npy-points'`` or ``'npy-mesh'``.
    n_rows : int
        Faces or points in the file (the length of the labels).
    """

    path: str
    kind: str
    layout: str
    n_rows: int
    chunk: int = CHUNK
    #: sensor position of a scan (a PCD's ``VIEWPOINT``): every tile turns its estimated
    #: normals towards it, so tiles orient them alike
    viewpoint: tuple | None = None
    #: the side an open surface was seen from (LAS: z up, ``PointCloud.up``): the survey's
    #: orientation sample is turned to agree with it, and the tiles with the sample
    up: tuple | None = None
    #: the divisor of the file's integer point colours, decided by the survey for the
    #: whole file (:func:`superfacets.inputs.rgb.color_top`); None: each chunk's own
    color_top: float | None = None
    #: the up coordinate's weight (``up_weight``): the points' positions and given normals
    #: are read stretched along ``up`` (:func:`superfacets.inputs.cloud.stretched_along`)
    up_weight: float = 1.0
    #: rows without a finite position are invalid points (an organized scan's holes, -1
    #: labels) rather than damage; only a spilled cloud that had such points says so
    invalid_ok: bool = False
    #: False: the points' normals are not read (the survey found them all zero)
    normals_given: bool = True

    # ------------------------------------------------------------------ opening
    @classmethod
    def open(cls, path, *, chunk: int = CHUNK) -> "RegionReader":
        """A reader of a streamed file (:data:`STREAMED`).

        Raises
        ------
        FileNotFoundError
            If there is no such file.
        MeshFormatError
            If the file is not a streamed format, or its header is damaged.
        """
        p = Path(path)
        if not p.is_file():
            raise FileNotFoundError(f"{p}: no such file")
        try:
            return cls._opened(p, chunk)
        except MeshFormatError as exc:
            raise MeshFormatError(str(exc) + format_hint(p)) from None

    @classmethod
    def _opened(cls, p: Path, chunk: int) -> "RegionReader":
        suffix = p.suffix.lower().lstrip(".")
        if suffix == "ply":
            ply = ply_mapped(p)  # memory-mapped: the header is read, not the data
            names = [e.name for e in ply.elements]
            if "face" in names and ply["face"].count > 0:
                return cls(str(p), "faces", "ply-mesh", int(ply["face"].count), chunk)
            return cls(str(p), "points", "ply-points", int(ply["vertex"].count), chunk)
        if suffix in ("las", "laz"):
            laspy = extras.require("laspy", "reading LAS/LAZ files")
            check_las(p)
            try:
                with laspy.open(p) as f:
                    n = int(f.header.point_count)
            except Exception as exc:  # noqa: BLE001 - laspy raises many types
                raise MeshFormatError(f"{p}: cannot read {suffix.upper()}: "
                                      f"{first_line(exc)}") from None
            # (a LAS position is an integer: only a withheld point, read as invalid, has none)
            return cls(str(p), "points", "las", n, chunk, up=(0.0, 0.0, 1.0), invalid_ok=True)
        if suffix == "npy":
            arr = npy_mapped(p)
            if arr.ndim != 2 or arr.shape[1] != 3:
                raise MeshFormatError(f"{p}: a tiled run reads NPY points of shape (N, 3), "
                                      f"got {arr.shape}")
            up = SCENE_UP if p.name == "coord.npy" else None  # (a scene folder's points)
            return cls(str(p), "points", "npy-points", int(arr.shape[0]), chunk, up=up)
        raise MeshFormatError(f"{p}: .{suffix} is not read in chunks (streamed: "
                              f"{', '.join('.' + s for s in STREAMED)}): use "
                              "RegionReader.spill, which reads it whole")

    @classmethod
    def spill(cls, source, folder, *, chunk: int = CHUNK) -> "RegionReader":
        """Write a mesh or cloud the package can read (a path or an object) to
        ``.npy`` files in ``folder`` and read those.

        Raises
        ------
        MeshFormatError, InvalidMeshError
            As the readers do; also for a polygon mesh (tiles take triangles).
        """

        obj = source
        if isinstance(source, (str, Path)):
            obj = read_cloud(source) if is_cloud_file(source) else read_mesh(source)
        from ..elements.builders import is_cloud  # (one rule of what a cloud is)

        obj = as_cloud(obj) if is_cloud(obj) else as_mesh(obj)
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        if isinstance(obj, PointCloud):
            pts = np.where(obj.valid[:, None], obj.points, np.nan)
            np.save(folder / "points.npy", np.ascontiguousarray(pts, dtype=np.float64))
            for name, a in (("colors", obj.colors), ("normals", obj.normals)):
                if a is not None:
                    np.save(folder / f"{name}.npy", np.ascontiguousarray(a, dtype=np.float64))
            vp = None if obj.viewpoint is None else tuple(float(x) for x in obj.viewpoint)
            up = getattr(obj, "up", None)
            return cls(str(folder), "points", "npy-points", int(pts.shape[0]), chunk, vp,
                       None if up is None else tuple(float(x) for x in up),
                       invalid_ok=not bool(obj.valid.all()))
        obj.check_usable()  # the whole run's checks (NaN coordinates, extent, ...)
        faces = obj.faces
        if faces.ndim != 2 or faces.shape[1] != 3:
            raise MeshFormatError(f"{obj.name or 'mesh'}: a tiled run takes triangle meshes "
                                  "or point clouds, and this mesh has polygons: segment it "
                                  "without tiles (one run takes polygons), or triangulate it")
        np.save(folder / "vertices.npy", np.ascontiguousarray(obj.vertices, dtype=np.float64))
        np.save(folder / "faces.npy", np.ascontiguousarray(faces, dtype=np.int64))
        if obj.colors_of_faces() is not None:
            np.save(folder / "face_colors.npy", obj.colors_of_faces())
        return cls(str(folder), "faces", "npy-mesh", int(faces.shape[0]), chunk)

    # ------------------------------------------------------------------ reading
    def chunks(self, stats: dict | None = None):
        """Yield ``(start, positions (c, 3) float64, sizes (c,) float64, extra)`` per chunk:
        face centroids and areas (``extra``: the faces' vertex indices, the vertex array
        and the faces' colours, None when absent), or points and ones (``extra``: their
        colours and normals, each None when absent)."""
        if self.kind == "faces":
            verts, faces, colors = self._mesh_arrays()
            n_v = verts.shape[0]
            for s in range(0, self.n_rows, self.chunk):
                tri = faces(s, min(s + self.chunk, self.n_rows))
                if tri.size and (tri.min() < 0 or tri.max() >= n_v):
                    bad = s + int(np.flatnonzero(((tri < 0) | (tri >= n_v)).any(1))[0])
                    raise MeshFormatError(f"{self.path}: face {bad} has a vertex index out "
                                          f"of range 0..{n_v - 1}")
                p = verts[tri]  # (c, 3, 3)
                x = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
                area = x[:, 0] * x[:, 0]  # (np.linalg.norm's sum of squares, in its order)
                area += x[:, 1] * x[:, 1]
                area += x[:, 2] * x[:, 2]
                area = 0.5 * np.sqrt(area)
                yield s, face_centroids(p), area, (tri, verts, colors(s, s + tri.shape[0], tri))
            return
        for s, pts, extra in self._point_chunks(stats):
            if not self.normals_given:  # (placeholders: estimated, as one run does)
                extra = (extra[0], None)
            if self.up_weight != 1:  # (the cloud the method's distances are read on)
                u = np.asarray(self.up, dtype=np.float64)
                pts = stretched_along(pts, u, self.up_weight)
                col, nrm = extra
                extra = (col, None if nrm is None else stretched_normals(nrm, u,
                                                                         self.up_weight))
            yield s, pts, np.ones(pts.shape[0]), extra

    def survey(self, axes: np.ndarray | None = None) -> Survey:
        """Bounds of the finite element positions, total size and count, and an even
        sample of the positions (at most :data:`SAMPLE`), in one pass.

        Parameters
        ----------
        axes : (a, 3) float64 ndarray, optional
            Also the least and greatest of the positions along each
            (:func:`~superfacets.inputs.bounds.along`): ``Survey.extent_along``.

        Raises
        ------
        MeshFormatError
            If no element has a finite position, or a face index is out of range.
        """
        lo = np.full(3, np.inf)
        hi = np.full(3, -np.inf)
        size = 0.0
        n = 0
        stride = max(1, -(-self.n_rows // SAMPLE))
        kept, kept_rows = [], []
        normals = colors = False
        bad = [0, 0, -1]  # (normals unusable, looked at, the first unusable's row)
        stats: dict = {}
        span = None if axes is None else np.array([[np.inf] * len(axes), [-np.inf] * len(axes)])
        if self.kind == "faces":
            self._check_vertices()
        for start, pos, sz, extra in self.chunks(stats):
            given = self.kind == "points" and extra[1] is not None
            normals = normals or given
            if given:
                _count_unusable(extra[1], finite_rows(pos), start, bad)
            colors = colors or extra[-1 if self.kind == "faces" else 0] is not None
            ok = finite_rows(pos)  # (one compiled pass each, not numpy's over short rows)
            every = bool(ok.all())
            if not (every or self.invalid_ok):
                self._non_finite(start, pos, ok)
            if every or ok.any():
                low, high = column_bounds(pos if every else pos[ok])
                lo = np.minimum(lo, low)
                hi = np.maximum(hi, high)
                if span is not None:
                    span = _extended(span, pos if every else pos[ok], axes)
                size += float(sz.sum() if every else sz[ok].sum())
                n += pos.shape[0] if every else int(ok.sum())
                at = np.arange((-start) % stride, pos.shape[0], stride)
                finite = ok[at]
                kept.append(pos[at[finite]])
                kept_rows.append(start + at[finite])
        if n == 0:
            raise MeshFormatError(f"{self.path}: no {kind_of(self.kind).singular} with a "
                                  "finite position")

        top = color_top(stats["itemsize"], stats["largest"]) if stats else None
        return Survey(lo, hi, size, n, np.concatenate(kept).astype(np.float64),
                      normals and not bad[0], colors, top,
                      np.concatenate(kept_rows).astype(np.int64),
                      dropped_normals=tuple(bad) if bad[0] else None,
                      extent_along=None if span is None else (span[0], span[1]))

    def _check_vertices(self):
        """Refuse a vertex without a finite position, used by a face or not, as a whole
        run refuses it (:func:`~superfacets.inputs.mesh.check_finite_vertices`)."""
        verts = self._mesh_arrays()[0]
        n = verts.shape[0]
        total, first = 0, None
        for a in range(0, n, self.chunk):
            b = min(n, a + self.chunk)
            block = np.asarray(verts[a:b] if isinstance(verts, np.ndarray) else
                               verts[np.arange(a, b)], dtype=np.float64)
            ok = finite_rows(block)
            if not ok.all():
                total += int((~ok).sum())
                first = first or (a, block)
        if first is not None:
            check_finite_vertices(first[1], f"{self.path}: ", first[0], total)

    def _non_finite(self, start: int, pos: np.ndarray, ok: np.ndarray):
        """Refuse a chunk's rows without a finite position, as a whole run refuses them,
        but a PLY's missing points (:func:`~superfacets.inputs.cloud.missing_points`)."""

        if self.layout == "ply-points":
            missing_points(pos, self.path, start)
            return
        row = start + int(np.flatnonzero(~ok)[0])
        if self.kind == "faces":
            raise InvalidMeshError(f"{self.path}: face {row} has a vertex with a non-finite "
                                   "coordinate (NaN or inf)")
        raise InvalidCloudError(f"{self.path}: point {row} has a non-finite coordinate (NaN "
                                "or inf)")

    def read_box(self, lo, hi, name: str = ""):
        """The elements whose position lies in ``[lo, hi]``, as an input of their own.

        Returns
        -------
        rows : (c,) int64 ndarray
            Their rows in the file, increasing.
        positions : (c, 3) float64 ndarray
            Their positions (face centroids, points).
        input : Mesh or PointCloud or None
            The faces (with the vertices they use) or the points (with their
            colours), in that order; None where the box holds no element.
        """

        lo = np.asarray(lo, dtype=np.float64)
        hi = np.asarray(hi, dtype=np.float64)
        rows, keep, where = [], [], []
        verts = None
        for s, pos, _, extra in self.chunks():
            inside = np.flatnonzero(rows_in_box(pos, lo, hi))
            rows.append(inside + s)
            where.append(pos[inside])
            if self.kind == "faces":
                tri, verts, col = extra
                keep.append((tri[inside], None if col is None else col[inside]))
            else:
                keep.append((None,) + tuple(None if a is None else a[inside] for a in extra))
        rows = np.concatenate(rows).astype(np.int64) if rows else np.empty(0, dtype=np.int64)
        where = np.concatenate(where) if where else np.empty((0, 3))
        if rows.size == 0:
            return rows, where, None
        if self.kind == "faces":
            tri = np.concatenate([k[0] for k in keep])
            col = None if keep[0][1] is None else np.concatenate([k[1] for k in keep])
            used, local = np.unique(tri, return_inverse=True)
            return rows, where, Mesh(np.asarray(verts[used], dtype=np.float64),
                                     local.reshape(tri.shape), name=name, face_colors=col)
        col, nrm = (None if keep[0][i] is None else np.concatenate([k[i] for k in keep])
                    for i in (1, 2))
        # (the cloud reads the positions the caller is given: one array, not two)
        return rows, where, point_cloud_of(where, col, nrm, self.viewpoint, name)

    # ------------------------------------------------------------------ layouts
    def _mesh_arrays(self):
        """(vertex positions (n, 3), faces(start, stop) -> (c, 3) int64, colors(start, stop,
        tri) -> the faces' colours (c, 3) float64 in [0, 1] or None)."""
        if self.layout == "npy-mesh":
            folder = Path(self.path)
            verts = np.load(folder / "vertices.npy", mmap_mode="r")
            faces = np.load(folder / "faces.npy", mmap_mode="r")
            fcol = (np.load(folder / "face_colors.npy", mmap_mode="r")
                    if (folder / "face_colors.npy").exists() else None)
            return (verts, lambda a, b: np.asarray(faces[a:b], dtype=np.int64),
                    lambda a, b, tri: None if fcol is None else np.asarray(fcol[a:b]))
        ply = ply_mapped(Path(self.path))
        v = ply["vertex"].data
        verts = VertexView(v).table(VERTEX_TABLE_BYTES)  # (in memory where it is small)
        rgb = next((c for c in (("red", "green", "blue"), ("r", "g", "b"))
                    if set(c) <= set(v.dtype.names)), None)
        vcol = None if rgb is None else VertexView(v, rgb)
        face = ply["face"]
        prop = face.properties[0]
        data = face.data
        if not isinstance(data, np.memmap) or len(face.properties) != 1:
            raise NotStreamedError(f"{self.path}: a tiled run reads binary PLY faces in "
                                   "chunks with one list property (vertex_indices) alone")
        order = ply.byte_order if ply.byte_order in "<>" else "="
        rec = np.dtype([("n", order + prop.len_dtype), ("v", order + prop.val_dtype, (3,))])
        raw = np.memmap(self.path, dtype=rec, mode="r", offset=data.offset, shape=(face.count,))

        def faces(a, b):
            block = raw[a:b]
            wrong = np.flatnonzero(block["n"] != 3)
            if wrong.size:
                raise MeshFormatError(f"{self.path}: face {a + int(wrong[0])} has "
                                      f"{int(block['n'][wrong[0]])} corners: a tiled run takes "
                                      "triangles (one run takes polygons: without tiles)")
            return np.asarray(block["v"], dtype=np.int64)

        # a face's colour: the mean of its vertices' (a tiled run reads binary PLY faces
        # with their vertex indices alone)
        return verts, faces, lambda a, b, tri: None if vcol is None else vcol[tri].mean(axis=1)

    def _colors(self, raw: np.ndarray, stats: dict | None) -> np.ndarray:
        """A chunk's colours in [0, 1]: integers divided by the file's :attr:`color_top`
        where the survey decided it (``stats`` collects what it needs)."""

        if stats is not None and np.issubdtype(raw.dtype, np.integer) and raw.size:
            stats["itemsize"] = raw.dtype.itemsize
            stats["largest"] = max(stats.get("largest", 0), int(raw.max()))
        return unit_colors(raw, self.color_top)

    def _point_chunks(self, stats: dict | None = None):
        if self.layout == "las":
            yield from self._las_chunks(stats)
            return
        if self.layout == "npy-points":
            p = Path(self.path)
            folder = p if p.is_dir() else None
            pts = np.load(folder / "points.npy" if folder else p, mmap_mode="r")
            more = [np.load(folder / f"{n}.npy", mmap_mode="r")
                    if folder and (folder / f"{n}.npy").exists() else None
                    for n in ("colors", "normals")]
            for s in range(0, self.n_rows, self.chunk):
                e = min(s + self.chunk, self.n_rows)
                yield s, np.asarray(pts[s:e], dtype=np.float64), tuple(
                    None if a is None else np.asarray(a[s:e], dtype=np.float64) for a in more)
            return
        v = ply_mapped(Path(self.path))["vertex"].data
        names = v.dtype.names
        rgb = next((c for c in (("red", "green", "blue"), ("r", "g", "b")) if set(c) <= set(names)),
                   None)
        named = ply_names(names)  # (X, Y, Z as PDAL writes them too)
        xyz = tuple(named[c] for c in "xyz")
        nrm = tuple(named[c] for c in ("nx", "ny", "nz")) if {"nx", "ny", "nz"} <= set(
            named) else None
        for s in range(0, self.n_rows, self.chunk):
            block = v[s:s + self.chunk]
            pos, n = (None if c is None else np.stack(
                [np.asarray(block[a], dtype=np.float64) for a in c], axis=1)
                for c in (xyz, nrm))
            yield s, pos, (None if rgb is None else self._colors(
                np.stack([np.asarray(block[c]) for c in rgb], axis=1), stats), n)

    def _las_chunks(self, stats: dict | None):
        import laspy

        s = 0
        try:
            with laspy.open(self.path) as f:
                dims = set(f.header.point_format.dimension_names)
                rgb = {"red", "green", "blue"} <= dims
                for pts in f.chunk_iterator(self.chunk):
                    xyz = np.stack([np.asarray(pts.x), np.asarray(pts.y), np.asarray(pts.z)],
                                   axis=1).astype(np.float64)
                    withheld = withheld_rows(pts, dims)
                    if withheld is not None:  # (invalid, as one run reads them)
                        xyz[withheld] = np.nan
                    col = (self._colors(np.stack([np.asarray(pts[c]) for c in
                                                  ("red", "green", "blue")], 1), stats)
                           if rgb else None)
                    yield s, xyz, (col, None)
                    s += xyz.shape[0]
        except Exception as exc:  # noqa: BLE001 - laspy and lazrs raise many types
            raise MeshFormatError(f"{self.path}: cannot read the points after row {s} "
                                  f"(damaged or truncated file?): {first_line(exc)}") from None
        if s != self.n_rows:
            raise MeshFormatError(f"{self.path}: the header declares {self.n_rows} points, "
                                  f"the file holds {s} (truncated?)")


def face_centroids(corners: np.ndarray) -> np.ndarray:
    """The centroids of triangles from their corners, as a reader's chunks give them.

    Parameters
    ----------
    corners : (c, 3, 3) float64 ndarray
        Each face's three corners.

    Returns
    -------
    (c, 3) float64 ndarray
        numpy's mean over the corners, bit for bit (its sum in the same order, without its
        reduction's strides), so a tile's records can leave them out and compute them
        again (:mod:`superfacets.scale.tiles.buckets`).

    Raises
    ------
    ParameterError
        Never: the shape is the caller's.

    Examples
    --------
    >>> p = np.random.default_rng(0).random((5, 3, 3))
    >>> bool((face_centroids(p) == p.mean(axis=1)).all())
    True
    """
    centroid = corners[:, 0] + corners[:, 1]
    centroid += corners[:, 2]
    centroid /= 3.0
    return centroid


def _count_unusable(normals: np.ndarray, finite: np.ndarray, start: int, bad: list) -> None:
    """Add a chunk's normals to ``bad`` (:meth:`RegionReader.survey`): how many of those at
    finite positions are zero or not finite, how many were looked at, the first's row."""
    rows = np.flatnonzero(finite)
    unusable = unusable_normals(normals, rows)
    if unusable.size and bad[2] < 0:
        bad[2] = start + int(unusable[0])
    bad[0] += int(unusable.size)
    bad[1] += int(rows.size)


def point_cloud_of(pts, colors, normals, viewpoint, name: str = ""):
    """A :class:`~superfacets.inputs.cloud.PointCloud` of a box's points (``viewpoint`` a tuple or
    None)."""

    vp = None if viewpoint is None else np.asarray(viewpoint)
    return PointCloud(pts, normals, name=name, colors=colors, viewpoint=vp)


def _extended(span: np.ndarray, pos: np.ndarray, axes) -> np.ndarray:
    """``span`` (2, a) widened to the positions' least and greatest along each axis."""
    vals = np.stack([along(pos, np.asarray(a, dtype=np.float64)) for a in axes])
    return np.stack([np.minimum(span[0], vals.min(axis=1)), np.maximum(span[1], vals.max(axis=1))])
