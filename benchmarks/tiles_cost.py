"""What a tiled run costs against one run, and what threads buy: wall and CPU seconds, a
new process each.

Usage: ``python benchmarks/tiles_cost.py [--points 10000000] [-k 2000] [--tiles 2 4 16]
[--workers 2] [--threads 1 2 4 8 16] [--mesh PATH] [--before DIR] [--repeat 2]``
(``--tiles`` with no count: the one runs alone)

Points are sampled on PSB mesh 281 (the benchmark's, from ``../shared``; ``--seed``) and
written to a binary PLY once (``--mesh PATH``: that mesh file instead, its faces
segmented). Each run is a new process: one run (``superfacets.segment`` on the file read
whole) at each ``--threads`` count this machine has cores for (the default: its run
threads), and ``segment_tiled`` with each ``--tiles`` count on ``--workers`` local Dask
workers (its border disagreements: elements two tiles labelled differently). Its CPU
seconds are the process's and its waited-for children's (the Dask workers: user + system
time), so a tiled run's is the total over its workers. ``--before DIR`` runs the same,
alternating, against a built copy of another version (``benchmarks/_versions.py``).
Prints a table: the median of ``--repeat`` runs, each run's CPU seconds over the first one
run's and, where one run was measured on as many threads as there are workers (``--threads
1 2`` with 2 workers), over that run's (two busy processes, like two busy threads, slow
each other down on a machine's shared memory: the same CPU seconds buy less), the first
one run's wall time over its own (the speed-up of threads) and, for the tiles, the
elements their boxes hold over their cores' (``TiledResult.halo_ratio``: every phase
runs over the boxes). A second table gives the one runs' seconds by stage (the result's
``timings``: the point graph, the weights, the start, the passes, connectivity and merges),
the wall time a thread count shortens and the part it leaves (a stage that does not shrink
with threads is a serial one).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _versions import run_code  # noqa: E402

#: The one runs' stages timed (reading the file, then ``SegmentationResult.timings``' keys)
STAGES = ("read", "graph", "weights", "init", "iterations", "connectivity", "merges")

CODE = """
import json, resource, sys, time
STAGES = %r
def cpu():
    a = resource.getrusage(resource.RUSAGE_SELF)
    b = resource.getrusage(resource.RUSAGE_CHILDREN)
    return a.ru_utime + a.ru_stime + b.ru_utime + b.ru_stime
def main():
    path, k, tiles, workers = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
    threads = int(sys.argv[5]) or None
    t, c = time.perf_counter(), cpu()
    apart, ratio, stages = -1, 1.0, {}
    if tiles == 0:
        from superfacets import segment
        from superfacets.io import read_input
        data = read_input(path)
        stages["read"] = time.perf_counter() - t
        r = segment(data, k, n_threads=threads)
        n = r.n_segments
        stages.update((s, float(r.timings.get(s, 0.0))) for s in STAGES[1:])
    else:
        from superfacets.scale.tiles.run import segment_tiled
        r = segment_tiled(path, k, tiles=tiles, workers=workers)
        n, apart = r.n_segments, r.disagreements / max(r.labels.shape[0], 1)
        # (TiledResult.halo_ratio, summed here: a --before version may not have it)
        ratio = sum(s["rows"] for s in r.tiles) / max(sum(s["core"] for s in r.tiles), 1)
    print(json.dumps(dict(wall=time.perf_counter() - t, cpu=cpu() - c, n=int(n),
                          apart=apart, ratio=ratio, stages=stages)))
if __name__ == "__main__":
    main()
