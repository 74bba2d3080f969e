"""The greedy merging of :func:`superfacets.graph.hierarchy.hierarchy`, in numba.

A heap of ``(cost, lo, hi, version_lo, version_hi)`` tuples with lazy
deletion (a pair is stale once either end merged or changed), union-find for
the merged nodes, and each node's adjacency as a linked list of entries
``(neighbour, border length, length x angle, length x concave share)``:
merging ``b`` into ``a`` appends ``b``'s list to ``a``'s and folds the
entries that now name the same node (after union-find) into one, in place.
Each undirected adjacency has an entry in both ends' lists; the stats of a
pair are those of its entry in the list of the node that merged last, which
folds every part. Private: imported by :mod:`superfacets.graph.hierarchy` only.
"""

import heapq
import math

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", inline="always")
def _find(owner, s):
    while owner[s] != s:
        owner[s] = owner[owner[s]]
        s = owner[s]
    return s


@njit(cache=True, error_model="numpy")
def _plane(xx, yy, zz, xy, xz, yz):
    """Smallest eigenvalue of a symmetric 3 x 3 matrix, >= 0 (trigonometric solution)."""
    off = xy * xy + xz * xz + yz * yz
    q = (xx + yy + zz) / 3.0
    p2 = (xx - q) ** 2 + (yy - q) ** 2 + (zz - q) ** 2 + 2.0 * off
    if p2 <= 1e-300:
        return max(q, 0.0)
    p = math.sqrt(p2 / 6.0)
    a, b, c = (xx - q) / p, (yy - q) / p, (zz - q) / p
    d, e, f = xy / p, xz / p, yz / p
    r = 0.5 * (a * (b * c - f * f) - d * (d * c - f * e) + e * (d * f - b * e))
    phi = math.acos(min(1.0, max(-1.0, r))) / 3.0
    return max(q + 2.0 * p * math.cos(phi + 2.0 * math.pi / 3.0), 0.0)


@njit(cache=True, error_model="numpy", inline="always")
def _merged_scatter(a, b, area, wsum, scatter, out):
    aa, ab = area[a], area[b]
    x = wsum[a, 0] / max(aa, 1e-300) - wsum[b, 0] / max(ab, 1e-300)
    y = wsum[a, 1] / max(aa, 1e-300) - wsum[b, 1] / max(ab, 1e-300)
    z = wsum[a, 2] / max(aa, 1e-300) - wsum[b, 2] / max(ab, 1e-300)
    w = aa * ab / max(aa + ab, 1e-300)
    out[0] = scatter[a, 0] + scatter[b, 0] + w * x * x
    out[1] = scatter[a, 1] + scatter[b, 1] + w * y * y
    out[2] = scatter[a, 2] + scatter[b, 2] + w * z * z
    out[3] = scatter[a, 3] + scatter[b, 3] + w * x * y
    out[4] = scatter[a, 4] + scatter[b, 4] + w * x * z
    out[5] = scatter[a, 5] + scatter[b, 5] + w * y * z


@njit(cache=True, error_model="numpy", inline="always")
def _spread(a, b, area, wsum):
    """Ward's: the rise of the weighted spread of the centroids."""
    aa, ab = area[a], area[b]
    tot = aa + ab
    d2 = 0.0
    for c in range(3):
        d = wsum[a, c] / max(aa, 1e-300) - wsum[b, c] / max(ab, 1e-300)
        d2 += d * d
    return aa * ab / tot * d2 if tot > 0 else 0.0


@njit(cache=True, error_model="numpy")
def _cost(a, b, ln, ang, conc, area, wsum, fsum, scatter, planarity, alpha, eta_convex,
          beta, compactness, max_rise, tmp, max_size, min_count):
    if max_size > 0 and area[a] + area[b] > max_size:  # no union weighing more
        return np.inf
    if planarity > 0:
        _merged_scatter(a, b, area, wsum, scatter, tmp)
        c = (_plane(tmp[0], tmp[1], tmp[2], tmp[3], tmp[4], tmp[5])
             - _plane(scatter[a, 0], scatter[a, 1], scatter[a, 2], scatter[a, 3],
                      scatter[a, 4], scatter[a, 5])
             - _plane(scatter[b, 0], scatter[b, 1], scatter[b, 2], scatter[b, 3],
                      scatter[b, 4], scatter[b, 5]))
        c = max(c, 0.0)
        if planarity == 2:  # flat pairs only (the rise per element of the smaller node)
            if c > (max_rise * max(min(area[a], area[b]), min_count)
                    + 64.0 * 2.220446049250313e-16 * (tmp[0] + tmp[1] + tmp[2])):
                return np.inf
        elif planarity == 3:  # the scene's: the rise in max_rise's units, Ward's in 1 / compactness
            c = c / max(max_rise, 1e-300) + compactness * _spread(a, b, area, wsum)
        elif compactness > 0:
            c += compactness * _spread(a, b, area, wsum)
    if planarity != 1:  # the crease factor: of Ward's cost, or of the scene's
        if ln > 0:
            theta, share = ang / ln, conc / ln
        else:
            theta, share = 0.0, 0.0
        s = theta * (share + eta_convex * (1.0 - share))
        w = c if planarity == 3 else _spread(a, b, area, wsum)
        c = w * (1.0 + alpha * s / math.pi)
    if beta > 0:
        d2 = 0.0
        for j in range(fsum.shape[1]):
            d = fsum[a, j] / max(area[a], 1e-300) - fsum[b, j] / max(area[b], 1e-300)
            d2 += d * d
        c *= 1.0 + beta * math.sqrt(d2)
    return c


