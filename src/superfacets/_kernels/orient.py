"""Consistent orientation of estimated normals: propagation along a minimum spanning tree.

Hoppe et al.'s rule ("Surface reconstruction from unorganized points", 1992):
grow a spanning tree over the neighbourhood graph that prefers the flattest
steps (Prim's algorithm on the cost ``1 - |n_u . n_v|``) and flip each normal
to agree with its parent's. Private kernel of :mod:`superfacets.elements.points`.
"""

import numpy as np
from numba import njit

from .heap import pop, push


@njit(cache=True, error_model="numpy")
def propagate_signs(indptr, indices, normals, sign, component):
    """Fill ``sign`` (+1/-1 per element) and ``component`` (ids from 0); return the
    number of components."""
    n = normals.shape[0]
    rows = np.empty(indices.shape[0], dtype=np.int32)  # the source of each pushed entry
    done = np.zeros(n, dtype=np.bool_)
    best = np.full(n, np.inf)  # the lowest key pushed for each element: a larger one
    # would only be popped after it, and skipped
    cap = indices.shape[0] + 1
    hkey = np.empty(cap, dtype=np.float64)
    hval = np.empty(cap, dtype=np.int64)
    n_comp = 0
    for s in range(n):
        if done[s]:
            continue
        done[s] = True
        sign[s] = 1
        component[s] = n_comp
        size = 0
        for t in range(indptr[s], indptr[s + 1]):
            w = indices[t]
            if not done[w]:
                d = normals[s, 0] * normals[w, 0] + normals[s, 1] * normals[w, 1] \
                    + normals[s, 2] * normals[w, 2]
                key = 1.0 - abs(d)
                if key < best[w]:
                    best[w] = key
                    rows[t] = s
                    size = push(hkey, hval, size, key, t)
        while size > 0:
            t = hval[0]
            size = pop(hkey, hval, size)
            v = indices[t]
            if done[v]:
                continue
            u = rows[t]
            done[v] = True
            component[v] = n_comp
            d = normals[u, 0] * normals[v, 0] + normals[u, 1] * normals[v, 1] \
                + normals[u, 2] * normals[v, 2]
            sign[v] = sign[u] if d >= 0 else -sign[u]
            for t2 in range(indptr[v], indptr[v + 1]):
                w = indices[t2]
                if not done[w]:
                    d = normals[v, 0] * normals[w, 0] + normals[v, 1] * normals[w, 1] \
                        + normals[v, 2] * normals[w, 2]
                    key = 1.0 - abs(d)
                    if key < best[w]:
                        best[w] = key
                        rows[t2] = v
                        size = push(hkey, hval, size, key, t2)
        n_comp += 1
    return n_comp


@njit(cache=True, error_model="numpy")
def turn_outwards(points, normals, sign, component, n_comp, out):
    """``out``: each normal times its sign, turned over in every component whose
    oriented normals point inwards on the whole (``sum n . (p - mean) < 0``, the mean
    of the component's points); sums in element order."""
    n = points.shape[0]
    count = np.zeros(n_comp)
    mean = np.zeros((n_comp, 3))
    for i in range(n):
        c = component[i]
        count[c] += 1.0
        for a in range(3):
            mean[c, a] += points[i, a]
    for c in range(n_comp):
        for a in range(3):
            mean[c, a] /= count[c]
    total = np.zeros(n_comp)
    for i in range(n):
        c = component[i]
        s = float(sign[i])
        total[c] += (normals[i, 0] * s * (points[i, 0] - mean[c, 0])
                     + normals[i, 1] * s * (points[i, 1] - mean[c, 1])) \
            + normals[i, 2] * s * (points[i, 2] - mean[c, 2])
    for i in range(n):
        s = float(sign[i])
        if total[component[i]] < 0:
            s = -s
        for a in range(3):
            out[i, a] = normals[i, a] * s
