"""Labelled real scans: public LiDAR and RGB-D point clouds with per-point ground truth.

Superpoints are judged on real scans (noise, uneven density, occlusion) by
the same metrics as on meshes, against each point's annotated class. The
scans listed in :data:`SCANS` are small public files from the test and demo
data of well-known open-source projects, pinned to one commit and checked by
SHA-256. They are never part of this repository: :func:`fetch_scan`
downloads them once into a cache folder (``$SUPERFACETS_SCANS``, by default
``~/.cache/superfacets/scans``), and :func:`load_scan` reads them from there.

Ground truth is the annotated class of each point (semantic labels, the
usual ground truth of superpoint benchmarks on scans: S3DIS, ScanNet,
SemanticKITTI, DALES). Points that no annotator labelled carry :data:`UNLABELLED` and are
left out of the metrics (``evaluate(..., ignore_label=UNLABELLED)``).

Orientation: every scan here has z up, so its clouds carry ``up = (0, 0, 1)``
(each connected piece's normals turned up by a vote, as a LAS file's; in the
ScanNet rooms that turns the floor's normals up, into the room, and the
walls' with them, so a room's corners read as concave, as seen from where
it was scanned). The
two SemanticKITTI frames are not both in their sensor's coordinates: frame
000700 has no point within 25 m of the origin, and the run of its scan lines
puts its sensor about 99 m from it (frame 000750's sensor is near the
origin), so no viewpoint is assumed.

Examples
--------
>>> from superfacets.evaluation.datasets.scans import load_scan  # doctest: +SKIP
>>> scan = load_scan("semantickitti-000700")          # doctest: +SKIP
>>> scan.cloud.n_total, scan.ground_truth.shape       # doctest: +SKIP
(85962, (85962,))
"""

from __future__ import annotations

import os
import urllib.request
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..._runtime import extras
from ...errors import MeshFormatError, ParameterError
from ...inputs.cloud import PointCloud
from ...io import read_cloud
from ...io.files import sha256_of
from ..metrics import evaluate_rows

__all__ = ["Scan", "ScanSource", "SCANS", "UNLABELLED", "scan_cache", "scan_files",
           "fetch_scan", "load_scan", "missing_help", "evaluate_scan"]

#: The ground-truth value of a point that no annotator labelled.
UNLABELLED = -1


@dataclass(frozen=True)
class ScanSource:
    """One labelled scan: where its files come from and how its labels are read.

    Attributes
    ----------
    name : str
        Key in :data:`SCANS`.
    kind : str
        The sensor and scene, for tables (``"mobile LiDAR, street"``).
    files : tuple of (str, str, str)
        ``(file name in the cache, URL, SHA-256)`` of each file.
    labels : str
        How the ground truth is read: ``"semantickitti"`` (a second ``.npy``
        of the 19 training classes, 0 unlabelled; the cloud is seen from
        above, ``up = (0, 0, 1)``: see the module notes)
        or ``"las"`` (the LAS ``classification`` field, ASPRS codes; 0,
        "never classified", is unlabelled) or ``"scannet"`` (an ``.npy`` of
        ``x y z r g b`` rows, colours 0-255, an ``.npy`` of NYU40 class
        ids and one of object instance ids, 0 unannotated in both; seen from
        above).
    credit : str
        Who made the data and under which licence.
    spt_preset : str
        The Superpoint Transformer dataset settings nearest this scan's
        sensor and scene (a key of
        :data:`superfacets.evaluation.baselines.spt_partition.PRESETS`), for
        that baseline.
    instance_field : str
        A LAS extra dimension naming each point's object (lidR's ``treeID``: 0 where
        the point is on no tree; those take one instance per class), or ``""``.
    """

    name: str
    kind: str
    files: tuple
    labels: str
    credit: str
    spt_preset: str = "scannet"
    instance_field: str = ""


def _github(repo: str, commit: str, path: str) -> str:
    return f"https://raw.githubusercontent.com/{repo}/{commit}/{path}"


