// Connectivity enforcement: stray pieces merged into their neighbours, and
// the borders of the pieces.
// Reference, bit for bit: tests/oracle/connectivity.py.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <type_traits>
#include <vector>

#include "common.hpp"

namespace sfk {

// connectivity.same_label_components, on threads: a union-find over the adjacencies within
// a label (each listed in both rows of the CSR; j > i taken), a root linked only under
// a smaller one, so each piece's root is its lowest element; the pieces then numbered
// in the order of their roots: the depth-first numbering of one pass, bit for bit.
namespace {

inline i64 uf_find(i64* parent, i64 x) {  // path halving; a parent only moves up
    while (true) {
        i64 p = __atomic_load_n(parent + x, __ATOMIC_RELAXED);
        if (p == x) return x;
        i64 g = __atomic_load_n(parent + p, __ATOMIC_RELAXED);
        if (g != p) __atomic_store_n(parent + x, g, __ATOMIC_RELAXED);
        x = g;
    }
}

inline void uf_union(i64* parent, i64 a, i64 b) {
    while (true) {
        a = uf_find(parent, a);
        b = uf_find(parent, b);
        if (a == b) return;
        if (a > b) std::swap(a, b);  // b, the larger root, goes under a
        i64 expected = b;
        if (__atomic_compare_exchange_n(parent + b, &expected, a, false, __ATOMIC_ACQ_REL,
                                        __ATOMIC_RELAXED))
            return;
    }
}

}  // namespace

nb::object same_label_components(nb::handle indptr_, nb::handle indices_,
                                       nb::handle labels_) {
    In<i64> indptr(indptr_, "indptr"), labels(labels_, "labels");
    In<i32> indices(indices_, "indices");
    const i64 n = labels.n;
    if (indptr.n != n + 1) throw Mismatch("argument indptr");
    check_csr(indptr, indices, n, n);
    Out<i64> comp;
    auto comp_a = fresh(n, comp);
    {
        nb::gil_scoped_release nogil;
        std::vector<i64> root(n);
        i64* parent = root.data();
        parallel_for(n, [&](i64 lo, i64 hi) {
            for (i64 i = lo; i < hi; ++i) parent[i] = i;
        });
        parallel_for(n, [&](i64 lo, i64 hi) {
            for (i64 i = lo; i < hi; ++i) {
                const i64 lab = labels[i];
                for (i64 e = indptr[i]; e < indptr[i + 1]; ++e) {
                    const i64 j = indices[e];
                    if (j > i && labels[j] == lab) uf_union(parent, i, j);
                }
            }
        });
        parallel_for(n, [&](i64 lo, i64 hi) {  // every element straight to its root
            for (i64 i = lo; i < hi; ++i) parent[i] = uf_find(parent, i);
        });
        // the roots numbered in order: a count per range of elements, then each range's
        // roots from its first number (comp holds the roots' numbers first)
        const i64 T = std::max<i64>(1, std::min<i64>(threads(), n / 4096));
        std::vector<i64> first(T + 1, 0);
        auto range = [&](i64 t) { return n * t / T; };
        on_threads(T, [&](i64 t) {
            i64 m = 0;
            for (i64 i = range(t); i < range(t + 1); ++i) m += parent[i] == i;
            first[t + 1] = m;
        });
        for (i64 t = 0; t < T; ++t) first[t + 1] += first[t];
        on_threads(T, [&](i64 t) {
            i64 c = first[t];
            for (i64 i = range(t); i < range(t + 1); ++i)
                if (parent[i] == i) comp[i] = c++;
        });
        parallel_for(n, [&](i64 lo, i64 hi) {
            for (i64 i = lo; i < hi; ++i)
                if (parent[i] != i) comp[i] = comp[parent[i]];
        });
    }
    return comp_a;
}

// connectivity.py
namespace {
i64 find(std::vector<i64>& parent, i64 x) {
    i64 root = x;
    while (parent[root] != root) root = parent[root];
    while (parent[x] != root) {
        i64 nxt = parent[x];
        parent[x] = root;
        x = nxt;
    }
    return root;
}
}  // namespace

nb::object merge_strays(nb::handle strays_, nb::handle nb_indptr_, nb::handle nb_indices_,
                              nb::handle nb_data_, i64 n_pieces, nb::handle count_,
                              nb::handle tiny_, i64 min_elements) {
    In<i64> strays(strays_, "strays"), nb_indptr(nb_indptr_, "nb_indptr"),
        nb_indices(nb_indices_, "nb_indices"), count(count_, "count");
    In<double> nb_data(nb_data_, "nb_data");
    In<bool> tiny(tiny_, "tiny");
    if (n_pieces < 0) throw OutOfRange("argument n_pieces");
    check_csr(nb_indptr, nb_indices, n_pieces, n_pieces, "nb_indptr");
    check_rows(nb_data, nb_indptr[n_pieces], "nb_data");
    check_rows(count, n_pieces, "count");
    check_rows(tiny, n_pieces, "tiny");
    check_range(strays, 0, n_pieces, "strays");
    Out<i64> root;
    auto root_a = fresh(n_pieces, root);
    {
        nb::gil_scoped_release nogil;
        std::vector<i64> parent(n_pieces);
        for (i64 q = 0; q < n_pieces; ++q) parent[q] = q;
        std::vector<i64> held(count.p, count.p + n_pieces);  // elements of each region
        std::vector<double> total(n_pieces, 0.0);
        std::vector<char> seen(n_pieces, 0);
        std::vector<i64> touched(n_pieces);
        for (i64 i = 0; i < strays.n; ++i) {
            i64 p = strays[i];
            i64 rp = find(parent, p);
            if (tiny[p] && held[rp] >= min_elements) continue;  // grown by earlier strays
            i64 m = 0;
            for (i64 e = nb_indptr[p]; e < nb_indptr[p + 1]; ++e) {
                i64 q = find(parent, nb_indices[e]);
                if (q == rp) continue;
                if (!seen[q]) {
                    seen[q] = 1;
                    touched[m++] = q;
                }
                total[q] += nb_data[e];
            }
            if (m == 0) continue;
            i64 target = -1;
            double best = 0.0;
            bool small_target = false;  // a tiny piece joins a region still small first
            for (i64 j = 0; j < m; ++j) {
                i64 q = touched[j];
                bool small = tiny[p] && tiny[q] && held[q] < min_elements;
                if (target < 0 || (small && !small_target) ||
                    (small == small_target &&
                     (total[q] > best || (total[q] == best && q < target)))) {
                    target = q;
                    best = total[q];
                    small_target = small;
                }
                total[q] = 0.0;
                seen[q] = 0;
            }
            parent[rp] = target;
            held[target] += held[rp];
        }
        for (i64 q = 0; q < n_pieces; ++q) root[q] = find(parent, q);
    }
    return root_a;
}

// connectivity.stray_borders, on threads: each thread a range of rows, counted first
// (its entries of either side and its adjacencies, for the lengths' numbers), then
// written at its places: the entries in the order of one pass.
nb::tuple stray_borders(nb::handle indptr_, nb::handle indices_, nb::handle piece_,
                        nb::handle is_main_, nb::handle lengths_, nb::handle shares_) {
    In<i64> indptr(indptr_, "indptr"), piece(piece_, "piece");
    In<i32> indices(indices_, "indices");
    In<bool> is_main(is_main_, "is_main");
    In<double> lengths(lengths_, "lengths"), shares(shares_, "shares");
    const i64 n = check_csr(indptr, indices, -1, piece.n);
    check_rows(piece, n, "piece", true);
    check_range(piece, 0, is_main.n, "piece");
    if (shares.n) check_rows(shares, n, "shares");
    else {
        i64 above = 0;  // (the adjacencies: lengths has one each)
        for (i64 i = 0; i < n; ++i)
            for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) above += indices[x] > i;
        check_rows(lengths, above, "lengths");
    }
    const i64 T = std::max<i64>(1, std::min<i64>(threads(), n / 4096));
    auto row = [&](i64 t) { return n * t / T; };
    // per thread: entries with a stray row on side 0 and on side 1, adjacencies before
    std::vector<i64> side0(T + 1, 0), side1(T + 1, 0), pairs(T + 1, 0);
    {
        nb::gil_scoped_release nogil;
        on_threads(T, [&](i64 t) {
            i64 s0 = 0, s1 = 0, np_ = 0;
            for (i64 i = row(t); i < row(t + 1); ++i)
                for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) {
                    i64 j = indices[x];
                    if (j > i) {
                        ++np_;
                        i64 p = piece[i], q = piece[j];
                        if (p != q) {
                            s0 += !is_main[p];
                            s1 += !is_main[q];
                        }
                    }
                }
            side0[t + 1] = s0;
            side1[t + 1] = s1;
            pairs[t + 1] = np_;
        });
        for (i64 t = 0; t < T; ++t) {
            side0[t + 1] += side0[t];
            side1[t + 1] += side1[t];
            pairs[t + 1] += pairs[t];
        }
    }
    const i64 m = side0[T] + side1[T];
    Out<i64> a, b;
    Out<double> w;
    auto a_a = fresh(m, a), b_a = fresh(m, b);
    auto w_a = fresh(m, w);
    {
        nb::gil_scoped_release nogil;
        on_threads(T, [&](i64 t) {
            for (int side = 0; side < 2; ++side) {
                i64 u = side == 0 ? side0[t] : side0[T] + side1[t];
                i64 pt = pairs[t];
                for (i64 i = row(t); i < row(t + 1); ++i)
                    for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) {
                        i64 j = indices[x];
                        if (j > i) {
                            i64 p = side == 0 ? piece[i] : piece[j];
                            i64 q = side == 0 ? piece[j] : piece[i];
                            if (p != q && !is_main[p]) {
                                a[u] = p;
                                b[u] = q;
                                w[u] = shares.n ? 0.5 * (shares[i] + shares[j]) : lengths[pt];
                                ++u;
                            }
                            ++pt;
                        }
                    }
            }
        });
    }
    return nb::make_tuple(a_a, b_a, w_a);
}

void bind_connectivity(nb::module_& m) {
    m.def("same_label_components", &same_label_components,
          "Connected pieces of each label.",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("labels"));
    m.def("merge_strays", &merge_strays,
          "The piece each piece ends in.",
          nb::arg("strays"), nb::arg("nb_indptr"), nb::arg("nb_indices"), nb::arg("nb_data"),
          nb::arg("n_pieces"), nb::arg("count"), nb::arg("tiny"), nb::arg("min_elements"));
    m.def("stray_borders", &stray_borders,
          "The entries (a, b, length) of the pieces' adjacency whose row a is a stray piece.",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("piece"), nb::arg("is_main"),
          nb::arg("lengths"), nb::arg("shares"));
}

}  // namespace sfk
