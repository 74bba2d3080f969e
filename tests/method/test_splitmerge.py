"""Split-and-merge swaps: a known answer on a folded plane, invariants on real meshes."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import MESHES, grid_mesh, need

from superfacets import Mesh, read_mesh, segment
from superfacets.elements import face_graph
from superfacets.errors import ParameterError
from superfacets.method.connectivity import label_components
from superfacets.method.splitmerge import swap_round
from superfacets.method.weights import csr_weights, edge_weights


def _valley():
    """A strip 2 x 0.5 of square cells 0.05 wide, folded along x = 0 into a
    concave valley z = 0.5 |x|; and the column of each face's cell."""
    nx, ny = 40, 10
    m = grid_mesh(nx, ny, height=lambda x, y: 0.5 * np.abs(x))
    v = m.vertices * [1.0, 0.25, 1.0]  # y in [-0.25, 0.25]: square cells
    mesh = Mesh(v, m.faces)
    col = np.floor((mesh.centroids[:, 0] + 1) / 2 * nx).astype(int)
    return mesh, col


def _weights(mesh, alpha=200.0):
    g = face_graph(mesh)
    return csr_weights(g, edge_weights(g, "paper", alpha=alpha, eta_convex=0.2))


def test_a_superfacet_straddling_a_crease_is_split_on_it_and_two_flat_ones_merge():
    mesh, col = _valley()
    x = mesh.centroids[:, 0]
    # 0 straddles the crease (|x| < 0.25); 1, 2, 3 are strips 0.25 wide on the right
    # slope, 4 the whole left slope beyond the crease's superfacet
    labels = np.select([np.abs(x) < 0.25, x < 0, x < 0.5, x < 0.75], [0, 4, 1, 2], 3)
    out, n = swap_round(face_graph(mesh), _weights(mesh), labels)
    assert n == 1
    assert np.unique(out).size == 5  # the number of superfacets is kept
    on_left = (np.abs(x) < 0.25) & (x < 0)
    on_right = (np.abs(x) < 0.25) & (x > 0)
    # the straddling superfacet is cut exactly on the crease
    assert np.unique(out[on_left]).size == 1 and np.unique(out[on_right]).size == 1
    assert out[on_left][0] != out[on_right][0]
    # two neighbouring strips of the flat slope became one; the left slope is untouched
    merged = [(a, b) for a, b in ((1, 2), (2, 3)) if out[labels == a][0] == out[labels == b][0]]
    assert len(merged) == 1
    assert np.unique(out[labels == 4]).size == 1 and out[labels == 4][0] == 4
    assert np.unique(label_components(face_graph(mesh), out)).size == 5  # each one connected


def test_the_crease_decides_which_superfacet_is_split():
    # alpha = 0: the fold is invisible to the distance; the square on it is as round
    # as any and is kept, the largest superfacet (the left slope) is split instead
    mesh, col = _valley()
    x = mesh.centroids[:, 0]
    labels = np.select([np.abs(x) < 0.25, x < 0, x < 0.5, x < 0.75], [0, 4, 1, 2], 3)
    out, n = swap_round(face_graph(mesh), _weights(mesh, alpha=0.0), labels)
    assert n == 1
    assert np.unique(out[labels == 0]).size == 1
    assert np.unique(out[labels == 4]).size == 2


def test_the_window_forbids_merging_beyond_its_reach():
    mesh, col = _valley()
    x = mesh.centroids[:, 0]
    labels = np.select([np.abs(x) < 0.25, x < 0, x < 0.5, x < 0.75], [0, 4, 1, 2], 3)
    # every union of two strips spans 0.5 x 0.5: from its center, its corners lie
    # ~0.35 away; a window of 0.2 allows no merge, hence no swap
    out, n = swap_round(face_graph(mesh), _weights(mesh), labels, window_r2=0.2 ** 2)
    assert n == 0


