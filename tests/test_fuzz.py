"""Random damage to valid files of every format: the readers raise the package's errors
(or OSError), never anything else, and warn about nothing (a fixed seed: deterministic)."""

from __future__ import annotations

import gzip
import lzma
import random
import warnings

import numpy as np
import pytest
import trimesh

import malformed
from superfacets import SuperfacetsError, read_labels, read_mesh
from superfacets.io.ply import ply_bytes


def _seeds() -> dict:
    v, f = malformed._grid()
    tm = trimesh.Trimesh(v, f, process=False)
    return {
        "m.off": malformed.grid_off(), "m.obj": malformed.grid_obj(), "m.tri": malformed.grid_tri(),
        "m.ply": malformed.grid_ply_binary(), "m.stl": malformed.grid_stl_ascii(),
        "b.stl": tm.export(file_type="stl"), "m.glb": trimesh.Scene([tm]).export(file_type="glb"),
        "m.off.gz": gzip.compress(malformed.grid_off()),
        "m.off.xz": lzma.compress(malformed.grid_off()),
        "l.seg": malformed.grid_seg(),
        "l.ply": ply_bytes(v, f.ravel(), np.arange(0, f.size + 1, 3), labels=np.arange(len(f))),
    }


def _damage(data: bytes, rng: random.Random) -> bytes:
    b = bytearray(data)
    op = rng.choice(["truncate", "flip", "insert", "repeat"])
    i = rng.randrange(len(b))
    if op == "truncate":
        return bytes(b[:i])
    if op == "flip":
        for _ in range(rng.randint(1, 8)):
            b[rng.randrange(len(b))] = rng.randrange(256)
    elif op == "insert":
        b[i:i] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 20)))
    else:
        b[i:i] = b[i:i + rng.randint(1, 200)]
    return bytes(b)


@pytest.mark.parametrize("name", sorted(_seeds()))
def test_damaged_files_give_clear_errors(name, tmp_path):
    rng = random.Random(name)
    data = _seeds()[name]
    read = read_labels if name.startswith("l.") else read_mesh
    path = tmp_path / name
    for _ in range(40):
        path.write_bytes(_damage(data, rng))
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            try:
                read(path)
            except (SuperfacetsError, OSError):
                pass


@pytest.mark.parametrize("name", sorted(n for n in _seeds() if not n.startswith("l.")))
def test_damaged_files_through_segment(name, tmp_path, capsys):
    """The whole command on damaged files: exit 0 or 2, no traceback, nothing half-written."""
    from superfacets.cli import main

    rng = random.Random("cli" + name)
    data = _seeds()[name]
    path, out, ply = tmp_path / name, tmp_path / "o.seg", tmp_path / "o.ply"
    for _ in range(8):
        path.write_bytes(_damage(data, rng))
        for p in (out, ply):
            p.unlink(missing_ok=True)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            rc = main(["segment", str(path), "-k", str(rng.choice([1, 3, 10])), "-o", str(out),
                       "--colored-mesh", str(ply)])
        err = capsys.readouterr().err
        assert rc in (0, 2) and "Traceback" not in err
        assert (out.exists() and ply.exists()) == (rc == 0)
