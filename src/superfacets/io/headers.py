"""What a file's header declares, read without its data: element counts, and whether the
data after the header can hold them.

Used before a file is read: a header that declares more than the file holds is damage
(refused in one line, whatever the header claims), and the counts size the run's memory
before anything large is read (:func:`superfacets._runtime.memory.check_memory`).
"""

from __future__ import annotations

import os
import re
import struct
from pathlib import Path

import numpy as np

from .._runtime import extras
from ..checks import not_real
from ..errors import MemoryLimitError, MeshFormatError, MissingExtraError
from .files import decompressed_head, max_ratio, split_suffix

__all__ = ["header_counts", "e57_counts", "check_las", "check_laz", "check_pcd", "check_stl",
           "ply_mapped", "npy_mapped", "first_line", "NotStreamedError", "PCD_LINES",
           "pcd_problem", "ply_names", "gltf_document", "gltf_points_only"]


class NotStreamedError(MeshFormatError):
    """A PLY file that cannot be read in chunks (ASCII, or faces that are not triangles
    alone): a tiled run reads it whole instead (``RegionReader.spill``)."""

_SIZE = {"char": 1, "uchar": 1, "int8": 1, "uint8": 1, "short": 2, "ushort": 2,
         "int16": 2, "uint16": 2, "int": 4, "uint": 4, "int32": 4, "uint32": 4,
         "float": 4, "float32": 4, "double": 8, "float64": 8}
_HEAD = 1 << 16  # a header longer than this is not one this package writes or reads


def header_counts(path) -> dict | None:
    """``{"faces": m, "vertices": n}`` or ``{"points": n}`` as a PLY, OFF, ``.tri`` or E57
    file's header declares them (of a compressed one, its start alone decompressed);
    None for other formats.

    Raises
    ------
    MeshFormatError
        If the data after a PLY header cannot hold what it declares (each element at
        its smallest: its scalar properties, a face's list of three indices; two
        characters a number in ASCII), or an OFF header's counts are not integers.

    Examples
    --------
    >>> _ = trimesh.creation.box().export("box.ply")
    >>> header_counts("box.ply")
    {'vertices': 8, 'faces': 12}

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    dict or None
    """

    p = Path(path)
    suffix, comp = split_suffix(p)
    if suffix == "e57" and comp is None and p.is_file():  # (its XML header: scans, counts)
        try:
            return {"points": sum(n for _, n, _ in e57_counts(p))}
        except MissingExtraError:
            return None  # the reader says which extra
    if suffix not in ("ply", "off", "tri") or not p.is_file():
        return None
    if comp is None:
        with open(p, "rb") as f:
            head = f.read(_HEAD)
        size = p.stat().st_size
    else:  # the head alone decompressed: the counts before the rest (a decompression
        head = decompressed_head(p, comp, _HEAD)  # bomb is refused by them, unread)
        size = None
    if suffix == "ply":
        return _ply(p, head, size)
    words = head.split(b"\n", 2)
    try:
        if suffix == "off":
            first = head.split(None, 4)
            if not first or not first[0].upper().endswith(b"OFF"):
                return None
            nv, nf = int(first[1]), int(first[2])
            return {"vertices": nv, "faces": nf}
        nv = int(words[0])
    except (ValueError, IndexError):
        return None  # the reader says what is wrong
    return {"vertices": nv}


