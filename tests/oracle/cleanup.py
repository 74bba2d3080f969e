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
exactly as a minimum s-t cut by push-relabel (:func:`min_cut`), whose source side keeps
the first label.
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


@njit(cache=True, error_model="numpy")
def min_cut(first, nxt, head, cap, tr, eps, source_side):
    """Minimum s-t cut by push-relabel (Goldberg and Tarjan, J. ACM 35(4), 1988), its
    first phase, on the network reversed.

    Nodes ``0..n-1``; arc ``a`` runs to ``head[a]`` with residual capacity
    ``cap[a]``, arc ``a ^ 1`` is its reverse; node ``u``'s arcs are
    ``first[u]``, ``nxt[first[u]]``, ... (-1 ends). ``tr[u] > 0`` is a
    capacity from the source to ``u``, ``tr[u] < 0`` one from ``u`` to the sink.
    Capacities at most ``eps`` count as saturated.

    Every arc is taken backwards and the terminals swapped: the sink's arcs are
    saturated at once, the excess pushed (first in, first out) down exact distance
    labels to the source, the labels recomputed from the source by a breadth-first
    search once the nodes have been relabelled ``n`` times. A maximum preflow is
    enough: the nodes that can still reach the source through the reversed residual
    capacities are those the source reaches in a maximum flow, the source side of the
    minimum cut with the fewest nodes, the same for any maximum flow (where ties leave
    several minimum cuts). The bands' data terms are weak, so the flow travels far from
    where it enters: pushed, it merges on its way, where augmenting paths (Boykov and
    Kolmogorov's, before) carried each node's share along its own long path.

    ``cap`` is left residual (of the reversed network); ``tr`` is not changed.
    ``source_side[u]`` is set to True for the nodes of that source side.
    """
    n = tr.shape[0]
    _min_cut_in(first, nxt, head, cap, tr, eps, source_side, n, np.empty(n, dtype=np.int64),
                np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64),
                np.empty(n, dtype=np.bool_), np.empty(n), np.empty(n))


@njit(cache=True, error_model="numpy")
def _labels_from_source(first, nxt, head, cap, eps, n, label, order, to_source):
    """Exact distance labels to the source in the reversed residual network (at most
    ``n``; ``n + 1``: none); the nodes labelled are listed first in ``order``. Returns how
    many."""
    for u in range(n):
        label[u] = n + 1
    qt = 0
    for u in range(n):
        if to_source[u] > eps:
            label[u] = 1
            order[qt] = u
            qt += 1
    qh = 0
    while qh < qt:
        u = order[qh]
        qh += 1
        a = first[u]
        while a != -1:
            v = head[a]
            # the reversed arc v -> u has the residual of u -> v
            if label[v] > n and cap[a] > eps:
                label[v] = label[u] + 1
                order[qt] = v
                qt += 1
            a = nxt[a]
    return qt


@njit(cache=True, error_model="numpy")
def _min_cut_in(first, nxt, head, cap, tr, eps, source_side, n, label, cur, queue, queued,
                excess, to_source):
    """:func:`min_cut` of nodes ``0..n-1`` with the work arrays given (length at least
    ``n`` each: distance labels, current arcs, the circular FIFO of active nodes, their
    flags, excesses, residual capacities to the source), so that many small cuts
    allocate nothing."""
    for u in range(n):
        excess[u] = -tr[u] if tr[u] < 0.0 else 0.0
        to_source[u] = tr[u] if tr[u] > 0.0 else 0.0
    while True:
        _labels_from_source(first, nxt, head, cap, eps, n, label, cur, to_source)
        qh = 0
        qn = 0
        for u in range(n):
            queued[u] = False
        for u in range(n):
            if excess[u] > eps and label[u] <= n:
                queue[qn] = u
                queued[u] = True
                qn += 1
        for u in range(n):
            cur[u] = first[u]
        if qn == 0:
            break
        relabels = 0
        while qn > 0 and relabels <= n:
            u = queue[qh]
            qh = (qh + 1) % n
            qn -= 1
            queued[u] = False
            while excess[u] > eps and label[u] <= n:
                if label[u] == 1 and to_source[u] > eps:
                    delta = min(excess[u], to_source[u])
                    to_source[u] -= delta
                    excess[u] -= delta
                    continue
                a = cur[u]
                if a == -1:  # relabel: one above the lowest neighbour it can push to
                    low = 0 if to_source[u] > eps else n
                    b = first[u]
                    while b != -1:
                        if cap[b ^ 1] > eps and label[head[b]] < low:
                            low = label[head[b]]
                        b = nxt[b]
                    label[u] = low + 1  # (n + 1: it cannot reach the source)
                    cur[u] = first[u]
                    relabels += 1
                    continue
                v = head[a]
                r = cap[a ^ 1]  # the reversed arc u -> v: the residual of v -> u
                if r > eps and label[u] == label[v] + 1:
                    delta = min(excess[u], r)
                    cap[a ^ 1] -= delta
                    cap[a] += delta
                    excess[u] -= delta
                    excess[v] += delta
                    if not queued[v] and excess[v] > eps:
                        queue[(qh + qn) % n] = v
                        queued[v] = True
                        qn += 1
                else:
                    cur[u] = nxt[a]
        if qn == 0:
            break
    # the nodes that reach the source
    for u in range(n):
        source_side[u] = False
    reach = _labels_from_source(first, nxt, head, cap, eps, n, label, cur, to_source)
    for t in range(reach):
        source_side[cur[t]] = True


@njit(cache=True, error_model="numpy")
def _solve_one(members, la, lb, pair_id, band_of, local, indptr, indices, cut_cost,
               labels, sizes, positions, means, smooth, out, head, cap, nxt, first, tr, side,
               work_l, work_c, work_q, work_b, work_e, work_s):
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
    _min_cut_in(first, nxt, head, cap, tr, 1e-12 * total, side, nb, work_l, work_c, work_q,
                work_b, work_e, work_s)
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
    work_l = np.empty(most_nodes, dtype=np.int64)
    work_c = np.empty(most_nodes, dtype=np.int64)
    work_q = np.empty(most_nodes, dtype=np.int64)
    work_b = np.empty(most_nodes, dtype=np.bool_)
    work_e = np.empty(most_nodes, dtype=np.float64)
    work_s = np.empty(most_nodes, dtype=np.float64)
    for p in range(p0, p1):
        members = order[starts[p]:starts[p + 1]]
        _solve_one(members, pair_a[p], pair_b[p], p, band_of, local, indptr, indices,
                   cut_cost, labels, sizes, positions, means, smooth, out, head, cap, nxt,
                   first, tr, side, work_l, work_c, work_q, work_b, work_e, work_s)
