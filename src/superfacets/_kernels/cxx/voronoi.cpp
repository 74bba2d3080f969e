// Voronoi cells of seeds in the weighted element graph, for the coarse-to-fine run
// (tests/oracle/voronoi.py): the same operations in the same order, the cells'
// search by blocks on threads (BlockedSearch: numba's search_buckets' result).
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <atomic>
#include <limits>
#include <memory>

#include "search.hpp"

namespace sfk {

namespace {

template <class W>
i64 nearest_seed_t(const In<i64>& indptr, const In<i32>& indices, const W* weights,
                   const In<i64>& seeds, i64 first, Out<double>& dist, Out<i32>& label,
                   nb::handle queue_, double inv_width) {
    auto tup = nb::borrow<nb::tuple>(queue_);
    if (!nb::isinstance<nb::tuple>(queue_) || tup.size() != 4) throw Mismatch("argument queue");
    Out<i64> head(tup[3], "head");  // (the rest of numba's queue is not used here)
    if (head.n < 1) throw OutOfRange("argument queue: its head holds no bucket");
    nb::gil_scoped_release nogil;
    std::vector<i64> todo(seeds.n - first);
    i64 n = 0;
    for (i64 s = first; s < seeds.n; ++s) {
        i64 f = seeds[s];
        if (dist[f] == 0.0) continue;
        dist[f] = 0.0;
        label[f] = static_cast<i32>(s);
        todo[n++] = f;
    }
    BlockedSearch<W, i32>(indptr.p, indices.p, weights, dist.p, label.p, label.n, inv_width,
                          head.n)
        .run(todo.data(), n);
    return 0;
}

// The pair (lo, h) among the pairs of lo (`first`: their offsets, `hi_of(g)`: a pair's
// hi, ascending), by bisection
template <class H>
inline i64 pair_index(const std::vector<i64>& first, H hi_of, i64 lo, i64 h) {
    i64 left = first[lo], right = first[lo + 1];
    while (left < right) {
        i64 mid = (left + right) >> 1;
        if (hi_of(mid) < h) left = mid + 1;
        else right = mid;
    }
    return left;
}

// Each crossing adjacency (i, j), j > i, x its CSR entry and t its number, with the
// cluster pair g it joins (found by bisection among the pairs of its lo, `first`: their
// offsets, `hi_of(g)`: a pair's hi): visit(g, i, j, x, t). On threads, thread u the
// pairs of the lo clusters c0(u) .. c0(u + 1) - 1, each reading every adjacency in
// order, so that a pair's sums are added in the order of one pass.
template <class C, class H, class V>
void crossing_pairs(const In<i64>& indptr, const In<i32>& indices, const In<C>& cluster,
                    const std::vector<i64>& first, i64 n_c, H hi_of, V visit) {
    const i64 n = indptr.n - 1;
    const i64 T = std::max<i64>(1, std::min<i64>(threads(), n / 65536));
    std::vector<i64> c0(T + 1);
    for (i64 u = 0; u <= T; ++u) c0[u] = n_c * u / T;
    on_threads(T, [&](i64 u) {
        const i64 lo_c = c0[u], hi_c = c0[u + 1];
        i64 t = 0;
        for (i64 i = 0; i < n; ++i) {
            i64 a = cluster[i];
            for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) {
                i64 j = indices[x];
                if (j <= i) continue;
                i64 b = cluster[j];
                i64 lo = mn(a, b);
                if (a != b && lo >= lo_c && lo < hi_c)
                    visit(pair_index(first, hi_of, lo, mx(a, b)), i, j, x, t);
                ++t;
            }
        }
    });
}

// Lower *p to v where v is less, atomically (the minimum of any order: the same value)
inline void atomic_min(double* p, double v) {
    std::uint64_t want, cur;
    std::memcpy(&want, &v, sizeof want);
    cur = __atomic_load_n(reinterpret_cast<std::uint64_t*>(p), __ATOMIC_RELAXED);
    for (;;) {
        double c;
        std::memcpy(&c, &cur, sizeof c);
        if (!(v < c) ||
            __atomic_compare_exchange_n(reinterpret_cast<std::uint64_t*>(p), &cur, want, true,
                                        __ATOMIC_RELAXED, __ATOMIC_RELAXED))
            return;
    }
}

template <class C, class W, class S>
nb::tuple coarse_pairs_t(const In<i64>& indptr, const In<i32>& indices, const In<C>& cluster,
                         const In<double>& dist, const W* csr_w, const In<double>& lengths,
                         const S* shares, i64 n_shares, i64 n_c) {
    const i64 n = indptr.n - 1;
    std::vector<i64> start(n_c + 1, 0), first(n_c + 1, 0);
    std::vector<i32> hi;
    {
        // the crossing adjacencies' hi bucketed by lo, on threads with atomic counters (a
        // bucket's order does not matter: each is then sorted and made distinct)
        nb::gil_scoped_release nogil;
        auto bump = [](i64* x) { return __atomic_fetch_add(x, 1, __ATOMIC_RELAXED); };
        auto crossings = [&](auto visit) {  // visit(lo, hi) of each crossing adjacency
            parallel_for(n, [&](i64 r0, i64 r1) {
                for (i64 i = r0; i < r1; ++i) {
                    i64 a = cluster[i];
                    for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) {
                        i64 j = indices[x];
                        const i64 b = cluster[j];
                        if (j > i && b != a) visit(mn(a, b), mx(a, b));
                    }
                }
            });
        };
        i64* st = start.data();
        crossings([&](i64 lo, i64) { bump(st + lo + 1); });
        for (i64 c = 0; c < n_c; ++c) start[c + 1] += start[c];
        hi.resize(start[n_c]);
        std::vector<i64> fill(start.begin(), start.end() - 1);
        i64* fl = fill.data();
        crossings([&](i64 lo, i64 h) { hi[bump(fl + lo)] = static_cast<i32>(h); });
        std::vector<i64>().swap(fill);
        // each bucket sorted and made distinct; first: the distinct ones' offsets
        parallel_for(n_c, [&](i64 lo, i64 hi_) {
            for (i64 c = lo; c < hi_; ++c)
                first[c + 1] = sort_distinct(hi.data(), start[c], start[c + 1]);
        });
        for (i64 c = 0; c < n_c; ++c) first[c + 1] += first[c];
        // the distinct hi alone, in a list of their own (the crossings are several times
        // the pairs: the outputs below are made once that list is let go)
        std::vector<i32> kept(first[n_c]);
        parallel_for(n_c, [&](i64 lo, i64 hi_) {
            for (i64 c = lo; c < hi_; ++c)
                std::copy(hi.begin() + start[c], hi.begin() + start[c] + (first[c + 1] - first[c]),
                          kept.begin() + first[c]);
        });
        hi.swap(kept);
    }
    std::vector<i64>().swap(start);
    const i64 m = first[n_c];
    Out<i32> out;  // clusters <= elements < 2**31 (as hi)
    auto out_a = fresh(m, out, 2);
    {
        nb::gil_scoped_release nogil;
        for (i64 c = 0; c < n_c; ++c)
            for (i64 g = first[c]; g < first[c + 1]; ++g) {
                out(g, 0) = static_cast<i32>(c);
                out(g, 1) = hi[g];
            }
    }
    std::vector<i32>().swap(hi);  // (read from the pairs' second column from here on)
    // the lengths only where given (lengths or shares: a run reads them later, with
    // coarse_lengths, once the distances and the fine weights are let go)
    const bool with_len = n_shares || lengths.n;
    Out<double> w_c, len_c;
    auto w_a = fresh(m, w_c), len_a = fresh(with_len ? m : 0, len_c);
    {
        nb::gil_scoped_release nogil;
        for (i64 g = 0; g < m; ++g) w_c[g] = INF;
        for (i64 g = 0; g < len_c.n; ++g) len_c[g] = 0.0;
        auto hi_of = [&](i64 g) { return out(g, 1); };
        if (!with_len) {  // the minima alone: rows on threads (any order gives them)
            parallel_for(n, [&](i64 r0, i64 r1) {
                for (i64 i = r0; i < r1; ++i) {
                    const i64 a = cluster[i];
                    for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) {
                        const i64 j = indices[x];
                        const i64 b = cluster[j];
                        if (j <= i || a == b) continue;
                        const i64 g = pair_index(first, hi_of, mn(a, b), mx(a, b));
                        atomic_min(&w_c[g], dist[i] + static_cast<double>(csr_w[x]) + dist[j]);
                    }
                }
            });
        } else {  // with the lengths: in the order of one pass (crossing_pairs)
            crossing_pairs(indptr, indices, cluster, first, n_c, hi_of,
                           [&](i64 g, i64 i, i64 j, i64 x, i64 t) {
                               double v = dist[i] + static_cast<double>(csr_w[x]) + dist[j];
                               if (v < w_c[g]) w_c[g] = v;
                               if (n_shares) {
                                   S sum = shares[i] + shares[j];  // the shares' precision
                                   len_c[g] += 0.5 * static_cast<double>(sum);
                               } else
                                   len_c[g] += lengths[t];
                           });
        }
    }
    return nb::make_tuple(out_a, w_a, len_a);
}

