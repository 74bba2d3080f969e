"""Meshes from what people have: arrays, trimesh, PyVista, Open3D objects.

:func:`as_mesh` is the one place that turns an input into a validated
:class:`~superfacets.inputs.mesh.Mesh`; it accepts each library's mesh type through
the functions here. None of the libraries is imported unless such an object
is given (Open3D is never a dependency). The other direction (a result as a
trimesh or PyVista object, labels and colours set) is
:func:`superfacets.io.export.to_trimesh` and :func:`~superfacets.io.export.to_pyvista`.

Scenes (several objects, e.g. a glTF/GLB file or a ``trimesh.Scene``) are
joined into one mesh: the objects in the order of the scene's geometry nodes
as trimesh lists them (for glTF, the file's node order), each with its node's
transform applied; faces keep their order within an object; the mesh's
``objects`` holds each object's name and face range.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidMeshError
from .mesh import Mesh
from .rgb import unit_colors

__all__ = ["as_mesh", "from_library", "mesh_from_scene", "trimesh_colors"]


def as_mesh(mesh, name: str = "") -> Mesh:
    """Turn a mesh given in any accepted form into a validated :class:`Mesh`.

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or Scene, pyvista.PolyData, open3d mesh, or tuple
        A mesh, or ``(vertices, faces)``:
        ``vertices`` is ``(n, 3)`` float; ``faces`` an ``(m, k)`` int array
        (triangles: ``k = 3``) or a list of vertex index sequences (polygons).
        A :class:`Mesh` is returned as is (its caches are reused); a scene's
        objects are joined (:func:`mesh_from_scene`).
    name : str, optional
        Name used in error messages.

    Returns
    -------
    Mesh

    Raises
    ------
    TypeError
        If ``mesh`` is none of the accepted forms.
    InvalidMeshError
        If the arrays are invalid (see :class:`Mesh`), a scene holds no mesh,
        or a PolyData no polygon.

    Examples
    --------
    >>> as_mesh(([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]))
    Mesh(3 vertices, 1 face: triangles)
    """
    if isinstance(mesh, Mesh):
        return mesh
    if isinstance(mesh, (tuple, list)) and len(mesh) == 2:
        return Mesh(mesh[0], mesh[1], name=name)
    converted = from_library(mesh, name)
    if converted is not None:
        return converted
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):  # trimesh.Trimesh and alike
        return Mesh(np.asarray(mesh.vertices), np.asarray(mesh.faces), name=name,
                    **trimesh_colors(mesh))
    got = type(mesh).__name__
    if hasattr(mesh, "n_tets"):  # (a volume where a surface is needed: say what takes it)
        raise TypeError("this takes a surface or a point cloud, not a tetrahedral mesh: "
                        "segment(volume, k) segments it, write_volume_labels writes its labels "
                        "as cell data, cut_surface(volume, labels) gives its cut to draw")
    if isinstance(mesh, np.ndarray):  # (an array of another shape: say which)
        got = f"an array of shape {mesh.shape}"
    elif isinstance(mesh, (list, tuple)):
        got += f" of {len(mesh)} items"
    elif type(mesh).__name__ == "DataFrame":
        got += f" with columns {', '.join(map(str, list(mesh.columns)[:12]))}"
    raise TypeError(
        "mesh must be a superfacets.Mesh, a trimesh.Trimesh or Scene, a pyvista.PolyData, an "
        "open3d TriangleMesh or a (vertices, faces) pair (a point cloud: a PointCloud, an "
        f"(N, 3) array or list, or a DataFrame of x, y, z columns), got {got}"
    )


def _module(obj) -> str:
    return type(obj).__module__.split(".")[0]


def from_library(obj, name: str = ""):
    """A :class:`~superfacets.inputs.mesh.Mesh` from a trimesh, PyVista or Open3D object, or None
    when ``obj`` is none of them.

    Raises
    ------
    InvalidMeshError
        On a scene without geometry, a PolyData without polygons, an Open3D
        object without triangles.

    Parameters
    ----------
    obj : object
    name : str, optional
        For messages.

    Returns
    -------
    Mesh or None

    Examples
    --------
    >>> from_library(trimesh.Scene(trimesh.creation.box())).n_faces, from_library([1, 2]) is None
    (12, True)
    """
    mod = _module(obj)
    if mod == "trimesh" and type(obj).__name__ == "Scene":
        return mesh_from_scene(obj, name)
    if mod == "pyvista" or (mod == "vtkmodules" and hasattr(obj, "faces")):
        if np.asarray(obj.faces).size == 0:
            raise InvalidMeshError(f"{name or 'PolyData'}: no polygons (points or lines only)")
        cells = np.asarray(obj.faces, dtype=np.int64)
        return Mesh(np.asarray(obj.points, dtype=np.float64), _split_cells(cells), name=name,
                    colors=_pyvista_colors(getattr(obj, "point_data", None)),
                    face_colors=_pyvista_colors(getattr(obj, "cell_data", None)))
    if mod == "open3d" and hasattr(obj, "triangle"):  # a tensor mesh (open3d.t.geometry)
        tri = obj.triangle.indices.numpy().astype(np.int64) if "indices" in obj.triangle \
            else np.zeros((0, 3), dtype=np.int64)
        if tri.size == 0:
            raise InvalidMeshError(f"{name or 'open3d mesh'}: no triangles")
        vc = obj.vertex.colors.numpy() if "colors" in obj.vertex else None
        return Mesh(obj.vertex.positions.numpy().astype(np.float64), tri, name=name,
                    colors=None if vc is None or not vc.size else vc.astype(np.float64))
    if mod == "open3d":
        if hasattr(obj, "triangles"):
            tri = np.asarray(obj.triangles, dtype=np.int64)
            if tri.size == 0:
                raise InvalidMeshError(f"{name or 'open3d mesh'}: no triangles")
            vc = np.asarray(getattr(obj, "vertex_colors", ()), dtype=np.float64)
            colors = vc if vc.size else None  # Open3D: an empty vector without colours
            return Mesh(np.asarray(obj.vertices, dtype=np.float64), tri, name=name,
                        colors=colors)
        raise InvalidMeshError(f"{type(obj).__name__}: an Open3D point cloud or other "
                               "geometry, not a triangle mesh")
    return None


def trimesh_colors(obj) -> dict:
    """``colors`` / ``face_colors`` of a ``trimesh.Trimesh`` whose visual holds vertex or
    face colours (not a texture, not trimesh's default grey), in ``[0, 1]``; {} else.

    Parameters
    ----------
    obj : trimesh.Trimesh

    Returns
    -------
    dict
        ``{"colors": (n, 3) float}`` or ``{"face_colors": (m, 3) float}``, or ``{}``.

    Raises
    ------
    TypeError
        Never: an object without colours gives ``{}``.

    Examples
    --------
    >>> trimesh_colors(trimesh.creation.box())
    {}
    """

    visual = getattr(obj, "visual", None)
    kind = getattr(visual, "kind", None)
    if kind == "vertex":
        return {"colors": unit_colors(np.asarray(visual.vertex_colors)[:, :3])}
    if kind == "face":
        return {"face_colors": unit_colors(np.asarray(visual.face_colors)[:, :3])}
    return {}


#: Names of a PyVista array read as colours (any case): PyVista's PLY reader names
#: vertex colours ``RGB``.
PYVISTA_COLORS = ("rgb", "rgba", "colors", "colours")


def _pyvista_colors(data) -> np.ndarray | None:
    """The first array of ``point_data`` / ``cell_data`` named as colours (:data:
    `PYVISTA_COLORS`), of 3 or 4 columns, as RGB in ``[0, 1]``; None without one."""

    for key in ([] if data is None else list(data.keys())):
        a = np.asarray(data[key])
        if str(key).lower() in PYVISTA_COLORS and a.ndim == 2 and a.shape[1] in (3, 4):
            return unit_colors(a[:, :3])
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
    """Join the objects of a ``trimesh.Scene`` into one :class:`~superfacets.inputs.mesh.Mesh`.

    Objects come in the order of ``scene.graph.nodes_geometry``, each
    transformed by its node; their names and face ranges are in
    ``mesh.objects``. Point clouds and paths in the scene are skipped.

    Raises
    ------
    InvalidMeshError
        If the scene holds no triangle mesh.

    Parameters
    ----------
    scene : trimesh.Scene
    name : str, optional

    Returns
    -------
    Mesh

    Examples
    --------
    >>> scene = trimesh.Scene({"a": trimesh.creation.box(), "b": trimesh.creation.box()})
    >>> [name for name, *_ in mesh_from_scene(scene).objects]
    ['a', 'b']
    """
    vs, fs, objects, base, start = [], [], [], 0, 0
    cols: dict[str, list] = {"colors": [], "face_colors": []}
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
        for key, a in trimesh_colors(geom).items():
            cols[key].append(a)
        objects.append((str(node), start, start + len(faces)))
        base += v.shape[0]
        start += len(faces)
    if not fs:
        raise InvalidMeshError(f"{name or 'scene'}: the scene holds no mesh with faces")
    # colours where every object has them (of the same kind)
    colors = {key: np.concatenate(a) for key, a in cols.items() if a and len(a) == len(fs)}
    return Mesh(np.concatenate(vs), np.concatenate(fs), name=name, objects=tuple(objects),
                **colors)
