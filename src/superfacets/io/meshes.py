"""Reading mesh files: OFF, ``.tri``, PLY, OBJ, STL (triangles or polygons).

OFF (the Princeton benchmark's format), the authors' ``.tri`` text format and OBJ are
parsed here (vectorized with :func:`numpy.loadtxt` where the faces are triangles); a
binary PLY of triangles through plyfile's memory map, other PLY and STL through
trimesh's parsers (PLY polygons through plyfile, since trimesh splits them), never
changing the face order. A trailing ``.gz``, ``.xz`` or ``.bz2`` is decompressed.
"""

from __future__ import annotations

import gc
import io
import logging
import threading
import warnings
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..errors import InvalidMeshError, MeshFormatError
from ..inputs.convert import mesh_from_scene
from ..inputs.mesh import Mesh, narrow_faces
from ..inputs.rgb import unit_colors
from .files import read_bytes, read_head, split_suffix, text_lines, user_path
from .headers import check_gltf, check_stl, check_stl_triangles, header_counts, ply_names
from .obj import parse_obj
from .ply import ply_colors, read_ply_triangles

__all__ = ["read_mesh", "MESH_FORMATS", "load_gltf_scene"]

#: Mesh file formats understood by :func:`read_mesh` (before any compression suffix).
MESH_FORMATS = ("off", "tri", "ply", "obj", "stl", "glb", "gltf")


def read_mesh(path, format: str | None = None) -> Mesh:
    """Read a triangle or polygon mesh, or a scene, from a file.

    Parameters
    ----------
    path : str or os.PathLike
        ``.off``, ``.tri``, ``.ply``, ``.obj``, ``.stl``, ``.glb`` or
        ``.gltf``, optionally followed by ``.gz``, ``.xz`` or ``.bz2``.
    format : str, optional
        Force a format (one of :data:`MESH_FORMATS`) instead of the suffix.

    Returns
    -------
    Mesh
        Vertices ``(n, 3) float64`` and faces in file order: ``(m, 3)`` for
        triangles, polygons kept as polygons (OFF, OBJ, PLY). STL: exactly
        coincident vertices are merged, since STL stores none shared. Several
        objects (OBJ ``o`` statements, glTF/GLB scenes) are joined, their
        face ranges in ``mesh.objects`` (:mod:`superfacets.inputs.convert` says in
        which order). Colours, where the file has them, in ``mesh.colors``
        (per vertex: PLY ``red green blue``, COFF, OBJ ``v x y z r g b``,
        glTF vertex colours) and ``mesh.face_colors`` (PLY faces' ``red
        green blue``), scaled to ``[0, 1]``.

    Raises
    ------
    FileNotFoundError, PermissionError, IsADirectoryError
        If the file cannot be opened.
    MeshFormatError
        If the format is unknown, or the file is truncated or malformed, or
        has non-triangle faces.
    InvalidMeshError
        If the content is not a usable mesh (empty, NaN/inf coordinates,
        indices out of range).
    TypeError
        If ``format`` is not a string.

    Examples
    --------
    >>> _ = trimesh.creation.box().export("box.ply")
    >>> m = read_mesh("box.ply")
    >>> m.n_faces, m.n_vertices
    (12, 8)
    """
    path = user_path(path)
    fmt, comp = split_suffix(path)
    if format is not None:
        if not isinstance(format, str):
            raise TypeError(f"format must be a suffix such as 'ply', got {format!r}")
        fmt = format.lower().lstrip(".")
    if fmt not in MESH_FORMATS:
        raise MeshFormatError(
            f"{path}: unknown mesh format {('.' + fmt) if fmt else '(no suffix)'}; "
            f"expected one of {', '.join('.' + f for f in MESH_FORMATS)} "
            "(optionally .gz/.xz/.bz2)")
    counts = header_counts(path)  # a header declaring more than the file holds: refused
    objects, colors, face_colors = (), None, None
    # (the common binary PLY of triangles: its header read and its arrays mapped, by plyfile)
    ply = fmt == "ply" and comp is None and read_ply_triangles(path, read_head(path))
    data = b"" if ply else read_bytes(path, comp, counts=counts)  # (folders refused there)
    if fmt == "off":
        v, f, colors = parse_off(data, path)[:3]
    elif fmt == "tri":
        v, f = _parse_tri(data, path)
    elif fmt == "obj":
        v, f, objects, colors = parse_obj(data, path)
    elif fmt in ("glb", "gltf"):
        return _load_scene(path, fmt, comp, data)
    else:
        v, f, colors, face_colors = ply or _load_trimesh(data, fmt, path)
    try:
        f = narrow_faces(f, len(v))  # (int32 while they fit: the file's arrays are ours)
        return Mesh(v, f, name=path.name, objects=objects, colors=colors,
                    face_colors=face_colors)
    except InvalidMeshError as exc:
        raise InvalidMeshError(f"{path}: {str(exc).removeprefix(path.name + ': ')}") from None


