"""Many superpoints merged to the count asked for, flat neighbours first
(``superfacets.method.merges``; the default on clouds of even density)."""

from __future__ import annotations

import numpy as np
import pytest

from superfacets import PointCloud, segment
from superfacets import segment as _segment
from superfacets.errors import ParameterError
from superfacets.method.merges import flat_merges, noise_of, noise_variance
from superfacets.method.params import DEFAULTS, resolve
from superfacets.method.rules import merge_from_of


def _graph(points):
    from superfacets.elements.points import point_graph

    return point_graph(PointCloud(points)).graph


def _room(seed: int = 0, noise: float = 0.002):
    """A noisy floor (1 x 1, 12,000 points) with four domes on it (half spheres of
    radius 0.1, 2,000 points each): returns the points and the part of each (0 the
    floor, 1..4 the domes)."""
    rng = np.random.default_rng(seed)
    floor = np.c_[rng.random((12_000, 2)), noise * rng.standard_normal(12_000)]
    parts = [floor]
    for x, y in [(0.2, 0.2), (0.7, 0.25), (0.25, 0.7), (0.7, 0.7)]:
        d = rng.standard_normal((2000, 3))
        d[:, 2] = np.abs(d[:, 2])
        d *= 0.1 / np.linalg.norm(d, axis=1, keepdims=True)
        parts.append(d + [x, y, 0.0] + noise * rng.standard_normal((2000, 3)))
    part = np.repeat(np.arange(5), [12_000] + [2000] * 4)
    return np.vstack(parts), part


def test_the_noise_is_the_planes_noise():
    rng = np.random.default_rng(1)
    xy = rng.random((20_000, 2))
    for sigma in (0.001, 0.004):
        pts = np.c_[xy, sigma * rng.standard_normal(20_000)]
        # the smallest eigenvalue of ~11 noisy points: a bit below sigma^2
        assert 0.4 * sigma ** 2 < noise_variance(_graph(pts)) < 1.2 * sigma ** 2
    assert noise_variance(_graph(np.c_[xy, np.zeros(20_000)])) < 1e-20  # exactly flat


def test_the_noise_of_a_curved_surface_is_not_its_curvature():
    """A clean sphere's neighbourhoods are curved, not noisy: the two-scale estimate
    takes the curvature's share out (one scale read it as noise, and the flat merges
    crossed the parts of curved objects); with noise added, the noise comes back."""
    from superfacets.method.merges import _plane_residual

    rng = np.random.default_rng(7)
    d = rng.standard_normal((30_000, 3))
    sphere = d / np.linalg.norm(d, axis=1, keepdims=True)
    g = _graph(sphere)
    one_scale = float(np.median(_plane_residual(g, np.arange(0, 30_000, 7), 1)[0]))
    assert one_scale > 1e-8 and noise_variance(g) == 0.0
    sigma = 0.004
    noisy = sphere * (1 + sigma * rng.standard_normal((30_000, 1)))
    assert 0.4 * sigma ** 2 < noise_variance(_graph(noisy)) < 1.2 * sigma ** 2


def test_the_noise_reads_zero_unless_its_median_is_significantly_positive():
    """Known answers of the sign test (:func:`noise_of`): estimates scattered about 0 (a
    clean surface's) read 0 whatever their median's sign, so two samples of one clean
    surface (one run's, a tiled run's) read alike; positive ones read their median; the
    median's lower bound is the estimate of rank floor(m/2 - 1.5 sqrt(m))."""
    from superfacets.method.merges import neighbourhood_noise

    rng = np.random.default_rng(2)
    for shift in (-1e-14, 0.0, 1e-14):  # a median of either sign, within its spread
        assert noise_of(1e-12 * rng.standard_normal(8000) + shift) == 0.0
    noisy = 1e-4 * (1 + 0.5 * rng.standard_normal(8000))
    assert noise_of(noisy) == float(np.median(noisy))
    # m = 100: the lower bound is the estimate of rank 35 (the 36th smallest)
    e = np.r_[np.full(35, -1.0), np.full(65, 2.0)]
    assert noise_of(e) == 2.0 and noise_of(np.r_[np.full(36, -1.0), np.full(64, 2.0)]) == 0.0
    assert noise_of(np.full(8, 3.0)) == 0.0 and noise_of(np.full(9, 3.0)) == 3.0
    assert noise_of(np.zeros(0)) == 0.0
    # a clean sphere read on two halves of its points: both 0, where the medians differ
    d = rng.standard_normal((30_000, 3))
    g = _graph(d / np.linalg.norm(d, axis=1, keepdims=True))
    halves = [neighbourhood_noise(g, np.arange(i, 30_000, 2)) for i in (0, 1)]
    assert noise_of(halves[0]) == noise_of(halves[1]) == 0.0
    assert (np.sort(halves[0])[:15_000] < 0).any() and (halves[0] > 0).any()


def test_flat_merges_join_each_plane_and_never_cross_the_ridge():
    x = np.linspace(0, 1, 50)
    xy = np.stack(np.meshgrid(x, x), -1).reshape(-1, 2)
    roof = np.c_[xy, 0.5 * np.abs(xy[:, 0] - 0.5)]
    g = _graph(roof)
    cells = (np.minimum(g.positions[:, 0] * 10, 9.999).astype(np.int64) * 10
             + np.minimum(g.positions[:, 1] * 10, 9.999).astype(np.int64))
    left = g.positions[:, 0] < 0.5 - 1e-9
    merged = flat_merges(g, cells, 1, 1e-12)
    assert int(merged.max()) + 1 == 2
    assert len(set(merged[left])) == 1 and not set(merged[left]) & set(merged[~left])
    # a threshold below what crossing the ridge costs, and k reached first: 30 left
    assert int(flat_merges(g, cells, 30, 1e-12).max()) + 1 == 30
    # no pair flat enough: nothing merges
    bumpy = roof.copy()
    bumpy[:, 2] += 0.05 * np.sin(40 * xy[:, 0]) * np.sin(40 * xy[:, 1])
    gb = _graph(bumpy)
    cb = (np.minimum(gb.positions[:, 0] * 10, 9.999).astype(np.int64) * 10
          + np.minimum(gb.positions[:, 1] * 10, 9.999).astype(np.int64))
    assert int(flat_merges(gb, cb, 1, 1e-12).max()) + 1 == 100


def test_a_room_spends_its_count_on_the_objects_not_the_floor():
    pts, part = _room()
    plain = segment(pts, 60, merge_from=1)
    merged = segment(pts, 60)
    assert merged.params["merge_from"] == 5 and merged.params["density"] == 0.0
    assert merged.n_segments == 60 and np.unique(merged.labels).size == 60

    assert _on_floor(merged.labels, part) <= _on_floor(plain.labels, part) // 2
    # the domes get the count: half the error (UE 0.13 -> 0.07), fewer points off their part
    def off_part(labels):
        return sum(int(np.bincount(part[labels == s]).sum() - np.bincount(part[labels == s]).max())
                   for s in np.unique(labels))

    assert off_part(merged.labels) < 0.7 * off_part(plain.labels)


