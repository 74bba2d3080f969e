"""Mesh files: reading (OFF, ``.tri``, PLY, OBJ, STL) and writing, coloured PLY.

OFF (the Princeton benchmark's format) and the authors' ``.tri`` text format
are parsed here (vectorized with :func:`numpy.loadtxt`); PLY, OBJ and STL go
through trimesh with ``process=False`` so the face order never changes. A
trailing ``.gz``, ``.xz`` or ``.bz2`` is decompressed transparently; every
write is atomic (:func:`superfacets.io.files.atomic_write`).
"""

from __future__ import annotations

import gc
import io
from pathlib import Path

import numpy as np

from ..errors import InvalidMeshError, MeshFormatError
from ..mesh import Mesh, as_mesh
from .files import Outputs, read_bytes, save, split_suffix, text_lines

__all__ = ["read_mesh", "write_mesh", "write_colored_mesh", "MESH_FORMATS"]

#: Mesh file formats understood by :func:`read_mesh` (before any compression suffix).
MESH_FORMATS = ("off", "tri", "ply", "obj", "stl")


def read_mesh(path, format: str | None = None) -> Mesh:
    """Read a triangle mesh from a file.

    Parameters
    ----------
    path : str or os.PathLike
        ``.off``, ``.tri``, ``.ply``, ``.obj`` or ``.stl``, optionally
        followed by ``.gz``, ``.xz`` or ``.bz2``.
    format : str, optional
        Force a format (one of :data:`MESH_FORMATS`) instead of the suffix.

    Returns
    -------
    Mesh
        Vertices ``(n, 3) float64`` and faces ``(m, 3) int64`` in file order
        (STL: exactly coincident vertices are merged, since STL stores none
        shared; the face order is kept).

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
    """
    path = Path(path)
    fmt, comp = split_suffix(path)
    if format is not None:
        fmt = format.lower().lstrip(".")
    if fmt not in MESH_FORMATS:
        raise MeshFormatError(
            f"{path}: unknown mesh format {('.' + fmt) if fmt else '(no suffix)'}; "
            f"expected one of {', '.join('.' + f for f in MESH_FORMATS)} "
            "(optionally .gz/.xz/.bz2)"
        )
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a directory")
    data = read_bytes(path, comp)
    if fmt == "off":
        v, f = _parse_off(data, path)
    elif fmt == "tri":
        v, f = _parse_tri(data, path)
    elif fmt == "obj":
        v, f = _parse_obj(data, path)
    else:
        v, f = _load_trimesh(data, fmt, path)
    try:
        return Mesh(v, f, name=path.name)
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


def _parse_off(data: bytes, path: Path) -> tuple[np.ndarray, np.ndarray]:
    lines = text_lines(data, path)
    if not lines:
        raise MeshFormatError(f"{path}: empty file")
    head = lines[0].split()
    magic = head[0].upper()
    if not magic.endswith("OFF"):
        raise MeshFormatError(f"{path}: not an OFF file (first word is {head[0]!r}, expected 'OFF')")
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
        raise MeshFormatError(f"{path}: truncated OFF file: expected {nv} vertices, found {len(vlines)}")
    if len(flines) < nf:
        raise MeshFormatError(f"{path}: truncated OFF file: expected {nf} faces, found {len(flines)}")
    v = _loadtxt(vlines, np.float64, "vertex lines", path) if nv else np.zeros((0, 3))
    if v.shape[1] < 3:
        raise MeshFormatError(f"{path}: vertex lines need 3 coordinates, found {v.shape[1]}")
    v = np.ascontiguousarray(v[:, :3])
    if nf == 0:
        raise InvalidMeshError(f"{path}: empty mesh: no faces")
    f = _off_faces(flines, path)
    return v, f


def _off_faces(flines: list[str], path: Path) -> np.ndarray:
    try:
        f = np.loadtxt(flines, dtype=np.int64, ndmin=2, comments=None)
    except (ValueError, OverflowError):
        f = None
    if f is None or f.shape[1] < 4 or not (f[:, 0] == 3).all():
        # error path only: find the first offending line
        for i, line in enumerate(flines):
            tok = line.split()
            try:
                n = int(tok[0])
                idx = [int(t) for t in tok[1:1 + n]]
            except ValueError:
                raise MeshFormatError(f"{path}: malformed face line {i}: {line!r}") from None
            if any(abs(x) >= 2**62 for x in idx):
                raise MeshFormatError(f"{path}: face {i} has a vertex index out of range: "
                                      f"{line!r}")
            if n != 3:
                raise MeshFormatError(
                    f"{path}: only triangle meshes are supported; face {i} has {n} vertices")
            if len(idx) < 3:
                raise MeshFormatError(f"{path}: face {i} lists fewer than 3 vertex indices: {line!r}")
        # every line is a triangle but with varying trailing colour fields
        return np.array([[int(t) for t in ln.split()[1:4]] for ln in flines], dtype=np.int64)
    return np.ascontiguousarray(f[:, 1:4])


