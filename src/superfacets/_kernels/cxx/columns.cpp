// Column statistics and gathers of large arrays: bounds, means, finite
// rows, gathers by index, the nearest row to a point.
// Reference, bit for bit: tests/oracle/columns.py.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <type_traits>
#include <vector>

#include "common.hpp"

namespace sfk {

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

void bind_columns(nb::module_& m) {
    m.def("gather", &gather,
          "Out[i] = values[index[i]] for each index in range (0 <= index[i] < len(values).",
          nb::arg("values"), nb::arg("index"), nb::arg("out"));
    m.def("nearest_row", &nearest_row,
          "The first row r of the (n, 3) a of least (dx dx + dy dy) + dz dz to point "
          "(np.argmin(((a - point) ** 2).sum(axis=1))).",
          nb::arg("a"), nb::arg("point"));
    m.def("column_bounds", &column_bounds,
          "Lo[c], hi[c].",
          nb::arg("a"), nb::arg("lo"), nb::arg("hi"));
    m.def("finite_rows", &finite_rows,
          "Out[r].",
          nb::arg("a"), nb::arg("out"));
    m.def("column_means", &column_means,
          "Out[c].",
          nb::arg("a"), nb::arg("out"));
}

}  // namespace sfk
