"""The experiment runner, the method registry, the report, and their command lines."""

from __future__ import annotations

import csv
import os

import numpy as np
import pytest
from conftest import grid_mesh, write_benchmark

from superfacets import ParameterError
from superfacets.cli import main
from superfacets.evaluation.datasets.psb import list_meshes
from superfacets.evaluation.methods import METHODS, MethodRun, Skipped, register_method
from superfacets.evaluation.report import load_results, markdown_summary, summary, write_report
from superfacets.evaluation.report.tables import series_order
from superfacets.scale.runner import expand_grid, read_results, run_experiment


def _valley(n, depth):
    return grid_mesh(n, n, height=lambda x, y: depth * np.abs(x))


@pytest.fixture
def bench(tmp_path):
    """A tiny benchmark folder: ids 1, 2 (Human) and 21 (Cup), two ground truths each."""
    return write_benchmark(tmp_path)


# module-level methods (the worker processes import them by reference)
def by_x_method(mesh, n_segments, *, cache, seed, shift=0.0):
    cache["calls"] = cache.get("calls", 0) + 1
    x = mesh.centroids[:, 0] + shift
    edges = np.linspace(x.min(), x.max(), n_segments + 1)[1:-1]
    return MethodRun(np.digitize(x, edges), n_iter=cache["calls"], converged=True)


def picky_method(mesh, n_segments, *, cache, seed, limit=500):
    if mesh.n_faces > limit:
        raise Skipped(f"{mesh.n_faces} faces > {limit}")
    if n_segments == 7:
        raise RuntimeError("seven is unlucky")
    return MethodRun(np.zeros(mesh.n_faces, np.int64))


def dying_method(mesh, n_segments, *, cache, seed):
    os._exit(3)


@pytest.fixture
def registry():
    saved = dict(METHODS)
    register_method("by_x", by_x_method, defaults={"shift": 0.0}, sweep={"shift": (0.0,)})
    register_method("picky", picky_method, defaults={"limit": 500})
    register_method("dying", dying_method, defaults={})
    yield
    METHODS.clear()
    METHODS.update(saved)


def test_expand_grid_resolves_and_validates():
    cfgs = expand_grid("superfacets", alpha=[0, 200], init="grid")
    assert len(cfgs) == 2
    assert cfgs[0].kwargs == {"alpha": 0.0, "cleanup": "auto", "eta_convex": 0.2, "init": "grid",
                              "max_iter": 50, "tol": 0.001, "window": 2.0, "center_tol": "auto",
                              "coarsen": "auto", "split_merge": "auto", "paper": False,
                              "density": "auto", "roughness": 0.0, "merge_from": "auto",
                              "max_size_ratio": "auto", "merge_cost": "noise", "assignment": "auto",
                              "beta": "auto", "up_weight": "auto",
                              "step_weight": "auto"}
    assert isinstance(cfgs[1].kwargs["alpha"], float)
    assert expand_grid("superfacets", alpha=[200, 200.0]) == expand_grid("superfacets", alpha=200)
    with pytest.raises(ParameterError, match="no parameter 'gamma'"):
        expand_grid("superfacets", gamma=[1])
    assert [c.kwargs["beta"] for c in expand_grid("superfacets", beta=["auto", 0])] == [
        "auto", "0"]  # ("auto" parameters keep their text: the run reads it)
    with pytest.raises(ParameterError, match="assignment must be auto or bounded or exact"):
        expand_grid("superfacets", assignment=["exact", "nearest"])
    assert [c.kwargs["assignment"] for c in expand_grid(
        "superfacets", assignment=["auto", "bounded", "exact"])] == ["auto", "bounded", "exact"]
    with pytest.raises(ParameterError, match="unknown method 'nope'.*superfacets"):
        expand_grid("nope")
    with pytest.raises(ParameterError, match="max_iter must be int"):
        expand_grid("superfacets", max_iter="many")
    # "auto" parameters: auto or a value of their kind, refused up front otherwise
    assert expand_grid("superfacets", cleanup="false")[0].kwargs["cleanup"] == "false"
    with pytest.raises(ParameterError, match="cleanup must be auto or bool"):
        expand_grid("superfacets", cleanup="maybe")
    with pytest.raises(ParameterError, match="coarsen must be auto or int"):
        expand_grid("superfacets", coarsen="fine")


