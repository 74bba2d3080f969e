"""A tile's box, graph and weights held in its worker's memory between phases
(superfacets.scale.tiles.held)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from tiled import _bumpy, _bumpy_cloud

from superfacets.scale.tiles import held
from superfacets.scale.tiles.run import segment_tiled


@pytest.fixture(autouse=True)
def _nothing_held_before_or_after():
    held.release_held()
    yield
    held.release_held()


def _counting(monkeypatch):
    """Count what each tiled run's phases do: the graph outcomes and weights made."""
    import superfacets.method.stages as stages
    import superfacets.scale.tiles.task as rt

    seen, made = [], []
    real_graph, real_weights = rt.tile_graph, stages.csr_point_weights
    monkeypatch.setattr(rt, "tile_graph",
                        lambda *a, **kw: seen.append(real_graph(*a, **kw)) or seen[-1])
    monkeypatch.setattr(stages, "csr_point_weights",
                        lambda *a, **kw: made.append(1) or real_weights(*a, **kw))
    return seen, made


def test_tiles_held_between_phases_label_as_tiles_read_from_the_work_folder(
        monkeypatch, tmp_path):
    """With room to hold them, a cloud's tiles are read and weighed once: the refine round
    and the labels phase find each tile's box and graph in memory (none read back from
    the work folder) and the labels phase the refine round's weights (4 tiles: 4 weighings
    fewer); with none (``SUPERFACETS_TILE_HOLD_MIB=0``) every phase reads them, and the
    labels are the same."""
    cloud = _bumpy_cloud(20000)
    seen, made = _counting(monkeypatch)
    monkeypatch.setenv("SUPERFACETS_TILE_HOLD_MIB", "1024")
    kept = segment_tiled(cloud, 60, tiles=4, workdir=tmp_path)
    assert seen.count("built") == 4 and "read" not in seen and seen.count("kept") >= 8
    assert not held._HELD  # let go at the run's end
    weighed = len(made)  # (the refine round's and the start's, on the survey's sample)
    seen.clear()
    made.clear()
    monkeypatch.setenv("SUPERFACETS_TILE_HOLD_MIB", "0")
    read = segment_tiled(cloud, 60, tiles=4, workdir=tmp_path)
    assert seen.count("read") >= 8 and len(made) == weighed + 4  # the labels phase's too
    np.testing.assert_array_equal(kept.labels, read.labels)


def test_a_held_mesh_tile_counts_its_weights_and_its_refine_rounds_records(monkeypatch):
    """What a held tile takes counts every array it keeps: its graph's weights and, after a
    mesh's refine round, that round's classifier's recorded expansions (the labels phase
    replays them), let go with it after the labels phase."""
    import superfacets.scale.tiles.task as rt

    counted = []
    real = rt.hold_box

    def spy(key, value, arrays, write=None):
        graph = value[2].__dict__["_face_graph"]
        kept = graph.__dict__.get("last_classifier")
        ids = {id(a) for a in arrays}
        w = next(iter(graph.__dict__["weights_kept"].values()))[0]
        counted.append((kept is not None, id(w) in ids,
                        kept is None or id(kept.face) in ids and id(kept.dist) in ids))
        return real(key, value, arrays, write)

    monkeypatch.setattr(rt, "hold_box", spy)
    segment_tiled(_bumpy(4), 40, tiles=2)
    assert sorted(counted) == [(False, True, True)] * 2 + [(True, True, True)] * 2


