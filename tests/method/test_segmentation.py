import os
import sys

import numpy as np
import pytest
import trimesh
from conftest import MESHES, TABLE1, grid_mesh, need
from oracle.expand import MERGE, expand
from scipy.sparse import csr_array
from scipy.sparse.csgraph import dijkstra

from superfacets import InvalidMeshError, Mesh, ParameterError, read_mesh, segment, superfacets
from superfacets.api.segmentation import pipeline
from superfacets.elements import face_graph
from superfacets.method.classify import Exact
from superfacets.method.connectivity import label_components
from superfacets.method.expansion import Workspace, Workspaces, bucket_width
from superfacets.method.params import resolve
from superfacets.method.weights import paper_weights


def reference(mesh, n_segments, **kw):
    """The plain run: every center expanded on every pass, no cycle jump."""
    return pipeline(mesh, resolve(n_segments=n_segments, **kw), replay=False, jump_cycles=False)


def check_invariants(mesh, labels):
    assert labels.shape == (mesh.n_faces,) and labels.dtype == np.int64
    k = int(labels.max()) + 1
    assert labels.min() == 0 and np.unique(labels).size == k  # dense, every face labelled
    assert label_components(face_graph(mesh), labels).max() + 1 == k  # each superfacet connected
    areas = np.bincount(labels, weights=mesh.areas)
    assert areas.sum() == pytest.approx(mesh.area)
    return k


def crease_fraction(mesh, labels):
    """Fraction of the crease (x = 0) edge length lying on superfacet boundaries."""
    g = face_graph(mesh)
    v = mesh.vertices
    on_crease = (np.abs(v[g.edges[:, 0], 0]) < 1e-12) & (np.abs(v[g.edges[:, 1], 0]) < 1e-12)
    cut = labels[g.pairs[:, 0]] != labels[g.pairs[:, 1]]
    return cut[on_crease].mean()


def test_sphere_invariants_and_count(sphere):
    r = segment(sphere, 40)
    assert check_invariants(sphere, r.labels) == r.n_segments == 40
    assert r.centers.shape == (40,)
    assert (r.labels[r.centers] == np.arange(40)).all()
    assert r.n_iter >= 1 and set(r.timings) >= {"init", "iterations", "total"}


def test_deterministic(sphere):
    a = superfacets(sphere, 30, alpha=200)
    b = superfacets(sphere, 30, alpha=200)
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("init", ["farthest", "flood", "grid"])
def test_invariant_to_uniform_scaling_and_translation(init):
    rng = np.random.default_rng(0)
    tm = trimesh.creation.icosphere(subdivisions=3)
    v = tm.vertices * (1 + 0.3 * rng.random((len(tm.vertices), 1)))  # bumpy, no symmetry ties
    base = Mesh(v, tm.faces)
    kw = dict(n_segments=25) if init == "farthest" else dict(radius=0.15, n_segments=None)
    a = superfacets(base, init=init, **kw)
    # powers of two keep every floating-point operation exact
    moved = Mesh(v * 8.0 + np.array([64.0, -32.0, 16.0]), tm.faces)
    b = superfacets(moved, init=init, **kw)
    np.testing.assert_array_equal(a, b)
    # and a non-trivial scale gives the same segmentation up to rounding-level ties
    c = superfacets(Mesh(v * 3.7 + 1.1, tm.faces), init=init, **kw)
    assert (a == c).mean() > 0.99


@pytest.mark.parametrize("init", ["farthest", "flood", "grid"])
def test_each_initialization_gives_valid_superfacets(init, sphere):
    kw = dict(n_segments=30) if init == "farthest" else dict(radius=0.12, n_segments=None)
    r = segment(sphere, init=init, **kw)
    check_invariants(sphere, r.labels)
    assert r.params["init"] == init
    assert 10 <= r.n_segments <= 120


def test_crease_followed_with_high_alpha(valley):
    low = crease_fraction(valley, superfacets(valley, 40, alpha=0))
    high = crease_fraction(valley, superfacets(valley, 40, alpha=1000))
    assert high > 0.85
    assert high > low + 0.4


def _exact(g, cw, centers, k):
    m = g.n_elements
    dist, label = np.empty(m), np.empty(m, np.int32)
    n = Exact(g, cw, np.inf, Workspaces(m, cw, 1)).classify(centers, k, dist, label)[0]
    return n, dist, label


def test_exact_assignment_is_nearest_center(sphere):
    g = face_graph(sphere)
    rng = np.random.default_rng(1)
    w = paper_weights(sphere, alpha=100) * (1 + 0.01 * rng.random(g.n_edges))  # no ties
    cw = w[g.dual_edge]
    m = sphere.n_faces
    centers = np.empty(m, np.int64)
    centers[:12] = rng.choice(m, 12, replace=False)
    k, dist, label = _exact(g, cw, centers, 12)
    assert k == 12
    d = dijkstra(g.to_csr(w), indices=centers[:12])
    np.testing.assert_array_equal(label, np.argmin(d, axis=0))
    np.testing.assert_allclose(dist, d.min(axis=0))


