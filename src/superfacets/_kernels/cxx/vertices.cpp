// The vertex graph of a mesh (tests/oracle/vertices.py), the same operations in
// the same order.
#include "common.hpp"

namespace sfk {

// Every corner's vertex numbered within [0, n) by index (the vertices no face uses may
// have any number: they are never read)
inline void check_used(const In<i64>& corners, const In<i64>& index, i64 n) {
    for (i64 c = 0; c < corners.n; ++c)
        if (index[corners[c]] < 0 || index[corners[c]] >= n)
            throw OutOfRange("argument index: a used vertex numbered outside 0.." +
                             std::to_string(n - 1));
}

void vertex_cells(nb::handle corners_, nb::handle offsets_, nb::handle index_,
                  nb::handle areas_, nb::handle normals_, nb::handle area_,
                  nb::handle normal_) {
    In<i64> corners(corners_, "corners"), offsets(offsets_, "offsets"), index(index_, "index");
    In<double> areas(areas_, "areas"), normals(normals_, "normals");
    Out<double> area(area_, "area"), normal(normal_, "normal");
    if (normals.cols != 3 || normal.cols != 3) throw Mismatch("argument normals");
    const i64 n_faces = check_csr(offsets, corners, -1, index.n, "offsets");
    check_used(corners, index, mn(area.n, normal.n));
    check_rows(areas, n_faces, "areas");
    check_rows(normals, n_faces, "normals");
    nb::gil_scoped_release nogil;
    const i64 n = area.n;
    for (i64 i = 0; i < n; ++i) {
        area[i] = 0.0;
        normal(i, 0) = normal(i, 1) = normal(i, 2) = 0.0;
    }
    for (i64 f = 0; f < offsets.n - 1; ++f) {
        i64 s = offsets[f], e = offsets[f + 1];
        double share = areas[f] / static_cast<double>(e - s);
        double fx = normals(f, 0) * areas[f], fy = normals(f, 1) * areas[f],
               fz = normals(f, 2) * areas[f];
        for (i64 c = s; c < e; ++c) {
            i64 i = index[corners[c]];
            area[i] += share;
            normal(i, 0) += fx;
            normal(i, 1) += fy;
            normal(i, 2) += fz;
        }
    }
    for (i64 i = 0; i < n; ++i)
        store_unit(normal.p + 3 * i, normal(i, 0), normal(i, 1), normal(i, 2));
}

nb::tuple mesh_edges(nb::handle corners_, nb::handle offsets_, nb::handle index_, i64 n,
                     nb::handle positions_, nb::handle centroids_) {
    In<i64> corners(corners_, "corners"), offsets(offsets_, "offsets"), index(index_, "index");
    In<double> pos(positions_, "positions"), cen(centroids_, "centroids");
    if (pos.cols != 3 || cen.cols != 3) throw Mismatch("argument positions");
    const i64 n_faces = check_csr(offsets, corners, -1, index.n, "offsets");
    if (offsets[n_faces] != corners.n || offsets[0] != 0)
        throw OutOfRange("argument offsets: not the corners' layout");
    check_used(corners, index, mn(n, pos.n));
    check_rows(cen, n_faces, "centroids");
    const i64 nh = corners.n;
    std::vector<i64> a(nh), b(nh), owner(nh), starts(n + 1, 0), order;
    std::vector<char> skip(nh);
    i64 ne = 0;
    {
        nb::gil_scoped_release nogil;
        for (i64 f = 0; f < offsets.n - 1; ++f) {
            i64 s = offsets[f], e = offsets[f + 1];
            for (i64 c = s; c < e; ++c) {
                i64 u = index[corners[c]], v = index[corners[c + 1 < e ? c + 1 : s]];
                a[c] = mn(u, v);
                b[c] = mx(u, v);
                owner[c] = f;
                skip[c] = u == v;
            }
        }
        for (i64 t = 0; t < nh; ++t)  // count_keys, scatter_keys: a stable counting sort on a
            if (!skip[t]) starts[a[t] + 1] += 1;
        for (i64 v = 0; v < n; ++v) starts[v + 1] += starts[v];
        order.resize(starts[n]);
        std::vector<i64> fill(starts.begin(), starts.end() - 1);
        for (i64 t = 0; t < nh; ++t)
            if (!skip[t]) order[fill[a[t]]++] = t;
        for (i64 v = 0; v < n; ++v) {  // sort_buckets: each bucket stably on b
            i64 lo = starts[v], hi = starts[v + 1];
            if (hi - lo <= 1) continue;
            if (hi - lo <= 32) {
                for (i64 i = lo + 1; i < hi; ++i) {
                    i64 x = order[i], kx = b[x], j = i - 1;
                    while (j >= lo && b[order[j]] > kx) {
                        order[j + 1] = order[j];
                        --j;
                    }
                    order[j + 1] = x;
                }
            } else {
                std::stable_sort(order.begin() + lo, order.begin() + hi,
                                 [&](i64 x, i64 y) { return b[x] < b[y]; });
            }
        }
        for (i64 t = 0; t < static_cast<i64>(order.size()); ++t)
            if (t == 0 || a[order[t]] != a[order[t - 1]] || b[order[t]] != b[order[t - 1]]) ++ne;
    }
    Out<i64> lo, hi, uses;
    Out<double> lengths, spans;
    auto lo_a = fresh(ne, lo), hi_a = fresh(ne, hi), uses_a = fresh(ne, uses);
    auto len_a = fresh(ne, lengths), span_a = fresh(ne, spans);
    {
        nb::gil_scoped_release nogil;
        for (i64 t = 0; t < ne; ++t) {
            lengths[t] = 0.0;
            uses[t] = 0;
        }
        i64 k = -1;
        const i64 m = static_cast<i64>(order.size());
        for (i64 t = 0; t < m; ++t) {
            i64 h = order[t], p = a[h], q = b[h];
            if (t == 0 || p != a[order[t - 1]] || q != b[order[t - 1]]) {
                ++k;
                lo[k] = p;
                hi[k] = q;
                double dx = pos(p, 0) - pos(q, 0), dy = pos(p, 1) - pos(q, 1),
                       dz = pos(p, 2) - pos(q, 2);
                spans[k] = std::sqrt(dx * dx + dy * dy + dz * dz);
            }
            i64 f = owner[h];
            double dx = cen(f, 0) - 0.5 * (pos(p, 0) + pos(q, 0));
            double dy = cen(f, 1) - 0.5 * (pos(p, 1) + pos(q, 1));
            double dz = cen(f, 2) - 0.5 * (pos(p, 2) + pos(q, 2));
            lengths[k] += std::sqrt(dx * dx + dy * dy + dz * dz);
            uses[k] += 1;
        }
    }
    return nb::make_tuple(lo_a, hi_a, len_a, span_a, uses_a);
}

void bind_vertices(nb::module_& m) {
    m.def("vertex_cells", &vertex_cells,
          "Barycentric area and unit area-weighted normal of every vertex element.",
          nb::arg("corners"), nb::arg("offsets"), nb::arg("index"), nb::arg("areas"),
          nb::arg("normals"), nb::arg("area"), nb::arg("normal"));
    m.def("mesh_edges", &mesh_edges,
          "The edges of a mesh's vertex elements, their dual lengths and uses.",
          nb::arg("corners"), nb::arg("offsets"), nb::arg("index"), nb::arg("n"),
          nb::arg("positions"), nb::arg("centroids"));
}

}  // namespace sfk
