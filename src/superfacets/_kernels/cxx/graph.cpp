// The face graph's build and its per-entry terms: superfacets/_kernels/adjacency.py,
// geometry.py (faces), terms.py and connectivity.py, the same operations in order.
#include <algorithm>

#include "common.hpp"

namespace sfk {

namespace {

constexpr i64 SMALL = 32;  // buckets up to this size: insertion sort

template <class O, class K>
void sort_bucket(O* order, i64 lo, i64 hi, const K* key2) {
    if (hi - lo <= SMALL) {
        for (i64 i = lo + 1; i < hi; ++i) {
            O x = order[i];
            K kx = key2[x];
            i64 j = i - 1;
            while (j >= lo && key2[order[j]] > kx) {
                order[j + 1] = order[j];
                --j;
            }
            order[j + 1] = x;
        }
    } else {
        std::vector<O> part(order + lo, order + hi);
        std::vector<i64> o(hi - lo);
        for (i64 i = 0; i < hi - lo; ++i) o[i] = i;
        std::stable_sort(o.begin(), o.end(),
                         [&](i64 x, i64 y) { return key2[part[x]] < key2[part[y]]; });
        for (i64 i = 0; i < hi - lo; ++i) order[lo + i] = part[o[i]];
    }
}

template <class I, class D>
void sort_row(I* indices, D* dual_edge, i64 s, i64 f) {
    if (f - s <= SMALL) {
        for (i64 i = s + 1; i < f; ++i) {
            I x = indices[i];
            D d = dual_edge[i];
            i64 j = i - 1;
            while (j >= s && indices[j] > x) {
                indices[j + 1] = indices[j];
                dual_edge[j + 1] = dual_edge[j];
                --j;
            }
            indices[j + 1] = x;
            dual_edge[j + 1] = d;
        }
    } else {
        std::vector<i64> o(f - s);
        for (i64 i = 0; i < f - s; ++i) o[i] = i;
        std::stable_sort(o.begin(), o.end(),
                         [&](i64 x, i64 y) { return indices[s + x] < indices[s + y]; });
        std::vector<I> ind(indices + s, indices + f);
        std::vector<D> de(dual_edge + s, dual_edge + f);
        for (i64 i = 0; i < f - s; ++i) {
            indices[s + i] = ind[o[i]];
            dual_edge[s + i] = de[o[i]];
        }
    }
}

// csr_of_pairs into indptr (n + 1)
template <class P, class D>
void csr_of_pairs(const P* lo, const P* hi, i64 e, i64 n, i32* indices, D* dual_edge,
                  i64* indptr) {
    // thread w owns the rows n w / T .. n (w + 1) / T: it reads every pair, in order,
    // and counts and writes only the entries of its rows (no atomics: one pass's layout)
    const i64 T = std::max<i64>(1, std::min<i64>(threads(), mn(n, e) / 65536));
    auto row0 = [&](i64 w) { return n * w / T; };
    indptr[0] = 0;
    on_threads(T, [&](i64 w) {
        const i64 r0 = row0(w), r1 = row0(w + 1);
        std::fill(indptr + r0 + 1, indptr + r1 + 1, 0);
        for (i64 t = 0; t < e; ++t) {
            i64 a = lo[t], b = hi[t];
            if (a >= r0 && a < r1) indptr[a + 1] += 1;
            if (b >= r0 && b < r1) indptr[b + 1] += 1;
        }
    });
    for (i64 v = 0; v < n; ++v) indptr[v + 1] += indptr[v];
    std::vector<i64> fill(indptr, indptr + n);
    on_threads(T, [&](i64 w) {
        const i64 r0 = row0(w), r1 = row0(w + 1);
        for (i64 t = 0; t < e; ++t) {
            i64 a = lo[t], b = hi[t];
            if (a >= r0 && a < r1) {
                i64 p = fill[a]++;
                indices[p] = static_cast<i32>(b);
                dual_edge[p] = static_cast<D>(t);
            }
            if (b >= r0 && b < r1) {
                i64 p = fill[b]++;
                indices[p] = static_cast<i32>(a);
                dual_edge[p] = static_cast<D>(t);
            }
        }
    });
    parallel_for(n, [&](i64 lo, i64 hi) {  // rows apart: on threads
        for (i64 v = lo; v < hi; ++v) sort_row(indices, dual_edge, indptr[v], indptr[v + 1]);
    });
}

// number_pairs: keep and pairs may be null
template <class D, class Q>
void number_pairs_into(const i64* indptr, const i32* indices, i64 n, D* dual_edge, i64* keep,
                       Q* pairs, i64 room = std::numeric_limits<i64>::max()) {
    // Thread w numbers the pairs of its rows (their first ids from the counts of the rows
    // before), and writes each id at its mirror too: for a symmetric CSR whose rows
    // ascend, the j-th entry g of row v (g > v) mirrors the entry of row g after those
    // below v, and j - 1 more (the ids one pass gives, and no entry written twice).
    const i64 T = std::max<i64>(1, std::min<i64>(threads(), n / 65536));
    auto row0 = [&](i64 w) { return n * w / T; };
    std::vector<i64> first_id(T + 1, 0);
    on_threads(T, [&](i64 w) {
        i64 c = 0;
        for (i64 v = row0(w); v < row0(w + 1); ++v)
            for (i64 i = indptr[v]; i < indptr[v + 1]; ++i) c += indices[i] > v;
        first_id[w + 1] = c;
    });
    for (i64 w = 0; w < T; ++w) first_id[w + 1] += first_id[w];
    if (first_id[T] > room) throw OutOfRange("arguments keep, pairs: too short for the pairs");
    on_threads(T, [&](i64 w) {
        i64 nid = first_id[w];
        for (i64 v = row0(w); v < row0(w + 1); ++v) {
            for (i64 i = indptr[v]; i < indptr[v + 1]; ++i) {
                i64 g = indices[i];
                if (g <= v) continue;
                // (binary searches: a vertex may have thousands of neighbours)
                const i32* row = indices + indptr[v];
                i64 j = i - indptr[v] - (std::lower_bound(row, indices + i, g) - row);
                const i32* mir = indices + indptr[g];
                i64 q = indptr[g] + (std::lower_bound(mir, indices + indptr[g + 1], v) - mir) + j;
                if (q >= indptr[g + 1] || indices[q] != v)
                    throw OutOfRange("argument indices: rows not symmetric");
                if (keep) keep[nid] = dual_edge[i];
                if (pairs) {
                    pairs[2 * nid] = static_cast<Q>(v);
                    pairs[2 * nid + 1] = static_cast<Q>(g);
                }
                dual_edge[i] = static_cast<D>(nid);
                dual_edge[q] = static_cast<D>(nid);
                nid += 1;
            }
        }
    });
}

}  // namespace

void triangle_half_edges(nb::handle faces_, nb::handle a_, nb::handle b_, nb::handle skip_) {
    Out<i32> a(a_, "a"), b(b_, "b");
    Out<bool> skip(skip_, "skip");
    with_index(faces_, "faces", [&](auto faces) {  // (int32 or int64 faces)
        if (faces.cols != 3) throw Mismatch("argument faces");
        check_rows(a, 3 * faces.n, "a");
        check_rows(b, 3 * faces.n, "b");
        check_rows(skip, 3 * faces.n, "skip");
        check_range(faces, 0, std::numeric_limits<i32>::max(), "faces");
        nb::gil_scoped_release nogil;
        parallel_for(faces.n, [&](i64 lo, i64 hi) {
            for (i64 f = lo; f < hi; ++f) {
                for (i64 c = 0; c < 3; ++c) {
                    i64 u = faces(f, c);
                    i64 v = faces(f, c == 2 ? 0 : c + 1);
                    i64 h = 3 * f + c;
                    a[h] = static_cast<i32>(mn(u, v));
                    b[h] = static_cast<i32>(mx(u, v));
                    skip[h] = u == v;
                }
            }
        });
    });
}

void count_keys(nb::handle key1_, nb::handle skip_, i64 lo, i64 hi, nb::handle counts_) {
    In<i32> key1(key1_, "key1");
    In<bool> skip(skip_, "skip");
    Out<i64> counts(counts_, "counts");
    check_span(lo, hi, key1.n, skip.n);
    check_range(In<i32>{key1.p + lo, hi - lo, 1}, 0, counts.n, "key1");
    nb::gil_scoped_release nogil;
    for (i64 t = lo; t < hi; ++t)
        if (!skip[t]) counts[key1[t]] += 1;
}

template <class O>
void scatter_into(const In<i32>& key1, const In<bool>& skip, i64 lo, i64 hi, Out<i64>& fill,
                  O* order, i64 n_order) {
    for (i64 t = lo; t < hi; ++t) {
        if (!skip[t]) {
            i64 k = key1[t];
            if (fill[k] < 0 || fill[k] >= n_order) throw OutOfRange("argument fill: past order");
            order[fill[k]] = static_cast<O>(t);
            fill[k] += 1;
        }
    }
}

void scatter_keys(nb::handle key1_, nb::handle skip_, i64 lo, i64 hi, nb::handle fill_,
                  nb::handle order_) {
    In<i32> key1(key1_, "key1");
    In<bool> skip(skip_, "skip");
    Out<i64> fill(fill_, "fill");
    check_span(lo, hi, key1.n, skip.n);
    check_range(In<i32>{key1.p + lo, hi - lo, 1}, 0, fill.n, "key1");
    if (matches<i32>(order_)) {
        Out<i32> order(order_, "order");
        nb::gil_scoped_release nogil;
        scatter_into(key1, skip, lo, hi, fill, order.p, order.n);
    } else {
        Out<i64> order(order_, "order");
        nb::gil_scoped_release nogil;
        scatter_into(key1, skip, lo, hi, fill, order.p, order.n);
    }
}

void sort_buckets(nb::handle order_, nb::handle starts_, nb::handle key2_, i64 v0, i64 v1) {
    Out<i32> order(order_, "order");
    In<i64> starts(starts_, "starts");
    In<i32> key2(key2_, "key2");
    check_span(v0, v1, starts.n - 1, starts.n - 1);
    check_csr(In<i64>{starts.p + v0, v1 - v0 + 1, 1}, order, v1 - v0, key2.n, "starts");
    nb::gil_scoped_release nogil;
    for (i64 v = v0; v < v1; ++v)
        if (starts[v + 1] - starts[v] > 1) sort_bucket(order.p, starts[v], starts[v + 1], key2.p);
}

// Faces around one edge up to which every two are paired (tests/oracle: MAX_FAN)
constexpr i64 kMaxFan = 8;

// adjacency.group_pairs, on threads: ranges of `half` cut at edge starts (each holds
// whole edges), each range counted, then written from its place, so the arrays are
// those of one pass (a face paired with itself is left out of the counts).
nb::tuple group_pairs(nb::handle half_, nb::handle owner_, nb::handle a_, nb::handle b_) {
    In<i32> half(half_, "half"), owner(owner_, "owner"), a(a_, "a"), b(b_, "b");
    const i64 n = half.n;
    const bool tri = owner.n == 0;
    check_rows(b, a.n, "b", true);
    check_range(half, 0, a.n, "half");
    if (!tri) check_rows(owner, a.n, "owner");
    std::vector<char> isnew(n + 1);
    isnew[n] = 1;
    auto same = [&](i64 i) {  // half[i] on the edge of half[i - 1]
        return a[half[i]] == a[half[i - 1]] && b[half[i]] == b[half[i - 1]];
    };
    auto face = [&](i64 x) { return tri ? half[x] / 3 : owner[half[x]]; };
    // the partners y of x in the run [i, j) of one edge: every later face up to
    // kMaxFan faces around the edge; beyond (a fan of copies, a "book" of thousands of
    // faces), the next face only, the last with the first: pairs in proportion to faces
    auto each_partner = [](i64 x, i64 i, i64 j, auto&& g) {
        if (j - i <= kMaxFan) {
            for (i64 y = x + 1; y < j; ++y) g(y);
        } else {
            g(x + 1 < j ? x + 1 : i);
        }
    };
    const i64 T = std::max<i64>(1, std::min<i64>(threads(), n / 65536));
    std::vector<i64> cut(T + 1), n_bound(T + 1, 0), n_pairs(T + 1, 0);
    {
        nb::gil_scoped_release nogil;
        for (i64 t = 0; t <= T; ++t) {
            i64 j = n * t / T;
            while (j > 0 && j < n && same(j)) ++j;
            cut[t] = t ? std::max(j, cut[t - 1]) : 0;
        }
        on_threads(T, [&](i64 t) {  // mark runs, count boundaries and pairs
            i64 nb = 0, np_ = 0;
            for (i64 i = cut[t]; i < cut[t + 1]; ++i) isnew[i] = i == 0 || !same(i);
            for (i64 i = cut[t]; i < cut[t + 1];) {
                i64 j = i + 1;
                while (j < cut[t + 1] && !isnew[j]) ++j;
                if (j - i == 1) {
                    ++nb;
                } else {
                    for (i64 x = i; x < j; ++x)
                        each_partner(x, i, j, [&](i64 y) { np_ += face(x) != face(y); });
                }
                i = j;
            }
            n_bound[t + 1] = nb;
            n_pairs[t + 1] = np_;
        });
        for (i64 t = 0; t < T; ++t) {
            n_bound[t + 1] += n_bound[t];
            n_pairs[t + 1] += n_pairs[t];
        }
    }
    Out<i64> boundary;
    Out<i32> lo, hi, ea, eb;
    auto boundary_a = fresh(n_bound[T], boundary);
    auto lo_a = fresh(n_pairs[T], lo), hi_a = fresh(n_pairs[T], hi);
    auto ea_a = fresh(n_pairs[T], ea), eb_a = fresh(n_pairs[T], eb);
    {
        nb::gil_scoped_release nogil;
        on_threads(T, [&](i64 t) {
            i64 nb = n_bound[t], p = n_pairs[t];
            for (i64 i = cut[t]; i < cut[t + 1];) {
                i64 j = i + 1;
                while (!isnew[j]) ++j;
                if (j - i == 1) {
                    boundary[nb++] = i;
                } else {
                    i32 va = a[half[i]], vb = b[half[i]];
                    for (i64 x = i; x < j; ++x) {
                        each_partner(x, i, j, [&](i64 y) {
                            i32 f = face(x), g = face(y);
                            if (f != g) {
                                lo[p] = mn(f, g);
                                hi[p] = mx(f, g);
                                ea[p] = va;
                                eb[p] = vb;
                                ++p;
                            }
                        });
                    }
                }
                i = j;
            }
        });
    }
    return nb::make_tuple(boundary_a, lo_a, hi_a, ea_a, eb_a);
}

// adjacency.take_pairs, on threads (each row on its own)
void take_pairs(nb::handle first_, nb::handle lo_, nb::handle hi_, nb::handle ka_,
                nb::handle kb_, nb::handle pairs_, nb::handle edges_) {
    In<i64> first(first_, "first");
    In<i32> lo(lo_, "lo"), hi(hi_, "hi"), ka(ka_, "ka"), kb(kb_, "kb");
    Out<i32> pairs(pairs_, "pairs"), edges(edges_, "edges");
    if (pairs.cols != 2 || edges.cols != 2 || pairs.n != first.n || edges.n != first.n)
        throw Mismatch("argument pairs");
    for (auto* x : {&hi, &ka, &kb}) check_rows(*x, lo.n, "hi, ka, kb");
    check_range(first, 0, lo.n, "first");
    nb::gil_scoped_release nogil;
    parallel_for(first.n, [&](i64 t0, i64 t1) {
        for (i64 t = t0; t < t1; ++t) {
            const i64 u = first[t];
            pairs(t, 0) = lo[u];
            pairs(t, 1) = hi[u];
            edges(t, 0) = ka[u];
            edges(t, 1) = kb[u];
        }
    });
}

// adjacency.shared_edges, on threads (each pair on its own): the mesh edge (a, b), a < b,
// two triangles share, from their vertices: the two distinct vertices of face i that
// face j has too. With `check`, edges are compared with what they would be, not written.
// Returns the pairs that do not share exactly two distinct vertices, or (check) whose
// edge differs: 0 where the edges are those of the triangles' pairs.
template <class F, class P, class E>
i64 shared_edges_t(const In<F>& faces, const In<P>& pairs, E* edges, bool check) {
    std::atomic<i64> bad{0};
    parallel_for(pairs.n, [&](i64 t0, i64 t1) {
        i64 miss = 0;
        for (i64 t = t0; t < t1; ++t) {
            const F* fi = faces.p + 3 * static_cast<i64>(pairs(t, 0));
            const F* fj = faces.p + 3 * static_cast<i64>(pairs(t, 1));
            i64 got[3];
            int k = 0;
            for (int c = 0; c < 3; ++c) {
                const i64 v = fi[c];
                bool twice = false;
                for (int u = 0; u < k; ++u) twice |= got[u] == v;
                if (!twice && (fj[0] == v || fj[1] == v || fj[2] == v)) got[k++] = v;
            }
            if (k != 2) {
                ++miss;
                continue;
            }
            const E a = static_cast<E>(mn(got[0], got[1])), b = static_cast<E>(mx(got[0], got[1]));
            if (check) {
                miss += edges[2 * t] != a || edges[2 * t + 1] != b;
            } else {
                edges[2 * t] = a;
                edges[2 * t + 1] = b;
            }
        }
        bad += miss;
    });
    return bad.load();
}

i64 shared_edges(nb::handle faces_, nb::handle pairs_, nb::handle edges_, bool check) {
    return with_index(faces_, "faces", [&](const auto& faces) {
        return with_index(pairs_, "pairs", [&](const auto& pairs) -> i64 {
            if (faces.cols != 3) throw Mismatch("argument faces");
            if (pairs.cols != 2) throw Mismatch("argument pairs");
            check_range(pairs, 0, faces.n, "pairs");
            auto run = [&](auto& edges) {
                if (edges.cols != 2 || edges.n != pairs.n) throw Mismatch("argument edges");
                nb::gil_scoped_release nogil;
                return shared_edges_t(faces, pairs, edges.p, check);
            };
            if (matches<i32>(edges_)) {
                Out<i32> edges(edges_, "edges");
                return run(edges);
            }
            Out<i64> edges(edges_, "edges");
            return run(edges);
        });
    });
}

template <class D>
nb::tuple csr_of_face_pairs_t(nb::handle lo_, nb::handle hi_, nb::handle ka_, nb::handle kb_,
                              i64 n, nb::handle indices_, nb::handle dual_edge_) {
    In<i32> lo(lo_, "lo"), hi(hi_, "hi"), ka(ka_, "ka"), kb(kb_, "kb");
    Out<i32> indices(indices_, "indices");
    Out<D> dual_edge(dual_edge_, "dual_edge");
    for (auto* x : {&hi, &ka, &kb}) check_rows(*x, lo.n, "hi, ka, kb", true);
    check_rows(indices, 2 * lo.n, "indices");
    check_rows(dual_edge, 2 * lo.n, "dual_edge");
    check_range(lo, 0, n, "lo");
    check_range(hi, 0, n, "hi");
    Out<i64> indptr;
    auto indptr_a = fresh(n + 1, indptr);
    i64 out = 0;
    {
        nb::gil_scoped_release nogil;
        csr_of_pairs(lo.p, hi.p, lo.n, n, indices.p, dual_edge.p, indptr.p);
        for (i64 v = 0; v < n; ++v) {
            i64 s = indptr[v], f = indptr[v + 1];
            indptr[v] = out;
            i64 i = s;
            while (i < f) {
                i32 g = indices[i];
                D best = dual_edge[i];
                i64 j = i + 1;
                while (j < f && indices[j] == g) {
                    D u = dual_edge[j];
                    if (ka[u] < ka[best] || (ka[u] == ka[best] && kb[u] < kb[best])) best = u;
                    ++j;
                }
                indices[out] = g;
                dual_edge[out] = best;
                ++out;
                i = j;
            }
        }
        indptr[n] = out;
    }
    Out<i64> keep;
    auto keep_a = fresh(out / 2, keep);
    {
        nb::gil_scoped_release nogil;
        number_pairs_into(indptr.p, indices.p, n, dual_edge.p, keep.p, static_cast<i32*>(nullptr));
    }
    return nb::make_tuple(indptr_a, keep_a);
}

// (int64 adjacency numbers from 2**31 CSR entries on)
nb::tuple csr_of_face_pairs(nb::handle lo, nb::handle hi, nb::handle ka, nb::handle kb, i64 n,
                            nb::handle indices, nb::handle dual_edge) {
    if (matches<i32>(dual_edge))
        return csr_of_face_pairs_t<i32>(lo, hi, ka, kb, n, indices, dual_edge);
    return csr_of_face_pairs_t<i64>(lo, hi, ka, kb, n, indices, dual_edge);
}

// adjacency.same_label_components, on threads: a union-find over the adjacencies within
// a label (each listed in both rows of the CSR; j > i taken), a root linked only under
// a smaller one, so each piece's root is its lowest element; the pieces then numbered
// in the order of their roots: the depth-first numbering of one pass, bit for bit.
namespace {

inline i64 uf_find(i64* parent, i64 x) {  // path halving; a parent only moves up
    while (true) {
        i64 p = __atomic_load_n(parent + x, __ATOMIC_RELAXED);
        if (p == x) return x;
        i64 g = __atomic_load_n(parent + p, __ATOMIC_RELAXED);
        if (g != p) __atomic_store_n(parent + x, g, __ATOMIC_RELAXED);
        x = g;
    }
}

inline void uf_union(i64* parent, i64 a, i64 b) {
    while (true) {
        a = uf_find(parent, a);
        b = uf_find(parent, b);
        if (a == b) return;
        if (a > b) std::swap(a, b);  // b, the larger root, goes under a
        i64 expected = b;
        if (__atomic_compare_exchange_n(parent + b, &expected, a, false, __ATOMIC_ACQ_REL,
                                        __ATOMIC_RELAXED))
            return;
    }
}

}  // namespace

nb::object same_label_components(nb::handle indptr_, nb::handle indices_,
                                       nb::handle labels_) {
    In<i64> indptr(indptr_, "indptr"), labels(labels_, "labels");
    In<i32> indices(indices_, "indices");
    const i64 n = labels.n;
    if (indptr.n != n + 1) throw Mismatch("argument indptr");
    check_csr(indptr, indices, n, n);
    Out<i64> comp;
    auto comp_a = fresh(n, comp);
    {
        nb::gil_scoped_release nogil;
        std::vector<i64> root(n);
        i64* parent = root.data();
        parallel_for(n, [&](i64 lo, i64 hi) {
            for (i64 i = lo; i < hi; ++i) parent[i] = i;
        });
        parallel_for(n, [&](i64 lo, i64 hi) {
            for (i64 i = lo; i < hi; ++i) {
                const i64 lab = labels[i];
                for (i64 e = indptr[i]; e < indptr[i + 1]; ++e) {
                    const i64 j = indices[e];
                    if (j > i && labels[j] == lab) uf_union(parent, i, j);
                }
            }
        });
        parallel_for(n, [&](i64 lo, i64 hi) {  // every element straight to its root
            for (i64 i = lo; i < hi; ++i) parent[i] = uf_find(parent, i);
        });
        // the roots numbered in order: a count per range of elements, then each range's
        // roots from its first number (comp holds the roots' numbers first)
        const i64 T = std::max<i64>(1, std::min<i64>(threads(), n / 4096));
        std::vector<i64> first(T + 1, 0);
        auto range = [&](i64 t) { return n * t / T; };
        on_threads(T, [&](i64 t) {
            i64 m = 0;
            for (i64 i = range(t); i < range(t + 1); ++i) m += parent[i] == i;
            first[t + 1] = m;
        });
        for (i64 t = 0; t < T; ++t) first[t + 1] += first[t];
        on_threads(T, [&](i64 t) {
            i64 c = first[t];
            for (i64 i = range(t); i < range(t + 1); ++i)
                if (parent[i] == i) comp[i] = c++;
        });
        parallel_for(n, [&](i64 lo, i64 hi) {
            for (i64 i = lo; i < hi; ++i)
                if (parent[i] != i) comp[i] = comp[parent[i]];
        });
    }
    return comp_a;
}

// geometry.py: triangles' centroids, areas and unit normals
void face_geometry(nb::handle vertices_, nb::handle faces_, nb::handle centroids_,
                   nb::handle areas_, nb::handle normals_) {
    In<double> v(vertices_, "vertices");
    Out<double> centroids(centroids_, "centroids"), areas(areas_, "areas"),
        normals(normals_, "normals");
    with_index(faces_, "faces", [&](auto faces) {  // (int32 or int64 faces)
        if (normals.cols != 3 || centroids.cols != 3 || faces.cols != 3)
            throw Mismatch("argument normals");
        for (auto* x : {&centroids, &areas, &normals}) check_rows(*x, faces.n, "centroids");
        if (v.cols != 3) throw Mismatch("argument vertices");
        check_range(faces, 0, v.n, "faces");
        nb::gil_scoped_release nogil;
        for (i64 f = 0; f < faces.n; ++f) {
            i64 i = faces(f, 0), j = faces(f, 1), k = faces(f, 2);
            for (i64 t = 0; t < 3; ++t) centroids(f, t) = (v(i, t) + v(j, t) + v(k, t)) / 3.0;
            double a0 = v(j, 0) - v(i, 0), a1 = v(j, 1) - v(i, 1), a2 = v(j, 2) - v(i, 2);
            double b0 = v(k, 0) - v(i, 0), b1 = v(k, 1) - v(i, 1), b2 = v(k, 2) - v(i, 2);
            double c0 = a1 * b2 - a2 * b1;
            double c1 = a2 * b0 - a0 * b2;
            double c2 = a0 * b1 - a1 * b0;
            double norm = store_unit(normals.p + 3 * f, c0, c1, c2);
            areas[f] = 0.5 * norm;
        }
    });
}

// geometry.py: polygons of any size (Newell's normal, the fan's signed-area centroid)
void polygon_geometry(nb::handle vertices_, nb::handle corners_, nb::handle offsets_,
                      nb::handle centroids_, nb::handle areas_, nb::handle normals_) {
    In<double> v(vertices_, "vertices");
    In<i64> corners(corners_, "corners"), offsets(offsets_, "offsets");
    Out<double> centroids(centroids_, "centroids"), areas(areas_, "areas"),
        normals(normals_, "normals");
    if (v.cols != 3 || centroids.cols != 3 || normals.cols != 3)
        throw Mismatch("argument vertices");
    check_csr(offsets, corners, -1, v.n, "offsets");
    for (i64 f = 0; f + 1 < offsets.n; ++f)
        if (offsets[f + 1] == offsets[f]) throw OutOfRange("argument offsets: an empty polygon");
    for (auto* x : {&centroids, &areas, &normals}) check_rows(*x, offsets.n - 1, "centroids");
    nb::gil_scoped_release nogil;
    for (i64 f = 0; f < offsets.n - 1; ++f) {
        const i64 a = offsets[f], k = offsets[f + 1] - a;
        const i64 o = corners[a];
        const double ox = v(o, 0), oy = v(o, 1), oz = v(o, 2);
        auto rel = [&](i64 p, double* q) {
            q[0] = v(p, 0) - ox;
            q[1] = v(p, 1) - oy;
            q[2] = v(p, 2) - oz;
        };
        double nx = 0.0, ny = 0.0, nz = 0.0, P[3], Q[3];
        for (i64 i = 0; i < k; ++i) {
            rel(corners[a + i], P);
            rel(corners[a + (i + 1) % k], Q);
            nx += (P[1] - Q[1]) * (P[2] + Q[2]);
            ny += (P[2] - Q[2]) * (P[0] + Q[0]);
            nz += (P[0] - Q[0]) * (P[1] + Q[1]);
        }
        double norm = std::sqrt(nx * nx + ny * ny + nz * nz);
        areas[f] = 0.5 * norm;
        if (norm > 0) {
            nx /= norm;
            ny /= norm;
            nz /= norm;
        } else {
            nx = ny = nz = 0.0;
        }
        normals(f, 0) = nx;
        normals(f, 1) = ny;
        normals(f, 2) = nz;
        double wsum = 0.0, cx = 0.0, cy = 0.0, cz = 0.0;
        for (i64 i = 1; i < k - 1; ++i) {
            rel(corners[a + i], P);
            rel(corners[a + i + 1], Q);
            double w = (P[1] * Q[2] - P[2] * Q[1]) * nx + (P[2] * Q[0] - P[0] * Q[2]) * ny +
                       (P[0] * Q[1] - P[1] * Q[0]) * nz;
            wsum += w;
            cx += w * (P[0] + Q[0]);
            cy += w * (P[1] + Q[1]);
            cz += w * (P[2] + Q[2]);
        }
        if (wsum != 0.0 && norm > 0) {
            centroids(f, 0) = ox + cx / (3.0 * wsum);
            centroids(f, 1) = oy + cy / (3.0 * wsum);
            centroids(f, 2) = oz + cz / (3.0 * wsum);
        } else {
            double sx = 0.0, sy = 0.0, sz = 0.0;
            for (i64 i = 0; i < k; ++i) {
                i64 p = corners[a + i];
                sx += v(p, 0);
                sy += v(p, 1);
                sz += v(p, 2);
            }
            centroids(f, 0) = sx / static_cast<double>(k);
            centroids(f, 1) = sy / static_cast<double>(k);
            centroids(f, 2) = sz / static_cast<double>(k);
        }
    }
}

void face_terms(nb::handle vertices_, nb::handle centroids_, nb::handle normals_,
                nb::handle pairs_, nb::handle edges_, i64 lo, i64 hi, nb::handle geo_,
                nb::handle cos_, nb::handle concave_) {
    In<double> v(vertices_, "vertices"), c(centroids_, "centroids"), nr(normals_, "normals");
    In<i32> pairs(pairs_, "pairs"), edges(edges_, "edges");
    Out<double> geo(geo_, "geo"), cs(cos_, "cos");
    Out<bool> concave(concave_, "concave");
    if (pairs.cols != 2 || edges.cols != 2 || v.cols != 3 || c.cols != 3 || nr.cols != 3)
        throw Mismatch("argument pairs");
    check_span(lo, hi, pairs.n, edges.n);
    check_range(In<i32>{pairs.p + 2 * lo, hi - lo, 2}, 0, mn(c.n, nr.n), "pairs");
    check_range(In<i32>{edges.p + 2 * lo, hi - lo, 2}, 0, v.n, "edges");
    for (auto* x : {&geo, &cs}) check_rows(*x, hi - lo, "geo");
    check_rows(concave, hi - lo, "concave");
    nb::gil_scoped_release nogil;
    for (i64 t = lo; t < hi; ++t) {
        i64 i = pairs(t, 0), j = pairs(t, 1), a = edges(t, 0), b = edges(t, 1);
        double mx_ = 0.5 * (v(a, 0) + v(b, 0));
        double my = 0.5 * (v(a, 1) + v(b, 1));
        double mz = 0.5 * (v(a, 2) + v(b, 2));
        double dx = c(i, 0) - mx_, dy = c(i, 1) - my, dz = c(i, 2) - mz;
        double ex = mx_ - c(j, 0), ey = my - c(j, 1), ez = mz - c(j, 2);
        i64 u = t - lo;
        geo[u] = std::sqrt(dx * dx + dy * dy + dz * dz) + std::sqrt(ex * ex + ey * ey + ez * ez);
        double d = (nr(i, 0) * nr(j, 0) + nr(i, 2) * nr(j, 2)) + nr(i, 1) * nr(j, 1);
        cs[u] = mn(mx(d, -1.0), 1.0);
        double s = (nr(i, 0) * (c(j, 0) - c(i, 0)) + nr(i, 2) * (c(j, 2) - c(i, 2))) +
                   nr(i, 1) * (c(j, 1) - c(i, 1));
        concave[u] = s > 0;
    }
}

template <class E>
void lengths_into(const In<double>& v, const E* edges, i64 m, double* out) {
    parallel_for(m, [&](i64 lo, i64 hi) {
        for (i64 t = lo; t < hi; ++t) {
            i64 a = edges[2 * t], b = edges[2 * t + 1];
            double x = v(b, 0) - v(a, 0), y = v(b, 1) - v(a, 1), z = v(b, 2) - v(a, 2);
            out[t] = std::sqrt(x * x + y * y + z * z);
        }
    });
}

void edge_lengths(nb::handle vertices_, nb::handle edges_, nb::handle out_) {
    In<double> v(vertices_, "vertices");
    Out<double> out(out_, "out");
    if (matches<i32>(edges_)) {
        In<i32> e(edges_, "edges");
        check_lengths(v, e, out);
        nb::gil_scoped_release nogil;
        lengths_into(v, e.p, e.n, out.p);
    } else {
        In<i64> e(edges_, "edges");
        check_lengths(v, e, out);
        nb::gil_scoped_release nogil;
        lengths_into(v, e.p, e.n, out.p);
    }
}

// terms.py
// terms.per_entry (float64 or float32 values, int32 adjacencies), on threads (each entry
// on its own)
void per_entry(nb::handle values_, nb::handle dual_edge_, nb::handle out_) {
    with_index(dual_edge_, "dual_edge", [&](const auto& dual_edge) {
        with_real(values_, "values", [&](const auto& values) {
            using T = std::remove_cv_t<std::remove_reference_t<decltype(values[0])>>;
            Out<T> out(out_, "out");  // (the values' dtype: float64 or float32)
            if (out.n != dual_edge.n) throw Mismatch("argument out");
            check_range(dual_edge, 0, values.n, "dual_edge");
            nb::gil_scoped_release nogil;
            parallel_for(dual_edge.n, [&](i64 lo, i64 hi) {
                for (i64 e = lo; e < hi; ++e) out[e] = values[dual_edge[e]];
            });
        });
    });
}

// terms.convex_scaled_csr: float64 or float32 weights, the values in the weights' dtype
// (each computed in float64, then rounded)
nb::object convex_scaled_csr(nb::handle weights_, nb::handle dual_edge_,
                                      nb::handle concave_, nb::handle cos_, nb::handle span_,
                                      double coef) {
    In<double> cs(cos_, "cos"), span(span_, "span");
    In<bool> concave(concave_, "concave");
    return with_real(weights_, "weights", [&](const auto& weights) -> nb::object {
        using T = std::remove_cv_t<std::remove_reference_t<decltype(weights[0])>>;
        with_index(dual_edge_, "dual_edge", [&](const auto& dual_edge) {
            check_rows(dual_edge, weights.n, "dual_edge");
            check_range(dual_edge, 0, mn(mn(concave.n, cs.n), span.n), "dual_edge", weights.n);
        });
        Out<T> out;
        auto out_a = fresh(weights.n, out);
        with_index(dual_edge_, "dual_edge", [&](const auto& dual_edge) {
            nb::gil_scoped_release nogil;
            // (no array of one delta per adjacency: 8 B each; both entries of an adjacency
            // compute the same value)
            parallel_for(weights.n, [&](i64 lo, i64 hi) {
                for (i64 e = lo; e < hi; ++e) {
                    i64 d = dual_edge[e];
                    const double we = static_cast<double>(weights[e]);
                    out[e] = static_cast<T>(
                        concave[d] ? we : mx(we - coef * span[d] * std::acos(cs[d]), 0.0));
                }
            });
        });
        return out_a;
    });
}

nb::object cut_costs_csr(nb::handle dual_edge_, nb::handle concave_, nb::handle cos_,
                                  nb::handle lengths_, double factor, double eta_convex,
                                  double scale) {
    In<bool> concave(concave_, "concave");
    In<double> cs(cos_, "cos"), lengths(lengths_, "lengths");
    Out<double> out;
    check_rows(concave, cs.n, "concave");
    check_rows(lengths, cs.n, "lengths");
    with_index(dual_edge_, "dual_edge",
               [&](const auto& dual_edge) { check_range(dual_edge, 0, cs.n, "dual_edge"); });
    auto out_a = fresh(size_of(dual_edge_), out);
    with_index(dual_edge_, "dual_edge", [&](const auto& dual_edge) {
        nb::gil_scoped_release nogil;
        std::vector<double> cost(cs.n);  // (each value on its own: on threads)
        parallel_for(cs.n, [&](i64 lo, i64 hi) {
            for (i64 d = lo; d < hi; ++d) {
                double eta = concave[d] ? 1.0 : eta_convex;
                cost[d] = lengths[d] / (1.0 + factor * eta * std::acos(cs[d])) * scale;
            }
        });
        parallel_for(dual_edge.n, [&](i64 lo, i64 hi) {
            for (i64 e = lo; e < hi; ++e) out[e] = cost[dual_edge[e]];
        });
    });
    return out_a;
}

// connectivity.py
namespace {
i64 find(std::vector<i64>& parent, i64 x) {
    i64 root = x;
    while (parent[root] != root) root = parent[root];
    while (parent[x] != root) {
        i64 nxt = parent[x];
        parent[x] = root;
        x = nxt;
    }
    return root;
}
}  // namespace

nb::object merge_strays(nb::handle strays_, nb::handle nb_indptr_, nb::handle nb_indices_,
                              nb::handle nb_data_, i64 n_pieces) {
    In<i64> strays(strays_, "strays"), nb_indptr(nb_indptr_, "nb_indptr"),
        nb_indices(nb_indices_, "nb_indices");
    In<double> nb_data(nb_data_, "nb_data");
    if (n_pieces < 0) throw OutOfRange("argument n_pieces");
    check_csr(nb_indptr, nb_indices, n_pieces, n_pieces, "nb_indptr");
    check_rows(nb_data, nb_indptr[n_pieces], "nb_data");
    check_range(strays, 0, n_pieces, "strays");
    Out<i64> root;
    auto root_a = fresh(n_pieces, root);
    {
        nb::gil_scoped_release nogil;
        std::vector<i64> parent(n_pieces);
        for (i64 q = 0; q < n_pieces; ++q) parent[q] = q;
        std::vector<double> total(n_pieces, 0.0);
        std::vector<char> seen(n_pieces, 0);
        std::vector<i64> touched(n_pieces);
        for (i64 i = 0; i < strays.n; ++i) {
            i64 p = strays[i];
            i64 rp = find(parent, p);
            i64 m = 0;
            for (i64 e = nb_indptr[p]; e < nb_indptr[p + 1]; ++e) {
                i64 q = find(parent, nb_indices[e]);
                if (q == rp) continue;
                if (!seen[q]) {
                    seen[q] = 1;
                    touched[m++] = q;
                }
                total[q] += nb_data[e];
            }
            if (m == 0) continue;
            i64 target = -1;
            double best = 0.0;
            for (i64 j = 0; j < m; ++j) {
                i64 q = touched[j];
                if (target < 0 || total[q] > best || (total[q] == best && q < target)) {
                    target = q;
                    best = total[q];
                }
                total[q] = 0.0;
                seen[q] = 0;
            }
            parent[rp] = target;
        }
        for (i64 q = 0; q < n_pieces; ++q) root[q] = find(parent, q);
    }
    return root_a;
}

// connectivity.stray_borders, on threads: each thread a range of rows, counted first
// (its entries of either side and its adjacencies, for the lengths' numbers), then
// written at its places: the entries in the order of one pass.
nb::tuple stray_borders(nb::handle indptr_, nb::handle indices_, nb::handle piece_,
                        nb::handle is_main_, nb::handle lengths_, nb::handle shares_) {
    In<i64> indptr(indptr_, "indptr"), piece(piece_, "piece");
    In<i32> indices(indices_, "indices");
    In<bool> is_main(is_main_, "is_main");
    In<double> lengths(lengths_, "lengths"), shares(shares_, "shares");
    const i64 n = check_csr(indptr, indices, -1, piece.n);
    check_rows(piece, n, "piece", true);
    check_range(piece, 0, is_main.n, "piece");
    if (shares.n) check_rows(shares, n, "shares");
    else {
        i64 above = 0;  // (the adjacencies: lengths has one each)
        for (i64 i = 0; i < n; ++i)
            for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) above += indices[x] > i;
        check_rows(lengths, above, "lengths");
    }
    const i64 T = std::max<i64>(1, std::min<i64>(threads(), n / 4096));
    auto row = [&](i64 t) { return n * t / T; };
    // per thread: entries with a stray row on side 0 and on side 1, adjacencies before
    std::vector<i64> side0(T + 1, 0), side1(T + 1, 0), pairs(T + 1, 0);
    {
        nb::gil_scoped_release nogil;
        on_threads(T, [&](i64 t) {
            i64 s0 = 0, s1 = 0, np_ = 0;
            for (i64 i = row(t); i < row(t + 1); ++i)
                for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) {
                    i64 j = indices[x];
                    if (j > i) {
                        ++np_;
                        i64 p = piece[i], q = piece[j];
                        if (p != q) {
                            s0 += !is_main[p];
                            s1 += !is_main[q];
                        }
                    }
                }
            side0[t + 1] = s0;
            side1[t + 1] = s1;
            pairs[t + 1] = np_;
        });
        for (i64 t = 0; t < T; ++t) {
            side0[t + 1] += side0[t];
            side1[t + 1] += side1[t];
            pairs[t + 1] += pairs[t];
        }
    }
    const i64 m = side0[T] + side1[T];
    Out<i64> a, b;
    Out<double> w;
    auto a_a = fresh(m, a), b_a = fresh(m, b);
    auto w_a = fresh(m, w);
    {
        nb::gil_scoped_release nogil;
        on_threads(T, [&](i64 t) {
            for (int side = 0; side < 2; ++side) {
                i64 u = side == 0 ? side0[t] : side0[T] + side1[t];
                i64 pt = pairs[t];
                for (i64 i = row(t); i < row(t + 1); ++i)
                    for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) {
                        i64 j = indices[x];
                        if (j > i) {
                            i64 p = side == 0 ? piece[i] : piece[j];
                            i64 q = side == 0 ? piece[j] : piece[i];
                            if (p != q && !is_main[p]) {
                                a[u] = p;
                                b[u] = q;
                                w[u] = shares.n ? 0.5 * (shares[i] + shares[j]) : lengths[pt];
                                ++u;
                            }
                            ++pt;
                        }
                    }
            }
        });
    }
    return nb::make_tuple(a_a, b_a, w_a);
}

