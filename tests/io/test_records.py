"""Labels written back into the input's own records (LAS/LAZ, PLY), read by laspy, by this
package and by CloudCompare; the commands that take a scan's labels from its own file."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

from superfacets.cli import main
from superfacets.errors import MeshFormatError, ParameterError
from superfacets.io import read_labels
from superfacets.io.records import write_labels_into

laspy = pytest.importorskip("laspy")

WKT = ('PROJCS["RGF93 v1 / Lambert-93",GEOGCS["RGF93 v1",DATUM["Reseau_Geodesique_Francais_'
       '1993_v1",SPHEROID["GRS 1980",6378137,298.257222101]],PRIMEM["Greenwich",0],UNIT["degree"'
       ',0.0174532925199433]],PROJECTION["Lambert_Conformal_Conic_2SP"],UNIT["metre",1]]')


def _laz(path, n=2000, seed=0):
    """A LAZ tile of two terraces with RGB, GPS time, classification, an extra dimension
    and a WKT CRS: what a user's airborne tile carries."""
    from laspy.vlrs.known import WktCoordinateSystemVlr

    rng = np.random.default_rng(seed)
    las = laspy.create(point_format=7, file_version="1.4")
    las.add_extra_dim(laspy.ExtraBytesParams(name="reflectance", type=np.float32))
    las.header.scales = [0.001, 0.001, 0.001]
    las.header.offsets = [652000.0, 6862000.0, 0.0]
    xy = rng.random((n, 2)) * [40.0, 20.0]
    high = xy[:, 0] > 20
    las.x, las.y = xy[:, 0] + 652000.0, xy[:, 1] + 6862000.0
    las.z = np.where(high, 0.8, 0.0) + rng.normal(0, 0.01, n)
    las.red = np.where(high, 60000, 9000).astype(np.uint16)
    las.green, las.blue = las.red, las.red
    las.gps_time = np.sort(rng.random(n)) * 100
    las.classification = np.where(high, 6, 2).astype(np.uint8)
    las.reflectance = rng.random(n).astype(np.float32)
    las.vlrs.append(WktCoordinateSystemVlr(WKT))
    las.header.global_encoding.wkt = True
    las.write(str(path))
    return path


def test_segment_writes_the_labels_into_a_copy_of_the_laz(tmp_path, capsys):
    src = _laz(tmp_path / "tile.laz")
    out = tmp_path / "out.laz"
    assert main(["segment", str(src), "-k", "12", "-o", str(out)]) == 0
    said = capsys.readouterr().out
    assert "labels as ClusterID" in said
    assert main(["segment", str(src), "-k", "12", "-o", str(tmp_path / "out.seg"), "-q"]) == 0
    a, b = laspy.read(src), laspy.read(out)
    assert out.read_bytes()[:4] == b"LASF" and b.header.are_points_compressed
    for dim in a.point_format.dimension_names:  # every dimension of the input, unchanged
        assert np.array_equal(np.asarray(a[dim]), np.asarray(b[dim])), dim
    assert list(b.point_format.dimension_names) == list(a.point_format.dimension_names) + [
        "ClusterID"]
    assert b.header.point_format.id == a.header.point_format.id == 7
    assert np.array_equal(b.header.scales, a.header.scales)
    assert np.array_equal(b.header.offsets, a.header.offsets)
    assert (b.header.version, b.header.global_encoding.wkt) == (a.header.version, True)
    assert b.header.parse_crs is not None
    wkt = [v for v in b.header.vlrs if type(v).__name__ == "WktCoordinateSystemVlr"]
    assert len(wkt) == 1 and WKT in wkt[0].string
    labels = np.asarray(b.ClusterID)
    assert labels.dtype == np.int32
    assert np.array_equal(labels, read_labels(tmp_path / "out.seg"))
    assert len(np.unique(labels)) == 12
    # read back by this package: as a label file, and as the input's own field
    assert np.array_equal(read_labels(out), labels)


def test_labels_from_the_file_feed_evaluate_render_and_html(tmp_path, capsys):
    src = _laz(tmp_path / "tile.laz")
    out = tmp_path / "out.laz"
    assert main(["segment", str(src), "-k", "12", "-o", str(out), "-q"]) == 0
    capsys.readouterr()
    assert main(["evaluate", str(out), str(out), "--ground-truth-field", "classification",
                 "--json"]) == 0
    import json

    scores = json.loads(capsys.readouterr().out)
    assert scores["segments"] == 12 and 0 <= scores["undersegmentation_error"] < 0.05
    assert main(["html", str(out), "--labels-from", "ClusterID", "-o",
                 str(tmp_path / "p.html")]) == 0
    assert (tmp_path / "p.html").stat().st_size > 10_000
    capsys.readouterr()
    # a field that is not there: one line naming those that are
    assert main(["html", str(src), "--labels-from", "ClusterID", "-o",
                 str(tmp_path / "q.html")]) == 2
    err = capsys.readouterr().err
    assert "no field 'ClusterID'" in err and "classification" in err
    assert not (tmp_path / "q.html").exists()


def test_ply_cloud_records_keep_every_property_and_cloudcompare_reads_the_field(tmp_path):
    from plyfile import PlyData, PlyElement

    rng = np.random.default_rng(1)
    n = 1500
    v = np.empty(n, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("intensity", "<f4"),
                           ("red", "u1"), ("green", "u1"), ("blue", "u1")])
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    v["x"], v["y"], v["z"] = p.T
    v["intensity"] = rng.random(n)
    v["red"] = v["green"] = v["blue"] = 128
    src = tmp_path / "ball.ply"
    PlyData([PlyElement.describe(v, "vertex")], text=True,
             comments=["scanned"]).write(str(src))
    out = tmp_path / "ball_sp.ply"
    assert main(["segment", str(src), "-k", "10", "-o", str(out), "-q"]) == 0
    a, b = PlyData.read(str(src)), PlyData.read(str(out))
    assert b.text and b.comments == ["scanned"]  # the input's encoding and comments kept
    for name in v.dtype.names:
        assert np.array_equal(a["vertex"][name], b["vertex"][name]), name
    labels = np.asarray(b["vertex"]["scalar_ClusterID"])
    assert labels.min() == 0 and labels.max() == 9
    assert np.array_equal(read_labels(out), labels)
    if shutil.which("CloudCompare") is None:
        pytest.skip("CloudCompare not found: install Debian's 'cloudcompare' package (make "
                    "test does, as root)")
    asc = tmp_path / "cc.asc"
    run = subprocess.run(["CloudCompare", "-SILENT", "-AUTO_SAVE", "OFF", "-O", str(out),
                          "-C_EXPORT_FMT", "ASC", "-ADD_HEADER", "-SAVE_CLOUDS", "FILE",
                          str(asc)], capture_output=True, text=True, timeout=120,
                         env={"QT_QPA_PLATFORM": "offscreen", "PATH": "/usr/bin:/bin",
                              "HOME": str(tmp_path)})
    assert run.returncode == 0, run.stdout[-2000:]
    head = asc.read_text().splitlines()[0]
    assert "ClusterID" in head.split(), head  # CloudCompare's scalar field
    column = head.lstrip("/").split().index("ClusterID")
    got = np.loadtxt(asc, comments="//")[:, column].astype(int)
    assert np.array_equal(got, labels)


