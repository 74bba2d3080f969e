"""Princeton Mesh Segmentation Benchmark: locating and unpacking the archive.

The archive ``psb.tar.xz`` (``../shared/data/`` beside the repository) holds
``psb/off/<id>.off`` and ``psb/seg/Benchmark/<id>/<id>_<j>.seg``. It is
unpacked once into a cache folder outside the repository.
"""

from __future__ import annotations

import os
import tarfile
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...io import read_labels, read_mesh

__all__ = ["default_archive", "default_cache", "psb_root", "category", "CATEGORIES",
           "first_per_category",
           "BenchmarkMesh", "list_meshes"]

#: Benchmark categories, 20 consecutive ids each (1-20 Human, 21-40 Cup, ...);
#: ids 261-280 (SHREC's "Spring") are not part of the segmentation benchmark.
CATEGORIES = ("Human", "Cup", "Glasses", "Airplane", "Ant", "Chair", "Octopus", "Table",
              "Teddy", "Hand", "Plier", "Fish", "Bird", None, "Armadillo", "Bust", "Mech",
              "Bearing", "Vase", "Fourleg")


def category(mesh_id: int) -> str:
    """Category name of a benchmark mesh id (``"other"`` outside the known ranges)."""
    i = (int(mesh_id) - 1) // 20
    name = CATEGORIES[i] if 0 <= i < len(CATEGORIES) else None
    return name or "other"

_REPO = Path(__file__).resolve().parents[4]


def default_archive() -> Path:
    """``$SUPERFACETS_SHARED/data/psb.tar.xz``, by default ``../shared`` beside the repository."""
    shared = Path(os.environ.get("SUPERFACETS_SHARED", _REPO.parent / "shared"))
    return shared / "data" / "psb.tar.xz"


def default_cache() -> Path:
    """``$SUPERFACETS_CACHE``, by default ``~/.cache/superfacets``."""
    return Path(os.environ.get("SUPERFACETS_CACHE", Path.home() / ".cache" / "superfacets"))


#: Where the benchmark is published, and what this package expects of it.
NOT_FOUND_HELP = (
    "the Princeton Mesh Segmentation Benchmark (Chen, Golovinskiy, Funkhouser, 2009: 380 "
    "meshes with human segmentations) was not found. Its data is published at "
    "https://segeval.cs.princeton.edu/ (MeshsegBenchmark-1.0.zip; its data/ folder is what "
    "is needed). Give the folder with --psb DIR or SUPERFACETS_PSB=DIR; it must hold "
    "off/<id>.off and seg/Benchmark/<id>/<id>_<j>.seg (a .tar.xz archive holding psb/off "
    "and psb/seg is accepted too, and unpacked once into the cache)")


def _is_root(folder: Path) -> bool:
    return (folder / "off").is_dir() and (folder / "seg").is_dir()


def _source_checkout_archive() -> Path | None:
    """``../shared/data/psb.tar.xz`` beside a source checkout (None from a wheel)."""
    if not ((_REPO / "pyproject.toml").is_file() and (_REPO / "src" / "superfacets").is_dir()):
        return None
    return default_archive()


def psb_root(root=None, *, archive=None, cache=None) -> Path:
    """The benchmark folder (holding ``off/`` and ``seg/``), found or unpacked.

    Looked for, in order: ``root`` (e.g. ``--psb DIR``); ``$SUPERFACETS_PSB``;
    the folder unpacked earlier into the cache; in a source checkout, the
    archive ``../shared/data/psb.tar.xz`` beside the repository. An archive
    (``root``, ``$SUPERFACETS_PSB`` or ``archive``, a tar file holding
    ``psb/off`` and ``psb/seg``) is unpacked once into ``cache/psb`` (about
    5 s, 313 MB; delete that folder to unpack another), through a temporary
    folder renamed at the end, so an interrupted unpack is never mistaken for
    a complete one.

    Parameters
    ----------
    root : path, optional
        A benchmark folder, or an archive.
    archive : path, optional
        An archive to unpack when no folder is found.
    cache : path, optional
        Default :func:`default_cache`.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    FileNotFoundError
        Saying what the benchmark is, where it is published and which layout
        is expected, when none of the places has it.
    """
    cache = Path(cache) if cache is not None else default_cache()
    given = root if root is not None else os.environ.get("SUPERFACETS_PSB") or None
    if given is not None:
        given = Path(given)
        if given.is_dir():
            if _is_root(given):
                return given
            raise FileNotFoundError(f"{given}: no off/ inside, or no seg/ (not a benchmark "
                                    f"folder): {NOT_FOUND_HELP}")
        if not given.is_file():
            raise FileNotFoundError(f"{given}: no such folder: {NOT_FOUND_HELP}")
        archive = given
    target = cache / "psb"
    if _is_root(target):  # unpacked earlier (delete it to unpack another archive)
        return target
    archive = Path(archive) if archive is not None else _source_checkout_archive()
    if archive is None or not archive.is_file():
        where = f"{archive}: " if archive is not None else ""
        raise FileNotFoundError(f"{where}{NOT_FOUND_HELP}")
    return _unpack(archive, cache)


