"""Binary PLY writing (polygons kept as polygons, colours, a ``label`` per face) and
reading the labels back.

The coloured PLY this package writes carries, per face, its colour
(``red``/``green``/``blue``, uchar) and its superfacet (``label``, int32), so
the segmentation can be read back from the file (:func:`read_ply_labels`) and
shown by MeshLab, Blender, Open3D or trimesh. Vertices are written as doubles
(no precision lost).
"""

from __future__ import annotations

import io
import warnings
from pathlib import Path

import numpy as np

from ..errors import MeshFormatError
from ..inputs.rgb import unit_colors
from .files import number_table
from .headers import ply_names

__all__ = ["ply_bytes", "read_ply_labels", "ply_colors", "ply_scalars", "read_ply_triangles",
           "VertexView", "read_ply_scalars"]

#: Colour properties of a PLY element, tried in this order.
COLOR_PROPERTIES = (("red", "green", "blue"), ("r", "g", "b"),
                    ("diffuse_red", "diffuse_green", "diffuse_blue"))


def ply_scalars(element, name: str, path=None, dtype=np.float64) -> np.ndarray:
    r"""One property of a ``plyfile`` element as an ``(N,)`` array: a list property of one
    value a row (``property list uchar float x``, as some writers declare scalars, and as
    trimesh reads it) taken as that value.

    Parameters
    ----------
    element : plyfile.PlyElement
    name : str
        A property of ``element``.
    path : str or os.PathLike, optional
        The file, for the message.
    dtype : numpy dtype or None, default float64
        None: the file's own (a list's values: their own).

    Returns
    -------
    (N,) ndarray of ``dtype``

    Raises
    ------
    MeshFormatError
        Where ``name`` is a list property with a row of other than one value (a
        coordinate, a normal's or a colour's component is one number).

    Examples
    --------
    >>> from plyfile import PlyData
    >>> head = b"ply\nformat ascii 1.0\nelement vertex 2\nproperty list uchar float x\n"
    >>> vertex = PlyData.read(io.BytesIO(head + b"end_header\n1 0.5\n1 2\n"))["vertex"]
    >>> ply_scalars(vertex, "x")
    array([0.5, 2. ])
    """
    values = np.asarray(element[name])
    if values.dtype != object or not values.size:
        return values if dtype is None else values.astype(dtype, copy=False)
    sizes = np.fromiter((np.size(v) for v in values), dtype=np.int64, count=values.size)
    if sizes.size and (sizes != 1).any():
        row = int(np.flatnonzero(sizes != 1)[0])
        where = f"{path}: " if path is not None else ""
        raise MeshFormatError(f"{where}{element.name} property {name} is a list, of "
                              f"{sizes[row]} values in row {row}: one number is expected")
    return np.array([np.ravel(v)[0] for v in values],
                    dtype=dtype if dtype is not None else np.ravel(values[0]).dtype)


def ply_colors(element) -> np.ndarray | None:
    """(N, 3) float64 in ``[0, 1]``: the RGB of a ``plyfile`` element (vertex or face),
    None where it has none (:data:`COLOR_PROPERTIES`; scaled by
    :func:`~superfacets.inputs.rgb.unit_colors`).

    Raises
    ------
    MeshFormatError
        Where a colour property is a list of other than one value a row
        (:func:`ply_scalars`).
    """

    names = [p.name for p in element.properties]
    for rgb in COLOR_PROPERTIES:
        if all(c in names for c in rgb):
            return unit_colors(np.stack([ply_scalars(element, c, dtype=None) for c in rgb],
                                        axis=1))
    return None


