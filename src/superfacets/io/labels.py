"""Label files: ``.seg``, one integer per element per line, in element order.

Optional ``#`` header lines come first; a ``.gz``/``.xz``/``.bz2`` suffix
compresses. These are the Princeton benchmark's ground-truth files.
"""

from __future__ import annotations

import unicodedata
from pathlib import Path
from typing import Iterable

import numpy as np

from .._runtime import extras
from ..elements.labels import check_labels
from ..errors import MeshFormatError, ParameterError
from .clouds import check_laz
from .files import Outputs, read_bytes, save, split_suffix, text_lines, user_path
from .ply import read_ply_labels, whole_labels
from .records import LABEL_FIELD
from .tetmeshes import VOLUME_FORMATS, volume_field

__all__ = ["read_labels", "write_labels", "write_segindices", "read_field", "class_names",
           "ASPRS_CLASSES"]


_BLOCK = 1 << 20  # labels formatted at a time


def write_labels(path, labels, header: dict | Iterable[str] | None = None, *,
                 outputs: Outputs | None = None) -> Path:
    """Write a ``.seg`` label file: one integer per face per line, face order (a ``.npy``
    path: the labels as a NumPy ``int64`` array, as learning pipelines load them).

    Parameters
    ----------
    path : str or os.PathLike
    labels : (m,) int ndarray
    header : dict or iterable of str, optional
        Written first as ``# key: value`` (or ``# line``) lines; readers of
        this package skip them. Leave it out for strict benchmark files. (Not in a
        ``.npy``, which holds the array alone.)
    outputs : Outputs, optional
        Stage the file there (written with the others, all or nothing)
        instead of writing it now. ``path`` ``-`` is standard output.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ParameterError
        If ``labels`` is not a 1-D integer array, or ``path`` is a ``.label`` or ``.bin``
        (SemanticKITTI's and nuScenes' binary formats, which :func:`read_labels` reads as
        such: text there would be read back wrong).

    Examples
    --------
    >>> import tempfile
    >>> folder = tempfile.mkdtemp()
    >>> write_labels(f"{folder}/labels.seg", [0, 1, 1]).read_text().split()
    ['0', '1', '1']
    """
    binary = {"label": "a .label file is SemanticKITTI's binary classes",
              "bin": "a .bin of labels is nuScenes' binary classes (_lidarseg.bin)"}
    if str(path) != "-" and split_suffix(Path(path))[0] in binary:
        raise ParameterError(f"{path}: {binary[split_suffix(Path(path))[0]]}, read back as "
                             "such; name the labels .seg")
    labels = check_labels(labels, None)
    if str(path) != "-" and split_suffix(Path(path))[0] == "npy":
        import io

        buf = io.BytesIO()
        np.save(buf, labels.astype(np.int64), allow_pickle=False)
        return save(path, buf.getvalue(), outputs)
    head = ""
    if header:
        items = header.items() if isinstance(header, dict) else ((None, h) for h in header)
        head = "".join(f"# {_one_line(k)}: {_one_line(v)}\n" if k is not None else
                       f"# {_one_line(v)}\n" for k, v in items)
    # formatted in blocks: the text of 10M labels as one list of str held 1.3 GB
    body = b"".join(integer_text(labels[s:s + _BLOCK], b"\n")
                    for s in range(0, labels.shape[0], _BLOCK))
    return save(path, head.encode("utf-8") + body, outputs)