def test_split_merge_invariants_on_a_real_mesh():
    mesh = read_mesh(need(MESHES / "bunny.tri.xz"))
    paper = segment(mesh, 150, split_merge=False, cleanup=False)
    r = segment(mesh, 150, split_merge=True, cleanup=False)
    assert r.timings["swaps"] > 0
    assert r.params["split_merge"] is True
    k = r.n_segments
    assert np.array_equal(np.unique(r.labels), np.arange(k))  # dense
    assert k == paper.n_segments  # the swaps keep K, and a round that adds one is undone
    comps = label_components(face_graph(mesh), r.labels)
    assert np.unique(comps).size == k  # every superfacet connected
    again = segment(mesh, 150, split_merge=True, cleanup=False, n_threads=1)
    np.testing.assert_array_equal(again.labels, r.labels)  # deterministic, any threads
    assert not np.array_equal(r.labels, paper.labels)
    # the candidates evaluated on 1 or 3 threads: the same swaps
    w = _weights(mesh)
    one, n1 = swap_round(face_graph(mesh), w, paper.labels, n_threads=1)
    three, n3 = swap_round(face_graph(mesh), w, paper.labels, n_threads=3)
    assert n1 == n3 > 0
    np.testing.assert_array_equal(one, three)
    # two threads: the second's merge searches run in the splits' second buffers
    two, n2 = swap_round(face_graph(mesh), w, paper.labels, n_threads=2)
    assert n2 == n1
    np.testing.assert_array_equal(two, one)


def test_a_swap_needs_a_split_that_removes_an_average_superfacets_energy():
    mesh, col = _valley()
    x = mesh.centroids[:, 0]
    labels = np.select([np.abs(x) < 0.25, x < 0, x < 0.5, x < 0.75], [0, 4, 1, 2], 3)
    g, w = face_graph(mesh), _weights(mesh)
    # the crease's superfacet holds most of the energy: its split is taken at the
    # default (1) and at 2; a gain is at most its superfacet's energy, which is below
    # the total (K = 5 times the mean), so min_gain = 5 allows no swap
    assert [swap_round(g, w, labels, min_gain=m)[1] for m in (0.0, 1.0, 2.0, 5.0)] == [
        1, 1, 1, 0]
    np.testing.assert_array_equal(swap_round(g, w, labels)[0],
                                  swap_round(g, w, labels, min_gain=1.0)[0])


def test_a_higher_min_gain_takes_fewer_swaps_on_a_real_mesh():
    mesh = read_mesh(need(MESHES / "bunny.tri.xz"))
    labels = segment(mesh, 300, split_merge=False, cleanup=False).labels
    g, w = face_graph(mesh), _weights(mesh)
    counts = [swap_round(g, w, labels, min_gain=m)[1] for m in (0.0, 1.0, 2.0, 4.0, 300.0)]
    assert counts == sorted(counts, reverse=True)  # the swaps of a higher bound: a prefix
    assert counts[0] > counts[2] > 0 and counts[-1] == 0


@pytest.mark.parametrize("k", [40, 150, 300])
def test_pruned_candidates_give_the_swaps_of_the_full_evaluation(k, monkeypatch):
    # the lazy splits and abandoned merge searches decide exactly what evaluating
    # every candidate decides, while evaluating a fraction of the splits
    from superfacets.method import splitmerge

    mesh = read_mesh(need(MESHES / "bunny.tri.xz"))
    labels = segment(mesh, k).labels
    w = _weights(mesh)
    full, n_full = swap_round(face_graph(mesh), w, labels, pruned=False)
    evaluated = []
    real = splitmerge.split_candidates

    def counting(*args):
        which, first, step = args[10], args[-2], args[-1]
        evaluated.extend(which[first::step].tolist())
        return real(*args)

    monkeypatch.setattr(splitmerge, "split_candidates", counting)
    for threads in (1, 2):
        evaluated.clear()
        out, n = swap_round(face_graph(mesh), w, labels, n_threads=threads)
        assert n == n_full
        np.testing.assert_array_equal(out, full)
        assert len(evaluated) == len(set(evaluated)) < 0.6 * k  # each once, most never


def test_split_merge_off_is_the_paper(monkeypatch):
    # (with the paper's float64 weights: a run's are float32)
    import superfacets.method.stages as stages

    monkeypatch.setattr(stages, "weight_dtype", lambda kind, paper: np.float64)
    mesh = grid_mesh(30, 30, height=lambda x, y: 0.3 * np.abs(x))
    a = segment(mesh, 12, split_merge=False, cleanup=False, tol=0)
    b = segment(mesh, 12, paper=True)
    np.testing.assert_array_equal(a.labels, b.labels)
    assert "swaps" not in a.timings


