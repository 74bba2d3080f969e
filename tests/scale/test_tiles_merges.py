"""The merges to the count of a tiled run (superfacets.scale.tiles.merges)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from tiled import _bumpy

from superfacets import ParameterError, segment
from superfacets.elements.faces import face_graph
from superfacets.method.params import resolve
from superfacets.scale.tiles.run import segment_tiled


def test_a_meshs_merges_from_its_tiles_sums_are_one_runs_wards_merges():
    """A tiled mesh merges its few extra superfacets from the tiles' sums (no noise read:
    no flat merges) as one run's exact count merges the same labels on the whole graph."""
    from superfacets.method.finish import exact_count
    from superfacets.method.stages import resolve_rules
    from superfacets.scale.tiles.merges import merge_names, tile_merge_stats

    mesh = _bumpy(4)
    g = face_graph(mesh)
    labels = np.asarray(segment(mesh, 60).labels, dtype=np.int64)
    names = np.arange(60, dtype=np.int64) * 7 + 3  # (the centers' rows, in a tiled run)
    south = g.positions[:, 1] < np.median(g.positions[:, 1])
    stats = [tile_merge_stats(g, labels, names, core, np.arange(g.n_elements), 0)
             for core in (south, ~south)]
    assert all(s["noise"].size == 0 for s in stats)
    p = resolve(n_segments=40)
    got, merged, flat, fewest = merge_names(stats, 40, p.alpha, p.eta_convex)
    assert flat == 60 and fewest == 40 and np.unique(merged).size == 40
    want, _ = exact_count(g, labels, resolve_rules(g, p))
    tiled = np.searchsorted(got, merged)[labels]  # each face's merged superfacet
    assert np.unique(want * 1000 + tiled).size == 40  # the same partition


def test_a_tiled_mesh_with_merge_from_1_keeps_its_tiles_own_superfacets():
    mesh = _bumpy(4)
    res = segment_tiled(mesh, 60, tiles=4, merge_from=1)
    plain = segment_tiled(mesh, 60, tiles=4)
    assert res.params["merged_from"] is None and res.n_segments <= 60
    assert plain.n_segments == 60 and plain.params["merged_from"] >= 60


def _one_runs_levels(graph_of, labels, levels, cost, extent_weight=0.0):
    """The hierarchy one run makes of ``labels`` on its element graph (``graph_of``: the
    graph and each row's element)."""
    from superfacets.graph.adjacency import superfacet_graph
    from superfacets.graph.hierarchy import hierarchy, planarity_graph

    graph, element = graph_of
    per = np.full(graph.n_elements, -1)
    per[element] = labels
    sg = (superfacet_graph if cost == "ward" else planarity_graph)(graph, per)
    return hierarchy(sg, levels, cost=cost, extent_weight=extent_weight)


def _cloud_file(path, pts, normals) -> None:
    """A PLY of points with their normals (each tile's graph then the whole cloud's)."""
    from plyfile import PlyData, PlyElement

    v = np.empty(len(pts), dtype=[(c, "f8") for c in ("x", "y", "z", "nx", "ny", "nz")])
    for i, c in enumerate(("x", "y", "z", "nx", "ny", "nz")):
        v[c] = np.c_[pts, normals][:, i]
    PlyData([PlyElement.describe(v, "vertex")]).write(str(path))


