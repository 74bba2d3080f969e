"""Reading point clouds: PLY without faces, PCD, XYZ/PTS/TXT columns, ``.npy``, LAS/LAZ,
E57.

Points keep their file order (labels come back in that order). Readers:

- PLY (a ``vertex`` element, no faces): plyfile; ``nx ny nz`` are read as normals;
- PCD (ASCII, binary, binary_compressed): ``pypcd4`` (extra ``clouds``). NaN
  points are PCL's mark of a missing measurement: they become invalid
  points (label -1); an organized cloud (``HEIGHT > 1``) keeps its layout;
  ``VIEWPOINT`` gives the sensor position that estimated normals face;
- XYZ / PTS / TXT: whitespace- or comma-separated columns ``x y z`` first;
  further columns are ignored unless a ``#``/``//`` header line names them
  (``nx ny nz`` are then read as normals); a PTS file may start with the
  point count;
- NPY: an ``(N, 3)`` array, ``(N, 6)`` (points then normals) or organized
  ``(H, W, 3)`` (NaN points invalid); or records with named fields ``x y z`` (a numpy
  structured array, as ``ros_numpy`` makes of a ROS ``PointCloud2``, ``(N,)`` or
  organized ``(H, W)``): normals from ``nx ny nz`` (or ``normal_x ...``), colours from
  ``r g b`` / ``red green blue`` or PCL's packed ``rgb``, a row NaN in x, y and z a
  missing point, the other fields readable as ground truths (:func:`~superfacets.io.
  labels.read_field`); a scene folder's ``coord.npy`` (Pointcept's layout) with its
  ``color.npy`` and ``normal.npy`` (:func:`scene_assets`), z up;
- LAS / LAZ: ``laspy`` (extra ``clouds``; LAZ through its ``lazrs`` backend),
  scaled coordinates.
- E57 (ASTM E2807, terrestrial scanners' exchange format): ``pye57`` (extra
  ``clouds``). Every scan in the file's order, in the file's common frame (each
  scan's pose applied); each scan an object (:attr:`PointCloud.objects`) with its
  scanner's position; points the scanner marked invalid are invalid points
  (label -1); z is up.

In a PLY file a row of NaN in x, y and z is a missing point (invalid, -1: how an
organized frame's holes and a new scan file's invalid rows are written). Elsewhere than
these, PCD and E57 files and organized arrays a non-finite coordinate is an error naming
its row.
"""

from __future__ import annotations

import io
import re
import warnings
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..errors import MeshFormatError
from ..inputs.rgb import unit_colors
from .columns import read_columns
from .files import read_bytes, split_suffix, user_path
from .ply import COLOR_PROPERTIES, ply_colors, ply_scalars, read_ply_scalars

__all__ = ["read_cloud", "scene_file", "CLOUD_FORMATS", "is_cloud_file", "check_laz", "check_las",
           "e57_counts", "scene_assets", "SCENE_ASSETS", "SCENE_UP"]

from .._runtime import extras
from ..checks import not_real
from ..inputs.cloud import InvalidCloudError, PointCloud, missing_points
from .headers import (  # noqa: E402 (re-exported: headers)
    check_las,
    check_laz,
    check_pcd,
    e57_counts,
    header_counts,
    pcd_problem,
    ply_names,
)
from .orientation import sensor_up

#: Point-cloud formats of :func:`read_cloud` (PLY files are clouds when they have no faces).
CLOUD_FORMATS = ("pcd", "xyz", "pts", "txt", "csv", "asc", "npy", "las", "laz", "e57", "bin")


def is_cloud_file(path) -> bool:
    """Whether ``path`` holds a point cloud: a cloud format, a PLY, OFF or OBJ of vertices
    and no face (as MeshLab saves a cloud in a mesh format), or a glTF/GLB whose meshes
    are all points (``POINTS`` primitives).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    bool

    Raises
    ------
    MeshFormatError
        If a PLY header cannot be read.

    Examples
    --------
    >>> is_cloud_file("scan.pcd"), is_cloud_file("bunny.off")
    (True, False)
    """
    path = Path(path)
    fmt, comp = split_suffix(path)
    if fmt in CLOUD_FORMATS:
        return True
    if fmt in ("glb", "gltf") and path.is_file():
        return _gltf_of_points(path, fmt, comp)
    if fmt not in ("ply", "off", "obj") or not path.is_file():
        return False
    if fmt == "obj":
        stat = path.stat()  # (a command asks more than once: the scan made once)
        return _obj_without_faces(str(path), comp, stat.st_size, stat.st_mtime_ns)
    if comp:
        data = read_bytes(path, comp)
    else:
        with path.open("rb") as f:
            data = f.read(1 << 16)
    if not data:  # an empty file: read_mesh says so
        return False
    if fmt == "off":
        counts = _off_counts(data)
        return counts is not None and counts[0] > 0 and counts[1] == 0
    head = _ply_header(data)
    faces = [int(p[2]) for p in (ln.split() for ln in head)
             if len(p) == 3 and p[0] == b"element" and p[1] == b"face" and p[2].isdigit()]
    return not faces or faces[0] == 0