def test_run_writes_one_row_per_combination_and_resumes(bench, tmp_path):
    meshes = list_meshes(bench)
    res = tmp_path / "r.csv"
    cfgs = expand_grid("superfacets", alpha=[0, 200])
    s = run_experiment(meshes, cfgs, res, [5, 10], workers=1, progress=False)
    assert (s.ok, s.failed, s.skipped, s.done_before) == (12, 0, 0, 0)
    rows = read_results(res)
    assert len(rows) == 12
    r = rows[0]
    assert r["status"] == "ok" and r["category"] in ("Human", "Cup") and r["n_ground_truths"] == "2"
    assert {row["segments"] for row in rows if row["n_segments"] == "5"} == {"5"}
    for row in rows:
        assert 0 <= float(row["undersegmentation_error"]) and 0 < float(row["boundary_recall"]) <= 1
        assert 0 < float(row["achievable_accuracy"]) <= 1 and float(row["compactness"]) > 3.5
    # a second run does nothing; a new k only adds its rows
    s = run_experiment(meshes, cfgs, res, [5, 10], workers=1, progress=False)
    assert (s.written, s.done_before) == (0, 12)
    s = run_experiment(meshes, cfgs, res, [5, 10, 20], workers=1, progress=False)
    assert (s.ok, s.done_before) == (6, 12)
    assert len(read_results(res)) == 18


def test_torn_last_line_is_repaired_and_rerun(bench, tmp_path):
    meshes = list_meshes(bench)
    res = tmp_path / "r.csv"
    cfgs = expand_grid("superfacets", alpha=200)
    run_experiment(meshes, cfgs, res, [5], workers=1, progress=False)
    full = res.read_text()
    res.write_text(full[: full.rstrip("\n").rfind("\n") + 1] + "21,21,Cup,39")  # hard kill
    assert len(read_results(res)) == 2
    s = run_experiment(meshes, cfgs, res, [5], workers=1, progress=False)
    assert (s.ok, s.done_before) == (1, 2)
    assert res.read_text().count("\n") == 4 and res.read_text().endswith("\n")


def test_registry_plugs_in_failures_and_skips_are_recorded(bench, tmp_path, registry):
    meshes = list_meshes(bench)
    res = tmp_path / "r.csv"
    cfgs = expand_grid("by_x") + expand_grid("picky")
    s = run_experiment(meshes, cfgs, res, [4, 7], workers=1, progress=False)
    rows = read_results(res)
    assert len(rows) == 12 and s.written == 12
    byx = [r for r in rows if r["method"] == "by_x"]
    assert all(r["status"] == "ok" for r in byx)
    # the cache is shared by the k values of one (mesh, setting): second call sees it
    assert sorted({r["iterations"] for r in byx}) == ["1", "2"]
    # faces 512 (16x16x2) and 800 (20x20x2) are over the limit: skipped; 392 faces: runs
    picky = {(r["mesh"], r["n_segments"]): r for r in rows if r["method"] == "picky"}
    assert picky[("1", "4")]["status"] == "skipped" and "512 faces" in picky[("1", "4")]["error"]
    assert picky[("21", "4")]["status"] == "ok"
    assert picky[("21", "7")]["status"] == "failed"
    assert "RuntimeError: seven is unlucky" in picky[("21", "7")]["error"]
    assert s.failed == 1 and s.skipped == 4
    # failed rows are not retried by default, but are with retry_failed
    assert run_experiment(meshes, cfgs, res, [4, 7], workers=1, progress=False).written == 0
    s = run_experiment(meshes, cfgs, res, [4, 7], workers=1, progress=False, retry_failed=True)
    assert s.failed == 1 and s.written == 1
    df = load_results(res)  # the retried row replaces the old one
    assert len(df) == 12


