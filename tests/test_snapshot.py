"""Every change keeps the labels: 426 runs compared with the stored snapshot.

The snapshot (``tests/data/label_snapshot.json.gz``, made by ``python
tests/snapshot.py`` before the code was reorganized) holds the SHA-256 of the
labels of each run of :func:`snapshot.runs` (Table-1 meshes and 30 benchmark
meshes; k, alpha, every init, assignment and weighting).
"""

from __future__ import annotations

import snapshot
from conftest import SHARED, need


def _same_as_stored(stored: dict, computed, digest, what: str = "superfacets") -> None:
    """Every run of ``computed`` (key, labels) gives the stored digest, and no run is
    missing or new."""
    seen, wrong = set(), []
    for key, labels in computed:
        seen.add(key)
        want_digest, want_k = stored[key]
        if digest(labels) != want_digest:
            wrong.append(f"{key}: {int(labels.max()) + 1} {what} (snapshot: {want_k})")
    assert seen == set(stored), "the set of runs differs from the snapshot's"
    assert not wrong, f"{len(wrong)} of {len(stored)} runs changed:\n" + "\n".join(wrong[:20])


def test_labels_equal_the_snapshot(psb):
    need(SHARED / "data" / "meshes" / "bunny.tri.xz")
    _same_as_stored(snapshot.load(), snapshot.compute(snapshot.mesh_sources(SHARED, psb)),
                    snapshot.digest)


def test_every_kind_and_stage_equals_its_snapshot():
    """Vertices, points, cells, coarse-to-fine, the paper on each kind, tiled runs and
    the content-adaptive level (``tests/snapshot_kinds.py``), bit for bit."""
    import snapshot_kinds

    need(SHARED / "data" / "meshes" / "bunny.tri.xz")
    _same_as_stored(snapshot_kinds.load(), snapshot_kinds.compute(SHARED),
                    snapshot_kinds.digest, "segments")
