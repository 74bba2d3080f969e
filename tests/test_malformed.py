"""The malformed-input corpus (tests/malformed.py): no traceback, no partial output,
the right exit status, one clear error line."""

from __future__ import annotations

import malformed
import pytest

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


#: The interrupted mesh's side in quads: 819,200 faces, a run of about 2.5 s from the
#: command line here (2026-11-25, compiled kernels), so that the interrupts at 0.3-1.8 s
#: land within it (405,000 faces ended in 1.2 s once the kernels were compiled C++).
SIDE = 640


@pytest.mark.parametrize("case", malformed.interrupts(), ids=lambda c: c.name)
def test_ctrl_c_at_any_moment_is_one_line_and_exit_130(case, tmp_path):
    # never a traceback (numba's, a Dask worker's), never a hang, never a half-written file
    import os
    import shutil
    import signal
    import subprocess
    import sys
    import time

    import numpy as np
    from conftest import grid_mesh

    from superfacets import read_labels, write_mesh

    big = write_mesh(tmp_path / "big.off",
                     grid_mesh(SIDE, SIDE, height=lambda x, y: 0.2 * np.sin(6 * x) * y))
    (tmp_path / "more").mkdir()
    for i in range(4):
        write_mesh(tmp_path / "more" / f"m{i}.off", grid_mesh(60 + 10 * i, 60))
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    codes = []
    for delay in case.delays:
        argv = [a.replace("{d}", str(tmp_path)).replace("{big}", str(big)) for a in case.argv]
        for o in case.outputs:
            (tmp_path / o).unlink(missing_ok=True)
        shutil.rmtree(tmp_path / "out", ignore_errors=True)  # a batch starts afresh
        proc = subprocess.Popen([sys.executable, "-m", "superfacets", *argv],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env,
                                text=True, start_new_session=True)
        time.sleep(delay)
        try:
            os.killpg(proc.pid, signal.SIGINT)
        except ProcessLookupError:  # it had ended
            pass
        out, err = proc.communicate(timeout=180)
        lines = [ln for ln in err.splitlines() if ln.strip() and "input/s" not in ln]
        assert "Traceback" not in err and "Exception ignored" not in err, err
        if proc.returncode == 130:  # one line (a batch adds what to do next)
            assert len(lines) == 1 and lines[0].startswith("superfacets: interrupted"), err
            for o in case.outputs:
                assert not (tmp_path / o).exists(), o
        else:  # it had finished (or was ending: killed by the signal itself, as any program
            # whose handlers are gone); its outputs are whole
            assert proc.returncode in (0, -signal.SIGINT), err
            if "o.seg" in case.outputs and (proc.returncode == 0 or (tmp_path / "o.seg").exists()):
                assert read_labels(tmp_path / "o.seg").shape == (2 * SIDE * SIDE,)
        codes.append(proc.returncode)
        left = [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]
        assert left == [], left
    assert codes.count(130) >= max(1, len(case.delays) - 2), codes


def test_a_ctrl_c_the_handler_could_not_raise_is_raised_at_the_next_stage():
    """A Ctrl-C that lands only in the import machinery or numba's dispatcher (every
    repeat of it, on a fast start-up) is kept pending and raised at the run's next stage
    boundary; a run outside the command line never sees one, and the command line
    forgets it when it ends."""
    import trimesh

    from superfacets import segment
    from superfacets._runtime import interrupts

    ball = trimesh.creation.icosphere(subdivisions=3)
    interrupts.reset()
    assert segment(ball, 10).n_segments == 10  # nothing pending: the run is unchanged
    interrupts.pending()
    with pytest.raises(KeyboardInterrupt):
        segment(ball, 10)
    assert segment(ball, 10).n_segments == 10  # raised once
    interrupts.pending()
    interrupts.caught()  # stopping in order already: not raised again
    assert segment(ball, 10).n_segments == 10
    interrupts.reset()