@pytest.mark.parametrize("kind", ["faces", "vertices"])
def test_exact_assignment_ties_go_to_the_first_center(kind):
    # weights in eighths: every path sum is exact, so equal distances are real ties (a
    # grid has many); an element goes to the first listed center at the least distance,
    # however the search orders its work, and a repeated center stays empty
    from superfacets.elements.builders import elements_of

    g = elements_of(grid_mesh(12, 12), kind).graph
    rng = np.random.default_rng(3)
    w = rng.integers(1, 5, g.n_edges) / 8.0
    m = g.n_elements
    ties = 0
    for _ in range(5):
        centers = np.empty(m + 1, np.int64)
        centers[:9] = rng.choice(m, 9, replace=False)
        centers[9] = centers[2]  # a repeat: label 9 stays empty
        k, dist, label = _exact(g, w[g.dual_edge], centers, 10)
        d = dijkstra(g.to_csr(w), indices=centers[:10])
        np.testing.assert_array_equal(dist, d.min(axis=0))
        np.testing.assert_array_equal(label, np.argmin(d, axis=0))  # the first on ties
        assert k == 10 and 9 not in label
        ties += int(((d[:9] == d.min(axis=0)).sum(axis=0) > 1).sum())
    assert ties > 20


def test_exact_assignment_updated_pass_by_pass_equals_a_fresh_search(monkeypatch):
    # one classifier over a sequence of center lists (moves, a center dropped, a
    # repeat, the order shuffled, a piece left without a center): each pass updates
    # the previous one's cells and must give the fresh search's labels, distances
    # and orphan centers bit for bit; weights in eighths make the ties real
    import superfacets.method.classify as classify_module
    from superfacets.elements.builders import elements_of

    updated = []

    def counted(*args):
        out = reclassify(*args)
        updated.append(out >= 0)
        return out

    reclassify = classify_module.reclassify_exact
    monkeypatch.setattr(classify_module, "reclassify_exact", counted)
    grid = grid_mesh(16, 16)
    two = Mesh(np.r_[grid.vertices, grid.vertices + [100.0, 0, 0]],
               np.r_[grid.faces, grid.faces + grid.n_vertices])
    g = elements_of(two, "vertices").graph
    m = g.n_elements
    rng = np.random.default_rng(5)
    cw = (rng.integers(1, 5, g.n_edges) / 8.0)[g.dual_edge]
    reused = Exact(g, cw, np.inf, Workspaces(m, cw, 1))
    centers = np.empty(m + 8, np.int64)
    n = 12
    centers[:n] = rng.choice(m, n, replace=False)
    dist, label = np.empty(m), np.empty(m, np.int32)  # kept from pass to pass, as the passes do
    for step in range(120):
        fresh_centers = centers.copy()
        k0, d0, l0 = _exact(g, cw, fresh_centers, n)
        if step % 15 == 14:  # other arrays: a fresh search (the same result)
            dist, label = np.full(m, 7.0), np.full(m, 3, np.int32)
        k = reused.classify(centers, n, dist, label)[0]
        assert k == k0 and np.array_equal(centers[:k], fresh_centers[:k])
        np.testing.assert_array_equal(label, l0)
        np.testing.assert_array_equal(dist, d0)
        cs = centers[:k].copy()
        moved = rng.choice(k, min(k, int(rng.integers(1, 4))), replace=False)
        cs[moved] = rng.choice(m, moved.shape[0])
        change = step % 10
        if change == 1 and k > 3:
            cs = np.delete(cs, int(rng.integers(k)))
        elif change == 2:
            cs[int(rng.integers(k))] = cs[int(rng.integers(k))]
        elif change == 3:
            rng.shuffle(cs)
        elif change == 4:  # every center on the first grid: the second becomes an orphan
            cs = cs[cs < m // 2] if (cs < m // 2).any() else cs
        n = cs.shape[0]
        centers[:n] = cs
    assert 80 < sum(updated) and len(updated) <= 120 - 8  # not where the arrays changed


def test_exact_assignment_resumed_from_another_list_equals_a_fresh_search():
    """A classifier resumed from another classifier's result (a tile's labels phase from
    its refine round's last pass): the next search gives the fresh search's labels and
    distances bit for bit, with real ties (weights in eighths), where the shared centers
    keep their order (only the others' cells searched again) and where they do not (a
    fresh search)."""
    import superfacets.method.classify as classify_module
    from superfacets.elements.builders import elements_of

    g = elements_of(grid_mesh(20, 20), "vertices").graph
    m = g.n_elements
    rng = np.random.default_rng(11)
    cw = (rng.integers(1, 5, g.n_edges) / 8.0)[g.dual_edge]
    incremental = 0
    for trial in range(12):
        before = np.sort(rng.choice(m, 30, replace=False))
        centers = np.empty(m + 1, np.int64)
        centers[:30] = before
        k, dist, label = _exact(g, cw, centers, 30)
        after = np.sort(np.r_[np.delete(before, rng.choice(30, 4, replace=False)),
                              rng.choice(np.setdiff1d(np.arange(m), before), 3, replace=False)])
        if trial % 4 == 3:  # the shared centers in another order: searched afresh
            after = after[::-1].copy()
        fresh = np.empty(m + 1, np.int64)
        fresh[:after.size] = after
        k0, d0, l0 = _exact(g, cw, fresh.copy(), after.size)
        resumed = Exact(g, cw, np.inf, Workspaces(m, cw, 1))
        resumed.resume(centers[:k], dist, label)
        kernel = classify_module.reclassify_exact
        outcome = []
        classify_module.reclassify_exact = lambda *a: outcome.append(kernel(*a)) or outcome[-1]
        try:
            k1 = resumed.classify(fresh, after.size, dist, label)[0]
        finally:
            classify_module.reclassify_exact = kernel
        assert k1 == k0
        np.testing.assert_array_equal(label, l0)
        np.testing.assert_array_equal(dist, d0)
        incremental += outcome[0] >= 0
        assert (outcome[0] >= 0) == (trial % 4 != 3)
    assert incremental == 9


def test_passes_listed_by_a_key_give_the_same_superfacets_their_list_in_its_order():
    """``order`` (a tile's refine round: centers listed by row) changes only the list's
    order: on a cloud without ties the same superfacets pass by pass, the same passes,
    and the last classification's centers listed by the key."""
    from superfacets.inputs.cloud import PointCloud

    rng = np.random.default_rng(2)
    xy = rng.random((6000, 2))
    cloud = PointCloud(np.c_[xy, 0.05 * np.sin(6 * xy[:, 0])])
    p = resolve(n_segments=40, merge_from=1)
    plain = pipeline(cloud, p, finished=False, order=None)
    key = rng.permutation(cloud.points.shape[0]).astype(np.int64)  # any distinct key
    ordered = pipeline(cloud, p, finished=False, order=key)
    label, centers, dist, _ = ordered.classification
    assert (np.diff(key[centers]) > 0).all()
    assert ordered.n_iter == plain.n_iter and ordered.timings["settled"] == \
        plain.timings["settled"]
    l0, c0, d0, _ = plain.classification
    np.testing.assert_array_equal(centers[label], c0[l0])  # each element's center
    np.testing.assert_array_equal(dist, d0)


@pytest.mark.parametrize("assignment", ["bounded", "exact"])
def test_centers_on_fixed_elements_stay_through_the_passes_and_the_swaps(sphere, assignment):
    """``fixed`` (a tile's halo): the centers started on those elements are centers at the
    end, on the same elements, through passes and swaps; the others move as the passes
    move them."""
    p = resolve(n_segments=60, assignment=assignment, cleanup=False)
    init = np.sort(np.random.default_rng(0).choice(sphere.n_faces, 60, replace=False))
    lower = np.asarray(sphere.centroids)[:, 2] < 0  # the lower half's centers held
    free = np.asarray(pipeline(sphere, p, finished=False, initial=init).centers)
    held = pipeline(sphere, p, finished=False, initial=init, fixed=lower)
    kept = np.asarray(held.centers)
    assert np.isin(init[lower[init]], kept).all()
    assert not np.isin(init[lower[init]], free).all()  # (where the passes move them)
    assert np.isin(init[~lower[init]], kept).mean() < 0.5  # the upper half's moved
    assert held.timings["passes"] >= 2


def test_bounded_expansion_is_dijkstra_inside_the_window(sphere):
    g = face_graph(sphere)
    w = paper_weights(sphere, alpha=200)
    cw = w[g.dual_edge]
    m = sphere.n_faces
    c = np.ascontiguousarray(sphere.centroids)
    src, radius = 17, 0.5
    inside = ((c - c[src]) ** 2).sum(1) <= radius**2
    # reference: Dijkstra on the subgraph induced by the window
    keep = inside[g.pairs[:, 0]] & inside[g.pairs[:, 1]]
    i, j = g.pairs[keep, 0], g.pairs[keep, 1]
    a = csr_array((np.r_[w[keep], w[keep]], (np.r_[i, j], np.r_[j, i])), shape=(m, m))
    ref = dijkstra(a, indices=src)
    dist = np.full(m, np.inf)
    label = np.full(m, -1, np.int64)
    ws = Workspace(m, *bucket_width(cw)[1:], g.indices.size + m + 1)
    local = np.zeros(m)  # (the reference's dense scratch)
    expand(g.indptr, g.indices, cw, c, src, 0, radius**2, dist, label, local,
           ws.queue, bucket_width(cw)[0], MERGE, ws.vis, np.empty(0), 0, ws.vis.size)
    assert not local.view(np.uint64).any()  # the scratch is left as it was found
    reached = label == 0
    assert reached.sum() > 50
    np.testing.assert_array_equal(reached, np.isfinite(ref))
    np.testing.assert_array_equal(dist[reached], ref[reached])  # the same sums, bit for bit


def test_interrupted_expansion_leaves_its_scratch_clean(sphere):
    """An expansion stopped by a full record or queue puts +0.0 back in the reference's
    ``local`` (and the compiled one clears its table), so the caller can grow the buffer
    and run it again: the uninterrupted result."""
    from oracle.expand import QUEUE_FULL, RECORD_FULL

    from superfacets._kernels import native

    g = face_graph(sphere)
    cw = paper_weights(sphere, alpha=200)[g.dual_edge]
    m = sphere.n_faces
    c = np.ascontiguousarray(sphere.centroids)
    inv_width, nb = bucket_width(cw)
    full = Workspace(m, nb, g.indices.size + m + 1)
    full.local = np.zeros(m)  # (the reference's dense scratch)
    dist, label = np.full(m, np.inf), np.full(m, -1, np.int64)
    n = expand(g.indptr, g.indices, cw, c, 17, 0, 1.0, dist, label, full.local, full.queue,
               inv_width, MERGE, full.vis, np.empty(0), 0, full.vis.size)
    assert n > 40
    small = Workspace(m, nb, g.indices.size + m + 1)
    small.local = np.zeros(m)
    small._queue(4)
    for ws, lim, status in ((full, 20, RECORD_FULL), (small, small.vis.size, QUEUE_FULL)):
        d2, l2 = np.full(m, np.inf), np.full(m, -1, np.int64)
        st = expand(g.indptr, g.indices, cw, c, 17, 0, 1.0, d2, l2, ws.local, ws.queue,
                    inv_width, MERGE, ws.vis, np.empty(0), 0, lim)
        assert st == status
        assert not ws.local.view(np.uint64).any()
        assert (ws.head == -1).all()
        assert (l2 == -1).all()  # nothing was merged
    # grown, the same expansion gives the uninterrupted result
    small.grow(QUEUE_FULL)
    while True:
        d2, l2 = np.full(m, np.inf), np.full(m, -1, np.int64)
        st = expand(g.indptr, g.indices, cw, c, 17, 0, 1.0, d2, l2, small.local, small.queue,
                    inv_width, MERGE, small.vis, np.empty(0), 0, small.vis.size)
        if st != QUEUE_FULL:
            break
        small.grow(st)
    assert st == n
    np.testing.assert_array_equal(d2, dist)
    np.testing.assert_array_equal(l2, label)
    # the compiled classification (its own scratch, no dense one given): stopped by a full
    # queue, it gives, grown, the same distances and labels as with room
    if native.available():
        classify = native.kernel("expand.classify_bounded")
        got, stops = [], 0
        for cap in (4, None):
            ws = Workspace(m, nb, g.indices.size + m + 1)
            if cap:
                ws._queue(cap)
            d3, l3 = np.full(m, np.inf), np.full(m, -1, np.int32)
            centers = np.zeros(m, dtype=np.int64)  # (room for orphans' centers)
            centers[:2] = [17, 400]
            while (k := classify(g.indptr, g.indices, cw, c, centers, 2, 1.0, d3, l3,
                                 ws.local, ws.queue, inv_width, ws.vis, np.empty(0))) < 0:
                assert k == QUEUE_FULL and cap
                stops += 1
                ws.grow(k)
                d3, l3 = np.full(m, np.inf), np.full(m, -1, np.int32)
                centers[2:] = 0
            got.append((d3, l3))
        assert stops >= 1 and (got[1][1] >= 0).sum() > 40
        np.testing.assert_array_equal(got[0][0], got[1][0])
        np.testing.assert_array_equal(got[0][1], got[1][1])


def test_replayed_expansions_equal_reference_on_synthetic(valley, sphere):
    for mesh in (valley, sphere):
        for kw in (dict(alpha=0), dict(alpha=200), dict(alpha=1000, init="grid", radius=0.1,
                                                           n_segments=None)):
            a = segment(mesh, **{"n_segments": 30, **kw})
            b = reference(mesh, **{"n_segments": 30, **kw})
            np.testing.assert_array_equal(a.labels, b.labels)
            assert a.n_iter == b.n_iter


@pytest.mark.parametrize("n_threads", [1, 2])
@pytest.mark.parametrize("source", ["grid", "bunny"])
def test_labels_updated_in_place_equal_the_plain_run(monkeypatch, source, n_threads):
    # late passes, where few centers move, update the previous labels in place (only the
    # faces of the centers that moved, from the records that can reach them): the labels
    # of merging every record, on a grid of exact ties too; counted, so that the path runs
    from superfacets.method import classify

    mesh = grid_mesh(70, 60) if source == "grid" else read_mesh(need(MESHES / "bunny.tri.xz"))
    k = 40 if source == "grid" else 150
    in_place = []
    orig = classify.BoundedReplay._unset_moved

    def counted(self, *args):
        out = orig(self, *args)
        in_place.append(out is not None)
        return out

    monkeypatch.setattr(classify.BoundedReplay, "_unset_moved", counted)
    monkeypatch.setattr(classify, "_PARALLEL_MIN_WORK", 0)
    a = segment(mesh, k, max_iter=40, paper=True, n_threads=n_threads)
    b = reference(mesh, k, max_iter=40, paper=True)
    np.testing.assert_array_equal(a.labels, b.labels)
    assert a.n_iter == b.n_iter and sum(in_place) >= 2, in_place


@pytest.mark.parametrize("name", TABLE1)
def test_replayed_expansions_equal_reference_on_real_meshes(name):
    mesh = read_mesh(need(MESHES / f"{name}.tri.xz"))
    a = segment(mesh, 150, max_iter=12)
    b = reference(mesh, 150, max_iter=12)
    np.testing.assert_array_equal(a.labels, b.labels)


@pytest.mark.parametrize("source, k, alpha, max_iter", [
    ("bunny", 150, 200, 10), ("hand_olivier", 150, 200, 6), ("psb:58", 60, 1000, 30),
    ("psb:124", 150, 200, 20), ("psb:216", 100, 0, 25), ("grid", 40, 200, 20)])
def test_optimized_path_gives_the_labels_of_the_straightforward_one(
        monkeypatch, psb, source, k, alpha, max_iter):
    # the plain iteration (scipy Dijkstra per window, numpy center update, every pass run)
    # against the package: bucket-queue expansions, replayed records, cycle skipping
    # (psb:58 falls into a cycle), on one thread and on two. On the flat regular grid many
    # distances tie exactly: the center of lowest index must win them, across threads too
    import straightforward

    from superfacets.elements.labels import relabel_dense
    from superfacets.method import classify

    if source == "grid":
        mesh = grid_mesh(70, 60)
    else:
        mesh = read_mesh(psb / "off" / f"{source[4:]}.off" if source.startswith("psb:")
                         else need(MESHES / f"{source}.tri.xz"))
    ref, n_iter = straightforward.segment_labels(mesh, k, alpha=alpha, max_iter=max_iter)
    monkeypatch.setattr(classify, "_PARALLEL_MIN_WORK", 0)  # threads on every pass
    for n_threads in (1, 2):
        r = segment(mesh, k, alpha=alpha, max_iter=max_iter, enforce_connectivity=False,
                    n_threads=n_threads, paper=True)  # the paper's method, whatever the defaults
        np.testing.assert_array_equal(r.labels, relabel_dense(ref))
        assert r.n_iter == n_iter


@pytest.mark.parametrize("n_threads", [1, 2, 3])
def test_threads_and_buffer_growth_change_no_label(monkeypatch, n_threads):
    # every expansion on threads (no minimum work), a heap of 4 entries and a record arena
    # of a tenth of the faces in a reservation of a fifth: the heap regrows, the arena is
    # compacted, its room raised within the reservation and then copied into a larger one,
    # an overflowing thread is redone; labels stay those of the straightforward loop
    from superfacets.method import classify, expansion

    mesh = read_mesh(need(MESHES / "bunny.tri.xz"))
    ref = reference(mesh, 150, max_iter=15)
    monkeypatch.setattr(classify, "_PARALLEL_MIN_WORK", 0)
    monkeypatch.setattr(expansion, "_QUEUE0", 4)
    monkeypatch.setattr(expansion, "_VISIT0", 8)
    monkeypatch.setattr(classify, "_ARENA", 0.1)
    monkeypatch.setattr(classify, "_RESERVE", 0.2)
    grown = []  # (arena allocation before, after) of each raise of the room
    orig = classify.BoundedReplay._grow

    def grow(self, x):
        before = self.face.shape[0]
        orig(self, x)
        grown.append((before, self.face.shape[0]))

    monkeypatch.setattr(classify.BoundedReplay, "_grow", grow)
    r = segment(mesh, 150, max_iter=15, n_threads=n_threads)
    np.testing.assert_array_equal(r.labels, ref.labels)
    np.testing.assert_array_equal(r.centers, ref.centers)
    assert (r.n_iter, r.n_orphan_seeds) == (ref.n_iter, ref.n_orphan_seeds)
    assert any(a == b for a, b in grown) and any(b > a for a, b in grown)


def test_n_threads_is_checked(sphere):
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ParameterError, match="n_threads"):
            segment(sphere, 10, n_threads=bad)