// The summed border lengths of the cluster pairs `pairs` (coarse_pairs' pairs, in (lo,
// hi) order): coarse_pairs' third output, the same values, made apart.
template <class C, class S>
nb::object coarse_lengths_t(const In<i64>& indptr, const In<i32>& indices, const In<C>& cluster,
                            const In<i32>& pairs, const In<double>& lengths, const S* shares,
                            i64 n_shares, i64 n_c) {
    const i64 m = pairs.n;
    std::vector<i64> first(n_c + 1, 0);
    for (i64 g = 0; g < m; ++g) ++first[pairs(g, 0) + 1];
    for (i64 c = 0; c < n_c; ++c) first[c + 1] += first[c];
    Out<double> len_c;
    auto len_a = fresh(m, len_c);
    nb::gil_scoped_release nogil;
    for (i64 g = 0; g < m; ++g) len_c[g] = 0.0;
    crossing_pairs(indptr, indices, cluster, first, n_c, [&](i64 g) { return pairs(g, 1); },
                   [&](i64 g, i64 i, i64 j, i64, i64 t) {
                       if (n_shares) {
                           S sum = shares[i] + shares[j];  // in the shares' own precision
                           len_c[g] += 0.5 * static_cast<double>(sum);
                       } else
                           len_c[g] += lengths[t];
                   });
    return len_a;
}

}  // namespace

