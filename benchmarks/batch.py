"""The benchmark meshes through ``batch``: engine overhead and speed-up with workers.

Usage: python benchmarks/batch.py [-k 150] [--per-category N] [--rounds 2]

Segments the Princeton benchmark's meshes (all 300, or the first N of each
category) at k = 150 four ways, in this order, each into a fresh folder:

- ``loop``: one process calls read_mesh + segment + write_labels on each
  file (what a user's own script would do; the reference for overhead);
- ``batch, in process``: ``run_batch(workers=1)`` (the manifest, the journal);
- ``batch, Dask, 1 worker`` and ``2 workers``, on a cluster started and warmed
  beforehand (one mesh per worker): the engine's cost per task;
- the same on a new cluster each (as the command line runs): start-up included.

The rounds alternate the six runs (a slower spell of a shared machine hits
them all); the table gives the median. Prints: seconds (wall clock, cluster
start included), meshes per
second, the overhead per task against the loop, the engine's own time per
task (wall clock x workers minus the tasks' seconds in the manifest), and the speed-up over
Dask with 1 worker; then checks that every run wrote the same
labels. Run it on an idle machine: the speed-up needs both cores.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _digest(folder: Path) -> str:
    h = hashlib.sha256()
    for p in sorted(folder.rglob("*.seg")):
        h.update(p.name.encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:16]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-k", type=int, default=150)
    ap.add_argument("--per-category", type=int, default=None, metavar="N")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--rounds", type=int, default=2, help="runs of each, alternating")
    args = ap.parse_args()

    from superfacets import read_mesh, segment, write_labels
    from superfacets.evaluation.datasets.psb import first_per_category, list_meshes, psb_root
    from superfacets.scale.runner.batch import read_manifest, run_batch

    meshes = list_meshes(psb_root())
    if args.per_category:
        meshes = first_per_category(meshes, args.per_category)
    files = [str(m.path) for m in meshes]
    n = len(files)
    tmp = Path(tempfile.mkdtemp(prefix="sf-batch-bench-"))

    from superfacets.scale.runner.engine import Engine

    labels = ["loop (read + segment + write, one process, warm)", "batch, in process (warm)",
              "batch, Dask, 1 worker (warm cluster)",
              f"batch, Dask, {args.workers} workers (warm cluster)",
              "batch, Dask, 1 worker (new cluster)",
              f"batch, Dask, {args.workers} workers (new cluster)"]
    seconds: dict = {lab: [] for lab in labels}
    engine_ms: dict = {lab: [] for lab in labels}
    digests: set = set()
    # warm: numba's kernels loaded in this process before the loop and the in-process batch
    segment(read_mesh(files[0]), args.k, n_threads=1)

    def record(label, sec, out, workers=None):
        seconds[label].append(sec)
        digests.add(_digest(out))
        if workers:
            tasks = sum(r["seconds"] for r in read_manifest(out))
            engine_ms[label].append(1000 * (sec * workers - tasks) / n)
        print(f"{label}: {sec:.1f} s", file=sys.stderr)

    def timed(label, slots, **kw):
        out = tmp / f"run{sum(map(len, seconds.values()))}"
        t0 = time.perf_counter()
        s = run_batch(files, out, args.k, progress=False, **kw)
        sec = time.perf_counter() - t0
        assert s.ok == n, (s.ok, s.failures[:3])
        record(label, sec, out, slots)

    for _ in range(args.rounds):  # the runs alternate: a slower spell hits them all
        out = tmp / f"loop{len(seconds[labels[0]])}"
        out.mkdir()
        t0 = time.perf_counter()
        for f in files:
            r = segment(read_mesh(f), args.k, n_threads=1)
            write_labels(out / (Path(f).stem + ".seg"), r.labels)
        record(labels[0], time.perf_counter() - t0, out)
        timed(labels[1], 1, workers=1)
        for i, w in enumerate((1, args.workers)):  # a cluster started, warmed, then timed
            with Engine(w, dask=True) as engine:
                address = engine.client.scheduler.address
                run_batch(files[:w], tmp / f"warm{w}-{len(seconds[labels[2]])}", args.k,
                          progress=False, scheduler=address)
                timed(labels[2 + i], w, scheduler=address)
        for i, w in enumerate((1, args.workers)):  # as a user runs it: a new cluster
            timed(labels[4 + i], w, workers=w, dask=True)

    med = {lab: float(np.median(v)) for lab, v in seconds.items()}
    base = med[labels[0]]
    print(f"\n{n} benchmark meshes, k = {args.k}, alpha 200 (defaults); wall clock, median "
          f"of {args.rounds} rounds (runs alternating)\n")
    print("| run | seconds (median; min-max) | meshes/s | ms per task vs loop | "
          "engine ms per task | speed-up vs Dask 1 worker |")
    print("|---|---|---|---|---|---|")
    for i, lab in enumerate(labels):
        one = med[labels[4]] if "new cluster" in lab else med[labels[2]]
        v = seconds[lab]
        eng = f"{np.median(engine_ms[lab]):.1f}" if engine_ms[lab] else ""
        print(f"| {lab} | {med[lab]:.1f} ({min(v):.1f}-{max(v):.1f}) | {n / med[lab]:.2f} | "
              f"{1000 * (med[lab] - base) / n:+.1f} | {eng} | "
              + (f"{one / med[lab]:.2f}x |" if i >= 2 else "|"))
    print("\nengine ms per task: (wall clock x workers - the tasks' own seconds in the "
          "manifest) / meshes: the time a worker slot spends outside the tasks")
    print("speed-up: against Dask with 1 worker, warm against warm and new against new; "
          "a new cluster's start-up (workers importing, loading kernels) counts in its "
          "overhead per task")
    print(f"\nsame labels in every run: {'yes' if len(digests) == 1 else 'NO'}")
    return 0 if len(digests) == 1 else 1


if __name__ == "__main__":
    sys.exit(main())
