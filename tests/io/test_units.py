"""A scan file's length unit, read from its coordinate reference system, in the summary."""

from __future__ import annotations

import numpy as np
import pytest

from superfacets.cli import main
from superfacets.io.units import length_unit

laspy = pytest.importorskip("laspy")
pyproj = pytest.importorskip("pyproj")


def _las(path, epsg=None, n=3000):
    rng = np.random.default_rng(2)
    xyz = rng.random((n, 3)) * [40.0, 40.0, 0.5] + [500_000.0, 4_000_000.0, 100.0]
    header = laspy.LasHeader(point_format=3, version="1.4")
    header.scales, header.offsets = [0.001] * 3, xyz.min(0)
    if epsg is not None:
        header.add_crs(pyproj.CRS.from_epsg(epsg))
    las = laspy.LasData(header)
    las.x, las.y, las.z = xyz.T
    las.write(str(path))
    return path


@pytest.mark.parametrize("epsg, unit", [(32632, "m"), (2903, "US survey ft"),
                                        (2913, "ft"), (4326, None), (None, None)])
def test_the_unit_is_the_projected_systems(tmp_path, epsg, unit):
    # UTM 32N in metres, New Mexico Central in US survey feet, Oregon North in international
    # feet; WGS 84 is geographic (degrees: no length), and a file may name no system
    assert length_unit(_las(tmp_path / "scan.las", epsg)) == unit
    assert length_unit(_las(tmp_path / "scan.laz", epsg)) == unit


def test_other_formats_and_unreadable_files_have_no_unit(tmp_path):
    assert length_unit(tmp_path / "scan.e57") == "m"  # (metres by the standard)
    for name in ("scan.ply", "scan.pcd", "scan.xyz", "scan.las.gz"):
        assert length_unit(tmp_path / name) is None
    bad = tmp_path / "bad.las"
    bad.write_bytes(b"LASF" + bytes(60))
    assert length_unit(bad) is None and length_unit(tmp_path / "missing.las") is None


def test_the_summary_says_widths_in_the_files_unit(tmp_path, capsys):
    for epsg, said in ((2903, "US survey ft wide)"), (None, "wide in the data's units)")):
        path = _las(tmp_path / f"s{epsg}.las", epsg)
        out = tmp_path / f"s{epsg}.seg"
        assert main(["segment", str(path), "-k", "20", "-o", str(out)]) == 0
        first = capsys.readouterr().out.splitlines()[0]
        assert said in first and "points each (median" in first, first
        assert main(["segment", str(path), "-k", "20", "--tiles", "2", "-o", str(out)]) == 0
        first = capsys.readouterr().out.splitlines()[0]
        assert said.replace("wide", "wide on average") in first, first


def test_longitude_and_latitude_are_said_before_the_run(tmp_path, capsys):
    from superfacets.io.units import geographic_note

    path = _las(tmp_path / "lonlat.las", 4326)
    assert "longitude and latitude (WGS 84, degrees)" in geographic_note(path)
    assert geographic_note(_las(tmp_path / "utm.las", 32632)) == ""
    assert geographic_note(tmp_path / "scan.ply") == ""
    out = tmp_path / "s.seg"
    assert main(["segment", str(path), "-k", "20", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "note: lonlat.las: its coordinates are longitude and latitude" in err
    assert main(["segment", str(path), "-k", "20", "--tiles", "2", "-o", str(out)]) == 0
    assert "longitude and latitude" in capsys.readouterr().err
    assert main(["segment", str(path), "-k", "20", "-o", str(out), "-q"]) == 0
    assert "longitude" not in capsys.readouterr().err


def test_a_count_from_a_seed_resolution_is_said_in_the_files_unit(tmp_path, capsys):
    path = _las(tmp_path / "ft.las", 2903)
    assert main(["segment", str(path), "--seed-resolution", "4", "-o",
                 str(tmp_path / "s.seg")]) == 0
    out = capsys.readouterr().out
    assert "US survey ft^2 / (4 US survey ft)^2" in out, out
    path = _las(tmp_path / "none.las")
    assert main(["segment", str(path), "--seed-resolution", "4", "-o",
                 str(tmp_path / "s.seg")]) == 0
    assert "square units / 4^2" in capsys.readouterr().out
