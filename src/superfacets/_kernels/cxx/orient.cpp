// Normals turned outwards (turn_outwards) and tests/oracle/orient.py's
// propagate_signs: the signs of Hoppe's orientation along
// the minimum spanning tree of the neighbourhood graph, the same tree and signs.
//
// The tree is the unique minimum spanning forest under a strict order of the undirected
// edges, (key, lower end, higher end) with key = 1 - |n_u . n_v|; numba's kernel grows
// it by Prim's algorithm over the whole graph, whose frontier (an invasion front) makes
// its heap the cost. Here the same forest is reached by blocks of elements (index ranges
// of 2^15: neighbours in space are mostly near in index), most of the work on threads:
//  1. each block's minimum spanning forest (Kruskal's algorithm over its edges sorted);
//     an edge outside it is the heaviest of a cycle inside the block, so in no minimum
//     spanning tree of the whole graph (the cycle property). The edges between blocks
//     are listed; their ends are the terminals.
//  2. each forest reduced to what those edges can change: branches without a terminal
//     peeled off (bridges), and each path through elements of two forest edges and no
//     terminal made one edge, ordered as its heaviest (a cycle through one of its edges
//     runs along all of it, so only the heaviest can leave the tree);
//  3. Kruskal's algorithm over those paths and the edges between blocks (one thread,
//     about a quarter of an edge per element): a path left out loses its heaviest edge;
//  4. each element's sign relative to the lowest element of its piece (its block's
//     forest less the edges left out), then each piece's sign along the tree's edges
//     between blocks, trees taken from their lowest element: the products of the same
//     signs along the same paths as Prim's.
// 10M points: 5.1-5.9 s with Prim's heap on one thread, 3.2-3.4 s here on two. Where a
// quarter or more of a sample's edges cross between blocks (a subdivided mesh's vertices,
// new ones listed after the old), one block.
#include <algorithm>
#include <atomic>
#include <cstring>

#include "common.hpp"
#include "points.hpp"

