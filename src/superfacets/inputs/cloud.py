"""Point clouds: validated points (and normals).

A :class:`PointCloud` holds ``(N, 3) float64`` points in input order. Rows
that are not finite are *invalid points* only where the input says so (an
organized cloud, a PCD file: PCL marks missing measurements with NaN); they
take no part in the method and get the label -1. Elsewhere a non-finite row is
an error naming the row. Exact duplicate points are segmented as one element
(they get the same label).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from .._kernels import native
from ..checks import check_name, check_real, check_unmasked, check_up, counted
from ..errors import InvalidCloudError, ParameterError
from .bounds import check_extent, column_bounds, finite_rows
from .mesh import readonly
from .rgb import check_colors, unit_colors

__all__ = ["PointCloud", "as_cloud", "InvalidCloudError", "up_weighted", "surface_up_weight",
           "UP_SAMPLE", "UP_NEIGHBOURHOODS", "UP_NEIGHBOURS", "unweighed_area_factor",
           "stretched_along",
           "stretched_normals", "check_weighable"]


@dataclass(frozen=True, eq=False)
class PointCloud:
    """A validated point cloud, optionally with normals.

    Parameters
    ----------
    points : (N, 3) float ndarray
        Point positions, any units.
    normals : (N, 3) float ndarray, optional
        Normals, trusted as consistently oriented (made unit). Leave them out
        to have them estimated (PCA of each neighbourhood, then oriented).
    name : str, optional
        For messages.
    viewpoint : (3,) float ndarray, optional
        Sensor position (a PCD file's ``VIEWPOINT``): estimated normals are
        turned towards it.
    allow_invalid : bool, default False
        Non-finite rows are invalid points (label -1) instead of an error.
    shape : tuple of int, optional
        ``(height, width)`` of an organized cloud (labels keep that layout
        in :func:`superfacets.superpoints`).
    colors : (N, 3) float ndarray, optional
        RGB colour of each point in ``[0, 1]`` (the readers scale 8- and
        16-bit colours): what ``beta > 0`` of :func:`superfacets.segment`
        uses when no ``features`` are given.
    orient_like : tuple of two (R, 3) float ndarray, optional
        ``(positions, normals)``: consistently oriented normals at some
        positions (a coarser sample of the same surface; empty: ignored).
        Each estimated normal is then turned to agree with the
        one of them nearest its point, instead of by propagation over the
        point graph: a rule of the point and the sample alone, so a tiled run
        that gives every tile one sample of the whole input has every tile
        turn a point alike. Ignored with ``normals`` or ``viewpoint``.
    up : (3,) float ndarray or {'x', 'y', 'z', '-x', '-y', '-z'}, optional
        The side the surface was seen from, on the whole, for a scan of an
        open surface (a terrain, a street) whose sensor position is not
        known: estimated normals are turned, each connected piece of the
        point graph as a whole, so that they agree with this direction by a
        vote (``sum n_i . up >= 0``) instead of outwards from the piece's
        mean, which a nearly flat piece decides by its small bumps (a
        terrain's normals then point down, and its concave edges read as
        convex). The LAS/LAZ reader sets ``(0, 0, 1)`` (LAS z is elevation:
        such scans are seen from above or from the side). Made unit.
        Ignored with ``normals``, ``viewpoint`` or ``orient_like``.
    frame : (2, 3) float ndarray, optional
        A box (lower corner, upper corner) holding the points, whose frame numbers
        them (the Z-order of their coordinates as integers from its lower corner,
        :func:`superfacets.elements.points.distinct_points`). A tiled run gives every
        tile the whole cloud's box, so that a tile numbers its points as the whole
        cloud does. Default: the points' own box.
    objects : tuple of (str, int, int), optional
        ``(name, start, end)`` of each object (each scan of a multi-scan E57 file), its
        rows ``start:end``, in row order, covering every row:
        :func:`superfacets.api.scenes.segment_objects` segments each alone.
    object_viewpoints : (len(objects), 3) float ndarray, optional
        Each object's sensor position (a scan's scanner): its estimated normals face it
        when objects are segmented alone.
    fields : dict of str to (N,) ndarray, optional
        The file's other values per point (a KITTI scan's reflectance, a nuScenes sweep's
        intensity and ring, NPY records' other fields, named text columns), in file order:
        not read by the method, written again into a new file of the points with their
        labels (:func:`superfacets.io.records.write_cloud_with_labels`).

    Raises
    ------
    InvalidCloudError
        If the arrays have the wrong shape, a row is NaN/inf (unless
        ``allow_invalid``), a normal is not finite or zero, or a colour of a
        valid point is not finite or outside ``[0, 1]``.
    TypeError
        If ``points`` is not numeric.

    Examples
    --------
    >>> cloud = PointCloud(np.random.default_rng(0).random((100, 3)))
    >>> cloud
    PointCloud(100 points)
    """

    points: np.ndarray
    normals: np.ndarray | None = None
    name: str = ""
    viewpoint: np.ndarray | None = None
    allow_invalid: bool = False
    shape: tuple | None = field(default=None, repr=False)
    colors: np.ndarray | None = field(default=None, repr=False)
    orient_like: tuple | None = field(default=None, repr=False)
    up: np.ndarray | None = field(default=None, repr=False)
    frame: np.ndarray | None = field(default=None, repr=False)
    objects: tuple = field(default=(), repr=False)
    object_viewpoints: np.ndarray | None = field(default=None, repr=False)
    fields: dict | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "name", check_name(self.name))  # (in every message)
        where = f"{self.name}: " if self.name else ""
        p = _coordinates(self.points, "points", where)
        finite = finite_rows(p)
        if not finite.all() and not self.allow_invalid:
            row = int(np.flatnonzero(~finite)[0])
            raise InvalidCloudError(
                f"{where}point {row} has a non-finite coordinate ({p[row].tolist()}); "
                f"{int((~finite).sum())} such rows (invalid points are marked only in "
                "organized clouds, PCD, E57 and LAS files, and by NaN rows in PLY files)")
        object.__setattr__(self, "points", readonly(p))
        if self.normals is not None:
            nrm = _coordinates(self.normals, "normals", where)
            if nrm.shape != p.shape:
                raise InvalidCloudError(f"{where}normals must have the shape of the points "
                                        f"{p.shape}, got {nrm.shape}")
            length = np.linalg.norm(nrm[finite], axis=1)
            bad = ~(np.isfinite(length) & (length > 0))
            if bad.any():
                row = int(np.flatnonzero(finite)[np.flatnonzero(bad)[0]])
                raise InvalidCloudError(f"{where}normal {row} is zero or not finite "
                                        f"({nrm[row].tolist()}); leave normals out to have "
                                        "them estimated")
            nrm = nrm.copy()
            nrm[finite] /= length[:, None]
            object.__setattr__(self, "normals", readonly(nrm))
        if self.colors is not None:
            col = check_colors(self.colors, p.shape[0], "colour", where, InvalidCloudError,
                               valid=finite)
            object.__setattr__(self, "colors", readonly(col))
        if self.viewpoint is not None:
            try:
                vp = np.asarray(self.viewpoint, dtype=np.float64).reshape(-1)
            except (TypeError, ValueError):  # (words, complex numbers, objects)
                vp = np.full(1, np.nan)
            if vp.shape != (3,) or not np.isfinite(vp).all():
                raise InvalidCloudError(f"{where}viewpoint must be 3 finite numbers, got "
                                        f"{self.viewpoint!r}")
            object.__setattr__(self, "viewpoint", vp)
        if self.orient_like is not None:
            ref = tuple(np.asarray(a, dtype=np.float64) for a in self.orient_like)
            if (len(ref) != 2 or ref[0].ndim != 2 or ref[0].shape[1:] != (3,)
                    or ref[1].shape != ref[0].shape or not all(np.isfinite(a).all() for a in ref)):
                raise InvalidCloudError(f"{where}orient_like must be (positions, normals), "
                                        "two finite (R, 3) arrays")
            object.__setattr__(self, "orient_like", ref)
        if self.frame is not None:
            box = np.asarray(self.frame, dtype=np.float64)
            if box.shape != (2, 3) or not np.isfinite(box).all() or (box[0] > box[1]).any():
                raise InvalidCloudError(f"{where}frame must be a box: its lower and upper "
                                        "corners, (2, 3) finite numbers, lower <= upper")
            object.__setattr__(self, "frame", readonly(box))
        self._check_objects(where, p.shape[0])
        self._check_fields(where, p.shape[0])
        if self.up is not None:
            try:  # (an axis name too, as every other up of the package)
                up = check_up(self.up)
            except ParameterError as exc:
                raise InvalidCloudError(f"{where}{exc}") from None
            object.__setattr__(self, "up", up)

    def _check_objects(self, where: str, n: int) -> None:
        """``objects`` cover the rows in order; ``object_viewpoints`` one finite position
        each."""
        objs = tuple((str(o[0]), int(o[1]), int(o[2])) for o in self.objects)
        ends = [0] + [b for _, _, b in objs]
        if objs and (any(a != ends[i] or b < a for i, (_, a, b) in enumerate(objs))
                     or ends[-1] != n):
            raise InvalidCloudError(f"{where}objects must be (name, start, end) rows in order, "
                                    f"covering the {n} rows, got {list(objs)[:4]}")
        object.__setattr__(self, "objects", objs)
        if self.object_viewpoints is not None:
            vp = np.asarray(self.object_viewpoints, dtype=np.float64)
            if vp.shape != (len(objs), 3) or not np.isfinite(vp).all():
                raise InvalidCloudError(f"{where}object_viewpoints must be one finite position "
                                        f"per object, ({len(objs)}, 3), got {vp.shape}")
            object.__setattr__(self, "object_viewpoints", readonly(vp))

    def _check_fields(self, where: str, n: int) -> None:
        """``fields``: named real or boolean values, one per point."""
        if self.fields is None:
            return
        kept = {}
        for name, values in dict(self.fields).items():
            a = np.asarray(values)
            if not isinstance(name, str) or a.shape != (n,) or a.dtype.kind not in "biuf":
                raise InvalidCloudError(f"{where}field {name!r} must be one number per point "
                                        f"({n:,}), got {a.dtype} {a.shape}")
            kept[name] = readonly(a)
        object.__setattr__(self, "fields", kept)

    def __getstate__(self) -> dict:
        # the fields only: the point graphs kept with the cloud hold functions (which
        # pickle cannot) and are built again where the cloud is unpickled
        return {f: getattr(self, f) for f in self.__dataclass_fields__}

    def __getattr__(self, name: str):
        # the points, lent to the point graph (lend_points): given back on first use
        lent = self.__dict__.get("_lent")
        if lent is None or name != _LENT_FIELD:
            raise AttributeError(f"'PointCloud' object has no attribute {name!r}")
        positions, index, rows, values = lent
        out = np.empty((index.shape[0], 3))
        if rows.shape[0] == 0:  # every row valid (invalid rows are kept among `rows`)
            np.take(positions, index, axis=0, out=out, mode="clip")  # (unbuffered)
        else:
            ok = index >= 0
            out[ok] = positions[index[ok]]
        out[rows] = values
        self.__dict__["points"] = readonly(out)
        self.__dict__.pop("_lent", None)
        return out

    def lend_points(self, positions: np.ndarray, index: np.ndarray) -> bool:
        """Free the points' memory while ``positions[index]`` holds them: the point graph's
        positions (:func:`superfacets.elements.points.point_graph`, the distinct points in
        another order) and each row's element (``-1``: an invalid row). The points are
        given back on first use of :attr:`points`, bit for bit: the rows that
        ``positions[index]`` does not give exactly (invalid rows, ``-0.0`` merged with
        ``0.0``) are kept here.

        Only where the cloud alone holds its points' memory (a cloud read from a file):
        an array the caller also holds would not be freed, so it is kept; and once the
        cloud was found usable (:meth:`check_usable`, which reads them). Saves 24 bytes
        per point of a run's peak.

        Parameters
        ----------
        positions : (m, 3) float64 ndarray
        index : (N,) int ndarray
            Row ``i`` is ``positions[index[i]]``, or invalid where ``index[i] < 0``.

        Returns
        -------
        bool
            Whether the points were lent.

        Examples
        --------
        >>> cloud = PointCloud(np.random.default_rng(0).random((500, 3)))  # its own array
        >>> cloud.check_usable()
        >>> graph = point_graph(cloud).graph  # the build lends the points to the graph
        >>> "points" in cloud.__dict__, cloud.points.shape  # given back when asked
        (False, (500, 3))
        """
        p = self.__dict__.get("points")
        if (p is None or not self.__dict__.get("_usable") or not _held_alone(p)
                or index.shape[0] != p.shape[0]):  # (checked once: not asked for again)
            return False

        bits, at = p.view(np.uint64), positions.view(np.uint64)
        if not (bits.flags.c_contiguous and at.flags.c_contiguous):
            return False
        rows = np.empty(max(1024, p.shape[0] // 8), dtype=np.int64)
        # (beyond that many, the exceptions would cost as much as the points)
        m = native.kernel("geometry.rows_apart")(bits, at, index, rows)
        if m < 0:
            return False
        rows = rows[:m].copy()
        del bits
        self.__dict__["_lent"] = (positions, index, rows, p[rows].copy())
        del self.__dict__["points"]
        return True

    def __repr__(self) -> str:
        invalid = self.n_total - int(self.valid.sum())
        extra = f", {invalid} invalid" if invalid else ""
        extra += ", with normals" if self.normals is not None else ""
        extra += ", with colours" if self.colors is not None else ""
        return f"PointCloud({counted(self.n_total, 'point')}{extra})"

    @property
    def n_total(self) -> int:
        """Number of rows ``N``, invalid ones included."""
        lent = self.__dict__.get("_lent")  # (the points lent: not given back for this)
        return int((self.points if lent is None else lent[1]).shape[0])

    @cached_property
    def valid(self) -> np.ndarray:
        """(N,) bool: True for points with finite coordinates."""
        return readonly(finite_rows(self.points))

    @cached_property
    def n_points(self) -> int:
        """Number of valid points."""
        return int(self.valid.sum())

    def check_usable(self) -> None:
        """Raise :class:`InvalidCloudError` unless the cloud spans a surface.

        Needs a valid point, a positive extent within ``1e-70 .. 1e70``
        (coordinates within ``1e300``), and points that are not all on one
        line (a line has no area, and no normal). The arrays are read-only, so a
        cloud found usable is not checked again (a run asks twice).
        """
        if self.__dict__.get("_usable"):
            return
        where = f"{self.name}: " if self.name else ""
        valid = self.valid
        p = self.points if valid.all() else self.points[valid]
        if p.shape[0] == 0:
            raise InvalidCloudError(f"{where}empty point cloud: no valid point")
        extent = check_extent(*column_bounds(p), where, "cloud")
        if extent == 0:
            raise InvalidCloudError(f"{where}" + (f"all {p.shape[0]} points coincide"
                                                   if p.shape[0] > 1 else "one point alone")
                                    + ": no surface to segment")
        if _on_a_line(p, extent):
            raise InvalidCloudError(f"{where}{_line_cause(p, np.flatnonzero(self.valid))}")
        self.__dict__["_usable"] = True


_BLOCK = 1 << 20  # points centred at a time
_SAMPLE = 4096  # points of the line test's sample (clouds of 4 times as many or more)
_LENT_FIELD = "points"  # the field a cloud lends to its graph (PointCloud.lend_points)


def _held_alone(a: np.ndarray) -> bool:
    """Whether the memory of ``a`` (held by the caller, in one place) is held nowhere
    else: no other reference to it, or to an array it views, down to the owner."""
    refs = 4  # the caller's place, its local name, this argument and getrefcount's
    while True:
        if sys.getrefcount(a) > refs:
            return False
        if a.flags.owndata:
            return True
        if not isinstance(a.base, np.ndarray):  # a buffer, a memory map: not ours to free
            return False
        a, refs = a.base, 3  # the view's reference, `a` and getrefcount's


def _on_a_line(p: np.ndarray, extent: float) -> bool:
    """Whether the points' scatter has no second direction, to double precision.

    A large cloud is first asked of a strided sample: the sample's scatter about its own
    mean is below the whole cloud's (in the Loewner order), whose largest eigenvalue is at
    most ``3 n`` in units of the extent (every centred coordinate within it), so a
    sample's second eigenvalue above twice the test's bound times ``3 n`` settles it
    without a pass over the cloud (10M points: 0.44 s)."""
    n = p.shape[0]
    if n >= 4 * _SAMPLE:
        q = p[::n // _SAMPLE]
        q = (q - q.mean(axis=0)) / extent
        if np.linalg.svd(q.T @ q, compute_uv=False)[1] > 2e-12 * 3.0 * n:
            return False
    mean = p.mean(axis=0)
    scatter = np.zeros((3, 3))
    for s in range(0, p.shape[0], _BLOCK):  # (not a centred copy of the whole cloud)
        q = (p[s:s + _BLOCK] - mean) / extent
        scatter += q.T @ q
    s = np.linalg.svd(scatter, compute_uv=False)
    return bool(s[1] <= 1e-12 * s[0])


#: A point this many times farther from the others' median than nine in ten of them is
#: named as a stray point when the cloud, with it, looks like a line.
_STRAY = 1e4


def _line_cause(p: np.ndarray, rows: np.ndarray) -> str:
    """The message for points that look like one line: a line, or a few stray points so
    far away that the rest look like one beside them (a scanner's error)."""
    d = np.linalg.norm(p - np.median(p, axis=0), axis=1)
    spread = float(np.quantile(d, 0.9))
    far = d > _STRAY * spread
    rest = p[~far]
    if spread > 0 and far.any() and rest.shape[0] >= 3 and \
            not _on_a_line(rest, float(np.ptp(rest, axis=0).max())):
        i = int(np.argmax(d))
        verb = "lies" if far.sum() == 1 else "lie"
        return (f"{int(far.sum())} of {p.shape[0]} points {verb} over {_STRAY:.0f} times "
                f"farther from the others than nine in ten of them (row {int(rows[i])} at "
                f"{d[i]:.3g} from their median, against {spread:.3g}), so the rest look like "
                "one line: remove such stray points")
    return f"all {p.shape[0]} points lie on one line: no surface to segment"


def _library_colors(values) -> np.ndarray | None:
    """A trimesh (RGBA, 8-bit) or Open3D (RGB in [0, 1]) cloud's colours, None when it
    has none (an empty array)."""
    a = np.asarray(values)
    return unit_colors(a[:, :3]) if a.ndim == 2 and a.shape[0] and a.shape[1] >= 3 else None


def _coordinates(a, what: str, where: str) -> np.ndarray:
    arr = check_unmasked(a, where + what, InvalidCloudError)
    check_real(arr.dtype, where + what)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InvalidCloudError(f"{where}{what} must have shape (N, 3), got {arr.shape}")
    return np.ascontiguousarray(arr, dtype=np.float64)


#: The columns of a table of points (a pandas ``DataFrame``) that a cloud reads, by what
#: they hold; in any case (``X``, as PDAL and laspy name them), each at most once.
TABLE_COLUMNS = {"points": ("x", "y", "z"), "normals": ("nx", "ny", "nz"),
                 "colors": ("red", "green", "blue")}


def missing_points(points, where: str = "", first_row: int = 0) -> bool:
    """Whether a file's non-finite rows are all missing points: NaN in x, y and z.

    A PLY file marks a point that was not measured (an organized frame's hole, an invalid
    row of a new scan file written by :func:`superfacets.io.records.write_cloud_with_labels`) by
    NaN in its three coordinates; such a point is invalid (label -1). A row with a finite
    coordinate beside a NaN, or an infinity, is damage.

    Parameters
    ----------
    points : (N, 3) float ndarray
        The file's positions, in file order.
    where : str, optional
        The file, for the message.
    first_row : int, default 0
        The file's row of ``points[0]`` (a chunk of a file read in parts), for the message.

    Returns
    -------
    bool
        True if some rows are missing points (then ``PointCloud(..., allow_invalid=True)``),
        False if every row is finite.

    Raises
    ------
    InvalidCloudError
        If a non-finite row is not NaN in all three coordinates (its row named).

    Examples
    --------
    >>> missing_points(np.array([[0.0, 0, 0], [np.nan, np.nan, np.nan]]))
    True
    >>> missing_points(np.zeros((2, 3)))
    False
    """
    points = np.asarray(points, dtype=np.float64)
    rows = np.flatnonzero(~finite_rows(points))
    if rows.size == 0:
        return False
    damaged = rows[~np.isnan(points[rows]).all(axis=1)]
    if damaged.size:
        row = int(damaged[0])
        raise InvalidCloudError(
            f"{where + ': ' if where else ''}point {first_row + row} has a non-finite "
            f"coordinate ({points[row].tolist()}): a missing point is NaN in all three "
            "coordinates")
    return True


def is_point_table(obj) -> bool:
    """Whether ``obj`` is a pandas ``DataFrame`` with ``x``, ``y`` and ``z`` columns (in
    any case: :data:`TABLE_COLUMNS`).

    Parameters
    ----------
    obj : object

    Returns
    -------
    bool

    Raises
    ------
    TypeError
        Never: anything else is answered False.

    Examples
    --------
    >>> import pandas as pd
    >>> is_point_table(pd.DataFrame({"X": [0.0], "Y": [0.0], "Z": [1.0]}))
    True
    """
    if type(obj).__name__ != "DataFrame" or not (type(obj).__module__ or "").startswith(
            "pandas"):
        return False
    return _table_columns(obj.columns, TABLE_COLUMNS["points"]) is not None


def _table_columns(columns, wanted) -> list | None:
    """The column holding each of ``wanted`` (of that name, else the one of that name in
    another case), None where one is missing or named twice."""
    names = [str(c) for c in columns]
    out = []
    for w in wanted:
        hit = [c for c, n in zip(columns, names) if n == w] or \
            [c for c, n in zip(columns, names) if n.lower() == w]
        if len(hit) != 1:
            return None
        out.append(hit[0])
    return out


def as_cloud(obj, normals=None, name: str = "") -> PointCloud:
    """A :class:`PointCloud` from what a user has.

    Parameters
    ----------
    obj : PointCloud, (N, 3) or organized (H, W, 3) float ndarray or nested list,
        trimesh.PointCloud, open3d.geometry.PointCloud or open3d.t.geometry.PointCloud (its
        ``positions``, ``normals`` and ``colors``), or a pandas DataFrame of ``x y z``
        columns (and ``nx ny nz``, ``red green blue`` where it has them, in any case:
        :data:`TABLE_COLUMNS`)
        An organized array may hold NaN rows (invalid points, label -1), or be a masked
        array (its masked pixels invalid).
    normals : (N, 3) or (H, W, 3) float ndarray, optional
        With an array: its normals (an Open3D cloud brings its own).
    name : str, optional

    Returns
    -------
    PointCloud

    Raises
    ------
    TypeError
        If ``obj`` is none of these.
    InvalidCloudError
        As :class:`PointCloud`; an ``(N, 3)`` masked array with masked entries (the mask
        would not be read).

    Examples
    --------
    >>> c = as_cloud(np.random.default_rng(0).random((100, 3)))
    >>> c.n_points, c.normals is None
    (100, True)
    """
    if isinstance(obj, PointCloud):
        return obj
    kind = f"{type(obj).__module__}.{type(obj).__name__}"
    if kind.startswith("trimesh.") and type(obj).__name__ == "PointCloud":
        return PointCloud(np.asarray(obj.vertices), normals, name=name,
                          colors=_library_colors(getattr(obj, "colors", ())))
    if kind.startswith("open3d.") and hasattr(obj, "point"):  # a tensor cloud (open3d.t)
        fields = obj.point
        got = {k: fields[k].numpy() for k in ("positions", "normals", "colors") if k in fields}
        if "positions" not in got:
            raise InvalidCloudError(f"{name or 'open3d cloud'}: no positions")
        return PointCloud(got["positions"], got.get("normals"), name=name,
                          colors=_library_colors(got.get("colors", ())))
    if kind.startswith("open3d.") and hasattr(obj, "points"):
        nrm = np.asarray(obj.normals) if getattr(obj, "has_normals", lambda: False)() else None
        return PointCloud(np.asarray(obj.points), nrm, name=name,
                          colors=_library_colors(getattr(obj, "colors", ())))
    if is_point_table(obj):
        got = {k: _table_columns(obj.columns, v) for k, v in TABLE_COLUMNS.items()}
        nrm = obj[got["normals"]].to_numpy(dtype=np.float64) if got["normals"] else normals
        col = unit_colors(obj[got["colors"]].to_numpy()) if got["colors"] else None
        return PointCloud(obj[got["points"]].to_numpy(dtype=np.float64), nrm, name=name,
                          colors=col)
    if isinstance(obj, (np.ndarray, list, tuple)):
        arr = np.asarray(obj)
        if arr.ndim == 3 and arr.shape[2] == 3:  # organized: rows of a sensor image
            if np.ma.isMaskedArray(obj):  # (its masked pixels: points not measured)
                arr = np.ma.filled(np.ma.asarray(obj, dtype=np.float64), np.nan)
            h, w = arr.shape[:2]
            nrm = None if normals is None else np.asarray(normals).reshape(-1, 3)
            return PointCloud(arr.reshape(-1, 3), nrm, name=name, allow_invalid=True,
                              shape=(h, w))
        return PointCloud(obj if np.ma.isMaskedArray(obj) else arr, normals, name=name)
    raise TypeError(f"expected a point cloud ((N, 3) array, PointCloud, trimesh or Open3D "
                    f"point cloud, a DataFrame of x y z columns), got {type(obj).__name__}")


def up_weighted(cloud: PointCloud, weight: float) -> PointCloud:
    """The cloud with its up coordinate (along ``cloud.up``) multiplied by ``weight``: the
    cloud the method sees with ``up_weight`` (not in the paper).

    Each point ``p`` becomes ``p + (weight - 1) (p . u) u``; the sensor positions and the
    box move alike, and given normals turn as the stretched surface's (``n - (1 - 1 /
    weight) (n . u) u``, made unit). The rows, colours and invalid points stay as they are.

    Parameters
    ----------
    cloud : PointCloud
        With ``up`` (a LAS, LAZ or E57 file's z; ``PointCloud(up=...)``).
    weight : float
        ``> 0`` (1: the cloud itself).

    Returns
    -------
    PointCloud

    Raises
    ------
    ParameterError
        If the cloud has no ``up``.

    Examples
    --------
    >>> c = PointCloud(np.array([[1.0, 2.0, 3.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]),
    ...                up=np.array([0.0, 0.0, 1.0]))
    >>> up_weighted(c, 2.0).points[0].tolist()
    [1.0, 2.0, 6.0]
    """
    if weight == 1:
        return cloud
    check_weighable(True, "points", cloud.up)
    u = np.asarray(cloud.up, dtype=np.float64)

    def moved(p):
        return None if p is None else stretched_along(p, u, weight)

    def turned(n):
        return None if n is None else stretched_normals(n, u, weight)

    frame = None
    if cloud.frame is not None:  # the box of the moved corners
        lo, hi = np.asarray(cloud.frame, dtype=np.float64)
        corners = moved(np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]]
                                  for i in (0, 1) for j in (0, 1) for k in (0, 1)]))
        frame = np.stack([corners.min(axis=0), corners.max(axis=0)])
    like = cloud.orient_like
    with np.errstate(invalid="ignore"):  # (an invalid point's NaN stays NaN)
        return replace(cloud, points=moved(cloud.points), normals=turned(cloud.normals),
                       viewpoint=moved(cloud.viewpoint), frame=frame,
                       orient_like=None if like is None else (moved(like[0]), turned(like[1])),
                       object_viewpoints=moved(cloud.object_viewpoints))


