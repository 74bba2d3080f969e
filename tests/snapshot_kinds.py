"""Label snapshot of every kind of element and every stage, beside the faces' snapshot.

``tests/snapshot.py`` pins the faces of 33 meshes. This one pins what it does not
reach: vertices, points (even and uneven density, the content-sensitive sizes, the
colour term, the minimum size), tetrahedral cells, coarse-to-fine on each kind, the
split-and-merge and clean-up off and on, the paper's method on each kind, tiled runs
(a mesh and a cloud) and the content-adaptive level. Inputs are made on the spot
(seeded) from ``trimesh.creation`` and the Table-1 bunny.

Only the public API is used, so the same script runs on any version of the package.
``python tests/snapshot_kinds.py SHARED`` writes ``tests/data/label_snapshot_kinds.json.gz``
(per run: the SHA-256 of the labels as little-endian int64, and the number of
segments); ``tests/test_snapshot.py`` recomputes every run and compares bit for bit.
"""

from __future__ import annotations

import gzip
import hashlib
import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SNAPSHOT = HERE / "data" / "label_snapshot_kinds.json.gz"


def _inputs(shared: Path) -> dict:
    import trimesh
    from scipy.spatial import Delaunay

    from superfacets import PointCloud, read_mesh

    bunny = read_mesh(shared / "data" / "meshes" / "bunny.tri.xz")
    capsule = trimesh.creation.capsule(height=2.0, radius=0.6, count=[48, 48])
    rng = np.random.default_rng(7)
    tm = trimesh.Trimesh(bunny.vertices, bunny.corners.reshape(-1, 3), process=False)
    even, _ = trimesh.sample.sample_surface(tm, 60_000, seed=3)
    # an uneven cloud: a dense half and a sparse half (the automatic density's cue)
    far = even[:, 0] > np.median(even[:, 0])
    uneven = np.r_[even[~far], even[far][::6]]
    colors = np.c_[uneven[:, 1] > np.median(uneven[:, 1]), np.zeros((len(uneven), 2))]
    cube = np.r_[rng.random((3000, 3)),
                 np.array(np.meshgrid([0.0, 1.0], [0.0, 1.0], [0.0, 1.0])).reshape(3, -1).T]
    from superfacets.inputs.tetmesh import TetMesh

    return dict(bunny=bunny, capsule=capsule, even=PointCloud(np.asarray(even)),
                uneven=PointCloud(np.asarray(uneven), colors=colors.astype(float)),
                cube=TetMesh(cube, Delaunay(cube).simplices))


def runs() -> list[tuple[str, str, dict]]:
    """(input name, method, options) of every run."""
    out = []
    for k in (20, 150):
        out += [("bunny", "segment", dict(n_segments=k, elements="vertices")),
                ("capsule", "segment", dict(n_segments=k, elements="vertices")),
                ("even", "segment", dict(n_segments=k)),
                ("uneven", "segment", dict(n_segments=k)),
                ("cube", "segment", dict(n_segments=k))]
    out += [
        ("bunny", "segment", dict(n_segments=10)),  # coarse-to-fine on faces
        ("bunny", "segment", dict(n_segments=5, elements="vertices")),  # ... on vertices
        ("even", "segment", dict(n_segments=30)),  # ... on points
        ("bunny", "segment", dict(n_segments=150, radius=None, paper=True,
                                  elements="vertices")),
        ("even", "segment", dict(n_segments=150, paper=True)),
        # the windows on an even cloud (its default before the exact search)
        ("even", "segment", dict(n_segments=20, assignment="bounded")),
        ("even", "segment", dict(n_segments=150, assignment="bounded")),
        ("even", "segment", dict(n_segments=30, assignment="bounded")),
        ("cube", "segment", dict(n_segments=40, paper=True)),
        ("bunny", "segment", dict(n_segments=150, split_merge=False)),
        ("bunny", "segment", dict(n_segments=150, cleanup=False)),
        ("even", "segment", dict(n_segments=150, cleanup=True, split_merge=True)),
        ("cube", "segment", dict(n_segments=40, cleanup=True, split_merge=True)),
        ("uneven", "segment", dict(n_segments=150, density=0.5, roughness=1.0)),
        ("uneven", "segment", dict(n_segments=150, beta=200.0)),
        ("uneven", "segment", dict(n_segments=300, min_elements=3)),
        ("capsule", "segment", dict(radius=0.1)),
        ("cube", "segment", dict(radius=0.2)),
        ("even", "segment", dict(radius=0.05, init="flood")),
        ("bunny", "tiled", dict(n_segments=100, tiles=4)),
        ("even", "tiled", dict(n_segments=100, tiles=4)),
        ("uneven", "adaptive", dict(n_segments=100, start=5)),
    ]
    return out


def key(name: str, method: str, options: dict) -> str:
    return f"{name} {method} " + " ".join(f"{k}={v}" for k, v in sorted(options.items()))


def compute(shared: Path, part: int = 0, parts: int = 1):
    """Yield (key, labels) of every run (of every ``parts``-th run from ``part``)."""
    from superfacets import segment
    from superfacets.api.levels import adaptive_superpoints
    from superfacets.scale.tiles.run import segment_tiled

    inputs = _inputs(shared)
    for name, method, options in runs()[part::parts]:
        obj = inputs[name]
        if method == "segment":
            labels = segment(obj, **options).labels
        elif method == "tiled":
            opts = dict(options)
            labels = segment_tiled(obj, opts.pop("n_segments"), workers=1, **opts).labels
        else:
            opts = dict(options)
            labels = adaptive_superpoints(obj, opts.pop("n_segments"), **opts)
        yield key(name, method, options), np.asarray(labels)


def digest(labels) -> str:
    return hashlib.sha256(np.ascontiguousarray(labels, dtype="<i8").tobytes()).hexdigest()


def load() -> dict:
    with gzip.open(SNAPSHOT, "rt") as f:
        return json.load(f)


def main(shared: str) -> None:
    stored = {}
    for k, labels in compute(Path(shared)):
        stored[k] = [digest(labels), int(labels.max()) + 1]
        print(k, stored[k][1], flush=True)
    SNAPSHOT.parent.mkdir(exist_ok=True)
    with gzip.open(SNAPSHOT, "wt") as f:
        json.dump(stored, f, indent=0, sort_keys=True)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else str(HERE.parents[1] / "shared"))
