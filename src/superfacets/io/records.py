"""Labels written back into the input's own records: a LAS/LAZ dimension, a PLY or PCD field.

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
- PCD: a field ``ClusterID`` (``TYPE I``, ``SIZE 4``) after the others; the header's
  lines (comments, ``VIEWPOINT``, an organized cloud's ``WIDTH`` and ``HEIGHT``) and the
  encoding kept: an ASCII file's lines as they were, each with the label after it; a
  binary file's records (padding fields included) with 4 bytes more (pypcd4 encodes a
  ``binary_compressed`` one). PDAL's PCD reader names the dimension ``ClusterID`` too.

``-1`` marks an invalid point (a non-finite row of the input): the type is signed
for that.

A cloud whose own file takes no field (text columns, NPY, KITTI's and nuScenes' ``.bin``,
E57, an OBJ or OFF of vertices) is written as a new LAS/LAZ or PLY file instead
(:func:`write_cloud_with_labels`): its points in file order, the colours and normals it
was read with, and the labels in the same ``ClusterID`` field.
"""

from __future__ import annotations

import io
import re
import tempfile
import warnings
from pathlib import Path

import numpy as np

from .._runtime import extras
from ..errors import MeshFormatError, ParameterError
from .files import Outputs, read_bytes, save, split_suffix
from .headers import check_las, first_line, pcd_problem

__all__ = ["LABEL_FIELD", "RECORD_FORMATS", "write_labels_into", "ply_field_name",
           "records_kind", "write_cloud_with_labels", "converts", "CONVERTED_FORMATS", "copc_said",
           "scan_output", "write_scan_labels", "kept_fields", "level_field"]

#: The dimension (LAS/LAZ) or scalar field (PLY, as ``scalar_ClusterID``) the labels go in.
LABEL_FIELD = "ClusterID"


def level_field(n_segments: int) -> str:
    """The field a hierarchy's level of ``n_segments`` segments is written in beside the
    labels (``segment --levels 100,30 -o OUT.laz``): ``ClusterID_<n>``.

    Parameters
    ----------
    n_segments : int
        The level's number of segments (exact: :func:`superfacets.graph.hierarchy.
        hierarchy`).

    Returns
    -------
    str

    Raises
    ------
    Never.

    Examples
    --------
    >>> level_field(100)
    'ClusterID_100'
    """
    return f"{LABEL_FIELD}_{int(n_segments)}"

#: Output formats that take the labels into the input's records, by input format.
RECORD_FORMATS = {"las": ("las", "laz"), "laz": ("las", "laz"), "ply": ("ply",),
                  "pcd": ("pcd",)}


def records_kind(output, source) -> str | None:
    """The format of the records ``output`` writes for input ``source``: ``'las'``,
    ``'ply'``, ``'pcd'`` or ``'npy'`` (NPY records, a structured array, as ``ros_numpy``
    makes) where it names one the input can be written back as, None for a label file
    (a ``.npy`` of labels for a ``.npy`` of plain positions).

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
        If ``output`` is a LAS/LAZ, PLY or PCD the input, itself one of those, cannot be
        written back as (a ``.ply`` of a ``.laz``), a compressed PCD, or a ``.copc.laz``
        (the copy is a plain LAZ): the message says what can. Other inputs give None
        (``-o`` then refuses the name as no label file).

    Examples
    --------
    >>> records_kind("out.laz", "scan.las"), records_kind("out.seg", "scan.las")
    ('las', None)
    """
    out_fmt, out_comp = split_suffix(Path(output))
    in_fmt, _ = split_suffix(Path(source))
    if out_fmt in ("las", "laz") and Path(output).name.lower().endswith(f".copc.{out_fmt}"):
        raise ParameterError(f"{output}: the labels go into a plain LAZ, not a COPC file (PDAL "
                             "reads a .copc.laz as one): name it NAME.laz; `pdal translate "
                             "NAME.laz NAME.copc.laz` indexes it")
    if out_fmt == "npy" and in_fmt == "npy":  # records (a structured array), or labels
        return "npy" if out_comp is None and _npy_records_of(Path(source)) else None
    if out_fmt not in ("las", "laz", "ply", "pcd") or in_fmt not in RECORD_FORMATS:
        return None  # (a label file, or a name the caller refuses as no label file)
    if out_fmt in RECORD_FORMATS.get(in_fmt, ()) and not (out_fmt != "ply" and out_comp):
        return {"ply": "ply", "pcd": "pcd"}.get(out_fmt, "las")
    if out_fmt == "pcd" and in_fmt == "pcd":  # a .pcd.gz
        raise ParameterError(f"{output}: a PCD file is compressed by its own encoding "
                             "(binary_compressed, kept from the input): name it .pcd")
    if out_fmt in RECORD_FORMATS[in_fmt]:  # a .las.gz
        raise ParameterError(f"{output}: a LAS file is compressed as LAZ: name it .laz")
    takes = {"ply": ".ply", "pcd": ".pcd"}.get(in_fmt, ".las")
    needs = "las/.laz" if out_fmt in ("las", "laz") else out_fmt
    raise ParameterError(
        f"{output}: -o writes the labels into a copy of the input's own records, so a "
        f".{out_fmt} needs a .{needs} input (this one is {Path(source).name}); for it use "
        f"-o NAME{takes}, or a label file (-o NAME.seg)"
        + ("; --colored-mesh NAME.ply writes a PLY of the points, coloured, their labels as "
           "scalar_ClusterID" if out_fmt == "ply" else ""))