def test_a_count_near_a_tenth_of_the_points_still_merges():
    """Where one first superpoint per 12 points is under twice the count, the first run
    makes twice the count (at most one per 4 points) and the merges choose the borders:
    before, such a run was the plain run, whose superpoints of about 11 points straddle
    the ground's border with the shrubs on it (the ISPRS samples at k = 3,000)."""
    from superfacets.elements.builders import elements_of
    from superfacets.evaluation.metrics import undersegmentation_error
    from superfacets.method.rules import fine_count

    assert fine_count(345, 5, 3800) == 690 and fine_count(150, 5, 3800) == 316
    assert fine_count(3000, 5, 7_500) == 3000  # (not 4 points each: no merges)
    rng = np.random.default_rng(0)
    ground = np.c_[rng.random((3000, 2)) * 4, 0.01 * rng.standard_normal(3000)]
    centers, which = rng.random((8, 2)) * 3.4 + 0.3, rng.integers(0, 8, 800)
    shrubs = np.c_[centers[which] + 0.15 * rng.standard_normal((800, 2)),
                   0.25 + 0.1 * rng.standard_normal(800)]
    pts, part = np.r_[ground, shrubs], np.r_[np.zeros(3000, dtype=int), which + 1]
    src = elements_of(PointCloud(pts), "points")
    first = src.first_rows(np.arange(src.graph.n_elements))
    k = pts.shape[0] // 11  # 345: one per 12 points would be 316

    def ue(result):
        return undersegmentation_error(src.graph, result.labels[first], part[first])

    merged, plain = segment(pts, k), segment(pts, k, merge_from=1)
    assert "merges" in merged.timings and merged.n_segments == plain.n_segments == k
    assert ue(merged) < 0.7 * ue(plain)  # 0.096 against 0.177 (seeds 1, 2: 0.69, 0.55)


def test_a_flat_plane_keeps_compact_superpoints():
    # no pair is less flat than another: the merges go by Ward's cost, compact
    rng = np.random.default_rng(0)
    xy = rng.random((6000, 2))
    r = segment(np.c_[xy, np.zeros(6000)], 24)
    assert r.params["merge_from"] == 5 and r.n_segments == 24
    spread = [xy[r.labels == s].std(axis=0).max() for s in range(24)]
    # a square of 1/24 of the unit square has a std of 0.059 along each side; over six
    # samplings the mean spread was 0.064-0.079 and the largest 0.10-0.16 (a
    # strip across the square has 0.29)
    assert np.mean(spread) < 0.085 and max(spread) < 0.17


@pytest.mark.parametrize("k", [20, 50])
def test_noisy_level_ground_has_no_specks(monkeypatch, k):
    """Known answer: level ground with 2 cm of noise (5,000 points over 50 x 50 m, a LAS
    tile's up direction), merged from 20 times k: every superpoint holds at least a quarter
    of the mean. Before FLAT_MIN_ELEMENTS the flat test read a piece of 1-11 points over
    its own few points, failed it by their noise alone, and 6 of 20 superpoints (11 of
    50) held under a quarter of the mean, the smallest 2 points."""
    import superfacets.method.merges as merges

    rng = np.random.default_rng(0)
    ground = np.c_[rng.random((5000, 2)) * 50, 0.02 * rng.standard_normal(5000)]
    cloud = PointCloud(ground, up=(0, 0, 1))
    r = segment(cloud, k)
    assert r.n_segments == k and r.params["merge_from"] == 20
    sizes = np.bincount(r.labels)
    assert sizes.min() >= 5000 / k / 4, np.sort(sizes)[:5]
    monkeypatch.setattr(merges, "FLAT_MIN_ELEMENTS", 0.0)  # each piece's own count
    old = np.bincount(segment(cloud, k).labels)
    assert (old < 5000 / k / 4).sum() >= 5