def test_a_bad_mesh_does_not_stop_the_run(bench, tmp_path):
    (bench / "seg" / "Benchmark" / "2" / "2_1.seg").write_text("0\n1\n")
    res = tmp_path / "r.csv"
    s = run_experiment(list_meshes(bench), expand_grid("superfacets"), res, [5, 1000],
                       workers=1, progress=False)
    rows = {(r["mesh"], r["n_segments"]): r for r in read_results(res)}
    assert "2_1.seg" in rows[("2", "5")]["error"] and rows[("2", "5")]["status"] == "failed"
    assert rows[("1", "5")]["status"] == "ok"
    assert "n_segments" in rows[("21", "1000")]["error"]  # 392 faces < 1000
    assert s.ok == 2 and s.failed == 4


def test_interrupt_keeps_rows_and_rerun_continues(bench, tmp_path, registry, monkeypatch):
    import superfacets.scale.runner.experiment as ex

    meshes = list_meshes(bench)
    res = tmp_path / "r.csv"
    calls = {"n": 0}
    real = ex._run_task

    def flaky(task):
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt
        return real(task)

    monkeypatch.setattr(ex, "_run_task", flaky)
    cfgs = expand_grid("by_x")
    s = run_experiment(meshes, cfgs, res, [3, 6], workers=1, progress=False)
    assert s.interrupted and s.ok == 4
    monkeypatch.setattr(ex, "_run_task", real)
    s = run_experiment(meshes, cfgs, res, [3, 6], workers=1, progress=False)
    assert not s.interrupted and (s.ok, s.done_before) == (2, 4)


def test_worker_processes_give_the_same_rows(bench, tmp_path, registry):
    meshes = list_meshes(bench)
    cfgs = expand_grid("superfacets", alpha=[0, 200]) + expand_grid("by_x")
    one, two = tmp_path / "one.csv", tmp_path / "two.csv"
    run_experiment(meshes, cfgs, one, [5, 8], workers=1, progress=False)
    s = run_experiment(meshes, cfgs, two, [5, 8], workers=2, progress=False)
    assert s.ok == 18

    def table(p):
        keep = ("mesh", "method", "alpha", "n_segments", "segments", "iterations",
                "undersegmentation_error", "compactness", "boundary_recall", "achievable_accuracy")
        return sorted(tuple(r[k] for k in keep) for r in read_results(p))

    assert table(one) == table(two)


def test_a_dying_worker_is_recorded_and_the_run_goes_on(bench, tmp_path, registry):
    import dask
    import distributed  # noqa: F401 - its configuration's defaults, before the set below:
    # set on a process that had not imported it, dask removed the whole "distributed"
    # section on leaving (the defaults the import added inside with it), and the next
    # test in the process to start a local cluster failed with KeyError: 'distributed'

    meshes = list_meshes(bench)
    res = tmp_path / "r.csv"
    cfgs = expand_grid("dying") + expand_grid("by_x")
    with dask.config.set({"distributed.scheduler.allowed-failures": 1}):  # one retry: quicker
        s = run_experiment(meshes, cfgs, res, [4], workers=2, progress=False)
    rows = read_results(res)
    assert len(rows) == 6 and s.ok == 3 and s.failed == 3
    assert all("worker process died" in r["error"] for r in rows if r["method"] == "dying")


def test_run_rejects_bad_arguments(bench, tmp_path):
    meshes = list_meshes(bench)
    cfgs = expand_grid("superfacets")
    with pytest.raises(ParameterError, match="no method"):
        run_experiment(meshes, [], tmp_path / "r.csv")
    with pytest.raises(ParameterError, match="n_segments"):
        run_experiment(meshes, cfgs, tmp_path / "r.csv", [0])
    with pytest.raises(ParameterError, match="workers"):
        run_experiment(meshes, cfgs, tmp_path / "r.csv", [5], workers=0)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        run_experiment(meshes, cfgs, tmp_path / "nowhere" / "r.csv", [5])
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match="not a superfacets results file"):
        run_experiment(meshes, cfgs, bad, [5])