def test_a_held_tiles_files_are_written_only_when_it_is_let_go(monkeypatch, tmp_path):
    """What a cloud tile's later phases read from the work folder (its box's records, its
    point graph, its refine round's last classification) is not written while the tile
    stays held; with room for about one tile (each takes about 3 MiB), a tile let go while
    the run goes on writes them first and its later phases read them back; with none held
    each phase writes them at once. The same labels each way."""
    import superfacets.scale.tiles.buckets as rb
    import superfacets.scale.tiles.task as rt

    cloud = _bumpy_cloud(20000)
    wrote = []
    for module, name in ((rt, "save_graph"), (rt, "keep_classification"), (rb, "keep_box")):
        real = getattr(module, name)
        monkeypatch.setattr(module, name,
                            lambda *a, _r=real, _n=name: wrote.append(_n) or _r(*a))
    seen, _ = _counting(monkeypatch)
    runs = {}
    for budget in ("1024", "4", "0"):
        wrote.clear()
        seen.clear()
        monkeypatch.setenv("SUPERFACETS_TILE_HOLD_MIB", budget)
        runs[budget] = (segment_tiled(cloud, 60, tiles=4, workdir=tmp_path).labels,
                        list(wrote), seen.count("read"))
    assert runs["1024"][1:] == ([], 0)  # nothing written, nothing read back
    # (each graph written once at most: as its tile is let go, never when read back)
    assert 0 < runs["4"][1].count("save_graph") <= 4 and runs["4"][2] > 0
    assert 0 < runs["4"][1].count("keep_box") <= 4
    assert sorted(runs["0"][1]) == (["keep_box"] * 4 + ["keep_classification"] * 4
                                    + ["save_graph"] * 4)
    for budget in ("4", "0"):
        np.testing.assert_array_equal(runs[budget][0], runs["1024"][0])


def test_a_let_go_tile_whose_files_cannot_be_written_is_built_again(monkeypatch, tmp_path):
    """A full disk as a let-go tile writes its graph and classification: its later phases
    find neither held nor written, build its graph again and classify afresh: the same
    labels, no error."""
    import superfacets.scale.tiles.task as rt

    cloud = _bumpy_cloud(20000)
    monkeypatch.setenv("SUPERFACETS_TILE_HOLD_MIB", "1024")
    ref = segment_tiled(cloud, 60, tiles=4, workdir=tmp_path).labels

    def full(*a):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(rt, "save_graph", full)
    monkeypatch.setattr(rt, "keep_classification", full)
    seen, _ = _counting(monkeypatch)
    monkeypatch.setenv("SUPERFACETS_TILE_HOLD_MIB", "4")  # (about one tile: most let go)
    again = segment_tiled(cloud, 60, tiles=4, workdir=tmp_path)
    assert "read" not in seen and seen.count("built") > 4  # (built again, never read)
    np.testing.assert_array_equal(again.labels, ref)


def test_held_tiles_stay_within_the_budget_and_go_with_their_run(monkeypatch, tmp_path):
    """The oldest held tile goes where a new one needs its room; one larger than the
    budget is not held; a run's tiles go when it lets them go, or when its graph folder
    is gone; the budget is a quarter of what the process may still use."""
    monkeypatch.setenv("SUPERFACETS_TILE_HOLD_MIB", "1")
    a, b = tmp_path / "run-a", tmp_path / "run-b"
    for tile in (a / "tile-0", a / "tile-1", b / "tile-0"):
        tile.mkdir(parents=True)
    part = [np.zeros(70_000)]  # 560,000 bytes: one fits in 1 MiB, two do not
    assert held.hold_box((str(a / "tile-0"), 0), "a0", part)
    assert held.hold_box((str(b / "tile-0"), 0), "b0", part)
    assert held.held_box((str(a / "tile-0"), 0)) is None  # the oldest went
    assert held.held_box((str(b / "tile-0"), 0)) == "b0"
    assert not held.hold_box((str(a / "tile-1"), 1), "big", [np.zeros(200_000)])
    assert held.held_box((str(b / "tile-0"), 0)) == "b0"  # (kept: the big one never came)
    held.release_held(a)
    assert held.held_box((str(b / "tile-0"), 0)) == "b0"
    held.release_held(b)
    assert held.held_box((str(b / "tile-0"), 0)) is None
    assert held.hold_box((str(b / "tile-0"), 0), "b0", part)
    shutil.rmtree(b)  # (the run ended: its work folder removed)
    assert held.held_box((str(b / "tile-0"), 0)) is None and not held._HELD
    # what a tile owes its later phases is written when it is let go while its run goes
    # on (room for another, a tile that never comes in, a memory retry), not at its end
    wrote = []
    assert held.hold_box((str(a / "tile-0"), 0), "a0", part, write=lambda: wrote.append(0))
    assert held.hold_box((str(a / "tile-1"), 1), "a1", part, write=lambda: wrote.append(1))
    assert not held.hold_box((str(a / "tile-1"), 2), "a2", [np.zeros(200_000)],
                             write=lambda: wrote.append(2))
    held.release_held()
    assert wrote == [0, 2, 1]
    assert held.hold_box((str(a / "tile-0"), 0), "a0", part, write=lambda: wrote.append(3))
    held.release_held(a)
    assert wrote == [0, 2, 1] and not held._HELD
    monkeypatch.delenv("SUPERFACETS_TILE_HOLD_MIB")
    from superfacets._runtime.memory import available_bytes

    avail = available_bytes()
    assert avail is None or abs(held.hold_budget() - held.HOLD_SHARE * avail) < 2**26