#: The most bytes of a ``.gltf`` read to tell whether it holds points (its JSON may hold its
#: buffers as base64; larger, it is read as a mesh, whose reader says what it holds).
GLTF_SNIFF_BYTES = 64 << 20


def _gltf_of_points(path: Path, fmt: str, comp: str | None) -> bool:
    """Whether a glTF/GLB file's meshes are all points (:func:`is_cloud_file`)."""
    from .headers import gltf_document, gltf_points_only

    try:
        if comp:
            data = read_bytes(path, comp)
        elif fmt == "glb":
            with path.open("rb") as f:
                head = f.read(20)
                size = int.from_bytes(head[12:16], "little") if len(head) == 20 else 0
                data = head + f.read(min(size, GLTF_SNIFF_BYTES))
        else:
            if path.stat().st_size > GLTF_SNIFF_BYTES:
                return False
            data = path.read_bytes()
    except (OSError, MeshFormatError):
        return False  # (read_mesh says what is wrong)
    return gltf_points_only(gltf_document(data, fmt))


def _read_gltf_points(path: Path, fmt: str, comp: str | None) -> dict:
    """The points of a glTF/GLB of ``POINTS`` primitives, each node's transform applied, in
    the scene's order, with their ``COLOR_0`` where every one has colours."""
    import trimesh

    from .meshes import load_gltf_scene

    scene = load_gltf_scene(path, fmt, comp, read_bytes(path, comp))
    parts, colours = [], []
    for node in scene.graph.nodes_geometry:
        transform, key = scene.graph[node]
        geom = scene.geometry[key]
        if not isinstance(geom, trimesh.PointCloud) or not len(geom.vertices):
            continue
        t = np.asarray(transform, dtype=np.float64)
        parts.append(np.asarray(geom.vertices, dtype=np.float64) @ t[:3, :3].T + t[:3, 3])
        rgb = np.asarray(geom.colors)
        colours.append(rgb[:, :3] if rgb.ndim == 2 and len(rgb) == len(geom.vertices)
                       else None)
    if not parts:
        raise InvalidCloudError(f"{path}: the scene holds no point")
    col = (unit_colors(np.concatenate(colours)) if all(c is not None for c in colours)
           else None)
    return {"points": np.concatenate(parts), "colors": col}


def _off_counts(data: bytes) -> tuple[int, int] | None:
    """The vertex and face counts an OFF header (the start of the file, ``data``) declares,
    or None where it declares none that can be read (:func:`read_mesh` says why)."""
    words: list[bytes] = []
    for line in data.split(b"\n")[:64]:
        line = line.split(b"#", 1)[0].strip()
        if line:
            words += line.split()
        if len(words) >= 3:
            break
    if len(words) < 3 or not words[0].upper().endswith(b"OFF") \
            or not (words[1].isdigit() and words[2].isdigit()):
        return None
    return int(words[1]), int(words[2])


#: A face statement at the start of an OBJ line (spaces or tabs before and after ``f``).
_OBJ_FACE = re.compile(rb"(?m)^[ \t]*f[ \t]")


@lru_cache(maxsize=16)
def _obj_without_faces(name: str, comp: str | None, size: int, mtime: int) -> bool:
    """Whether an OBJ file holds a vertex statement and no face statement (a point cloud
    in OBJ). The usual mesh is told at its first face line (a scan of the bytes, mapped,
    not read); an empty or unreadable file is left to :func:`read_mesh` (False). Cached
    by the file's name, size and modification time."""
    import mmap

    path = Path(name)
    try:
        if comp:
            data = read_bytes(path, comp)
            return b"v" in data and _OBJ_FACE.search(data) is None
        with path.open("rb") as f:
            if not path.stat().st_size:
                return False
            with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as mm:
                if mm.find(b"\nf ") >= 0 or mm[:2] == b"f ":  # (the usual mesh: at once)
                    return False
                return _OBJ_FACE.search(mm) is None and re.search(
                    rb"(?m)^[ \t]*v[ \t]", mm) is not None
    except (OSError, ValueError, MeshFormatError):
        return False


