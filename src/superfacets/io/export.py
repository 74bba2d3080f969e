"""Writing meshes, and coloured meshes that carry the segmentation.

- :func:`write_mesh`: OFF, ``.tri`` (triangles), PLY, OBJ (polygons kept),
  STL (triangles; polygons are fanned);
- :func:`write_colored_mesh`: one colour per superfacet, adjacent ones always
  different. PLY: polygons kept, face colours and an int32 face property
  ``label`` (read back with :func:`superfacets.read_labels`); GLB (glTF
  binary, for Blender, three.js and model viewers): triangles with per-vertex
  colours, each face's vertices its own so colours stay per face; OBJ with a
  material per colour (and its ``.mtl`` beside). ``vertex_colors=True`` gives
  a PLY with per-vertex colours the same way, for viewers that show no face
  colours.

Every write is atomic, and a file with a companion (OBJ + MTL) is written all
or nothing (:class:`superfacets.io.files.Outputs`).

The same result also goes to the libraries' objects: :func:`to_trimesh` and
:func:`to_pyvista` return them with the labels as face (cell) data and the
superfacet colours set.
"""

from __future__ import annotations

import io
from contextlib import nullcontext
from pathlib import Path

import numpy as np

from .._runtime import extras
from ..elements.kinds import kind_of
from ..elements.labels import check_labels
from ..errors import MeshFormatError
from ..inputs.convert import as_mesh
from .colors import face_colors, labelled_colors
from .files import Outputs, save, split_suffix
from .meshes import MESH_FORMATS
from .ply import ply_bytes, points_ply_bytes

__all__ = ["write_mesh", "write_colored_mesh", "write_colored_elements", "element_colors",
           "point_colors", "to_trimesh", "to_pyvista", "COLORED_FORMATS"]

#: Formats of :func:`write_colored_mesh`.
COLORED_FORMATS = ("ply", "glb", "obj")


def _rows(a: np.ndarray, fmt: str) -> str:
    buf = io.StringIO()
    np.savetxt(buf, a, fmt=fmt)
    return buf.getvalue()


def _off_face_lines(mesh) -> str:
    """OFF face lines: ``k i1 .. ik`` per face."""
    if mesh.is_triangular:
        return _rows(np.c_[np.full(mesh.n_faces, 3), mesh.faces], "%d")
    return "".join(f"{p.size} {' '.join(map(str, p.tolist()))}\n" for p in mesh.polygons())


def write_mesh(path, mesh, face_colors: np.ndarray | None = None, *,
               outputs: Outputs | None = None) -> Path:
    """Write a mesh: OFF, ``.tri``, PLY, OBJ or STL (optionally ``.gz``/``.xz``/``.bz2``).

    Parameters
    ----------
    path : str or os.PathLike
    mesh : Mesh, trimesh.Trimesh or (vertices, faces)
        Triangles or polygons (polygons are kept, except in ``.tri`` which
        refuses them and STL which fans them into triangles).
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
        If the format is unknown, colours are asked of a format other than
        PLY, or ``.tri`` is asked for polygons.

    Examples
    --------
    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "quad.off")
    >>> _ = write_mesh(p, ([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2, 3]]))
    >>> open(p).read().splitlines()[-1]
    '4 0 1 2 3'
    """
    mesh = as_mesh(mesh)
    path = Path(path)
    fmt, _ = split_suffix(path)
    if fmt not in MESH_FORMATS:
        raise MeshFormatError(f"{path}: unknown mesh format .{fmt}")
    if face_colors is not None and fmt != "ply":
        raise MeshFormatError(f"{path}: per-face colours need the .ply format")
    v = mesh.vertices
    if fmt == "off":
        head = f"OFF\n{len(v)} {mesh.n_faces} 0\n"
        return save(path, (head + _rows(v, "%.17g") + _off_face_lines(mesh)).encode("utf-8"),
                    outputs)
    if fmt == "tri":
        if not mesh.is_triangular:
            raise MeshFormatError(f"{path}: the .tri format holds triangles only; write .off, "
                                  ".ply or .obj for polygons")
        body = f"{len(v)}\n" + _rows(v, "%.17g") + f"{mesh.n_faces}\n" + _rows(mesh.faces, "%d")
        return save(path, body.encode("utf-8"), outputs)
    if fmt == "ply":
        return save(path, ply_bytes(v, mesh.corners, mesh.offsets, face_colors=face_colors),
                    outputs)
    if fmt == "obj":
        text = _rows(v, "v %.17g %.17g %.17g") + "".join(
            f"f {' '.join(str(i + 1) for i in poly.tolist())}\n" for poly in mesh.polygons())
        return save(path, text.encode("utf-8"), outputs)
    import trimesh  # STL: triangles

    tri, _ = mesh.triangulated()
    data = trimesh.Trimesh(vertices=v, faces=tri, process=False, validate=False).export(
        file_type="stl")
    return save(path, data, outputs)


