"""Boundary clean-up: bands along superfacet boundaries and one minimum cut per band
(private kernels of :mod:`superfacets.cleanup`).

``band_distances`` grows, inside each superfacet, the distance from its
boundary (a multi-source Dijkstra that never crosses a label change), up to a
limit, and remembers for each element which neighbouring superfacet its
nearest boundary faces: the element then belongs to the band of that pair of
superfacets. Bands of different pairs are disjoint, so ``solve_bands`` cuts
each one on its own (on several threads; the result does not depend on the
order or the thread count): a two-label graph cut, solved exactly as a minimum s-t
cut by Dinic's max-flow, whose source side keeps the first label.
"""

import numpy as np
from numba import njit

from .heap import pop_min, push

_INF = np.inf


@njit(cache=True, error_model="numpy")
def band_distances(indptr, indices, geo, length, labels, pinned, limit, dist, partner,
                   hkey, hval):
    """Distance of every element from its superfacet's boundary, below ``limit``.

    Seeds: elements with a neighbour of another label (distance 0; partner:
    the neighbouring label sharing the longest border, ties to the lowest).
    The distance grows by ``geo`` (per CSR entry) along entries that join two
    elements of the same label. ``pinned`` elements are never in a band.
    Elements farther than ``limit`` (or pinned) keep ``dist = inf`` and
    ``partner = -1``.
    """
    n = labels.shape[0]
    size = 0
    for f in range(n):
        dist[f] = _INF
        partner[f] = -1
    for f in range(n):
        if pinned[f]:
            continue
        lf = labels[f]
        best = -1
        best_len = -1.0
        for e in range(indptr[f], indptr[f + 1]):
            lg = labels[indices[e]]
            if lg == lf:
                continue
            # total border with label lg (a few neighbours: a quadratic scan is cheapest)
            tot = 0.0
            for e2 in range(indptr[f], indptr[f + 1]):
                if labels[indices[e2]] == lg:
                    tot += length[e2]
            if tot > best_len or (tot == best_len and lg < best):
                best_len = tot
                best = lg
        if best >= 0:
            dist[f] = 0.0
            partner[f] = best
            size = push(hkey, hval, size, 0.0, f)
    while size > 0:
        d, f, size = pop_min(hkey, hval, size)
        if d > dist[f]:
            continue
        lf = labels[f]
        for e in range(indptr[f], indptr[f + 1]):
            g = indices[e]
            if labels[g] != lf or pinned[g]:
                continue
            nd = d + geo[e]
            if nd < limit and nd < dist[g]:
                dist[g] = nd
                partner[g] = partner[f]
                size = push(hkey, hval, size, nd, g)


@njit(cache=True, error_model="numpy", inline="always")
def _levels(n, first, nxt, head, cap, s, eps, level, queue):
    """Breadth-first levels from ``s`` along arcs of residual capacity ``> eps``
    (-1: unreachable)."""
    for u in range(n):
        level[u] = -1
    level[s] = 0
    qh = 0
    qt = 1
    queue[0] = s
    while qh < qt:
        u = queue[qh]
        qh += 1
        a = first[u]
        while a != -1:
            v = head[a]
            if level[v] < 0 and cap[a] > eps:
                level[v] = level[u] + 1
                queue[qt] = v
                qt += 1
            a = nxt[a]


@njit(cache=True, error_model="numpy")
def _max_flow(n, first, nxt, head, cap, s, t, eps, level, it, queue, path):
    """Dinic's algorithm on arcs ``(head, cap)`` (arc ``a ^ 1`` reverses ``a``).

    Leaves the residual capacities in ``cap``; returns the flow value.
    """
    flow = 0.0
    while True:
        _levels(n, first, nxt, head, cap, s, eps, level, queue)
        if level[t] < 0:
            return flow
        for u in range(n):
            it[u] = first[u]
        while True:  # blocking flow: depth-first paths in the level graph
            depth = 0
            u = s
            found = False
            while True:
                if u == t:
                    found = True
                    break
                a = it[u]
                moved = False
                while a != -1:
                    v = head[a]
                    if cap[a] > eps and level[v] == level[u] + 1:
                        path[depth] = a
                        depth += 1
                        u = v
                        moved = True
                        break
                    a = nxt[a]
                    it[u] = a
                if not moved:
                    if u == s:
                        break
                    level[u] = -1  # dead end
                    depth -= 1
                    a = path[depth]
                    u = head[a ^ 1]
                    it[u] = nxt[it[u]]
            if not found:
                break
            push_ = _INF
            for i in range(depth):
                if cap[path[i]] < push_:
                    push_ = cap[path[i]]
            for i in range(depth):
                a = path[i]
                cap[a] -= push_
                cap[a ^ 1] += push_
            flow += push_


