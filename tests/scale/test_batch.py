"""``superfacets batch`` and its engine: inputs, names, manifest, resuming, Dask."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh
from conftest import grid_mesh

from superfacets import (
    Mesh,
    MissingExtraError,
    ParameterError,
    read_labels,
    read_mesh,
    segment,
    write_mesh,
)
from superfacets.cli import main
from superfacets.scale.runner import batch as bt
from superfacets.scale.runner import manifest
from superfacets.scale.runner.batch import collect_inputs, output_names, read_manifest, run_batch

KEEP = ("output", "status", "elements", "n_elements", "segments", "passes", "converged")


def _blob(i: int) -> Mesh:
    """A bumpy sphere, different for each i (a few thousand faces)."""
    s = trimesh.creation.icosphere(subdivisions=3)
    v = s.vertices * (1 + 0.15 * np.sin((i + 2) * s.vertices[:, :1]) *
                      np.cos(3 * s.vertices[:, 1:2]))
    return Mesh(v, s.faces)


@pytest.fixture
def corpus(tmp_path):
    """A dozen small meshes in nested folders (two share a name), one malformed file,
    a README that is not an input."""
    root = tmp_path / "corpus"
    for i in range(12):
        sub = root / ("a" if i < 6 else "b") / ("deep" if i % 4 == 0 else "")
        sub.mkdir(parents=True, exist_ok=True)
        write_mesh(sub / f"m{i % 6}.off", _blob(i) if i % 3 else grid_mesh(12 + i, 10))
    (root / "b" / "broken.off").write_text("OFF\n3 1 0\n0 0 0\n")
    (root / "README.txt").write_text("not a point cloud\n")
    return root


def _table(rows) -> list:
    return sorted(tuple(r[k] for k in KEEP) for r in rows)


def _labels(out: Path) -> dict:
    return {p.relative_to(out).as_posix(): p.read_text() for p in sorted(out.rglob("*.seg"))}


def test_collect_inputs_folders_globs_lists_once_in_order(corpus, tmp_path):
    files = collect_inputs([str(corpus)])
    assert len(files) == 13 and all(f.is_absolute() for f in files)
    assert not any(f.name == "README.txt" for f in files)  # .txt only when named
    lst = tmp_path / "list.txt"
    lst.write_text(f"# some meshes\n{corpus}/a/m1.off\n\n{corpus}/b/*.off\n{corpus}/a/m1.off\n")
    got = collect_inputs([f"@{lst}", str(corpus / "a" / "m1.off")])
    assert [f.relative_to(corpus).as_posix() for f in got] == [
        "a/m1.off", "b/broken.off", "b/m0.off", "b/m1.off", "b/m3.off", "b/m4.off",
        "b/m5.off"]  # listed order, each file once
    assert len(collect_inputs([f"{corpus}/**/deep/*.off"])) == 3
    assert len(collect_inputs([str(corpus)], exclude=corpus / "b")) == 6
    with pytest.raises(FileNotFoundError, match="no file matches"):
        collect_inputs([f"{corpus}/*.stl"])
    with pytest.raises(FileNotFoundError, match="no such file or folder"):
        collect_inputs([str(corpus / "nope.off")])
    with pytest.raises(FileNotFoundError, match="no such list file"):
        collect_inputs(["@" + str(tmp_path / "missing.txt")])
    (tmp_path / "empty").mkdir()
    with pytest.raises(ParameterError, match="no mesh or point-cloud file"):
        collect_inputs([str(tmp_path / "empty")])


def test_output_names_never_collide():
    p = [Path(x) for x in ("/d/a/x.off", "/d/b/x.off", "/d/b/x.ply", "/d/b/y.tri.xz")]
    names = output_names(p)
    assert names == {p[0]: "a/x", p[1]: "b/x.off", p[2]: "b/x.ply", p[3]: "b/y"}
    again = output_names(p, reserved={"a/x", "b/y"})
    assert again[p[1]] == "b/x.off" and again[p[0]].startswith("a/x~") \
        and again[p[3]].startswith("b/y~") and len(set(again.values())) == 4
    assert output_names([Path("/only/one.ply")]) == {Path("/only/one.ply"): "one"}


def test_in_process_batch_equals_segment_and_resumes(corpus, tmp_path):
    out = tmp_path / "out"
    s = run_batch([str(corpus)], out, 20, workers=1, progress=False)
    assert (s.inputs, s.ok, s.failed, s.done_before) == (13, 12, 1, 0)
    rows = read_manifest(out)
    assert len(rows) == 13 and (out / "manifest.parquet").exists()
    assert not (out / ".manifest.jsonl").exists()
    bad = [r for r in rows if r["status"] == "failed"]
    assert len(bad) == 1 and bad[0]["input"].endswith("broken.off")
    assert "\n" not in bad[0]["error"] and "broken.off" in bad[0]["error"]
    for r in rows:
        if r["status"] != "ok":
            continue
        ref = segment(read_mesh(r["input"]), 20)
        got = read_labels(out / r["output"])
        assert np.array_equal(got, ref.labels)
        assert r["segments"] == ref.n_segments and r["passes"] == ref.n_iter
        assert r["elements"] == "faces" and r["n_elements"] == len(got)
        assert r["seconds"] > 0 and r["finished"]
    names = {r["output"] for r in rows}
    assert {"a/m1.seg", "b/m1.seg", "a/deep/m0.seg", "b/deep/m2.seg"} <= names
    # a rerun does nothing; --retry-failed runs the failed one only
    s = run_batch([str(corpus)], out, 20, workers=1, progress=False)
    assert (s.ok, s.failed, s.done_before, s.failed_before) == (0, 0, 13, 1)
    s = run_batch([str(corpus)], out, 20, workers=1, progress=False, retry_failed=True)
    assert (s.ok, s.failed, s.done_before) == (0, 1, 12)
    # other options are refused: results are never mixed
    with pytest.raises(ParameterError, match="n_segments 20 -> 30"):
        run_batch([str(corpus)], out, 30, workers=1, progress=False)


def test_interrupted_and_hard_killed_runs_lose_nothing(corpus, tmp_path, monkeypatch):
    out = tmp_path / "out"
    real = bt.segment_file
    calls = {"n": 0}

    def flaky(task):
        calls["n"] += 1
        if calls["n"] == 5:
            raise KeyboardInterrupt
        return real(task)

    monkeypatch.setattr(bt, "segment_file", flaky)
    s = run_batch([str(corpus)], out, 10, workers=1, progress=False)
    assert s.interrupted and s.ok + s.failed == 4
    rows = read_manifest(out)
    assert len(rows) == 13 and sum(r["status"] == "skipped" for r in rows) == 9
    assert len(list(out.rglob("*.seg"))) == s.ok
    assert not list(out.rglob("*.tmp*"))  # nothing torn
    monkeypatch.setattr(bt, "segment_file", real)
    # a hard kill: the journal holds a row and a torn line, the manifest is older
    first = read_manifest(out)[0]
    (out / "manifest.parquet").unlink()
    (out / ".manifest.jsonl").write_text(json.dumps(first) + "\n" + '{"input": "/x", "sta')
    s = run_batch([str(corpus)], out, 10, workers=1, progress=False)
    assert s.done_before == 1 and s.ok + s.failed == 12 and not s.interrupted
    assert sorted(r["status"] for r in read_manifest(out)).count("ok") == 12


def test_csv_manifest_without_pyarrow(corpus, tmp_path, monkeypatch):
    out = tmp_path / "out"
    monkeypatch.setattr(manifest, "_has_pyarrow", lambda: False)
    run_batch([str(corpus / "a")], out, 8, workers=1, progress=False)
    assert (out / "manifest.csv").exists() and not (out / "manifest.parquet").exists()
    rows = read_manifest(out)
    assert len(rows) == 6 and all(r["status"] == "ok" and r["converged"] in (True, False)
                                  and isinstance(r["segments"], int) for r in rows)
    monkeypatch.undo()  # pyarrow back: the next manifest is Parquet, the CSV goes
    run_batch([str(corpus / "a")], out, 8, workers=1, progress=False)
    assert (out / "manifest.parquet").exists() and not (out / "manifest.csv").exists()


def test_without_dask_the_default_runs_in_this_process(corpus, tmp_path, monkeypatch):
    import superfacets.scale.runner.engine as eng

    monkeypatch.setattr(eng, "_have_dask", lambda: False)
    s = run_batch([str(corpus / "a")], tmp_path / "out", 8, progress=False)
    assert s.ok == 6 and "in this process" in s.engine and "distributed" in s.engine
    import superfacets._runtime.extras as extras

    monkeypatch.setattr(extras.importlib, "import_module",
                        lambda name: (_ for _ in ()).throw(ImportError(name)))
    with pytest.raises(MissingExtraError, match=r"superfacets\[distributed\]"):
        run_batch([str(corpus / "a")], tmp_path / "out2", 8, workers=2, progress=False)


def test_every_element_kind_and_output(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    write_mesh(src / "blob.ply", _blob(1))
    pts = np.random.default_rng(0).normal(size=(600, 3))
    np.savetxt(src / "cloud.xyz", pts)
    out = tmp_path / "out"
    s = run_batch([str(src)], out, 12, workers=1, progress=False, labels="json",
                  colored_mesh="ply", html=True, elements=None)
    assert s.ok == 2
    rows = {Path(r["input"]).name: r for r in read_manifest(out)}
    assert rows["cloud.xyz"]["elements"] == "points" and rows["cloud.xyz"]["n_elements"] == 600
    assert rows["blob.ply"]["elements"] == "faces"
    for name in ("blob", "cloud"):
        seg = json.loads((out / f"{name}.json").read_text())["segIndices"]
        assert len(seg) == rows[f"{name}.{'ply' if name == 'blob' else 'xyz'}"]["n_elements"]
        assert (out / f"{name}_superfacets.ply").exists() and (out / f"{name}.html").exists()
    v = tmp_path / "v"
    s = run_batch([str(src / "blob.ply")], v, 12, workers=1, progress=False,
                  elements="vertices")
    r = read_manifest(v)[0]
    assert r["elements"] == "vertices" and r["n_elements"] == _blob(1).n_vertices


def test_local_cluster_of_two_equals_sequential(corpus, tmp_path):
    one, two = tmp_path / "one", tmp_path / "two"
    run_batch([str(corpus)], one, 20, workers=1, progress=False)
    s = run_batch([str(corpus)], two, 20, workers=2, progress=False)
    assert (s.ok, s.failed) == (12, 1) and "2 worker processes" in s.engine
    assert _table(read_manifest(one)) == _table(read_manifest(two))
    assert _labels(one) == _labels(two)
    # the worker's whole resident memory during the task (Python, numpy, numba: > 50 MiB)
    assert all(r["peak_mib"] > 50 for r in read_manifest(two) if r["status"] == "ok")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _dask(*args) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))  # the same superfacets
    return subprocess.Popen([sys.executable, "-m", "dask", *args], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, env=env)


def test_external_scheduler_and_workers_give_the_same_manifest(corpus, tmp_path):
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = [_dask("scheduler", "--host", "127.0.0.1", "--port", str(port),
                   "--no-dashboard")]
    try:
        procs += [_dask("worker", address, "--nthreads", "1", "--no-dashboard",
                        "--host", "127.0.0.1") for _ in range(2)]
        from distributed import Client

        with Client(address, timeout="60s") as c:
            c.wait_for_workers(2, timeout=120)
        one, ext = tmp_path / "one", tmp_path / "ext"
        run_batch([str(corpus)], one, 20, workers=1, progress=False)
        assert main(["batch", str(corpus), "-o", str(ext), "-k", "20", "--scheduler",
                     address, "-q"]) == 1  # one input failed: exit status 1
        assert _table(read_manifest(one)) == _table(read_manifest(ext))
        assert _labels(one) == _labels(ext)
    finally:
        for p in procs:
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:  # pragma: no cover
                p.kill()


def test_a_worker_killed_mid_run_loses_no_input(corpus, tmp_path):
    import dask
    from distributed import Client, LocalCluster

    with dask.config.set({"distributed.scheduler.allowed-failures": 1}), \
            LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        out = tmp_path / "out"
        journal = out / ".manifest.jsonl"
        killed = []

        def killer():  # a worker process dies as soon as the first input is done
            deadline = time.monotonic() + 120
            while time.monotonic() < deadline:
                done = journal.read_text().count("\n") if journal.exists() else 0
                if done >= 1:
                    pid = next(iter(client.run(os.getpid).values()))
                    os.kill(pid, 9)
                    killed.append(done)
                    return
                time.sleep(0.01)

        th = threading.Thread(target=killer)
        th.start()
        s = run_batch([str(corpus)], out, 20, scheduler=cluster.scheduler_address,
                      progress=False)
        th.join()
        assert killed and killed[0] < 13  # killed mid-run
        rows = read_manifest(out)
        assert len(rows) == 13 and {r["status"] for r in rows} <= {"ok", "failed"}
        assert s.ok + s.failed == 13
        s = run_batch([str(corpus)], out, 20, scheduler=cluster.scheduler_address,
                      progress=False, retry_failed=True)
        assert sum(r["status"] == "ok" for r in read_manifest(out)) == 12
    ref = tmp_path / "ref"
    run_batch([str(corpus)], ref, 20, workers=1, progress=False)
    assert _labels(ref) == _labels(out)


def test_cli_batch_as_in_the_issue(corpus, tmp_path, capsys):
    out = tmp_path / "OUT"
    assert main(["batch", str(corpus / "a"), "-o", str(out), "--workers", "2", "-k", "15"]) == 0
    text = capsys.readouterr().out
    assert "6 ok, 0 failed" in text and (out / "manifest.parquet").exists()
    assert len(list(out.rglob("*.seg"))) == 6
    assert main(["batch", str(corpus / "a"), "-o", str(out), "--workers", "2", "-k", "15"]) == 0
    assert "0 ok, 0 failed, 6 already done" in capsys.readouterr().out


@pytest.mark.parametrize("args, match", [
    (["-o", "{file}"], "exists and is not a folder"),
    (["-o", "{tmp}/no/such/OUT"], "does not exist"),
    (["{tmp}/nothing*.off", "-o", "{tmp}/o"], "no file matches"),
    (["-o", "{tmp}/o", "--alpha", "-1"], "alpha"),
    (["-o", "{tmp}/o", "--labels", "json", "--per-object", "--radius", "0.1"], "per-object"),
    (["-o", "{tmp}/o", "--memory-limit", "lots"], "a size such as 4GiB"),
    (["-o", "{tmp}/o", "--memory-limit", "1KB"], "at least 128 MiB"),  # (it never ended)
    (["-o", "{tmp}/o", "--view", "top"], "give picture or html"),
])
def test_cli_batch_bad_input_one_line_before_any_work(corpus, tmp_path, capsys, args, match):
    f = tmp_path / "a_file"
    f.write_text("x")
    args = [a.format(file=f, tmp=tmp_path) for a in args]
    if not args[0].endswith("*.off"):
        args = [str(corpus)] + args
    assert main(["batch", *args, "--workers", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("superfacets: error:") and match in err[0]
    assert not (tmp_path / "o").exists()


def test_cli_batch_unreachable_scheduler(corpus, tmp_path, capsys):
    port = _free_port()  # nothing listens there
    out = tmp_path / "o"
    assert main(["batch", str(corpus), "-o", str(out), "--scheduler",
                 f"tcp://127.0.0.1:{port}"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot reach the Dask scheduler" in err[0]
    assert not out.exists()


def test_an_output_folder_in_use_is_refused(corpus, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    with manifest.FolderLock(out):
        with pytest.raises(ParameterError, match="another batch"):
            run_batch([str(corpus / "a")], out, 8, workers=1, progress=False)


def test_no_lock_file_is_left_and_a_stale_one_is_reused(corpus, tmp_path):
    out = tmp_path / "out"
    run_batch([str(corpus / "a")], out, 8, workers=1, progress=False)
    assert not (out / ".lock").exists()
    (out / ".lock").write_text("")  # left by a killed run: no one holds it
    s = run_batch([str(corpus / "a")], out, 8, workers=1, progress=False)
    assert s.done_before == 6 and not (out / ".lock").exists()


def test_the_bar_goes_to_a_terminal_only(corpus, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["batch", str(corpus / "a"), "-o", str(out), "-k", "8", "-j", "1"]) == 0
    err = capsys.readouterr().err
    assert "batch:" not in err and "input/s" not in err  # stderr is no terminal here
    assert main(["batch", str(corpus / "a"), "-o", str(tmp_path / "o2"), "-k", "8", "-j", "1",
                 "--progress"]) == 0
    assert "input" in capsys.readouterr().err  # asked for: shown


def test_vertex_labels_get_pictures_with_the_up_axis(corpus, tmp_path):
    pytest.importorskip("pyvista")
    out = tmp_path / "out"
    s = run_batch([str(corpus / "a" / "m1.off")], out, 8, workers=1, progress=False,
                  elements="vertices", picture=True, html=True, up="z", view="front")
    assert s.ok == 1
    assert (out / "m1.png").is_file() and (out / "m1.html").is_file()
    assert json.loads((out / "batch.json").read_text())["options"]["outputs"]["up"] == "z"
    with pytest.raises(ParameterError, match="unknown view"):
        run_batch([str(corpus / "a")], tmp_path / "o3", 8, workers=1, progress=False,
                  picture=True, view="sideways")


def test_batch_says_the_pictures_up_axis(corpus, tmp_path, capsys):
    pytest.importorskip("pyvista")
    assert main(["batch", str(corpus / "a" / "m1.off"), "-o", str(tmp_path / "o"), "-k", "8",
                 "-j", "1", "--picture"]) == 0
    assert "up axis of each input's file or format (else y" in capsys.readouterr().out
    assert main(["batch", str(corpus / "a" / "m2.off"), "-o", str(tmp_path / "p"), "-k", "8",
                 "-j", "1", "--html", "--up", "z"]) == 0
    assert "pages drawn with up axis z" in capsys.readouterr().out


# --- datasets laid out with symbolic links -------------------------------------------

@pytest.fixture
def linked(tmp_path):
    """``lnk/`` holding two links to meshes elsewhere, a plain file, a dangling link, a
    looping pair of links and a link to a folder; ``data/`` the meshes themselves."""
    data = tmp_path / "data" / "meshes"
    data.mkdir(parents=True)
    write_mesh(data / "bunny.off", _blob(1))
    write_mesh(data / "horse.off", _blob(2))
    lnk = tmp_path / "lnk"
    lnk.mkdir()
    (lnk / "scan_a.off").symlink_to(data / "bunny.off")
    (lnk / "scan_b.off").symlink_to(data / "horse.off")
    write_mesh(lnk / "copy_of_a.off", _blob(1))
    return tmp_path, lnk


def test_links_keep_the_names_given(linked):
    tmp_path, lnk = linked
    files = collect_inputs([str(lnk)])
    assert [f.name for f in files] == ["copy_of_a.off", "scan_a.off", "scan_b.off"]
    assert all(f.parent == lnk for f in files)  # not resolved to data/meshes
    names = output_names(files)
    assert sorted(names.values()) == ["copy_of_a", "scan_a", "scan_b"]
    out = tmp_path / "out"
    s = run_batch([str(lnk)], out, 20, workers=1, progress=False)
    assert (s.inputs, s.ok, s.failed) == (3, 3, 0)
    assert sorted(p.name for p in out.glob("*.seg")) == ["copy_of_a.seg", "scan_a.seg",
                                                         "scan_b.seg"]
    rows = read_manifest(out)
    assert sorted(r["input"] for r in rows) == sorted(str(f) for f in files)
    # the link and the copy of one mesh: the same labels
    assert (out / "scan_a.seg").read_text() == (out / "copy_of_a.seg").read_text()


def test_several_links_to_one_file_are_several_inputs(linked):
    tmp_path, _ = linked
    many = tmp_path / "many"
    many.mkdir()
    for i in range(1, 5):
        (many / f"h{i}.off").symlink_to(tmp_path / "data" / "meshes" / "horse.off")
    out = tmp_path / "out"
    s = run_batch([str(many)], out, 20, workers=1, progress=False)
    assert (s.inputs, s.ok) == (4, 4)
    assert sorted(p.name for p in out.glob("*.seg")) == [f"h{i}.seg" for i in range(1, 5)]


def test_a_dangling_or_looping_link_is_a_failed_row(linked, capsys):
    tmp_path, lnk = linked
    (lnk / "gone.off").symlink_to(tmp_path / "nowhere.off")
    (lnk / "loop1.off").symlink_to(lnk / "loop2.off")
    (lnk / "loop2.off").symlink_to(lnk / "loop1.off")
    out = tmp_path / "out"
    assert main(["batch", str(lnk), "-o", str(out), "-k", "20", "-j", "1"]) == 1
    captured = capsys.readouterr()
    assert "batch: 6 inputs: 3 ok, 3 failed" in captured.out
    assert "gone.off: a symbolic link to" in captured.err and "which does not exist" in captured.err
    assert "loop1.off: a symbolic link that loops" in captured.err
    rows = {Path(r["input"]).name: r for r in read_manifest(out)}
    assert rows["gone.off"]["status"] == "failed" and rows["scan_a.off"]["status"] == "ok"
    # named directly too
    s = run_batch([str(lnk / "gone.off")], tmp_path / "out2", 20, workers=1, progress=False)
    assert (s.inputs, s.failed) == (1, 1) and "does not exist" in s.failures[0][1]


def test_links_to_folders_and_folder_loops(linked, capsys):
    tmp_path, lnk = linked
    (lnk / "sub").symlink_to(tmp_path / "data")        # a link to a folder: followed
    (lnk / "back").symlink_to(lnk)                     # a link back to itself: a loop
    (tmp_path / "data" / "meshes" / "up").symlink_to(tmp_path / "data")  # another loop
    files = collect_inputs([str(lnk)])
    assert sorted(f.relative_to(lnk).as_posix() for f in files) == [
        "copy_of_a.off", "scan_a.off", "scan_b.off", "sub/meshes/bunny.off",
        "sub/meshes/horse.off"]


def test_an_unreadable_folder_is_named(linked, monkeypatch, capsys):
    tmp_path, lnk = linked
    real_walk = os.walk

    def walk(top, **kw):  # as root no folder is unreadable: make one say so
        kw["onerror"](PermissionError(13, "Permission denied", str(lnk / "private")))
        yield from real_walk(top, **kw)

    monkeypatch.setattr(os, "walk", walk)
    assert main(["batch", str(lnk), "-o", str(tmp_path / "out"), "-k", "20", "-j", "1"]) == 0
    captured = capsys.readouterr()
    assert "batch: 3 inputs: 3 ok" in captured.out
    assert f"note: {lnk / 'private'}: not read (Permission denied)" in captured.err


def test_the_summary_counts_one_input_in_the_singular(linked, capsys):
    tmp_path, lnk = linked
    assert main(["batch", str(lnk / "scan_a.off"), "-o", str(tmp_path / "o"), "-k", "20",
                 "-j", "1"]) == 0
    assert "batch: 1 input: 1 ok" in capsys.readouterr().out


def test_tetrahedral_meshes_are_collected_from_folders(tmp_path, capsys):
    """The help says every format segment reads: tetrahedral meshes (.vtu, .msh, ...) are
    collected from folders and segmented, one label per tetrahedron."""
    pytest.importorskip("meshio")
    from scipy.spatial import Delaunay

    from superfacets import TetMesh, write_volume_labels

    p = np.random.default_rng(0).random((300, 3))
    vol = TetMesh(p, Delaunay(p).simplices)
    folder = tmp_path / "vols"
    folder.mkdir()
    write_volume_labels(folder / "part.vtu", vol, np.zeros(vol.n_tets, dtype=int))
    files = collect_inputs([str(folder)])
    assert [f.name for f in files] == ["part.vtu"]
    out = tmp_path / "out"
    s = run_batch([str(folder)], out, 5, workers=1, progress=False)
    assert (s.ok, s.failed) == (1, 0)
    labels = np.loadtxt(out / "part.seg", dtype=int)
    assert labels.shape == (vol.n_tets,) and labels.max() + 1 >= 5
    pytest.importorskip("pyvista")
    s = run_batch([str(folder)], tmp_path / "o2", 5, workers=1, progress=False, picture=True,
                  html=True)  # (refused before: segment drew them; the cut, as segment does)
    assert (s.ok, s.failed) == (1, 0)
    assert (tmp_path / "o2" / "part.png").stat().st_size > 0
    assert "cut at the middle of x" in (tmp_path / "o2" / "part.html").read_text()
    s = run_batch([str(folder)], tmp_path / "o3", 5, workers=1, progress=False,
                  colored_mesh="ply")
    assert s.failed == 1 and "--colored-mesh OUT.vtu" in s.failures[0][1]


def test_local_workers_started_outside_a_main_guard_say_what_to_do(tmp_path):
    """A script that starts local Dask workers outside ``if __name__ == "__main__":`` ran
    itself again in each worker, and the run ended in Dask's "Nanny failed to start.":
    it ends in a SchedulerError that names the guard and one worker."""
    pytest.importorskip("distributed")
    script = tmp_path / "noguard.py"
    script.write_text("from superfacets.scale.runner.engine import Engine\n"
                      "with Engine(workers=2) as engine:\n"
                      "    print(list(engine.run(abs, [-1], on_lost=lambda t, e: None)))\n")
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                         timeout=120, cwd=tmp_path)
    assert out.returncode != 0
    last = out.stderr.strip().splitlines()[-1]
    assert last.startswith("superfacets.errors.SchedulerError: the local Dask workers did "
                           "not start") and 'if __name__ == "__main__":' in last
    assert "workers=1" in last


def test_the_local_cluster_runs_without_the_dashboards_samplers():
    """The engine's own scheduler and workers run with ``QUIET_CLUSTER``: no statistical
    profiler in the workers, a 200 ms tick (Dask's 20 ms), a 2 s system monitor (0.5 s),
    CPU that no run reads; a user's own settings outside the engine stay as they were."""
    pytest.importorskip("distributed")
    import dask.config

    from superfacets.scale.runner.engine import QUIET_CLUSTER, Engine

    before = {k: dask.config.get(k) for k in QUIET_CLUSTER}
    with Engine(workers=2) as engine:
        seen = engine.client.run(lambda dask_worker: (
            dask.config.get("distributed.worker.profile.enabled"), dask_worker._tick_interval))
        assert sorted(seen.values()) == [(False, 0.2), (False, 0.2)]
        assert engine.client.run_on_scheduler(lambda dask_scheduler:
                                              dask_scheduler._tick_interval) == 0.2
    assert {k: dask.config.get(k) for k in QUIET_CLUSTER} == before


def test_a_batch_bar_is_redrawn_while_an_input_runs(tmp_path, monkeypatch, capsys):
    """A large input takes minutes in a worker: the batch's bar (its elapsed time) is
    redrawn every TICK seconds meanwhile, not only when an input ends."""
    from conftest import slowed

    slowed(monkeypatch, bt, "segment_file")  # (an input that takes a while)
    folder = tmp_path / "in"
    folder.mkdir()
    trimesh.creation.icosphere(subdivisions=2).export(folder / "s.off")
    s = run_batch([str(folder)], tmp_path / "out", 8, workers=1, progress=True)
    assert s.ok == 1
    assert capsys.readouterr().err.count("batch") >= 10  # redrawn while it ran


def test_sizes_in_each_inputs_units(tmp_path, capsys):
    """batch --seed-resolution R / --neighbor-distance D ("unrecognized arguments" before):
    each input's own count and neighbours, as segment gives them for that file alone; a
    mesh with --neighbor-distance fails with the reason; with -k refused before any work."""
    rng = np.random.default_rng(2)
    folder = tmp_path / "in"
    folder.mkdir()
    for name, side in (("small", 2.0), ("large", 6.0)):
        uv = rng.random((4000, 2)) * side
        np.savetxt(folder / f"{name}.xyz", np.c_[uv, 0.05 * np.sin(3 * uv[:, 0])])
    out = tmp_path / "out"
    assert main(["batch", str(folder / "*.xyz"), "-o", str(out), "-j", "1", "--labels", "npy",
                 "--seed-resolution", "0.4", "--neighbor-distance", "0.5"]) == 0
    for name in ("small", "large"):
        alone = tmp_path / f"{name}.npy"
        assert main(["segment", str(folder / f"{name}.xyz"), "--seed-resolution", "0.4",
                     "--neighbor-distance", "0.5", "-o", str(alone), "-q"]) == 0
        np.testing.assert_array_equal(np.load(out / f"{name}.npy"), np.load(alone))
    counts = [len(np.unique(np.load(out / f"{n}.npy"))) for n in ("small", "large")]
    assert counts[1] > 4 * counts[0]  # (nine times the area: one count per file)
    write_mesh(tmp_path / "m.ply", grid_mesh(6, 6))
    s = run_batch([str(tmp_path / "m.ply")], tmp_path / "o2", workers=1, progress=False,
                  neighbor_distance=0.5)
    assert s.failed == 1 and "point cloud's graph" in s.failures[0][1]
    capsys.readouterr()
    assert main(["batch", str(folder), "-o", str(tmp_path / "o3"), "-k", "20",
                 "--seed-resolution", "0.4"]) == 2
    assert "instead of n_segments (-k)" in capsys.readouterr().err


def test_a_graph_per_input_as_segment_writes_it(tmp_path, capsys):
    """batch --graph (none before: a corpus for a learning pipeline took one segment per
    file): each input's NAME.npz holds what segment --graph writes for that file alone,
    the levels with it (with any --labels); not with --per-object; a folder made without
    graphs is not resumed with them."""
    rng = np.random.default_rng(4)
    folder = tmp_path / "in"
    folder.mkdir()
    uv = rng.random((3000, 2)) * 4
    np.savetxt(folder / "cloud.xyz", np.c_[uv, 0.3 * (uv[:, 0] > 2)])
    write_mesh(folder / "m.ply", grid_mesh(12, 12))
    out = tmp_path / "out"
    assert main(["batch", str(folder), "-o", str(out), "-j", "1", "-k", "24", "--graph",
                 "--levels", "8,3"]) == 0
    for name, source in (("cloud", "cloud.xyz"), ("m", "m.ply")):
        alone = tmp_path / f"{name}.npz"
        assert main(["segment", str(folder / source), "-k", "24", "--graph", str(alone),
                     "--levels", "8,3", "-q"]) == 0
        got, want = np.load(out / f"{name}.npz"), np.load(alone)
        assert sorted(got) == sorted(want) and {"levels", "labels_1", "x"} <= set(got)
        for key in want:
            np.testing.assert_array_equal(got[key], want[key], err_msg=f"{name}: {key}")
        assert len(np.unique(got["labels_1"])) == 3
        np.testing.assert_array_equal(got["labels"], np.loadtxt(out / f"{name}.seg"))
    capsys.readouterr()
    assert main(["batch", str(folder), "-o", str(tmp_path / "o2"), "--graph",
                 "--per-object"]) == 2
    assert "one segmentation" in capsys.readouterr().err
    assert main(["batch", str(folder), "-o", str(tmp_path / "o3"), "--levels", "3"]) == 2
    assert "--graph" in capsys.readouterr().err
    assert main(["batch", str(folder), "-o", str(out), "-j", "1", "-k", "24",
                 "--levels", "8,3", "--labels", "laz"]) == 2  # (other outputs: refused)
    assert not list(tmp_path.glob("o[23]"))


def test_batch_seen_from_segments_clouds_as_scans(tmp_path):
    """``batch --seen-from z``: each cloud as ``segment --seen-from z`` segments it (the
    same labels: a scan's), a mesh as it is; an axis that is none refused before any work."""
    from superfacets import PointCloud
    from superfacets.scale.runner.batch import run_batch

    rng = np.random.default_rng(6)
    street = rng.random((4000, 3)) * [60.0, 40.0, 3.0]
    np.save(tmp_path / "street.npy", street)
    ball = trimesh.creation.icosphere(subdivisions=3)
    ball.export(tmp_path / "ball.off")
    inputs = [str(tmp_path / "street.npy"), str(tmp_path / "ball.off")]
    s = run_batch(inputs, tmp_path / "scan", 40, seen_from="z", workers=1, progress=False)
    assert s.ok == 2
    scan = segment(PointCloud(street, up="z"), 40).labels
    assert np.array_equal(np.loadtxt(tmp_path / "scan" / "street.seg"), scan)
    assert not np.array_equal(scan, segment(PointCloud(street), 40).labels)
    mesh = read_mesh(tmp_path / "ball.off")
    assert np.array_equal(read_labels(tmp_path / "scan" / "ball.seg"), segment(mesh, 40).labels)
    assert main(["batch", *inputs, "-o", str(tmp_path / "cli"), "-k", "40", "--seen-from",
                 "z", "-j", "1", "-q"]) == 0
    assert np.array_equal(np.loadtxt(tmp_path / "cli" / "street.seg"), scan)
    with pytest.raises(ParameterError, match="seen_from"):
        run_batch(inputs, tmp_path / "bad", 40, seen_from="up", workers=1, progress=False)