def _ply(p: Path, head: bytes, size: int | None) -> dict | None:
    end = head.find(b"end_header")
    if not head.startswith(b"ply") or end < 0:
        return None
    body = head[:end].decode("ascii", "replace").splitlines()
    start = end + len(b"end_header") + (2 if head[end + 10:end + 12] == b"\r\n" else 1)
    ascii_ = any(line.split()[:2] == ["format", "ascii"] for line in body)
    elements: list[list] = []  # [name, count, smallest record]
    layout: list[list] = []  # per element: (type, or ("list", count type)) of each property
    for line in body:
        w = line.split()
        if len(w) >= 3 and w[0] == "element":
            try:
                elements.append([w[1], int(w[2]), 0])
            except ValueError:
                return None
            layout.append([])
        elif len(w) >= 3 and w[0] == "property" and elements:
            layout[-1].append(("list", w[2]) if w[1] == "list" else w[1])
            if w[1] == "list" and len(w) >= 5:
                # (binary faces: three corners at least, as the first face is checked;
                # an ASCII list may be shorter, which its reader then names)
                corners = 3 if elements[-1][0] == "face" else 0
                elements[-1][2] += (2 if ascii_ else
                                    _SIZE.get(w[2], 1) + corners * _SIZE.get(w[3], 1))
            else:
                elements[-1][2] += 2 if ascii_ else _SIZE.get(w[1], 1)
    negative = [f"{count:,} {name}" for name, count, _ in elements if count < 0]
    if negative:  # (numpy's "negative dimensions are not allowed" said no more)
        raise MeshFormatError(f"{p}: damaged PLY header: it declares {', '.join(negative)} "
                              "elements, a count below zero")
    need = sum(count * smallest for _, count, smallest in elements)
    if size is not None and need > size - start:
        declared = ", ".join(f"{count:,} {name}" for name, count, _ in elements)
        raise MeshFormatError(f"{p}: damaged PLY file: its header declares {declared} "
                              f"({need:,} bytes at the least), and {size - start:,} bytes "
                              "follow it (truncated?)")
    if size is not None and not ascii_:
        _check_first_face(p, head, start, elements, layout)
    counts = {("vertices" if name == "vertex" else "faces" if name == "face" else name): c
              for name, c, _ in elements}
    if counts.get("faces", 0) == 0 and "vertices" in counts:
        counts = {"points": counts["vertices"]}
    return counts


_NUMPY = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2",
          "int16": "i2", "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4",
          "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8",
          "float64": "f8"}


def _check_first_face(p: Path, head: bytes, start: int, elements: list, layout: list) -> None:
    """Refuse a binary PLY whose first face lists fewer than 3 vertices, before its faces
    are parsed one by one (50M faces of no vertex took minutes to be refused): where every
    element before the faces has records of one size, the first face's count is read
    where it lies. A file laid out otherwise passes: the reader says what is wrong."""
    names = [e[0] for e in elements]
    if "face" not in names:
        return
    f = names.index("face")
    if not layout[f] or not isinstance(layout[f][0], tuple) or elements[f][1] < 1:
        return
    offset = start
    for (_, count, _), props in zip(elements[:f], layout[:f]):
        if any(isinstance(t, tuple) or t not in _NUMPY for t in props):
            return  # (lists before the faces: records of several sizes)
        offset += count * sum(int(_NUMPY[t][1]) for t in props)
    kind = _NUMPY.get(layout[f][0][1])
    if kind is None or kind[0] == "f":
        return
    order = "<" if b"binary_little_endian" in head[:start] else ">"
    with open(p, "rb") as fh:
        fh.seek(offset)
        raw = fh.read(int(kind[1]))
    if len(raw) < int(kind[1]):
        return
    n = int(np.frombuffer(raw, dtype=order + kind)[0])
    if n < 3:
        raise MeshFormatError(f"{p}: face 0 lists {n} vertices (a face needs at least 3); "
                              f"its header declares {elements[f][1]:,} faces")


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

    Returns
    -------
    None
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
    MemoryLimitError
        If its points would take more than :func:`~superfacets.io.files.max_ratio`
        times its size (a decompression bomb).

    Examples
    --------
    >>> check_laz("missing.laz")
    Traceback (most recent call last):
    ...
    FileNotFoundError: [Errno 2] No such file or directory: 'missing.laz'

    Returns
    -------
    None
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
        f.seek(0)
        full = f.read(255)
    most = (table - start - 8) // _SMALLEST_RECORD + 1
    if count > most:
        raise MeshFormatError(f"{path}: damaged LAZ file: its chunk table declares {count} "
                              f"chunks, more than its {table - start - 8} bytes of points "
                              f"can hold ({most} at most)")
    _check_laz_ratio(path, full, size)


