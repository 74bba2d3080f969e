// The point graph's build: distinct positions in Z order, the symmetric kNN layout, PCA
// normals and their turn outwards (their signs: orient.cpp), the per-entry terms
// (superfacets/_kernels/geometry.py, columns.py, adjacency.py, normals.py, orient.py,
// terms.py), the same operations in the same order.
// The loops numba runs with prange run here on threads, each element on its own.
#include "common.hpp"

#include <array>
#include <cstring>

namespace sfk {

namespace {

// A 2-D int32 array of any row and column strides (the kNN lists are a column slice).
struct In2i {
    const char* p;
    i64 n, k, s0, s1;
    In2i(nb::handle h, const char* name) {
        Buffer b;
        if (!Buffer::read<i32>(h, b) || b.ndim != 2)
            throw Mismatch(std::string("argument ") + name);
        p = static_cast<const char*>(b.data);
        n = b.shape[0];
        k = b.shape[1];
        s0 = b.strides[0];
        s1 = b.strides[1];
    }
    i32 operator()(i64 i, i64 j) const {
        return *reinterpret_cast<const i32*>(p + i * s0 + j * s1);
    }
    void check(i64 hi, const char* name) const {  // every entry within [0, hi)
        for (i64 i = 0; i < n; ++i)
            for (i64 j = 0; j < k; ++j)
                if ((*this)(i, j) < 0 || (*this)(i, j) >= hi)
                    throw OutOfRange(std::string("argument ") + name + ": entry " +
                                     std::to_string((*this)(i, j)) + " outside 0.." +
                                     std::to_string(hi - 1));
    }
};

inline std::uint64_t spread21(std::uint64_t x) {
    x &= 0x1FFFFFULL;
    x = (x | (x << 32)) & 0x1F00000000FFFFULL;
    x = (x | (x << 16)) & 0x1F0000FF0000FFULL;
    x = (x | (x << 8)) & 0x100F00F00F00F00FULL;
    x = (x | (x << 4)) & 0x10C30C30C30C30C3ULL;
    x = (x | (x << 2)) & 0x1249249249249249ULL;
    return x;
}

// normals.py's closed-form spectrum of a symmetric 3x3 matrix
struct Spectrum {
    double q, p, phi;
};

inline Spectrum spectrum(double a00, double a01, double a02, double a11, double a12,
                         double a22) {
    double p1 = a01 * a01 + a02 * a02 + a12 * a12;
    double q = (a00 + a11 + a22) / 3.0;
    double p2 = (a00 - q) * (a00 - q) + (a11 - q) * (a11 - q) + (a22 - q) * (a22 - q) + 2.0 * p1;
    if (p2 <= 0.0) return {q, 0.0, 0.0};
    double p = std::sqrt(p2 / 6.0);
    double b00 = (a00 - q) / p, b11 = (a11 - q) / p, b22 = (a22 - q) / p;
    double b01 = a01 / p, b02 = a02 / p, b12 = a12 / p;
    double r = 0.5 * (b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) +
                      b02 * (b01 * b12 - b11 * b02));
    r = mn(1.0, mx(-1.0, r));
    return {q, p, std::acos(r) / 3.0};
}

constexpr double PI = 3.141592653589793;

inline void smallest_eigenvector(double a00, double a01, double a02, double a11, double a12,
                                 double a22, double* out) {
    Spectrum sp = spectrum(a00, a01, a02, a11, a12, a22);
    if (sp.p <= 0.0) {
        out[0] = 0.0;
        out[1] = 0.0;
        out[2] = 1.0;
        return;
    }
    double lam = sp.q + 2.0 * sp.p * std::cos(sp.phi + 2.0 * PI / 3.0);
    double r0x = a00 - lam, r0y = a01, r0z = a02;
    double r1x = a01, r1y = a11 - lam, r1z = a12;
    double r2x = a02, r2y = a12, r2z = a22 - lam;
    double c0x = r0y * r1z - r0z * r1y, c0y = r0z * r1x - r0x * r1z, c0z = r0x * r1y - r0y * r1x;
    double c1x = r0y * r2z - r0z * r2y, c1y = r0z * r2x - r0x * r2z, c1z = r0x * r2y - r0y * r2x;
    double c2x = r1y * r2z - r1z * r2y, c2y = r1z * r2x - r1x * r2z, c2z = r1x * r2y - r1y * r2x;
    double d0 = c0x * c0x + c0y * c0y + c0z * c0z;
    double d1 = c1x * c1x + c1y * c1y + c1z * c1z;
    double d2 = c2x * c2x + c2y * c2y + c2z * c2z;
    double x, y, z, d;
    if (d0 >= d1 && d0 >= d2) {
        x = c0x, y = c0y, z = c0z, d = d0;
    } else if (d1 >= d2) {
        x = c1x, y = c1y, z = c1z, d = d1;
    } else {
        x = c2x, y = c2y, z = c2z, d = d2;
    }
    if (d <= 0.0) {
        out[0] = 0.0;
        out[1] = 0.0;
        out[2] = 1.0;
        return;
    }
    double s = 1.0 / std::sqrt(d);
    out[0] = x * s;
    out[1] = y * s;
    out[2] = z * s;
}

template <class I>
inline void scatter(const double* pts, const I* idx, i64 k, double* a) {
    for (int t = 0; t < 6; ++t) a[t] = 0.0;
    if (k == 0) return;
    double mx_ = 0.0, my = 0.0, mz = 0.0;
    for (i64 t = 0; t < k; ++t) {
        i64 j = idx[t];
        mx_ += pts[3 * j];
        my += pts[3 * j + 1];
        mz += pts[3 * j + 2];
    }
    mx_ /= static_cast<double>(k);
    my /= static_cast<double>(k);
    mz /= static_cast<double>(k);
    for (i64 t = 0; t < k; ++t) {
        i64 j = idx[t];
        double x = pts[3 * j] - mx_, y = pts[3 * j + 1] - my, z = pts[3 * j + 2] - mz;
        a[0] += x * x;
        a[1] += x * y;
        a[2] += x * z;
        a[3] += y * y;
        a[4] += y * z;
        a[5] += z * z;
    }
}

// The scatter of the points idx[0:k], divided by its trace where that is positive;
// returns whether it was.
inline bool unit_scatter(const double* pts, const i32* idx, i64 k, double* a) {
    scatter(pts, idx, k, a);
    double scale = a[0] + a[3] + a[5];
    if (!(scale > 0.0)) return false;
    for (int t = 0; t < 6; ++t) a[t] /= scale;
    return true;
}

inline double linearity(double a00, double a01, double a02, double a11, double a12,
                        double a22) {
    Spectrum sp = spectrum(a00, a01, a02, a11, a12, a22);
    if (sp.p <= 0.0 || sp.q <= 0.0) return 0.0;
    double l1 = sp.q + 2.0 * sp.p * std::cos(sp.phi);
    double l3 = sp.q + 2.0 * sp.p * std::cos(sp.phi + 2.0 * PI / 3.0);
    double l2 = 3.0 * sp.q - l1 - l3;
    return l1 > 0.0 ? (l1 - l2) / l1 : 0.0;
}

// geometry.pair_terms (normals float64, or float32 read as float64)
template <class N>
inline void pair_terms(const double* pos, const N* nor, i64 i, i64 j, double& geo,
                       double& cs, bool& concave) {
    double dx = pos[3 * i] - pos[3 * j], dy = pos[3 * i + 1] - pos[3 * j + 1],
           dz = pos[3 * i + 2] - pos[3 * j + 2];
    const double ix = nor[3 * i], iy = nor[3 * i + 1], iz = nor[3 * i + 2];
    const double jx = nor[3 * j], jy = nor[3 * j + 1], jz = nor[3 * j + 2];
    double c = (ix * jx + iz * jz) + iy * jy;
    double s = ((ix - jx) * dx + (iz - jz) * dz) + (iy - jy) * dy;
    geo = std::sqrt(dx * dx + dy * dy + dz * dz);
    cs = mn(mx(c, -1.0), 1.0);
    concave = s < 0;
}

// The 63 x 3 bits of o[0..2], interleaved x, y, z from the top: 21 of each a word.
inline void interleave(const std::uint64_t* o, std::uint64_t* key) {
    for (int w = 0; w < 3; ++w) {
        std::uint64_t s = static_cast<std::uint64_t>(43 - 21 * w);
        key[w] = (spread21(o[0] >> s) << 2) | (spread21(o[1] >> s) << 1) | spread21(o[2] >> s);
    }
}

}  // namespace

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

