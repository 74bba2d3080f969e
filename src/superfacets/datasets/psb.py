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

__all__ = ["default_archive", "default_cache", "psb_root", "category", "CATEGORIES",
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

_REPO = Path(__file__).resolve().parents[3]


def default_archive() -> Path:
    """``$SUPERFACETS_SHARED/data/psb.tar.xz``, by default ``../shared`` beside the repository."""
    shared = Path(os.environ.get("SUPERFACETS_SHARED", _REPO.parent / "shared"))
    return shared / "data" / "psb.tar.xz"


def default_cache() -> Path:
    """``$SUPERFACETS_CACHE``, by default ``~/.cache/superfacets``."""
    return Path(os.environ.get("SUPERFACETS_CACHE", Path.home() / ".cache" / "superfacets"))


def psb_root(archive=None, cache=None) -> Path:
    """The unpacked benchmark folder (holding ``off/`` and ``seg/``).

    Unpacks ``archive`` into ``cache/psb`` the first time (about 5 s,
    313 MB), through a temporary folder renamed at the end, so an
    interrupted unpack is never mistaken for a complete one.

    Parameters
    ----------
    archive : path, optional
        Default :func:`default_archive`.
    cache : path, optional
        Default :func:`default_cache`.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    FileNotFoundError
        If the folder is not unpacked yet and the archive is missing.
    """
    cache = Path(cache) if cache is not None else default_cache()
    target = cache / "psb"
    if (target / "off").is_dir():
        return target
    archive = Path(archive) if archive is not None else default_archive()
    if not archive.exists():
        raise FileNotFoundError(f"{archive}: Princeton benchmark archive not found")
    cache.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".psb-", dir=cache))
    try:
        with tarfile.open(archive, "r:xz") as tar:
            tar.extractall(tmp, filter="data")
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
        from ..io import read_mesh

        return read_mesh(self.path)

    def ground_truths(self, n_faces: int) -> list[np.ndarray]:
        """Read every human segmentation, checking one label per face.

        Raises
        ------
        MeshFormatError
            Naming the file, if a ``.seg`` is malformed or has a wrong count.
        """
        from ..io import read_labels

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