#: The most points :func:`surface_up_weight` reads (the finite ones of every ``ceil(n /
#: UP_SAMPLE)``-th row, in the input's order: a tiled run's survey sample,
#: ``io.regions.SAMPLE``) ...
UP_SAMPLE = 1 << 20
#: ... the neighbourhoods of at most this many of them (evenly spaced) ...
UP_NEIGHBOURHOODS = 8_192
#: ... each of this many nearest points of the sample (itself included).
UP_NEIGHBOURS = 10
#: The power of ``2 m`` :func:`surface_up_weight` gives (level ground: ``2^3 = 8``). Chosen on
#: all 30 labelled scans at three densities at once, where the airborne error falls alike
#: from 3 to 4 and the rooms read 1 either way (docs/notes/superpoints.md).
UP_POWER = 3


def surface_up_weight(points, up) -> float:
    """The weight of a scene's up coordinate read off its surfaces (``up_weight`` None on a
    cloud with an up direction; not in the paper): ``(2 m)^3`` (:data:`UP_POWER`) where ``m
    > 1/2``, else 1, where ``m`` is the mean ``|n . up|`` over the planar neighbourhoods of
    an even sample of the points; rounded to a hundredth.

    A neighbourhood (the :data:`UP_NEIGHBOURS` nearest points of the sample, at most
    :data:`UP_SAMPLE` of them, around each of :data:`UP_NEIGHBOURHOODS` evenly spaced
    ones) is planar where planarity is the largest of its three
    dimensionality features (Demantke et al. 2011: with ``s1 >= s2 >= s3`` the square
    roots of its covariance's eigenvalues, ``(s1 - s2) / s1``, ``(s2 - s3) / s1`` and
    ``s3 / s1``), and ``n`` is its normal. Surfaces facing every way alike give ``m =
    1/2`` (the mean ``|n . up|`` of directions uniform on the sphere), walls 0, level
    ground 1: the weight is 1 (none) where the planar surfaces stand no more level than
    an isotropic surface's (a room: walls, floor, furniture), and grows to 8 as they lie
    level (airborne ground and roofs, where what a scan stacks in height, ground under
    vegetation, is then kept apart; a street of road and facades reads 1.5-2). The only
    reference read off no scan is the isotropic surface's ``1/2``; the power is one
    constant for every scene, chosen on the whole labelled set.

    Parameters
    ----------
    points : (n, 3) float ndarray
        Positions (non-finite rows skipped), in any unit.
    up : (3,) float array-like
        The up direction (normalised here).

    Returns
    -------
    float
        In ``[1, 8]``; 1 where fewer than :data:`UP_NEIGHBOURS` finite points or no
        planar neighbourhood.

    Raises
    ------
    ValueError
        If ``up`` has length 0 or is not finite.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> ground = np.c_[rng.random((2000, 2)) * 100, 0.01 * rng.standard_normal(2000)]
    >>> surface_up_weight(ground, (0, 0, 1))           # level ground: the full weight
    8.0
    >>> wall = ground[:, [0, 2, 1]]                     # the same surface standing up
    >>> surface_up_weight(wall, (0, 0, 1))
    1.0
    """
    from scipy.spatial import cKDTree

    from .._runtime.threads import default_threads

    u = np.asarray(up, dtype=np.float64).reshape(3)
    length = float(np.linalg.norm(u))
    if not (np.isfinite(length) and length > 0):
        raise ValueError(f"up must be a finite non-zero vector, got {up!r}")
    pts = np.asarray(points)  # (every ceil(n / UP_SAMPLE)-th row, then the finite ones:
    pts = np.asarray(pts[::max(1, -(-pts.shape[0] // UP_SAMPLE))], dtype=np.float64)
    pts = np.ascontiguousarray(pts[finite_rows(pts)])  # a survey's sample; no copy of
    if pts.shape[0] < UP_NEIGHBOURS:  # the whole cloud)
        return 1.0
    at = pts[::max(1, -(-pts.shape[0] // UP_NEIGHBOURHOODS))]
    tree = cKDTree(pts, balanced_tree=False, compact_nodes=False)  # (built faster)
    _, near = tree.query(at, k=UP_NEIGHBOURS, workers=default_threads())
    nb = pts[near]
    nb -= nb.mean(axis=1, keepdims=True)
    cov = np.matmul(nb.transpose(0, 2, 1), nb)
    low, high = np.empty(at.shape[0]), np.empty(at.shape[0])  # (compiled, on threads)
    native.kernel("normals.extreme_eigenvalues")(cov, low, high)
    mid = np.trace(cov, axis1=1, axis2=2) - low - high
    s = np.sqrt(np.maximum(np.stack([high, mid, low], axis=1), 0.0))  # s1 >= s2 >= s3
    ok = s[:, 0] > 0
    dims = np.stack([s[:, 0] - s[:, 1], s[:, 1] - s[:, 2], s[:, 2]], axis=1)
    planar = ok & (dims.argmax(axis=1) == 1)
    if not planar.any():
        return 1.0
    normal, linearity = np.empty((at.shape[0], 3)), np.empty(at.shape[0])  # (each one's
    native.kernel("normals.pca_normals")(pts, np.ascontiguousarray(near, dtype=np.int32),
                                         normal, linearity)  # smallest eigenvector)
    m = float(np.abs(normal[planar] @ (u / length)).mean())
    return round((2.0 * max(m, 0.5)) ** UP_POWER, 2)


def unweighed_area_factor(normals, up, weight: float) -> np.ndarray:
    """What an area on a surface of the cloud stretched by ``weight`` along ``up``
    (:func:`up_weighted`) is in the cloud as given, per unit of it: ``sqrt(c^2 + (1 -
    c^2) / weight^2)``, ``c = |n . up|`` of the stretched surface's unit normal ``n``
    (level: 1; a wall: ``1 / weight``). Exact for a tangent plane's area element; a
    point's size, read from its neighbours' distances, follows it approximately.

    Parameters
    ----------
    normals : (n, 3) float ndarray
        Unit normals of the stretched surface.
    up : (3,) float array-like
        The direction stretched (normalised here).
    weight : float
        ``> 0``.

    Returns
    -------
    (n,) float64 ndarray
        In ``(0, inf)``: at most 1 where ``weight >= 1``.

    Raises
    ------
    ValueError
        If ``up`` has length 0.

    Examples
    --------
    >>> n = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    >>> unweighed_area_factor(n, (0, 0, 1), 2.0).tolist()
    [1.0, 0.5]
    """
    u = np.asarray(up, dtype=np.float64).reshape(3)
    length = float(np.linalg.norm(u))
    if not length > 0:
        raise ValueError(f"up must be a non-zero vector, got {up!r}")
    c = np.clip(np.abs(np.asarray(normals, dtype=np.float64) @ (u / length)), 0.0, 1.0)
    return np.sqrt(c * c + (1.0 - c * c) / (float(weight) ** 2))


def stretched_along(points, up, weight: float) -> np.ndarray:
    """Positions with their coordinate along the unit vector ``up`` times ``weight``:
    ``p + (weight - 1) (p . up) up`` (:func:`up_weighted`).

    Parameters
    ----------
    points : (..., 3) float ndarray
    up : (3,) float ndarray
        Of length 1.
    weight : float

    Returns
    -------
    (..., 3) float64 ndarray

    Raises
    ------
    ValueError
        Never for finite inputs (NaN rows stay NaN).

    Examples
    --------
    >>> stretched_along(np.array([[1.0, 2.0, 3.0]]), np.array([0.0, 0.0, 1.0]), 2.0).tolist()
    [[1.0, 2.0, 6.0]]
    """
    p = np.asarray(points, dtype=np.float64)
    u = np.asarray(up, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        return p + (weight - 1.0) * (p @ u)[..., None] * u


def stretched_normals(normals, up, weight: float) -> np.ndarray:
    """The unit normals of a surface stretched by :func:`stretched_along`: ``n - (1 - 1 /
    weight) (n . up) up``, made unit.

    Parameters
    ----------
    normals : (..., 3) float ndarray
    up : (3,) float ndarray
        Of length 1.
    weight : float
        ``> 0``.

    Returns
    -------
    (..., 3) float64 ndarray

    Raises
    ------
    ValueError
        Never for finite inputs.

    Examples
    --------
    >>> n = stretched_normals(np.array([[1.0, 0.0, 1.0]]), np.array([0.0, 0.0, 1.0]), 2.0)
    >>> np.round(n, 4).tolist()
    [[0.8944, 0.0, 0.4472]]
    """
    n = np.asarray(normals, dtype=np.float64)
    u = np.asarray(up, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        n = n - (1.0 - 1.0 / weight) * (n @ u)[..., None] * u
        return n / np.linalg.norm(n, axis=-1, keepdims=True)


def check_weighable(cloud: bool, kind: str, up) -> None:
    """Refuse ``up_weight`` (other than 1) where there is no up coordinate to weigh: elements
    that are not points (``cloud`` False; ``kind`` named), or a cloud without ``up``.

    Parameters
    ----------
    cloud : bool
        Whether the elements are points.
    kind : str
        Their kind, for the message.
    up : (3,) float array-like or None

    Returns
    -------
    None

    Raises
    ------
    ParameterError
        As said.

    Examples
    --------
    >>> check_weighable(True, "points", (0.0, 0.0, 1.0))
    """
    if not cloud:
        raise ParameterError(f"up_weight weighs a point cloud's up coordinate; this input's "
                             f"elements are {kind}")
    if up is None:
        raise ParameterError("up_weight weighs a cloud's up coordinate, and this cloud has no "
                             "up: a LAS, LAZ or E57 file's is z; give one (--seen-from AXIS, "
                             "or PointCloud(up=...))")
