// Point normals: PCA of each point's neighbours (normals, linearity) and the
// neighbourhoods' moments within some rings.
// Reference, bit for bit: tests/oracle/normals.py.
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

// A set of element rows for one ball: open addressing, cleared by the slots it filled (a
// ball holds a few hundred rows, so a table of the input's size per thread is not needed).
class BallSet {
  public:
    void clear() {
        for (i64 slot : used_) table_[slot] = -1;
        used_.clear();
    }
    bool insert(i64 v) {  // false if already there
        if (2 * (static_cast<i64>(used_.size()) + 1) > static_cast<i64>(table_.size())) grow();
        const i64 mask = static_cast<i64>(table_.size()) - 1;
        const std::uint64_t h = static_cast<std::uint64_t>(v) * 0x9E3779B97F4A7C15ull;
        i64 slot = static_cast<i64>(h >> 20) & mask;
        while (table_[slot] != -1) {
            if (table_[slot] == v) return false;
            slot = (slot + 1) & mask;
        }
        table_[slot] = v;
        used_.push_back(slot);
        return true;
    }

  private:
    void grow() {
        std::vector<i64> old;
        for (i64 slot : used_) old.push_back(table_[slot]);
        table_.assign(table_.empty() ? 1024 : 2 * table_.size(), -1);
        used_.clear();
        for (i64 v : old) insert(v);
    }
    std::vector<i64> table_;
    std::vector<i64> used_;
};

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
            BallSet seen;
            double a[6];
            for (i64 i = lo; i < hi; ++i) {
                const i64 p = pick[i];
                ball.assign(1, p);
                seen.clear();
                seen.insert(p);
                i64 from = 0;  // the last ring's members: only theirs can be new
                for (i64 r = 0; r < rings; ++r) {
                    const i64 end = static_cast<i64>(ball.size());
                    if (from == end) break;  // (the ball stopped growing: done)
                    for (i64 t = from; t < end; ++t)
                        for (i64 e = indptr[ball[t]]; e < indptr[ball[t] + 1]; ++e)
                            if (seen.insert(static_cast<i64>(indices[e])))
                                ball.push_back(indices[e]);
                    from = end;
                }
                std::sort(ball.begin(), ball.end());
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

// The smallest and the largest eigenvalue of the symmetric 3x3 matrix (a00 a01 a02 / a11 a12
// / a22) by cyclic Jacobi rotations: each sweep the pairs (0, 1), (0, 2), (1, 2), at most 64
// sweeps; an off-diagonal entry negligible beside both its diagonal ones (100 times it adds
// nothing to either) is set to 0 without a rotation. Accurate to the matrix's rounding
// (an exact plane's covariance: its smallest within a few machine epsilons of its largest),
// where the trigonometric solution loses half the digits near a repeated eigenvalue.
inline void jacobi_extremes(double a00, double a01, double a02, double a11, double a12,
                            double a22, double& low, double& high) {
    double d[3] = {a00, a11, a22};
    double o[3] = {a01, a02, a12};  // the pairs (0, 1), (0, 2), (1, 2)
    static const int P[3] = {0, 0, 1}, Q[3] = {1, 2, 2};
    static const int RP[3] = {1, 0, 0}, RQ[3] = {2, 2, 1};  // (r, p), (r, q): r the third
    for (int sweep = 0; sweep < 64; ++sweep) {
        if (o[0] == 0.0 && o[1] == 0.0 && o[2] == 0.0) break;
        for (int k = 0; k < 3; ++k) {
            const double apq = o[k];
            if (apq == 0.0) continue;
            const int p = P[k], q = Q[k];
            const double g = 100.0 * std::fabs(apq);
            if (std::fabs(d[p]) + g == std::fabs(d[p]) && std::fabs(d[q]) + g == std::fabs(d[q])) {
                o[k] = 0.0;
                continue;
            }
            const double theta = (d[q] - d[p]) / (2.0 * apq);
            double t;
            if (std::fabs(theta) > 1e150)
                t = 0.5 / theta;
            else
                t = (theta >= 0.0 ? 1.0 : -1.0) /
                    (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
            const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
            d[p] -= t * apq;
            d[q] += t * apq;
            o[k] = 0.0;
            const double arp = o[RP[k]], arq = o[RQ[k]];
            o[RP[k]] = c * arp - s * arq;
            o[RQ[k]] = s * arp + c * arq;
        }
    }
    low = mn(mn(d[0], d[1]), d[2]);
    high = mx(mx(d[0], d[1]), d[2]);
}

// normals.extreme_eigenvalues: the smallest and the largest eigenvalue of each symmetric
// 3x3 matrix cov[i] (its upper triangle read; jacobi_extremes). On threads.
void extreme_eigenvalues(nb::handle cov_, nb::handle low_, nb::handle high_) {
    In<double> cov(cov_, "cov");
    Out<double> low(low_, "low"), high(high_, "high");
    if (size_of(cov_) != 9 * cov.n || low.n != cov.n || high.n != cov.n)
        throw Mismatch("argument cov");
    nb::gil_scoped_release nogil;
    parallel_for(cov.n, [&](i64 lo, i64 hi) {
        for (i64 i = lo; i < hi; ++i) {
            const double* a = cov.p + 9 * i;
            jacobi_extremes(a[0], a[1], a[2], a[4], a[5], a[8], low[i], high[i]);
        }
    });
}

void bind_normals(nb::module_& m) {
    m.def("neighbourhood_moments", &neighbourhood_moments,
          "For each element pick[i], over the elements within rings graph steps of it (itself "
          "included.",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("points"), nb::arg("pick"),
          nb::arg("rings"), nb::arg("cov"), nb::arg("radius"));
    m.def("extreme_eigenvalues", &extreme_eigenvalues,
          "The smallest and the largest eigenvalue of each symmetric 3x3 matrix cov[i].",
          nb::arg("cov"), nb::arg("low"), nb::arg("high"));
    m.def("pca_normals", &pca_normals,
          "Out[i].",
          nb::arg("points"), nb::arg("neighbors"), nb::arg("out"), nb::arg("linearity"));
    m.def("pca_linearity", &pca_linearity,
          "Linearity[i] of the points neighbors[i] alone (pca_normals' second output, for "
          "clouds whose normals are given).",
          nb::arg("points"), nb::arg("neighbors"), nb::arg("linearity"));
}

}  // namespace sfk