i64 nearest_seed(nb::handle indptr_, nb::handle indices_, nb::handle weights_, nb::handle seeds_,
                 i64 first, nb::handle dist_, nb::handle label_, nb::handle queue,
                 double inv_width) {
    In<i64> indptr(indptr_, "indptr"), seeds(seeds_, "seeds");
    In<i32> indices(indices_, "indices");
    Out<double> dist(dist_, "dist");
    Out<i32> label(label_, "label");
    const i64 n = check_csr(indptr, indices, label.n, label.n);
    check_rows(dist, n, "dist");
    check_range(seeds, 0, n, "seeds");
    if (first < 0 || first > seeds.n) throw OutOfRange("argument first");
    if (!(inv_width > 0.0) || !std::isfinite(inv_width))  // (the buckets' width: > 0)
        throw OutOfRange("argument inv_width: " + std::to_string(inv_width) +
                         ", not a finite number > 0");
    return with_real(weights_, "weights", [&](auto w) {
        check_rows(w, indptr[n], "weights");
        return nearest_seed_t(indptr, indices, w.p, seeds, first, dist, label, queue, inv_width);
    });
}

// shares (one per element) or lengths (one per adjacency), where given or `needed`
static void check_border(const In<i64>& indptr, const In<i32>& indices, const In<double>& lengths,
                         i64 n_shares, bool needed) {
    const i64 n = indptr.n - 1;
    if (n_shares) {
        if (n_shares != n) throw Mismatch("argument shares");
    } else if (lengths.n || needed) {
        i64 above = 0;  // (the adjacencies: lengths has one each)
        for (i64 i = 0; i < n; ++i)
            for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) above += indices[x] > i;
        check_rows(lengths, above, "lengths");
    }
}