void pca_normals(nb::handle points_, nb::handle neighbors_, nb::handle out_,
                 nb::handle linearity_) {
    In<double> points(points_, "points");
    In<i32> nb(neighbors_, "neighbors");
    Out<double> out(out_, "out"), lin(linearity_, "linearity");
    if (points.cols != 3 || out.cols != 3) throw Mismatch("argument points");
    check_range(nb, 0, points.n, "neighbors");
    check_rows(out, nb.n, "out");
    check_rows(lin, nb.n, "linearity");
    nb::gil_scoped_release nogil;
    const i64 k = nb.cols;
    parallel_for(nb.n, [&](i64 lo, i64 hi) {
        double a[6];
        for (i64 i = lo; i < hi; ++i) {
            unit_scatter(points.p, nb.p + i * k, k, a);
            smallest_eigenvector(a[0], a[1], a[2], a[3], a[4], a[5], out.p + 3 * i);
            lin[i] = linearity(a[0], a[1], a[2], a[3], a[4], a[5]);
        }
    });
}

void pca_linearity(nb::handle points_, nb::handle neighbors_, nb::handle linearity_) {
    In<double> points(points_, "points");
    In<i32> nb(neighbors_, "neighbors");
    Out<double> lin(linearity_, "linearity");
    if (points.cols != 3) throw Mismatch("argument points");
    check_range(nb, 0, points.n, "neighbors");
    check_rows(lin, nb.n, "linearity");
    nb::gil_scoped_release nogil;
    const i64 k = nb.cols;
    parallel_for(nb.n, [&](i64 lo, i64 hi) {
        double a[6];
        for (i64 i = lo; i < hi; ++i) {
            lin[i] = unit_scatter(points.p, nb.p + i * k, k, a)
                         ? linearity(a[0], a[1], a[2], a[3], a[4], a[5])
                         : 0.0;
        }
    });
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

void turn_outwards(nb::handle points_, nb::handle normals_, nb::handle sign_,
                   nb::handle component_, i64 n_comp, nb::handle out_) {
    In<double> pts(points_, "points"), nor(normals_, "normals");
    In<std::int8_t> sign(sign_, "sign");
    In<i64> component(component_, "component");
    Out<double> out(out_, "out");
    if (pts.cols != 3 || nor.cols != 3 || out.cols != 3) throw Mismatch("argument points");
    for (i64 m : {nor.n, sign.n, component.n, out.n})
        if (m != pts.n) throw Mismatch("argument normals");
    check_range(component, 0, n_comp, "component");
    nb::gil_scoped_release nogil;
    const i64 n = pts.n;
    std::vector<double> count(n_comp, 0.0), mean(3 * n_comp, 0.0), total(n_comp, 0.0);
    for (i64 i = 0; i < n; ++i) {
        i64 c = component[i];
        count[c] += 1.0;
        for (int a = 0; a < 3; ++a) mean[3 * c + a] += pts(i, a);
    }
    for (i64 c = 0; c < n_comp; ++c)
        for (int a = 0; a < 3; ++a) mean[3 * c + a] /= count[c];
    for (i64 i = 0; i < n; ++i) {
        i64 c = component[i];
        double s = static_cast<double>(sign[i]);
        total[c] += (nor(i, 0) * s * (pts(i, 0) - mean[3 * c]) +
                     nor(i, 1) * s * (pts(i, 1) - mean[3 * c + 1])) +
                    nor(i, 2) * s * (pts(i, 2) - mean[3 * c + 2]);
    }
    for (i64 i = 0; i < n; ++i) {
        double s = static_cast<double>(sign[i]);
        if (total[component[i]] < 0) s = -s;
        for (int a = 0; a < 3; ++a) out(i, a) = nor(i, a) * s;
    }
}

void point_terms_csr(nb::handle positions_, nb::handle normals_, nb::handle indptr_,
                     nb::handle indices_, i64 r0, i64 r1, nb::handle geo_, nb::handle cos_,
                     nb::handle concave_) {
    In<double> pos(positions_, "positions");
    In<i64> indptr(indptr_, "indptr");
    In<i32> indices(indices_, "indices");
    Out<double> geo(geo_, "geo"), cs(cos_, "cos");
    Out<bool> concave(concave_, "concave");
    with_real(normals_, "normals", [&](const auto& nor) {
        if (pos.cols != 3 || nor.cols != 3) throw Mismatch("argument positions");
        check_span(r0, r1, indptr.n - 1, indptr.n - 1);
        check_csr(In<i64>(indptr.p + r0, r1 - r0 + 1), indices, r1 - r0, mn(pos.n, nor.n));
        if (r1 > pos.n || r1 > nor.n) throw OutOfRange("arguments r0, r1: rows past positions");
        const i64 m = indptr[r1] - indptr[r0];
        check_rows(geo, m, "geo");
        check_rows(cs, m, "cos");
        check_rows(concave, m, "concave");
        nb::gil_scoped_release nogil;
        i64 u = 0;
        for (i64 i = r0; i < r1; ++i)
            for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) {
                i64 j = indices[x];
                pair_terms(pos.p, nor.p, mn(i, j), mx(i, j), geo[u], cs[u], concave[u]);
                ++u;
            }
        return 0;
    });
}

