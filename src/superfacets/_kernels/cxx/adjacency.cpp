// The element graphs' build: the face graph's pairs (half edges bucketed and
// grouped), the CSR layouts of pairs, the points' symmetric kNN layout, and the
// components of one label.
// Reference, bit for bit: tests/oracle/adjacency.py.
#include <algorithm>
#include <cstring>
#include <vector>

#include "common.hpp"
#include "points.hpp"

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

// Sort row raw[s:e] ascending and move its distinct values to its front; returns their
// number. Its first nf entries are in any order, the rest usually ascending already (the
// entries other rows listed, written in the order of those rows): then the first part is
// sorted alone (into tmp) and merged with the rest, in place; else the whole row is sorted.
i64 sort_row(i32* raw, i64 s, i64 nf, i64 e, std::vector<i32>& tmp) {
    bool sorted = true;
    for (i64 x = s + nf + 1; x < e && sorted; ++x) sorted = raw[x - 1] <= raw[x];
    if (!sorted || nf > 64) return sort_distinct(raw, s, e);
    tmp.assign(raw + s, raw + s + nf);
    const i64 na = sort_distinct(tmp.data(), 0, nf);
    i64 a = 0, b = s + nf, o = s;
    auto put = [&](i32 v) {
        if (o == s || raw[o - 1] != v) raw[o++] = v;
    };
    while (a < na && b < e) {  // o < b always: the output never passes the unread rest
        if (tmp[a] <= raw[b])
            put(tmp[a++]);
        else
            put(raw[b++]);
    }
    while (a < na) put(tmp[a++]);
    while (b < e) put(raw[b++]);
    return o - s;
}