def test_both_are_on_by_default_for_faces_and_vertices():
    mesh = grid_mesh(30, 30, height=lambda x, y: 0.3 * np.abs(x))
    on = segment(mesh, 12)
    assert on.params["split_merge"] is True and on.params["cleanup"] is True
    assert "swaps" in on.timings and "cleanup" in on.timings
    both = segment(mesh, 12, split_merge=True, cleanup=True)
    np.testing.assert_array_equal(on.labels, both.labels)
    paper = segment(mesh, 12, paper=True)
    assert paper.params["split_merge"] is False and paper.params["cleanup"] is False
    v = segment(mesh, 12, elements="vertices")  # better there too (docs/notes/cleanup.md)
    assert v.params["split_merge"] is True and v.params["cleanup"] is True
    pts = segment(mesh.vertices, 12)  # points: not better on UE, the paper's method
    assert pts.params["split_merge"] is False and pts.params["cleanup"] is False
    shl = segment(mesh, 12, weighting="shlafman", alpha=0.5)
    assert shl.params["split_merge"] is False and shl.params["cleanup"] is False
    with pytest.raises(ParameterError, match="cleanup"):
        segment(mesh, 12, paper=True, cleanup=True)
    np.testing.assert_array_equal(segment(mesh, 12, paper=True, cleanup=False).labels,
                                  paper.labels)


@pytest.mark.parametrize("bad", ["yes", 1])
def test_split_merge_is_checked(bad):
    with pytest.raises(ParameterError, match="split_merge"):
        segment(grid_mesh(4, 4), 2, split_merge=bad)


def test_a_round_that_changes_the_number_of_superfacets_is_undone(monkeypatch):
    # passes that empty a superfacet (as zero-weight edges of degenerate faces can):
    # the round is undone, the labels are those before it, no swap is counted
    from dataclasses import replace

    from superfacets.method import passes

    mesh = read_mesh(need(MESHES / "bunny.tri.xz"))
    paper = segment(mesh, 150, paper=True)  # the passes to convergence before the swaps
    real = passes.iterate

    def emptying(*args, **kwargs):
        it = real(*args, **kwargs)
        label = it.label.copy()
        label[label == 0] = 1  # superfacet 0 is left empty
        return replace(it, label=label)

    monkeypatch.setattr(passes, "iterate", emptying)
    r = segment(mesh, 150, split_merge=True, cleanup=False, tol=0)
    assert r.timings["swaps"] == 0
    np.testing.assert_array_equal(r.labels, paper.labels)
    fast = segment(mesh, 150, split_merge=True)  # early swaps: undone the same way
    assert fast.timings["swaps"] == 0 and fast.n_segments == 150


def test_members_are_the_stable_sort_of_the_labels():
    from superfacets.method.splitmerge import _members

    rng = np.random.default_rng(5)
    for n, k in ((1, 1), (7, 3), (5000, 40)):
        lab = rng.integers(0, k, n).astype(np.int32)
        lab[:k] = np.arange(k)
        members, bounds = _members(lab, k)
        order = np.argsort(lab, kind="stable")
        np.testing.assert_array_equal(members, order)
        np.testing.assert_array_equal(bounds, np.searchsorted(lab[order], np.arange(k + 1)))


def _ridge():
    """The valley's strip folded the other way: a convex ridge z = -0.5 |x|."""
    nx, ny = 40, 10
    m = grid_mesh(nx, ny, height=lambda x, y: -0.5 * np.abs(x))
    return Mesh(m.vertices * [1.0, 0.25, 1.0], m.faces)


def test_convex_folds_count_less_in_the_swap_energies_on_faces():
    # with the run's weights the superfacet over the convex ridge is split on it; with
    # the convex angular term removed (concave creases alone) the ridge is as flat as the
    # slopes: that square is kept and the largest superfacet is split instead
    from superfacets.elements.kinds import kind_of
    from superfacets.method.weights import convex_scaled

    mesh = _ridge()
    g = face_graph(mesh)
    x = mesh.centroids[:, 0]
    labels = np.select([np.abs(x) < 0.25, x < 0, x < 0.5, x < 0.75], [0, 4, 1, 2], 3)
    w = _weights(mesh)
    out, n = swap_round(g, w, labels)
    assert n == 1
    assert np.unique(out[(np.abs(x) < 0.25) & (x < 0)]).size == 1
    assert out[(np.abs(x) < 0.25) & (x < 0)][0] != out[(np.abs(x) < 0.25) & (x > 0)][0]
    assert kind_of("faces").swap_eta_convex == 0.5 and kind_of("vertices").swap_eta_convex == 1.0
    concave_only = convex_scaled(g, w, alpha=200.0, eta_convex=0.2, factor=0.0)
    out, n = swap_round(g, concave_only, labels)
    assert n == 1
    assert np.unique(out[labels == 0]).size == 1
    assert np.unique(out[labels == 4]).size == 2
    # on the valley the concave crease still counts: the straddling square is split
    mesh, _ = _valley()
    g = face_graph(mesh)
    x = mesh.centroids[:, 0]
    labels = np.select([np.abs(x) < 0.25, x < 0, x < 0.5, x < 0.75], [0, 4, 1, 2], 3)
    w = convex_scaled(g, _weights(mesh), alpha=200.0, eta_convex=0.2, factor=0.0)
    out, _ = swap_round(g, w, labels)
    assert out[(np.abs(x) < 0.25) & (x < 0)][0] != out[(np.abs(x) < 0.25) & (x > 0)][0]


