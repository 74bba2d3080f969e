"""Reading point clouds: PLY without faces, PCD, XYZ/PTS/TXT columns, ``.npy``, LAS/LAZ.

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
  ``(H, W, 3)`` (NaN points invalid);
- LAS / LAZ: ``laspy`` (extra ``clouds``; LAZ through its ``lazrs`` backend),
  scaled coordinates.

Elsewhere than PCD files and organized arrays a non-finite coordinate is an
error naming its row.
"""

from __future__ import annotations

import io
import os
import re
import struct
from pathlib import Path

import numpy as np

from ..errors import MeshFormatError
from ..inputs.rgb import unit_colors
from .files import read_bytes, split_suffix
from .ply import ply_colors

__all__ = ["read_cloud", "CLOUD_FORMATS", "is_cloud_file", "check_laz", "check_las"]

#: Point-cloud formats of :func:`read_cloud` (PLY files are clouds when they have no faces).
CLOUD_FORMATS = ("pcd", "xyz", "pts", "txt", "npy", "las", "laz")


def is_cloud_file(path) -> bool:
    """Whether ``path`` holds a point cloud: a cloud format, or a PLY declaring no face."""
    path = Path(path)
    fmt, comp = split_suffix(path)
    if fmt in CLOUD_FORMATS:
        return True
    if fmt != "ply" or not path.is_file():
        return False
    if comp:
        data = read_bytes(path, comp)
    else:
        with path.open("rb") as f:
            data = f.read(1 << 16)
    if not data:  # an empty file: read_mesh says so
        return False
    head = _ply_header(data)
    faces = [int(p[2]) for p in (ln.split() for ln in head)
             if len(p) == 3 and p[0] == b"element" and p[1] == b"face" and p[2].isdigit()]
    return not faces or faces[0] == 0


def _ply_header(data: bytes) -> list[bytes]:
    end = data.find(b"end_header")
    return data[:end if end >= 0 else 1 << 16].split(b"\n")


def read_cloud(path, format: str | None = None):
    """Read a point cloud from a file.

    Parameters
    ----------
    path : str or os.PathLike
        ``.ply`` (no faces), ``.pcd``, ``.xyz``, ``.pts``, ``.txt``, ``.npy``,
        ``.las`` or ``.laz``; text formats and PLY may end in ``.gz``/``.xz``/``.bz2``.
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
        If a point has a non-finite coordinate (outside PCD files), or
        normals are zero or not finite.
    MissingExtraError
        PCD and LAS/LAZ without the ``clouds`` extra.

    Examples
    --------
    >>> import numpy as np
    >>> np.savetxt("cloud.xyz", np.random.default_rng(0).random((50, 3)))
    >>> c = read_cloud("cloud.xyz")
    >>> c.n_points, c.points.dtype
    (50, dtype('float64'))
    """
    from ..inputs.cloud import InvalidCloudError, PointCloud

    path = Path(path)
    fmt, comp = split_suffix(path)
    if format is not None:
        fmt = format.lower().lstrip(".")
    if fmt not in CLOUD_FORMATS + ("ply",):
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
    else:
        from .headers import header_counts

        header_counts(path)  # a header declaring more than the file holds: refused unread
        data = read_bytes(path, comp)
        if fmt == "ply":
            kw = _read_ply(data, path)
        elif fmt == "npy":
            kw = _read_npy(data, path)
        else:
            kw = _read_columns(data, path)
    if kw["points"].shape[0] == 0:
        raise InvalidCloudError(f"{path}: empty point cloud: no point")
    try:
        return PointCloud(name=path.name, **kw)
    except InvalidCloudError as exc:
        raise InvalidCloudError(f"{path}: {str(exc).removeprefix(path.name + ': ')}") from None


