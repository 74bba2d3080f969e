"""Reading and writing meshes and label files (see the modules for each family).

- :mod:`.meshes`: :func:`read_mesh` (triangles or polygons, in file order);
- :mod:`.clouds`: :func:`read_cloud` (PLY without faces, PCD, XYZ/PTS/TXT, NPY, LAS/LAZ);
- :mod:`.export`: :func:`write_mesh`, :func:`write_colored_mesh` (PLY with labels, GLB, OBJ),
  :func:`to_trimesh` and :func:`to_pyvista` (a result as the libraries' objects);
- :mod:`.tetmeshes`: :func:`read_volume`, :func:`write_volume_labels` (tetrahedra, meshio);
- :mod:`.labels`: :func:`read_labels` (``.seg``, or a coloured PLY), :func:`write_labels`;
- :mod:`.ply`: the binary PLY writer and the label reader;
- :mod:`.files`: compression by suffix, :func:`atomic_write` and all-or-nothing outputs.
"""

from pathlib import Path

from ..errors import InvalidCloudError, InvalidMeshError, MeshFormatError
from .clouds import CLOUD_FORMATS, is_cloud_file, read_cloud, scene_file
from .export import to_pyvista, to_trimesh, write_colored_mesh, write_mesh
from .files import atomic_write, format_hint, split_suffix, user_path
from .labels import read_labels, write_labels, write_segindices
from .meshes import MESH_FORMATS, read_mesh
from .tetmeshes import VOLUME_FORMATS, read_volume, write_volume_labels


def input_kind(path) -> str:
    """What a file holds, decided by its name and, for a PLY, OFF or OBJ, its content:
    ``"volume"`` (a tetrahedral mesh: ``.msh``, ``.vtk``, ``.vtu``, ``.mesh``), ``"cloud"``
    (a cloud format, or a PLY, OFF or OBJ of vertices and no face) or ``"mesh"``. Every
    command and reader asks here.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    str

    Raises
    ------
    MeshFormatError
        If a PLY header cannot be read.

    Examples
    --------
    >>> input_kind("part.msh"), input_kind("scan.laz"), input_kind("bunny.off.gz")
    ('volume', 'cloud', 'mesh')
    """
    if split_suffix(Path(path))[0] in VOLUME_FORMATS:
        return "volume"
    return "cloud" if is_cloud_file(path) else "mesh"


def read_input(path):
    """A mesh (:func:`read_mesh`), a point cloud (:func:`read_cloud`: a cloud format, or a
    PLY, OBJ or OFF without faces) or a tetrahedral mesh (:func:`read_volume`: ``.msh``, ``.vtk``,
    ``.vtu``, ``.mesh``), by the file.

    Parameters
    ----------
    path : str or os.PathLike
        A mesh or point-cloud file (optionally ``.gz``, ``.xz``, ``.bz2``).

    Returns
    -------
    Mesh, PointCloud or TetMesh

    Raises
    ------
    FileNotFoundError, MeshFormatError, InvalidMeshError, InvalidCloudError
        As :func:`read_mesh` and :func:`read_cloud`; MeshFormatError also for a suffix no
        reader takes (every format named) or ``-`` (standard input).

    Examples
    --------
    >>> _ = trimesh.creation.box().export("box.ply")
    >>> np.save("points.npy", np.random.default_rng(0).random((20, 3)))
    >>> type(read_input("box.ply")).__name__, type(read_input("points.npy")).__name__
    ('Mesh', 'PointCloud')
    """

    path = scene_file(user_path(path)) if str(path) != "-" else Path(path)
    fmt = split_suffix(path)[0]
    if fmt not in (*MESH_FORMATS, *CLOUD_FORMATS, *VOLUME_FORMATS):
        what = "standard input is not read (a format is told by its suffix): save it to a " \
            "file" if str(path) == "-" else f"unknown format {'.' + fmt if fmt else '(no suffix)'}"
        raise MeshFormatError(
            f"{path}: {what}; meshes: {', '.join('.' + f for f in MESH_FORMATS)} (optionally "
            f".gz/.xz/.bz2); point clouds: {', '.join('.' + f for f in CLOUD_FORMATS)}, or "
            ".ply, .obj, .off without faces; tetrahedral meshes: "
            f"{', '.join('.' + f for f in VOLUME_FORMATS)}")
    try:
        kind = input_kind(path)
        return (read_volume(path) if kind == "volume" else read_cloud(path) if kind == "cloud"
                else read_mesh(path))
    except (MeshFormatError, InvalidMeshError, InvalidCloudError) as exc:
        raise type(exc)(str(exc) + format_hint(path)) from None



__all__ = ["input_kind", "read_mesh", "write_mesh", "read_labels", "write_labels",
           "write_colored_mesh", "atomic_write", "MESH_FORMATS", "read_cloud", "read_input",
           "CLOUD_FORMATS", "is_cloud_file", "write_segindices", "to_trimesh", "to_pyvista",
           "read_volume", "write_volume_labels", "VOLUME_FORMATS"]
