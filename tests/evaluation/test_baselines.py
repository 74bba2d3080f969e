"""Baselines: normalized cuts and Variational Shape Approximation; the registry's call shape."""

from __future__ import annotations

import tracemalloc
import warnings

import numpy as np
import pytest
import trimesh
from conftest import grid_mesh, write_benchmark

from superfacets import Mesh, ParameterError, as_mesh
from superfacets.elements import face_graph
from superfacets.errors import MemoryLimitError
from superfacets.evaluation.baselines import (
    ncut_embedding,
    normalized_cuts,
    variational_shape_approximation,
    vsa,
)
from superfacets.evaluation.baselines.ncuts import ncut_memory_estimate
from superfacets.evaluation.methods import METHODS, Skipped
from superfacets.method.connectivity import label_components
from superfacets.scale.runner import expand_grid, read_results, run_experiment


def _box(subdivisions=2, extents=(1.0, 1.0, 1.0)) -> Mesh:
    m = trimesh.creation.box(extents=extents)
    for _ in range(subdivisions):
        m = m.subdivide()
    return as_mesh(m)


def _side(mesh) -> np.ndarray:
    n = mesh.normals
    ax = np.argmax(np.abs(n), axis=1)
    return 2 * ax + (n[np.arange(mesh.n_faces), ax] > 0)


def _dumbbell() -> Mesh:
    """Two unit spheres (centres z = -1.1, +1.1) joined by a short neck of radius 0.15."""
    z = np.linspace(-2.1, 2.1, 61)  # 3,776 faces: normalized cuts' all-pairs distances
    r = np.maximum(np.sqrt(np.clip(1.0 - (np.abs(z) - 1.1) ** 2, 0, None)), 0.15)
    r[0] = r[-1] = 0.0
    profile = np.column_stack([r, z])
    return as_mesh(trimesh.creation.revolve(profile, sections=32))


@pytest.fixture
def ball() -> Mesh:
    """1280 faces: small enough for the dense eigen-solver path of normalized cuts."""
    return as_mesh(trimesh.creation.icosphere(subdivisions=3))


def _dense(labels, m):
    assert labels.shape == (m,) and labels.dtype == np.int64
    assert np.array_equal(np.unique(labels), np.arange(labels.max() + 1))


# --- VSA ---------------------------------------------------------------------------------


@pytest.mark.parametrize("metric", ["l21", "l2"])
@pytest.mark.parametrize("subdivisions", [1, 2, 3])
def test_vsa_recovers_the_six_sides_of_a_box(metric, subdivisions):
    box = _box(subdivisions, extents=(1.0, 2.0, 3.0))
    for seed in range(3):
        r = variational_shape_approximation(box, 6, metric=metric, init="incremental", rng=seed)
        assert r.labels.max() + 1 == 6
        side = _side(box)
        # one region per side, exactly
        table = np.zeros((6, 6), int)
        np.add.at(table, (r.labels, side), 1)
        assert (np.count_nonzero(table, axis=1) == 1).all()
        assert (np.count_nonzero(table, axis=0) == 1).all()
        assert r.distortion == pytest.approx(0.0, abs=1e-12)
        assert r.converged
        # proxies are the side planes: normals axis-aligned, points on the faces
        assert np.allclose(np.abs(r.normals).max(axis=1), 1.0)


def test_vsa_l2_fits_the_plane_of_least_variance_exactly():
    # a bent sheet (V shape): the L2 proxy of one region is the least-squares plane of the
    # surface, computed from the exact triangle covariance; compare with dense sampling
    mesh = grid_mesh(12, 12, height=lambda x, y: 0.3 * np.abs(x) + 0.1 * y)
    r = variational_shape_approximation(mesh, 1, metric="l2", init="random", rng=0)
    rng = np.random.default_rng(1)
    pts = []
    for f in mesh.faces:
        a, b = rng.random((2, 400))
        flip = a + b > 1
        a[flip], b[flip] = 1 - a[flip], 1 - b[flip]
        v = mesh.vertices[f]
        pts.append(v[0] + a[:, None] * (v[1] - v[0]) + b[:, None] * (v[2] - v[0]))
    pts = np.vstack(pts)
    w = np.repeat(mesh.areas, 400)
    mu = (w[:, None] * pts).sum(0) / w.sum()
    cov = ((pts - mu).T * w) @ (pts - mu)
    normal = np.linalg.eigh(cov)[1][:, 0]
    assert np.allclose(r.points[0], mu, atol=1e-3)
    assert abs(abs(r.normals[0] @ normal) - 1.0) < 1e-4
    # distortion is the integral of the squared distance to that plane
    d2 = ((pts - r.points[0]) @ r.normals[0]) ** 2
    assert r.distortion == pytest.approx((w * d2).sum() / 400, rel=0.02)


