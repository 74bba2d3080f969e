"""Meshes from and to the libraries people use: trimesh, PyVista, Open3D.

:func:`superfacets.mesh.as_mesh` accepts each library's mesh type through the
functions here; none of the libraries is imported unless such an object is
given (Open3D is never a dependency). :func:`to_trimesh` and
:func:`to_pyvista` return the library's object with the labels as face (cell)
data and the superfacet colours set.

Scenes (several objects, e.g. a glTF/GLB file or a ``trimesh.Scene``) are
joined into one mesh: the objects in the order of the scene's geometry nodes
as trimesh lists them (for glTF, the file's node order), each with its node's
transform applied; faces keep their order within an object; the mesh's
``objects`` holds each object's name and face range.
"""

from __future__ import annotations

import numpy as np

from .errors import InvalidMeshError

__all__ = ["from_library", "mesh_from_scene", "to_trimesh", "to_pyvista"]


def _module(obj) -> str:
    return type(obj).__module__.split(".")[0]


def from_library(obj, name: str = ""):
    """A :class:`~superfacets.mesh.Mesh` from a trimesh, PyVista or Open3D object, or None
    when ``obj`` is none of them.

    Raises
    ------
    InvalidMeshError
        On a scene without geometry, a PolyData without polygons, an Open3D
        object without triangles.
    """
    from .mesh import Mesh

    mod = _module(obj)
    if mod == "trimesh" and type(obj).__name__ == "Scene":
        return mesh_from_scene(obj, name)
    if mod == "pyvista" or (mod == "vtkmodules" and hasattr(obj, "faces")):
        if np.asarray(obj.faces).size == 0:
            raise InvalidMeshError(f"{name or 'PolyData'}: no polygons (points or lines only)")
        cells = np.asarray(obj.faces, dtype=np.int64)
        return Mesh(np.asarray(obj.points, dtype=np.float64), _split_cells(cells), name=name)
    if mod == "open3d":
        if hasattr(obj, "triangles"):
            tri = np.asarray(obj.triangles, dtype=np.int64)
            if tri.size == 0:
                raise InvalidMeshError(f"{name or 'open3d mesh'}: no triangles")
            return Mesh(np.asarray(obj.vertices, dtype=np.float64), tri, name=name)
        raise InvalidMeshError(f"{type(obj).__name__}: an Open3D point cloud or other "
                               "geometry, not a triangle mesh")
    return None


def _split_cells(cells: np.ndarray):
    """PyVista's flat ``[k, i1..ik, k, ...]`` face array as an (m, 3) array or polygons."""
    if cells.size % 4 == 0 and (cells[::4] == 3).all():
        return cells.reshape(-1, 4)[:, 1:]
    polys, i = [], 0
    while i < cells.size:
        k = int(cells[i])
        polys.append(cells[i + 1:i + 1 + k])
        i += k + 1
    return polys


def mesh_from_scene(scene, name: str = ""):
    """Join the objects of a ``trimesh.Scene`` into one :class:`~superfacets.mesh.Mesh`.

    Objects come in the order of ``scene.graph.nodes_geometry``, each
    transformed by its node; their names and face ranges are in
    ``mesh.objects``. Point clouds and paths in the scene are skipped.

    Raises
    ------
    InvalidMeshError
        If the scene holds no triangle mesh.
    """
    from .mesh import Mesh

    vs, fs, objects, base, start = [], [], [], 0, 0
    for node in scene.graph.nodes_geometry:
        transform, key = scene.graph[node]
        geom = scene.geometry[key]
        faces = getattr(geom, "faces", None)
        if faces is None or len(faces) == 0:
            continue
        v = np.asarray(geom.vertices, dtype=np.float64)
        v = v @ np.asarray(transform)[:3, :3].T + np.asarray(transform)[:3, 3]
        vs.append(v)
        fs.append(np.asarray(faces, dtype=np.int64) + base)
        objects.append((str(node), start, start + len(faces)))
        base += v.shape[0]
        start += len(faces)
    if not fs:
        raise InvalidMeshError(f"{name or 'scene'}: the scene holds no mesh with faces")
    return Mesh(np.concatenate(vs), np.concatenate(fs), name=name, objects=tuple(objects))


def _labelled(mesh, labels):
    from .colors import face_colors
    from .labels import check_labels

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
    >>> import trimesh
    >>> box = trimesh.creation.box()
    >>> t = to_trimesh(box, list(range(12)))
    >>> t.face_attributes["label"][:3].tolist()
    [0, 1, 2]
    """
    import trimesh

    from .mesh import as_mesh

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
    from .extras import require
    from .mesh import as_mesh

    pv = require("pyvista", "to_pyvista")
    mesh = as_mesh(mesh)
    cells = np.insert(np.asarray(mesh.corners), np.asarray(mesh.offsets)[:-1], mesh.face_sizes)
    poly = pv.PolyData(np.array(mesh.vertices), cells)
    if labels is not None:
        labels, colors = _labelled(mesh, labels)
        poly.cell_data["label"] = labels
        poly.cell_data["rgb"] = colors
    return poly