nb::object knn_csr(nb::handle nbr_, nb::handle keep_, nb::handle indptr_,
                         nb::handle rows_, nb::handle more_, nb::handle more_keep_) {
    In2i nbr(nbr_, "nbr"), more(more_, "more");
    In<bool> keep(keep_, "keep"), more_keep(more_keep_, "more_keep");
    Out<i64> indptr(indptr_, "indptr");
    In<i64> rows(rows_, "rows");
    const i64 n = nbr.n, k = nbr.k, mk = more.k;
    const bool all_kept = keep.n == 0;  // no rows: every entry listed
    if ((!all_kept && (keep.cols != k || keep.n != n)) || (rows.n && more_keep.cols != mk))
        throw Mismatch("argument keep");
    if (n >= (i64(1) << 31)) throw Mismatch("argument nbr");
    nbr.check(n, "nbr");
    check_rows(indptr, n + 1, "indptr");
    if (rows.n) {
        check_range(rows, 0, n, "rows");
        if (more.n != rows.n || more_keep.n != rows.n) throw Mismatch("argument more");
        more.check(n, "more");
    }
    // Every listed pair in both rows. Thread t owns the rows lo(t) .. lo(t + 1): it counts
    // and writes their own lists and the reverse entries they make in its rows; those
    // they make in another thread's rows are posted to it (pairs (row, entry), in the
    // order of the lists: few, the lists being near in space and the rows in Z-order).
    // The longer lists of the rows `rows` are read by every thread, in order. A row's
    // entries are then sorted and made distinct: the layout of one pass in order. A pair
    // that both rows' own lists hold makes no reverse entry (it would be a duplicate):
    // the entries are then about the layout's own number, not twice the lists'.
    const i64 T = std::max<i64>(1, std::min<i64>(threads(), n / 4096));
    auto lo = [&](i64 t) { return n * t / T; };
    auto owner = [&](i64 j) {
        i64 t = j * T / mx<i64>(n, 1);
        while (t > 0 && j < lo(t)) --t;
        while (t + 1 < T && j >= lo(t + 1)) ++t;
        return t;
    };
    std::vector<i32> own(n), rev(n);
    std::vector<i64> start(n + 1, 0);
    std::vector<std::vector<std::pair<i32, i32>>> post(T * T);  // [from * T + to]
    auto listed = [&](i64 i, i64 c) { return (all_kept || keep(i, c)) && nbr(i, c) != i; };
    auto listed_more = [&](i64 t, i64 c) { return more_keep(t, c) && more(t, c) != rows[t]; };
    auto mutual = [&](i64 i, i64 j) {  // j's own list holds i too
        for (i64 c = 0; c < k; ++c)
            if (nbr(j, c) == i && (all_kept || keep(j, c))) return true;
        return false;
    };
    // which listings are mutual, found when counting and read when writing (a bit each)
    std::vector<std::uint64_t> both((n * k + 63) / 64, 0);
    auto mark = [&](i64 i, i64 c) {
        const i64 b = i * k + c;
        __atomic_fetch_or(&both[b >> 6], std::uint64_t(1) << (b & 63), __ATOMIC_RELAXED);
    };
    auto marked = [&](i64 i, i64 c) {
        const i64 b = i * k + c;
        return (both[b >> 6] >> (b & 63)) & 1;
    };
    {
        nb::gil_scoped_release nogil;
        on_threads(T, [&](i64 t) {
            const i64 a = lo(t), b = lo(t + 1);
            std::fill(rev.begin() + a, rev.begin() + b, 0);
            for (i64 i = a; i < b; ++i) {
                i32 m = 0;
                for (i64 c = 0; c < k; ++c)
                    if (listed(i, c)) {
                        ++m;
                        const i64 j = nbr(i, c);
                        if (mutual(i, j)) {
                            mark(i, c);
                            continue;
                        }
                        if (j >= a && j < b)
                            ++rev[j];
                        else
                            post[t * T + owner(j)].emplace_back(static_cast<i32>(j),
                                                                static_cast<i32>(i));
                    }
                own[i] = m;
            }
            for (i64 r = 0; r < rows.n; ++r)
                for (i64 c = 0; c < mk; ++c)
                    if (listed_more(r, c)) {
                        i64 i = rows[r], j = more(r, c);
                        if (i >= a && i < b) ++own[i];
                        if (j >= a && j < b) ++rev[j];
                    }
        });
        on_threads(T, [&](i64 t) {
            for (i64 f = 0; f < T; ++f)
                for (const auto& x : post[f * T + t]) ++rev[x.first];
        });
        for (i64 i = 0; i < n; ++i) start[i + 1] = start[i] + own[i] + rev[i];
    }
    Out<i32> raw;
    auto raw_a = fresh(start[n], raw);
    {
        nb::gil_scoped_release nogil;
        on_threads(T, [&](i64 t) {
            const i64 a = lo(t), b = lo(t + 1);
            // each row: its own list, its longer list, then the reverse entries in the
            // order of their lists (those posted by the threads of lower rows, this
            // thread's, those posted by the threads of higher rows, the longer lists')
            std::fill(rev.begin() + a, rev.begin() + b, 0);  // now: reverse entries written
            auto put = [&](i64 j, i64 i) {
                raw[start[j] + own[j] + rev[j]++] = static_cast<i32>(i);
            };
            for (i64 f = 0; f < t; ++f)
                for (const auto& x : post[f * T + t]) put(x.first, x.second);
            for (i64 i = a; i < b; ++i) {
                i64 u = start[i];
                for (i64 c = 0; c < k; ++c)
                    if (listed(i, c)) {
                        const i64 j = nbr(i, c);
                        raw[u++] = static_cast<i32>(j);
                        if (j >= a && j < b && !marked(i, c)) put(j, i);
                    }
            }
            for (i64 r = 0; r < rows.n; ++r) {
                i64 i = rows[r];
                if (i < a || i >= b) continue;
                i64 u = start[i];
                for (i64 c = 0; c < k; ++c) u += listed(i, c) ? 1 : 0;
                for (i64 c = 0; c < mk; ++c)
                    if (listed_more(r, c)) raw[u++] = more(r, c);
            }
            for (i64 f = t + 1; f < T; ++f)
                for (const auto& x : post[f * T + t]) put(x.first, x.second);
            for (i64 r = 0; r < rows.n; ++r)
                for (i64 c = 0; c < mk; ++c)
                    if (listed_more(r, c)) {
                        i64 j = more(r, c);
                        if (j >= a && j < b)
                            raw[start[j] + own[j] + rev[j]++] = static_cast<i32>(rows[r]);
                    }
            std::vector<i32> tmp;
            i64 w = start[a];  // rows made distinct, moved left within this thread's part
            for (i64 i = a; i < b; ++i) {
                i64 m = sort_row(raw.p, start[i], own[i], start[i + 1], tmp);
                if (w != start[i]) std::copy(raw.p + start[i], raw.p + start[i] + m, raw.p + w);
                w += m;
                own[i] = static_cast<i32>(m);
            }
        });
        indptr[0] = 0;
        for (i64 i = 0; i < n; ++i) indptr[i + 1] = indptr[i] + own[i];
        for (i64 t = 1; t < T; ++t) {  // each part to its place (left: never over the next)
            const i64 a = lo(t), b = lo(t + 1);
            std::memmove(raw.p + indptr[a], raw.p + start[a],
                         sizeof(i32) * static_cast<size_t>(indptr[b] - indptr[a]));
        }
    }
    return raw_a;
}