# --------------------------------------------------------------------- text
def _loadtxt(lines: list[str], dtype, what: str, path: Path) -> np.ndarray:
    try:
        return np.loadtxt(lines, dtype=dtype, ndmin=2, comments=None)
    except (ValueError, OverflowError) as exc:
        msg = str(exc).split("; use `usecols`")[0]
        raise MeshFormatError(f"{path}: malformed {what}: {msg}") from None


def _count(token: str, what: str, path: Path) -> int:
    try:
        n = int(token)
    except ValueError:
        raise MeshFormatError(f"{path}: expected the {what} count, got {token!r}") from None
    if n < 0:
        raise MeshFormatError(f"{path}: negative {what} count {n}")
    return n


def parse_off(data: bytes, path: Path, cloud: bool = False):
    """OFF: vertices, faces, the vertices' colours of a COFF file and normals of a NOFF
    file (or None); with ``cloud``, a file of no face is read (its faces an empty (0, 3)
    array), not refused."""
    lines = text_lines(data, path)
    if not lines:
        raise MeshFormatError(f"{path}: empty file")
    head = lines[0].split()
    magic = head[0].upper()
    if not magic.endswith("OFF"):
        raise MeshFormatError(f"{path}: not an OFF file (first word is {head[0]!r}, "
                              "expected 'OFF')")
    counts = head[1:]
    pos = 1
    if not counts:
        if len(lines) < 2:
            raise MeshFormatError(f"{path}: truncated OFF file: no vertex/face counts")
        counts = lines[1].split()
        pos = 2
    if len(counts) < 2:
        raise MeshFormatError(f"{path}: OFF counts line must give vertex and face counts")
    nv = _count(counts[0], "vertex", path)
    nf = _count(counts[1], "face", path)
    vlines = lines[pos:pos + nv]
    flines = lines[pos + nv:pos + nv + nf]
    if len(vlines) < nv:
        raise MeshFormatError(f"{path}: truncated OFF file: expected {nv} vertices, "
                              f"found {len(vlines)}")
    if len(flines) < nf:
        raise MeshFormatError(f"{path}: truncated OFF file: expected {nf} faces, "
                              f"found {len(flines)}")
    v = _loadtxt(vlines, np.float64, "vertex lines", path) if nv else np.zeros((0, 3))
    if v.shape[1] < 3:
        raise MeshFormatError(f"{path}: vertex lines need 3 coordinates, found {v.shape[1]}")
    colors = normals = None
    prefix = magic[:-3]
    if "N" in prefix and v.shape[1] >= 6:
        normals = np.ascontiguousarray(v[:, 3:6])
    if "C" in prefix:  # [ST][C][N]OFF: x y z [nx ny nz] [r g b [a]]
        at = 3 + 3 * ("N" in prefix)
        if v.shape[1] < at + 3:
            raise MeshFormatError(f"{path}: {magic} vertex lines need {at + 3} numbers (the "
                                  f"colour after the coordinates), found {v.shape[1]}")
        colors = _unit(v[:, at:at + 3])
    v = np.ascontiguousarray(v[:, :3])
    if nf == 0:
        if cloud:
            return v, np.zeros((0, 3), dtype=np.int64), colors, normals
        raise InvalidMeshError(f"{path}: empty mesh: no faces")
    f = _off_faces(flines, path)
    _unread_lines(lines[pos + nv + nf:], nf, path)
    return v, f, colors, normals


