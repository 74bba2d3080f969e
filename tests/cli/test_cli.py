import json
import os
import re
import sys

import numpy as np
import pytest
import trimesh
from conftest import MESHES, need

from superfacets import read_labels, read_mesh, segment, write_mesh
from superfacets.cli import main


@pytest.fixture
def small_off(tmp_path, sphere):
    return write_mesh(tmp_path / "sphere.off", sphere)


def test_segment_writes_labels_colored_mesh_and_summary(tmp_path, small_off, capsys):
    seg, ply = tmp_path / "out.seg", tmp_path / "out.ply"
    assert main(["segment", str(small_off), "-k", "30", "--alpha", "200", "-o", str(seg),
                 "--colored-mesh", str(ply)]) == 0
    line, wrote = capsys.readouterr().out.strip().splitlines()
    assert line.startswith("sphere.off: 5,120 faces, 30 superfacets,") and line.endswith(" s")
    assert wrote == f"wrote {seg} (labels), {ply} (coloured mesh)"
    labels = read_labels(seg, n_faces=5120)
    assert labels.max() + 1 == 30
    sizes = np.bincount(labels)  # the summary says how even they are, and how wide
    areas = np.bincount(labels, weights=read_mesh(small_off).areas)
    wide = 2 * np.sqrt(np.median(areas) / np.pi)  # (a disc of the median area)
    assert (f", {sizes.min():,} to {sizes.max():,} faces each (median "
            f"{np.median(sizes):,.0f}, about {wide:.3g} wide in the data's units)") in line
    assert not seg.read_text().startswith("#")
    assert read_mesh(ply).n_faces == 5120


def test_threads_option_gives_the_same_labels(tmp_path, small_off):
    outs = []
    for n in ("1", "2"):
        outs.append(tmp_path / f"t{n}.seg")
        assert main(["segment", str(small_off), "-k", "40", "--threads", n, "-o",
                     str(outs[-1]), "-q"]) == 0
    assert outs[0].read_text() == outs[1].read_text()
    assert main(["segment", str(small_off), "--threads", "0", "-q"]) == 2


def test_the_command_line_keeps_few_allocator_arenas(tmp_path, small_off, monkeypatch):
    # before any thread starts: each thread's arena would keep what its kernels freed
    from superfacets._runtime import memory

    calls = []
    monkeypatch.setattr(memory, "limit_arenas", lambda n=memory.ARENAS: calls.append(n))
    assert main(["segment", str(small_off), "-k", "10", "-o", str(tmp_path / "a.seg"),
                 "-q"]) == 0
    assert calls == [2]
    if memory._libc("mallopt", ("c_int", "c_int")):  # glibc: the option is one it takes
        assert memory._libc("mallopt", ("c_int", "c_int"))(-8, 2) == 1


def test_header_option(tmp_path, small_off, capsys):
    seg = tmp_path / "h.seg"
    assert main(["segment", str(small_off), "--radius", "0.1", "--init", "grid", "-o", str(seg),
                 "--header", "-q"]) == 0
    assert capsys.readouterr().out == ""
    text = seg.read_text()
    assert "# parameters:" in text and "init=grid" in text and "# iterations:" in text
    assert "center_tol=0.05" in text and "coarsen=1" in text  # the resolved tolerances
    assert read_labels(seg, n_faces=5120).shape == (5120,)


@pytest.mark.parametrize("args, match", [
    (["segment", "{missing}"], "no such file"),
    (["segment", "{bad}"], "expected 2 faces, found 1"),
    (["segment", "{off}", "-k", "0"], "n_segments must be an integer >= 1"),
    (["segment", "{off}", "-k", "999999"], "larger than the number of faces"),
    (["segment", "{off}", "--alpha", "-1"], "alpha must be a finite number in [0, 1e+12]"),
    (["segment", "{off}", "-o", "{nodir}"], "does not exist"),
    (["segment", "{off}", "--colored-mesh", "{txt}"], "must end in .ply"),
    (["segment", "{off}", "--center-tol", "1.5"], "center_tol must be a finite number in [0, 1]"),
    (["segment", "{off}", "--coarsen", "0"], "coarsen must be an integer >= 1"),
])
def test_bad_input_one_line_exit_2_no_output(tmp_path, small_off, capsys, args, match):
    bad = tmp_path / "bad.off"
    bad.write_text("OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n")
    names = dict(missing=str(tmp_path / "none.off"), bad=str(bad), off=str(small_off),
                 nodir=str(tmp_path / "no" / "x.seg"), txt=str(tmp_path / "x.txt"))
    out = tmp_path / "result.seg"
    argv = [a.format(**names) for a in args] + (["-o", str(out)] if "-o" not in args else [])
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("superfacets: error: ")
    assert match in err[0]
    assert "Traceback" not in err[0]
    assert not out.exists()


