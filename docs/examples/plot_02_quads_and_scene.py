"""
A quad mesh and a glTF scene
============================

Polygons are segmented as they are: one label per polygon, never triangulated. A scene
(glTF, OBJ with ``o`` objects) is read as one mesh, object after object; each object
can also be segmented on its own, ``k`` shared out by area.
"""

from pathlib import Path
from tempfile import mkdtemp

import matplotlib.pyplot as plt
import numpy as np
import trimesh

from superfacets import Mesh, read_mesh, segment
from superfacets.api.scenes import segment_objects
from superfacets.viz.render import render_panel

# a wavy quad grid: 40 x 40 quads
n = 41
x, y = np.meshgrid(np.linspace(0, 2, n), np.linspace(0, 2, n))
z = 0.15 * np.sin(3 * x) * np.cos(2 * y)
vertices = np.c_[x.ravel(), y.ravel(), z.ravel()]
i = np.arange(n * n).reshape(n, n)
quads = np.c_[i[:-1, :-1].ravel(), i[:-1, 1:].ravel(), i[1:, 1:].ravel(), i[1:, :-1].ravel()]
grid = Mesh(vertices, quads)
quad_labels = segment(grid, 30).labels
print(f"{grid.n_faces} quads -> {quad_labels.max() + 1} superfacets, one label per quad")

# a scene of two objects, written as glTF and read back
scene = trimesh.Scene({"box": trimesh.creation.box(extents=(1, 1, 1)),
                       "ball": trimesh.creation.icosphere(subdivisions=3).apply_translation(
                           (2, 0, 0))})
path = Path(mkdtemp()) / "scene.glb"
scene.export(path)
mesh = read_mesh(path)
print("objects:", [name for name, *_ in mesh.objects])
scene_labels, per_object = segment_objects(mesh, 24)
print("superfacets per object:", [r.n_segments for r in per_object])

image = render_panel([(grid, quad_labels, "quads"), (mesh, scene_labels, "scene, per object")],
                     size=(480, 400), up="z")
plt.figure(figsize=(9.6, 4))
plt.imshow(image)
plt.axis("off")
plt.show()