def test_convex_scaled_weights_are_the_paper_weights_with_a_smaller_eta_convex():
    from superfacets.method.weights import convex_scaled, paper_weights, shlafman_weights

    mesh = read_mesh(need(MESHES / "bunny.tri.xz"))  # concave and convex edges
    g = face_graph(mesh)
    assert g.terms.concave.any() and (~g.terms.concave).any()
    w = csr_weights(g, paper_weights(g, alpha=200.0, eta_convex=0.2))
    for factor in (0.0, 0.5):
        want = csr_weights(g, paper_weights(g, alpha=200.0, eta_convex=0.2 * factor))
        got = convex_scaled(g, w, alpha=200.0, eta_convex=0.2, factor=factor)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * want.max())
        assert (got >= 0).all()
    assert convex_scaled(g, w, alpha=200.0, eta_convex=0.2, factor=1.0) is w
    s = csr_weights(g, shlafman_weights(g, alpha=0.5))
    assert convex_scaled(g, s, alpha=0.5, eta_convex=0.2, factor=0.0,
                         weighting="shlafman") is s


def test_the_run_swaps_with_the_weights_of_its_kind(monkeypatch):
    # faces: the convex angular term halved; vertices: the run's own weights
    from superfacets.method import splitmerge
    from superfacets.method.weights import convex_scaled

    seen = []
    real = splitmerge.swap_round

    def spy(graph, weights, labels, **kw):
        seen.append((graph, weights.copy()))
        return real(graph, weights, labels, **kw)

    monkeypatch.setattr(splitmerge, "swap_round", spy)
    mesh = grid_mesh(30, 30, height=lambda x, y: 0.3 * np.abs(x) - 0.3 * np.abs(y))
    segment(mesh, 12)
    g, got = seen[-1]
    assert g.kind == "faces"
    w = csr_weights(g, edge_weights(g, "paper", alpha=200.0, eta_convex=0.2,
                                    dtype=np.float32), np.float32)  # (a run's: float32)
    np.testing.assert_array_equal(got, convex_scaled(g, w, alpha=200.0, eta_convex=0.2,
                                                     factor=0.5).astype(np.float64))
    assert (got < w).any()  # the ridge along y = 0 is convex
    segment(mesh, 12, elements="vertices")
    g, got = seen[-1]
    assert g.kind == "vertices"
    np.testing.assert_array_equal(
        got, csr_weights(g, edge_weights(g, "paper", alpha=200.0, eta_convex=0.2)))


def test_the_passes_after_the_swaps_hold_small_center_moves_on_faces(monkeypatch):
    # a center moving by less than 4 x center_tol x r after the swaps stays (faces);
    # on vertices (the exact classification) by less than center_tol x r, as before them
    from superfacets.elements.kinds import kind_of
    from superfacets.method import passes

    holds = []
    real = passes.iterate

    def spy(*args, min_move=0.0, **kw):
        holds.append(min_move)
        return real(*args, min_move=min_move, **kw)

    monkeypatch.setattr(passes, "iterate", spy)  # the passes after the swaps only
    mesh = read_mesh(need(MESHES / "bunny.tri.xz"))
    r = segment(mesh, 100)
    assert kind_of("faces").hold_after == 4.0 and kind_of("vertices").hold_after == 1.0
    assert r.timings["swaps"] > 0 and len(holds) == 1
    assert holds[-1] == pytest.approx(4.0 * 0.05 * r.mesh_radius)
    r = segment(mesh, 100, elements="vertices")
    assert r.timings["swaps"] > 0 and len(holds) == 2
    assert holds[-1] == pytest.approx(0.05 * r.mesh_radius)
    r = segment(mesh, 100, center_tol=0.0)  # no hold asked: none after the swaps either
    assert r.timings["swaps"] > 0 and holds[-1] == 0.0