#: The formats a cloud whose own file takes no field is written as, with its labels
#: (:func:`write_cloud_with_labels`).
CONVERTED_FORMATS = ("las", "laz", "ply")


def converts(output, source) -> bool:
    """Whether ``output`` is a new LAS/LAZ or PLY file of the points of ``source``, a
    cloud whose own file takes no field (:func:`write_cloud_with_labels`).

    Parameters
    ----------
    output, source : str or os.PathLike
        The output's name; the input file.

    Returns
    -------
    bool

    Raises
    ------
    MeshFormatError
        If a PLY, OBJ or OFF input's header cannot be read (to tell a cloud).

    Examples
    --------
    >>> converts("out.laz", "scan.xyz"), converts("out.laz", "scan.las")
    (True, False)
    """
    from .clouds import is_cloud_file

    out_fmt, out_comp = split_suffix(Path(output))
    in_fmt, _ = split_suffix(Path(source))
    return (out_fmt in CONVERTED_FORMATS and out_comp is None and in_fmt not in RECORD_FORMATS
            and is_cloud_file(source))


def scan_output(output, source) -> str | None:
    """What ``-o OUTPUT`` writes for the input ``source``: ``'records'`` (a copy of its own
    records with the labels: :func:`write_labels_into`), ``'new'`` (a new LAS/LAZ or PLY of
    its points: :func:`write_cloud_with_labels`), or None (a label file).

    Parameters
    ----------
    output : str or os.PathLike or None
        The output's name (None or ``-``: a label file, or none).
    source : str or os.PathLike
        The input file.

    Returns
    -------
    str or None

    Raises
    ------
    ParameterError
        As :func:`records_kind` (a record format the input cannot be written back as).

    Examples
    --------
    >>> scan_output("o.laz", "scan.las"), scan_output("o.laz", "sweep.bin")
    ('records', 'new')
    """
    if output is None or str(output) == "-":
        return None
    if records_kind(output, source) is not None:
        return "records"
    return "new" if converts(output, source) else None


def write_scan_labels(path, source, labels, *, cloud=None, levels=None,
                      outputs: Outputs | None = None) -> Path:
    """The labels into a copy of the input's own records (:func:`write_labels_into`), or,
    for a cloud whose file takes no field, into a new LAS/LAZ or PLY file of its points
    (:func:`write_cloud_with_labels`): what :func:`scan_output` says ``path`` is.

    Parameters
    ----------
    path, source : str or os.PathLike
        The output; the input file.
    labels : (N,) int ndarray
        One label per record (point, vertex), ``-1`` for an invalid point.
    cloud : PointCloud, optional
        The input as read (else read again here, for a new file).
    levels : mapping of str to (N,) int ndarray, optional
        More fields after the labels, each a name and one label per record (a
        hierarchy's levels, named by :func:`level_field`), in this order.
    outputs : Outputs, optional
        Stage the file there.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ParameterError
        If ``path`` is neither (a label file's name), or as the two writers (for each
        field).

    Examples
    --------
    >>> import tempfile
    >>> from superfacets import read_labels
    >>> folder = tempfile.mkdtemp()
    >>> np.savetxt(f"{folder}/scan.xyz", np.random.default_rng(0).random((6, 3)))
    >>> out = write_scan_labels(f"{folder}/scan.ply", f"{folder}/scan.xyz", [0, 0, 1, 1, 2, 2])
    >>> read_labels(out).tolist()
    [0, 0, 1, 1, 2, 2]
    """
    what = scan_output(path, source)
    if what == "records" and levels:
        return _into_with_levels(Path(path), Path(source), labels, dict(levels), outputs)
    if what == "records":
        return write_labels_into(path, source, labels, outputs=outputs)
    if what is None:
        raise ParameterError(f"{path}: labels go into .las, .laz, .ply, .pcd or NPY records")
    if cloud is None:
        from .clouds import read_cloud

        cloud = read_cloud(source)
    return write_cloud_with_labels(path, cloud, labels, levels=levels, outputs=outputs)


def _into_with_levels(path: Path, source: Path, labels, levels: dict,
                      outputs: Outputs | None) -> Path:
    """The labels and then each of ``levels`` written into a copy of the records of
    ``source``, one field after the other, through uncompressed copies in a folder beside
    ``path`` (removed after), each named as the input (what a warning names)."""
    fmt = records_kind(path, source)
    in_fmt, in_comp = split_suffix(source)
    stem = source.name[:len(source.name) - len(f".{in_fmt}{in_comp or ''}")]
    fields = [(LABEL_FIELD, labels), *levels.items()]
    with tempfile.TemporaryDirectory(prefix=".superfacets-", dir=path.parent) as folder:
        step = source
        for i, (name, values) in enumerate(fields):
            last = i == len(fields) - 1
            target = path if last else Path(folder) / str(i) / f"{stem}.{fmt}"
            if not last:
                target.parent.mkdir()
            write_labels_into(target, step, values, name=name,
                              outputs=outputs if last else None)
            step = target
    return path


