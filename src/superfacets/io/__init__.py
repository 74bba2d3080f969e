"""Reading and writing meshes and label files (see the modules for each family).

- :mod:`.meshes`: :func:`read_mesh` (triangles or polygons, in file order);
- :mod:`.export`: :func:`write_mesh`, :func:`write_colored_mesh` (PLY with labels, GLB, OBJ);
- :mod:`.labels`: :func:`read_labels` (``.seg``, or a coloured PLY), :func:`write_labels`;
- :mod:`.ply`: the binary PLY writer and the label reader;
- :mod:`.files`: compression by suffix, :func:`atomic_write` and all-or-nothing outputs.
"""

from .files import atomic_write
from .labels import read_labels, write_labels
from .export import write_colored_mesh, write_mesh
from .meshes import MESH_FORMATS, read_mesh

__all__ = ["read_mesh", "write_mesh", "read_labels", "write_labels", "write_colored_mesh",
           "atomic_write", "MESH_FORMATS"]