def _write_rows(path, rows):
    cols = ["mesh", "mesh_id", "category", "n_faces", "method", "n_segments", "alpha", "seed",
            "status", "segments", "iterations", "converged", "seconds",
            "undersegmentation_error", "compactness", "boundary_recall", "achievable_accuracy",
            "n_ground_truths", "error"]
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, cols, restval="")
        w.writeheader()
        w.writerows(rows)


def test_report_averages_categories_equally_and_keeps_last_row(tmp_path):
    def row(mesh, cat, alpha, ue, status="ok"):
        return dict(mesh=mesh, mesh_id=mesh, category=cat, method="superfacets",
                    n_segments=50, alpha=alpha, seed=0, status=status, segments=50,
                    iterations=3, converged="true", seconds=0.1, undersegmentation_error=ue,
                    compactness=4.0, boundary_recall=0.5, achievable_accuracy=0.9,
                    n_ground_truths=1)

    res = tmp_path / "r.csv"
    _write_rows(res, [row("1", "A", 0.0, 0.1), row("2", "A", 0.0, 0.3), row("3", "B", 0.0, 9.9),
                      row("3", "B", 0.0, 0.5),  # retried: the last row counts
                      row("1", "A", 200.0, 0.2), row("2", "A", 200.0, 0.2),
                      row("3", "B", 200.0, 0.0, status="failed")])
    df = load_results(res)
    assert len(df) == 6
    s = summary(df, "undersegmentation_error")
    # categories weigh the same: (mean(0.1, 0.3) + 0.5) / 2, not mean(0.1, 0.3, 0.5)
    assert s.loc["superfacets α=0", 50] == pytest.approx(0.35)
    assert s.loc["superfacets α=200", 50] == pytest.approx(0.2)  # failed row left out
    text = markdown_summary(df)
    assert "| superfacets α=0 | 0.350 |" in text and "1 failed" in text


def test_report_orders_series_whose_values_mix_numbers_and_words(tmp_path):
    # two files where a parameter was a number in one and "auto" in the other: the
    # series sort numbers first (they once raised a TypeError comparing float and str)
    def row(mesh, ctol, ue):
        return dict(mesh=mesh, mesh_id=mesh, category="A", n_faces=100, method="superfacets",
                    n_segments=50, alpha=200.0, center_tol=ctol, seed=0, status="ok",
                    segments=50, iterations=3, converged="true", seconds=0.1,
                    undersegmentation_error=ue, compactness=4.0, boundary_recall=0.5,
                    achievable_accuracy=0.9, n_ground_truths=1)

    res = tmp_path / "r.csv"
    cols = ["mesh", "mesh_id", "category", "n_faces", "method", "n_segments", "alpha",
            "center_tol",
            "seed", "status", "segments", "iterations", "converged", "seconds",
            "undersegmentation_error", "compactness", "boundary_recall",
            "achievable_accuracy", "n_ground_truths"]
    with open(res, "w", newline="") as f:
        w = csv.DictWriter(f, cols)
        w.writeheader()
        w.writerows([row("1", "auto", 0.1), row("1", "0.05", 0.2), row("1", "0", 0.3)])
    df = load_results(res)
    assert series_order(df) == ["superfacets center_tol=0", "superfacets center_tol=0.05",
                                "superfacets center_tol=auto"]
    assert "center_tol=auto" in markdown_summary(df)


