// Per-element geometry and orders: faces' and polygons' centroids, normals and
// areas, their pairs' terms, edge lengths; the points' Z-order keys, distinct positions,
// pair terms and per-label sums; key windows and tie orders.
// Reference, bit for bit: tests/oracle/geometry.py.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <type_traits>
#include <vector>

#include "common.hpp"
#include "points.hpp"

namespace sfk {

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

// Z-order keys in a local frame: each coordinate as the integer
// min(floor((x - lo) * scale), 2^62), its top bit set, interleaved x, y, z from the top
// (21 bits of each a word). With lo the cloud's lower corner and 2^62 / scale the least
// power of two above its largest side, the keys split space alike along every axis,
// wherever the cloud sits.
void local_morton_keys(nb::handle pts_, nb::handle lo_, double scale, nb::handle keys_) {
    In<double> pts(pts_, "pts"), lo(lo_, "lo");
    Out<std::uint64_t> keys(keys_, "keys");
    if (pts.cols != 3 || lo.n != 3 || keys.cols != 3) throw Mismatch("argument pts");
    check_rows(keys, pts.n, "keys");
    nb::gil_scoped_release nogil;
    const double cap = 4611686018427387904.0;  // 2^62
    const double l0 = lo[0], l1 = lo[1], l2 = lo[2];
    parallel_for(pts.n, [&](i64 a0, i64 a1) {
        for (i64 i = a0; i < a1; ++i) {
            std::uint64_t o[3];
            const double l[3] = {l0, l1, l2};
            for (int a = 0; a < 3; ++a) {
                double q = std::floor((pts(i, a) - l[a]) * scale);
                if (!(q > 0.0)) q = 0.0;  // (NaN too)
                if (q > cap) q = cap;
                o[a] = static_cast<std::uint64_t>(q) | (1ULL << 63);
            }
            interleave(o, &keys(i, 0));
        }
    });
}

i64 distinct_in_order(nb::handle p_, nb::handle order_, nb::handle out_, nb::handle inverse_) {
    In<double> p(p_, "p");
    In<i64> order(order_, "order");
    Out<double> out(out_, "out");
    Out<i64> inverse(inverse_, "inverse");
    if (p.cols != 3 || out.cols != 3) throw Mismatch("argument p");
    check_range(order, 0, mn(p.n, inverse.n), "order");
    check_rows(out, order.n, "out");
    nb::gil_scoped_release nogil;
    const i64 n = order.n;
    std::vector<i64> place(n);
    parallel_for(n, [&](i64 lo, i64 hi) {
        for (i64 i = lo; i < hi; ++i) {
            if (i == 0) {
                place[i] = 1;
            } else {
                i64 row = order[i], prev = order[i - 1];
                bool nw = p(row, 0) != p(prev, 0) || p(row, 1) != p(prev, 1) ||
                          p(row, 2) != p(prev, 2);
                place[i] = nw ? 1 : 0;
            }
        }
    });
    i64 m = 0;
    for (i64 i = 0; i < n; ++i) {
        m += place[i];
        place[i] = m - 1;
    }
    parallel_for(n, [&](i64 lo, i64 hi) {
        for (i64 i = lo; i < hi; ++i) {
            i64 row = order[i], j = place[i];
            if (i == 0 || place[i - 1] != j) {
                out(j, 0) = p(row, 0);
                out(j, 1) = p(row, 1);
                out(j, 2) = p(row, 2);
            }
            inverse[row] = j;
        }
    });
    return m;
}

void point_terms(nb::handle positions_, nb::handle normals_, nb::handle pairs_, i64 lo, i64 hi,
                 nb::handle geo_, nb::handle cos_, nb::handle concave_) {
    In<double> pos(positions_, "positions");
    Out<double> geo(geo_, "geo"), cs(cos_, "cos");
    Out<bool> concave(concave_, "concave");
    with_real(normals_, "normals", [&](const auto& nor) {
        if (pos.cols != 3 || nor.cols != 3) throw Mismatch("argument positions");
        return with_index(pairs_, "pairs", [&](const auto& pairs) {
            if (pairs.cols != 2) throw Mismatch("argument pairs");
            check_span(lo, hi, pairs.n, pairs.n);
            using P = std::remove_cv_t<std::remove_reference_t<decltype(pairs.p[0])>>;
            check_range(In<P>(pairs.p + 2 * lo, hi - lo, 2), 0, mn(pos.n, nor.n), "pairs");
            check_rows(geo, hi - lo, "geo");
            check_rows(cs, hi - lo, "cos");
            check_rows(concave, hi - lo, "concave");
            nb::gil_scoped_release nogil;
            for (i64 t = lo; t < hi; ++t)
                pair_terms(pos.p, nor.p, pairs(t, 0), pairs(t, 1), geo[t - lo], cs[t - lo],
                           concave[t - lo]);
            return 0;
        });
    });
}

// f(i, s) for each element i and its label s (of k), on threads, each owning a range of
// the labels: every thread reads all the elements, in order, and takes those of its
// labels, so each label's sums are those of one pass (bit for bit)
template <class L, class F>
void each_by_label(const L& labels, i64 k, F f) {
    const i64 n = labels.n;
    const i64 T = std::max<i64>(1, std::min<i64>({threads(), k, n / 65536}));
    on_threads(T, [&](i64 t) {
        const i64 lo = k * t / T, hi = k * (t + 1) / T;
        for (i64 i = 0; i < n; ++i) {
            const i64 s = labels[i];
            if (s >= lo && s < hi) f(i, s);
        }
    });
}

void label_sums(nb::handle labels_, nb::handle weights_, nb::handle positions_,
                nb::handle normals_, nb::handle area_, nb::handle wpos_, nb::handle wnrm_) {
    In<double> w(weights_, "weights"), pos(positions_, "positions");
    Out<double> area(area_, "area"), wpos(wpos_, "wpos"), wnrm(wnrm_, "wnrm");
    with_real(normals_, "normals", [&](const auto& nor) {
        return with_index(labels_, "labels", [&](const auto& labels) {
            if (pos.cols != 3 || nor.cols != 3 || wpos.cols != 3 || wnrm.cols != 3 ||
                w.n != labels.n || pos.n != labels.n || nor.n != labels.n ||
                wpos.n != area.n || wnrm.n != area.n)
                throw Mismatch("argument positions");
            nb::gil_scoped_release nogil;  // (labels outside 0..k - 1 are skipped)
            each_by_label(labels, area.n, [&](i64 i, i64 s) {
                double x = w[i];
                area[s] += x;
                for (int c = 0; c < 3; ++c) wpos(s, c) += x * pos(i, c);
                for (int c = 0; c < 3; ++c) wnrm(s, c) += x * static_cast<double>(nor(i, c));
            });
            return 0;
        });
    });
}

void label_scatter(nb::handle labels_, nb::handle weights_, nb::handle positions_,
                   nb::handle centroid_, nb::handle scatter_) {
    In<i64> labels(labels_, "labels");
    In<double> w(weights_, "weights"), pos(positions_, "positions"), cen(centroid_, "centroid");
    Out<double> sc(scatter_, "scatter");
    if (pos.cols != 3 || cen.cols != 3 || sc.cols != 9 || w.n != labels.n ||
        pos.n != labels.n || sc.n != cen.n)
        throw Mismatch("argument positions");
    nb::gil_scoped_release nogil;  // (labels outside 0..k - 1 are skipped)
    each_by_label(labels, sc.n, [&](i64 i, i64 s) {
        double x = w[i];
        double d[3] = {pos(i, 0) - cen(s, 0), pos(i, 1) - cen(s, 1), pos(i, 2) - cen(s, 2)};
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) sc(s, 3 * a + b) += x * d[a] * d[b];
    });
}

