"""Wavefront OBJ, read in pieces of a few megabytes.

Each piece's lines are sorted by their statement (``v``, ``f``, ``o``; others skipped)
and its numbers parsed by :func:`numpy.loadtxt`; a piece that numpy cannot read whole
(ragged rows, ``i/t/n`` triplets it cannot simplify, a malformed number) is read line by
line, which names the faulty line. The lines of the whole file are never held at once, so
a large text costs about its arrays, not a Python string per line.
"""

from __future__ import annotations

import re
from operator import itemgetter
from pathlib import Path

import numpy as np

from ..errors import InvalidMeshError, MeshFormatError
from ..inputs.rgb import unit_colors
from .files import number_table, text_chunks

__all__ = ["parse_obj"]

# the statement of a (stripped) line, from its first two characters
_KIND = {"v": 1, "v ": 1, "v\t": 1, "f": 2, "f ": 2, "f\t": 2, "o": 3, "o ": 3, "o\t": 3}
_SLASH = re.compile(r"/\S*")  # the texture and normal indices of "i/t/n"
_TAIL = itemgetter(slice(1, None))  # a line without its statement's letter
_CONTINUED = re.compile(rb"\\\r?\n")  # a backslash that ends a line: it goes on


def parse_obj(data: bytes, path: Path, size: int = 1 << 23, *, cloud: bool = False):
    """``v`` and ``f`` lines, in file order, every object of the file.

    Faces of any size are kept as polygons; ``o`` statements name objects (returned as
    face ranges). Indices are 1-based; a negative index counts back from the last vertex
    defined before its face line (the OBJ rule); ``0`` is an error. In ``f`` lines,
    ``i/t/n`` keeps ``i``. ``v x y z r g b`` lines give vertex colours (where every ``v``
    line has them). Separators may be spaces or tabs; a line ending in ``\\`` goes on
    on the next.

    Parameters
    ----------
    data : bytes
        The file's (decompressed) content.
    path : pathlib.Path
        Named in errors.
    size : int
        Bytes per piece.
    cloud : bool, default False
        A file of ``v`` lines alone is read (a point cloud: :func:`superfacets.read_cloud`),
        not refused; its faces are then an empty (0, 3) array.

    Returns
    -------
    vertices : (n, 3) float64 ndarray
    faces : (m, 3) int64 ndarray, or a list of m lists of 0-based indices (polygons)
    objects : tuple of (str, int, int)
        Each ``o`` statement's name and face range.
    colors : (n, 3) float64 ndarray in [0, 1], or None

    Raises
    ------
    MeshFormatError
        A malformed vertex, colour or face line, or an index 0 or out of range.
    InvalidMeshError
        If the file has no face (unless ``cloud``).

    Examples
    --------
    >>> v, f, objects, colors = parse_obj(b"v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nf 1 2 -1\\n",
    ...                                   Path("t.obj"))
    >>> f.tolist(), objects, colors
    ([[0, 1, 2]], (), None)
    """
    if b"\\\n" in data or b"\\\r\n" in data:  # a line continued on the next (the OBJ rule)
        data = _CONTINUED.sub(b" ", data)
    state = _State()
    for lines in text_chunks(data, path, size):
        state.read(lines, path)
    return state.result(path, cloud)


class _State:
    """What the pieces read so far hold."""

    def __init__(self) -> None:
        self.vertices: list[np.ndarray] = []
        self.colors: list[np.ndarray | None] = []
        self.colour_error: str | None = None
        self.faces: list = []  # (m, k) arrays or lists of lists, 0-based
        self.starts: list[tuple[str, int]] = []  # ("o" statements) object name, first face
        self.nv = self.nf = 0

    def read(self, lines: list[str], path: Path) -> None:
        heads = np.array(lines, dtype="U2")  # (each line's first two characters, in C)
        codes = np.zeros(len(lines), np.int8)
        for head, code in _KIND.items():
            codes[heads == head] = code
        vat, fat = np.flatnonzero(codes == 1), np.flatnonzero(codes == 2)
        before = self.nv + np.cumsum(codes == 1)[fat]  # vertices defined before each face
        for i in np.flatnonzero(codes == 3):
            first = self.nf + int(np.count_nonzero(fat < i))
            self.starts.append((lines[i][1:].strip() or f"object{len(self.starts)}", first))
        if len(vat):
            xyz, rgb, error = _vertices(_rows(lines, vat), self.nv, path)
            self.vertices.append(xyz)
            self.colors.append(rgb)
            self.colour_error = self.colour_error or error
            self.nv += len(xyz)
        if len(fat):
            rows = _rows(lines, fat)
            self.faces.append(_faces(rows, before, self.nf, path))
            self.nf += len(rows)

    def result(self, path: Path, cloud: bool = False):
        if not self.nf and not cloud:
            raise InvalidMeshError(f"{path}: empty mesh: no faces")
        v = np.concatenate(self.vertices) if self.vertices else np.zeros((0, 3))
        colors = None
        if self.colors and all(c is not None for c in self.colors):
            if self.colour_error:
                raise MeshFormatError(self.colour_error)
            colors = unit_colors(np.concatenate(self.colors))
        _check_range(self.faces, self.nv, path)
        objects = []
        if self.starts:  # faces before the first "o" form an unnamed object
            bounds = ([("default", 0)] if self.starts[0][1] > 0 else []) + self.starts
            ends = [b for _, b in bounds[1:]] + [self.nf]
            objects = [(nm, a, b) for (nm, a), b in zip(bounds, ends) if b > a]
        faces = _joined(self.faces) if self.faces else np.zeros((0, 3), dtype=np.int64)
        return v, faces, tuple(objects), colors