@pytest.mark.parametrize("init", ["random", "incremental"])
@pytest.mark.parametrize("metric", ["l21", "l2"])
def test_vsa_labels_dense_connected_and_deterministic(sphere, init, metric):
    a = vsa(sphere, 24, metric=metric, init=init, rng=7)
    b = vsa(sphere, 24, metric=metric, init=init, rng=7)
    _dense(a, sphere.n_faces)
    assert a.max() + 1 == 24
    assert np.array_equal(a, b)
    # flooding grows each region from its seed: face-connected
    pieces = label_components(face_graph(sphere), a)
    assert pieces.max() + 1 == 24


def test_vsa_incremental_continues_from_the_cache(sphere):
    cache: dict = {}
    for k in (5, 12, 30):
        cont = variational_shape_approximation(sphere, k, init="incremental", rng=3, cache=cache)
        fresh = variational_shape_approximation(sphere, k, init="incremental", rng=3)
        assert np.array_equal(cont.labels, fresh.labels)
        assert cont.distortion == fresh.distortion
    assert cache["vsa_incremental"]["n"] == 30


def test_vsa_every_component_gets_a_region():
    a = _box(1)
    b = trimesh.Trimesh(a.vertices + [3.0, 0, 0], a.faces, process=False)
    two = as_mesh(trimesh.util.concatenate([trimesh.Trimesh(a.vertices, a.faces, process=False),
                                            b]))
    for init in ("random", "incremental"):
        labels = vsa(two, 1, init=init, rng=0)
        assert labels.max() + 1 == 2
        half = two.n_faces // 2
        assert len(set(labels[:half])) == 1 and len(set(labels[half:])) == 1


def test_vsa_rejects_bad_parameters(sphere):
    with pytest.raises(ParameterError, match="metric"):
        vsa(sphere, 5, metric="l1")
    with pytest.raises(ParameterError, match="init"):
        vsa(sphere, 5, init="farthest")
    with pytest.raises(ParameterError, match="max_iter"):
        vsa(sphere, 5, max_iter=0)
    with pytest.raises(ParameterError, match="insert_iter"):
        vsa(sphere, 5, insert_iter=-1)
    with pytest.raises(ParameterError, match="larger than the number of faces"):
        vsa(sphere, sphere.n_faces + 1)


# --- normalized cuts ---------------------------------------------------------------------


def test_ncuts_separates_two_spheres_joined_by_a_neck():
    mesh = _dumbbell()
    z = mesh.centroids[:, 2]
    for alpha in (0.0, 100.0):
        labels = normalized_cuts(mesh, 2, alpha=alpha, rng=0)
        _dense(labels, mesh.n_faces)
        assert labels.max() + 1 == 2
        # the cut runs through the neck: every face of the two bulbs is on its own side
        bulb = np.abs(z) > 0.8
        top = labels[bulb & (z > 0)]
        bottom = labels[bulb & (z < 0)]
        assert len(set(top)) == 1 and len(set(bottom)) == 1 and top[0] != bottom[0]


def test_ncuts_embedding_is_shared_by_every_k_and_deterministic(ball):
    sphere = ball
    emb = ncut_embedding(sphere, 30, alpha=100.0, rng=0)
    assert emb.vectors.shape == (sphere.n_faces, 30)
    assert np.all(np.diff(emb.eigenvalues) <= 1e-12)
    assert emb.eigenvalues[0] == pytest.approx(1.0, abs=1e-8)  # connected: one eigenvalue 1
    assert emb.sigma > 0 and emb.nnz >= sphere.n_faces
    for k in (2, 10, 30):
        a = normalized_cuts(sphere, k, embedding=emb, rng=5)
        b = normalized_cuts(sphere, k, alpha=100.0, rng=5)  # its own embedding, k vectors
        _dense(a, sphere.n_faces)
        assert a.max() + 1 <= k
        assert np.array_equal(a, normalized_cuts(sphere, k, embedding=emb, rng=5))
        _dense(b, sphere.n_faces)
    with pytest.raises(ParameterError, match="eigenvectors"):
        normalized_cuts(sphere, 31, embedding=emb)
    with pytest.raises(ParameterError, match="either"):
        normalized_cuts(sphere, 5, embedding=emb, alpha=3.0)