def _ply_header(data: bytes) -> list[bytes]:
    end = data.find(b"end_header")
    return data[:end if end >= 0 else 1 << 16].split(b"\n")


def read_cloud(path, format: str | None = None):
    """Read a point cloud from a file.

    Parameters
    ----------
    path : str or os.PathLike
        ``.ply``, ``.obj`` or ``.off`` (no faces), ``.glb``/``.gltf`` (points), ``.pcd``,
        ``.xyz``, ``.pts``, ``.txt``,
        ``.csv``, ``.npy``, ``.las``, ``.laz``, ``.e57``, KITTI's ``.bin`` or nuScenes'
        ``.pcd.bin``; text formats and PLY may end in ``.gz``/``.xz``/``.bz2``.
    format : str, optional
        Force a format instead of the suffix.

    Returns
    -------
    PointCloud
        Points in file order (float64), normals when the file has them,
        invalid points marked (PCD), the organized layout kept.

    Raises
    ------
    FileNotFoundError, IsADirectoryError
    MeshFormatError
        If the file is malformed or truncated, or its columns are not understood.
    InvalidCloudError
        If a point has a non-finite coordinate (outside PCD files). (Normals that are zero
        or not finite are estimated instead, with a warning: :func:`given_normals`.)
    MissingExtraError
        PCD and LAS/LAZ without the ``clouds`` extra.
    TypeError
        If ``format`` is not a string.

    Examples
    --------
    >>> np.savetxt("cloud.xyz", np.random.default_rng(0).random((50, 3)))
    >>> c = read_cloud("cloud.xyz")
    >>> c.n_points, c.points.dtype
    (50, dtype('float64'))
    """

    path = scene_file(user_path(path))
    fmt, comp = split_suffix(path)
    if format is not None:
        if not isinstance(format, str):
            raise TypeError(f"format must be a suffix such as 'ply', got {format!r}")
        fmt = format.lower().lstrip(".")
    if fmt not in CLOUD_FORMATS + ("ply", "obj", "off", "glb", "gltf"):
        raise MeshFormatError(f"{path}: unknown point-cloud format "
                              f"{('.' + fmt) if fmt else '(no suffix)'}; expected .ply or one of "
                              f"{', '.join('.' + f for f in CLOUD_FORMATS)}")
    kw: dict = {}
    if fmt == "pcd":
        if comp:
            raise MeshFormatError(f"{path}: compressed PCD files are not supported; "
                                  "decompress it first")
        kw = _read_pcd(path)
    elif fmt in ("las", "laz"):
        kw = _read_las(path)
    elif fmt in ("glb", "gltf"):
        kw = _read_gltf_points(path, fmt, comp)
    elif fmt == "e57":
        if comp:
            raise MeshFormatError(f"{path}: compressed E57 files are not supported; "
                                  "decompress it first")
        kw = _read_e57(path)
    else:
        counts = header_counts(path)  # a header declaring more than the file holds: refused
        data = read_bytes(path, comp, counts=counts)
        if fmt == "ply":
            kw = _read_ply(data, path)
        elif fmt in ("obj", "off"):
            kw = _read_mesh_vertices(data, path, fmt)
        elif fmt == "npy":
            kw = _read_npy(data, path)
        elif fmt == "bin":
            kw = (_read_nuscenes(data, path) if path.name.lower().endswith(".pcd.bin")
                  else _read_kitti(data, path))
        else:
            kw = read_columns(data, path)
    if kw["points"].shape[0] == 0:
        raise InvalidCloudError(f"{path}: empty point cloud: no point")
    kw["normals"] = given_normals(kw.get("normals"), path, kw["points"])
    try:
        return PointCloud(name=path.name, **kw)
    except InvalidCloudError as exc:
        raise InvalidCloudError(f"{path}: {str(exc).removeprefix(path.name + ': ')}") from None


def _read_mesh_vertices(data: bytes, path: Path, fmt: str) -> dict:
    """The vertices of an OBJ or OFF file of no face as a cloud (with an OBJ's ``v x y z r
    g b`` colours, a COFF's colours, a NOFF's normals)."""
    from .meshes import parse_off
    from .obj import parse_obj

    if fmt == "obj":
        v, f, _, colors = parse_obj(data, path, cloud=True)
        normals = None
    else:
        v, f, colors, normals = parse_off(data, path, cloud=True)
    if len(f):
        raise MeshFormatError(f"{path}: the file holds faces: a mesh (read_mesh), not a "
                              "point cloud")
    return {"points": v, "colors": colors, "normals": normals}