def _rows(lines: list[str], at: np.ndarray) -> list[str]:
    """The lines at ``at`` (all of them where they are all)."""
    return lines if len(at) == len(lines) else list(map(lines.__getitem__, at.tolist()))


def _table(rows: list[str], dtype) -> np.ndarray | None:
    """The numbers after each row's statement as one table, or None where numpy cannot
    read them whole (rows of different lengths, a word that is not a number, a bare
    ``f`` or ``v``: numpy skips an empty row)."""
    try:
        table = number_table(list(map(_TAIL, rows)), dtype)
    except (ValueError, OverflowError):
        return None
    return table if table.shape[0] == len(rows) else None


def _vertices(rows: list[str], at: int, path: Path):
    """A piece's ``v`` rows: (n, 3) coordinates, (n, 3) colours or None, and the message
    of a malformed colour (raised only where every ``v`` line of the file has one)."""
    arr = _table(rows, np.float64)
    if arr is not None and arr.shape[1] >= 3:
        return arr[:, :3].copy(), (arr[:, 3:6].copy() if arr.shape[1] >= 6 else None), None
    rows = [r[1:].strip() for r in rows]
    split = [r.split() for r in rows]
    try:
        xyz = np.array([r[:3] for r in split], dtype=np.float64).reshape(-1, 3)
    except ValueError:
        bad = next(i for i, r in enumerate(rows) if not _floats3(r))
        raise MeshFormatError(f"{path}: malformed vertex {at + bad}: 'v {rows[bad]}' (3 "
                              "coordinates expected)") from None
    if not all(len(r) >= 6 for r in split):  # v x y z r g b (MeshLab, Open3D)
        return xyz, None, None
    try:
        return xyz, np.array([r[3:6] for r in split], dtype=np.float64), None
    except ValueError:
        bad = next(i for i, r in enumerate(split) if not _floats3(" ".join(r[3:6])))
        return xyz, np.zeros((len(rows), 3)), (
            f"{path}: malformed vertex colour {at + bad}: 'v {rows[bad]}' (x y z r g b "
            "expected)")


def _faces(rows: list[str], before: np.ndarray, at: int, path: Path):
    """A piece's ``f`` rows as 0-based indices (not yet checked against the vertex count):
    an (m, k) table where numpy reads them whole, else a list of lists."""
    arr = _table(rows, np.int64)
    if arr is None and any("/" in r for r in rows):
        arr = _table([_SLASH.sub("", r) for r in rows], np.int64)  # (a regex: 1 s per 2M)
    if arr is not None and arr.shape[1] >= 3 and (arr != 0).all():
        idx = np.where(arr > 0, arr - 1, before[:, None] + arr)
        if (idx >= 0).all():
            return idx
    return [_face(row[1:].strip(), nv, at + i, path)
            for i, (row, nv) in enumerate(zip(rows, before.tolist()))]


def _face(row: str, nv: int, i: int, path: Path) -> list[int]:
    """One face line's 0-based indices, its faults named."""
    tok = row.split()
    if len(tok) < 3:
        raise MeshFormatError(f"{path}: face {i} has only {len(tok)} vertex indices (3 or "
                              f"more needed): 'f {row}'")
    face = [0] * len(tok)
    for j, t in enumerate(tok):
        try:
            k = int(t.split("/", 1)[0])
        except ValueError:
            raise MeshFormatError(f"{path}: face {i}: malformed vertex index {t!r}") from None
        if k == 0:
            raise MeshFormatError(f"{path}: face {i}: vertex index 0 (OBJ indices start at 1)")
        k = k - 1 if k > 0 else nv + k
        if k < 0 or k >= 2**62:
            raise MeshFormatError(f"{path}: face {i}: vertex index {t} out of range ({nv} "
                                  "vertices defined before it)")
        face[j] = k
    return face


def _check_range(parts: list, nv: int, path: Path) -> None:
    """Every index below the file's vertex count (an index may name a later vertex)."""
    at = 0
    for part in parts:
        if isinstance(part, np.ndarray):
            bad = np.flatnonzero((part >= nv).any(axis=1))
            i, k = (int(bad[0]), int(part[bad[0]].max())) if len(bad) else (None, 0)
        else:
            i = next((j for j, f in enumerate(part) if max(f) >= nv), None)
            k = max(part[i]) if i is not None else 0
        if i is not None:
            raise MeshFormatError(f"{path}: face {at + i}: vertex index {k + 1} out of range "
                                  f"({nv} vertices in the file)")
        at += len(part)


def _joined(parts: list):
    """One (m, 3) array where every face is a triangle, else a list of polygons."""
    if all(isinstance(p, np.ndarray) and p.shape[1] == 3 for p in parts):
        return np.concatenate(parts)
    faces: list[list[int]] = []
    for p in parts:
        faces.extend(p.tolist() if isinstance(p, np.ndarray) else p)
    if all(len(f) == 3 for f in faces):
        return np.array(faces, dtype=np.int64).reshape(-1, 3)
    return faces


def _floats3(row: str) -> bool:
    try:
        return len([float(x) for x in row.split()[:3]]) == 3
    except ValueError:
        return False