// terms.combine_weights: out = (geo + alpha * ang) / diagonal, ang = eta * geo * theta / pi
// (eta 1 where concave, else eta_convex), the float64 value rounded to out's dtype.
template <class T>
void combine_into(const In<double>& geo, const In<double>& theta, const In<bool>& concave,
                  double eta_convex, double alpha, double diagonal, T* out) {
    constexpr double PI = 3.141592653589793;
    for (i64 u = 0; u < geo.n; ++u) {
        const double eta = concave[u] ? 1.0 : eta_convex;
        const double ang = eta * geo[u] * theta[u] / PI;
        out[u] = static_cast<T>((geo[u] + alpha * ang) / diagonal);
    }
}

void combine_weights(nb::handle geo_, nb::handle theta_, nb::handle concave_, double eta_convex,
                     double alpha, double diagonal, nb::handle out_) {
    In<double> geo(geo_, "geo"), theta(theta_, "theta");
    In<bool> concave(concave_, "concave");
    if (theta.n != geo.n || concave.n != geo.n) throw Mismatch("argument theta");
    if (matches<float>(out_)) {
        Out<float> out(out_, "out");
        if (out.n != geo.n) throw Mismatch("argument out");
        nb::gil_scoped_release nogil;
        combine_into(geo, theta, concave, eta_convex, alpha, diagonal, out.p);
    } else {
        Out<double> out(out_, "out");
        if (out.n != geo.n) throw Mismatch("argument out");
        nb::gil_scoped_release nogil;
        combine_into(geo, theta, concave, eta_convex, alpha, diagonal, out.p);
    }
}