def integer_text(values: np.ndarray, end: bytes) -> bytes:
    """The decimal text of integers, each followed by the one byte ``end``: what
    ``"".join(f"{v}{end}" ...)`` gives: where the values span few integers (labels), each
    one's text made once and gathered; else its digits written by numpy, one pass per
    digit (6.8M labels in 150 values: 2.3 s as Python text, 0.43 s by digits, 0.33 s).

    Examples
    --------
    >>> integer_text(np.array([0, 7, -12, 305]), b"\\n")
    b'0\\n7\\n-12\\n305\\n'
    """
    v = np.asarray(values, dtype=np.int64)
    if v.size == 0:
        return b""
    lo, hi = int(v.min()), int(v.max())
    if hi - lo < v.size // 16:  # few values (labels): each one's text made once, gathered
        texts = [f"{x}".encode() + end for x in range(lo, hi + 1)]
        size = np.fromiter(map(len, texts), np.int64, len(texts))
        width = int(size.max())
        rows = np.frombuffer(b"".join(t.ljust(width, b"\0") for t in texts),
                             np.uint8).reshape(-1, width)
        at = v - lo
        return rows[at][(np.arange(width) < size[:, None])[at]].tobytes()
    neg = v < 0
    a = np.abs(v).astype(np.uint64)  # (-2**63 too)
    kind = np.uint32 if int(a.max()) < 2**32 else np.uint64  # (32-bit division is faster)
    a, ten = a.astype(kind), kind(10)
    width = np.ones(v.shape, dtype=np.int64)
    for power in range(1, 20):
        more = a >= kind(10**power) if 10**power < 2**32 or kind is np.uint64 else None
        if more is None or not more.any():
            break
        width += more
    cols = int(width.max()) + int(neg.any()) + 1  # right-aligned in rows, then compacted
    text = np.empty((v.shape[0], cols), dtype=np.uint8)
    text[:, -1] = end[0]
    for d in range(int(width.max())):
        text[:, -2 - d] = (a % ten).astype(np.uint8) + ord("0")
        a //= ten
    rows = np.flatnonzero(neg)
    text[rows, cols - 2 - width[rows]] = ord("-")
    out = text[np.arange(cols) >= (cols - 1 - width - neg)[:, None]]
    return out.tobytes()


def _one_line(value) -> str:
    """A header value on one line: line breaks and other control characters (a glTF node
    named with a newline) become spaces, so a name never adds a line to the file."""
    return "".join(" " if unicodedata.category(c)[0] == "C" else c for c in str(value))


def write_segindices(path, labels, params: dict | None = None, scene_id: str = "", *,
                     outputs: Outputs | None = None) -> Path:
    """Write labels as the ScanNet Segmentator's JSON: ``{"params", "sceneId", "segIndices"}``.

    Parameters
    ----------
    path : str or os.PathLike
        ``.json`` (``-``: standard output).
    labels : (n,) int ndarray
        One label per vertex or point (-1 for points that are not elements).
    params : dict, optional
        The run's parameters, stored under ``"params"``.
    scene_id : str, optional
        Stored as ``"sceneId"`` (the input's name without suffix).
    outputs : Outputs, optional
        Stage the file there (all or nothing).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ParameterError
        If ``labels`` is not a 1-D integer array, or ``params`` not a dict.

    Examples
    --------
    >>> import json, tempfile
    >>> folder = tempfile.mkdtemp()
    >>> p = write_segindices(f"{folder}/scene.segs.json", [0, 0, 1], {"n_segments": 2},
    ...                      "scene")
    >>> d = json.loads(p.read_text())
    >>> d["sceneId"], d["segIndices"]
    ('scene', [0, 0, 1])
    """
    import json

    labels = check_labels(labels, None)
    if params is not None and not isinstance(params, dict):
        raise ParameterError(f"params must be a dict, got {type(params).__name__}")
    clean = {k: (v.item() if hasattr(v, "item") else v) for k, v in (params or {}).items()}
    head = json.dumps({"params": clean, "sceneId": scene_id, "segIndices": []},
                      separators=(",", ":"), ensure_ascii=False)[:-2]
    # the labels formatted in blocks, as json.dumps writes a list of ints
    body = b"".join(integer_text(labels[s:s + _BLOCK], b",")
                    for s in range(0, labels.shape[0], _BLOCK))[:-1]
    return save(path, head.encode("utf-8") + body + b"]}\n", outputs)


