"""Packaging and first run: a light import, one version, extras named when missing."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import superfacets
from superfacets import MissingExtraError
from superfacets.elements import face_graph


def _modules_after(code: str) -> set:
    out = subprocess.run([sys.executable, "-c",
                          code + "; import sys; print(' '.join(sys.modules))"],
                         capture_output=True, text=True, check=True).stdout
    return set(out.split())


def test_import_and_help_load_neither_numba_nor_scipy():
    mods = _modules_after("import superfacets")
    assert not {"numba", "scipy", "trimesh", "pyvista", "pandas"} & mods
    mods = _modules_after("from superfacets.cli import build_parser; build_parser()")
    assert not {"numba", "scipy", "trimesh"} & mods
    r = subprocess.run([sys.executable, "-m", "superfacets", "segment", "--help"],
                       capture_output=True, text=True)
    assert r.returncode == 0 and "--alpha" in r.stdout
    # batch: an argument error or an input matching nothing loads neither numba nor Dask
    mods = _modules_after("from superfacets.cli import main; "
                          "assert main(['batch', '/no/such/*.off', '-o', '/tmp/x']) == 2; "
                          "assert main(['batch', '.', '-o', '/tmp/x', '--alpha', '-1']) == 2")
    assert not {"numba", "scipy", "trimesh", "dask", "distributed"} & mods
    # segment: an option out of range, a missing input: nothing heavy loaded
    mods = _modules_after("from superfacets.cli import main; "
                          "assert main(['segment', '/no/such.off', '--alpha', '-1']) == 2; "
                          "assert main(['segment', '/no/such.off']) == 2")
    assert not {"numba", "scipy", "trimesh"} & mods


def test_a_plain_segment_loads_no_scipy_sparse():
    """The paper's run (with its connectivity step) needs no scipy.sparse, about 0.15 s
    of a new process, and loads no numba (not a dependency: the kernels are compiled)."""
    mods = _modules_after(
        "import superfacets; from superfacets.inputs.shapes import creature; "
        "m = creature(24); r = superfacets.segment(m, 30); assert len(r.labels) == len(m.faces)")
    assert "numba" not in mods and "scipy.sparse" not in mods


def test_public_names_resolve_and_are_listed():
    for name in superfacets.__all__:
        assert getattr(superfacets, name) is not None
    # what a notebook's completion lists: the public names, not the imports' helpers
    # (annotations, importlib, TYPE_CHECKING were listed), NotebookView among them
    shown = [n for n in dir(superfacets) if not n.startswith("_")]
    assert shown == sorted(superfacets.__all__) and "NotebookView" in shown
    assert callable(superfacets.segment) and callable(superfacets.superfacets)
    import importlib

    importlib.import_module("superfacets.api.segmentation")  # never shadows the function
    assert callable(superfacets.segment)
    with pytest.raises(AttributeError):
        superfacets.nope


def test_version_is_defined_once():
    from importlib.metadata import version

    assert version("superfacets") == superfacets.__version__


def test_missing_extra_names_the_pip_command(monkeypatch, sphere):
    from superfacets.evaluation.report import load_results
    from superfacets.viz.render import render

    monkeypatch.setitem(sys.modules, "pyvista", None)  # import pyvista now fails
    with pytest.raises(MissingExtraError, match=r"pip install 'superfacets\[render\]'"):
        render(sphere)
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(MissingExtraError, match=r"superfacets\[report\]"):
        load_results("x.csv")


def test_benchmark_locator(tmp_path, monkeypatch):
    from superfacets.evaluation.datasets.psb import psb_root

    root = tmp_path / "bench"
    (root / "off").mkdir(parents=True)
    (root / "seg").mkdir()
    assert psb_root(root) == root
    monkeypatch.setenv("SUPERFACETS_PSB", str(root))
    assert psb_root(cache=tmp_path / "cache") == root
    monkeypatch.setenv("SUPERFACETS_PSB", str(tmp_path / "nowhere"))
    with pytest.raises(FileNotFoundError, match="segeval.cs.princeton.edu.*off/<id>.off"):
        psb_root(cache=tmp_path / "cache")
    monkeypatch.delenv("SUPERFACETS_PSB")
    with pytest.raises(FileNotFoundError, match="Princeton Mesh Segmentation Benchmark"):
        psb_root(archive=tmp_path / "none.tar.xz", cache=tmp_path / "cache")
    import tarfile

    arc = tmp_path / "psb.tar.xz"
    with tarfile.open(arc, "w:xz") as tar:
        tar.add(root, arcname="psb")
    got = psb_root(arc, cache=tmp_path / "cache")
    assert got == tmp_path / "cache" / "psb" and (got / "off").is_dir()


def test_yu_shi_discretization_finds_clear_blocks():
    from superfacets.evaluation.baselines.ncuts import discretize

    rng = np.random.default_rng(0)
    truth = np.repeat(np.arange(5), 40)
    vectors = np.eye(5)[truth] + 0.05 * rng.standard_normal((200, 5))
    q, r = np.linalg.qr(rng.standard_normal((5, 5)))
    labels = discretize(vectors @ q, rng=1)  # any rotation of the indicators
    assert len(set(zip(truth.tolist(), labels.tolist()))) == 5  # one label per block
    assert np.unique(labels).size == 5


def test_contour_is_watertight_and_faces_outwards():
    from superfacets import Mesh
    from superfacets.inputs.shapes import contour, creature

    g = np.mgrid[-1:1:31j, -1:1:31j, -1:1:31j]
    v, f = contour(np.sqrt((g ** 2).sum(0)) - 0.7, (-1, -1, -1), 2 / 30)
    mesh = Mesh(v, f)
    graph = face_graph(mesh)
    assert graph.boundary_elements.size == 0  # every edge shared by two faces
    assert np.allclose(np.linalg.norm(v, axis=1), 0.7, atol=0.01)
    assert (np.einsum("ij,ij->i", mesh.normals, mesh.centroids) > 0).mean() > 0.99
    c = creature(40)
    assert face_graph(c).boundary_elements.size == 0 and c.n_faces > 5000


@pytest.mark.parametrize("call, kind", [
    (lambda m: superfacets.superfacets(m, "ten"), superfacets.ParameterError),
    (lambda m: superfacets.superfacets(m, 10, alpha=-1), superfacets.ParameterError),
    (lambda m: superfacets.superfacets(m, 10, n_threads=10**6), superfacets.ParameterError),
    (lambda m: superfacets.enforce_connectivity(m, np.zeros(3, int)), superfacets.ParameterError),
    (lambda m: superfacets.enforce_connectivity(m, np.zeros(m.n_faces)),
     superfacets.ParameterError),
    (lambda m: superfacets.paper_weights(m, eta_convex=float("nan")), superfacets.ParameterError),
    (lambda m: superfacets.write_labels("x.seg", [0.5, 1.5]), superfacets.ParameterError),
    (lambda m: superfacets.write_colored_mesh("x.ply", m, [1, 2]), superfacets.ParameterError),
    (lambda m: superfacets.segment(m, 10, init="random"), superfacets.ParameterError),
    (lambda m: superfacets.Mesh(np.zeros((3, 2)), [[0, 1, 2]]), superfacets.InvalidMeshError),
])
def test_public_functions_raise_the_package_errors(sphere, call, kind, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(kind) as info:
        call(sphere)
    assert isinstance(info.value, ValueError) and list(tmp_path.iterdir()) == []


def test_metrics_and_colors_refuse_wrong_labels_with_one_error_type(sphere):
    from superfacets.evaluation.metrics import compactness, evaluate
    from superfacets.io.colors import face_colors

    for call in (lambda: compactness(sphere, [0, 1]), lambda: face_colors(sphere, [0]),
                 lambda: evaluate(sphere, np.zeros(sphere.n_faces, int), [np.zeros(4, int)])):
        with pytest.raises(superfacets.ParameterError, match="one per face"):
            call()