def test_one_pass_follows_the_swaps_on_faces_two_on_vertices(monkeypatch):
    # the bound on the passes after the swaps each kind gets, and the runs keep to it
    from superfacets.elements.kinds import kind_of
    from superfacets.method import passes

    runs = []
    real = passes.iterate

    def spy(*args, **kw):
        out = real(*args, **kw)
        runs.append((args[5], out.n_passes))  # (bound, passes run)
        return out

    monkeypatch.setattr(passes, "iterate", spy)  # the passes after the swaps only
    mesh = read_mesh(need(MESHES / "bunny.tri.xz"))
    assert kind_of("faces").passes_after == 1 and kind_of("vertices").passes_after == 2
    r = segment(mesh, 100)
    assert r.timings["swaps"] > 0 and runs[-1][0] == 1 and runs[-1][1] == 1
    assert r.converged  # the schedule's end, not max_iter
    r = segment(mesh, 100, elements="vertices")
    assert r.timings["swaps"] > 0 and runs[-1][0] == 2 and 1 <= runs[-1][1] <= 2
    r = segment(mesh, 100, tol=0)  # the paper's rule: the passes after run to convergence
    assert all(bound == 50 for bound, _ in runs[2:])


def test_label_pairs_from_the_csr_layout_equal_those_of_the_pairs(sphere):
    # the adjacent superfacets of a swap round, read without the graph's pairs
    from oracle.splitmerge import label_pairs

    from superfacets.elements import face_graph

    g = face_graph(sphere)
    lab = np.random.default_rng(0).integers(0, 40, g.n_elements).astype(np.int32)
    a, b = lab[g.pairs[:, 0]], lab[g.pairs[:, 1]]
    cross = a != b
    want = np.unique(np.minimum(a[cross], b[cross]).astype(np.int64) * 40
                     + np.maximum(a[cross], b[cross]))
    np.testing.assert_array_equal(label_pairs(g.indptr, g.indices, lab, np.int64(40)), want)
    same = np.zeros(g.n_elements, dtype=np.int32)  # one superfacet: no pair
    assert label_pairs(g.indptr, g.indices, same, np.int64(1)).shape == (0,)


def test_letting_the_kept_expansions_go_before_the_swaps_keeps_the_labels(monkeypatch):
    # large graphs forget the passes' records before the swaps (FORGET_MIN): the pass
    # after the swaps then expands every center, with the labels of replaying them
    from superfacets.method import classify, splitmerge

    mesh = read_mesh(need(MESHES / "bunny.tri.xz"))
    kept = segment(mesh, 150, cleanup=False)
    assert kept.timings["swaps"] > 0
    forgot = []
    real = classify.BoundedReplay.forget_records

    def spy(self):
        forgot.append(self.end)
        real(self)
        assert self.end == 0 and self.prev_centers.size == 0

    monkeypatch.setattr(classify.BoundedReplay, "forget_records", spy)
    monkeypatch.setattr(splitmerge, "FORGET_MIN", 0)
    r = segment(mesh, 150, cleanup=False)
    assert forgot and forgot[0] > 0  # records were kept, and let go
    np.testing.assert_array_equal(r.labels, kept.labels)
    assert r.timings["expansions"] > kept.timings["expansions"]  # every center again


def test_frozen_superfacets_take_no_part_in_a_swap():
    """The valley's swap splits the superfacet on the crease and merges two strips of the
    right slope; with that superfacet frozen, it is neither split nor merged (another swap
    may be made elsewhere), and with the three strips frozen too, no swap is left."""
    mesh, _ = _valley()
    x = mesh.centroids[:, 0]
    labels = np.select([np.abs(x) < 0.25, x < 0, x < 0.5, x < 0.75], [0, 4, 1, 2], 3)
    g, w = face_graph(mesh), _weights(mesh)
    free, n = swap_round(g, w, labels)
    assert n == 1 and np.unique(free[labels == 0]).size == 2  # (the crease's, split)
    frozen = np.zeros(5, dtype=bool)
    frozen[0] = True
    out, _ = swap_round(g, w, labels, frozen=frozen)
    crease = out[labels == 0]
    assert np.unique(crease).size == 1 and (out == crease[0]).sum() == (labels == 0).sum()
    frozen[[1, 2, 3]] = True
    out, n = swap_round(g, w, labels, frozen=frozen)
    assert n == 0
    np.testing.assert_array_equal(out, labels)
