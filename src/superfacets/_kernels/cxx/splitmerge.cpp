// Split and merge candidates of the K-preserving swaps (tests/oracle/splitmerge.py),
// the same operations in the same order.
#include <type_traits>

#include "common.hpp"

namespace sfk {

namespace {

inline double pw(double d, double power) {
    if (power == 4.0) {
        double q = d * d;
        return q * q;
    }
    return std::pow(d, power);
}

struct Search {
    const i64* indptr;
    const i32* indices;
    const double* w;
    const i32* label;
    const double* sizes;
    const double* positions;  // (n, 3)
    Heap* heap;  // (the numba kernels' hkey / hval: here one array of pairs)
};

// f's neighbours within labels la and lb improved from f's distance d (queued in q: the
// search's heap, or a bucket queue)
template <class Q>
inline void relax_into(const Search& s, i64 la, i64 lb, i64 f, double d, double* dist,
                       i64* stamp, i64 sid, Q& q) {
    for (i64 e = s.indptr[f]; e < s.indptr[f + 1]; ++e) {
        i64 g = s.indices[e];
        i64 lg = s.label[g];
        if (lg != la && lg != lb) continue;
        double nd = d + s.w[e];
        if (stamp[g] != sid || nd < dist[g]) {
            dist[g] = nd;
            stamp[g] = sid;
            if constexpr (std::is_same_v<Q, Heap>)
                q.push(nd, g);
            else
                q.push(g, nd);
        }
    }
}

inline void relax(const Search& s, i64 la, i64 lb, i64 f, double d, double* dist, i64* stamp,
                  i64 sid) {
    relax_into(s, la, lb, f, d, dist, stamp, sid, *s.heap);
}

void search(const Search& s, i64 la, i64 lb, i64 src, double* dist, i64* stamp, i64 sid) {
    dist[src] = 0.0;
    stamp[src] = sid;
    Heap& h = *s.heap;
    h.size = 0;
    h.push(0.0, src);
    while (h.size > 0) {
        double d = h.h[0].key;
        i64 f = h.h[0].val;
        h.pop();
        if (d > dist[f]) continue;
        relax(s, la, lb, f, d, dist, stamp, sid);
    }
}

// The same search by a label-correcting bucket queue (common.hpp): its distances and
// stamps are those of `search` to the bit, every element reached ending with the least
// float sum over paths, a fixed point that does not depend on the order of the work (the
// energies and the splits read nothing else; the merges' early stop reads the order of
// the pops: they keep the heap).
void bucket_search(BucketQueue& q, const Search& s, i64 la, i64 lb, i64 src, double* dist,
                   i64* stamp, i64 sid) {
    q.reset();
    dist[src] = 0.0;
    stamp[src] = sid;
    q.push(src, 0.0);
    while (!q.empty()) {
        i64 f;
        double d;
        q.pop(f, d);
        if (d > dist[f]) continue;
        relax_into(s, la, lb, f, d, dist, stamp, sid, q);
    }
}

i64 nearest_mean(const i64* elems, i64 n, const double* sizes, const double* pos) {
    double tot = 0.0, mx_ = 0.0, my = 0.0, mz = 0.0;
    for (i64 i = 0; i < n; ++i) {
        i64 f = elems[i];
        double a = sizes[f];
        tot += a;
        mx_ += a * pos[3 * f];
        my += a * pos[3 * f + 1];
        mz += a * pos[3 * f + 2];
    }
    if (tot > 0) {
        mx_ /= tot;
        my /= tot;
        mz /= tot;
    } else {
        mx_ = my = mz = 0.0;
        for (i64 i = 0; i < n; ++i) {
            i64 f = elems[i];
            mx_ += pos[3 * f] / static_cast<double>(n);
            my += pos[3 * f + 1] / static_cast<double>(n);
            mz += pos[3 * f + 2] / static_cast<double>(n);
        }
    }
    i64 best = elems[0];
    double bd = INF;
    for (i64 i = 0; i < n; ++i) {
        i64 f = elems[i];
        double dx = pos[3 * f] - mx_, dy = pos[3 * f + 1] - my, dz = pos[3 * f + 2] - mz;
        double q = dx * dx + dy * dy + dz * dz;
        if (q < bd) {
            bd = q;
            best = f;
        }
    }
    return best;
}

std::pair<double, i64> energy_of(const i64* elems, i64 n, const double* sizes,
                                 const double* dist, const i64* stamp, i64 sid, double power) {
    double e = 0.0;
    i64 far = elems[0];
    double fd = -1.0;
    for (i64 i = 0; i < n; ++i) {
        i64 f = elems[i];
        if (stamp[f] == sid) {
            double d = dist[f];
            e += sizes[f] * pw(d, power);
            if (d > fd) {
                fd = d;
                far = f;
            }
        }
    }
    for (i64 i = 0; i < n; ++i) {
        i64 f = elems[i];
        if (stamp[f] != sid) e += sizes[f] * pw(fd, power);
    }
    return {e, far};
}

// The same search over the union of superfacets la and lb, its distances and stamps kept
// by slot, not by element (a thread's scratch the size of the union, not of the input):
// an element g of la at rank[g], of lb at na + rank[g] (rank: its place in its
// superfacet's members; na: la's members). The same pops in the same order.
bool union_search_below(const Search& s, i64 la, i64 lb, i64 na, const i64* rank, i64 src,
                        double* dist, i64* stamp, i64 sid, double power, double area,
                        double limit) {
    auto slot = [&](i64 g, i64 lg) { return lg == la ? rank[g] : na + rank[g]; };
    const i64 x0 = slot(src, s.label[src]);
    dist[x0] = 0.0;
    stamp[x0] = sid;
    Heap& h = *s.heap;
    h.size = 0;
    h.push(0.0, src);
    double settled = 0.0, rest = area;
    while (h.size > 0) {
        double d = h.h[0].key;
        i64 f = h.h[0].val;
        h.pop();
        if (d > dist[slot(f, s.label[f])]) continue;
        double dp = pw(d, power);
        settled += s.sizes[f] * dp;
        rest -= s.sizes[f];
        if (settled + mx(rest, 0.0) * dp >= limit) return false;
        for (i64 e = s.indptr[f]; e < s.indptr[f + 1]; ++e) {
            i64 g = s.indices[e];
            i64 lg = s.label[g];
            if (lg != la && lg != lb) continue;
            double nd = d + s.w[e];
            i64 xg = slot(g, lg);
            if (stamp[xg] != sid || nd < dist[xg]) {
                dist[xg] = nd;
                stamp[xg] = sid;
                h.push(nd, g);
            }
        }
    }
    return true;
}

// energy_of over the union's elems, whose slots are their places in elems
double union_energy(const i64* elems, i64 n, const double* sizes, const double* dist,
                    const i64* stamp, i64 sid, double power) {
    double e = 0.0, fd = -1.0;
    for (i64 i = 0; i < n; ++i)
        if (stamp[i] == sid) {
            double d = dist[i];
            e += sizes[elems[i]] * pw(d, power);
            if (d > fd) fd = d;
        }
    for (i64 i = 0; i < n; ++i)
        if (stamp[i] != sid) e += sizes[elems[i]] * pw(fd, power);
    return e;
}

struct Common {
    In<i64> indptr, members, bounds;
    In<i32> indices, label;
    In<double> w, sizes, positions;
    Common(nb::handle indptr_, nb::handle indices_, nb::handle w_, nb::handle label_,
           nb::handle members_, nb::handle bounds_, nb::handle sizes_, nb::handle positions_)
        : indptr(indptr_, "indptr"), members(members_, "members"), bounds(bounds_, "bounds"),
          indices(indices_, "indices"), label(label_, "label"), w(w_, "w"),
          sizes(sizes_, "sizes"), positions(positions_, "positions") {
        if (positions.cols != 3) throw Mismatch("argument positions");
        const i64 n = check_csr(indptr, indices, label.n, label.n);
        check_rows(w, indptr[n], "w");
        check_rows(sizes, n, "sizes");
        check_rows(positions, n, "positions");
        check_csr(bounds, members, -1, n, "bounds");
    }
    i64 k() const { return bounds.n - 1; }
    // per-element arrays of a search (at least one entry per element), the loop's stride
    template <class... V>
    void check_scratch(i64 first, i64 step, const V&... per_element) const {
        if (first < 0 || step < 1) throw OutOfRange("arguments first, step");
        for (i64 m : {per_element.n...})
            if (m < label.n) throw OutOfRange("arguments dist, stamp: one entry per element");
    }
    i64 members_of(i64 sp) const { return bounds[sp + 1] - bounds[sp]; }
    Search search(Heap* heap) const {
        return Search{indptr.p, indices.p, w.p, label.p, sizes.p, positions.p, heap};
    }
};

}  // namespace

i64 energies(nb::handle indptr, nb::handle indices, nb::handle w, nb::handle label,
             nb::handle members, nb::handle bounds, nb::handle sizes, nb::handle positions,
             double power, nb::handle energy_, nb::handle far_, nb::handle dist_,
             nb::handle stamp_, i64 sid, nb::handle hkey_, nb::handle hval_, i64 first, i64 step) {
    Common c(indptr, indices, w, label, members, bounds, sizes, positions);
    Out<double> energy(energy_, "energy"), dist(dist_, "dist"), hkey(hkey_, "hkey");
    Out<i64> far(far_, "far"), stamp(stamp_, "stamp"), hval(hval_, "hval");
    c.check_scratch(first, step, dist, stamp);
    check_rows(energy, c.k(), "energy");
    check_rows(far, c.k(), "far");
    nb::gil_scoped_release nogil;
    Search s = c.search(nullptr);
    BucketQueue bq(c.w.p, c.w.n);
    const i64 k = c.bounds.n - 1;
    for (i64 sp = first; sp < k; sp += step) {
        i64 lo = c.bounds[sp], n = c.bounds[sp + 1] - lo;
        const i64* elems = c.members.p + lo;
        i64 ctr = nearest_mean(elems, n, c.sizes.p, c.positions.p);
        bucket_search(bq, s, sp, sp, ctr, dist.p, stamp.p, sid);
        auto ef = energy_of(elems, n, c.sizes.p, dist.p, stamp.p, sid, power);
        energy[sp] = ef.first;
        far[sp] = ef.second;
        ++sid;
    }
    return sid;
}

i64 split_candidates(nb::handle indptr, nb::handle indices, nb::handle w, nb::handle label,
                     nb::handle members, nb::handle bounds, nb::handle sizes,
                     nb::handle positions, double power, i64 lloyd, nb::handle which_,
                     nb::handle far_, nb::handle split_energy_, nb::handle second_,
                     nb::handle dist_, nb::handle dist2_, nb::handle stamp_, nb::handle stamp2_,
                     i64 sid, nb::handle hkey_, nb::handle hval_, nb::handle work_, i64 first,
                     i64 step) {
    Common c(indptr, indices, w, label, members, bounds, sizes, positions);
    In<i64> which(which_, "which"), far(far_, "far");
    Out<double> split_energy(split_energy_, "split_energy"), dist(dist_, "dist"),
        dist2(dist2_, "dist2"), hkey(hkey_, "hkey");
    Out<bool> second(second_, "second");
    Out<i64> stamp(stamp_, "stamp"), stamp2(stamp2_, "stamp2"), hval(hval_, "hval"),
        work(work_, "work");
    c.check_scratch(first, step, dist, dist2, stamp, stamp2, second);
    if (lloyd < 0 || lloyd > (i64(1) << 16))  // (the Lloyd rounds of a split: a few)
        throw OutOfRange("argument lloyd: " + std::to_string(lloyd) + ", outside 0..65536");
    check_range(which, 0, c.k(), "which");
    check_rows(far, c.k(), "far");
    check_rows(split_energy, c.k(), "split_energy");
    for (i64 t = 0; t < which.n; ++t) {
        const i64 sp = which[t];
        if (far[sp] < 0 || far[sp] >= c.label.n) throw OutOfRange("argument far: not an element");
        if (c.members_of(sp) > work.n) throw OutOfRange("argument work: too short");
    }
    nb::gil_scoped_release nogil;
    Search s = c.search(nullptr);
    BucketQueue bq(c.w.p, c.w.n);
    const double* sizes_p = c.sizes.p;
    for (i64 t = first; t < which.n; t += step) {
        i64 sp = which[t];
        i64 lo = c.bounds[sp], n = c.bounds[sp + 1] - lo;
        const i64* elems = c.members.p + lo;
        split_energy[sp] = INF;
        if (n < 4) continue;
        i64 p = far[sp];
        bucket_search(bq, s, sp, sp, p, dist.p, stamp.p, sid);
        i64 q = energy_of(elems, n, sizes_p, dist.p, stamp.p, sid, power).second;
        if (q == p) {
            ++sid;
            continue;
        }
        bool ok = true;
        i64 last_p = -1, last_q = -1;
        double e = 0.0;
        for (i64 it = 0; it < lloyd + 1; ++it) {
            if (it > 0) {
                i64 na = 0, nb = 0;
                for (i64 i = 0; i < n; ++i) {
                    i64 f = elems[i];
                    if (second[f]) work[n - 1 - nb++] = f;
                    else work[na++] = f;
                }
                p = nearest_mean(work.p, na, sizes_p, c.positions.p);
                q = nearest_mean(work.p + (n - nb), nb, sizes_p, c.positions.p);
                if (p == last_p && q == last_q) break;
            }
            last_p = p;
            last_q = q;
            bucket_search(bq, s, sp, sp, p, dist.p, stamp.p, sid);
            bucket_search(bq, s, sp, sp, q, dist2.p, stamp2.p, sid);
            i64 na = 0, nb = 0;
            e = 0.0;
            for (i64 i = 0; i < n; ++i) {
                i64 f = elems[i];
                double dp = stamp[f] == sid ? dist[f] : INF;
                double dq = stamp2[f] == sid ? dist2[f] : INF;
                second[f] = dq < dp;
                if (dq < dp) {
                    ++nb;
                    e += sizes_p[f] * pw(dq, power);
                } else {
                    ++na;
                    e += dp < INF ? sizes_p[f] * pw(dp, power) : 0.0;
                }
            }
            ++sid;
            if (na == 0 || nb == 0) {
                ok = false;
                break;
            }
        }
        if (ok) {
            split_energy[sp] = e;
        } else {
            for (i64 i = 0; i < n; ++i) second[elems[i]] = false;
        }
    }
    return sid;
}

i64 merge_energies(nb::handle indptr, nb::handle indices, nb::handle w, nb::handle label,
                   nb::handle members, nb::handle bounds, nb::handle sizes, nb::handle positions,
                   double power, nb::handle pair_a_, nb::handle pair_b_, nb::handle energy_,
                   double window_r2, double most, nb::handle out_, nb::handle dist_,
                   nb::handle stamp_, nb::handle rank_, i64 sid, nb::handle hkey_,
                   nb::handle hval_, nb::handle work_, i64 first, i64 step) {
    Common c(indptr, indices, w, label, members, bounds, sizes, positions);
    In<i64> pair_a(pair_a_, "pair_a"), pair_b(pair_b_, "pair_b"), rank(rank_, "rank");
    In<double> energy(energy_, "energy");
    Out<double> out(out_, "out"), dist(dist_, "dist"), hkey(hkey_, "hkey");
    Out<i64> stamp(stamp_, "stamp"), hval(hval_, "hval"), work(work_, "work");
    if (first < 0 || step < 1) throw OutOfRange("arguments first, step");
    check_rows(pair_b, pair_a.n, "pair_b", true);
    check_range(pair_a, 0, c.k(), "pair_a");
    check_range(pair_b, 0, c.k(), "pair_b");
    check_rows(energy, c.k(), "energy");
    check_rows(out, pair_a.n, "out");
    check_range(c.label, 0, c.k(), "label");
    check_rows(rank, c.label.n, "rank");
    for (i64 g = 0; g < rank.n; ++g)  // (a slot within its union)
        if (rank[g] < 0 || rank[g] >= c.members_of(c.label[g]))
            throw OutOfRange("argument rank: not a place among the members");
    for (i64 t = 0; t < pair_a.n; ++t) {
        const i64 u = c.members_of(pair_a[t]) + c.members_of(pair_b[t]);
        if (u > work.n) throw OutOfRange("argument work: too short");
        if (u > dist.n || u > stamp.n)
            throw OutOfRange("arguments dist, stamp: one entry per element of a union");
    }
    nb::gil_scoped_release nogil;
    Heap heap(4096);
    Search s = c.search(&heap);
    const double* pos = c.positions.p;
    const double slack = 1.0 + 1e-9;
    for (i64 t = first; t < pair_a.n; t += step) {
        i64 a = pair_a[t], b = pair_b[t];
        i64 n = 0;
        double area = 0.0;
        for (i64 sp : {a, b})
            for (i64 i = c.bounds[sp]; i < c.bounds[sp + 1]; ++i) {
                work[n] = c.members[i];
                area += c.sizes[c.members[i]];
                ++n;
            }
        i64 ctr = nearest_mean(work.p, n, c.sizes.p, pos);
        double far = 0.0;
        for (i64 i = 0; i < n; ++i) {
            i64 f = work[i];
            double dx = pos[3 * f] - pos[3 * ctr], dy = pos[3 * f + 1] - pos[3 * ctr + 1],
                   dz = pos[3 * f + 2] - pos[3 * ctr + 2];
            far = mx(far, dx * dx + dy * dy + dz * dz);
        }
        out[t] = INF;
        if (far <= window_r2) {
            double limit = (energy[a] + energy[b] + most) * slack;
            if (union_search_below(s, a, b, c.members_of(a), rank.p, ctr, dist.p, stamp.p, sid,
                                   power, area, limit))
                out[t] = union_energy(work.p, n, c.sizes.p, dist.p, stamp.p, sid, power);
        }
        ++sid;
    }
    return sid;
}

nb::object label_pairs(nb::handle indptr_, nb::handle indices_, nb::handle label_, i64 k) {
    In<i64> indptr(indptr_, "indptr");
    In<i32> indices(indices_, "indices"), label(label_, "label");
    check_csr(indptr, indices, label.n, label.n);
    if (k < 0 || k > (i64(1) << 31)) throw OutOfRange("argument k");
    check_range(label, 0, k, "label");
    std::vector<i64> keys;
    {
        nb::gil_scoped_release nogil;
        const i64 n = indptr.n - 1;
        for (i64 i = 0; i < n; ++i) {
            i64 a = label[i];
            for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) {
                i64 j = indices[x];
                i64 b = label[j];
                if (j > i && b != a) keys.push_back(mn(a, b) * k + mx(a, b));
            }
        }
        std::sort(keys.begin(), keys.end());
        keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    }
    Out<i64> out;
    auto out_a = fresh(static_cast<i64>(keys.size()), out);
    std::copy(keys.begin(), keys.end(), out.p);
    return out_a;
}

