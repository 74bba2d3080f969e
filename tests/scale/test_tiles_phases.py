"""What each tile does (superfacets.scale.tiles.phases): the start on the sample, the
labels, the orientation, the connectivity pass."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from tiled import _bumpy, _bumpy_cloud, _lattice_cloud

from superfacets import Mesh, segment
from superfacets.elements.faces import face_graph
from superfacets.inputs.cloud import PointCloud
from superfacets.io.regions import RegionReader
from superfacets.method.connectivity import label_components
from superfacets.method.params import resolve
from superfacets.scale.tiles.layout import (
    tile_box,
    tile_grid,
    tile_of,
)
from superfacets.scale.tiles.phases import tile_labels
from superfacets.scale.tiles.run import segment_tiled


def test_the_surveys_sample_names_its_rows(tmp_path, monkeypatch):
    """Every ``ceil(n / SAMPLE)``-th finite row, over chunks whose starts are not
    multiples of the stride: ``sample == positions[sample_rows]``."""
    from superfacets.io import regions

    monkeypatch.setattr(regions, "SAMPLE", 1000)
    monkeypatch.setattr(regions, "CHUNK", 777)
    pts = np.random.default_rng(0).random((10_001, 3))
    np.save(tmp_path / "c.npy", pts)
    survey = RegionReader.open(tmp_path / "c.npy").survey()
    np.testing.assert_array_equal(survey.sample_rows, np.arange(0, 10_001, 11))
    np.testing.assert_array_equal(survey.sample, pts[survey.sample_rows])


def test_a_clouds_tiles_start_from_centers_found_on_the_sample(monkeypatch):
    """On a cloud the tiles' centers phase is replaced by one run on the survey's
    sample (thinned to a quarter of the cloud here); the refine round starts from its
    centers, the labels phase from theirs; the same count; ``refine=0`` keeps the
    centers phase (where no round follows to run the passes on every point)."""
    from superfacets.scale.tiles import phases as tiling

    seen = []
    real = tiling.sample_start

    def start(sample, rows, *args, **kw):
        out = real(sample, rows, *args, **kw)
        seen.append((sample, rows, out))
        return out

    monkeypatch.setattr(tiling, "sample_start", start)
    monkeypatch.setattr(tiling, "START_MIN_POINTS", 1000)
    cloud = _bumpy_cloud(20_000)
    res = segment_tiled(cloud, 30, tiles=4, merge_from=1)
    (sample, rows, (found, pos)), = seen
    np.testing.assert_array_equal(sample[rows], cloud.points)  # (the whole cloud here)
    assert 30 <= found.size and (np.diff(found) > 0).all() and found.max() < 20_000
    assert (found % 4 == 0).all()  # on every 4th point: a quarter of the cloud
    np.testing.assert_array_equal(pos, cloud.points[found])
    assert res.n_segments == 30 and "start" in res.timings and "centers" not in res.timings
    assert sum(t["centers"] for t in res.tiles) >= 30
    assert all(t["peak_mib"] is None or t["peak_mib"] >= t["labels_peak_mib"]
               for t in res.tiles)
    assert all("refine_seconds" in t and "labels_seconds" in t for t in res.tiles)
    plain = segment_tiled(cloud, 30, tiles=4, merge_from=1, refine=0)
    assert "centers" in plain.timings and "start" not in plain.timings and len(seen) == 1


def test_the_orientation_and_the_start_read_one_thinned_sample(monkeypatch, tmp_path):
    """The normals' orientation reference is made on the sample the start runs on (the
    survey's, thinned to a quarter of the cloud here), and the start runs on that cloud and
    the point graph the orientation built, not on a graph of its own."""
    from superfacets.scale.tiles import phases as tiling

    seen = []
    real = tiling.sample_start

    def start(sample, rows, n_rows, params, r, diagonal, cloud=None, *args, **kw):
        step = tiling.start_step(sample.shape[0], n_rows, params.n_segments)
        seen.append((cloud, sample[::step], bool(cloud.__dict__.get("_point_graphs"))))
        return real(sample, rows, n_rows, params, r, diagonal, cloud, *args, **kw)

    monkeypatch.setattr(tiling, "sample_start", start)
    monkeypatch.setattr(tiling, "START_MIN_POINTS", 1000)
    np.save(tmp_path / "c.npy", _bumpy_cloud(20_000).points)  # (no normals: oriented)
    res = segment_tiled(tmp_path / "c.npy", 30, tiles=4, merge_from=1)
    (cloud, thinned, had_graph), = seen
    assert thinned.shape[0] == 5000 and res.n_segments == 30  # (every 4th point)
    np.testing.assert_array_equal(cloud.points, thinned)  # the orientation's own cloud,
    assert had_graph  # with the graph it built


@pytest.mark.parametrize("options", [dict(n_segments=100), dict(n_segments=None,
                                                                radius=0.004)])
def test_a_sample_too_small_for_the_centers_leaves_them_to_the_tiles(options, tmp_path,
                                                                     monkeypatch):
    """A survey's sample of fewer than START_FEWEST_PER_CENTER (5) points a center (a
    huge count on a huge cloud), or of fewer points than the radius asks centers, starts
    no run: each tile samples its own centers, as on a mesh. From 5 a center, the start
    runs on the sample."""
    from superfacets.io import regions
    from superfacets.scale.tiles.phases import START_FEWEST_PER_CENTER

    monkeypatch.setattr(regions, "SAMPLE", 400)  # every 50th of 20,000 points: 4 a center
    np.save(tmp_path / "c.npy", _bumpy_cloud(20_000).points)
    res = segment_tiled(tmp_path / "c.npy", tiles=4, merge_from=1, **options)
    assert "centers" in res.timings and all(t["centers_seconds"] >= 0 for t in res.tiles)
    assert res.n_segments >= (100 if options["n_segments"] else 2000)
    if options["n_segments"]:
        assert START_FEWEST_PER_CENTER == 5
        monkeypatch.setattr(regions, "SAMPLE", 500)  # every 40th: 5 a center
        res = segment_tiled(tmp_path / "c.npy", tiles=4, merge_from=1, **options)
        assert "start" in res.timings and "centers" not in res.timings
        assert res.n_segments == 100


@pytest.mark.parametrize("kind", ["mesh", "cloud"])
def test_the_refine_round_moves_only_the_cores_centers(kind, monkeypatch):
    """Each tile's refine round holds the centers of its halo where they are (their own
    tiles move them): its passes get every element outside its core as fixed, and every
    halo center it was given is a center of its last pass; without the hold (FREEZE_HALO
    False) some move. Either way a whole run's count comes out."""
    from superfacets.scale.tiles import phases as tiling

    seen = []
    real = tiling.pipeline

    def spy(inp, p, **kw):
        out = real(inp, p, **kw)
        if kw.get("initial") is not None:  # (the refine round's passes)
            seen.append((kw["initial"], kw.get("fixed"), out.classification[1]))  # (elements)
        return out

    monkeypatch.setattr(tiling, "pipeline", spy)
    source = _bumpy(4) if kind == "mesh" else _bumpy_cloud(8000)
    for hold in (True, False):
        monkeypatch.setattr(tiling, "FREEZE_HALO", hold)
        seen.clear()
        res = segment_tiled(source, 40, tiles=2)  # (merged to the count at the end)
        assert res.n_segments == 40 and len(seen) == 2
        still = []
        for initial, fixed, last in seen:
            assert (fixed is not None) == hold
            halo = initial[fixed[initial]] if hold else initial
            still.append(np.isin(halo, last).all())
            if hold:
                assert 0 < fixed.sum() < fixed.size  # (the halo's elements, not the core's)
        assert all(still) == hold