def _unread_lines(rest: list[str], nf: int, path: Path) -> None:
    """Warn of lines after the faces a header declares (a face count too small loses
    the faces after it; they are not read)."""
    if rest:
        warnings.warn(f"{path}: {len(rest):,} line{'s' if len(rest) > 1 else ''} after the "
                      f"{nf:,} face{'s' if nf != 1 else ''} its header declares, not read "
                      f"(is the face count right?): {rest[0][:60]!r}", stacklevel=3)


def _unit(rgb: np.ndarray) -> np.ndarray:
    """Text colours (floats in [0, 1], or 0..255) in [0, 1]."""

    return unit_colors(rgb)


def _off_faces(flines: list[str], path: Path):
    """Face lines ``k i1 .. ik [colour...]``: an (m, 3) array for triangles (the fast
    path), else a list of polygons."""
    try:
        f = np.loadtxt(flines, dtype=np.int64, ndmin=2, comments=None)
    except (ValueError, OverflowError):
        f = None
    if f is not None and f.shape[1] >= 4 and (f[:, 0] == 3).all():
        return np.ascontiguousarray(f[:, 1:4])
    faces = []
    for i, line in enumerate(flines):
        tok = line.split()
        try:
            n = int(tok[0])
            idx = [int(t) for t in tok[1:1 + n]]
        except ValueError:
            raise MeshFormatError(f"{path}: malformed face line {i}: {line!r}") from None
        if n < 3 or len(idx) < n:
            raise MeshFormatError(f"{path}: face {i} lists {min(n, len(idx))} vertex indices "
                                  f"(3 or more needed): {line!r}")
        if any(abs(x) >= 2**62 for x in idx):
            raise MeshFormatError(f"{path}: face {i} has a vertex index out of range: "
                                  f"{line!r}")
        faces.append(idx)
    if all(len(x) == 3 for x in faces):
        return np.array(faces, dtype=np.int64).reshape(-1, 3)
    return faces


def _parse_tri(data: bytes, path: Path) -> tuple[np.ndarray, np.ndarray]:
    lines = text_lines(data, path)
    if not lines:
        raise MeshFormatError(f"{path}: empty file")
    nv = _count(lines[0].split()[0], "vertex", path)
    vlines = lines[1:1 + nv]
    if len(vlines) < nv:
        raise MeshFormatError(f"{path}: truncated .tri file: expected {nv} vertices, "
                              f"found {len(vlines)}")
    if len(lines) < nv + 2:
        raise MeshFormatError(f"{path}: truncated .tri file: no face count after the vertices")
    nf = _count(lines[1 + nv].split()[0], "face", path)
    flines = lines[2 + nv:2 + nv + nf]
    if len(flines) < nf:
        raise MeshFormatError(f"{path}: truncated .tri file: expected {nf} faces, "
                              f"found {len(flines)}")
    v = _loadtxt(vlines, np.float64, "vertex lines", path) if nv else np.zeros((0, 3))
    if v.shape[1] != 3:
        raise MeshFormatError(f"{path}: vertex lines need 3 coordinates, found {v.shape[1]}")
    if nf == 0:
        raise InvalidMeshError(f"{path}: empty mesh: no faces")
    f = _loadtxt(flines, np.int64, "face lines", path)
    if f.shape[1] != 3:
        raise MeshFormatError(
            f"{path}: only triangle meshes are supported; face lines have {f.shape[1]} indices")
    _unread_lines(lines[2 + nv + nf:], nf, path)
    return v, f


