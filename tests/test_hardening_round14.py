"""Round 14 of hardening: faults an attack on the Python doors found, each with its test.

- A masked array (``numpy.ma``) of points, vertices, colours, features or labels was read through
  ``numpy.asarray``, which drops the mask: the values under it were segmented or scored
  as if the user had not masked them. Now refused, naming how many rows are masked; an
  organized cloud's masked pixels are its invalid points.
- A metric given a point cloud (``evaluate(cloud, labels, [truth])``) said "mesh must be
  ... (a point cloud: a PointCloud ...), got PointCloud": it now names what scores a
  cloud (``evaluate_rows``) or its graph.
- A file named by another format's suffix (a PCD saved as ``.ply``, an OFF as ``.obj``,
  a LAS as ``.ply``, a gzip without ``.gz``) was refused in the reader's words ("line 1:
  expected 'ply'", "empty mesh: no faces"); the message now says what its first bytes
  are, in one run, a tiled run and ``batch``.
- ``-o`` naming the input said "writing label file there would overwrite it".
- A label file with a UTF-8 byte-order mark (Windows tools write one) lost its first label
  (read as a column's name): "69,450 labels, but ... 69,451 faces". A file of all its labels
  on one line, comma-separated, was refused with the whole line quoted (270 kB).
- ``segment --tiles N --seed-resolution R`` on an input of more separate pieces than the
  resolution asks for said "k = 2 superpoints from --seed-resolution ...": the count the
  pieces made, not the one asked (one run says k = 1 and why it made 2).
- ``evaluation.metrics.has_border`` (public since round 13) read its ground truth
  unchecked: a short one raised numpy's IndexError, a string "too many indices", floats
  and masked arrays were read. ``io.files.sniffed_format`` took only a ``Path``.
- ``report`` of an empty results file said "the results file has no rows" without its name.
"""

from __future__ import annotations

import numpy as np
import pytest

import superfacets as sf
from superfacets.cli import main
from superfacets.errors import InvalidCloudError, InvalidMeshError, ParameterError
from superfacets.evaluation.metrics import evaluate, evaluate_rows


def _flat(n=2000, seed=0):
    xyz = np.random.default_rng(seed).random((n, 3))
    xyz[:, 2] *= 0.05
    return xyz


def test_masked_points_are_refused_not_read_unmasked():
    xyz = _flat()
    mask = np.zeros_like(xyz, bool)
    mask[:40, 2] = True
    masked = np.ma.masked_array(xyz, mask=mask)
    for call in (lambda: sf.segment(masked, 20), lambda: sf.PointCloud(masked)):
        with pytest.raises(InvalidCloudError, match="masked array with 40 rows"):
            call()
    colours = np.ma.masked_array(np.full_like(xyz, 0.5), mask=mask)
    with pytest.raises(InvalidCloudError, match="colours: a masked array with 40 rows"):
        sf.PointCloud(xyz, colors=colours)
    with pytest.raises(ParameterError, match="features: a masked array with 40 rows"):
        sf.segment(sf.PointCloud(xyz), 20, features=colours, beta=1)
    # a mask that masks nothing is the array itself
    clear = sf.segment(np.ma.masked_array(xyz), 20).labels
    assert np.array_equal(clear, sf.segment(xyz, 20).labels)


def test_masked_pixels_of_an_organized_cloud_are_its_invalid_points():
    grid = _flat(50 * 60).reshape(50, 60, 3)
    mask = np.zeros(grid.shape, bool)
    mask[0, :7] = True
    result = sf.segment(np.ma.masked_array(grid, mask=mask), 20)
    assert result.labels.shape == (3000,)
    assert np.flatnonzero(result.labels == -1).tolist() == list(range(7))
    assert result.n_segments == 20


def test_masked_vertices_and_labels_are_refused():
    v = np.ma.masked_array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]],
                           mask=[[0, 0, 0], [0, 0, 0], [0, 1, 0]])
    with pytest.raises(InvalidMeshError, match="vertices: a masked array with 1 row"):
        sf.segment((v, [[0, 1, 2]]), 1)
    with pytest.raises(InvalidMeshError, match="masked array"):
        sf.TetMesh(v, [[0, 1, 2, 0]])
    cloud = sf.PointCloud(_flat())
    labels = sf.segment(cloud, 10).labels
    truth = np.ma.masked_array((cloud.points[:, 0] > 0.5).astype(int),
                               mask=np.r_[np.ones(5, bool), np.zeros(1995, bool)])
    with pytest.raises(ParameterError, match="5 masked values.*ignore_label"):
        evaluate_rows(cloud, labels, [truth])
    # filled with an ignored value it is scored without those points
    scores = evaluate_rows(cloud, labels, [truth.filled(-1)], ignore_label=-1)
    assert 0 <= scores["undersegmentation_error"] < 1


def test_a_metric_given_a_cloud_names_what_scores_one():
    cloud = sf.PointCloud(_flat())
    labels = sf.segment(cloud, 10).labels
    truth = (cloud.points[:, 0] > 0.5).astype(int)
    with pytest.raises(TypeError, match="not a point cloud: .*evaluate_rows") as err:
        evaluate(cloud, labels, [truth])
    assert "got PointCloud" not in str(err.value)
    from superfacets.elements.builders import elements_of
    graph = elements_of(cloud).graph      # what the message offers works
    assert 0 <= evaluate(graph, labels, [truth])["undersegmentation_error"] < 1