template <class P, class D>
nb::object csr_of_pairs_t(nb::handle lo_, nb::handle hi_, i64 n, nb::handle indices_,
                                nb::handle dual_edge_) {
    In<P> lo(lo_, "lo"), hi(hi_, "hi");
    Out<i32> indices(indices_, "indices");
    Out<D> dual_edge(dual_edge_, "dual_edge");
    check_rows(hi, lo.n, "hi", true);
    check_rows(indices, 2 * lo.n, "indices");
    check_rows(dual_edge, 2 * lo.n, "dual_edge");
    check_range(lo, 0, n, "lo");
    check_range(hi, 0, n, "hi");
    Out<i64> indptr;
    auto indptr_a = fresh(n + 1, indptr);
    {
        nb::gil_scoped_release nogil;
        csr_of_pairs(lo.p, hi.p, lo.n, n, indices.p, dual_edge.p, indptr.p);
    }
    return indptr_a;
}

nb::object csr_of_pairs_any(nb::handle lo, nb::handle hi, i64 n, nb::handle indices,
                                  nb::handle dual_edge) {
    const bool p32 = matches<i32>(lo), d32 = matches<i32>(dual_edge);
    if (p32) return d32 ? csr_of_pairs_t<i32, i32>(lo, hi, n, indices, dual_edge)
                        : csr_of_pairs_t<i32, i64>(lo, hi, n, indices, dual_edge);
    return d32 ? csr_of_pairs_t<i64, i32>(lo, hi, n, indices, dual_edge)
               : csr_of_pairs_t<i64, i64>(lo, hi, n, indices, dual_edge);
}