@pytest.mark.parametrize("name, faces", [("bunny", 69451), ("horse", 96966), ("hand_olivier",
                                                                              105860)])
def test_table1_meshes_invariants(name, faces):
    mesh = read_mesh(need(MESHES / f"{name}.tri.xz"))
    r = segment(mesh, 150, alpha=200)
    assert mesh.n_faces == faces
    k = check_invariants(mesh, r.labels)
    assert 140 <= k <= 170


@pytest.mark.parametrize("part", range(4))  # (four tests: a parallel run shares them)
def test_psb_every_mesh_invariants(psb, part):
    files = sorted((psb / "off").glob("*.off"), key=lambda p: int(p.stem))
    assert len(files) >= 4
    for path in files[part::4]:
        mesh = read_mesh(path)
        labels = superfacets(mesh, 150, alpha=200)
        k = check_invariants(mesh, labels)
        assert 140 <= k <= 170, path.name


def test_components_each_get_superfacets():
    a = trimesh.creation.icosphere(subdivisions=2)
    b = trimesh.creation.icosphere(subdivisions=2)
    v = np.vstack([a.vertices, b.vertices * 0.5 + [5, 0, 0]])
    f = np.vstack([a.faces, b.faces + len(a.vertices)])
    mesh = Mesh(v, f)
    # the paper's one center: the other sphere is re-seeded by its orphans; by default
    # every piece has a center from the start (more pieces than asked: one each)
    for r, orphans in ((segment(mesh, 1, paper=True), 1), (segment(mesh, 1), 0)):
        assert r.n_segments == 2 and (r.n_orphan_seeds >= 1) == bool(orphans)
        assert len(np.unique(r.labels[: len(a.faces)])) == 1
        assert len(np.unique(r.labels[len(a.faces):])) == 1
    labels = superfacets(mesh, 20)
    check_invariants(mesh, labels)
    assert not set(labels[: len(a.faces)]) & set(labels[len(a.faces):])


