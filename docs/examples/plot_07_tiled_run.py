"""
One input in tiles, on a local Dask cluster
===========================================

An input larger than a machine is cut into spatial tiles with halos, one task each;
the superfacets crossing a tile border are seen whole from both sides, so none is cut.
``workers=2`` starts a local Dask cluster of two processes (``scheduler=`` reaches a
running one; ``workers=1`` runs in this process). Binary PLY, LAS/LAZ and ``.npy``
files are read in chunks, one box at a time.
"""

from pathlib import Path
from tempfile import mkdtemp

import matplotlib.pyplot as plt
import trimesh

from superfacets import read_mesh, segment_tiled
from superfacets.viz.render import render

path = Path(mkdtemp()) / "ball.ply"
trimesh.creation.icosphere(subdivisions=5).export(path)  # 20,480 faces, binary PLY

if __name__ == "__main__":  # the workers are processes: they import this file
    result = segment_tiled(path, 200, tiles=4, workers=2)
    print(f"{result.labels.size} faces, {result.n_segments} superfacets in "
          f"{len(result.tiles)} tiles; {result.disagreements} border disagreements")
    image = render(read_mesh(path), result.labels, size=(640, 480), view=(1, 0.4, 0.3))
    plt.figure(figsize=(6.4, 4.8))
    plt.imshow(image)
    plt.axis("off")
    plt.show()