// terms.feature_weights_csr: the weights of the CSR entries of rows r0:r1 with the
// feature term, as csr_point_weights' numpy expression gives them, bit for bit:
// out = ((geo + alpha * ang) + (beta * geo) * jump) / diagonal, ang as combine_weights,
// jump = ||f_i - f_j|| (its squares added in column order, as numpy's norm adds up to 5
// columns) less floor, at least 0, where floor > 0.
template <class T>
void feature_weights_into(const In<double>& geo, const In<double>& theta,
                          const In<bool>& concave, const In<double>& f, const In<i64>& indptr,
                          const In<i32>& indices, i64 r0, i64 r1, double eta_convex,
                          double alpha, double beta, double floor, double diagonal, T* out) {
    constexpr double PI = 3.141592653589793;
    const i64 d = f.cols;
    i64 u = 0;
    for (i64 i = r0; i < r1; ++i)
        for (i64 x = indptr[i]; x < indptr[i + 1]; ++x, ++u) {
            const i64 j = indices[x];
            double s = 0.0;
            for (i64 c = 0; c < d; ++c) {
                const double t = f(i, c) - f(j, c);
                s += t * t;
            }
            double jump = std::sqrt(s);
            if (floor > 0) {
                const double over = jump - floor;
                jump = over >= 0.0 ? over : 0.0;
            }
            const double eta = concave[u] ? 1.0 : eta_convex;
            const double ang = eta * geo[u] * theta[u] / PI;
            out[u] = static_cast<T>((geo[u] + alpha * ang + beta * geo[u] * jump) / diagonal);
        }
}