void bind_adjacency(nb::module_& m) {
    m.def("csr_of_pairs", &csr_of_pairs_any,
          "Symmetric CSR of the pairs (lo[t], hi[t]).",
          nb::arg("lo"), nb::arg("hi"), nb::arg("n"), nb::arg("indices"), nb::arg("dual_edge"));
    m.def("number_pairs", &number_pairs,
          "Number the pairs of a symmetric CSR (rows ascending) in (lo, hi) order.",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("n"), nb::arg("dual_edge"),
          nb::arg("keep"), nb::arg("pairs"));
    m.def("triangle_half_edges", &triangle_half_edges,
          "The half-edges of triangles.",
          nb::arg("faces"), nb::arg("a"), nb::arg("b"), nb::arg("skip"));
    m.def("count_keys", &count_keys,
          "Counts[v] += the number of t in lo..hi-1 with key1[t] == v and not skip[t] (the "
          "first pass of a counting sort on key1).",
          nb::arg("key1"), nb::arg("skip"), nb::arg("lo"), nb::arg("hi"), nb::arg("counts"));
    m.def("scatter_keys", &scatter_keys,
          "Put each kept t in lo..hi-1 at order[fill[key1[t]]], advancing fill (the second pass"
          " of a stable counting sort).",
          nb::arg("key1"), nb::arg("skip"), nb::arg("lo"), nb::arg("hi"), nb::arg("fill"),
          nb::arg("order"));
    m.def("sort_buckets", &sort_buckets,
          "Sort each bucket order[starts[v]:starts[v + 1]], v0 <= v < v1, by key2, stably.",
          nb::arg("order"), nb::arg("starts"), nb::arg("key2"), nb::arg("v0"), nb::arg("v1"));
    m.def("group_pairs", &group_pairs,
          "The edges of sorted half-edges and the face pairs that share them.",
          nb::arg("half"), nb::arg("owner"), nb::arg("a"), nb::arg("b"));
    m.def("csr_of_face_pairs", &csr_of_face_pairs,
          "The distinct pairs among (lo[t], hi[t]) (lo < hi < n, repeats allowed) and their "
          "symmetric CSR, in one counting sort.",
          nb::arg("lo"), nb::arg("hi"), nb::arg("ka"), nb::arg("kb"), nb::arg("n"),
          nb::arg("indices"), nb::arg("dual_edge"));
    m.def("take_pairs", &take_pairs,
          "Pairs[t] = (lo[first[t]], hi[first[t]]) and edges[t] = (ka[first[t]], kb[first[t]]).",
          nb::arg("first"), nb::arg("lo"), nb::arg("hi"), nb::arg("ka"), nb::arg("kb"),
          nb::arg("pairs"), nb::arg("edges"));
    m.def("shared_edges", &shared_edges,
          "The mesh edge (a, b), a < b, each pair of triangles pairs[t] shares.",
          nb::arg("faces"), nb::arg("pairs"), nb::arg("edges"), nb::arg("check"));
    m.def("knn_csr", &knn_csr,
          "The symmetric graph of k-nearest-neighbour lists.",
          nb::arg("nbr"), nb::arg("keep"), nb::arg("indptr"), nb::arg("rows"), nb::arg("more"),
          nb::arg("more_keep"));
}

}  // namespace sfk
