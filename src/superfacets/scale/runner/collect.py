"""The inputs of a batch or an experiment: which files, and what their outputs are called.

:func:`collect_inputs` turns files, folders, globs and ``@list.txt`` into a
list of files, each once; :func:`output_names` gives each a name under the
output folder that no other input shares (``superfacets batch``, :mod:`.batch`).
"""

from __future__ import annotations

import errno
import glob
import hashlib
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from ...errors import ParameterError
from ...io import CLOUD_FORMATS, MESH_FORMATS, VOLUME_FORMATS, input_kind
from ...io.files import COMPRESSIONS, split_suffix
from .manifest import OPTIONS

__all__ = ["collect_inputs", "output_names", "broken_link_reason", "no_inputs", "FileEntry",
           "file_entries", "batch_output"]


def _readable_suffixes(explicit: bool) -> set[str]:

    # in folders, .txt, .csv and .bin are too often something else (a README, a table of
    # results, model weights) to be read as clouds
    return (set(MESH_FORMATS) | set(VOLUME_FORMATS) |
            set(CLOUD_FORMATS) - (set() if explicit else set(_NAMED_ONLY)))


#: Cloud formats read where a file is named (or matched by a glob), not where a folder holds
#: it: a .txt or .csv is often a README or a table, a .bin other binary data.
_NAMED_ONLY = ("txt", "csv", "asc", "bin")


def _is_input(path: Path, explicit: bool) -> bool:
    fmt, _ = split_suffix(path)
    if fmt == "bin" and path.name.lower().endswith(".pcd.bin"):
        return True  # (a nuScenes sweep says what it is: a folder's are read)
    return fmt in _readable_suffixes(explicit)


def no_inputs(inputs, outdir: Path) -> ParameterError:
    """The error of a batch that found nothing to segment, naming an input folder that
    holds the output folder (whose files are left out)."""
    inside = [str(p) for p in inputs if outdir.exists() and Path(p).resolve()
              in (outdir.resolve(), *outdir.resolve().parents)]
    if inside:
        return ParameterError(f"no input to segment: {inside[0]} is or holds the output "
                              f"folder {outdir} (its files are left out); give -o a folder "
                              "outside the inputs")
    return ParameterError("no input to segment")


def _why_not(name: str) -> str:
    """Why a file found in a folder is not an input, in one phrase."""

    fmt, _ = split_suffix(Path(name))
    if fmt in _NAMED_ONLY:
        what = dict(txt="README", csv="table", asc="grid of heights").get(fmt, "file of "
                                                                          "other data")
        return (f"a .{fmt} in a folder is not read as a cloud (a {what}?); name it "
                "(or a glob: velodyne/*.bin) to read it")
    return f"{'.' + fmt if fmt else 'no suffix'}: not a mesh, cloud or volume format"