namespace sfk {

namespace {

constexpr i64 kOrientBlock = i64(1) << 15;
constexpr double kLeftOut = -2.0;  // the key of a forest edge left out (keys are >= -1e-15)

struct Edge {
    double key;
    i32 a, b;  // a < b
};

// the strict order of the undirected edges: by key, then the lower end, then the higher
template <class E>
inline bool edge_before(const E& x, const E& y) {
    return x.key < y.key || (x.key == y.key && (x.a < y.a || (x.a == y.a && x.b < y.b)));
}

inline double dot3(const double* nor, i64 u, i64 v) {
    return nor[3 * u] * nor[3 * v] + nor[3 * u + 1] * nor[3 * v + 1] +
           nor[3 * u + 2] * nor[3 * v + 2];
}

// union-find over elements lo .. lo + size - 1 (path halving; which root survives a
// union does not change which edges Kruskal's algorithm keeps)
struct Forest {
    std::vector<i32> up;
    i64 lo = 0;
    void reset(i64 lo_, i64 size) {
        lo = lo_;
        up.resize(size);
        for (i64 i = 0; i < size; ++i) up[i] = static_cast<i32>(i);
    }
    i32 find(i32 x) {
        while (up[x] != x) {
            up[x] = up[up[x]];
            x = up[x];
        }
        return x;
    }
    // Kruskal's algorithm: the edges of `sorted` that join two trees, appended to `out`
    void keep(const std::vector<Edge>& sorted, std::vector<Edge>& out) {
        for (const Edge& e : sorted) {
            i32 x = find(static_cast<i32>(e.a - lo)), y = find(static_cast<i32>(e.b - lo));
            if (x == y) continue;
            up[x] = y;
            out.push_back(e);
        }
    }
};

// The bits of a double as an unsigned integer of the same order (-0.0 below 0.0: a key is
// never -0.0, 1.0 - |d| is +0.0 where |d| is 1)
inline std::uint64_t order_bits(double x) {
    std::uint64_t u;
    std::memcpy(&u, &x, sizeof u);
    return (u >> 63) ? ~u : (u | (std::uint64_t{1} << 63));
}

// Sort edges by edge_before: a least-significant-digit radix sort of the keys' bits (11
// bits a pass, passes where every key has the same digit skipped), then each run of
// equal keys by its ends where not in that order already (the lists come by rows).
template <class E>
void sort_edges(std::vector<E>& e, std::vector<E>& tmp) {
    const i64 n = static_cast<i64>(e.size());
    tmp.resize(n);
    std::vector<i64> count(2048);
    for (int shift = 31; shift < 64; shift += 11) {
        std::fill(count.begin(), count.end(), 0);
        for (const E& x : e) ++count[(order_bits(x.key) >> shift) & 2047];
        if (std::find(count.begin(), count.end(), n) != count.end()) continue;
        i64 at = 0;
        for (auto& c : count) {
            const i64 k = c;
            c = at;
            at += k;
        }
        for (const E& x : e) tmp[count[(order_bits(x.key) >> shift) & 2047]++] = x;
        e.swap(tmp);
    }
    for (i64 i = 0; i < n;) {
        i64 j = i + 1;
        const std::uint64_t top = order_bits(e[i].key) >> 31;
        while (j < n && order_bits(e[j].key) >> 31 == top) ++j;
        if (j - i > 1 && !std::is_sorted(e.begin() + i, e.begin() + j, edge_before<E>))
            std::sort(e.begin() + i, e.begin() + j, edge_before<E>);
        i = j;
    }
}

// A path of a block's forest made one edge (ordered as its heaviest edge, a, b: the
// heaviest's ends; u, w: the path's ends; edge: the heaviest's place in the block's
// forest), or an edge between blocks (u, w its ends, edge -1).
struct Chain {
    double key;
    i32 a, b, u, w, edge;
};

// The rows of a block's forest over its local elements: neighbour and edge (its place
// in the forest's list) per entry.
struct Rows {
    std::vector<i32> ptr, nbr, edge;
    void build(const std::vector<Edge>& f, i64 lo, i64 nb) {
        ptr.assign(nb + 1, 0);
        for (const Edge& e : f) {
            ++ptr[e.a - lo + 1];
            ++ptr[e.b - lo + 1];
        }
        for (i64 u = 0; u < nb; ++u) ptr[u + 1] += ptr[u];
        nbr.resize(ptr[nb]);
        edge.resize(ptr[nb]);
        std::vector<i32> fill(ptr.begin(), ptr.end() - 1);
        for (i64 i = 0; i < static_cast<i64>(f.size()); ++i) {
            const i32 a = static_cast<i32>(f[i].a - lo), b = static_cast<i32>(f[i].b - lo);
            nbr[fill[a]] = b;
            edge[fill[a]++] = static_cast<i32>(i);
            nbr[fill[b]] = a;
            edge[fill[b]++] = static_cast<i32>(i);
        }
    }
};

}  // namespace

i64 propagate_signs(nb::handle indptr_, nb::handle indices_, nb::handle normals_,
                    nb::handle sign_, nb::handle component_) {
    In<i64> indptr(indptr_, "indptr");
    In<i32> indices(indices_, "indices");
    In<double> nor(normals_, "normals");
    Out<std::int8_t> sign(sign_, "sign");
    Out<i64> component(component_, "component");
    if (nor.cols != 3 || indptr.n != nor.n + 1 || sign.n != nor.n || component.n != nor.n ||
        nor.n >= (i64(1) << 31) - 1)
        throw Mismatch("argument normals");
    check_csr(indptr, indices, nor.n, nor.n);
    nb::gil_scoped_release nogil;
    const i64 n = nor.n;
    const double* np_ = nor.p;
    // blocks only where they are patches (as BlockedSearch): a strided sample's edges
    i64 edges = 0, crossing = 0;
    const i64 step = std::max<i64>(1, n >> 16);
    for (i64 f = 0; f < n; f += step)
        for (i64 e = indptr[f]; e < indptr[f + 1]; ++e, ++edges)
            crossing += indices[e] / kOrientBlock != f / kOrientBlock;
    const i64 block = 4 * crossing < edges ? kOrientBlock : std::max<i64>(n, 1);
    const i64 n_blocks = (n + block - 1) / block;
    // 1. each block's minimum spanning forest, and the edges to later blocks
    std::vector<std::vector<Edge>> kept(n_blocks), cross(n_blocks);
    std::atomic<i64> next{0};
    const i64 T = std::max<i64>(1, std::min<i64>(threads(), n_blocks));
    on_threads(T, [&](i64) {
        std::vector<Edge> inside, tmp;
        Forest forest;
        for (i64 b = next++; b < n_blocks; b = next++) {
            check_interrupt();
            const i64 lo = b * block, hi = mn(n, lo + block);
            inside.clear();
            for (i64 v = lo; v < hi; ++v)
                for (i64 t = indptr[v]; t < indptr[v + 1]; ++t) {
                    const i64 w = indices[t];
                    if (w <= v) continue;  // each edge once, from its lower end
                    Edge e{1.0 - std::fabs(dot3(np_, v, w)), static_cast<i32>(v),
                           static_cast<i32>(w)};
                    (w < hi ? inside : cross[b]).push_back(e);
                }
            sort_edges(inside, tmp);
            forest.reset(lo, hi - lo);
            forest.keep(inside, kept[b]);
        }
    });
    // 2. each block's forest reduced to what the edges between blocks can change (on
    // threads): the branches without an end of such an edge (a "terminal") peeled off
    // (bridges: in every spanning tree), and each path through elements of two tree
    // edges and no terminal made one edge ordered as its heaviest (any cycle through
    // one of the path's edges runs along all of it: the others are in the tree)
    std::vector<char> terminal(n, 0);
    for (const auto& c : cross)
        for (const Edge& x : c) terminal[x.a] = terminal[x.b] = 1;
    std::vector<std::vector<Chain>> chains(n_blocks);
    next = 0;
    on_threads(T, [&](i64) {
        Rows rows;
        std::vector<i32> degree, todo;
        std::vector<char> key_node;
        for (i64 b = next++; b < n_blocks; b = next++) {
            check_interrupt();
            const i64 lo = b * block, nb = mn(n, lo + block) - lo;
            const auto& f = kept[b];
            rows.build(f, lo, nb);
            degree.assign(rows.ptr.begin() + 1, rows.ptr.end());
            for (i64 u = 0; u < nb; ++u) degree[u] -= rows.ptr[u];
            todo.clear();
            for (i64 u = 0; u < nb; ++u)
                if (degree[u] == 1 && !terminal[lo + u]) todo.push_back(static_cast<i32>(u));
            while (!todo.empty()) {  // peel: a leaf that is no terminal leaves the core
                const i32 u = todo.back();
                todo.pop_back();
                degree[u] = 0;
                for (i64 t = rows.ptr[u]; t < rows.ptr[u + 1]; ++t) {
                    const i32 w = rows.nbr[t];
                    if (degree[w] > 0 && --degree[w] == 1 && !terminal[lo + w]) todo.push_back(w);
                }
            }
            key_node.assign(nb, 0);
            for (i64 u = 0; u < nb; ++u)
                key_node[u] = degree[u] > 0 && (terminal[lo + u] || degree[u] >= 3);
            auto& out = chains[b];
            for (i64 u = 0; u < nb; ++u) {
                if (!key_node[u]) continue;
                for (i64 t = rows.ptr[u]; t < rows.ptr[u + 1]; ++t) {
                    i32 prev = static_cast<i32>(u), cur = rows.nbr[t];
                    if (degree[cur] == 0) continue;
                    i32 heavy = rows.edge[t];
                    while (!key_node[cur]) {  // along the path to the next key element
                        i64 s = rows.ptr[cur];
                        while (rows.nbr[s] == prev || degree[rows.nbr[s]] == 0) ++s;
                        if (edge_before(f[heavy], f[rows.edge[s]])) heavy = rows.edge[s];
                        prev = cur;
                        cur = rows.nbr[s];
                    }
                    if (u < cur)
                        out.push_back({f[heavy].key, f[heavy].a, f[heavy].b,
                                       static_cast<i32>(lo + u), static_cast<i32>(lo + cur),
                                       heavy});
                }
            }
        }
    });
    std::vector<char>().swap(terminal);
    // 3. Kruskal's algorithm over the paths and the edges between blocks: a path left
    // out loses its heaviest edge, an edge between blocks kept joins two pieces
    std::vector<Chain> all;
    {
        i64 total = 0;
        for (i64 b = 0; b < n_blocks; ++b) total += chains[b].size() + cross[b].size();
        all.reserve(total);
        for (i64 b = 0; b < n_blocks; ++b) {
            for (const Chain& c : chains[b]) all.push_back(c);
            for (const Edge& x : cross[b]) all.push_back({x.key, x.a, x.b, x.a, x.b, -1});
            std::vector<Chain>().swap(chains[b]);
            std::vector<Edge>().swap(cross[b]);
        }
        std::vector<Chain> tmp;
        sort_edges(all, tmp);
    }
    std::vector<Edge> joins;  // the edges between blocks in the tree
    {
        Forest forest;
        forest.reset(0, n);
        for (const Chain& c : all) {
            i32 x = forest.find(c.u), y = forest.find(c.w);
            if (x != y) {
                forest.up[x] = y;
                if (c.edge < 0) joins.push_back({c.key, c.a, c.b});
            } else if (c.edge >= 0) {
                kept[c.u / block][c.edge].key = kLeftOut;  // the path's heaviest edge
            }
        }
    }
    std::vector<Chain>().swap(all);
    // 4. each element's sign relative to the lowest element of its piece (its block's
    // tree less the edges left out), on threads; pieces numbered in order of those
    std::vector<i64> pieces(n_blocks + 1, 0);
    next = 0;
    on_threads(T, [&](i64) {
        Rows rows;
        std::vector<char> seen;
        std::vector<i32> stack;
        for (i64 b = next++; b < n_blocks; b = next++) {
            check_interrupt();
            const i64 lo = b * block, nb = mn(n, lo + block) - lo;
            const auto& f = kept[b];
            rows.build(f, lo, nb);
            seen.assign(nb, 0);
            i64 count = 0;
            for (i64 s = 0; s < nb; ++s) {
                if (seen[s]) continue;
                seen[s] = 1;
                sign[lo + s] = 1;
                component[lo + s] = count;
                stack.assign(1, static_cast<i32>(s));
                while (!stack.empty()) {
                    const i32 v = stack.back();
                    stack.pop_back();
                    for (i64 t = rows.ptr[v]; t < rows.ptr[v + 1]; ++t) {
                        const i32 w = rows.nbr[t];
                        if (seen[w] || f[rows.edge[t]].key == kLeftOut) continue;
                        seen[w] = 1;
                        sign[lo + w] = static_cast<std::int8_t>(
                            dot3(np_, lo + v, lo + w) >= 0 ? sign[lo + v] : -sign[lo + v]);
                        component[lo + w] = count;
                        stack.push_back(w);
                    }
                }
                ++count;
            }
            pieces[b + 1] = count;
        }
    });
    for (i64 b = 0; b < n_blocks; ++b) pieces[b + 1] += pieces[b];
    // 5. the pieces joined by the tree's edges between blocks, walked from the lowest
    // piece of each tree: each piece's sign and tree
    const i64 np = pieces[n_blocks];
    auto piece = [&](i64 v) { return pieces[v / block] + component[v]; };
    std::vector<i64> pptr(np + 1, 0);
    for (const Edge& j : joins) {
        ++pptr[piece(j.a) + 1];
        ++pptr[piece(j.b) + 1];
    }
    for (i64 q = 0; q < np; ++q) pptr[q + 1] += pptr[q];
    struct Link {
        i64 to;
        std::int8_t flip;
    };
    std::vector<Link> links(pptr[np]);
    {
        std::vector<i64> fill(pptr.begin(), pptr.end() - 1);
        for (const Edge& j : joins) {
            const std::int8_t r = static_cast<std::int8_t>(
                sign[j.a] * sign[j.b] * (dot3(np_, j.a, j.b) >= 0 ? 1 : -1));
            const i64 qa = piece(j.a), qb = piece(j.b);
            links[fill[qa]++] = {qb, r};
            links[fill[qb]++] = {qa, r};
        }
    }
    std::vector<std::int8_t> psign(np, 0);
    std::vector<i64> pcomp(np, -1), stack;
    i64 n_comp = 0;
    for (i64 q = 0; q < np; ++q) {
        if (pcomp[q] >= 0) continue;
        pcomp[q] = n_comp;
        psign[q] = 1;
        stack.assign(1, q);
        while (!stack.empty()) {
            const i64 x = stack.back();
            stack.pop_back();
            for (i64 t = pptr[x]; t < pptr[x + 1]; ++t) {
                const Link& l = links[t];
                if (pcomp[l.to] >= 0) continue;
                pcomp[l.to] = n_comp;
                psign[l.to] = static_cast<std::int8_t>(psign[x] * l.flip);
                stack.push_back(l.to);
            }
        }
        ++n_comp;
    }
    parallel_for(n, [&](i64 a, i64 b) {
        for (i64 v = a; v < b; ++v) {
            const i64 q = piece(v);
            sign[v] = static_cast<std::int8_t>(sign[v] * psign[q]);
            component[v] = pcomp[q];
        }
    });
    return n_comp;
}

void turn_outwards(nb::handle points_, nb::handle normals_, nb::handle sign_,
                   nb::handle component_, i64 n_comp, nb::handle out_) {
    In<double> pts(points_, "points"), nor(normals_, "normals");
    In<std::int8_t> sign(sign_, "sign");
    In<i64> component(component_, "component");
    Out<double> out(out_, "out");
    if (pts.cols != 3 || nor.cols != 3 || out.cols != 3) throw Mismatch("argument points");
    for (i64 m : {nor.n, sign.n, component.n, out.n})
        if (m != pts.n) throw Mismatch("argument normals");
    check_range(component, 0, n_comp, "component");
    nb::gil_scoped_release nogil;
    const i64 n = pts.n;
    std::vector<double> count(n_comp, 0.0), mean(3 * n_comp, 0.0), total(n_comp, 0.0);
    for (i64 i = 0; i < n; ++i) {
        i64 c = component[i];
        count[c] += 1.0;
        for (int a = 0; a < 3; ++a) mean[3 * c + a] += pts(i, a);
    }
    for (i64 c = 0; c < n_comp; ++c)
        for (int a = 0; a < 3; ++a) mean[3 * c + a] /= count[c];
    for (i64 i = 0; i < n; ++i) {
        i64 c = component[i];
        double s = static_cast<double>(sign[i]);
        total[c] += (nor(i, 0) * s * (pts(i, 0) - mean[3 * c]) +
                     nor(i, 1) * s * (pts(i, 1) - mean[3 * c + 1])) +
                    nor(i, 2) * s * (pts(i, 2) - mean[3 * c + 2]);
    }
    for (i64 i = 0; i < n; ++i) {
        double s = static_cast<double>(sign[i]);
        if (total[component[i]] < 0) s = -s;
        for (int a = 0; a < 3; ++a) out(i, a) = nor(i, a) * s;
    }
}

void bind_orient(nb::module_& m) {
    m.def("turn_outwards", &turn_outwards,
          "Out.",
          nb::arg("points"), nb::arg("normals"), nb::arg("sign"), nb::arg("component"),
          nb::arg("n_comp"), nb::arg("out"));
    m.def("propagate_signs", &propagate_signs,
          "Fill sign (+1/-1 per element) and component (ids from 0).",
          nb::arg("indptr"), nb::arg("indices"), nb::arg("normals"), nb::arg("sign"),
          nb::arg("component"));
}

}  // namespace sfk