def test_a_tiled_runs_levels_are_one_runs_hierarchy_of_its_labels(tmp_path):
    """The levels merged from the tiles' sums are those one run's hierarchy makes of the
    same labels, parent for parent: a cloud (its normals in the file, so that each tile's
    graph is the whole cloud's over its core) by both costs, and a mesh."""
    from superfacets import PointCloud
    from superfacets.elements.points import point_graph
    from superfacets.evaluation.datasets.sampling import sample_points

    mesh = _bumpy(4)
    pts, face = sample_points(mesh, 12000, seed=2)
    normals = trimesh.Trimesh(mesh.vertices, mesh.faces).face_normals[face]
    path = tmp_path / "cloud.ply"
    _cloud_file(path, pts, normals)
    built = point_graph(PointCloud(pts, normals=normals))
    for tiles, cost in ((1, "ward"), (3, "ward"), (3, "planarity")):
        r = segment_tiled(str(path), 120, tiles=tiles, workers=1, levels=[40, 8],
                          level_cost=cost, extent_weight=0.0 if cost == "planarity" else None)
        assert r.hierarchy.levels == (40, 8)
        want = _one_runs_levels((built.graph, built.index), r.labels, [40, 8], cost)
        for got, expect in zip(r.hierarchy.parents, want.parents):
            np.testing.assert_array_equal(got, expect)
        top = r.hierarchy.labels(1, r.labels)
        assert len(np.unique(top)) == 8
    # a cloud of uneven density: a planarity level's extent weighs (as one run's), Ward's not
    from superfacets.elements.density import AUTO_SPREAD
    from superfacets.graph.hierarchy import AUTO_EXTENT_WEIGHT

    keep = np.random.default_rng(3).random(len(pts)) < np.exp(-4 * (pts[:, 0] - pts[:, 0].min()))
    _cloud_file(tmp_path / "uneven.ply", pts[keep], normals[keep])
    built = point_graph(PointCloud(pts[keep], normals=normals[keep]))
    for cost, weight in (("ward", 0.0), ("planarity", AUTO_EXTENT_WEIGHT)):
        r = segment_tiled(str(tmp_path / "uneven.ply"), 80, tiles=3, workers=1, levels=[20],
                          level_cost=cost)
        assert r.size_spread > AUTO_SPREAD
        want = _one_runs_levels((built.graph, built.index), r.labels, [20], cost, weight)
        np.testing.assert_array_equal(r.hierarchy.parents[0], want.parents[0])
    r = segment_tiled((mesh.vertices, mesh.faces), 60, tiles=3, workers=1, levels=20)
    want = _one_runs_levels((face_graph(mesh), np.arange(mesh.n_faces)), r.labels, [20],
                            "ward")
    np.testing.assert_array_equal(r.hierarchy.parents[0], want.parents[0])
    assert segment_tiled((mesh.vertices, mesh.faces), 60, tiles=2, workers=1).hierarchy is None


def test_a_tiled_runs_level_options_are_refused_in_words(monkeypatch):
    import superfacets.scale.tiles.run as run

    mesh = _bumpy(3)
    for kw, said in ((dict(levels=[61]), r"at most the 60 segments they merge \(n_segments\)"),
                     (dict(levels=[10], level_cost="flat"), "level_cost must be"),
                     (dict(levels=[10], extent_weight=0.1), "a term of level_cost="),
                     (dict(level_cost="planarity"), "give levels too"),
                     (dict(levels="ten"), "levels")):
        with pytest.raises(ParameterError, match=said):  # (before the survey)
            monkeypatch.setattr(run, "_surveyed", None)
            segment_tiled((mesh.vertices, mesh.faces), 60, tiles=2, workers=1, **kw)
    monkeypatch.undo()
    with pytest.raises(ParameterError, match="mesh's levels merge by Ward's cost"):
        segment_tiled((mesh.vertices, mesh.faces), 60, tiles=2, workers=1, levels=[10],
                      level_cost="planarity")


