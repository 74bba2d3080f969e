"""Label snapshot: the labels of a fixed set of runs, to prove a change alters no result.

The set: the three Table-1 meshes and 30 benchmark meshes (the 1st and the
11th of each of the 15 categories, by id); on each, ``k`` in {50, 150, 500} x
``alpha`` in {0, 200} with the defaults, and at ``k = 150``: ``init`` flood
and grid, ``assignment='exact'``, ``weighting='shlafman'`` (alpha 0.5); on
the Table-1 meshes and the first benchmark mesh of five categories, every
combination of init x assignment x weighting at ``k = 150``.

Only the public API is used, so the same script runs on any version of the
package. ``python tests/snapshot.py`` writes ``tests/data/label_snapshot.json.gz``:
per run, the SHA-256 of its labels (as little-endian int64) and its number of
superfacets (the labels themselves would take 8 MB);
``tests/test_snapshot.py`` recomputes every run and compares bit for bit.
"""

from __future__ import annotations

import gzip
import hashlib
import json
import sys
from itertools import product
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SNAPSHOT = HERE / "data" / "label_snapshot.json.gz"
TABLE1 = ("bunny", "horse", "hand_olivier")
INITS = ("farthest", "flood", "grid")
ASSIGNMENTS = ("bounded", "exact")
WEIGHTINGS = (("paper", 200.0), ("shlafman", 0.5))


def mesh_sources(shared: Path, psb: Path) -> dict[str, Path]:
    """name -> mesh file: the Table-1 meshes, then 2 benchmark meshes per category."""
    from superfacets.evaluation.datasets.psb import list_meshes

    out = {name: shared / "data" / "meshes" / f"{name}.tri.xz" for name in TABLE1}
    by_cat: dict[str, list] = {}
    for bm in list_meshes(psb):
        by_cat.setdefault(bm.category, []).append(bm)
    for cat in sorted(by_cat):
        ms = sorted(by_cat[cat], key=lambda b: b.id)
        for bm in (ms[0], ms[10]):
            out[f"psb{bm.id}"] = bm.path
    return out


def runs(names: list[str]) -> list[tuple[str, dict]]:
    """(mesh name, segment() keyword arguments) of every run of the snapshot."""
    full = set(TABLE1)
    psb = [n for n in names if n.startswith("psb")]
    full |= set(psb[0::2][:5])  # first benchmark mesh of five categories
    out = []
    for name in names:
        seen = set()

        def add(kw):
            key = tuple(sorted(kw.items()))
            if key not in seen:
                seen.add(key)
                out.append((name, kw))

        for k, alpha in product((50, 150, 500), (0.0, 200.0)):
            add(dict(n_segments=k, alpha=alpha))
        for init in ("flood", "grid"):
            add(dict(n_segments=150, alpha=200.0, init=init))
        add(dict(n_segments=150, alpha=200.0, assignment="exact"))
        add(dict(n_segments=150, alpha=0.5, weighting="shlafman"))
        if name in full:
            for init, assignment, (weighting, alpha) in product(INITS, ASSIGNMENTS, WEIGHTINGS):
                add(dict(n_segments=150, alpha=alpha, init=init, assignment=assignment,
                         weighting=weighting))
    return out


def run_key(name: str, kw: dict) -> str:
    return name + "|" + ",".join(f"{k}={v}" for k, v in sorted(kw.items()))


def digest(labels: np.ndarray) -> str:
    """SHA-256 of the labels as little-endian int64."""
    return hashlib.sha256(np.ascontiguousarray(labels, dtype="<i8").tobytes()).hexdigest()


def load() -> dict:
    """The stored snapshot: run key -> [digest, number of superfacets]."""
    with gzip.open(SNAPSHOT, "rt") as f:
        return json.load(f)


def compute(sources: dict[str, Path], progress: bool = False, part: int = 0,
            parts: int = 1):
    """Yield (key, labels) for every run (for every ``parts``-th run from ``part``),
    reading each mesh once."""
    from superfacets import read_mesh, segment

    todo = runs(list(sources))[part::parts]
    mesh_name, mesh = None, None
    for i, (name, kw) in enumerate(todo):
        if name != mesh_name:
            mesh_name, mesh = name, read_mesh(sources[name])
        if progress:
            print(f"\r{i + 1}/{len(todo)} {name:<14}", end="", file=sys.stderr, flush=True)
        # the paper's method: its stopping rule (tol = 0), no clean-up, no split-and-merge
        # (the snapshot guards the paper's labels; the default adds both on faces)
        yield run_key(name, kw), segment(mesh, **{"tol": 0.0, "cleanup": False,
                                                   "split_merge": False, **kw}).labels
    if progress:
        print(file=sys.stderr)


def main() -> int:
    from superfacets.evaluation.datasets.psb import default_archive, psb_root

    shared = default_archive().parent.parent
    out = {}
    for key, lab in compute(mesh_sources(shared, psb_root()), progress=True):
        out[key] = [digest(lab), int(lab.max()) + 1]
    SNAPSHOT.parent.mkdir(exist_ok=True)
    with gzip.open(SNAPSHOT, "wt") as f:
        json.dump(out, f, indent=0, sort_keys=True)
    print(f"{len(out)} runs -> {SNAPSHOT} ({SNAPSHOT.stat().st_size / 1e3:.0f} kB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