def _check_laz_ratio(path, head: bytes, size: int) -> None:
    """Refuse a LAZ whose points would take more than :func:`~superfacets.io.files.max_ratio`
    times its size as LAS records (real LAZ: about 10; millions of one point repeated
    compress to a few bytes each): a decompression bomb, refused before it is read."""

    length = struct.unpack_from("<H", head, 105)[0]
    points = struct.unpack_from("<I", head, 107)[0]
    if len(head) >= 255 and head[25] >= 4:  # LAS 1.4: the 64-bit count
        points = max(points, struct.unpack_from("<Q", head, 247)[0])
    ratio = max_ratio()
    if points * length > ratio * max(size, 1 << 12):
        raise MemoryLimitError(
            f"{path}: its {points:,} points of {length} bytes would take more than {ratio:g} "
            f"times its {size:,} bytes (real LAZ files: about 10 times): refused as a likely "
            "decompression bomb; SUPERFACETS_MAX_RATIO raises the bound for a genuine file",
            points * length, int(ratio * size))


def ply_mapped(path: Path):
    """A PLY file's elements, memory-mapped where its format allows (the header is read,
    not the data).

    Parameters
    ----------
    path : pathlib.Path

    Returns
    -------
    plyfile.PlyData

    Raises
    ------
    NotStreamedError
        If the file is an ASCII PLY, or its faces are not all triangles.
    MeshFormatError
        If its header cannot be read, or its sizes do not fit.

    Examples
    --------
    >>> _ = trimesh.creation.box().export("box.ply")
    >>> ply_mapped(Path("box.ply"))["face"].count
    12
    """
    from plyfile import PlyData, PlyParseError

    try:
        with path.open("rb") as f:
            head = f.read(1 << 12)
        if b"format ascii" in head.split(b"end_header")[0]:
            raise NotStreamedError(f"{path}: an ASCII PLY is not read in chunks")
        ply = PlyData.read(str(path), mmap=True,
                           known_list_len={"face": {"vertex_indices": 3, "vertex_index": 3}})
    except MeshFormatError:
        raise
    except (PlyParseError, ValueError, KeyError, IndexError, TypeError, EOFError,
            OSError) as exc:
        if "unexpected list length" in str(exc):  # plyfile's check of the face sizes
            raise NotStreamedError(f"{path}: a face is not a triangle ({first_line(exc)}): "
                                   "polygons are not read in chunks") from None
        raise MeshFormatError(f"{path}: cannot read PLY: {first_line(exc)}") from None
    elements = [e.name for e in ply.elements]
    if "vertex" not in elements:
        raise MeshFormatError(f"{path}: the PLY has no vertex element (it has: "
                              f"{', '.join(elements) or 'none'})")
    names = ply["vertex"].data.dtype.names or ()
    missing = [c for c in "xyz" if c not in ply_names(names)]
    if missing:
        raise MeshFormatError(f"{path}: the vertex element has no {', '.join(missing)} property")
    return ply


def ply_names(names, wanted=("x", "y", "z", "nx", "ny", "nz")) -> dict:
    """The PLY property holding each of ``wanted``: the one of that name, else the one name
    that differs from it in case alone (``X``, as PDAL names its dimensions; PDAL's readers
    take either).

    Parameters
    ----------
    names : sequence of str
        The element's property names.
    wanted : sequence of str

    Returns
    -------
    dict
        ``wanted`` name -> property name, for those found.

    Raises
    ------
    TypeError
        Never: a name not found is left out.

    Examples
    --------
    >>> ply_names(["X", "Y", "Z", "intensity"])
    {'x': 'X', 'y': 'Y', 'z': 'Z'}
    """
    out = {}
    for w in wanted:
        alike = [w] if w in names else [n for n in names if n.lower() == w]
        if len(alike) == 1:
            out[w] = alike[0]
    return out


def npy_mapped(path: Path) -> np.ndarray:
    """A ``.npy`` file's array, memory-mapped (nothing read but the header).

    Parameters
    ----------
    path : pathlib.Path

    Returns
    -------
    numpy.memmap or ndarray

    Raises
    ------
    MeshFormatError
        If the file is not a readable ``.npy`` array.

    Examples
    --------
    >>> np.save("p.npy", np.zeros((5, 3)))
    >>> npy_mapped(Path("p.npy")).shape
    (5, 3)
    """
    try:
        arr = np.load(path, mmap_mode="r", allow_pickle=False)
    except Exception as exc:  # noqa: BLE001 - numpy raises many types on damaged files
        raise MeshFormatError(f"{path}: cannot read NPY: {first_line(exc)}") from None

    if not_real(arr.dtype, "NPY points"):
        raise MeshFormatError(f"{path}: {not_real(arr.dtype, 'NPY points')}")
    return arr