def write_colored_mesh(path, mesh, labels, *, vertex_colors: bool = False,
                       outputs: Outputs | None = None) -> Path:
    """Write a mesh coloured by superfacet, carrying the labels where the format can.

    Adjacent superfacets always get clearly different colours (a greedy
    colouring of the superfacet adjacency graph,
    :func:`superfacets.io.colors.superfacet_colors`).

    Parameters
    ----------
    path : str or os.PathLike
        ``.ply`` (polygons kept, face colours and an int32 face property
        ``label``; MeshLab, Blender, Open3D, trimesh), ``.glb`` (triangles,
        colours per face through split vertices; Blender, three.js, viewers)
        or ``.obj`` (a material per colour, in ``path`` with ``.mtl``).
    mesh : Mesh, trimesh.Trimesh, pyvista.PolyData or (vertices, faces)
        Or a point cloud (``PointCloud``, an ``(N, 3)`` array, as ``--colored-mesh``
        writes it): a ``.ply`` of its points (:func:`write_colored_elements`).
    labels : (m,) int ndarray
        One label per face (per point of a cloud).
    vertex_colors : bool, default False
        PLY only: per-vertex colours instead of per-face ones (each face gets
        its own copy of its vertices, so the colours stay per face; the
        ``label`` face property is kept).
    outputs : Outputs, optional
        Stage the file(s) there (all or nothing with the others).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ParameterError
        If ``labels`` is not one integer per face (point).
    MeshFormatError
        On another format (a cloud: other than PLY), or ``vertex_colors`` with one other
        than PLY.

    Examples
    --------
    >>> import tempfile, os
    >>> from superfacets import read_labels
    >>> quads = ([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]],
    ...          [[0, 1, 2, 3], [1, 4, 5, 2]])
    >>> p = os.path.join(tempfile.mkdtemp(), "s.ply")
    >>> _ = write_colored_mesh(p, quads, [0, 1])
    >>> read_labels(p).tolist()
    [0, 1]
    """

    from ..elements.builders import elements_of, is_cloud

    if is_cloud(mesh):  # (a cloud's points, coloured as `segment --colored-mesh` does)
        return write_colored_elements(path, elements_of(mesh, "points"), labels,
                                      outputs=outputs)
    mesh = as_mesh(mesh)
    labels = check_labels(labels, mesh.n_faces, per="face")
    path = Path(path)
    fmt, comp = split_suffix(path)
    if fmt not in COLORED_FORMATS:
        raise MeshFormatError(f"{path}: a coloured mesh is written as "
                              f"{', '.join('.' + f for f in COLORED_FORMATS)}")
    if vertex_colors and fmt != "ply":
        raise MeshFormatError(f"{path}: per-vertex colours are written as .ply (GLB always "
                              "has them)")
    colors = face_colors(mesh, labels)
    if fmt == "ply":
        if not vertex_colors:
            data = ply_bytes(mesh.vertices, mesh.corners, mesh.offsets, face_colors=colors,
                             labels=labels)
        else:
            corners = np.asarray(mesh.corners)
            owner = np.repeat(np.arange(mesh.n_faces), mesh.face_sizes)
            data = ply_bytes(mesh.vertices[corners], np.arange(corners.size), mesh.offsets,
                             vertex_colors=colors[owner], labels=labels)
        return save(path, data, outputs)
    if fmt == "glb":
        import trimesh

        tri, owner = mesh.triangulated()
        split = mesh.vertices[tri.ravel()]
        tm = trimesh.Trimesh(vertices=split, faces=np.arange(split.shape[0]).reshape(-1, 3),
                             process=False, validate=False)
        rgba = np.c_[np.repeat(colors[owner], 3, axis=0), np.full(split.shape[0], 255)]
        tm.visual = trimesh.visual.ColorVisuals(tm, vertex_colors=rgba.astype(np.uint8))
        return save(path, tm.export(file_type="glb"), outputs)
    # OBJ with a material per colour, switched in face order
    mtl = path.name[:-len(comp)] if comp else path.name
    mtl = Path(mtl).with_suffix(".mtl").name
    palette, index = np.unique(colors, axis=0, return_inverse=True)
    index = index.ravel()
    lines = [f"# made by superfacets: {mesh.n_faces} faces, labels in the material names",
             f"mtllib {mtl}", _rows(mesh.vertices, "v %.17g %.17g %.17g").rstrip("\n")]
    current = -1
    for f, poly in enumerate(mesh.polygons()):
        if index[f] != current:
            current = index[f]
            lines.append(f"usemtl color{current}")
        lines.append("f " + " ".join(str(i + 1) for i in poly.tolist()))
    mat = "".join(f"newmtl color{i}\nKd {r / 255:.4f} {g / 255:.4f} {b / 255:.4f}\n"
                  for i, (r, g, b) in enumerate(palette.tolist()))
    with Outputs() if outputs is None else nullcontext(outputs) as out:
        out.write(path, ("\n".join(lines) + "\n").encode("utf-8"))
        out.write(path.with_name(mtl), mat.encode("utf-8"))
    return path