void feature_weights_csr(nb::handle geo_, nb::handle theta_, nb::handle concave_,
                         nb::handle features_, nb::handle indptr_, nb::handle indices_, i64 r0,
                         i64 r1, double eta_convex, double alpha, double beta, double floor,
                         double diagonal, nb::handle out_) {
    In<double> geo(geo_, "geo"), theta(theta_, "theta"), f(features_, "features");
    In<bool> concave(concave_, "concave");
    In<i64> indptr(indptr_, "indptr");
    In<i32> indices(indices_, "indices");
    if (f.cols < 1 || f.cols > 5) throw Mismatch("argument features: 1 to 5 columns");
    check_span(r0, r1, indptr.n - 1, indptr.n - 1);
    check_csr(In<i64>(indptr.p + r0, r1 - r0 + 1), indices, r1 - r0, f.n);
    if (r1 > f.n) throw OutOfRange("arguments r0, r1: rows past features");
    const i64 m = indptr[r1] - indptr[r0];
    if (geo.n != m || theta.n != m || concave.n != m) throw Mismatch("argument geo");
    auto run = [&](auto* tag) {
        using T = std::remove_pointer_t<decltype(tag)>;
        Out<T> out(out_, "out");
        if (out.n != m) throw Mismatch("argument out");
        nb::gil_scoped_release nogil;
        feature_weights_into(geo, theta, concave, f, indptr, indices, r0, r1, eta_convex, alpha,
                             beta, floor, diagonal, out.p);
    };
    if (matches<float>(out_))
        run(static_cast<float*>(nullptr));
    else
        run(static_cast<double*>(nullptr));
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

template <class X>
void neighbour_mean_t(const In<i64>& indptr, const In<i32>& indices, const X* x, double* out) {
    for (i64 i = 0; i < indptr.n - 1; ++i) {
        double above = 0.0, below = 0.0;
        for (i64 e = indptr[i]; e < indptr[i + 1]; ++e) {
            i64 j = indices[e];
            if (j > i) above += x[j];
            else below += x[j];
        }
        out[i] = (x[i] + above + below) / (1.0 + static_cast<double>(indptr[i + 1] - indptr[i]));
    }
}

void neighbour_mean(nb::handle indptr_, nb::handle indices_, nb::handle x_, nb::handle out_) {
    In<i64> indptr(indptr_, "indptr");
    In<i32> indices(indices_, "indices");
    Out<double> out(out_, "out");
    In<double> x(x_, "x");
    const i64 n = check_csr(indptr, indices, -1, x.n);
    check_rows(x, n, "x");
    check_rows(out, n, "out");
    nb::gil_scoped_release nogil;
    neighbour_mean_t(indptr, indices, x.p, out.p);
}

nb::object crossing_pairs(nb::handle indptr_, nb::handle indices_, nb::handle labels_) {
    In<i64> indptr(indptr_, "indptr"), labels(labels_, "labels");
    In<i32> indices(indices_, "indices");
    const i64 n = check_csr(indptr, indices, -1, labels.n);
    check_rows(labels, n, "labels");
    // rows in blocks on threads: each block counts its pairs, then writes them from its
    // place (a prefix sum of the counts), so the pairs are in row order as in one pass
    const i64 n_blocks = std::max<i64>(1, std::min<i64>(64, n / 4096));
    std::vector<i64> at(n_blocks + 1, 0);
    auto rows = [&](i64 b) { return std::make_pair(n * b / n_blocks, n * (b + 1) / n_blocks); };
    auto each_block = [&](auto f) {  // f(b) for every block, the blocks split among threads
        parallel_for(n_blocks * 4096, [&](i64 lo, i64 hi) {
            for (i64 b = (lo + 4095) / 4096; b * 4096 < hi; ++b) f(b);
        });
    };
    {
        nb::gil_scoped_release nogil;
        each_block([&](i64 b) {
            auto [r0, r1] = rows(b);
            i64 m = 0;
            for (i64 i = r0; i < r1; ++i)
                for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) {
                    i64 j = indices[x];
                    if (j > i && labels[j] != labels[i]) ++m;
                }
            at[b + 1] = m;
        });
        for (i64 b = 0; b < n_blocks; ++b) at[b + 1] += at[b];
    }
    Out<i64> out;
    auto out_a = fresh(at[n_blocks], out, 2);
    {
        nb::gil_scoped_release nogil;
        each_block([&](i64 b) {
            auto [r0, r1] = rows(b);
            i64 u = at[b];
            for (i64 i = r0; i < r1; ++i)
                for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) {
                    i64 j = indices[x];
                    if (j > i && labels[j] != labels[i]) {
                        out(u, 0) = i;
                        out(u, 1) = j;
                        ++u;
                    }
                }
        });
    }
    return out_a;
}