def check_stl(data: bytes, path: Path) -> None:
    """Refuse a truncated STL in one line: a binary STL's size is 84 bytes plus 50 per
    triangle it declares; an ASCII one ends its last facet (trimesh read both as an
    empty mesh).

    Parameters
    ----------
    data : bytes
        The file's bytes.
    path : pathlib.Path
        Its name, for the message.

    Returns
    -------
    None

    Raises
    ------
    MeshFormatError
        If the file is shorter than it declares.

    Examples
    --------
    >>> check_stl(bytes(84), Path("empty.stl"))  # a binary STL of no triangles
    """
    if data[:5].lower() == b"solid" and b"facet" in data[:4096].lower():  # ASCII (its
        # keywords in any case: "FACET NORMAL" too)
        tail = data.rstrip()[-256:].lower()
        if b"endsolid" not in tail and not tail.endswith(b"endfacet"):
            raise MeshFormatError(f"{path}: truncated ASCII STL (its last facet does not end)")
        return
    if len(data) < 84:
        if data[:5].lower() == b"solid" and b"endsolid" in data.lower():
            raise MeshFormatError(f"{path}: empty mesh: an ASCII STL of no facet")
        raise MeshFormatError(f"{path}: truncated STL: {len(data)} bytes, not even the "
                              "84 of a binary STL's header")
    n = int.from_bytes(data[80:84], "little")
    if len(data) < 84 + 50 * n:
        raise MeshFormatError(f"{path}: truncated binary STL: {n:,} triangles declared "
                              f"({84 + 50 * n:,} bytes), {len(data):,} bytes in the file")


_STL_KEYWORD = re.compile(rb"^[ \t]*(facet|vertex)\b([^\n]*)", re.M | re.I)


def check_stl_triangles(data: bytes, path: Path) -> None:
    r"""Refuse an ASCII STL facet that is not a triangle of three ``x y z`` vertices (read
    where trimesh failed: its message is numpy's "cannot reshape array").

    Parameters
    ----------
    data : bytes
        The file's bytes.
    path : pathlib.Path
        Its name, for the message.

    Returns
    -------
    None

    Raises
    ------
    MeshFormatError
        Naming the first facet of other than three vertices, or the first vertex of other
        than three coordinates.

    Examples
    --------
    >>> facet = b"facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n"
    >>> try:
    ...     check_stl_triangles(b"solid t\n" + facet + b"endfacet\nendsolid\n", Path("a.stl"))
    ... except MeshFormatError as exc:
    ...     print(exc)
    a.stl: ASCII STL facet 1 has 2 vertices, not 3 (STL holds triangles only)
    """
    facet = vertices = 0
    for match in _STL_KEYWORD.finditer(data):
        if match.group(1).lower() == b"facet":
            if facet and vertices != 3:
                break
            facet, vertices = facet + 1, 0
        elif len(match.group(2).split()) != 3:
            raise MeshFormatError(f"{path}: vertex {vertices + 1} of ASCII STL facet "
                                  f"{facet:,} has not three coordinates: "
                                  f"{match.group(0).strip().decode(errors='replace')!r}")
        else:
            vertices += 1
    if facet and vertices != 3:
        raise MeshFormatError(f"{path}: ASCII STL facet {facet:,} has {vertices} vertices, "
                              "not 3 (STL holds triangles only)")


def first_line(exc: BaseException) -> str:
    """The first line of an exception's message (its type's name when it has none).

    Parameters
    ----------
    exc : BaseException

    Returns
    -------
    str

    Raises
    ------
    TypeError
        Never.

    Examples
    --------
    >>> first_line(ValueError("bad")), first_line(KeyError())
    ('bad', 'KeyError')
    """
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


