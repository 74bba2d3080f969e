"""
A benchmark mesh judged against its ground truth
================================================

The Princeton Mesh Segmentation Benchmark gives several human segmentations per mesh.
The metrics of the paper (undersegmentation error, eq. 4; compactness, eq. 5) and the
boundary recall judge a result against them. This example reads the benchmark from
``../shared/data/psb.tar.xz`` beside the repository (or ``$SUPERFACETS_PSB``); where it
is absent it says so and uses a mesh with a known answer instead: two boxes joined by
a crease.
"""

import matplotlib.pyplot as plt
import numpy as np
import trimesh

from superfacets import Mesh, read_mesh, segment
from superfacets.evaluation.metrics import evaluate
from superfacets.viz.render import render_panel

try:
    from superfacets.evaluation.datasets.psb import list_meshes, psb_root

    bm = [b for b in list_meshes(psb_root()) if b.id == 1][0]
    mesh = read_mesh(bm.path)
    truths = bm.ground_truths(mesh.n_faces)
    title = f"benchmark mesh {bm.id} ({bm.category})"
except Exception as exc:  # noqa: BLE001 - no benchmark here: a known answer instead
    print(f"the benchmark is not here ({exc}); using two boxes with a crease")
    a = trimesh.creation.box(extents=(2, 1, 1)).subdivide().subdivide()
    b = trimesh.creation.box(extents=(1, 1, 2)).subdivide().subdivide()
    b.apply_translation((0.5, 0, 1.0))
    joined = trimesh.util.concatenate([a, b])
    mesh = Mesh(joined.vertices, joined.faces)
    truths = [np.r_[np.zeros(len(a.faces), int), np.ones(len(b.faces), int)]]
    title = "two boxes"

result = segment(mesh, 150)
scores = evaluate(mesh, result.labels, truths)
for name, value in scores.items():
    print(f"{name:24s} {value:.4f}")

image = render_panel([(mesh, truths[0], "a human segmentation"),
                      (mesh, result.labels, "150 superfacets")], size=(480, 420))
plt.figure(figsize=(9.6, 4.2))
plt.imshow(image)
plt.title(title)
plt.axis("off")
plt.show()
