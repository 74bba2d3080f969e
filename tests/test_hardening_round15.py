"""Round 15 of hardening: faults an attack on the command line found, each with its test.

- argparse took any unambiguous prefix of an option: ``segment scan.pcd --seed 3`` (a user
  asking for a random seed, which the method does not take) ran as ``--seed-resolution 3``,
  one superpoint per 9 square units, said only in the summary; ``render scan.laz --labels
  b.seg`` ran as ``--labels-from b.seg`` ("no field 'b.seg'"). Options are now taken whole
  (an unknown one is refused, naming the options it begins), ``--labels FILE`` names
  LABELS in ``render``, ``html``, ``view`` and ``evaluate``, and ``--ground-truth GT``
  (refused before, as the field's abbreviation) a ground truth of ``evaluate``.
- Pictures, pages and coloured files drew an element labelled below 0 (unassigned: DBSCAN's
  noise, which ``evaluate`` leaves out) as one more segment in a palette colour; a label
  file of -5 and -4 drew two "superpoints" where the legend counted none. Now grey.
- ``NotebookView(cloud, labels)`` took labels of the wrong length or dtype and a height of
  0 or ``"big"`` without a word, and failed only when the notebook showed it (a traceback
  beside the cell); now refused when made.
- An OBJ with a bare ``v`` line (a vertex statement with no numbers, as a truncated file ends)
  was read without it, every later index one vertex off (a silent wrong mesh); a bare ``f``
  line raised numpy's "operands could not be broadcast". Both are refused, naming the line.
- An OFF or ``.tri`` file with more face lines than its header declares lost the others
  without a word, an ASCII PLY cloud its rows past the vertex count; now a warning says how
  many lines were not read.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from superfacets.cli import main
from superfacets.io import read_labels


def _cloud(tmp_path):
    rng = np.random.default_rng(3)
    xyz = rng.random((3000, 3)) * [4.0, 4.0, 0.05]
    path = tmp_path / "flat.xyz"
    np.savetxt(path, xyz)
    return path


def test_an_option_is_taken_whole_not_by_its_prefix(tmp_path, capsys):
    path = _cloud(tmp_path)
    out = tmp_path / "s.seg"
    with pytest.raises(SystemExit) as exc:
        main(["segment", str(path), "--seed", "3", "-o", str(out)])
    assert exc.value.code == 2 and not out.exists()
    err = capsys.readouterr().err
    assert "unrecognized arguments: --seed 3" in err and "did you mean --seed-resolution" in err
    with pytest.raises(SystemExit):
        main(["segment", str(path), "-k", "10", "--tile", "2", "-o", str(out)])
    assert "--tile: did you mean --tile-start or --tiles?" in capsys.readouterr().err
    assert not out.exists()


def test_labels_given_by_name_are_labels_in_every_command_that_reads_them(tmp_path, capsys):
    path = _cloud(tmp_path)
    seg = tmp_path / "s.seg"
    assert main(["segment", str(path), "-k", "12", "-o", str(seg), "-q"]) == 0
    labels = read_labels(seg)
    for order in ([str(path), "--labels", str(seg)], ["--labels", str(seg), str(path)]):
        png = tmp_path / "r.png"
        assert main(["render", *order, "-o", str(png)]) == 0 and png.stat().st_size > 0
        png.unlink()
    capsys.readouterr()
    assert main(["evaluate", str(path), "--labels", str(seg), str(seg)]) == 0
    said = capsys.readouterr().out
    assert "undersegmentation" in said and "12" in said  # judged against itself: a truth
    assert main(["evaluate", str(path), "--labels", str(seg)]) == 0
    assert "undersegmentation" not in capsys.readouterr().out  # (no ground truth)
    with pytest.raises(SystemExit):
        main(["render", str(path), str(seg), "--labels", str(seg), "-o",
              str(tmp_path / "x.png")])
    assert "give the labels once" in capsys.readouterr().err
    assert labels.size == 3000


def test_a_ground_truth_given_by_name_is_one(tmp_path, capsys):
    import json

    path = _cloud(tmp_path)
    seg, half = tmp_path / "s.seg", tmp_path / "half.seg"
    assert main(["segment", str(path), "-k", "12", "-o", str(seg), "-q"]) == 0
    xyz = np.loadtxt(path)
    half.write_text("\n".join(str(int(x > 2)) for x in xyz[:, 0]) + "\n")
    capsys.readouterr()
    assert main(["evaluate", str(path), str(seg), "--ground-truth", str(half),
                 "--ground-truth", str(seg), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["ground_truths"] == 2
    assert main(["evaluate", str(path), str(seg), str(half), "--json"]) == 0
    alone = json.loads(capsys.readouterr().out)
    assert main(["evaluate", str(path), "--labels", str(seg), "--ground-truth", str(half),
                 "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == alone  # the same judgement, by name


def test_unassigned_elements_are_drawn_grey_not_as_a_segment():
    from superfacets.elements.builders import elements_of
    from superfacets.io.colors import PALETTE, UNASSIGNED, face_colors
    from superfacets.io.export import element_colors
    from superfacets.viz.html import html_page

    rng = np.random.default_rng(0)
    xyz = rng.random((2000, 3)) * [4.0, 4.0, 0.05]
    labels = np.where(xyz[:, 0] < 1, -1, (xyz[:, 0] > 2.5).astype(np.int64))
    labels[xyz[:, 0] > 3.5] = -7
    rgb = element_colors(elements_of(xyz, "points"), labels)
    assert (rgb[labels < 0] == UNASSIGNED).all()
    assert not (rgb[labels >= 0] == UNASSIGNED).all(axis=1).any()
    palette = {tuple(c) for c in PALETTE}
    assert {tuple(c) for c in rgb[labels >= 0]} <= palette
    import trimesh

    from superfacets.inputs.convert import as_mesh

    box = as_mesh(trimesh.creation.box())
    face = np.r_[[-1, -1], np.arange(10)]
    colours = face_colors(box, face)
    assert (colours[:2] == UNASSIGNED).all() and (colours[2:] != UNASSIGNED).any(axis=1).all()
    assert '"superfacets": 10' in html_page(box, face).replace('\\"', '"')  # not 11


def test_a_notebook_view_refuses_its_labels_and_height_when_made():
    import trimesh

    from superfacets import NotebookView, ParameterError, PointCloud

    xyz = np.random.default_rng(0).random((3000, 3)) * [4.0, 4.0, 0.05]
    for labels, msg in ((np.zeros(5, int), "3000 integers, one per point"),
                        (np.full(3000, 0.5), "dtype float64")):
        with pytest.raises(ParameterError, match=msg):
            NotebookView(PointCloud(xyz), labels)
    for height in (0, "big", 2.5, True):
        with pytest.raises(ParameterError, match="height must be a whole number"):
            NotebookView(PointCloud(xyz), np.zeros(3000, int), height=height)
    box = trimesh.creation.box()
    with pytest.raises(ParameterError, match="one per face"):
        NotebookView(box, np.zeros(8, int))
    view = NotebookView(box, np.zeros(8, int), elements="vertices")  # one per vertex
    assert view._repr_html_().startswith("<iframe")


def test_a_bare_obj_statement_is_refused_not_skipped(tmp_path):
    from superfacets.errors import MeshFormatError
    from superfacets.io import read_input

    head = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 1 1\n"
    for text, msg in ((head.replace("v 0 1 0\n", "v\nv 0 1 0\n") + "f 1 2 4\nf 1 2 5\n",
                       "malformed vertex 2: 'v '"),
                      (head + "f 1 2 3\nf 1 2 4\nf\n", "face 2 has only 0 vertex indices")):
        path = tmp_path / "m.obj"
        path.write_text(text)
        with pytest.raises(MeshFormatError, match=msg):
            read_input(path)
    path.write_text(head + "f 1 2 3\nf 1 2 4\n")
    assert read_input(path).n_faces == 2


def test_face_lines_past_the_header_count_are_said(tmp_path):
    from superfacets.io import read_input

    body = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
    cases = {"m.off": f"OFF\n4 1 0\n{body}3 0 1 2\n3 0 1 3\n3 0 2 3\n",
             "m.tri": f"4\n{body}1\n0 1 2\n0 1 3\n0 2 3\n"}
    for name, text in cases.items():
        path = tmp_path / name
        path.write_text(text)
        with pytest.warns(UserWarning, match="2 lines after the 1 face its header declares"):
            assert read_input(path).n_faces == 1
        path.write_text(text.replace("4 1 0", "4 3 0").replace("\n1\n", "\n3\n"))
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            assert read_input(path).n_faces == 3
    head = "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\n" \
        "property float z\nend_header\n"
    path = tmp_path / "c.ply"
    path.write_text(head.format(4) + body + "1 1 1\n")
    with pytest.warns(UserWarning, match="c.ply: 1 line after the 4 rows its header declares"):
        assert read_input(path).points.shape == (4, 3)
    path.write_text(head.format(5) + body + "1 1 1\n\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read_input(path).points.shape == (5, 3)