def test_a_mesh_tiles_labels_phase_replays_its_refine_rounds_expansions(monkeypatch):
    """A mesh tile held between its phases labels its box by replaying the refine round's
    recorded expansions of the centers the two share (its core's) and expanding only the
    others (its halo's, moved by their own tiles): fewer expansions than centers, and the
    same labels as a fresh classification of every center."""
    from superfacets.scale.tiles import phases as tiling

    real = tiling._replaying
    runs = []

    def spy(graph, w, window_r2, spaces):
        kept = real(graph, w, window_r2, spaces)
        if kept is not None:
            classify = kept.classify

            def counted(centers, n, dist, label):
                k, expanded = classify(centers, n, dist, label)
                runs.append((n, expanded))
                return k, expanded

            kept.classify = counted
        return kept

    mesh = _bumpy(4)
    monkeypatch.setattr(tiling, "_replaying", spy)
    replayed = segment_tiled(mesh, 40, tiles=2)
    assert len(runs) == 2  # (each tile's labels phase)
    assert all(0 < expanded < n for n, expanded in runs), runs
    monkeypatch.setattr(tiling, "_replaying", lambda *a: None)
    fresh = segment_tiled(mesh, 40, tiles=2)
    np.testing.assert_array_equal(replayed.labels, fresh.labels)


