"""Shared fixtures: small synthetic meshes with known answers, and real data."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from superfacets import Mesh
from superfacets.evaluation.datasets.psb import default_archive, psb_root

SHARED = default_archive().parent.parent
MESHES = SHARED / "data" / "meshes"
TABLE1 = ["bunny", "horse", "hand_olivier"]


def grid_mesh(nx: int, ny: int, height=None, size=1.0) -> Mesh:
    """A triangulated (nx x ny)-cell grid on [-size, size]^2, z = height(x, y)."""
    xs = np.linspace(-size, size, nx + 1)
    ys = np.linspace(-size, size, ny + 1)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    Z = np.zeros_like(X) if height is None else height(X, Y)
    v = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
    idx = np.arange((nx + 1) * (ny + 1)).reshape(nx + 1, ny + 1)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    f = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return Mesh(v, f)


def street_sweep(seed: int, ground: float):
    """A street sweep in miniature around a roof sensor at the origin (z up): 8,000 road
    points at height ``ground``, 3,000 of a wall and 1,500 of a car; their positions (12,500,
    3), the part of each (0 road, 1 wall, 2 car) and the generator, to draw on from."""
    rng = np.random.default_rng(seed)
    ang, rad = rng.uniform(0, 2 * np.pi, 8000), rng.uniform(3, 30, 8000)
    road = np.c_[rad * np.cos(ang), rad * np.sin(ang), np.full(8000, ground)]
    wall = np.c_[rng.uniform(-20, 20, 3000), np.full(3000, 6.0), rng.uniform(ground, 2, 3000)]
    car = np.c_[rng.uniform(4, 8, 1500), rng.uniform(-3, -1.5, 1500),
                rng.uniform(ground, -0.3, 1500)]
    part = np.r_[np.zeros(8000, int), np.ones(3000, int), np.full(1500, 2)]
    return np.vstack([road, wall, car]), part, rng


def slab_and_beads() -> tuple[Mesh, int, int]:
    """A thin slab (768 faces) and two beads (80 faces each) just above its middle, each
    a separate piece: the paper's farthest points miss the beads up to 10 centers."""
    slab = trimesh.creation.box(extents=(2, 2, 0.01)).subdivide().subdivide().subdivide()
    bead = trimesh.creation.icosphere(subdivisions=1)
    v, f, nv = [slab.vertices], [slab.faces], len(slab.vertices)
    for at in ([0.3, 0.2, 0.1], [-0.4, 0.1, 0.1]):
        v.append(bead.vertices * 0.03 + at)
        f.append(bead.faces + nv)
        nv += len(bead.vertices)
    return Mesh(np.vstack(v), np.vstack(f)), len(slab.faces), len(bead.faces)


def write_benchmark(tmp_path: Path) -> Path:
    """A tiny benchmark folder: ids 1, 2 (Human) and 21 (Cup), two ground truths each."""
    from superfacets import write_labels, write_mesh

    def valley_mesh(n, depth):
        return grid_mesh(n, n, height=lambda x, y: depth * np.abs(x))

    root = tmp_path / "psb"
    (root / "off").mkdir(parents=True)
    for mid, mesh in [(1, valley_mesh(16, 1.0)), (2, valley_mesh(20, 0.5)),
                      (21, grid_mesh(14, 14))]:
        write_mesh(root / "off" / f"{mid}.off", mesh)
        seg = root / "seg" / "Benchmark" / str(mid)
        seg.mkdir(parents=True)
        x = mesh.centroids[:, 0]
        write_labels(seg / f"{mid}_0.seg", (x > 0).astype(np.int64))
        write_labels(seg / f"{mid}_1.seg", np.digitize(x, [-0.5, 0, 0.5]))
    return root


@pytest.fixture
def valley() -> Mesh:
    """A V-shaped valley z = |x| (normals up): a sharp concave crease along x = 0."""
    return grid_mesh(60, 60, height=lambda x, y: np.abs(x))


@pytest.fixture
def sphere() -> Mesh:
    s = trimesh.creation.icosphere(subdivisions=4)
    return Mesh(s.vertices, s.faces)


