// The label-correcting multi-source search over the circular bucket queue of the
// expansions (superfacets/_kernels/exact.py's search_buckets), shared by the Voronoi
// cells of coarse-to-fine and the exact assignment.
#pragma once

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


}  // namespace sfk