def test_core_classification_is_the_whole_inputs_from_the_same_centers():
    """Known answer: with a halo of 2 window * r, each tile labels its core as one run over
    the whole input does from the same centers (paper's classification, no post-step)."""
    mesh = _bumpy(4)
    p = resolve(n_segments=60, paper=True, enforce_connectivity=False)
    g = face_graph(mesh)
    r = math.sqrt(g.area / (60 * math.pi))
    centers = np.sort(segment(mesh, 60, paper=True).centers)
    whole = tile_labels(mesh, centers, p, r, g.diagonal)
    edges = tile_grid(g.positions.min(0), g.positions.max(0), 4)
    tiles = tile_of(g.positions, edges)
    seen = 0
    for t in range(4):
        lo, hi = tile_box(edges, t, 2 * p.window * r)
        rows = np.flatnonzero(((g.positions >= lo) & (g.positions <= hi)).all(1))
        used, local = np.unique(np.asarray(mesh.faces)[rows], return_inverse=True)
        part = Mesh(np.asarray(mesh.vertices)[used], local.reshape(-1, 3))
        at = np.searchsorted(rows, centers)
        ok = (at < rows.size) & (rows[np.minimum(at, rows.size - 1)] == centers)
        named = tile_labels(part, at[ok], p, r, g.diagonal)
        core = tiles[rows] == t
        np.testing.assert_array_equal(rows[named[core]], whole[rows[core]])
        seen += core.sum()
    assert seen == mesh.n_faces


def test_every_tile_orients_points_like_the_whole_cloud(tmp_path):
    """Points with no normals and no viewpoint: each tile's pieces are turned like the
    oriented sample the survey keeps, so a tile holding the inside of a torus's ring
    (concave seen from its own mean) gets the whole cloud's normals, not their opposite."""
    from scipy.spatial import cKDTree

    from superfacets.elements.points import point_graph
    from superfacets.scale.tiles.phases import orientation_reference

    torus = trimesh.creation.torus(major_radius=1.0, minor_radius=0.4, major_sections=64,
                                   minor_sections=32)
    pts, _ = trimesh.sample.sample_surface_even(torus, 20000, seed=2)
    np.save(tmp_path / "t.npy", np.asarray(pts, dtype=np.float64))
    reader = RegionReader.open(tmp_path / "t.npy")
    s = reader.survey()
    assert not s.normals and reader.viewpoint is None
    whole = point_graph(PointCloud(pts)).graph
    reference = orientation_reference(s.sample, 10)
    layout = tile_grid(s.lo, s.hi, (3, 3, 1))  # the middle tile (+0.3): the ring's inner side
    agree = {}
    for use in (False, True):
        for t in range(layout.n_tiles):
            lo, hi = layout.box(t, 0.3)
            _, pos, cloud = reader.read_box(lo, hi)
            if use:
                inside = ((reference[0] >= lo - 0.1) & (reference[0] <= hi + 0.1)).all(1)
                cloud = PointCloud(cloud.points, orient_like=(reference[0][inside],
                                                              reference[1][inside]))
            g = point_graph(cloud).graph
            _, j = cKDTree(whole.positions).query(g.positions)
            agree[use, t] = (np.einsum("ij,ij->i", g.normals, whole.normals[j]) > 0).mean()
    assert agree[False, 4] < 0.01  # turned outwards from its own mean: all inverted
    assert min(agree[True, t] for t in range(9)) > 0.99