def e57_counts(path: Path) -> list:
    """``(name, points, position)`` of each scan of an E57 file, from its XML header
    alone (no point is read).

    Parameters
    ----------
    path : pathlib.Path

    Returns
    -------
    list of (str, int, (3,) float64 ndarray)
        Each scan's name (``scan i`` where it has none), its number of point records
        and its scanner's position in the file's common frame (the pose's translation;
        the origin without a pose).

    Raises
    ------
    MeshFormatError
        If the file is not an E57 file pye57 can open.
    MissingExtraError
        Without the ``clouds`` extra.

    Examples
    --------
    >>> e57_counts(Path("site.e57"))  # doctest: +SKIP
    [('station 0', 3000, array([0., 0., 0.]))]
    """

    pye57 = extras.require("pye57", "reading E57 files")
    try:
        e57 = pye57.E57(str(path))
        try:
            out = []
            for i in range(e57.scan_count):
                head = e57.get_header(i)
                try:
                    name = str(head["name"].value())
                except Exception:  # noqa: BLE001 - an unnamed scan
                    name = f"scan {i}"
                position = np.asarray(head.translation, dtype=np.float64) if \
                    head.has_pose() else np.zeros(3)
                out.append((name, int(head.point_count), position))
            return out
        finally:
            e57.close()
    except Exception as exc:  # noqa: BLE001 - libE57Format raises its own types
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise MeshFormatError(f"{path}: cannot read E57 (damaged or not E57?): {msg}") from None


#: The deepest node hierarchy a glTF scene may have (a model's hierarchy is a few dozen
#: levels; trimesh walks each level with Python calls: 5,000 levels ran for minutes).
GLTF_MAX_DEPTH = 1000


def gltf_document(data: bytes, fmt: str) -> dict | None:
    """The JSON document of a ``.gltf`` (its text) or a ``.glb`` (its first chunk), or None
    where it cannot be read (the reader then says what is wrong).

    Parameters
    ----------
    data : bytes
        The file's content, or for a ``.glb`` at least its header and JSON chunk.
    fmt : {'gltf', 'glb'}

    Returns
    -------
    dict or None

    Raises
    ------
    TypeError
        Never: anything unreadable is None.

    Examples
    --------
    >>> gltf_document(b'{"asset": {"version": "2.0"}}', "gltf")
    {'asset': {'version': '2.0'}}
    """
    import json

    text = data
    if fmt == "glb":
        if len(data) < 20 or data[:4] != b"glTF" or data[16:20] != b"JSON":
            return None
        size = struct.unpack_from("<I", data, 12)[0]
        text = data[20:20 + size]
    try:
        doc = json.loads(text)
    except (ValueError, UnicodeDecodeError, RecursionError):
        return None
    return doc if isinstance(doc, dict) else None


def gltf_points_only(doc: dict | None) -> bool:
    """Whether a glTF document's meshes are all points (every primitive of mode 0,
    ``POINTS``: a point cloud), with at least one primitive.

    Parameters
    ----------
    doc : dict or None
        :func:`gltf_document`'s.

    Returns
    -------
    bool

    Raises
    ------
    TypeError
        Never.

    Examples
    --------
    >>> gltf_points_only({"meshes": [{"primitives": [{"mode": 0}]}]})
    True
    >>> gltf_points_only({"meshes": [{"primitives": [{}]}]})   # (4, triangles, by default)
    False
    """
    meshes = doc.get("meshes") if isinstance(doc, dict) else None
    if not isinstance(meshes, list):
        return False
    modes = [p.get("mode", 4) if isinstance(p, dict) else None
             for m in meshes if isinstance(m, dict)
             for p in (m.get("primitives") if isinstance(m.get("primitives"), list) else [])]
    return bool(modes) and all(mode == 0 for mode in modes)


