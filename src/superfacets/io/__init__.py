"""Reading and writing meshes and label files (see the modules for each family).

- :mod:`.meshes`: :func:`read_mesh`, :func:`write_mesh`, :func:`write_colored_mesh`;
- :mod:`.labels`: :func:`read_labels`, :func:`write_labels` (``.seg``);
- :mod:`.files`: compression by suffix and :func:`atomic_write`.
"""

from .files import atomic_write
from .labels import read_labels, write_labels
from .meshes import MESH_FORMATS, read_mesh, write_colored_mesh, write_mesh

__all__ = ["read_mesh", "write_mesh", "read_labels", "write_labels", "write_colored_mesh",
           "atomic_write", "MESH_FORMATS"]