def _unpack(archive: Path, cache: Path) -> Path:
    target = cache / "psb"
    cache.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".psb-", dir=cache))
    try:
        try:
            with tarfile.open(archive, "r:*") as tar:
                tar.extractall(tmp, filter="data")
        except (tarfile.TarError, EOFError, OSError) as exc:
            raise FileNotFoundError(f"{archive}: not a readable benchmark archive ({exc}): "
                                    f"{NOT_FOUND_HELP}") from None
        if not _is_root(tmp / "psb"):
            raise FileNotFoundError(f"{archive}: holds no psb/off and psb/seg: {NOT_FOUND_HELP}")
        os.replace(tmp / "psb", target)
    finally:
        import shutil

        shutil.rmtree(tmp, ignore_errors=True)
    return target


@dataclass(frozen=True)
class BenchmarkMesh:
    """One mesh of the benchmark and its human segmentations.

    Attributes
    ----------
    id : int
        Benchmark id (the file stem).
    category : str
        From the id ranges (:func:`category`).
    path : pathlib.Path
        ``off/<id>.off``.
    seg_paths : tuple of pathlib.Path
        ``seg/Benchmark/<id>/<id>_<j>.seg``, sorted by ``j``.
    """

    id: int
    category: str
    path: Path
    seg_paths: tuple

    def load(self):
        """Read the mesh (:func:`superfacets.read_mesh`)."""

        return read_mesh(self.path)

    def ground_truths(self, n_faces: int) -> list[np.ndarray]:
        """Read every human segmentation, checking one label per face.

        Raises
        ------
        MeshFormatError
            Naming the file, if a ``.seg`` is malformed or has a wrong count.
        """

        return [read_labels(p, n_faces=n_faces) for p in self.seg_paths]


def _seg_index(p: Path) -> int:
    tail = p.stem.rsplit("_", 1)[-1]
    return int(tail) if tail.isdigit() else -1


def list_meshes(root=None) -> list[BenchmarkMesh]:
    """The meshes present in an unpacked benchmark folder, sorted by id.

    Parameters
    ----------
    root : path, optional
        Folder holding ``off/`` and ``seg/Benchmark/``; default :func:`psb_root`.

    Returns
    -------
    list of BenchmarkMesh
        Only meshes whose ``.off`` file exists; ids are read from the files,
        never from a fixed list. A mesh without human segmentations has an
        empty ``seg_paths``.

    Raises
    ------
    FileNotFoundError
        If ``root/off`` does not exist.
    """
    root = Path(root) if root is not None else psb_root()
    off = root / "off"
    if not off.is_dir():
        raise FileNotFoundError(f"{off}: not a benchmark folder (no off/ inside)")
    out = []
    for path in off.glob("*.off"):
        if not path.stem.isdigit():
            continue
        mid = int(path.stem)
        segs = sorted((root / "seg" / "Benchmark" / path.stem).glob(f"{path.stem}_*.seg"),
                      key=_seg_index)
        out.append(BenchmarkMesh(id=mid, category=category(mid), path=path, seg_paths=tuple(segs)))
    return sorted(out, key=lambda b: b.id)


def first_per_category(meshes: list, n: int) -> list:
    """The first ``n`` meshes of each category, in the given order.

    Parameters
    ----------
    meshes : list of BenchmarkMesh
        Usually :func:`list_meshes` (sorted by id).
    n : int
        Meshes kept per category (``>= 1``).

    Returns
    -------
    list of BenchmarkMesh

    Examples
    --------
    >>> from types import SimpleNamespace as M
    >>> ms = [M(id=i, category=c) for i, c in enumerate("aabba")]
    >>> [m.id for m in first_per_category(ms, 1)]
    [0, 2]
    """
    seen: dict[str, int] = {}
    kept = []
    for m in meshes:
        if seen.get(m.category, 0) < n:
            kept.append(m)
            seen[m.category] = seen.get(m.category, 0) + 1
    return kept
