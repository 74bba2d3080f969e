"""
A tetrahedral mesh
==================

The paper's other future work: the same method on the tetrahedra of a volume mesh
(their adjacency through shared triangles, volumes as sizes). With ``beta`` the
materials of the cells (Gmsh physical groups) join the weights as features.
"""

import matplotlib.pyplot as plt
import numpy as np
from scipy.spatial import Delaunay

from superfacets import TetMesh, segment
from superfacets.inputs.tetmesh import cut_surface
from superfacets.viz.render import render

rng = np.random.default_rng(0)
g = np.linspace(0.0, 1.0, 15)
points = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
inside = ((points > 0) & (points < 1)).all(axis=1)
points[inside] += rng.normal(scale=0.015, size=(int(inside.sum()), 3))  # a jittered lattice
tets = Delaunay(points).simplices
materials = (points[tets].mean(axis=1)[:, 0] > 0.6).astype(int)  # two regions
volume = TetMesh(points, tets, materials=materials)

result = segment(volume, 30, beta=100)
labels = result.labels
inside = np.array([len(set(materials[labels == s])) for s in range(result.n_segments)])
print(f"{volume.n_tets} tetrahedra -> {result.n_segments} superfacets; "
      f"{int((inside > 1).sum())} hold both materials")

surface, face_labels = cut_surface(volume, labels, axis=0, at=0.5)  # the cube cut in half
image = render(surface, face_labels, size=(640, 480), view=(1, -0.8, 0.6), up="z")
plt.figure(figsize=(6.4, 4.8))
plt.imshow(image)
plt.axis("off")
plt.show()