def load_gltf_scene(path: Path, fmt: str, comp: str | None, data: bytes):
    """A glTF/GLB file as a ``trimesh.Scene`` (its node hierarchy checked first:
    :func:`~superfacets.io.headers.check_gltf`).

    Parameters
    ----------
    path : pathlib.Path
    fmt : {'gltf', 'glb'}
    comp : str or None
        The file's compression (``'gz'``, ...); None: read from ``path``, where a ``.gltf``
        finds the buffers beside it.
    data : bytes
        The file's (decompressed) content.

    Returns
    -------
    trimesh.Scene

    Raises
    ------
    MeshFormatError
        If trimesh cannot read it, or its hierarchy is not a forest.

    Examples
    --------
    >>> _ = trimesh.creation.box().export("box.glb")
    >>> data = Path("box.glb").read_bytes()
    >>> len(load_gltf_scene(Path("box.glb"), "glb", None, data).geometry)
    1
    """
    import trimesh

    check_gltf(data, fmt, path)  # (a cycle or a deep nesting: before trimesh walks it)
    try:
        with _quiet_trimesh():
            if comp is None:  # a .gltf may point to buffers beside it: load from the path
                return trimesh.load(str(path), file_type=fmt, force="scene", process=False)
            return trimesh.load(io.BytesIO(data), file_type=fmt, force="scene", process=False)
    except Exception as exc:  # trimesh raises many types for malformed input
        raise MeshFormatError(f"{path}: cannot read {fmt.upper()}: "
                              f"{exc or type(exc).__name__}") from None


def _load_scene(path: Path, fmt: str, comp: str | None, data: bytes) -> Mesh:
    """A glTF/GLB file through trimesh, its objects joined (:mod:`superfacets.inputs.convert`)."""
    scene = load_gltf_scene(path, fmt, comp, data)
    try:
        return mesh_from_scene(scene, name=path.name)
    except InvalidMeshError as exc:
        raise InvalidMeshError(f"{path}: {str(exc).removeprefix(path.name + ': ')}") from None


# ---------------------------------------------------------- via trimesh
@contextmanager
def _quiet_trimesh():
    """Keep trimesh's log (which prints tracebacks of what it could not parse) off stderr
    while this thread reads: a malformed file is reported once, by our own error. (A
    filter that asks the thread, not the logger's level: two threads reading at once and
    restoring the level out of order left trimesh's log silenced for good.)"""
    import trimesh  # noqa: F401 - (its modules' loggers made, each given the filter)

    for name, log in list(logging.root.manager.loggerDict.items()):
        if (name == "trimesh" or name.startswith("trimesh.")) and isinstance(
                log, logging.Logger) and _QUIET not in log.filters:
            log.addFilter(_QUIET)
    depth = getattr(_READING, "depth", 0)
    _READING.depth = depth + 1
    try:
        yield
    finally:
        _READING.depth = depth


#: This thread's readers of trimesh files, nested (:func:`_quiet_trimesh`).
_READING = threading.local()


def _QUIET(record) -> bool:  # noqa: N802 - a logging filter, named as the constant it is
    """trimesh's records pass where no reader of this thread is inside trimesh."""
    return not getattr(_READING, "depth", 0)


def _load_trimesh(data: bytes, fmt: str, path: Path):
    """PLY or STL: vertices, faces, vertex colours, face colours (None where absent)."""
    if fmt == "stl":  # (a truncated STL named so: trimesh reads it as no faces)
        check_stl(data, path)
    with _quiet_trimesh():
        return _load_trimesh_quietly(data, fmt, path)


def _load_trimesh_quietly(data: bytes, fmt: str, path: Path):
    import trimesh

    colors = [None, None]
    try:
        if fmt == "ply":  # trimesh's PLY parser alone: building a Trimesh costs 40x more
            from trimesh.exchange.ply import load_ply

            loaded = load_ply(io.BytesIO(data))
            v, f = loaded.get("vertices"), loaded.get("faces")
            colors = [_rgb(loaded.get(key)) for key in ("vertex_colors", "face_colors")]
        else:
            loaded = trimesh.load(io.BytesIO(data), file_type=fmt, process=False, force="mesh")
            v, f = getattr(loaded, "vertices", None), getattr(loaded, "faces", None)
        v = np.array(np.zeros((0, 3)) if v is None else v, dtype=np.float64)
        f = np.array(np.zeros((0, 3)) if f is None else f, dtype=np.int64)
    except Exception as exc:  # trimesh raises many types for malformed input
        if fmt == "ply" and data.startswith(b"ply"):  # e.g. polygons of mixed sizes
            return _ply_polygons(data, path)
        if fmt == "stl":  # (an ASCII facet of two vertices: "cannot reshape array")
            check_stl_triangles(data, path)
        why = exc or type(exc).__name__
        raise MeshFormatError(f"{path}: cannot read {fmt.upper()}: {why}") from None
    polygons = f.size and (f.ndim != 2 or f.shape[1] != 3)
    if v.size and (v.ndim != 2 or v.shape[1] != 3):
        raise MeshFormatError(f"{path}: vertices must have 3 coordinates")
    # a trimesh object sits in reference cycles (its caches): free its arrays now rather
    # than at some later garbage collection (hundreds of MiB on a large mesh)
    del loaded
    gc.collect()
    declared = _declared_faces(data, fmt)
    if f.size == 0 and not (fmt == "ply" and declared):
        raise InvalidMeshError(f"{path}: empty mesh: no faces")
    if fmt == "ply" and (polygons or (declared is not None and declared != len(f))):
        return _ply_polygons(data, path)  # trimesh split (and reordered) the polygons
    if polygons:
        raise MeshFormatError(f"{path}: faces of {fmt.upper()} must be triangles")
    if fmt == "stl":  # STL stores no shared vertices: merge exact duplicates
        v, inv = _merged_rows(v)
        f = inv[f]
    return v, f, colors[0], colors[1]