def _parse_tri(data: bytes, path: Path) -> tuple[np.ndarray, np.ndarray]:
    lines = text_lines(data, path)
    if not lines:
        raise MeshFormatError(f"{path}: empty file")
    nv = _count(lines[0].split()[0], "vertex", path)
    vlines = lines[1:1 + nv]
    if len(vlines) < nv:
        raise MeshFormatError(f"{path}: truncated .tri file: expected {nv} vertices, found {len(vlines)}")
    if len(lines) < nv + 2:
        raise MeshFormatError(f"{path}: truncated .tri file: no face count after the vertices")
    nf = _count(lines[1 + nv].split()[0], "face", path)
    flines = lines[2 + nv:2 + nv + nf]
    if len(flines) < nf:
        raise MeshFormatError(f"{path}: truncated .tri file: expected {nf} faces, found {len(flines)}")
    v = _loadtxt(vlines, np.float64, "vertex lines", path) if nv else np.zeros((0, 3))
    if v.shape[1] != 3:
        raise MeshFormatError(f"{path}: vertex lines need 3 coordinates, found {v.shape[1]}")
    if nf == 0:
        raise InvalidMeshError(f"{path}: empty mesh: no faces")
    f = _loadtxt(flines, np.int64, "face lines", path)
    if f.shape[1] != 3:
        raise MeshFormatError(
            f"{path}: only triangle meshes are supported; face lines have {f.shape[1]} indices")
    return v, f


