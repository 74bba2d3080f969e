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


def _seven_columns(path, fourth, last3):
    """A text cloud of seven headerless columns: x y z, then ``fourth`` and ``last3``."""
    rng = np.random.default_rng(2)
    xyz = rng.random((len(fourth), 3))
    rows = (f"{a:.4f} {b:.4f} {c:.4f} {d:d} {e:d} {f:d} {g:d}\n"
            for (a, b, c), d, (e, f, g) in zip(xyz, fourth, last3))
    path.write_text("".join(rows))
    return path


def test_a_terrestrial_scan_s_seven_columns_give_its_colours(tmp_path):
    # (Semantic3D's x y z intensity r g b .txt, a terrestrial scanner's layout as Leica's
    # PTS: only a .pts file's colours were read)
    from superfacets import read_cloud

    rng = np.random.default_rng(0)
    rgb = rng.integers(0, 256, (300, 3))
    signed = rng.integers(-2048, 2048, 300)
    for name in ("bildstein_station1_xyz_intensity_rgb.txt", "scan.xyz"):
        cloud = read_cloud(_seven_columns(tmp_path / name, signed, rgb))
        assert np.allclose(cloud.colors * 255, rgb), name
    # x y z r g b label (the fourth column 0..255) or a fractional fourth: no colours read
    label = rng.integers(0, 9, (300, 1))
    plain = read_cloud(_seven_columns(tmp_path / "rgbl.txt", rgb[:, 0],
                                      np.c_[rgb[:, 1:], label]))
    assert plain.colors is None
    (tmp_path / "frac.txt").write_text("".join(
        f"0.{i:03d} 0.{(7 * i) % 997:03d} 0.5 -3.5 1 2 3\n" for i in range(300)))
    assert read_cloud(tmp_path / "frac.txt").colors is None


def test_each_task_s_warnings_go_to_its_own_row_on_a_worker_of_many_threads(recwarn):
    # (warnings.catch_warnings swaps the process's filters and showwarning: on a Dask worker
    # of several threads one task's warnings went into another's row, and two tasks ending
    # out of order left every later warning recorded into a list no one read)
    import threading
    import warnings

    from superfacets._runtime.warned import task_warnings

    step = threading.Barrier(2)
    said = {}

    def task(name, first_out):
        with task_warnings(ignore=("dull",)) as mine:
            step.wait()
            for i in range(3):
                warnings.warn(f"{name} {i}", RuntimeWarning)
                warnings.warn(f"{name} dull {i}", UserWarning)
                step.wait()
            if first_out:
                step.wait()  # the other ends first
        if not first_out:
            step.wait()
        said[name] = mine

    threads = [threading.Thread(target=task, args=(n, n == "a")) for n in ("a", "b")]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=60)
    assert said == {"a": ["a 0", "a 1", "a 2"], "b": ["b 0", "b 1", "b 2"]}
    assert not [w for w in recwarn if "dull" in str(w.message) or " 0" in str(w.message)]
    warnings.warn("after the tasks", UserWarning)  # shown as before, not recorded away
    assert [str(w.message) for w in recwarn] == ["after the tasks"]


def test_a_colour_of_nan_or_infinity_is_refused_without_numpy_s_warning(tmp_path):
    # (an all-NaN colour file: numpy's "All-NaN slice" warning before the refusal; an
    # infinite colour was clipped to 1, a silent colour)
    import warnings

    import pytest

    from superfacets import read_cloud
    from superfacets.inputs.cloud import InvalidCloudError

    scene = tmp_path / "scene"
    scene.mkdir()
    np.save(scene / "coord.npy", np.random.default_rng(0).random((50, 3)))
    bad = np.full((50, 3), 100.0)
    for value, row in ((np.nan, 0), (np.inf, 7)):
        colour = np.full((50, 3), np.nan) if row == 0 else bad.copy()
        colour[row, 1] = value
        np.save(scene / "color.npy", colour)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(InvalidCloudError, match=f"colour {row} is not finite"):
                read_cloud(scene / "coord.npy")