def check_gltf(data: bytes, fmt: str, path) -> None:
    """Refuse a glTF or GLB file whose node hierarchy is not a forest of bounded depth,
    before a reader walks it: a node that is its own ancestor (the specification forbids
    cycles; a reader's walk never ends or stops on its own limit), a node with two
    parents, a child index outside the nodes, or a nesting deeper than
    :data:`GLTF_MAX_DEPTH` levels. Checked iteratively: no recursion to exhaust.

    Parameters
    ----------
    data : bytes
        The file's content (a ``.gltf``'s JSON, or a ``.glb``'s binary container).
    fmt : {'gltf', 'glb'}
    path : str or os.PathLike
        For messages.

    Returns
    -------
    None

    Raises
    ------
    MeshFormatError
        Naming the node and what is wrong. A JSON that cannot be read is left to the
        reader, which says what is wrong with it.

    Examples
    --------
    >>> import json
    >>> nodes = [{"children": [1]}, {"children": [2]}, {"children": [0]}]
    >>> try:
    ...     check_gltf(json.dumps({"nodes": nodes}).encode(), "gltf", "loop.gltf")
    ... except MeshFormatError as exc:
    ...     print(str(exc).split(": ", 1)[1])
    the glTF node hierarchy has a cycle: node 0 is its own ancestor (0 -> 1 -> 2 -> 0)
    """
    doc = gltf_document(data, fmt)  # (None: the reader says what is wrong)
    nodes = doc.get("nodes") if isinstance(doc, dict) else None
    if not isinstance(nodes, list):
        return
    children = []
    for i, node in enumerate(nodes):
        kids = node.get("children", []) if isinstance(node, dict) else []
        if not isinstance(kids, list) or not all(isinstance(c, int) and not
                                                 isinstance(c, bool) for c in kids):
            raise MeshFormatError(f"{path}: glTF node {i}: children must be a list of node "
                                  "indices")
        bad = [c for c in kids if not 0 <= c < len(nodes)]
        if bad:
            raise MeshFormatError(f"{path}: glTF node {i} names a child {bad[0]}, outside "
                                  f"the {len(nodes)} nodes")
        children.append(kids)
    parent = [-1] * len(nodes)
    for i, kids in enumerate(children):
        for c in kids:
            if parent[c] >= 0 or c == i:
                if c == i:
                    raise MeshFormatError(f"{path}: the glTF node hierarchy has a cycle: node "
                                          f"{i} is its own child")
                raise MeshFormatError(f"{path}: glTF node {c} has two parents ({parent[c]} "
                                      f"and {i}); a glTF node hierarchy is a tree")
            parent[c] = i
    depth = [0] * len(nodes)  # 0: not known yet
    for start in range(len(nodes)):  # up each node's chain of parents, each node once
        chain, seen, at = [], set(), start
        while at >= 0 and depth[at] == 0:
            chain.append(at)
            seen.add(at)
            at = parent[at]
            if at in seen:
                raise MeshFormatError(f"{path}: the glTF node hierarchy has a cycle: node "
                                      f"{at} is its own ancestor ({_loop(parent, at)})")
            if len(chain) > GLTF_MAX_DEPTH:
                raise MeshFormatError(f"{path}: the glTF node hierarchy is nested deeper "
                                      f"than {GLTF_MAX_DEPTH:,} levels (node {start})")
        base = depth[at] if at >= 0 else 0
        for k, node in enumerate(reversed(chain)):
            depth[node] = base + k + 1
        if base + len(chain) > GLTF_MAX_DEPTH:
            raise MeshFormatError(f"{path}: the glTF node hierarchy is nested deeper than "
                                  f"{GLTF_MAX_DEPTH:,} levels (node {start})")


def _loop(parent: list, start: int) -> str:
    """``0 -> 1 -> 2 -> 0``: the cycle through ``start``, each node followed by its child."""
    up, at = [start], parent[start]
    while at != start:
        up.append(at)
        at = parent[at]
    return " -> ".join(map(str, [start] + up[:0:-1] + [start]))