""" % (STAGES,)


def _cloud(n: int, seed: int, folder: Path) -> Path:
    import numpy as np
    import trimesh
    from plyfile import PlyData, PlyElement

    from superfacets.evaluation.datasets.psb import list_meshes
    from superfacets.io import read_mesh

    m = read_mesh(next(b for b in list_meshes() if b.id == 281).path)
    pts, _ = trimesh.sample.sample_surface(
        trimesh.Trimesh(np.asarray(m.vertices), np.asarray(m.faces), process=False), n,
        seed=seed)
    v = np.empty(n, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    v["x"], v["y"], v["z"] = pts.T
    path = folder / f"psb281_{n}.ply"
    PlyData([PlyElement.describe(v, "vertex")]).write(str(path))
    return path


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--points", type=int, default=10_000_000)
    p.add_argument("-k", type=int, default=2000)
    p.add_argument("--tiles", type=int, nargs="*", default=[2, 4, 16])
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--repeat", type=int, default=1)
    p.add_argument("--threads", type=int, nargs="+", default=[0],
                   help="threads of the one run (0: its default); counts above this "
                        "machine's cores are left out")
    p.add_argument("--mesh", default=None, help="a mesh file instead of the sampled cloud")
    p.add_argument("--before", default=None, help="a built copy of another version")
    a = p.parse_args()
    versions = ["installed"] + ([a.before] if a.before else [])
    cores = os.cpu_count() or 1
    threads = [t for t in a.threads if t <= cores] or [0]
    # (threads, tiles): the one runs first (tiles 0), each thread count; the tiled runs with
    # their default threads
    plan = [(t, 0) for t in threads] + [(0, tiles) for tiles in a.tiles]
    runs: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(a.mesh) if a.mesh else _cloud(a.points, a.seed, Path(tmp))
        for _ in range(a.repeat):
            for t, tiles in plan:
                for v in versions:  # alternating
                    out = run_code(v, CODE, str(path), str(a.k), str(tiles), str(a.workers),
                                   str(t))
                    if out.returncode:
                        raise SystemExit(out.stderr[-2000:])
                    got = json.loads(out.stdout.strip().splitlines()[-1])
                    runs.setdefault((v, t, tiles), []).append(got)
                    print(f"({v}, {t} threads, {tiles} tiles: {got['wall']:.1f} s, "
                          f"{got['cpu']:.1f} CPU s)", file=sys.stderr, flush=True)
    what = (Path(a.mesh).name if a.mesh
            else f"{a.points:,} points on PSB 281 (seed {a.seed})")
    print(f"{what}, k = {a.k}, {a.workers} workers, {cores} cores; median of {a.repeat}, "
          "a new process each")
    print("| version | run | wall s | CPU s | CPU / one run's | CPU / one run's on as many "
          "threads as workers | speed-up | disagreements | boxes / cores | segments |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for v in versions:
        base = (v, threads[0], 0)
        one = statistics.median(r["cpu"] for r in runs[base])
        first = statistics.median(r["wall"] for r in runs[base])
        # the tiles' workers share the machine as one run's threads do (memory bandwidth)
        alike = runs.get((v, a.workers, 0))
        alike = statistics.median(r["cpu"] for r in alike) if alike else None
        for t, tiles in plan:
            rs = runs[(v, t, tiles)]
            wall, cpu = (statistics.median(r[f] for r in rs) for f in ("wall", "cpu"))
            name = (f"{tiles} tiles" if tiles else
                    f"one run, {t} thread{'s' * (t != 1)}" if t else "one run")
            apart = f"{100 * rs[0]['apart']:.3f} %" if tiles else ""
            ratio = f"{rs[0]['ratio']:.2f}" if tiles else ""
            same = f"{cpu / alike:.2f}" if tiles and alike else ""
            print(f"| {'this' if v == 'installed' else Path(v).name} | {name} | {wall:.1f} | "
                  f"{cpu:.1f} | {cpu / one:.2f} | {same} | {first / wall:.2f} | {apart} | "
                  f"{ratio} | {rs[0]['n']} |")
    _stages(runs, versions, threads)


def _stages(runs: dict, versions: list, threads: list) -> None:
    """The one runs' seconds by stage, the medians of the repeats."""
    print("\nOne run's seconds by stage (wall; the medians):")
    heads = ("import, read",) + STAGES[1:]  # (the first is timed from before the import)
    print("| version | threads | " + " | ".join(heads) + " | total |")
    print("|---|---|" + "---|" * (len(STAGES) + 1))
    for v in versions:
        for t in threads:
            rs = [r for r in runs[(v, t, 0)] if r.get("stages")]
            if not rs:  # (a --before version that does not report them)
                continue
            cells = [statistics.median(r["stages"][s] for r in rs) for s in STAGES]
            wall = statistics.median(r["wall"] for r in rs)
            print(f"| {'this' if v == 'installed' else Path(v).name} | {t or 'default'} | "
                  + " | ".join(f"{c:.2f}" for c in cells) + f" | {wall:.2f} |")


if __name__ == "__main__":
    main()
