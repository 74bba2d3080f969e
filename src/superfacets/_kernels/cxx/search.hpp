// The label-correcting multi-source search over the circular bucket queue of the
// expansions (superfacets/_kernels/exact.py's search_buckets), shared by the Voronoi
// cells of coarse-to-fine and the exact assignment.
#pragma once

#include <atomic>

#include "common.hpp"

namespace sfk {

constexpr i64 QUEUE_FULL = -2;

// exact.search_buckets: spread the seeds' labels; with LEX an equal distance with a
// smaller label wins too, without only a strictly smaller distance
template <bool LEX, class W, class L, class QN, class QL>
i64 search_buckets(const i64* indptr, const i32* indices, const W* weights, double* dist,
                   L* label, const i64* seeds, i64 ns, i32* qface, double* qdist, QN* qnext,
                   i64* head, i64 qcap, i64 nb, QL* qlab, double inv_width) {
    const i64 bmask = nb - 1;
    i64 free = -1, bump = 0, live = 0, sp = 0, cur = 0;
    auto node = [&]() -> i64 {  // queue_node
        if (free >= 0) {
            i64 n = free;
            free = qnext[free];
            return n;
        }
        if (bump < qcap) return bump++;
        return -1;
    };
    auto push = [&](i64 n, i64 g, double nd) {  // queue_push
        i64 i = static_cast<i64>(nd * inv_width);
        if (i < cur) i = cur;
        i64 b = i & bmask;
        qface[n] = static_cast<i32>(g);
        qdist[n] = nd;
        qnext[n] = static_cast<QN>(head[b]);
        head[b] = n;
    };
    while (live > 0 || sp < ns) {
        if (live == 0) {
            i64 b0 = static_cast<i64>(dist[seeds[sp]] * inv_width);
            if (b0 > cur) cur = b0;
        }
        while (sp < ns) {
            i64 g = seeds[sp];
            if (static_cast<i64>(dist[g] * inv_width) > cur + nb - 1) break;
            ++sp;
            i64 n = node();
            if (n < 0) {
                for (i64 b = 0; b < nb; ++b) head[b] = -1;
                return QUEUE_FULL;
            }
            push(n, g, dist[g]);
            qlab[n] = static_cast<QL>(label[g]);
            ++live;
        }
        // queue_pop
        i64 b = cur & bmask;
        while (head[b] < 0) {
            ++cur;
            b = cur & bmask;
        }
        i64 popped = head[b];
        head[b] = qnext[popped];
        qnext[popped] = static_cast<QN>(free);
        free = popped;
        i64 f = qface[popped];
        double d = qdist[popped];
        i64 lf = qlab[free];
        --live;
        if (d != dist[f] || lf != static_cast<i64>(label[f])) continue;
        for (i64 e = indptr[f]; e < indptr[f + 1]; ++e) {
            i64 g = indices[e];
            double nd = d + static_cast<double>(weights[e]);
            if (nd < dist[g] || (LEX && nd == dist[g] && lf < static_cast<i64>(label[g]))) {
                dist[g] = nd;
                label[g] = static_cast<L>(lf);
                i64 n = node();
                if (n < 0) {
                    for (i64 bb = 0; bb < nb; ++bb) head[bb] = -1;
                    return QUEUE_FULL;
                }
                push(n, g, nd);
                qlab[n] = static_cast<QL>(lf);
                ++live;
            }
        }
    }
    return 0;
}


// The elements of one block of search_blocked, searched from its seeds on one thread: the
// search of search_buckets<true> kept within [lo, hi), each element it settles with an
// edge out of the block listed in `sent` (its pairs are offered across between rounds).
// The queue's nodes grow as needed (a block's search cannot run out).
template <class W, class L>
struct BlockSearch {
    std::vector<i64> qface, qnext;
    std::vector<double> qdist;
    std::vector<L> qlab;
    std::vector<i64> head, sent;

    explicit BlockSearch(i64 nb) : head(nb, -1) {}