def _read_ply(data: bytes, path: Path) -> dict:
    from plyfile import PlyData, PlyParseError

    try:
        fast = read_ply_scalars(data, path)  # (plyfile reads bytes a row at a time)
        if fast and "vertex" in fast:
            vert = fast["vertex"]
        else:
            ply = PlyData.read(io.BytesIO(data))
            elements = [e.name for e in ply.elements]
            if "vertex" not in elements:
                raise MeshFormatError(f"{path}: the PLY has no vertex element (it has: "
                                      f"{', '.join(elements) or 'none'})")
            vert = ply["vertex"]
        names = [p.name for p in vert.properties]
        named = ply_names(names)
        missing = [c for c in "xyz" if c not in named]
        if missing:
            raise MeshFormatError(f"{path}: the vertex element has no {', '.join(missing)} "
                                  f"property (it has: {', '.join(names)})")
        with np.errstate(invalid="ignore"):  # a signalling NaN: the rows check names it
            pts = np.stack([ply_scalars(vert, named[c], path) for c in "xyz"], axis=1)
            nrm = None
            if all(c in named for c in ("nx", "ny", "nz")):
                nrm = np.stack([ply_scalars(vert, named[c], path) for c in ("nx", "ny", "nz")],
                               axis=1)
        col = ply_colors(vert)
    except (PlyParseError, KeyError, ValueError, IndexError, TypeError, EOFError,
            MemoryError) as exc:
        if isinstance(exc, MeshFormatError):
            raise
        raise MeshFormatError(f"{path}: cannot read PLY points: {exc}") from None
    return {"points": pts, "normals": nrm, "colors": col,
            "allow_invalid": missing_points(pts, str(path))}


def given_normals(normals, path, points=None) -> np.ndarray | None:
    """A file's normals, or None where any of them (at a point of finite position) is zero
    or not finite: then they are all estimated from the points instead, with a warning that
    says so (3D Gaussian splats' PLY files hold ``nx ny nz`` of zero for every point; PCL's
    normal estimation leaves NaN where a point has too few neighbours).

    Parameters
    ----------
    normals : (N, 3) ndarray or None
    path : str or os.PathLike
        The file, for the warning.
    points : (N, 3) ndarray, optional
        The positions: the normals of points without a finite one are not looked at.

    Returns
    -------
    (N, 3) ndarray or None

    Raises
    ------
    TypeError
        Never: normals that are all usable are returned as given.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True):
    ...     given_normals(np.zeros((4, 3)), "splats.ply") is None
    True
    """
    if normals is None or np.size(normals) == 0:
        return normals
    rows = np.arange(len(normals)) if points is None else np.flatnonzero(
        np.isfinite(np.asarray(points, dtype=np.float64)).all(axis=1))
    bad = unusable_normals(normals, rows)
    if not bad.size:
        return normals
    warnings.warn(dropped_normals_said(path, bad.size, rows.size, int(bad[0])), stacklevel=2)
    return None


def unusable_normals(normals, rows: np.ndarray) -> np.ndarray:
    """The ``rows`` (increasing) whose normal is zero or not finite (:func:`given_normals`;
    a tiled run's survey, chunk by chunk)."""
    n = np.asarray(normals, dtype=np.float64)[rows]
    with np.errstate(over="ignore", invalid="ignore"):
        length = np.einsum("ij,ij->i", n, n)
    return rows[~(np.isfinite(length) & (length > 0))]


def dropped_normals_said(path, bad: int, total: int, first: int) -> str:
    """The warning of :func:`given_normals`: ``bad`` of ``total`` normals unusable, the
    first at row ``first``."""
    what = ("its normals are all zero or not finite (placeholders, as 3D Gaussian splats "
            "write them)" if bad == total else
            f"{bad:,} of its {total:,} normals are zero or not finite (the first: point "
            f"{first})")
    return f"{Path(path).name}: {what}: all estimated from the points instead"


def _packed_rgb(values: np.ndarray) -> np.ndarray:
    """PCL's packed ``rgb``/``rgba`` field (a float32 or uint32 holding 0x00RRGGBB)."""
    v = np.ascontiguousarray(values)
    u = v.view(np.uint32) if v.dtype.itemsize == 4 else v.astype(np.uint32)
    return np.stack([(u >> 16) & 255, (u >> 8) & 255, u & 255], axis=1).astype(np.uint8)