// geometry.border_shares: out[i] = 2 sqrt(pi area[i]) / max(deg_i, 1), the degree from
// the CSR layout, each operation as numpy's expression rounds it
void border_shares(nb::handle indptr_, nb::handle area_, nb::handle out_) {
    In<i64> indptr(indptr_, "indptr");
    In<double> area(area_, "area");
    Out<double> out(out_, "out");
    if (indptr.n != area.n + 1 || out.n != area.n) throw Mismatch("argument out");
    nb::gil_scoped_release nogil;  // (only differences of indptr read: any values)
    constexpr double pi = 3.141592653589793;  // np.pi
    parallel_for(area.n, [&](i64 i0, i64 i1) {
        for (i64 i = i0; i < i1; ++i) {
            const double deg = static_cast<double>(indptr[i + 1] - indptr[i]);
            out[i] = 2.0 * std::sqrt(pi * area[i]) / (deg > 1.0 ? deg : 1.0);
        }
    });
}

namespace {

struct Pair {
    std::uint64_t key;
    i64 row;
};

// Stable LSD radix sort of a[0:n] by key, 11 bits a pass (a digit every key shares is
// skipped); tmp: room for n pairs. Returns the buffer that holds the result.
Pair* radix_sort(Pair* a, Pair* tmp, i64 n) {
    constexpr int BITS = 11, DIGITS = (64 + BITS - 1) / BITS, R = 1 << BITS;
    constexpr std::uint64_t MASK = R - 1;
    std::vector<i64> count(DIGITS * R, 0);
    for (i64 i = 0; i < n; ++i) {
        std::uint64_t k = a[i].key;
        for (int d = 0; d < DIGITS; ++d) ++count[d * R + ((k >> (BITS * d)) & MASK)];
    }
    Pair *src = a, *dst = tmp;
    for (int d = 0; d < DIGITS; ++d) {
        i64* c = count.data() + d * R;
        bool one = false;
        for (int b = 0; b < R; ++b) {
            if (c[b] == n) one = true;
        }
        if (one || n == 0) continue;  // every key has this digit: the order stands
        i64 at = 0;
        for (int b = 0; b < R; ++b) {
            i64 m = c[b];
            c[b] = at;
            at += m;
        }
        const int shift = BITS * d;
        for (i64 i = 0; i < n; ++i) dst[c[(src[i].key >> shift) & MASK]++] = src[i];
        std::swap(src, dst);
    }
    return src;
}

// The number of entries of a (length na) that come before place k of the stable merge
// of a and b (a first among equal keys).
i64 corank(i64 k, const Pair* a, i64 na, const Pair* b, i64 nb) {
    i64 lo = std::max<i64>(0, k - nb), hi = std::min(k, na);
    while (lo < hi) {
        i64 i = (lo + hi) / 2, j = k - i;
        if (j > 0 && i < na && b[j - 1].key >= a[i].key)
            lo = i + 1;
        else
            hi = i;
    }
    return lo;
}

}  // namespace