@pytest.mark.parametrize("elements", ["faces", "vertices"])
def test_separate_pieces_keep_the_count_asked(elements):
    # two beads above a slab, missed by the paper's farthest points: the paper seeds
    # each from its orphans, 2 more than asked; by default each bead has a center
    # within the count (the paper's first k - 2 and one per bead): k asked are k
    from conftest import slab_and_beads

    mesh, n, n_bead = slab_and_beads()
    for k in (10, 20):
        paper = segment(mesh, k, paper=True, elements=elements)
        default = segment(mesh, k, elements=elements)
        assert (paper.n_segments, paper.n_orphan_seeds) == (k + 2, 2)
        assert (default.n_segments, default.n_orphan_seeds) == (k, 0)
        if elements == "faces":
            for r in (paper, default):
                beads = r.labels[n:].reshape(2, n_bead)
                assert all(len(set(b)) == 1 for b in beads)       # a bead is one superfacet
                assert not set(beads[:, 0]) & set(r.labels[:n])   # of its own
    # more pieces than asked: one superfacet each, as the paper's orphans give
    assert segment(mesh, 2, elements=elements).n_segments == 3


def test_separate_pieces_of_a_cloud_keep_the_count_asked():
    from superfacets import PointCloud

    rng = np.random.default_rng(0)
    plane = np.c_[rng.uniform(0, 1, (4000, 2)), np.zeros(4000)]
    blobs = [rng.normal(0, 0.005, (40, 3)) + [0.2 * i + 0.1, 1.05, 0.0] for i in range(5)]
    cloud = PointCloud(np.vstack([plane] + blobs))
    paper = segment(cloud, 30, paper=True)  # blobs its farthest points missed: extra
    assert paper.n_segments > 30 and paper.n_orphan_seeds == paper.n_segments - 30
    r = segment(cloud, 30, merge_from=1)  # the method's own centers: 30
    assert r.params["n_init_centers"] == 30 and r.n_segments < paper.n_segments
    merged = segment(cloud, 30)  # 150 superpoints merged to 30: pieces stay apart
    assert merged.n_segments == 30 and all(
        len(set(merged.labels[4000 + 40 * i:4040 + 40 * i])) == 1 for i in range(5))
    blob_labels = [set(r.labels[4000 + 40 * i:4040 + 40 * i]) for i in range(5)]
    assert all(len(b) == 1 for b in blob_labels)              # a blob is one superpoint
    assert not set().union(*blob_labels) & set(r.labels[:4000])  # of its own


