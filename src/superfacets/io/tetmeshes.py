"""Tetrahedral meshes in and labels out, through meshio (the ``volumes`` extra).

Read: Gmsh ``.msh``, VTK ``.vtk``/``.vtu``, MEDIT ``.mesh`` (and the other
volume formats meshio reads), the ``tetra`` cells in file order; other cell
kinds (the surface triangles Gmsh writes beside, lines, points) are left out.
The first integer cell data of the tetrahedra (Gmsh's ``gmsh:physical``,
MEDIT's ``medit:ref``, else any) become the materials. Write: the mesh with
the labels as cell data ``superfacet`` (one per tetrahedron, -1 nowhere),
atomically.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .._runtime import extras
from ..elements.labels import check_labels
from ..errors import MemoryLimitError, MeshFormatError
from ..inputs.tetmesh import TetMesh
from .files import atomic_write, decompressed, split_suffix, user_path

__all__ = ["read_volume", "write_volume_labels", "volume_field", "VOLUME_FORMATS"]

#: Suffixes read as tetrahedral meshes (by ``segment`` and :func:`read_volume`).
VOLUME_FORMATS = ("msh", "vtk", "vtu", "mesh")
_PREFERRED = ("gmsh:physical", "medit:ref", "CellEntityIds", "material", "materials")


def read_volume(path):
    """Read the tetrahedra of a volume mesh file.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    TetMesh
        Vertices and tetrahedra in file order, the materials when the file
        has integer cell data on its tetrahedra.

    Raises
    ------
    FileNotFoundError, IsADirectoryError
    MeshFormatError
        If meshio cannot read it, or it holds no tetrahedron.
    InvalidMeshError
        As :class:`~superfacets.inputs.tetmesh.TetMesh`.
    MissingExtraError
        Without meshio (``pip install 'superfacets[volumes]'``).

    Examples
    --------
    >>> from superfacets import TetMesh
    >>> t = TetMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 1, 2, 3]])
    >>> _ = write_volume_labels("t.vtu", t, [0])
    >>> read_volume("t.vtu").n_tets
    1
    """

    path = user_path(path)
    m, blocks = _tetra_blocks(path)
    tets = np.concatenate([m.cells[i].data for i in blocks])
    materials = None
    names = [n for n in _PREFERRED if n in m.cell_data] + [n for n in m.cell_data
                                                            if n not in _PREFERRED]
    for name in names:
        data = [np.asarray(m.cell_data[name][i]).reshape(-1) for i in blocks]
        if all(np.issubdtype(d.dtype, np.integer) for d in data):
            materials = np.concatenate(data)
            break
    return TetMesh(np.asarray(m.points, dtype=np.float64)[:, :3] if m.points.shape[1] >= 3
                   else m.points, tets, materials=materials, name=path.name)


def _tetra_blocks(path: Path):
    """The meshio mesh of a volume file and the indices of its ``tetra`` cell blocks."""
    meshio = extras.require("meshio", "reading tetrahedral meshes")
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a directory")
    import contextlib
    import io
    import tempfile

    said = io.StringIO()
    fmt, comp = split_suffix(path)
    try:  # meshio prints its complaints, and exits on a file no reader takes
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said), \
                tempfile.TemporaryDirectory(prefix="superfacets-") as tmp:
            source = path
            if comp is not None:  # (meshio reads names: the content, checked, under one)
                source = Path(tmp) / f"volume.{fmt}"
                source.write_bytes(decompressed(path, comp))
            m = meshio.read(source)
    except (MeshFormatError, MemoryLimitError):
        raise
    except (Exception, SystemExit) as exc:  # noqa: BLE001 - meshio raises many types
        msg = (str(exc).strip() if not isinstance(exc, SystemExit) else "") or \
            " ".join(said.getvalue().split()) or type(exc).__name__
        msg = re.sub(r"\S*superfacets-[^/\s]+/volume\.\w+", path.name, msg)  # (not ours)
        raise MeshFormatError(f"{path}: cannot read it as a volume mesh: "
                              f"{msg.splitlines()[0][:300]}") from None
    blocks = [i for i, c in enumerate(m.cells) if c.type == "tetra"]
    if not blocks:
        kinds = ", ".join(sorted({c.type for c in m.cells})) or "none"
        raise MeshFormatError(f"{path}: no tetrahedra (cells: {kinds}); superfacets segments "
                              "tetrahedral meshes (or surfaces: superfacets segment MESH)")
    return m, blocks


def volume_field(path, name: str) -> tuple[list[str], np.ndarray | None]:
    """The cell data ``name`` of a volume mesh's tetrahedra, in file order (the rows of
    :func:`read_volume`), with the names of the file's cell data.

    Parameters
    ----------
    path : str or os.PathLike
    name : str
        A cell data name: Gmsh's ``gmsh:physical``, MEDIT's ``medit:ref``, VTK's
        arrays (``CellEntityIds``, ``superfacet`` as :func:`write_volume_labels`
        writes it).

    Returns
    -------
    names : list of str
    values : (T,) ndarray or None
        One per tetrahedron; None where the file has no such cell data.

    Raises
    ------
    FileNotFoundError, IsADirectoryError, MeshFormatError, MissingExtraError
        As :func:`read_volume`; a MeshFormatError too where the data holds more than one
        value per tetrahedron.

    Examples
    --------
    >>> from superfacets import TetMesh
    >>> t = TetMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 1, 2, 3]])
    >>> _ = write_volume_labels("t.vtu", t, [3])
    >>> volume_field("t.vtu", "superfacet")[1].tolist()
    [3]
    """
    path = Path(path)
    m, blocks = _tetra_blocks(path)
    names = list(m.cell_data)
    if name not in m.cell_data:
        return names, None
    data = [np.asarray(m.cell_data[name][i]) for i in blocks]
    if any(d.shape[0] != m.cells[i].data.shape[0] or d.size != d.shape[0]
           for d, i in zip(data, blocks)):
        raise MeshFormatError(f"{path}: cell data {name!r} holds more than one value per "
                              "tetrahedron")
    return names, np.concatenate([d.reshape(-1) for d in data])


def write_volume_labels(path, mesh, labels, *, outputs=None) -> Path:
    """Write a tetrahedral mesh with one label per tetrahedron as cell data ``superfacet``.

    Parameters
    ----------
    path : str or os.PathLike
        Any volume format meshio writes (``.vtu`` for ParaView, ``.msh``, ...).
    mesh : TetMesh
    labels : (m,) int ndarray
    outputs : Outputs, optional
        Write as part of an all-or-nothing group.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ParameterError
        If the labels are not one per tetrahedron.
    MissingExtraError
        Without meshio.

    Examples
    --------
    >>> from superfacets import TetMesh
    >>> t = TetMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 1, 2, 3]])
    >>> write_volume_labels("part.vtu", t, [0]).name
    'part.vtu'
    """
    import tempfile

    if not isinstance(mesh, TetMesh):
        raise TypeError(f"write_volume_labels writes a superfacets.TetMesh, got "
                        f"{type(mesh).__name__} (read_volume gives one)")
    meshio = extras.require("meshio", "writing tetrahedral meshes")
    lab = np.asarray(check_labels(labels, mesh.n_tets, per="tetrahedron"), dtype=np.int64)
    path = Path(path)
    cell_data = {"superfacet": [lab]}
    if mesh.materials is not None:
        cell_data["material"] = [mesh.materials]
    out = meshio.Mesh(np.asarray(mesh.vertices), [("tetra", np.asarray(mesh.tets))],
                      cell_data=cell_data)
    with tempfile.TemporaryDirectory() as tmp:  # meshio writes by name: write, then move
        t = Path(tmp) / path.name
        out.write(t)
        data = t.read_bytes()
    return outputs.write(path, data) if outputs is not None else atomic_write(path, data)