// adjacency.label_pair_sums: the adjacencies of a symmetric CSR point graph whose two
// points have different labels (of k), summed per pair of labels without listing them
// (crossing_pairs, point_terms and a np.bincount per sum would hold every one): the keys
// lo * k + hi, ascending, and per key (border, border * angle, border * concave,
// crossings, angle, concave) summed over its adjacencies in pair order (rows ascending,
// then j: np.bincount's order over crossing_pairs' rows), an adjacency's border the
// mean of its points' border shares and its angle acos of its normals' cosine.
nb::object label_pair_sums(nb::handle indptr_, nb::handle indices_, nb::handle labels_, i64 k,
                           nb::handle positions_, nb::handle normals_, nb::handle shares_) {
    In<i64> indptr(indptr_, "indptr"), labels(labels_, "labels");
    In<i32> indices(indices_, "indices");
    In<double> pos(positions_, "positions"), shares(shares_, "shares");
    const i64 n = check_csr(indptr, indices, -1, labels.n);
    check_rows(labels, n, "labels");
    check_rows(shares, n, "shares");
    check_range(labels, 0, k, "labels");
    if (pos.cols != 3 || pos.n < n) throw Mismatch("argument positions");
    std::vector<std::vector<std::pair<i64, i64>>> seen(static_cast<size_t>(k));  // (hi, row)
    std::vector<std::array<double, 6>> acc;
    with_real(normals_, "normals", [&](const auto& nor) {
        if (nor.cols != 3 || nor.n < n) throw Mismatch("argument normals");
        nb::gil_scoped_release nogil;
        for (i64 i = 0; i < n; ++i)
            for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) {
                const i64 j = indices[x];
                if (j <= i || labels[j] == labels[i]) continue;
                const i64 lo = mn(labels[i], labels[j]), hi = mx(labels[i], labels[j]);
                auto& near = seen[static_cast<size_t>(lo)];
                i64 at = -1;
                for (const auto& [h, r] : near)
                    if (h == hi) { at = r; break; }
                if (at < 0) {
                    at = static_cast<i64>(acc.size());
                    near.emplace_back(hi, at);
                    acc.push_back({0.0, 0.0, 0.0, 0.0, 0.0, 0.0});
                }
                double geo, cs;
                bool concave;
                pair_terms(pos.p, nor.p, i, j, geo, cs, concave);
                const double len = 0.5 * (shares[i] + shares[j]), ang = std::acos(cs);
                const double cc = concave ? 1.0 : 0.0;
                auto& a = acc[static_cast<size_t>(at)];
                a[0] += len;
                a[1] += len * ang;
                a[2] += len * cc;
                a[3] += 1.0;
                a[4] += ang;
                a[5] += cc;
            }
        return 0;
    });
    Out<i64> keys;
    Out<double> sums;
    auto keys_a = fresh(static_cast<i64>(acc.size()), keys);
    auto sums_a = fresh(static_cast<i64>(acc.size()), sums, 6);
    i64 u = 0;
    for (i64 lo = 0; lo < k; ++lo) {
        auto& near = seen[static_cast<size_t>(lo)];
        std::sort(near.begin(), near.end());
        for (const auto& [h, r] : near) {
            keys[u] = lo * k + h;
            for (int c = 0; c < 6; ++c) sums(u, c) = acc[static_cast<size_t>(r)][c];
            ++u;
        }
    }
    return nb::make_tuple(keys_a, sums_a);
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

// columns.column_bounds: each column's least and greatest value (NaN where the column
// has one; of equal values, the first row's), by row ranges on threads combined in order
void column_bounds(nb::handle a_, nb::handle lo_, nb::handle hi_) {
    In<double> a(a_, "a");
    Out<double> lo(lo_, "lo"), hi(hi_, "hi");
    const i64 n = a.n, d = a.cols;
    if (lo.n != d || hi.n != d || n < 1 || d > 16) throw Mismatch("argument lo");
    nb::gil_scoped_release nogil;
    const i64 T = std::max<i64>(1, std::min<i64>(threads(), n / 65536));
    std::vector<double> plo(T * d), phi(T * d);
    auto keep = [](double& l, double& h, double x) {
        if (x < l || x != x) l = x;
        if (x > h || x != x) h = x;
    };
    on_threads(T, [&](i64 t) {
        const i64 r0 = n * t / T, r1 = n * (t + 1) / T;
        double l[16], h[16];
        for (i64 c = 0; c < d; ++c) l[c] = h[c] = a(r0, c);
        for (i64 r = r0 + 1; r < r1; ++r)
            for (i64 c = 0; c < d; ++c) keep(l[c], h[c], a(r, c));
        for (i64 c = 0; c < d; ++c) {
            plo[t * d + c] = l[c];
            phi[t * d + c] = h[c];
        }
    });
    for (i64 c = 0; c < d; ++c) {
        double l = plo[c], h = phi[c];
        for (i64 t = 1; t < T; ++t) {
            const double pl = plo[t * d + c], ph = phi[t * d + c];
            if (pl < l || pl != pl) l = pl;
            if (ph > h || ph != ph) h = ph;
        }
        lo[c] = l;
        hi[c] = h;
    }
}

