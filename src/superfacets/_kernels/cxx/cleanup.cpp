// Boundary clean-up: band distances and one minimum cut per band by push-relabel
// (tests/oracle/cleanup.py), the same operations in order.
#include <algorithm>
#include <atomic>
#include <memory>

#include "common.hpp"

namespace sfk {

namespace {

struct Arcs {  // a band's network as built: per node a list of arcs, arc a ^ 1 a's reverse
    i64* first;
    i64* nxt;
    i64* head;
    double* cap;
    double* tr;
};

struct CutWork {
    std::vector<i64> head, nxt, first, label, cur, queue;
    std::vector<double> cap, tr, excess, to_source;
    std::vector<char> side, queued;
    // the lists laid out node by node, each in its list's order (so the cut's every step
    // is the one the lists give, without chasing them): node u's arcs are start[u] ..
    // start[u + 1], arc p goes to to[p] with residual capacity rcap[p], its reverse rev[p]
    std::vector<i64> start, to, rev, at;
    std::vector<double> rcap;
};

// The lists of g laid out node by node in W (each node's arcs in its list's order).
void lay_out(const Arcs& g, i64 n, CutWork& W) {
    i64* start = W.start.data();
    i64* at = W.at.data();
    i64 p = 0;
    for (i64 u = 0; u < n; ++u) {
        start[u] = p;
        for (i64 a = g.first[u]; a != -1; a = g.nxt[a]) {
            at[a] = p;
            W.to[p] = g.head[a];
            W.rcap[p] = g.cap[a];
            ++p;
        }
    }
    start[n] = p;
    for (i64 u = 0; u < n; ++u)
        for (i64 a = g.first[u]; a != -1; a = g.nxt[a]) W.rev[at[a]] = at[a ^ 1];
}

// cleanup._labels_from_source (on the laid-out arcs: the same visits in the same order)
i64 labels_from_source(const CutWork& W, double eps, i64 n, i64* label, i64* order,
                       const double* to_source) {
    const i64* start = W.start.data();
    const i64* to = W.to.data();
    const double* rcap = W.rcap.data();
    for (i64 u = 0; u < n; ++u) label[u] = n + 1;
    i64 qt = 0;
    for (i64 u = 0; u < n; ++u) {
        if (to_source[u] > eps) {
            label[u] = 1;
            order[qt++] = u;
        }
    }
    i64 qh = 0;
    while (qh < qt) {
        i64 u = order[qh++];
        for (i64 p = start[u]; p < start[u + 1]; ++p) {
            i64 v = to[p];
            if (label[v] > n && rcap[p] > eps) {
                label[v] = label[u] + 1;
                order[qt++] = v;
            }
        }
    }
    return qt;
}

// cleanup._min_cut_in: push-relabel's first phase on the reversed network (on the
// laid-out arcs: the same pushes and relabels in the same order as on the lists)
void min_cut_in(const Arcs& g, double eps, char* source_side, i64 n, CutWork& W) {
    lay_out(g, n, W);
    const i64* start = W.start.data();
    const i64* to = W.to.data();
    const i64* rev = W.rev.data();
    double* cap = W.rcap.data();
    const double* tr = g.tr;
    i64* label = W.label.data();
    i64* cur = W.cur.data();
    i64* queue = W.queue.data();
    char* queued = W.queued.data();
    double* excess = W.excess.data();
    double* to_source = W.to_source.data();
    for (i64 u = 0; u < n; ++u) {
        excess[u] = tr[u] < 0.0 ? -tr[u] : 0.0;
        to_source[u] = tr[u] > 0.0 ? tr[u] : 0.0;
    }
    while (true) {
        labels_from_source(W, eps, n, label, cur, to_source);
        i64 qh = 0, qn = 0;
        for (i64 u = 0; u < n; ++u) queued[u] = 0;
        for (i64 u = 0; u < n; ++u) {
            if (excess[u] > eps && label[u] <= n) {
                queue[qn++] = u;
                queued[u] = 1;
            }
        }
        for (i64 u = 0; u < n; ++u) cur[u] = start[u];
        if (qn == 0) break;
        i64 relabels = 0;
        while (qn > 0 && relabels <= n) {
            i64 u = queue[qh];
            qh = (qh + 1) % n;
            --qn;
            queued[u] = 0;
            while (excess[u] > eps && label[u] <= n) {
                if (label[u] == 1 && to_source[u] > eps) {
                    double delta = mn(excess[u], to_source[u]);
                    to_source[u] -= delta;
                    excess[u] -= delta;
                    continue;
                }
                i64 p = cur[u];
                if (p == start[u + 1]) {
                    i64 low = to_source[u] > eps ? 0 : n;
                    for (i64 b = start[u]; b < start[u + 1]; ++b)
                        if (cap[rev[b]] > eps && label[to[b]] < low) low = label[to[b]];
                    label[u] = low + 1;
                    cur[u] = start[u];
                    ++relabels;
                    continue;
                }
                i64 v = to[p];
                double r = cap[rev[p]];
                if (r > eps && label[u] == label[v] + 1) {
                    double delta = mn(excess[u], r);
                    cap[rev[p]] -= delta;
                    cap[p] += delta;
                    excess[u] -= delta;
                    excess[v] += delta;
                    if (!queued[v] && excess[v] > eps) {
                        queue[(qh + qn) % n] = v;
                        queued[v] = 1;
                        ++qn;
                    }
                } else {
                    cur[u] = p + 1;
                }
            }
        }
        if (qn == 0) break;
    }
    for (i64 u = 0; u < n; ++u) source_side[u] = 0;
    i64 reach = labels_from_source(W, eps, n, label, cur, to_source);
    for (i64 t = 0; t < reach; ++t) source_side[cur[t]] = 1;
}

struct Bands {
    const i64* band_of;
    const i64* indptr;
    const i32* indices;
    const double* cut_cost;
    const i64* labels;
    const double* sizes;
    const double* positions;
    const double* means;
    double smooth;
    i64* out;
};

void solve_one(const Bands& B, const i64* members, i64 nb, i64 la, i64 lb, i64 pair_id,
               i64* local, CutWork& W) {
    for (i64 i = 0; i < nb; ++i) {
        local[members[i]] = i;
        W.first[i] = -1;
    }
    i64 na = 0;
    double total = 0.0;
    for (i64 i = 0; i < nb; ++i) {
        i64 f = members[i];
        double da = 0.0, db = 0.0;
        for (int c = 0; c < 3; ++c) {
            double xa = B.positions[3 * f + c] - B.means[3 * la + c];
            double xb = B.positions[3 * f + c] - B.means[3 * lb + c];
            da += xa * xa;
            db += xb * xb;
        }
        double cost_a = B.smooth * B.sizes[f] * da;
        double cost_b = B.smooth * B.sizes[f] * db;
        for (i64 e = B.indptr[f]; e < B.indptr[f + 1]; ++e) {
            i64 g = B.indices[e];
            if (B.band_of[g] == pair_id) {
                if (g > f) {
                    i64 j = local[g];
                    double c_e = B.cut_cost[e];
                    W.head[na] = j;
                    W.cap[na] = c_e;
                    W.nxt[na] = W.first[i];
                    W.first[i] = na;
                    W.head[na + 1] = i;
                    W.cap[na + 1] = c_e;
                    W.nxt[na + 1] = W.first[j];
                    W.first[j] = na + 1;
                    na += 2;
                    total += c_e;
                }
            } else if (B.labels[g] == lb) {
                cost_a += B.cut_cost[e];
            } else if (B.labels[g] == la) {
                cost_b += B.cut_cost[e];
            }
        }
        double m = mn(cost_a, cost_b);
        cost_a -= m;
        cost_b -= m;
        total += cost_a + cost_b;
        W.tr[i] = cost_b > 0.0 ? cost_b : -cost_a;
    }
    Arcs g{W.first.data(), W.nxt.data(), W.head.data(), W.cap.data(), W.tr.data()};
    min_cut_in(g, 1e-12 * total, W.side.data(), nb, W);
    for (i64 i = 0; i < nb; ++i) B.out[members[i]] = W.side[i] ? la : lb;
}

}  // namespace

template <class D>
void band_distances_t(nb::handle indptr_, nb::handle indices_, nb::handle dual_edge_,
                      nb::handle geo_, nb::handle length_, nb::handle labels_, nb::handle pinned_,
                      double limit, nb::handle dist_, nb::handle partner_, nb::handle hkey_,
                      nb::handle hval_) {
    In<i64> indptr(indptr_, "indptr"), labels(labels_, "labels");
    In<i32> indices(indices_, "indices");
    In<D> dual_edge(dual_edge_, "dual_edge");
    In<double> geo(geo_, "geo"), length(length_, "length");
    In<bool> pinned(pinned_, "pinned");
    Out<double> dist(dist_, "dist"), hkey(hkey_, "hkey");
    Out<i64> partner(partner_, "partner"), hval(hval_, "hval");
    check_csr(indptr, indices, labels.n, labels.n);
    check_rows(dual_edge, indptr[labels.n], "dual_edge");
    check_range(dual_edge, 0, mn(geo.n, length.n), "dual_edge", indptr[labels.n]);
    check_range(labels, 0, labels.n, "labels");
    for (i64 m : {pinned.n, dist.n, partner.n})
        if (m < labels.n) throw OutOfRange("arguments pinned, dist, partner: one per element");
    nb::gil_scoped_release nogil;
    const i64 n = labels.n;
    (void)hkey;  // (the heap's arrays of the numba kernel: here one heap per thread)
    (void)hval;
    // the seeds, each element on its own (a seed's distance is -0.0 while the searches
    // run: equal to 0.0, but never taken over by a lower partner at distance 0)
    parallel_for(n, [&](i64 lo, i64 hi) {
        for (i64 f = lo; f < hi; ++f) {
            dist[f] = INF;
            partner[f] = -1;
            if (pinned[f]) continue;
            i64 lf = labels[f];
            i64 best = -1;
            double best_len = -1.0;
            for (i64 e = indptr[f]; e < indptr[f + 1]; ++e) {
                i64 lg = labels[indices[e]];
                if (lg == lf) continue;
                double tot = 0.0;
                for (i64 e2 = indptr[f]; e2 < indptr[f + 1]; ++e2)
                    if (labels[indices[e2]] == lg) tot += length[dual_edge[e2]];
                if (tot > best_len || (tot == best_len && lg < best)) {
                    best_len = tot;
                    best = lg;
                }
            }
            if (best >= 0) {
                dist[f] = -0.0;
                partner[f] = best;
            }
        }
    });
    i64 k = 0;
    for (i64 f = 0; f < n; ++f) k = mx(k, labels[f] + 1);
    // the seeds by label, in element order (a counting sort)
    std::vector<i64> first(k + 1, 0);
    for (i64 f = 0; f < n; ++f)
        if (partner[f] >= 0) ++first[labels[f] + 1];
    for (i64 l = 0; l < k; ++l) first[l + 1] += first[l];
    std::vector<i64> seeds(first[k]);
    {
        std::vector<i64> fill(first.begin(), first.end() - 1);
        for (i64 f = 0; f < n; ++f)
            if (partner[f] >= 0) seeds[fill[labels[f]]++] = f;
    }
    // the searches never cross a label change: each superfacet's search on its own (its
    // heap holds its border: small, in cache), a range of labels on each thread; ties of
    // distance go to the lowest partner, so the result is that of any order
    auto search = [&](i64 la, i64 lb) {
        Heap heap(1024);
        for (i64 l = la; l < lb; ++l) {
            for (i64 t = first[l]; t < first[l + 1]; ++t) heap.push(0.0, seeds[t]);
            while (heap.size > 0) {
                double d = heap.h[0].key;
                i64 f = heap.h[0].val;
                heap.pop();
                if (d > dist[f]) continue;
                i64 pf = partner[f];
                for (i64 e = indptr[f]; e < indptr[f + 1]; ++e) {
                    i64 g = indices[e];
                    if (labels[g] != l || pinned[g]) continue;
                    double nd = d + geo[dual_edge[e]];
                    double dg = dist[g];
                    if (nd < limit && (nd < dg || (nd == dg && pf < partner[g] &&
                                                   !std::signbit(dg)))) {
                        dist[g] = nd;
                        partner[g] = pf;
                        heap.push(nd, g);
                    }
                }
            }
        }
    };
    const i64 t = n < (1 << 16) ? 1 : std::min<i64>(threads(), k);
    if (t <= 1) {
        search(0, k);
    } else {
        on_threads(t, [&](i64 w) { search(k * w / t, k * (w + 1) / t); });
    }
    parallel_for(n, [&](i64 lo, i64 hi) {
        for (i64 f = lo; f < hi; ++f)
            if (dist[f] == 0.0) dist[f] = 0.0;  // (the seeds' -0.0)
    });
}

// (int64 adjacency numbers from 2**31 CSR entries on)
template <class... A>
void band_distances(nb::handle indptr, nb::handle indices, nb::handle dual_edge, A... rest) {
    if (matches<i32>(dual_edge)) return band_distances_t<i32>(indptr, indices, dual_edge, rest...);
    band_distances_t<i64>(indptr, indices, dual_edge, rest...);
}

// Bands p0 .. p1 - 1 of n elements: band p the elements order[starts[p]:starts[p + 1]],
// each of them with band_of p and no other element with it; pair_a, pair_b the labels of
// each band's two sides, rows of means (n_means).
inline void check_bands(i64 p0, i64 p1, const In<i64>& order, const In<i64>& starts,
                        const In<i64>& pair_a, const In<i64>& pair_b, const In<i64>& band_of,
                        i64 n_means, i64 n) {
    check_span(p0, p1, starts.n - 1, mn(pair_a.n, pair_b.n));
    check_csr(In<i64>(starts.p + p0, p1 - p0 + 1), order, p1 - p0, n, "starts");
    check_range(In<i64>(pair_a.p + p0, p1 - p0), 0, n_means, "pair_a");
    check_range(In<i64>(pair_b.p + p0, p1 - p0), 0, n_means, "pair_b");
    check_rows(band_of, n, "band_of");
    i64 in_bands = 0;
    for (i64 f = 0; f < n; ++f) in_bands += band_of[f] >= p0 && band_of[f] < p1;
    for (i64 p = p0; p < p1; ++p)
        for (i64 t = starts[p]; t < starts[p + 1]; ++t)
            if (band_of[order[t]] != p) throw OutOfRange("argument band_of: not the bands' own");
    if (in_bands != starts[p1] - starts[p0])
        throw OutOfRange("argument band_of: elements of a band not among its members");
}

void solve_bands(i64 p0, i64 p1, nb::handle order_, nb::handle starts_, nb::handle pair_a_,
                 nb::handle pair_b_, nb::handle band_of_, nb::handle indptr_,
                 nb::handle indices_, nb::handle cut_cost_, nb::handle labels_,
                 nb::handle sizes_, nb::handle positions_, nb::handle means_, double smooth,
                 nb::handle out_) {
    In<i64> order(order_, "order"), starts(starts_, "starts"), pair_a(pair_a_, "pair_a"),
        pair_b(pair_b_, "pair_b"), band_of(band_of_, "band_of"), indptr(indptr_, "indptr"),
        labels(labels_, "labels");
    In<i32> indices(indices_, "indices");
    In<double> cut_cost(cut_cost_, "cut_cost"), sizes(sizes_, "sizes"),
        positions(positions_, "positions"), means(means_, "means");
    Out<i64> out(out_, "out");
    if (positions.cols != 3 || means.cols != 3) throw Mismatch("argument positions");
    check_bands(p0, p1, order, starts, pair_a, pair_b, band_of, means.n, labels.n);
    check_csr(indptr, indices, labels.n, labels.n);
    check_rows(cut_cost, indptr[labels.n], "cut_cost");
    for (i64 m : {sizes.n, positions.n, out.n})
        if (m < labels.n) throw OutOfRange("arguments sizes, positions, out: one per element");
    nb::gil_scoped_release nogil;
    // (written for a band's elements before being read, as numba's np.empty: the pages
    // of the elements in no band of this call are never touched; the bands hold disjoint
    // elements, so the threads share it)
    std::unique_ptr<i64[]> local(new i64[labels.n]);
    i64 most_nodes = 1, most_arcs = 1;
    std::vector<i64> by_size;  // the bands, largest first (taken in turn by the threads)
    std::vector<i64> nodes_of(p1 - p0);
    for (i64 p = p0; p < p1; ++p) {
        i64 nodes = starts[p + 1] - starts[p], arcs = 0;
        for (i64 t = starts[p]; t < starts[p + 1]; ++t) {
            i64 f = order[t];
            arcs += indptr[f + 1] - indptr[f];
        }
        most_nodes = mx(most_nodes, nodes);
        most_arcs = mx(most_arcs, arcs);
        nodes_of[p - p0] = nodes;
        by_size.push_back(p);
    }
    std::stable_sort(by_size.begin(), by_size.end(),
                     [&](i64 a, i64 b) { return nodes_of[a - p0] > nodes_of[b - p0]; });
    Bands B{band_of.p, indptr.p, indices.p, cut_cost.p, labels.p, sizes.p, positions.p, means.p,
            smooth, out.p};
    // each band on its own (its cut reads and writes its elements alone): any thread, any
    // order gives the same labels
    const i64 n_bands = p1 - p0;
    const i64 T = std::max<i64>(1, std::min<i64>(threads(), (starts[p1] - starts[p0]) / 4096));
    std::atomic<i64> next{0};
    on_threads(std::min(T, n_bands), [&](i64) {
        CutWork W;
        W.head.resize(most_arcs);
        W.cap.resize(most_arcs);
        W.nxt.resize(most_arcs);
        for (auto* v : {&W.to, &W.rev, &W.at}) v->resize(most_arcs);
        W.rcap.resize(most_arcs);
        W.start.resize(most_nodes + 1);
        for (auto* v : {&W.first, &W.label, &W.cur, &W.queue}) v->resize(most_nodes);
        for (auto* v : {&W.tr, &W.excess, &W.to_source}) v->resize(most_nodes);
        for (auto* v : {&W.side, &W.queued}) v->resize(most_nodes);
        for (i64 j = next++; j < n_bands; j = next++) {
            const i64 p = by_size[j];
            solve_one(B, order.p + starts[p], starts[p + 1] - starts[p], pair_a[p], pair_b[p], p,
                      local.get(), W);
        }
    });
}

void bind_cleanup(nb::module_& m) {
    m.def("band_distances", &band_distances<nb::handle, nb::handle, nb::handle, nb::handle,
                                             double, nb::handle, nb::handle, nb::handle,
                                             nb::handle>,
          "Distance of every element from its superfacet's boundary, below limit.",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("dual_edge"), nb::arg("geo"),
          nb::arg("length"), nb::arg("labels"), nb::arg("pinned"), nb::arg("limit"),
          nb::arg("dist"), nb::arg("partner"), nb::arg("hkey"), nb::arg("hval"));
    m.def("solve_bands", &solve_bands,
          "Cut bands p0 .",
          nb::arg("p0"), nb::arg("p1"), nb::arg("order"), nb::arg("starts"), nb::arg("pair_a"),
          nb::arg("pair_b"), nb::arg("band_of"), nb::arg("indptr"), nb::arg("indices"),
          nb::arg("cut_cost"), nb::arg("labels"), nb::arg("sizes"), nb::arg("positions"),
          nb::arg("means"), nb::arg("smooth"), nb::arg("out"));
}

}  // namespace sfk