def test_both_k_and_radius_is_a_usage_error(small_off, capsys):
    with pytest.raises(SystemExit) as info:
        main(["segment", str(small_off), "-k", "5", "--radius", "0.1"])
    assert info.value.code == 2
    assert "not allowed with" in capsys.readouterr().err


def test_help_lists_every_option_with_default(capsys):
    with pytest.raises(SystemExit):
        main(["segment", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for opt in ["-k", "--radius", "--alpha", "--eta-convex", "--init", "--window", "--max-iter",
                "-o", "--header", "--colored-mesh", "--assignment", "--no-connectivity",
                "--tol", "--center-tol", "--coarsen"]:
        assert opt in text
    assert "(default: 200)" in text and "(default: 0.2)" in text and "(default: 50)" in text


def test_demo(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--output-dir", str(out), "--resolution", "40", "-k", "20"]) == 0
    mesh = read_mesh(out / "creature.off")
    labels = read_labels(out / "creature.seg", n_faces=mesh.n_faces)
    assert labels.max() + 1 == 20
    assert (out / "creature_superfacets.ply").exists()
    assert '"superfacets": 20' in (out / "creature.html").read_text()
    from PIL import Image

    assert Image.open(out / "creature.png").size == (1000, 750)
    assert "creature:" in capsys.readouterr().out


def test_horse_as_in_the_issue(tmp_path, capsys):
    horse = need(MESHES / "horse.tri.xz")
    seg, ply = tmp_path / "horse.seg", tmp_path / "horse.ply"
    assert main(["segment", str(horse), "-k", "150", "--alpha", "200", "-o", str(seg),
                 "--colored-mesh", str(ply)]) == 0
    labels = read_labels(seg, n_faces=96966)
    assert 140 <= labels.max() + 1 <= 170
    assert len(np.unique(labels)) == labels.max() + 1


def test_evaluate_one_call(tmp_path, capsys):
    from conftest import grid_mesh

    from superfacets import write_labels

    mesh = grid_mesh(20, 20)
    off = write_mesh(tmp_path / "plane.off", mesh)
    x = mesh.centroids[:, 0]
    gt = write_labels(tmp_path / "gt.seg", (x > 0).astype(int))
    sf = write_labels(tmp_path / "sf.seg", np.searchsorted([-0.5, 0.0, 0.5], x))
    assert main(["evaluate", str(off), str(sf), str(gt), str(gt)]) == 0
    out = capsys.readouterr().out
    assert "4 superfacets, 2 ground truths" in out
    assert "undersegmentation_error 0.0000" in out and "boundary_recall         1.0000" in out
    # three borders of equal length, one of them the true one
    assert "boundary_precision      0.3333" in out
    assert capsys.readouterr().err == ""  # (no terminal, and small: no bar)
    bad = tmp_path / "short.seg"
    bad.write_text("0\n1\n")
    assert main(["evaluate", str(off), str(sf), str(bad)]) == 2
    assert (f"short.seg: 2 labels, but {off} has 800 faces (one label per face is needed)"
            in capsys.readouterr().err)


def test_evaluate_points_and_vertices_with_unlabelled_rows(tmp_path, capsys):
    """A labelled scan: one label per point in file order; ``--ignore-label`` leaves the
    unlabelled points out. A mesh's vertex labels with ``--elements vertices``."""
    from conftest import grid_mesh

    from superfacets import write_labels

    rng = np.random.default_rng(0)
    xy = rng.random((3000, 2))
    np.save(tmp_path / "scan.npy", np.c_[xy, np.zeros(3000)])
    truth = (xy[:, 0] > 0.5).astype(int)
    truth[xy[:, 0] < 0.1] = -1  # unlabelled strip
    gt = write_labels(tmp_path / "gt.seg", truth)
    # superpoints: the strip and the left half together, the right half alone
    sp = write_labels(tmp_path / "sp.seg", (xy[:, 0] > 0.5).astype(int))
    assert main(["evaluate", str(tmp_path / "scan.npy"), str(sp), str(gt),
                 "--ignore-label", "-1"]) == 0
    out = capsys.readouterr().out
    assert "3,000 points, 2 superpoints, 1 ground truth" in out
    assert "undersegmentation_error 0.0000" in out and "achievable_accuracy     1.0000" in out
    assert "boundary_precision      1.0000" in out  # its one border is the true one
    assert main(["evaluate", str(tmp_path / "scan.npy"), str(sp), str(gt)]) == 0
    assert "undersegmentation_error 0.0000" not in capsys.readouterr().out  # -1 is a class
    from superfacets.errors import ParameterError
    from superfacets.evaluation.metrics import oracle_miou

    # every point noise (below 0): said so, with the file (it said "no labelled element")
    noise = write_labels(tmp_path / "noise.seg", np.full(3000, -1))
    assert main(["evaluate", str(tmp_path / "scan.npy"), str(noise), str(gt)]) == 2
    assert "noise.seg: every label is below 0" in capsys.readouterr().err
    with pytest.raises(ParameterError, match="every label is below 0"):
        oracle_miou(np.full(4, -1), np.zeros(4, int))
    with pytest.raises(ParameterError, match="the ground truth is 7 wherever a label is 0"):
        oracle_miou(np.zeros(4, int), np.full(4, 7), ignore_label=7)
    mesh = grid_mesh(10, 10)
    off = write_mesh(tmp_path / "plane.off", mesh)
    vx = write_labels(tmp_path / "v.seg", (mesh.vertices[:, 0] > 0).astype(int))
    assert main(["evaluate", str(off), str(vx), str(vx), "--elements", "vertices"]) == 0
    out = capsys.readouterr().out
    assert "121 vertices, 2 superpoints" in out and "boundary_recall         1.0000" in out
    assert main(["evaluate", str(tmp_path / "scan.npy"), str(sp), str(gt), "--elements",
                 "vertices"]) == 2
    assert "point cloud" in capsys.readouterr().err


def test_evaluate_reads_a_ground_truth_field_of_the_input(tmp_path, capsys):
    """A LAS file's classification and a PLY's vertex label as the ground truth; a missing
    field or none at all is one clear error."""
    laspy = pytest.importorskip("laspy")
    from plyfile import PlyData, PlyElement

    from superfacets import write_labels
    from superfacets.io.labels import read_field

    rng = np.random.default_rng(1)
    xy = rng.random((2000, 2))
    classes = np.where(xy[:, 0] > 0.5, 6, 2).astype(np.uint8)  # building | ground
    classes[:100] = 0  # never classified
    header = laspy.LasHeader(point_format=1, version="1.2")
    header.scales = [0.0001] * 3
    las = laspy.LasData(header)
    las.x, las.y, las.z = xy[:, 0], xy[:, 1], np.zeros(2000)
    las.classification = classes
    las.write(tmp_path / "scan.las")
    np.testing.assert_array_equal(read_field(tmp_path / "scan.las", "classification"), classes)
    sp = write_labels(tmp_path / "sp.seg", (xy[:, 0] > 0.5).astype(int))
    assert main(["evaluate", str(tmp_path / "scan.las"), str(sp), "--ground-truth-field",
                 "classification", "--ignore-label", "0"]) == 0
    out = capsys.readouterr().out
    assert "2,000 points, 2 superpoints, 1 ground truth" in out
    assert "undersegmentation_error 0.0000" in out
    vertex = np.empty(2000, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("label", "i4")])
    vertex["x"], vertex["y"], vertex["z"] = xy[:, 0], xy[:, 1], 0
    vertex["label"] = classes
    PlyData([PlyElement.describe(vertex, "vertex")]).write(str(tmp_path / "scan.ply"))
    np.testing.assert_array_equal(read_field(tmp_path / "scan.ply", "label"), classes)
    assert main(["evaluate", str(tmp_path / "scan.ply"), str(sp), "--ground-truth-field",
                 "label", "--ignore-label", "0"]) == 0
    out = capsys.readouterr().out
    assert "undersegmentation_error 0.0000" in out and "  class 6      IoU 1.0000" in out
    # a field that is no labels (a coordinate): its classes counted, not listed, and asked
    # about
    assert main(["evaluate", str(tmp_path / "scan.las"), str(sp), "--ground-truth-field",
                 "X"]) == 0
    out = capsys.readouterr().out
    assert "  class " not in out and "1,831 classes: each one's IoU with --json" in out
    assert "has 1,831 classes for 2,000 points: is it a field of labels?" in out
    # a ground-truth file after an option is still a ground truth (argparse left it over)
    assert main(["evaluate", str(tmp_path / "scan.las"), str(sp), "--ground-truth-field",
                 "classification", str(sp), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["ground_truths"] == 2
    for args, said in ((["evaluate", str(sp), "--json", str(sp), "--csv2"],
                        "--csv2: did you mean --csv?"),
                       (["render", str(sp), str(sp), "-o", str(tmp_path / "x.png")],
                        "unrecognized arguments: " + str(sp))):
        with pytest.raises(SystemExit):  # (refused, as before)
            main([args[0], str(tmp_path / "scan.las"), *args[1:]])
        assert said in capsys.readouterr().err
    # a ground-truth file given to the field's option; by name it is a ground truth
    gt_file = "after the labels: superfacets evaluate INPUT LABELS " + str(sp)
    for args, msg in ((["--ground-truth-field", "klass"], "no field 'klass'; it has: "),
                      (["--ground-truth-field", str(sp)], gt_file),
                      (["--ground-truth-field", "gt.seg"], "not a file ('gt.seg')")):
        assert main(["evaluate", str(tmp_path / "scan.las"), str(sp), *args]) == 2
        err = capsys.readouterr().err
        assert msg in err and "Traceback" not in err
    assert main(["evaluate", str(tmp_path / "scan.las"), str(sp), "--ground-truth", str(sp),
                 "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["ground_truths"] == 1
    np.save(tmp_path / "scan.npy", np.c_[xy, np.zeros(2000)])
    assert main(["evaluate", str(tmp_path / "scan.npy"), str(sp), "--ground-truth-field",
                 "label"]) == 2
    assert "NPY array of plain numbers (float64) has no fields" in capsys.readouterr().err
    np.savetxt(tmp_path / "scan.xyz", np.c_[xy, np.zeros(2000)])
    assert main(["evaluate", str(tmp_path / "scan.xyz"), str(sp), "--ground-truth-field",
                 "label"]) == 2
    assert "a text cloud whose columns are its points' alone has no fields" in \
        capsys.readouterr().err
    (tmp_path / "cut.ply").write_text("ply\nformat ascii 1.0\nelement vertex 3\n"
                                      "property float x\nend_header\n1\n2\n")
    with pytest.raises(ValueError, match="cannot read PLY vertices"):
        read_field(tmp_path / "cut.ply", "label")


def test_progress_bar_names_the_stages_then_counts_passes(tmp_path, small_off, capsys):
    assert main(["segment", str(small_off), "-k", "20", "--progress", "-q"]) == 0
    err = capsys.readouterr().err
    for stage in ("reading sphere.off", "face graph", "weights", "init (farthest)",
                  "superfacets", "connectivity", "clean-up"):
        assert stage in err, stage
    # no remaining time reckoned from --max-iter (it read "03:46 remaining" just before
    # the end): the passes to come are guessed from how fast the movers fall
    assert "pass [" in err and "/50" not in err
    rng = np.random.default_rng(0)
    cloud = tmp_path / "plane.npy"
    np.save(cloud, np.c_[rng.random((20000, 2)), np.zeros(20000)])
    assert main(["segment", str(cloud), "-k", "300", "--progress", "-q"]) == 0
    err = capsys.readouterr().err
    totals = [int(t) for t in re.findall(r"\| *\d+/(\d+) \[", err)]
    assert totals and max(totals) < 50 and "merges to the count" in err
    assert main(["segment", str(small_off), "-k", "20", "-q"]) == 0  # small mesh: no bar
    assert capsys.readouterr().err == ""
    # the outputs written under a bar of their own (a large mesh's picture takes seconds)
    assert main(["segment", str(small_off), "-k", "20", "--progress", "-q", "-o",
                 str(tmp_path / "o.seg"), "--html", str(tmp_path / "o.html")]) == 0
    assert "writing o.seg, o.html [" in capsys.readouterr().err
    assert main(["segment", str(small_off), "-k", "20", "-q", "-o", str(tmp_path / "o.seg")]) == 0
    assert capsys.readouterr().err == ""



@pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX")
def test_progress_shows_on_a_terminal_that_reports_no_width(tmp_path, small_off):
    """A pseudo-terminal opened without a size reports 0 columns, and tqdm drew nothing
    there: a long run stayed silent to its end. The bars are 80 columns wide there."""
    import pty
    import select
    import subprocess

    leader, follower = pty.openpty()  # (no size set: 0 x 0)
    assert os.get_terminal_size(follower).columns == 0
    proc = subprocess.Popen([sys.executable, "-m", "superfacets", "segment", str(small_off),
                             "-k", "20", "--progress", "-q"], stdin=follower,
                            stdout=follower, stderr=follower, close_fds=True)
    os.close(follower)
    seen = b""
    while True:
        ready, _, _ = select.select([leader], [], [], 60)
        try:
            chunk = os.read(leader, 65536) if ready else b""
        except OSError:  # (the other end closed: the run is over)
            chunk = b""
        if not chunk:
            break
        seen += chunk
    os.close(leader)
    assert proc.wait(timeout=60) == 0
    assert b"face graph" in seen and b"superfacets" in seen and b"pass" in seen


def test_cleanup_option(tmp_path, small_off):
    out = {}
    for flag in ("--cleanup", "--no-cleanup"):
        out[flag] = tmp_path / f"{flag[2:]}.seg"
        assert main(["segment", str(small_off), "-k", "30", flag, "-o", str(out[flag]),
                     "--header", "-q"]) == 0
    clean = read_labels(out["--cleanup"], n_faces=5120)
    paper = read_labels(out["--no-cleanup"], n_faces=5120)
    assert clean.max() == paper.max() == 29 and not np.array_equal(clean, paper)
    mesh = read_mesh(small_off)
    assert np.array_equal(paper, segment(mesh, 30, cleanup=False).labels)
    assert np.array_equal(clean, segment(mesh, 30, cleanup=True).labels)
    assert " cleanup=True " in out["--cleanup"].read_text().split("\n", 4)[3]  # the header
    assert " cleanup=False " in out["--no-cleanup"].read_text().split("\n", 4)[3]


def test_summary_names_the_coarse_run(small_off, capsys):
    assert main(["segment", str(small_off), "-k", "2", "--coarsen", "16"]) == 0
    out = capsys.readouterr().out
    assert "clusters (coarse-to-fine)" in out and "5,120 faces, 2 superfacets" in out


def test_split_merge_flag_runs_the_swaps_and_names_them(small_off, tmp_path, capsys):
    out = tmp_path / "sm.seg"
    assert main(["segment", str(small_off), "-k", "30", "--split-merge", "-o", str(out),
                 "--header"]) == 0
    said = capsys.readouterr().out
    r = segment(read_mesh(small_off), 30, split_merge=True)
    assert f", {r.timings['swaps']} split-and-merge swaps, " in said
    assert np.array_equal(read_labels(out, n_faces=5120), r.labels)
    assert " split_merge=True " in out.read_text().split("\n", 4)[3]  # the header


# --- the first hour of a new user (issue 34) -----------------------------------------------

def test_segment_lists_the_files_it_wrote_and_the_picture_axis(tmp_path, small_off, capsys):
    pytest.importorskip("pyvista")
    seg, png = tmp_path / "s.seg", tmp_path / "s.png"
    assert main(["segment", str(small_off), "-k", "20", "-o", str(seg), "--picture",
                 str(png)]) == 0
    out, err = capsys.readouterr()
    assert f"wrote {seg} (labels), {png} (picture, up axis y (the default; --up z" in out
    assert "nothing was saved" not in out + err
    assert main(["segment", str(small_off), "-k", "20", "--picture", str(png), "--up", "z"]) == 0
    out, err = capsys.readouterr()
    assert f"wrote {png} (picture, up axis z)" in out and "nothing was saved" not in err
    stl = tmp_path / "part.stl"  # an STL stands on z, as CAD and 3D printing write it
    m = read_mesh(small_off)
    trimesh.Trimesh(m.vertices, m.faces, process=False).export(stl)
    assert main(["segment", str(stl), "-k", "20", "--picture", str(png)]) == 0
    assert "up axis z (STL's convention)" in capsys.readouterr().out
    assert main(["segment", str(small_off), "-k", "20"]) == 0
    assert "nothing was saved" in capsys.readouterr().err


@pytest.mark.parametrize("name, option", [("x.ply", "--colored-mesh"), ("x.obj", "--colored-mesh"),
                                          ("x.png", "--picture"), ("x.html", "--html"),
                                          ("x.off", None), ("x.pcd", None)])
def test_labels_to_a_mesh_or_picture_name_are_refused(tmp_path, small_off, capsys, name,
                                                      option):
    assert main(["segment", str(small_off), "-k", "20", "-o", str(tmp_path / name)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("superfacets: error: ") and "-o writes the labels as text" in err
    assert (f"use {option} {name}" in err) if option else "use --" not in err
    assert list(tmp_path.iterdir()) == [small_off]


def test_labels_to_text_names_are_written(tmp_path, small_off):
    for name in ("x.seg", "x.txt", "x.labels", "x.json"):
        assert main(["segment", str(small_off), "-k", "20", "-q", "-o", str(tmp_path / name)]) == 0
        assert (tmp_path / name).is_file()


def test_a_folder_points_to_batch(tmp_path, capsys):
    assert main(["segment", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "is a directory" in err and f"superfacets batch {tmp_path} -o OUTDIR" in err


@pytest.mark.parametrize("typo, hint", [("--k", "did you mean -k?"),
                                        ("--n_segments", "did you mean --n-segments"),
                                        ("--colored_mesh", "did you mean --colored-mesh?")])
def test_a_misspelt_option_is_named(small_off, capsys, typo, hint):
    with pytest.raises(SystemExit) as info:
        main(["segment", str(small_off), typo, "10"])
    assert info.value.code == 2
    assert hint in capsys.readouterr().err


def test_more_superfacets_than_k_says_why(tmp_path, capsys):
    import trimesh

    from superfacets import Mesh

    parts = []
    for i in range(12):  # twelve separate balls in a row, of very different sizes
        s = trimesh.creation.icosphere(2, radius=0.1 + 0.08 * i)
        s.apply_translation([4.0 * i, 0, 0])
        parts.append(s)
    joined = trimesh.util.concatenate(parts)
    off = write_mesh(tmp_path / "balls.off", Mesh(joined.vertices, joined.faces))
    assert main(["segment", str(off), "-k", "8", "-q", "-o", str(tmp_path / "a.seg")]) == 0
    assert capsys.readouterr().err == ""  # quiet: nothing
    assert main(["segment", str(off), "-k", "8", "-o", str(tmp_path / "a.seg")]) == 0
    err = capsys.readouterr().err
    assert "12 superfacets for -k 8: the input has 12 separate pieces" in err
    assert "12 is the fewest this input can have" in err
    labels = read_labels(tmp_path / "a.seg")
    assert labels.max() + 1 == 12
    assert main(["segment", str(off), "-k", "20", "-o", str(tmp_path / "b.seg")]) == 0
    err = capsys.readouterr().err
    n = read_labels(tmp_path / "b.seg").max() + 1
    if n > 20:  # regions with no center became superfacets of their own: said, with a k
        assert f"{n} superfacets for -k 20: the input has 12 separate pieces" in err
        assert "about -k" in err
    else:
        assert "note:" not in err
    # the paper's farthest points miss two beads above a slab: each becomes a
    # superfacet of its own beyond the 10 asked, said; by default 10 are 10
    from conftest import slab_and_beads

    beads = write_mesh(tmp_path / "beads.off", slab_and_beads()[0])
    assert main(["segment", str(beads), "-k", "10", "--paper", "-o", str(tmp_path / "c.seg")]) == 0
    err = capsys.readouterr().err
    assert read_labels(tmp_path / "c.seg").max() + 1 == 12
    assert "12 superfacets for -k 10: the input has 3 separate pieces" in err
    assert "a region cannot cross from one piece to another" in err and "about -k 8" in err
    assert main(["segment", str(beads), "-k", "10", "-o", str(tmp_path / "d.seg")]) == 0
    assert read_labels(tmp_path / "d.seg").max() + 1 == 10
    assert "note:" not in capsys.readouterr().err


def test_interrupt_helpers():
    from superfacets import cli

    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise SystemError("returned a result with an exception set")
    except SystemError as exc:
        assert cli._interrupted(exc)
    assert not cli._interrupted(SystemError("other"))
    code = compile("f = sys._getframe()", "<frozen importlib._bootstrap>", "exec")
    ns = {"sys": __import__("sys")}
    exec(code, ns)
    assert cli._in_machinery(ns["f"])
    assert not cli._in_machinery(__import__("sys")._getframe())


def _non_default(p):
    """A value of parameter ``p`` other than its default, and its command-line words."""
    from superfacets.cli.parameters import SHOWN

    style = SHOWN.get(p.name, ("", None, ""))[1]
    if style in ("switch", "negated"):
        return (not p.default), [p.cli]
    if style == "both":
        value = not p.default if p.default is not None else False
        return value, [p.cli if value else "--no-" + p.cli[2:]]
    if p.choices:
        value = next(c for c in p.choices if c != p.default)
        extra = ["--alpha", "0.5"] if value == "shlafman" else []  # (its alpha's range)
        return value, [p.cli, value, *extra]
    special = {"n_segments": 7, "radius": 0.3, "n_threads": 1, "elements": "faces",
               "center_tol": 0.01, "coarsen": 3, "density": 0.25, "merge_from": 2,
               "tol": 0.01, "neighbor_radius": 0.2, "n_neighbors": 6, "max_iter": 9,
               "window": 1.5, "min_elements": 2, "max_size_ratio": 4.0, "step_weight": 2.0}
    value = special.get(p.name, 0.125 if "float" in p.type else 3)
    return value, [p.cli, str(value)]


def test_every_parameter_has_an_option_that_reaches_the_run(monkeypatch, small_off,
                                                              tmp_path):
    """The options are made from the declarations (PARAMETERS): each one, given on the
    command line, arrives in the run's parameters (a forgotten entry would be dropped)."""
    import superfacets.api.segmentation as api
    from superfacets.method.params import PARAMETERS

    seen = []

    def record(mesh, params, **kw):
        seen.append(params)
        raise SystemExit(0)

    monkeypatch.setattr(api, "pipeline", record)
    cloud = tmp_path / "c.xyz"  # (a cloud's neighbourhood: refused for a mesh's faces)
    np.savetxt(cloud, np.random.default_rng(0).random((200, 3)))
    for p in PARAMETERS:
        assert p.cli, f"{p.name} has no option"
        value, words = _non_default(p)
        size = [] if p.name in ("n_segments", "radius") else ["-k", "5"]
        given = cloud if p.name in ("n_neighbors", "neighbor_radius") else small_off
        seen.clear()
        with pytest.raises(SystemExit):
            main(["segment", str(given), *size, *words, "-o", str(tmp_path / "x.seg")])
        assert seen, p.name
        got = getattr(seen[0], p.name)
        assert got == value or (p.name == "n_threads" and got == 1), (p.name, got, value)


def test_pictures_of_a_cloud_with_an_up_axis_stand_on_it():
    """A LAS cloud is read with z up: its pictures are upright without --up (y stays the
    default where the input says nothing; --up wins)."""
    from types import SimpleNamespace

    from superfacets.cli.options import up_of

    las = SimpleNamespace(up=np.array([0.0, 0.0, 1.0]))
    assert up_of(SimpleNamespace(up=None), las) == ("z", "the file's")
    assert up_of(SimpleNamespace(up=None), SimpleNamespace(up=np.array([0.0, -2.0, 0.1])))[0] \
        == "-y"
    assert up_of(SimpleNamespace(up="x"), las) == ("x", "--up")
    mesh = SimpleNamespace()  # a mesh: its format's convention, else y
    assert up_of(SimpleNamespace(up=None, mesh="a.stl.gz"), mesh) == ("z", "STL's convention")
    assert up_of(SimpleNamespace(up=None, mesh="a.glb"), mesh) == ("y", "GLB's convention")
    assert up_of(SimpleNamespace(up=None, mesh="a.off"), mesh) == ("y", "the default")
    assert up_of(SimpleNamespace(up=None), SimpleNamespace()) == ("y", "the default")


def test_the_summary_is_in_the_singular_where_there_is_one(tmp_path, small_off, capsys):
    assert main(["segment", str(small_off), "-k", "1", "-o", str(tmp_path / "one.seg")]) == 0
    line = capsys.readouterr().out.splitlines()[0]
    assert ", 1 superfacet, 1 iteration (" in line and "1 superfacets" not in line


def test_compressed_inputs_show_the_reading_bar_from_a_smaller_size(tmp_path, monkeypatch):
    """A compressed file takes longer to read a byte (a LAZ tile of 3 MiB holds 0.7M
    points): on a terminal its reading bar shows from 4 MiB, a plain file's from 32."""
    from types import SimpleNamespace

    from superfacets.cli import reading, segmenting

    assert reading.COMPRESSED_BAR_BYTES < 5 << 20 <= reading.READING_BAR_BYTES
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    for name in ("m.ply", "m.ply.gz", "s.laz"):
        (tmp_path / name).write_bytes(b"\0" * (5 << 20))
        args = SimpleNamespace(mesh=str(tmp_path / name), progress=None, quiet=False)
        assert segmenting._reading_bar(args).show == (name != "m.ply"), name
    args = SimpleNamespace(mesh=str(tmp_path / "s.laz"), progress=None, quiet=True)
    assert not segmenting._reading_bar(args).show


def test_evaluate_shows_its_long_stages_on_a_terminal(tmp_path, capsys, monkeypatch):
    """Measuring millions of faces takes seconds (6.8M faces: 6.7 s of silence): on a
    terminal the labels' reading and the measuring each show a line, its time going on."""
    from conftest import grid_mesh

    from superfacets import write_labels
    from superfacets.cli import reading

    mesh = grid_mesh(20, 20)
    off = write_mesh(tmp_path / "plane.off", mesh)
    gt = write_labels(tmp_path / "gt.seg", (mesh.centroids[:, 0] > 0).astype(int))
    monkeypatch.setattr(reading, "LONG_ELEMENTS", 100)  # (as if it were large)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert main(["evaluate", str(off), str(gt), str(gt)]) == 0
    err = capsys.readouterr().err
    assert "reading the labels of 800 faces [" in err and "measuring plane.off (800 faces) [" in err



def test_html_shows_its_long_stages_on_a_terminal(tmp_path, capsys, monkeypatch):
    """A page of millions of faces takes seconds to segment and write (6.8M faces: 7.3 s
    of silence): on a terminal the segmentation shows its bars and the writing a line."""
    from conftest import grid_mesh

    from superfacets.cli import reading

    off = write_mesh(tmp_path / "plane.off", grid_mesh(20, 20))
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert main(["html", str(off), "-k", "5", "-o", str(tmp_path / "p.html"), "-q"]) == 0
    assert capsys.readouterr().err == ""  # (-q: nothing)
    monkeypatch.setattr(reading, "LONG_ELEMENTS", 100)  # (as if it were large)
    assert main(["html", str(off), "-k", "5", "-o", str(tmp_path / "p.html")]) == 0
    err = capsys.readouterr().err
    assert "face graph" in err and "writing p.html [" in err


def test_the_summary_says_a_scene_merges_from_twenty_times_k(tmp_path, capsys):
    """A LAS file has an up direction: a scene, merged from 20 times -k with no superpoint
    above 4 times the mean, which the summary says; the same points as an array (no up
    direction) merge from 5 times, bounded at 16; a given --merge-from is not put down to
    the scene."""
    laspy = pytest.importorskip("laspy")
    rng = np.random.default_rng(3)
    xy = rng.random((6000, 2)) * 50
    z = 0.02 * rng.standard_normal(6000) + np.where(xy[:, 0] > 25, 3.0, 0.0)
    header = laspy.LasHeader(point_format=1, version="1.2")
    header.scales = [0.001] * 3
    las = laspy.LasData(header)
    las.x, las.y, las.z = xy[:, 0], xy[:, 1], z
    las.write(tmp_path / "scan.las")
    np.save(tmp_path / "scan.npy", np.c_[xy, z])
    said = "20 times -k as on a scene (the input's up direction)"
    for name, extra, first, scene in (("scan.las", [], 400, True),
                                      ("scan.npy", [], 100, False),
                                      ("scan.las", ["--merge-from", "20"], 400, False)):
        assert main(["segment", str(tmp_path / name), "-k", "20", *extra,
                     "-o", str(tmp_path / "out.seg")]) == 0
        out = capsys.readouterr().out
        assert f"merged from {first:,} finer ones" in out and (said in out) == scene, out
        # the size bound the merges kept: a scene's 4 times the mean (the LAS), else 16
        bound = 4 if name.endswith(".las") else 16
        assert f"none above {bound} times the mean" in out, out
        assert "where its points allow" not in out, out  # 400 = 20 times -k
    # at k = 200, 20 times -k (4,000) is more than one per 12 of the 6,000 points: fewer
    assert main(["segment", str(tmp_path / "scan.las"), "-k", "200",
                 "-o", str(tmp_path / "out.seg")]) == 0
    out = capsys.readouterr().out
    assert "merged from 500 finer ones, 20 times -k as on a scene (the input's up direction) " \
        "where its points allow," in out, out


def test_a_flat_cloud_that_names_no_up_is_pointed_to_seen_from(tmp_path, capsys):
    """A street or room scan as XYZ/NPY (no up direction) is segmented as an object; the
    note names the axis its box is thinnest along and --seen-from, which makes it a scan
    (the summary then says a scene's merges); an object-like cloud gets no note."""
    rng = np.random.default_rng(4)
    street = rng.random((6000, 3)) * [60.0, 40.0, 4.0]
    ball = rng.standard_normal((6000, 3))
    ball /= np.linalg.norm(ball, axis=1)[:, None]
    for name, pts, said in (("street.npy", street, "--seen-from z segments it as a scan"),
                            ("wall.npy", street[:, [0, 2, 1]], "--seen-from y segments"),
                            ("ball.npy", ball, None)):
        path = tmp_path / name
        np.save(path, pts)
        assert main(["segment", str(path), "-k", "30", "-o", str(tmp_path / "s.seg")]) == 0
        out, err = capsys.readouterr()
        assert (said in err) if said else "--seen-from" not in err, err
        if said and "z" in said:
            assert main(["segment", str(path), "-k", "30", "--seen-from", "z", "-o",
                         str(tmp_path / "s.seg")]) == 0
            out, err = capsys.readouterr()
            assert "as on a scene" in out and "--seen-from" not in err
        for side in ([], ["--seen-from", "z"]):  # a tiled run, from its tiles' boxes
            assert main(["segment", str(path), "-k", "30", "--tiles", "2", "-j", "1", *side,
                         "-o", str(tmp_path / "s.seg")]) == 0
            err = capsys.readouterr().err
            assert (said in err) if said and not side else "--seen-from" not in err, err


def test_panel_and_experiment_take_counts_and_alphas_with_commas_too():
    """``-k 20,50 100`` is ``-k 20 50 100`` (``--levels`` and ``--param`` take commas)."""
    from superfacets.cli import build_parser

    parser = build_parser()
    args = parser.parse_args(["panel", "m.off", "-o", "p.png", "-k", "20,50", "100",
                              "--alpha", "0,1e3"])
    assert args.n_segments == [20, 50, 100] and args.alpha == [0.0, 1000.0]
    args = parser.parse_args(["experiment", "-k", "50,150", "--alpha", "0", "200"])
    assert args.n_segments == [50, 150] and args.alpha == [0.0, 200.0]
    assert parser.parse_args(["panel", "m.off", "-o", "p.png"]).n_segments == [150]
    with pytest.raises(SystemExit):
        parser.parse_args(["panel", "m.off", "-o", "p.png", "-k", "20,x"])


def test_baseline_and_panel_read_a_scans_side_as_segment_does(tmp_path, capsys):
    """``baseline`` and ``panel`` take ``--seen-from`` (refused before): a cloud with no up
    direction run as the scan it is, the same labels as the registry's method on the cloud
    given that up; a mesh is refused, as ``segment`` refuses it."""
    from superfacets import PointCloud
    from superfacets.evaluation.methods import get_method

    rng = np.random.default_rng(9)
    xy = rng.random((3000, 2)) * [30.0, 20.0]
    street = np.c_[xy, 0.5 * np.sin(xy[:, 0] / 3)]
    path = tmp_path / "street.npy"
    np.save(path, street)
    out = tmp_path / "b.seg"
    assert main(["baseline", str(path), "-m", "graph_segmentation", "-k", "40",
                 "--seen-from", "-z", "-o", str(out), "-q"]) == 0
    method = get_method("graph_segmentation")
    want = method.run(PointCloud(street, up="-z", viewpoint=None), 40, cache={}, seed=0,
                      elements="points", **method.resolve({})).labels
    assert np.array_equal(np.loadtxt(out), want)
    png = tmp_path / "p.png"
    pytest.importorskip("pyvista")
    assert main(["panel", str(path), "-k", "20", "40", "--seen-from", "z", "-o", str(png)]) == 0
    assert "2 panels, up axis z" in capsys.readouterr().out and png.stat().st_size > 0
    ball = tmp_path / "ball.off"
    trimesh.creation.icosphere(subdivisions=2).export(ball)
    assert main(["baseline", str(ball), "-m", "vsa", "-k", "8", "--seen-from", "z", "-o",
                 str(out)]) == 2
    assert "orient point clouds; the input is a mesh" in capsys.readouterr().err
