"""Boundary clean-up: bands along superfacet boundaries and one minimum cut per band
(private kernels of :mod:`superfacets.method.cleanup`).

``band_distances`` grows, inside each superfacet, the distance from its
boundary (a multi-source Dijkstra that never crosses a label change), up to a
limit, and remembers for each element which neighbouring superfacet its
nearest boundary faces (the lowest at equal distances, so any order of the search
gives it: the compiled kernel runs the superfacets on several threads): the element
then belongs to the band of that pair of superfacets. Bands of different pairs are
disjoint, so ``solve_bands`` cuts each one on its own (on several threads; the result
does not depend on the order or the thread count): a two-label graph cut, solved
exactly as a minimum s-t cut by Boykov and Kolmogorov's max-flow (:func:`min_cut`),
whose source side keeps the first label.
"""

import numpy as np
from numba import njit

from .heap import pop_min, push

_INF = np.inf


@njit(cache=True, error_model="numpy")
def band_distances(indptr, indices, dual_edge, geo, length, labels, pinned, limit, dist,
                   partner, hkey, hval):
    """Distance of every element from its superfacet's boundary, below ``limit``.

    Seeds: elements with a neighbour of another label (distance 0; partner:
    the neighbouring label sharing the longest border, ties to the lowest).
    The distance grows by ``geo`` (per adjacency ``dual_edge[e]`` of CSR entry
    ``e``, as ``length``) along entries that join two
    elements of the same label; an element reached at the same distance from
    seeds of different partners takes the lowest partner (so the result does not
    depend on the order of the search: the compiled kernel searches the
    superfacets on several threads). ``pinned`` elements are never in a band.
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
                    tot += length[dual_edge[e2]]
            if tot > best_len or (tot == best_len and lg < best):
                best_len = tot
                best = lg
        if best >= 0:
            dist[f] = -0.0  # (a seed: never taken over at distance 0; +0.0 at the end)
            partner[f] = best
            size = push(hkey, hval, size, 0.0, f)
    while size > 0:
        d, f, size = pop_min(hkey, hval, size)
        if d > dist[f]:
            continue
        lf = labels[f]
        pf = partner[f]
        for e in range(indptr[f], indptr[f + 1]):
            g = indices[e]
            if labels[g] != lf or pinned[g]:
                continue
            nd = d + geo[dual_edge[e]]
            dg = dist[g]
            if nd < limit and (nd < dg or (nd == dg and pf < partner[g]
                                           and not np.signbit(dg))):
                dist[g] = nd
                partner[g] = pf
                size = push(hkey, hval, size, nd, g)
    for f in range(n):
        if dist[f] == 0.0:
            dist[f] = 0.0


_NONE = -1  # parent of a free node
_TERMINAL = -2  # parent of a node joined straight to its terminal
_ORPHAN = -3


@njit(cache=True, error_model="numpy", inline="always")
def _rooted(parent, head, j):
    """True when the tree path from ``j`` reaches a terminal (no orphan on it)."""
    while True:
        p = parent[j]
        if p == _TERMINAL:
            return True
        if p < 0:
            return False
        j = head[p]


@njit(cache=True, error_model="numpy")
def min_cut(first, nxt, head, cap, tr, eps, source_side):
    """Minimum s-t cut by Boykov and Kolmogorov's max-flow (IEEE PAMI 26(9), 2004).

    Nodes ``0..n-1``; arc ``a`` runs to ``head[a]`` with residual capacity
    ``cap[a]``, arc ``a ^ 1`` is its reverse; node ``u``'s arcs are
    ``first[u]``, ``nxt[first[u]]``, ... (-1 ends). ``tr[u] > 0`` is a
    capacity from the source to ``u``, ``tr[u] < 0`` one from ``u`` to the sink.
    Capacities at most ``eps`` count as saturated. Two search trees grow from
    the terminals; each path found between them is augmented, and the nodes
    cut off from their tree adopt a new parent or become free.

    ``cap`` and ``tr`` are left residual. ``source_side[u]`` is set to True
    for the nodes still reachable from the source (through capacities above
    ``eps``): the source side of the minimum cut with the fewest nodes, the
    same for any maximum flow.
    """
    n = tr.shape[0]
    _min_cut_in(first, nxt, head, cap, tr, eps, source_side, n, np.empty(n, dtype=np.int64),
                np.empty(n, dtype=np.bool_), np.empty(n, dtype=np.bool_),
                np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64))


@njit(cache=True, error_model="numpy")
def _min_cut_in(first, nxt, head, cap, tr, eps, source_side, n, parent, sink, queued, active,
                orphans):
    """:func:`min_cut` of nodes ``0..n-1`` with the work arrays given (length at least
    ``n`` each: tree parents, tree sides, queue flags, the circular FIFO of active
    nodes, the orphans), so that many small cuts allocate nothing."""
    qh = 0
    qn = 0
    for u in range(n):
        sink[u] = False
        queued[u] = False
    for u in range(n):
        if tr[u] > eps or -tr[u] > eps:
            parent[u] = _TERMINAL
            sink[u] = tr[u] < 0.0
            active[(qh + qn) % n] = u
            queued[u] = True
            qn += 1
        else:
            parent[u] = _NONE
    while qn > 0:
        i = active[qh]
        if parent[i] == _NONE:  # freed since it was queued
            qh = (qh + 1) % n
            qn -= 1
            queued[i] = False
            continue
        # grow the tree of i by one arc, or find an arc to the other tree
        # (the source tree grows along residual i -> j, the sink tree along j -> i)
        mid = -1
        side = sink[i]
        a = first[i]
        while a != -1:
            j = head[a]
            if (cap[a ^ 1] if side else cap[a]) > eps:
                if parent[j] == _NONE:
                    parent[j] = a ^ 1
                    sink[j] = side
                    if not queued[j]:
                        active[(qh + qn) % n] = j
                        queued[j] = True
                        qn += 1
                elif sink[j] != side:
                    mid = a ^ 1 if side else a
                    break
            a = nxt[a]
        if mid == -1:  # i has no arc left to grow along: done with it
            qh = (qh + 1) % n
            qn -= 1
            queued[i] = False
            continue
        # augment the path source .. x -> y .. sink through arc mid = x -> y
        b = cap[mid]
        u = head[mid ^ 1]
        while parent[u] != _TERMINAL:
            pa = parent[u]
            b = min(b, cap[pa ^ 1])
            u = head[pa]
        b = min(b, tr[u])
        u = head[mid]
        while parent[u] != _TERMINAL:
            pa = parent[u]
            b = min(b, cap[pa])
            u = head[pa]
        b = min(b, -tr[u])
        cap[mid] -= b
        cap[mid ^ 1] += b
        n_orphans = 0
        u = head[mid ^ 1]
        while parent[u] != _TERMINAL:
            pa = parent[u]
            cap[pa] += b
            cap[pa ^ 1] -= b
            if not cap[pa ^ 1] > eps:
                parent[u] = _ORPHAN
                orphans[n_orphans] = u
                n_orphans += 1
            u = head[pa]
        tr[u] -= b
        if not tr[u] > eps:
            parent[u] = _ORPHAN
            orphans[n_orphans] = u
            n_orphans += 1
        u = head[mid]
        while parent[u] != _TERMINAL:
            pa = parent[u]
            cap[pa ^ 1] += b
            cap[pa] -= b
            if not cap[pa] > eps:
                parent[u] = _ORPHAN
                orphans[n_orphans] = u
                n_orphans += 1
            u = head[pa]
        tr[u] += b
        if not -tr[u] > eps:
            parent[u] = _ORPHAN
            orphans[n_orphans] = u
            n_orphans += 1
        # adoption: each orphan takes a neighbour of its tree still rooted, else is freed
        k = 0
        while k < n_orphans:
            o = orphans[k]
            k += 1
            side = sink[o]
            new = -1
            a = first[o]
            while a != -1:
                j = head[a]
                if sink[j] == side and parent[j] != _NONE and (
                        cap[a] > eps if side else cap[a ^ 1] > eps) and _rooted(parent, head, j):
                    new = a
                    break
                a = nxt[a]
            if new != -1:
                parent[o] = new
                continue
            a = first[o]
            while a != -1:
                j = head[a]
                if sink[j] == side and parent[j] != _NONE:
                    if (cap[a] > eps if side else cap[a ^ 1] > eps) and not queued[j]:
                        active[(qh + qn) % n] = j
                        queued[j] = True
                        qn += 1
                    pj = parent[j]
                    if pj >= 0 and head[pj] == o:
                        parent[j] = _ORPHAN
                        orphans[n_orphans] = j  # each node is orphaned at most once at a time
                        n_orphans += 1
                a = nxt[a]
            parent[o] = _NONE
    for u in range(n):
        source_side[u] = parent[u] != _NONE and not sink[u]


@njit(cache=True, error_model="numpy")
def _solve_one(members, la, lb, pair_id, band_of, local, indptr, indices, cut_cost,
               labels, sizes, positions, means, smooth, out, head, cap, nxt, first, tr, side,
               work_i, work_b, work_q, work_a, work_o):
    """Minimum cut of one band between labels ``la`` (source) and ``lb`` (sink), in the
    work arrays given (arcs: ``head``, ``cap``, ``nxt``; nodes: the others)."""
    nb = members.shape[0]
    for i in range(nb):
        local[members[i]] = i
        first[i] = -1
    # two arcs per band-internal adjacency; the terminal capacities in tr
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
        # source -> f (cut when f takes lb: pays cost_b), f -> sink (cut when f keeps la)
        tr[i] = cost_b if cost_b > 0.0 else -cost_a
    _min_cut_in(first, nxt, head, cap, tr, 1e-12 * total, side, nb, work_i, work_b, work_q,
                work_a, work_o)
    for i in range(nb):
        out[members[i]] = la if side[i] else lb


@njit(cache=True, error_model="numpy", nogil=True)
def solve_bands(p0, p1, order, starts, pair_a, pair_b, band_of, indptr, indices, cut_cost,
                labels, sizes, positions, means, smooth, out):
    """Cut bands ``p0 .. p1 - 1`` (``order[starts[p]:starts[p + 1]]`` holds band ``p``).

    ``out`` (a copy of ``labels``) receives the new label of every band
    element. Bands are disjoint: calls on disjoint ranges may run at once
    (the GIL is released) and give the same result in any order. One set of
    work arrays serves every band of the call, sized for the largest.
    """
    local = np.empty(labels.shape[0], dtype=np.int64)
    most_nodes = 1
    most_arcs = 1
    for p in range(p0, p1):
        nodes = starts[p + 1] - starts[p]
        arcs = 0  # at most the CSR entries of the band's elements
        for t in range(starts[p], starts[p + 1]):
            f = order[t]
            arcs += indptr[f + 1] - indptr[f]
        most_nodes = max(most_nodes, nodes)
        most_arcs = max(most_arcs, arcs)
    head = np.empty(most_arcs, dtype=np.int64)
    cap = np.empty(most_arcs, dtype=np.float64)
    nxt = np.empty(most_arcs, dtype=np.int64)
    first = np.empty(most_nodes, dtype=np.int64)
    tr = np.empty(most_nodes, dtype=np.float64)
    side = np.empty(most_nodes, dtype=np.bool_)
    work_i = np.empty(most_nodes, dtype=np.int64)
    work_b = np.empty(most_nodes, dtype=np.bool_)
    work_q = np.empty(most_nodes, dtype=np.bool_)
    work_a = np.empty(most_nodes, dtype=np.int64)
    work_o = np.empty(most_nodes, dtype=np.int64)
    for p in range(p0, p1):
        members = order[starts[p]:starts[p + 1]]
        _solve_one(members, pair_a[p], pair_b[p], p, band_of, local, indptr, indices,
                   cut_cost, labels, sizes, positions, means, smooth, out, head, cap, nxt,
                   first, tr, side, work_i, work_b, work_q, work_a, work_o)
