// The greedy merges of the superfacet hierarchy and of the exact count
// (tests/oracle/hierarchy.py), the same operations in the same order. The heap
// pops its (cost, lo, hi, version_lo, version_hi) tuples in increasing lexicographic
// order, as Python's heapq does: equal tuples are equal values, so any heap gives the
// same sequence.
#include <cstdint>
#include <queue>
#include <tuple>

#include "common.hpp"

namespace sfk {

namespace {

constexpr double TINY = 1e-300;
constexpr double PI = 3.141592653589793;
// float64's rounding of a plane fit, per unit of its scatter's trace (64 machine epsilons,
// merges.PLANE_ROUNDING): a rise within it is none (an exact plane's pieces, sampled)
constexpr double ROUNDING = 64.0 * 2.220446049250313e-16;

inline i64 find(i64* owner, i64 s) {
    while (owner[s] != s) {
        owner[s] = owner[owner[s]];
        s = owner[s];
    }
    return s;
}

double plane(double xx, double yy, double zz, double xy, double xz, double yz) {
    double off = xy * xy + xz * xz + yz * yz;
    double q = (xx + yy + zz) / 3.0;
    double p2 = (xx - q) * (xx - q) + (yy - q) * (yy - q) + (zz - q) * (zz - q) + 2.0 * off;
    if (p2 <= 1e-300) return mx(q, 0.0);
    double p = std::sqrt(p2 / 6.0);
    double a = (xx - q) / p, b = (yy - q) / p, c = (zz - q) / p;
    double d = xy / p, e = xz / p, f = yz / p;
    double r = 0.5 * (a * (b * c - f * f) - d * (d * c - f * e) + e * (d * f - b * e));
    double phi = std::acos(mn(1.0, mx(-1.0, r))) / 3.0;
    return mx(q + 2.0 * p * std::cos(phi + 2.0 * PI / 3.0), 0.0);
}

struct Nodes {
    double* area;
    double* wsum;  // (k, 3)
    double* fsum;  // (k, d)
    i64 d;
    double* scatter;  // (k, 6)
    const double* own;  // (k,): plane() of each node's scatter, kept as the nodes merge
};

inline void merged_scatter(i64 a, i64 b, const Nodes& N, double* out) {
    double aa = N.area[a], ab = N.area[b];
    const double* wa = N.wsum + 3 * a;
    const double* wb = N.wsum + 3 * b;
    double x = wa[0] / mx(aa, TINY) - wb[0] / mx(ab, TINY);
    double y = wa[1] / mx(aa, TINY) - wb[1] / mx(ab, TINY);
    double z = wa[2] / mx(aa, TINY) - wb[2] / mx(ab, TINY);
    double w = aa * ab / mx(aa + ab, TINY);
    const double* sa = N.scatter + 6 * a;
    const double* sb = N.scatter + 6 * b;
    out[0] = sa[0] + sb[0] + w * x * x;
    out[1] = sa[1] + sb[1] + w * y * y;
    out[2] = sa[2] + sb[2] + w * z * z;
    out[3] = sa[3] + sb[3] + w * x * y;
    out[4] = sa[4] + sb[4] + w * x * z;
    out[5] = sa[5] + sb[5] + w * y * z;
}

inline double spread(i64 a, i64 b, const Nodes& N) {
    double aa = N.area[a], ab = N.area[b];
    double tot = aa + ab;
    double d2 = 0.0;
    for (int c = 0; c < 3; ++c) {
        double d = N.wsum[3 * a + c] / mx(aa, TINY) - N.wsum[3 * b + c] / mx(ab, TINY);
        d2 += d * d;
    }
    return tot > 0 ? aa * ab / tot * d2 : 0.0;
}

struct Params {
    // 0 Ward's, 1 the plane's rise, 2 Ward's of the flat pairs only, 3 the scene's cost:
    // (the rise / max_rise + compactness * Ward's term) times the crease factor
    i64 planarity;
    double alpha, eta_convex, beta, compactness, max_rise, max_size;
    double min_count;  // planarity 2: the fewest elements the smaller node's rise is read over
};

double cost(i64 a, i64 b, double ln, double ang, double conc, const Nodes& N, const Params& P,
            double* tmp) {
    // no union above max_size (the nodes' weights: elements, for the planes' graphs)
    if (P.max_size > 0 && N.area[a] + N.area[b] > P.max_size) return INF;
    double c = 0.0;
    if (P.planarity > 0) {
        merged_scatter(a, b, N, tmp);
        c = plane(tmp[0], tmp[1], tmp[2], tmp[3], tmp[4], tmp[5]) - N.own[a] - N.own[b];
        c = mx(c, 0.0);
        if (P.planarity == 2) {  // flat pairs only: the rise per element of the smaller
            // (read over at least min_count of them: below, one point's noise decides)
            if (c > P.max_rise * mx(mn(N.area[a], N.area[b]), P.min_count) +
                        ROUNDING * (tmp[0] + tmp[1] + tmp[2]))
                return INF;
        } else if (P.planarity == 3) {  // the rise in max_rise's units, Ward's in 1 / compactness
            c = c / mx(P.max_rise, TINY) + P.compactness * spread(a, b, N);
        } else if (P.compactness > 0) {
            c += P.compactness * spread(a, b, N);
        }
    }
    if (P.planarity != 1) {  // the crease factor: of Ward's cost, or of the scene's
        double theta = 0.0, share = 0.0;
        if (ln > 0) {
            theta = ang / ln;
            share = conc / ln;
        }
        double s = theta * (share + P.eta_convex * (1.0 - share));
        c = (P.planarity == 3 ? c : spread(a, b, N)) * (1.0 + P.alpha * s / PI);
    }
    if (P.beta > 0) {
        double d2 = 0.0;
        for (i64 j = 0; j < N.d; ++j) {
            double d = N.fsum[N.d * a + j] / mx(N.area[a], TINY) -
                       N.fsum[N.d * b + j] / mx(N.area[b], TINY);
            d2 += d * d;
        }
        c *= 1.0 + P.beta * std::sqrt(d2);
    }
    return c;
}

// (cost, lo << 32 | hi, version_lo << 32 | version_hi): the order of (cost, lo, hi,
// version_lo, version_hi) for nodes and versions below 2^32, in 24 bytes, not 40
using Entry = std::tuple<double, std::uint64_t, std::uint64_t>;
inline std::uint64_t pack(i64 x, i64 y) {
    return (static_cast<std::uint64_t>(x) << 32) | static_cast<std::uint64_t>(y);
}

}  // namespace

nb::object merge_levels(i64 k, nb::handle ea_, nb::handle eb_, nb::handle stats_,
                              nb::handle area_, nb::handle wsum_, nb::handle fsum_,
                              nb::handle scatter_, i64 planarity, double alpha,
                              double eta_convex, double beta, double compactness,
                              double max_rise, nb::handle targets_, double max_size,
                              double min_count) {
    In<i64> ea(ea_, "ea"), eb(eb_, "eb"), targets(targets_, "targets");
    In<double> stats(stats_, "stats");
    Out<double> area(area_, "area"), wsum(wsum_, "wsum"), fsum(fsum_, "fsum"),
        scatter(scatter_, "scatter");
    if (stats.cols != 3 || wsum.cols != 3 || scatter.cols != 6 || k < 1)
        throw Mismatch("argument stats");
    if (k >= (i64(1) << 32)) throw Mismatch("argument k");  // (the heap's packed entries)
    check_rows(eb, ea.n, "eb", true);
    check_rows(stats, ea.n, "stats");
    check_range(ea, 0, k, "ea");
    check_range(eb, 0, k, "eb");
    check_rows(area, k, "area");
    check_rows(wsum, k, "wsum");
    check_rows(fsum, k, "fsum");
    check_rows(scatter, k, "scatter");
    Out<i64> out;
    auto out_a = fresh(targets.n, out, k);
    {
    nb::gil_scoped_release nogil;
    const i64 n_e = ea.n, cap = 2 * n_e;
    // each node's own plane() once, not at each of its pairs' costs (the same values)
    std::vector<double> own(planarity > 0 ? k : 0);
    for (i64 s = 0; s < (i64)own.size(); ++s) {
        const double* q = scatter.p + 6 * s;
        own[s] = plane(q[0], q[1], q[2], q[3], q[4], q[5]);
    }
    Nodes N{area.p, wsum.p, fsum.p, fsum.cols, scatter.p, own.data()};
    Params P{planarity, alpha, eta_convex, beta, compactness, max_rise, max_size, min_count};
    std::vector<i64> nb(cap), nxt(cap, -1), head(k, -1), tail(k, -1);
    std::vector<double> st(3 * cap);
    for (i64 t = 0; t < n_e; ++t)
        for (int side = 0; side < 2; ++side) {
            i64 u = side == 0 ? ea[t] : eb[t], v = side == 0 ? eb[t] : ea[t];
            i64 e = 2 * t + side;
            nb[e] = v;
            for (int j = 0; j < 3; ++j) st[3 * e + j] = stats(t, j);
            if (head[u] < 0) head[u] = e;
            else nxt[tail[u]] = e;
            tail[u] = e;
        }
    std::vector<i64> owner(k), version(k, 0), mark(k, -1), slot(k, 0);
    for (i64 s = 0; s < k; ++s) owner[s] = s;
    double tmp[6];
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap;
    heap.emplace(INF, ~std::uint64_t(0), ~std::uint64_t(0));  // a sentinel, never reached
    for (i64 t = 0; t < n_e; ++t) {
        i64 a = mn(ea[t], eb[t]), b = mx(ea[t], eb[t]);
        double c = cost(a, b, stats(t, 0), stats(t, 1), stats(t, 2), N, P, tmp);
        // (a pair that may not merge is left out: popped, it would end the merging, as
        // the sentinel does, and no finite entry comes after it)
        if (c != INF) heap.emplace(c, pack(a, b), 0);
    }
    i64 live = k, step = 0, i = 0;
    while (i < targets.n) {
        if (live == targets[i]) {
            for (i64 s = 0; s < k; ++s) out(i, s) = find(owner.data(), s);
            ++i;
            continue;
        }
        auto [c0, ab, vab] = heap.top();
        heap.pop();
        i64 a = static_cast<i64>(ab >> 32), b = static_cast<i64>(ab & 0xffffffffu);
        i64 va = static_cast<i64>(vab >> 32), vb = static_cast<i64>(vab & 0xffffffffu);
        if (c0 == INF) break;  // the sentinel, or no pair left that may merge
        if (owner[a] != a || owner[b] != b || version[a] != va || version[b] != vb) continue;
        owner[b] = a;
        if (planarity > 0) {
            merged_scatter(a, b, N, tmp);
            for (int j = 0; j < 6; ++j) scatter(a, j) = tmp[j];
            own[a] = plane(tmp[0], tmp[1], tmp[2], tmp[3], tmp[4], tmp[5]);
        }
        area[a] += area[b];
        for (int j = 0; j < 3; ++j) wsum(a, j) += wsum(b, j);
        for (i64 j = 0; j < N.d; ++j) fsum.p[N.d * a + j] += fsum.p[N.d * b + j];
        if (head[b] >= 0) {
            if (head[a] < 0) head[a] = head[b];
            else nxt[tail[a]] = head[b];
            tail[a] = tail[b];
        }
        head[b] = -1;
        version[a] += 1;
        ++step;
        i64 r = head[a], w_prev = -1;
        while (r >= 0) {
            i64 r_next = nxt[r];
            i64 c = find(owner.data(), nb[r]);
            if (c != a) {
                if (mark[c] == step) {
                    i64 e = slot[c];
                    for (int j = 0; j < 3; ++j) st[3 * e + j] += st[3 * r + j];
                } else {
                    i64 w = w_prev < 0 ? head[a] : nxt[w_prev];
                    nb[w] = c;
                    for (int j = 0; j < 3; ++j) st[3 * w + j] = st[3 * r + j];
                    mark[c] = step;
                    slot[c] = w;
                    w_prev = w;
                }
            }
            r = r_next;
        }
        if (w_prev < 0) {
            head[a] = -1;
            tail[a] = -1;
        } else {
            nxt[w_prev] = -1;
            tail[a] = w_prev;
        }
        for (i64 e = head[a]; e >= 0; e = nxt[e]) {
            i64 c = nb[e];
            i64 lo = a < c ? a : c, hi = a < c ? c : a;
            double ce = cost(lo, hi, st[3 * e], st[3 * e + 1], st[3 * e + 2], N, P, tmp);
            if (ce != INF) heap.emplace(ce, pack(lo, hi), pack(version[lo], version[hi]));
        }
        --live;
    }
    for (; i < targets.n; ++i)  // stopped: the roots as they are
        for (i64 s = 0; s < k; ++s) out(i, s) = find(owner.data(), s);
    }
    return out_a;
}

void bind_hierarchy(nb::module_& m) {
    m.def("merge_levels", &merge_levels,
          "Merge the cheapest adjacent pair until each of targets (decreasing, each reachable) "
          "live nodes remain, or no pair has a finite cost (max_size > 0: no union weighing "
          "more; planarity 2: a pair's rise read over at least min_count elements).",
          nb::arg("k"), nb::arg("ea"), nb::arg("eb"), nb::arg("stats"), nb::arg("area"),
          nb::arg("wsum"), nb::arg("fsum"), nb::arg("scatter"), nb::arg("planarity"),
          nb::arg("alpha"), nb::arg("eta_convex"), nb::arg("beta"), nb::arg("compactness"),
          nb::arg("max_rise"), nb::arg("targets"), nb::arg("max_size") = 0.0,
          nb::arg("min_count") = 0.0);
}

}  // namespace sfk