// columns.column_means: each column's mean as numpy's a.mean(axis=0) makes it, the rows
// added in order (numpy's reduction over the outer axis: no pairwise sum), then divided
// (one thread: the order of the additions is the value)
void column_means(nb::handle a_, nb::handle out_) {
    In<double> a(a_, "a");
    Out<double> out(out_, "out");
    const i64 n = a.n, d = a.cols;
    if (out.n != d || n < 1 || d > 16) throw Mismatch("argument out");
    nb::gil_scoped_release nogil;
    double s[16] = {0.0};
    for (i64 r = 0; r < n; ++r)
        for (i64 c = 0; c < d; ++c) s[c] += a(r, c);
    for (i64 c = 0; c < d; ++c) out[c] = s[c] / static_cast<double>(n);
}

// columns.finite_rows: out[r] whether every value of row r is finite
void finite_rows(nb::handle a_, nb::handle out_) {
    In<double> a(a_, "a");
    Out<bool> out(out_, "out");
    if (out.n != a.n) throw Mismatch("argument out");
    nb::gil_scoped_release nogil;
    const i64 d = a.cols;
    parallel_for(a.n, [&](i64 r0, i64 r1) {
        for (i64 r = r0; r < r1; ++r) {
            bool ok = true;
            for (i64 c = 0; c < d; ++c) ok = ok && std::isfinite(a(r, c));
            out[r] = ok;
        }
    });
}