def test_report_pools_files_filters_series_and_draws_cost(tmp_path):
    def row(mesh, method, alpha, ue, faces, seconds, peak):
        return dict(mesh=mesh, mesh_id=mesh, category="A", n_faces=faces, method=method,
                    n_segments=150, alpha=alpha, seed=0, status="ok", segments=150,
                    seconds=seconds, peak_mib=peak, undersegmentation_error=ue,
                    compactness=5.0, boundary_recall=0.8, achievable_accuracy=0.9,
                    n_ground_truths=1)

    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    cols = ["mesh", "mesh_id", "category", "n_faces", "method", "n_segments", "alpha", "seed",
            "status", "segments", "seconds", "peak_mib", "undersegmentation_error",
            "compactness", "boundary_recall", "achievable_accuracy", "n_ground_truths"]
    for path, rows in [(a, [row("1", "superfacets", 0.0, 0.2, 1000, 0.01, 2.0),
                            row("2", "superfacets", 0.0, 0.4, 4000, 0.04, 8.0),
                            row("1", "superfacets", 200.0, 0.1, 1000, 0.01, 2.0)]),
                       (b, [row("1", "ncuts", 100.0, 0.3, 1000, 5.0, 400.0),
                            row("2", "ncuts", 100.0, 0.5, 4000, 80.0, 6000.0)])]:
        with open(path, "w", newline="") as f:
            w = csv.DictWriter(f, cols)
            w.writeheader()
            w.writerows(rows)
    df = load_results([a, b], series=["superfacets α=0", "ncuts"])
    assert set(df["series"]) == {"superfacets α=0", "ncuts"} and len(df) == 4
    with pytest.raises(ParameterError, match="no series 'vsa'.*present: 'superfacets α=0'"):
        load_results([a, b], series=["vsa"])
    text = markdown_summary(df)
    # cost table: medians per series at k = 150
    assert "| ncuts | 2 | 2500 | 42.500 | 80.000 | 3200 | 6000 |" in text
    files = write_report([a, b], tmp_path / "rep", series=["superfacets α=0", "ncuts"])
    assert tmp_path / "rep" / "cost.png" in files
    from PIL import Image

    img = np.asarray(Image.open(tmp_path / "rep" / "cost.png").convert("L"))
    assert img.std() > 10


def test_cli_experiment_report_and_evaluate(bench, tmp_path, capsys):
    res = tmp_path / "r.csv"
    assert main(["experiment", "--psb", str(bench), "-k", "4", "8", "--alpha", "0", "500",
                 "-o", str(res), "-q", "-j", "1", "--categories", "human"]) == 0
    out = capsys.readouterr().out
    assert "8 rows written (8 ok, 0 failed, 0 skipped)" in out
    assert main(["experiment", "--psb", str(bench), "-k", "4", "8", "--alpha", "0", "500",
                 "-o", str(res), "-q", "-j", "1", "--ids", "1-2,21"]) == 0
    assert "4 rows written (4 ok" in capsys.readouterr().out and len(read_results(res)) == 12
    rep = tmp_path / "rep"
    assert main(["report", str(res), "-o", str(rep)]) == 0
    out, err = capsys.readouterr()
    assert "superfacets α=500" in out and "Cup" in out and err == ""  # (no terminal: no line)
    from PIL import Image

    for name in ("fig4", "fig4_extra", "per_category_undersegmentation_error",
                 "per_category_compactness"):
        assert (rep / f"{name}.svg").read_text().lstrip().startswith("<?xml")
        img = np.asarray(Image.open(rep / f"{name}.png").convert("L"))
        assert img.std() > 10  # lines and text, not blank
    # errors: one line, exit 2
    assert main(["experiment", "--psb", str(bench), "-o", str(res), "--ids", "x"]) == 2
    assert main(["experiment", "--psb", str(bench), "-o", str(res), "--ids", "99"]) == 2
    assert main(["experiment", "--psb", str(bench), "-o", str(res), "-m", "nope"]) == 2
    assert main(["experiment", "--psb", str(tmp_path), "-o", str(res)]) == 2
    assert main(["report", str(tmp_path / "missing.csv")]) == 2
    err = capsys.readouterr().err
    assert err.count("superfacets: error:") == 5 and "unknown method 'nope'" in err
    assert "no off/ inside" in err and "missing.csv" in err


def test_cli_list_methods(capsys):
    assert main(["experiment", "--list-methods"]) == 0
    out = capsys.readouterr().out
    assert "superfacets:" in out and "shlafman:" in out and "alpha in 0.0, 100.0" in out