def _read_pcd(path: Path) -> dict:
    pypcd4 = extras.require("pypcd4", "reading PCD files")
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a directory")
    check_pcd(path)
    try:
        pc = pypcd4.PointCloud.from_path(path)
        fields = tuple(pc.fields)
        missing = [c for c in "xyz" if c not in fields]
        if missing:
            raise MeshFormatError(f"{path}: PCD fields {' '.join(fields)} have no "
                                  f"{', '.join(missing)}")
        pts = np.asarray(pc.numpy(("x", "y", "z")), dtype=np.float64)
        nrm = None
        if all(c in fields for c in ("normal_x", "normal_y", "normal_z")):
            nrm = np.asarray(pc.numpy(("normal_x", "normal_y", "normal_z")), dtype=np.float64)
        col = None
        for packed in ("rgb", "rgba"):
            if packed in fields:
                col = unit_colors(_packed_rgb(pc.pc_data[packed]))
                break
        meta = pc.metadata
        height, width = int(meta.height), int(meta.width)
        viewpoint = np.asarray(meta.viewpoint, dtype=np.float64)
    except MeshFormatError:
        raise
    except Exception as exc:  # noqa: BLE001 - pypcd4/pydantic raise many types
        raise MeshFormatError(f"{path}: cannot read PCD: {pcd_problem(exc)}") from None
    if pts.shape[0] != height * width:
        raise MeshFormatError(f"{path}: PCD has {pts.shape[0]} points, the header says "
                              f"{width} x {height}")
    # (normals NaN at invalid points are left alone; NaN at a valid one, where PCL could not
    # estimate it, sets them all aside with a warning, as every reader does: given_normals)
    out = {"points": pts, "normals": nrm, "colors": col, "allow_invalid": True,
           "viewpoint": viewpoint[:3], "shape": (height, width) if height > 1 else None}
    if height > 1:  # an image of a camera: up is its -y, turned as the sensor was
        out["up"] = sensor_up(viewpoint)
    return out


def _read_las(path: Path) -> dict:
    laspy = extras.require("laspy", "reading LAS/LAZ files")
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a directory")
    check_las(path)
    try:
        las = laspy.read(path)
        pts = np.stack([np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)], axis=1)
        dims = set(las.point_format.dimension_names)
        col = (unit_colors(np.stack([np.asarray(las[c]) for c in ("red", "green", "blue")],
                                    axis=1))
               if {"red", "green", "blue"} <= dims else None)
        withheld = withheld_rows(las, dims)
    except Exception as exc:  # noqa: BLE001 - laspy raises many types
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise MeshFormatError(f"{path}: cannot read {path.suffix.upper()[1:]} (damaged or "
                              f"truncated file?): {msg}") from None
    pts = pts.astype(np.float64)
    if withheld is not None:  # (ASPRS: a withheld point is not to be processed: invalid)
        pts[withheld] = np.nan
    # LAS z is elevation: an airborne, mobile or terrestrial scan sees its surfaces from
    # above or from the side, so estimated normals are turned upwards piece by piece
    return {"points": pts, "colors": col, "up": np.array([0.0, 0.0, 1.0]),
            "allow_invalid": withheld is not None}


def withheld_rows(points, dims) -> np.ndarray | None:
    """The rows of LAS points flagged ``withheld`` (the ASPRS specification: "should not be
    included in processing"; the points a new scan file marks invalid), or None where there
    is none. ``points``: laspy's records (a file's, or a chunk's); ``dims``: their
    dimension names."""
    if "withheld" not in dims:
        return None
    flags = np.asarray(points.withheld, dtype=bool)
    return np.flatnonzero(flags) if flags.any() else None


def _e57_positions(raw: dict, path: Path) -> np.ndarray:
    """A scan's local positions: its Cartesian fields, else its spherical ones (range,
    azimuth, elevation, as E57 defines them)."""
    if all(c in raw for c in ("cartesianX", "cartesianY", "cartesianZ")):
        return np.stack([np.asarray(raw[c], dtype=np.float64) for c in
                         ("cartesianX", "cartesianY", "cartesianZ")], axis=1)
    if all(c in raw for c in ("sphericalRange", "sphericalAzimuth", "sphericalElevation")):
        r, az, el = (np.asarray(raw[c], dtype=np.float64) for c in
                     ("sphericalRange", "sphericalAzimuth", "sphericalElevation"))
        return np.stack([r * np.cos(el) * np.cos(az), r * np.cos(el) * np.sin(az),
                         r * np.sin(el)], axis=1)
    raise MeshFormatError(f"{path}: an E57 scan without Cartesian or spherical coordinates")


