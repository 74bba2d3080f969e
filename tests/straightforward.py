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

from superfacets.graph import FaceGraph, paper_weights
from superfacets.seeding import farthest_point_centers


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
    g = mesh.graph
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


def face_graph_by_sorting(faces: np.ndarray, n_vertices: int) -> FaceGraph:
    """The face graph built with numpy sorts (the package's first version).

    Parameters
    ----------
    faces : (m, 3) int64 ndarray
        Triangles, indices in ``[0, n_vertices)``.
    n_vertices : int
        Number of vertices.

    Returns
    -------
    FaceGraph
    """
    m = faces.shape[0]
    # 32-bit half-edge and vertex ids while they fit: the temporaries of the edge grouping
    # are the memory peak of a whole run on large meshes
    itype = np.int32 if max(int(n_vertices), 3 * m) < 2**31 - 1 else np.int64
    a = np.empty(3 * m, dtype=itype)  # half-edge h = 3 * face + corner, corner c joins
    b = np.empty(3 * m, dtype=itype)  # vertices (0, 1), (1, 2), (2, 0) of the face
    for c, (u, v) in enumerate(((0, 1), (1, 2), (2, 0))):
        np.minimum(faces[:, u], faces[:, v], out=a[c::3], casting="unsafe")
        np.maximum(faces[:, u], faces[:, v], out=b[c::3], casting="unsafe")
    valid = np.flatnonzero(a != b).astype(itype)  # collapsed edges join nothing
    key = a[valid].astype(np.int64)
    key *= np.int64(n_vertices)
    key += b[valid]
    order = np.argsort(key, kind="stable")
    skey = key[order]
    del key
    half = valid[order]  # half-edge ids, grouped by edge
    del valid, order
    sface = half // 3
    n_half = skey.shape[0]
    if n_half:
        brk = np.empty(n_half, dtype=bool)
        brk[0] = True
        np.not_equal(skey[1:], skey[:-1], out=brk[1:])
        starts = np.flatnonzero(brk)
        del brk
    else:
        starts = np.zeros(0, np.int64)
    del skey
    sizes = np.diff(np.r_[starts, n_half])

    # boundary edges: groups of size 1
    one = starts[sizes == 1]
    boundary_faces = sface[one].astype(np.int64)
    boundary_edges = np.stack([a[half[one]], b[half[one]]], axis=1).astype(np.int64)
    del one

    # pairs within every group of size >= 2 (all pairs for non-manifold edges)
    pi, pj, pe = [], [], []
    for s in np.unique(sizes[sizes >= 2]):
        st = starts[sizes == s]
        ii, jj = np.triu_indices(int(s), 1)
        pi.append(sface[st[:, None] + ii[None, :]].ravel())
        pj.append(sface[st[:, None] + jj[None, :]].ravel())
        pe.append(np.repeat(half[st], ii.size))
    del starts, sizes, sface, half
    if pi:
        fi = np.concatenate(pi)
        fj = np.concatenate(pj)
        he = np.concatenate(pe)
    else:
        fi = fj = he = np.zeros(0, itype)
    del pi, pj, pe
    lo = np.minimum(fi, fj)
    hi = np.maximum(fi, fj)
    del fi, fj
    keep = lo != hi  # a degenerate face sharing an edge with itself
    if not keep.all():
        lo, hi, he = lo[keep], hi[keep], he[keep]
    del keep
    # one dual edge per face pair: the first in edge-key order (smallest vertex pair)
    pkey = lo.astype(np.int64) * np.int64(m) + hi
    ekey = a[he].astype(np.int64) * np.int64(n_vertices) + b[he]
    o = np.lexsort((ekey, pkey))
    del ekey
    pkey, lo, hi, he = pkey[o], lo[o], hi[o], he[o]
    del o
    first = np.r_[True, pkey[1:] != pkey[:-1]] if pkey.size else np.zeros(0, bool)
    del pkey
    if not first.all():
        lo, hi, he = lo[first], hi[first], he[first]
    del first
    pairs = np.stack([lo, hi], axis=1).astype(np.int64)
    edges = np.stack([a[he], b[he]], axis=1).astype(np.int64)
    del a, b, he

    # symmetric CSR, neighbours ascending within each row
    e = pairs.shape[0]
    rows = np.concatenate([lo, hi])
    cols = np.concatenate([hi, lo])
    del lo, hi
    o = np.lexsort((cols, rows))
    indptr = np.zeros(m + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=m), out=indptr[1:])
    del rows
    indices = np.ascontiguousarray(cols[o], dtype=np.int32)
    del cols
    dual_edge = o.astype(np.int64)
    dual_edge[dual_edge >= e] -= e  # entry t of [lo->hi, hi->lo] is dual edge t mod e
    del o
    return FaceGraph(
        n_faces=m,
        pairs=pairs,
        edges=edges,
        indptr=indptr,
        indices=indices,
        dual_edge=dual_edge,
        boundary_edges=boundary_edges,
        boundary_faces=boundary_faces,
    )