// geometry.sort_keys: order = the stable argsort of keys, sorted = keys[order]. Each
// thread sorts a run of the keys (radix), then the runs are merged two by two, each
// merge split over the threads at equal output places (the stable merge: the same
// order as one stable sort of all the keys).
void sort_keys(nb::handle keys_, nb::handle order_, nb::handle sorted_) {
    In<std::uint64_t> keys(keys_, "keys");
    Out<i64> order(order_, "order");
    Out<std::uint64_t> sorted(sorted_, "sorted");
    const i64 n = keys.n;
    if (order.n != n || sorted.n != n || keys.cols != 1) throw Mismatch("argument order");
    nb::gil_scoped_release nogil;
    const i64 T = std::max<i64>(1, std::min<i64>(threads(), n / (1 << 16)));
    std::vector<Pair> a(static_cast<size_t>(n)), b(static_cast<size_t>(n));
    std::vector<i64> cut(T + 1);
    for (i64 t = 0; t <= T; ++t) cut[t] = n * t / T;
    Pair *src = a.data(), *dst = b.data();
    on_threads(T, [&](i64 t) {  // each run sorted, left in src
        const i64 lo = cut[t], m = cut[t + 1] - lo;
        for (i64 i = lo; i < lo + m; ++i) src[i] = {keys[i], i};
        if (radix_sort(src + lo, dst + lo, m) != src + lo)
            std::copy(dst + lo, dst + lo + m, src + lo);
    });
    std::vector<i64> runs(cut);  // run r: src[runs[r]:runs[r + 1]]
    while (true) {
        const i64 nr = static_cast<i64>(runs.size()) - 1;
        const bool last = nr <= 2;  // the last merge writes the outputs
        std::vector<i64> next;
        for (i64 r = 0; r < nr; r += 2) {
            next.push_back(runs[r]);
            const i64 lo = runs[r];
            const i64 mid = r + 1 < nr ? runs[r + 1] : runs[r + 1];
            const i64 hi = r + 1 < nr ? runs[r + 2] : runs[r + 1];
            const Pair* x = src + lo;
            const Pair* y = src + mid;
            const i64 nx = mid - lo, ny = hi - mid, total = nx + ny;
            on_threads(T, [&](i64 t) {  // the stable merge of x and y, split at equal places
                const i64 k0 = total * t / T, k1 = total * (t + 1) / T;
                i64 i = corank(k0, x, nx, y, ny), j = k0 - i;
                const i64 ie = corank(k1, x, nx, y, ny), je = k1 - ie;
                for (i64 k = k0; k < k1; ++k) {
                    const Pair& p =
                        (j >= je || (i < ie && x[i].key <= y[j].key)) ? x[i++] : y[j++];
                    if (last) {
                        order[lo + k] = p.row;
                        sorted[lo + k] = p.key;
                    } else {
                        dst[lo + k] = p;
                    }
                }
            });
        }
        if (last) return;
        next.push_back(n);
        runs.swap(next);
        std::swap(src, dst);
    }
}