_O3D = ("isl-org/Open3D-ML", "0cbfde63a7eb5821f73118bbe0cf20ca353bb974")
_PDAL = ("PDAL/PDAL", "ccf0ab7046072f68cab78734e90d0d3149f3af10")
_MMDET3D = ("open-mmlab/mmdetection3d", "9e39d469eb37054d469b8979ae5ac031a48017fc")
_LIDR = ("r-lidar/lidR", "d185a7eb3d8de52272c9c60500fd104b97197cf3")


def _las(name: str, kind: str, repo: tuple, path: str, sha: str, credit: str, *,
         instance_field: str = "") -> ScanSource:
    """An airborne tile of a project's test data, its ASPRS classes as ground truth."""
    return ScanSource(name, kind, ((f"{name.replace('-', '_')}.{path.rsplit('.', 1)[1]}",
                                    _github(*repo, path), sha),), "las", credit, "dales",
                      instance_field)


_LIDR_CREDIT = ("from lidR's example data (Roussel et al., Remote Sensing of Environment "
                "2020; GPL-3 package, data as shipped in inst/extdata): ASPRS classes ")
_PDAL_CREDIT = "from PDAL's test data (BSD): ASPRS classes "


def _pinned(repo: tuple, prefix: str, files) -> tuple:
    """``(cache name, URL, SHA-256)`` of each ``(suffix, path in repo, sha)``: the cache
    name is ``{prefix}_{suffix}.npy``."""
    return tuple((f"{prefix}_{suffix}.npy", _github(*repo, path), sha)
                 for suffix, path, sha in files)


def _kitti(frame: str, points_sha: str, labels_sha: str) -> ScanSource:
    base = "examples/demo_data/SemanticKITTI"
    return ScanSource(
        f"semantickitti-{frame}", "mobile LiDAR (Velodyne HDL-64E), street",
        _pinned(_O3D, f"semantickitti_{frame}",
                (("points", f"{base}/points/{frame}.npy", points_sha),
                 ("labels", f"{base}/labels/{frame}.npy", labels_sha))),
        "semantickitti",
        "SemanticKITTI (Behley et al., ICCV 2019; CC BY-NC-SA 4.0), sequence 08 frame "
        f"{frame} as shipped in Open3D-ML's demo data (19 classes, 0 unlabelled)", "kitti360")


def _scannet(scene: str, points_sha: str, labels_sha: str, instances_sha: str) -> ScanSource:
    base = f"tests/data/scannet/scannet_train_instance_data/{scene}"
    return ScanSource(
        f"scannet-{scene}", "indoor RGB-D reconstruction (Structure sensor), a room",
        _pinned(_MMDET3D, f"scannet_{scene}",
                (("points", f"{base}_vert_all.npy", points_sha),
                 ("labels", f"{base}_sem_label_all.npy", labels_sha),
                 ("instances", f"{base}_ins_label_all.npy", instances_sha))),
        "scannet",
        f"ScanNet (Dai et al., CVPR 2017; ScanNet terms of use, non-commercial research), "
        f"{scene}: every vertex of the room's reconstruction, axis-aligned, with its colour, "
        "NYU40 class and object instance (0 unannotated), as shipped in MMDetection3D's "
        "test data")