def _pcd(path, pts) -> None:
    head = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            f"WIDTH {len(pts)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {len(pts)}\n"
            "DATA ascii\n")
    path.write_text(head + "\n".join(" ".join(f"{v:.6f}" for v in p) for p in pts) + "\n")


def test_a_file_under_another_formats_suffix_is_named_by_its_first_bytes(tmp_path, capsys):
    import gzip

    pts = _flat(400)
    _pcd(tmp_path / "scan.pcd", pts)
    assert main(["segment", str(tmp_path / "scan.pcd"), "-k", "5", "-o",
                 str(tmp_path / "ok.seg")]) == 0
    data = (tmp_path / "scan.pcd").read_bytes()
    (tmp_path / "scan.ply").write_bytes(data)
    (tmp_path / "shape.obj").write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    (tmp_path / "packed.pcd").write_bytes(gzip.compress(data))
    capsys.readouterr()
    for name, said in (("scan.ply", "(it begins as PCD files do: name it .pcd)"),
                       ("shape.obj", "(it begins as OFF files do: name it .off)"),
                       ("packed.pcd", "(it is gzip-compressed: name it packed.pcd.gz)")):
        assert main(["segment", str(tmp_path / name), "-k", "2", "-o",
                     str(tmp_path / "o.seg")]) == 2
        err = capsys.readouterr().err
        assert said in err, err
    # the tiled run's own reader (a PLY is streamed), and batch's rows
    assert main(["segment", str(tmp_path / "scan.ply"), "--tiles", "2", "-k", "4", "-o",
                 str(tmp_path / "o.seg")]) == 2
    assert "(it begins as PCD files do" in capsys.readouterr().err
    with pytest.raises(sf.errors.MeshFormatError, match="begins as PCD files do"):
        sf.io.read_input(tmp_path / "scan.ply")
    # a file of its own format that is damaged says nothing of the kind
    (tmp_path / "bad.pcd").write_bytes(data[:40])
    assert main(["segment", str(tmp_path / "bad.pcd"), "-k", "2", "-o",
                 str(tmp_path / "o.seg")]) == 2
    assert "begins as" not in capsys.readouterr().err
    assert not (tmp_path / "o.seg").exists()


def test_output_over_the_input_is_refused_in_plain_words(tmp_path, capsys):
    _pcd(tmp_path / "scan.pcd", _flat(300))
    assert main(["segment", str(tmp_path / "scan.pcd"), "-k", "5", "-o",
                 str(tmp_path / "scan.pcd")]) == 2
    err = capsys.readouterr().err
    assert "writing the labels there would overwrite it" in err, err


def test_a_label_file_with_a_byte_order_mark_reads_every_label(tmp_path):
    from superfacets.io import read_labels

    labels = np.arange(50) % 7
    text = "\n".join(map(str, labels)) + "\n"
    (tmp_path / "plain.seg").write_text(text)
    (tmp_path / "bom.seg").write_text(text, encoding="utf-8-sig")
    (tmp_path / "bom.json").write_text('{"segIndices": [%s]}' % ", ".join(map(str, labels)),
                                       encoding="utf-8-sig")
    for name in ("plain.seg", "bom.seg", "bom.json"):
        assert read_labels(tmp_path / name, 50).tolist() == labels.tolist(), name


def test_a_label_file_on_one_line_is_refused_in_a_short_message(tmp_path):
    from superfacets.io import read_labels

    (tmp_path / "one.seg").write_text(",".join(["12"] * 5000) + "\n")
    with pytest.raises(sf.errors.MeshFormatError, match="5,000 columns in a line") as err:
        read_labels(tmp_path / "one.seg", 5000)
    assert len(str(err.value)) < 300


def test_a_tiled_runs_count_from_the_resolution_is_the_one_asked(tmp_path, capsys):
    a, b = _flat(1500, 1), _flat(1500, 2)
    b[:, 0] += 50.0                                   # two pieces, far apart
    np.save(tmp_path / "two.npy", np.r_[a, b])
    said = []
    for extra in ([], ["--tiles", "2"]):
        assert main(["segment", str(tmp_path / "two.npy"), "--seed-resolution", "1e6",
                     "-o", str(tmp_path / "o.seg"), *extra]) == 0
        out = capsys.readouterr()
        said.append([ln for ln in (out.out + out.err).splitlines() if ln.startswith("k = ")])
        assert len(set(np.loadtxt(tmp_path / "o.seg", dtype=int))) == 2
    assert said[0] == said[1] and said[0][0].startswith("k = 1 superpoints"), said


def test_report_of_an_empty_results_file_names_it(tmp_path, capsys):
    (tmp_path / "empty.csv").write_text("")
    assert main(["report", str(tmp_path / "empty.csv"), "-o", str(tmp_path / "r")]) == 2
    assert "empty.csv: the results file has no rows" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


def test_has_border_checks_its_ground_truth():
    from superfacets.elements.builders import elements_of
    from superfacets.evaluation.metrics import has_border
    from superfacets.io.files import sniffed_format

    graph = elements_of(_flat(200)).graph
    assert has_border(graph, np.arange(200) % 2) and not has_border(graph, np.zeros(200, int))
    for bad in (np.zeros(5, int), "x", None, np.zeros(200),
                np.ma.masked_array(np.zeros(200, int), mask=np.r_[1, np.zeros(199)])):
        with pytest.raises(ParameterError, match="ground_truth"):
            has_border(graph, bad)
    assert sniffed_format(__file__) is None                # a str path, of no known format
