"""The faults of the ninth attack (a user's folders, outputs and repeated runs): each case
fails without its fix."""

from __future__ import annotations

import numpy as np

from superfacets.cli import main


def _clouds(folder, n=2):
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(0)
    for i in range(n):
        xy = rng.random((600, 2))
        np.savetxt(folder / f"s{i}.xyz", np.c_[xy, 0.1 * np.sin(4 * xy[:, 0])], fmt="%.5f")


def test_a_batch_s_output_folder_inside_its_inputs_is_not_read_as_inputs(tmp_path, capsys):
    # (`batch scans -o scans/out`, then again with other options into scans/out2: the
    # second batch segmented the first one's label copies as if they were scans)
    scans = tmp_path / "scans"
    _clouds(scans)
    for out, quiet in (("out", ["-q"]), ("out2", [])):
        assert main(["batch", str(scans), "-o", str(scans / out), "-k", "5",
                     "--labels", "laz", "--workers", "1", *quiet]) == 0
    err = capsys.readouterr().err
    assert sorted(p.name for p in (scans / "out2").glob("*.laz")) == ["s0.laz", "s1.laz"]
    assert not (scans / "out2" / "out").exists()
    assert f"skipped: {scans / 'out'} (a batch's output folder" in err
    # the same folder named as an input is read: the user asked for it
    assert main(["batch", str(scans / "out"), "-o", str(tmp_path / "again"), "-k", "5",
                 "--workers", "1", "-q"]) == 0
    assert len(list((tmp_path / "again").glob("*.seg"))) == 2


def test_a_label_file_with_a_column_s_name_is_read_and_a_bad_one_named(tmp_path, capsys):
    # (pandas' to_csv(index=False) of one column, "label" on its first line: refused with
    # numpy's "could not convert string 'label' to int64 at row 0, column 1"; a table of
    # two columns (pandas' default index) and a fractional label said as numpy says it)
    import pytest

    from superfacets.errors import MeshFormatError
    from superfacets.io import read_labels

    labels = np.array([3, 0, 0, 2, 1])
    (tmp_path / "gt.csv").write_text("label\n" + "\n".join(map(str, labels)) + "\n")
    assert read_labels(tmp_path / "gt.csv", n_faces=5).tolist() == labels.tolist()
    (tmp_path / "two.csv").write_text(",label\n" + "".join(f"{i},{v}\n"
                                                          for i, v in enumerate(labels)))
    with pytest.raises(MeshFormatError, match=r"2 columns in a line \('0,3'\); it holds one "
                                              r"label per line"):
        read_labels(tmp_path / "two.csv")
    (tmp_path / "half.seg").write_text("1\n2\n2.5\n3\n")
    with pytest.raises(MeshFormatError, match=r"label 3 of 4, '2.5', is not one whole"):
        read_labels(tmp_path / "half.seg")
    np.save(tmp_path / "pairs.npy", np.c_[labels, labels])
    with pytest.raises(MeshFormatError, match=r"has 10 labels \(an organized 5 x 2 array, "
                                              r"read row by row\) but the input has 5"):
        read_labels(tmp_path / "pairs.npy", n_faces=5)
    np.save(tmp_path / "column.npy", labels[:, None])  # (N, 1) is one label a row
    assert read_labels(tmp_path / "column.npy", n_faces=5).tolist() == labels.tolist()
