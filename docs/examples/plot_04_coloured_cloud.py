"""
A coloured point cloud
======================

A cloud of points with RGB (from PLY, PCD or LAS files, or ``PointCloud(colors=...)``):
superpoints follow the geometry, and with ``beta`` also the colour edges. Here a table
top (one plane) carrying two coloured mats and a box, sampled as a depth sensor would.
"""

import matplotlib.pyplot as plt
import numpy as np

from superfacets import PointCloud, segment
from superfacets.viz.render import render_points

rng = np.random.default_rng(0)
top = np.c_[rng.random((30000, 2)) * [2.0, 1.2], np.zeros(30000)]
colour = np.full((len(top), 3), 0.8)
mat1 = (np.abs(top[:, 0] - 0.5) < 0.3) & (np.abs(top[:, 1] - 0.6) < 0.3)
mat2 = (np.abs(top[:, 0] - 1.4) < 0.25) & (np.abs(top[:, 1] - 0.4) < 0.25)
colour[mat1] = (0.8, 0.1, 0.1)
colour[mat2] = (0.1, 0.2, 0.8)
box = rng.random((6000, 3)) * [0.3, 0.3, 0.3] + [1.4, 0.75, 0.0]
box[np.arange(6000) % 3 == 0, 2] = 0.3  # its lid
colour = np.r_[colour, np.tile((0.2, 0.6, 0.2), (len(box), 1))]
cloud = PointCloud(np.r_[top, box], colors=colour, viewpoint=(1.0, 0.6, 2.0))

plain = segment(cloud, 60)
with_colour = segment(cloud, 60, beta=200)
mats = mat1 | mat2
for name, r in (("geometry", plain), ("geometry + colour", with_colour)):
    lab = r.labels[: len(top)]
    mixed = sum(len(set(mats[lab == s])) > 1 for s in np.unique(lab))
    print(f"{name:18s}: {r.n_segments} superpoints, {mixed} straddle a mat's border")

images = [render_points(cloud, r.labels, size=(480, 360), up="z", view=(0.3, -1, 1.2))
          for r in (plain, with_colour)]
plt.figure(figsize=(9.6, 3.6))
for j, (img, title) in enumerate(zip(images, ("geometry", "geometry + colour (beta=200)"))):
    plt.subplot(1, 2, j + 1)
    plt.imshow(img)
    plt.title(title)
    plt.axis("off")
plt.show()