@njit(cache=True, error_model="numpy")
def merge_levels(k, ea, eb, stats, area, wsum, fsum, scatter, planarity, alpha, eta_convex,
                 beta, compactness, max_rise, targets, max_size=0.0, min_count=0.0):
    """Merge the cheapest adjacent pair until each of ``targets`` (decreasing, each
    reachable) live nodes remain, or no pair has a finite cost; ``(len(targets), k)``
    int64: each node's root then (the rows of targets not reached: the roots where the
    merging stopped). ``planarity``: 0 Ward's cost, 1 the rise of the best plane's
    distances, 2 Ward's cost of the pairs whose plane rises by at most ``max_rise``
    per element of the smaller node, read over at least ``min_count`` elements (the
    others: infinite), 3 the scene's cost: the rise
    over ``max_rise`` plus ``compactness`` times Ward's term, times the crease factor.
    ``area``, ``wsum``,
    ``fsum`` (k, d) and ``scatter`` (k, 6) are updated in place. ``max_size > 0``: no
    pair whose union's ``area`` (the planes' graphs: elements) is above it merges."""
    n_e = ea.shape[0]
    cap = 2 * n_e
    nb = np.empty(cap, np.int64)
    st = np.empty((cap, 3), np.float64)
    nxt = np.full(cap, -1, np.int64)
    head = np.full(k, -1, np.int64)
    tail = np.full(k, -1, np.int64)
    for t in range(n_e):
        for side in range(2):
            u, v = (ea[t], eb[t]) if side == 0 else (eb[t], ea[t])
            e = 2 * t + side
            nb[e] = v
            st[e, 0], st[e, 1], st[e, 2] = stats[t, 0], stats[t, 1], stats[t, 2]
            if head[u] < 0:
                head[u] = e
            else:
                nxt[tail[u]] = e
            tail[u] = e
    owner = np.arange(k)
    version = np.zeros(k, np.int64)
    mark = np.full(k, -1, np.int64)
    slot = np.zeros(k, np.int64)
    tmp = np.empty(6, np.float64)
    heap = [(np.inf, -1, -1, -1, -1)]  # a sentinel, never reached: the targets are
    for t in range(n_e):
        a, b = min(ea[t], eb[t]), max(ea[t], eb[t])
        heapq.heappush(heap, (_cost(a, b, stats[t, 0], stats[t, 1], stats[t, 2], area, wsum,
                                    fsum, scatter, planarity, alpha, eta_convex, beta,
                                    compactness, max_rise, tmp, max_size, min_count), a, b, 0, 0))
    out = np.empty((targets.shape[0], k), np.int64)
    live = k
    step = 0
    i = 0
    while i < targets.shape[0]:
        if live == targets[i]:
            for s in range(k):
                out[i, s] = _find(owner, s)
            i += 1
            continue
        c0, a, b, va, vb = heapq.heappop(heap)
        if c0 == np.inf:  # the sentinel, or no pair left that may merge
            break
        if owner[a] != a or owner[b] != b or version[a] != va or version[b] != vb:
            continue  # stale
        owner[b] = a  # merge b into a
        if planarity > 0:
            _merged_scatter(a, b, area, wsum, scatter, tmp)
            for j in range(6):
                scatter[a, j] = tmp[j]
        area[a] += area[b]
        for j in range(3):
            wsum[a, j] += wsum[b, j]
        for j in range(fsum.shape[1]):
            fsum[a, j] += fsum[b, j]
        if head[b] >= 0:  # b's adjacency appended to a's
            if head[a] < 0:
                head[a] = head[b]
            else:
                nxt[tail[a]] = head[b]
            tail[a] = tail[b]
        head[b] = -1
        version[a] += 1
        step += 1
        r = head[a]  # fold entries naming one node; drop those naming a; in place
        w_prev = -1
        while r >= 0:
            r_next = nxt[r]
            c = _find(owner, nb[r])
            if c != a:
                if mark[c] == step:
                    e = slot[c]
                    st[e, 0] += st[r, 0]
                    st[e, 1] += st[r, 1]
                    st[e, 2] += st[r, 2]
                else:
                    w = head[a] if w_prev < 0 else nxt[w_prev]
                    nb[w] = c
                    st[w, 0], st[w, 1], st[w, 2] = st[r, 0], st[r, 1], st[r, 2]
                    mark[c] = step
                    slot[c] = w
                    w_prev = w
            r = r_next
        if w_prev < 0:
            head[a] = -1
            tail[a] = -1
        else:
            nxt[w_prev] = -1
            tail[a] = w_prev
        e = head[a]
        while e >= 0:
            c = nb[e]
            lo, hi = (a, c) if a < c else (c, a)
            heapq.heappush(heap, (_cost(lo, hi, st[e, 0], st[e, 1], st[e, 2], area, wsum,
                                        fsum, scatter, planarity, alpha, eta_convex, beta,
                                        compactness, max_rise, tmp, max_size, min_count),
                                  lo, hi, version[lo], version[hi]))
            e = nxt[e]
        live -= 1
    while i < targets.shape[0]:  # stopped: the roots as they are
        for s in range(k):
            out[i, s] = _find(owner, s)
        i += 1
    return out