def read_labels(path, n_faces: int | None = None) -> np.ndarray:
    """Read labels: a ``.seg`` file (``#`` lines skipped; may be compressed), the
    labels of a PLY written by this package (the ``label`` face property of a
    coloured mesh, else the vertex property ``scalar_ClusterID``), the
    ``ClusterID`` dimension of a LAS/LAZ written by ``segment -o OUT.laz``, the
    ``segIndices`` of a ScanNet-style ``.json``, the classes of a SemanticKITTI
    ``.label`` file (uint32 a point: its lower 16 bits, the instance above left out),
    those of a nuScenes ``*_lidarseg.bin`` file (uint8 a point), or a ``.npy`` array of
    labels (a learning pipeline's; of NPY records, their ``ClusterID`` field, as ``segment
    -o OUT.npy`` writes them), or a ``.npz`` archive of one such array or of one named
    ``labels`` (``segment --graph OUT.npz`` writes the labels there).

    Parameters
    ----------
    path : str or os.PathLike
    n_faces : int, optional
        If given, the number of labels must equal it.

    Returns
    -------
    labels : (m,) int64 ndarray
        The labels as stored (not relabelled).

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    MeshFormatError
        If a line is not one integer, a ``.bin`` is not named ``*_lidarseg.bin``, or the
        count differs from ``n_faces``.

    Examples
    --------
    >>> import tempfile
    >>> path = write_labels(f"{tempfile.mkdtemp()}/run.seg", [0, 0, 1, 2])
    >>> read_labels(path, n_faces=4).tolist()
    [0, 0, 1, 2]
    """
    path = user_path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    fmt, comp = split_suffix(path)
    if fmt in ("las", "laz", "pcd"):  # a scan written by segment -o OUT.laz (OUT.pcd)
        labels = read_field(path, LABEL_FIELD)
        if n_faces is not None and labels.shape[0] != n_faces:
            raise MeshFormatError(f"{path}: has {labels.shape[0]} points but the input has "
                                  f"{n_faces}")
        return labels
    data = read_bytes(path, comp, "file of labels", bounded=False)  # (runs of one value)
    shape = ""
    if fmt == "ply":
        labels = read_ply_labels(path, data)
    elif fmt == "label":  # SemanticKITTI's: uint32 a point, the class in its lower 16 bits
        if len(data) % 4:
            raise MeshFormatError(f"{path}: a .label file (SemanticKITTI's) holds 4 bytes a "
                                  f"point; its {len(data):,} bytes are not a whole number")
        labels = (np.frombuffer(data, dtype="<u4") & 0xFFFF).astype(np.int64)
    elif fmt in ("npy", "npz"):  # a learning pipeline's array of labels
        labels, shape = _npy_labels(data, path)
    elif fmt == "bin":  # nuScenes' lidarseg: uint8 a point
        if not path.name.lower().endswith("_lidarseg.bin"):
            raise MeshFormatError(f"{path}: a .bin of labels is read as nuScenes' lidarseg "
                                  "classes (one uint8 a point), named *_lidarseg.bin")
        labels = np.frombuffer(data, dtype=np.uint8).astype(np.int64)
    elif fmt == "json":  # the ScanNet Segmentator's {"segIndices": [...]}
        import json

        try:
            labels = np.asarray(json.loads(data)["segIndices"], dtype=np.int64)
        except (ValueError, KeyError, TypeError, OverflowError) as exc:
            raise MeshFormatError(f"{path}: not a segIndices JSON file ({type(exc).__name__}: "
                                  f"{exc})") from None
        if labels.ndim != 1:
            raise MeshFormatError(f"{path}: segIndices must be a list of integers")
    else:
        labels = _text_labels(text_lines(data, path), path)
    if n_faces is not None and labels.shape[0] != n_faces:
        raise MeshFormatError(f"{path}: has {labels.shape[0]} labels{shape} but the input "
                              f"has {n_faces} elements")
    return labels


def _text_labels(lines: list, path: Path) -> np.ndarray:
    """The labels of a text file: one whole number a line, after a column's name where
    the first line is one (pandas' ``to_csv(index=False)`` of one column: ``label``)."""
    header = ""
    if lines and len(lines) > 1 and len(lines[0].replace(",", " ").split()) == 1 \
            and not _is_number(lines[0]):
        header = (f" (after the first line, {lines[0][:40]!r}, read as the column's "
                  "name)")
        lines = lines[1:]
    if not lines:
        return np.zeros(0, dtype=np.int64)
    columns = lines[0].replace(",", " ").replace(";", " ").split()
    if len(columns) > 1:
        raise MeshFormatError(
            f"{path}: malformed label file: {len(columns):,} columns in a line "
            f"({lines[0][:60]!r}{' ...' if len(lines[0]) > 60 else ''}); "
            "it holds one label per line (pandas: to_csv(index=False) of one column)")
    try:
        labels = np.loadtxt(lines, dtype=np.int64, ndmin=1, comments=None)
    except (ValueError, OverflowError):
        labels = _whole_numbers(lines)  # (numpy.savetxt's default: 1.000000000000e+00)
    if labels is None or labels.ndim != 1:
        at = next((i for i, line in enumerate(lines) if not _is_whole(line)), 0)
        big = _is_number(lines[at]) and np.isfinite(float(lines[at])) and \
            float(lines[at]) == round(float(lines[at]))
        what = ("is beyond 2**53, the largest label kept exactly" if big else
                "is not one whole number")
        raise MeshFormatError(f"{path}: malformed label file: label {at + 1:,} of "
                              f"{len(lines):,}{header}, {lines[at][:40]!r}, {what}")
    return labels


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _is_whole(text: str) -> bool:
    """One finite whole number (``3``, ``3.0``, ``3e0``) of at most 2**53."""
    try:
        value = float(text)
    except ValueError:
        return False
    return bool(np.isfinite(value) and value == round(value) and abs(value) <= 2**53)