def test_equal_distances_give_a_tile_the_whole_clouds_neighbours():
    """Invariant: ties at the k-th distance go to the lowest index (the Z-order in the
    cloud's frame), so a box of the cloud given the whole cloud's frame (as a tiled run
    gives its tiles) has the whole cloud's neighbours away from its edge."""
    from superfacets import PointCloud
    from superfacets.elements.points import point_graph

    cloud = _lattice_cloud()
    whole = point_graph(cloud, 10).graph
    frame = np.array([cloud.points.min(axis=0), cloud.points.max(axis=0)])
    box = ((cloud.points[:, 0] >= 3) & (cloud.points[:, 0] < 28) & (cloud.points[:, 1] < 30))
    part = point_graph(PointCloud(cloud.points[box], frame=frame), 10).graph

    def neighbours(g):
        pos = g.positions
        return {tuple(pos[i]): {tuple(pos[j]) for j in g.indices[g.indptr[i]:g.indptr[i + 1]]}
                for i in range(g.n_elements)}

    a, b = neighbours(whole), neighbours(part)
    inner = [p for p in b if 8 <= p[0] < 23 and p[1] < 25]
    assert len(inner) == 375
    assert all(a[p] == b[p] for p in inner)
    assert any(len(a[p]) != 10 for p in inner)  # ties were in play (degrees vary)


def test_tile_connect_joins_stray_pieces_of_its_own_superfacets():
    """Known answer on a strip of 10 faces x 2: the stray piece of an owned label joins
    the neighbour it shares the longest border with; other labels' pieces are left."""
    from superfacets.scale.tiles.phases import tile_connect

    v = np.array([[x, y, 0.0] for y in (0, 1) for x in range(11)])
    faces = []
    for x in range(10):
        a, b, c, d = x, x + 1, 11 + x, 12 + x
        faces += [[a, b, d], [a, d, c]]
    mesh = Mesh(v, np.array(faces))
    labels = np.repeat([100, 200, 100, 300, 300], 4).astype(np.int64)  # 100 in two pieces
    p = resolve(n_segments=3)
    fixed = tile_connect(mesh, labels, np.array([100]), np.array([0]), p)
    np.testing.assert_array_equal(fixed, np.repeat([100, 200, 200, 300, 300], 4))
    # not owned here (its center is in another tile's core): left as it is
    assert tile_connect(mesh, labels, np.array([200, 300]), np.array([4, 12]), p) is None
    # the center's piece keeps the name, wherever it is
    fixed = tile_connect(mesh, labels, np.array([100]), np.array([9]), p)
    np.testing.assert_array_equal(fixed, np.repeat([200, 200, 100, 300, 300], 4))


def test_tile_connect_on_points_reads_an_unoriented_graph_of_the_same_adjacency(monkeypatch):
    """The repair reads the adjacency, sizes and border lengths: on points it builds the
    graph without orienting the normals (a third of the build), and repairs as with the
    oriented graph."""
    from superfacets.elements import points
    from superfacets.inputs.cloud import PointCloud
    from superfacets.scale.tiles.phases import tile_connect

    rng = np.random.default_rng(3)
    xyz = rng.normal(size=(4000, 3))
    xyz /= np.linalg.norm(xyz, axis=1, keepdims=True)
    cloud = PointCloud(xyz)
    u = points.point_graph(cloud, oriented=False).graph
    g = points.point_graph(cloud).graph
    assert u is not g and points.point_graph(cloud, oriented=False).graph is g  # (built)
    for name in ("indptr", "indices", "sizes", "border_shares", "lengths"):
        np.testing.assert_array_equal(getattr(u, name), getattr(g, name), err_msg=name)
    cos = (np.asarray(g.normals, float) * np.asarray(u.normals, float)).sum(axis=1)
    np.testing.assert_allclose(np.abs(cos), 1.0, atol=1e-5)
    assert (cos < 0).any()  # PCA's signs, not turned outwards
    labels = (xyz[:, 0] > 0).astype(np.int64) * 7 + 3  # two halves, names 3 and 10
    labels[(xyz[:, 0] < -0.6) & (xyz[:, 1] > 0.5)] = 10  # a stray piece of 10
    p = resolve(n_segments=2)
    center = np.array([int(np.argmax(xyz[:, 0]))])
    fixed = tile_connect(PointCloud(xyz), labels, np.array([10]), center, p)
    assert fixed is not None and (fixed[labels == 10] != 10).sum() > 0
    built = points.point_graph
    monkeypatch.setattr(points, "point_graph",
                        lambda *a, oriented=True, **k: built(*a, **k))  # oriented anyway
    np.testing.assert_array_equal(
        tile_connect(PointCloud(xyz), labels, np.array([10]), center, p), fixed)