def _parse_obj(data: bytes, path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Wavefront OBJ: ``v`` and ``f`` lines, in file order, every object of the file.

    Indices are 1-based; a negative index counts back from the last vertex
    defined before its face line (the OBJ rule); ``0`` is an error. In ``f``
    lines, ``i/t/n`` keeps ``i``. Separators may be spaces or tabs. Other
    statements (``vt``, ``vn``, ``g``, ``o``, ``usemtl``, ...) are skipped.
    """
    vrows: list[str] = []
    frows: list[str] = []
    before: list[int] = []  # vertices defined before each face line
    for ln in text_lines(data, path):
        key, *rest = ln.split(None, 1)  # spaces or tabs
        rest = rest[0] if rest else ""
        if key == "v":
            vrows.append(rest)
        elif key == "f":
            frows.append(rest)
            before.append(len(vrows))
    if not frows:
        raise InvalidMeshError(f"{path}: empty mesh: no faces")
    try:
        v = np.array([r.split()[:3] for r in vrows], dtype=np.float64).reshape(-1, 3)
    except ValueError:
        bad = next(i for i, r in enumerate(vrows) if not _floats3(r))
        raise MeshFormatError(f"{path}: malformed vertex {bad}: 'v {vrows[bad]}' (3 "
                              "coordinates expected)") from None
    faces = np.empty((len(frows), 3), dtype=np.int64)
    for i, (row, nv) in enumerate(zip(frows, before)):
        tok = row.split()
        if len(tok) != 3:
            what = (f"{len(tok)} vertices (only triangle meshes are supported)" if len(tok) > 3
                    else f"only {len(tok)} vertex indices")
            raise MeshFormatError(f"{path}: face {i} has {what}: 'f {row}'")
        for j, t in enumerate(tok):
            try:
                k = int(t.split("/", 1)[0])
            except ValueError:
                raise MeshFormatError(f"{path}: face {i}: malformed vertex index {t!r}") \
                    from None
            if k == 0:
                raise MeshFormatError(f"{path}: face {i}: vertex index 0 (OBJ indices start "
                                      "at 1)")
            k = k - 1 if k > 0 else nv + k
            if not 0 <= k < len(vrows):
                raise MeshFormatError(f"{path}: face {i}: vertex index {t} out of range "
                                      f"({nv} vertices defined before it, {len(vrows)} in all)")
            faces[i, j] = k
    return v, faces


def _floats3(row: str) -> bool:
    try:
        return len([float(x) for x in row.split()[:3]]) == 3
    except ValueError:
        return False


# ---------------------------------------------------------- via trimesh
def _load_trimesh(data: bytes, fmt: str, path: Path) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    kwargs = {}
    try:
        if fmt == "ply":  # trimesh's PLY parser alone: building a Trimesh costs 40x more
            from trimesh.exchange.ply import load_ply

            loaded = load_ply(io.BytesIO(data))
            v, f = loaded.get("vertices"), loaded.get("faces")
        else:
            loaded = trimesh.load(io.BytesIO(data), file_type=fmt, process=False,
                                  validate=False, force="mesh", **kwargs)
            v, f = getattr(loaded, "vertices", None), getattr(loaded, "faces", None)
        v = np.array(np.zeros((0, 3)) if v is None else v, dtype=np.float64)
        f = np.array(np.zeros((0, 3)) if f is None else f, dtype=np.int64)
    except Exception as exc:  # trimesh raises many types for malformed input
        raise MeshFormatError(f"{path}: cannot read {fmt.upper()}: {exc or type(exc).__name__}") from None
    if f.size and (f.ndim != 2 or f.shape[1] != 3):
        raise MeshFormatError(f"{path}: only triangle meshes are supported; faces have "
                              f"{f.shape[1] if f.ndim == 2 else 'varying numbers of'} vertices")
    if v.size and (v.ndim != 2 or v.shape[1] != 3):
        raise MeshFormatError(f"{path}: vertices must have 3 coordinates")
    # a trimesh object sits in reference cycles (its caches): free its arrays now rather
    # than at some later garbage collection (hundreds of MiB on a large mesh)
    del loaded
    gc.collect()
    if f.size == 0:
        raise InvalidMeshError(f"{path}: empty mesh: no faces")
    declared = _declared_faces(data, fmt)
    if declared is not None and declared != f.shape[0]:
        raise MeshFormatError(
            f"{path}: only triangle meshes are supported; the file declares {declared} faces "
            f"but they make {f.shape[0]} triangles (polygons were split)")
    if fmt == "stl":  # STL stores no shared vertices: merge exact duplicates
        v, inv = np.unique(v, axis=0, return_inverse=True)
        f = inv.reshape(-1)[f]
    return v, f


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


# ------------------------------------------------------------------ writes
def write_mesh(path, mesh, face_colors: np.ndarray | None = None, *,
               outputs: Outputs | None = None) -> Path:
    """Write a mesh: ``.off`` and ``.tri`` here, ``.ply``/``.obj``/``.stl`` via trimesh.

    Parameters
    ----------
    path : str or os.PathLike
        Optionally ending in ``.gz``/``.xz``/``.bz2``.
    mesh : Mesh or (vertices, faces)
    face_colors : (m, 3) or (m, 4) uint8 ndarray, optional
        Per-face colours (PLY only).
    outputs : Outputs, optional
        Stage the file there (all or nothing with the others).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    MeshFormatError
        If the format is unknown, or colours are asked of a format other
        than PLY.
    """
    mesh = as_mesh(mesh)
    path = Path(path)
    fmt, _ = split_suffix(path)
    if fmt not in MESH_FORMATS:
        raise MeshFormatError(f"{path}: unknown mesh format .{fmt}")
    if face_colors is not None and fmt != "ply":
        raise MeshFormatError(f"{path}: per-face colours need the .ply format")
    v, f = mesh.vertices, mesh.faces
    if fmt == "off":
        head = f"OFF\n{len(v)} {len(f)} 0\n"
        body = _rows(v, "%.17g") + _rows(np.c_[np.full(len(f), 3), f], "%d")
        return save(path, (head + body).encode("ascii"), outputs)
    if fmt == "tri":
        body = f"{len(v)}\n" + _rows(v, "%.17g") + f"{len(f)}\n" + _rows(f, "%d")
        return save(path, body.encode("ascii"), outputs)
    import trimesh

    tm = trimesh.Trimesh(vertices=v, faces=f, process=False, validate=False)
    if face_colors is not None:
        tm.visual.face_colors = face_colors
    kwargs = {"encoding": "binary"} if fmt == "ply" else {}
    data = tm.export(file_type=fmt, **kwargs)
    return save(path, data.encode("utf-8") if isinstance(data, str) else data, outputs)


def _rows(a: np.ndarray, fmt: str) -> str:
    buf = io.StringIO()
    np.savetxt(buf, a, fmt=fmt)
    return buf.getvalue()


def write_colored_mesh(path, mesh, labels, *, outputs: Outputs | None = None) -> Path:
    """Write a binary PLY with one colour per face, one colour per superfacet.

    Adjacent superfacets always get clearly different colours (a greedy
    colouring of the superfacet adjacency graph, see
    :func:`superfacets.colors.superfacet_colors`). Opens in MeshLab or Blender.

    Parameters
    ----------
    path : str or os.PathLike
        Should end in ``.ply``.
    mesh : Mesh or (vertices, faces)
    labels : (m,) int ndarray

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ParameterError
        If ``labels`` is not one integer per face.
    """
    from ..colors import face_colors

    mesh = as_mesh(mesh)
    return write_mesh(path, mesh, face_colors=face_colors(mesh, labels), outputs=outputs)
