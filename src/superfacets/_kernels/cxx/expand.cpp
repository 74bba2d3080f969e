// Bounded expansions and the merging of their records (reference, bit for bit:
// tests/oracle/expand.py; the flood: tests/oracle/flood.py), the same operations in the
// same order.
#include <cmath>
#include <memory>
#include "common.hpp"

namespace sfk {

namespace {

constexpr int MERGE = 0, UNLABELLED = 1, RECORD = 2;
constexpr i64 RECORD_FULL = -1, QUEUE_FULL = -2;

template <class W>
struct Graph {
    const i64* indptr;
    const i32* indices;
    const W* weights;  // float64 (faces) or float32 (points)
    const double* centroids;
};

struct Queue {
    i32* qface;
    double* qdist;
    i32* qnext;
    i64* head;
    i64 qcap, nb;
};

// An expansion's scratch distances: -distance for each element it reached (-0.0 for
// its source), +0.0 for every other element, as a dense array of one entry per element
// would hold them (the argument `local`, which the reference kernels use), but kept for
// the reached elements only (open addressing by element id): a thread's scratch is the
// size of its largest expansion, not of the input (8 bytes an element per thread).
struct Scratch {
    std::vector<i32> key;  // -1: an empty slot
    std::vector<double> val;
    std::vector<i64> used;  // the slots taken, emptied by clear()
    i64 mask = 0;
    int shift = 0;
    Scratch() { make(i64(1) << 12); }
    void make(i64 cap) {
        key.assign(cap, -1);
        val.assign(cap, 0.0);
        used.clear();
        mask = cap - 1;
        shift = 64 - __builtin_ctzll(static_cast<unsigned long long>(cap));
    }
    i64 slot(i64 g) const {  // g's slot, or the empty one where it would go
        i64 h = static_cast<i64>((static_cast<std::uint64_t>(g) * 0x9E3779B97F4A7C15ull) >> shift);
        while (key[h] >= 0 && key[h] != g) h = (h + 1) & mask;
        return h;
    }
    double at(i64 h, i64 g) const { return key[h] == g ? val[h] : 0.0; }
    double get(i64 g) const { return at(slot(g), g); }
    void put(i64 h, i64 g, double v) {  // (h: slot(g), nothing put since)
        if (key[h] != g) {
            key[h] = static_cast<i32>(g);
            used.push_back(h);
        }
        val[h] = v;
        if (2 * static_cast<i64>(used.size()) > mask) grow();
    }
    void grow() {
        std::vector<std::pair<i32, double>> kept;
        kept.reserve(used.size());
        for (i64 h : used) kept.emplace_back(key[h], val[h]);
        make(2 * (mask + 1));
        for (const auto& kv : kept) put(slot(kv.first), kv.first, kv.second);
    }
    void clear() {
        for (i64 h : used) key[h] = -1;
        used.clear();
    }
};

template <class W>
struct Work {
    Graph<W> g;
    Queue q;
    std::shared_ptr<Scratch> local;
    double inv_width;
    const double* wscale;
    i64 n_wscale;
    double window(double window_r2, i64 f) const {
        return n_wscale > 0 ? window_r2 * wscale[f] : window_r2;
    }
};

Queue queue_of(nb::handle t) {
    auto tup = nb::borrow<nb::tuple>(t);
    if (!nb::isinstance<nb::tuple>(t) || tup.size() != 4) throw Mismatch("argument queue");
    Out<i32> qface(tup[0], "qface"), qnext(tup[2], "qnext");
    Out<double> qdist(tup[1], "qdist");
    Out<i64> head(tup[3], "head");
    // (a bucket ring of a power of two of empty buckets, a node pool of equal arrays)
    if (head.n < 1 || (head.n & (head.n - 1)) || qdist.n != qface.n || qnext.n != qface.n ||
        qface.n < 1)
        throw OutOfRange("argument queue: not an empty queue");
    for (i64 b = 0; b < head.n; ++b)
        if (head[b] != -1) throw OutOfRange("argument queue: not an empty queue");
    return Queue{qface.p, qdist.p, qnext.p, head.p, qface.n, head.n};
}

// expand.expand; dist / label / vis_dist may be null (RECORD mode, no distances kept)
template <class W>
i64 expand(const Work<W>& w, i64 src, i64 lab, double window_r2, double* dist, i32* label,
           int mode, i32* vis_face, double* vis_dist, i64 pos, i64 lim) {
    const Queue& q = w.q;
    const i64 bmask = q.nb - 1;
    const double* c = w.g.centroids;
    Scratch& local = *w.local;
    const double cx = c[3 * src], cy = c[3 * src + 1], cz = c[3 * src + 2];
    const bool only_unlabelled = mode == UNLABELLED;
    const i64 start = pos;
    if (pos >= lim) return RECORD_FULL;
    local.put(local.slot(src), src, -0.0);  // reached: -distance (+0.0: not reached)
    vis_face[pos++] = static_cast<i32>(src);
    q.qface[0] = static_cast<i32>(src);
    q.qdist[0] = 0.0;
    q.qnext[0] = -1;
    q.head[0] = 0;
    i64 free = -1, bump = 1, live = 1, cur = 0, status = 0;
    Poll poll;
    while (live > 0) {
        poll.tick();
        // queue_pop
        i64 b = cur & bmask;
        while (q.head[b] < 0) {
            ++cur;
            b = cur & bmask;
        }
        i64 node = q.head[b];
        q.head[b] = q.qnext[node];
        q.qnext[node] = static_cast<i32>(free);
        i64 f = q.qface[node];
        double d = q.qdist[node];
        free = node;
        --live;
        {  // the next pop's row, fetched while this one is relaxed (its index was
           // fetched when it was queued)
            i64 nx = q.head[b];
            if (nx >= 0) {
                i64 f2 = q.qface[nx];
                i64 r = w.g.indptr[f2];
                __builtin_prefetch(w.g.indices + r);
                __builtin_prefetch(w.g.weights + r);
            }
        }
        if (d > -local.get(f)) continue;
        for (i64 e = w.g.indptr[f]; e < w.g.indptr[f + 1]; ++e) {
            i64 g = w.g.indices[e];
            double nd = d + static_cast<double>(w.g.weights[e]);
            const i64 hg = local.slot(g);
            double lg = local.at(hg, g);
            if (!std::signbit(lg)) {
                double dx = c[3 * g] - cx, dy = c[3 * g + 1] - cy, dz = c[3 * g + 2] - cz;
                if (dx * dx + dy * dy + dz * dz > window_r2 || (only_unlabelled && label[g] >= 0))
                    continue;
                if (pos >= lim) {
                    status = RECORD_FULL;
                    break;
                }
                vis_face[pos++] = static_cast<i32>(g);
            } else if (!(nd < -lg)) {
                continue;
            }
            local.put(hg, g, -nd);
            // queue_node
            i64 n;
            if (free >= 0) {
                n = free;
                free = q.qnext[free];
            } else if (bump < q.qcap) {
                n = bump++;
            } else {
                status = QUEUE_FULL;
                break;
            }
            __builtin_prefetch(w.g.indptr + g);
            // queue_push
            i64 i = static_cast<i64>(nd * w.inv_width);
            if (i < cur) i = cur;
            i64 bk = i & bmask;
            q.qface[n] = static_cast<i32>(g);
            q.qdist[n] = nd;
            q.qnext[n] = static_cast<i32>(q.head[bk]);
            q.head[bk] = n;
            ++live;
        }
        if (status != 0) {
            for (i64 bb = 0; bb < q.nb; ++bb) q.head[bb] = -1;
            local.clear();
            return status;
        }
    }
    if (vis_dist)
        for (i64 j = start; j < pos; ++j) vis_dist[j] = -local.get(vis_face[j]);
    if (mode == MERGE) {
        for (i64 j = start; j < pos; ++j) {
            i64 f = vis_face[j];
            double d = -local.get(f);
            if (d < dist[f]) {
                dist[f] = d;
                label[f] = static_cast<i32>(lab);
            }
        }
    } else if (only_unlabelled) {
        for (i64 j = start; j < pos; ++j) label[vis_face[j]] = static_cast<i32>(lab);
    }
    local.clear();
    return pos;
}

inline void merge_segment(i64 a, i64 n, i64 s, const i32* rec_face, const double* rec_dist,
                          double* dist, i32* label) {
    for (i64 e = a; e < a + n; ++e) {
        i64 f = rec_face[e];
        double d = rec_dist[e];
        if (d < dist[f] || (d == dist[f] && s < label[f])) {
            dist[f] = d;
            label[f] = static_cast<i32>(s);
        }
    }
}

// An element graph an expansion stays inside: n rows (n centroids), each entry a
// weight. (The argument `local`, the reference kernels' dense scratch, may have any
// length here: the compiled expansion keeps its own, a Scratch.)
template <class W>
void check_graph(const In<i64>& indptr, const In<i32>& indices, const In<W>& weights,
                 const In<double>& centroids) {
    const i64 n = check_csr(indptr, indices, centroids.n, centroids.n);
    check_rows(weights, indptr[n], "weights");
}

// Records pos .. lim of an expansion's elements in rec (and rec_dist, where given)
inline void check_records(i64 pos, i64 lim, i64 n_rec, i64 n_dist) {
    if (pos < 0 || lim < pos || lim > n_rec || (n_dist >= 0 && lim > n_dist))
        throw OutOfRange("arguments pos, lim: records past their arrays");
}

// Each segment s (of labs) within the records rec_face, each record an element of n
template <class L>
void check_segments(const L& labs, const In<i64>& seg_start, const In<i64>& seg_len,
                    const In<i32>& rec_face, i64 n) {
    check_rows(seg_len, seg_start.n, "seg_len", true);
    check_range(labs, 0, seg_start.n, "labs");
    for (i64 i = 0; i < labs.n; ++i) {
        const i64 s = labs[i], a = seg_start[s], m = seg_len[s];
        if (a < 0 || m < 0 || a > rec_face.n - m)
            throw OutOfRange("arguments seg_start, seg_len: a segment past the records");
        check_range(In<i32>(rec_face.p + a, m), 0, n, "rec_face");
    }
}

template <class W>
Work<W> work_of(nb::handle indptr_, nb::handle indices_, nb::handle weights_,
                nb::handle centroids_, nb::handle local_, nb::handle queue_, double inv_width,
                nb::handle wscale_) {
    In<i64> indptr(indptr_, "indptr");
    In<i32> indices(indices_, "indices");
    In<W> weights(weights_, "weights");
    In<double> centroids(centroids_, "centroids"), wscale(wscale_, "wscale");
    Out<double> local(local_, "local");
    if (centroids.cols != 3) throw Mismatch("argument centroids");
    check_graph(indptr, indices, weights, centroids);
    if (wscale.n) check_rows(wscale, centroids.n, "wscale");
    return Work<W>{Graph<W>{indptr.p, indices.p, weights.p, centroids.p}, queue_of(queue_),
                   std::make_shared<Scratch>(), inv_width, wscale.p, wscale.n};
}

}  // namespace

template <class W>
i64 classify_bounded_t(nb::handle indptr, nb::handle indices, nb::handle weights,
                       nb::handle centroids, nb::handle centers_, i64 n_centers,
                       double window_r2, nb::handle dist_, nb::handle label_, nb::handle local,
                       nb::handle queue, double inv_width, nb::handle vis_, nb::handle wscale) {
    auto w = work_of<W>(indptr, indices, weights, centroids, local, queue, inv_width, wscale);
    Out<i64> centers(centers_, "centers");
    Out<double> dist(dist_, "dist");
    Out<i32> label(label_, "label"), vis(vis_, "vis");
    const i64 n = size_of(centroids) / 3;
    check_rows(label, n, "label", true);
    check_rows(dist, n, "dist", true);
    check_range(centers, 0, n, "centers", n_centers);
    if (centers.n < n) throw OutOfRange("argument centers: no room for the orphans' centers");
    nb::gil_scoped_release nogil;
    const i64 m = label.n, lim = vis.n;
    for (i64 f = 0; f < m; ++f) {
        dist[f] = INF;
        label[f] = -1;
    }
    for (i64 s = 0; s < n_centers; ++s) {
        i64 st = expand(w, centers[s], s, w.window(window_r2, centers[s]), dist.p, label.p, MERGE,
                        vis.p, nullptr, 0, lim);
        if (st < 0) return st;
    }
    i64 k = n_centers;
    for (i64 f = 0; f < m; ++f) {
        if (label[f] < 0) {
            centers[k] = f;
            i64 st = expand(w, f, k, w.window(window_r2, f), dist.p, label.p, MERGE, vis.p,
                            nullptr, 0, lim);
            if (st < 0) return st;
            ++k;
        }
    }
    return k;
}

template <class W>
i64 expand_many_t(nb::handle indptr, nb::handle indices, nb::handle weights,
                  nb::handle centroids, nb::handle srcs_, nb::handle labs_, double window_r2,
                  nb::handle local, nb::handle queue, double inv_width, nb::handle rec_face_,
                  nb::handle rec_dist_, i64 pos, i64 lim, nb::handle out_start_,
                  nb::handle out_len_, nb::handle dist_, nb::handle label_, nb::handle wscale) {
    auto w = work_of<W>(indptr, indices, weights, centroids, local, queue, inv_width, wscale);
    In<i64> srcs(srcs_, "srcs"), labs(labs_, "labs");
    Out<i32> rec_face(rec_face_, "rec_face"), label(label_, "label");
    Out<double> rec_dist(rec_dist_, "rec_dist"), dist(dist_, "dist");
    Out<i64> out_start(out_start_, "out_start"), out_len(out_len_, "out_len");
    const i64 n = size_of(centroids) / 3;
    check_range(srcs, 0, n, "srcs");
    check_rows(out_start, srcs.n, "out_start");
    check_rows(out_len, srcs.n, "out_len");
    check_records(pos, lim, rec_face.n, rec_dist.n);
    if (dist.n > 0) {
        check_rows(dist, n, "dist", true);
        check_rows(label, n, "label", true);
        check_rows(labs, srcs.n, "labs");
    }
    nb::gil_scoped_release nogil;
    for (i64 i = 0; i < srcs.n; ++i) {
        out_start[i] = pos;
        i64 p = expand(w, srcs[i], 0, w.window(window_r2, srcs[i]), nullptr, nullptr, RECORD,
                       rec_face.p, rec_dist.p, pos, lim);
        if (p < 0) return p;
        out_len[i] = p - pos;
        if (dist.n > 0) merge_segment(pos, p - pos, labs[i], rec_face.p, rec_dist.p, dist.p, label.p);
        pos = p;
    }
    return pos;
}

void merge_some(nb::handle labs_, nb::handle seg_start_, nb::handle seg_len_,
                nb::handle rec_face_, nb::handle rec_dist_, nb::handle dist_, nb::handle label_) {
    In<i64> labs(labs_, "labs"), seg_start(seg_start_, "seg_start"), seg_len(seg_len_, "seg_len");
    In<i32> rec_face(rec_face_, "rec_face");
    In<double> rec_dist(rec_dist_, "rec_dist");
    Out<double> dist(dist_, "dist");
    Out<i32> label(label_, "label");
    check_rows(label, dist.n, "label", true);
    check_rows(rec_dist, rec_face.n, "rec_dist");
    check_segments(labs, seg_start, seg_len, rec_face, dist.n);
    nb::gil_scoped_release nogil;
    for (i64 i = 0; i < labs.n; ++i) {
        i64 s = labs[i];
        merge_segment(seg_start[s], seg_len[s], s, rec_face.p, rec_dist.p, dist.p, label.p);
    }
}

void unset_owned(nb::handle labs_, nb::handle seg_start_, nb::handle seg_len_,
                 nb::handle rec_face_, nb::handle dist_, nb::handle label_) {
    In<i64> labs(labs_, "labs"), seg_start(seg_start_, "seg_start"), seg_len(seg_len_, "seg_len");
    In<i32> rec_face(rec_face_, "rec_face");
    Out<double> dist(dist_, "dist");
    Out<i32> label(label_, "label");
    check_rows(label, dist.n, "label", true);
    check_segments(labs, seg_start, seg_len, rec_face, dist.n);
    nb::gil_scoped_release nogil;
    for (i64 i = 0; i < labs.n; ++i) {
        i64 s = labs[i];
        for (i64 e = seg_start[s]; e < seg_start[s] + seg_len[s]; ++e) {
            i64 f = rec_face[e];
            if (label[f] == s) {
                dist[f] = INF;
                label[f] = -1;
            }
        }
    }
}

void reset_labels(nb::handle dist_, nb::handle label_) {
    Out<double> dist(dist_, "dist");
    Out<i32> label(label_, "label");
    check_rows(label, dist.n, "label");
    nb::gil_scoped_release nogil;
    for (i64 f = 0; f < dist.n; ++f) {
        dist[f] = INF;
        label[f] = -1;
    }
}

template <class W>
nb::tuple seed_orphans_t(nb::handle indptr, nb::handle indices, nb::handle weights,
                         nb::handle centroids, nb::handle centers_, i64 n_centers,
                         double window_r2, nb::handle dist_, nb::handle label_, nb::handle local,
                         nb::handle queue, double inv_width, nb::handle rec_face_,
                         nb::handle rec_dist_, i64 pos, i64 lim, nb::handle seg_start_,
                         nb::handle seg_len_, nb::handle wscale) {
    auto w = work_of<W>(indptr, indices, weights, centroids, local, queue, inv_width, wscale);
    Out<i64> centers(centers_, "centers"), seg_start(seg_start_, "seg_start"),
        seg_len(seg_len_, "seg_len");
    Out<double> dist(dist_, "dist"), rec_dist(rec_dist_, "rec_dist");
    Out<i32> label(label_, "label"), rec_face(rec_face_, "rec_face");
    const i64 n = size_of(centroids) / 3;
    check_rows(label, n, "label", true);
    check_rows(dist, n, "dist", true);
    check_records(pos, lim, rec_face.n, rec_dist.n);
    if (n_centers < 0) throw OutOfRange("argument n_centers");
    i64 orphans = 0;
    for (i64 f = 0; f < n; ++f) orphans += label[f] < 0;
    for (auto* x : {&centers, &seg_start, &seg_len})
        check_rows(*x, n_centers + orphans, "centers, seg_start, seg_len");
    i64 k = n_centers, status = pos;
    {
        nb::gil_scoped_release nogil;
        for (i64 f = 0; f < label.n; ++f) {
            if (label[f] < 0) {
                centers[k] = f;
                seg_start[k] = pos;
                i64 p = expand(w, f, k, w.window(window_r2, f), dist.p, label.p, MERGE,
                               rec_face.p, rec_dist.p, pos, lim);
                if (p < 0) {
                    status = p;
                    break;
                }
                seg_len[k] = p - pos;
                pos = p;
                ++k;
            }
        }
        if (status >= 0) status = pos;
    }
    return nb::make_tuple(status, k);
}

i64 compact_records(nb::handle order_, nb::handle seg_start_, nb::handle seg_len_,
                    nb::handle rec_face_, nb::handle rec_dist_) {
    In<i64> order(order_, "order"), seg_len(seg_len_, "seg_len");
    Out<i64> seg_start(seg_start_, "seg_start");
    Out<i32> rec_face(rec_face_, "rec_face");
    Out<double> rec_dist(rec_dist_, "rec_dist");
    check_rows(seg_len, seg_start.n, "seg_len", true);
    check_range(order, 0, seg_start.n, "order");
    for (i64 j = 0; j < order.n; ++j) {
        const i64 a = seg_start[order[j]], m = seg_len[order[j]];
        if (a < 0 || m < 0 || a > mn(rec_face.n, rec_dist.n) - m)
            throw OutOfRange("arguments seg_start, seg_len: a segment past the records");
    }
    nb::gil_scoped_release nogil;
    i64 w = 0;
    for (i64 j = 0; j < order.n; ++j) {
        i64 i = order[j], a = seg_start[i], n = seg_len[i];
        if (a != w)
            for (i64 e = 0; e < n; ++e) {
                rec_face[w + e] = rec_face[a + e];
                rec_dist[w + e] = rec_dist[a + e];
            }
        seg_start[i] = w;
        w += n;
    }
    return w;
}

// flood.flood: the flood initialization (the authors' implementation). Elements are
// visited in `order`; each one still unlabelled starts a new region, grown by a bounded
// expansion that claims only unlabelled elements. Returns the number of regions, or
// the negative status of expand where the queue or the visit buffer `vis` was too small.
template <class W>
i64 flood_t(nb::handle indptr_, nb::handle indices_, nb::handle weights_, nb::handle centroids_,
            nb::handle order_, double window_r2, nb::handle label_, nb::handle local_,
            nb::handle queue_, double inv_width, nb::handle vis_) {
    In<i64> indptr(indptr_, "indptr"), order(order_, "order");
    In<i32> indices(indices_, "indices");
    In<W> weights(weights_, "weights");
    In<double> centroids(centroids_, "centroids");
    Out<double> local(local_, "local");
    Out<i64> label(label_, "label");
    Out<i32> vis(vis_, "vis");
    if (centroids.cols != 3) throw Mismatch("argument centroids");
    check_graph(indptr, indices, weights, centroids);
    check_rows(label, centroids.n, "label", true);
    check_range(order, 0, centroids.n, "order");
    const Work<W> w{Graph<W>{indptr.p, indices.p, weights.p, centroids.p}, queue_of(queue_),
                    std::make_shared<Scratch>(), inv_width, nullptr, 0};
    nb::gil_scoped_release nogil;
    const i64 m = label.n;
    std::vector<i32> lab(m, -1);  // (expand's labels are int32; the regions fit)
    i64 n = 0;
    for (i64 i = 0; i < order.n; ++i) {
        const i64 f = order[i];
        if (lab[f] < 0) {
            i64 st = expand(w, f, n, window_r2, nullptr, lab.data(), UNLABELLED, vis.p, nullptr,
                            0, vis.n);
            if (st < 0) return st;
            ++n;
        }
    }
    for (i64 f = 0; f < m; ++f) label[f] = lab[f];
    return n;
}

// float64 weights (faces) or float32 (points): the same sums, each weight widened first
template <class... A>
i64 classify_bounded(nb::handle indptr, nb::handle indices, nb::handle weights, A... rest) {
    if (matches<float>(weights)) return classify_bounded_t<float>(indptr, indices, weights, rest...);
    return classify_bounded_t<double>(indptr, indices, weights, rest...);
}

template <class... A>
i64 flood(nb::handle indptr, nb::handle indices, nb::handle weights, A... rest) {
    if (matches<float>(weights)) return flood_t<float>(indptr, indices, weights, rest...);
    return flood_t<double>(indptr, indices, weights, rest...);
}

template <class... A>
i64 expand_many(nb::handle indptr, nb::handle indices, nb::handle weights, A... rest) {
    if (matches<float>(weights)) return expand_many_t<float>(indptr, indices, weights, rest...);
    return expand_many_t<double>(indptr, indices, weights, rest...);
}

template <class... A>
nb::tuple seed_orphans(nb::handle indptr, nb::handle indices, nb::handle weights, A... rest) {
    if (matches<float>(weights)) return seed_orphans_t<float>(indptr, indices, weights, rest...);
    return seed_orphans_t<double>(indptr, indices, weights, rest...);
}

void bind_expand(nb::module_& m) {
    m.def("classify_bounded", &classify_bounded<nb::handle, nb::handle, i64, double, nb::handle, nb::handle,
                            nb::handle, nb::handle, double, nb::handle, nb::handle>,
          "Classification step of the paper (section 3.1) with orphan re-seeding.",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("weights"), nb::arg("centroids"),
          nb::arg("centers"), nb::arg("n_centers"), nb::arg("window_r2"), nb::arg("dist"),
          nb::arg("label"), nb::arg("local"), nb::arg("queue"), nb::arg("inv_width"),
          nb::arg("vis"), nb::arg("wscale"));
    m.def("expand_many", &expand_many<nb::handle, nb::handle, nb::handle, double, nb::handle, nb::handle,
                       double, nb::handle, nb::handle, i64, i64, nb::handle, nb::handle,
                       nb::handle, nb::handle, nb::handle>,
          "Record-only expansions (RECORD) of the faces srcs, each merged right after (while in"
          " cache) into dist/label with label labs[i] by the lexicographic ....",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("weights"), nb::arg("centroids"),
          nb::arg("srcs"), nb::arg("labs"), nb::arg("window_r2"), nb::arg("local"),
          nb::arg("queue"), nb::arg("inv_width"), nb::arg("rec_face"), nb::arg("rec_dist"),
          nb::arg("pos"), nb::arg("lim"), nb::arg("out_start"), nb::arg("out_len"),
          nb::arg("dist"), nb::arg("label"), nb::arg("wscale"));
    m.def("flood", &flood<nb::handle, nb::handle, double, nb::handle, nb::handle, nb::handle,
                          double, nb::handle>,
          "Flood initialization (authors' implementation).",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("weights"), nb::arg("centroids"),
          nb::arg("order"), nb::arg("window_r2"), nb::arg("label"), nb::arg("local"),
          nb::arg("queue"), nb::arg("inv_width"), nb::arg("vis"));
    m.def("merge_some", &merge_some,
          "Merge the records of the centers labs into dist/label.",
          nb::arg("labs"), nb::arg("seg_start"), nb::arg("seg_len"), nb::arg("rec_face"),
          nb::arg("rec_dist"), nb::arg("dist"), nb::arg("label"));
    m.def("reset_labels", &reset_labels,
          "Dist = inf, label = -1 (records have finite distances, so the label of an unreached "
          "face never takes part in a comparison).",
          nb::arg("dist"), nb::arg("label"));
    m.def("unset_owned", &unset_owned,
          "Unlabel (dist = inf, label = -1) every face that the record of center s (for s in "
          "labs) labels s.",
          nb::arg("labs"), nb::arg("seg_start"), nb::arg("seg_len"), nb::arg("rec_face"),
          nb::arg("dist"), nb::arg("label"));
    m.def("seed_orphans", &seed_orphans<nb::handle, nb::handle, i64, double, nb::handle, nb::handle, nb::handle,
                        nb::handle, double, nb::handle, nb::handle, i64, i64, nb::handle,
                        nb::handle, nb::handle>,
          "Orphan re-seeding of classify_bounded, recording the expansions.",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("weights"), nb::arg("centroids"),
          nb::arg("centers"), nb::arg("n_centers"), nb::arg("window_r2"), nb::arg("dist"),
          nb::arg("label"), nb::arg("local"), nb::arg("queue"), nb::arg("inv_width"),
          nb::arg("rec_face"), nb::arg("rec_dist"), nb::arg("pos"), nb::arg("lim"),
          nb::arg("seg_start"), nb::arg("seg_len"), nb::arg("wscale"));
    m.def("compact_records", &compact_records,
          "Move the given record segments to the front, in order of their start.",
          nb::arg("order"), nb::arg("seg_start"), nb::arg("seg_len"), nb::arg("rec_face"),
          nb::arg("rec_dist"));
}

}  // namespace sfk