template <class D, class Q>
void number_pairs_t(nb::handle indptr_, nb::handle indices_, i64 n, nb::handle dual_edge_,
                    nb::handle keep_, nb::handle pairs_) {
    In<i64> indptr(indptr_, "indptr");
    In<i32> indices(indices_, "indices");
    Out<D> dual_edge(dual_edge_, "dual_edge");
    Out<i64> keep(keep_, "keep");
    Out<Q> pairs(pairs_, "pairs");
    check_csr(indptr, indices, n, n);
    check_rows(dual_edge, indptr[n], "dual_edge");
    for (i64 v = 0; v < n; ++v)  // (rows ascending: their mirrors found by bisection)
        for (i64 i = indptr[v] + 1; i < indptr[v + 1]; ++i)
            if (indices[i] < indices[i - 1]) throw OutOfRange("argument indices: rows not sorted");
    const i64 room = mn(keep.n ? keep.n : std::numeric_limits<i64>::max(),
                        pairs.n ? pairs.n * pairs.cols / 2 : std::numeric_limits<i64>::max());
    nb::gil_scoped_release nogil;
    number_pairs_into(indptr.p, indices.p, n, dual_edge.p, keep.n ? keep.p : nullptr,
                      pairs.n ? pairs.p : static_cast<Q*>(nullptr), room);
}