#: The labelled scans, by name.
SCANS: dict[str, ScanSource] = {s.name: s for s in (
    _kitti("000700", "b973b11a6eb4d0bab3e25b2cff811bab8184194e49e8bdfef6a51646c0368fb4",
           "bf17c72c6b148fb2820b9446faa6e9b96926c6f495c1ea8bcdbb2d05f9edbe62"),
    _kitti("000750", "b2c1ea24de6301a87615a821e75fc82d2fc551798b3525fc2ab1f258e0b2cb7f",
           "bfed4664e59cd49b2b25092579bdea2b81a22a43045bfdc24feac40e5ce5c347"),
    ScanSource(
        "lidarhd-rgb", "airborne LiDAR (RIEGL) with RGB",
        (("lidarhd_rgb.laz", _github(*_PDAL, "test/data/laz/las_with_several_extra_byte_bloc.laz"),
          "4acb579c77e2b8eb07136d55857481122d87991490aa7c875893341005e043e7"),),
        "las",
        "a crop of an airborne survey of France (Lambert-93 coordinates, RIEGL scanner, "
        "classified with TerraScan in the IGN LiDAR HD scheme, coloured), from PDAL's test "
        "data: ASPRS classes ground, low/medium/high vegetation, building, unclassified, "
        "and 65 (IGN's artefacts)", "dales"),
    _las("lidr-megaplot", "airborne LiDAR, forest plot", _LIDR, "inst/extdata/Megaplot.laz",
         "e6526a427e3a7554dc7fd9df13900b8365b2136c6ff219a9fc130844c853a627",
         _LIDR_CREDIT + "ground and unclassified (the trees)"),
    _las("lidr-mixedconifer", "airborne LiDAR, conifer forest", _LIDR,
         "inst/extdata/MixedConifer.laz",
         "b7af31a4cf752044e493c3620d4f4301aa41553dd840502569f2f110ad876eb3",
         _LIDR_CREDIT + "ground, unclassified and water; each tree an instance (treeID)",
         instance_field="treeID"),
    _las("lidr-topography", "airborne LiDAR, hilly terrain", _LIDR,
         "inst/extdata/Topography.laz",
         "3016d0d654a7b38f5589c1f60c302a50045b9bba6b2047b2e47a474e9ac8c149",
         _LIDR_CREDIT + "ground, unclassified and water"),
    _las("pdal-autzen", "airborne LiDAR, town (Autzen Stadium, Oregon)", _PDAL,
         "test/data/las/autzen_trim.las",
         "3d351885f3aa03d5ac92358037ba0b850ea4f56f644ffcc56d57cd5d830aaf75",
         _PDAL_CREDIT + "ground and unclassified (buildings, trees)"),
    _las("pdal-crop", "airborne LiDAR, 200 m tile", _PDAL, "test/data/las/4_6_crop.las",
         "c432b44d4e938ed3895d3a8515f4e425da1ae5d9cffa74f95937854c40b8ed83",
         _PDAL_CREDIT + "ground and unclassified"),
    _las("pdal-sample", "airborne LiDAR, classified town block", _PDAL,
         "test/data/las/sample_c.las",
         "6f6b0be5970a86fceddde988ef6ae42661309a5067a6f65019581300e1df4fe8",
         _PDAL_CREDIT + "ground, low/medium/high vegetation, building and others"),
    _las("pdal-hexbin", "airborne LiDAR, open ground", _PDAL, "test/data/filters/hexbin-crop.las",
         "d1206c580a8c9c56ae7b7bac4ac09d3e7c0082365fcd2340eeffcf6a2825ceef",
         _PDAL_CREDIT + "ground and unclassified"),
    _scannet("scene0000_00", "c73b979bbff0bb2cc93cf6d57aea10234c807d246df16c6ecc40e8fbd896ac00",
             "7b5bf6e35fd5007618dc22748f50991208635be3aec9783ffd3f0f93761e2f68",
             "5ef2f8b2622c3512a19902807294216130f6332872cf3db121f6d5815cd0a8c4"),
    _scannet("scene0000_01", "1c0aee74f2c94ecd67d5726831120335c44fa201b60c6822689439f5fa9b6d01",
             "1eeccfd9d3bd6ea431ffe4d79c9a0bbef8ce7e36a2ed1d4fceebc7451e6071c1",
             "152df03e56a93b9523779e6af9b365520f1d930b356c1107881e451daa2ce0bd"),
)}


@dataclass
class Scan:
    """A labelled scan read from the cache.

    Attributes
    ----------
    name : str
    cloud : PointCloud
        The points in file order (colours where the file has them).
    ground_truth : (N,) int64 ndarray
        One class per point, in file order; :data:`UNLABELLED` (-1) where no
        annotator labelled the point.
    source : ScanSource
    instances : (N,) int64 ndarray or None
        The object instance of each point, where the scan has them (the
        ScanNet rooms: two chairs of one class are two instances);
        :data:`UNLABELLED` where unannotated.
    """

    name: str
    cloud: object
    ground_truth: np.ndarray
    source: ScanSource
    instances: np.ndarray | None = None


def scan_cache() -> Path:
    """``$SUPERFACETS_SCANS``, by default ``~/.cache/superfacets/scans``."""
    default = Path(os.environ.get("SUPERFACETS_CACHE",
                                  Path.home() / ".cache" / "superfacets")) / "scans"
    return Path(os.environ.get("SUPERFACETS_SCANS", default))