def _read_e57(path: Path) -> dict:
    pye57 = extras.require("pye57", "reading E57 files")
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a directory")
    scans = e57_counts(path)
    if not scans:
        raise MeshFormatError(f"{path}: the E57 file holds no scan")
    pts, cols, levels, objects, at = [], [], [], [], 0
    try:
        e57 = pye57.E57(str(path))
        try:
            for i, (name, _, _) in enumerate(scans):
                head = e57.get_header(i)
                raw = e57.read_scan_raw(i)  # every record, in file order
                p = _e57_positions(raw, path)
                if "cartesianInvalidState" in raw:  # 1: a direction only, 2: no point
                    p[np.asarray(raw["cartesianInvalidState"]) != 0] = np.nan
                if head.has_pose():  # to the file's common frame
                    p = p @ np.asarray(head.rotation_matrix).T + np.asarray(head.translation)
                pts.append(p)
                colors = [raw.get(c) for c in ("colorRed", "colorGreen", "colorBlue")]
                cols.append(None if any(c is None for c in colors) else
                            np.stack([np.asarray(c) for c in colors], axis=1))
                levels.append(None if raw.get("intensity") is None else
                              np.asarray(raw["intensity"], dtype=np.float64).reshape(-1))
                objects.append((name, at, at + p.shape[0]))
                at += p.shape[0]
        finally:
            e57.close()
    except MeshFormatError:
        raise
    except Exception as exc:  # noqa: BLE001 - libE57Format raises its own types
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise MeshFormatError(f"{path}: cannot read E57 (damaged or truncated file?): "
                              f"{msg}") from None
    points = np.concatenate(pts) if len(pts) > 1 else pts[0]
    col = None
    if all(c is not None for c in cols):
        col = np.empty((points.shape[0], 3))
        for (_, a, b), c in zip(objects, cols):
            col[a:b] = unit_colors(c)
    positions = np.array([s[2] for s in scans])
    out = {"points": points, "colors": col, "up": np.array([0.0, 0.0, 1.0]),
           "allow_invalid": bool(not np.isfinite(points).all())}
    if all(v is not None and v.shape[0] == b - a for v, (_, a, b) in zip(levels, objects)):
        out["fields"] = {"intensity": np.concatenate(levels)}  # (kept for a new file)
    if len(scans) == 1:  # one scan: its normals face its scanner
        out["viewpoint"] = positions[0]
    else:
        out.update(objects=tuple(objects), object_viewpoints=positions)
    return out


def _read_kitti(data: bytes, path: Path) -> dict:
    """A KITTI velodyne scan (``.bin``): float32 ``x y z reflectance`` per point, little
    endian, no header, ``z`` up. Seen from above, as a LAS tile is (``up``), not from the
    scanner at the origin: on the two SemanticKITTI sweeps of the development set, normals
    turned towards the origin gave a 12-22 % higher undersegmentation error at k = 300 and
    1,000 than seen from above (docs/notes/scans-io.md). The reflectance (in [0, 1]) is not
    read as a position (kept as a field for a new file of the points); it tells such a
    file from other binary data."""
    if data[:3] == b"CCB":  # (CloudCompare's own BIN format: its header, then its entities)
        raise MeshFormatError(f"{path}: a CloudCompare .bin (its own format), not a KITTI "
                              "scan: save the cloud from CloudCompare as PLY, LAS/LAZ or ASCII "
                              "(.asc, .txt) to segment it")
    if len(data) % 16:
        raise MeshFormatError(f"{path}: a .bin is read as a KITTI velodyne scan (float32 x, "
                              f"y, z, reflectance: 16 bytes a point); its {len(data):,} bytes "
                              "are not a whole number of points")
    arr = np.frombuffer(data, dtype="<f4").reshape(-1, 4)
    with np.errstate(invalid="ignore"):
        off = np.flatnonzero(~((arr[:, 3] >= 0) & (arr[:, 3] <= 1)))
    if off.size:
        raise MeshFormatError(f"{path}: not a KITTI velodyne scan (float32 x, y, z, "
                              f"reflectance in [0, 1]): point {int(off[0])}'s fourth value is "
                              f"{float(arr[off[0], 3])!r} ({off.size:,} such points)")
    return {"points": arr[:, :3].astype(np.float64), "up": np.array([0.0, 0.0, 1.0]),
            "fields": {"reflectance": arr[:, 3].copy()}}


#: Most laser rings of a nuScenes-style ``.pcd.bin`` sweep's fifth value (the ring index:
#: 0..31 on nuScenes' 32-beam sensor; a sensor of up to 128 beams read alike).
MAX_RINGS = 128