def test_odd_but_valid_input():
    tm = trimesh.creation.icosphere(subdivisions=3)
    v = np.vstack([tm.vertices, [[9.0, 9.0, 9.0]]])  # unreferenced vertex
    f = tm.faces.copy()
    extra = [
        f[0],                                  # duplicate face
        [f[1, 0], f[1, 0], f[1, 1]],           # degenerate face (repeated vertex)
        [f[2, 0], f[2, 1], len(tm.vertices) - 1],  # a fin on an edge: non-manifold edge
    ]
    mesh = Mesh(v, np.vstack([f, extra]))
    assert mesh.areas[-2] == 0
    r = segment(mesh, 30)
    check_invariants(mesh, r.labels)
    r2 = segment(mesh, 30, assignment="exact")
    check_invariants(mesh, r2.labels)


def test_exact_assignment_option(sphere):
    r = segment(sphere, 30, assignment="exact")
    check_invariants(sphere, r.labels)
    assert r.params["assignment"] == "exact"


def test_default_assignment_is_exact_on_vertices_only():
    # the default's exact classification reaches every vertex of a connected mesh (no
    # window to miss one), so it seeds no orphan and returns the count asked; faces and
    # the paper's method keep the windows
    mesh = grid_mesh(40, 40, height=lambda x, y: 0.15 * np.sin(6 * x) * np.cos(5 * y))
    paper = segment(mesh, 60, elements="vertices", paper=True)
    default = segment(mesh, 60, elements="vertices")
    assert paper.params["assignment"] == "bounded"
    assert default.params["assignment"] == "exact"
    assert segment(mesh, 60).params["assignment"] == "bounded"
    assert segment(mesh, 60, elements="vertices", assignment="bounded").params[
        "assignment"] == "bounded"
    assert default.n_segments == 60 and default.n_orphan_seeds == 0