def test_a_held_graph_is_weighed_once_per_set_of_weights():
    """A graph that carries ``weights_kept`` (a held tile's) gets the same, read-only
    arrays each time it is weighed alike, equal to weights made afresh; other parameters
    make and keep their own."""
    from dataclasses import replace

    from superfacets.method.pipeline import passes_example
    from superfacets.method.stages import weigh

    s = passes_example()
    fresh, _ = weigh(s.graph, s.rules)
    s.graph.__dict__["weights_kept"] = {}  # (what a held tile's graph carries)
    w, swap = weigh(s.graph, s.rules)
    again, swap_again = weigh(s.graph, s.rules)
    assert again is w and swap_again is swap and not w.flags.writeable
    np.testing.assert_array_equal(w, fresh)
    other = replace(s.rules, params=replace(s.rules.params, alpha=2 * s.rules.params.alpha))
    w2, _ = weigh(s.graph, other)
    assert w2 is not w and len(s.graph.__dict__["weights_kept"]) == 2 and not np.array_equal(w2, w)


def test_a_task_preferring_a_worker_runs_there():
    """``Engine.run(..., prefer=)`` sends each task to the worker it names (a tiled run:
    the one holding the tile from the phase before)."""
    pytest.importorskip("distributed")
    from superfacets.scale.runner.engine import Engine

    with Engine(workers=2) as engine:
        workers = sorted(engine.client.scheduler_info()["workers"])
        for want in workers:
            got = list(engine.run(lambda t: held.worker_address(), range(6),
                                  on_lost=lambda t, e: e, prefer=lambda t, w=want: w))
            assert got == [want] * 6


def test_a_tile_that_does_not_fit_beside_the_held_ones_runs_again_without_them(
        monkeypatch, tmp_path):
    """A tile whose memory check fails while other tiles are held lets them go and runs
    again (the same labels); one that fails with nothing held fails as before."""
    import superfacets.scale.tiles.task as rt
    from superfacets.errors import MemoryLimitError, SuperfacetsError

    cloud = _bumpy_cloud(20000)
    monkeypatch.setenv("SUPERFACETS_TILE_HOLD_MIB", "1024")
    ref = segment_tiled(cloud, 60, tiles=4, workdir=tmp_path)
    real, refused = rt._phase, []

    def tight(task, out):
        if held._HELD and task["phase"] == "labels":
            refused.append(task["tile"])
            raise MemoryLimitError("too much beside the held tiles", 2, 1)
        return real(task, out)

    monkeypatch.setattr(rt, "_phase", tight)
    again = segment_tiled(cloud, 60, tiles=4, workdir=tmp_path)
    assert refused  # (each refused tile ran again with nothing held)
    np.testing.assert_array_equal(again.labels, ref.labels)

    def never(task, out):
        if task["phase"] == "labels":
            raise MemoryLimitError("the tile alone does not fit", 2, 1)
        return real(task, out)

    monkeypatch.setattr(rt, "_phase", never)
    monkeypatch.setenv("SUPERFACETS_TILE_HOLD_MIB", "0")
    with pytest.raises(SuperfacetsError, match="the tile alone does not fit"):
        segment_tiled(cloud, 60, tiles=4, workdir=tmp_path)