def _whole_numbers(lines: list) -> np.ndarray | None:
    """Labels written as floats of whole values (``numpy.savetxt``'s default format, a
    spreadsheet's ``3.0``) as integers, or None where a line holds anything else."""
    try:
        values = np.loadtxt(lines, dtype=np.float64, ndmin=1, comments=None)
    except (ValueError, OverflowError):
        return None
    flat = values.reshape(-1)
    if values.ndim != 1 or not np.isfinite(flat).all() or (flat != np.round(flat)).any() \
            or (np.abs(flat) > 2**53).any():
        return None
    return flat.astype(np.int64)


def _npy_labels(data: bytes, path: Path) -> tuple[np.ndarray, str]:
    """The labels of a ``.npy`` file: an integer (or boolean, or whole-valued float) array
    of one label per element, ``(N,)``, ``(N, 1)`` or an organized ``(H, W)`` read row by
    row; and, for the last, its shape as said where the count differs."""
    import io

    npz = split_suffix(path)[0] == "npz"
    if not data.startswith(b"PK" if npz else b"\x93NUMPY"):
        what = ".npz archive (a zip file)" if npz else ".npy file"
        raise MeshFormatError(f"{path}: not a NumPy {what} (it starts {data[:8]!r})")
    try:
        arr = np.load(io.BytesIO(data), allow_pickle=False)
        if npz:
            arr = _npz_array(arr, path)
    except MeshFormatError:
        raise
    except Exception as exc:  # noqa: BLE001 - numpy raises many types on damaged files
        raise MeshFormatError(f"{path}: cannot read {'NPZ' if npz else 'NPY'}: "
                              f"{exc}") from None
    if isinstance(arr, np.ndarray) and arr.dtype.names:  # records: ``segment -o OUT.npy``'s
        if LABEL_FIELD not in arr.dtype.names:
            raise MeshFormatError(f"{path}: NPY records without a {LABEL_FIELD} field (they "
                                  f"have: {', '.join(arr.dtype.names)}); a ground truth in "
                                  "a field of the input's: --ground-truth-field NAME")
        return whole_labels(arr[LABEL_FIELD], f"{path} ({LABEL_FIELD})"), ""
    if not isinstance(arr, np.ndarray) or arr.ndim not in (1, 2) or (
            arr.ndim == 2 and arr.shape[1] == 3):
        raise MeshFormatError(f"{path}: a .npy of labels holds one integer per element ((N,), "
                              f"(N, 1) or an organized (H, W)); got "
                              f"{getattr(arr, 'shape', type(arr).__name__)}")
    organized = arr.ndim == 2 and arr.shape[1] != 1
    return whole_labels(arr, str(path)), (f" (an organized {arr.shape[0]:,} x {arr.shape[1]:,}"
                                         " array, read row by row)" if organized else "")


def _npz_array(npz, path: Path) -> np.ndarray:
    """The array of labels of a ``.npz`` archive: its one array, or its ``labels`` (as
    ``segment --graph OUT.npz`` writes them beside the graph)."""
    if not hasattr(npz, "files"):
        raise MeshFormatError(f"{path}: not a NumPy .npz archive")
    names = list(npz.files)
    if len(names) != 1 and "labels" not in names:
        raise MeshFormatError(f"{path}: a .npz of labels holds one array, or one named "
                              f"'labels'; this one has {', '.join(names) or 'none'}")
    return npz[names[0] if len(names) == 1 else "labels"]


