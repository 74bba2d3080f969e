"""A tiled run's work folder (superfacets.scale.tiles.workdir): its own, removed, and a
full disk said."""

from __future__ import annotations

import numpy as np
import pytest
from tiled import _bumpy, _write_ply_mesh

from superfacets import ParameterError
from superfacets.scale.tiles import buckets as buckets_module
from superfacets.scale.tiles.run import segment_tiled


def test_the_work_folder_is_the_runs_own(tmp_path, capsys):
    """A tiled run removed a user's W/graphs/ with its files, unlinked W/.lock and
    overwrote W/orientation.npy (exit 0): it now works in a folder of its own that it
    makes inside --workdir and removes at its end, nothing else there touched; two runs
    share a folder; the leftovers of a killed run are removed, and said, by the next."""
    import fcntl

    mesh = _bumpy(3)
    work = tmp_path / "work"
    (work / "graphs").mkdir(parents=True)
    mine = {work / "graphs" / "keep.txt": b"mine", work / "orientation.npy": b"not an array",
            work / ".lock": b"lock of mine"}
    for path, data in mine.items():
        path.write_bytes(data)
    live = work / "superfacets-tiles-live"  # another run, still going: its lock held
    live.mkdir()
    (live / "tile-0.npy").write_bytes(b"its work")
    held = open(live / "run.lock", "w")
    fcntl.flock(held, fcntl.LOCK_EX)
    dead = work / "superfacets-tiles-dead"  # a killed run's leftovers: lock released
    dead.mkdir()
    (dead / "run.lock").write_bytes(b"")
    (dead / "tile-0.npy").write_bytes(b"stale")
    try:
        res = segment_tiled(mesh, 20, tiles=2, workers=1, workdir=work)
        assert res.labels.shape == (mesh.n_faces,)
        assert all(path.read_bytes() == data for path, data in mine.items())
        assert (live / "tile-0.npy").read_bytes() == b"its work"  # the live run's, kept
        assert not dead.exists() and f"removed {dead}" in capsys.readouterr().err
        assert sorted(p.name for p in work.iterdir()) == [
            ".lock", "graphs", "orientation.npy", "superfacets-tiles-live"]
        # a folder inside a run's own folder: that run's end would remove it
        with pytest.raises(ParameterError, match="inside the work folder of a tiled run"):
            segment_tiled(mesh, 20, tiles=2, workers=1, workdir=live / "graphs")
    finally:
        held.close()
    with pytest.raises(ParameterError, match="empty path"):
        segment_tiled(mesh, 20, tiles=2, workers=1, workdir="")
    with pytest.raises(ParameterError, match="not a folder"):
        segment_tiled(mesh, 20, tiles=2, workers=1, workdir=work / ".lock")
    same = segment_tiled(mesh, 20, tiles=2, workers=1)  # a temporary folder: the same labels
    np.testing.assert_array_equal(same.labels, res.labels)


def test_a_full_disk_under_the_work_folder_says_so(tmp_path, monkeypatch):
    """A full disk under the work folder said only '50000 requested and 48256 written'
    (numpy's short write): it names the folder and the room the tiles' files need."""
    import builtins

    mesh = _bumpy(3)
    path = tmp_path / "m.ply"
    _write_ply_mesh(path, mesh.vertices, mesh.faces)

    class Full:
        def __init__(self, *a, **k):
            pass

        def __enter__(self):
            raise OSError("50000 requested and 48256 written")

        def __exit__(self, *a):
            return False

    real_open = builtins.open
    monkeypatch.setattr(buckets_module, "open",
                        lambda p, mode="r", *a, **k: Full() if str(p).endswith(".bin")
                        and "a" in mode else real_open(p, mode, *a, **k), raising=False)
    with pytest.raises(OSError, match=r"the tiles' files of the input could not be written "
                                      r"\(50000 requested.*needs about the input's size free"):
        segment_tiled(path, 20, tiles=2, workers=1, workdir=tmp_path / "work")
    assert list((tmp_path / "work").iterdir()) == []  # (the run's own folder, removed)


def test_a_killed_tiled_run_leaves_nothing_for_long(tmp_path, monkeypatch, capsys):
    """A SIGKILLed tiled run left its temporary folder (about 14 times the input)
    forever: without --workdir the runs work in the system's temporary folder the same
    way, and the next run removes what a killed one left (its lock released)."""
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    dead = tmp_path / "superfacets-tiles-killed"
    dead.mkdir()
    (dead / "run.lock").write_bytes(b"")
    (dead / "buckets").mkdir()
    other = tmp_path / "superfacets-tiles-not-ours"  # no lock file: not a run's, kept
    other.mkdir()
    res = segment_tiled(_bumpy(3), 20, tiles=2, workers=1)
    assert res.n_segments > 0 and not dead.exists() and other.exists()
    assert f"removed {dead}" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["superfacets-tiles-not-ours"]
