"""What a file's header declares, read without its data: element counts, and whether the
data after the header can hold them.

Used before a file is read: a header that declares more than the file holds is damage
(refused in one line, whatever the header claims), and the counts size the run's memory
before anything large is read (:func:`superfacets._runtime.memory.check_memory`).
"""

from __future__ import annotations

from pathlib import Path

from ..errors import MeshFormatError

__all__ = ["header_counts"]

_SIZE = {"char": 1, "uchar": 1, "int8": 1, "uint8": 1, "short": 2, "ushort": 2,
         "int16": 2, "uint16": 2, "int": 4, "uint": 4, "int32": 4, "uint32": 4,
         "float": 4, "float32": 4, "double": 8, "float64": 8}
_HEAD = 1 << 16  # a header longer than this is not one this package writes or reads


def header_counts(path) -> dict | None:
    """``{"faces": m, "vertices": n}`` or ``{"points": n}`` as an uncompressed PLY, OFF or
    ``.tri`` file's header declares them; None for other formats and compressed files.

    Raises
    ------
    MeshFormatError
        If the data after a PLY header cannot hold what it declares (each element at
        its smallest: its scalar properties, a face's list of three indices; two
        characters a number in ASCII), or an OFF header's counts are not integers.

    Examples
    --------
    >>> import trimesh
    >>> _ = trimesh.creation.box().export("box.ply")
    >>> header_counts("box.ply")
    {'vertices': 8, 'faces': 12}
    """
    p = Path(path)
    suffix = p.suffix.lower().lstrip(".")
    if suffix not in ("ply", "off", "tri") or not p.is_file():
        return None
    with open(p, "rb") as f:
        head = f.read(_HEAD)
    size = p.stat().st_size
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


def _ply(p: Path, head: bytes, size: int) -> dict | None:
    end = head.find(b"end_header")
    if not head.startswith(b"ply") or end < 0:
        return None
    body = head[:end].decode("ascii", "replace").splitlines()
    start = end + len(b"end_header") + (2 if head[end + 10:end + 12] == b"\r\n" else 1)
    ascii_ = any(line.split()[:2] == ["format", "ascii"] for line in body)
    elements: list[list] = []  # [name, count, smallest record]
    for line in body:
        w = line.split()
        if len(w) >= 3 and w[0] == "element":
            try:
                elements.append([w[1], int(w[2]), 0])
            except ValueError:
                return None
        elif len(w) >= 3 and w[0] == "property" and elements:
            if w[1] == "list" and len(w) >= 5:
                corners = 3 if elements[-1][0] == "face" else 0
                elements[-1][2] += (2 * (1 + corners) if ascii_ else
                                    _SIZE.get(w[2], 1) + corners * _SIZE.get(w[3], 1))
            else:
                elements[-1][2] += 2 if ascii_ else _SIZE.get(w[1], 1)
    need = sum(count * smallest for _, count, smallest in elements)
    if need > size - start:
        declared = ", ".join(f"{count:,} {name}" for name, count, _ in elements)
        raise MeshFormatError(f"{p}: damaged PLY file: its header declares {declared} "
                              f"({need:,} bytes at the least), and {size - start:,} bytes "
                              "follow it (truncated?)")
    counts = {("vertices" if name == "vertex" else "faces" if name == "face" else name): c
              for name, c, _ in elements}
    if counts.get("faces", 0) == 0 and "vertices" in counts:
        counts = {"points": counts["vertices"]}
    return counts