def collect_inputs(specs: Sequence[str], exclude=None, skipped: list | None = None,
                   passed: list | None = None) -> list[Path]:
    """The files named by ``specs``, absolute, each once, in order, as given.

    Paths keep the names the user gave: a symbolic link stays the link (its outputs are
    named after it, not after its target), ``..`` is folded without resolving links.
    Several links to one file are several inputs. A link that points nowhere or loops
    is kept: its task fails with that reason.

    Parameters
    ----------
    specs : sequence of str
        Files; folders (searched recursively, links to folders followed once each, for
        every format the readers accept, hidden files, ``.txt`` and ``.csv`` left out, and
        in a scene folder of Pointcept's the ``.npy`` beside ``coord.npy``); glob
        patterns (``**`` recurses); ``@list.txt`` (one of these per line, ``#``
        comments). A sub-folder of a searched folder that holds a batch's output
        (its ``batch.json`` and manifest) is left out: its files are that batch's
        results, not inputs.
    exclude : path, optional
        A folder whose files are never inputs (the output folder).
    skipped : list, optional
        Receives ``(folder, reason)`` for each sub-folder that could not be read (its
        files are not inputs); without it such a folder is skipped silently.
    passed : list, optional
        Receives ``(file, reason)`` for each file of a searched folder that is not an
        input (another format, a ``.txt`` or ``.csv``; hidden files are left out
        silently).

    Returns
    -------
    list of pathlib.Path

    Raises
    ------
    FileNotFoundError
        When a spec matches nothing (a typo is not skipped silently).
    ParameterError
        When a folder holds no readable file.

    Examples
    --------
    >>> collect_inputs(["/no/such/*.off"])
    Traceback (most recent call last):
    ...
    FileNotFoundError: /no/such/*.off: no file matches
    """
    skip = _Inside(exclude) if exclude is not None else None
    out: list[Path] = []
    seen: set[Path] = set()

    def keep(p: Path) -> None:
        p = Path(os.path.abspath(p))  # the name as given: links are not resolved
        if p in seen or (skip is not None and skip(p)):
            return
        seen.add(p)
        out.append(p)

    def folder(d: Path) -> int:
        n = 0
        visited: set[tuple[int, int]] = set()

        def unreadable(err: OSError) -> None:
            if skipped is not None:
                skipped.append((str(err.filename or d), err.strerror or str(err)))

        for root, dirs, files in os.walk(d, followlinks=True, onerror=unreadable):
            try:
                st = os.stat(root)
            except OSError:
                continue
            if (st.st_dev, st.st_ino) in visited:  # a link back to a folder seen: a loop
                dirs[:] = []
                continue
            visited.add((st.st_dev, st.st_ino))
            _walked_dirs(Path(root), dirs, passed, skip)
            scene = "coord.npy" in files  # (a scene folder: its other .npy are its assets)
            for name in sorted(files):
                asset = scene and name.endswith(".npy") and name != "coord.npy"
                if not name.startswith(".") and not asset and _is_input(Path(name),
                                                                         explicit=False):
                    keep(Path(root) / name)
                    n += 1
                elif passed is not None and not name.startswith(".") and (
                        skip is None or not skip(Path(root) / name)):
                    passed.append((str(Path(root) / name), "an asset of the scene in "
                                   "coord.npy (Pointcept's layout)" if asset else
                                   _why_not(name)))
        return n

    def one(spec: str, depth: int = 0) -> None:
        if spec.startswith("@") and depth == 0:
            lst = Path(spec[1:])
            if not lst.is_file():
                raise FileNotFoundError(f"{lst}: no such list file")
            for line in lst.read_text(errors="replace").splitlines():
                line = line.strip()
                if line and not line.startswith("#"):
                    one(line, depth + 1)
            return
        p = Path(spec).expanduser()
        if p.is_dir():
            before = len(passed) if passed is not None else 0
            if folder(p) == 0:
                left = passed[before:] if passed is not None else []
                raise ParameterError(f"{spec}: no mesh or point-cloud file in this folder" + (
                    f" ({len(left):,} other files, as {Path(left[0][0]).name}: {left[0][1]})"
                    if left else ""))
        elif p.is_file() or p.is_symlink():  # a dangling or looping link: its task says so
            keep(p)
        elif glob.has_magic(spec):
            hits = sorted(glob.glob(str(p), recursive=True))
            files = [Path(h) for h in hits if (Path(h).is_file() or Path(h).is_symlink())
                     and not Path(h).is_dir() and _is_input(Path(h), True)]
            for h in hits:
                if Path(h).is_dir():
                    folder(Path(h))
            for f in files:
                keep(f)
            if not hits:
                raise FileNotFoundError(f"{spec}: no file matches")
        else:
            raise FileNotFoundError(f"{spec}: no such file or folder")

    for s in specs:
        one(str(s))
    return out


