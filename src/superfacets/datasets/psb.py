"""Princeton Mesh Segmentation Benchmark: locating and unpacking the archive.

The archive ``psb.tar.xz`` (``../shared/data/`` beside the repository) holds
``psb/off/<id>.off`` and ``psb/seg/Benchmark/<id>/<id>_<j>.seg``. It is
unpacked once into a cache folder outside the repository.
"""

from __future__ import annotations

import os
import tarfile
import tempfile
from pathlib import Path

__all__ = ["default_archive", "default_cache", "psb_root", "category", "CATEGORIES"]

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