def test_a_vertex_segmentation_goes_into_the_mesh_ply_and_its_coloured_ply(tmp_path, sphere):
    from plyfile import PlyData

    from superfacets import write_mesh

    src = tmp_path / "ball.ply"
    write_mesh(src, sphere)
    out, col = tmp_path / "out.ply", tmp_path / "col.ply"
    assert main(["segment", str(src), "--elements", "vertices", "-k", "8", "-o", str(out),
                 "--colored-mesh", str(col), "-q"]) == 0
    for path in (out, col):
        ply = PlyData.read(str(path))
        assert len(ply["face"].data) == sphere.n_faces
        labels = np.asarray(ply["vertex"]["scalar_ClusterID"])
        assert labels.shape == (sphere.n_vertices,) and len(np.unique(labels)) == 8
    # the faces of a mesh have no records of their own: -o OUT.ply is refused before the run
    assert main(["segment", str(src), "-k", "8", "-o", str(tmp_path / "f.ply")]) == 2
    assert not (tmp_path / "f.ply").exists()


@pytest.mark.parametrize("name, said", [("x.ply", "needs a .ply input"),
                                        ("x.las.gz", "compressed as LAZ: name it .laz")])
def test_records_of_another_family_are_refused_in_one_line(tmp_path, capsys, name, said):
    src = _laz(tmp_path / "tile.laz", n=300)
    assert main(["segment", str(src), "-k", "5", "-o", str(tmp_path / name)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("superfacets: error:") and len(err.splitlines()) == 1
    assert said in err, err
    assert not (tmp_path / name).exists()


def test_write_labels_into_checks_counts_and_types(tmp_path):
    src = _laz(tmp_path / "tile.las", n=50)
    with pytest.raises(ParameterError, match="49 labels for 50 points"):
        write_labels_into(tmp_path / "o.las", src, np.zeros(49, dtype=int))
    with pytest.raises(ParameterError, match="-1"):
        write_labels_into(tmp_path / "o.las", src, np.full(50, -2))
    assert not (tmp_path / "o.las").exists()
    # a second run over its own output overwrites the field, not adds another
    once = write_labels_into(tmp_path / "o.las", src, np.arange(50) % 3)
    with pytest.warns(UserWarning, match="o.las has a field ClusterID: the copy holds"):
        twice = write_labels_into(tmp_path / "p.laz", once, np.arange(50) % 4)
    las = laspy.read(twice)
    assert list(las.point_format.dimension_names).count("ClusterID") == 1
    assert np.array_equal(las.ClusterID, np.arange(50) % 4)


def test_a_tiled_run_writes_the_labels_into_the_laz_too(tmp_path, capsys):
    src = _laz(tmp_path / "tile.laz", n=6000)
    out = tmp_path / "tiled.laz"
    assert main(["segment", str(src), "--tiles", "2", "--workers", "1", "-k", "20", "-o",
                 str(out), "--up-weight", "1"]) == 0
    said = capsys.readouterr().out
    assert "labels as ClusterID" in said
    # its tiles' weights said as one run's: the colour, a scene's steps (heights unweighed:
    # weighed twice, as this tile's level terraces ask by default, the step alone parts them)
    assert "following colour (beta" in said and "steps weighed 4 times" in said
    a, b = laspy.read(src), laspy.read(out)
    for dim in a.point_format.dimension_names:
        assert np.array_equal(np.asarray(a[dim]), np.asarray(b[dim])), dim
    assert len(np.unique(np.asarray(b.ClusterID))) == 20
    levels = tmp_path / "levels.laz"  # (its levels from the tiles' sums, as fields)
    assert main(["segment", str(src), "--tiles", "2", "--workers", "1", "-k", "20",
                 "--levels", "8,3", "-o", str(levels), "--up-weight", "1"]) == 0
    assert "labels as ClusterID, levels as ClusterID_8, ClusterID_3" in capsys.readouterr().out
    c = laspy.read(levels)
    fine, mid, top = (np.asarray(c[n]) for n in ("ClusterID", "ClusterID_8", "ClusterID_3"))
    assert np.array_equal(fine, np.asarray(b.ClusterID))  # (the same run's labels)
    assert _nested(fine, mid) and _nested(mid, top)
    assert (len(np.unique(mid)), len(np.unique(top))) == (8, 3)
    for args, said in ((["--levels", "8", "-o", str(tmp_path / "l.seg")], "ClusterID_N"),
                       (["--level-cost", "planarity"], "give --levels too"),
                       (["--levels", "8", "--colored-mesh", str(tmp_path / "c.ply")],
                        "--colored-mesh needs the whole input")):
        assert main(["segment", str(src), "--tiles", "2", "-k", "20", *args]) == 2
        assert said in capsys.readouterr().err


def test_a_batch_writes_each_scan_s_own_records(tmp_path, capsys, sphere):
    from superfacets import write_mesh

    folder = tmp_path / "in"
    folder.mkdir()
    _laz(folder / "a.laz", n=1500, seed=1)
    _pcd(folder / "frame.pcd", "binary_compressed")
    write_mesh(folder / "ball.off", sphere)
    out = tmp_path / "out"
    assert main(["batch", str(folder), "-o", str(out), "-k", "9", "--labels", "records",
                 "--workers", "1"]) == 0
    labels = np.asarray(laspy.read(out / "a.laz").ClusterID)
    assert labels.shape == (1500,) and len(np.unique(labels)) == 9
    frame = read_labels(out / "frame.pcd")  # the PCD's ClusterID field
    assert frame.shape == (1200,) and set(frame.tolist()) == set(range(-1, 9))
    assert len(np.unique(read_labels(out / "ball.seg"))) == 9  # a mesh: its label file


def test_a_batch_writes_a_laz_for_every_cloud(tmp_path, sphere, capsys):
    # (--labels records leaves a cloud whose file takes no field a .seg: --labels laz gives
    # every cloud a LAZ, as PDAL and QGIS read them)
    from superfacets import write_mesh

    folder = tmp_path / "in"
    folder.mkdir()
    _laz(folder / "a.las", n=1500, seed=1)
    _pcd(folder / "depth.pcd", "binary")
    frame, cloud, xyz, rgb = _sweep_with_holes(folder)
    write_mesh(folder / "ball.off", sphere)
    out = tmp_path / "out"
    assert main(["batch", str(folder), "-o", str(out), "-k", "9", "--labels", "laz",
                 "--workers", "1", "-q"]) == 0
    assert sorted(p.name for p in out.iterdir() if p.suffix in (".laz", ".seg")) == [
        "a.laz", "ball.seg", "cloud.laz", "depth.laz", "frame.laz"]
    holes = ~np.isfinite(np.load(frame).reshape(-1, 3)).all(axis=1)
    assert (np.asarray(laspy.read(str(out / "frame.laz")).ClusterID)[holes] == -1).all()
    kept = laspy.read(str(out / "a.laz"))  # a LAS input: its own records, every field
    assert np.array_equal(np.asarray(kept.classification),
                          np.asarray(laspy.read(str(folder / "a.las")).classification))
    assert len(np.unique(np.asarray(kept.ClusterID))) == 9
    new = laspy.read(str(out / "cloud.laz"))  # an XYZ: a new file of its points
    assert np.abs(np.c_[new.x, new.y, new.z] - xyz).max() < 1e-6
    assert len(np.unique(np.asarray(new.ClusterID))) == 9
    assert len(np.unique(read_labels(out / "ball.seg"))) == 9  # a mesh: its label file
    levels = tmp_path / "levels"  # each cloud's level beside its labels; the mesh's alone
    assert main(["batch", str(folder), "-o", str(levels), "-k", "9", "--labels", "laz",
                 "--levels", "4", "--workers", "1", "-q"]) == 0
    for name in ("a.laz", "cloud.laz", "depth.laz", "frame.laz"):
        las = laspy.read(str(levels / name))
        fine, coarse = np.asarray(las.ClusterID), np.asarray(las.ClusterID_4)
        assert np.array_equal(fine, np.asarray(laspy.read(str(out / name)).ClusterID)), name
        assert _nested(fine, coarse) and len(np.unique(coarse[coarse >= 0])) == 4, name
    assert np.array_equal(read_labels(levels / "ball.seg"), read_labels(out / "ball.seg"))
    for args, said in ((["--labels", "seg", "--levels", "4"], "labels='records' or 'laz'"),
                       (["--labels", "laz", "--levels", "10"], "they merge (n_segments (-k))")):
        assert main(["batch", str(folder), "-o", str(tmp_path / "no"), "-k", "9", *args,
                     "-q"]) == 2
        assert said in capsys.readouterr().err and not (tmp_path / "no").exists()


def _pcd(path, encoding: str, *, seed=0, label=None):
    """An organized PCD of two terraces, 40 x 30, with packed colour, intensity, a padding
    field (binary: PCL pads records with ``_`` fields; it leaves them out of ASCII and
    compressed files) and a NaN row of points (a depth camera's holes); ``label``: a
    ``label`` field (PCL's ``PointXYZL``) too."""
    rng = np.random.default_rng(seed)
    h, w = 30, 40
    n = h * w
    xy = np.stack(np.meshgrid(np.arange(w) * 0.05, np.arange(h) * 0.05), -1).reshape(-1, 2)
    z = np.where(xy[:, 0] > 1.0, 0.5, 0.0) + rng.normal(0, 0.002, n)
    p = np.c_[xy, z].astype(np.float32)
    p[40:80] = np.nan
    rgb = np.where(xy[:, 0] > 1.0, 0xFF2020, 0x2020FF).astype(np.uint32)
    fields = [("x", "F", 4), ("y", "F", 4), ("z", "F", 4), ("rgb", "U", 4),
              ("intensity", "F", 4)]
    cols = [p[:, 0], p[:, 1], p[:, 2], rgb, rng.random(n).astype(np.float32)]
    if encoding == "binary":
        fields.insert(3, ("_", "U", 1))
        cols.insert(3, np.zeros(n, np.uint8))
    if label is not None:
        fields.append(("label", "U", 4))
        cols.append(np.asarray(label, np.uint32))
    head = ("# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
            f"FIELDS {' '.join(f[0] for f in fields)}\nSIZE {' '.join(str(f[2]) for f in fields)}"
            f"\nTYPE {' '.join(f[1] for f in fields)}\nCOUNT {' '.join('1' for _ in fields)}\n"
            f"WIDTH {w}\nHEIGHT {h}\nVIEWPOINT 0 0 2 0 1 0 0\nPOINTS {n}\nDATA {encoding}\n")
    dtype = [(f"f{i}", {"F": "<f", "U": "<u", "I": "<i"}[t] + str(s))
             for i, (_, t, s) in enumerate(fields)]
    rec = np.empty(n, dtype=dtype)
    for i, c in enumerate(cols):
        rec[f"f{i}"] = c
    if encoding == "ascii":
        body = "".join(" ".join(f"{v:.6g}" if isinstance(v, float) else str(v)
                                for v in row.tolist()) + "\n" for row in rec)
        path.write_bytes(head.encode() + body.encode())
    elif encoding == "binary":
        path.write_bytes(head.encode() + rec.tobytes())
    else:  # compressed by pypcd4 from the binary file's records
        from pypcd4 import Encoding, PointCloud

        plain = path.with_suffix(".txt.pcd")
        _pcd(plain, "ascii", seed=seed, label=label)
        PointCloud.from_path(plain).save(path, encoding=Encoding.BINARY_COMPRESSED)
        plain.unlink()
    return path


def _pcd_head(path) -> list[bytes]:
    raw = path.read_bytes()
    return raw[:raw.index(b"\nDATA ") + 1].split(b"\n")[:-1] + [
        raw[raw.index(b"\nDATA ") + 1:].split(b"\n")[0]]


@pytest.mark.parametrize("encoding", ["ascii", "binary", "binary_compressed"])
def test_pcd_records_keep_the_header_and_every_field(tmp_path, capsys, encoding):
    pypcd4 = pytest.importorskip("pypcd4")
    src = _pcd(tmp_path / "frame.pcd", encoding)
    out = tmp_path / "out.pcd"
    assert main(["segment", str(src), "-k", "6", "-o", str(out)]) == 0
    assert "labels as ClusterID" in capsys.readouterr().out
    before, after = _pcd_head(src), _pcd_head(out)
    grown = {b"FIELDS": b" ClusterID", b"SIZE": b" 4", b"TYPE": b" I", b"COUNT": b" 1"}
    assert len(before) == len(after)
    for a, b in zip(before, after):  # comments, VIEWPOINT, WIDTH x HEIGHT, DATA as they were
        word = a.split()[0] if a.split() else b""
        assert b == a + grown.get(word, b""), (a, b)
    a, b = pypcd4.PointCloud.from_path(src), pypcd4.PointCloud.from_path(out)
    assert b.metadata.data == a.metadata.data
    for na, nb in zip(a.pc_data.dtype.names, b.pc_data.dtype.names):  # (padding: renamed)
        assert np.array_equal(a.pc_data[na], b.pc_data[nb], equal_nan=True), na
    labels = b.pc_data["ClusterID"]
    assert labels.dtype == np.int32
    invalid = np.isnan(a.pc_data["x"])
    assert invalid.sum() == 40 and (labels[invalid] == -1).all()
    assert set(labels[~invalid].tolist()) == set(range(6))
    assert np.array_equal(read_labels(out), labels)
    if encoding == "ascii":  # each line as it was, its label after it
        lines = [ln for ln in src.read_bytes().split(b"DATA ascii\n")[1].splitlines()]
        got = out.read_bytes().split(b"DATA ascii\n")[1].splitlines()
        assert all(g == ln + b" " + str(v).encode() for g, ln, v in zip(got, lines, labels))
    if encoding == "binary":  # the records' bytes, 4 more each
        rec = len(src.read_bytes().split(b"DATA binary\n")[1]) // 1200
        old = np.frombuffer(src.read_bytes().split(b"DATA binary\n")[1], f"V{rec}")
        new = np.frombuffer(out.read_bytes().split(b"DATA binary\n")[1],
                            [("old", f"V{rec}"), ("label", "<i4")])
        assert new["old"].tobytes() == old.tobytes()
        assert np.array_equal(new["label"], labels)
    tool = shutil.which("pcl_convert_pcd_ascii_binary")
    if tool is None:
        pytest.skip("PCL's tools not found: install Debian's 'pcl-tools' package (make test "
                    "does, as root)")
    asc = tmp_path / "pcl.pcd"  # PCL reads the copy, and writes it as ASCII
    run = subprocess.run([tool, str(out), str(asc), "0"], capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0 and "ClusterID" in run.stdout + run.stderr, run.stderr
    head, body = asc.read_text().split("DATA ascii\n")
    fields = next(ln for ln in head.splitlines() if ln.startswith("FIELDS")).split()[1:]
    assert fields[-1] == "ClusterID" and "TYPE F F F U F I" in head
    got = np.array([int(row.split()[-1]) for row in body.splitlines()])
    assert np.array_equal(got, labels)


def test_pcd_records_twice_and_a_pcd_ground_truth(tmp_path, capsys):
    pytest.importorskip("pypcd4")
    truth = (np.arange(1200) % 40 > 20).astype(np.uint32)  # the two terraces
    src = _pcd(tmp_path / "frame.pcd", "binary", label=truth)
    once = write_labels_into(tmp_path / "o.pcd", src, np.where(np.arange(1200) < 3, -1, 1))
    with pytest.warns(UserWarning, match="o.pcd has a field ClusterID"):
        twice = write_labels_into(tmp_path / "p.pcd", once, np.arange(1200) % 7)
    assert _pcd_head(twice) == _pcd_head(once)  # the field overwritten, not added again
    assert np.array_equal(read_labels(twice), np.arange(1200) % 7)
    # the ground truth from the PCD's own label field, the labels from the copy
    assert main(["segment", str(src), "-k", "8", "-o", str(tmp_path / "s.pcd"), "-q"]) == 0
    capsys.readouterr()
    assert main(["evaluate", str(src), str(tmp_path / "s.pcd"), "--ground-truth-field",
                 "label", "--json"]) == 0
    import json

    scores = json.loads(capsys.readouterr().out)
    assert scores["segments"] == 8 and scores["undersegmentation_error"] < 0.05
    assert main(["evaluate", str(src), str(tmp_path / "s.pcd"), "--ground-truth-field",
                 "nope"]) == 2
    err = capsys.readouterr().err
    assert "no field 'nope'" in err and "intensity" in err and "#" not in err


def test_pcd_records_refused_where_they_cannot_be_written(tmp_path, capsys):
    pytest.importorskip("pypcd4")
    src = _pcd(tmp_path / "frame.pcd", "ascii")
    head, body = src.read_bytes().split(b"DATA ascii\n")  # a field of 2 values of that name
    head = head.replace(b"intensity", b"ClusterID").replace(b"COUNT 1 1 1 1 1", b"COUNT 1 1 1 1 2")
    body = b"\n".join(line + b" 0" for line in body.splitlines()) + b"\n"
    (tmp_path / "pair.pcd").write_bytes(head + b"DATA ascii\n" + body)
    with pytest.raises(MeshFormatError, match="type F4 x 2, which cannot hold"):
        write_labels_into(tmp_path / "o.pcd", tmp_path / "pair.pcd", np.zeros(1200, int))
    with pytest.raises(MeshFormatError, match="'classification' of type uint8, which cannot"):
        write_labels_into(tmp_path / "o.las", _laz(tmp_path / "t.las", n=50), np.zeros(50, int),
                          name="classification")  # (a standard dimension stays as it is)
    with pytest.raises(ParameterError, match="1,199 labels for 1,200 points"):
        write_labels_into(tmp_path / "o.pcd", src, np.zeros(1199, int))
    laz = _laz(tmp_path / "tile.laz", n=300)
    for args, said in (([str(src), "-o", str(tmp_path / "o.pcd.gz")], "its own encoding"),
                       ([str(laz), "-o", str(tmp_path / "o.pcd")], "needs a .pcd input")):
        assert main(["segment", *args, "-k", "5"]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and said in err, err
    assert not list(tmp_path.glob("o.*"))


def _retyped(tmp_path, fmt: str):
    """A scan whose label field has the type another program gave it: PDAL's ``uint64``
    ``ClusterID``, CloudCompare's ``float`` scalar field (PLY, PCD, LAS)."""
    from plyfile import PlyData, PlyElement

    if fmt in ("las-uint64", "las-float"):
        las = laspy.read(_laz(tmp_path / "tile.las", n=1200))
        las.add_extra_dim(laspy.ExtraBytesParams(
            name="ClusterID", type=np.uint64 if fmt == "las-uint64" else np.float32))
        las.ClusterID = np.full(1200, 7)
        las.write(str(tmp_path / "old.las"))
        return tmp_path / "old.las", tmp_path / "new.laz"
    if fmt == "ply-float":
        v = np.zeros(1200, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"),
                                  ("scalar_ClusterID", "<f4"), ("red", "u1")])
        p = np.random.default_rng(3).normal(size=(1200, 3))
        v["x"], v["y"], v["z"] = (p / np.linalg.norm(p, axis=1, keepdims=True)).T
        v["scalar_ClusterID"], v["red"] = 7.0, 9
        PlyData([PlyElement.describe(v, "vertex")]).write(str(tmp_path / "old.ply"))
        return tmp_path / "old.ply", tmp_path / "new.ply"
    pytest.importorskip("pypcd4")
    src = _pcd(tmp_path / "frame.pcd", fmt.split("-")[1])
    (tmp_path / "old.pcd").write_bytes(src.read_bytes().replace(b"intensity", b"ClusterID"))
    return tmp_path / "old.pcd", tmp_path / "new.pcd"


@pytest.mark.parametrize("fmt", ["las-uint64", "las-float", "ply-float", "pcd-ascii",
                                 "pcd-binary", "pcd-binary_compressed"])
def test_a_label_field_of_another_type_is_made_int32(tmp_path, fmt):
    # (they were refused: "has a vertex property 'scalar_ClusterID' of type float32, which
    # cannot hold the labels", so a cloud CloudCompare had saved could not be segmented again)
    src, out = _retyped(tmp_path, fmt)
    before = read_input_fields(src)
    assert main(["segment", str(src), "-k", "6", "-o", str(out), "-q"]) == 0
    after = read_input_fields(out)
    labels = read_labels(out)
    assert after["ClusterID"].dtype == np.int32 and np.array_equal(after["ClusterID"], labels)
    assert len(np.unique(labels[labels >= 0])) == 6 and (labels != 7).any()
    assert before.keys() == after.keys()
    for name in before:  # every other field kept
        if name != "ClusterID":
            assert np.array_equal(before[name], after[name], equal_nan=True), name


def read_input_fields(path) -> dict:
    """Each field of a scan's points by name (a PLY's ``scalar_`` prefix dropped)."""
    from plyfile import PlyData

    suffix = path.suffix
    if suffix in (".las", ".laz"):
        las = laspy.read(str(path))
        return {n: np.asarray(las[n]) for n in las.point_format.dimension_names}
    if suffix == ".ply":
        v = PlyData.read(str(path))["vertex"]
        return {p.name.removeprefix("scalar_"): np.asarray(v[p.name]) for p in v.properties}
    from pypcd4 import PointCloud

    data = PointCloud.from_path(path).pc_data
    return {n: np.asarray(data[n]) for n in data.dtype.names  # (not padding: "_", or the
            if n.isidentifier() and n != "_"}                  # random names pypcd4 gives it)


def test_a_cloud_cloudcompare_saved_segments_again_and_it_reads_the_new_labels(tmp_path):
    if shutil.which("CloudCompare") is None:
        pytest.skip("CloudCompare not found: install Debian's 'cloudcompare' package (make "
                    "test does, as root)")
    src, _ = _retyped(tmp_path, "ply-float")
    first, saved, again = tmp_path / "a.ply", tmp_path / "cc.ply", tmp_path / "b.ply"
    assert main(["segment", str(src), "-k", "5", "-o", str(first), "-q"]) == 0
    _cloudcompare(tmp_path, first, "PLY", saved)
    assert b"property float scalar_ClusterID" in saved.read_bytes()[:1000]  # (its own type)
    assert main(["segment", str(saved), "-k", "12", "-o", str(again), "-q"]) == 0
    asc = tmp_path / "b.asc"
    _cloudcompare(tmp_path, again, "ASC", asc)
    head = asc.read_text().splitlines()[0]
    got = np.loadtxt(asc, comments="//")[:, head.lstrip("/").split().index("ClusterID")]
    assert np.array_equal(got.astype(int), read_labels(again))
    assert len(np.unique(got)) == 12


def _cloudcompare(home, path, fmt: str, out) -> None:
    """CloudCompare's command line, headless: ``path`` saved as ``fmt`` to ``out``."""
    extra = ["-ADD_HEADER"] if fmt == "ASC" else []
    run = subprocess.run(["CloudCompare", "-SILENT", "-AUTO_SAVE", "OFF", "-O", str(path),
                          "-C_EXPORT_FMT", fmt, *extra, "-SAVE_CLOUDS", "FILE", str(out)],
                         capture_output=True, text=True, timeout=120,
                         env={"QT_QPA_PLATFORM": "offscreen", "PATH": "/usr/bin:/bin",
                              "HOME": str(home)})
    assert run.returncode == 0 and out.exists(), run.stdout[-2000:]


def _sweep_with_holes(tmp_path):
    """An organized frame (NPY (H, W, 3)) with NaN holes, and an XYZ cloud with colours."""
    rng = np.random.default_rng(3)
    u, v = np.meshgrid(np.linspace(0, 4, 40), np.linspace(0, 3, 30))
    frame = np.dstack([u, v, 0.2 * np.sin(u)])
    frame[rng.random((30, 40)) < 0.05] = np.nan
    np.save(tmp_path / "frame.npy", frame)
    xyz = np.c_[rng.uniform(0, 10, (2000, 2)), np.zeros(2000)]
    rgb = rng.integers(0, 256, (2000, 3))
    np.savetxt(tmp_path / "cloud.xyz", np.c_[xyz, rgb], header="x y z r g b",
               comments="// ", fmt="%.6f %.6f %.6f %d %d %d")
    return tmp_path / "frame.npy", tmp_path / "cloud.xyz", xyz, rgb


def test_a_cloud_whose_file_takes_no_field_is_written_as_a_new_scan(tmp_path, capsys):
    # (refused before: "-o writes the labels as text ..., not a .laz file")
    frame, cloud, xyz, rgb = _sweep_with_holes(tmp_path)
    for src, k in ((cloud, 12), (frame, 8)):
        text = tmp_path / f"{src.stem}.seg"
        assert main(["segment", str(src), "-k", str(k), "-o", str(text), "-q"]) == 0
        want = read_labels(text)
        for out in (tmp_path / f"{src.stem}.laz", tmp_path / f"{src.stem}.ply"):
            assert main(["segment", str(src), "-k", str(k), "-o", str(out)]) == 0
            assert "a new file of the input's points" in capsys.readouterr().out
            fields = read_input_fields(out)
            assert np.array_equal(fields["ClusterID"], want) and fields["ClusterID"].dtype \
                == np.int32
            assert np.array_equal(read_labels(out), want)  # (evaluate reads it back)
    las = laspy.read(str(tmp_path / "cloud.laz"))
    assert np.abs(np.c_[las.x, las.y, las.z] - xyz).max() < 1e-6
    assert np.array_equal(np.c_[las.red, las.green, las.blue] // 257, rgb)
    holes = ~np.isfinite(np.load(frame).reshape(-1, 3)).all(axis=1)
    las = laspy.read(str(tmp_path / "frame.laz"))
    assert holes.any() and np.array_equal(np.asarray(las.withheld, bool), holes)
    assert (np.asarray(las.ClusterID)[holes] == -1).all()
    ply = read_input_fields(tmp_path / "frame.ply")
    assert np.isnan(ply["x"][holes]).all() and np.isfinite(ply["x"][~holes]).all()
    # tiles write the same new file; a LAS input still takes only LAS records
    for out in ("tiled.laz", "tiled.seg"):
        assert main(["segment", str(cloud), "-k", "12", "--tiles", "2", "-o",
                     str(tmp_path / out), "-q"]) == 0
    assert np.array_equal(read_labels(tmp_path / "tiled.laz"),
                          read_labels(tmp_path / "tiled.seg"))
    assert main(["segment", str(tmp_path / "cloud.laz"), "-k", "5", "-o",
                 str(tmp_path / "x.ply")]) == 2
    assert "needs a .ply input" in capsys.readouterr().err


def test_a_new_scan_opens_in_cloudcompare_with_its_labels(tmp_path):
    if shutil.which("CloudCompare") is None:
        pytest.skip("CloudCompare not found: install Debian's 'cloudcompare' package (make "
                    "test does, as root)")
    _, cloud, _, _ = _sweep_with_holes(tmp_path)
    out, asc = tmp_path / "new.ply", tmp_path / "new.asc"
    assert main(["segment", str(cloud), "-k", "9", "-o", str(out), "-q"]) == 0
    _cloudcompare(tmp_path, out, "ASC", asc)
    head = asc.read_text().splitlines()[0].lstrip("/").split()
    got = np.loadtxt(asc, comments="//")
    assert np.array_equal(got[:, head.index("ClusterID")].astype(int), read_labels(out))
    assert {"R", "G", "B"} <= set(head)  # (the colours it was read with)


def test_a_new_scan_is_written_from_any_cloud_and_refuses_a_mesh(tmp_path):
    import trimesh

    from superfacets.io.records import write_cloud_with_labels

    xyz = np.random.default_rng(0).random((5, 3))
    out = write_cloud_with_labels(tmp_path / "a.ply", xyz, [0, 0, 1, 1, -1])
    assert read_labels(out).tolist() == [0, 0, 1, 1, -1]
    with pytest.raises(TypeError, match="expected a point cloud"):
        write_cloud_with_labels(tmp_path / "b.ply", trimesh.creation.box(), [0] * 8)
    with pytest.raises(ParameterError, match="4 labels for 5 points"):
        write_cloud_with_labels(tmp_path / "c.laz", xyz, [0] * 4)
    with pytest.raises(ParameterError, match="written as .las, .laz or .ply"):
        write_cloud_with_labels(tmp_path / "d.pcd", xyz, [0] * 5)
    assert not [p.name for p in tmp_path.iterdir() if p.name != "a.ply"]


@pytest.mark.parametrize("extent, corner", [(1e-6, -4e-7), (1.0, 0.0), (300.0, 5e5),
                                            (1e9, -4e8), (1e-10, 3e-10), (1e-30, 0.0)])
def test_a_new_las_keeps_the_points_to_a_millionth_of_their_extent(tmp_path, extent, corner):
    # (an offset rounded to a whole unit took a millimetre cloud near the origin to a
    # precision of half its size; a scale of at least 1e-12 a cloud of 1e-10 to 100 steps)
    from superfacets.io.records import write_cloud_with_labels

    xyz = np.random.default_rng(2).random((200, 3)) * extent + corner
    out = write_cloud_with_labels(tmp_path / "c.laz", xyz, np.arange(200) % 5)
    las = laspy.read(str(out))
    assert np.abs(np.c_[las.x, las.y, las.z] - xyz).max() <= 1e-6 * extent


@pytest.mark.parametrize("suffix", ["laz", "ply"])
def test_a_new_scan_s_invalid_points_are_invalid_when_read_again(tmp_path, capsys, suffix):
    # (a LAS's withheld points, "not to be processed" by the ASPRS specification, were
    # segmented; a frame's holes written as withheld came back as one superpoint of
    # coincident points at the file's offset; written NaN into a new PLY, refused: "only
    # organized clouds and PCD files may mark invalid points with NaN")
    from superfacets import segment, segment_tiled

    frame, _, _, _ = _sweep_with_holes(tmp_path)
    holes = ~np.isfinite(np.load(frame).reshape(-1, 3)).all(axis=1)
    out = tmp_path / f"frame.{suffix}"
    assert main(["segment", str(frame), "-k", "8", "-o", str(out), "-q"]) == 0
    for labels in (segment(out, 8).labels, segment_tiled(out, 8, tiles=2).labels):
        assert np.array_equal(labels < 0, holes) and len(np.unique(labels[~holes])) == 8
    assert main(["segment", str(out), "-k", "8", "--tiles", "2"]) == 0
    assert f"1,200 points ({holes.sum():,} invalid)" in capsys.readouterr().out


def test_a_ply_row_nan_in_one_coordinate_is_damage_named_by_its_row(tmp_path):
    from superfacets import segment, segment_tiled
    from superfacets.inputs.cloud import InvalidCloudError

    # a row NaN in one coordinate only is damage, named by its row, whole or in tiles
    rows = "0 0 0\n1 0 0\nnan nan nan\n0 1 nan\n1 1 1\n0 2 0\n"
    (tmp_path / "part.ply").write_text("ply\nformat ascii 1.0\nelement vertex 6\nproperty "
                                       "float x\nproperty float y\nproperty float z\n"
                                       "end_header\n" + rows)
    for run in (lambda p: segment(p, 2), lambda p: segment_tiled(p, 2, tiles=2)):
        with pytest.raises(InvalidCloudError, match=r"point 3 has a non-finite coordinate "
                           r"\(\[0.0, 1.0, nan\]\): a missing point is NaN in all three"):
            run(tmp_path / "part.ply")


def test_a_new_file_of_a_cloud_keeps_its_other_values(tmp_path, capsys):
    """``-o OUT.ply`` / ``OUT.laz`` of a cloud whose file takes no field: a KITTI scan's
    reflectance, a nuScenes sweep's intensity and ring, NPY records' fields, a text cloud's
    named columns were dropped; now a PLY's ``scalar_<field>`` (CloudCompare's) and a LAS's
    standard dimension where the values fit, else an extra dimension."""
    from plyfile import PlyData

    rng = np.random.default_rng(0)
    xyz = np.c_[rng.uniform(0, 20, (3000, 2)), rng.normal(0, 0.02, 3000)].astype("<f4")
    level = np.round(rng.uniform(0, 255, 3000)).astype("<f4")
    ring = rng.integers(0, 32, 3000).astype("<f4")
    (tmp_path / "sweep.pcd.bin").write_bytes(np.c_[xyz, level, ring].astype("<f4").tobytes())
    (tmp_path / "scan.bin").write_bytes(np.c_[xyz, level / 255].astype("<f4").tobytes())
    records = np.zeros(3000, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"),
                                    ("intensity", "<f4"), ("t", "<f8"), ("ok", "?")])
    records["x"], records["y"], records["z"] = xyz.T
    records["intensity"], records["t"], records["ok"] = level / 7, np.arange(3000), True
    np.save(tmp_path / "records.npy", records)
    cases = {"sweep.pcd.bin": {"intensity": level, "ring": ring},
             "scan.bin": {"reflectance": level / 255},
             "records.npy": {"intensity": level / 7, "t": np.arange(3000), "ok": np.ones(3000)}}
    for name, values in cases.items():
        ply, laz = tmp_path / f"{name}.ply", tmp_path / f"{name}.laz"
        assert main(["segment", str(tmp_path / name), "-k", "10", "-o", str(ply), "-q"]) == 0
        vertex = PlyData.read(str(ply))["vertex"]
        for field, want in values.items():
            assert np.allclose(vertex[f"scalar_{field}"], want, atol=1e-4), (name, field)
        capsys.readouterr()
        assert main(["segment", str(tmp_path / name), "-k", "10", "-o", str(laz), "-q"]) == 0
        said = [ln for ln in capsys.readouterr().err.splitlines() if "not kept" in ln]
        # a float intensity (records' level / 7) fits no LAS intensity: said, not rounded
        lost = ["intensity"] if name == "records.npy" else []
        assert said == [f"superfacets: warning: field '{f}' is not kept in the new LAS file: "
                        "LAS's intensity holds whole numbers 0..65535; a .ply keeps every "
                        "field" for f in lost], name
        las = laspy.read(laz)
        dims = {d.lower(): d for d in las.point_format.dimension_names}
        for field in set(values) - set(lost):
            assert np.allclose(las[dims[field]], values[field], atol=1e-4), (name, field)
        assert las.intensity.dtype == np.uint16 and not (lost and las.intensity.any())
    assert main(["segment", str(tmp_path / "sweep.pcd.bin"), "-k", "10", "-o",
                 str(tmp_path / "said.laz")]) == 0
    assert ("wrote " + str(tmp_path / "said.laz") + " (a new file of the input's points with "
            "their intensity and ring, labels as ClusterID)") in capsys.readouterr().out
    assert main(["segment", str(tmp_path / "sweep.pcd.bin"), "-k", "10", "--tiles", "2",
                 "--workdir", str(tmp_path / "work"), "-o", str(tmp_path / "tiled.laz")]) == 0
    assert "(a new file of the input's points with their intensity and ring, labels as " \
        "ClusterID)" in capsys.readouterr().out
    assert np.array_equal(laspy.read(tmp_path / "tiled.laz")["ring"], ring)
    if shutil.which("CloudCompare") is None:
        pytest.skip("CloudCompare not found: install Debian's 'cloudcompare' package (make "
                    "test does, as root)")
    asc = tmp_path / "sweep.asc"
    _cloudcompare(tmp_path, tmp_path / "sweep.pcd.bin.ply", "ASC", asc)
    head = asc.read_text().splitlines()[0].lstrip("/").split()
    assert {"intensity", "ring", "ClusterID"} <= set(head), head
    got = np.loadtxt(asc, comments="//")
    assert np.allclose(got[:, head.index("ring")], ring)


def _nested(fine: np.ndarray, coarse: np.ndarray) -> bool:
    """Whether every segment of ``fine`` lies in one segment of ``coarse`` (-1 with -1)."""
    pairs = np.unique(np.c_[fine, coarse], axis=0)
    return len(pairs) == len(np.unique(fine)) and ((pairs[:, 0] < 0) == (pairs[:, 1] < 0)).all()


@pytest.mark.parametrize("name", ["out.laz", "out.las"])
def test_levels_go_into_the_las_after_the_labels_and_evaluate_reads_each(tmp_path, capsys,
                                                                         name):
    src, out, graph = _laz(tmp_path / "tile.laz"), tmp_path / name, tmp_path / "g.npz"
    assert main(["segment", str(src), "-k", "12", "--levels", "3,6", "-o", str(out)]) == 0
    assert "labels as ClusterID, levels as ClusterID_6, ClusterID_3" in capsys.readouterr().out
    assert main(["segment", str(src), "-k", "12", "--levels", "6,3", "--graph", str(graph),
                 "-q"]) == 0
    las, a = laspy.read(str(out)), laspy.read(str(src))
    assert list(las.point_format.dimension_names) == list(a.point_format.dimension_names) + [
        "ClusterID", "ClusterID_6", "ClusterID_3"]
    saved = np.load(graph)
    fields = [np.asarray(las[n]) for n in ("ClusterID", "ClusterID_6", "ClusterID_3")]
    for got, want, count in zip(fields, ("labels", "labels_0", "labels_1"), (12, 6, 3)):
        assert got.dtype == np.int32 and np.array_equal(got, saved[want])  # (the same run's)
        assert len(np.unique(got)) == count
    assert _nested(fields[0], fields[1]) and _nested(fields[1], fields[2])
    assert main(["evaluate", str(out), "--labels-from", "ClusterID_6", "--ground-truth-field",
                 "classification", "--json"]) == 0
    import json

    scores = json.loads(capsys.readouterr().out)
    assert scores["segments"] == 6 and scores["labels"] == "ClusterID_6"
    assert scores["ground_truths"] == 1 and 0 <= scores["undersegmentation_error"] < 0.2
    truth = tmp_path / "truth.seg"  # (with --labels-from, every file named is a truth)
    np.savetxt(truth, fields[2], fmt="%d")
    assert main(["evaluate", str(out), "--labels-from", "ClusterID_3", str(truth)]) == 0
    said = capsys.readouterr().out
    assert "3 superpoints, 1 ground truth" in said and "undersegmentation_error 0.0000" in said


def test_levels_without_a_file_that_holds_them_are_refused_before_the_run(tmp_path, capsys):
    src = _laz(tmp_path / "tile.laz")
    out = tmp_path / "out.seg"
    assert main(["segment", str(src), "-k", "12", "--levels", "6", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--graph OUT.npz" in err and "ClusterID_N" in err and not out.exists()
    assert main(["segment", str(src), "-k", "12", "--levels", "13", "-o",
                 str(tmp_path / "o.laz")]) == 2  # (a level above k: refused before the run)
    said = "--levels must each be at most the 12 segments they merge (-k)"
    assert said in capsys.readouterr().err
    assert not (tmp_path / "o.laz").exists() and [p.name for p in tmp_path.iterdir()] == [
        "tile.laz", ]
    assert main(["evaluate", str(src)]) == 2
    assert "LABELS (a file) or --labels-from FIELD" in capsys.readouterr().err


@pytest.mark.parametrize("encoding", ["ascii", "binary_compressed"])
def test_levels_go_into_pcd_records_and_a_new_scan(tmp_path, capsys, encoding):
    pytest.importorskip("pypcd4")
    src = _pcd(tmp_path / "frame.pcd", encoding)
    out = tmp_path / "out.pcd"
    assert main(["segment", str(src), "-k", "8", "--levels", "4,2", "-o", str(out), "-q"]) == 0
    head = _pcd_head(out)
    assert next(ln for ln in head if ln.startswith(b"FIELDS")).split()[-3:] == [
        b"ClusterID", b"ClusterID_4", b"ClusterID_2"]
    got = read_input_fields(out)
    invalid = got["ClusterID"] < 0
    assert invalid.sum() == 40  # (the frame's holes: -1 at every level)
    for fine, coarse, count in (("ClusterID", "ClusterID_4", 4),
                                ("ClusterID_4", "ClusterID_2", 2)):
        assert (got[coarse][invalid] == -1).all() and _nested(got[fine], got[coarse])
        assert len(np.unique(got[coarse][~invalid])) == count
    _, cloud, _, _ = _sweep_with_holes(tmp_path)  # a text cloud: a new file, levels in it
    for new in (tmp_path / "new.laz", tmp_path / "new.ply"):
        assert main(["segment", str(cloud), "-k", "9", "--levels", "3", "-o", str(new)]) == 0
        said = capsys.readouterr().out
        assert ("levels as scalar_ClusterID_3" if new.suffix == ".ply" else
                "levels as ClusterID_3") in said
        fields = read_input_fields(new)
        assert list(fields)[-2:] == ["ClusterID", "ClusterID_3"]
        assert _nested(fields["ClusterID"], fields["ClusterID_3"])
        assert len(np.unique(fields["ClusterID_3"])) == 3


def test_levels_of_a_ply_open_in_cloudcompare_and_a_second_run_replaces_them(tmp_path,
                                                                             capsys):
    _, cloud, _, _ = _sweep_with_holes(tmp_path)
    first, again = tmp_path / "a.ply", tmp_path / "b.ply"
    assert main(["segment", str(cloud), "-k", "9", "--levels", "4", "-o", str(first),
                 "-q"]) == 0
    assert main(["segment", str(first), "-k", "12", "--levels", "4,2", "-o", str(again),
                 "-q"]) == 0
    assert "warning: a.ply has a field scalar_ClusterID_4" in capsys.readouterr().err
    tiled = tmp_path / "t.ply"  # (a tiled run's summary names the PLY's fields as one run's)
    assert main(["segment", str(first), "-k", "12", "--tiles", "2", "--workers", "1",
                 "--levels", "4", "-o", str(tiled)]) == 0
    assert ("labels as scalar_ClusterID, CloudCompare's scalar field ClusterID, levels as "
            "scalar_ClusterID_4") in capsys.readouterr().out
    assert list(read_input_fields(tiled))[-2:] == ["ClusterID", "ClusterID_4"]
    fields = read_input_fields(again)
    assert list(fields)[-3:] == ["ClusterID", "ClusterID_4", "ClusterID_2"]
    assert len(np.unique(fields["ClusterID"])) == 12 and _nested(fields["ClusterID"],
                                                                 fields["ClusterID_4"])
    if shutil.which("CloudCompare") is None:
        pytest.skip("CloudCompare not found: install Debian's 'cloudcompare' package (make "
                    "test does, as root)")
    asc = tmp_path / "b.asc"
    _cloudcompare(tmp_path, again, "ASC", asc)
    head = asc.read_text().splitlines()[0].lstrip("/").split()
    got = np.loadtxt(asc, comments="//")
    for name in ("ClusterID", "ClusterID_4", "ClusterID_2"):  # CloudCompare's scalar fields
        assert np.array_equal(got[:, head.index(name)].astype(int), fields[name]), name
