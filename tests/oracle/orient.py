"""Consistent orientation of estimated normals: propagation along a minimum spanning tree.

Hoppe et al.'s rule ("Surface reconstruction from unorganized points", 1992):
grow a spanning tree over the neighbourhood graph that prefers the flattest
steps (Prim's algorithm on the cost ``1 - |n_u . n_v|``) and flip each normal
to agree with its parent's. Private kernel of :mod:`superfacets.elements.points`.
"""

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", inline="always")
def _before(k1, a1, b1, k2, a2, b2):
    """Strict order of candidate tree edges: by key, then the lower end, then the higher."""
    return k1 < k2 or (k1 == k2 and (a1 < a2 or (a1 == a2 and b1 < b2)))


@njit(cache=True, error_model="numpy", inline="always")
def _put(hkey, hlo, hhi, hel, at, i, key, a, b, el):
    """Entry ``(key, a, b)`` of element ``el`` at heap place ``i``."""
    hkey[i] = key
    hlo[i] = a
    hhi[i] = b
    hel[i] = el
    at[el] = i


@njit(cache=True, error_model="numpy")
def propagate_signs(indptr, indices, normals, sign, component):
    """Fill ``sign`` (+1/-1 per element) and ``component`` (ids from 0); return the
    number of components.

    Prim's algorithm with an indexed 4-ary heap of the frontier (one entry per
    element, its best edge lowered in place), the edges ordered by ``(key, lower
    end, higher end)``: a strict order of the undirected edges, so the tree is the
    graph's one minimum spanning forest under it, whatever the heap's layout or the
    algorithm (the compiled kernel reaches it by blocks of elements). Trees grow
    from the lowest element not yet reached; each element takes its tree
    neighbour's sign, flipped where their normals disagree.
    """
    n = normals.shape[0]
    done = np.zeros(n, dtype=np.bool_)
    at = np.full(n, -1, dtype=np.int64)  # place of each element in the heap, -1: none
    source = np.empty(n, dtype=np.int64)  # the tree neighbour of its best key
    hkey = np.empty(n)
    hlo = np.empty(n, dtype=np.int64)  # the ends of the entry's edge (the tie rule)
    hhi = np.empty(n, dtype=np.int64)
    hel = np.empty(n, dtype=np.int64)  # element
    n_comp = 0
    for s in range(n):
        if done[s]:
            continue
        size = 0
        v = s
        done[s] = True
        sign[s] = 1
        component[s] = n_comp
        while True:
            for t in range(indptr[v], indptr[v + 1]):
                w = indices[t]
                if done[w]:
                    continue
                d = normals[v, 0] * normals[w, 0] + normals[v, 1] * normals[w, 1] \
                    + normals[v, 2] * normals[w, 2]
                key = 1.0 - abs(d)
                a = min(v, w)
                b = max(v, w)
                i = at[w]
                if i < 0:
                    i = size
                    size += 1
                elif not _before(key, a, b, hkey[i], hlo[i], hhi[i]):
                    continue
                source[w] = v
                while i > 0:  # sift up
                    p = (i - 1) >> 2
                    if _before(hkey[p], hlo[p], hhi[p], key, a, b):
                        break
                    _put(hkey, hlo, hhi, hel, at, i, hkey[p], hlo[p], hhi[p], hel[p])
                    i = p
                _put(hkey, hlo, hhi, hel, at, i, key, a, b, w)
            if size == 0:
                break
            v = hel[0]
            at[v] = -1
            size -= 1
            if size > 0:  # the last entry sifts down from the root
                key = hkey[size]
                a = hlo[size]
                b = hhi[size]
                x = hel[size]
                i = 0
                while True:
                    c = 4 * i + 1
                    if c >= size:
                        break
                    m = c
                    for c2 in range(c + 1, min(c + 4, size)):
                        if _before(hkey[c2], hlo[c2], hhi[c2], hkey[m], hlo[m], hhi[m]):
                            m = c2
                    if not _before(hkey[m], hlo[m], hhi[m], key, a, b):
                        break
                    _put(hkey, hlo, hhi, hel, at, i, hkey[m], hlo[m], hhi[m], hel[m])
                    i = m
                _put(hkey, hlo, hhi, hel, at, i, key, a, b, x)
            u = source[v]
            done[v] = True
            component[v] = n_comp
            d = normals[u, 0] * normals[v, 0] + normals[u, 1] * normals[v, 1] \
                + normals[u, 2] * normals[v, 2]
            sign[v] = sign[u] if d >= 0 else -sign[u]
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
