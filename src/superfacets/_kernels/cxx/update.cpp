// The centers' update after a pass (paper, section 3.1): each center moved to its
// superfacet's element nearest the superfacet's area-weighted centroid.
// Reference, bit for bit: tests/oracle/update.py.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <type_traits>
#include <vector>

#include "common.hpp"

namespace sfk {

// update.update_centers: per superfacet, the area-weighted mean of its elements' centroids,
// then its element nearest that mean (the old center stays on ties; paper, section 3.1).
void update_centers(nb::handle label_, i64 k, nb::handle areas_, nb::handle centroids_,
                    nb::handle old_centers_, nb::handle new_centers_) {
    In<i32> label(label_, "label");
    In<double> areas(areas_, "areas"), c(centroids_, "centroids");
    In<i64> old_centers(old_centers_, "old_centers");
    Out<i64> new_centers(new_centers_, "new_centers");
    if (c.cols != 3) throw Mismatch("argument centroids");
    check_rows(areas, label.n, "areas");
    check_rows(c, label.n, "centroids");
    check_range(label, 0, k, "label");
    check_rows(old_centers, k, "old_centers");
    check_range(old_centers, -1, label.n, "old_centers", k);
    check_rows(new_centers, k, "new_centers");
    nb::gil_scoped_release nogil;
    const i64 m = label.n;
    // (one thread for superfacets of 16 elements or fewer: the ranges' sums would cost
    // more than they save)
    const i64 nt = 16 * k > m ? 1 : std::max<i64>(1, std::min<i64>(threads(), m / (1 << 16)));
    // The sums over each superfacet's elements in index order, as one pass over all of
    // them adds them: thread w adds those of the range m w / nt .. m (w + 1) / nt from 0,
    // each superfacet apart (8 values per superfacet per range). A superfacet whose
    // elements all lie in one range has its sums then; the others go on from their first
    // range's sums over their elements in the later ranges, in order (one more pass over
    // those ranges' labels: few superfacets span two ranges).
    // Every step on threads but the sums of the superfacets that span ranges, over their
    // few elements past their first range: the accumulators, the ranges' merge and the
    // choices' merge were serial passes over nt * k entries (16 threads and 100,000
    // superpoints: more time than the threads saved).
    std::vector<i64> bound(nt + 1);
    for (i64 w = 0; w <= nt; ++w) bound[w] = m * w / nt;
    std::vector<std::vector<double>> acc(nt);
    auto add_to = [&](double* a, i64 f) {  // per superfacet: sums (3), plain (3), wsum, count
        const double ar = areas[f];
        for (int t = 0; t < 3; ++t) {
            a[t] += ar * c(f, t);
            a[3 + t] += c(f, t);
        }
        a[6] += ar;
        a[7] += 1.0;
    };
    on_threads(nt, [&](i64 w) {
        acc[w].assign(8 * k, 0.0);
        double* A = acc[w].data();
        for (i64 f = bound[w]; f < bound[w + 1]; ++f) add_to(A + 8 * label[f], f);
    });
    std::vector<double>& sum = acc[0];
    std::vector<i64> first(k, -1);  // each superfacet's first range with elements
    std::vector<char> span(k, 0);
    parallel_for(nt > 1 ? k : 0, [&](i64 s0, i64 s1) {
        for (i64 s = s0; s < s1; ++s)
            for (i64 w = 0; w < nt; ++w) {
                const double* A = acc[w].data();
                if (A[8 * s + 7] == 0.0) continue;
                if (first[s] < 0) {
                    first[s] = w;
                    if (w > 0) std::copy(A + 8 * s, A + 8 * s + 8, sum.data() + 8 * s);
                } else {
                    span[s] = 1;
                }
            }
    });
    // those spanning ranges: their elements past their first range, listed by range on
    // threads, then added range by range (each superfacet's in index order)
    std::vector<std::vector<i64>> later(nt);
    on_threads(nt, [&](i64 w) {
        if (w == 0) return;
        for (i64 f = bound[w]; f < bound[w + 1]; ++f) {
            const i64 s = label[f];
            if (span[s] && first[s] < w) later[w].push_back(f);
        }
    });
    for (i64 w = 1; w < nt; ++w)
        for (i64 f : later[w]) add_to(sum.data() + 8 * label[f], f);
    std::vector<double> sums(3 * k, 0.0);  // each superfacet's mean
    for (i64 s = 0; s < k; ++s) {
        const double* a = sum.data() + 8 * s;
        if (a[6] > 0.0) {
            for (int t = 0; t < 3; ++t) sums[3 * s + t] = a[t] / a[6];
        } else if (a[7] > 0.0) {  // (the count, exact in a double)
            for (int t = 0; t < 3; ++t) sums[3 * s + t] = a[3 + t] / a[7];
        }
    }
    std::vector<double> best(k, INF);
    for (i64 s = 0; s < k; ++s) {
        new_centers[s] = -1;
        i64 cc = old_centers[s];
        if (cc >= 0 && label[cc] == s) {
            double d = 0.0;
            for (int t = 0; t < 3; ++t) {
                double x = c(cc, t) - sums[3 * s + t];
                d += x * x;
            }
            best[s] = d;
            new_centers[s] = cc;
        }
    }
    // the element nearest to each mean: each range of elements on its own thread from the
    // old centers' distances, a strictly smaller distance winning (the lowest index of its
    // range on ties); the ranges in order, a later one winning only if strictly nearer:
    // the choices of one pass over all elements
    // (each range from its own copy of the old centers' choices, made on its thread: the
    // first range's are the choices so far)
    std::vector<std::vector<double>> bests(nt);
    std::vector<std::vector<i64>> picks(nt);
    auto nearest = [&](i64 w) {
        bests[w] = best;
        if (w == 0) picks[w].assign(new_centers.p, new_centers.p + k);
        else picks[w].assign(k, -1);
        double* bw = bests[w].data();
        i64* pw = picks[w].data();
        for (i64 f = m * w / nt; f < m * (w + 1) / nt; ++f) {
            i64 s = label[f];
            double d = 0.0;
            for (int t = 0; t < 3; ++t) {
                double x = c(f, t) - sums[3 * s + t];
                d += x * x;
            }
            if (d < bw[s]) {
                bw[s] = d;
                pw[s] = f;
            }
        }
    };
    on_threads(nt, nearest);
    best.swap(bests[0]);
    std::copy(picks[0].begin(), picks[0].end(), new_centers.p);
    parallel_for(nt > 1 ? k : 0, [&](i64 s0, i64 s1) {
        for (i64 s = s0; s < s1; ++s)
            for (i64 w = 1; w < nt; ++w)
                if (picks[w][s] >= 0 && bests[w][s] < best[s]) {
                    best[s] = bests[w][s];
                    new_centers[s] = picks[w][s];
                }
    });
}

void bind_update(nb::module_& m) {
    m.def("update_centers", &update_centers,
          "Center update of the paper (section 3.1).",
          nb::arg("label"), nb::arg("k"), nb::arg("areas"), nb::arg("centroids"),
          nb::arg("old_centers"), nb::arg("new_centers"));
}

}  // namespace sfk