def write_cloud_with_labels(path, cloud, labels, *, name: str = LABEL_FIELD, levels=None,
                            outputs: Outputs | None = None) -> Path:
    """Write a new LAS/LAZ or PLY file of a cloud's points with ``labels`` as a field.

    For a cloud whose own file cannot take one more field (text columns, NPY, KITTI's
    and nuScenes' ``.bin``, E57, an OBJ or OFF of vertices): PDAL, QGIS and CloudCompare
    read the result.

    - LAS/LAZ 1.4, point format 6 (7 with colours): ``X Y Z`` at a scale of a power of
      ten that holds the cloud's extent in 2**30 steps (the data's own precision, in
      whatever units), the offset its lowest corner rounded down to the extent's power of
      ten; ``Red Green Blue`` (16 bits) where
      the cloud has colours; the labels as the ``int32`` extra dimension ``name``. An
      invalid point (non-finite, -1) is written at the offset, ``withheld``.
    - PLY (binary): ``x y z`` as doubles (an invalid point NaN), ``nx ny nz`` where the
      file gave normals, ``red green blue`` where it gave colours, and
      ``scalar_<name>`` (CloudCompare's scalar field ``name``).

    The cloud's other values (:attr:`~superfacets.PointCloud.fields`: a KITTI scan's
    reflectance, NPY records' fields, named text columns) are kept: in a PLY as
    ``scalar_<field>`` (CloudCompare's scalar fields); in a LAS in the standard dimension
    of their name where their values fit it (``intensity``, ``classification``,
    ``gps_time``, ...; an intensity of floats from 0 to 1, an E57's, scaled to 0..65535
    as PDAL's E57 reader scales it), else as extra dimensions of their own type. One that
    cannot be kept (a standard name whose values do not fit, a name of more than 32
    characters) is left out with a warning that says why.

    Parameters
    ----------
    path : str or os.PathLike
        ``.las``, ``.laz`` or ``.ply``.
    cloud : PointCloud or what :func:`superfacets.as_cloud` takes
        The cloud as read (:func:`superfacets.read_cloud`): its rows in file order.
    labels : (N,) int ndarray
        One label per point, ``-1`` for an invalid point.
    name : str, default ``'ClusterID'``
        The field's name (PDAL's).
    levels : mapping of str to (N,) int ndarray, optional
        More label fields, each a name and one label per point (a hierarchy's levels,
        named by :func:`level_field`), written as the labels are (``int32``).
    outputs : Outputs, optional
        Stage the file there (all or nothing with the run's other files).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ParameterError
        If ``path`` is not ``.las``, ``.laz`` or ``.ply``, the labels are not one integer
        per point from -1 to 2**31 - 1, or ``name`` is not a word (of at most 32
        characters in a LAS file).
    TypeError
        If ``cloud`` is not a point cloud (:func:`superfacets.as_cloud`).
    MissingExtraError
        LAS/LAZ without the ``clouds`` extra.

    Examples
    --------
    >>> import tempfile
    >>> from plyfile import PlyData
    >>> cloud = PointCloud(np.random.default_rng(0).random((5, 3)))
    >>> out = write_cloud_with_labels(f"{tempfile.mkdtemp()}/out.ply", cloud, [0, 0, 1, 1, 2])
    >>> PlyData.read(out)["vertex"]["scalar_ClusterID"].tolist()
    [0, 0, 1, 1, 2]
    """
    path = Path(path)
    fmt, comp = split_suffix(path)
    if fmt not in CONVERTED_FORMATS or comp is not None:
        raise ParameterError(f"{path}: a cloud with its labels is written as .las, .laz or "
                             ".ply")
    from ..inputs.cloud import as_cloud

    cloud = as_cloud(cloud)
    points = np.asarray(cloud.points, dtype=np.float64)
    labels = _checked_labels(labels, points.shape[0])
    ply_name = ply_field_name(name)
    if fmt != "ply" and len(name) > 32:
        raise ParameterError(f"a LAS dimension's name holds at most 32 characters: {name!r}")
    colors = getattr(cloud, "colors", None)
    fields = dict(getattr(cloud, "fields", None) or {})
    after = {}  # (each level after the labels, as in the input's records)
    for level, values in (levels or {}).items():
        if fmt != "ply" and len(level) > 32:
            raise ParameterError(f"a LAS dimension's name holds at most 32 characters: "
                                 f"{level!r}")
        after[ply_field_name(level) if fmt == "ply" else level] = _checked_labels(
            values, points.shape[0])
        fields.pop(level, None)  # (an earlier run's level, read as the cloud's field)
    if fmt == "ply":
        content = _new_ply(points, labels, ply_name, colors, getattr(cloud, "normals", None),
                           fields, after)
    else:
        content = _new_las(points, labels, name, colors, compress=fmt == "laz", fields=fields,
                           after=after)
    return save(path, content, outputs)