#: The lines of a PCD header the reader (``pypcd4``) needs, DATA last (HEIGHT, VERSION and
#: VIEWPOINT have defaults).
PCD_LINES = ("FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "POINTS", "DATA")


def pcd_problem(exc: BaseException) -> str:
    """What the PCD reader (``pypcd4``, its header checked by pydantic) found wrong, in one
    line a user can act on: the header line and value refused (pydantic's own text is
    "1 validation error for MetaData"), or the ASCII row of too few values (numpy's words
    for it name ``usecols``).

    Parameters
    ----------
    exc : BaseException
        What the reader raised.

    Returns
    -------
    str

    Raises
    ------
    MeshFormatError
        Never: the caller raises one with this text.

    Examples
    --------
    >>> pcd_problem(ValueError("the data requires 3 columns but 2 were found at row 7"))
    'line 7 of its ASCII data has 2 values, 3 expected'
    """
    errors = getattr(exc, "errors", None)
    if callable(errors):  # (pydantic: each field of the header it refused)
        try:
            found = list(errors())
        except Exception:  # noqa: BLE001 - not pydantic's after all
            found = []
        if found:
            first = found[0]
            loc = [str(x) for x in first.get("loc", ())]
            what = f"its {loc[0].upper()} line" if loc else "its header"
            if len(loc) > 1 and loc[1].isdigit():
                what += f"'s value {int(loc[1]) + 1}"
            more = f" ({len(found) - 1} more)" if len(found) > 1 else ""
            return f"{what} is {first.get('input')!r}: {first.get('msg')}{more}"
    msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    short = re.search(r"requires (\d+) columns but (\d+) were found at row (\d+)", msg)
    if short:
        return f"line {short[3]} of its ASCII data has {short[2]} values, {short[1]} expected"
    return msg


def check_pcd(path: Path) -> None:
    r"""Refuse a PCD whose header lacks a line the reader needs, or declares more points
    than the file can hold, before anything is allocated (a 200-byte file declaring 10**12
    points was a MemoryError).

    Parameters
    ----------
    path : pathlib.Path
        An existing ``.pcd`` file.

    Returns
    -------
    None

    Raises
    ------
    MeshFormatError
        If the header lacks one of :data:`PCD_LINES`, gives SIZE, TYPE or COUNT a number
        of values other than its FIELDS', or declares more points than the bytes after
        it hold.

    Examples
    --------
    >>> _ = Path("one.pcd").write_text("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
    ...                                "WIDTH 1\nPOINTS 1\nDATA ascii\n0 0 0\n")
    >>> check_pcd(Path("one.pcd"))
    """
    size = path.stat().st_size
    head: dict = {}
    with open(path, "rb") as f:
        for _ in range(64):  # (the header's lines, DATA last)
            line = f.readline(4096).decode("ascii", "replace").split("#")[0].split()
            if line:
                head[line[0].upper()] = line[1:]
            if not line and f.tell() >= size or "DATA" in head:
                break
        body = size - f.tell()
        sizes = f.read(8)  # binary_compressed: the compressed and the whole sizes
    packed = np.frombuffer(sizes, dtype="<u4") if len(sizes) == 8 else np.zeros(2, int)
    missing = [name for name in PCD_LINES if name not in head]
    if missing:
        raise MeshFormatError(f"{path}: damaged PCD header: no {', '.join(missing)} "
                              f"line{'s' if len(missing) > 1 else ''} (a PCD header names "
                              f"{', '.join(PCD_LINES)})")
    fields = head["FIELDS"]
    uneven = [(name, len(head[name])) for name in ("SIZE", "TYPE", "COUNT")
              if len(head[name]) != len(fields)]
    if uneven:
        name, got = uneven[0]
        raise MeshFormatError(f"{path}: damaged PCD header: FIELDS names {len(fields)} "
                              f"field{'s' if len(fields) != 1 else ''} ({' '.join(fields)}), "
                              f"{name} gives {got} value{'s' if got != 1 else ''} (SIZE, TYPE "
                              "and COUNT give one per field)")
    try:
        n = int(head.get("POINTS", ["0"])[0])
        per = sum(int(a) * int(b) for a, b in zip(head.get("SIZE", []),
                                                   head.get("COUNT", head.get("SIZE", [])))
                  ) if "COUNT" in head else sum(int(a) for a in head.get("SIZE", []))
    except ValueError:
        return  # (pypcd4 names what is wrong)
    kind = (head.get("DATA") or ["ascii"])[0].lower()
    need = {"binary": n * per, "ascii": n}.get(kind, 0)  # (ascii: a byte a point at least)
    if kind == "binary_compressed" and (int(packed[1]) != n * per
                                        or int(packed[0]) > body - 8):
        raise MeshFormatError(f"{path}: damaged PCD file: its header declares {n:,} points "
                              f"({n * per:,} bytes), its compressed block {int(packed[1]):,} "
                              f"bytes packed in {int(packed[0]):,}, and {max(body - 8, 0):,} "
                              "bytes of it follow (truncated?)")
    if n < 0 or need > body:
        raise MeshFormatError(f"{path}: the PCD header declares {n:,} points "
                              f"({need:,} bytes at least) but the file holds {body:,} bytes "
                              "after it")