def read_field(path, name: str) -> np.ndarray:
    """One integer per point (vertex) from a field of the input file itself.

    A labelled scan often carries its ground truth beside the coordinates:
    the ``classification`` of a LAS/LAZ file (ASPRS classes), the ``label``
    property of a PLY's vertices (ScanNet's ``*_vh_clean_2.labels.ply``), the
    ``label`` field of a PCD (PCL's ``PointXYZL``); a tetrahedral mesh's regions
    (Gmsh's ``gmsh:physical`` cell data: one value per tetrahedron).

    Parameters
    ----------
    path : str or os.PathLike
        A ``.las``/``.laz``, ``.ply`` (optionally compressed) or ``.pcd`` file, NPY records
        (a structured ``.npy``, its fields by name), or a tetrahedral mesh (``.msh``,
        ``.vtk``, ``.vtu``, ``.mesh``).
    name : str
        The LAS dimension or the PLY vertex property (``NAME`` also finds
        ``scalar_NAME``, CloudCompare's name of a scalar field).

    Returns
    -------
    (N,) int64 ndarray
        In file order: one per point of a cloud, one per vertex of a mesh, one per
        tetrahedron.

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    MeshFormatError
        If the file has no such field (the message lists its fields), the
        field is not integer, or the format carries no fields.

    Warns
    -----
    UserWarning
        Where the field is a measurement, not a label (a coordinate, a colour, the
        intensity: :data:`MEASURED_FIELDS`).

    Examples
    --------
    >>> classes = read_field("scan.las", "classification")  # doctest: +SKIP
    """
    path = user_path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    fmt, comp = split_suffix(path)
    if fmt in ("las", "laz"):
        laspy = extras.require("laspy", "reading LAS/LAZ files")
        check_laz(path)
        try:
            las = laspy.read(path)
            names = list(las.point_format.dimension_names)
            values = np.asarray(las[name]) if name in names else None
        except Exception as exc:  # noqa: BLE001 - laspy raises many types
            raise MeshFormatError(f"{path}: cannot read {fmt.upper()}: {exc}") from None
    elif fmt == "ply":
        import io

        from plyfile import PlyData, PlyParseError

        try:
            vertex = PlyData.read(io.BytesIO(read_bytes(path, comp, "PLY file")))["vertex"]
            names = [p.name for p in vertex.properties]
            if name not in names and f"scalar_{name}" in names:  # CloudCompare's scalar field
                name = f"scalar_{name}"
            values = np.asarray(vertex[name]) if name in names else None
        except (PlyParseError, KeyError, ValueError, IndexError, EOFError) as exc:
            raise MeshFormatError(f"{path}: cannot read PLY vertices: {exc}") from None
    elif fmt == "pcd" and comp is None:
        names, values = _pcd_field(path, name)
    elif fmt == "npy" and comp is None:
        names, values = _npy_field(path, name)
    elif fmt in VOLUME_FORMATS:
        names, values = volume_field(path, name)
    elif fmt in TEXT_CLOUDS:
        names, values = _text_field(path, name)
    else:
        raise MeshFormatError(f"{path}: only LAS/LAZ, PLY, PCD files, NPY records and text "
                              "clouds with named columns carry per-point fields (and "
                              "tetrahedral meshes per-cell ones); give the labels "
                              "(or the ground truth) as a file, one per point (.seg)")
    if values is None:
        raise MeshFormatError(f"{path}: no field {name!r}; " + (
            f"it has: {', '.join(names)}" if names else "it has none"))
    labels = whole_labels(values, f"{path}: field {name!r}")
    what = MEASURED_FIELDS.get(name.lower().removeprefix("scalar_"))
    if what is not None:
        import warnings

        warnings.warn(f"{path.name}: field {name!r} is {what} measured at each point, not a "
                      f"class or a segment: {len(np.unique(labels)):,} values read as labels "
                      "(a scan's ground truth is a field such as classification or label)",
                      stacklevel=2)
    return labels


#: The ASPRS classes of a LAS file's ``classification`` (LAS 1.4 R15, table 17; 19-63
#: reserved, 64-255 user definable).
ASPRS_CLASSES = {0: "never classified", 1: "unclassified", 2: "ground", 3: "low vegetation",
                 4: "medium vegetation", 5: "high vegetation", 6: "building",
                 7: "low point (noise)", 8: "reserved", 9: "water", 10: "rail",
                 11: "road surface", 12: "reserved", 13: "wire guard", 14: "wire conductor",
                 15: "transmission tower", 16: "wire-structure connector", 17: "bridge deck",
                 18: "high noise"}