def test_a_gltf_of_points_is_a_point_cloud(tmp_path):
    # (a GLB of POINTS primitives, as trimesh or a photogrammetry tool writes a cloud: "the
    # scene holds no mesh with faces")
    import gzip

    import trimesh

    from superfacets import read_input, segment, segment_tiled
    from superfacets.io.clouds import is_cloud_file

    rng = np.random.default_rng(0)
    xy = rng.random((2000, 2))
    pts = np.c_[xy, 0.1 * np.sin(6 * xy[:, 0])]
    rgb = np.c_[(xy * 255).astype(np.uint8), np.full((2000, 2), 255, dtype=np.uint8)]
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.PointCloud(pts[:1200], colors=rgb[:1200]))
    moved = np.eye(4)
    moved[:3, 3] = [5.0, 0, 0]
    scene.add_geometry(trimesh.PointCloud(pts[1200:], colors=rgb[1200:]), transform=moved)
    data = scene.export(file_type="glb")
    (tmp_path / "scan.glb").write_bytes(data)
    (tmp_path / "scan.glb.gz").write_bytes(gzip.compress(data))
    want = np.r_[pts[:1200], pts[1200:] + [5.0, 0, 0]]
    for name in ("scan.glb", "scan.glb.gz"):
        cloud = read_input(tmp_path / name)
        assert is_cloud_file(tmp_path / name) and cloud.n_points == 2000, name
        order = np.lexsort(cloud.points.T)
        assert np.allclose(cloud.points[order], want[np.lexsort(want.T)], atol=1e-6)
        assert np.allclose(np.sort(cloud.colors[:, 0] * 255), np.sort(rgb[:, 0]), atol=0.5)
    labels = segment(read_input(tmp_path / "scan.glb"), 10).labels
    assert labels.shape == (2000,) and len(np.unique(labels)) == 10
    tiled = segment_tiled(tmp_path / "scan.glb", 10, tiles=2, workdir=tmp_path / "work")
    assert len(np.unique(tiled.labels)) == 10
    # a scene with faces stays a mesh (its points left out, as before)
    both = trimesh.Scene([trimesh.creation.icosphere(2), trimesh.PointCloud(pts)])
    (tmp_path / "both.glb").write_bytes(both.export(file_type="glb"))
    assert not is_cloud_file(tmp_path / "both.glb")
    assert read_input(tmp_path / "both.glb").n_faces == 320


def test_a_reader_silences_trimesh_s_log_on_its_own_thread_only(caplog):
    # (the reader lowered the "trimesh" logger's level and restored it after: two threads
    # reading at once, ending out of order, left trimesh's log silenced for the process)
    import logging
    import threading

    import trimesh  # noqa: F401

    from superfacets.io.meshes import _quiet_trimesh

    log = logging.getLogger("trimesh.util")
    inside, step = threading.Event(), threading.Event()

    def reader():
        with _quiet_trimesh():
            log.warning("from a reader")
            inside.set()
            step.wait(30)

    t = threading.Thread(target=reader)
    with caplog.at_level(logging.WARNING):
        t.start()
        inside.wait(30)
        log.warning("beside the reader")
        step.set()
        t.join(30)
        log.warning("after it")
    said = [r.getMessage() for r in caplog.records]
    assert said == ["beside the reader", "after it"]


def test_a_batch_on_a_worker_of_four_threads_keeps_each_input_s_warning(tmp_path):
    import pytest

    pytest.importorskip("distributed")
    import pandas as pd
    from dask.distributed import LocalCluster
    from plyfile import PlyData, PlyElement

    from superfacets.scale.runner.batch import run_batch

    rng = np.random.default_rng(0)
    (tmp_path / "in").mkdir()
    for i in range(6):  # zero normals: each file's reader warns, naming it
        rows = np.zeros(3000, dtype=[(c, "f4") for c in ("x", "y", "z", "nx", "ny", "nz")])
        rows["x"], rows["y"] = rng.random((2, 3000))
        PlyData([PlyElement.describe(rows, "vertex")]).write(str(tmp_path / "in" / f"s{i}.ply"))
    with LocalCluster(n_workers=1, threads_per_worker=4, processes=False,
                      dashboard_address=None) as cluster:
        run_batch([str(tmp_path / "in")], tmp_path / "out", n_segments=10,
                  scheduler=cluster.scheduler_address, progress=False)
    rows = pd.read_parquet(tmp_path / "out" / "manifest.parquet")
    assert len(rows) == 6 and (rows["status"] == "ok").all()
    for _, row in rows.iterrows():
        name = row["input"].rsplit("/", 1)[-1]
        said = row["warnings"].splitlines()
        assert len(said) == 1 and said[0].startswith(f"{name}: its normals are all zero"), row


