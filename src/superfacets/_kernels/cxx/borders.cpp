// The superpoints' borders: the crossing adjacencies, the sums of each pair
// of labels, and the distinct label pairs.
// Reference, bit for bit: tests/oracle/borders.py.
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

// borders.label_pair_sums: the adjacencies of a symmetric CSR point graph whose two
// points have different labels (of k), summed per pair of labels without listing them
// (crossing_pairs, point_terms and a np.bincount per sum would hold every one): the keys
// lo * k + hi, ascending, and per key (border, border * angle, border * concave,
// crossings, angle, concave) summed over its adjacencies in pair order (rows ascending,
// then j: np.bincount's order over crossing_pairs' rows), an adjacency's border the
// mean of its points' border shares and its angle acos of its normals' cosine. On T
// threads: the rows in chunks, each chunk's rows split among the threads, each listing
// its crossings (their terms computed) in pair order, one list per range of lo; then
// each thread adds the lists of its range of lo, the row ranges' in order: every sum
// adds what one pass adds, in its order.
struct Crossing {
    i64 lo, hi;
    double len, ang, cc;
};

// Rows a chunk of label_pair_sums' threaded pass lists the crossings of (at most some
// 50 MB of lists on a kNN graph, whatever its size).
constexpr i64 PAIR_SUMS_CHUNK = i64{1} << 17;

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
    const i64 T = std::max<i64>(1, std::min<i64>(threads(), mn(n / 16384, k)));
    auto owner = [&](i64 lo) { return static_cast<size_t>(lo * T / mx(k, i64{1})); };
    std::vector<std::vector<std::pair<i64, i64>>> seen(static_cast<size_t>(k));  // (hi, row)
    std::vector<std::vector<std::array<double, 6>>> acc(static_cast<size_t>(T));  // by owner
    auto add = [&](const Crossing& e) {  // (only the owner of e.lo adds it)
        auto& near = seen[static_cast<size_t>(e.lo)];
        auto& mine = acc[owner(e.lo)];
        i64 at = -1;
        for (const auto& [h, r] : near)
            if (h == e.hi) { at = r; break; }
        if (at < 0) {
            at = static_cast<i64>(mine.size());
            near.emplace_back(e.hi, at);
            mine.push_back({0.0, 0.0, 0.0, 0.0, 0.0, 0.0});
        }
        auto& a = mine[static_cast<size_t>(at)];
        a[0] += e.len;
        a[1] += e.len * e.ang;
        a[2] += e.len * e.cc;
        a[3] += 1.0;
        a[4] += e.ang;
        a[5] += e.cc;
    };
    with_real(normals_, "normals", [&](const auto& nor) {
        if (nor.cols != 3 || nor.n < n) throw Mismatch("argument normals");
        nb::gil_scoped_release nogil;
        // f(e) for each crossing adjacency of rows r0..r1, in pair order
        auto crossings = [&](i64 r0, i64 r1, auto f) {
            for (i64 i = r0; i < r1; ++i)
                for (i64 x = indptr[i]; x < indptr[i + 1]; ++x) {
                    const i64 j = indices[x];
                    if (j <= i || labels[j] == labels[i]) continue;
                    double geo, cs;
                    bool concave;
                    pair_terms(pos.p, nor.p, i, j, geo, cs, concave);
                    f(Crossing{mn(labels[i], labels[j]), mx(labels[i], labels[j]),
                               0.5 * (shares[i] + shares[j]), std::acos(cs),
                               concave ? 1.0 : 0.0});
                }
        };
        if (T <= 1) {
            check_interrupt();
            crossings(0, n, add);
            return 0;
        }
        // lists[w * T + d]: row range w's crossings whose lo thread d adds
        std::vector<std::vector<Crossing>> lists(static_cast<size_t>(T * T));
        for (i64 c0 = 0; c0 < n; c0 += PAIR_SUMS_CHUNK) {
            check_interrupt();
            const i64 c1 = mn(n, c0 + PAIR_SUMS_CHUNK);
            on_threads(T, [&](i64 w) {
                for (i64 d = 0; d < T; ++d) lists[static_cast<size_t>(w * T + d)].clear();
                crossings(c0 + (c1 - c0) * w / T, c0 + (c1 - c0) * (w + 1) / T,
                          [&](const Crossing& e) {
                              lists[static_cast<size_t>(w * T) + owner(e.lo)].push_back(e);
                          });
            });
            on_threads(T, [&](i64 d) {
                for (i64 w = 0; w < T; ++w)
                    for (const auto& e : lists[static_cast<size_t>(w * T + d)]) add(e);
            });
        }
        return 0;
    });
    // the keys ascending: lo in order, each lo's hi sorted; thread d writes its lo's
    std::vector<i64> first(static_cast<size_t>(T) + 1, 0);
    for (i64 d = 0; d < T; ++d)
        first[static_cast<size_t>(d) + 1] = first[static_cast<size_t>(d)] +
            static_cast<i64>(acc[static_cast<size_t>(d)].size());
    Out<i64> keys;
    Out<double> sums;
    auto keys_a = fresh(first[static_cast<size_t>(T)], keys);
    auto sums_a = fresh(first[static_cast<size_t>(T)], sums, 6);
    {
        nb::gil_scoped_release nogil;
        on_threads(T, [&](i64 d) {
            i64 u = first[static_cast<size_t>(d)];
            const auto& mine = acc[static_cast<size_t>(d)];
            for (i64 lo = (k * d + T - 1) / T; lo < k && owner(lo) == static_cast<size_t>(d);
                 ++lo) {
                auto& near = seen[static_cast<size_t>(lo)];
                std::sort(near.begin(), near.end());
                for (const auto& [h, r] : near) {
                    keys[u] = lo * k + h;
                    for (int c = 0; c < 6; ++c) sums(u, c) = mine[static_cast<size_t>(r)][c];
                    ++u;
                }
            }
        });
    }
    return nb::make_tuple(keys_a, sums_a);
}

