"""numba kernels of Variational Shape Approximation (private; see ``vsa.py``).

Proxies are planes ``(X_p, N_p)``. ``metric`` is 0 for L2,1 and 1 for L2.
Arrays are contiguous; outputs are preallocated by the caller. The heap is
the binary min-heap of ``superfacets._kernels`` (float64 keys, int64 values
``face * n_proxies + proxy``), capacity ``len(indices) + 1``.
"""

import numpy as np
from numba import njit

from .heap import pop, push


@njit(cache=True, inline="always")
def _error(f, p, metric, areas, normals, corners, X, N):
    """Distortion of face ``f`` against proxy ``p`` (CSAD04, section 2.3)."""
    if metric == 0:  # L2,1: area * |n_f - N_p|^2
        dx = normals[f, 0] - N[p, 0]
        dy = normals[f, 1] - N[p, 1]
        dz = normals[f, 2] - N[p, 2]
        return areas[f] * (dx * dx + dy * dy + dz * dz)
    # L2: integral over the triangle of the squared distance to the plane
    d0 = ((corners[f, 0, 0] - X[p, 0]) * N[p, 0] + (corners[f, 0, 1] - X[p, 1]) * N[p, 1]
          + (corners[f, 0, 2] - X[p, 2]) * N[p, 2])
    d1 = ((corners[f, 1, 0] - X[p, 0]) * N[p, 0] + (corners[f, 1, 1] - X[p, 1]) * N[p, 1]
          + (corners[f, 1, 2] - X[p, 2]) * N[p, 2])
    d2 = ((corners[f, 2, 0] - X[p, 0]) * N[p, 0] + (corners[f, 2, 1] - X[p, 1]) * N[p, 1]
          + (corners[f, 2, 2] - X[p, 2]) * N[p, 2])
    return areas[f] / 6.0 * (d0 * d0 + d1 * d1 + d2 * d2 + d0 * d1 + d1 * d2 + d2 * d0)


@njit(cache=True, inline="always")
def _push_neighbours(f, p, n_proxies, indptr, indices, metric, areas, normals, corners, X, N,
                     label, hkey, hval, size):
    for j in range(indptr[f], indptr[f + 1]):
        g = indices[j]
        if label[g] < 0:
            size = push(hkey, hval, size, _error(g, p, metric, areas, normals, corners, X, N),
                         g * n_proxies + p)
    return size


@njit(cache=True)
def partition(indptr, indices, metric, areas, normals, corners, X, N, seeds, n_proxies,
              label, hkey, hval):
    """Distortion-minimizing flooding from the seeds with one priority queue.

    Every seed takes its proxy; the unlabelled neighbours of each labelled
    face are pushed with their distortion to that face's proxy; the face of
    the smallest entry popped takes the entry's proxy (CSAD04, section 3.3).
    Faces no seed can reach keep -1.
    """
    label[:] = -1
    for p in range(n_proxies):
        label[seeds[p]] = p
    size = 0
    for p in range(n_proxies):
        size = _push_neighbours(seeds[p], p, n_proxies, indptr, indices, metric, areas,
                                normals, corners, X, N, label, hkey, hval, size)
    while size > 0:
        v = hval[0]
        size = pop(hkey, hval, size)
        f = v // n_proxies
        if label[f] >= 0:
            continue
        p = v - f * n_proxies
        label[f] = p
        size = _push_neighbours(f, p, n_proxies, indptr, indices, metric, areas, normals,
                                corners, X, N, label, hkey, hval, size)


@njit(cache=True, inline="always")
def _d2(centroids, f, P, p):
    dx = centroids[f, 0] - P[p, 0]
    dy = centroids[f, 1] - P[p, 1]
    dz = centroids[f, 2] - P[p, 2]
    return dx * dx + dy * dy + dz * dz


@njit(cache=True, inline="always")
def _tie(a, b):
    return abs(a - b) <= 1e-9 * max(abs(a), abs(b)) + 1e-300


@njit(cache=True)
def assess(label, n_proxies, metric, areas, normals, centroids, corners, X, N, seeds, total):
    """Per region: new seed and total distortion, in place; returns the mesh total.

    The seed is the face of least distortion against the region's proxy;
    among equal distortions (flat regions), the face whose centroid is
    nearest ``X``, so the next flooding starts from the middle.
    """
    best = np.full(n_proxies, np.inf)
    best_d = np.full(n_proxies, np.inf)
    total[:n_proxies] = 0.0
    out = 0.0
    for f in range(label.shape[0]):
        p = label[f]
        e = _error(f, p, metric, areas, normals, corners, X, N)
        total[p] += e
        out += e
        if e < best[p] and not _tie(e, best[p]):
            best[p] = e
            best_d[p] = _d2(centroids, f, X, p)
            seeds[p] = f
        elif _tie(e, best[p]):
            d = _d2(centroids, f, X, p)
            if d < best_d[p]:
                best_d[p] = d
                seeds[p] = f
    return out


@njit(cache=True)
def worst_faces(label, n_proxies, metric, areas, normals, centroids, corners, X, N, seeds,
                is_seed, worst):
    """Per region, the face of largest distortion that is not a seed (-1 if none);
    among equal distortions, the one farthest from the region's seed.
    """
    worst_e = np.full(n_proxies, -1.0)
    worst_d = np.full(n_proxies, -1.0)
    worst[:n_proxies] = -1
    S = np.empty((n_proxies, 3))
    for p in range(n_proxies):
        for i in range(3):
            S[p, i] = centroids[seeds[p], i]
    for f in range(label.shape[0]):
        if is_seed[f]:
            continue
        p = label[f]
        e = _error(f, p, metric, areas, normals, corners, X, N)
        if e > worst_e[p] and not _tie(e, worst_e[p]):
            worst_e[p] = e
            worst_d[p] = _d2(centroids, f, S, p)
            worst[p] = f
        elif _tie(e, worst_e[p]):
            d = _d2(centroids, f, S, p)
            if d > worst_d[p]:
                worst_d[p] = d
                worst[p] = f
