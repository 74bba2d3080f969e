"""The cost of installing superfacets, and of each option's first run against its second.

Usage: python benchmarks/install.py [--skip-install] [--skip-runs] [--mesh MESH]

1. ``pip install .`` of a clean clone of this checkout's HEAD (``git clone``) into a
   fresh virtual environment, a new process: its wall time (the dependencies come from
   pip's cache where they are in it, as on a machine that installed them once), the
   environment's size (``du -s``) and its largest packages; then ``pip wheel`` of the
   same clone and the wheel installed into a second fresh environment (no build).
2. Every option of ``superfacets segment`` (each ``--init``, ``--assignment``,
   ``--weighting``, coarse-to-fine, clean-up, split-and-merge, the hierarchy, tiles, each
   element kind) and the baselines that are not GPL (``superfacets baseline``), each run
   twice in new processes of the environment this script runs in: the first run's wall
   time against the second's. Nothing is compiled at run time, so the two are equal up
   to the machine's noise (the operating system's file cache aside).

Prints one table per part.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data" / "meshes"


def _timed(cmd, **kwargs) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, **kwargs)
    return time.perf_counter() - t0


def _du(path: Path) -> int:
    out = subprocess.run(["du", "-sk", str(path)], capture_output=True, text=True, check=True)
    return int(out.stdout.split()[0]) * 1024


def _largest(env: Path, n: int = 6) -> list[tuple[str, int]]:
    site = next(env.glob("lib/python*/site-packages"))
    sizes = [(p.name, _du(p)) for p in site.iterdir() if p.is_dir()
             and not p.name.endswith((".dist-info", "__pycache__"))]
    return sorted(sizes, key=lambda x: -x[1])[:n]


def install_rows(work: Path) -> list[tuple[str, str]]:
    clone = work / "clone"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
    rows = []
    env = work / "env"
    subprocess.run([sys.executable, "-m", "venv", str(env)], check=True)
    pip = [str(env / "bin" / "python"), "-m", "pip"]
    subprocess.run(pip + ["install", "-q", "--upgrade", "pip"], check=True,
                   stderr=subprocess.DEVNULL)
    base = _du(env)
    t = _timed(pip + ["install", "-q", str(clone)], stderr=subprocess.DEVNULL)
    rows.append(("pip install . (clean clone, fresh venv)", f"{t:.1f} s"))
    rows.append(("core environment (du -s of the venv)", f"{_du(env) / 2**20:.0f} MiB "
                 f"(empty venv with pip: {base / 2**20:.0f} MiB)"))
    for name, size in _largest(env):
        rows.append((f"  {name}", f"{size / 2**20:.1f} MiB"))
    dist = work / "dist"
    t = _timed(pip + ["wheel", "-q", "--no-deps", "-w", str(dist), str(clone)],
               stderr=subprocess.DEVNULL)
    rows.append(("pip wheel (the build alone)", f"{t:.1f} s"))
    wheel = next(dist.glob("superfacets-*.whl"))
    rows.append(("  wheel size", f"{wheel.stat().st_size / 2**20:.2f} MiB"))
    env2 = work / "env2"
    subprocess.run([sys.executable, "-m", "venv", str(env2)], check=True)
    pip2 = [str(env2 / "bin" / "python"), "-m", "pip"]
    subprocess.run(pip2 + ["install", "-q", "--upgrade", "pip"], check=True,
                   stderr=subprocess.DEVNULL)
    t = _timed(pip2 + ["install", "-q", str(wheel)], stderr=subprocess.DEVNULL)
    rows.append(("pip install of the built wheel (fresh venv)", f"{t:.1f} s"))
    return rows


def _cases(mesh: Path, cloud: Path, tet: Path) -> list[tuple[str, list[str]]]:
    seg = ["segment", str(mesh), "-k", "100", "-o", "{out}", "-q"]
    cases = [("faces, defaults", seg)]
    by_radius = ["segment", str(mesh), "--radius", "0.05", "-o", "{out}", "-q"]
    for init in ("farthest", "flood", "grid"):
        cases.append((f"--init {init}" + (" --radius 0.05" if init != "farthest" else ""),
                      (seg if init == "farthest" else by_radius) + ["--init", init]))
    cases += [("--assignment exact", seg + ["--assignment", "exact"]),
              ("--weighting shlafman", seg + ["--weighting", "shlafman", "--alpha", "0.5"]),
              ("--coarsen 16", seg + ["--coarsen", "16"]),
              ("--no-cleanup --no-split-merge", seg + ["--no-cleanup", "--no-split-merge"]),
              ("--paper", seg + ["--paper"]),
              ("--graph --levels 30,10 (hierarchy)",
               seg + ["--graph", "{out}.npz", "--levels", "30,10"]),
              ("--tiles 4", seg + ["--tiles", "4"]),
              ("--elements vertices", seg + ["--elements", "vertices"]),
              ("points (a cloud)", ["segment", str(cloud), "-k", "100", "-o", "{out}", "-q"]),
              ("points --adaptive", ["segment", str(cloud), "-k", "100", "--adaptive",
                                     "-o", "{out}", "-q"]),
              ("tetrahedra", ["segment", str(tet), "-k", "30", "-o", "{out}", "-q"])]
    for method in ("vsa", "shlafman", "graph_segmentation"):
        cases.append((f"baseline {method}",
                      ["baseline", str(mesh), "-m", method, "-k", "30", "-o", "{out}", "-q"]))
    # (on clouds, from the API: the command line's baseline reads meshes)
    cases.append(("cut_pursuit on the cloud (API)", [
        "-c", "import numpy as np; from superfacets.evaluation.baselines.cut_pursuit import "
        f"cut_pursuit; cut_pursuit(np.load({str(cloud)!r}), 100)"]))
    return cases


def first_run_rows(work: Path, mesh: Path | None) -> list[tuple[str, str, str]]:
    import numpy as np

    sf = [sys.executable, "-m", "superfacets"]
    if mesh is None:
        mesh = work / "creature.off"
        subprocess.run(sf + ["demo", "--output-dir", str(work / "demo"), "-q"], check=True)
        shutil.copy(work / "demo" / "creature.off", mesh)
    import trimesh

    m = trimesh.load(mesh, process=False, force="mesh") if mesh.suffix != ".xz" else None
    if m is None:
        from superfacets import read_mesh

        rm = read_mesh(mesh)
        vertices, faces = rm.vertices, rm.faces
    else:
        vertices, faces = m.vertices, m.faces
    cloud = work / "cloud.npy"
    rng = np.random.default_rng(0)
    tri = vertices[faces[rng.integers(0, len(faces), 50_000)]]
    w = rng.dirichlet(np.ones(3), 50_000)[:, :, None]
    np.save(cloud, (tri * w).sum(axis=1))
    from scipy.spatial import Delaunay

    pts = rng.random((3000, 3))
    tet = work / "tets.vtu"
    try:  # (the volumes extra)
        import meshio

        meshio.write(tet, meshio.Mesh(pts, [("tetra", Delaunay(pts).simplices)]))
    except ImportError:
        tet = None
    rows = []
    env = dict(os.environ)
    for name, args in _cases(mesh, cloud, tet):
        times = []
        for rnd in range(2):
            out = str(work / f"out{rnd}.seg")
            cmd = ([sys.executable] if args[0] == "-c" else sf) + [
                a.replace("{out}", out) for a in args]
            times.append(_timed(cmd, env=env))
        rows.append((name, f"{times[0]:.2f} s", f"{times[1]:.2f} s"))
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--skip-install", action="store_true")
    ap.add_argument("--skip-runs", action="store_true")
    ap.add_argument("--mesh", type=Path, default=None,
                    help="the mesh of the runs (default: the bunny of ../shared, else the "
                         "demo's creature)")
    args = ap.parse_args(argv)
    mesh = args.mesh or (SHARED / "bunny.tri.xz" if (SHARED / "bunny.tri.xz").is_file()
                         else None)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        if not args.skip_install:
            rows = install_rows(work)
            print("| install | measured |\n|---|---|")
            for r in rows:
                print(f"| {r[0]} | {r[1]} |")
            print()
        if not args.skip_runs:
            rows = first_run_rows(work, mesh)
            print(f"| option ({mesh.name if mesh else 'creature'}, a new process each) "
                  "| first run | second run |\n|---|---|---|")
            for r in rows:
                print(f"| {r[0]} | {r[1]} | {r[2]} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