// borders.label_pairs: the distinct label pairs lo * k + hi of the rows of `pairs`,
// ascending (returned), and each row's place among them (inv): a counting sort on lo,
// each lo's distinct hi sorted.
nb::object label_pairs(nb::handle labels_, nb::handle pairs_, i64 k, nb::handle inv_) {
    In<i64> labels(labels_, "labels");
    Out<i64> inv(inv_, "inv");
    if (k < 0) throw Mismatch("argument k");
    std::vector<i64> key;
    with_index(pairs_, "pairs", [&](const auto& pairs) {
        if (pairs.cols != 2 || inv.n != pairs.n) throw Mismatch("argument pairs");
        check_range(pairs, 0, labels.n, "pairs");
        check_range(labels, 0, k, "labels");
        nb::gil_scoped_release nogil;
        const i64 m = pairs.n;
        std::vector<i64> lo(m), hi(m), start(k + 1, 0), order(m);
        for (i64 c = 0; c < m; ++c) {
            i64 a = labels[pairs(c, 0)], b = labels[pairs(c, 1)];
            if (a > b) std::swap(a, b);
            lo[c] = a;
            hi[c] = b;
            ++start[a + 1];
        }
        for (i64 s = 0; s < k; ++s) start[s + 1] += start[s];
        std::vector<i64> fill(start.begin(), start.end() - 1);
        for (i64 c = 0; c < m; ++c) order[fill[lo[c]]++] = c;
        std::vector<i64> stamp(k, -1), slot(k), seen;
        for (i64 s = 0; s < k; ++s) {
            seen.clear();
            for (i64 t = start[s]; t < start[s + 1]; ++t) {
                const i64 h = hi[order[t]];
                if (stamp[h] != s) {
                    stamp[h] = s;
                    seen.push_back(h);
                }
            }
            std::sort(seen.begin(), seen.end());
            for (i64 h : seen) {
                slot[h] = static_cast<i64>(key.size());
                key.push_back(s * k + h);
            }
            for (i64 t = start[s]; t < start[s + 1]; ++t) inv[order[t]] = slot[hi[order[t]]];
        }
        return 0;
    });
    Out<i64> out;
    auto out_a = fresh(static_cast<i64>(key.size()), out);
    std::copy(key.begin(), key.end(), out.p);
    return out_a;
}

void bind_borders(nb::module_& m) {
    m.def("crossing_pairs", &crossing_pairs,
          "The pairs (i, j), i < j, of a symmetric CSR layout whose labels differ, in pair "
          "order (rows ascending, then j).",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("labels"));
    m.def("label_pair_sums", &label_pair_sums,
          "The crossing adjacencies (crossing_pairs) summed per pair of labels.",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("labels"), nb::arg("k"),
          nb::arg("positions"), nb::arg("normals"), nb::arg("shares"));
    m.def("label_pairs", &label_pairs,
          "The distinct label pairs lo * k + hi (lo < hi, the labels of the two elements of "
          "each row of pairs), ascending, returned.",
          nb::arg("labels"), nb::arg("pairs"), nb::arg("k"), nb::arg("inv"));
}

}  // namespace sfk