def test_shlafman_weighting_runs(sphere):
    r = segment(sphere, 30, weighting="shlafman", alpha=0.5)
    check_invariants(sphere, r.labels)


def test_without_connectivity_labels_stay_dense(valley):
    labels = superfacets(valley, 60, alpha=1000, enforce_connectivity=False)
    assert np.unique(labels).size == labels.max() + 1


def test_max_iter_one_and_convergence_flag(sphere):
    r = segment(sphere, 30, max_iter=1)
    assert r.n_iter == 1 and not r.converged
    r = segment(sphere, 30, max_iter=200)
    assert r.converged == (r.n_iter < 200)


@pytest.mark.parametrize("kwargs, match", [
    (dict(n_segments=0), "n_segments must be an integer >= 1"),
    (dict(n_segments=10**7), "larger than the number of faces"),
    (dict(n_segments=3.5), "must be an integer"),
    (dict(n_segments=20, radius=0.1), "not both"),
    (dict(radius=-0.1, n_segments=None), r"radius must be a finite number in \(0, 1000\]"),
    (dict(radius=1e300, n_segments=None), r"radius must be a finite number in \(0, 1000\]"),
    (dict(alpha=-5.0), r"alpha must be a finite number in \[0, 1e\+12\]"),
    (dict(alpha=float("nan")), r"alpha must be a finite number in \[0, 1e\+12\]"),
    (dict(window=0), r"window must be a finite number in \(0, 1000\]"),
    (dict(max_iter=0), "max_iter must be an integer >= 1"),
    (dict(init="random"), "init must be one of"),
    (dict(assignment="fast"), "assignment must be one of"),
    (dict(weighting="shlafman", alpha=200.0), r"\[0, 1\]"),
])
def test_parameter_errors(sphere, kwargs, match):
    with pytest.raises(ParameterError, match=match):
        segment(sphere, **kwargs)


def test_unusable_meshes():
    with pytest.raises(InvalidMeshError, match="zero total area"):
        superfacets((np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], float), [[0, 1, 2]]), 1)
    with pytest.raises(InvalidMeshError, match="empty mesh"):
        superfacets((np.zeros((3, 3)), np.zeros((0, 3), int)), 1)


def test_k_equals_faces_gives_one_face_each():
    mesh = grid_mesh(3, 3)
    labels = superfacets(mesh, mesh.n_faces, alpha=0)
    assert np.unique(labels).size == mesh.n_faces


@pytest.mark.parametrize("mesh_id, max_iter", [(58, 30), (58, 31), (124, 30), (124, 33), (216, 30)])
def test_cycle_jump_gives_the_labels_of_running_every_pass(psb, mesh_id, max_iter):
    # these runs (k = 60, alpha = 1000) fall into a cycle of center sets of period 2, 4, 3:
    # the optimized run classifies only until the cycle shows, then the state of the
    # last pass; the reference runs all max_iter passes
    mesh = read_mesh(psb / "off" / f"{mesh_id}.off")
    a = segment(mesh, 60, alpha=1000, max_iter=max_iter, paper=True)  # the paper's rule: cycles
    b = reference(mesh, 60, alpha=1000, max_iter=max_iter, paper=True)
    assert a.timings["cycle_period"] >= 2 and a.timings["passes"] < max_iter
    assert b.timings["passes"] == max_iter and b.timings["cycle_period"] == 0
    np.testing.assert_array_equal(a.labels, b.labels)
    np.testing.assert_array_equal(a.centers, b.centers)
    assert (a.n_iter, a.converged, a.n_orphan_seeds) == (b.n_iter, b.converged, b.n_orphan_seeds)