def element_colors(source, labels) -> np.ndarray:
    """Per-row RGB colours of vertex or point labels (adjacent segments differ; rows that
    are no element, and elements labelled below 0, grey).

    Parameters
    ----------
    source : ElementInput
        From :func:`superfacets.elements.builders.elements_of`.
    labels : (N,) int ndarray
        One label per input row (-1 where the row is not an element).

    Returns
    -------
    (N, 3) uint8 ndarray
    """

    g, index = source.graph, source.index
    ok = index >= 0
    per_element = np.zeros(g.n_elements, dtype=np.int64)
    per_element[index[ok]] = labels[ok]
    out = np.full((index.shape[0], 3), 128, dtype=np.uint8)
    out[ok] = labelled_colors(g, per_element)[index[ok]]
    return out


def point_colors(source, labels=None) -> np.ndarray:
    """Per-element RGB colours of point labels (grey without labels), for pictures.

    Parameters
    ----------
    source : ElementInput
        A point cloud's elements.
    labels : (N,) int ndarray, optional
        One label per point of the input.

    Returns
    -------
    (n_elements, 3) uint8 ndarray

    Raises
    ------
    ParameterError
        If ``labels`` is not one integer per point.
    """

    g, index = source.graph, source.index
    if labels is None:
        return np.full((g.n_elements, 3), 180, dtype=np.uint8)
    labels = check_labels(labels, index.shape[0], per="point")
    rows = np.flatnonzero(index >= 0)
    rgb = np.empty((g.n_elements, 3), dtype=np.uint8)
    rgb[index[rows]] = element_colors(source, labels)[rows]
    return rgb


def write_colored_elements(path, source, labels, *, outputs: Outputs | None = None) -> Path:
    """Write vertex or point labels as a coloured PLY.

    Points: a PLY of the points (file order, invalid rows kept) with
    ``red green blue`` and an int32 ``scalar_ClusterID`` per point. Vertices:
    the mesh with per-vertex colours and ``scalar_ClusterID``. CloudCompare
    loads ``scalar_ClusterID`` as the scalar field ``ClusterID``.

    Parameters
    ----------
    path : str or os.PathLike
        ``.ply``.
    source : ElementInput
        The segmented input (``kind`` ``"points"`` or ``"vertices"``).
    labels : (N,) int ndarray
        One label per point or vertex.
    outputs : Outputs, optional

    Returns
    -------
    pathlib.Path

    Raises
    ------
    MeshFormatError
        If ``path`` does not end in ``.ply``.
    """

    path = Path(path)
    fmt, _ = split_suffix(path)
    if fmt != "ply":
        raise MeshFormatError(f"{path}: coloured {source.graph.kind} are written as .ply")
    labels = check_labels(labels, source.n_rows, per=source.graph.element)
    colors = element_colors(source, labels)
    if kind_of(source.graph.kind).cloud:
        data = points_ply_bytes(source.source.points, colors, labels)
    else:
        mesh = source.source
        data = ply_bytes(mesh.vertices, mesh.corners, mesh.offsets, vertex_colors=colors,
                         vertex_labels=labels)
    return save(path, data, outputs)


def _labelled(mesh, labels):
    labels = check_labels(labels, mesh.n_faces, per="face")
    return labels, face_colors(mesh, labels)


def to_trimesh(mesh, labels=None):
    """A ``trimesh.Trimesh`` of the mesh, with the labels and colours per face.

    Polygons are split into the triangles of their fans (trimesh holds
    triangles); ``face_attributes['label']`` and the face colours follow, and
    ``metadata['face_of_triangle']`` maps each triangle to its polygon.

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh, pyvista.PolyData or (vertices, faces)
    labels : (m,) int ndarray, optional

    Returns
    -------
    trimesh.Trimesh

    Examples
    --------
    >>> box = trimesh.creation.box()
    >>> t = to_trimesh(box, list(range(12)))
    >>> t.face_attributes["label"][:3].tolist()
    [0, 1, 2]
    """
    import trimesh

    mesh = as_mesh(mesh)
    tri, owner = mesh.triangulated()
    out = trimesh.Trimesh(vertices=np.array(mesh.vertices), faces=np.array(tri), process=False,
                          validate=False)
    out.metadata["face_of_triangle"] = owner
    if labels is not None:
        labels, colors = _labelled(mesh, labels)
        out.face_attributes["label"] = labels[owner]
        out.visual.face_colors = colors[owner]
    return out


def to_pyvista(mesh, labels=None):
    """A ``pyvista.PolyData`` of the mesh (polygons kept), labels and colours per cell.

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh, pyvista.PolyData or (vertices, faces)
    labels : (m,) int ndarray, optional
        Stored as ``cell_data['label']``, colours as ``cell_data['rgb']``.

    Returns
    -------
    pyvista.PolyData

    Raises
    ------
    MissingExtraError
        Without the ``render`` extra.
    """

    pv = extras.require("pyvista", "to_pyvista")
    mesh = as_mesh(mesh)
    cells = np.insert(np.asarray(mesh.corners), np.asarray(mesh.offsets)[:-1], mesh.face_sizes)
    poly = pv.PolyData(np.array(mesh.vertices), cells)
    if labels is not None:
        labels, colors = _labelled(mesh, labels)
        poly.cell_data["label"] = labels
        poly.cell_data["rgb"] = colors
    return poly
