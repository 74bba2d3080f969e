"""The faults of the fourth attack (issue 110) that a file, an option or a public function
reaches: each case fails without its fix."""

from __future__ import annotations

import gzip
import json
import lzma
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh

from superfacets import Mesh, PointCloud, segment
from superfacets.cli import main
from superfacets.errors import MemoryLimitError, ParameterError


@pytest.mark.parametrize("name, content", [
    ("bomb.obj.gz", lambda: gzip.compress(b"v 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                          + b"f 1 2 3\n" * 3_000_000)),
    ("bomb.xyz.gz", lambda: gzip.compress(b"0 0 0\n" * 5_000_000)),
    ("bomb.off.xz", lambda: lzma.compress(b"OFF\n3 2000000 0\n0 0 0\n1 0 0\n0 1 0\n"
                                          + b"3 0 1 2\n" * 2_000_000)),
])
def test_a_small_compressed_file_cannot_cost_gigabytes(tmp_path, capsys, name, content):
    """One element repeated millions of times, in formats without a header (and one whose
    header declares them): refused after decompressing a bounded multiple of its size."""
    path = tmp_path / name
    path.write_bytes(content())
    assert path.stat().st_size < 100_000
    t0 = time.perf_counter()
    assert main(["segment", str(path), "-o", str(tmp_path / "x.seg")]) == 2
    assert time.perf_counter() - t0 < 30  # (was a minute and 5.7 GB at the attack's size)
    err = capsys.readouterr().err
    assert "likely decompression bomb" in err and "SUPERFACETS_MAX_RATIO" in err
    assert not (tmp_path / "x.seg").exists()


def test_a_genuine_compressed_file_reads_and_the_bound_can_be_raised(tmp_path, monkeypatch):
    from superfacets import read_cloud
    from superfacets.io.files import MAX_RATIO

    g = np.mgrid[0:200, 0:200].reshape(2, -1).T * 0.01  # a regular grid: compresses well
    text = "\n".join(f"{x:.6f} {y:.6f} 0.000000" for x, y in g).encode()
    path = tmp_path / "grid.xyz.xz"
    path.write_bytes(lzma.compress(text))
    assert len(text) / path.stat().st_size < MAX_RATIO
    assert read_cloud(path).n_points == 40000
    monkeypatch.setenv("SUPERFACETS_MAX_RATIO", "2")
    with pytest.raises(MemoryLimitError, match="decompression bomb"):
        read_cloud(path)
    monkeypatch.setenv("SUPERFACETS_MAX_RATIO", "lots")
    with pytest.raises(ParameterError, match="SUPERFACETS_MAX_RATIO='lots'"):
        read_cloud(path)


def test_compressed_labels_are_not_bounded_by_the_ratio(tmp_path):
    from superfacets import read_labels, write_labels

    labels = np.repeat(np.arange(3), 400_000)  # runs of one value: thousands of times
    path = write_labels(tmp_path / "l.seg.gz", labels)
    assert np.array_equal(read_labels(path), labels)


@pytest.mark.parametrize("leaf", [-1, 0, 2**62, 1.5, True])
def test_point_tree_refuses_a_leaf_size_it_cannot_build(leaf):
    from superfacets.elements.neighbors import point_tree

    pts = np.random.default_rng(0).random((200, 3))
    with pytest.raises(ParameterError, match="leaf"):
        point_tree(pts, leaf=leaf)
    assert point_tree(pts, leaf=1).points.shape == (200, 3)


def test_huge_features_are_refused_not_looped_over():
    mesh = trimesh.creation.icosphere(subdivisions=3)
    f = np.random.default_rng(0).random((len(mesh.faces), 3))
    for scale, says in ((1e100, "too large for float32"), (1e200, "beyond 1e\\+150")):
        with pytest.raises(ParameterError, match=says):
            segment(mesh, 20, features=f * scale, beta=1.0)
    assert segment(mesh, 20, features=f * 1e100).n_segments == 20  # beta from the data
    assert segment(mesh, 20, features=f * 1e30, beta=1.0).n_segments == 20


def _gltf(nodes, scene_nodes) -> dict:
    import base64

    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype="<f4")
    i = np.array([0, 1, 2, 0], dtype="<u2")
    buf = v.tobytes() + i.tobytes()
    return {"asset": {"version": "2.0"},
            "buffers": [{"byteLength": len(buf), "uri": "data:application/octet-stream;"
                         "base64," + base64.b64encode(buf).decode()}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                            {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]},
                          {"bufferView": 1, "componentType": 5123, "count": 3,
                           "type": "SCALAR"}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
            "nodes": nodes, "scenes": [{"nodes": scene_nodes}], "scene": 0}


@pytest.mark.parametrize("nodes, roots, says", [
    ([{"mesh": 0, "children": [1]}, {"children": [2]}, {"mesh": 0, "children": [0]}], [1],
     "cycle: node 0 is its own ancestor (0 -> 1 -> 2 -> 0)"),
    ([{"mesh": 0, "children": [0]}], [0], "node 0 is its own child"),
    ([{"mesh": 0, "children": [1]}, {"mesh": 0}, {"children": [1]}], [0, 2], "two parents"),
    ([{"mesh": 0, "children": [7]}], [0], "outside the 1 nodes"),
    ([{"mesh": 0, "children": [1]}] + [{"children": [k + 1]} for k in range(1, 1500)]
     + [{"mesh": 0}], [0], "nested deeper than 1,000 levels"),
])
def test_gltf_node_graphs_are_checked_before_they_are_walked(tmp_path, capsys, nodes, roots,
                                                             says):
    path = tmp_path / "scene.gltf"
    path.write_text(json.dumps(_gltf(nodes, roots)))
    t0 = time.perf_counter()
    assert main(["segment", str(path), "-k", "1", "-o", str(tmp_path / "x.seg")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("superfacets: error:") and len(err.splitlines()) == 1
    assert says in err and time.perf_counter() - t0 < 20
    deep = tmp_path / "deep.gltf"  # a deep but bounded hierarchy reads
    chain = [{"mesh": 0, "children": [1]}] + [{"children": [k + 1]} for k in range(1, 50)] + [
        {"mesh": 0}]
    deep.write_text(json.dumps(_gltf(chain, [0])))
    assert main(["segment", str(deep), "-k", "2", "-o", str(tmp_path / "d.seg"), "-q"]) == 0


def test_complex_colours_and_features_are_refused_like_coordinates():
    mesh = trimesh.creation.icosphere(subdivisions=2)
    with pytest.raises(TypeError, match="real numbers"):
        PointCloud(np.random.default_rng(0).random((10, 3)), colors=np.full((10, 3), 0.5 + 1j))
    with pytest.raises(TypeError, match="real numbers"):
        Mesh(mesh.vertices, mesh.faces, face_colors=np.full((len(mesh.faces), 3), 0.5 + 0j))
    with pytest.raises(ParameterError, match="real numbers"):
        segment(mesh, 10, features=np.ones((len(mesh.faces), 3)) * (1 + 2j), beta=1.0)
    with pytest.raises(ParameterError, match="real numbers"):
        segment(mesh, 10, features=np.ones((len(mesh.faces), 3)) * (1 + 0j))


@pytest.mark.parametrize("value", ["1e3", "9223372036854775808", "10000", "0", "-2", "2.5"])
def test_the_thread_variable_follows_the_option_s_rule(tmp_path, sphere, value):
    from superfacets import write_mesh

    path = tmp_path / "ball.off"
    write_mesh(path, sphere)
    run = subprocess.run([sys.executable, "-m", "superfacets", "segment", str(path), "-k", "5",
                          "-o", str(tmp_path / "x.seg")], capture_output=True, text=True,
                         env={"SUPERFACETS_NUM_THREADS": value, "PATH": "/usr/bin:/bin"},
                         timeout=120)
    assert run.returncode == 2, run.stderr[-500:]
    from superfacets.checks import max_threads

    assert run.stderr.strip().splitlines() == [
        f"superfacets: error: SUPERFACETS_NUM_THREADS={value!r}: give a whole number of "
        f"threads from 1 to {max_threads()} (as --threads), or unset it"]


def test_smaller_faults_speak_the_user_s_terms():
    from superfacets._runtime.memory import _amount
    from superfacets.evaluation.baselines.graph_segmentation import graph_segmentation

    box = trimesh.creation.box()
    with pytest.raises(ParameterError, match="min_size must be an integer <="):
        graph_segmentation(box, min_size=2**63)
    ints = np.empty(len(box.faces), dtype=object)  # an object array of Python ints
    ints[:] = [list(map(int, f)) for f in box.faces]
    assert Mesh(box.vertices, ints).n_faces == 12
    assert Mesh(box.vertices, np.array(box.faces.tolist(), dtype=object)).n_faces == 12
    big = box.faces.astype(np.uint64)
    big[0, 0] = np.iinfo(np.uint64).max
    with pytest.raises(Exception, match="18446744073709551615"):  # as given, not as -1
        Mesh(box.vertices, big)
    assert (_amount(0.1 * 2**30), _amount(0.06 * 2**30)) == ("102 MiB", "61.4 MiB")


_SWALLOWED = r"""
import os, signal, sys, time
import superfacets.cli.segmenting as seg
from superfacets.cli import main

class Finalized:
    def __del__(self):  # as a callback of Dask's garbage collection: the SIGTERM lands here
        os.kill(os.getpid(), signal.SIGTERM)
        for _ in range(100000):
            pass

def command(args):
    x = Finalized()
    del x  # its finalizer took the SIGTERM: printed as ignored, the run went on
    t0 = time.monotonic()
    while time.monotonic() - t0 < 20:
        time.sleep(0.01)
    print("ran to the end")
    return 0

seg.cmd_segment = command
sys.exit(main(["segment", "anything.off"]))
"""


def test_a_sigterm_swallowed_by_a_finalizer_still_ends_the_run_with_143(tmp_path):
    t0 = time.perf_counter()
    run = subprocess.run([sys.executable, "-c", _SWALLOWED], capture_output=True, text=True,
                         timeout=60, cwd=tmp_path)
    assert run.returncode == 143, (run.returncode, run.stderr[-1000:])
    assert time.perf_counter() - t0 < 15  # sent again at once, not after the 20 s of work
    assert "ran to the end" not in run.stdout
    assert "Traceback" not in run.stderr and "Exception ignored" not in run.stderr
    assert run.stderr.strip().splitlines()[-1] == "superfacets: terminated"


_UNDER_LIMIT = r"""
import resource, sys
resource.setrlimit(resource.RLIMIT_AS, (6 << 30, 6 << 30))
from superfacets.cli import main
code = main(["segment", "missing.off", "-o", "x.seg"])  # (refused: no such file)
import numpy, threadpoolctl
blas = [p for p in threadpoolctl.threadpool_info() if p["user_api"] == "blas"]
print(code, sorted({p["num_threads"] for p in blas}))
"""


def test_under_an_address_space_limit_the_blas_starts_one_thread(tmp_path):
    """(OpenBLAS retried a refused mmap for ever as it started its threads, deaf to
    SIGTERM, under `ulimit -v 400 MB`.)"""
    pytest.importorskip("threadpoolctl")
    env = {k: v for k, v in __import__("os").environ.items()
           if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")}
    run = subprocess.run([sys.executable, "-c", _UNDER_LIMIT], capture_output=True,
                         text=True, timeout=120, env=env, cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-1000:]
    assert run.stdout.split("\n")[-2].endswith("[1]"), run.stdout


def test_a_laz_of_one_point_repeated_is_refused_before_it_is_read(tmp_path, capsys):
    laspy = pytest.importorskip("laspy")
    las = laspy.create(point_format=0, file_version="1.2")
    n = 2_000_000  # (the attack's: 50M points in a few hundred KiB)
    las.x, las.y, las.z = np.zeros(n), np.zeros(n), np.zeros(n)
    path = tmp_path / "same.laz"
    las.write(str(path))
    assert path.stat().st_size < 40_000
    t0 = time.perf_counter()
    assert main(["segment", str(path), "-o", str(tmp_path / "x.seg")]) == 2
    assert time.perf_counter() - t0 < 5
    assert "likely decompression bomb" in capsys.readouterr().err


def test_a_ply_of_faces_listing_no_vertex_is_refused_before_they_are_parsed(tmp_path, capsys):
    """(50M such faces in 2 GB were parsed one by one for minutes, then refused.)"""
    import struct

    n = 1_000_000
    head = (f"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
            f"property float y\nproperty float z\nelement face {n}\n"
            "property list uchar int vertex_indices\nend_header\n").encode()
    body = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + b"\0" * n + b"\0" * (13 * n)
    path = tmp_path / "zero.ply"
    path.write_bytes(head + body)
    t0 = time.perf_counter()
    assert main(["segment", str(path), "-o", str(tmp_path / "x.seg")]) == 2
    assert time.perf_counter() - t0 < 3  # (was 4 s here for this 1M, minutes for 50M)
    assert "face 0 lists 0 vertices" in capsys.readouterr().err


def test_public_functions_refuse_spoilt_arguments_without_crash_or_hang():
    """Each public function's own example call with one argument spoilt (numbers: -1,
    2**62, NaN; the top-level functions' arguments also a word, None, an object, an empty
    array, a complex number), each in a forked child: a result or an exception, never a
    crash or a hang (issue 110: boundary tolerances and smoothing rounds of 2**62 looped)."""
    import inspect

    import superfacets.errors as errors

    script = Path(__file__).resolve().parent / "hostile_api.py"
    out = subprocess.run([sys.executable, str(script), "30"], capture_output=True, text=True,
                         timeout=900, cwd=script.parent,
                         env={**os.environ, "SUPERFACETS_NUM_THREADS": "1"})
    lines = out.stdout.splitlines()
    assert out.returncode == 0 and lines and lines[-1] == "DONE", out.stderr[-2000:]
    recorded = int(next(x for x in lines if x.startswith("RECORDED")).split()[1])
    cases = [x[5:] for x in lines if x.startswith("CASE")]
    outcomes = [x.split(" ", 1)[1] for x in lines if x.startswith("RESULT")]
    ours = {n for n, c in vars(errors).items() if inspect.isclass(c)
            and issubclass(c, errors.SuperfacetsError)}
    allowed = ours | {"ok", "ValueError", "TypeError", "OverflowError", "MemoryError",
                      "FileNotFoundError", "OutOfRange", "Mismatch"}
    bad = [(c, o) for c, o in zip(cases, outcomes) if o not in allowed]
    assert not bad, bad
    assert recorded > 250 and len(cases) > 600 and outcomes.count("ParameterError") > 200


def test_arguments_of_the_wrong_kind_are_named(tmp_path):
    """A non-mesh to face_graph, a non-string format, a stray ``outputs``, a viewpoint in
    words: one clear error each (were AttributeError and ValueError from inside)."""
    from superfacets import face_graph, read_mesh, write_labels
    from superfacets.errors import InvalidCloudError

    with pytest.raises(TypeError, match="face_graph needs a superfacets.Mesh"):
        face_graph(np.zeros((3, 3)))
    with pytest.raises(TypeError, match="format must be a suffix"):
        read_mesh(tmp_path / "m.off", format=3)
    with pytest.raises(TypeError, match="outputs must be"):
        write_labels(tmp_path / "l.seg", np.zeros(3, int), outputs=object())
    assert not (tmp_path / "l.seg").exists()
    with pytest.raises(InvalidCloudError, match="viewpoint must be 3 finite numbers"):
        PointCloud(np.random.default_rng(0).random((10, 3)), viewpoint="x")


def test_functions_the_guide_names_refuse_objects_of_the_wrong_kind_in_words(tmp_path):
    """A word, None or an array where a graph, a tetrahedral mesh, an info dict, weights
    or a field name is expected: a TypeError or ParameterError naming what is expected,
    not an AttributeError or IndexError from inside (found by the sweep of every public
    function's arguments, 2026-11-28)."""
    import trimesh

    from superfacets import TetMesh, segment
    from superfacets.evaluation.metrics import oracle_miou
    from superfacets.graph.hierarchy import hierarchy
    from superfacets.io.records import ply_field_name, write_labels_into
    from superfacets.io.tetmeshes import write_volume_labels
    from superfacets.viz.html import html_page

    ball = trimesh.creation.icosphere(subdivisions=2)
    r = segment(ball, 8)
    for bad in ("x", None, np.zeros((3, 3))):
        with pytest.raises(TypeError, match="superfacet graph"):
            hierarchy(bad, [4])
        with pytest.raises(TypeError, match="TetMesh"):
            write_volume_labels(tmp_path / "v.vtu", bad, [0])
    assert hierarchy(r.graph(), [4]).levels == (4,)
    tet = TetMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 1, 2, 3]])
    pytest.importorskip("meshio")
    assert write_volume_labels(tmp_path / "v.vtu", tet, [0]).exists()
    for bad in ("x", 3, object()):
        with pytest.raises(ParameterError, match="info must be a dict"):
            html_page(ball, r.labels, info=bad)
    labels = np.array([0, 0, 1, 1])
    for bad in (np.array([]), np.ones(3), 2.0):
        with pytest.raises(ParameterError, match="one value per element"):
            oracle_miou(labels, labels, weights=bad)
    assert oracle_miou(labels, labels, weights=np.ones(4))[0] == 1.0
    for bad in (None, "", "a b", "x;y", 5):
        with pytest.raises(ParameterError, match="word of letters"):
            ply_field_name(bad)
    ply = tmp_path / "c.ply"
    ply.write_text("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                   "property float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n")
    with pytest.raises(ParameterError, match="word of letters"):
        write_labels_into(tmp_path / "out.ply", ply, np.array([0, 1]), name="a b")
    assert not (tmp_path / "out.ply").exists()
    write_labels_into(tmp_path / "out.ply", ply, np.array([0, 1]), name="Seg_1")
    assert b"scalar_Seg_1" in (tmp_path / "out.ply").read_bytes()


def test_the_stages_say_what_they_take():
    """Each of the run's stages given a word, None or an array where the run's graph, rules
    or parameters go: a TypeError naming what it takes (an AttributeError from inside
    before), and the stages as the run calls them unchanged."""
    from superfacets.method import finish as F
    from superfacets.method import stages as S
    from superfacets.method.pipeline import passes_example

    s = passes_example()
    calls = {
        "weigh": lambda g, r: S.weigh(g, r), "initialize": lambda g, r: S.initialize(
            g, s.w, r, s.hooks), "finish": lambda g, r: F.finish(g, s.it.label, s.it.centers, r),
        "exact_count": lambda g, r: F.exact_count(g, s.labels, r),
        "merge_small": lambda g, r: F.merge_small(g, s.labels, s.kept, r)}
    for name, call in calls.items():
        for bad in ("x", None, np.zeros(3)):
            with pytest.raises(TypeError, match=f"{name} takes the run's element graph"):
                call(bad, s.rules)
            with pytest.raises(TypeError, match=f"{name} takes the run's rules"):
                call(s.graph, bad)
    with pytest.raises(TypeError, match="build_graph takes the run's parameters"):
        S.build_graph(np.zeros((4, 3)), {"n_segments": 4})
    assert F.exact_count(s.graph, s.labels, s.rules)[1] == 12