// geometry.rows_apart: the rows i (ascending) where index[i] < 0 or the three words of
// at[index[i]] differ from bits[i], into rows; their number, or -1 (rows[:cap] written,
// the first cap of them) when there are more than rows' length cap.
i64 rows_apart(nb::handle bits_, nb::handle at_, nb::handle index_, nb::handle rows_) {
    In<std::uint64_t> bits(bits_, "bits"), at(at_, "at");
    Out<i64> rows(rows_, "rows");
    if (bits.cols != 3 || at.cols != 3) throw Mismatch("argument bits");
    return with_index(index_, "index", [&](const auto& index) -> i64 {
        if (index.n != bits.n) throw Mismatch("argument index");
        check_range(index, std::numeric_limits<i64>::min(), at.n, "index");  // (-1: none)
        nb::gil_scoped_release nogil;
        const i64 n = bits.n, cap = rows.n;
        const i64 T = std::max<i64>(1, std::min<i64>(threads(), n / 4096));
        std::vector<std::vector<i64>> found(T);
        on_threads(T, [&](i64 t) {
            auto& f = found[t];
            for (i64 i = n * t / T; i < n * (t + 1) / T; ++i) {
                const i64 j = index[i];
                if (j < 0 || at(j, 0) != bits(i, 0) || at(j, 1) != bits(i, 1) ||
                    at(j, 2) != bits(i, 2)) {
                    f.push_back(i);
                    if (static_cast<i64>(f.size()) > cap) return;  // too many already
                }
            }
        });
        i64 m = 0;
        for (i64 t = 0; t < T; ++t) {
            for (i64 r : found[t]) {
                if (m == cap) return -1;
                rows[m++] = r;
            }
        }
        return m;
    });
}

// geometry.order_ties: each run of equal keys in `ordered` (the sorted Z-order windows)
// put in the order of the rows' whole keys (keys[row, 0..2]), then their positions,
// stably: equal in all, in the order given. Threads take the runs of their range.
void order_ties(nb::handle order_, nb::handle ordered_, nb::handle keys_, nb::handle p_) {
    Out<i64> order(order_, "order");
    In<std::uint64_t> ordered(ordered_, "ordered"), keys(keys_, "keys");
    In<double> p(p_, "p");
    const i64 n = order.n;
    if (ordered.n != n || keys.cols != 3 || p.cols != 3 || keys.n != p.n)
        throw Mismatch("argument keys");
    check_range(order, 0, keys.n, "order");
    nb::gil_scoped_release nogil;
    auto less = [&](i64 a, i64 b) {
        for (int w = 0; w < 3; ++w)
            if (keys(a, w) != keys(b, w)) return keys(a, w) < keys(b, w);
        for (int w = 0; w < 3; ++w)
            if (p(a, w) != p(b, w)) return p(a, w) < p(b, w);
        return false;
    };
    parallel_for(n, [&](i64 lo, i64 hi) {
        // the runs that start in [lo, hi)
        i64 a = lo;
        while (a > 0 && a < hi && ordered[a] == ordered[a - 1]) ++a;
        while (a < hi) {
            i64 b = a + 1;
            while (b < n && ordered[b] == ordered[a]) ++b;
            if (b - a > 1) std::stable_sort(order.p + a, order.p + b, less);
            a = b;
        }
    });
}