def _walked_dirs(root: Path, dirs: list, passed: list | None, skip) -> None:
    """Sort ``dirs`` (an ``os.walk`` step's) and take out the hidden ones and each holding
    another batch's results (a rerun elsewhere would read them), said in ``passed``."""
    dirs[:] = sorted(x for x in dirs if not x.startswith("."))
    for x in [x for x in dirs if batch_output(root / x)]:
        dirs.remove(x)
        if passed is not None and (skip is None or not skip(root / x)):
            passed.append((str(root / x), "a batch's output folder: its files are results, "
                           "not inputs; name them to segment them"))


def batch_output(folder: Path) -> bool:
    """Whether ``folder`` holds the output of ``superfacets batch`` (its options file and
    its manifest, as :func:`~superfacets.scale.runner.batch.run_batch` writes them).

    Examples
    --------
    >>> batch_output(Path("/no/such/folder"))
    False
    """
    return (folder / OPTIONS).is_file() and any(
        (folder / f"manifest.{ext}").is_file() for ext in ("parquet", "csv"))


class _Inside:
    """Whether a path lies in a folder, by its name or by where it leads."""

    def __init__(self, folder) -> None:
        self.name = Path(os.path.abspath(folder))
        self.real = Path(os.path.realpath(folder))

    def __call__(self, p: Path) -> bool:
        if p.is_relative_to(self.name):
            return True
        try:
            return Path(os.path.realpath(p)).is_relative_to(self.real)
        except (OSError, RuntimeError):  # a looping link leads nowhere
            return False


def broken_link_reason(path) -> str | None:
    """Why ``path`` cannot be read when it is a symbolic link that points nowhere or loops
    (None otherwise).

    Examples
    --------
    >>> broken_link_reason("/no/such/file") is None
    True
    """
    p = Path(path)
    if not p.is_symlink() or p.exists():
        return None
    try:
        target = os.readlink(p)
    except OSError:
        target = "?"
    try:
        os.stat(p)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return f"a symbolic link that loops (-> {target})"
    return f"a symbolic link to {target}, which does not exist"


def _stem(path: Path) -> str:
    """The file name without its format and compression suffixes (``bunny.tri.xz`` -> bunny,
    ``tile.copc.laz`` -> tile, ``sweep.pcd.bin`` -> sweep)."""

    name = path.name
    low = name.lower()
    for comp in COMPRESSIONS:
        if low.endswith(comp):
            name, low = name[: -len(comp)], low[: -len(comp)]
            break
    base, dot, fmt = name.rpartition(".")
    if not (dot and base):
        return name
    inner = {"laz": ".copc", "las": ".copc", "bin": ".pcd"}.get(fmt.lower())
    if inner and base.lower().endswith(inner) and len(base) > len(inner):
        return base[: -len(inner)]  # (a COPC tile's .copc.laz, a nuScenes sweep's .pcd.bin)
    return base


def output_names(inputs: Sequence[Path], reserved=()) -> dict[Path, str]:
    """A name for each input's outputs, relative to the output folder, without suffix.

    The input's path relative to the inputs' common folder, its format
    suffix dropped (``psb/1.off`` -> ``psb/1``; a scene folder's ``coord.npy`` its
    folder's, ``val/scene0011_00/coord.npy`` -> ``val/scene0011_00``); inputs that would share a
    name keep their whole file name (``x.off`` -> ``x.off``, ``x.ply`` ->
    ``x.ply``); a name still taken (by one in ``reserved``, outputs of an
    earlier run) gets ``~`` and 8 hex digits of the input path's hash.

    Parameters
    ----------
    inputs : sequence of pathlib.Path
        Absolute, distinct.
    reserved : iterable of str
        Names not to give.

    Returns
    -------
    dict
        Input -> name (``/`` separated).

    Examples
    --------
    >>> from pathlib import Path
    >>> names = output_names([Path("/d/a/x.off"), Path("/d/b/x.off"), Path("/d/b/x.ply")])
    >>> sorted(names.values())
    ['a/x', 'b/x.off', 'b/x.ply']
    """
    if not inputs:
        return {}
    root = Path(os.path.commonpath([str(p.parent) for p in inputs]))
    rel = {p: p.relative_to(root) for p in inputs}
    # (a scene folder's coord.npy is named by its scene: scene0000_00, not .../coord)
    first = {p: (r.parent if r.parent != Path(".") else Path(p.parent.name)).as_posix()
             if p.name == "coord.npy" and p.parent.name else (r.parent / _stem(r)).as_posix()
             for p, r in rel.items()}
    count: dict[str, int] = {}
    for n in first.values():
        count[n] = count.get(n, 0) + 1
    names = {p: (n if count[n] == 1 else rel[p].as_posix()) for p, n in first.items()}
    taken = set(reserved)
    out = {}
    for p, n in names.items():
        if n in taken:
            n = f"{n}~{hashlib.sha1(str(p).encode()).hexdigest()[:8]}"
        taken.add(n)
        out[p] = n
    return out