    void run(const i64* indptr, const i32* indices, const W* weights, double* dist, L* label,
             const i64* seeds, i64 ns, i64 lo, i64 hi, double inv_width) {
        const i64 nb = static_cast<i64>(head.size()), bmask = nb - 1;
        i64 free = -1, live = 0, sp = 0, cur = 0;
        qface.clear();
        qnext.clear();
        qdist.clear();
        qlab.clear();
        auto push = [&](i64 g, double nd, L lab) {
            i64 n = free;
            if (n >= 0) {
                free = qnext[n];
            } else {
                n = static_cast<i64>(qface.size());
                qface.push_back(0);
                qnext.push_back(0);
                qdist.push_back(0.0);
                qlab.push_back(0);
            }
            i64 i = static_cast<i64>(nd * inv_width);
            if (i < cur) i = cur;
            i64 b = i & bmask;
            qface[n] = g;
            qdist[n] = nd;
            qlab[n] = lab;
            qnext[n] = head[b];
            head[b] = n;
            ++live;
        };
        while (live > 0 || sp < ns) {
            if (live == 0) {
                i64 b0 = static_cast<i64>(dist[seeds[sp]] * inv_width);
                if (b0 > cur) cur = b0;
            }
            while (sp < ns) {
                i64 g = seeds[sp];
                if (static_cast<i64>(dist[g] * inv_width) > cur + nb - 1) break;
                ++sp;
                push(g, dist[g], label[g]);
            }
            i64 b = cur & bmask;
            while (head[b] < 0) {
                ++cur;
                b = cur & bmask;
            }
            i64 popped = head[b];
            head[b] = qnext[popped];
            qnext[popped] = free;
            free = popped;
            --live;
            const i64 f = qface[popped];
            const double d = qdist[popped];
            const L lf = qlab[popped];
            if (d != dist[f] || lf != label[f]) continue;
            bool out = false;
            for (i64 e = indptr[f]; e < indptr[f + 1]; ++e) {
                i64 g = indices[e];
                if (g < lo || g >= hi) {
                    out = true;
                    continue;
                }
                double nd = d + static_cast<double>(weights[e]);
                if (nd < dist[g] || (nd == dist[g] && lf < label[g])) {
                    dist[g] = nd;
                    label[g] = lf;
                    push(g, nd, lf);
                }
            }
            if (out) sent.push_back(f);
        }
    }
};

// The search of search_buckets<true> from `seeds` (elements already holding their pair;
// any order), its result the same to the bit: every element reached ends with the least
// (distance, label) pair, lexicographically, over its neighbours' pairs plus the edge's
// weight, a fixed point that does not depend on the order of the work. Reached block by
// block: the elements in index ranges of `block` (neighbours in space are mostly near in
// index), each block searched from its seeds on one thread while its memory stays in
// cache; between rounds the pairs its settled elements offer across its edges are handed
// to the neighbouring blocks, whose improved elements seed their next round, until no
// block has seeds. (A million points, 2,500 centers: 1.0 s in one search, 0.39 s by
// blocks of 2^15 on one thread, 0.19 s on two.)
template <class W, class L>
void search_blocked(const i64* indptr, const i32* indices, const W* weights, double* dist,
                    L* label, i64 m, const i64* seeds, i64 ns, double inv_width, i64 nb,
                    i64 block = i64{1} << 15) {
    const i64 n_blocks = (m + block - 1) / block;
    std::vector<std::vector<i64>> pending(n_blocks);
    std::vector<char> queued(m, 0);
    for (i64 s = 0; s < ns; ++s) {
        i64 g = seeds[s];
        if (!queued[g]) {
            queued[g] = 1;
            pending[g / block].push_back(g);
        }
    }
    const int T = threads();
    std::vector<BlockSearch<W, L>> work;
    for (int t = 0; t < T; ++t) work.emplace_back(nb);
    std::vector<i64> active;
    while (true) {
        active.clear();
        for (i64 b = 0; b < n_blocks; ++b)
            if (!pending[b].empty()) active.push_back(b);
        if (active.empty()) break;
        std::atomic<i64> next{0};
        on_threads(std::min<i64>(T, static_cast<i64>(active.size())), [&](i64 t) {
            auto& w = work[t];
            for (i64 j = next++; j < static_cast<i64>(active.size()); j = next++) {
                const i64 b = active[j];
                auto& sd = pending[b];
                for (i64 g : sd) queued[g] = 0;
                std::stable_sort(sd.begin(), sd.end(),
                                 [&](i64 x, i64 y) { return dist[x] < dist[y]; });
                w.run(indptr, indices, weights, dist, label, sd.data(),
                      static_cast<i64>(sd.size()), b * block, std::min(m, (b + 1) * block),
                      inv_width);
                sd.clear();
            }
        });
        for (auto& w : work) {  // the pairs offered across the blocks' edges
            for (i64 f : w.sent) {
                const i64 bf = f / block;
                const double d = dist[f];
                const L lf = label[f];
                for (i64 e = indptr[f]; e < indptr[f + 1]; ++e) {
                    i64 g = indices[e];
                    if (g / block == bf) continue;
                    double nd = d + static_cast<double>(weights[e]);
                    if (nd < dist[g] || (nd == dist[g] && lf < label[g])) {
                        dist[g] = nd;
                        label[g] = lf;
                        if (!queued[g]) {
                            queued[g] = 1;
                            pending[g / block].push_back(g);
                        }
                    }
                }
            }
            w.sent.clear();
        }
    }
}

}  // namespace sfk
