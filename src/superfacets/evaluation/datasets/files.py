"""A user's own files as the inputs of ``superfacets experiment``: meshes and point clouds
in every format ``segment`` reads, judged against a field of each file (a LAS/LAZ
``classification``, a PLY vertex ``label``) where one is named."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

__all__ = ["FileEntry", "file_entries"]


@dataclass(frozen=True)
class FileEntry:
    """A file as an entry of ``superfacets experiment`` (beside the benchmark's meshes:
    :class:`~superfacets.evaluation.datasets.psb.BenchmarkMesh`).

    Attributes
    ----------
    id : int
        Its place among the inputs.
    category : str
        ``"cloud"`` or ``"mesh"``.
    path : pathlib.Path
    seg_paths : tuple
        Empty: the ground truth, if any, is the file's own ``field``.
    field : str or None
        The LAS/LAZ dimension or PLY vertex property holding the ground truth.
    file : bool
        True.
    """

    id: int
    category: str
    path: Path
    seg_paths: tuple = ()
    field: str | None = None
    file: bool = True


def file_entries(specs, field: str | None = None) -> list[FileEntry]:
    """The files named by ``specs`` (files, folders, globs, ``@list.txt``, as ``batch``
    takes them) as entries of an experiment.

    Parameters
    ----------
    specs : sequence of str
    field : str, optional
        Each file's ground-truth field (a cloud's points, or a mesh's vertices).

    Returns
    -------
    list of FileEntry

    Raises
    ------
    FileNotFoundError
        When a spec matches nothing.
    ParameterError
        When a folder holds no input, or an input is a tetrahedral mesh (the registry's
        methods segment surfaces and clouds).

    Examples
    --------
    >>> import numpy as np, tempfile
    >>> path = f"{tempfile.mkdtemp()}/scan.npy"
    >>> np.save(path, np.random.default_rng(0).random((100, 3)))
    >>> [(e.category, e.path.name) for e in file_entries([path])]
    [('cloud', 'scan.npy')]
    """
    from ...errors import ParameterError
    from ...io import VOLUME_FORMATS, is_cloud_file
    from ...io.files import split_suffix
    from ...scale.runner.collect import collect_inputs

    out = []
    for i, p in enumerate(collect_inputs([str(s) for s in specs])):
        if split_suffix(p)[0] in VOLUME_FORMATS:
            raise ParameterError(f"{p}: a tetrahedral mesh; the experiment's methods segment "
                                 "surfaces and point clouds ('superfacets segment' takes it)")
        out.append(FileEntry(i, "cloud" if is_cloud_file(p) else "mesh", p, field=field))
    return out