def _read_ply(data: bytes, path: Path) -> dict:
    from plyfile import PlyData, PlyParseError

    try:
        ply = PlyData.read(io.BytesIO(data))
        vert = ply["vertex"]
        names = [p.name for p in vert.properties]
        missing = [c for c in "xyz" if c not in names]
        if missing:
            raise MeshFormatError(f"{path}: the vertex element has no {', '.join(missing)} "
                                  f"property (it has: {', '.join(names)})")
        with np.errstate(invalid="ignore"):  # a signalling NaN: the rows check names it
            pts = np.stack([np.asarray(vert[c], dtype=np.float64) for c in "xyz"], axis=1)
            nrm = None
            if all(c in names for c in ("nx", "ny", "nz")):
                nrm = np.stack([np.asarray(vert[c], dtype=np.float64)
                                for c in ("nx", "ny", "nz")], axis=1)
        col = ply_colors(vert)
    except (PlyParseError, KeyError, ValueError, IndexError, TypeError, EOFError,
            MemoryError) as exc:
        if isinstance(exc, MeshFormatError):
            raise
        raise MeshFormatError(f"{path}: cannot read PLY points: {exc}") from None
    return {"points": pts, "normals": nrm, "colors": col}


def _packed_rgb(values: np.ndarray) -> np.ndarray:
    """PCL's packed ``rgb``/``rgba`` field (a float32 or uint32 holding 0x00RRGGBB)."""
    v = np.ascontiguousarray(values)
    u = v.view(np.uint32) if v.dtype.itemsize == 4 else v.astype(np.uint32)
    return np.stack([(u >> 16) & 255, (u >> 8) & 255, u & 255], axis=1).astype(np.uint8)


def _read_pcd(path: Path) -> dict:
    from .._runtime.extras import require

    pypcd4 = require("pypcd4", "reading PCD files")
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a directory")
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
        viewpoint = np.asarray(meta.viewpoint[:3], dtype=np.float64)
    except MeshFormatError:
        raise
    except Exception as exc:  # noqa: BLE001 - pypcd4/pydantic raise many types
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise MeshFormatError(f"{path}: cannot read PCD: {msg}") from None
    if pts.shape[0] != height * width:
        raise MeshFormatError(f"{path}: PCD has {pts.shape[0]} points, the header says "
                              f"{width} x {height}")
    if nrm is not None:
        bad = ~np.isfinite(nrm).all(axis=1) | (np.abs(nrm).sum(axis=1) == 0)
        if bad.any():  # PCL leaves normals NaN where it could not estimate one
            nrm = None
    return {"points": pts, "normals": nrm, "colors": col, "allow_invalid": True,
            "viewpoint": viewpoint,
            "shape": (height, width) if height > 1 else None}


def _read_las(path: Path) -> dict:
    from .._runtime.extras import require

    laspy = require("laspy", "reading LAS/LAZ files")
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
    except Exception as exc:  # noqa: BLE001 - laspy raises many types
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise MeshFormatError(f"{path}: cannot read {path.suffix.upper()[1:]} (damaged or "
                              f"truncated file?): {msg}") from None
    # LAS z is elevation: an airborne, mobile or terrestrial scan sees its surfaces from
    # above or from the side, so estimated normals are turned upwards piece by piece
    return {"points": pts.astype(np.float64), "colors": col, "up": np.array([0.0, 0.0, 1.0])}


#: The smallest point record of any LAS point format (format 0), in bytes: each chunk
#: of a LAZ file begins with one point stored raw, so a chunk takes at least this much.
_SMALLEST_RECORD = 20


#: The size of a point record of each LAS point format (its standard fields), in bytes.
_RECORD = {0: 20, 1: 28, 2: 26, 3: 34, 4: 57, 5: 63, 6: 30, 7: 36, 8: 38, 9: 59, 10: 67}