def test_a_tiled_runs_learning_graph_is_one_runs_of_its_labels(tmp_path):
    """The superpoint graph in the learning layout summed over the tiles is the one one
    run's learning_graph makes of the same labels: its features to the last bit of their
    float32, centroids to 1e-12 (the order of the additions): a cloud with normals and
    colours in 1 and 3 tiles, and a mesh."""
    from plyfile import PlyData, PlyElement

    from superfacets import PointCloud
    from superfacets.elements.builders import elements_of
    from superfacets.elements.features import per_element
    from superfacets.evaluation.datasets.sampling import sample_points
    from superfacets.graph.adjacency import superfacet_graph
    from superfacets.graph.learning import learning_arrays

    mesh = _bumpy(4)
    pts, face = sample_points(mesh, 12000, seed=5)
    normals = trimesh.Trimesh(mesh.vertices, mesh.faces).face_normals[face]
    rgb = (np.abs(pts) * 120).clip(0, 255).astype(np.uint8)
    names = ("x", "y", "z", "nx", "ny", "nz", "red", "green", "blue")
    v = np.empty(len(pts), dtype=[(c, "f8") for c in names[:6]] + [(c, "u1") for c in names[6:]])
    for i, c in enumerate(names):
        v[c] = np.c_[pts, normals, rgb][:, i]
    path = tmp_path / "cloud.ply"
    PlyData([PlyElement.describe(v, "vertex")]).write(str(path))
    src = elements_of(PointCloud(pts, normals=normals, colors=rgb / 255.0), "points")

    def one_runs(graph, element_of_row, labels, colours=None):
        per = np.full(graph.n_elements, -1)
        per[element_of_row] = labels
        sg = superfacet_graph(graph, per, colours)
        return learning_arrays(sg, graph.positions, per, labels, (0.0, 0.0, 1.0))

    runs = [(segment_tiled(str(path), 100, tiles=t, workers=1, graph=True, beta=0),
             lambda r: one_runs(src.graph, src.index, r.labels,
                                per_element(src, src.colors()))) for t in (1, 3)]
    runs.append((segment_tiled((mesh.vertices, mesh.faces), 60, tiles=3, workers=1, graph=True),
                 lambda r: one_runs(face_graph(mesh), np.arange(mesh.n_faces), r.labels)))
    for r, want_of in runs:
        want, got = want_of(r), r.learning
        for key in ("x", "edge_index", "edge_attr", "super_index", "node_features"):
            np.testing.assert_array_equal(got[key], want[key], err_msg=key)
        np.testing.assert_allclose(got["pos"], want["pos"], rtol=0, atol=1e-12)
    assert list(runs[0][0].learning["node_features"])[-3:] == ["red", "green", "blue"]
    assert segment_tiled(str(path), 100, tiles=2, workers=1).learning is None


def test_a_tiled_learning_graph_of_estimated_normals_is_one_runs_of_its_labels(tmp_path):
    """Without normals in the file each tile orients the normals it estimates like a sample
    (a component's vote in one run): the superpoints' features are still one run's of the
    same labels to the last bit (a superpoint's normal is its best plane's, turned up), on a
    scene with z up and one with a tilted up; the edges' edge_index, borders and offsets too."""
    from superfacets import PointCloud, segment
    from superfacets.graph.adjacency import superfacet_graph
    from superfacets.graph.learning import learning_arrays

    rng = np.random.default_rng(4)
    pts = rng.random((6000, 3)) * [4.0, 3.0, 0.3]
    pts[:, 2] += 0.2 * np.sin(3 * pts[:, 0])
    for up in ((0.0, 0.0, 1.0), (0.3, -0.2, 1.0)):
        tiled = segment_tiled(PointCloud(pts, up=up), 80, tiles=3, workers=1, graph=True,
                              up_weight=1)
        src = segment(PointCloud(pts, up=up), 80, up_weight=1).elements  # (the scene graph)
        per = np.full(src.graph.n_elements, -1)
        per[src.index] = tiled.labels
        want = learning_arrays(superfacet_graph(src.graph, per, None), src.graph.positions,
                               per, tiled.labels, np.asarray(up) / np.linalg.norm(up))
        got = tiled.learning
        for key in ("x", "edge_index", "super_index"):
            np.testing.assert_array_equal(got[key], want[key], err_msg=f"{key}, up {up}")
        for col in (0, 3, 4, 5):  # border length and offsets (the angles read orientations)
            np.testing.assert_array_equal(got["edge_attr"][:, col], want["edge_attr"][:, col])
        # the planes' angle reads no orientation: one run's, to the float32 of nearly
        # parallel planes (arccos near 1 magnifies the last bits of the summed scatter)
        np.testing.assert_allclose(got["edge_attr"][:, 6], want["edge_attr"][:, 6], atol=1e-5)