def test_the_connect_pass_repairs_pieces_left_by_a_thin_halo():
    """A halo of one expansion's reach makes tiles disagree at their borders; the pass
    after stitching leaves every superfacet in one piece."""
    mesh = _bumpy(5)  # how many pieces a thin halo leaves depends on the method: 72 here
    res = segment_tiled(mesh, 40, tiles=(2, 2, 2), halo=1, start="tiles")  # (the tiles'
    # own start: their borders leave pieces; from the survey's sample this input has none)
    assert res.disagreements > 0 and res.repaired > 0 and "connect" in res.timings
    pieces = label_components(face_graph(mesh), res.labels)
    assert np.unique(pieces).size == res.n_segments


def test_the_connect_pass_looks_only_at_the_superfacets_the_disagreements_name(monkeypatch):
    """Every other superfacet is its owner tile's, whole: repairing only those the
    disagreeing rows name gives the labels that repairing every superfacet of every tile
    gives, bit for bit: on a mesh whose thin halo leaves pieces to repair (every
    superfacet named there), and on a cloud where the disagreements name 185 of its 299
    superpoints (fewer looked at)."""
    from superfacets.scale.tiles import phases as tiling
    from superfacets.scale.tiles import run as tiled_run

    real_connect, real_stitched, owned = tiling.tile_connect, tiled_run._stitched, []

    def connect(inp, labels, mine, mine_rows, params):
        owned.append(len(mine))
        return real_connect(inp, labels, mine, mine_rows, params)

    def every(done, n_rows):  # (the repair of every superfacet: all of them suspects)
        labels, disagreements, _ = real_stitched(done, n_rows)
        return labels, disagreements, np.unique(labels[labels >= 0])

    monkeypatch.setattr(tiling, "tile_connect", connect)
    for data, k, own in ((_bumpy(5), 40, "tiles"), (_bumpy_cloud(6000), 60, "sample")):
        owned.clear()  # (the mesh: its tiles' own start, whose borders leave pieces)
        res = segment_tiled(data, k, tiles=(2, 2, 2), halo=1, start=own)
        few = sum(owned)
        owned.clear()
        monkeypatch.setattr(tiled_run, "_stitched", every)
        full = segment_tiled(data, k, tiles=(2, 2, 2), halo=1, start=own)
        monkeypatch.setattr(tiled_run, "_stitched", real_stitched)
        assert res.disagreements > 0 and res.repaired == full.repaired
        np.testing.assert_array_equal(res.labels, full.labels)
        if isinstance(data, Mesh):
            assert res.repaired > 0 and np.unique(label_components(
                face_graph(data), res.labels)).size == res.n_segments
        else:
            assert 0 < few < sum(owned)