def test_import_starts_no_thread():
    import subprocess
    import sys

    code = "import threading, superfacets; print(threading.active_count())"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["1"]  # nothing started by the import


def test_tol_zero_is_the_paper_rule_and_tol_stops_early(psb):
    mesh = read_mesh(psb / "off" / "124.off")  # falls into a cycle at alpha 1000
    same = segment(mesh, 60, alpha=1000, max_iter=40, paper=True)
    base = reference(mesh, 60, alpha=1000, max_iter=40, paper=True)  # every pass, no jump
    np.testing.assert_array_equal(base.labels, same.labels)
    assert same.timings["changed"] == -1.0 and not same.timings["stopped_by_tol"]
    paper_passes = dict(cleanup=False, split_merge=False)  # the passes alone, tol aside
    default = segment(mesh, 60, alpha=1000, max_iter=40, **paper_passes)  # tol = 0.001
    assert default.params["tol"] == 0.001 and default.n_iter <= same.n_iter
    early = segment(mesh, 60, alpha=1000, max_iter=40, tol=0.01, **paper_passes)
    assert early.timings["stopped_by_tol"] and early.converged
    assert early.n_iter < base.n_iter and 0 <= early.timings["changed"] <= 0.01
    # the rule against the plain loop: the labels of the pass where the change fell below tol
    plain = reference(mesh, 60, alpha=1000, max_iter=early.n_iter, tol=0.01, **paper_passes)
    np.testing.assert_array_equal(early.labels, plain.labels)
    with pytest.raises(ParameterError, match="tol"):
        segment(mesh, 60, tol=-0.1)


def test_n_threads_also_bounds_the_graph_build(monkeypatch):
    # a fresh mesh's face graph is built inside the run: with n_threads=1 every
    # range-splitting step runs one range, with 2 some run two; same labels
    from superfacets import Mesh, segment
    from superfacets._runtime import threads as _threads
    from superfacets.inputs.shapes import creature

    shape = creature(24)
    monkeypatch.setattr(_threads, "MIN_PER_THREAD", 50)
    seen = []
    run = _threads.run_ranges
    monkeypatch.setattr(_threads, "run_ranges",
                        lambda fn, bounds: seen.append(len(bounds) - 1) or run(fn, bounds))
    one = segment(Mesh(shape.vertices, shape.faces), 40, n_threads=1).labels
    assert seen and max(seen) == 1
    seen.clear()
    two = segment(Mesh(shape.vertices, shape.faces), 40, n_threads=2).labels
    assert max(seen) == 2
    assert np.array_equal(one, two)


def test_paper_switch_gives_the_straightforward_papers_labels(sphere, valley):
    # paper=True: the method as published, bit for bit, whatever the package's defaults
    import straightforward

    from superfacets.elements.labels import relabel_dense

    for mesh, k in ((sphere, 40), (valley, 12)):
        ref, _ = straightforward.segment_labels(mesh, k, alpha=200.0, max_iter=50)
        got = segment(mesh, k, paper=True, enforce_connectivity=False)
        np.testing.assert_array_equal(got.labels, relabel_dense(ref))
        assert got.params["tol"] == 0.0 and got.params["cleanup"] is False
        assert got.params["split_merge"] is False


@pytest.mark.parametrize("option", [dict(cleanup=True), dict(split_merge=True), dict(tol=0.01),
                                    dict(center_tol=0.1), dict(coarsen=50)])
def test_paper_switch_refuses_what_the_paper_does_not_do(sphere, option):
    from superfacets import ParameterError

    with pytest.raises(ParameterError, match="paper=True is the paper's method"):
        segment(sphere, 20, paper=True, **option)


def test_fast_split_merge_schedule_keeps_k_connected_and_is_deterministic(sphere):
    from superfacets.elements import face_graph
    from superfacets.method.connectivity import label_components

    one = segment(sphere, 30, split_merge=True, cleanup=True, n_threads=1)
    two = segment(sphere, 30, split_merge=True, cleanup=True, n_threads=2)
    np.testing.assert_array_equal(one.labels, two.labels)
    assert one.n_segments == 30
    assert label_components(face_graph(sphere), one.labels).max() + 1 == 30
    # the early schedule: fewer passes than iterating to convergence before the swaps
    slow = segment(sphere, 30, split_merge=True, cleanup=True, tol=0.0)
    assert one.timings["passes"] <= slow.timings["passes"]


def test_the_result_says_why_the_passes_stopped(tmp_path, capsys):
    """A run that stops on a detected cycle of center lists said 'stopped at max-iter'
    (converged False) on 18 of 19 scans: it says 'cycle' now, and the command line
    names the period."""
    from superfacets.cli import main
    from superfacets.inputs.shapes import creature

    mesh = creature(40)
    cyc = segment(mesh, 20, paper=True)
    assert cyc.stop_reason == "cycle" and cyc.timings["cycle_period"] == 2
    assert cyc.n_iter == 50 and not cyc.converged
    assert segment(mesh, 40, paper=True).stop_reason == "converged"
    assert segment(mesh, 40).stop_reason in ("tolerance", "converged")
    assert segment(mesh, 40, paper=True, max_iter=3).stop_reason == "max_iter"
    from superfacets import write_mesh

    write_mesh(tmp_path / "c.off", mesh)
    assert main(["segment", str(tmp_path / "c.off"), "-k", "20", "--paper",
                 "-o", str(tmp_path / "c.seg")]) == 0
    out = capsys.readouterr().out
    assert "stopped: the centers oscillate with period 2 (the labels of pass 50" in out


