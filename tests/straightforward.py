"""The paper's iteration written the plain way, for the exactness tests.

No record replay, no cycle skipping, no bucket queue, no threads: for each
center, scipy's Dijkstra on the subgraph induced by its window, merged in
center order with a strict ``<``; orphans seeded at the lowest-index
unlabelled face; the center update in numpy. It shares with the package only
the face graph, the weights and the farthest-point initialization, which
have tests of their own.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.sparse import csr_array
from scipy.sparse.csgraph import dijkstra

from superfacets.elements import face_graph
from superfacets.method.initialization import farthest_point_centers
from superfacets.method.weights import paper_weights


def classify(a: csr_array, c: np.ndarray, centers: list, window_r2: float):
    """Labels and distances of one classification; appends orphan centers."""
    m = c.shape[0]
    dist = np.full(m, np.inf)
    label = np.full(m, -1, dtype=np.int64)

    def expand(src: int, lab: int):
        idx = np.flatnonzero(((c - c[src]) ** 2).sum(axis=1) <= window_r2)
        d = dijkstra(a[idx][:, idx], indices=int(np.searchsorted(idx, src)))
        better = np.isfinite(d) & (d < dist[idx])
        dist[idx[better]] = d[better]
        label[idx[better]] = lab

    for s, src in enumerate(centers):
        expand(src, s)
    while (label < 0).any():
        centers.append(int(np.flatnonzero(label < 0)[0]))
        expand(centers[-1], len(centers) - 1)
    return label, dist


def update(label: np.ndarray, k: int, areas: np.ndarray, c: np.ndarray, old: list) -> list:
    """Center update: face nearest the area-weighted mean (old center on ties, else
    lowest index); -1 for an empty superfacet."""
    wsum = np.bincount(label, weights=areas, minlength=k)
    mean = np.stack([np.bincount(label, weights=areas * c[:, t], minlength=k) for t in range(3)], 1)
    mean = mean / wsum[:, None]
    d = ((c - mean[label]) ** 2).sum(axis=1)
    new = []
    for s in range(k):
        faces = np.flatnonzero(label == s)
        if faces.size == 0:
            new.append(-1)
            continue
        best = d[faces].min()
        if label[old[s]] == s and d[old[s]] == best:
            new.append(old[s])
        else:
            new.append(int(faces[d[faces] == best][0]))
    return new


def segment_labels(mesh, k: int, *, alpha: float = 200.0, eta_convex: float = 0.2,
                   window: float = 2.0, max_iter: int = 50):
    """Labels of the last classification (not made dense) and the number of passes."""
    g = face_graph(mesh)
    w = paper_weights(mesh, alpha=alpha, eta_convex=eta_convex)
    assert (w > 0).all()  # scipy's csgraph would drop explicit zero weights
    m = mesh.n_faces
    a = csr_array((w[g.dual_edge], g.indices, g.indptr), shape=(m, m))
    c = np.asarray(mesh.centroids)
    r = math.sqrt(mesh.area / (k * math.pi))
    centers = [int(x) for x in farthest_point_centers(mesh, k)]
    for it in range(1, max_iter + 1):
        n_before = len(centers)
        label, _ = classify(a, c, centers, (window * r) ** 2)
        new = update(label, len(centers), np.asarray(mesh.areas), c, centers)
        if len(centers) == n_before and new == centers:
            break
        centers = [x for x in new if x >= 0]
    return label, it
