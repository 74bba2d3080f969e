"""Split and merge candidates of the K-preserving swaps (private kernels).

Every distance here is the face-graph distance of the paper's weights,
restricted to the elements of one superfacet (or of two, for a merge); the
energy of a set of elements around a center is ``sum(size * d ** power)``.
``members[bounds[s]:bounds[s + 1]]`` are the elements of superfacet ``s``.
``dist`` / ``stamp`` are per-element work arrays (``stamp[f] == sid``: ``dist[f]``
is set in the current search), ``hkey`` / ``hval`` a heap (:mod:`.heap`) with
room for one push per CSR entry of the elements searched, plus one (a search
pushes an element again only on a strict decrease).
"""

import numpy as np
from numba import njit

from .heap import pop_min, push


@njit(cache=True, error_model="numpy", inline="always")
def _pow(d, power):
    """``d ** power``, by two multiplications for the default ``power = 4`` (libm's
    pow costs about 16 ns a call, most of an energy's time; the two differ in the
    last bit on about half the values)."""
    if power == 4.0:
        q = d * d
        return q * q
    return d ** power


@njit(cache=True, error_model="numpy", inline="always")
def _relax(indptr, indices, w, label, la, lb, f, d, dist, stamp, sid, hkey, hval, size,
           na=0, rank=None):
    """Relax the edges of ``f`` (settled at ``d``) toward elements labelled ``la`` or
    ``lb``; return the heap's new size. ``dist`` and ``stamp`` by element, or with
    ``rank`` by slot within the union (:func:`_slot`)."""
    for e in range(indptr[f], indptr[f + 1]):
        g = indices[e]
        lg = label[g]
        if lg != la and lg != lb:
            continue
        nd = d + w[e]
        x = g if rank is None else _slot(g, lg, la, na, rank)
        if stamp[x] != sid or nd < dist[x]:
            dist[x] = nd
            stamp[x] = sid
            size = push(hkey, hval, size, nd, g)
    return size


@njit(cache=True, error_model="numpy", nogil=True)
def _search(indptr, indices, w, label, la, lb, src, dist, stamp, sid, hkey, hval):
    """Dijkstra from ``src`` over the elements labelled ``la`` or ``lb``."""
    dist[src] = 0.0
    stamp[src] = sid
    size = push(hkey, hval, 0, 0.0, src)
    while size > 0:
        d, f, size = pop_min(hkey, hval, size)
        if d > dist[f]:
            continue
        size = _relax(indptr, indices, w, label, la, lb, f, d, dist, stamp, sid, hkey, hval,
                      size)


@njit(cache=True, error_model="numpy", nogil=True)
def _nearest_mean(elems, n, sizes, positions):
    """The element of ``elems[:n]`` nearest their size-weighted mean (first on ties)."""
    tot = 0.0
    mx = my = mz = 0.0
    for i in range(n):
        f = elems[i]
        a = sizes[f]
        tot += a
        mx += a * positions[f, 0]
        my += a * positions[f, 1]
        mz += a * positions[f, 2]
    if tot > 0:
        mx /= tot
        my /= tot
        mz /= tot
    else:  # zero-size elements: the plain mean
        mx = my = mz = 0.0
        for i in range(n):
            f = elems[i]
            mx += positions[f, 0] / n
            my += positions[f, 1] / n
            mz += positions[f, 2] / n
    best = elems[0]
    bd = np.inf
    for i in range(n):
        f = elems[i]
        dx = positions[f, 0] - mx
        dy = positions[f, 1] - my
        dz = positions[f, 2] - mz
        q = dx * dx + dy * dy + dz * dz
        if q < bd:
            bd = q
            best = f
    return best


@njit(cache=True, error_model="numpy", nogil=True)
def _energy(elems, n, sizes, dist, stamp, sid, power):
    """``sum(size * d ** power)`` over ``elems[:n]``, and the farthest element
    (an element the search did not reach counts as the farthest reached)."""
    e = 0.0
    far = elems[0]
    fd = -1.0
    for i in range(n):
        f = elems[i]
        if stamp[f] == sid:
            d = dist[f]
            e += sizes[f] * _pow(d, power)
            if d > fd:
                fd = d
                far = f
    for i in range(n):  # unreached (a piece cut off): as far as the farthest
        f = elems[i]
        if stamp[f] != sid:
            e += sizes[f] * _pow(fd, power)
    return e, far


