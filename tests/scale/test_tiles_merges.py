"""The merges to the count of a tiled run (superfacets.scale.tiles.merges)."""

from __future__ import annotations

import numpy as np
from tiled import _bumpy

from superfacets import segment
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
