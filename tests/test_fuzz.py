"""Random damage to valid files of every format: the readers raise the package's errors
(or OSError), never anything else, and warn about nothing but lines a header's count leaves
unread (a fixed seed: deterministic)."""

from __future__ import annotations

import gzip
import lzma
import random
import warnings

import malformed
import numpy as np
import pytest
import trimesh

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


#: The one warning a damaged file may give: a header's count that leaves lines unread (the
#: file is read as its header declares, and the warning says so).
_LINES_NOT_READ = r".*after the .* (faces|rows) its header declares, not read"


def _read_damaged(read, data: bytes, path, rng: random.Random, times: int = 40) -> None:
    """Read ``times`` damaged copies of ``data``: the package's errors or OSError only,
    and no warning."""
    for _ in range(times):
        path.write_bytes(_damage(data, rng))
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            warnings.filterwarnings("ignore", message=_LINES_NOT_READ)
            try:
                read(path)
            except (SuperfacetsError, OSError):
                pass


@pytest.mark.parametrize("name", sorted(_seeds()))
def test_damaged_files_give_clear_errors(name, tmp_path):
    read = read_labels if name.startswith("l.") else read_mesh
    _read_damaged(read, _seeds()[name], tmp_path / name, random.Random(name))


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
            warnings.filterwarnings("ignore", message=_LINES_NOT_READ)
            rc = main(["segment", str(path), "-k", str(rng.choice([1, 3, 10])), "-o", str(out),
                       "--colored-mesh", str(ply)])
        err = capsys.readouterr().err
        assert rc in (0, 2) and "Traceback" not in err
        assert (out.exists() and ply.exists()) == (rc == 0)


def _cloud_seeds() -> dict:
    """Small valid point clouds of every cloud format (LAS/LAZ where laspy and lazrs are)."""
    rng = np.random.default_rng(3)
    pts = rng.random((300, 3))
    rgb = (rng.random((300, 3)) * 255).astype(np.uint8)
    text = "".join(f"{x:.4f} {y:.4f} {z:.4f}\n" for x, y, z in pts).encode()
    pcd = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
           "WIDTH 300\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 300\nDATA binary\n").encode()
    seeds = {"c.xyz": text, "c.pts": b"300\n" + text, "c.npy": malformed._npy(pts),
             "c.pcd": pcd + pts.astype("<f4").tobytes(),
             "c.ply": trimesh.PointCloud(pts, colors=rgb).export(file_type="ply")}
    records = np.zeros(300, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("rgb", "<f4"),
                                   ("label", "<i4")])
    records["x"], records["y"], records["z"] = pts.T
    records["rgb"] = (rgb.astype(np.uint32) @ np.array([1 << 16, 1 << 8, 1],
                                                         dtype=np.uint32)).view("<f4")
    seeds["r.npy"] = malformed._npy(records)
    seeds["p.glb"] = trimesh.Scene(trimesh.PointCloud(pts, colors=rgb)).export(file_type="glb")
    seeds["s.txt"] = "".join(f"{x:.4f} {y:.4f} {z:.4f} {-i} {r} {g} {b}\n" for i, ((x, y, z), (
        r, g, b)) in enumerate(zip(pts, rgb))).encode()  # (Semantic3D's seven columns)
    for name, las in _las_files(pts, rgb).items():
        seeds[name] = las
    return seeds


def _las_files(pts, rgb) -> dict:
    import io

    try:
        import laspy
    except ImportError:
        return {}
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales = [0.001] * 3
    las = laspy.LasData(header)
    las.x, las.y, las.z = pts.T
    las.red, las.green, las.blue = rgb.T.astype(np.uint16) * 256
    out = {}
    for name, compress in (("c.las", False), ("c.laz", True)):
        buf = io.BytesIO()
        try:
            las.write(buf, do_compress=compress)
        except Exception:  # noqa: BLE001 - no LAZ backend
            continue
        out[name] = buf.getvalue()
    return out


@pytest.mark.parametrize("name", sorted(_cloud_seeds()))
def test_damaged_point_clouds_give_clear_errors(name, tmp_path):
    from superfacets import read_cloud

    _read_damaged(read_cloud, _cloud_seeds()[name], tmp_path / name,
                  random.Random("cloud" + name))


_READ_ALL_WAYS = """
import sys
from superfacets.errors import SuperfacetsError
from superfacets.io.clouds import read_cloud
from superfacets.io.labels import read_field
from superfacets.io.regions import RegionReader
for read in (read_cloud, lambda p: read_field(p, "classification"), RegionReader.open):
    try:
        read(sys.argv[1])
        print("read")
    except SuperfacetsError as exc:
        print("error:", exc)
"""


@pytest.mark.parametrize("damage", ["count", "offset", "truncated"])
def test_laz_with_a_damaged_chunk_table_is_refused_not_aborted(damage, tmp_path):
    """lazrs aborts the whole process (no Python exception) when a LAZ file's chunk table
    declares more chunks than it can allocate: every reader refuses such a file first."""
    import struct
    import subprocess
    import sys

    rng = np.random.default_rng(0)
    laz = _las_files(rng.random((300, 3)), np.zeros((300, 3), np.uint8)).get("c.laz")
    if laz is None:
        pytest.skip("no LAZ backend (laspy with lazrs) installed")
    data = bytearray(laz)
    start = struct.unpack_from("<I", data, 96)[0]
    table = struct.unpack_from("<q", data, start)[0]
    if damage == "count":  # about 68 GB of table entries
        struct.pack_into("<I", data, table + 4, 0xFFFFFFF0)
    elif damage == "offset":
        struct.pack_into("<q", data, start, len(data) + 1000)
    else:
        data = data[:table + 2]
    path = tmp_path / "c.laz"
    path.write_bytes(bytes(data))
    run = subprocess.run([sys.executable, "-c", _READ_ALL_WAYS, str(path)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    lines = run.stdout.splitlines()
    assert len(lines) == 3 and all(ln.startswith("error:") for ln in lines), lines
    assert all("damaged LAZ file" in ln for ln in lines), lines
    # the file as written reads
    path.write_bytes(laz)
    run = subprocess.run([sys.executable, "-c", _READ_ALL_WAYS, str(path)],
                         capture_output=True, text=True, timeout=300)
    assert run.stdout.splitlines()[:1] == ["read"], run.stdout + run.stderr[-2000:]