@dataclass(frozen=True)
class FileEntry:
    """A file as an entry of ``superfacets experiment`` (beside the benchmark's meshes:
    :class:`~superfacets.evaluation.datasets.psb.BenchmarkMesh`).

    Attributes
    ----------
    id : int
        Its place among the inputs.
    category : str
        ``"cloud"``, ``"mesh"`` or ``"volume"`` (a tetrahedral mesh:
        :func:`superfacets.io.input_kind`).
    path : pathlib.Path
    seg_paths : tuple of pathlib.Path
        Label files of the file's ground truth (``--ground-truths``); empty: the ground
        truth, if any, is the file's own ``field``.
    field : str or None
        The LAS/LAZ dimension, PLY vertex property, PCD field or tetrahedra's cell data
        holding the ground truth.
    name : str
        Its rows' name (``mesh``): its path from the inputs' common folder, its suffix
        dropped, one for each input (:func:`output_names`); empty: its file's stem.
    file : bool
        True.
    """

    id: int
    category: str
    path: Path
    seg_paths: tuple = ()
    field: str | None = None
    name: str = ""
    file: bool = True


def file_entries(specs, field: str | None = None, truths: str | None = None
                 ) -> list[FileEntry]:
    """The files named by ``specs`` (files, folders, globs, ``@list.txt``, as ``batch``
    takes them) as entries of an experiment.

    Parameters
    ----------
    specs : sequence of str
    field : str, optional
        Each file's ground-truth field (a cloud's points, or a mesh's vertices).
    truths : str, optional
        Each file's ground truth as a label file (what :func:`superfacets.read_labels`
        reads: ``.seg``, SemanticKITTI's ``.label``, ...): named by this pattern from the
        file's folder, ``{stem}`` the file's name without its suffix
        (``"../labels/{stem}.label"``; ``"segment.npy"`` in a scene folder of Pointcept's,
        each input's its own); or a list file (``.csv``, ``.tsv``, ``.txt``) of
        one input and its ground truth a line (separated by a comma, a tab or spaces, a
        path with spaces in double quotes;
        relative paths from the list's folder; ``#`` comments), for names no pattern
        makes (Open3D-ML's ``X_points.npy`` and ``X_labels.npy``, nuScenes' tokens).

    Returns
    -------
    list of FileEntry

    Raises
    ------
    FileNotFoundError
        When a spec matches nothing, or a file's ground truth (``truths``) is not there:
        the first missing named, and how many are.
    ParameterError
        When a folder holds no input, ``truths`` names another field than ``{stem}`` and
        is no list file, a line of the list is not two paths, an input is not listed, or
        two inputs would share one ground truth.

    Examples
    --------
    >>> import numpy as np, tempfile
    >>> path = f"{tempfile.mkdtemp()}/scan.npy"
    >>> np.save(path, np.random.default_rng(0).random((100, 3)))
    >>> [(e.category, e.path.name) for e in file_entries([path])]
    [('cloud', 'scan.npy')]
    """
    out = []
    files = collect_inputs([str(s) for s in specs])
    names = output_names(files)  # (one name each: 00/velodyne/000000 beside 01/velodyne/...)
    listed = _truth_list(Path(truths)) if truths is not None and _is_list(truths) else None
    if listed is not None:
        unlisted = [p for p in files if p.resolve() not in listed]
        if unlisted:
            raise ParameterError(f"{unlisted[0]}: no line of {truths} names it; "
                                 f"{len(unlisted)} of {len(files)} inputs are not listed")
    for i, p in enumerate(files):
        seg = () if truths is None else (
            listed[p.resolve()] if listed is not None else _truth_of(p, truths),)
        out.append(FileEntry(i, input_kind(p), p, seg_paths=seg, field=field, name=names[p]))
    shared = {}
    for e in out:
        if e.seg_paths:
            shared.setdefault(e.seg_paths[0].resolve(), []).append(e.path)
    one = next((t for t, by in shared.items() if len(by) > 1), None)
    if one is not None:  # (a pattern without {stem}, all inputs in one folder)
        raise ParameterError(f"--ground-truths {truths}: {len(shared[one])} inputs "
                             f"({shared[one][0]}, {shared[one][1]}, ...) would "
                             f"share one ground truth, {one}: name each its own with {{stem}}")
    missing = [e.seg_paths[0] for e in out if e.seg_paths and not e.seg_paths[0].is_file()]
    if missing:
        raise FileNotFoundError(f"{missing[0]}: no such ground truth (--ground-truths "
                                f"{truths}); {len(missing)} of {len(out)} inputs have none")
    return out