void bind_splitmerge(nb::module_& m) {
    m.def("label_pairs", &label_pairs,
          "The pairs of labels a < b that some adjacency joins, each once, as sorted keys a * k"
          " + b.",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("label"), nb::arg("k"));
    m.def("energies", &energies,
          "Energy of each superfacet first, first + step, .",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("w"), nb::arg("label"),
          nb::arg("members"), nb::arg("bounds"), nb::arg("sizes"), nb::arg("positions"),
          nb::arg("power"), nb::arg("energy"), nb::arg("far"), nb::arg("dist"),
          nb::arg("stamp"), nb::arg("sid"), nb::arg("hkey"), nb::arg("hval"), nb::arg("first"),
          nb::arg("step"));
    m.def("split_candidates", &split_candidates,
          "Energy of the best split in two of each superfacet s = which[first], which[first + "
          "step], .",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("w"), nb::arg("label"),
          nb::arg("members"), nb::arg("bounds"), nb::arg("sizes"), nb::arg("positions"),
          nb::arg("power"), nb::arg("lloyd"), nb::arg("which"), nb::arg("far"),
          nb::arg("split_energy"), nb::arg("second"), nb::arg("dist"), nb::arg("dist2"),
          nb::arg("stamp"), nb::arg("stamp2"), nb::arg("sid"), nb::arg("hkey"), nb::arg("hval"),
          nb::arg("work"), nb::arg("first"), nb::arg("step"));
    m.def("merge_energies", &merge_energies,
          "Energy of the union of superfacets a = pair_a[t] and b = pair_b[t] around the "
          "element nearest its mean, into out[t], for t = first, first + step, .",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("w"), nb::arg("label"),
          nb::arg("members"), nb::arg("bounds"), nb::arg("sizes"), nb::arg("positions"),
          nb::arg("power"), nb::arg("pair_a"), nb::arg("pair_b"), nb::arg("energy"),
          nb::arg("window_r2"), nb::arg("most"), nb::arg("out"), nb::arg("dist"),
          nb::arg("stamp"), nb::arg("rank"), nb::arg("sid"), nb::arg("hkey"), nb::arg("hval"),
          nb::arg("work"), nb::arg("first"), nb::arg("step"));
}

}  // namespace sfk