def _folder(cache) -> Path:
    return Path(cache) if cache is not None else scan_cache()


def _source(name: str) -> ScanSource:
    try:
        return SCANS[name]
    except KeyError:
        raise ParameterError(f"unknown scan {name!r}; known: {', '.join(SCANS)}") from None


def scan_files(name: str, cache=None) -> list[Path]:
    """The paths the files of scan ``name`` have in the cache (present or not)."""
    folder = _folder(cache)
    return [folder / f for f, _, _ in _source(name).files]


def missing_help(name: str, cache=None) -> str:
    """What to do when scan ``name`` is not in the cache: the files and where they come from."""
    src = _source(name)
    folder = _folder(cache)
    lines = [f"scan {name!r} is not in {folder}: run fetch_scan({name!r}) (network needed) or "
             "put these files there (SUPERFACETS_SCANS=DIR to use another folder):"]
    lines += [f"  {f}  <- {url}  (sha256 {sha[:12]}...)" for f, url, sha in src.files]
    return "\n".join(lines)


def fetch_scan(name: str, cache=None, *, timeout: float = 60.0) -> list[Path]:
    """Download the files of scan ``name`` into the cache (those not already there).

    Each file is checked against its SHA-256 and only then moved into place,
    so an interrupted or corrupted download leaves no file behind.

    Parameters
    ----------
    name : str
        A key of :data:`SCANS`.
    cache : path, optional
        Default :func:`scan_cache`.
    timeout : float, default 60
        Seconds per request.

    Returns
    -------
    list of Path
        The scan's files in the cache.

    Raises
    ------
    ParameterError
        On an unknown name.
    FileNotFoundError
        When a download fails or its checksum differs (nothing is kept).
    """
    src = _source(name)
    folder = _folder(cache)
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for fname, url, sha in src.files:
        path = folder / fname
        if not (path.is_file() and sha256_of(path) == sha):
            tmp = path.with_name(f".{fname}.{os.getpid()}.part")
            try:
                with urllib.request.urlopen(url, timeout=timeout) as resp, open(tmp, "wb") as fh:
                    while block := resp.read(1 << 20):
                        fh.write(block)
                got = sha256_of(tmp)
                if got != sha:
                    raise FileNotFoundError(f"{url}: checksum {got[:12]}... differs from the "
                                     f"expected {sha[:12]}...; nothing kept")
                os.replace(tmp, path)
            except FileNotFoundError:
                raise
            except OSError as exc:
                raise FileNotFoundError(f"could not download {url}: {exc}") from None
            finally:
                tmp.unlink(missing_ok=True)
        out.append(path)
    return out