def test_ncuts_sparse_solver_agrees_with_the_dense_one():
    mesh = as_mesh(trimesh.creation.icosphere(subdivisions=4))  # 5120 faces: ARPACK path
    emb = ncut_embedding(mesh, 12, alpha=0.0, rng=0)
    assert emb.eigenvalues[0] == pytest.approx(1.0, abs=1e-6)
    # the relaxed indicators satisfy (D - W) y = (1 - lambda) D y; check via the row sums:
    # the first generalized eigenvector of a connected graph is constant
    y0 = emb.vectors[:, 0]
    assert np.ptp(y0) < 1e-6 * np.abs(y0).max()


def test_ncuts_memory_guard_refuses_before_allocating():
    mesh = as_mesh(trimesh.creation.icosphere(subdivisions=5))  # 20480 faces: 1.6 GB matrix
    need = ncut_memory_estimate(mesh.n_faces, 300)
    assert need > 4 * mesh.n_faces ** 2
    tracemalloc.start()
    try:
        with pytest.raises(MemoryLimitError, match=r"needs about 1\.\d GiB.*limit 0\.5 GiB") \
                as err:
            ncut_embedding(mesh, 300, memory_limit=2**29)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 50 * 2**20  # nothing near the matrix was allocated
    assert err.value.required == need and err.value.limit == 2**29
    assert isinstance(err.value, MemoryError)


def test_ncuts_rejects_bad_parameters(ball):
    sphere = ball
    with pytest.raises(ParameterError, match="bandwidth"):
        ncut_embedding(sphere, 5, bandwidth=0)
    with pytest.raises(ParameterError, match="cutoff"):
        ncut_embedding(sphere, 5, cutoff=1.0)
    with pytest.raises(ParameterError, match="memory_limit"):
        ncut_embedding(sphere, 5, memory_limit=0)
    with pytest.raises(ParameterError, match="n_segments"):
        normalized_cuts(sphere, 0)


# --- the registry ------------------------------------------------------------------------


@pytest.mark.filterwarnings("ignore:.* segments for n_segments=:RuntimeWarning")  # (tiny)
@pytest.mark.parametrize("name", sorted(METHODS))
def test_every_registered_method_has_one_call_shape(name, monkeypatch):
    sphere = as_mesh(trimesh.creation.icosphere(subdivisions=2))
    method = METHODS[name]
    if name == "cut_pursuit":
        pytest.importorskip("cut_pursuit_py", reason="the baselines extra")
    faces = "faces" in method.elements
    extra = {} if faces else {"elements": "vertices"}  # a method of vertices and points
    obj = sphere
    if name == "vccs":  # points only, through an external module: a stand-in
        import sys

        monkeypatch.setitem(sys.modules, "vccs_supervoxel", _grid_vccs())
        obj, extra = np.asarray(sphere.vertices), {"elements": "points"}
    if name == "spt_partition":  # points only; its GPL solver installed by hand, or a stand-in
        pytest.importorskip("pgeof", reason="the baselines extra")
        pytest.importorskip("sklearn", reason="the baselines extra")
        try:
            import pycut_pursuit.cp_d0_dist  # noqa: F401
        except ImportError:
            from conftest import components_solver

            from superfacets._runtime import extras

            real = extras.require
            monkeypatch.setattr(extras, "require", lambda m, f: components_solver()
                                if m == "pycut_pursuit.cp_d0_dist" else real(m, f))
        obj, extra = np.asarray(sphere.vertices), {"elements": "points"}
    for cfg in expand_grid(name, **{k: list(v) for k, v in method.sweep.items()}):
        runs = [method.run(obj, 12, cache={}, seed=4, **cfg.kwargs, **extra)
                for _ in range(2)]
        _dense(runs[0].labels, sphere.n_faces if faces else sphere.n_vertices)
        assert np.array_equal(runs[0].labels, runs[1].labels), cfg.label()