// columns.gather: out[i] = values[index[i]] for each index in range (others leave out[i]
// as it was), on threads; returns how many were out of range
i64 gather(nb::handle values_, nb::handle index_, nb::handle out_) {
    auto run = [&](auto tag) -> i64 {
        using V = decltype(tag);
        In<V> values(values_, "values");
        Out<V> out(out_, "out");
        return with_index(index_, "index", [&](const auto& index) -> i64 {
            if (out.n != index.n) throw Mismatch("argument out");
            nb::gil_scoped_release nogil;
            const i64 n = values.n;
            std::atomic<i64> bad{0};
            parallel_for(index.n, [&](i64 i0, i64 i1) {
                i64 b = 0;
                for (i64 i = i0; i < i1; ++i) {
                    const i64 j = index[i];
                    if (j < 0 || j >= n) {
                        ++b;
                        continue;
                    }
                    out[i] = values[j];
                }
                bad += b;
            });
            return bad;
        });
    };
    if (matches<i32>(values_)) return run(i32{});
    return run(i64{});
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

// normals.neighbourhood_moments: over the elements within `rings` graph steps of each
// pick[i] (itself included, ascending: each sum in that order, from 0), their covariance
// (the scatter divided by their number) and their mean distance to it (the sum divided by
// their number less one, at least 1). On threads, a ball per element picked.
void neighbourhood_moments(nb::handle indptr_, nb::handle indices_, nb::handle points_,
                           nb::handle pick_, i64 rings, nb::handle cov_, nb::handle radius_) {
    In<i64> indptr(indptr_, "indptr"), pick(pick_, "pick");
    In<double> points(points_, "points");
    Out<double> cov(cov_, "cov"), radius(radius_, "radius");
    if (points.cols != 3 || cov.n != pick.n || radius.n != pick.n ||
        size_of(cov_) != 9 * pick.n)
        throw Mismatch("argument cov");
    if (rings < 0 || rings > 64)  // (a neighbourhood of a few graph steps)
        throw OutOfRange("argument rings: " + std::to_string(rings) + ", outside 0..64");
    with_index(indices_, "indices", [&](const auto& indices) {
        check_csr(indptr, indices, points.n, points.n);
        check_range(pick, 0, points.n, "pick");
        nb::gil_scoped_release nogil;
        parallel_for(pick.n, [&](i64 lo, i64 hi) {
            std::vector<i64> ball;
            double a[6];
            for (i64 i = lo; i < hi; ++i) {
                const i64 p = pick[i];
                i64 grown = 0;
                ball.assign(1, p);
                for (i64 r = 0; r < rings; ++r) {  // every member's neighbours added
                    const i64 end = static_cast<i64>(ball.size());
                    if (r > 0 && end == grown) break;  // (the ball stopped growing: done)
                    grown = end;
                    for (i64 t = 0; t < end; ++t)
                        for (i64 e = indptr[ball[t]]; e < indptr[ball[t] + 1]; ++e)
                            ball.push_back(indices[e]);
                    std::sort(ball.begin(), ball.end());
                    ball.erase(std::unique(ball.begin(), ball.end()), ball.end());
                }
                const i64 k = static_cast<i64>(ball.size());
                const double size = static_cast<double>(k);
                scatter(points.p, ball.data(), k, a);
                double* c = cov.p + 9 * i;
                c[0] = a[0] / size;
                c[1] = c[3] = a[1] / size;
                c[2] = c[6] = a[2] / size;
                c[4] = a[3] / size;
                c[5] = c[7] = a[4] / size;
                c[8] = a[5] / size;
                double s = 0.0;
                const double px = points(p, 0), py_ = points(p, 1), pz = points(p, 2);
                for (i64 t = 0; t < k; ++t) {
                    const i64 j = ball[t];
                    double dx = points(j, 0) - px, dy = points(j, 1) - py_,
                           dz = points(j, 2) - pz;
                    s += std::sqrt(dx * dx + dy * dy + dz * dz);
                }
                radius[i] = s / mx(size - 1.0, 1.0);
            }
        });
        return 0;
    });
}

// columns.nearest_row: the first row of least (dx dx + dy dy) + dz dz to `point` (numpy's
// argmin of the squared distances), each range of rows on a thread, the ranges' bests
// taken in order (a later one only if strictly nearer); -1 where a distance is NaN
i64 nearest_row(nb::handle a_, nb::handle point_) {
    In<double> a(a_, "a"), point(point_, "point");
    if (a.cols != 3 || point.n != 3 || a.n < 1) throw Mismatch("argument a");
    nb::gil_scoped_release nogil;
    const double px = point[0], py_ = point[1], pz = point[2];
    const i64 n = a.n, T = std::max<i64>(1, std::min<i64>(threads(), n / 65536));
    std::vector<double> best(T, INF);
    std::vector<i64> at(T, -1);
    std::vector<char> nan(T, 0);
    on_threads(T, [&](i64 t) {
        double b = INF;
        i64 w = -1;
        for (i64 r = n * t / T; r < n * (t + 1) / T; ++r) {
            const double dx = a(r, 0) - px, dy = a(r, 1) - py_, dz = a(r, 2) - pz;
            const double d = dx * dx + dy * dy + dz * dz;
            if (d != d) {
                nan[t] = 1;
                return;
            }
            if (d < b || w < 0) {
                b = d;
                w = r;
            }
        }
        best[t] = b;
        at[t] = w;
    });
    i64 w = -1;
    double b = INF;
    for (i64 t = 0; t < T; ++t) {
        if (nan[t]) return -1;
        if (at[t] >= 0 && (w < 0 || best[t] < b)) {
            b = best[t];
            w = at[t];
        }
    }
    return w;
}

void bind_points(nb::module_& m) {
    m.def("gather", &gather);
    m.def("nearest_row", &nearest_row);
    m.def("neighbourhood_moments", &neighbourhood_moments);
    m.def("border_shares", &border_shares);
    m.def("local_morton_keys", &local_morton_keys);
    m.def("distinct_in_order", &distinct_in_order);
    m.def("pca_normals", &pca_normals);
    m.def("pca_linearity", &pca_linearity);
    m.def("knn_csr", &knn_csr);
    m.def("turn_outwards", &turn_outwards);
    m.def("point_terms_csr", &point_terms_csr);
    m.def("combine_weights", &combine_weights);
    m.def("feature_weights_csr", &feature_weights_csr);
    m.def("point_terms", &point_terms);
    m.def("neighbour_mean", &neighbour_mean);
    m.def("crossing_pairs", &crossing_pairs);
    m.def("label_pair_sums", &label_pair_sums);
    m.def("label_sums", &label_sums);
    m.def("label_scatter", &label_scatter);
    m.def("column_bounds", &column_bounds);
    m.def("finite_rows", &finite_rows);
    m.def("column_means", &column_means);
}

}  // namespace sfk
