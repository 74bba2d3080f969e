"""Each tile's element graph, built once and read back (superfacets.scale.tiles.graphs)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from tiled import _bumpy_cloud

from superfacets.inputs.cloud import PointCloud
from superfacets.scale.tiles.run import segment_tiled


def test_a_tile_graph_read_back_is_the_graph_built(tmp_path):
    """What the later phases of a tile read is what the first built: every array, the
    pairs' type, and the cloud's points given back bit for bit."""
    from superfacets.elements.points import point_graph
    from superfacets.scale.tiles.graphs import tile_graph

    xyz = np.random.default_rng(5).normal(size=(3000, 3))
    xyz[10] = xyz[11]  # a duplicate point: two rows, one element
    assert tile_graph(PointCloud(xyz.copy()), tmp_path / "tile-0", 10) == "built"
    assert not (tmp_path / "tile-0.part").exists()
    built = point_graph(PointCloud(xyz.copy()), 10)
    again = PointCloud(xyz.copy())
    assert tile_graph(again, tmp_path / "tile-0", 10) == "read"
    read = point_graph(again, 10)  # the graph read back, kept with the cloud
    for name in ("positions", "sizes", "normals", "indptr", "indices", "centroid", "lower",
                 "pairs", "lengths", "border_shares"):
        a, b = getattr(read.graph, name), getattr(built.graph, name)
        assert a.dtype == b.dtype and np.array_equal(a, b), name
    assert read.graph.diagonal == built.graph.diagonal
    np.testing.assert_array_equal(read.index, built.index)
    assert np.array_equal(again.points.view(np.uint64), xyz.view(np.uint64))
    # a half-written graph (a task stopped while saving) is not read: built again
    (tmp_path / "tile-1").mkdir()
    np.save(tmp_path / "tile-1" / "positions.npy", xyz)
    assert tile_graph(PointCloud(xyz.copy()), tmp_path / "tile-1", 10) != "read"


@pytest.mark.parametrize("change", ["indices", "indptr", "index", "positions", "meta"])
def test_a_tile_graph_changed_between_phases_is_refused(tmp_path, change):
    """Work files changed between phases went to the compiled kernels unchecked: an
    index of 2**62, an indptr entry past the end or a row of 2**30 crashed the process
    (SIGSEGV), other positions gave another cloud's labels. Each file's SHA-256 is kept
    with the graph and checked before anything reads it: one line."""
    from superfacets.errors import SuperfacetsError
    from superfacets.scale.tiles.graphs import tile_graph

    xyz = np.random.default_rng(5).normal(size=(2000, 3))
    folder = tmp_path / "tile-0"
    assert tile_graph(PointCloud(xyz.copy()), folder, 10) == "built"
    if change == "meta":  # a graph.json without the digests (or of another writer)
        (folder / "graph.json").write_text('{"pair_dtype": "int32"}')
    else:
        a = np.load(folder / f"{change}.npy")
        if change == "positions":
            a = a + 1e-9  # valid, but not the cloud's
        else:
            a.flat[len(a) // 2] = 2**30 if a.dtype.itemsize == 4 else 2**62
        np.save(folder / f"{change}.npy", a)
    with pytest.raises(SuperfacetsError, match="changed since this run wrote it"):
        tile_graph(PointCloud(xyz.copy()), folder, 10)


def test_a_tile_face_graph_read_back_is_the_graph_built_and_a_changed_file_is_refused(
        tmp_path):
    """A mesh tile's later phases read the face graph's topology its first phase saved:
    every array of the graph as built (a duplicate face included), and a file changed
    since (an index past the end would crash the kernels) refused in one line."""
    import trimesh

    from superfacets import Mesh
    from superfacets.elements.faces import face_graph
    from superfacets.errors import SuperfacetsError
    from superfacets.scale.tiles.graphs import tile_face_graph

    ball = trimesh.creation.icosphere(subdivisions=3)
    faces = np.vstack([ball.faces, ball.faces[:1]])  # (a duplicate: kept once, counted)
    folder = tmp_path / "faces-0"
    assert tile_face_graph(Mesh(ball.vertices, faces), folder) == "built"
    again = Mesh(ball.vertices, faces)
    assert tile_face_graph(again, folder) == "read"
    assert tile_face_graph(again, folder) == "kept"
    read, built = face_graph(again), face_graph(Mesh(ball.vertices, faces))
    for name in ("positions", "sizes", "normals", "pairs", "edges", "indptr", "indices",
                 "dual_edge", "lengths", "boundary_elements", "boundary_lengths"):
        a, b = getattr(read, name), getattr(built, name)
        assert a.dtype == b.dtype and np.array_equal(a, b), name
    assert again.__dict__["_repeated_face_pairs"] > 0
    a = np.load(folder / "indices.npy")
    a[3] = 2**30
    np.save(folder / "indices.npy", a)
    with pytest.raises(SuperfacetsError, match="changed since this run wrote it"):
        tile_face_graph(Mesh(ball.vertices, faces), folder)


def test_tiles_that_keep_their_graphs_label_as_those_that_build_them(monkeypatch, tmp_path):
    """A cloud's tiles build their graphs once and read them in the later phases: the
    same labels as building them every phase, and the work folder left without them."""
    import superfacets.scale.tiles.task as rt

    cloud = _bumpy_cloud(20000)
    seen, real = [], rt.tile_graph
    monkeypatch.setattr(rt, "tile_graph",
                        lambda *a, **kw: seen.append(real(*a, **kw)) or seen[-1])
    monkeypatch.setenv("SUPERFACETS_TILE_HOLD_MIB", "0")  # (read back, not held: test_tiles_held)
    kept = segment_tiled(cloud, 60, tiles=4, halo=1, workdir=tmp_path)
    assert seen.count("built") == 4 and seen.count("read") >= 8  # refine, labels (connect)
    assert not (tmp_path / "graphs").exists()
    import superfacets.scale.tiles.run as run

    monkeypatch.setattr(run, "graph_folder", lambda *a: None)
    seen.clear()
    built = segment_tiled(cloud, 60, tiles=4, halo=1)
    assert seen == [] and kept.disagreements > 0  # (the connect phase ran too)
    np.testing.assert_array_equal(kept.labels, built.labels)


def test_tiles_read_the_whole_clouds_area_on_the_graphs_they_keep(monkeypatch, tmp_path):
    """The areas of a cloud's tiles are read on the graphs they build once (boxes sized by
    the survey's sample): the radius is one run's; a sample that asks for too narrow a
    halo has the graphs dropped and built again on the halo the radius asks for."""
    import superfacets.scale.tiles.task as rt
    from superfacets.elements.points import point_graph

    cloud = _bumpy_cloud(20000)
    area = float(point_graph(cloud, 10).graph.sizes.sum())
    seen, real = [], rt.tile_graph
    monkeypatch.setattr(rt, "tile_graph",
                        lambda *a, **kw: seen.append(real(*a, **kw)) or seen[-1])
    res = segment_tiled(cloud, 60, tiles=4, workdir=tmp_path)
    fine = 60 * res.params["merge_from"]  # (an even cloud: superpoints merged to the count)
    assert res.mesh_radius == pytest.approx(math.sqrt(area / (fine * math.pi)), rel=1e-9)
    assert seen.count("built") == 4 and res.halo >= 3 * 2 * res.mesh_radius
    import superfacets.scale.tiles.run as run

    monkeypatch.setattr(run, "GRAPH_SLACK", 0.5)  # the sample's halo too narrow
    seen.clear()
    narrow = segment_tiled(cloud, 60, tiles=4, workdir=tmp_path)
    assert seen.count("built") == 8 and narrow.halo == pytest.approx(6 * narrow.mesh_radius)
    assert narrow.mesh_radius == pytest.approx(res.mesh_radius, rel=1e-12)
    monkeypatch.setattr(run, "graph_folder", lambda *a: None)
    np.testing.assert_array_equal(segment_tiled(cloud, 60, tiles=4).labels, narrow.labels)


def test_a_meshs_tiles_read_their_boxes_once_from_the_tiles_files(monkeypatch, tmp_path):
    """A tiled mesh's later phases read each tile's box from the file its first phase kept
    (not from the tiles' files again: the faces' records were gathered and sorted three
    times), and its face graph's topology from the files it saved beside (not made
    again), with the same labels as a run that keeps none."""
    import trimesh

    import superfacets.elements.faces as faces
    import superfacets.scale.tiles.run as run
    from superfacets.scale.tiles.buckets import TileBuckets

    m = trimesh.creation.icosphere(subdivisions=5)
    reads, real = [], TileBuckets._records
    monkeypatch.setattr(TileBuckets, "_records",
                        lambda self, lo, hi: reads.append(1) or real(self, lo, hi))
    built, build = [], faces.build_face_graph  # (the face graph's topology, made)
    monkeypatch.setattr(faces, "build_face_graph", lambda *a: built.append(1) or build(*a))
    kept = segment_tiled((m.vertices, m.faces), 60, tiles=4, workdir=tmp_path)
    assert len(reads) == 4  # one per tile: its refine round (the start ran on the survey's
    assert len(built) == 4  # sample); the labels phase reads the kept, its topology too
    reads.clear()
    built.clear()
    monkeypatch.setattr(run, "box_folder", lambda *a: None)
    again = segment_tiled((m.vertices, m.faces), 60, tiles=4, workdir=tmp_path)
    assert len(reads) == 8 and len(built) == 8  # (two phases of four tiles)
    np.testing.assert_array_equal(kept.labels, again.labels)


def test_a_clouds_labels_phase_starts_from_its_refine_rounds_last_classification(
        monkeypatch, tmp_path):
    """The refine round lists its centers by row, as the labels phase lists the run's, and
    keeps its last classification beside the tile's graph: the labels phase searches
    again only the cells of the centers that differ (every tile's search incremental),
    with the same labels as tiles that classify from nothing."""
    import superfacets.method.classify as classify_module
    import superfacets.scale.tiles.phases as phases

    cloud = _bumpy_cloud(20000)
    kernel, outcomes = classify_module.reclassify_exact, []
    labels_phase, real_labels = [], phases.tile_labels

    def counted(*a):
        out = kernel(*a)
        if labels_phase:
            outcomes.append(out)
        return out

    def labelling(*a, **kw):
        labels_phase.append(1)
        try:
            return real_labels(*a, **kw)
        finally:
            labels_phase.pop()

    monkeypatch.setattr(classify_module, "reclassify_exact", counted)
    monkeypatch.setattr(phases, "tile_labels", labelling)
    import superfacets.scale.tiles.task as rt

    monkeypatch.setattr(rt, "tile_labels", labelling)
    resumed = segment_tiled(cloud, 60, tiles=4, workdir=tmp_path)
    assert len(outcomes) == 4 and min(outcomes) >= 0  # each tile: only the cells that differ
    monkeypatch.setattr(phases, "kept_classification", lambda *a: None)
    outcomes.clear()
    fresh = segment_tiled(cloud, 60, tiles=4, workdir=tmp_path)
    assert outcomes == []
    np.testing.assert_array_equal(resumed.labels, fresh.labels)


def test_a_kept_classification_changed_since_written_is_refused(tmp_path):
    """The labels phase's search trusts the kept labels and distances: a file changed
    since the refine round wrote it is refused in one line; one of another graph is not
    read."""
    from superfacets.errors import SuperfacetsError
    from superfacets.scale.tiles.graphs import keep_classification, kept_classification

    label = np.arange(10, dtype=np.int32) % 3
    keep_classification(tmp_path, label, np.array([0, 4, 8]), np.linspace(0, 1, 10))
    assert kept_classification(tmp_path, 11) is None
    got = kept_classification(tmp_path, 10)
    assert got[0].dtype == np.int32 and np.array_equal(got[0], label)
    changed = np.load(tmp_path / "classification-label.npy")
    changed[5] = 2**30
    np.save(tmp_path / "classification-label.npy", changed)
    with pytest.raises(SuperfacetsError, match="changed since this run wrote it"):
        kept_classification(tmp_path, 10)