def _checked_labels(labels, n: int | None = None) -> np.ndarray:
    """``labels`` as ``int32``: integers from -1 to 2**31 - 1, one per point (``n``; None:
    any number, checked against the file's records later)."""
    labels = np.asarray(labels)
    if labels.ndim != 1 or not np.issubdtype(labels.dtype, np.integer):
        raise ParameterError(f"labels must be a 1-D integer array, got {labels.dtype} "
                             f"{labels.shape}")
    if n is not None and labels.shape[0] != n:
        raise ParameterError(f"{labels.shape[0]:,} labels for {n:,} points: one label per "
                             "point, in file order, is needed")
    if labels.size and (labels.min() < -1 or labels.max() > np.iinfo(np.int32).max):
        raise ParameterError("labels must be -1 (invalid point) or from 0 to 2**31 - 1")
    return labels.astype(np.int32)


def _las_scale(extent: float) -> float:
    """The LAS scale of a new file of a cloud of this ``extent`` (its largest side, in its
    units): the power of ten that spans it in at most 2**30 steps (the stored integers
    keep half of their int32 range free), however small the extent (a cloud of a
    micrometre keeps its shape); ``1e-12`` where there is no extent.

    Examples
    --------
    >>> _las_scale(100.0), _las_scale(1e-6), _las_scale(0.0)
    (1e-07, 1e-15, 1e-12)
    """
    if not extent > 0 or not np.isfinite(extent):
        return 1e-12
    return float(10.0 ** max(-300.0, np.ceil(np.log10(extent / 2**30))))


def _new_las(points: np.ndarray, labels: np.ndarray, name: str, colors, compress: bool,
             fields: dict | None = None, after: dict | None = None) -> bytes:
    """A new LAS/LAZ file's bytes (:func:`write_cloud_with_labels`; ``after``: more
    ``int32`` label dimensions after ``name``)."""
    laspy = extras.require("laspy", "writing LAS/LAZ files")
    valid = np.isfinite(points).all(axis=1)
    lo = points[valid].min(axis=0) if valid.any() else np.zeros(3)
    hi = points[valid].max(axis=0) if valid.any() else np.zeros(3)
    extent = float(np.max(hi - lo))
    unit = 10.0 ** np.floor(np.log10(extent)) if extent > 0 else 1.0  # (a round offset, as
    offset = np.floor(lo / unit) * unit  # near the points as their extent: no precision lost)
    scale = _las_scale(float(np.max(hi - offset)))
    header = laspy.LasHeader(point_format=7 if colors is not None else 6, version="1.4")
    header.offsets, header.scales = offset, np.full(3, scale)
    after = after or {}
    for dim in (name, *after):
        header.add_extra_dim(laspy.ExtraBytesParams(name=dim, type=np.int32,
                                                    description="superfacets label"))
    standard, extra, _ = _las_fields(header.point_format, {
        k: v for k, v in (fields or {}).items() if k not in after}, name)
    for field_name, values in extra.items():
        header.add_extra_dim(laspy.ExtraBytesParams(name=field_name, type=values.dtype))
    las = laspy.LasData(header, laspy.ScaleAwarePointRecord.zeros(points.shape[0],
                                                                  header=header))
    for dim, values in {**standard, **extra}.items():
        las[dim] = values
    xyz = np.where(valid[:, None], points, offset)
    las.x, las.y, las.z = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    if not valid.all():
        las.withheld = ~valid
    if colors is not None:
        rgb = np.round(np.clip(np.nan_to_num(np.asarray(colors, dtype=np.float64)), 0, 1)
                       * 65535).astype(np.uint16)
        las.red, las.green, las.blue = rgb[:, 0], rgb[:, 1], rgb[:, 2]
    las[name] = labels
    for dim, values in after.items():
        las[dim] = values
    buf = io.BytesIO()
    kw = {"laz_backend": laspy.LazBackend.LazrsParallel} if compress else {}
    las.write(buf, do_compress=compress, **kw)
    return buf.getvalue()


#: Standard LAS dimensions a cloud's field never goes into: the positions and colours are
#: the cloud's own; ``withheld`` marks its invalid points.
_LAS_OWN = ("x", "y", "z", "red", "green", "blue", "withheld")  # (as _las_key spells them)


def kept_fields(path, cloud, name: str = LABEL_FIELD) -> list:
    """The names of a cloud's fields (:attr:`~superfacets.PointCloud.fields`) that a new
    file of its points keeps (:func:`write_cloud_with_labels`), in order.

    Parameters
    ----------
    path : str or os.PathLike
        The new file: ``.ply``, ``.las`` or ``.laz``.
    cloud : PointCloud
    name : str, default ``'ClusterID'``
        The labels' field.

    Returns
    -------
    list of str

    Raises
    ------
    MissingExtraError
        A LAS/LAZ without the ``clouds`` extra.

    Examples
    --------
    >>> cloud = PointCloud(np.zeros((2, 3)), fields={"intensity": np.array([0.5, 1.5])})
    >>> kept_fields("out.ply", cloud), kept_fields("out.las", cloud)
    (['intensity'], [])
    """
    fields = dict(getattr(cloud, "fields", None) or {})
    if split_suffix(Path(path))[0] == "ply":
        own = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", ply_field_name(name)}
        return [f for f, p in _ply_names(fields).items() if p not in own]
    laspy = extras.require("laspy", "writing LAS/LAZ files")
    pf = laspy.PointFormat(7 if getattr(cloud, "colors", None) is not None else 6)
    return list(_las_fields(pf, fields, name, warn=False)[2])


