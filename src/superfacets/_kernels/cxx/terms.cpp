// The per-entry weights of the CSR layouts: the crease factor's terms, the colour
// term, the convex scaling, the cut costs, and the neighbours' means.
// Reference, bit for bit: tests/oracle/terms.py.
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

// The arguments of a kernel over the CSR rows r0:r1 of a graph of points with normals.
template <class N>
void check_point_rows(const In<double>& pos, const N& nor, const In<i64>& indptr,
                      const In<i32>& indices, i64 r0, i64 r1) {
    if (pos.cols != 3 || nor.cols != 3) throw Mismatch("argument positions");
    check_span(r0, r1, indptr.n - 1, indptr.n - 1);
    check_csr(In<i64>(indptr.p + r0, r1 - r0 + 1), indices, r1 - r0, mn(pos.n, nor.n));
    if (r1 > pos.n || r1 > nor.n) throw OutOfRange("arguments r0, r1: rows past positions");
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
        check_point_rows(pos, nor, indptr, indices, r0, r1);
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

// terms.step_terms_csr: geo of the CSR entries of rows r0:r1 (written from index 0) with
// the part of each offset d = p_j - p_i along the two normals weighed `step` times:
// geo = sqrt(geo^2 + (step^2 - 1) off^2), off = (|n_i . d| + |n_j . d|) / 2.
void step_terms_csr(nb::handle positions_, nb::handle normals_, nb::handle indptr_,
                    nb::handle indices_, i64 r0, i64 r1, double step, nb::handle geo_) {
    In<double> pos(positions_, "positions");
    In<i64> indptr(indptr_, "indptr");
    In<i32> indices(indices_, "indices");
    Out<double> geo(geo_, "geo");
    with_real(normals_, "normals", [&](const auto& nor) {
        check_point_rows(pos, nor, indptr, indices, r0, r1);
        check_rows(geo, indptr[r1] - indptr[r0], "geo");
        const double grow = step * step - 1.0;
        nb::gil_scoped_release nogil;
        i64 u = 0;
        for (i64 i = r0; i < r1; ++i)
            for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) {
                const i64 j = indices[x];
                const double dx = pos[3 * j] - pos[3 * i], dy = pos[3 * j + 1] - pos[3 * i + 1],
                             dz = pos[3 * j + 2] - pos[3 * i + 2];
                const double a = std::abs((dx * nor[3 * i] + dy * nor[3 * i + 1]) +
                                          dz * nor[3 * i + 2]);
                const double b = std::abs((dx * nor[3 * j] + dy * nor[3 * j + 1]) +
                                          dz * nor[3 * j + 2]);
                const double off = 0.5 * (a + b);
                geo[u] = std::sqrt(geo[u] * geo[u] + grow * off * off);
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

void bind_terms(nb::module_& m) {
    m.def("convex_scaled_csr", &convex_scaled_csr,
          "Weights[e] - coef * span * arccos(cos) (at least 0) on the entries of convex "
          "adjacencies, weights[e] on concave ones (adjacency dual_edge[e]).",
          nb::arg("weights"), nb::arg("dual_edge"), nb::arg("concave"), nb::arg("cos"),
          nb::arg("span"), nb::arg("coef"));
    m.def("cut_costs_csr", &cut_costs_csr,
          "Scale * lengths / (1 + factor * eta * arccos(cos)) per CSR entry, eta 1 on concave "
          "adjacencies and eta_convex on convex ones.",
          nb::arg("dual_edge"), nb::arg("concave"), nb::arg("cos"), nb::arg("lengths"),
          nb::arg("factor"), nb::arg("eta_convex"), nb::arg("scale"));
    m.def("per_entry", &per_entry,
          "Out[e] = values[dual_edge[e]].",
          nb::arg("values"), nb::arg("dual_edge"), nb::arg("out"));
    m.def("point_terms_csr", &point_terms_csr,
          "Superfacets._kernels.geometry.point_terms per CSR entry of the rows r0:r1 (written "
          "from index 0).",
          nb::arg("positions"), nb::arg("normals"), nb::arg("indptr"), nb::arg("indices"),
          nb::arg("r0"), nb::arg("r1"), nb::arg("geo"), nb::arg("cos"), nb::arg("concave"));
    m.def("step_terms_csr", &step_terms_csr,
          "Geo of the CSR entries of rows r0:r1 with the offset along the normals weighed "
          "step times: sqrt(geo^2 + (step^2 - 1) off^2).",
          nb::arg("positions"), nb::arg("normals"), nb::arg("indptr"), nb::arg("indices"),
          nb::arg("r0"), nb::arg("r1"), nb::arg("step"), nb::arg("geo"));
    m.def("combine_weights", &combine_weights,
          "Out = (geo + alpha * ang) / diagonal with ang = eta * geo * theta / pi (eta 1 where "
          "concave, else eta_convex), as numpy evaluates the same expression ....",
          nb::arg("geo"), nb::arg("theta"), nb::arg("concave"), nb::arg("eta_convex"),
          nb::arg("alpha"), nb::arg("diagonal"), nb::arg("out"));
    m.def("feature_weights_csr", &feature_weights_csr,
          "The weights of the CSR entries of rows r0:r1 with the feature term.",
          nb::arg("geo"), nb::arg("theta"), nb::arg("concave"), nb::arg("features"),
          nb::arg("indptr"), nb::arg("indices"), nb::arg("r0"), nb::arg("r1"),
          nb::arg("eta_convex"), nb::arg("alpha"), nb::arg("beta"), nb::arg("floor"),
          nb::arg("diagonal"), nb::arg("out"));
    m.def("neighbour_mean", &neighbour_mean,
          "Out[i] = ((x_i + above) + below) / (1 + degree).",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("x"), nb::arg("out"));
}

}  // namespace sfk
