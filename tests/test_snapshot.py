"""Every change keeps the labels: 426 runs compared with the stored snapshot.

The snapshot (``tests/data/label_snapshot.json.gz``, made by ``python
tests/snapshot.py`` before the code was reorganized) holds the SHA-256 of the
labels of each run of :func:`snapshot.runs` (Table-1 meshes and 30 benchmark
meshes; k, alpha, every init, assignment and weighting).
"""

from __future__ import annotations

import pytest
import snapshot
from conftest import SHARED, need

#: The benchmark's runs in this many parts, each a test of its own (a parallel run of the
#: suite shares them among its workers): every part takes every PARTS-th run.
PARTS = 6


def _same_as_stored(stored: dict, computed, digest, what: str = "superfacets",
                    whole: bool = True) -> None:
    """Every run of ``computed`` (key, labels) gives the stored digest; with ``whole``,
    no run is missing or new."""
    seen, wrong = set(), []
    for key, labels in computed:
        seen.add(key)
        assert key in stored, f"{key}: a run the snapshot does not hold"
        want_digest, want_k = stored[key]
        if digest(labels) != want_digest:
            wrong.append(f"{key}: {int(labels.max()) + 1} {what} (snapshot: {want_k})")
    if whole:
        assert seen == set(stored), "the set of runs differs from the snapshot's"
    assert seen, "no run computed"
    assert not wrong, f"{len(wrong)} of {len(seen)} runs changed:\n" + "\n".join(wrong[:20])


def test_the_snapshot_holds_every_run_and_no_other(psb):
    need(SHARED / "data" / "meshes" / "bunny.tri.xz")
    sources = snapshot.mesh_sources(SHARED, psb)
    keys = {snapshot.run_key(name, kw) for name, kw in snapshot.runs(list(sources))}
    assert keys == set(snapshot.load())


@pytest.mark.parametrize("part", range(PARTS))
def test_labels_equal_the_snapshot(psb, part):
    need(SHARED / "data" / "meshes" / "bunny.tri.xz")
    sources = snapshot.mesh_sources(SHARED, psb)
    _same_as_stored(snapshot.load(), snapshot.compute(sources, part=part, parts=PARTS),
                    snapshot.digest, whole=False)


@pytest.mark.parametrize("part", range(2))
def test_every_kind_and_stage_equals_its_snapshot(part):
    """Vertices, points, cells, coarse-to-fine, the paper on each kind, tiled runs and
    the content-adaptive level (``tests/snapshot_kinds.py``), bit for bit (in two
    parts: every other run)."""
    import snapshot_kinds

    need(SHARED / "data" / "meshes" / "bunny.tri.xz")
    stored = snapshot_kinds.load()
    keys = {snapshot_kinds.key(*run) for run in snapshot_kinds.runs()}
    assert keys == set(stored), "the set of runs differs from the snapshot's"
    _same_as_stored(stored, snapshot_kinds.compute(SHARED, part=part, parts=2),
                    snapshot_kinds.digest, "segments", whole=False)