def test_runner_records_a_mesh_too_large_for_ncuts_as_skipped(tmp_path):
    root = write_benchmark(tmp_path)
    from superfacets.evaluation.datasets.psb import list_meshes

    meshes = list_meshes(root)
    out = tmp_path / "r.csv"
    cfgs = expand_grid("ncuts", alpha=[100.0], memory_limit_gib=[1e-4])
    s = run_experiment(meshes, cfgs, out, [2, 4], workers=1, progress=False)
    assert s.skipped == 2 * len(meshes) and s.ok == 0
    rows = read_results(out)
    assert all(r["status"] == "skipped" and "GiB" in r["error"] for r in rows)
    s = run_experiment(meshes, expand_grid("ncuts", alpha=[100.0]), out, [2, 4], workers=1,
                       progress=False)
    rows = [r for r in read_results(out) if r["status"] == "ok"]
    assert len(rows) == 2 * len(meshes)
    # the second k reused the embedding: its seconds include it, so they are not smaller
    # than the embedding's own share, and its peak memory is that of the first call
    by_mesh = {}
    for r in rows:
        by_mesh.setdefault(r["mesh"], {})[int(r["n_segments"])] = r
    for pair in by_mesh.values():
        if pair[2]["peak_mib"]:
            assert float(pair[4]["peak_mib"]) >= float(pair[2]["peak_mib"]) - 1e-9


def test_skipped_is_the_runner_signal(ball):
    sphere = ball
    with pytest.raises(Skipped, match="GiB"):
        METHODS["ncuts"].run(sphere, 4, cache={}, seed=0, alpha=0.0, eta_convex=0.2,
                             bandwidth=1.0, components=10, memory_limit_gib=1e-6)


def test_cli_baseline_writes_labels_and_refuses_too_large(tmp_path, capsys):
    from superfacets import read_labels, write_mesh
    from superfacets.cli import main

    mesh = as_mesh(trimesh.creation.icosphere(subdivisions=3))
    path = tmp_path / "ball.off"
    write_mesh(path, mesh)
    seg = tmp_path / "ball.seg"
    assert main(["baseline", str(path), "-m", "vsa", "-k", "12", "--param", "metric=l2",
                 "--param", "init=incremental", "-o", str(seg)]) == 0
    out = capsys.readouterr().out
    assert "vsa (metric=l2, init=incremental" in out and "12 segments" in out
    labels = read_labels(seg, n_faces=mesh.n_faces)
    assert np.array_equal(labels, vsa(mesh, 12, metric="l2", init="incremental", rng=0))
    assert main(["baseline", str(path), "-m", "ncuts", "-k", "8", "-o", str(seg),
                 "--param", "memory_limit_gib=0.001"]) == 2
    err = capsys.readouterr().err
    assert "needs about" in err and "limit 0.0 GiB" in err
    assert main(["baseline", str(path), "-m", "vsa", "--param", "metric=l1,l2"]) == 2
    assert "one value" in capsys.readouterr().err


# --- cut pursuit ---------------------------------------------------------------------------


def test_cut_pursuit_features_and_known_answers():
    pytest.importorskip("cut_pursuit_py", reason="the baselines extra")
    from superfacets.elements.points import point_graph
    from superfacets.evaluation.baselines.cut_pursuit import cut_pursuit, dimensionality_features
    from superfacets.inputs.cloud import PointCloud

    rng = np.random.default_rng(0)
    # a plane and a line: planarity ~1 on the plane, linearity ~1 on the line
    plane = np.c_[rng.random((3000, 2)), np.zeros(3000)]
    line = np.c_[np.linspace(2, 3, 500), np.full(500, 0.5), np.full(500, 0.5)]
    cloud = PointCloud(np.r_[plane, line + rng.normal(0, 1e-4, (500, 3))])
    g = point_graph(cloud).graph
    f = dimensionality_features(g)
    on_plane = g.positions[:, 0] < 1.5
    np.testing.assert_allclose(f[:, :3].sum(axis=1), 1.0)  # the three shares of l1
    assert f[on_plane, 2].max() < 1e-9 and np.median(f[on_plane, 1]) > 0.3  # flat: no scatter
    assert np.median(f[~on_plane, 0]) > 0.9  # the line
    assert np.median(f[on_plane, 3]) < 0.1  # a horizontal plane: not vertical
    # a fold: a horizontal and a vertical square meeting along an edge
    h = np.c_[rng.random((3000, 2)), np.zeros(3000)]
    v = np.c_[rng.random(3000), np.zeros(3000), rng.random(3000)]
    cloud = PointCloud(np.r_[h, v])
    labels = cut_pursuit(cloud, 40)  # the count asked for, found by bisection
    assert abs(int(labels.max()) + 1 - 40) <= 4
    np.testing.assert_array_equal(labels, cut_pursuit(cloud, 40))  # deterministic
    flat = np.arange(6000) < 3000
    k = int(labels.max()) + 1
    a, b = np.bincount(labels, flat, k), np.bincount(labels, ~flat, k)
    assert np.minimum(a, b).sum() < 0.03 * 6000  # superpoints keep to one side of the fold
    # the regularisation takes effect (the package ignores its own argument)
    few = int(cut_pursuit(cloud, reg_strength=1.0).max()) + 1
    many = int(cut_pursuit(cloud, reg_strength=1e-3).max()) + 1
    assert few < many
    with pytest.raises(ParameterError, match="elements"):
        cut_pursuit(cloud, 10, elements="faces")


