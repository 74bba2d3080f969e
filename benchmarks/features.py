"""The colour (feature) term on and off: benchmark meshes coloured by a ground truth, real scans.

Usage: python benchmarks/features.py [--per-category 3] [-k 150] [--beta 0 50 200]
       [--noise 0.1]

Rows:

- benchmark meshes (the first ``--per-category`` of each category), each face
  coloured by the segment of its first human segmentation (a random RGB per
  segment, fixed seed) plus Gaussian noise of ``--noise`` per channel, clipped
  to [0, 1]: undersegmentation error, compactness and boundary recall against
  that segmentation, for each ``--beta`` (the default method on faces). What
  the term can do where colour tells the parts apart, and what noise costs;
- the same meshes with colours in the file: each vertex coloured by its
  vertex ground truth (the majority of its faces' segments) plus the same
  noise, written as a PLY with vertex colours and read back
  (``read_mesh``: ``mesh.colors``), segmented on faces (each face the mean
  of its vertices' colours) and on vertices with no ``features`` given;
  vertices are evaluated on the vertex graph against the vertex ground
  truth, each vertex counted once;
- each real RGB-D scan of ``../shared/data/clouds`` at k = 150: the mean
  colour distance of a point to its superpoint's mean colour (lower: more
  uniform superpoints), the superpoints' compactness is not defined on a
  cloud, so only this and the time.

In process, one thread, each setting one after the other on the same input.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("SUPERFACETS_SHARED", ROOT.parent / "shared")) / "data"


def coloured_by_truth(gt: np.ndarray, noise: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    palette = rng.random((int(gt.max()) + 1, 3))
    return np.clip(palette[gt] + rng.normal(0, noise, (gt.shape[0], 3)), 0, 1)


def colour_spread(cloud, labels: np.ndarray) -> float:
    ok = cloud.colors[cloud.valid]
    lab = labels[cloud.valid]
    k = int(lab.max()) + 1
    count = np.bincount(lab, minlength=k)
    mean = np.stack([np.bincount(lab, ok[:, i], k) / count for i in range(3)], 1)
    return float(np.mean(np.linalg.norm(ok - mean[lab], axis=1)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--per-category", type=int, default=3)
    ap.add_argument("-k", type=int, default=150)
    ap.add_argument("--beta", type=float, nargs="+", default=[0.0, 50.0, 200.0])
    ap.add_argument("--noise", type=float, default=0.1)
    a = ap.parse_args()

    from superfacets import segment
    from superfacets.evaluation.datasets.psb import first_per_category, list_meshes
    from superfacets.evaluation.metrics import evaluate
    from superfacets.io import read_cloud, read_mesh

    meshes = first_per_category(list_meshes(), a.per_category)
    rows = {b: [] for b in a.beta}
    for bm in meshes:
        mesh = read_mesh(bm.path)
        gts = bm.ground_truths(mesh.n_faces)
        col = coloured_by_truth(gts[0], a.noise, bm.id)
        for b in a.beta:
            t = time.perf_counter()
            r = segment(mesh, a.k, beta=b, features=col if b > 0 else None, n_threads=1)
            sec = time.perf_counter() - t
            e = evaluate(mesh, r.labels, gts[:1])
            rows[b].append((e["undersegmentation_error"], e["compactness"],
                            e["boundary_recall"], sec))
    print(f"{len(meshes)} benchmark meshes, faces coloured by their first ground truth "
          f"+ noise {a.noise}, k = {a.k}, against that ground truth")
    print("| beta | UE | compactness | boundary recall | seconds |")
    print("|---|---|---|---|---|")
    for b, v in rows.items():
        m = np.mean(v, axis=0)
        print(f"| {b:g} | {m[0]:.4f} | {m[1]:.3f} | {m[2]:.3f} | {np.sum(v, axis=0)[3]:.1f} |")

    file_colours(meshes, a)

    print("\nreal RGB-D scans, k = 150: mean colour distance to the superpoint's mean")
    print("| scan | beta | colour spread | superpoints | seconds |")
    print("|---|---|---|---|---|")
    for path in sorted((SHARED / "clouds").glob("*.pcd")):
        for b in a.beta:
            c = read_cloud(path)
            t = time.perf_counter()
            r = segment(c, 150, beta=b, n_threads=1)
            sec = time.perf_counter() - t
            print(f"| {path.stem} | {b:g} | {colour_spread(c, r.labels):.4f} | "
                  f"{r.n_segments} | {sec:.1f} |")


def file_colours(meshes, a) -> None:
    """The colours of a mesh file (vertex colours), on faces and on vertices."""
    import tempfile

    import trimesh

    from superfacets import Mesh, segment
    from superfacets.elements.builders import elements_of
    from superfacets.evaluation.datasets.sampling import vertex_ground_truth
    from superfacets.evaluation.metrics import evaluate
    from superfacets.io import read_mesh

    rows = {(e, b): [] for e in ("faces", "vertices") for b in a.beta}
    with tempfile.TemporaryDirectory() as tmp:
        for bm in meshes:
            mesh = read_mesh(bm.path)
            gt = bm.ground_truths(mesh.n_faces)[0]
            vgt = vertex_ground_truth(mesh, gt)
            rgb = np.round(coloured_by_truth(vgt, a.noise, bm.id) * 255).astype(np.uint8)
            tm = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
            tm.visual.vertex_colors = np.c_[rgb, np.full(len(rgb), 255, np.uint8)]
            path = Path(tmp) / f"{bm.id}.ply"
            tm.export(path)
            coloured = read_mesh(path)
            src = elements_of(Mesh(mesh.vertices, mesh.faces), "vertices")
            first = src.first_rows(np.arange(src.graph.n_elements))
            for el in ("faces", "vertices"):
                for b in a.beta:
                    t = time.perf_counter()
                    r = segment(coloured, a.k, beta=b, elements=el, n_threads=1)
                    sec = time.perf_counter() - t
                    if el == "faces":
                        e = evaluate(mesh, r.labels, [gt])
                    else:
                        e = evaluate(src.graph, np.asarray(r.labels)[first], [vgt[first]],
                                     equal_weight=True)
                    rows[(el, b)].append((e["undersegmentation_error"], e["compactness"],
                                          e["boundary_recall"], sec))
    print(f"\nthe same meshes, vertex colours (vertex ground truth + noise {a.noise}) read "
          f"from a PLY, k = {a.k}")
    print("| elements | beta | UE | compactness | boundary recall | seconds |")
    print("|---|---|---|---|---|---|")
    for (el, b), v in rows.items():
        m = np.mean(v, axis=0)
        print(f"| {el} | {b:g} | {m[0]:.4f} | {m[1]:.3f} | {m[2]:.3f} | "
              f"{np.sum(v, axis=0)[3]:.1f} |")


if __name__ == "__main__":
    main()