def class_names(path, name: str) -> dict:
    """The names of a ground-truth field's classes, where its format names them: a LAS/LAZ
    file's ``classification`` holds the ASPRS classes (:data:`ASPRS_CLASSES`).

    Parameters
    ----------
    path : str or os.PathLike
        The file the field was read from (:func:`read_field`).
    name : str
        The field.

    Returns
    -------
    dict of int to str
        Empty where the format names none; a LAS file's 0-255 (19-63 "reserved", 64-255
        "user defined").

    Raises
    ------
    TypeError
        Never: any path and name are looked at.

    Examples
    --------
    >>> class_names("tile.laz", "Classification")[2], class_names("room.ply", "label")
    ('ground', {})
    """
    fmt = split_suffix(Path(path))[0]
    if fmt in ("las", "laz") and name.lower() == "classification":
        return {c: ASPRS_CLASSES.get(c, "reserved" if c < 64 else "user defined")
                for c in range(256)}
    return {}


#: Fields (lower case) that hold what the sensor measured at each point, not a label: read
#: as one (:func:`read_field`), they say so.
MEASURED_FIELDS = {**dict.fromkeys(("x", "y", "z"), "a coordinate"),
                   **dict.fromkeys(("nx", "ny", "nz", "normal_x", "normal_y", "normal_z"),
                                   "a normal's component"),
                   **dict.fromkeys(("red", "green", "blue", "nir", "r", "g", "b", "alpha"),
                                   "a colour"),
                   "intensity": "the return's intensity", "gps_time": "a time",
                   "scan_angle": "the scan angle", "scan_angle_rank": "the scan angle"}


#: Text clouds, whose named columns other than the points' are fields (:func:`read_field`).
TEXT_CLOUDS = ("xyz", "pts", "txt", "csv", "asc")


def _text_field(path: Path, name: str) -> tuple[list[str], np.ndarray | None]:
    """A text cloud's other columns (``//X;Y;Z;Classification``, as CloudCompare writes a
    scalar field) and the values of ``name`` (any case; None where absent)."""
    from .clouds import read_cloud

    fields = read_cloud(path).fields
    if not fields:
        raise MeshFormatError(f"{path}: a text cloud whose columns are its points' alone has "
                              "no fields (a header such as //X;Y;Z;Classification names them"
                              "); LAS/LAZ, PLY, PCD files and NPY records carry per-point "
                              "fields")
    names = list(fields)
    found = next((n for n in names if n == name), None) or next(
        (n for n in names if n.lower() == name.lower()), None)
    return names, (None if found is None else np.asarray(fields[found]))


def _npy_field(path: Path, name: str) -> tuple[list[str], np.ndarray | None]:
    """The field names of NPY records (a structured array) and the values of ``name``."""
    from .headers import npy_mapped

    try:
        arr = np.load(path, mmap_mode="r", allow_pickle=False)
    except Exception:  # noqa: BLE001 - numpy raises many types (npy_mapped says which)
        arr = npy_mapped(path)
    names = list(arr.dtype.names or ())
    if not names:
        raise MeshFormatError(f"{path}: an NPY array of plain numbers ({arr.dtype}) has no "
                              "fields; NPY records (a structured array) have")
    if name not in names:
        return names, None
    kind = arr.dtype.fields[name][0]
    if kind.shape:
        raise MeshFormatError(f"{path}: field {name!r} holds {int(np.prod(kind.shape))} "
                              "values per point, not one label")
    return names, np.asarray(arr[name]).reshape(-1)


def _pcd_field(path: Path, name: str) -> tuple[list[str], np.ndarray | None]:
    """A PCD's field names and the values of the field ``name`` (None where absent)."""
    from .headers import check_pcd, pcd_problem

    pypcd4 = extras.require("pypcd4", "reading PCD files")
    check_pcd(path)
    try:
        pc = pypcd4.PointCloud.from_path(path)
        meta = pc.metadata
        names = [f for f in meta.fields if not f.startswith("#")]  # (not the padding)
        if name in names and meta.count[list(meta.fields).index(name)] != 1:
            count = meta.count[list(meta.fields).index(name)]
            raise MeshFormatError(f"{path}: field {name!r} holds {count} values per point, "
                                  "not one label")
        return names, np.asarray(pc.pc_data[name]) if name in names else None
    except MeshFormatError:
        raise
    except Exception as exc:  # noqa: BLE001 - pypcd4/pydantic raise many types
        raise MeshFormatError(f"{path}: cannot read PCD: {pcd_problem(exc)}") from None