def read_ply_triangles(path: Path, data: bytes):
    """A binary PLY of triangles, read by plyfile's memory map: ``(vertices, faces,
    vertex colours, face colours)``, or None where the file is anything else.

    The common PLY (a ``vertex`` element of scalars, a ``face`` element with one list of
    3 indices and scalars, 8-bit colours if any) is read by ``plyfile`` with
    ``known_list_len``, which maps the file as a fixed-size record per face, instead of
    by trimesh (whose import alone takes about 1.5 s): 6.8M faces in about 0.3 s. Anything
    else (ASCII, polygons, other elements or lists, colours of other types, a file too
    short) is None, for the general readers (:func:`superfacets.read_mesh`), which also
    give the errors.

    Parameters
    ----------
    path : pathlib.Path
        An uncompressed PLY file.
    data : bytes
        Its first bytes (64 KiB, or its whole content): the header is read from them.

    Returns
    -------
    tuple or None
        ``(n, 3) float64`` vertices, ``(m, 3)`` faces (int32, or int64 for unsigned
        32-bit indices), ``(n, 3)`` and ``(m, 3)`` float64 colours in ``[0, 1]`` or None.

    Raises
    ------
    Nothing: a file it cannot read is None.

    Examples
    --------
    >>> _ = trimesh.creation.box().export("box.ply")
    >>> v, f, vc, fc = read_ply_triangles(Path("box.ply"), Path("box.ply").read_bytes())
    >>> v.shape, f.shape, f.dtype.name
    ((8, 3), (12, 3), 'int32')
    """
    elements = _binary_elements(data)
    if elements is None or [name for name, _ in elements] != ["vertex", "face"]:
        return None
    (_, vprops), (_, fprops) = elements
    lists = [name for name, kind in fprops.items() if kind == "list"]
    if ("list" in vprops.values() or not {"x", "y", "z"} <= set(vprops) or len(lists) != 1
            or lists[0] not in ("vertex_indices", "vertex_index")
            or any(props.get(c, "uchar") not in ("uchar", "uint8")
                   for props in (vprops, fprops) for rgb in COLOR_PROPERTIES for c in rgb)):
        return None
    from plyfile import PlyData

    key = lists[0]
    try:
        ply = PlyData.read(str(path), mmap="r", known_list_len={"face": {key: 3}})
        vert, face = ply["vertex"], ply["face"]
        rows = face.data
        if not isinstance(rows, np.memmap) or rows.shape[0] == 0 or vert.count == 0:
            return None
        field, at = rows.dtype.fields[key][:2]  # the count lies just before the indices
        count = np.dtype(face.ply_property(key).len_dtype).newbyteorder(
            field.base.byteorder if field.base.byteorder in "<>" else "=")
        counts = rows.view(np.dtype({"names": ["n"], "formats": [count],
                                     "offsets": [at - count.itemsize],
                                     "itemsize": rows.dtype.itemsize}))["n"]
        if not (counts == 3).all():
            return None
        index = field.base
        wide = index.kind == "u" and index.itemsize >= 4 or index.itemsize > 4
        faces = np.array(face[key], dtype=np.int64 if wide else np.int32)
        vertices = np.stack([np.asarray(vert[c], dtype=np.float64) for c in "xyz"], axis=1)
        return vertices, faces, ply_colors(vert), ply_colors(face)
    except Exception:  # (the general readers name what is wrong)
        return None


#: numpy's type of each PLY scalar type (both spellings)
_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2",
              "int16": "i2", "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4",
              "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8",
              "float64": "f8"}


class ScalarElement:
    """A PLY element of scalar properties read into a structured array: its ``properties``
    (each with a ``name``) and its columns by name, as a ``plyfile`` element gives them."""

    def __init__(self, data: np.ndarray) -> None:
        self.data = data
        self.count = int(data.shape[0])
        self.properties = [type("Property", (), {"name": n})() for n in data.dtype.names]

    def __getitem__(self, name: str) -> np.ndarray:
        return self.data[name]


def read_ply_scalars(data: bytes, path=None) -> dict | None:
    r"""The elements of a PLY whose elements all hold scalar properties (a point cloud),
    each a :class:`ScalarElement`: binary ones viewing ``data`` (no copy, no loop over
    rows), ASCII ones parsed by numpy; None for anything else (list properties, a header
    it cannot read, a body too short, a line it cannot parse), which ``plyfile`` then
    reads and names.

    ``plyfile`` reads such a file from memory (a decompressed or in-memory one) a row and a
    property at a time: 5M binary points took 13.7 s, here 0.6 s; 2M ASCII points 6.7 s.

    Parameters
    ----------
    data : bytes
        The whole file, uncompressed.
    path : str or os.PathLike, optional
        The file's name, for the warning of lines after the rows an ASCII header declares
        (not read).

    Returns
    -------
    dict of str to ScalarElement, or None

    Raises
    ------
    Nothing: a file it cannot read is None.

    Examples
    --------
    >>> head = b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
    >>> body = np.array([1.5, -2.0], dtype="<f4").tobytes()
    >>> read_ply_scalars(head + b"end_header\n" + body)["vertex"]["x"].tolist()
    [1.5, -2.0]
    """
    header = _ply_header(data)
    order = header and {"binary_little_endian": "<", "binary_big_endian": ">",
                        "ascii": "="}.get(header[0])
    if not order or any(count is None or any(t not in _PLY_TYPES for t in props.values())
                        for _, count, props in header[2]):
        return None
    start = header[1]
    layout = [(name, count, [(p, order + _PLY_TYPES[t]) for p, t in props.items()])
              for name, count, props in header[2]]
    if order == "=":
        return _ascii_scalars(data[start:], layout, path)
    out = {}
    for name, count, props in layout:
        if not props:
            return None
        dtype = np.dtype(props)
        if start + count * dtype.itemsize > len(data):
            return None
        out[name] = ScalarElement(np.frombuffer(data, dtype, count, start))
        start += count * dtype.itemsize
    return out