@njit(cache=True, error_model="numpy")
def _solve_one(members, la, lb, pair_id, band_of, local, indptr, indices, cut_cost,
               labels, sizes, positions, means, smooth, out):
    """Minimum cut of one band between labels ``la`` (source) and ``lb`` (sink)."""
    nb = members.shape[0]
    for i in range(nb):
        local[members[i]] = i
    s = nb
    t = nb + 1
    n_nodes = nb + 2
    # arcs: two per t-link, two per band-internal adjacency
    n_arcs = 4 * nb
    for i in range(nb):
        f = members[i]
        for e in range(indptr[f], indptr[f + 1]):
            g = indices[e]
            if band_of[g] == pair_id and g > f:
                n_arcs += 2
    head = np.empty(n_arcs, dtype=np.int64)
    cap = np.empty(n_arcs, dtype=np.float64)
    nxt = np.empty(n_arcs, dtype=np.int64)
    first = np.full(n_nodes, -1, dtype=np.int64)
    na = 0
    total = 0.0
    for i in range(nb):
        f = members[i]
        # unary: squared distance to each superfacet's mean, in units of r^2
        da = 0.0
        db = 0.0
        for c in range(3):
            xa = positions[f, c] - means[la, c]
            xb = positions[f, c] - means[lb, c]
            da += xa * xa
            db += xb * xb
        cost_a = smooth * sizes[f] * da
        cost_b = smooth * sizes[f] * db
        for e in range(indptr[f], indptr[f + 1]):
            g = indices[e]
            if band_of[g] == pair_id:
                if g > f:
                    j = local[g]
                    c_e = cut_cost[e]
                    head[na] = j
                    cap[na] = c_e
                    nxt[na] = first[i]
                    first[i] = na
                    head[na + 1] = i
                    cap[na + 1] = c_e
                    nxt[na + 1] = first[j]
                    first[j] = na + 1
                    na += 2
                    total += c_e
            elif labels[g] == lb:
                cost_a += cut_cost[e]  # f keeps la: the edge to g is cut
            elif labels[g] == la:
                cost_b += cut_cost[e]
        m = min(cost_a, cost_b)
        cost_a -= m
        cost_b -= m
        total += cost_a + cost_b
        # s -> f (cut when f takes lb: pays cost_b), f -> t (cut when f keeps la)
        head[na] = i
        cap[na] = cost_b
        nxt[na] = first[s]
        first[s] = na
        head[na + 1] = s
        cap[na + 1] = 0.0
        nxt[na + 1] = first[i]
        first[i] = na + 1
        head[na + 2] = t
        cap[na + 2] = cost_a
        nxt[na + 2] = first[i]
        first[i] = na + 2
        head[na + 3] = i
        cap[na + 3] = 0.0
        nxt[na + 3] = first[t]
        first[t] = na + 3
        na += 4
    level = np.empty(n_nodes, dtype=np.int64)
    it = np.empty(n_nodes, dtype=np.int64)
    queue = np.empty(n_nodes, dtype=np.int64)
    path = np.empty(n_nodes, dtype=np.int64)
    eps = 1e-12 * total
    _max_flow(n_nodes, first, nxt, head, cap, s, t, eps, level, it, queue, path)
    # source side of the minimum cut: reachable from s in the residual graph
    _levels(n_nodes, first, nxt, head, cap, s, eps, level, queue)
    for i in range(nb):
        out[members[i]] = la if level[i] >= 0 else lb


@njit(cache=True, error_model="numpy", nogil=True)
def solve_bands(p0, p1, order, starts, pair_a, pair_b, band_of, indptr, indices, cut_cost,
                labels, sizes, positions, means, smooth, out):
    """Cut bands ``p0 .. p1 - 1`` (``order[starts[p]:starts[p + 1]]`` holds band ``p``).

    ``out`` (a copy of ``labels``) receives the new label of every band
    element. Bands are disjoint: calls on disjoint ranges may run at once
    (the GIL is released) and give the same result in any order.
    """
    local = np.empty(labels.shape[0], dtype=np.int64)
    for p in range(p0, p1):
        members = order[starts[p]:starts[p + 1]]
        _solve_one(members, pair_a[p], pair_b[p], p, band_of, local, indptr, indices,
                   cut_cost, labels, sizes, positions, means, smooth, out)
