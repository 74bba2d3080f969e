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
        above) or ``"ground"`` (a PCD of every point and a PCD of the ground's points:
        ASPRS class 2 where a point is in the second, 1 elsewhere; seen from above, its
        ``VIEWPOINT`` not a sensor).
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
_PCL = ("PointCloudLibrary/data", "5c26bdd0591ba150b91858b5c9fe5e91cb39ae86")


def _las(name: str, kind: str, repo: tuple, path: str, sha: str, credit: str, *,
         instance_field: str = "") -> ScanSource:
    """An airborne tile of a project's test data, its ASPRS classes as ground truth."""
    return ScanSource(name, kind, ((f"{name.replace('-', '_')}.{path.rsplit('.', 1)[1]}",
                                    _github(*repo, path), sha),), "las", credit, "dales",
                      instance_field)


_LIDR_CREDIT = ("from lidR's example data (Roussel et al., Remote Sensing of Environment "
                "2020; GPL-3 package, data as shipped in inst/extdata): ASPRS classes ")
_PDAL_CREDIT = "from PDAL's test data (BSD): ASPRS classes "
_SERC = ("kccushman/SERC_lidarComparison", "6f7764a70b58bbad1097bbddcd8c16c140c37d69")
_SERC_CREDIT = ("from the data of Cushman et al., 'A primer on forest structure measurement "
                "with lidar for ecologists' (an 80 x 5 m transect of the Smithsonian "
                "Environmental Research Center's forest plot, Maryland; shared openly, no "
                "licence named: read for measurement, never redistributed), coloured: ASPRS "
                "classes ground and vegetation (5)")