nb::tuple coarse_pairs(nb::handle indptr_, nb::handle indices_, nb::handle cluster_,
                       nb::handle dist_, nb::handle csr_w_, nb::handle lengths_,
                       nb::handle shares_, i64 n_c) {
    In<i64> indptr(indptr_, "indptr");
    In<i32> indices(indices_, "indices");
    In<double> dist(dist_, "dist"), lengths(lengths_, "lengths");
    const i64 n = check_csr(indptr, indices, -1, indptr.n - 1);
    check_rows(dist, n, "dist");
    if (n_c < 0) throw OutOfRange("argument n_c");
    return with_index(cluster_, "cluster", [&](const auto& cluster) {
        check_rows(cluster, n, "cluster");
        check_range(cluster, 0, n_c, "cluster", n);
        return with_real(csr_w_, "csr_w", [&](auto w) {
            check_rows(w, indptr[n], "csr_w");
            return with_real(shares_, "shares", [&](auto sh) {
                check_border(indptr, indices, lengths, sh.n, false);
                return coarse_pairs_t(indptr, indices, cluster, dist, w.p, lengths, sh.p, sh.n,
                                      n_c);
            });
        });
    });
}

nb::object coarse_lengths(nb::handle indptr_, nb::handle indices_, nb::handle cluster_,
                          nb::handle pairs_, nb::handle lengths_, nb::handle shares_, i64 n_c) {
    In<i64> indptr(indptr_, "indptr");
    In<i32> indices(indices_, "indices"), pairs(pairs_, "pairs");
    In<double> lengths(lengths_, "lengths");
    const i64 n = check_csr(indptr, indices, -1, indptr.n - 1);
    if (n_c < 0) throw OutOfRange("argument n_c");
    if (pairs.cols != 2) throw Mismatch("argument pairs");
    check_range(pairs, 0, n_c, "pairs");
    for (i64 g = 1; g < pairs.n; ++g)  // (lo, hi) order, distinct: coarse_pairs' pairs
        if (pairs(g, 0) < pairs(g - 1, 0) ||
            (pairs(g, 0) == pairs(g - 1, 0) && pairs(g, 1) <= pairs(g - 1, 1)))
            throw Mismatch("argument pairs");
    return with_index(cluster_, "cluster", [&](const auto& cluster) {
        check_rows(cluster, n, "cluster");
        check_range(cluster, 0, n_c, "cluster", n);
        return with_real(shares_, "shares", [&](auto sh) {
            check_border(indptr, indices, lengths, sh.n, true);
            return coarse_lengths_t(indptr, indices, cluster, pairs, lengths, sh.p, sh.n, n_c);
        });
    });
}

// The cell of x along one axis, within 0..dims - 1 (a point outside the grid or not finite
// counts in the nearest cell: a cell number never falls outside the table's keys)
static inline i64 cell_of(double x, double lo, double h, i64 dims) {
    const double c = std::floor((x - lo) / h);
    if (!(c >= 0.0)) return 0;
    return c >= static_cast<double>(dims - 1) ? dims - 1 : static_cast<i64>(c);
}