def check_las(path) -> None:
    """Refuse a LAS or LAZ file whose header does not match its data, before it is read;
    both readers (a whole run's and a tiled run's) call it.

    An uncompressed file's point records must fill its point data: a record length
    shorter than its point format's, or a point count that the bytes after the header
    cannot hold (a file truncated, even at a record boundary), or bytes left over for
    more records (a wrong record length) would give fewer or garbage points. A LAZ
    file's chunk table is checked by :func:`check_laz`.

    Parameters
    ----------
    path : str or Path

    Raises
    ------
    MeshFormatError
        Naming what the header declares and what the file holds.

    Examples
    --------
    >>> check_las("missing.las")
    Traceback (most recent call last):
    ...
    FileNotFoundError: [Errno 2] No such file or directory: 'missing.las'
    """
    with open(path, "rb") as f:
        head = f.read(375)
        size = os.fstat(f.fileno()).st_size
    if len(head) < 227 or head[:4] != b"LASF":
        return  # not LAS at all: laspy says what is wrong
    if head[104] & 0xC0:  # compressed: LAZ
        check_laz(path)
        return
    fmt, length = head[104] & 0x3F, struct.unpack_from("<H", head, 105)[0]
    start = struct.unpack_from("<I", head, 96)[0]
    count = struct.unpack_from("<I", head, 107)[0]
    minor = head[25]
    end = size
    if minor >= 4 and len(head) >= 375:
        count = count or struct.unpack_from("<Q", head, 247)[0]
        evlr, n_evlr = struct.unpack_from("<QI", head, 235)
        if n_evlr and start < evlr <= size:
            end = evlr
    if minor >= 3 and len(head) >= 235:
        wave = struct.unpack_from("<Q", head, 227)[0]
        if start < wave <= end:
            end = wave
    if fmt in _RECORD and length < _RECORD[fmt]:
        raise MeshFormatError(f"{path}: damaged LAS file: point record length {length} is "
                              f"shorter than point format {fmt}'s {_RECORD[fmt]} bytes")
    held = max(0, end - start) // length if length else 0
    if count > held:
        raise MeshFormatError(f"{path}: damaged LAS file: the header declares {count} points, "
                              f"the file holds {held} (truncated?)")
    if length and end - start - count * length >= length:
        raise MeshFormatError(f"{path}: damaged LAS file: {count} points of {length} bytes "
                              f"leave {end - start - count * length} bytes of point data "
                              "unread (a wrong point count or record length?)")


def check_laz(path) -> None:
    """Refuse a LAZ file whose chunk table cannot be right, before ``lazrs`` reads it.

    LAZ data is compressed in chunks listed in a table near the end of the
    file. ``lazrs`` allocates that table from the count it declares, and a
    count it cannot allocate (a damaged or truncated file) aborts the whole
    process, where Python would raise ``MemoryError``. Each chunk begins with
    one point stored raw, so a count larger than the point data can hold is
    refused here with a clear error. Files that are not compressed LAS (or
    are too short to be LAS at all) pass, and laspy says what is wrong.

    Parameters
    ----------
    path : str or Path
        A ``.las`` or ``.laz`` file (LAZ is told by the point format's
        compression bits, not by the suffix).

    Raises
    ------
    MeshFormatError
        If the chunk table's position lies outside the file, or it declares
        more chunks than the points can fill.

    Examples
    --------
    >>> check_laz("missing.laz")
    Traceback (most recent call last):
    ...
    FileNotFoundError: [Errno 2] No such file or directory: 'missing.laz'
    """
    with open(path, "rb") as f:
        head = f.read(107)
        if len(head) < 107 or head[:4] != b"LASF" or not head[104] & 0xC0:
            return
        size = os.fstat(f.fileno()).st_size
        start = struct.unpack_from("<I", head, 96)[0]  # the offset to the point data
        f.seek(start)
        raw = f.read(8)
        table = struct.unpack("<q", raw)[0] if len(raw) == 8 else -2
        if table == -1 and size >= 8:  # written as a stream: the offset is at the very end
            f.seek(size - 8)
            table = struct.unpack("<q", f.read(8))[0]
        if not start + 8 <= table <= size - 8:
            raise MeshFormatError(f"{path}: damaged LAZ file: its chunk table should start "
                                  f"at byte {table}, outside its {size} bytes (truncated?)")
        f.seek(table)
        count = struct.unpack("<4xI", f.read(8))[0]
    most = (table - start - 8) // _SMALLEST_RECORD + 1
    if count > most:
        raise MeshFormatError(f"{path}: damaged LAZ file: its chunk table declares {count} "
                              f"chunks, more than its {table - start - 8} bytes of points "
                              f"can hold ({most} at most)")


