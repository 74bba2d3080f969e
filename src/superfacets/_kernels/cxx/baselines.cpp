// The kernels of the baselines that are not the method: the Felzenszwalb-Huttenlocher
// graph segmentation (the ScanNet Segmentator's method), the covariances of cut pursuit's
// geometric features, and Variational Shape Approximation's flooding, fitting sums and
// assessment (Cohen-Steiner, Alliez, Desbrun 2004). Reference, bit for bit:
// tests/oracle/baselines.py (felzenszwalb.py, vsa.py); the same operations in order.
#include "common.hpp"

namespace sfk {

namespace {

// union-find root with path compression (the stray-piece merge's find)
inline i64 find_root(i64* parent, i64 x) {
    i64 root = x;
    while (parent[root] != root) root = parent[root];
    while (parent[x] != root) {
        const i64 nxt = parent[x];
        parent[x] = root;
        x = nxt;
    }
    return root;
}

// union by rank; returns the new root
inline i64 join(i64* parent, i64* rank, i64* size, i64 a, i64 b) {
    if (rank[a] > rank[b]) {
        parent[b] = a;
        size[a] += size[b];
        return a;
    }
    parent[a] = b;
    size[b] += size[a];
    if (rank[a] == rank[b]) rank[b] += 1;
    return b;
}

// VSA's proxies: planes (X_p, N_p); metric 0 is L2,1, 1 is L2
struct Proxies {
    In<double> areas, normals, corners, X, N;
    i64 metric;
    // the distortion of face f against proxy p (CSAD04, section 2.3)
    double error(i64 f, i64 p) const {
        if (metric == 0) {
            const double dx = normals(f, 0) - N(p, 0), dy = normals(f, 1) - N(p, 1),
                         dz = normals(f, 2) - N(p, 2);
            return areas[f] * (dx * dx + dy * dy + dz * dz);
        }
        const double* c = corners.p + 9 * f;
        double d[3];
        for (int v = 0; v < 3; ++v)
            d[v] = (c[3 * v] - X(p, 0)) * N(p, 0) + (c[3 * v + 1] - X(p, 1)) * N(p, 1) +
                   (c[3 * v + 2] - X(p, 2)) * N(p, 2);
        return areas[f] / 6.0 *
               (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + d[0] * d[1] + d[1] * d[2] +
                d[2] * d[0]);
    }
};

Proxies proxies_of(i64 metric, nb::handle areas, nb::handle normals, nb::handle corners,
                   nb::handle X, nb::handle N) {
    Proxies q{In<double>(areas, "areas"), In<double>(normals, "normals"),
              In<double>(corners, "corners"), In<double>(X, "X"), In<double>(N, "N"), metric};
    if (q.normals.cols != 3 || q.X.cols != 3 || q.N.cols != 3 || q.normals.n != q.areas.n ||
        (metric == 1 && q.corners.n != q.areas.n) || (metric != 0 && metric != 1))
        throw Mismatch("argument normals");
    return q;
}

inline double d2(const In<double>& c, i64 f, const double* P, i64 p) {
    const double dx = c(f, 0) - P[3 * p], dy = c(f, 1) - P[3 * p + 1], dz = c(f, 2) - P[3 * p + 2];
    return dx * dx + dy * dy + dz * dz;
}

inline bool tie(double a, double b) {
    return std::fabs(a - b) <= 1e-9 * std::max(std::fabs(a), std::fabs(b)) + 1e-300;
}

}  // namespace

// felzenszwalb.felzenszwalb: fill `labels` with the root of each element; returns the
// number of segments. `order` sorts the edges (lo, hi) by their float32 weight w; an edge
// joins two components when its weight is at most both thresholds Int(C) + k / |C|
// (Felzenszwalb and Huttenlocher 2004, eq. 5); then every edge (same order) joins
// components smaller than min_size.
i64 felzenszwalb(i64 n, nb::handle lo_, nb::handle hi_, nb::handle w_, nb::handle order_,
                 double k_thresh, i64 min_size, nb::handle labels_) {
    In<i64> lo(lo_, "lo"), hi(hi_, "hi"), order(order_, "order");
    In<float> w(w_, "w");
    Out<i64> labels(labels_, "labels");
    if (labels.n != n || lo.n != hi.n || w.n != lo.n || order.n != lo.n || n < 0)
        throw Mismatch("argument labels");
    for (i64 t = 0; t < lo.n; ++t)
        if (lo[t] < 0 || lo[t] >= n || hi[t] < 0 || hi[t] >= n || order[t] < 0 ||
            order[t] >= lo.n)
            throw Mismatch("argument lo");
    nb::gil_scoped_release nogil;
    const float k = static_cast<float>(k_thresh);
    std::vector<i64> parent(n), rank(n, 0), size(n, 1);
    for (i64 i = 0; i < n; ++i) parent[i] = i;
    std::vector<float> thresh(n, k);
    i64 count = n;
    for (i64 s = 0; s < order.n; ++s) {
        const i64 t = order[s];
        const i64 a = find_root(parent.data(), lo[t]), b = find_root(parent.data(), hi[t]);
        if (a != b && w[t] <= thresh[a] && w[t] <= thresh[b]) {
            const i64 r = join(parent.data(), rank.data(), size.data(), a, b);
            // float32 + (float32 / int64): numpy's rules widen to float64, stored as float32
            thresh[r] = static_cast<float>(static_cast<double>(w[t]) +
                                           static_cast<double>(k) / static_cast<double>(size[r]));
            --count;
        }
    }
    for (i64 s = 0; s < order.n; ++s) {
        const i64 t = order[s];
        const i64 a = find_root(parent.data(), lo[t]), b = find_root(parent.data(), hi[t]);
        if (a != b && (size[a] < min_size || size[b] < min_size)) {
            join(parent.data(), rank.data(), size.data(), a, b);
            --count;
        }
    }
    for (i64 i = 0; i < n; ++i) labels[i] = find_root(parent.data(), i);
    return count;
}

// normals.csr_covariances: out[i], the 3x3 covariance of the CSR neighbours of point i
// (their scatter divided by their number; zeros for none). On threads.
void csr_covariances(nb::handle indptr_, nb::handle indices_, nb::handle points_,
                     nb::handle out_) {
    In<i64> indptr(indptr_, "indptr");
    In<double> points(points_, "points");
    Out<double> out(out_, "out");
    const i64 n = indptr.n - 1;
    if (points.cols != 3 || out.n != n || size_of(out_) != 9 * n) throw Mismatch("argument out");
    with_index(indices_, "indices", [&](const auto& indices) {
        check_csr(indptr, indices, n, points.n);
        nb::gil_scoped_release nogil;
        parallel_for(n, [&](i64 lo, i64 hi) {
            double a[6] = {0, 0, 0, 0, 0, 0};
            for (i64 i = lo; i < hi; ++i) {
                const i64 s = indptr[i], k = indptr[i + 1] - s;
                for (int t = 0; t < 6; ++t) a[t] = 0.0;
                if (k > 0) {
                    double m0 = 0.0, m1 = 0.0, m2 = 0.0;
                    for (i64 t = 0; t < k; ++t) {
                        const i64 j = indices[s + t];
                        m0 += points(j, 0);
                        m1 += points(j, 1);
                        m2 += points(j, 2);
                    }
                    m0 /= static_cast<double>(k);
                    m1 /= static_cast<double>(k);
                    m2 /= static_cast<double>(k);
                    for (i64 t = 0; t < k; ++t) {
                        const i64 j = indices[s + t];
                        const double x = points(j, 0) - m0, y = points(j, 1) - m1,
                                     z = points(j, 2) - m2;
                        a[0] += x * x;
                        a[1] += x * y;
                        a[2] += x * z;
                        a[3] += y * y;
                        a[4] += y * z;
                        a[5] += z * z;
                    }
                }
                const i64 m = std::max<i64>(k, 1);
                const double md = static_cast<double>(m);
                double* c = out.p + 9 * i;
                c[0] = a[0] / md;
                c[1] = c[3] = a[1] / md;
                c[2] = c[6] = a[2] / md;
                c[4] = a[3] / md;
                c[5] = c[7] = a[4] / md;
                c[8] = a[5] / md;
            }
        });
    });
}

// VSA's flooding from the seeds with one priority queue: every seed takes its proxy; the
// unlabelled neighbours of each labelled face are pushed with their distortion to that
// face's proxy; the face of the smallest entry popped takes the entry's proxy (CSAD04,
// section 3.3). Faces no seed reaches keep -1.
void vsa_partition(nb::handle indptr_, nb::handle indices_, i64 metric, nb::handle areas,
                   nb::handle normals, nb::handle corners, nb::handle X, nb::handle N,
                   nb::handle seeds_, i64 n_proxies, nb::handle label_) {
    In<i64> indptr(indptr_, "indptr"), seeds(seeds_, "seeds");
    In<i32> indices(indices_, "indices");
    Out<i64> label(label_, "label");
    const Proxies q = proxies_of(metric, areas, normals, corners, X, N);
    const i64 m = label.n;
    if (indptr.n != m + 1 || q.areas.n != m || seeds.n < n_proxies || q.X.n < n_proxies ||
        q.N.n < n_proxies || n_proxies < 1)
        throw Mismatch("argument seeds");
    for (i64 p = 0; p < n_proxies; ++p)
        if (seeds[p] < 0 || seeds[p] >= m) throw Mismatch("argument seeds");
    check_csr(indptr, indices, m, m);
    nb::gil_scoped_release nogil;
    Heap heap(indices.n + 1);
    for (i64 f = 0; f < m; ++f) label[f] = -1;
    for (i64 p = 0; p < n_proxies; ++p) label[seeds[p]] = p;
    auto push_neighbours = [&](i64 f, i64 p) {
        for (i64 j = indptr[f]; j < indptr[f + 1]; ++j) {
            const i64 g = indices[j];
            if (label[g] < 0) heap.push(q.error(g, p), g * n_proxies + p);
        }
    };
    for (i64 p = 0; p < n_proxies; ++p) push_neighbours(seeds[p], p);
    while (heap.size > 0) {
        const i64 v = heap.h[0].val;
        heap.pop();
        const i64 f = v / n_proxies;
        if (label[f] >= 0) continue;
        const i64 p = v - f * n_proxies;
        label[f] = p;
        push_neighbours(f, p);
    }
}

// VSA's fitting sums per region (CSAD04, section 3.4): area, area-weighted normal and
// centroid sums, and for L2 the integral of x x^T over the region's triangles
// (a / 12 (sum_i v_i v_i^T + s s^T), s = sum_i v_i), each summed in face order.
void vsa_sums(nb::handle label_, i64 n_proxies, i64 metric, nb::handle areas_,
              nb::handle normals_, nb::handle centroids_, nb::handle corners_, nb::handle area_,
              nb::handle nsum_, nb::handle csum_, nb::handle mom_) {
    In<i64> label(label_, "label");
    In<double> areas(areas_, "areas"), normals(normals_, "normals"),
        centroids(centroids_, "centroids"), corners(corners_, "corners");
    Out<double> area(area_, "area"), nsum(nsum_, "nsum"), csum(csum_, "csum"), mom(mom_, "mom");
    const i64 m = label.n;
    if (areas.n != m || normals.n != m || centroids.n != m || normals.cols != 3 ||
        centroids.cols != 3 || (metric == 1 && corners.n != m) || area.n != n_proxies ||
        size_of(nsum_) != 3 * n_proxies || size_of(csum_) != 3 * n_proxies ||
        size_of(mom_) != 9 * n_proxies)
        throw Mismatch("argument area");
    for (i64 f = 0; f < m; ++f)
        if (label[f] < 0 || label[f] >= n_proxies) throw Mismatch("argument label");
    nb::gil_scoped_release nogil;
    for (i64 p = 0; p < n_proxies; ++p) {
        area[p] = 0.0;
        for (int i = 0; i < 3; ++i) nsum.p[3 * p + i] = csum.p[3 * p + i] = 0.0;
        for (int i = 0; i < 9; ++i) mom.p[9 * p + i] = 0.0;
    }
    for (i64 f = 0; f < m; ++f) {
        const i64 p = label[f];
        const double a = areas[f];
        area[p] += a;
        for (int i = 0; i < 3; ++i) {
            nsum.p[3 * p + i] += a * normals(f, i);
            csum.p[3 * p + i] += a * centroids(f, i);
        }
        if (metric == 1) {
            const double* c = corners.p + 9 * f;
            for (int r = 0; r < 3; ++r) {
                const double sr = c[r] + c[3 + r] + c[6 + r];
                for (int k = 0; k < 3; ++k) {
                    const double sc = c[k] + c[3 + k] + c[6 + k];
                    const double vv = c[r] * c[k] + c[3 + r] * c[3 + k] + c[6 + r] * c[6 + k];
                    mom.p[9 * p + 3 * r + k] += a / 12.0 * (vv + sr * sc);
                }
            }
        }
    }
}

// VSA's assessment: per region, the new seed (the face of least distortion against its
// proxy; among equal distortions the face nearest X) and the total distortion, in place;
// returns the mesh's total.
double vsa_assess(nb::handle label_, i64 n_proxies, i64 metric, nb::handle areas,
                  nb::handle normals, nb::handle centroids_, nb::handle corners, nb::handle X,
                  nb::handle N, nb::handle seeds_, nb::handle total_) {
    In<i64> label(label_, "label");
    In<double> centroids(centroids_, "centroids");
    Out<i64> seeds(seeds_, "seeds");
    Out<double> total(total_, "total");
    const Proxies q = proxies_of(metric, areas, normals, corners, X, N);
    const i64 m = label.n;
    if (q.areas.n != m || centroids.n != m || centroids.cols != 3 || seeds.n < n_proxies ||
        total.n < n_proxies || q.X.n < n_proxies || q.N.n < n_proxies)
        throw Mismatch("argument seeds");
    for (i64 f = 0; f < m; ++f)
        if (label[f] < 0 || label[f] >= n_proxies) throw Mismatch("argument label");
    nb::gil_scoped_release nogil;
    std::vector<double> best(n_proxies, INF), best_d(n_proxies, INF);
    for (i64 p = 0; p < n_proxies; ++p) total[p] = 0.0;
    double out = 0.0;
    for (i64 f = 0; f < m; ++f) {
        const i64 p = label[f];
        const double e = q.error(f, p);
        total[p] += e;
        out += e;
        if (e < best[p] && !tie(e, best[p])) {
            best[p] = e;
            best_d[p] = d2(centroids, f, q.X.p, p);
            seeds[p] = f;
        } else if (tie(e, best[p])) {
            const double d = d2(centroids, f, q.X.p, p);
            if (d < best_d[p]) {
                best_d[p] = d;
                seeds[p] = f;
            }
        }
    }
    return out;
}

// VSA's region insertion: per region, the face of largest distortion that is not a seed
// (-1 if none); among equal distortions the one farthest from the region's seed.
void vsa_worst_faces(nb::handle label_, i64 n_proxies, i64 metric, nb::handle areas,
                     nb::handle normals, nb::handle centroids_, nb::handle corners,
                     nb::handle X, nb::handle N, nb::handle seeds_, nb::handle is_seed_,
                     nb::handle worst_) {
    In<i64> label(label_, "label"), seeds(seeds_, "seeds");
    In<double> centroids(centroids_, "centroids");
    In<bool> is_seed(is_seed_, "is_seed");
    Out<i64> worst(worst_, "worst");
    const Proxies q = proxies_of(metric, areas, normals, corners, X, N);
    const i64 m = label.n;
    if (q.areas.n != m || centroids.n != m || centroids.cols != 3 || is_seed.n != m ||
        seeds.n < n_proxies || worst.n < n_proxies || q.X.n < n_proxies || q.N.n < n_proxies)
        throw Mismatch("argument seeds");
    for (i64 f = 0; f < m; ++f)
        if (label[f] < 0 || label[f] >= n_proxies) throw Mismatch("argument label");
    for (i64 p = 0; p < n_proxies; ++p)
        if (seeds[p] < 0 || seeds[p] >= m) throw Mismatch("argument seeds");
    nb::gil_scoped_release nogil;
    std::vector<double> worst_e(n_proxies, -1.0), worst_d(n_proxies, -1.0), S(3 * n_proxies);
    for (i64 p = 0; p < n_proxies; ++p) {
        worst[p] = -1;
        for (int i = 0; i < 3; ++i) S[3 * p + i] = centroids(seeds[p], i);
    }
    for (i64 f = 0; f < m; ++f) {
        if (is_seed[f]) continue;
        const i64 p = label[f];
        const double e = q.error(f, p);
        if (e > worst_e[p] && !tie(e, worst_e[p])) {
            worst_e[p] = e;
            worst_d[p] = d2(centroids, f, S.data(), p);
            worst[p] = f;
        } else if (tie(e, worst_e[p])) {
            const double d = d2(centroids, f, S.data(), p);
            if (d > worst_d[p]) {
                worst_d[p] = d;
                worst[p] = f;
            }
        }
    }
}

void bind_baselines(nb::module_& m) {
    m.def("felzenszwalb", &felzenszwalb,
          ".felzenszwalb.felzenszwalb with its threshold as float32 (the compiled kernel takes "
          "it as a float holding a float32 value).",
          nb::arg("n"), nb::arg("lo"), nb::arg("hi"), nb::arg("w"), nb::arg("order"),
          nb::arg("k_thresh"), nb::arg("min_size"), nb::arg("labels"));
    m.def("csr_covariances", &csr_covariances,
          "Out[i].",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("points"), nb::arg("out"));
    m.def("vsa_partition", &vsa_partition,
          ".vsa.partition with its heap arrays made here.",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("metric"), nb::arg("areas"),
          nb::arg("normals"), nb::arg("corners"), nb::arg("X"), nb::arg("N"), nb::arg("seeds"),
          nb::arg("n_proxies"), nb::arg("label"));
    m.def("vsa_sums", &vsa_sums,
          "The sums of .vsa.fit, in its order.",
          nb::arg("label"), nb::arg("n_proxies"), nb::arg("metric"), nb::arg("areas"),
          nb::arg("normals"), nb::arg("centroids"), nb::arg("corners"), nb::arg("area"),
          nb::arg("nsum"), nb::arg("csum"), nb::arg("mom"));
    m.def("vsa_assess", &vsa_assess,
          "Per region.",
          nb::arg("label"), nb::arg("n_proxies"), nb::arg("metric"), nb::arg("areas"),
          nb::arg("normals"), nb::arg("centroids"), nb::arg("corners"), nb::arg("X"),
          nb::arg("N"), nb::arg("seeds"), nb::arg("total"));
    m.def("vsa_worst_faces", &vsa_worst_faces,
          "Per region, the face of largest distortion that is not a seed (-1 if none).",
          nb::arg("label"), nb::arg("n_proxies"), nb::arg("metric"), nb::arg("areas"),
          nb::arg("normals"), nb::arg("centroids"), nb::arg("corners"), nb::arg("X"),
          nb::arg("N"), nb::arg("seeds"), nb::arg("is_seed"), nb::arg("worst"));
}

}  // namespace sfk