def _isprs(sample: int, points_sha: str, ground_sha: str) -> ScanSource:
    """A reference sample of the ISPRS filter test (urban sites 1-4, rural 5-8), as PCL's
    data repository converts it: every point, and the ground's."""
    base = f"terrain/samp{sample}-utm"
    site = "urban" if sample < 50 else "rural"
    return ScanSource(
        f"isprs-samp{sample}", f"airborne LiDAR, ISPRS filter test, {site}",
        ((f"isprs_samp{sample}.pcd", _github(*_PCL, f"{base}.pcd"), points_sha),
         (f"isprs_samp{sample}_ground.pcd", _github(*_PCL, f"{base}-ground.pcd"), ground_sha)),
        "ground",
        f"the ISPRS Commission III filter test's reference sample {sample} (Sithole and "
        "Vosselman, ISPRS J. 2004; Optech ALTM, 1-3.5 m spacing), as PCL's data repository "
        "ships it (BSD; projected to UTM 32U, float32 coordinates: northings in 0.5 m steps): "
        "ground (2) and the rest (1)", "dales")


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
    _las("serc-als", "airborne LiDAR, deciduous forest transect", _SERC,
         "Data/transect/transect_als.laz",
         "ea05665b23c21db7b54b8227bcd9c9a2965628a869b8470267f5dcd0e763bdaa",
         _SERC_CREDIT + " and unclassified (1)"),
    _las("serc-uls", "airborne LiDAR from a drone (ULS), the same transect in leaf", _SERC,
         "Data/transect/transect_drone.laz",
         "0247ac69a82f3b0da6154d101b65cd9a8aeffa1a78341498c2e49f9d9457b6f8",
         _SERC_CREDIT + " (class 0, never classified, unlabelled)"),
    _las("serc-uls-leafoff", "airborne LiDAR from a drone (ULS), the same transect leaf-off",
         _SERC, "Data/transect/transect_drone_leafoff.laz",
         "fda5db05f29c0929f83aa8b54c494b7c29d171491b86d2d13a96a89a671b7b3e",
         _SERC_CREDIT + " (class 0, 43 % of the points, unlabelled)"),
    _scannet("scene0000_00", "c73b979bbff0bb2cc93cf6d57aea10234c807d246df16c6ecc40e8fbd896ac00",
             "7b5bf6e35fd5007618dc22748f50991208635be3aec9783ffd3f0f93761e2f68",
             "5ef2f8b2622c3512a19902807294216130f6332872cf3db121f6d5815cd0a8c4"),
    _scannet("scene0000_01", "1c0aee74f2c94ecd67d5726831120335c44fa201b60c6822689439f5fa9b6d01",
             "1eeccfd9d3bd6ea431ffe4d79c9a0bbef8ce7e36a2ed1d4fceebc7451e6071c1",
             "152df03e56a93b9523779e6af9b365520f1d930b356c1107881e451daa2ce0bd"),
    _isprs(11, "0b2029dcd2c738e9c1631e553999f2c0995c59e2443c597b32cf928ebc1d1fb7",
           "8112c6ed6914d7434ee94ea97d692f07034323ef177e437af0737f197d0ecce6"),
    _isprs(12, "6cf0e4a6ce8d4a1be35a79aad892e2a9552c9bbb333d47d630a213143a424d61",
           "51fce5a78172874d2cad7045e61b283acb22cc15d149d7799db9fb90c1727acd"),
    _isprs(21, "9aebd0ed77388fa22835f07bde6bced1eb2bfc5a6260d18468b7e67993bed56f",
           "3529972af85fe5bd67bdd1886e28d321746a7f0dc7e7113157ee9123ad6e091a"),
    _isprs(22, "e436292b5950bee955b053d3990cc6b42e1d648f8923ad2b1ce62a79d336a5f5",
           "d31b8a246d93b02fa748dbc2aaad56ea52d05ec6fcd6da109595794d88c74007"),
    _isprs(23, "35e872a6b4e36fa35f55d5f7bef2f159690c93e9aaa31bc24e4363d1e38dbd98",
           "9005cacb07b5b9aeb4a7890737aef83d8b6a1c601cac04d4abe5035a14980c69"),
    _isprs(24, "d8962dfc992053fa3647673d0af8cbb34077827be027fbee850dc9878afad944",
           "7d996a6194116f838b4bfc5a27eb0e4b8cce7e9a0414ab59fb77df68f3156a18"),
    _isprs(31, "1a1677c5ccbfbbc9fafa21ae0293ae9b53d32867ccf138e99ff74900cef74ea3",
           "f78aa4d5dc8a8b205b0e178fd6cba6c855beb796c72fd2c460849d76bf1636c4"),
    _isprs(41, "1ef417dc4c9aaec5496ca6c7b87f3763f9b116ad03c9247552b753091479f72d",
           "4cb530ffa90fb58dbf6c7d55f229ff301f24ddffcf54d75f724746bdc4d96f8a"),
    _isprs(42, "d029873e134927b4a7950c5973a49b4bdac9bd19980c2b34e9eb8452611b37ba",
           "c5199cb0f7a1ec2c557af9157fbfadb8cad5b144536f2e5e8ca10661a940f1ee"),
    _isprs(51, "ba3ded183136b1dec94111149be9040ec1ee6f15eecf1014a2c5a0bd651c05c5",
           "c443163e0e5475c662e4ba4766008fddfded5829c4ea51508146bd6d432aaf7b"),
    _isprs(52, "ba89c6d90004963587aa5ae2620630c83927a43d243bdfc3ad9d00aaa59336ca",
           "ed92936a8253ec4e02227624c7c8c2fdab585518308e6bdc17b31352676bac63"),
    _isprs(53, "89427e8b6f24061d2dcc6ac63de3321077982b7c36add77cbff0c2df375e3abd",
           "791a310ab9e32b4eb45d5d366aa4597055130dc519ae83b7032cd390c2d91265"),
    _isprs(54, "c8ee4c94ed3c278c09b3797848724405c6187acbc42b9d6fc509c4cb356ae600",
           "4a20cfb17e612c0eedbd25755536776a6cb02dbb6b5059ac4da985b67414170d"),
    _isprs(61, "b717382cf30cc8a0c7430908ab777fc362ad33d0fc07720d5eac7d609d2b60c9",
           "2162fb18560f1ac2320fbe5b8b55de39398ce5832c525e0a111a44844117fd16"),
    _isprs(71, "56685bf711877028369ed6899bf84b66df928dc92850f2f38135e15c7ef40ede",
           "b35ca5cabbb847935f93bbb1609045f1246c59852a64c83c0d7133dd01dda9af"),
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
    elif src.labels == "ground":
        from dataclasses import replace

        # airborne, z up; the PCD's VIEWPOINT is PCL's default, not a sensor: seen from above
        cloud = replace(read_cloud(paths[0]), up=np.array([0.0, 0.0, 1.0]), viewpoint=None)
        gt = _ground_classes(cloud.points, read_cloud(paths[1]).points, name)
    else:  # pragma: no cover - the registry above is the only source
        raise ParameterError(f"scan {name!r}: unknown label kind {src.labels!r}")
    if gt.shape[0] != cloud.n_total:
        raise MeshFormatError(f"scan {name!r}: {gt.shape[0]} labels for {cloud.n_total} points")
    return Scan(name, cloud, gt, src, instances)


def _ground_classes(points: np.ndarray, ground: np.ndarray, name: str) -> np.ndarray:
    """ASPRS classes of ``points`` ((n, 3)): 2 (ground) where a point's position is one of
    ``ground``'s ((g, 3), the same values: both read from float32 files), else 1."""
    def keyed(a):
        return np.ascontiguousarray(a, dtype=np.float64).view(
            np.dtype((np.void, 24))).reshape(-1)

    every, on_ground = keyed(points), keyed(ground)
    if not np.isin(on_ground, every).all():
        raise MeshFormatError(f"scan {name!r}: the ground file holds points that are not in "
                              "the scan")
    return np.where(np.isin(every, on_ground), 2, 1).astype(np.int64)


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
        ``undersegmentation_error``, ``undersegmentation_error_np`` (Neubert and
        Protzel's), ``boundary_recall``, ``boundary_precision``,
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
