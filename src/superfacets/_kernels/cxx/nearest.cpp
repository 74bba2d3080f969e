// tests/oracle/nearest.py: the tree of a cloud's Z-order and the k nearest
// neighbours of its points, the same operations in the same order. The tree's rows are
// the points in its own order; ids names the point of each row (ties go to the lower id;
// no ids: the rows are the points).
#include "common.hpp"
#include "points.hpp"

#include <algorithm>
#include <limits>

namespace sfk {

namespace {

constexpr i64 STACK = 512;

inline i64 first_bit(const std::uint64_t* keys, i64 a, i64 b, i64 start) {
    for (i64 w = start / 63; w < 3; ++w) {
        std::uint64_t x = keys[3 * a + w] ^ keys[3 * b + w];
        if (w == start / 63) x &= (std::uint64_t{1} << (63 - (start - w * 63))) - 1;
        if (x != 0) {
            int top = 62;
            while (((x >> top) & 1u) == 0) --top;
            return w * 63 + (62 - top);
        }
    }
    return -1;
}

inline bool bit_of(const std::uint64_t* keys, i64 r, i64 bit) {
    i64 w = bit / 63;
    return (keys[3 * r + w] >> (62 - (bit - w * 63))) & 1u;
}

inline double gap2(double lo, double hi, double q) {
    double g = lo - q;
    if (g <= 0.0) {
        g = q - hi;
        if (g < 0.0) g = 0.0;
    }
    return g * g;
}

inline double box_distance(const double* box, double qx, double qy, double qz) {
    return gap2(box[0], box[3], qx) + gap2(box[1], box[4], qy) + gap2(box[2], box[5], qz);
}

struct Tree {
    const double* pts;
    const i64* start;
    const i64* end;
    const i64* left;
    const double* boxes;
    const i64* ids;  // the point of each row (rows in the tree's order); null: the row
};

// The children of inner node v's first child c, nearer first: near, far and their boxes'
// squared distances d0 <= d1 from the query.
inline void children_by_distance(const Tree& t, i64 c, double qx, double qy, double qz,
                                 i64& near, i64& far, double& d0, double& d1) {
    d0 = box_distance(t.boxes + 6 * c, qx, qy, qz);
    d1 = box_distance(t.boxes + 6 * (c + 1), qx, qy, qz);
    near = c;
    far = c + 1;
    if (d1 < d0) {
        near = c + 1;
        far = c;
        std::swap(d0, d1);
    }
}

// nearest._query
i64 query(const Tree& t, i64 i, i64 k, double* bd, i64* bi, i64* stack, double* sd,
          i64* sib) {
    const double* p = t.pts;
    const double qx = p[3 * i], qy = p[3 * i + 1], qz = p[3 * i + 2];
    i64 cnt = 0, ns = 0, v = 0;
    while (t.left[v] >= 0) {
        i64 c = t.left[v];
        if (i < t.end[c]) {
            sib[ns] = c + 1;
            v = c;
        } else {
            sib[ns] = c;
            v = c + 1;
        }
        ++ns;
    }
    stack[0] = v;
    sd[0] = 0.0;
    i64 sp = 1;
    while (true) {
        while (sp > 0) {
            --sp;
            v = stack[sp];
            if (cnt == k && sd[sp] > bd[k - 1]) continue;
            i64 c = t.left[v];
            if (c < 0) {
                for (i64 r = t.start[v]; r < t.end[v]; ++r) {
                    if (r == i) continue;
                    double dx = p[3 * r] - qx, dy = p[3 * r + 1] - qy, dz = p[3 * r + 2] - qz;
                    double d = dx * dx + dy * dy + dz * dz;
                    const i64 id = t.ids ? t.ids[r] : r;
                    i64 q;
                    if (cnt < k) {
                        q = cnt++;
                    } else if (d < bd[k - 1] || (d == bd[k - 1] && id < bi[k - 1])) {
                        q = k - 1;
                    } else {
                        continue;
                    }
                    while (q > 0 && (bd[q - 1] > d || (bd[q - 1] == d && bi[q - 1] > id))) {
                        bd[q] = bd[q - 1];
                        bi[q] = bi[q - 1];
                        --q;
                    }
                    bd[q] = d;
                    bi[q] = id;
                }
            } else {
                i64 near, far;
                double d0, d1;
                children_by_distance(t, c, qx, qy, qz, near, far, d0, d1);
                if (!(cnt == k && d1 > bd[k - 1])) {
                    stack[sp] = far;
                    sd[sp] = d1;
                    ++sp;
                }
                stack[sp] = near;
                sd[sp] = d0;
                ++sp;
            }
        }
        if (ns == 0) break;
        --ns;
        stack[0] = sib[ns];
        sd[0] = box_distance(t.boxes + 6 * sib[ns], qx, qy, qz);
        sp = 1;
    }
    return cnt;
}

// nearest._closest
i64 closest(const Tree& t, double qx, double qy, double qz, i64* stack, double* sd) {
    const double* p = t.pts;
    double best = INF;
    i64 bid = -1;
    stack[0] = 0;
    sd[0] = box_distance(t.boxes, qx, qy, qz);
    i64 sp = 1;
    while (sp > 0) {
        --sp;
        const i64 v = stack[sp];
        if (sd[sp] > best) continue;
        const i64 c = t.left[v];
        if (c < 0) {
            for (i64 r = t.start[v]; r < t.end[v]; ++r) {
                double dx = p[3 * r] - qx, dy = p[3 * r + 1] - qy, dz = p[3 * r + 2] - qz;
                double d = dx * dx + dy * dy + dz * dz;
                const i64 id = t.ids ? t.ids[r] : r;
                if (d < best || (d == best && id < bid)) {
                    best = d;
                    bid = id;
                }
            }
        } else {
            i64 near, far;
            double d0, d1;
            children_by_distance(t, c, qx, qy, qz, near, far, d0, d1);
            if (d1 <= best) {
                stack[sp] = far;
                sd[sp] = d1;
                ++sp;
            }
            if (d0 <= best) {
                stack[sp] = near;
                sd[sp] = d0;
                ++sp;
            }
        }
    }
    return bid;
}

}  // namespace

i64 tree_nodes(nb::handle pts_, nb::handle keys_, i64 leaf, nb::handle start_, nb::handle end_,
               nb::handle left_, nb::handle boxes_) {
    In<double> pts(pts_, "pts");
    In<std::uint64_t> keys(keys_, "keys");
    Out<i64> start(start_, "start"), end(end_, "end"), left(left_, "left");
    Out<double> boxes(boxes_, "boxes");
    if (pts.cols != 3 || keys.cols != 3 || keys.n != pts.n || boxes.cols != 6 ||
        end.n != start.n || left.n != start.n || boxes.n != start.n)
        throw Mismatch("argument pts");
    if (leaf < 1)  // (a leaf of 0 points is never small enough: the split never ends)
        throw OutOfRange("argument leaf: " + std::to_string(leaf) + ", outside 1..");
    nb::gil_scoped_release nogil;
    const i64 n = pts.n, cap = start.n;
    if (cap < 1) return -1;
    std::vector<i64> stack(2 * STACK);
    start[0] = 0;
    end[0] = n;
    i64 nn = 1, sp = 1;
    stack[0] = 0;
    stack[1] = 0;
    while (sp > 0) {
        --sp;
        i64 v = stack[2 * sp], b = stack[2 * sp + 1];
        i64 s = start[v], e = end[v];
        left[v] = -1;
        if (e - s <= leaf) continue;
        i64 m = s;
        while (true) {
            i64 bit = first_bit(keys.p, s, e - 1, b);
            if (bit < 0) {
                m = (s + e) / 2;
                b = 189;
                break;
            }
            i64 lo = s, hi = e - 1;
            while (lo < hi) {
                i64 mid = (lo + hi) / 2;
                if (bit_of(keys.p, mid, bit))
                    hi = mid;
                else
                    lo = mid + 1;
            }
            b = bit + 1;
            if (s < lo && lo < e) {
                m = lo;
                break;
            }
        }
        if (nn + 2 > cap) return -1;
        left[v] = nn;
        start[nn] = s;
        end[nn] = m;
        start[nn + 1] = m;
        end[nn + 1] = e;
        stack[2 * sp] = nn + 1;
        stack[2 * sp + 1] = b;
        stack[2 * sp + 2] = nn;
        stack[2 * sp + 3] = b;
        sp += 2;
        nn += 2;
    }
    // the leaves' boxes on threads (the points' pass), then the others' from their
    // children, bottom up (children come after their parent)
    parallel_for(nn, [&](i64 v0, i64 v1) {
        for (i64 v = v0; v < v1; ++v) {
            if (left[v] >= 0) continue;
            for (int a = 0; a < 3; ++a) {
                double lo = INF, hi = -INF;
                for (i64 t = start[v]; t < end[v]; ++t) {
                    double x = pts(t, a);
                    if (x < lo) lo = x;
                    if (x > hi) hi = x;
                }
                boxes(v, a) = lo;
                boxes(v, 3 + a) = hi;
            }
        }
    });
    for (i64 v = nn - 1; v >= 0; --v) {
        i64 c = left[v];
        if (c < 0) continue;
        for (int a = 0; a < 3; ++a) {
            boxes(v, a) = mn(boxes(c, a), boxes(c + 1, a));
            boxes(v, 3 + a) = mx(boxes(c, 3 + a), boxes(c + 1, 3 + a));
        }
    }
    return nn;
}

// A tree that keeps a search inside its arrays: nodes of the points start..end, each
// inner node's children later than it and splitting its range, at most STACK - 2 deep.
inline void check_tree(i64 n_pts, const In<i64>& start, const In<i64>& end,
                       const In<i64>& left, i64 n_boxes) {
    const i64 n = start.n;
    if (n < 1 || end.n != n || left.n != n || n_boxes != n)
        throw OutOfRange("arguments start, end, left, boxes: one entry per node");
    if (start[0] != 0 || end[0] != n_pts) throw OutOfRange("argument start: not the points");
    std::vector<i64> depth(n, 0);
    for (i64 v = 0; v < n; ++v) {
        const i64 c = left[v];
        if (c < 0) continue;
        if (c <= v || c + 1 >= n || start[c] != start[v] || end[c] != start[c + 1] ||
            end[c + 1] != end[v] || start[c] > end[c] || start[c + 1] > end[c + 1] ||
            depth[v] + 1 >= STACK - 2)
            throw OutOfRange("argument left: not a tree of the points");
        depth[c] = depth[c + 1] = depth[v] + 1;
    }
}

void nearest_in_tree(nb::handle pts_, nb::handle start_, nb::handle end_, nb::handle left_,
                     nb::handle boxes_, nb::handle ids_, nb::handle own_, i64 k, double limit,
                     nb::handle nbr_, nb::handle kth_, nb::handle within_) {
    In<double> pts(pts_, "pts"), boxes(boxes_, "boxes");
    In<i64> start(start_, "start"), end(end_, "end"), left(left_, "left"), own(own_, "own"),
        ids(ids_, "ids");
    Out<i32> nbr(nbr_, "nbr");
    Out<double> kth(kth_, "kth");
    Out<bool> within(within_, "within");
    if (pts.cols != 3 || boxes.cols != 6 || nbr.cols != k + 1 || nbr.n != own.n ||
        kth.n != own.n || k < 1)
        throw Mismatch("argument nbr");
    // (the neighbours within `limit` where asked for, else an empty (0, k) array)
    if (within.n != 0 && (within.n != own.n || within.cols != k))
        throw Mismatch("argument within");
    check_tree(pts.n, start, end, left, boxes.n);
    check_range(own, 0, pts.n, "own");
    if (ids.n != pts.n && ids.n != 0) throw Mismatch("argument ids");
    check_range(ids, 0, std::numeric_limits<i32>::max(), "ids");
    nb::gil_scoped_release nogil;
    const Tree t{pts.p, start.p, end.p, left.p, boxes.p, ids.n ? ids.p : nullptr};
    const bool flag = within.n != 0;
    // every query in one loop (its ranges taken in turn by the threads): queried in blocks
    // from Python, each block waited for its slowest range and checked the tree again
    parallel_for(own.n, [&](i64 lo, i64 hi) {
        std::vector<double> bd(k), sd(STACK);
        std::vector<i64> bi(k), stack(STACK), sib(STACK);
        for (i64 r = lo; r < hi; ++r) {
            i64 i = own[r];
            i64 got = query(t, i, k, bd.data(), bi.data(), stack.data(), sd.data(), sib.data());
            nbr(r, 0) = static_cast<i32>(t.ids ? t.ids[i] : i);
            for (i64 j = 0; j < got; ++j) nbr(r, j + 1) = static_cast<i32>(bi[j]);
            kth[r] = got > 0 ? std::sqrt(bd[got - 1]) : 0.0;
            if (flag)
                for (i64 j = 0; j < k; ++j) within(r, j) = j < got && std::sqrt(bd[j]) <= limit;
        }
    });
}

void closest_in_tree(nb::handle pts_, nb::handle start_, nb::handle end_, nb::handle left_,
                     nb::handle boxes_, nb::handle ids_, nb::handle queries_,
                     nb::handle out_) {
    In<double> pts(pts_, "pts"), boxes(boxes_, "boxes"), queries(queries_, "queries");
    In<i64> start(start_, "start"), end(end_, "end"), left(left_, "left"), ids(ids_, "ids");
    Out<i64> out(out_, "out");
    if (pts.cols != 3 || boxes.cols != 6 || queries.cols != 3 || out.n != queries.n)
        throw Mismatch("argument out");
    if (pts.n < 1) throw OutOfRange("argument pts: no points to be nearest");
    check_tree(pts.n, start, end, left, boxes.n);
    if (ids.n != pts.n && ids.n != 0) throw Mismatch("argument ids");
    check_range(ids, 0, std::numeric_limits<i64>::max(), "ids");
    nb::gil_scoped_release nogil;
    const Tree t{pts.p, start.p, end.p, left.p, boxes.p, ids.n ? ids.p : nullptr};
    parallel_for(queries.n, [&](i64 lo, i64 hi) {
        std::vector<double> sd(STACK);
        std::vector<i64> stack(STACK);
        for (i64 r = lo; r < hi; ++r)
            out[r] = closest(t, queries(r, 0), queries(r, 1), queries(r, 2), stack.data(),
                             sd.data());
    });
}

// nearest.surface_select: of each point's candidates (cand: itself, then its kc nearest in
// the order of (distance, id), as nearest_in_tree lists them), the k whose offset d has the
// least |d|^2 + (step^2 - 1) (n . d)^2 (ties: the lower id), n the normal (PCA) of the
// point and its k nearest (cand's first k + 1), in that order, into nbr (itself first);
// the distance to the farthest of them into kth; where pick is not empty, the column of
// cand each came from.
void surface_select(nb::handle pts_, nb::handle cand_, i64 k, double step, nb::handle nbr_,
                    nb::handle kth_, nb::handle pick_) {
    In<double> pts(pts_, "pts");
    In<i32> cand(cand_, "cand");
    Out<i32> nbr(nbr_, "nbr"), pick(pick_, "pick");
    Out<double> kth(kth_, "kth");
    const i64 kc = cand.cols - 1;
    if (pts.cols != 3 || cand.n != pts.n || k < 1 || k > kc || nbr.n != pts.n ||
        nbr.cols != k + 1 || kth.n != pts.n)
        throw Mismatch("argument nbr");
    if (pick.n != 0 && (pick.n != pts.n || pick.cols != k)) throw Mismatch("argument pick");
    check_range(cand, 0, pts.n, "cand");
    const double grow = step * step - 1.0;
    nb::gil_scoped_release nogil;
    // The candidates come by (distance, id) and no key is below its squared distance, so
    // the k best keys are found once a candidate lies farther than the k-th best key:
    // a sorted insertion that stops there (on a flat patch, after the k nearest).
    parallel_for(pts.n, [&](i64 lo, i64 hi) {
        std::vector<double> bk(k), bd(k);
        std::vector<i64> bc(k), bid(k);
        for (i64 r = lo; r < hi; ++r) {
            const i64 i = cand(r, 0);
            const double px = pts(i, 0), py = pts(i, 1), pz = pts(i, 2);
            double a[6], nor[3];
            unit_scatter(pts.p, cand.p + r * cand.cols, k + 1, a);
            smallest_eigenvector(a[0], a[1], a[2], a[3], a[4], a[5], nor);
            const double nx = nor[0], ny = nor[1], nz = nor[2];
            i64 cnt = 0;
            for (i64 c = 0; c < kc; ++c) {
                const i64 j = cand(r, c + 1);
                const double dx = pts(j, 0) - px, dy = pts(j, 1) - py, dz = pts(j, 2) - pz;
                const double d2 = (dx * dx + dy * dy) + dz * dz;
                if (cnt == k && d2 > bk[k - 1]) break;
                const double off = (dx * nx + dy * ny) + dz * nz;
                const double key = d2 + grow * (off * off);
                i64 q;
                if (cnt < k) {
                    q = cnt++;
                } else if (key < bk[k - 1] || (key == bk[k - 1] && j < bid[k - 1])) {
                    q = k - 1;
                } else {
                    continue;
                }
                while (q > 0 && (bk[q - 1] > key || (bk[q - 1] == key && bid[q - 1] > j))) {
                    bk[q] = bk[q - 1];
                    bd[q] = bd[q - 1];
                    bc[q] = bc[q - 1];
                    bid[q] = bid[q - 1];
                    --q;
                }
                bk[q] = key;
                bd[q] = d2;
                bc[q] = c;
                bid[q] = j;
            }
            nbr(r, 0) = cand(r, 0);
            double far = 0.0;
            for (i64 m = 0; m < k; ++m) {
                nbr(r, m + 1) = static_cast<i32>(bid[m]);
                far = std::max(far, bd[m]);
                if (pick.n != 0) pick(r, m) = static_cast<i32>(bc[m] + 1);
            }
            kth[r] = std::sqrt(far);
        }
    });
}

void bind_nearest(nb::module_& m) {
    m.def("tree_nodes", &tree_nodes,
          "Build the tree over pts ((n, 3) float64, sorted by their Z-order keys, (n, 3) "
          "uint64).",
          nb::arg("pts"), nb::arg("keys"), nb::arg("leaf"), nb::arg("start"), nb::arg("end"),
          nb::arg("left"), nb::arg("boxes"));
    m.def("nearest_in_tree", &nearest_in_tree,
          "For each query r (the row own[r] of pts, the rows in the tree's order, ids[row] each"
          " one's point, none: the rows are the points): its k nearest others into nbr, the "
          "distance to the last into kth and, where within is not empty, which lie within "
          "limit.",
          nb::arg("pts"), nb::arg("start"), nb::arg("end"), nb::arg("left"), nb::arg("boxes"),
          nb::arg("ids"), nb::arg("own"), nb::arg("k"), nb::arg("limit"), nb::arg("nbr"),
          nb::arg("kth"), nb::arg("within"));
    m.def("surface_select", &surface_select,
          "Of each point's candidates (cand: itself, then its nearest by (distance, id)), the "
          "k whose offset d has the least |d|^2 + (step^2 - 1) (n . d)^2 (ties: the lower "
          "id), n the PCA normal of cand's first k + 1, into nbr; the distance to the "
          "farthest into kth; their columns into pick where not empty.",
          nb::arg("pts"), nb::arg("cand"), nb::arg("k"), nb::arg("step"),
          nb::arg("nbr"), nb::arg("kth"), nb::arg("pick"));
    m.def("closest_in_tree", &closest_in_tree,
          "For each query position r (queries: (m, 3) float64): the id of the tree's nearest "
          "point into out[r] (ties: the lower id; ids[row] each row's point, none: the rows "
          "are the points; -1 where the query is not finite).",
          nb::arg("pts"), nb::arg("start"), nb::arg("end"), nb::arg("left"), nb::arg("boxes"),
          nb::arg("ids"), nb::arg("queries"), nb::arg("out"));
}

}  // namespace sfk
