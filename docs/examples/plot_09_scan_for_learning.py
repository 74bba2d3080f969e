"""
A scan in, its superpoints out: LAZ records, a map, a graph for learning
========================================================================

An airborne tile (here made on the spot: a ground with a building and a row of poles,
RGB and classes, as a LAZ file carries them) is segmented from its own file; the labels
go back into a copy of the file as the ``ClusterID`` dimension (every other dimension
and the header kept), where PDAL, lidR, QGIS or CloudCompare read them. The tile is
drawn from above as a map (north up, its aspect kept). The superpoint graph is then
laid out as PyTorch Geometric reads it (``edge_index`` both ways, the handcrafted
features of Superpoint Transformer per superpoint); ``result.to_pyg()`` gives the
``Data`` where torch_geometric is installed, and ``NotebookView(result)`` shows the
interactive viewer inline in a notebook.
"""

import tempfile
from pathlib import Path

import laspy
import matplotlib.pyplot as plt
import numpy as np

from superfacets import read_cloud, segment
from superfacets.io.orientation import default_view
from superfacets.io.records import write_labels_into
from superfacets.viz.html import NotebookView
from superfacets.viz.render import render_points

rng = np.random.default_rng(0)
ground = np.c_[rng.random((40000, 2)) * [120.0, 60.0], rng.normal(0, 0.03, 40000)]
ground = ground[~((abs(ground[:, 0] - 35) < 15) & (abs(ground[:, 1] - 30) < 10))]  # roofed
roof = np.c_[rng.random((6000, 2)) * [30.0, 20.0] + [20.0, 20.0], np.full(6000, 8.0)]
t = rng.random(3000)
poles = np.c_[np.repeat(np.arange(70.0, 115.0, 9.0), 600) + rng.normal(0, 0.05, 3000),
              np.full(3000, 30.0) + rng.normal(0, 0.05, 3000), t * 6.0]
xyz = np.r_[ground, roof, poles] + [651000.0, 6862000.0, 40.0]
classes = np.r_[np.full(len(ground), 2), np.full(6000, 6), np.full(3000, 1)].astype(np.uint8)

folder = Path(tempfile.mkdtemp())
las = laspy.create(point_format=3, file_version="1.4")
las.header.scales, las.header.offsets = [0.01] * 3, [651000.0, 6862000.0, 0.0]
las.x, las.y, las.z = xyz.T
las.classification = classes
las.write(folder / "tile.laz")

cloud = read_cloud(folder / "tile.laz")  # z up, as LAS declares it
result = segment(cloud, 150)
out = write_labels_into(folder / "tile_sp.laz", folder / "tile.laz", result.labels)
back = laspy.read(out)
print(f"{out.name}: dimensions {list(back.point_format.dimension_names)[-3:]}, "
      f"{len(np.unique(back.ClusterID))} superpoints")

graph = result.learning_graph()
names = list(graph["node_features"])
x = graph["x"]
print(f"PyG layout: x {x.shape}, edge_index {graph['edge_index'].shape} (both ways), "
      f"edge_attr {graph['edge_attr'].shape}")
for cls, name in ((2, "ground"), (6, "roof"), (1, "poles")):
    sp = np.unique(result.labels[classes == cls])
    means = {f: float(np.median(x[sp, names.index(f)]))
             for f in ("linearity", "planarity", "verticality", "elevation")}
    print(f"{name:7s}: " + ", ".join(f"{k} {v:.2f}" for k, v in means.items()))

view = NotebookView(result)  # in a notebook, the last line of a cell shows it inline
print(f"inline viewer: {len(view._repr_html_()) / 1e6:.1f} MB of self-contained HTML")

image = render_points(cloud, result.labels, size=(800, 420), view=default_view(cloud),
                      up="z", title="150 superpoints, seen from above (north up)")
plt.figure(figsize=(8, 4.2))
plt.imshow(image)
plt.axis("off")
plt.show()