def _ascii_scalars(body: bytes, layout: list, path=None) -> dict | None:
    """:func:`read_ply_scalars` of an ASCII body: each element's lines parsed by numpy."""
    lines = body.split(b"\n")
    out, at = {}, 0
    for name, count, props in layout:
        if not props or at + count > len(lines):
            return None
        try:
            values = number_table([ln.decode("ascii") for ln in lines[at:at + count]])
        except (ValueError, UnicodeDecodeError):
            return None
        if values.shape != (count, len(props)) and count:
            return None
        dtype = np.dtype([(p, "=" + t[1:]) for p, t in props])
        rows = np.empty(count, dtype=dtype)
        for j, (p, t) in enumerate(props):
            column = values[:, j] if count else np.zeros(0)
            if t[1] in "iu" and not np.array_equal(column, np.round(column)):
                return None  # (an integer property holding a fraction: plyfile says so)
            rows[p] = column
        out[name] = ScalarElement(rows)
        at += count
    rest = sum(1 for ln in lines[at:] if ln.strip())
    if rest:  # (a count too small in the header loses the rows after it)
        warnings.warn(f"{path or 'PLY'}: {rest:,} line{'s' if rest > 1 else ''} after the "
                      f"{at:,} rows its header declares, not read (is its element count "
                      "right?)", stacklevel=4)
    return out


def _ply_header(data: bytes):
    """A PLY header: ``(format, offset of the body, [(element, count or None,
    {property: type or 'list'})])``, or None where ``data`` does not start with one. A
    property named twice is kept once (the readers then differ from plyfile: None)."""
    end = data.find(b"end_header", 0, 1 << 16)
    if not data.startswith(b"ply") or end < 0:
        return None
    fmt, elements = "", []
    for line in data[:end].split(b"\n")[1:]:
        parts = line.decode("ascii", "replace").split()
        if not parts or parts[0] in ("comment", "obj_info"):
            continue
        if parts[0] == "format":
            fmt = parts[1] if len(parts) >= 2 else ""
        elif parts[0] == "element" and len(parts) == 3:
            elements.append((parts[1], int(parts[2]) if parts[2].isdigit() else None, {}))
        elif parts[0] == "property" and elements and len(parts) in (3, 5):
            props = elements[-1][2]
            if parts[-1] in props:
                return None
            props[parts[-1]] = "list" if parts[1] == "list" else parts[1]
        else:
            return None
    return fmt, data.find(b"\n", end) + 1, elements


def _binary_elements(data: bytes):
    """The elements of a binary PLY header, ``[(name, {property: type or 'list'})]``,
    or None where the header is not one."""
    header = _ply_header(data)
    if header is None or not header[0].startswith("binary_"):
        return None
    return [(name, props) for name, _, props in header[2]]


#: The vertex property of a point's or vertex's label in the PLY files written here: the
#: ``scalar_`` prefix is what CloudCompare loads as a scalar field (here ``ClusterID``, the
#: name PDAL gives a cluster's label).
LABEL_PROPERTY = "scalar_ClusterID"


