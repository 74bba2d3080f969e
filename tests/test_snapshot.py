"""Every change keeps the labels: 426 runs compared with the stored snapshot.

The snapshot (``tests/data/label_snapshot.json.gz``, made by ``python
tests/snapshot.py`` before the code was reorganized) holds the SHA-256 of the
labels of each run of :func:`snapshot.runs` (Table-1 meshes and 30 benchmark
meshes; k, alpha, every init, assignment and weighting).
"""

from __future__ import annotations

import snapshot
from conftest import SHARED, need


def test_labels_equal_the_snapshot(psb):
    need(SHARED / "data" / "meshes" / "bunny.tri.xz")
    stored = snapshot.load()
    sources = snapshot.mesh_sources(SHARED, psb)
    seen, wrong = set(), []
    for key, labels in snapshot.compute(sources):
        seen.add(key)
        want_digest, want_k = stored[key]
        if snapshot.digest(labels) != want_digest:
            wrong.append(f"{key}: {int(labels.max()) + 1} superfacets (snapshot: {want_k})")
    assert seen == set(stored), "the set of runs differs from the snapshot's"
    assert not wrong, f"{len(wrong)} of {len(stored)} runs changed:\n" + "\n".join(wrong[:20])


def test_every_kind_and_stage_equals_its_snapshot():
    """Vertices, points, cells, coarse-to-fine, the paper on each kind, tiled runs and
    the content-adaptive level (``tests/snapshot_kinds.py``), bit for bit."""
    import snapshot_kinds

    need(SHARED / "data" / "meshes" / "bunny.tri.xz")
    stored = snapshot_kinds.load()
    seen, wrong = set(), []
    for key, labels in snapshot_kinds.compute(SHARED):
        seen.add(key)
        want_digest, want_k = stored[key]
        if snapshot_kinds.digest(labels) != want_digest:
            wrong.append(f"{key}: {int(labels.max()) + 1} segments (snapshot: {want_k})")
    assert seen == set(stored), "the set of runs differs from the snapshot's"
    assert not wrong, f"{len(wrong)} of {len(stored)} runs changed:\n" + "\n".join(wrong)