def _read_npy(data: bytes, path: Path) -> dict:
    try:
        arr = np.load(io.BytesIO(data), allow_pickle=False)
    except Exception as exc:  # noqa: BLE001 - numpy raises many types on damaged files
        raise MeshFormatError(f"{path}: cannot read NPY: {exc}") from None
    if not isinstance(arr, np.ndarray) or arr.dtype.names is not None \
            or not np.issubdtype(arr.dtype, np.number):
        raise MeshFormatError(f"{path}: NPY must hold a numeric array, got dtype "
                              f"{getattr(arr, 'dtype', type(arr).__name__)}")
    if arr.ndim == 3 and arr.shape[2] == 3:
        h, w = arr.shape[:2]
        return {"points": arr.reshape(-1, 3).astype(np.float64), "allow_invalid": True,
                "shape": (h, w)}
    if arr.ndim == 2 and arr.shape[1] in (3, 6):
        arr = arr.astype(np.float64)
        return {"points": arr[:, :3], "normals": arr[:, 3:] if arr.shape[1] == 6 else None}
    raise MeshFormatError(f"{path}: NPY array of shape {arr.shape}: expected (N, 3) points, "
                          "(N, 6) points and normals, or organized (H, W, 3)")


_HEADER = re.compile(r"^\s*(#|//)\s*")


def _read_columns(data: bytes, path: Path) -> dict:
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise MeshFormatError(f"{path}: not a text file (binary data in a text format)") \
            from None
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    names = None
    body = []
    for ln in lines:
        if _HEADER.match(ln):
            if names is None and body == []:
                words = [w.lower() for w in re.split(r"[\s,]+", _HEADER.sub("", ln).strip()) if w]
                if words and not all(_is_number(w) for w in words):
                    names = words
            continue
        body.append(ln)
    if body and len(body[0].split()) == 1 and body[0].strip().isdigit():
        declared = int(body[0])  # a PTS count line
        body = body[1:]
        if len(body) < declared:
            raise MeshFormatError(f"{path}: truncated: the first line declares {declared} "
                                  f"points, the file has {len(body)}")
        body = body[:declared]
    if not body:
        return {"points": np.zeros((0, 3))}
    rows = [re.split(r"[\s,;]+", b.strip()) for b in body]
    width = len(rows[0])
    for i, r in enumerate(rows):
        if len(r) != width:
            raise MeshFormatError(f"{path}: line {i + 1} of the points has {len(r)} columns, "
                                  f"the first has {width}")
    try:
        arr = np.array(rows, dtype=np.float64)
    except ValueError:
        bad = next(i for i, r in enumerate(rows) if not all(_is_number(w) for w in r))
        raise MeshFormatError(f"{path}: point line {bad + 1} is not numbers: "
                              f"{body[bad].strip()[:80]!r}") from None
    if names is not None:
        if len(names) != width:
            raise MeshFormatError(f"{path}: the header names {len(names)} columns "
                                  f"({' '.join(names)}), the lines have {width}")
        missing = [c for c in "xyz" if c not in names]
        if missing:
            raise MeshFormatError(f"{path}: unknown columns: the header {' '.join(names)} "
                                  f"names no {', '.join(missing)} column")
        pts = arr[:, [names.index(c) for c in "xyz"]]
        nrm = None
        if all(c in names for c in ("nx", "ny", "nz")):
            nrm = arr[:, [names.index(c) for c in ("nx", "ny", "nz")]]
        return {"points": pts, "normals": nrm}
    if width < 3:
        raise MeshFormatError(f"{path}: point lines need 3 columns (x y z), found {width}")
    return {"points": arr[:, :3]}


def _is_number(word: str) -> bool:
    try:
        float(word)
        return True
    except ValueError:
        return False