def _ascii(name: str) -> str:
    """A field's name as a file's header spells it: ASCII letters, digits and ``_``."""
    return re.sub(r"[^A-Za-z0-9_]", "_", name)


def _las_fields(point_format, fields: dict, label: str, warn: bool = True
                ) -> tuple[dict, dict, dict]:
    """A cloud's fields for a new LAS: ``(standard, extra, written)``, the first two each
    dimension -> values (the standard dimensions' names as laspy spells them, the others'
    in ASCII), the third each field kept -> its dimension; a field that fits neither is
    left out with a warning (:func:`write_cloud_with_labels`)."""
    dims = {_las_key(d.name): d for d in point_format.dimensions if d.is_standard}
    standard, extra, written = {}, {}, {}
    for field_name, values in fields.items():
        a = np.asarray(values)
        dim = dims.get(_las_key(field_name))
        why = None
        if field_name == label:
            why = f"the labels are written as {label}"
        elif _las_key(field_name) in _LAS_OWN:
            why = "the file's own dimension of that name holds the points' own values"
        elif dim is not None:
            if dim.dtype is not None and dim.dtype.kind == "f":
                standard[dim.name] = a.astype(dim.dtype)
                written[field_name] = dim.name
                continue
            lo, hi = ((np.iinfo(dim.dtype).min, np.iinfo(dim.dtype).max) if dim.dtype
                      is not None else (0, 2 ** dim.num_bits - 1))
            if dim.name == "intensity" and _normalised(a) and dim.name not in standard:
                standard[dim.name] = np.round(a * hi).astype(np.int64)  # (0..1 to 16 bits)
                written[field_name] = dim.name
                continue
            with np.errstate(invalid="ignore"):
                fits = bool(np.all((a == np.floor(a)) & (a >= lo) & (a <= hi)))
            if fits and dim.name not in standard:
                standard[dim.name] = a.astype(np.int64)
                written[field_name] = dim.name
                continue
            why = (f"another field is written as {dim.name}" if dim.name in standard else
                   f"LAS's {dim.name} holds whole numbers {lo}..{hi}")
        elif len(field_name) > 32:
            why = "a LAS extra dimension's name holds at most 32 characters"
        elif _ascii(field_name) in extra or _ascii(field_name).lower() in dims:
            why = f"another field is written as {_ascii(field_name)}"
        else:
            kind = {"b": np.uint8, "f": np.float64 if a.dtype.itemsize > 4 else np.float32}
            extra[_ascii(field_name)] = a.astype(kind.get(a.dtype.kind, a.dtype))
            written[field_name] = _ascii(field_name)
            continue
        if warn:
            warnings.warn(f"field {field_name!r} is not kept in the new LAS file: {why}; a "
                          ".ply keeps every field", stacklevel=4)
    return standard, extra, written


def _normalised(values: np.ndarray) -> bool:
    """Whether an intensity is normalised: floats from 0 to 1, not all whole (an E57's
    usual limits, Open3D's), which a LAS file's 16-bit ``intensity`` holds scaled."""
    if values.dtype.kind != "f" or values.size == 0:
        return False
    with np.errstate(invalid="ignore"):
        return bool(np.all((values >= 0) & (values <= 1))
                    and not np.all(values == np.floor(values)))


def _las_key(name: str) -> str:
    """A LAS dimension's name as compared: any case, no ``_`` (PDAL's ``ReturnNumber``,
    ``GpsTime`` are laspy's ``return_number``, ``gps_time``; PDAL's ``ScanAngleRank``, in
    degrees, is not point formats 6-10's ``scan_angle``, in steps of 0.006 degrees: an
    extra dimension)."""
    return name.lower().replace("_", "")


def _ply_names(fields: dict) -> dict:
    """Each field's PLY property, ``scalar_<name>`` in ASCII; the first of two alike kept."""
    out = {}
    for field_name in fields:
        prop = "scalar_" + _ascii(field_name)
        if prop not in out.values():
            out[field_name] = prop
    return out


def _ply_fields(fields: dict, taken: set) -> dict:
    """A cloud's fields as PLY properties ``scalar_<name>`` (CloudCompare's scalar fields) of
    a type PLY has: 64-bit integers as int32 where they fit, else as doubles; a name another
    property already has is left out with a warning (:func:`write_cloud_with_labels`)."""
    out = {}
    names = _ply_names(fields)
    for field_name, values in fields.items():
        prop = names.get(field_name, "scalar_" + _ascii(field_name))
        a = np.asarray(values)
        if prop in taken or prop in out or field_name not in names:
            warnings.warn(f"field {field_name!r} is not kept in the new PLY file: another "
                          f"property is named {prop}", stacklevel=4)
            continue
        if a.dtype.kind == "b":
            a = a.astype(np.uint8)
        elif a.dtype.kind in "iu" and a.dtype.itemsize == 8:
            small = a.size == 0 or (a.min() >= np.iinfo(np.int32).min
                                    and a.max() <= np.iinfo(np.int32).max)
            a = a.astype(np.int32 if small else np.float64)
        elif a.dtype.kind == "f" and a.dtype.itemsize == 2:
            a = a.astype(np.float32)
        out[prop] = a
    return out


