"""Boundary clean-up: known answers on synthetic meshes, invariants on real ones."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import grid_mesh
from oracle import reference

from superfacets import segment
from superfacets.elements import face_graph
from superfacets.errors import ParameterError
from superfacets.evaluation.metrics import compactness
from superfacets.method.cleanup import clean_boundaries, cut_costs
from superfacets.method.connectivity import label_components


def _cut_length(graph, labels) -> float:
    i, j = graph.pairs[:, 0], graph.pairs[:, 1]
    return float(graph.lengths[labels[i] != labels[j]].sum())


def _cells(mesh, nx: int, ny: int):
    """Column and row of the grid cell of each face of :func:`grid_mesh`."""
    c = mesh.centroids
    col = np.floor((c[:, 0] + 1) / 2 * nx).astype(int)
    row = np.floor((c[:, 1] + 1) / 2 * ny).astype(int)
    return col, row


def test_boundary_two_rings_beside_a_concave_crease_ends_on_it():
    # a folded plane z = 0.5 |x| (a concave valley along x = 0), cells 0.05 wide;
    # the boundary starts two cells to the right of the crease
    nx, ny = 40, 20
    mesh = grid_mesh(nx, ny, height=lambda x, y: 0.5 * np.abs(x))
    col, _ = _cells(mesh, nx, ny)
    labels = (col >= nx // 2 + 2).astype(np.int64)
    out = clean_boundaries(face_graph(mesh), labels, alpha=200)
    assert np.array_equal(out, (col >= nx // 2).astype(np.int64))
    # without a crease term the same boundary has no reason to jump onto the fold
    flat = clean_boundaries(face_graph(mesh), labels, alpha=0)
    assert not np.array_equal(flat, out)


def test_stair_stepped_boundary_on_a_flat_grid_becomes_straight():
    nx, ny = 40, 20
    mesh = grid_mesh(nx, ny)
    col, row = _cells(mesh, nx, ny)
    labels = (col >= nx // 2 + (row % 2)).astype(np.int64)  # a zigzag, one cell deep
    before = _cut_length(face_graph(mesh), labels)
    assert before == pytest.approx(2.0 + (ny - 1) * 0.05)  # a jog between rows
    out = clean_boundaries(face_graph(mesh), labels, alpha=200)
    assert _cut_length(face_graph(mesh), out) == pytest.approx(2.0)  # one straight column edge line
    per_row = [np.unique(col[(row == r) & (out == 1)]).min() for r in range(ny)]
    assert len(set(per_row)) == 1


def test_superfacets_are_never_lost_and_stay_connected():
    # a one-face superfacet inside another lies wholly in a band: it keeps its center
    nx = ny = 20
    mesh = grid_mesh(nx, ny)
    col, row = _cells(mesh, nx, ny)
    labels = (col >= nx // 2).astype(np.int64)
    tiny = int(np.flatnonzero((col == 5) & (row == 5))[0])
    labels[tiny] = 2
    centers = np.array([int(np.flatnonzero(col == 0)[0]), int(np.flatnonzero(col == nx - 1)[0]),
                        tiny])
    out = clean_boundaries(face_graph(mesh), labels, centers)
    assert int(out.max()) + 1 == 3 and out[tiny] == 2
    assert np.unique(label_components(face_graph(mesh), out)).size == 3


def test_cut_costs_are_the_lengths_without_creases_and_cheaper_on_folds(valley):
    g = face_graph(valley)
    assert np.allclose(cut_costs(g, alpha=0), g.lengths)
    c = cut_costs(g, alpha=200)
    fold = np.arccos(g.terms.cos) > 0.1
    assert np.all(c[fold] < 0.5 * g.lengths[fold])
    assert np.allclose(c[~fold & (np.arccos(g.terms.cos) < 1e-9)], g.lengths[~fold & (
        np.arccos(g.terms.cos) < 1e-9)])
    with pytest.raises(ParameterError, match="crease"):
        cut_costs(g, crease=-1)


def test_pipeline_cleanup_on_real_meshes(psb):
    from superfacets.evaluation.datasets.psb import list_meshes

    meshes = list_meshes(psb)
    by_cat = {}
    for m in meshes:
        by_cat.setdefault(m.category, m)
    for bm in list(by_cat.values())[:5]:
        mesh = bm.load()
        paper = segment(mesh, 60, paper=True)
        clean = segment(mesh, 60, cleanup=True, split_merge=False, tol=0)
        again = segment(mesh, 60, cleanup=True, split_merge=False, tol=0, n_threads=1)
        assert np.array_equal(clean.labels, again.labels), bm.id  # deterministic, any threads
        k = paper.n_segments
        assert clean.n_segments == k and int(clean.labels.max()) + 1 == k, bm.id
        assert np.array_equal(np.unique(clean.labels), np.arange(k)), bm.id  # dense
        assert np.unique(label_components(face_graph(mesh), clean.labels)).size == k, bm.id
        assert np.array_equal(clean.labels[clean.centers], np.arange(k)), bm.id
        assert compactness(face_graph(mesh), clean.labels) < compactness(face_graph(mesh),
                                                                         paper.labels)
        assert clean.params["cleanup"] is True and "cleanup" in clean.timings


@pytest.mark.parametrize("elements", ["vertices", "points"])
def test_cleanup_on_vertices_and_points(sphere, elements):
    obj = sphere if elements == "vertices" else sphere.vertices
    paper = segment(obj, 25, elements=elements, paper=True)
    clean = segment(obj, 25, elements=elements, cleanup=True, split_merge=False)
    assert clean.n_segments == paper.n_segments
    assert clean.labels.shape == paper.labels.shape
    assert not np.array_equal(clean.labels, paper.labels)
    # the default: both options on vertices (paper weighting), the paper's method on points
    default = segment(obj, 25, elements=elements)
    on = elements == "vertices"
    assert default.params["cleanup"] is on and default.params["split_merge"] is on
    same = segment(obj, 25, elements=elements, cleanup=on, split_merge=on)
    assert np.array_equal(default.labels, same.labels)
    off = segment(obj, 25, elements=elements, weighting="shlafman", alpha=0.5)
    assert off.params["cleanup"] is False and off.params["split_merge"] is False


def test_crease_weight_per_element_kind():
    from superfacets.elements.kinds import kind_of
    from superfacets.method.cleanup import CREASE, CREASE_SMOOTH_NORMALS

    assert kind_of("faces").crease == CREASE == 0.1
    assert kind_of("vertices").crease == kind_of("points").crease == CREASE_SMOOTH_NORMALS == 1.0


def test_data_term_weight_per_element_kind():
    # faces weigh roundness more (0.7) than vertices and points (0.3); the default is
    # the kind's, and it matters: a heavier data term leaves rounder superfacets
    from superfacets.elements.builders import elements_of
    from superfacets.elements.kinds import kind_of
    from superfacets.method.cleanup import SMOOTHNESS, SMOOTHNESS_FACES

    assert kind_of("faces").smoothness == SMOOTHNESS_FACES == 0.7
    assert kind_of("vertices").smoothness == kind_of("points").smoothness == SMOOTHNESS == 0.3
    mesh = grid_mesh(30, 30, height=lambda x, y: 0.2 * np.sin(3 * x) * np.cos(2 * y))
    for kind, value, other in (("faces", 0.7, 0.3), ("vertices", 0.3, 1.0)):
        g = elements_of(mesh, kind).graph
        labels = segment(mesh, 20, elements=kind, paper=True).element_labels
        default = clean_boundaries(g, labels, alpha=200)
        np.testing.assert_array_equal(default, clean_boundaries(g, labels, alpha=200,
                                                                smoothness=value))
        assert not np.array_equal(default, clean_boundaries(g, labels, alpha=200,
                                                            smoothness=other))


def test_point_boundary_two_spacings_beside_a_concave_crease_ends_on_it():
    # points on the folded plane z = 0.5 |x| (a valley along x = 0), spacing 0.05;
    # the boundary starts two columns right of the crease and ends on it, except in
    # the first and last rows, whose one-sided neighbourhoods keep the old corner
    from superfacets.elements.points import point_graph
    from superfacets.inputs.cloud import PointCloud

    nx, ny = 40, 20
    x, y = np.meshgrid((np.arange(nx) + 0.5) / nx * 2 - 1, (np.arange(ny) + 0.5) / ny * 2 - 1,
                       indexing="ij")
    g = point_graph(PointCloud(np.c_[x.ravel(), y.ravel(), 0.5 * np.abs(x.ravel())])).graph
    col = np.floor((g.positions[:, 0] + 1) / 2 * nx).astype(int)
    inner = np.abs(g.positions[:, 1]) < 0.9
    labels = (col >= nx // 2 + 2).astype(np.int64)
    out = clean_boundaries(g, labels, alpha=200)  # the points' crease weight
    assert np.array_equal(out[inner], (col[inner] >= nx // 2).astype(np.int64))
    flat = clean_boundaries(g, labels, alpha=0)  # no crease term: nothing to move it
    assert np.array_equal(flat, labels)


def test_bad_arguments(sphere):
    g = face_graph(sphere)
    labels = segment(sphere, 10).labels
    with pytest.raises(ParameterError, match="centers"):
        clean_boundaries(g, labels, np.zeros(10, dtype=np.int64))
    with pytest.raises(ParameterError, match="smoothness"):
        clean_boundaries(g, labels, smoothness=-1)
    with pytest.raises(ParameterError, match="band"):
        clean_boundaries(g, labels, band=0)
    with pytest.raises(ParameterError, match="labels"):
        clean_boundaries(g, labels[:-1])
    with pytest.raises(ParameterError, match="cleanup"):
        segment(sphere, 10, cleanup="yes")
    # sweeps = 0 changes nothing
    assert np.array_equal(clean_boundaries(g, labels, sweeps=0), labels)


def test_odd_inputs_and_extreme_counts():
    import trimesh

    from superfacets import Mesh

    tm = trimesh.creation.icosphere(subdivisions=3)
    v = np.vstack([tm.vertices, [[9.0, 9.0, 9.0]], tm.vertices * 0.3 + [4, 0, 0]])
    f = tm.faces.copy()
    extra = [f[0], [f[1, 0], f[1, 0], f[1, 1]], [f[2, 0], f[2, 1], len(tm.vertices)]]
    # duplicate, degenerate and non-manifold faces; a second component
    mesh = Mesh(v, np.vstack([f, extra, tm.faces + len(tm.vertices) + 1]))
    for k in (1, 2, 30):
        paper = segment(mesh, k)
        clean = segment(mesh, k, cleanup=True)
        assert clean.n_segments == paper.n_segments, k
        assert np.unique(label_components(face_graph(mesh), clean.labels)).size == clean.n_segments
    one_each = grid_mesh(3, 3)
    r = segment(one_each, one_each.n_faces, alpha=0, cleanup=True)
    assert np.unique(r.labels).size == one_each.n_faces
    # without connectivity, the clean-up leaves the pieces it makes
    r = segment(mesh, 30, cleanup=True, enforce_connectivity=False)
    assert np.array_equal(np.unique(r.labels), np.arange(r.n_segments))


def _arcs(n, caps):
    """Linked arc lists (first, nxt, head, cap) of the arcs ``caps[(u, v)]``; an arc
    and its reverse are ``a``, ``a ^ 1``."""
    first = np.full(n, -1, dtype=np.int64)
    nxt, head, cap = [], [], []
    for (u, v), (c_uv, c_vu) in caps.items():
        for tail, tip, c in ((u, v, c_uv), (v, u, c_vu)):
            head.append(tip)
            cap.append(float(c))
            nxt.append(first[tail])
            first[tail] = len(head) - 1
    return (first, np.array(nxt, dtype=np.int64), np.array(head, dtype=np.int64),
            np.array(cap, dtype=np.float64))


def test_min_cut_is_the_smallest_minimum_source_side_by_brute_force():
    from itertools import product

    from oracle.cleanup import min_cut

    rng = np.random.default_rng(3)
    for trial in range(200):
        n = int(rng.integers(1, 9))
        caps = {}
        for u in range(n):
            for v in range(u + 1, n):
                if rng.random() < 0.5:  # integer capacities: sums are exact, ties real
                    caps[(u, v)] = (int(rng.integers(0, 4)), int(rng.integers(0, 4)))
        tr = rng.integers(-3, 4, n).astype(np.float64)
        first, nxt, head, cap = _arcs(n, caps)
        side = np.zeros(n, dtype=bool)
        min_cut(first, nxt, head, cap, tr.copy(), 0.0, side)
        best, smallest = np.inf, None
        for bits in product((False, True), repeat=n):
            s = np.array(bits)
            value = (tr[~s & (tr > 0)].sum() - tr[s & (tr < 0)].sum()
                     + sum(c_uv * (s[u] and not s[v]) + c_vu * (s[v] and not s[u])
                           for (u, v), (c_uv, c_vu) in caps.items()))
            if value < best:
                best, smallest = value, s.copy()
            elif value == best:
                smallest &= s  # the minimum cuts' source sides are closed under intersection
        assert np.array_equal(side, smallest), trial


def test_min_cut_matches_scipys_maximum_flow_on_bands():
    """Known answer on bands large enough for the global relabelling (a grid strip whose
    data term is weak, as the clean-up's, and random sparse graphs), integer capacities
    with many ties: the source side is what the source reaches in the residual network of
    scipy's maximum flow (the smallest minimum source side), and the cut's value is the
    flow's."""
    from oracle.cleanup import min_cut
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import breadth_first_order, maximum_flow

    rng = np.random.default_rng(8)
    sizes = []
    for trial in range(12):
        if trial < 4:  # a strip of w x h nodes, neighbours in rows and columns
            w, h = 60, 12
            n = w * h
            caps = {}
            for y in range(h):
                for x in range(w):
                    u = y * w + x
                    for v in ((u + 1) if x + 1 < w else None, (u + w) if y + 1 < h else None):
                        if v is not None:
                            c = int(rng.integers(20, 40))
                            caps[(u, v)] = (c, c)
            ramp = np.tile(np.linspace(-1.0, 1.0, w), h)  # the sides' pull, weak
            tr = np.round(-3 * ramp + rng.integers(-1, 2, n)).astype(np.float64)
        else:
            n = int(rng.integers(50, 400))
            caps = {}
            for _ in range(3 * n):
                u, v = sorted(rng.choice(n, 2, replace=False).tolist())
                caps[(u, v)] = (int(rng.integers(0, 6)), int(rng.integers(0, 6)))
            tr = rng.integers(-4, 5, n).astype(np.float64)
        first, nxt, head, cap = _arcs(n, caps)
        side = np.zeros(n, dtype=bool)
        min_cut(first, nxt, head, cap, tr.copy(), 0.0, side)
        # scipy: nodes 0..n-1, the source n, the sink n + 1
        rows, cols, vals = [], [], []
        for (u, v), (c_uv, c_vu) in caps.items():
            rows += [u, v]
            cols += [v, u]
            vals += [c_uv, c_vu]
        for u in range(n):
            if tr[u] > 0:
                rows, cols, vals = rows + [n], cols + [u], vals + [int(tr[u])]
            elif tr[u] < 0:
                rows, cols, vals = rows + [u], cols + [n + 1], vals + [int(-tr[u])]
        g = csr_matrix((np.array(vals, dtype=np.int32), (rows, cols)), shape=(n + 2, n + 2))
        g.sum_duplicates()
        flow = maximum_flow(g, n, n + 1)
        residual = g - flow.flow
        residual.data[residual.data < 0] = 0
        residual.eliminate_zeros()
        reached = breadth_first_order(residual, n, directed=True, return_predecessors=False)
        expected = np.zeros(n, dtype=bool)
        expected[reached[reached < n]] = True
        assert np.array_equal(side, expected), trial
        value = (tr[~side & (tr > 0)].sum() - tr[side & (tr < 0)].sum()
                 + sum(c_uv * (side[u] and not side[v]) + c_vu * (side[v] and not side[u])
                       for (u, v), (c_uv, c_vu) in caps.items()))
        assert value == flow.flow_value, trial
        sizes.append(int(side.sum()))
    assert all(0 < x < 720 for x in sizes[:4]) and any(x > 0 for x in sizes[4:]), sizes


def test_progress_bar_names_the_cleanup_stage(capsys):
    mesh = grid_mesh(30, 30, height=lambda x, y: 0.5 * np.abs(x))
    labels = segment(mesh, 12, cleanup=True, progress=True).labels
    err = capsys.readouterr().err
    assert "superfacets" in err and "clean-up" in err
    assert labels.max() + 1 == 12


def test_the_clean_up_does_not_depend_on_how_the_superfacets_are_numbered():
    # ties go by the centers' order, not the labels': a permutation of the labels (a
    # tiled run numbers superfacets by their centers' rows) gives the permuted result
    mesh = grid_mesh(20, 20)  # flat and regular: ties everywhere
    r = segment(mesh, 20, cleanup=False)
    clean = clean_boundaries(mesh, r.labels, r.centers)
    perm = np.random.default_rng(0).permutation(r.n_segments)
    inverse = np.argsort(perm)
    again = clean_boundaries(mesh, perm[r.labels], r.centers[inverse])
    np.testing.assert_array_equal(again, perm[clean])
    assert not np.array_equal(clean, r.labels)  # the clean-up moved something


def test_a_piece_with_no_neighbour_becomes_a_superfacet_numbered_from_k():
    # superfacet 0 spans the right half of one grid and the whole of a second, separate
    # grid; its center lies in the first: the second grid's piece touches no other
    # superfacet and becomes superfacet 3 (k = 3), whatever the other labels' order
    from superfacets import Mesh

    a = grid_mesh(8, 8)
    mesh = Mesh(np.r_[a.vertices, a.vertices + [10.0, 0.0, 0.0]],
                np.r_[a.faces, a.faces + a.vertices.shape[0]])
    m = a.faces.shape[0]
    col, _ = _cells(a, 8, 8)
    labels = np.r_[np.where(col < 4, 2, 0), np.zeros(m, dtype=np.int64)]
    labels[0] = 1  # a one-face superfacet at a corner
    centers = np.array([int(np.flatnonzero(labels[:m] == 0)[0]), 0,
                        int(np.flatnonzero(labels[:m] == 2)[5])])
    out = clean_boundaries(mesh, labels, centers)
    np.testing.assert_array_equal(out[m:], 3)  # the separate piece: a number of its own
    assert set(np.unique(out[:m])) == {0, 1, 2}  # the others keep theirs
    np.testing.assert_array_equal(out[centers], [0, 1, 2])


@pytest.mark.parametrize("threads", ["1", "2"])
def test_band_distances_are_the_shortest_and_ties_take_the_lowest_partner(monkeypatch,
                                                                           threads):
    """Each element's distance from its superfacet's boundary is the shortest within the
    superfacet, and its partner the lowest of the seeds at that distance (a regular grid:
    many exact ties), whatever the threads and the kernel (compiled or numba)."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import dijkstra

    from superfacets._kernels import native

    mesh = grid_mesh(64, 64)
    g = face_graph(mesh)
    col, row = _cells(mesh, 64, 64)
    labels = (col // 16) * 4 + row // 16 + ((col + row) % 5 == 0) * 0  # 16 squares
    labels = np.where((col - 30) ** 2 + (row - 34) ** 2 < 40, 16, labels).astype(np.int64)
    n = g.n_elements
    pinned = np.zeros(n, dtype=bool)
    pinned[::97] = True
    geo, de, limit = g.terms.geo, g.dual_edge, 0.25
    heap = g.indices.shape[0] + n + 1
    got = []
    for compiled in (False, True):
        dist, partner = np.empty(n), np.empty(n, dtype=np.int64)
        args = (g.indptr, g.indices, de, geo, g.lengths, labels, pinned, limit, dist,
                partner, np.empty(heap), np.empty(heap, dtype=np.int64))
        if not compiled:
            reference("cleanup.band_distances")(*args)
        else:  # the compiled kernel's threads (numba, which would read its config again
            with monkeypatch.context() as m:  # on compiling, runs before)
                m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
                native.kernel("cleanup.band_distances")(*args)
        got.append((dist, partner))
    assert got[0][0].tobytes() == got[1][0].tobytes()
    assert np.array_equal(got[0][1], got[1][1])
    dist, partner = got[1]
    # the reference: one multi-source search per partner, inside each superfacet
    src = np.repeat(np.arange(n), np.diff(g.indptr))
    dst = g.indices.astype(np.int64)
    inside = (labels[src] == labels[dst]) & ~pinned[src] & ~pinned[dst]
    w = csr_matrix((geo[de][inside], (src[inside], dst[inside])), shape=(n, n))
    seeds = (partner >= 0) & (dist == 0) & ~pinned
    seed_partner = partner[seeds]
    best = np.full(n, np.inf)
    lowest = np.full(n, -1)
    for p in np.unique(seed_partner):  # ascending: a tie keeps the lower partner
        d = dijkstra(w, indices=np.flatnonzero(seeds)[seed_partner == p], min_only=True)
        closer = d < best
        best[closer], lowest[closer] = d[closer], p
    best[(best >= limit) | pinned] = np.inf
    lowest[~np.isfinite(best)] = -1
    assert np.array_equal(dist, best)
    assert np.array_equal(partner, lowest)
    assert (partner >= 0).sum() > n // 4 and not np.signbit(dist).any()


def test_the_clean_up_lets_the_graph_go_once_its_bands_are_found(valley):
    # what a run forgets there (the terms, border lengths, dual-edge map) is not read by
    # the cuts: the same labels, the callback called once, the graph left without them
    from superfacets import Mesh

    mesh = Mesh(valley.vertices, valley.faces)
    r = segment(mesh, 12, cleanup=False)
    g = face_graph(mesh)
    plain = clean_boundaries(g, r.labels, r.centers)
    calls = []

    def forget():
        calls.append(len(calls))
        g.release()
        g.release_terms()

    got = clean_boundaries(g, r.labels, r.centers, bands_found=forget)
    assert calls == [0]
    np.testing.assert_array_equal(got, plain)
    assert not {"terms", "lengths", "dual_edge", "edges"} & set(g.__dict__)


def test_a_run_unfinished_gives_its_last_pass_not_the_finishing_stages():
    """``pipeline(..., finished=False)`` (a tile's centers and refine phases, which keep
    only centers): the last pass's labels, made dense, each center in its own superfacet,
    no finishing stage timed; the finished run's labels differ only where those stages
    moved elements, and its centers are the same elements."""
    import trimesh

    from superfacets.method.params import resolve
    from superfacets.method.pipeline import pipeline

    m = trimesh.creation.icosphere(subdivisions=4)
    p = resolve(n_segments=40)
    raw = pipeline(m, p, finished=False)
    done = pipeline(m, p)
    labels, centers = np.asarray(raw.labels), np.asarray(raw.centers)
    assert labels.max() + 1 == centers.size == np.unique(labels).size
    np.testing.assert_array_equal(labels[centers], np.arange(centers.size))
    assert "cleanup" in done.timings and "cleanup" not in raw.timings
    np.testing.assert_array_equal(np.sort(done.centers), np.sort(centers))
    assert 0 < (np.asarray(done.labels) != labels).mean() < 0.2  # the clean-up's moves