def load_scan(name: str, cache=None, *, download: bool = False) -> Scan:
    """Read labelled scan ``name`` from the cache.

    Parameters
    ----------
    name : str
        A key of :data:`SCANS`.
    cache : path, optional
        Default :func:`scan_cache`.
    download : bool, default False
        Fetch missing files first (:func:`fetch_scan`).

    Returns
    -------
    Scan

    Raises
    ------
    ParameterError
        On an unknown name.
    FileNotFoundError
        When a file is missing (the message lists the files and their
        sources).
    MeshFormatError
        When the labels do not match the points, or a file is malformed.
    """

    src = _source(name)
    paths = scan_files(name, cache)
    if download:
        paths = fetch_scan(name, cache)
    missing = [p for p in paths if not p.is_file()]
    if missing:
        raise FileNotFoundError(missing_help(name, cache))
    instances = None
    if src.labels == "semantickitti":
        from dataclasses import replace

        # z is up, but the sensor is not always at the origin (module notes): seen from above
        cloud = replace(read_cloud(paths[0]), up=np.array([0.0, 0.0, 1.0]))
        gt = _ids(paths[1], name, "labels")
    elif src.labels == "scannet":
        rows = _npy(paths[0], name, "points")
        if rows.ndim != 2 or rows.shape[1] != 6:
            raise MeshFormatError(f"{paths[0]}: expected rows of x y z r g b, got an array of "
                                  f"shape {rows.shape}")
        rows = rows.astype(np.float64)
        cloud = PointCloud(rows[:, :3], name=name, colors=np.clip(rows[:, 3:] / 255.0, 0, 1),
                           up=np.array([0.0, 0.0, 1.0]))
        gt = _ids(paths[1], name, "labels")
        instances = _ids(paths[2], name, "instances")
        if instances.shape[0] != cloud.n_total:
            raise MeshFormatError(f"scan {name!r}: {instances.shape[0]} instance labels for "
                                  f"{cloud.n_total} points")
    elif src.labels == "las":
        laspy = extras.require("laspy", "reading LAS/LAZ files")
        cloud = read_cloud(paths[0])
        with laspy.open(paths[0]) as fh:
            records = fh.read()
        gt = np.asarray(records.classification, dtype=np.int64)
        gt[gt == 0] = UNLABELLED
        if src.instance_field:  # each object; a point on none: one instance per class
            raw = np.asarray(records[src.instance_field], dtype=np.float64)
            none = ~(np.isfinite(raw) & (raw > 0) & (raw < 2**31))  # (lidR's NA: DBL_MAX)
            ids = np.where(none, 0, raw).astype(np.int64)
            instances = np.where(ids > 0, ids, ids.max(initial=0) + 1 + gt)
            instances[gt == UNLABELLED] = UNLABELLED
    else:  # pragma: no cover - the registry above is the only source
        raise ParameterError(f"scan {name!r}: unknown label kind {src.labels!r}")
    if gt.shape[0] != cloud.n_total:
        raise MeshFormatError(f"scan {name!r}: {gt.shape[0]} labels for {cloud.n_total} points")
    return Scan(name, cloud, gt, src, instances)


def _npy(path: Path, name: str, what: str) -> np.ndarray:
    """An ``.npy`` file of the cache, or one clear error naming it."""
    try:
        return np.load(path, allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise MeshFormatError(f"{path}: cannot read the {what} ({exc}); delete it "
                              f"and fetch_scan({name!r}) again") from None


def _ids(path: Path, name: str, what: str) -> np.ndarray:
    """Per-point ids from an ``.npy`` file, int64, 0 (unannotated) as :data:`UNLABELLED`."""
    ids = _npy(path, name, what).reshape(-1).astype(np.int64)
    ids[ids == 0] = UNLABELLED
    return ids


def evaluate_scan(scan: Scan, labels, *, tau: float = 0.05, tolerance: int = 1,
                  against: str = "classes") -> dict:
    """The metrics of one labelling of a scan, against its ground truth.

    Measured on the scan's point graph (the one the methods segment: 10
    nearest neighbours, duplicate points merged, each point graph element
    taking the class of its first row), each point weighing the same
    (``evaluate(..., equal_weight=True)``), unlabelled points left out
    (``ignore_label=UNLABELLED``).

    Parameters
    ----------
    scan : Scan
    labels : (N,) int ndarray
        One label per point of the file (-1 for invalid points), as
        :func:`superfacets.segment` and the baselines return them.
    tau, tolerance
        As in :func:`superfacets.evaluation.metrics.evaluate`.
    against : {"classes", "instances"}, default "classes"
        The ground truth: the annotated classes (``scan.ground_truth``) or
        the object instances (``scan.instances``, where the scan has them).

    Returns
    -------
    dict
        ``undersegmentation_error``, ``boundary_recall``, ``boundary_precision``,
        ``achievable_accuracy`` and ``compactness`` (an estimate on points),
        and ``segments`` (distinct labels among the valid points).

    Raises
    ------
    ParameterError
        If ``labels`` does not have one integer per point, or ``against``
        names a ground truth the scan does not have.
    """

    if against == "classes":
        truth = scan.ground_truth
    elif against == "instances" and scan.instances is not None:
        truth = scan.instances
    elif against == "instances":
        raise ParameterError(f"scan {scan.name!r} has no instance labels (only the ScanNet "
                             "rooms do); use against='classes'")
    else:
        raise ParameterError(f"against must be 'classes' or 'instances', not {against!r}")
    return evaluate_rows(scan.cloud, labels, [truth], elements="points", tau=tau,
                         tolerance=tolerance, ignore_label=UNLABELLED, precision=True)