def _read_nuscenes(data: bytes, path: Path) -> dict:
    """A nuScenes lidar sweep (``.pcd.bin``): float32 ``x y z intensity ring`` per point,
    little endian, no header, ``z`` up, in the sensor's frame. Seen from above, as a KITTI
    scan is (:func:`_read_kitti`: the same roof-mounted sensor's sweep). Neither the
    intensity (0..255) nor the ring index (an integer below :data:`MAX_RINGS`) is read as
    a position (both kept as fields); they tell such a file from other binary data (a
    KITTI scan renamed, four values a point)."""
    if len(data) % 20:
        raise MeshFormatError(f"{path}: a .pcd.bin is read as a nuScenes lidar sweep (float32 "
                              "x, y, z, intensity, ring: 20 bytes a point); its "
                              f"{len(data):,} bytes are not a whole number of points")
    arr = np.frombuffer(data, dtype="<f4").reshape(-1, 5)
    with np.errstate(invalid="ignore"):
        ring, level = arr[:, 4], arr[:, 3]
        off = np.flatnonzero(~((ring >= 0) & (ring < MAX_RINGS) & (ring == np.floor(ring))
                               & (level >= 0) & (level <= 255)))
    if off.size:
        i = int(off[0])
        raise MeshFormatError(f"{path}: not a nuScenes lidar sweep (float32 x, y, z, intensity "
                              f"in [0, 255], ring index 0..{MAX_RINGS - 1}): point {i}'s "
                              f"intensity is {float(arr[i, 3])!r} and ring "
                              f"{float(arr[i, 4])!r} ({off.size:,} such points)")
    return {"points": arr[:, :3].astype(np.float64), "up": np.array([0.0, 0.0, 1.0]),
            "fields": {"intensity": arr[:, 3].copy(), "ring": arr[:, 4].astype(np.uint8)}}


def _read_npy(data: bytes, path: Path) -> dict:
    try:
        arr = np.load(io.BytesIO(data), allow_pickle=False)
    except Exception as exc:  # noqa: BLE001 - numpy raises many types on damaged files
        raise MeshFormatError(f"{path}: cannot read NPY: {exc}") from None

    if isinstance(arr, np.ndarray) and arr.dtype.names and arr.ndim in (1, 2):
        return _npy_records(arr, path)
    if not isinstance(arr, np.ndarray) or not_real(arr.dtype, "NPY points"):
        raise MeshFormatError(f"{path}: " + (not_real(arr.dtype, "NPY points") if isinstance(
            arr, np.ndarray) else f"NPY must hold an array, got {type(arr).__name__}"))
    if arr.ndim == 3 and arr.shape[2] == 3:
        h, w = arr.shape[:2]
        return {"points": arr.reshape(-1, 3).astype(np.float64), "allow_invalid": True,
                "shape": (h, w)}
    if arr.ndim == 2 and arr.shape[1] in (3, 6):
        arr = arr.astype(np.float64)
        out = {"points": arr[:, :3], "normals": arr[:, 3:] if arr.shape[1] == 6 else None}
        if arr.shape[1] == 3 and path.name == "coord.npy":  # (a scene's: z up, its assets)
            return {**out, **scene_assets(path, len(arr)), "up": np.array(SCENE_UP)}
        return out
    raise MeshFormatError(f"{path}: NPY array of shape {arr.shape}: expected (N, 3) points, "
                          "(N, 6) points and normals, or organized (H, W, 3)")


#: The fields of NPY records read as normals, either naming.
_NORMAL_FIELDS = (("nx", "ny", "nz"), ("normal_x", "normal_y", "normal_z"))