void number_pairs(nb::handle indptr, nb::handle indices, i64 n, nb::handle dual_edge,
                  nb::handle keep, nb::handle pairs) {
    const bool d32 = matches<i32>(dual_edge), q32 = matches<i32>(pairs);
    if (d32) return q32 ? number_pairs_t<i32, i32>(indptr, indices, n, dual_edge, keep, pairs)
                        : number_pairs_t<i32, i64>(indptr, indices, n, dual_edge, keep, pairs);
    return q32 ? number_pairs_t<i64, i32>(indptr, indices, n, dual_edge, keep, pairs)
               : number_pairs_t<i64, i64>(indptr, indices, n, dual_edge, keep, pairs);
}

void bind_graph(nb::module_& m) {
    m.def("csr_of_pairs", &csr_of_pairs_any);
    m.def("number_pairs", &number_pairs);
    m.def("triangle_half_edges", &triangle_half_edges);
    m.def("count_keys", &count_keys);
    m.def("scatter_keys", &scatter_keys);
    m.def("sort_buckets", &sort_buckets);
    m.def("group_pairs", &group_pairs);
    m.def("csr_of_face_pairs", &csr_of_face_pairs);
    m.def("take_pairs", &take_pairs);
    m.def("shared_edges", &shared_edges);
    m.def("same_label_components", &same_label_components);
    m.def("face_geometry", &face_geometry);
    m.def("face_terms", &face_terms);
    m.def("polygon_geometry", &polygon_geometry);
    m.def("edge_lengths", &edge_lengths);
    m.def("convex_scaled_csr", &convex_scaled_csr);
    m.def("cut_costs_csr", &cut_costs_csr);
    m.def("per_entry", &per_entry);
    m.def("merge_strays", &merge_strays);
    m.def("stray_borders", &stray_borders);
}

}  // namespace sfk
