// The exact nearest-center assignment and its pass-by-pass update
// (tests/oracle/exact.py): the same operations in the same order, but each
// search by blocks of elements on threads (BlockedSearch: the same labels and
// distances to the bit, never out of queue).
#include <atomic>
#include <memory>

#include "search.hpp"

namespace sfk {

namespace {

constexpr i64 NOT_INCREMENTAL = -100;

// The exact classifier's state and its search (by blocks on threads: BlockedSearch). The
// node pool numba's search takes its nodes from is checked, not used.
template <class W, class L>
struct Exact {
    double* dist;
    L* label;
    std::unique_ptr<BlockedSearch<W, L>> searcher;
    void search(const i64* seeds, i64 ns) const { searcher->run(seeds, ns); }
};

template <class W, class L>
i64 seed_orphans(const Exact<W, L>& x, i64* centers, i64 n_centers, i64 m) {
    i64 k = n_centers;
    i64 one[1];
    for (i64 f = 0; f < m; ++f) {
        if (x.label[f] < 0) {
            centers[k] = f;
            x.dist[f] = 0.0;
            x.label[f] = static_cast<L>(k);
            one[0] = f;
            x.search(one, 1);
            ++k;
        }
    }
    return k;
}

template <class W, class L>
Exact<W, L> exact_of(const In<i64>& indptr, const In<i32>& indices, nb::handle weights_,
                     Out<double>& dist, Out<L>& label, nb::handle queue_, Out<i32>& qlab,
                     double inv_width) {
    In<W> weights(weights_, "weights");
    auto tup = nb::borrow<nb::tuple>(queue_);
    if (!nb::isinstance<nb::tuple>(queue_) || tup.size() != 4) throw Mismatch("argument queue");
    Out<i32> qface(tup[0], "qface");
    Out<double> qdist(tup[1], "qdist");
    Out<i64> qnext(tup[2], "qnext"), head(tup[3], "head");
    (void)qlab;
    const i64 n = check_csr(indptr, indices, label.n, label.n);
    check_rows(weights, indptr[n], "weights");
    check_rows(dist, n, "dist", true);
    if (head.n < 1 || (head.n & (head.n - 1)))
        throw OutOfRange("argument queue: a ring of a power of two of buckets");
    return Exact<W, L>{dist.p, label.p,
                       std::make_unique<BlockedSearch<W, L>>(indptr.p, indices.p, weights.p,
                                                             dist.p, label.p, label.n,
                                                             inv_width, head.n)};
}

// The arguments both entry points share, checked.
template <class W, class L>
struct Args {
    In<i64> indptr;
    In<i32> indices;
    Out<i64> centers;
    Out<double> dist;
    Out<L> label;
    Out<i32> qlab;
    Exact<W, L> x;
    Args(nb::handle indptr_, nb::handle indices_, nb::handle weights_, nb::handle centers_,
         nb::handle dist_, nb::handle label_, nb::handle queue_, nb::handle qlab_,
         double inv_width)
        : indptr(indptr_, "indptr"),
          indices(indices_, "indices"),
          centers(centers_, "centers"),
          dist(dist_, "dist"),
          label(label_, "label"),
          qlab(qlab_, "qlab"),
          x(exact_of<W, L>(indptr, indices, weights_, dist, label, queue_, qlab, inv_width)) {}
    // n_centers centers, each an element, and room for a center per element (the orphans')
    void check_centers(i64 n_centers) const {
        if (n_centers < 0 || centers.n < label.n)
            throw OutOfRange("argument centers: room for a center per element");
        check_range(centers, 0, label.n, "centers", n_centers);
    }
};

template <class W, class L>
i64 classify_exact_t(nb::handle indptr_, nb::handle indices_, nb::handle weights_,
                     nb::handle centers_, i64 n_centers, nb::handle dist_, nb::handle label_,
                     nb::handle queue_, nb::handle qlab_, double inv_width) {
    Args<W, L> A(indptr_, indices_, weights_, centers_, dist_, label_, queue_, qlab_, inv_width);
    auto& centers = A.centers;
    auto& label = A.label;
    auto& dist = A.dist;
    const auto& x = A.x;
    A.check_centers(n_centers);
    nb::gil_scoped_release nogil;
    const i64 m = label.n;
    parallel_for(m, [&](i64 f0, i64 f1) {
        for (i64 f = f0; f < f1; ++f) {
            dist[f] = INF;
            label[f] = -1;
        }
    });
    std::vector<i64> seeds(n_centers);
    i64 ns = 0;
    for (i64 s = 0; s < n_centers; ++s) {
        i64 c = centers[s];
        if (label[c] < 0) {
            dist[c] = 0.0;
            label[c] = static_cast<L>(s);
            seeds[ns++] = c;
        }
    }
    x.search(seeds.data(), ns);
    return seed_orphans(x, centers.p, n_centers, m);
}

template <class W, class L>
i64 reclassify_exact_t(nb::handle indptr_, nb::handle indices_, nb::handle weights_,
                       nb::handle centers_, i64 n_centers, nb::handle dist_, nb::handle label_,
                       nb::handle queue_, nb::handle qlab_, double inv_width, nb::handle prev_,
                       nb::handle first_, nb::handle border_mark_) {
    Args<W, L> A(indptr_, indices_, weights_, centers_, dist_, label_, queue_, qlab_, inv_width);
    auto& centers = A.centers;
    auto& label = A.label;
    auto& dist = A.dist;
    const auto& indptr = A.indptr;
    const auto& indices = A.indices;
    const auto& x = A.x;
    In<i64> prev(prev_, "prev");
    Out<i32> first(first_, "first");
    Out<bool> border_mark(border_mark_, "border_mark");  // (numba's; not used here)
    A.check_centers(n_centers);
    check_range(prev, 0, label.n, "prev");
    check_rows(first, label.n, "first");
    check_range(first, -1, 0, "first", label.n);  // (all -1 between passes)
    nb::gil_scoped_release nogil;
    const i64 m = label.n;
    for (i64 s = 0; s < n_centers; ++s) {
        i64 c = centers[s];
        if (first[c] < 0) first[c] = static_cast<i32>(s);
    }
    const i64 kp = prev.n;
    std::vector<i64> remap(kp);
    i64 last = -1;
    bool usable = true;
    for (i64 j = 0; j < kp; ++j) {
        i64 i = first[prev[j]];
        remap[j] = i;
        if (i >= 0) {
            if (i <= last) usable = false;
            last = i;
        }
    }
    if (usable) {  // every label one of the previous pass's centers
        std::atomic<bool> in_range{true};
        parallel_for(m, [&](i64 f0, i64 f1) {
            for (i64 f = f0; f < f1; ++f) {
                i64 lab = label[f];
                if (lab < 0 || lab >= kp) {
                    in_range = false;
                    return;
                }
            }
        });
        usable = in_range;
    }
    if (!usable) {
        for (i64 s = 0; s < n_centers; ++s) first[centers[s]] = -1;
        return NOT_INCREMENTAL;
    }
    parallel_for(m, [&](i64 f0, i64 f1) {  // the cells of the centers that moved cleared
        for (i64 f = f0; f < f1; ++f) {
            i64 i = remap[label[f]];
            if (i < 0) {
                dist[f] = INF;
                label[f] = -1;
            } else {
                label[f] = static_cast<L>(i);
            }
        }
    });
    std::vector<i64> seeds(n_centers);
    i64 ns = 0;
    for (i64 s = 0; s < n_centers; ++s) {
        i64 c = centers[s];
        if (first[c] == s && (label[c] < 0 || dist[c] > 0.0 || label[c] > s)) {
            dist[c] = 0.0;
            label[c] = static_cast<L>(s);
            seeds[ns++] = c;
        }
    }
    for (i64 s = 0; s < n_centers; ++s) first[centers[s]] = -1;
    // the kept elements bordering the cleared ones, on threads (in any order, repeated
    // or not: the search's result does not depend on its seeds' order)
    const int T = threads();
    std::vector<std::vector<i64>> border(T);
    std::atomic<i64> next{0};
    const i64 chunk = 1 << 16;
    on_threads(T, [&](i64 t) {
        for (i64 f0 = next.fetch_add(chunk); f0 < m; f0 = next.fetch_add(chunk)) {
            for (i64 f = f0; f < std::min(m, f0 + chunk); ++f) {
                if (label[f] >= 0) continue;
                for (i64 e = indptr[f]; e < indptr[f + 1]; ++e) {
                    i64 g = indices[e];
                    if (label[g] >= 0) border[t].push_back(g);
                }
            }
        }
    });
    std::vector<i64> all_seeds(seeds.begin(), seeds.begin() + ns);
    for (auto& b : border) all_seeds.insert(all_seeds.end(), b.begin(), b.end());
    x.search(all_seeds.data(), static_cast<i64>(all_seeds.size()));
    return seed_orphans(x, centers.p, n_centers, m);
}

}  // namespace

// float64 or float32 weights; int32 or int64 labels
template <class... A>
i64 classify_exact(nb::handle indptr, nb::handle indices, nb::handle weights, nb::handle centers,
                   i64 n_centers, nb::handle dist, nb::handle label, A... rest) {
    const bool w32 = matches<float>(weights), l32 = matches<i32>(label);
    if (w32 && l32)
        return classify_exact_t<float, i32>(indptr, indices, weights, centers, n_centers, dist,
                                            label, rest...);
    if (w32)
        return classify_exact_t<float, i64>(indptr, indices, weights, centers, n_centers, dist,
                                            label, rest...);
    if (l32)
        return classify_exact_t<double, i32>(indptr, indices, weights, centers, n_centers, dist,
                                             label, rest...);
    return classify_exact_t<double, i64>(indptr, indices, weights, centers, n_centers, dist,
                                         label, rest...);
}

template <class... A>
i64 reclassify_exact(nb::handle indptr, nb::handle indices, nb::handle weights,
                     nb::handle centers, i64 n_centers, nb::handle dist, nb::handle label,
                     A... rest) {
    const bool w32 = matches<float>(weights), l32 = matches<i32>(label);
    if (w32 && l32)
        return reclassify_exact_t<float, i32>(indptr, indices, weights, centers, n_centers, dist,
                                              label, rest...);
    if (w32)
        return reclassify_exact_t<float, i64>(indptr, indices, weights, centers, n_centers,
                                              dist, label, rest...);
    if (l32)
        return reclassify_exact_t<double, i32>(indptr, indices, weights, centers, n_centers,
                                               dist, label, rest...);
    return reclassify_exact_t<double, i64>(indptr, indices, weights, centers, n_centers, dist,
                                           label, rest...);
}

void bind_exact(nb::module_& m) {
    m.def("classify_exact", &classify_exact<nb::handle, nb::handle, double>,
          "Exact nearest-center assignment.",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("weights"), nb::arg("centers"),
          nb::arg("n_centers"), nb::arg("dist"), nb::arg("label"), nb::arg("queue"),
          nb::arg("qlab"), nb::arg("inv_width"));
    m.def("reclassify_exact", &reclassify_exact<nb::handle, nb::handle, double, nb::handle, nb::handle, nb::handle>,
          "Classify_exact of centers[:n_centers], updated from the previous pass's result "
          "instead of searched again from scratch.",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("weights"), nb::arg("centers"),
          nb::arg("n_centers"), nb::arg("dist"), nb::arg("label"), nb::arg("queue"),
          nb::arg("qlab"), nb::arg("inv_width"), nb::arg("prev"), nb::arg("first"),
          nb::arg("border_mark"));
}

}  // namespace sfk