@njit(cache=True, error_model="numpy", nogil=True)
def _slot(g, lg, la, na, rank):
    """The slot of element ``g`` (of superfacet ``lg``) in the union of ``la`` (``na``
    members) and another."""
    return rank[g] if lg == la else na + rank[g]


@njit(cache=True, error_model="numpy", nogil=True)
def _union_search_below(indptr, indices, w, label, la, lb, na, rank, src, dist, stamp, sid,
                        hkey, hval, sizes, power, area, limit):
    """Dijkstra from ``src`` over the union of ``la`` and ``lb``, its distances and
    stamps kept by slot (:func:`_slot`), abandoned (returning False) as soon as the energy
    of the elements it spans is sure to reach ``limit``: the elements settled so far at
    their distances, the others (``area`` in all) at least at the distance being
    settled."""
    x = _slot(src, label[src], la, na, rank)
    dist[x] = 0.0
    stamp[x] = sid
    size = push(hkey, hval, 0, 0.0, src)
    settled = 0.0
    rest = area
    while size > 0:
        d, f, size = pop_min(hkey, hval, size)
        if d > dist[_slot(f, label[f], la, na, rank)]:
            continue
        dp = _pow(d, power)
        settled += sizes[f] * dp
        rest -= sizes[f]
        if settled + max(rest, 0.0) * dp >= limit:
            return False
        size = _relax(indptr, indices, w, label, la, lb, f, d, dist, stamp, sid, hkey, hval,
                      size, na, rank)
    return True


@njit(cache=True, error_model="numpy", nogil=True)
def _union_energy(elems, n, sizes, dist, stamp, sid, power):
    """:func:`_energy` over a union's ``elems``, whose slots are their places in it."""
    e = 0.0
    fd = -1.0
    for i in range(n):
        if stamp[i] == sid:
            d = dist[i]
            e += sizes[elems[i]] * _pow(d, power)
            if d > fd:
                fd = d
    for i in range(n):
        if stamp[i] != sid:
            e += sizes[elems[i]] * _pow(fd, power)
    return e


@njit(cache=True, error_model="numpy", nogil=True)
def energies(indptr, indices, w, label, members, bounds, sizes, positions, power, energy,
             far, dist, stamp, sid, hkey, hval, first, step):
    """Energy of each superfacet ``first, first + step, ...`` around the element
    nearest its mean, into ``energy[s]``, and its farthest element, into
    ``far[s]``. Returns the next free search id; calls on disjoint superfacets
    may share ``dist`` and ``stamp`` (with search ids of their own)."""
    k = bounds.shape[0] - 1
    for s in range(first, k, step):
        lo = bounds[s]
        n = bounds[s + 1] - lo
        elems = members[lo:lo + n]
        c = _nearest_mean(elems, n, sizes, positions)
        _search(indptr, indices, w, label, s, s, c, dist, stamp, sid, hkey, hval)
        energy[s], far[s] = _energy(elems, n, sizes, dist, stamp, sid, power)
        sid += 1
    return sid


@njit(cache=True, error_model="numpy", nogil=True)
def split_candidates(indptr, indices, w, label, members, bounds, sizes, positions, power,
                     lloyd, which, far, split_energy, second, dist, dist2, stamp, stamp2, sid,
                     hkey, hval, work, first, step):
    """Energy of the best split in two of each superfacet ``s = which[first],
    which[first + step], ...``: a 2-means with ``lloyd`` re-centerings, seeded
    by its farthest element ``far[s]`` (from :func:`energies`) and the
    element farthest from that.

    Writes ``split_energy[s]`` (``inf``: no split) and ``second[f] = True``
    for the elements of the split's second part. Returns the next free search
    id. A search touches only the elements of its superfacet, so calls on
    disjoint sets of superfacets may share ``dist``, ``stamp`` and ``second``
    (with search ids of their own) and run at once; ``hkey``, ``hval`` and
    ``work`` are per call.
    """
    for t in range(first, which.shape[0], step):
        s = which[t]
        lo = bounds[s]
        n = bounds[s + 1] - lo
        elems = members[lo:lo + n]
        split_energy[s] = np.inf
        if n < 4:
            continue
        p = far[s]
        _search(indptr, indices, w, label, s, s, p, dist, stamp, sid, hkey, hval)
        _, q = _energy(elems, n, sizes, dist, stamp, sid, power)
        if q == p:
            sid += 1
            continue
        ok = True
        last_p = last_q = -1
        for it in range(lloyd + 1):
            if it > 0:  # re-center each part on the element nearest its mean
                na = nb = 0
                for i in range(n):
                    f = elems[i]
                    if second[f]:
                        work[n - 1 - nb] = f
                        nb += 1
                    else:
                        work[na] = f
                        na += 1
                p = _nearest_mean(work[:na], na, sizes, positions)
                q = _nearest_mean(work[n - nb:n], nb, sizes, positions)
                if p == last_p and q == last_q:  # converged: the same parts again
                    break
            last_p, last_q = p, q
            _search(indptr, indices, w, label, s, s, p, dist, stamp, sid, hkey, hval)
            _search(indptr, indices, w, label, s, s, q, dist2, stamp2, sid, hkey, hval)
            na = nb = 0
            e = 0.0
            for i in range(n):  # each element to the nearer seed (the first on ties)
                f = elems[i]
                dp = dist[f] if stamp[f] == sid else np.inf
                dq = dist2[f] if stamp2[f] == sid else np.inf
                second[f] = dq < dp
                if dq < dp:
                    nb += 1
                    e += sizes[f] * _pow(dq, power)
                else:
                    na += 1
                    e += sizes[f] * _pow(dp, power) if dp < np.inf else 0.0
            sid += 1
            if na == 0 or nb == 0:
                ok = False
                break
        if ok:
            split_energy[s] = e
        else:
            for i in range(n):
                second[elems[i]] = False
    return sid


