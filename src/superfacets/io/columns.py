"""Points as columns of text (XYZ, PTS, TXT, CSV), read in pieces of a few megabytes.

The header (comment lines before the first point, ``#`` or ``//``; the first of them
that holds words names the columns; else a first line of names alone, ``x``, ``y`` and
``z`` among them, as a CSV's; a surveyor's ``Easting Northing Elevation`` read as those)
is read line by line; fields may be quoted, and a spreadsheet's decimal commas
(semicolon-, tab- or space-separated) are read as decimal points; the points' lines are cut
into pieces parsed by :func:`numpy.loadtxt` (2M lines of three numbers: 0.3 s), a piece
numpy cannot read whole being read line by line, which names the faulty line. The lines
of the whole file are never held at once as Python strings.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import MeshFormatError
from ..inputs.rgb import unit_colors
from .files import number_table, split_suffix, utf8_text
from .ply import COLOR_PROPERTIES

__all__ = ["read_columns"]

_HEADER = re.compile(r"^\s*(#|//)\s*")
#: The first line of an ESRI ASCII grid (``.asc``, a raster), refused as a cloud.
_ESRI_GRID = re.compile(r"\s*ncols\s+\d+\s*\n", re.IGNORECASE)
#: Surveyors' names of the coordinates in a header, read as x, y, z.
SYNONYMS = {"easting": "x", "east": "x", "northing": "y", "north": "y", "elevation": "z",
            "height": "z", "altitude": "z"}
_COMMENT = ("#", "//")


def read_columns(data: bytes, path: Path, size: int = 1 << 23) -> dict:
    """The points (and normals and colours, where the header names ``nx ny nz`` and
    ``r g b`` or ``red green blue``) of a text cloud.

    Parameters
    ----------
    data : bytes
        The file's (decompressed) content, UTF-8.
    path : pathlib.Path
        Named in errors.
    size : int
        Bytes per piece.

    Returns
    -------
    dict
        ``points`` ``(N, 3) float64`` and, where named, ``normals`` and ``colors``
        (``[0, 1]``: 0-255 values divided by 255).

    Raises
    ------
    MeshFormatError
        Binary data, a header naming other columns than the lines have or no x, y, z, a
        line of another width than the first or holding something else than numbers, a
        PTS count line declaring more points than follow.

    Examples
    --------
    >>> read_columns(b"// x y z\\n0 0 1\\n1 0 0\\n", Path("p.xyz"))["points"].tolist()
    [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]
    """
    data = utf8_text(data, path)
    try:
        text = data.decode("utf-8-sig")  # (a spreadsheet's "CSV UTF-8" starts with a BOM)
    except UnicodeDecodeError:
        if b"\0" in data:
            raise MeshFormatError(f"{path}: not a text file (binary data in a text format)") \
                from None
        text = data.decode("cp1252", errors="replace")  # (a header in a Windows code page:
        # the numbers are ASCII in every one)
    if "\r" in text:  # (old Mac and Windows line ends, as the header is read by "\n")
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    if _ESRI_GRID.match(text):  # (its rows of three heights would read as points)
        raise MeshFormatError(f"{path}: an ESRI ASCII grid (ncols, nrows, ...: a raster of "
                              "heights), not a point cloud")
    names, start = _header(text)
    parts: list[np.ndarray] = []
    seen, declared = 0, None
    for lines in _pieces(text, start, size, _decimal_comma(text, start)):
        if not parts and declared is None and lines[0].isdigit() and \
                len(lines[0].split()) == 1:
            declared, lines = int(lines[0]), lines[1:]  # a PTS count line
        if declared is not None:
            lines = lines[:declared - seen]
        if lines:
            arr = _numbers(lines)
            if arr is None:  # (ragged, or not numbers as numpy reads them: line by line)
                arr = _parsed_by_line(lines, path, seen)
            _check_width(arr, parts, seen, path)
            parts.append(arr)
            seen += len(arr)
        if declared is not None and seen >= declared:
            break
    if declared is not None and seen < declared:
        raise MeshFormatError(f"{path}: truncated: the first line declares {declared} "
                              f"points, the file has {seen}")
    if not parts:
        return {"points": np.zeros((0, 3))}
    return _named(np.concatenate(parts), names, path)


def _header(text: str) -> tuple[list[str] | None, int]:
    """The column names (or None) and the offset of the first point's line."""
    names, at = None, 0
    while at < len(text):
        end = text.find("\n", at)
        end = len(text) if end < 0 else end + 1
        ln = text[at:end].strip()
        if ln and not _HEADER.match(ln):
            words = _coordinates([w.strip("\"'").lower() for w in re.split(r"[\s,;]+", ln)
                                  if w])
            if names is None and set("xyz") <= set(words) and not any(map(_is_number,
                                                                           words)):
                names, at = words, end  # a first line of names alone (a CSV's header)
            break
        if ln and names is None:
            words = _coordinates([w.strip("\"'").lower() for w in  # (//X;Y;Z: CloudCompare)
                                  re.split(r"[\s,;]+", _HEADER.sub("", ln).strip()) if w])
            if words and not all(_is_number(w) for w in words):
                names = words
        at = end
    return names, at