def _npy_records(arr: np.ndarray, path: Path) -> dict:
    """A cloud from NPY records (a structured array, ``(N,)`` or organized ``(H, W)``): the
    fields ``x y z`` (any case), normals, colours (:func:`_read_npy`)."""
    fields = list(arr.dtype.names)
    named = ply_names(fields, ("x", "y", "z", "nx", "ny", "nz", "normal_x", "normal_y",
                               "normal_z"))
    missing = [c for c in "xyz" if c not in named]
    if missing:
        raise MeshFormatError(f"{path}: NPY records have no {', '.join(missing)} field (they "
                              f"have: {', '.join(fields)})")
    flat = arr.reshape(-1)

    def columns(names, what):
        for n in names:
            kind = arr.dtype.fields[n][0]
            if kind.shape or not_real(kind, what):
                raise MeshFormatError(f"{path}: NPY field {n!r} ({kind}) is not one real "
                                      f"number per point")
        with np.errstate(invalid="ignore"):
            return np.stack([np.asarray(flat[n], dtype=np.float64) for n in names], axis=1)

    pts = columns([named[c] for c in "xyz"], "NPY points")
    nrm = next((columns([named[c] for c in trio], "NPY normals") for trio in _NORMAL_FIELDS
                if all(c in named for c in trio)), None)
    col = next((unit_colors(columns(list(trio), "NPY colours")) for trio in COLOR_PROPERTIES
                if all(c in fields for c in trio)), None)
    packed = next((n for n in ("rgb", "rgba") if n in fields), None)
    if col is None and packed is not None and arr.dtype.fields[packed][0].itemsize == 4:
        col = unit_colors(_packed_rgb(flat[packed]))
    used = {named[c] for c in named} | {n for n in (packed,) if col is not None and n} | {
        c for trio in COLOR_PROPERTIES if all(x in fields for x in trio) for c in trio}
    kept = {n: np.asarray(flat[n]).copy() for n in fields if n not in used
            and not arr.dtype.fields[n][0].shape and arr.dtype.fields[n][0].kind in "biuf"}
    out = {"points": pts, "normals": nrm, "colors": col, "fields": kept or None}
    if arr.ndim == 2:  # an organized cloud (a depth camera's frame): NaN points invalid
        return {**out, "allow_invalid": True, "shape": tuple(arr.shape)}
    return {**out, "allow_invalid": missing_points(pts, str(path))}


#: A learning pipeline's scene folder (Pointcept's: one ``NAME.npy`` per asset, the points
#: in ``coord.npy``): the assets read beside the points, as what the cloud holds.
SCENE_ASSETS = {"color": "colors", "normal": "normals"}
#: The up direction of a scene folder's points: Pointcept's datasets (ScanNet, S3DIS,
#: nuScenes, SemanticKITTI, ...) all keep gravity along -z.
SCENE_UP = (0.0, 0.0, 1.0)


def scene_file(path: Path) -> Path:
    """The file a reader reads for ``path``: a scene folder of Pointcept's (one holding
    ``coord.npy``) is its ``coord.npy``; any other folder is refused.

    Parameters
    ----------
    path : pathlib.Path

    Returns
    -------
    pathlib.Path
        ``path``, or the scene's ``coord.npy``.

    Raises
    ------
    MeshFormatError
        If ``path`` is a folder that is no scene.

    Examples
    --------
    >>> scene_file(Path("scan.las"))
    PosixPath('scan.las')
    """
    if not path.is_dir():
        return path
    if (path / "coord.npy").is_file():
        return path / "coord.npy"
    raise MeshFormatError(f"{path}: a folder, not a file: name a file in it (a scene folder "
                          "of Pointcept's holds coord.npy)")


def scene_assets(path, n: int) -> dict:
    """The colours and normals of a scene folder's ``coord.npy`` (Pointcept's layout:
    ``coord.npy``, ``color.npy``, ``normal.npy``, ``segment.npy``, ... one row a point):
    the files beside ``path`` of :data:`SCENE_ASSETS`, where ``path`` is a ``coord.npy``.

    Parameters
    ----------
    path : str or os.PathLike
        The points' file.
    n : int
        Its points.

    Returns
    -------
    dict
        ``colors`` (``(n, 3)`` in ``[0, 1]``) and ``normals`` (``(n, 3)``), those found;
        empty for any other file.

    Raises
    ------
    MeshFormatError
        If an asset is there but not ``(n, 3)`` real numbers (the file named).

    Examples
    --------
    >>> import tempfile
    >>> scene = Path(tempfile.mkdtemp())
    >>> np.save(scene / "coord.npy", np.zeros((4, 3))); np.save(scene / "color.npy",
    ...     np.full((4, 3), 255, dtype=np.uint8))
    >>> scene_assets(scene / "coord.npy", 4)["colors"].tolist()[0]
    [1.0, 1.0, 1.0]
    """
    path = Path(path)
    if path.name != "coord.npy":
        return {}
    out = {}
    for asset, key in SCENE_ASSETS.items():
        beside = path.parent / f"{asset}.npy"
        if not beside.is_file():
            continue
        try:
            arr = np.load(beside, allow_pickle=False)
        except Exception as exc:  # noqa: BLE001 - numpy raises many types on damaged files
            raise MeshFormatError(f"{beside}: cannot read NPY: {exc}") from None
        if arr.shape != (n, 3) or not_real(arr.dtype, "NPY"):
            raise MeshFormatError(f"{beside}: the scene's {asset} should be ({n:,}, 3) real "
                                  f"numbers, one row a point of coord.npy; it is "
                                  f"{arr.shape} {arr.dtype}")
        out[key] = unit_colors(arr) if key == "colors" else arr.astype(np.float64)
    return out
