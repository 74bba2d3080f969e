// The label-correcting multi-source search of tests/oracle/exact.py's
// search_buckets (lexicographic pairs), by blocks of elements on threads: shared by the
// Voronoi cells of coarse-to-fine and the exact assignment.
#pragma once

#include <atomic>

#include "common.hpp"

namespace sfk {

// The elements of one block of a BlockedSearch, searched from its seeds on one thread: the
// search of exact.search_buckets (lexicographic) kept within [lo, hi), each element it settles with an
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
        Poll poll;
        while (live > 0 || sp < ns) {
            poll.tick();
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
            if (head[b] >= 0) {  // the next pop's row, fetched while this one is relaxed
                i64 r = indptr[qface[head[b]]];
                __builtin_prefetch(indices + r);
                __builtin_prefetch(weights + r);
            }
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

// The search of exact.search_buckets (lexicographic) from seeds (elements already holding
// their pair; any order), its result the same to the bit: every element reached ends with
// the least (distance, label) pair, lexicographically, over its neighbours' pairs plus the
// edge's weight, a fixed point that does not depend on the order of the work. Reached
// block by block: the elements in index ranges of 2^15 (neighbours in space are mostly
// near in index), each block searched from its seeds on one thread while its memory stays
// in cache; between rounds the pairs its settled elements offer across its edges are
// handed to the neighbouring blocks, whose improved elements seed their next round, until
// no block has seeds. (A million points, 2,500 centers: 1.0 s in one search, 0.39 s by
// blocks of 2^15 on one thread, 0.19 s on two.) One object serves many searches over the
// same arrays (the orphans' one by one): its marks and lists are left empty by each.
template <class W, class L>
class BlockedSearch {
  public:
    BlockedSearch(const i64* indptr, const i32* indices, const W* weights, double* dist,
                  L* label, i64 m, double inv_width, i64 nb)
        : indptr_(indptr), indices_(indices), weights_(weights), dist_(dist), label_(label),
          m_(m), inv_width_(inv_width), queued_(m, false) {
        // blocks only where they are patches: where a quarter or more of the edges (of a
        // sample of elements) cross between blocks, as on a subdivided mesh's vertices
        // (new ones listed after the old), every round would hand most of the work over:
        // one block, one search. The sample: 1,024 runs of 64 consecutive elements spread
        // evenly (every element below 65,536), whose rows are read in order (a strided
        // sample's were each a cache miss)
        i64 edges = 0, crossing = 0;
        const i64 step = std::max<i64>(kRun, m >> 10);
        for (i64 f0 = 0; f0 < m; f0 += step)
            for (i64 f = f0; f < std::min(m, f0 + kRun); ++f)
                for (i64 e = indptr[f]; e < indptr[f + 1]; ++e, ++edges)
                    crossing += (indices[e] >> kShift) != (f >> kShift);
        shift_ = 4 * crossing < edges ? kShift : 62;  // (62: every element in block 0)
        pending_.resize(std::max<i64>(1, (m + (i64{1} << shift_) - 1) >> shift_));
        for (int t = 0; t < threads(); ++t) work_.emplace_back(nb);
    }

    void run(const i64* seeds, i64 ns) {
        for (i64 s = 0; s < ns; ++s) wait(seeds[s]);
        const i64 n_blocks = static_cast<i64>(pending_.size());
        std::vector<i64> active;
        while (true) {
            active.clear();
            for (i64 b = 0; b < n_blocks; ++b)
                if (!pending_[b].empty()) active.push_back(b);
            if (active.empty()) break;
            std::atomic<i64> next{0};
            const i64 n_active = static_cast<i64>(active.size());
            on_threads(std::min<i64>(static_cast<i64>(work_.size()), n_active), [&](i64 t) {
                for (i64 j = next++; j < n_active; j = next++) search(active[j], work_[t]);
            });
            for (auto& w : work_) {  // the pairs offered across the blocks' edges
                for (i64 f : w.sent) offer(f);
                w.sent.clear();
            }
        }
    }

  private:
    void wait(i64 g) {  // g seeds its block's next round
        if (!queued_[g]) {
            queued_[g] = true;
            pending_[g >> shift_].push_back(g);
        }
    }

    void search(i64 b, BlockSearch<W, L>& w) {
        auto& sd = pending_[b];
        for (i64 g : sd) queued_[g] = false;  // (a block's bits share no word with another's)
        std::stable_sort(sd.begin(), sd.end(),
                         [&](i64 x, i64 y) { return dist_[x] < dist_[y]; });
        w.run(indptr_, indices_, weights_, dist_, label_, sd.data(), static_cast<i64>(sd.size()),
              b << shift_, std::min(m_, (b + 1) << shift_), inv_width_);
        sd.clear();
    }

    void offer(i64 f) {  // f's pair over its edges out of its block
        const i64 bf = f >> shift_;
        const double d = dist_[f];
        const L lf = label_[f];
        for (i64 e = indptr_[f]; e < indptr_[f + 1]; ++e) {
            const i64 g = indices_[e];
            if ((g >> shift_) == bf) continue;
            const double nd = d + static_cast<double>(weights_[e]);
            if (nd < dist_[g] || (nd == dist_[g] && lf < label_[g])) {
                dist_[g] = nd;
                label_[g] = lf;
                wait(g);
            }
        }
    }

    const i64* indptr_;
    const i32* indices_;
    const W* weights_;
    double* dist_;
    L* label_;
    i64 m_;
    // elements per block: in a core's cache; a multiple of 64, so that no two blocks'
    // marks share a word of queued_ (or all of them, in one block)
    static constexpr int kShift = 15;
    static constexpr i64 kRun = 64;  // consecutive elements per run of the blocks' sample
    // (a shift, not a division: the sample's divisions showed in every search)
    int shift_ = kShift;
    double inv_width_;
    std::vector<std::vector<i64>> pending_;
    std::vector<bool> queued_;  // (a bit per element)
    std::vector<BlockSearch<W, L>> work_;
};

}  // namespace sfk