// geometry.key_window: bits start .. start + 63 of each row's 189-bit key string (63 bits
// a word, the first bit the highest; zeros past its end), as one uint64, on threads
void key_window(nb::handle keys_, i64 start, nb::handle out_) {
    In<std::uint64_t> keys(keys_, "keys");
    Out<std::uint64_t> out(out_, "out");
    if (keys.cols != 3 || out.n != keys.n || start < 0 || start >= 189)
        throw Mismatch("argument keys");
    nb::gil_scoped_release nogil;
    const i64 j = start / 63, o = start % 63;
    const std::uint64_t mask = (std::uint64_t{1} << (63 - o)) - 1;
    parallel_for(keys.n, [&](i64 r0, i64 r1) {
        for (i64 r = r0; r < r1; ++r) {
            std::uint64_t x = (keys(r, j) & mask) << (o + 1);
            if (j < 2) x |= keys(r, j + 1) >> (62 - o);
            out[r] = x;
        }
    });
}

void bind_geometry(nb::module_& m) {
    m.def("face_geometry", &face_geometry,
          "Centroids, areas and unit normals of all faces in one pass.",
          nb::arg("vertices"), nb::arg("faces"), nb::arg("centroids"), nb::arg("areas"),
          nb::arg("normals"));
    m.def("face_terms", &face_terms,
          "The terms of the paper's weights for the face pairs lo:hi, in one pass.",
          nb::arg("vertices"), nb::arg("centroids"), nb::arg("normals"), nb::arg("pairs"),
          nb::arg("edges"), nb::arg("lo"), nb::arg("hi"), nb::arg("geo"), nb::arg("cos"),
          nb::arg("concave"));
    m.def("polygon_geometry", &polygon_geometry,
          "Centroids, areas and unit normals of polygons of any size, in one pass.",
          nb::arg("vertices"), nb::arg("corners"), nb::arg("offsets"), nb::arg("centroids"),
          nb::arg("areas"), nb::arg("normals"));
    m.def("edge_lengths", &edge_lengths,
          "Out[t] = |v[edges[t, 1]] - v[edges[t, 0]]|, as np.linalg.norm(axis=1) computes it.",
          nb::arg("vertices"), nb::arg("edges"), nb::arg("out"));
    m.def("border_shares", &border_shares,
          "Out = 2.0 * np.sqrt(np.pi * area) / np.maximum(np.diff(indptr), 1.0), each operation"
          " rounded as numpy's.",
          nb::arg("indptr"), nb::arg("area"), nb::arg("out"));
    m.def("local_morton_keys", &local_morton_keys,
          "Z-order keys in a local frame.",
          nb::arg("pts"), nb::arg("lo"), nb::arg("scale"), nb::arg("keys"));
    m.def("distinct_in_order", &distinct_in_order,
          "The rows of p taken in order, each run of equal positions once, into out (from 0).",
          nb::arg("p"), nb::arg("order"), nb::arg("out"), nb::arg("inverse"));
    m.def("point_terms", &point_terms,
          "The terms of the paper's weights for pairs lo:hi of elements that are points with "
          "normals (mesh vertices, cloud points), in one pass.",
          nb::arg("positions"), nb::arg("normals"), nb::arg("pairs"), nb::arg("lo"),
          nb::arg("hi"), nb::arg("geo"), nb::arg("cos"), nb::arg("concave"));
    m.def("label_sums", &label_sums,
          "Per label, added to the zeroed area (k,), wpos and wnrm (k, 3).",
          nb::arg("labels"), nb::arg("weights"), nb::arg("positions"), nb::arg("normals"),
          nb::arg("area"), nb::arg("wpos"), nb::arg("wnrm"));
    m.def("label_scatter", &label_scatter,
          "Per label, added to the zeroed scatter (k, 9).",
          nb::arg("labels"), nb::arg("weights"), nb::arg("positions"), nb::arg("centroid"),
          nb::arg("scatter"));
    m.def("key_window", &key_window,
          "Out[r].",
          nb::arg("keys"), nb::arg("start"), nb::arg("out"));
    m.def("sort_keys", &sort_keys,
          "Order.",
          nb::arg("keys"), nb::arg("order"), nb::arg("out"));
    m.def("rows_apart", &rows_apart,
          "The rows i (ascending) where index[i] < 0 or the three words of at[index[i]] differ "
          "from bits[i], written into rows.",
          nb::arg("bits"), nb::arg("at"), nb::arg("index"), nb::arg("rows"));
    m.def("order_ties", &order_ties,
          "Each run of equal keys in ordered (the sorted Z-order windows of the rows order) put"
          " in the order of the rows' whole keys keys[row, 0..2], then their ....",
          nb::arg("order"), nb::arg("ordered"), nb::arg("keys"), nb::arg("p"));
}

}  // namespace sfk