def ply_bytes(vertices: np.ndarray, corners: np.ndarray, offsets: np.ndarray, *,
              face_colors: np.ndarray | None = None, labels: np.ndarray | None = None,
              vertex_colors: np.ndarray | None = None,
              vertex_labels: np.ndarray | None = None) -> bytes:
    """A binary little-endian PLY of polygons (any sizes), in face order.

    Parameters
    ----------
    vertices : (n, 3) float ndarray
    corners : (c,) int ndarray
        Vertex indices of every face, face after face.
    offsets : (m + 1,) int ndarray
        Face ``f`` has ``corners[offsets[f]:offsets[f + 1]]``.
    face_colors : (m, 3) uint8 ndarray, optional
    labels : (m,) int ndarray, optional
        Written as the int32 face property ``label``.
    vertex_colors : (n, 3) uint8 ndarray, optional
    vertex_labels : (n,) int ndarray, optional
        Written as the int32 vertex property ``scalar_ClusterID`` (a vertex
        segmentation; CloudCompare's scalar field ``ClusterID``).

    Returns
    -------
    bytes
    """
    v = np.asarray(vertices, dtype="<f8")
    n, m = v.shape[0], offsets.shape[0] - 1
    sizes = np.diff(offsets)
    count = "uchar" if sizes.max() <= 255 else "int"
    head = ["ply", "format binary_little_endian 1.0", "comment made by superfacets",
            f"element vertex {n}", "property double x", "property double y", "property double z"]
    vfields = [("xyz", "<f8", (3,))]
    if vertex_colors is not None:
        head += ["property uchar red", "property uchar green", "property uchar blue"]
        vfields.append(("rgb", "u1", (3,)))
    if vertex_labels is not None:
        head.append(f"property int {LABEL_PROPERTY}")
        vfields.append(("label", "<i4"))
    head += [f"element face {m}", f"property list {count} int vertex_indices"]
    extra = []
    if face_colors is not None:
        head += ["property uchar red", "property uchar green", "property uchar blue"]
        extra.append(("rgb", "u1", (3,)))
    if labels is not None:
        head.append("property int label")
        extra.append(("label", "<i4"))
    head.append("end_header")
    vrec = np.empty(n, dtype=vfields)
    vrec["xyz"] = v
    if vertex_colors is not None:
        vrec["rgb"] = np.asarray(vertex_colors)[:, :3]
    if vertex_labels is not None:
        vrec["label"] = vertex_labels
    out = io.BytesIO()
    out.write(("\n".join(head) + "\n").encode("ascii"))
    out.write(vrec.tobytes())
    # faces: one record layout per polygon size, scattered into face order
    cdt = "u1" if count == "uchar" else "<i4"
    length = np.empty(m, dtype=np.int64)
    for k in np.unique(sizes):
        length[sizes == k] = np.dtype([("k", cdt), ("i", "<i4", (int(k),)), *extra]).itemsize
    start = np.zeros(m + 1, dtype=np.int64)
    np.cumsum(length, out=start[1:])
    buf = np.empty(int(start[-1]), dtype=np.uint8)
    corners = np.asarray(corners)
    for k in np.unique(sizes):
        k = int(k)
        sel = np.flatnonzero(sizes == k)
        rec = np.empty(sel.size, dtype=[("k", cdt), ("i", "<i4", (k,)), *extra])
        rec["k"] = k
        rec["i"] = corners[offsets[sel][:, None] + np.arange(k)]
        if face_colors is not None:
            rec["rgb"] = np.asarray(face_colors)[sel, :3]
        if labels is not None:
            rec["label"] = np.asarray(labels)[sel]
        size = rec.dtype.itemsize
        buf[(start[sel][:, None] + np.arange(size)).ravel()] = rec.view(np.uint8).ravel()
    out.write(buf.tobytes())
    return out.getvalue()


def points_ply_bytes(points: np.ndarray, colors: np.ndarray, labels: np.ndarray) -> bytes:
    """A binary little-endian PLY of coloured points (no faces): ``x y z`` (double),
    ``red green blue`` (uchar) and an int32 ``scalar_ClusterID`` per point (the scalar
    field ``ClusterID`` of CloudCompare), in point order."""
    n = points.shape[0]
    head = ["ply", "format binary_little_endian 1.0", "comment made by superfacets",
            f"element vertex {n}", "property double x", "property double y", "property double z",
            "property uchar red", "property uchar green", "property uchar blue",
            f"property int {LABEL_PROPERTY}", "end_header"]
    rec = np.empty(n, dtype=[("xyz", "<f8", (3,)), ("rgb", "u1", (3,)), ("label", "<i4")])
    rec["xyz"], rec["rgb"], rec["label"] = points, colors, labels
    return ("\n".join(head) + "\n").encode("ascii") + rec.tobytes()


