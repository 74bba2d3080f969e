"""The faults of the tenth attack (the names a user gives outputs and label files from
learning pipelines): each case fails without its fix."""

from __future__ import annotations

import gzip

import numpy as np
import pytest

from superfacets.cli import main
from superfacets.errors import MeshFormatError
from superfacets.io import read_labels


@pytest.fixture()
def cloud(tmp_path):
    xy = np.random.default_rng(0).random((800, 2))
    path = tmp_path / "s.xyz"
    np.savetxt(path, np.c_[xy, 0.1 * np.sin(4 * xy[:, 0])], fmt="%.5f")
    return path


@pytest.mark.parametrize("name, says", [("l.npz", "NumPy's archive"), ("l.h5", "HDF5"),
                                        ("l.pt", "PyTorch"), ("l.parquet", "Parquet"),
                                        ("l.pkl", "pickle"), ("l.zip", "zip")])
def test_labels_are_not_written_as_text_under_a_data_file_s_name(cloud, tmp_path, capsys,
                                                                  name, says):
    # (`-o labels.npz` wrote one label per line as text: np.load then failed on it)
    out = tmp_path / name
    assert main(["segment", str(cloud), "-k", "10", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"not a {out.suffix} file ({says})" in err and "l.npy (np.load)" in err
    assert not out.exists()


def test_compressed_text_labels_are_still_written(cloud, tmp_path):
    out = tmp_path / "l.seg.gz"
    assert main(["segment", str(cloud), "-k", "10", "-o", str(out), "-q"]) == 0
    labels = np.loadtxt(gzip.open(out), dtype=int)
    assert labels.shape == (800,) and np.unique(labels).size == 10


def test_labels_in_an_npz_archive_are_read(cloud, tmp_path, capsys):
    # (a .npz of labels, or the labels `--graph OUT.npz` writes beside the graph, was "not a
    # text file"; a damaged .npy was said in numpy's words about pickles)
    graph = tmp_path / "g.npz"
    seg = tmp_path / "l.seg"
    assert main(["segment", str(cloud), "-k", "10", "--graph", str(graph), "-o", str(seg),
                 "-q"]) == 0
    labels = read_labels(seg)
    assert np.array_equal(read_labels(graph), labels)
    np.savez(tmp_path / "one.npz", anything=labels)
    assert np.array_equal(read_labels(tmp_path / "one.npz"), labels)
    np.savez(tmp_path / "two.npz", a=labels, b=labels)
    with pytest.raises(MeshFormatError, match="one named 'labels'; this one has a, b"):
        read_labels(tmp_path / "two.npz")
    for name in ("bad.npz", "bad.npy"):
        (tmp_path / name).write_text("0\n1\n")
        with pytest.raises(MeshFormatError, match=f"{name}: not a NumPy .np. (file|archive)"):
            read_labels(tmp_path / name)
    assert main(["evaluate", str(cloud), str(graph), str(tmp_path / "one.npz")]) == 0
    assert "undersegmentation" in capsys.readouterr().out


def test_a_ply_asked_of_a_las_names_the_option_that_writes_one(tmp_path, capsys):
    laspy = pytest.importorskip("laspy")
    xy = np.random.default_rng(1).random((600, 2)) * 20
    las = laspy.LasData(laspy.LasHeader(point_format=3, version="1.2"))
    las.x, las.y, las.z = xy[:, 0], xy[:, 1], np.sin(xy[:, 0])
    las.write(str(tmp_path / "t.las"))
    assert main(["segment", str(tmp_path / "t.las"), "-k", "10", "-o",
                 str(tmp_path / "t.ply")]) == 2
    assert "--colored-mesh NAME.ply" in capsys.readouterr().err


def test_a_name_the_terminal_cannot_write_is_escaped_not_a_traceback(cloud, tmp_path):
    # (PYTHONIOENCODING=ascii, or a terminal of another encoding: the summary naming
    # `scän.xyz` raised UnicodeEncodeError after the labels were written, exit status 1)
    import os
    import subprocess
    import sys

    src = tmp_path / "scän é.xyz"
    src.write_bytes(cloud.read_bytes())
    env = dict(os.environ, PYTHONIOENCODING="ascii", LC_ALL="C")
    out = subprocess.run([sys.executable, "-m", "superfacets", "segment", str(src), "-k", "10",
                          "-o", str(tmp_path / "ö.seg")], capture_output=True, text=True,
                         env=env, encoding="ascii", errors="replace")
    assert out.returncode == 0 and "Traceback" not in out.stderr, out.stderr
    assert "sc\\xe4n \\xe9.xyz: 800 points" in out.stdout
    assert (tmp_path / "ö.seg").exists()


def test_evaluate_names_the_input_and_the_elements_its_labels_do_not_match(tmp_path, capsys):
    # ("vb.seg: has 35947 labels but the input has 69451 elements": vertex labels of a mesh
    # given to evaluate, which judges faces unless --elements vertices)
    import trimesh

    from superfacets import write_mesh

    mesh = tmp_path / "ball.off"
    write_mesh(mesh, trimesh.creation.icosphere(3))
    vertices = tmp_path / "v.seg"
    assert main(["segment", str(mesh), "--elements", "vertices", "-k", "8", "-o",
                 str(vertices), "-q"]) == 0
    assert main(["evaluate", str(mesh), str(vertices)]) == 2
    err = capsys.readouterr().err
    assert f"v.seg: 642 labels, but {mesh} has 1,280 faces (one label per face" in err
    assert "they are one per vertex: --elements vertices" in err
    assert main(["evaluate", str(mesh), str(vertices), "--elements", "vertices"]) == 0


def test_a_result_given_for_labels_is_named_with_what_to_pass(tmp_path):
    # (`write_labels("out.seg", segment(...))`: "labels must be a 1-D array of integers, one
    # per element; got shape (), dtype object")
    from superfacets import ParameterError, segment, segment_tiled, write_labels

    xyz = np.random.default_rng(0).random((1500, 3)) * [1, 1, 0.1]
    for result in (segment(xyz, 10), segment_tiled(xyz, 10, tiles=2, workers=1)):
        with pytest.raises(ParameterError, match=f"got a {type(result).__name__}; pass its "
                                                 r"labels \(result.labels\)"):
            write_labels(tmp_path / "l.seg", result)
        assert write_labels(tmp_path / "l.seg", result.labels).exists()


def test_a_results_file_edited_by_hand_is_read_or_named_not_a_traceback(tmp_path, capsys):
    # (`report` on a results file re-saved by a spreadsheet (a BOM), with a metric's column
    # cut, or a word, 'ten', or 1e308 in a number's place: KeyError, ValueError tracebacks)
    import csv

    from superfacets.evaluation.report import load_results

    row = dict(mesh="a", mesh_id="a", category="scan", method="superfacets", n_segments=10,
               alpha=200.0, seed=0, status="ok", segments=10, iterations=3,
               converged="true", seconds=0.1, undersegmentation_error=0.2, compactness=4.0,
               boundary_recall=0.5, achievable_accuracy=0.9, n_ground_truths=1)

    def write(name, rows, encoding="utf-8", keys=tuple(row)):
        path = tmp_path / name
        with path.open("w", newline="", encoding=encoding) as f:
            w = csv.DictWriter(f, list(keys), extrasaction="ignore")
            w.writeheader()
            w.writerows(rows)
        return path

    spreadsheet = write("bom.csv", [row, dict(row, mesh="b", mesh_id="b")], "utf-8-sig")
    assert len(load_results(spreadsheet)) == 2
    cut = write("cut.csv", [row], keys=[k for k in row if k != "undersegmentation_error"])
    assert load_results(cut)["undersegmentation_error"].isna().all()
    assert main(["report", str(cut), "-o", str(tmp_path / "rep")]) == 0
    assert "per_category_undersegmentation_error" in capsys.readouterr().out  # (not drawn)
    for value, column in (("ten", "n_segments"), ("1e308", "undersegmentation_error"),
                          ("abc", "compactness")):
        bad = write(f"{column}.csv", [dict(row, **{column: value})])
        assert main(["report", str(bad), "-o", str(tmp_path / "r2")]) == 2
        assert f"has {column} = {value}, which no run records" in capsys.readouterr().err
    (tmp_path / "semi.csv").write_text(spreadsheet.read_text(encoding="utf-8-sig")
                                       .replace(",", ";"))
    assert main(["report", str(tmp_path / "semi.csv"), "-o", str(tmp_path / "r3")]) == 2
    assert "separated by ';'" in capsys.readouterr().err