# --- VCCS (an external module) -------------------------------------------------------------


def _grid_vccs():
    """A stand-in for the external ``vccs_supervoxel``: one label per cube of the seed
    resolution, -1 for the points of cubes holding fewer than 3 (as the port leaves
    small voxels unlabelled)."""
    import types

    def segment_vccs(data, seed, voxel, spatial, normal):
        assert data.shape[1] == 9 and voxel > 0 and spatial >= 0 and normal >= 0
        cell = np.floor(data[:, :3] / seed).astype(np.int64)
        _, lab, count = np.unique(cell, axis=0, return_inverse=True, return_counts=True)
        lab = lab.ravel()
        lab = np.where(count[lab] >= 3, lab, -1)
        return np.c_[data, lab.astype(np.float64)]

    return types.SimpleNamespace(segment_vccs=segment_vccs)


def test_vccs_without_its_module_says_where_it_comes_from(monkeypatch):
    import sys

    from superfacets.errors import MissingExtraError
    from superfacets.evaluation.baselines.vccs import vccs

    monkeypatch.setitem(sys.modules, "vccs_supervoxel", None)  # import fails
    with pytest.raises(MissingExtraError, match="py_vccs"):
        vccs(np.random.default_rng(0).random((50, 3)), 5)


def test_vccs_search_and_labels_for_every_point(monkeypatch):
    import sys

    from superfacets.evaluation.baselines.vccs import vccs

    monkeypatch.setitem(sys.modules, "vccs_supervoxel", _grid_vccs())
    rng = np.random.default_rng(1)
    pts = np.c_[rng.random((4000, 2)), np.zeros(4000)]
    pts[7] = np.nan
    from superfacets.inputs.cloud import PointCloud

    pts = PointCloud(pts, allow_invalid=True)
    labels = vccs(pts, 25)  # seed resolution found by bisection
    assert labels[7] == -1 and (np.delete(labels, 7) >= 0).all()
    assert abs(int(labels.max()) + 1 - 25) <= 0.3 * 25
    assert np.unique(labels[labels >= 0]).size == labels.max() + 1  # dense
    one = vccs(pts, seed_resolution=2.0)  # a seed cell larger than the cloud: one label
    assert set(np.unique(one).tolist()) == {-1, 0}
    with pytest.raises(ParameterError):
        vccs(pts, 10, spatial_importance=-1)
    run = METHODS["vccs"]
    assert run.elements == ("points",)


def test_a_count_the_segmentators_search_cannot_reach_is_said():
    """A flat plane without noise is one segment to the Segmentator's method at any
    threshold: asked for 10, it gives 1 and says so (a comparison at equal counts would
    otherwise compare 1 segment with 10 in silence)."""
    from superfacets.evaluation.baselines.graph_segmentation import graph_segmentation
    from superfacets.inputs.cloud import PointCloud

    xy = np.random.default_rng(0).random((2000, 2))
    plane = PointCloud(np.c_[xy, np.zeros(2000)])
    with pytest.warns(RuntimeWarning, match="gave 1 segments for n_segments=10"):
        labels = graph_segmentation(plane, n_segments=10, elements="points")
    assert labels.max() == 0
    bumpy = PointCloud(np.c_[xy, 0.05 * np.sin(12 * xy[:, 0]) * np.cos(9 * xy[:, 1])])
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # reached: nothing said
        got = int(graph_segmentation(bumpy, n_segments=10, elements="points").max()) + 1
    assert abs(got - 10) <= 1