#: A number written with a decimal comma (``-12,5``, ``3``, ``1,2e-3``): a field of a
#: semicolon-separated line as a spreadsheet in a European locale writes it.
_COMMA_NUMBER = re.compile(r'\s*"?[+-]?(\d+(,\d*)?|,\d+)([eE][+-]?\d+)?"?\s*')


#: A field of whitespace-separated columns with a decimal comma (``-12,5``, ``1,2e-3``,
#: ``3``), digits on both sides of the comma (``1,`` ends a comma-separated field).
_SPACED_COMMA_NUMBER = re.compile(r'"?[+-]?\d+(,\d+)?([eE][+-]?\d+)?"?')


def _decimal_comma(text: str, start: int) -> bool:
    """Whether the points' lines (from ``start``) write their numbers with a decimal comma,
    as the first point line tells: fields separated by semicolons (``1,5;2,25;0,5``: a CSV
    saved in a European locale) or by tabs or spaces (``1,5\t2,25\t0,5``: a
    spreadsheet's tab-separated text), at least one with a comma, every one such a
    number and none with a point."""
    end = text.find("\n", start)
    line = text[start:len(text) if end < 0 else end].strip()
    if "," not in line:
        return False
    if ";" in line:
        return all(_COMMA_NUMBER.fullmatch(f) for f in line.rstrip(";").split(";"))
    fields = line.split()
    return "." not in line and len(fields) >= 3 and all(
        _SPACED_COMMA_NUMBER.fullmatch(f) for f in fields)


def _coordinates(words: list[str]) -> list[str]:
    """A header's column names, the first of a surveyor's names of a coordinate read as
    ``x``, ``y`` or ``z`` (:data:`SYNONYMS`) where the header names no such column."""
    out = list(words)
    for i, w in enumerate(words):
        axis = SYNONYMS.get(w)
        if axis is not None and axis not in out:
            out[i] = axis
    return out


def _pieces(text: str, start: int, size: int, decimal_comma: bool = False):
    """Lists of the points' lines (stripped, commas and semicolons as spaces, quotes
    around fields left out, comments and blank lines left out), each from about ``size``
    characters; with ``decimal_comma``, commas as decimal points."""
    while start < len(text):
        end = text.find("\n", min(start + size, len(text)) - 1)
        end = len(text) if end < 0 else end + 1
        piece = text[start:end]
        if decimal_comma:
            piece = piece.replace(",", ".")
        if ";" in piece or "," in piece:
            piece = piece.replace(",", " ").replace(";", " ")
        if '"' in piece:  # (a CSV's quoted fields)
            piece = piece.replace('"', " ")
        lines = list(filter(None, map(str.strip, piece.splitlines())))  # (the loop in C)
        if "#" in piece or "//" in piece:
            lines = [ln for ln in lines if not ln.startswith(_COMMENT)]
        if lines:
            yield lines
        start = end


def _check_width(arr: np.ndarray, parts: list, seen: int, path: Path) -> None:
    if parts and arr.shape[1] != parts[0].shape[1]:
        raise MeshFormatError(f"{path}: line {seen + 1} of the points has {arr.shape[1]} "
                              f"columns, the first has {parts[0].shape[1]}")