def test_a_new_file_keeps_fields_of_any_name_or_says_why_not(tmp_path, capsys):
    # (a field named in another alphabet: plyfile's "non-ASCII character in name" traceback;
    # the summary named fields the LAS had left out)
    import laspy
    from plyfile import PlyData

    from superfacets.cli import main

    rows = np.zeros(400, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("intensité", "f4"),
                                ("a b", "i4"), ("ClusterID", "i4"), ("n" * 40, "f4"),
                                ("big", "u8"), ("flag", "?")])
    rows["x"], rows["y"] = np.random.default_rng(0).random((2, 400))
    rows["big"], rows["flag"], rows["a b"] = 2**40, True, 7
    np.save(tmp_path / "odd.npy", rows)
    for suffix in ("ply", "laz"):
        out = tmp_path / f"odd.{suffix}"
        assert main(["segment", str(tmp_path / "odd.npy"), "-k", "5", "-o", str(out)]) == 0
        said = capsys.readouterr()
        assert "Traceback" not in said.err
        assert "field 'ClusterID' is not kept" in said.err
        kept = "intensité, a b, big and flag" if suffix == "laz" else (
            f"intensité, a b, {'n' * 40}, big and flag")
        assert f"with their {kept}, labels as" in said.out
    vertex = PlyData.read(str(tmp_path / "odd.ply"))["vertex"]
    assert vertex["scalar_a_b"].tolist() == [7] * 400 and vertex["scalar_big"][0] == 2**40
    las = laspy.read(tmp_path / "odd.laz")
    assert las["a_b"].tolist() == [7] * 400 and las["big"][0] == 2**40
    assert "intensit_" in las.point_format.extra_dimension_names


def test_a_corpus_in_semantic3d_s_layout_is_judged_by_its_labels_files(tmp_path):
    # (x y z intensity r g b .txt beside a .labels of one class a line, 0 unlabelled)
    import csv

    from superfacets.cli import main

    rng = np.random.default_rng(1)
    for name in ("bildstein_station1_xyz_intensity_rgb", "domfountain_station1_xyz_intensity_rgb"):
        xy = rng.random((1500, 2)) * 10
        cls = np.where(xy[:, 0] > 5, 2, 1)
        cls[:100] = 0
        rgb = np.where(cls[:, None] == 2, [180, 40, 40], [40, 160, 40])
        rows = (f"{a:.3f} {b:.3f} {0.5 * (c == 2):.3f} {-i} {r} {g} {bl}\n"
                for i, ((a, b), c, (r, g, bl)) in enumerate(zip(xy, cls, rgb)))
        (tmp_path / f"{name}.txt").write_text("".join(rows))
        np.savetxt(tmp_path / f"{name}.labels", cls, fmt="%d")
    out = tmp_path / "rows.csv"
    assert main(["experiment", "--inputs", str(tmp_path / "*.txt"), "--ground-truths",
                 "{stem}.labels", "--ignore-label", "0", "-m", "superfacets", "-k", "12",
                 "--alpha", "0", "-o", str(out), "-q"]) == 0
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 2 and all(r["status"] == "ok" for r in rows)
    assert all(float(r["undersegmentation_error"]) < 0.05 and float(r["oracle_miou"]) > 0.95
               for r in rows)


def test_pdal_s_dimension_names_go_into_a_new_las_s_standard_dimensions(tmp_path):
    # (a CSV of PDAL's writers.text: ReturnNumber, GpsTime, ... became extra dimensions
    # beside the empty standard ones; ScanAngleRank, in degrees, stays an extra one)
    import laspy

    from superfacets.cli import main

    rng = np.random.default_rng(0)
    n = 2000
    xyz = np.c_[rng.uniform(0, 50, (n, 2)), rng.normal(0, 0.05, n)]
    ret, cls, angle = rng.integers(1, 4, n), rng.integers(1, 7, n), rng.integers(-20, 20, n)
    head = '"X","Y","Z","Intensity","ReturnNumber","Classification","ScanAngleRank","GpsTime"\n'
    rows = "".join(f"{a:.3f},{b:.3f},{c:.3f},{100 + i % 50},{r},{k},{s},{1e5 + i:.1f}\n"
                   for i, ((a, b, c), r, k, s) in enumerate(zip(xyz, ret, cls, angle)))
    (tmp_path / "tile.csv").write_text(head + rows)
    assert main(["segment", str(tmp_path / "tile.csv"), "-k", "10", "-o",
                 str(tmp_path / "tile.laz"), "-q"]) == 0
    las = laspy.read(tmp_path / "tile.laz")
    assert np.array_equal(las.return_number, ret) and np.array_equal(las.classification, cls)
    assert np.array_equal(las.intensity, 100 + np.arange(n) % 50)
    assert np.allclose(las.gps_time, 1e5 + np.arange(n))
    assert set(las.point_format.extra_dimension_names) == {"ClusterID", "scananglerank"}
    assert np.array_equal(las["scananglerank"], angle) and not las.scan_angle.any()
