"""The faults of the eighth attack (a user's own formats and label conventions): each case
fails without its fix."""

from __future__ import annotations

import numpy as np

from superfacets.cli import main


def test_a_ground_truth_of_one_class_or_below_zero_is_said(tmp_path, capsys):
    # (a ground truth of -1 everywhere, Pointcept's "ignore": recall 1.0000 and precision
    # 0.0000 printed as measurements, -1 measured as a class without a word)
    rng = np.random.default_rng(0)
    xy = rng.random((1500, 2))
    np.save(tmp_path / "scan.npy", np.c_[xy, 0.1 * np.sin(5 * xy[:, 0])])
    assert main(["segment", str(tmp_path / "scan.npy"), "-k", "8", "-o",
                 str(tmp_path / "sp.seg")]) == 0
    np.savetxt(tmp_path / "none.seg", np.full(1500, -1), fmt="%d")
    np.savetxt(tmp_path / "some.seg", np.where(xy[:, 0] > 0.5, 3, -1), fmt="%d")
    capsys.readouterr()
    args = ["evaluate", str(tmp_path / "scan.npy"), str(tmp_path / "sp.seg")]
    assert main([*args, str(tmp_path / "none.seg")]) == 0
    out = capsys.readouterr().out
    assert "one class (-1) here: it has no border" in out
    assert "--ignore-label -1 leaves them out" in out
    assert main([*args, str(tmp_path / "some.seg")]) == 0
    out = capsys.readouterr().out
    assert "one class" not in out and "class -1 measured as a class" in out
    assert main([*args, str(tmp_path / "some.seg"), "--ignore-label", "-1"]) == 0
    out = capsys.readouterr().out
    assert "measured as a class" not in out and "one class (3) here" in out