def _named(arr: np.ndarray, names: list[str] | None, path: Path) -> dict:
    """The points (and normals and colours) from the columns the header names, else the
    first three (and the colours of a scanner's seven columns, ``x y z intensity r g b``:
    :func:`_scanner_columns`)."""
    width = arr.shape[1]
    if names is not None:
        shown = " ".join(names)
        shown = shown if len(shown) <= 80 else shown[:77] + "..."
        if len(names) != width:
            raise MeshFormatError(f"{path}: the header names {len(names)} columns "
                                  f"({shown}), the lines have {width}")
        missing = [c for c in "xyz" if c not in names]
        if missing:
            raise MeshFormatError(f"{path}: unknown columns: the header {shown} "
                                  f"names no {', '.join(missing)} column")
        pts = arr[:, [names.index(c) for c in "xyz"]]
        nrm = None
        if all(c in names for c in ("nx", "ny", "nz")):
            nrm = arr[:, [names.index(c) for c in ("nx", "ny", "nz")]]
        rgb = next((c for c in COLOR_PROPERTIES if all(x in names for x in c)), None)
        col = None if rgb is None else unit_colors(arr[:, [names.index(c) for c in rgb]])
        used = {"x", "y", "z", *(("nx", "ny", "nz") if nrm is not None else ()), *(rgb or ())}
        return {"points": pts, "normals": nrm, "colors": col,
                "fields": _kept(arr, {n: names.index(n) for n in names if n not in used})}
    if width < 3:
        raise MeshFormatError(f"{path}: point lines need 3 columns (x y z), found {width}")
    if width == 7 and _scanner_columns(arr, split_suffix(Path(path))[0]):
        return {"points": arr[:, :3], "colors": arr[:, 4:7] / 255.0,
                "fields": _kept(arr, {"intensity": 3})}
    return {"points": arr[:, :3],
            "fields": _kept(arr, {f"column{j + 1}": j for j in range(3, width)})}


def _kept(arr: np.ndarray, columns: dict) -> dict | None:
    """The columns not read as positions, normals or colours (name: column), kept for a new
    file of the points (:attr:`superfacets.PointCloud.fields`); None where there are none."""
    return {name: arr[:, j].copy() for name, j in columns.items()} or None


def _scanner_columns(arr: np.ndarray, fmt: str) -> bool:
    """Whether seven headerless columns are a terrestrial scanner's ``x y z intensity r g
    b`` (Leica's PTS, Semantic3D's ``.txt``): the last three whole numbers in 0..255; in a
    file other than ``.pts`` also the fourth whole and somewhere outside 0..255 (a
    scanner's signed intensity, -2048..2047), so that ``x y z r g b label`` is not read as
    colours (g, b, label)."""
    rgb = arr[:, 4:7]
    if not ((rgb >= 0) & (rgb <= 255) & (rgb == np.floor(rgb))).all():
        return False
    if fmt == "pts":
        return True
    intensity = arr[:, 3]
    return bool((intensity == np.floor(intensity)).all()
                and ((intensity < 0) | (intensity > 255)).any())


def _numbers(body: list) -> np.ndarray | None:
    """The lines' numbers as an (n, width) float64 array, parsed by numpy (about 0.5 s per
    million lines), or None where a line is ragged or holds something else."""
    try:
        return number_table(body)
    except ValueError:
        return None


def _parsed_by_line(body: list, path: Path, seen: int) -> np.ndarray:
    """The lines' numbers, split line by line; a line with another number of columns than
    the first, or holding something other than numbers, named (:class:`MeshFormatError`)."""
    rows = [re.split(r"[\s,;]+", b.strip()) for b in body]
    width = len(rows[0])
    for i, r in enumerate(rows):
        if len(r) != width:
            raise MeshFormatError(f"{path}: line {seen + i + 1} of the points has {len(r)} "
                                  f"columns, the first has {width}")
    try:
        return np.array(rows, dtype=np.float64)
    except ValueError:
        bad = next(i for i, r in enumerate(rows) if not all(_is_number(w) for w in r))
        raise MeshFormatError(f"{path}: point line {seen + bad + 1} is not numbers: "
                              f"{body[bad].strip()[:80]!r}") from None


def _is_number(word: str) -> bool:
    try:
        float(word)
        return True
    except ValueError:
        return False