def test_a_meshs_tiles_are_held_between_phases_too(monkeypatch, tmp_path):
    """A mesh's tiles keep their boxes and face graphs in memory between the centers
    phase, the refine round and the labels phase (no box or topology written or read
    back), and weigh once per set of weights; with none held each tile writes its box
    and topology once; the same labels."""
    import trimesh

    import superfacets.scale.tiles.task as rt
    from superfacets.scale.tiles.buckets import TileBuckets

    m = trimesh.creation.icosphere(subdivisions=5)
    seen, real = [], rt.tile_face_graph
    def counted(*a, **kw):  # (a topology made and not yet saved: "built")
        out = real(*a, **kw)
        seen.append(out if isinstance(out, str) else "built")
        return out

    monkeypatch.setattr(rt, "tile_face_graph", counted)
    reads, records = [], TileBuckets._records
    monkeypatch.setattr(TileBuckets, "_records",
                        lambda self, lo, hi: reads.append(1) or records(self, lo, hi))
    import superfacets.method.stages as stages

    made, weights = [], stages.edge_weights
    monkeypatch.setattr(stages, "edge_weights",
                        lambda *a, **kw: made.append(1) or weights(*a, **kw))
    wrote = []
    for name in ("keep_box", "save_face_topology"):
        real_write = getattr(rt, name)
        monkeypatch.setattr(rt, name, lambda *a, _r=real_write, _n=name:
                            wrote.append(_n) or _r(*a))
    monkeypatch.setenv("SUPERFACETS_TILE_HOLD_MIB", "1024")
    kept = segment_tiled((m.vertices, m.faces), 60, tiles=4, workdir=tmp_path,
                         start="tiles")  # (the tiles' own start: three phases)
    assert seen.count("built") == 4 and "read" not in seen and seen.count("kept") >= 8
    assert len(reads) == 4  # (the centers phase's; the later phases' boxes held)
    assert wrote == []  # (nothing written for later phases that find the tiles held)
    assert not held._HELD  # let go at the run's end (a mesh's held tiles too)
    weighed = len(made)
    seen.clear()
    made.clear()
    monkeypatch.setenv("SUPERFACETS_TILE_HOLD_MIB", "0")
    read = segment_tiled((m.vertices, m.faces), 60, tiles=4, workdir=tmp_path,
                         start="tiles")
    assert seen.count("read") >= 8 and len(made) == weighed + 8  # refine's, labels'
    assert sorted(wrote) == ["keep_box"] * 4 + ["save_face_topology"] * 4
    np.testing.assert_array_equal(kept.labels, read.labels)


@pytest.mark.parametrize("value", ["abc", "-1", "2.5", "1e3", "9999999999"])
def test_a_hold_budget_that_is_not_a_number_of_mib_is_refused_before_the_run(
        monkeypatch, tmp_path, value):
    """``SUPERFACETS_TILE_HOLD_MIB`` set to anything but a whole number of MiB is a
    ParameterError naming it, before any work (not a budget of 0 in silence)."""
    from superfacets.errors import ParameterError

    monkeypatch.setenv("SUPERFACETS_TILE_HOLD_MIB", value)
    with pytest.raises(ParameterError, match="SUPERFACETS_TILE_HOLD_MIB"):
        segment_tiled(_bumpy_cloud(2000), 20, tiles=2, workdir=tmp_path)
    assert not list(tmp_path.iterdir())  # (nothing written)
