// Farthest-point sampling over spatial blocks (tests/oracle/farthest.py): the same centers,
// ties included; the groups of blocks, their grid and their tree are this file's (a new
// center visits fewer blocks than the reference does, never with another result).
#include "common.hpp"

namespace sfk {

// farthest.py's _nearest_so_far: a point's squared distance to its nearest center so far
// (times its scale; a scale of 1.0 changes no bit), lowered by the center at (cx, cy, cz);
// -1: the point is a center
inline double nearest_so_far(double& mind, const double* p, double cx, double cy, double cz,
                             double scale) {
    if (mind < 0.0) return mind;
    double dx = p[0] - cx, dy = p[1] - cy, dz = p[2] - cz;
    double d = (dx * dx + dy * dy + dz * dz) * scale;
    if (d < mind) mind = d;
    return mind;
}

nb::tuple spatial_blocks(nb::handle centroids_, i64 cells_per_axis) {
    In<double> c(centroids_, "centroids");
    if (c.cols != 3 || c.n == 0) throw Mismatch("argument centroids");
    // (cells^3 about the elements: the count array stays O(m))
    if (cells_per_axis < 1 || cells_per_axis > (i64(1) << 20) ||
        cells_per_axis * cells_per_axis * cells_per_axis > 8 * c.n + 4096)
        throw OutOfRange("argument cells_per_axis: " + std::to_string(cells_per_axis) +
                         ", outside 1..(8 m + 4096)^(1/3)");
    const i64 m = c.n, g = cells_per_axis, g3 = g * g * g;
    std::vector<i64> order(m), count(g3 + 1, 0), bstart;
    i64 nb = 0;
    {
        nb::gil_scoped_release nogil;
        double lo[3];
        double span = 0.0;
        for (int t = 0; t < 3; ++t) {
            double a = c(0, t), b = c(0, t);
            for (i64 f = 0; f < m; ++f) {
                double x = c(f, t);
                if (x < a) a = x;
                if (x > b) b = x;
            }
            lo[t] = a;
            if (b - a > span) span = b - a;
        }
        double scale = span > 0 ? static_cast<double>(g) / span : 0.0;
        std::vector<i64> cell(m);
        for (i64 f = 0; f < m; ++f) {
            i64 key = 0;
            for (int t = 0; t < 3; ++t) {
                i64 i = static_cast<i64>((c(f, t) - lo[t]) * scale);
                if (i >= g) i = g - 1;
                if (i < 0) i = 0;
                key = key * g + i;
            }
            cell[f] = key;
            count[key + 1] += 1;
        }
        for (i64 i = 0; i < g3; ++i) count[i + 1] += count[i];
        std::vector<i64> fill(count.begin(), count.end() - 1);
        for (i64 f = 0; f < m; ++f) order[fill[cell[f]]++] = f;
        for (i64 i = 0; i < g3; ++i)
            if (count[i + 1] > count[i]) {
                bstart.push_back(count[i]);
                ++nb;
            }
        bstart.push_back(m);
    }
    Out<i64> order_o, bstart_o;
    Out<double> bcenter, bradius;
    auto order_a = fresh(m, order_o), bstart_a = fresh(nb + 1, bstart_o);
    auto bcenter_a = fresh(nb, bcenter, 3);
    auto bradius_a = fresh(nb, bradius);
    {
        nb::gil_scoped_release nogil;
        std::copy(order.begin(), order.end(), order_o.p);
        std::copy(bstart.begin(), bstart.end(), bstart_o.p);
        for (i64 b = 0; b < nb; ++b) {
            for (int t = 0; t < 3; ++t) {
                double a = INF, z = -INF;
                for (i64 j = bstart[b]; j < bstart[b + 1]; ++j) {
                    double x = c(order[j], t);
                    if (x < a) a = x;
                    if (x > z) z = x;
                }
                bcenter(b, t) = 0.5 * (a + z);
            }
            double r2 = 0.0;
            for (i64 j = bstart[b]; j < bstart[b + 1]; ++j) {
                i64 f = order[j];
                double d = 0.0;
                for (int t = 0; t < 3; ++t) {
                    double x = c(f, t) - bcenter(b, t);
                    d += x * x;
                }
                if (d > r2) r2 = d;
            }
            bradius[b] = std::sqrt(r2) * (1.0 + 1e-9);
        }
    }
    return nb::make_tuple(order_a, bstart_a, bcenter_a, bradius_a);
}

// k samples of m elements from `first`, into out; scale2 (where given) one per element
inline void check_sampling(i64 m, i64 k, i64 first, i64 n_out, i64 n_scale) {
    if (first < 0 || first >= m) throw OutOfRange("argument first: not an element");
    if (k < 0 || k > n_out || k > m) throw OutOfRange("argument k: more samples than room");
    check_rows(In<double>(nullptr, n_scale), m, "scale2");
}

void farthest_point_blocked(nb::handle centroids_, i64 k, i64 first, nb::handle out_,
                            nb::handle order_, nb::handle bstart_, nb::handle bcenter_,
                            nb::handle bradius_, nb::object scale2_, nb::object bscale2_) {
    In<double> c(centroids_, "centroids"), bcenter(bcenter_, "bcenter"),
        bradius(bradius_, "bradius");
    Out<i64> out(out_, "out");
    In<i64> order(order_, "order"), bstart(bstart_, "bstart");
    In<double> scale2, bscale2;
    const bool scaled = !scale2_.is_none();
    if (scaled) {
        scale2 = In<double>(scale2_, "scale2");
        bscale2 = In<double>(bscale2_, "bscale2");
    }
    if (c.cols != 3 || bcenter.cols != 3) throw Mismatch("argument centroids");
    check_sampling(c.n, k, first, out.n, scaled ? scale2.n : c.n);
    const i64 n_blocks = check_csr(bstart, order, -1, c.n, "bstart");
    check_rows(bcenter, n_blocks, "bcenter");
    check_rows(bradius, n_blocks, "bradius");
    if (scaled) check_rows(bscale2, n_blocks, "bscale2");
    nb::gil_scoped_release nogil;
    const i64 m = c.n, nb = bstart.n - 1;
    // each element's place in the block order (32 bits where they hold it: 4 bytes a point
    // less), its block found from that place (a binary search, once a center)
    std::vector<double> pos(3 * m);
    std::vector<std::int32_t> slot32(m < INT32_MAX ? m : 0);
    std::vector<i64> slot64(m < INT32_MAX ? 0 : m);
    for (i64 j = 0; j < m; ++j) {
        i64 f = order[j];
        if (m < INT32_MAX) slot32[f] = static_cast<std::int32_t>(j);
        else slot64[f] = j;
        pos[3 * j] = c(f, 0);
        pos[3 * j + 1] = c(f, 1);
        pos[3 * j + 2] = c(f, 2);
    }
    auto slot = [&](i64 f) { return m < INT32_MAX ? static_cast<i64>(slot32[f]) : slot64[f]; };
    auto home = [&](i64 f) {  // the block holding place slot(f): bstart[b] <= it < bstart[b + 1]
        const i64 j = slot(f);
        i64 lo = 0, hi = nb;
        while (hi - lo > 1) {
            const i64 mid = (lo + hi) / 2;
            if (bstart[mid] <= j) lo = mid;
            else hi = mid;
        }
        return lo;
    };
    std::vector<double> mind(m, INF);
    std::vector<i64> barg(nb);
    for (i64 b = 0; b < nb; ++b) {
        barg[b] = m;
        for (i64 j = bstart[b]; j < bstart[b + 1]; ++j) {
            i64 f = order[j];
            if (f < barg[b]) barg[b] = f;
        }
    }
    // Groups of 32 blocks in the Z-order of their centers, each with a sphere holding its
    // blocks' spheres, the least scale of its blocks and the best (bmax, barg) among them:
    // a new center skips a whole group where the group's bound shows that it would skip
    // each of its blocks (with a margin far above rounding), and the next center is the
    // best of the groups' bests. The same blocks are scanned, so the same centers as a
    // loop over every block (which took most of the time: docs/notes/code-measurements.md).
    constexpr i64 G = 32;
    std::vector<i64> gb(nb);
    {
        double lo3[3] = {INF, INF, INF}, hi3[3] = {-INF, -INF, -INF};
        for (i64 b = 0; b < nb; ++b)
            for (int t = 0; t < 3; ++t) {
                lo3[t] = mn(lo3[t], bcenter(b, t));
                hi3[t] = mx(hi3[t], bcenter(b, t));
            }
        std::vector<std::pair<std::uint64_t, i64>> key(nb);
        for (i64 b = 0; b < nb; ++b) {
            std::uint64_t z = 0;
            for (int t = 0; t < 3; ++t) {
                const double span = hi3[t] - lo3[t];
                std::uint64_t q = span > 0 ? static_cast<std::uint64_t>(
                                                 (bcenter(b, t) - lo3[t]) / span * 1023.0)
                                           : 0;
                for (int bit = 0; bit < 10; ++bit) z |= ((q >> bit) & 1u) << (3 * bit + t);
            }
            key[b] = {z, b};
        }
        std::sort(key.begin(), key.end());
        for (i64 b = 0; b < nb; ++b) gb[b] = key[b].second;
    }
    // The blocks' data in the groups' order (a group's blocks side by side): a visit reads
    // a group's 32 blocks from a few cache lines, not from 32 places in each array (the
    // visits of a run's late centers were mostly these misses); bmax and barg are kept
    // by that place, and the home block is found by it.
    std::vector<double> qc(3 * nb), qr(nb), qs(nb, 1.0), qmax(nb, INF);
    std::vector<i64> qbeg(nb), qend(nb), qarg(nb), place(nb);
    for (i64 i = 0; i < nb; ++i) {
        const i64 b = gb[i];
        for (int t = 0; t < 3; ++t) qc[3 * i + t] = bcenter(b, t);
        qr[i] = bradius[b];
        if (scaled) qs[i] = bscale2[b];
        qbeg[i] = bstart[b];
        qend[i] = bstart[b + 1];
        qarg[i] = barg[b];
        place[b] = i;
    }
    const i64 ng = (nb + G - 1) / G;
    std::vector<double> gc(3 * ng), gr(ng), gscale(ng, 1.0), gmax(ng, INF);
    std::vector<i64> garg(ng, -1);
    for (i64 g = 0; g < ng; ++g) {
        const i64 s0 = g * G, s1 = mn(nb, s0 + G);
        for (int t = 0; t < 3; ++t) {
            double a = INF, z = -INF;
            for (i64 i = s0; i < s1; ++i) {
                a = mn(a, bcenter(gb[i], t) - bradius[gb[i]]);
                z = mx(z, bcenter(gb[i], t) + bradius[gb[i]]);
            }
            gc[3 * g + t] = 0.5 * (a + z);
        }
        double r = 0.0;
        for (i64 i = s0; i < s1; ++i) {
            const i64 b = gb[i];
            double dx = bcenter(b, 0) - gc[3 * g], dy = bcenter(b, 1) - gc[3 * g + 1],
                   dz = bcenter(b, 2) - gc[3 * g + 2];
            r = mx(r, std::sqrt(dx * dx + dy * dy + dz * dz) + bradius[b]);
            if (scaled) gscale[g] = i == s0 ? bscale2[b] : mn(gscale[g], bscale2[b]);
        }
        gr[g] = r * (1.0 + 1e-6);
    }
    // Each center visits only the groups whose boxes lie within reach: a group farther than
    // sqrt(D / s) from it, D the largest scaled distance left (the new center's own) and s
    // the smallest scale, would skip every one of its blocks (its bound exceeds their
    // largest distance), so its best stays as it is. The groups are found on a grid of
    // cells, each group listed in every cell its box overlaps, and their bests are kept
    // in a tournament tree (the next center: its root, ties to the lowest element, as a
    // loop over the groups picks it). The same centers as visiting every group; the
    // groups' loop scanned all of them for each of a run's 100,000 centers on 10M points.
    std::vector<double> glo(3 * ng, INF), ghi(3 * ng, -INF);
    double alo[3] = {INF, INF, INF}, ahi[3] = {-INF, -INF, -INF};
    for (i64 g = 0; g < ng; ++g)
        for (i64 i = g * G; i < mn(nb, g * G + G); ++i)
            for (int t = 0; t < 3; ++t) {
                const i64 b = gb[i];
                glo[3 * g + t] = mn(glo[3 * g + t], bcenter(b, t) - bradius[b]);
                ghi[3 * g + t] = mx(ghi[3 * g + t], bcenter(b, t) + bradius[b]);
                alo[t] = mn(alo[t], glo[3 * g + t]);
                ahi[t] = mx(ahi[t], ghi[3 * g + t]);
            }
    double diag2 = 0.0, smin = 1.0;
    for (int t = 0; t < 3; ++t) diag2 += (ahi[t] - alo[t]) * (ahi[t] - alo[t]);
    const double diag = std::sqrt(diag2);
    if (scaled)
        for (i64 g = 0; g < ng; ++g) smin = g == 0 ? gscale[g] : mn(smin, gscale[g]);
    const i64 q = mx<i64>(1, static_cast<i64>(std::llround(std::cbrt(static_cast<double>(ng)))));
    double cell[3];
    for (int t = 0; t < 3; ++t) cell[t] = (ahi[t] - alo[t]) / static_cast<double>(q);
    auto cell_of = [&](double x, int t) {  // the cell holding coordinate x on axis t
        if (!(cell[t] > 0.0)) return i64(0);
        const double u = (x - alo[t]) / cell[t];
        return u <= 0.0 ? i64(0) : u >= static_cast<double>(q - 1) ? q - 1 : static_cast<i64>(u);
    };
    std::vector<i64> cstart(q * q * q + 1, 0), cgroups;
    for (int pass = 0; pass < 2; ++pass) {  // counts, then the lists
        std::vector<i64> fill(cstart.begin(), cstart.end() - 1);
        for (i64 g = 0; g < ng; ++g) {
            i64 a[3], z[3];
            for (int t = 0; t < 3; ++t) {
                a[t] = cell_of(glo[3 * g + t], t);
                z[t] = cell_of(ghi[3 * g + t], t);
            }
            for (i64 x = a[0]; x <= z[0]; ++x)
                for (i64 y = a[1]; y <= z[1]; ++y)
                    for (i64 w = a[2]; w <= z[2]; ++w) {
                        const i64 id = (x * q + y) * q + w;
                        if (pass == 0) ++cstart[id + 1];
                        else cgroups[fill[id]++] = g;
                    }
        }
        if (pass == 0) {
            for (i64 i = 0; i < q * q * q; ++i) cstart[i + 1] += cstart[i];
            cgroups.resize(cstart[q * q * q]);
        }
    }
    i64 P = 1;
    while (P < ng) P *= 2;
    std::vector<double> tv(2 * P, -INF);
    std::vector<i64> ta(2 * P, std::numeric_limits<i64>::max());
    auto settle = [&](i64 g) {  // group g's best into the tree, up to the root
        i64 i = P + g;
        tv[i] = gmax[g];
        ta[i] = garg[g];
        for (i >>= 1; i >= 1; i >>= 1) {
            const i64 l = 2 * i, r = 2 * i + 1;
            const bool right = tv[r] > tv[l] || (tv[r] == tv[l] && ta[r] < ta[l]);
            tv[i] = right ? tv[r] : tv[l];
            ta[i] = right ? ta[r] : ta[l];
        }
    };
    std::vector<i64> seen(ng, -1);
    i64 cur = first;
    for (i64 t = 0; t < k; ++t) {
        check_interrupt();  // (each center a pass over the elements)
        out[t] = cur;
        const double D = t == 0 ? INF : tv[1];  // the new center's distance: the largest
        mind[slot(cur)] = -1.0;
        const double cx = c(cur, 0), cy = c(cur, 1), cz = c(cur, 2);
        const i64 hb = place[home(cur)];
        auto visit = [&](i64 g) {
            {
                double dx = gc[3 * g] - cx, dy = gc[3 * g + 1] - cy, dz = gc[3 * g + 2] - cz;
                double dc = std::sqrt(dx * dx + dy * dy + dz * dz);
                double lb = dc - gr[g] - 1e-6 * (dc + gr[g]);
                if (lb > 0.0 && lb * lb * gscale[g] >= gmax[g] * (1.0 + 1e-6)) return;
            }
            double gbest = -1.0;
            i64 gbarg = -1;
            for (i64 i = g * G; i < mn(nb, g * G + G); ++i) {
                bool skip = false;
                if (i != hb) {
                    double dx = qc[3 * i] - cx, dy = qc[3 * i + 1] - cy, dz = qc[3 * i + 2] - cz;
                    double dc = std::sqrt(dx * dx + dy * dy + dz * dz);
                    double lb = dc - qr[i] - 1e-9 * (dc + qr[i]);
                    double lb2 = lb * lb;
                    if (scaled) lb2 *= qs[i];
                    skip = lb > 0.0 && lb2 >= qmax[i];
                }
                if (!skip) {
                    double best = -1.0;
                    i64 arg = m;
                    for (i64 j = qbeg[i]; j < qend[i]; ++j) {
                        // on the block-ordered positions
                        const double mf = nearest_so_far(mind[j], pos.data() + 3 * j, cx, cy,
                                                         cz, scaled ? scale2[j] : 1.0);
                        if (mf < 0.0) continue;
                        i64 f = order[j];
                        if (mf > best || (mf == best && f < arg)) {
                            best = mf;
                            arg = f;
                        }
                    }
                    qmax[i] = best;
                    qarg[i] = arg;
                }
                if (qmax[i] > gbest || (qmax[i] == gbest && qarg[i] < gbarg)) {
                    gbest = qmax[i];
                    gbarg = qarg[i];
                }
            }
            gmax[g] = gbest;
            garg[g] = gbarg;
            settle(g);
        };
        const double R = (D < INF && smin > 0.0)
                             ? std::sqrt(mx(D, 0.0) * (1.0 + 1e-6) / smin) * (1.0 + 1e-9) +
                                   4e-6 * diag
                             : INF;
        i64 a[3] = {0, 0, 0}, z[3] = {q - 1, q - 1, q - 1};
        double span = 1.0;
        if (R < INF) {
            const double at[3] = {cx, cy, cz};
            for (int t3 = 0; t3 < 3; ++t3) {
                a[t3] = cell_of(at[t3] - R, t3);
                z[t3] = cell_of(at[t3] + R, t3);
                span *= static_cast<double>(z[t3] - a[t3] + 1);
            }
        }
        if (R == INF || span >= static_cast<double>(ng)) {
            for (i64 g = 0; g < ng; ++g) visit(g);
        } else {
            for (i64 x = a[0]; x <= z[0]; ++x)
                for (i64 y = a[1]; y <= z[1]; ++y)
                    for (i64 w = a[2]; w <= z[2]; ++w) {
                        const i64 id = (x * q + y) * q + w;
                        for (i64 j = cstart[id]; j < cstart[id + 1]; ++j) {
                            const i64 g = cgroups[j];
                            if (seen[g] == t) continue;
                            seen[g] = t;
                            visit(g);
                        }
                    }
        }
        cur = ta[1];
    }
}

void farthest_point(nb::handle centroids_, i64 k, i64 first, nb::handle out_,
                    nb::object scale2_) {
    In<double> c(centroids_, "centroids");
    Out<i64> out(out_, "out");
    In<double> scale2;
    const bool scaled = !scale2_.is_none();
    if (scaled) scale2 = In<double>(scale2_, "scale2");
    if (c.cols != 3) throw Mismatch("argument centroids");
    check_sampling(c.n, k, first, out.n, scaled ? scale2.n : c.n);
    nb::gil_scoped_release nogil;
    const i64 m = c.n;
    std::vector<double> mind(m, INF);
    i64 cur = first;
    for (i64 t = 0; t < k; ++t) {
        check_interrupt();  // (each center a pass over the elements)
        out[t] = cur;
        mind[cur] = -1.0;
        const double cx = c(cur, 0), cy = c(cur, 1), cz = c(cur, 2);
        double best = -1.0;
        i64 nxt = -1;
        for (i64 f = 0; f < m; ++f) {
            const double mf =
                nearest_so_far(mind[f], c.p + 3 * f, cx, cy, cz, scaled ? scale2[f] : 1.0);
            if (mf < 0.0) continue;
            if (mf > best) {
                best = mf;
                nxt = f;
            }
        }
        cur = nxt;
    }
}

void bind_farthest(nb::module_& m) {
    m.def("farthest_point", &farthest_point,
          "Iterative farthest point sampling in O(m k) with a running minimum.",
          nb::arg("centroids"), nb::arg("k"), nb::arg("first"), nb::arg("out"),
          nb::arg("scale2") = nb::none());
    m.def("spatial_blocks", &spatial_blocks,
          "Group faces by the cell of a regular grid that holds their centroid.",
          nb::arg("centroids"), nb::arg("cells_per_axis"));
    m.def("farthest_point_blocked", &farthest_point_blocked,
          "Farthest_point, skipping the blocks a new center cannot change.",
          nb::arg("centroids"), nb::arg("k"), nb::arg("first"), nb::arg("out"),
          nb::arg("order"), nb::arg("bstart"), nb::arg("bcenter"), nb::arg("bradius"),
          nb::arg("scale2") = nb::none(), nb::arg("bscale2") = nb::none());
}

}  // namespace sfk
