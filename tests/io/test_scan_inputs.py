"""Scans in: E57 files (each scan an object, its scanner's position kept), Open3D's tensor
clouds and meshes, and a batch that lists every file it leaves out."""

from __future__ import annotations

import numpy as np
import pytest

from superfacets import read_cloud, segment
from superfacets.api.scenes import segment_objects
from superfacets.cli import main
from superfacets.errors import MeshFormatError
from superfacets.io import read_labels


def _station(rng, n, centre):
    """A terrestrial scan in miniature: a floor and a wall around a scanner."""
    floor = np.c_[rng.random((n // 2, 2)) * 10 - 5, np.zeros(n // 2)]
    wall = np.c_[rng.random(n - n // 2) * 10 - 5, np.full(n - n // 2, 5.0),
                 rng.random(n - n // 2) * 3]
    return np.vstack([floor, wall]) + rng.normal(0, 0.005, (n, 3)), np.asarray(centre)


def _e57(path, scans=2, n=3000, invalid=0, seed=0, intensity=False):
    pye57 = pytest.importorskip("pye57")
    rng = np.random.default_rng(seed)
    e57 = pye57.E57(str(path), mode="w")
    truths = []
    for i in range(scans):
        local, _ = _station(rng, n, (0, 0, 1.5))
        pose = np.array([20.0 * i, 0.0, 0.0])
        d = {"cartesianX": local[:, 0], "cartesianY": local[:, 1], "cartesianZ": local[:, 2],
             "colorRed": np.full(n, 200, np.uint8), "colorGreen": np.full(n, 100, np.uint8),
             "colorBlue": np.full(n, 50, np.uint8)}
        if intensity:
            d["intensity"] = np.linspace(0, 1, n) * (i + 1) / scans
        if invalid:
            state = np.zeros(n, dtype=np.int8)
            state[:invalid] = 2
            d["cartesianInvalidState"] = state
        e57.write_scan_raw(d, name=f"station {i}", translation=pose,
                           rotation=np.array([1.0, 0.0, 0.0, 0.0]))
        truths.append(local + pose)
    e57.close()
    return path, np.vstack(truths)


def test_an_e57_file_reads_every_scan_in_its_common_frame(tmp_path):
    path, truth = _e57(tmp_path / "site.e57", scans=2)
    cloud = read_cloud(path)
    assert cloud.n_total == 6000 and np.allclose(cloud.points, truth)  # each pose applied
    assert cloud.objects == (("station 0", 0, 3000), ("station 1", 3000, 6000))
    assert np.allclose(cloud.object_viewpoints, [[0, 0, 0], [20, 0, 0]])
    assert np.allclose(cloud.colors[0], [200 / 255, 100 / 255, 50 / 255])
    assert np.allclose(cloud.up, [0, 0, 1])
    labels, parts = segment_objects(cloud, 20)
    assert [r.n_segments for r in parts] == [10, 10]
    assert set(labels[:3000]) == set(range(10)) and set(labels[3000:]) == set(range(10, 20))


def test_one_scan_faces_its_scanner_and_invalid_points_stay_rows(tmp_path):
    path, _ = _e57(tmp_path / "one.e57", scans=1, invalid=25)
    cloud = read_cloud(path)
    assert cloud.objects == () and np.allclose(cloud.viewpoint, [0, 0, 0])
    assert cloud.n_total == 3000 and cloud.n_points == 2975
    r = segment(cloud, 12)
    assert r.n_segments == 12 and (r.labels[:25] == -1).all() and (r.labels[25:] >= 0).all()


def test_the_command_line_segments_an_e57_per_scan(tmp_path, capsys):
    path, _ = _e57(tmp_path / "site.e57", scans=2)
    out = tmp_path / "site.seg"
    assert main(["segment", str(path), "-k", "16", "--per-object", "-o", str(out)]) == 0
    assert "6,000 points, 16 superpoints" in capsys.readouterr().out
    labels = read_labels(out)
    assert labels.shape == (6000,) and len(np.unique(labels)) == 16
    assert not set(labels[:3000]) & set(labels[3000:])  # labels unique over the site


def test_an_e57_s_levels_per_scan_go_into_its_records(tmp_path, capsys):
    """``--per-object --levels`` (a traceback after the run before): each level shared out
    among the scans, nested in the labels, no segment over two scans; a level below one
    segment per scan refused before the run, nothing written; batch likewise."""
    laspy = pytest.importorskip("laspy")
    path, _ = _e57(tmp_path / "site.e57", scans=2)
    out = tmp_path / "site.las"
    assert main(["segment", str(path), "-k", "16", "--per-object", "--levels", "4,2",
                 "-o", str(out)]) == 0
    assert "levels as ClusterID_4, ClusterID_2" in capsys.readouterr().out
    rec = laspy.read(out)
    labels = np.asarray(rec["ClusterID"])
    for n in (4, 2):
        level = np.asarray(rec[f"ClusterID_{n}"])
        assert len(np.unique(level)) == n and not set(level[:3000]) & set(level[3000:])
        parent = {}
        for s, t in zip(labels, level):  # nested: each superpoint in one segment
            assert parent.setdefault(int(s), int(t)) == int(t)
    assert main(["segment", str(path), "-k", "16", "--per-object", "--levels", "4,1",
                 "-o", str(tmp_path / "no.las")]) == 2
    assert "at least one segment per object (2)" in capsys.readouterr().err
    assert not (tmp_path / "no.las").exists()
    folder = tmp_path / "in"
    folder.mkdir()
    path.rename(folder / "site.e57")
    assert main(["batch", str(folder), "-o", str(tmp_path / "res"), "-k", "16", "-j", "1",
                 "--per-object", "--labels", "laz", "--levels", "6"]) == 0
    done = laspy.read(next((tmp_path / "res").rglob("*.laz")))
    level = np.asarray(done["ClusterID_6"])
    assert len(np.unique(level)) == 6 and not set(level[:3000]) & set(level[3000:])


def test_an_e57_s_intensity_is_kept_in_a_new_file(tmp_path):
    from plyfile import PlyData

    path, _ = _e57(tmp_path / "site.e57", scans=2, intensity=True)
    want = np.r_[np.linspace(0, 1, 3000) / 2, np.linspace(0, 1, 3000)]
    assert np.allclose(read_cloud(path).fields["intensity"], want)
    assert main(["segment", str(path), "-k", "16", "-o", str(tmp_path / "site.ply")]) == 0
    got = PlyData.read(str(tmp_path / "site.ply"))["vertex"]["scalar_intensity"]
    assert np.allclose(got, want)
    laspy = pytest.importorskip("laspy")  # LAS's 16-bit intensity: 0..1 scaled, as PDAL does
    assert main(["segment", str(path), "-k", "16", "-o", str(tmp_path / "site.laz")]) == 0
    las = laspy.read(str(tmp_path / "site.laz"))
    assert np.abs(las.intensity.astype(float) - want * 65535).max() <= 0.5 + 1e-6
    assert las.intensity.max() == 65535
    assert "intensity" not in las.point_format.extra_dimension_names
    plain, _ = _e57(tmp_path / "plain.e57", scans=1)
    assert read_cloud(plain).fields is None


def test_a_damaged_e57_is_refused_in_one_line(tmp_path, capsys):
    pytest.importorskip("pye57")
    bad = tmp_path / "bad.e57"
    bad.write_bytes(b"ASTM-E57" + b"\0" * 200)
    with pytest.raises(MeshFormatError, match="cannot read E57"):
        read_cloud(bad)
    assert main(["segment", str(bad), "-o", str(tmp_path / "x.seg")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("superfacets: error:") and len(err.splitlines()) == 1
    assert not (tmp_path / "x.seg").exists()


def test_open3d_tensor_clouds_and_meshes_segment():
    o3d = pytest.importorskip("open3d", exc_type=ImportError)
    rng = np.random.default_rng(0)
    x = rng.normal(size=(4000, 3))
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    cloud = o3d.t.geometry.PointCloud(o3d.core.Tensor(x))
    cloud.point.colors = o3d.core.Tensor(np.full((4000, 3), 0.25, dtype=np.float32))
    r = segment(cloud, 25)
    assert r.labels.shape == (4000,) and r.n_segments == 25
    mesh = o3d.t.geometry.TriangleMesh.from_legacy(o3d.geometry.TriangleMesh.create_sphere())
    r = segment(mesh, 30)
    assert r.labels.shape == (mesh.triangle.indices.shape[0],) and r.n_segments == 30


def test_a_batch_lists_every_file_it_leaves_out(tmp_path, capsys, sphere):
    from superfacets import write_mesh

    folder = tmp_path / "in"
    folder.mkdir()
    write_mesh(folder / "ball.off", sphere)
    (folder / "notes.txt").write_text("a readme\n")
    (folder / "results.csv").write_text("method,k,error\nours,10,0.1\n")  # (not a cloud)
    (folder / "scan.rcp").write_bytes(b"\0" * 10)
    (folder / ".hidden").write_text("x")
    assert main(["batch", str(folder), "-o", str(tmp_path / "out"), "-k", "8",
                 "--workers", "1"]) == 0
    err = capsys.readouterr().err
    assert f"skipped: {folder / 'notes.txt'} (a .txt in a folder" in err
    assert f"skipped: {folder / 'results.csv'} (a .csv in a folder is not read" in err
    assert f"skipped: {folder / 'scan.rcp'} (.rcp: not a mesh, cloud or volume format)" in err
    assert ".hidden" not in err


def test_a_seed_resolution_gives_about_area_over_r_squared_on_a_plane(tmp_path, capsys):
    from superfacets.api.sizes import count_for_resolution

    rng = np.random.default_rng(4)
    plane = np.c_[rng.random((40000, 2)) * [40.0, 25.0], rng.normal(0, 0.01, 40000)]
    path = tmp_path / "plane.npy"
    np.save(path, plane)
    for r in (0.5, 1.0, 2.5):
        k, area = count_for_resolution(read_cloud(path), r)
        assert abs(area - 1000.0) < 100  # the points' areas add up to the plane's
        assert abs(k - 1000.0 / r**2) <= 0.3 * 1000.0 / r**2, (r, k)
    out = tmp_path / "plane.seg"
    assert main(["segment", str(path), "--seed-resolution", "2", "-o", str(out)]) == 0
    said = capsys.readouterr().out
    n = len(np.unique(read_labels(out)))
    assert 175 <= n <= 325 and f"k = {n} superpoints from --seed-resolution 2" in said
    assert main(["segment", str(path), "--seed-resolution", "2", "-k", "9"]) == 2
    assert "not with -k" in capsys.readouterr().err



def test_a_seed_resolution_whose_square_underflows_gives_the_most_superpoints(tmp_path, capsys):
    """``area / r^2`` where ``r * r`` underflows to 0 (1e-200) or the quotient overflows
    (1e-170) raised ZeroDivisionError / OverflowError through the command line: the count
    is the most the input takes (one per 12 points), and the summary says it is capped."""
    from superfacets.api.sizes import count_for_resolution

    rng = np.random.default_rng(6)
    cloud = np.c_[rng.random((1200, 2)) * 10.0, rng.normal(0, 0.01, 1200)]
    path = tmp_path / "plane.npy"
    np.save(path, cloud)
    for r in (1e-200, 1e-170, 1e-9):
        assert count_for_resolution(read_cloud(path), r)[0] == 100, r
    assert count_for_resolution(read_cloud(path), 1e200)[0] == 1
    out = tmp_path / "plane.seg"
    assert main(["segment", str(path), "--seed-resolution", "1e-200", "-o", str(out)]) == 0
    said = capsys.readouterr().out
    assert "k = 100 superpoints from --seed-resolution 1e-200" in said
    assert "at most one per 12 points" in said
    assert len(np.unique(read_labels(out))) == 100
    assert main(["segment", str(path), "--seed-resolution", "3", "-o", str(out)]) == 0
    assert "at most one per" not in capsys.readouterr().out


def test_the_command_line_says_a_warning_in_one_line_and_refuses_a_huge_radius(tmp_path,
                                                                               capsys):
    """A library warning (here: more superpoints than asked, the graph's points all apart)
    printed Python's file, line and source line; it is one ``superfacets: warning:`` line.
    ``--radius 1e300`` overflowed the superfacet's area into a traceback."""
    rng = np.random.default_rng(7)
    path = tmp_path / "c.npy"
    np.save(path, rng.random((300, 3)))
    out = tmp_path / "c.seg"
    assert main(["segment", str(path), "-k", "20", "--neighbor-distance", "1e-300",
                 "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert err.startswith("superfacets: warning: 300 superpoints for n_segments=20")
    assert len(err.strip().splitlines()) == 1 and "pipeline(" not in err
    assert main(["segment", str(path), "--radius", "1e300", "-o", str(tmp_path / "r.seg")]) == 2
    assert "radius must be a finite number in (0, 1000]" in capsys.readouterr().err
    assert not (tmp_path / "r.seg").exists()


def test_the_default_count_grows_with_a_cloud_and_the_summary_says_so(tmp_path, capsys):
    from superfacets.api.sizes import default_count

    rng = np.random.default_rng(5)
    big = tmp_path / "big.npy"
    np.save(big, rng.random((400_000, 3)) * [100, 100, 0.1])
    assert main(["segment", str(big), "-o", str(tmp_path / "big.seg")]) == 0
    said = capsys.readouterr().out
    assert "k = 400 superpoints by default (one per 1,000 points" in said
    assert len(np.unique(read_labels(tmp_path / "big.seg"))) == 400
    small = rng.random((70, 3))
    assert default_count(read_cloud(_npy(tmp_path / "small.npy", small))) == 5
    np.save(tmp_path / "mid.npy", rng.random((20_000, 3)))
    assert default_count(read_cloud(tmp_path / "mid.npy")) == 150  # the method's default


def test_a_neighbour_distance_in_the_data_s_units(tmp_path, capsys):
    from superfacets.api.sizes import diagonal_fraction

    rng = np.random.default_rng(6)
    pts = rng.random((5000, 3)) * [30.0, 40.0, 0.0]
    np.save(tmp_path / "p.npy", pts)
    cloud = read_cloud(tmp_path / "p.npy")
    assert abs(diagonal_fraction(cloud, 5.0) - 5.0 / 50.0) < 1e-2
    assert main(["segment", str(tmp_path / "p.npy"), "-k", "20", "--neighbor-distance", "2",
                 "-o", str(tmp_path / "a.seg")]) == 0
    fraction = diagonal_fraction(cloud, 2.0)  # the same radius as a fraction: same labels
    assert main(["segment", str(tmp_path / "p.npy"), "-k", "20", "--neighbor-radius",
                 repr(fraction), "-o", str(tmp_path / "b.seg")]) == 0
    assert np.array_equal(read_labels(tmp_path / "a.seg"), read_labels(tmp_path / "b.seg"))


def _npy(path, a):
    np.save(path, a)
    return path
