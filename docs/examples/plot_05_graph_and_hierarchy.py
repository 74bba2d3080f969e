"""
The superpoint graph and its hierarchy
======================================

``result.graph()`` is the adjacency of the superfacets (border lengths, mean dihedral
angles, areas, centroids, normals); ``result.hierarchy(levels)`` merges adjacent ones,
cheapest first, into nested coarser levels, every segment connected.
"""

import matplotlib.pyplot as plt

from superfacets import segment
from superfacets.inputs.shapes import creature
from superfacets.viz.render import render_panel

mesh = creature(48)
result = segment(mesh, 120)
graph = result.graph()
print(f"{graph.n_segments} superfacets, {graph.edge_index.shape[1]} adjacencies; "
      f"{int(graph.concave.sum())} along concave borders")
levels = result.hierarchy([40, 12])
coarse = [levels.labels(i, result.labels) for i in range(2)]

# the graph drawn over the superfacets' centroids (x, y)
c = graph.centroid
fig, ax = plt.subplots(1, 1, figsize=(5, 4))
for a, b in graph.edge_index.T:
    ax.plot(c[[a, b], 0], c[[a, b], 1], color="red" if graph.concave[
        (graph.edge_index[0] == a) & (graph.edge_index[1] == b)].any() else "0.6", lw=0.8)
ax.scatter(c[:, 0], c[:, 1], s=graph.area / graph.area.max() * 60, zorder=3)
ax.set_aspect("equal")
ax.set_title("superfacet graph (red: concave borders)")

image = render_panel([(mesh, result.labels, "120 superfacets"), (mesh, coarse[0], "level 40"),
                      (mesh, coarse[1], "level 12")], size=(360, 300), up="y")
plt.figure(figsize=(10.8, 3))
plt.imshow(image)
plt.axis("off")
plt.show()