def whole_labels(values, where: str) -> np.ndarray:
    """Labels read from a file as ``int64``: integers, booleans, or floats of whole values
    (CloudCompare saves a scalar field as ``float32``; ``numpy.save`` of a float array).

    Parameters
    ----------
    values : ndarray
        The file's values, any shape (flattened, in order).
    where : str
        The file and field, for the message.

    Returns
    -------
    (m,) int64 ndarray

    Raises
    ------
    MeshFormatError
        If the values are not numbers, or one is not a whole number within ``int64`` (NaN,
        1.5, 1e19, an unsigned 2**63): the first such named, never cast silently.

    Examples
    --------
    >>> whole_labels(np.array([0.0, 3.0, -1.0], dtype=np.float32), "a.ply").tolist()
    [0, 3, -1]
    """
    flat = np.asarray(values).reshape(-1)
    if flat.dtype.kind not in "iubf":
        raise MeshFormatError(f"{where}: labels must be integers; the file holds {flat.dtype}")
    bad = np.zeros(flat.shape, dtype=bool)
    if flat.dtype.kind == "f":
        with np.errstate(invalid="ignore"):
            bad = ~np.isfinite(flat) | (flat != np.round(flat)) | (np.abs(flat) >= 2.0**63)
    elif flat.dtype == np.uint64:
        bad = flat > np.iinfo(np.int64).max
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise MeshFormatError(f"{where}: labels must be whole numbers within int64; label "
                              f"{row} is {flat[row]} ({flat.dtype})")
    return flat.astype(np.int64)


def read_ply_labels(path, data: bytes | None = None) -> np.ndarray:
    """The labels of a PLY: its ``label`` face property (as written by ``--colored-mesh``),
    else its vertex property ``scalar_ClusterID`` (a coloured cloud or vertex
    segmentation, or ``-o OUT.ply`` of a PLY input), else a vertex ``label``.

    Parameters
    ----------
    path : path
    data : bytes, optional
        The (decompressed) content, if already read.

    Returns
    -------
    (m,) int64 ndarray

    Raises
    ------
    MeshFormatError
        If the file is not a PLY with faces holding a ``label`` property, or a label is not
        a whole number (:func:`whole_labels`).
    """
    from plyfile import PlyData, PlyParseError

    try:
        ply = PlyData.read(io.BytesIO(Path(path).read_bytes() if data is None else data))
        names = {e.name: [p.name for p in e.properties] for e in ply.elements}
        if "label" in names.get("face", ()):
            return whole_labels(ply["face"]["label"], f"{path}: face property 'label'")
        for name in (LABEL_PROPERTY, "label"):  # a coloured cloud's or vertices' labels
            if name in names.get("vertex", ()):
                return whole_labels(ply["vertex"][name], f"{path}: vertex property {name!r}")
        raise MeshFormatError(f"{path}: the PLY has no labels: no face property 'label', no "
                              f"vertex property {LABEL_PROPERTY!r} or 'label'")
    except (PlyParseError, KeyError, ValueError, IndexError, TypeError, EOFError) as exc:
        if isinstance(exc, MeshFormatError):
            raise
        raise MeshFormatError(f"{path}: cannot read labels from this PLY: {exc}") from None


class VertexView:
    """Three properties of a memory-mapped PLY vertex element (the position; or the colour,
    scaled to [0, 1] by its type: 8-bit / 255, 16-bit / 65535, floats clipped), indexed
    like an (n, 3) float64 array."""

    def __init__(self, data, fields=None) -> None:
        self.position = fields is None  # (the position: x, y, z in any case, as PDAL's X)
        if fields is None:
            named = ply_names(data.dtype.names, "xyz")
            fields = tuple(named.get(c, c) for c in "xyz")
        self.data, self.fields = data, fields
        self.shape = (data.shape[0], 3)
        kind = data.dtype[fields[0]]
        self.scale = (None if self.position or kind.kind == "f"
                      else 255.0 if kind.itemsize == 1 else 65535.0)

    def table(self, most_bytes: int) -> np.ndarray | VertexView:
        """The three properties as one contiguous (n, 3) float64 array (the same values
        as indexing this view), where it takes at most ``most_bytes``; else this view. A
        face's corners gathered from it are one row each, not three strided reads of the
        mapped file (a tiled run's survey and sorting of 6.8M faces: 3.7 s of gathers)."""
        if 24 * self.shape[0] > most_bytes or not self.position:
            return self
        out = np.empty(self.shape)
        for i, c in enumerate(self.fields):  # (a column at a time: no copy beside it)
            out[:, i] = self.data[c]
        return out

    def __getitem__(self, idx) -> np.ndarray:
        flat = np.asarray(idx).ravel()
        out = np.stack([np.asarray(self.data[c][flat], dtype=np.float64) for c in self.fields],
                       axis=1)
        if not self.position:
            out = out / self.scale if self.scale else np.clip(out, 0.0, 1.0)
        return out.reshape(np.shape(idx) + (3,))