@njit(cache=True, error_model="numpy", nogil=True)
def merge_energies(indptr, indices, w, label, members, bounds, sizes, positions, power,
                   pair_a, pair_b, energy, window_r2, most, out, dist, stamp, rank, sid, hkey,
                   hval, work, first, step):
    """Energy of the union of superfacets ``a = pair_a[t]`` and ``b = pair_b[t]``
    around the element nearest its mean, into ``out[t]``, for ``t = first,
    first + step, ...``; ``inf`` where some element of the union lies farther
    (in space) than ``sqrt(window_r2)`` from that element, or where the union's
    energy exceeds ``energy[a] + energy[b] + most`` (its search is then
    abandoned: a merge that costs more than ``most`` is never taken). Returns
    the next free search id. ``dist`` and ``stamp`` are kept by slot within the union
    (an element ``g`` of ``a`` at ``rank[g]``, its place among ``a``'s members, of ``b``
    after ``a``'s): one entry per element of the largest union. Unions overlap:
    concurrent calls need their own ``dist`` and ``stamp``."""
    slack = 1.0 + 1e-9  # abandon only beyond rounding
    for t in range(first, pair_a.shape[0], step):
        a = pair_a[t]
        b = pair_b[t]
        n = 0
        area = 0.0
        for s in (a, b):
            for i in range(bounds[s], bounds[s + 1]):
                work[n] = members[i]
                area += sizes[members[i]]
                n += 1
        c = _nearest_mean(work, n, sizes, positions)
        far = 0.0
        for i in range(n):
            f = work[i]
            dx = positions[f, 0] - positions[c, 0]
            dy = positions[f, 1] - positions[c, 1]
            dz = positions[f, 2] - positions[c, 2]
            far = max(far, dx * dx + dy * dy + dz * dz)
        out[t] = np.inf
        if far <= window_r2:
            limit = (energy[a] + energy[b] + most) * slack
            na = bounds[a + 1] - bounds[a]
            if _union_search_below(indptr, indices, w, label, a, b, na, rank, c, dist, stamp,
                                   sid, hkey, hval, sizes, power, area, limit):
                out[t] = _union_energy(work, n, sizes, dist, stamp, sid, power)
        sid += 1
    return sid


@njit(cache=True, error_model="numpy", nogil=True)
def label_pairs(indptr, indices, label, k):
    """The pairs of labels ``a < b`` that some adjacency joins, each once, as sorted keys
    ``a * k + b``: read from the CSR layout (each adjacency in the row of its lower
    element), so the graph's pairs are not needed."""
    n = indptr.shape[0] - 1
    m = 0
    for i in range(n):
        for x in range(indptr[i], indptr[i + 1]):
            j = indices[x]
            if j > i and label[j] != label[i]:
                m += 1
    keys = np.empty(m, dtype=np.int64)
    m = 0
    for i in range(n):
        a = np.int64(label[i])
        for x in range(indptr[i], indptr[i + 1]):
            j = indices[x]
            b = np.int64(label[j])
            if j > i and b != a:
                keys[m] = min(a, b) * k + max(a, b)
                m += 1
    return np.unique(keys)