#: The suffixes of a list file of inputs and their ground truths (``--ground-truths``).
_LIST_SUFFIXES = (".csv", ".tsv", ".txt", ".lst")


def _is_list(truths: str) -> bool:
    """Whether ``--ground-truths`` names a list file rather than a pattern."""
    return "{" not in truths and Path(truths).suffix.lower() in _LIST_SUFFIXES


def _truth_list(path: Path) -> dict:
    """An input's resolved path -> its ground truth, from a list file (:func:`file_entries`)."""
    import csv

    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such list of ground truths (--ground-truths: a "
                                "list file of INPUT GROUND_TRUTH lines, or a pattern with "
                                "{stem})")
    out = {}
    with open(path, encoding="utf-8-sig", newline="") as f:
        for number, line in enumerate(f, 1):
            text = line.strip()
            if not text or text.startswith("#"):
                continue
            sep = "," if "," in text else "\t" if "\t" in text else " " if '"' in text else None
            fields = (next(csv.reader([text], delimiter=sep, skipinitialspace=True)) if sep
                      else text.split())  # (a path with spaces in double quotes)
            fields = [x.strip() for x in fields if x.strip()]
            if number == 1 and [x.lower() for x in fields] in (
                    ["input", "ground_truth"], ["input", "ground truth"], ["input", "gt"]):
                continue  # (a header)
            if len(fields) != 2:
                raise ParameterError(f"{path}: line {number} is not an input and its ground "
                                     f"truth (2 paths), it has {len(fields)} field"
                                     f"{'s' if len(fields) != 1 else ''}: {text[:80]!r}")
            key = (path.parent / fields[0]).resolve()
            if key in out:
                raise ParameterError(f"{path}: line {number} names {fields[0]} again")
            out[key] = path.parent / fields[1]
    return out


def _truth_of(path: Path, pattern: str) -> Path:
    """The ground truth of ``path`` named by ``pattern`` (:func:`file_entries`)."""
    import string

    try:
        names = {f for _, f, _, _ in string.Formatter().parse(pattern) if f is not None}
    except ValueError:  # (an unmatched brace)
        names = set()
    if names not in ({"stem"}, set()) or "{" in pattern and not names:
        raise ParameterError(f"--ground-truths {pattern!r}: name each file's ground truth "
                             "with {stem} (the file's name without its suffix) and nothing "
                             "else in braces, e.g. '../labels/{stem}.label', or give a list "
                             "file (.csv, .tsv, .txt) of INPUT GROUND_TRUTH lines")
    return path.parent / pattern.format(stem=_stem(path))