def need(path: Path) -> Path:
    if not path.exists():
        pytest.skip(f"{path} is missing (the shared data beside the repository)")
    return path


@pytest.fixture(scope="session")
def psb() -> Path:
    """The unpacked Princeton benchmark (unpacked once from ../shared)."""
    try:
        return psb_root()
    except FileNotFoundError:
        pytest.skip(f"{default_archive()} is missing (the shared data beside the repository)")


def minority(labels, side) -> int:
    """Elements in a segment whose side (a bool per element) is that segment's minority:
    0 when every segment lies on one side of a border."""
    k = int(labels.max()) + 1
    a = np.bincount(labels, weights=side, minlength=k)
    b = np.bincount(labels, weights=~side, minlength=k)
    return int(np.minimum(a, b).sum())


def components_solver():
    """A stand-in for ``cp_d0_dist``: the connected pieces of the edges whose weight
    (times the regularisation) is at least 0.05, so that a larger regularisation gives
    fewer pieces; their weighted mean values and reduced graph, as the real one returns."""
    import types

    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    def cp_d0_dist(d, y, first, adj, edge_weights, vert_weights, coor_weights,
                   min_comp_weight, **_):
        n = y.shape[1]
        lo = np.repeat(np.arange(n), np.diff(first.astype(np.int64)))
        hi = adj.astype(np.int64)
        keep = edge_weights >= 0.05
        g = coo_matrix((np.ones(keep.sum()), (lo[keep], hi[keep])), shape=(n, n))
        _, comp = connected_components(g, directed=False)
        k = comp.max() + 1
        size = np.bincount(comp, vert_weights, k)
        values = np.stack([np.bincount(comp, vert_weights * row, k) / size for row in y])
        a, b = comp[lo], comp[hi]
        cut = a != b
        key = np.unique(np.minimum(a, b)[cut] * k + np.maximum(a, b)[cut], return_inverse=True)
        w = np.bincount(key[1], edge_weights[cut])
        ra, rb = key[0] // k, key[0] % k
        rfirst = np.r_[0, np.cumsum(np.bincount(ra, minlength=k))].astype(np.uint32)
        return comp.astype(np.uint32), values, (rfirst, rb.astype(np.uint32), w)

    return types.SimpleNamespace(cp_d0_dist=cp_d0_dist)


def slowed(monkeypatch, owner, name: str, seconds: float = 0.4) -> None:
    """Make ``owner.name`` (a function) take ``seconds`` more, and the progress bars redraw
    every 0.02 s: a stage long enough to be seen redrawn while it runs."""
    import time

    from superfacets._runtime import progress

    monkeypatch.setattr(progress, "TICK", 0.02)
    real = getattr(owner, name)

    def slow(*args, **kwargs):
        time.sleep(seconds)
        return real(*args, **kwargs)

    monkeypatch.setattr(owner, name, slow)


# -- nothing written into the repository ------------------------------------------------
# A test or an example writes into temporary folders only: the untracked files that git
# does not ignore are listed as the session starts and again as it ends (in the process
# that runs the session, not in pytest-xdist's workers); a new one fails the run.
_REPO = Path(__file__).resolve().parent.parent


def _stray_files() -> set[str] | None:
    import shutil
    import subprocess

    if shutil.which("git") is None or not (_REPO / ".git").exists():
        return None
    run = subprocess.run(["git", "status", "--porcelain", "--untracked-files=all"],
                         cwd=_REPO, capture_output=True, text=True)
    if run.returncode != 0:
        return None
    return {line[3:] for line in run.stdout.splitlines() if line.startswith("?? ")}


def pytest_sessionstart(session):
    if not hasattr(session.config, "workerinput"):
        session.config._stray_before = _stray_files()


def pytest_sessionfinish(session, exitstatus):
    before = getattr(session.config, "_stray_before", None)
    if before is None or hasattr(session.config, "workerinput"):
        return
    new = sorted((_stray_files() or set()) - before)
    if new:
        reporter = session.config.pluginmanager.get_plugin("terminalreporter")
        if reporter is not None:
            reporter.write_line(f"the tests left files in the repository: {new[:10]}",
                                red=True)
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