def _new_ply(points: np.ndarray, labels: np.ndarray, prop: str, colors, normals,
             fields: dict | None = None, after: dict | None = None) -> bytes:
    """A new binary PLY file's bytes (:func:`write_cloud_with_labels`; ``after``: more
    ``int32`` label properties after ``prop``)."""
    from plyfile import PlyData, PlyElement

    after = after or {}
    columns = [("x", "<f8"), ("y", "<f8"), ("z", "<f8")]
    if normals is not None:
        columns += [("nx", "<f4"), ("ny", "<f4"), ("nz", "<f4")]
    if colors is not None:
        columns += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    kept = _ply_fields(fields or {}, {c for c, _ in columns} | {prop, *after})
    data = np.empty(points.shape[0], dtype=columns + [(p, a.dtype.newbyteorder("<"))
                                                      for p, a in kept.items()]
                    + [(prop, "<i4")] + [(p, "<i4") for p in after])
    for p, a in kept.items():
        data[p] = a
    for i, c in enumerate("xyz"):
        data[c] = points[:, i]
    if normals is not None:
        for i, c in enumerate(("nx", "ny", "nz")):
            data[c] = np.asarray(normals)[:, i]
    if colors is not None:
        rgb = np.round(np.clip(np.nan_to_num(np.asarray(colors, dtype=np.float64)), 0, 1)
                       * 255).astype(np.uint8)
        for i, c in enumerate(("red", "green", "blue")):
            data[c] = rgb[:, i]
    data[prop] = labels
    for p, a in after.items():
        data[p] = a
    buf = io.BytesIO()
    PlyData([PlyElement.describe(data, "vertex")], comments=["made by superfacets"]).write(buf)
    return buf.getvalue()


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
        mesh whose vertices were segmented), ``.pcd`` for a PCD input (in its
        encoding), ``.npy`` for NPY records (a structured array, ``(N,)`` or organized
        ``(H, W)``: its shape and fields kept, the labels one more ``int32`` field, as
        ``ros_numpy`` turns back into a ``PointCloud2``).
    source : str or os.PathLike
        The input file the labels are of.
    labels : (N,) int ndarray
        One label per point (vertex) in file order, ``-1`` for an invalid
        point; written as ``int32``.
    name : str, default ``'ClusterID'``
        The dimension's (LAS/LAZ) or field's (PCD) name; in a PLY the property is
        ``scalar_<name>``. An existing field of that name is overwritten; one of a type
        that cannot hold the labels (CloudCompare's float scalar fields, PDAL's unsigned
        ``ClusterID``) is made ``int32``.
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
        If the input cannot be read, or holds a field of that name that cannot be made
        to take the labels (a standard LAS dimension, a PCD field of several values).
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
    labels = _checked_labels(labels)
    ply_name = ply_field_name(name)  # (a word: checked here for both layouts)
    kind = records_kind(path, source)
    if kind is None:
        raise ParameterError(f"{path}: labels go into .las, .laz, .ply, .pcd or NPY records")
    if kind == "las" and len(name) > 32:
        raise ParameterError(f"a LAS dimension's name holds at most 32 characters: {name!r}")
    if kind == "las":
        content = _las_with(source, labels, name, compress=split_suffix(path)[0] == "laz")
    elif kind == "npy":
        content = _npy_with(source, labels, name)
    elif kind == "pcd":
        content = _pcd_with(source, labels, name)
    else:
        content = _ply_with(source, labels, ply_name)
    return save(path, content, outputs)


def _npy_records_of(source: Path) -> bool:
    """Whether the ``.npy`` file ``source`` holds records (a structured array); a file that
    cannot be read: no (its reader says why)."""
    _, comp = split_suffix(source)
    try:
        if comp is None:
            return bool(np.load(source, mmap_mode="r", allow_pickle=False).dtype.names)
        return bool(_npy_array(source).dtype.names)
    except Exception:  # noqa: BLE001 - numpy raises many types on damaged files
        return False


def _npy_array(source: Path) -> np.ndarray:
    """The array of a ``.npy`` file (optionally compressed)."""
    data = read_bytes(source, split_suffix(source)[1], "NPY file", bounded=False)
    try:
        return np.load(io.BytesIO(data), allow_pickle=False)
    except Exception as exc:  # noqa: BLE001 - numpy raises many types on damaged files
        raise MeshFormatError(f"{source}: cannot read NPY: {exc}") from None


