// superfacets/_kernels/geometry.py: key_window, sort_keys, order_ties and rows_apart, the
// point graph's first steps (a cloud's Z-order, and the rows its distinct points give back).
#include "common.hpp"

namespace sfk {

namespace {

struct Pair {
    std::uint64_t key;
    i64 row;
};

// Stable LSD radix sort of a[0:n] by key, 11 bits a pass (a digit every key shares is
// skipped); tmp: room for n pairs. Returns the buffer that holds the result.
Pair* radix_sort(Pair* a, Pair* tmp, i64 n) {
    constexpr int BITS = 11, DIGITS = (64 + BITS - 1) / BITS, R = 1 << BITS;
    constexpr std::uint64_t MASK = R - 1;
    std::vector<i64> count(DIGITS * R, 0);
    for (i64 i = 0; i < n; ++i) {
        std::uint64_t k = a[i].key;
        for (int d = 0; d < DIGITS; ++d) ++count[d * R + ((k >> (BITS * d)) & MASK)];
    }
    Pair *src = a, *dst = tmp;
    for (int d = 0; d < DIGITS; ++d) {
        i64* c = count.data() + d * R;
        bool one = false;
        for (int b = 0; b < R; ++b) {
            if (c[b] == n) one = true;
        }
        if (one || n == 0) continue;  // every key has this digit: the order stands
        i64 at = 0;
        for (int b = 0; b < R; ++b) {
            i64 m = c[b];
            c[b] = at;
            at += m;
        }
        const int shift = BITS * d;
        for (i64 i = 0; i < n; ++i) dst[c[(src[i].key >> shift) & MASK]++] = src[i];
        std::swap(src, dst);
    }
    return src;
}

// The number of entries of a (length na) that come before place k of the stable merge
// of a and b (a first among equal keys).
i64 corank(i64 k, const Pair* a, i64 na, const Pair* b, i64 nb) {
    i64 lo = std::max<i64>(0, k - nb), hi = std::min(k, na);
    while (lo < hi) {
        i64 i = (lo + hi) / 2, j = k - i;
        if (j > 0 && i < na && b[j - 1].key >= a[i].key)
            lo = i + 1;
        else
            hi = i;
    }
    return lo;
}

}  // namespace

// geometry.sort_keys: order = the stable argsort of keys, sorted = keys[order]. Each
// thread sorts a run of the keys (radix), then the runs are merged two by two, each
// merge split over the threads at equal output places (the stable merge: the same
// order as one stable sort of all the keys).
void sort_keys(nb::handle keys_, nb::handle order_, nb::handle sorted_) {
    In<std::uint64_t> keys(keys_, "keys");
    Out<i64> order(order_, "order");
    Out<std::uint64_t> sorted(sorted_, "sorted");
    const i64 n = keys.n;
    if (order.n != n || sorted.n != n || keys.cols != 1) throw Mismatch("argument order");
    nb::gil_scoped_release nogil;
    const i64 T = std::max<i64>(1, std::min<i64>(threads(), n / (1 << 16)));
    std::vector<Pair> a(static_cast<size_t>(n)), b(static_cast<size_t>(n));
    std::vector<i64> cut(T + 1);
    for (i64 t = 0; t <= T; ++t) cut[t] = n * t / T;
    Pair *src = a.data(), *dst = b.data();
    on_threads(T, [&](i64 t) {  // each run sorted, left in src
        const i64 lo = cut[t], m = cut[t + 1] - lo;
        for (i64 i = lo; i < lo + m; ++i) src[i] = {keys[i], i};
        if (radix_sort(src + lo, dst + lo, m) != src + lo)
            std::copy(dst + lo, dst + lo + m, src + lo);
    });
    std::vector<i64> runs(cut);  // run r: src[runs[r]:runs[r + 1]]
    while (true) {
        const i64 nr = static_cast<i64>(runs.size()) - 1;
        const bool last = nr <= 2;  // the last merge writes the outputs
        std::vector<i64> next;
        for (i64 r = 0; r < nr; r += 2) {
            next.push_back(runs[r]);
            const i64 lo = runs[r];
            const i64 mid = r + 1 < nr ? runs[r + 1] : runs[r + 1];
            const i64 hi = r + 1 < nr ? runs[r + 2] : runs[r + 1];
            const Pair* x = src + lo;
            const Pair* y = src + mid;
            const i64 nx = mid - lo, ny = hi - mid, total = nx + ny;
            on_threads(T, [&](i64 t) {  // the stable merge of x and y, split at equal places
                const i64 k0 = total * t / T, k1 = total * (t + 1) / T;
                i64 i = corank(k0, x, nx, y, ny), j = k0 - i;
                const i64 ie = corank(k1, x, nx, y, ny), je = k1 - ie;
                for (i64 k = k0; k < k1; ++k) {
                    const Pair& p =
                        (j >= je || (i < ie && x[i].key <= y[j].key)) ? x[i++] : y[j++];
                    if (last) {
                        order[lo + k] = p.row;
                        sorted[lo + k] = p.key;
                    } else {
                        dst[lo + k] = p;
                    }
                }
            });
        }
        if (last) return;
        next.push_back(n);
        runs.swap(next);
        std::swap(src, dst);
    }
}

// geometry.rows_apart: the rows i (ascending) where index[i] < 0 or the three words of
// at[index[i]] differ from bits[i], into rows; their number, or -1 (rows[:cap] written,
// the first cap of them) when there are more than rows' length cap.
i64 rows_apart(nb::handle bits_, nb::handle at_, nb::handle index_, nb::handle rows_) {
    In<std::uint64_t> bits(bits_, "bits"), at(at_, "at");
    Out<i64> rows(rows_, "rows");
    if (bits.cols != 3 || at.cols != 3) throw Mismatch("argument bits");
    return with_index(index_, "index", [&](const auto& index) -> i64 {
        if (index.n != bits.n) throw Mismatch("argument index");
        check_range(index, std::numeric_limits<i64>::min(), at.n, "index");  // (-1: none)
        nb::gil_scoped_release nogil;
        const i64 n = bits.n, cap = rows.n;
        const i64 T = std::max<i64>(1, std::min<i64>(threads(), n / 4096));
        std::vector<std::vector<i64>> found(T);
        on_threads(T, [&](i64 t) {
            auto& f = found[t];
            for (i64 i = n * t / T; i < n * (t + 1) / T; ++i) {
                const i64 j = index[i];
                if (j < 0 || at(j, 0) != bits(i, 0) || at(j, 1) != bits(i, 1) ||
                    at(j, 2) != bits(i, 2)) {
                    f.push_back(i);
                    if (static_cast<i64>(f.size()) > cap) return;  // too many already
                }
            }
        });
        i64 m = 0;
        for (i64 t = 0; t < T; ++t) {
            for (i64 r : found[t]) {
                if (m == cap) return -1;
                rows[m++] = r;
            }
        }
        return m;
    });
}

// geometry.order_ties: each run of equal keys in `ordered` (the sorted Z-order windows)
// put in the order of the rows' whole keys (keys[row, 0..2]), then their positions,
// stably: equal in all, in the order given. Threads take the runs of their range.
void order_ties(nb::handle order_, nb::handle ordered_, nb::handle keys_, nb::handle p_) {
    Out<i64> order(order_, "order");
    In<std::uint64_t> ordered(ordered_, "ordered"), keys(keys_, "keys");
    In<double> p(p_, "p");
    const i64 n = order.n;
    if (ordered.n != n || keys.cols != 3 || p.cols != 3 || keys.n != p.n)
        throw Mismatch("argument keys");
    check_range(order, 0, keys.n, "order");
    nb::gil_scoped_release nogil;
    auto less = [&](i64 a, i64 b) {
        for (int w = 0; w < 3; ++w)
            if (keys(a, w) != keys(b, w)) return keys(a, w) < keys(b, w);
        for (int w = 0; w < 3; ++w)
            if (p(a, w) != p(b, w)) return p(a, w) < p(b, w);
        return false;
    };
    parallel_for(n, [&](i64 lo, i64 hi) {
        // the runs that start in [lo, hi)
        i64 a = lo;
        while (a > 0 && a < hi && ordered[a] == ordered[a - 1]) ++a;
        while (a < hi) {
            i64 b = a + 1;
            while (b < n && ordered[b] == ordered[a]) ++b;
            if (b - a > 1) std::stable_sort(order.p + a, order.p + b, less);
            a = b;
        }
    });
}

// geometry.key_window: bits start .. start + 63 of each row's 189-bit key string (63 bits
// a word, the first bit the highest; zeros past its end), as one uint64, on threads
void key_window(nb::handle keys_, i64 start, nb::handle out_) {
    In<std::uint64_t> keys(keys_, "keys");
    Out<std::uint64_t> out(out_, "out");
    if (keys.cols != 3 || out.n != keys.n || start < 0 || start >= 189)
        throw Mismatch("argument keys");
    nb::gil_scoped_release nogil;
    const i64 j = start / 63, o = start % 63;
    const std::uint64_t mask = (std::uint64_t{1} << (63 - o)) - 1;
    parallel_for(keys.n, [&](i64 r0, i64 r1) {
        for (i64 r = r0; r < r1; ++r) {
            std::uint64_t x = (keys(r, j) & mask) << (o + 1);
            if (j < 2) x |= keys(r, j + 1) >> (62 - o);
            out[r] = x;
        }
    });
}

void bind_order(nb::module_& m) {
    m.def("key_window", &key_window);
    m.def("sort_keys", &sort_keys);
    m.def("rows_apart", &rows_apart);
    m.def("order_ties", &order_ties);
}

}  // namespace sfk
