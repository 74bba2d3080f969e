"""Labels written back into the input's own records: a LAS/LAZ dimension, a PLY field.

A scan's users keep working in the scan's own file (PDAL, lidR, CloudCompare,
QGIS): the labels go in as one more field of each point, every other field and
the header kept.

- LAS/LAZ: an extra-bytes dimension ``ClusterID`` (``int32``), the name PDAL's
  ``filters.cluster`` writes; the point format, scale, offset, CRS and every
  other VLR unchanged (laspy).
- PLY: a vertex property ``scalar_ClusterID`` (``int``), the ``scalar_`` prefix
  being the one CloudCompare loads as a scalar field (named ``ClusterID``
  there); every other element and property kept, in the input's encoding
  (plyfile).

``-1`` marks an invalid point (a non-finite row of the input): the type is signed
for that.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from .._runtime import extras
from ..errors import MeshFormatError, ParameterError
from .files import Outputs, read_bytes, save, split_suffix
from .headers import check_las

__all__ = ["LABEL_FIELD", "RECORD_FORMATS", "write_labels_into", "ply_field_name",
           "records_kind"]

#: The dimension (LAS/LAZ) or scalar field (PLY, as ``scalar_ClusterID``) the labels go in.
LABEL_FIELD = "ClusterID"

#: Output formats that take the labels into the input's records, by input format.
RECORD_FORMATS = {"las": ("las", "laz"), "laz": ("las", "laz"), "ply": ("ply",)}


def records_kind(output, source) -> str | None:
    """The format of the records ``output`` writes for input ``source``: ``'las'`` or
    ``'ply'`` where it names one the input can be written back as, None for a label file.

    Parameters
    ----------
    output, source : str or os.PathLike
        The output's name; the input file.

    Returns
    -------
    str or None

    Raises
    ------
    ParameterError
        If ``output`` is a LAS/LAZ or PLY the input, itself a LAS/LAZ or PLY, cannot be
        written back as (a ``.ply`` of a ``.laz``): the message says what can. Other
        inputs give None (``-o`` then refuses the name as no label file).

    Examples
    --------
    >>> records_kind("out.laz", "scan.las"), records_kind("out.seg", "scan.las")
    ('las', None)
    """
    out_fmt, out_comp = split_suffix(Path(output))
    in_fmt, _ = split_suffix(Path(source))
    if out_fmt not in ("las", "laz", "ply") or in_fmt not in RECORD_FORMATS:
        return None  # (a label file, or a name the caller refuses as no label file)
    if out_fmt in RECORD_FORMATS.get(in_fmt, ()) and not (out_fmt != "ply" and out_comp):
        return "ply" if out_fmt == "ply" else "las"
    if out_fmt in RECORD_FORMATS[in_fmt]:  # a .las.gz
        raise ParameterError(f"{output}: a LAS file is compressed as LAZ: name it .laz")
    takes = ".ply" if in_fmt == "ply" else ".las or .laz"
    raise ParameterError(
        f"{output}: -o writes the labels into a copy of the input's own records, so a "
        f".{out_fmt} needs a .{out_fmt if out_fmt == 'ply' else 'las/.laz'} input (this one is "
        f"{Path(source).name}); for it use -o NAME{takes.split(' or ')[0]}, or a label file "
        "(-o NAME.seg)")


def ply_field_name(name: str) -> str:
    """The PLY property that CloudCompare loads as the scalar field ``name``.

    Parameters
    ----------
    name : str

    Returns
    -------
    str
        ``scalar_<name>`` (``name`` itself where it already starts so).

    Raises
    ------
    ParameterError
        If ``name`` is not a non-empty word of letters, digits and ``_`` (a PLY
        property name).

    Examples
    --------
    >>> ply_field_name("ClusterID")
    'scalar_ClusterID'
    """
    if not isinstance(name, str) or not name or not name.replace("_", "").isalnum():
        raise ParameterError(f"a field name is a word of letters, digits and _, got {name!r}")
    return name if name.startswith("scalar_") else f"scalar_{name}"


def write_labels_into(path, source, labels, *, name: str = LABEL_FIELD,
                      outputs: Outputs | None = None) -> Path:
    """Write a copy of ``source`` whose point (vertex) records carry ``labels``.

    Parameters
    ----------
    path : str or os.PathLike
        The copy: ``.las`` or ``.laz`` for a LAS/LAZ input (LAZ compressed,
        through laspy's ``lazrs``), ``.ply`` for a PLY input (cloud, or a
        mesh whose vertices were segmented).
    source : str or os.PathLike
        The input file the labels are of.
    labels : (N,) int ndarray
        One label per point (vertex) in file order, ``-1`` for an invalid
        point; written as ``int32``.
    name : str, default ``'ClusterID'``
        The dimension's name (LAS/LAZ); in a PLY the property is
        ``scalar_<name>``. An existing field of that name is overwritten.
    outputs : Outputs, optional
        Stage the file there (all or nothing with the run's other files).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ParameterError
        If the labels do not fit ``int32``, their count is not the input's
        number of records, the formats do not match, or ``name`` is not a word of
        letters, digits and ``_`` (of at most 32 characters in a LAS file).
    MeshFormatError
        If the input cannot be read, or holds a field of that name of a type
        that cannot take the labels.
    MissingExtraError
        LAS/LAZ without the ``clouds`` extra.

    Examples
    --------
    >>> import tempfile, numpy as np, laspy
    >>> folder = tempfile.mkdtemp()
    >>> las = laspy.create(point_format=3, file_version="1.4")
    >>> las.x, las.y, las.z = np.arange(4.0), np.zeros(4), np.ones(4)
    >>> las.write(f"{folder}/scan.las")
    >>> out = write_labels_into(f"{folder}/out.laz", f"{folder}/scan.las", [0, 0, 1, -1])
    >>> laspy.read(out).ClusterID.tolist()
    [0, 0, 1, -1]
    """
    path, source = Path(path), Path(source)
    labels = np.asarray(labels)
    if labels.ndim != 1 or not np.issubdtype(labels.dtype, np.integer):
        raise ParameterError(f"labels must be a 1-D integer array, got {labels.dtype} "
                             f"{labels.shape}")
    if labels.size and (labels.min() < -1 or labels.max() > np.iinfo(np.int32).max):
        raise ParameterError("labels must be -1 (invalid point) or from 0 to 2**31 - 1")
    ply_name = ply_field_name(name)  # (a word: checked here for both layouts)
    kind = records_kind(path, source)
    if kind is None:
        raise ParameterError(f"{path}: labels go into .las, .laz or .ply records")
    if kind == "las" and len(name) > 32:
        raise ParameterError(f"a LAS dimension's name holds at most 32 characters: {name!r}")
    labels = labels.astype(np.int32)
    if kind == "las":
        content = _las_with(source, labels, name, compress=split_suffix(path)[0] == "laz")
    else:
        content = _ply_with(source, labels, ply_name)
    return save(path, content, outputs)


def _count_error(source: Path, n_labels: int, n_records: int) -> ParameterError:
    return ParameterError(f"{source}: {n_labels:,} labels for {n_records:,} points: one label "
                          "per point of the file, in file order, is needed")


def _las_with(source: Path, labels: np.ndarray, name: str, compress: bool) -> bytes:
    """The LAS/LAZ bytes of ``source`` with ``labels`` as the extra dimension ``name``."""

    laspy = extras.require("laspy", "writing LAS/LAZ files")
    check_las(source)
    try:
        las = laspy.read(source)
    except Exception as exc:  # noqa: BLE001 - laspy raises many types
        raise MeshFormatError(f"{source}: cannot read LAS/LAZ: {exc}") from None
    if len(las.points) != labels.shape[0]:
        raise _count_error(source, labels.shape[0], len(las.points))
    if name in las.point_format.dimension_names:
        dtype = np.asarray(las[name][:0]).dtype
        if not (np.issubdtype(dtype, np.signedinteger) and dtype.itemsize >= 4):
            raise MeshFormatError(f"{source}: has a dimension {name!r} of type {dtype}, "
                                  "which cannot hold the labels (-1 and up to 2**31 - 1)")
    else:
        las.add_extra_dim(laspy.ExtraBytesParams(
            name=name, type=np.int32, description="superfacets label"))
    las[name] = labels
    buf = io.BytesIO()
    kw = {"laz_backend": laspy.LazBackend.Lazrs} if compress else {}
    las.write(buf, do_compress=compress, **kw)
    return buf.getvalue()


def _ply_with(source: Path, labels: np.ndarray, prop: str) -> bytes:
    """The PLY bytes of ``source`` with ``labels`` as the vertex property ``prop``."""
    from plyfile import PlyData, PlyParseError, PlyProperty

    fmt, comp = split_suffix(source)
    try:
        ply = PlyData.read(io.BytesIO(read_bytes(source, comp, "PLY file")))
        vertex = ply["vertex"]
    except (PlyParseError, KeyError, ValueError, IndexError, EOFError) as exc:
        raise MeshFormatError(f"{source}: cannot read PLY vertices: {exc}") from None
    data = vertex.data
    if len(data) != labels.shape[0]:
        raise _count_error(source, labels.shape[0], len(data))
    names = [p.name for p in vertex.properties]
    if prop in names:
        kind = np.dtype(data.dtype[prop])
        if not (np.issubdtype(kind, np.signedinteger) and kind.itemsize >= 4):
            raise MeshFormatError(f"{source}: has a vertex property {prop!r} of type {kind}, "
                                  "which cannot hold the labels (-1 and up to 2**31 - 1)")
        data = data.copy()
        data[prop] = labels
        vertex.data = data
    else:
        order = "<" if ply.byte_order in ("<", "=") else ">"
        fields = [(n, data.dtype.fields[n][0]) for n in data.dtype.names]
        grown = np.empty(len(data), dtype=fields + [(prop, order + "i4")])
        for n in data.dtype.names:
            grown[n] = data[n]
        grown[prop] = labels
        vertex.data = grown  # (then the property that names the new field)
        vertex.properties = tuple(vertex.properties) + (PlyProperty(prop, "int32"),)
    buf = io.BytesIO()
    ply.write(buf)
    return buf.getvalue()
