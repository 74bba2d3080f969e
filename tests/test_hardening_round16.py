"""Round 16 of hardening: faults an attack on the readers and the command line found, each
with its test.

- An ASCII STL facet of two or four vertices, or a vertex of two coordinates, gave numpy's
  "cannot reshape array of size 2 into shape (3)" through trimesh; now the facet is named.
- ``html --background`` took any word as a colour (``notacolour``: a page whose background
  the browser drops) and ``#12345``; now a CSS colour name, ``#rgb(a)``, ``#rrggbb(aa)`` or
  ``rgb()``-style only.
- A label file whose first line was not a number had that line taken as a column's name
  without a word, so a file of hexadecimal labels said "label 1 of 319, '0x1f'" for the
  second line of 320; the message now says the first line was read as the name.
- A label beyond 64 bits (``99999999999999999999``) was "not one whole number"; it is one,
  too large to keep: the message says so.
- ``--levels`` above ``-k`` said the levels "are coarser than" the count (they were finer:
  the sentence stated the rule as if it held); one check and one message in the API, the
  tiled run, ``segment`` and ``batch``.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from superfacets import ParameterError, read_mesh, segment, segment_tiled
from superfacets.cli import main
from superfacets.errors import MeshFormatError
from superfacets.io import read_labels
from superfacets.viz.html import html_page

_FACET = "facet normal 0 0 1\nouter loop\n{}endloop\nendfacet\n"


def _stl(path, *facets):
    body = "".join(_FACET.format("".join(f"vertex {v}\n" for v in f)) for f in facets)
    path.write_text(f"solid t\n{body}endsolid t\n")
    return path


def test_an_ascii_stl_facet_that_is_not_a_triangle_is_named(tmp_path):
    good = ("0 0 0", "1 0 0", "0 1 0")
    assert read_mesh(_stl(tmp_path / "ok.stl", good, good[::-1])).faces.shape == (2, 3)
    for name, facets, said in (
            ("two.stl", (good, good[:2]), "facet 2 has 2 vertices, not 3"),
            ("four.stl", (good + ("1 1 0",),), "facet 1 has 4 vertices, not 3"),
            ("flat.stl", (good, ("0 0 0", "1 0", "0 1 0")),
             "vertex 2 of ASCII STL facet 2 has not three coordinates: 'vertex 1 0'")):
        with pytest.raises(MeshFormatError, match=said):
            read_mesh(_stl(tmp_path / name, *facets))


def test_a_page_background_is_a_css_colour(tmp_path, capsys):
    colors = pytest.importorskip("matplotlib.colors")
    ball = trimesh.creation.icosphere(subdivisions=1)
    for name in sorted(colors.CSS4_COLORS):  # every CSS colour name (matplotlib's list)
        assert f"background: {name.upper()};" in html_page(ball, background=name.upper())
    for good in ("#abc", "#abcd", "#a1b2c3", "#a1b2c3d4", "rgb(1, 2, 3)", "transparent"):
        assert f"background: {good};" in html_page(ball, background=good)
    for bad, said in (("notacolour", "not a CSS colour name"), ("#12345", "CSS colour"),
                      ("#1234567", "CSS colour"), ("red;x", "CSS colour")):
        with pytest.raises(ParameterError, match=said):
            html_page(ball, background=bad)
    path = tmp_path / "ball.off"
    ball.export(path)
    out = tmp_path / "ball.html"
    assert main(["html", str(path), "-k", "5", "--background", "notacolour", "-o",
                 str(out)]) == 2
    assert "not a CSS colour name" in capsys.readouterr().err and not out.exists()


def test_a_first_line_read_as_a_column_name_is_said(tmp_path):
    path = tmp_path / "hex.seg"
    path.write_text("0x1f\n" * 20)
    with pytest.raises(MeshFormatError, match=r"label 1 of 19 \(after the first line, "
                                              r"'0x1f', read as the column's name\)"):
        read_labels(path)
    named = tmp_path / "named.seg"
    named.write_text("label\n" + "1\n" * 4 + "x\n")
    with pytest.raises(MeshFormatError, match=r"label 5 of 5 \(after the first line, "
                                              r"'label'"):
        read_labels(named)
    named.write_text("label\n" + "1\n" * 4)
    assert read_labels(named).tolist() == [1] * 4


def test_a_label_too_large_to_keep_is_said_so(tmp_path):
    path = tmp_path / "big.seg"
    for value, said in (("99999999999999999999", "is beyond 2\\*\\*53"),
                        ("1e17", "is beyond 2\\*\\*53"), ("1.5", "is not one whole number"),
                        ("nan", "is not one whole number"), ("inf", "is not one whole number")):
        path.write_text(f"1\n{value}\n2\n")
        with pytest.raises(MeshFormatError, match=f"label 2 of 3, '{value}', {said}"):
            read_labels(path)


def test_levels_above_the_count_are_refused_in_one_sentence_everywhere(tmp_path, capsys):
    rng = np.random.default_rng(5)
    xyz = rng.random((2000, 3)) * [4.0, 4.0, 0.05]
    said = "must each be at most the 12 segments they merge"
    with pytest.raises(ParameterError, match=f"levels {said} \\(n_segments\\), got 13"):
        segment_tiled(xyz, 12, tiles=2, levels=[13, 4])
    path = tmp_path / "flat.xyz"
    np.savetxt(path, xyz)
    graph = tmp_path / "g.npz"
    assert main(["segment", str(path), "-k", "12", "--levels", "4,13", "--graph",
                 str(graph)]) == 2
    assert not graph.exists()
    assert f"--levels {said} (-k), got 13" in capsys.readouterr().err
    assert main(["batch", str(path), "-o", str(tmp_path / "out"), "-k", "12", "--graph",
                 "--levels", "13", "-q"]) == 2
    assert f"levels (--levels) {said} (n_segments (-k)), got 13" in capsys.readouterr().err
    assert segment(xyz, 12).n_segments == 12  # (the same count is a valid run)