def _merged_rows(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(v, axis=0, return_inverse=True)``, the same arrays, by a sort of the
    columns (a third of numpy's time on a large STL): the distinct rows in lexicographic
    order (``-0.0`` as ``0.0``, NaN rows apart) and the one of each row."""
    if v.shape[0] == 0:
        return v, np.zeros(0, dtype=np.int64)
    order = np.lexsort((v[:, 2], v[:, 1], v[:, 0]))
    rows = v[order]
    new = np.empty(rows.shape[0], dtype=bool)
    new[0] = True
    np.any(rows[1:] != rows[:-1], axis=1, out=new[1:])
    inverse = np.empty(rows.shape[0], dtype=np.int64)
    inverse[order] = np.cumsum(new) - 1
    return rows[new], inverse


def _rgb(values) -> np.ndarray | None:
    """trimesh's RGBA colours (uint8, or floats) as RGB in [0, 1]."""
    if values is None:
        return None
    a = np.asarray(values)
    return _unit(a[:, :3]) if a.ndim == 2 and a.shape[1] >= 3 else None


def _ply_polygons(data: bytes, path: Path):
    """A PLY of polygons, read with plyfile: faces of any size, in file order, and the
    colours of the vertices and the faces."""
    from plyfile import PlyData, PlyParseError

    end = data.find(b"end_header")
    declared = sum(int(line.split()[2]) for line in data[:max(end, 0)].split(b"\n")
                   if line.startswith(b"element ") and len(line.split()) == 3
                   and line.split()[2].isdigit())
    if declared > len(data):  # every element takes a byte at least: the counts are wrong
        raise MeshFormatError(f"{path}: the header declares {declared} elements but the file "
                              f"has {len(data)} bytes (truncated or malformed)")
    try:
        ply = PlyData.read(io.BytesIO(data))
        vert = ply["vertex"]
        xyz = ply_names([p.name for p in vert.properties], "xyz")  # (X, Y, Z too)
        v = np.stack([np.asarray(vert[xyz.get(c, c)], dtype=np.float64) for c in "xyz"],
                     axis=1)
        face = ply["face"]
        names = [p.name for p in face.properties]
        key = "vertex_indices" if "vertex_indices" in names else "vertex_index"
        rows = [np.asarray(r, dtype=np.int64) for r in face[key]]
        colors = ply_colors(vert), ply_colors(face)
    except (PlyParseError, KeyError, ValueError, IndexError, TypeError, EOFError,
            MemoryError) as exc:
        raise MeshFormatError(f"{path}: cannot read PLY polygons: {exc}") from None
    if not rows:
        raise InvalidMeshError(f"{path}: empty mesh: no faces")
    return v, rows, colors[0], colors[1]


def _declared_faces(data: bytes, fmt: str) -> int | None:
    """Face count declared by a PLY header."""
    if fmt == "ply":
        end = data.find(b"end_header")
        for line in data[:end].split(b"\n"):
            parts = line.split()
            if len(parts) == 3 and parts[0] == b"element" and parts[1] == b"face":
                return int(parts[2])
        return None
    return None