def _npy_with(source: Path, labels: np.ndarray, name: str) -> bytes:
    """The bytes of a ``.npy`` of the records of ``source`` with ``labels`` as the field
    ``name`` (``int32``; one of that name replaced), in the records' shape."""
    arr = _npy_array(source)
    if labels.shape[0] != arr.size:
        raise _count_error(source, labels.shape[0], arr.size)
    if name in arr.dtype.names:
        _replaced(source, name)
    kept = [(f, arr.dtype.fields[f][0]) for f in arr.dtype.names if f != name]
    out = np.empty(arr.shape, dtype=np.dtype([*kept, (name, "<i4")]))
    for f, _ in kept:
        out[f] = arr[f]
    out[name] = labels.reshape(arr.shape)
    buf = io.BytesIO()
    np.save(buf, out, allow_pickle=False)
    return buf.getvalue()


def _replaced(source: Path, name: str) -> None:
    """Warn that the input's own field ``name`` (an earlier run's labels?) is replaced."""
    warnings.warn(f"{source.name} has a field {name}: the copy holds these labels in it "
                  "instead (the input keeps its own)", stacklevel=4)


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
        if not _holds_labels(dtype):
            if name not in las.point_format.extra_dimension_names:  # (a standard one)
                raise MeshFormatError(f"{source}: has a dimension {name!r} of type {dtype}, "
                                      "which cannot hold the labels (-1 and up to 2**31 - 1)")
            las.remove_extra_dim(name)  # (PDAL's uint64 ClusterID, a float field: retyped)
        _replaced(source, name)
    if name not in las.point_format.dimension_names:
        las.add_extra_dim(laspy.ExtraBytesParams(
            name=name, type=np.int32, description="superfacets label"))
    las[name] = labels
    _without_copc_index(las)
    buf = io.BytesIO()
    kw = {"laz_backend": laspy.LazBackend.LazrsParallel} if compress else {}
    try:
        las.write(buf, do_compress=compress, **kw)
    except Exception as exc:  # noqa: BLE001 - laspy raises many types
        raise MeshFormatError(f"{source}: cannot write a copy of this LAS/LAZ with the "
                              f"labels: {first_line(exc)}") from None
    return buf.getvalue()


def _without_copc_index(las) -> None:
    """Leave out a COPC file's index (its ``copc`` info VLR and hierarchy EVLR): it points
    into the source's compressed chunks, which a copy does not keep, so the copy is a plain
    LAZ of the same points in the same order (``pdal translate`` with ``writers.copc``
    indexes it again)."""
    from laspy.vlrs.vlrlist import VLRList

    las.vlrs = VLRList(v for v in las.vlrs if v.user_id != "copc")
    if las.header.evlrs is not None:
        las.header.evlrs = VLRList(v for v in las.header.evlrs if v.user_id != "copc")


def copc_said(source) -> str:
    """What the summary adds where ``source`` is a COPC file (cloud-optimized LAZ, as
    3DEP's and LiDAR HD's tiles come): its copy with the labels is a plain LAZ.

    Parameters
    ----------
    source : str or os.PathLike
        The input file.

    Returns
    -------
    str
        ``", its COPC index left out"`` for a COPC file, else ``""`` (also for a file
        that is not a LAS/LAZ or cannot be read).

    Raises
    ------
    Never: a file that cannot be read says nothing (reading it is refused elsewhere).

    Examples
    --------
    >>> copc_said("scan.xyz")
    ''
    """
    if split_suffix(Path(source))[0] not in ("las", "laz"):
        return ""
    try:
        import laspy

        with laspy.open(source) as f:
            copc = any(v.user_id == "copc" for v in f.header.vlrs)
    except Exception:  # noqa: BLE001 - a file that does not read says nothing more
        return ""
    return ", its COPC index left out" if copc else ""


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
    order = "<" if ply.byte_order in ("<", "=") else ">"
    if prop in names and not _holds_labels(np.dtype(data.dtype[prop])):
        # (CloudCompare saves its scalar fields as float: the property becomes an int)
        retyped = np.empty(len(data), dtype=[(n, order + "i4" if n == prop else
                                              data.dtype.fields[n][0]) for n in names])
        for n in names:
            if n != prop:
                retyped[n] = data[n]
        data = retyped
        vertex.properties = tuple(PlyProperty(prop, "int32") if p.name == prop else p
                                  for p in vertex.properties)
    if prop in names:
        _replaced(source, prop)
        data = data.copy()
        data[prop] = labels
        vertex.data = data
    else:
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