def test_a_bush_of_a_few_points_stays_off_the_flat_ground():
    """Known answer: the floor of the flat test is the noise's, not an object's: five
    points 1 m above level ground (2 cm of noise) fail it whatever it reads them over,
    and stay a superpoint of their own."""
    from superfacets.graph.hierarchy import planarity_graph
    from superfacets.method.merges import FLAT_MIN_ELEMENTS, flat_merge_nodes

    rng = np.random.default_rng(1)
    ground = np.c_[rng.random((3000, 2)) * 30, 0.02 * rng.standard_normal(3000)]
    bush = np.c_[15 + 0.3 * rng.random((5, 2)), 1 + 0.05 * rng.random(5)]
    graph = _graph(np.vstack([ground, bush]))
    pts = graph.positions  # (the graph's order)
    cells = (pts[:, 0] // 5).astype(np.int64) * 6 + (pts[:, 1] // 5).astype(np.int64)
    cells[pts[:, 2] > 0.5] = 36
    pg = planarity_graph(graph, cells)
    noise = 0.02 ** 2
    for floor in (0.0, FLAT_MIN_ELEMENTS, 100.0):
        top = flat_merge_nodes(pg, 1, 2 * noise, min_count=floor)
        assert np.unique(top[:36]).size == 1 and top[36] != top[0]


def test_the_merges_keep_separate_pieces_apart_and_warn_below_them():
    rng = np.random.default_rng(2)
    a = np.c_[rng.random((3000, 2)), np.zeros(3000)]
    pts = np.r_[a, a + [5.0, 0.0, 0.0], a + [10.0, 0.0, 0.0]]
    r = segment(pts, 9)
    assert r.n_segments == 9
    assert all(len(set(r.labels[3000 * i:3000 * (i + 1)]) & set(r.labels[:3000])) == 0
               for i in (1, 2))
    with pytest.warns(RuntimeWarning, match="3 superpoints for n_segments=2"):
        assert segment(pts, 2).n_segments == 3


def test_the_first_run_has_at_most_one_superpoint_per_12_points():
    rng = np.random.default_rng(3)
    pts = np.c_[rng.random((1200, 2)), np.zeros(1200)]
    r = segment(pts, 50)
    assert r.params["n_init_centers"] == 100 and r.n_segments == 50
    # where that is under twice the count: twice it, at most one per 4 points
    assert segment(pts, 120).params["n_init_centers"] == 240
    assert segment(pts, 200).params["n_init_centers"] == 300
    # one per 4 points or more already: no merges at all (the method's own run)
    assert segment(pts, 300).params["n_init_centers"] == 300
    # and at least one per 100 points: a large scan at a small k starts from small pieces
    big = np.c_[rng.random((30_000, 2)), np.zeros(30_000)]
    assert segment(big, 10).params["n_init_centers"] == 300


def _terrain(seed: int = 0, n: int = 40_000, bushes: int = 10):
    """Gently rolling ground (1 x 1, amplitude 0.01, noise 0.002) with ``bushes`` half
    spheres of radius 0.04 (400 points each) standing on it: the points and the part of
    each (0 the ground)."""
    rng = np.random.default_rng(seed)

    def ground(xy):
        return 0.01 * np.sin(2 * np.pi * xy[..., 0]) * np.cos(np.pi * xy[..., 1])

    xy = rng.random((n, 2))
    parts = [np.c_[xy, ground(xy) + 0.002 * rng.standard_normal(n)]]
    for c in rng.random((bushes, 2)) * 0.8 + 0.1:
        d = rng.standard_normal((400, 3))
        d[:, 2] = np.abs(d[:, 2])
        d *= 0.04 / np.linalg.norm(d, axis=1, keepdims=True)
        parts.append(d + [c[0], c[1], ground(c)] + 0.002 * rng.standard_normal((400, 3)))
    return np.vstack(parts), np.repeat(np.arange(bushes + 1), [n] + [400] * bushes)


def _costs_run(monkeypatch) -> list:
    """The costs the merges to the count run, in order (the plane's rise under the size
    bound is its own kernel call; beyond it, and Ward's, the hierarchy's)."""
    import superfacets.graph.hierarchy as hierarchy
    import superfacets.method.merges as merges

    ran, real, bounded = [], hierarchy.hierarchy, merges.rise_merge_nodes
    monkeypatch.setattr(hierarchy, "hierarchy", lambda *a, **kw: (
        ran.append(kw.get("cost", "ward")), real(*a, **kw))[1])
    monkeypatch.setattr(merges, "rise_merge_nodes", lambda *a, **kw: (
        ran.append("planarity"), bounded(*a, **kw))[1])
    return ran


def test_a_scene_merges_by_the_planes_rise_and_an_object_by_wards(monkeypatch):
    ran = _costs_run(monkeypatch)
    # an airborne tile in miniature: most points on the ground, flat to within its noise
    pts, part = _terrain()
    r = segment(pts, 15, merge_cost="auto")
    assert set(ran) == {"planarity"} and r.n_segments == 15
    # the count goes to the bushes: a few ground superpoints, and UE about a fifth of
    # Ward's merges' (0.08-0.11 over three samplings, against 0.40-0.59)
    assert _on_floor(r.labels, part) <= 8
    assert _ue(r.labels, part) < 0.15
    # a curved object: no flat region, Ward's merges keep compact superpoints
    ran.clear()
    ball = np.random.default_rng(1).standard_normal((6000, 3))
    ball /= np.linalg.norm(ball, axis=1, keepdims=True)
    assert segment(ball, 20, merge_cost="auto").n_segments == 20 and ran == ["ward"]


def _forest(seed: int = 0, n: int = 16_000, trees: int = 20):
    """An airborne forest in miniature: noisy ground (40 x 40, ``n`` points) under 20
    crowns (1,000 points inside each, 9 above the ground) on trunks (100 points each):
    the ground is 42 % of the points at 16,000, 59 % at 32,000. The points and the part
    of each (0 the ground)."""
    rng = np.random.default_rng(seed)
    xy = rng.random((n, 2)) * 40.0
    parts, part = [np.c_[xy, 0.05 * rng.standard_normal(n)]], [np.zeros(n, np.int64)]
    for c in rng.random((trees, 2)) * 36 + 2:
        u = rng.standard_normal((1000, 3))
        u *= (rng.random(1000) ** (1 / 3) / np.linalg.norm(u, axis=1))[:, None]
        trunk = np.c_[c + 0.2 * rng.standard_normal((100, 2)), rng.random(100) * 8]
        parts += [u * [2.5, 2.5, 2.0] + [c[0], c[1], 9.0], trunk]
        part += [np.ones(1100, np.int64)]
    return np.vstack(parts), np.concatenate(part)


def test_one_share_chooses_the_merges_on_scans_as_on_sampled_surfaces(monkeypatch):
    """The plane's rise where most of the points lie in flat regions (FLAT_SHARE), one
    rule whatever the noise: the miniature forest with 59 % of its points on the ground
    merges by it (UE 0.003-0.004 over three samplings); with 42 %, by Ward's."""
    from superfacets.method.merges import FLAT_SHARE

    ran = _costs_run(monkeypatch)
    pts, part = _forest(n=32_000)
    r = segment(pts, 40, merge_cost="auto")
    assert set(ran) == {"planarity"} and r.n_segments == 40 and FLAT_SHARE == 0.5
    assert _ue(r.labels, part) < 0.01
    ran.clear()
    pts, part = _forest(n=16_000)
    r = segment(pts, 40, merge_cost="auto")
    assert set(ran) == {"ward"} and r.n_segments == 40


def test_the_planes_rise_keeps_a_rug_of_another_colour_off_its_floor(monkeypatch):
    """The plane's rise merges neighbours of one colour first: a blue rug on the floor (as
    flat as the floor) stays a superpoint of its own at k = 8 (UE 0.03; merged into the
    floor without the colour guard: 0.65), while isolated points of another colour (colour
    noise) still join their neighbours: no superpoint of a single point."""
    pts, part = _room(0)
    rug = (part == 0) & (np.abs(pts[:, 0] - 0.45) < 0.15) & (np.abs(pts[:, 1] - 0.45) < 0.15)
    part = np.where(rug, 5, part)
    rng = np.random.default_rng(1)
    colors = np.where(rug[:, None], [0.1, 0.2, 0.8], [0.6, 0.6, 0.6]) + \
        0.01 * rng.standard_normal((len(pts), 3))
    odd = rng.choice(np.flatnonzero(part == 0), 40, replace=False)  # colour noise
    colors[odd] = [0.9, 0.1, 0.1]
    ran = _costs_run(monkeypatch)
    r = segment(PointCloud(pts, colors=np.clip(colors, 0, 1)), 8, merge_cost="auto")
    assert "planarity" in ran and r.n_segments == 8
    own = np.bincount(r.labels[rug]).argmax()
    assert (r.labels[rug] == own).mean() > 0.95 and rug[r.labels == own].mean() > 0.95
    assert np.bincount(r.labels).min() > 1 and _ue(r.labels, part) < 0.1


def _ue(labels, part):
    """Undersegmentation error (eq. 4, 5 % tolerance) against ``part``."""
    table = np.zeros((labels.max() + 1, part.max() + 1))
    np.add.at(table, (labels, part), 1)
    size = table.sum(1)
    return float(((size[:, None] - table) * (table > 0.05 * size[:, None])).sum() / labels.size)


def test_merge_from_is_chosen_from_the_kind_and_the_density():
    from dataclasses import replace

    even = replace(DEFAULTS, density=0.0)
    assert merge_from_of(even, "points") == 5
    assert merge_from_of(replace(even, density=0.5), "points") == 5  # 'noise' merges sweeps too
    assert merge_from_of(replace(even, density=0.5, merge_cost="auto"), "points") == 1
    assert merge_from_of(replace(even, density=0.5, merge_cost="scene"), "points") == 5
    assert merge_from_of(replace(even, beta=10.0), "points") == 5  # colour: merges of one colour
    assert merge_from_of(replace(even, paper=True), "points") == 1
    assert merge_from_of(even, "points", tiled=True) == 1
    assert [merge_from_of(even, kind) for kind in ("faces", "vertices", "cells")] == [1, 1, 1]
    assert merge_from_of(replace(even, merge_from=3), "faces") == 3  # as given
    with pytest.raises(ParameterError, match="merge_from must be"):
        resolve(merge_from=0)
    with pytest.raises(ParameterError, match="does not go with merge_from"):
        resolve(paper=True, merge_from=5)
    resolve(paper=True, merge_from=1)  # 1 is the paper's: no merges


def test_a_scene_with_an_up_direction_merges_from_twenty_times_the_count(monkeypatch):
    """A cloud with an up direction (a LAS file's, ``--seen-from``) is a scene: with the
    default cost its merges choose from 20 times the count, one run and tiled alike; the
    same points without one (an object) from 5; the other costs, the paper and meshes
    keep theirs."""
    from dataclasses import replace

    from superfacets import segment_tiled
    from superfacets.method.rules import SCENE_MERGE_FROM
    from superfacets.scale.tiles import run as tiled_run

    assert SCENE_MERGE_FROM == 20
    assert merge_from_of(DEFAULTS, "points", scene=True) == 20
    assert merge_from_of(replace(DEFAULTS, merge_cost="auto", density=0.0), "points",
                         scene=True) == 5
    assert merge_from_of(replace(DEFAULTS, paper=True), "points", scene=True) == 1
    assert merge_from_of(DEFAULTS, "faces", scene=True) == 1
    assert merge_from_of(replace(DEFAULTS, merge_from=3), "points", scene=True) == 3
    rng = np.random.default_rng(0)
    xy = rng.random((20000, 2))
    pts = np.c_[xy, 0.002 * rng.standard_normal(20000) + 0.05 * np.sin(5 * xy[:, 0])]
    asked = []
    real = tiled_run.fine_count
    monkeypatch.setattr(tiled_run, "fine_count",
                        lambda k, ratio, n: asked.append(ratio) or real(k, ratio, n))
    for up, ratio in ((None, 5), ((0.0, 0.0, 1.0), 20)):
        r = segment(PointCloud(pts, up=up), 60)
        assert r.params["merge_from"] == ratio and r.n_segments == 60
        assert segment_tiled(PointCloud(pts, up=up), 60, tiles=2).n_segments == 60
        assert asked.pop() == ratio


def test_an_uneven_cloud_keeps_the_density_and_merges_by_the_default_cost_only():
    rng = np.random.default_rng(4)
    dense = np.c_[rng.random((6000, 2)), np.zeros(6000)]
    sparse = np.c_[rng.random((300, 2)) * [4, 1] + [1.5, 0], np.zeros(300)]
    r = segment(np.r_[dense, sparse], 40)
    assert r.params["density"] == 0.5 and r.params["merge_from"] == 5
    assert r.n_segments == 40 and r.params["merge_cost"] == "noise"
    r = segment(np.r_[dense, sparse], 40, merge_cost="auto")
    assert r.params["density"] == 0.5 and r.params["merge_from"] == 1


def _on_floor(labels, part):  # superpoints mostly of floor points
    share = np.bincount(labels, weights=(part == 0)) / np.bincount(labels)
    return int((share > 0.5).sum())


def test_a_tiled_run_merges_to_the_count_like_one_run():
    from superfacets.scale.tiles.run import segment_tiled

    pts, part = _room(5)
    plain = segment_tiled(pts, 60, tiles=4, merge_from=1)
    tiled = segment_tiled(pts, 60, tiles=4)
    assert tiled.params["merge_from"] == 5 and tiled.params["merged_from"] >= 250
    assert tiled.n_segments == 60 and np.unique(tiled.labels).size == 60
    assert plain.params["merge_from"] == 1 and plain.params["merged_from"] is None
    # as in one run (above): the floor's superpoints at least halve, the domes get the count
    assert _on_floor(tiled.labels, part) <= _on_floor(plain.labels, part) // 2
    assert _on_floor(tiled.labels, part) <= 2 * _on_floor(segment(pts, 60).labels, part)
    # every superpoint one connected piece of the point graph: no merge across a gap
    from superfacets.elements.points import point_graph
    from superfacets.method.connectivity import label_components

    g = point_graph(PointCloud(pts))
    lab = np.zeros(g.graph.n_elements, dtype=np.int64)
    lab[g.index] = tiled.labels
    assert np.unique(label_components(g.graph, lab)).size == 60


def test_the_tiles_sums_add_up_to_the_whole_clouds():
    """Each adjacency is summed by one tile, each point by its core's: the sums of two
    tiles are one tile's, and one tile's merges are one run's, partition for partition."""
    from dataclasses import replace

    from superfacets.elements.points import point_graph
    from superfacets.method.merges import FLAT_NOISE, flat_share, merge_to_count
    from superfacets.method.stages import resolve_rules
    from superfacets.scale.tiles.merges import _outer_sums, merge_names, tile_merge_stats

    pts, _ = _room(6)
    cloud = PointCloud(pts)
    pe = point_graph(cloud)
    g = pe.graph
    fine = np.zeros(g.n_elements, dtype=np.int64)
    fine[pe.index] = segment(cloud, 200, merge_from=1).labels  # per element
    names = 7 * np.arange(200) + 3
    rows = np.arange(g.n_elements)
    whole = tile_merge_stats(g, fine, names, np.ones(g.n_elements, bool), rows, 8192)
    east = g.positions[:, 0] > 0.43
    halves = [tile_merge_stats(g, fine, names, core, rows, 4096) for core in (east, ~east)]
    for field in ("count", "area"):
        total = np.zeros(200)
        for h in halves:
            total[np.searchsorted(names, h["names"])] += h[field]
        np.testing.assert_allclose(total, whole[field], rtol=1e-12)
    # the adjacencies inside each core summed there, those leaving a core by the driver
    # (named by the stitched labels: here the whole cloud's)
    sums = [*halves, _outer_sums(halves, names[fine])]
    assert all(h["outer_rows"].shape[0] > 0 for h in halves)
    assert whole["outer_rows"].shape[0] == 0
    edges = np.concatenate([h["edges"] for h in sums])
    assert len({tuple(e) for e in edges}) < len(edges)  # pairs summed by both halves
    key = lambda e: e[:, 0] * 10_000 + e[:, 1]  # noqa: E731
    border = np.bincount(np.searchsorted(key(whole["edges"]), key(edges)),
                         weights=np.concatenate([h["border"] for h in sums]))
    np.testing.assert_allclose(border, whole["border"], rtol=1e-12)
    # one tile holding everything sums each pair as one run does (named, in names' order)
    from superfacets.graph.sums import PAIR_FIELDS, border_sums

    one = border_sums(g, fine, 200)
    np.testing.assert_array_equal(whole["edges"], names[one["edges"]])
    for field in PAIR_FIELDS:
        np.testing.assert_allclose(whole[field], one[field], rtol=1e-12, atol=1e-15)

    rules = replace(resolve_rules(g, resolve(n_segments=40, density=0.0, merge_cost="auto")),
                    target=40)
    one_run, _ = merge_to_count(g, fine, rules)
    got, merged, _, fewest = merge_names([whole], 40, DEFAULTS.alpha, DEFAULTS.eta_convex)
    assert fewest == 40
    tiled = merged[np.searchsorted(got, names[fine])]
    assert np.unique(one_run * 10_000 + tiled).size == 40  # the same partition
    split = merge_names(halves, 40, DEFAULTS.alpha, DEFAULTS.eta_convex, labels=names[fine])
    assert np.unique(split[1]).size == 40
    # the default cost ('noise') too (this room reads no noise: auto's merges)
    noisy, _ = merge_to_count(g, fine, replace(resolve_rules(g, resolve(n_segments=40,
                                                                        density=0.0)),
                                               target=40))
    got, merged, _, _ = merge_names([whole], 40, DEFAULTS.alpha, DEFAULTS.eta_convex,
                                    cost="noise")
    tiled = merged[np.searchsorted(got, names[fine])]
    assert np.unique(noisy * 10_000 + tiled).size == 40
    # down to 10 the flat merges stop at 34, most points on the floor: the plane's rise
    rules = replace(rules, target=10)
    assert flat_share(fine, flat_merges(g, fine, 10, FLAT_NOISE * noise_variance(g))) > 0.5
    one_run, _ = merge_to_count(g, fine, rules)
    got, merged, flat, fewest = merge_names([whole], 10, DEFAULTS.alpha, DEFAULTS.eta_convex)
    assert (flat, fewest) == (34, 10)
    tiled = merged[np.searchsorted(got, names[fine])]
    assert np.unique(one_run * 10_000 + tiled).size == 10  # the same partition


def test_a_border_disagreement_never_merges_superpoints_that_do_not_touch():
    """A tile's label of a point in another tile's core can differ from the stitched one
    (the run's disagreements); the pairs such points make are named by the stitched
    labels, so no merged superpoint is left in two pieces."""
    from superfacets.elements.points import point_graph
    from superfacets.method.connectivity import label_components
    from superfacets.scale.tiles.merges import merge_names, tile_merge_stats

    pts, _ = _room(6, noise=0.0)  # one flat floor: the flat merges join any two neighbours
    cloud = PointCloud(pts)
    pe = point_graph(cloud)
    g = pe.graph
    fine = np.zeros(g.n_elements, dtype=np.int64)
    fine[pe.index] = segment(cloud, 200, merge_from=1).labels
    names = 7 * np.arange(200) + 3
    rows = np.arange(g.n_elements)
    east = g.positions[:, 0] > 0.43
    # the east tile sees the west points along its border as a far superpoint's
    ring = ~east & (g.positions[:, 0] > 0.40)
    floor = np.flatnonzero(np.abs(g.positions[:, 2]) < 1e-9)
    far = int(fine[floor[np.argmin(g.positions[floor, 0] + g.positions[floor, 1])]])
    assert not east[fine == far].any()  # far in the west, away from the border
    seen = fine.copy()
    seen[ring] = far
    tiles = [tile_merge_stats(g, seen, names, east, rows, 4096),
             tile_merge_stats(g, fine, names, ~east, rows, 4096)]
    for target in (150, 100, 60, 30):
        got, merged, _, _ = merge_names(tiles, target, DEFAULTS.alpha, DEFAULTS.eta_convex,
                                        labels=names[fine])
        lab = np.searchsorted(got, merged[np.searchsorted(got, names[fine])])
        assert np.unique(label_components(g, lab)).size == np.unique(lab).size, target


def test_a_tiled_run_merges_points_only():
    import trimesh

    from superfacets.scale.tiles.run import segment_tiled

    with pytest.raises(ParameterError, match="merge_from above 1: a tiled run merges"):
        segment_tiled(trimesh.creation.icosphere(3), 20, tiles=2, merge_from=5)


def test_the_command_line_takes_merge_from(tmp_path, capsys):
    from superfacets.cli import main
    rng = np.random.default_rng(5)
    pts = np.c_[rng.random((3000, 2)), 0.01 * np.sin(9 * rng.random(3000))]
    path = tmp_path / "cloud.xyz"
    np.savetxt(path, pts)
    out = tmp_path / "labels.txt"
    assert main(["segment", str(path), "-k", "20", "--merge-from", "1", "-o", str(out),
                 "-q"]) == 0
    np.testing.assert_array_equal(np.loadtxt(out, dtype=np.int64),
                                  segment(PointCloud(pts), 20, merge_from=1).labels)
    capsys.readouterr()
    assert main(["segment", str(path), "-k", "20", "-o", str(out)]) == 0
    assert "20 superpoints (merged from 100 finer ones, flat neighbours first, none above " \
        "16 times the mean; --merge-from 1" in capsys.readouterr().out  # (the default cost)
    assert main(["segment", str(path), "-k", "20", "--max-size-ratio", "0", "--merge-cost",
                 "auto", "-o", str(out)]) == 0
    assert "flat neighbours first; by the plane's rise or Ward's cost (--merge-cost auto); " \
        "--merge-from 1" in capsys.readouterr().out
    assert main(["segment", str(path), "-k", "20", "--merge-cost", "scene", "-o",
                 str(out)]) == 0
    assert "none above 16 times the mean; the scene's cost, its rise unweighted; " \
        "--merge-from 1" in capsys.readouterr().out
    np.testing.assert_array_equal(np.loadtxt(out, dtype=np.int64),
                                  segment(PointCloud(pts), 20, merge_cost="scene").labels)
    with pytest.raises(SystemExit):
        main(["segment", str(path), "-k", "20", "--merge-cost", "ward", "-o", str(out)])
    assert "invalid choice: 'ward'" in capsys.readouterr().err


def test_sorted_unique_is_numpys_unique():
    from superfacets._runtime.arrays import sorted_unique

    rng = np.random.default_rng(4)
    cases = [np.array([], dtype=np.int64), np.array([3]), rng.integers(-50, 50, 1000),
             rng.integers(0, 10**12, 20_000), rng.integers(0, 5, (40, 30)),
             np.array([2.5, np.nan, -1.0, 2.5, np.nan]), rng.random(100) > 0.5,
             rng.integers(0, 300, 5000).astype(np.int32)]
    for values in cases:
        got, want = sorted_unique(values), np.unique(values)
        assert got.dtype == want.dtype
        np.testing.assert_array_equal(got, want)


def test_ranked_labels_are_numpys_unique_with_its_inverse():
    """The tables that number a tiled run's labels (named by rows) and look up its merged
    names give what ``np.unique`` and ``np.searchsorted`` gave, -1 kept."""
    from superfacets._runtime.arrays import ranked, row_table

    rng = np.random.default_rng(8)
    for n, upper in ((0, 5), (1, 1), (1000, 50), (20_000, 10**6)):
        labels = rng.integers(-1, upper, n)
        names, ranks = ranked(labels, upper)
        valid = labels >= 0
        want, inverse = np.unique(labels[valid], return_inverse=True)
        np.testing.assert_array_equal(names, want)
        np.testing.assert_array_equal(ranks[valid], inverse)
        assert ranks.dtype == np.int64 and (ranks[~valid] == -1).all()
        at = row_table(names, upper)[labels]
        np.testing.assert_array_equal(np.where(valid, names[np.maximum(at, 0)], -1), labels)
    table = row_table(np.array([4, 0]), 6)
    assert table.tolist() == [1, -1, -1, -1, 0, -1, -1]
    with pytest.raises(ValueError, match="-1..9"):
        ranked(np.array([3, 10]), 10)


def test_the_merges_do_not_join_neighbours_of_another_colour():
    # a flat floor, a third of it painted: flat merges join the paint to the floor unless
    # the colour term is on; with it, only neighbours of one colour merge
    from superfacets import PointCloud

    rng = np.random.default_rng(5)
    xy = rng.random((6000, 2))
    painted = xy[:, 0] > 0.62
    col = np.where(painted[:, None], [0.2, 0.3, 0.8], [0.8, 0.8, 0.75])
    col = np.clip(col + rng.normal(0, 0.02, col.shape), 0, 1)
    cloud = PointCloud(np.c_[xy, rng.normal(0, 1e-3, 6000)], colors=col)
    blind, seeing = segment(cloud, 6, beta=0), segment(cloud, 6)
    assert blind.params["merge_from"] == seeing.params["merge_from"] == 5

    def mixed(labels):  # points in a superpoint whose majority is of the other side
        out = 0
        for s in np.unique(labels):
            m = painted[labels == s]
            out += min(m.sum(), (~m).sum())
        return out

    assert mixed(seeing.labels) < 0.1 * mixed(blind.labels)
    # a tiled run merges as one run does: its tiles' sums carry the colours
    from superfacets import segment_tiled

    tiled_blind = segment_tiled(cloud, 6, tiles=2, beta=0)
    tiled = segment_tiled(cloud, 6, tiles=2)
    assert tiled.n_segments == 6 and mixed(tiled.labels) < 0.1 * mixed(tiled_blind.labels)


def test_textured_neighbours_merge_and_an_even_board_stays_apart():
    """The colour gate of the flat merges reads each superpoint's own spread: neighbours
    on a textured floor (a photograph's grass) merge though their means differ beyond the
    points' noise floor; an evenly painted board does not, however flat."""
    from superfacets.inputs.cloud import PointCloud
    from superfacets.method.merges import feature_spread

    x = np.linspace(0, 1, 60)
    xy = np.stack(np.meshgrid(x, x), -1).reshape(-1, 2)
    g = _graph(np.c_[xy, np.zeros(len(xy))])
    cells = (np.minimum(g.positions[:, 0] * 6, 5.999).astype(np.int64) * 6
             + np.minimum(g.positions[:, 1] * 6, 5.999).astype(np.int64))
    rng = np.random.default_rng(2)
    shade = rng.normal(0, 0.06, (36, 1))  # each square's own mean: beyond the floor below
    texture = 0.5 + shade[cells] + rng.normal(0, 0.15, (len(xy), 1))
    spread = feature_spread(cells, texture, 36)
    assert np.allclose(spread, 0.15 ** 2, rtol=0.5)  # (100 points a square)
    merged = flat_merges(g, cells, 1, 1e-12, features=texture, max_jump=0.01)
    assert int(merged.max()) + 1 == 1  # the texture's spread lets every pair merge
    board = (cells == 14)[:, None]  # one square painted evenly, 0.3 apart
    even = 0.5 + 0.3 * board + rng.normal(0, 0.01, (len(xy), 1))
    merged = flat_merges(g, cells, 1, 1e-12, features=even, max_jump=0.03)
    assert int(merged.max()) + 1 == 2 and len(set(merged[board[:, 0]])) == 1
    # the same in tiles: their sums carry the squares of the colours
    from superfacets import segment, segment_tiled

    rgb = np.repeat(np.clip(texture, 0, 1), 3, axis=1)
    cloud = PointCloud(np.c_[xy, np.zeros(len(xy))], colors=rgb)
    one, tiled = segment(cloud, 4), segment_tiled(cloud, 4, tiles=2)
    assert one.n_segments == tiled.n_segments == 4


def test_the_merges_make_no_superpoint_above_the_size_bound():
    """An airborne tile in miniature (40,000 ground points, ten bushes) at k = 15: merged
    without a bound, its flat ground is five superpoints, the largest a third of the
    points (five times the mean); the bound
    (max_size_ratio, 16 by default) keeps every superpoint under that many times the mean
    count while the merges can, what the bushes are left paying for it."""
    from functools import partial

    from superfacets.errors import ParameterError

    segment = partial(_segment, merge_cost="auto")  # (the rule this terrain was measured on)
    pts, part = _terrain()
    k, n = 15, len(pts)
    free = segment(pts, k, max_size_ratio=0).labels
    assert np.bincount(free).max() > 4 * n / k  # the ground in a few large pieces
    ue = {}
    for ratio in (4, 2):
        r = segment(pts, k, max_size_ratio=ratio)
        assert r.n_segments == k and r.params["max_size_ratio"] == ratio
        assert np.bincount(r.labels).max() <= ratio * n / k
        ue[ratio] = _ue(r.labels, part)
    # the count the ground now takes is the bushes': UE 0.11 -> 0.14 at 4; at 2 the
    # ground takes seven superpoints or more, leaving eight for ten bushes (0.45)
    assert ue[4] < 1.5 * _ue(free, part) < ue[2]
    # a bound no superpoint reaches changes nothing: the merges before, bit for bit
    np.testing.assert_array_equal(segment(pts, k, max_size_ratio=n).labels, free)
    # where the bound cannot be kept (ten superpoints of a plane of one piece at 1): the
    # merges go on past it to the count
    plane = np.c_[np.random.default_rng(2).random((3000, 2)), np.zeros(3000)]
    assert segment(plane, 10, max_size_ratio=1).n_segments == 10
    with pytest.raises(ParameterError, match="max_size_ratio must be 0"):
        segment(pts, k, max_size_ratio=0.5)
    with pytest.raises(ParameterError, match="got inf; 0 means no bound"):
        segment(pts, k, max_size_ratio=float("inf"))


def test_a_tiled_run_keeps_the_size_bound():
    from superfacets import segment_tiled

    pts, _ = _terrain(n=20_000, bushes=4)
    free = segment_tiled(PointCloud(pts), 12, tiles=2, max_size_ratio=0).labels
    bound = segment_tiled(PointCloud(pts), 12, tiles=2, max_size_ratio=2).labels
    assert np.bincount(free).max() > 4 * len(pts) / 12
    assert np.unique(bound).size == 12 and np.bincount(bound).max() <= 2 * len(pts) / 12


def test_a_scene_keeps_its_superpoints_under_four_times_the_mean():
    """The bound by the input (None): a scene (a cloud with an up direction) 4, as the
    summary records it: the terrain at k = 20 with its heights unweighed (``up_weight`` 1:
    the default's weight of 7.1 cuts its ground already), whose ground in one run bounded
    at 16 keeps a superpoint of 6 times the mean, then has none above 4 times, in one run
    and in tiles; an object (no up direction) 16, its labels those of 16 given, bit for
    bit."""
    from superfacets import segment, segment_tiled

    pts, _ = _terrain(n=20_000, bushes=4)
    k, n, up = 20, len(pts), np.array([0.0, 0.0, 1.0])
    obj = segment(PointCloud(pts), k)
    assert obj.params["max_size_ratio"] == 16.0
    np.testing.assert_array_equal(obj.labels, segment(PointCloud(pts), k,
                                                      max_size_ratio=16).labels)
    wide = segment(PointCloud(pts, up=up), k, max_size_ratio=16, up_weight=1)
    assert wide.params["max_size_ratio"] == 16.0
    assert np.bincount(wide.labels).max() > 5 * n / k
    scene = segment(PointCloud(pts, up=up), k, up_weight=1)
    assert scene.params["max_size_ratio"] == 4.0 and scene.n_segments == k
    assert np.bincount(scene.labels).max() <= 4 * n / k
    tiled = segment_tiled(PointCloud(pts, up=up), k, tiles=2, up_weight=1)
    assert tiled.params["max_size_ratio"] == 4.0 and np.unique(tiled.labels).size == k
    assert np.bincount(tiled.labels).max() <= 4 * n / k


def test_no_stage_is_silent_on_a_terminal(monkeypatch):
    # the bar is redrawn every TICK seconds while a stage runs (its elapsed time goes on)
    import io
    import time

    from tqdm import tqdm

    from superfacets._runtime import progress

    monkeypatch.setattr(progress, "TICK", 0.02)
    out = io.StringIO()
    bar = tqdm(total=None, desc="a long stage", file=out, mininterval=0)
    stop = progress.tick(bar)
    give_up = time.monotonic() + 30  # (a stage that releases the interpreter, as the
    while out.getvalue().count("a long stage") < 5 and time.monotonic() < give_up:
        time.sleep(0.01)  # compiled ones do: the bar is drawn again meanwhile)
    stop.set()
    bar.close()
    assert out.getvalue().count("a long stage") >= 5
    with progress.waiting_bar("reading", show=False) as w:
        assert w.bar is None


def _street_graph(curb_angle: float, points: bool = False):
    """Road A, B (smooth, one plane), sidewalk C 12 cm up (a curb whose border turns by
    ``curb_angle``, concave), two rough pieces of vegetation D, E 2 m above, in a chain;
    as the merges read them (each point weighs one); with ``points``, also each part's."""
    from superfacets.graph.adjacency import SuperfacetGraph

    rng = np.random.default_rng(0)

    def plane(x0, z, sigma, n=200):
        p = rng.random((n, 3))
        p[:, 0] += x0
        p[:, 2] = z + sigma * rng.standard_normal(n)
        return p

    parts = [plane(0, 0.0, 0.005), plane(1, 0.0, 0.005), plane(2, 0.12, 0.005),
             plane(3, 2.0, 0.1), plane(4, 2.2, 0.1)]
    mean = np.array([p.mean(0) for p in parts])
    graph = SuperfacetGraph(
        edge_index=np.array([[0, 1, 2, 3], [1, 2, 3, 4]]), border_length=np.ones(4),
        mean_angle=np.array([0.0, curb_angle, 0.0, 0.0]),
        concave=np.array([0.0, 1.0, 0.0, 0.0]), area=np.full(5, 200.0), centroid=mean,
        normal=np.zeros((5, 3)), feature=None,
        scatter=np.array([(p - m).T @ (p - m) for p, m in zip(parts, mean)]))
    return (graph, parts) if points else graph


def test_the_scene_cost_keeps_a_concave_curb_and_merges_the_vegetation():
    """The scene's cost, down to 3 of 5: the road's coplanar halves first; then the curb
    (a rise of many noise units, but less than the vegetation's) where its border is flat,
    the vegetation where the curb's border turns by one radian (the crease factor, alpha
    200); the same from the compiled kernel and from numba's (the tests' oracle)."""
    from superfacets.method.merges import scene_merge_nodes

    noise = 0.005 ** 2
    assert scene_merge_nodes(_street_graph(0.0), 3, noise, 1.0, 200.0, 0.2).tolist() == \
        [0, 0, 0, 1, 2]
    assert scene_merge_nodes(_street_graph(1.0), 3, noise, 1.0, 200.0, 0.2).tolist() == \
        [0, 0, 1, 2, 2]


def test_the_ring_residual_is_the_neighbourhoods_plane_residual():
    """Each node's union with its neighbours: four points in a chain make rings of two or
    three points, each on a plane (0); the rough pieces of the street raise the median."""
    from superfacets.graph.adjacency import SuperfacetGraph
    from superfacets.method.merges import ring_residual

    corners = np.array([[1.0, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]])
    chain = SuperfacetGraph(edge_index=np.array([[0, 1, 2], [1, 2, 3]]),
                            border_length=np.ones(3), mean_angle=np.zeros(3),
                            concave=np.zeros(3), area=np.ones(4), centroid=corners,
                            normal=np.zeros((4, 3)), feature=None, scatter=np.zeros((4, 3, 3)))
    assert ring_residual(chain) == pytest.approx(0.0, abs=1e-12)
    # the street's rings AB, ABC, BCD, CDE, DE, from their points
    graph, parts = _street_graph(0.0, points=True)
    rings = [np.vstack([parts[j] for j in ring]) for ring in
             ((0, 1), (0, 1, 2), (1, 2, 3), (2, 3, 4), (3, 4))]
    expected = np.median([np.linalg.eigvalsh(np.cov(p.T, bias=True))[0] for p in rings])
    assert ring_residual(graph) == pytest.approx(expected, rel=1e-9)


def test_merge_cost_scene_reaches_the_count_in_one_run_and_in_tiles(monkeypatch):
    """``merge_cost='scene'``: every input merges by the scene's cost (the kernel's fourth
    cost, on a terrain whose flat regions hold most of the points too), to exactly k, in
    one run and in a tiled run; ``'auto'`` never calls it; anything else is refused,
    naming the choices."""
    from superfacets import segment_tiled
    from superfacets.method import merges

    ran = []
    scene = merges.scene_merge_nodes
    monkeypatch.setattr(merges, "scene_merge_nodes",
                        lambda *a, **kw: ran.append(a[1]) or scene(*a, **kw))
    pts, part = _terrain(n=20_000, bushes=4)
    auto = segment(pts, 12, merge_cost="auto")
    assert not ran and auto.params["merge_cost"] == "auto"
    r = segment(pts, 12, merge_cost="scene")
    assert ran and r.n_segments == 12 and r.params["merge_cost"] == "scene"
    assert _ue(r.labels, part) < 0.2  # the bushes are not lost in the ground
    ran.clear()
    tiled = segment_tiled(PointCloud(pts), 12, tiles=2, merge_cost="scene").labels
    assert ran and np.unique(tiled).size == 12
    with pytest.raises(ParameterError, match="merge_cost.*auto.*scene"):
        segment(pts, 12, merge_cost="ward")


def test_the_rise_weight_is_the_noises_share_of_the_residual():
    """``merge_cost='noise'``'s weight of the rise: ``min(1, s / v)``, ``v`` the median
    residual per point of the superpoints: 0 without noise, 1 where the noise is all they
    hold (or more), a quarter where it is a quarter; 1 where no superpoint has a residual."""
    from superfacets.method.merges import rise_weight

    count = np.array([4.0, 4.0, 8.0])
    scatter = np.stack([4.0 * np.eye(3), 4.0 * np.eye(3), 80.0 * np.eye(3)])  # 1, 1, 10
    assert rise_weight(0.0, count, scatter) == 0.0
    assert rise_weight(0.25, count, scatter) == pytest.approx(0.25)
    assert rise_weight(1.0, count, scatter) == rise_weight(3.0, count, scatter) == 1.0
    assert rise_weight(0.01, count, np.zeros((3, 3, 3))) == 1.0
    # a street's rough vegetation and smooth road: the median part is the road's (2 of 3)
    graph, parts = _street_graph(0.0, points=True)
    keep = [0, 1, 3]
    v = np.median([np.linalg.eigvalsh(np.cov(parts[i].T, bias=True))[0] for i in keep])
    assert rise_weight(0.005 ** 2, np.full(3, 200.0), graph.scatter[keep]) == \
        pytest.approx(min(1.0, 0.005 ** 2 / v), rel=1e-9)


def test_an_exact_tilted_plane_has_no_noise_whatever_the_rounding():
    """Points on a plane of no axis's direction: each neighbourhood's smallest eigenvalue
    is float64's rounding (up to 1e-19 here, most of them not 0), not noise: every one
    reads 0 (the noise of a machined part's sampled faces, which gave
    ``merge_cost='noise'`` a weight of 0.1-0.3 on a noise-free cloud)."""
    from superfacets.method import merges

    rng = np.random.default_rng(0)
    xy = rng.random((5000, 2))
    n = np.array([0.3, -0.5, 1.0]) / np.linalg.norm([0.3, -0.5, 1.0])
    u = np.cross(n, [1.0, 0, 0])
    u /= np.linalg.norm(u)
    g = _graph(xy[:, :1] * u + xy[:, 1:] * np.cross(n, u) + 0.1)
    assert not merges.neighbourhood_noise(g, np.arange(5000)).any()
    with pytest.MonkeyPatch.context() as m:  # the rounding the test rests on is there
        m.setattr(merges, "PLANE_ROUNDING", 0.0)
        assert np.count_nonzero(merges.neighbourhood_noise(g, np.arange(5000))) > 1000


def test_merge_cost_noise_charges_the_rise_by_the_noise_and_reaches_the_count(monkeypatch):
    """``merge_cost='noise'``: the scene's cost (the kernel's fourth) with the rise's unit
    over the weight: finite on a scanned terrain (noise 2 mm); on the same terrain without
    noise the default's merges, label for label; exactly k in one run and in tiles; merges
    on a cloud of uneven density too; the summary says it."""
    from superfacets import segment_tiled
    from superfacets.method import merges

    units = []
    scene = merges.scene_merge_nodes
    monkeypatch.setattr(merges, "scene_merge_nodes",
                        lambda *a, **kw: units.append(a[2]) or scene(*a, **kw))
    pts, part = _terrain(n=20_000, bushes=4)
    r = segment(pts, 12, merge_cost="noise")
    assert r.n_segments == 12 and r.params["merge_cost"] == "noise"
    assert units and all(np.isfinite(units)) and _ue(r.labels, part) < 0.2
    units.clear()
    rng = np.random.default_rng(1)
    xy = rng.random((20_000, 2))
    clean = np.c_[xy, 0.05 * np.sin(2 * np.pi * xy[:, 0]) * np.cos(np.pi * xy[:, 1])]
    r = segment(clean, 12, merge_cost="noise")
    assert r.n_segments == 12 and not units
    assert np.array_equal(r.labels, segment(clean, 12).labels)
    units.clear()
    tiled = segment_tiled(PointCloud(pts), 12, tiles=2, merge_cost="noise").labels
    assert units and np.unique(tiled).size == 12
    from dataclasses import replace

    from superfacets.method.params import DEFAULTS
    from superfacets.method.rules import merge_from_of
    assert merge_from_of(replace(DEFAULTS, density=0.5, merge_cost="noise"), "points") == 5


def test_the_cli_says_nothing_more_for_the_default_cost(tmp_path, capsys):
    """``--merge-cost noise``, the default, adds nothing to the summary (the others name
    theirs: ``test_the_command_line_takes_merge_from``)."""
    from superfacets.cli import main

    pts, _ = _terrain(n=8_000, bushes=2)
    path = tmp_path / "terrain.xyz"
    np.savetxt(path, pts)
    assert main(["segment", str(path), "-k", "10", "--merge-cost", "noise", "-o",
                 str(tmp_path / "labels.txt")]) == 0
    said = capsys.readouterr().out
    assert "none above 16 times the mean; --merge-from 1" in said and "cost" not in said


def test_an_exact_plane_is_merged_in_even_pieces():
    """Known answer: points on an exact plane (no noise: the flat test's threshold 0), with
    and without an up direction, merged to k = 100 of 20,000: every superpoint holds at
    least a quarter of the mean. Before the test allowed its union's rounding (64 machine
    epsilons of the scatter's trace), the pieces' rises, all float64's rounding, failed it
    at random, and 16 of 100 held 4-29 points (14 of 100 without an up direction)."""
    rng = np.random.default_rng(0)
    pts = np.c_[rng.random((20_000, 2)) * 100, np.zeros(20_000)]
    for cloud in (PointCloud(pts, up=(0, 0, 1)), PointCloud(pts)):
        r = segment(cloud, 100)
        sizes = np.bincount(r.labels)
        assert r.n_segments == 100 and sizes.min() >= 50, np.sort(sizes)[:5]