def test_param_syntax_applies_to_each_method_that_has_the_name():
    from superfacets.evaluation.methods import get_method
    from superfacets.scale.runner import method_grid, parse_params

    sf, vsa = get_method("superfacets"), get_method("vsa")
    given = method_grid([sf, vsa], parse_params(["max_iter=5,7", "vsa.metric=l2",
                                                 "superfacets.alpha=0"]))
    assert given == {"superfacets": {"max_iter": ["5", "7"], "alpha": ["0"]},
                     "vsa": {"max_iter": ["5", "7"], "metric": ["l2"]}}
    with pytest.raises(ParameterError, match=r"--param gamma: no method given has it.*vsa: "
                                             r"init, insert_iter, max_iter, metric"):
        method_grid([sf, vsa], parse_params(["gamma=1"]))
    with pytest.raises(ParameterError, match="NAME=V1,V2"):
        parse_params(["alpha"])


def test_experiment_param_reaches_only_the_methods_that_have_it(bench, tmp_path):
    res = tmp_path / "r.csv"
    assert main(["experiment", "--psb", str(bench), "-o", str(res), "-m", "superfacets",
                 "-m", "vsa", "-k", "4", "--ids", "21", "--param", "max_iter=3", "-j", "1",
                 "-q"]) == 0
    rows = read_results(res)
    assert {(r["method"], r["max_iter"]) for r in rows} == {("superfacets", "3"), ("vsa", "3")}
    assert main(["experiment", "--psb", str(bench), "-o", str(res), "--param", "bogus=1",
                 "-q"]) == 2


def test_results_written_with_the_old_superfacets_column_are_read(tmp_path):
    old = tmp_path / "old.csv"
    old.write_text("mesh,method,n_segments,seed,status,superfacets\n1,superfacets,50,0,ok,49\n")
    (row,) = read_results(old)
    assert row["segments"] == "49" and "superfacets" not in row


def test_report_leaves_the_matplotlib_backend_alone(bench, tmp_path):
    import matplotlib

    res = tmp_path / "r.csv"
    run_experiment(list_meshes(bench), expand_grid("superfacets"), res, [4, 6], workers=1,
                   progress=False)
    before = matplotlib.get_backend()
    write_report(res, tmp_path / "rep")
    assert matplotlib.get_backend() == before
    assert (tmp_path / "rep" / "fig4.png").stat().st_size > 1000


def test_an_experiment_bar_is_redrawn_while_a_mesh_runs(bench, tmp_path, monkeypatch,
                                                         capsys):
    """The experiment's bar (its elapsed time) is redrawn every TICK seconds while a mesh
    runs in a worker, not only when its rows arrive, and a baseline's count far from k
    is recorded in the row's `segments`, not warned about."""
    import warnings

    from conftest import slowed

    from superfacets.scale.runner import experiment

    slowed(monkeypatch, experiment, "_run_task")  # (a mesh that takes a while)
    res = tmp_path / "r.csv"
    cfgs = expand_grid("graph_segmentation")
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        s = run_experiment(list_meshes(bench)[:1], cfgs, res, [300], workers=1,
                           progress=True)
    assert s.ok == 1 and not [w for w in seen if "n_segments=300" in str(w.message)]
    assert capsys.readouterr().err.count("experiment") >= 10
    assert int(read_results(res)[0]["segments"]) < 270  # (the mesh holds fewer)


def test_report_shows_a_line_while_it_draws_on_a_terminal(bench, tmp_path, capsys,
                                                          monkeypatch):
    """Drawing a report's figures takes seconds: on a terminal a line says so meanwhile."""
    import sys

    res = tmp_path / "r.csv"
    run_experiment(list_meshes(bench)[:1], expand_grid("superfacets"), res, [4], workers=1,
                   progress=False)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert main(["report", str(res), "-o", str(tmp_path / "rep")]) == 0
    assert f"writing the report to {tmp_path / 'rep'} [" in capsys.readouterr().err