def test_workspaces_released_between_passes_give_the_same_labels(sphere):
    # split-and-merge releases the expansions' buffers during its swaps; the next
    # passes make them again (all inf) and replay the same records
    from superfacets.method.classify import make_classifier

    g = face_graph(sphere)
    cw = paper_weights(sphere, alpha=200)[g.dual_edge]
    m = sphere.n_faces

    def passes(release: bool):
        spaces = Workspaces(m, cw, 2)
        clf = make_classifier("bounded", g, cw, 0.6**2, spaces)
        out = []
        for first in (np.arange(0, m, 97), np.r_[np.arange(0, m, 97)[:-3], 5, 6, 7]):
            centers = np.zeros(m, dtype=np.int64)
            centers[:first.size] = first
            dist, label = np.full(m, np.inf), np.full(m, -1, dtype=np.int32)
            k, _ = clf.classify(centers, first.size, dist, label)
            out.append((k, label.copy(), dist.copy()))
            if release:
                spaces.release()
                assert spaces.ws == []
        spaces.close()
        return out

    for (k1, l1, d1), (k2, l2, d2) in zip(passes(False), passes(True)):
        assert k1 == k2
        np.testing.assert_array_equal(l1, l2)
        np.testing.assert_array_equal(d1, d2)
    assert Workspaces(m, cw, 2).get(1).local.size == 0  # (the compiled scratch is a table)


def test_arena_tail_discarded_after_each_pass_gives_the_same_labels(sphere, monkeypatch):
    # on large graphs the record arena's pages past its end are discarded after each
    # pass: the same labels and distances; the threads' buffers stay zeros between
    # passes (kept, not handed back) and are forgotten when the workspaces close
    from superfacets.method import classify

    discarded = []
    real_discard = classify.discard_pages
    monkeypatch.setattr(classify, "discard_pages",
                        lambda a: discarded.append(a.shape[0]) or real_discard(a))

    g = face_graph(sphere)
    cw = paper_weights(sphere, alpha=200)[g.dual_edge]
    m = sphere.n_faces

    def passes(discard_min):
        monkeypatch.setattr(classify, "_DISCARD_MIN", discard_min)
        monkeypatch.setattr(classify, "_PARALLEL_MIN_WORK", 0)  # both threads expand
        spaces = Workspaces(m, cw, 2)
        clf = classify.make_classifier("bounded", g, cw, 0.6**2, spaces)
        out = []
        centers = np.zeros(m, dtype=np.int64)
        first = np.arange(0, m, 97)
        centers[:first.size] = first
        dist, label = np.full(m, np.inf), np.full(m, -1, dtype=np.int32)
        for _ in range(3):  # passes, each center moved to the next face
            k, _ = clf.classify(centers, first.size, dist, label)
            out.append((k, label.copy(), dist.copy()))
            assert len(spaces.ws) == 2
            assert all(ws.local.size == 0 for ws in spaces.ws)  # (no dense scratch)
            centers[:first.size] = (centers[:first.size] + 1) % m
        spaces.close()
        assert spaces.ws == []
        return out

    kept, tail_discarded = passes(1 << 60), passes(0)
    assert len(discarded) == 6  # the arena's two arrays past the end, each pass
    for (k1, l1, d1), (k2, l2, d2) in zip(kept, tail_discarded):
        assert k1 == k2
        np.testing.assert_array_equal(l1, l2)
        np.testing.assert_array_equal(d1, d2)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="madvise: Linux only")
def test_pages_handed_back_leave_zeros_and_free_the_memory():
    from superfacets._runtime.memory import discard_pages

    def resident_mib():
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20

    a = np.ones(16 << 20)  # 128 MiB, written
    a[:] = 0.0
    before = resident_mib()
    discard_pages(a)
    assert resident_mib() < before - 100  # its pages are gone...
    assert not a.view(np.uint64).any()  # ... and read as zeros
    a[::4096] = 1.0  # written again: as any array
    assert a.sum() == a[::4096].shape[0]
    discard_pages(a[::2])  # not contiguous: nothing done
    assert a.sum() == a[::4096].shape[0]


def test_the_record_arena_does_not_grow_every_pass_when_windows_differ_in_size(monkeypatch):
    """One large piece and eleven small ones, two threads: a thread's share of the room, in
    proportion to its centers, falls short every pass; each retry doubled the whole free
    room, so the arena grew twofold each pass (267M entries for 31,650 points in 14 passes;
    a scan of 209,280 points ran out of memory). Now a retry first takes the room there is:
    the same labels as one thread, the arena as first reserved."""
    from superfacets.method import classify

    monkeypatch.setattr(classify, "_PARALLEL_MIN_WORK", 0)
    sizes = []
    orig = classify.BoundedReplay._grow

    def grow(self, x):
        orig(self, x)
        sizes.append(self.face.shape[0])

    monkeypatch.setattr(classify.BoundedReplay, "_grow", grow)
    rng = np.random.default_rng(0)
    pts = np.concatenate([np.c_[rng.random((30000, 2)) * 10, np.zeros(30000)]] + [
        np.c_[rng.random((150, 2)) * 0.5 + [20 + 3 * i, 0], np.zeros(150)] for i in range(11)])
    two = segment(pts, 12, paper=True, n_threads=2, max_iter=30)
    one = segment(pts, 12, paper=True, n_threads=1, max_iter=30)
    np.testing.assert_array_equal(two.labels, one.labels)
    assert two.n_iter >= 10 and max(sizes, default=0) <= 4 * classify._RESERVE * len(pts)