def test_the_connect_pass_looks_again_near_what_a_repair_moved(monkeypatch):
    """Tiles repair at once, from the same stitched labels: a piece one tile moves can be
    left apart by another's repair (seen on a 5M-point cloud in 16 tiles: 4 points).
    Here one tile's first repair also moves one face into a superfacet it does not
    touch; the superfacets it moved to and from are looked at again (by their tiles), and
    every superfacet ends in one piece; then nothing moves, and the pass stops."""
    from superfacets.scale.tiles import phases as tiling

    mesh = _bumpy(5)
    plain = segment_tiled(mesh, 40, tiles=(2, 2, 2), halo=1,  # 1 repair round suffices
                          start="tiles")  # (the tiles' own start: pieces to repair)
    real, calls, spoiled = tiling.tile_connect, [], []

    def connect(inp, labels, owned, owned_rows, params):
        fixed = real(inp, labels, owned, owned_rows, params)
        calls.append(len(owned))
        if not spoiled and fixed is not None:  # one face of a far superfacet's, once
            out = fixed.copy()
            g = face_graph(inp)
            lab = np.asarray(out)
            for e in range(lab.size):
                near = set(lab[g.indices[g.indptr[e]:g.indptr[e + 1]]].tolist())
                far = [x for x in owned.tolist() if x not in near and x != lab[e]]
                if lab[e] in owned and far and (lab == lab[e]).sum() > 1:
                    out[e] = far[0]
                    spoiled.append(e)
                    return out
        return fixed

    monkeypatch.setattr(tiling, "tile_connect", connect)
    res = segment_tiled(mesh, 40, tiles=(2, 2, 2), halo=1, start="tiles")
    assert spoiled and len(calls) > 8  # a second round, on the tiles owning what moved
    assert len(calls) < 3 * 8  # not every tile every round: then nothing moved
    pieces = label_components(face_graph(mesh), res.labels)
    assert np.unique(pieces).size == res.n_segments
    assert res.repaired == plain.repaired + 2  # the face moved away, and back


def test_a_sample_of_fewer_than_three_distinct_points_gives_no_reference():
    """The survey's sample is oriented only where it holds three distinct points (a pass
    per point found, as ``np.unique`` over its rows counted them): one or two distinct
    points, repeated, give empty arrays; a third anywhere in the sample gives normals."""
    from superfacets.scale.tiles.phases import _three_distinct, orientation_reference

    rng = np.random.default_rng(11)
    a, b, c = np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 1.0, 0])
    for rows, want in (([a], False), ([a, a, a], False), ([a, b, a, b, b], False),
                       ([a, b, c], True), ([b, b, b, b, a, a, c], True),
                       ([a, -0.0 * a, b], False)):
        pts = np.array(rows, dtype=np.float64)
        assert _three_distinct(pts) == want == (np.unique(pts, axis=0).shape[0] >= 3)
    for _ in range(20):
        pts = rng.integers(0, 2, (rng.integers(1, 9), 3)).astype(np.float64)
        assert _three_distinct(pts) == (np.unique(pts, axis=0).shape[0] >= 3)
    positions, normals = orientation_reference(np.array([a, b] * 50), 10)
    assert positions.shape == normals.shape == (0, 3)


def test_a_scans_viewpoint_reaches_the_start_on_its_sample(monkeypatch):
    """The sample a tiled scan starts from faces its scanner, as every tile does."""
    from superfacets.scale.tiles import phases as tiling

    seen = []
    real = tiling.pipeline

    def pipeline(cloud, *args, **kw):
        seen.append(cloud.viewpoint)
        return real(cloud, *args, **kw)

    monkeypatch.setattr(tiling, "pipeline", pipeline)
    cloud = _bumpy_cloud(20_000)
    scan = PointCloud(cloud.points, viewpoint=np.array([0.0, 0.0, 9.0]))
    res = segment_tiled(scan, 30, tiles=4, merge_from=1)
    assert "start" in res.timings
    np.testing.assert_array_equal(seen[0], [0.0, 0.0, 9.0])  # (the start runs first)


def test_a_tile_whose_clean_up_leaves_a_piece_alone_names_it_by_a_center_of_its_own():
    """The clean-up makes a piece left with no neighbour a superfacet of its own (one
    tile of the bunny in 4, at 109 superfacets): the tile names it by a center in it, as
    one run does (it stopped the run with an IndexError), and the run gives exactly k."""
    from conftest import MESHES, need

    from superfacets.io import read_input
    from superfacets.scale.tiles import phases as tiling

    seen = []
    real = tiling.clean_up

    def spy(graph, labels, kept, *a):
        out = real(graph, labels, kept, *a)
        seen.append(int(out.max()) + 1 - len(kept))
        return out

    mesh = read_input(need(MESHES / "bunny.tri.xz"))
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(tiling, "clean_up", spy)
        res = segment_tiled(mesh, 100, tiles=4, start="tiles")  # (the case's start)
    assert max(seen) >= 1  # the case: a superfacet more than centers
    assert res.n_segments == 100 and (res.labels >= 0).all()
    pieces = label_components(face_graph(mesh), res.labels)
    assert np.unique(pieces).size == 100