nb::object first_in_cells(nb::handle positions_, nb::handle lo_, double h,
                                nb::handle dims_, i64 cap) {
    In<double> positions(positions_, "positions"), lo(lo_, "lo");
    In<i64> dims(dims_, "dims");
    if (positions.cols != 3 || lo.n != 3 || dims.n != 3) throw Mismatch("argument positions");
    // the table: a power of two of slots (its mask), at most 2**40; cells of a finite
    // width > 0 over a grid whose cell numbers fit in 62 bits
    if (cap < 2 || cap > (i64(1) << 40) || (cap & (cap - 1)) != 0)
        throw OutOfRange("argument cap: " + std::to_string(cap) +
                         ", not a power of two in 2..2**40");
    if (!(h > 0.0) || !std::isfinite(h))
        throw OutOfRange("argument h: " + std::to_string(h) + ", not a finite number > 0");
    for (int t = 0; t < 3; ++t)
        if (dims[t] < 1 || dims[t] > (i64(1) << 20) || !std::isfinite(lo[t]))
            throw OutOfRange("argument dims: each in 1..2**20, lo finite");
    // one table filled on threads: a cell's slot taken by compare-and-swap, its first
    // element the least any thread offers; the slots' order then depends on the threads'
    // timing, so the firsts are given back ascending (as numba's)
    std::unique_ptr<std::atomic<i64>[]> keys(new std::atomic<i64>[cap]);
    std::unique_ptr<std::atomic<i64>[]> first(new std::atomic<i64>[cap]);
    std::atomic<i64> count{0};
    std::atomic<bool> full{false};
    std::vector<i64> got;
    {
        nb::gil_scoped_release nogil;
        parallel_for(cap, [&](i64 a, i64 b) {
            for (i64 i = a; i < b; ++i) {
                keys[i].store(-1, std::memory_order_relaxed);
                first[i].store(std::numeric_limits<i64>::max(), std::memory_order_relaxed);
            }
        });
        const std::uint64_t mask = static_cast<std::uint64_t>(cap - 1);
        const std::uint64_t mult = 11400714819323198485ULL;
        parallel_for(positions.n, [&](i64 t0, i64 t1) {
            for (i64 t = t0; t < t1; ++t) {
                if (full.load(std::memory_order_relaxed)) return;  // (never past half)
                i64 cx = cell_of(positions(t, 0), lo[0], h, dims[0]);
                i64 cy = cell_of(positions(t, 1), lo[1], h, dims[1]);
                i64 cz = cell_of(positions(t, 2), lo[2], h, dims[2]);
                i64 k = (cx * dims[1] + cy) * dims[2] + cz;
                std::uint64_t s = ((static_cast<std::uint64_t>(k) * mult) >> 20) & mask;
                while (true) {
                    i64 i = static_cast<i64>(s);
                    i64 now = keys[i].load(std::memory_order_relaxed);
                    if (now < 0) {
                        i64 expected = -1;
                        if (keys[i].compare_exchange_strong(expected, k)) {
                            if (2 * (count.fetch_add(1) + 1) > cap) full.store(true);
                            now = k;
                        } else {
                            now = expected;
                        }
                    }
                    if (now == k) {
                        i64 f = first[i].load(std::memory_order_relaxed);
                        while (t < f && !first[i].compare_exchange_weak(f, t)) {
                        }
                        break;
                    }
                    s = (s + 1) & mask;
                }
            }
        });
        if (!full.load()) {  // ascending: each first marked, the marks read in order
            std::vector<char> mark(positions.n, 0);
            parallel_for(cap, [&](i64 a, i64 b) {
                for (i64 i = a; i < b; ++i)
                    if (keys[i].load(std::memory_order_relaxed) >= 0)
                        mark[first[i].load(std::memory_order_relaxed)] = 1;
            });
            got.reserve(count.load());
            for (i64 t = 0; t < positions.n; ++t)
                if (mark[t]) got.push_back(t);
        }
    }
    Out<i64> out;
    auto out_a = fresh(static_cast<i64>(got.size()), out);
    for (i64 j = 0; j < static_cast<i64>(got.size()); ++j) out[j] = got[j];
    return out_a;
}

void bind_voronoi(nb::module_& m) {
    m.def("nearest_seed", &nearest_seed,
          "Label every element with its nearest seed (index into seeds) and that distance, by a"
          " label-correcting multi-source search from seeds[first:] ....",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("weights"), nb::arg("seeds"),
          nb::arg("first"), nb::arg("dist"), nb::arg("label"), nb::arg("queue"),
          nb::arg("inv_width"));
    m.def("coarse_pairs", &coarse_pairs,
          "The adjacency of clusters.",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("cluster"), nb::arg("dist"),
          nb::arg("csr_w"), nb::arg("lengths"), nb::arg("shares"), nb::arg("n_c"));
    m.def("coarse_lengths", &coarse_lengths,
          "The summed border lengths of the cluster pairs pairs (coarse_pairs' pairs, in (lo, "
          "hi) order).",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("cluster"), nb::arg("pairs"),
          nb::arg("lengths"), nb::arg("shares"), nb::arg("n_c"));
    m.def("first_in_cells", &first_in_cells,
          "The lowest-index element of each occupied cell of pitch h from lo (dims cells per "
          "axis, their product below 2**62), ascending (the compiled kernel ....",
          nb::arg("positions"), nb::arg("lo"), nb::arg("h"), nb::arg("dims"), nb::arg("cap"));
}

}  // namespace sfk
