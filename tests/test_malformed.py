"""The malformed-input corpus (tests/malformed.py): no traceback, no partial output,
the right exit status, one clear error line."""

from __future__ import annotations

import pytest

import malformed
from superfacets.cli import main

CASES = malformed.cases()


def test_the_corpus_is_large():
    assert len(CASES) >= 100
    assert len({c.name for c in CASES}) == len(CASES)


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_malformed_input(case, tmp_path, capsys):
    for name, data in case.files.items():
        p = tmp_path / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes(data)
    before = {p.relative_to(tmp_path) for p in tmp_path.rglob("*")}
    argv = [a.replace("{d}", str(tmp_path)) for a in case.argv]
    try:
        status = main(argv)
    except SystemExit as exc:  # argparse's usage errors
        status = exc.code
    captured = capsys.readouterr()
    err = captured.err
    assert "Traceback" not in err and "Traceback" not in captured.out
    after = {p.relative_to(tmp_path) for p in tmp_path.rglob("*")}
    new = sorted(str(p) for p in after - before)
    if case.expect == "ok":
        assert status == 0, err
        for o in case.outputs:
            assert (tmp_path / o).is_file(), f"{o} not written"
        return
    assert status == 2, f"exit {status}; stderr: {err}"
    assert new == [], f"left behind: {new}"
    lines = [ln for ln in err.splitlines() if ln.strip()]
    if case.expect == "usage":
        assert lines[-1].startswith("superfacets") and ": error: " in lines[-1]
        return
    assert len(lines) == 1 and lines[0].startswith("superfacets: error: "), err
    assert case.match in lines[0], lines[0]
    for name in case.files:  # the input is named once, not once per layer
        assert lines[0].count(f"{name}: ") <= 1, lines[0]


def test_a_pipe_or_device_is_refused_as_input(tmp_path, capsys):
    import os

    fifo = tmp_path / "m.off"
    os.mkfifo(fifo)
    assert main(["segment", str(fifo), "-o", str(tmp_path / "o.seg")]) == 2
    assert "not a regular file" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.off"]