def _pcd_with(source: Path, labels: np.ndarray, name: str) -> bytes:
    """The PCD bytes of ``source`` with ``labels`` as the field ``name`` (``I 4``): its
    header's lines kept, the field's name, size, type and count added to theirs."""
    pypcd4 = extras.require("pypcd4", "writing PCD files")
    from .headers import check_pcd

    check_pcd(source)
    raw = read_bytes(source, None, "PCD file")
    try:
        pc = pypcd4.PointCloud.from_path(source)
        meta, data = pc.metadata, pc.pc_data
    except Exception as exc:  # noqa: BLE001 - pypcd4/pydantic raise many types
        raise MeshFormatError(f"{source}: cannot read PCD: {pcd_problem(exc)}") from None
    if len(data) != labels.shape[0]:
        raise _count_error(source, labels.shape[0], len(data))
    head, body = _pcd_split(source, raw)
    fields = list(meta.fields)
    if name in fields:
        at = fields.index(name)
        if meta.count[at] != 1:
            raise MeshFormatError(f"{source}: has a field {name!r} of type {meta.type[at]}"
                                  f"{meta.size[at]} x {meta.count[at]}, which cannot hold "
                                  "the labels (-1 and up to 2**31 - 1)")
        _replaced(source, name)
        if meta.type[at] != "I" or meta.size[at] < 4:  # (a float field: made I 4)
            head = [_pcd_retyped_line(line, at) for line in head]
            meta = meta.model_copy(update=dict(
                size=tuple(4 if i == at else v for i, v in enumerate(meta.size)),
                type=tuple("I" if i == at else v for i, v in enumerate(meta.type))))
        grown = np.empty(len(data), dtype=[(d[0], "<i4") if d[0] == name else d
                                           for d in data.dtype.descr])
        for n in data.dtype.names:
            if n != name:
                grown[n] = data[n]
        grown[name] = labels
        column = sum(meta.count[:at])
    else:
        head = [_pcd_grown_line(line, name) for line in head]
        grown = np.empty(len(data), dtype=data.dtype.descr + [(name, "<i4")])
        for n in data.dtype.names:
            grown[n] = data[n]
        grown[name] = labels
        column = None
    kind = meta.data.value
    if kind == "ascii":
        return _pcd_ascii(source, head, body, labels, column)
    if kind == "binary":
        return b"".join(head) + grown.tobytes()
    out = pypcd4.PointCloud(meta.model_copy(update=dict(
        fields=tuple(fields) if column is not None else (*fields, name),
        size=meta.size if column is not None else (*meta.size, 4),
        type=meta.type if column is not None else (*meta.type, "I"),
        count=meta.count if column is not None else (*meta.count, 1))), grown)
    buf = io.BytesIO()
    out.save(buf, encoding=meta.data)
    encoded = buf.getvalue()
    end = encoded.index(b"\nDATA ") + 1
    stop = encoded.index(b"\n", end) + 1
    # (pypcd4 writes a binary file where the records do not compress: its DATA line)
    return b"".join(head[:-1]) + encoded[end:stop] + encoded[stop:]


def _pcd_split(source: Path, raw: bytes) -> tuple[list[bytes], bytes]:
    """A PCD file's header lines (each with its line end; ``DATA`` last) and its body."""
    head, at = [], 0
    while at < len(raw):
        stop = raw.find(b"\n", at)
        stop = len(raw) if stop < 0 else stop + 1
        line = raw[at:stop]
        head.append(line)
        at = stop
        if line.split(b"#")[0].strip().upper().startswith(b"DATA"):
            return head, raw[at:]
    raise MeshFormatError(f"{source}: no DATA line ends the PCD header")


def _pcd_grown_line(line: bytes, name: str) -> bytes:
    """A PCD header line with the new field's entry added (``FIELDS``, ``SIZE``,
    ``TYPE``, ``COUNT``), else as it was."""
    words = line.split(b"#")[0].split()
    add = {b"FIELDS": name.encode(), b"SIZE": b"4", b"TYPE": b"I", b"COUNT": b"1"}.get(
        words[0].upper() if words else b"")
    if add is None:
        return line
    end = line[len(line.rstrip(b"\r\n")):]
    return line.rstrip(b"\r\n").rstrip() + b" " + add + (end or b"\n")


def _holds_labels(dtype: np.dtype) -> bool:
    """Whether a field of ``dtype`` holds every label (-1 and up to 2**31 - 1)."""
    return bool(np.issubdtype(dtype, np.signedinteger) and dtype.itemsize >= 4)


def _pcd_retyped_line(line: bytes, at: int) -> bytes:
    """A PCD header line with field ``at``'s ``SIZE`` made 4 and its ``TYPE`` I, else as
    it was."""
    words = line.split(b"#")[0].split()
    new = {b"SIZE": b"4", b"TYPE": b"I"}.get(words[0].upper() if words else b"")
    if new is None or len(words) <= at + 1:
        return line
    words[at + 1] = new
    end = line[len(line.rstrip(b"\r\n")):]
    return b" ".join(words) + (end or b"\n")


def _pcd_ascii(source: Path, head: list[bytes], body: bytes, labels: np.ndarray,
               column: int | None) -> bytes:
    """An ASCII PCD's data lines as they were, the label after each (or in place of its
    ``column``, where the field was there)."""
    lines = [ln for ln in body.splitlines() if ln.strip()]
    if len(lines) != labels.shape[0]:
        raise _count_error(source, labels.shape[0], len(lines))
    text = labels.astype(str)
    if column is None:
        rows = [ln.rstrip() + b" " + t.encode() for ln, t in zip(lines, text)]
    else:
        rows = []
        for ln, t in zip(lines, text):
            words = ln.split()
            words[column] = t.encode()
            rows.append(b" ".join(words))
    return b"".join(head) + b"\n".join(rows) + b"\n"
