"""Files: compression by suffix, text lines, and atomic writes.

A trailing ``.gz``, ``.xz`` or ``.bz2`` is decompressed on reading and
applied on writing. Every write is atomic: the data goes to a temporary file
in the target folder, which is then renamed over the target, so an
interrupted run never leaves a half-written file; :class:`Outputs` does the
same for several files at once, all or nothing.
"""

from __future__ import annotations

import bz2
import gzip
import io
import lzma
import math
import os
import re
import tempfile
import zlib
from collections.abc import Iterator
from pathlib import Path
from typing import Callable

from .._runtime import memory
from ..checks import check_int
from ..errors import MemoryLimitError, MeshFormatError, ParameterError, SuperfacetsError

__all__ = ["split_suffix", "read_bytes", "text_lines", "text_chunks", "utf8_text",
           "not_a_folder", "number_table", "atomic_write", "Outputs",
           "save", "COMPRESSIONS", "decompressed", "decompressed_head", "sha256_of", "array_digest",
           "load_checked", "user_path", "sniffed_format", "format_hint", "MAGIC"]


#: Compression suffixes understood on reading and writing.
COMPRESSIONS = {".gz": gzip.decompress, ".xz": lzma.decompress, ".bz2": bz2.decompress}
#: Their streams, read a block at a time (never the whole output at once)
_OPENERS = {".gz": gzip.open, ".xz": lzma.open, ".bz2": bz2.open}
_ERRORS = (OSError, EOFError, lzma.LZMAError, ValueError, zlib.error)
_COMPRESSORS = {".gz": gzip.compress, ".xz": lzma.compress, ".bz2": bz2.compress}


def split_suffix(path: Path) -> tuple[str, str | None]:
    """Return (format, compression suffix or None) of a file name."""
    suffixes = [s.lower() for s in path.suffixes]
    comp = suffixes[-1] if suffixes and suffixes[-1] in COMPRESSIONS else None
    rest = suffixes[:-1] if comp else suffixes
    fmt = rest[-1].lstrip(".") if rest else ""
    return fmt, comp


def _check_regular(path: Path) -> None:
    """Refuse a missing file, a folder, a device or a pipe (see :func:`read_bytes`)."""
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a directory")
    if not path.is_file():
        raise MeshFormatError(f"{path}: not a regular file (a device or a pipe); give a file")


def read_head(path: Path, size: int = 1 << 16) -> bytes:
    r"""The first ``size`` bytes of the uncompressed file ``path`` (all of a shorter one):
    enough for a header, without reading a large file whole.

    Raises
    ------
    FileNotFoundError, IsADirectoryError, MeshFormatError
        As :func:`read_bytes`.

    Examples
    --------
    >>> _ = Path("h.txt").write_bytes(b"ply\nformat ascii 1.0\n")
    >>> read_head(Path("h.txt"), 3)
    b'ply'
    """
    _check_regular(path)
    with open(path, "rb") as fh:
        return fh.read(size)


#: How the formats' files begin: ``(name, suffixes, first bytes)``, for telling a file
#: whose suffix names another format what it looks like (:func:`sniffed_format`).
MAGIC = (("PLY", ("ply",), (b"ply\n", b"ply\r")), ("LAS", ("las", "laz"), (b"LASF",)),
         ("E57", ("e57",), (b"ASTM-E57",)), ("PCD", ("pcd",), (b"# .PCD", b"VERSION")),
         ("NPY", ("npy",), (b"\x93NUMPY",)), ("GLB", ("glb",), (b"glTF",)),
         ("Gmsh", ("msh",), (b"$MeshFormat",)), ("VTK", ("vtk",), (b"# vtk DataFile",)),
         ("Medit", ("mesh",), (b"MeshVersionFormatted",)),
         ("OFF", ("off",), (b"OFF", b"COFF", b"NOFF")), ("gzip", ("gz",), (b"\x1f\x8b",)),
         ("xz", ("xz",), (b"\xfd7zXZ",)), ("bzip2", ("bz2",), (b"BZh",)),
         ("ZIP (NPZ)", ("npz", "zip"), (b"PK\x03\x04",)))


def sniffed_format(path: Path) -> tuple[str, tuple[str, ...]] | None:
    r"""The format a file's first bytes show (its name and suffixes, a row of
    :data:`MAGIC`), or None where they show none of them: what a file looks like when its
    suffix's reader cannot read it.

    Parameters
    ----------
    path : str or os.PathLike
        A regular file, read as it is (not decompressed).

    Returns
    -------
    (str, tuple of str) or None

    Raises
    ------
    FileNotFoundError, IsADirectoryError, MeshFormatError
        As :func:`read_head`.

    Examples
    --------
    >>> _ = Path("scan.ply").write_bytes(b"LASF" + bytes(300))
    >>> sniffed_format(Path("scan.ply"))
    ('LAS', ('las', 'laz'))
    """
    head = read_head(Path(path), 32)
    for name, suffixes, starts in MAGIC:
        if head.startswith(starts):
            return name, suffixes
    return None


def format_hint(path) -> str:
    r"""What a file its suffix's reader refused looks like, where its first bytes show
    another format (:func:`sniffed_format`), for the end of the reader's message:
    ``" (it begins as PCD files do: name it .pcd)"``; "" where they show its own format,
    none, or the file cannot be read.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    str

    Raises
    ------
    TypeError
        Never for a path: an unreadable file gives "".

    Examples
    --------
    >>> _ = Path("scan.ply").write_bytes(b"# .PCD v0.7\nVERSION 0.7\n")
    >>> format_hint("scan.ply")
    ' (it begins as PCD files do: name it .pcd)'
    """
    path = Path(path)
    fmt, comp = split_suffix(path)
    try:
        seen = sniffed_format(path) if path.is_file() else None
    except (OSError, MeshFormatError):
        return ""
    if seen is None or (comp or "").lstrip(".") in seen[1] or (not comp and fmt in seen[1]):
        return ""
    name, suffixes = seen
    if "." + suffixes[0] in COMPRESSIONS:
        return f" (it is {name}-compressed: name it {path.name}.{suffixes[0]})"
    return f" (it begins as {name} files do: name it {' or '.join('.' + x for x in suffixes)})"


#: A compressed mesh or cloud decompresses to at most this many times its size: real
#: ones are 3 to 10 times (the benchmark's archive 6, its Table-1 meshes 3.5-4.8), a
#: regular grid's coordinates written as text up to 82 (xz); the decompression bombs of
#: an attack, one element repeated millions of times, 700 to 7,000.
#: ``SUPERFACETS_MAX_RATIO`` raises it for a genuine file.
MAX_RATIO = 250


def max_ratio() -> float:
    """The bound on decompressed / compressed size: ``SUPERFACETS_MAX_RATIO`` where set
    (a number >= 1), else :data:`MAX_RATIO`.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        If ``SUPERFACETS_MAX_RATIO`` is set to anything but a number >= 1.

    Examples
    --------
    >>> max_ratio() == MAX_RATIO
    True
    """
    raw = os.environ.get("SUPERFACETS_MAX_RATIO", "").strip()
    if not raw:
        return float(MAX_RATIO)
    try:
        value = float(raw)
    except ValueError:
        value = float("nan")
    if not (value >= 1 and math.isfinite(value)):
        raise ParameterError(f"SUPERFACETS_MAX_RATIO={raw[:40]!r}: give a number >= 1 (the "
                             "most times a compressed input may grow), or unset it")
    return value


def read_bytes(path: Path, comp: str | None, what: str = "file",
               counts: dict | None = None, bounded: bool = True) -> bytes:
    """The content of ``path``, decompressed when ``comp`` names a compression suffix:
    at most 256 bytes for each element its header declares (``counts``, from
    :func:`~superfacets.io.headers.header_counts`) beyond its first 64 KiB, at most
    :func:`max_ratio` times the file's size where ``bounded`` (a mesh or a cloud: a
    label file, a run of repeated values, is not), and at most half of what this process
    may allocate (:func:`decompressed`).

    Raises
    ------
    FileNotFoundError, IsADirectoryError
        If there is no such file, or it is a folder.
    MeshFormatError
        If it is not a regular file (a device or FIFO, which could be endless),
        cannot be decompressed, or is empty ("empty {what}").
    """
    _check_regular(path)
    limit = (1 << 16) + 256 * sum(counts.values()) if counts else None
    ratio = max_ratio() if bounded and comp is not None else None
    data = path.read_bytes() if comp is None else decompressed(path, comp, limit, ratio)
    if not data:
        raise MeshFormatError(f"{path}: empty {what}")
    return data


def decompressed(path: Path, comp: str, limit: int | None = None,
                 ratio: float | None = None) -> bytes:
    """The decompressed content of ``path``, read as a stream a block at a time and
    stopped past ``limit`` bytes or half of what this process may still allocate (a run
    needs more than its file), so that a small file that decompresses to more than it
    declares or than fits (a decompression bomb) is refused early, not after filling
    the memory.

    Parameters
    ----------
    path : pathlib.Path
    comp : str
        The compression suffix (``".gz"``, ``".xz"``, ``".bz2"``).
    limit : int, optional
        The most bytes to decompress.
    ratio : float, optional
        The most times the file's size it may decompress to.

    Returns
    -------
    bytes

    Raises
    ------
    MeshFormatError
        If the stream is damaged.
    MemoryLimitError
        If it decompresses to more than ``limit``.

    Examples
    --------
    >>> _ = Path("x.txt.gz").write_bytes(gzip.compress(b"0 1 2"))
    >>> decompressed(Path("x.txt.gz"), ".gz")
    b'0 1 2'
    """

    avail = memory.available_bytes()
    cap = avail // 2 if avail else 1 << 62
    why = ("what its header declares allows" if limit is not None and limit < cap else
           "this process may use for it")
    limit = min(limit or cap, cap)
    size = path.stat().st_size
    bomb = ratio is not None and int(ratio * max(size, 1 << 12)) < limit
    if bomb:
        limit = int(ratio * max(size, 1 << 12))  # (a file of a few KiB: as one of 4 KiB)
    out = io.BytesIO()
    try:
        with _OPENERS[comp](path, "rb") as f:
            while out.tell() <= limit and (block := f.read(min(1 << 24, limit + 1 - out.tell()))):
                out.write(block)
    except _ERRORS as exc:
        raise MeshFormatError(f"{path}: cannot decompress ({comp[1:]}): {exc}") from None
    if out.tell() > limit:
        if bomb:
            raise MemoryLimitError(
                f"{path}: decompresses to more than {ratio:g} times its {size:,} bytes (real "
                "meshes and scans: 3 to 80 times): refused as a likely decompression bomb; "
                "SUPERFACETS_MAX_RATIO raises the bound for a genuine file", limit, limit)
        raise MemoryLimitError(f"{path}: decompresses to more than {limit:,} bytes (the file "
                               f"holds {size:,}), more than {why}: refused", limit, limit)
    return out.getvalue()


def decompressed_head(path: Path, comp: str, size: int) -> bytes:
    r"""The first ``size`` bytes of the decompressed content (the rest not decompressed).

    Parameters
    ----------
    path : pathlib.Path
    comp : str
        The compression suffix.
    size : int
        At most 1 GiB (a header is a few kilobytes).

    Returns
    -------
    bytes

    Raises
    ------
    MeshFormatError
        If the stream's start is damaged.
    ParameterError
        If ``size`` is not an integer in ``[0, 2**30]``.

    Examples
    --------
    >>> _ = Path("x.off.gz").write_bytes(gzip.compress(b"OFF\n3 1 0\n" + bytes(10**6)))
    >>> decompressed_head(Path("x.off.gz"), ".gz", 10)
    b'OFF\n3 1 0\n'
    """
    size = check_int("size", size, lo=0, hi=1 << 30)
    try:
        with _OPENERS[comp](path, "rb") as f:
            return f.read(size)
    except _ERRORS as exc:
        raise MeshFormatError(f"{path}: cannot decompress ({comp[1:]}): {exc}") from None


def sha256_of(path) -> str:
    """The SHA-256 of a file's bytes, read 16 MiB at a time (hex digits).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    str

    Raises
    ------
    OSError
        If the file cannot be read.

    Examples
    --------
    >>> _ = Path("e.bin").write_bytes(b"")
    >>> sha256_of("e.bin")[:12]
    'e3b0c44298fc'
    """
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 24), b""):
            h.update(block)
    return h.hexdigest()


def array_digest(a, described: bool = True) -> str:
    """The CRC-32 of an array's dtype, shape and bytes (8 hex digits), read where it lies in
    memory: a work file's digest taken as it is written (no second read of the file), and
    checked on the array read back (:func:`load_checked`).

    A checksum that catches a file changed by accident (another run, another machine on a
    shared folder, a truncated copy), at about 7 GB/s (SHA-256 reads 2 GB/s: 3 of the 45 s
    of 10M points in 4 tiles); not a signature: a work file's digest is kept in the work
    folder beside it.

    Parameters
    ----------
    a : ndarray
        Any dtype (structured included), any shape.
    described : bool, default True
        False: of the bytes alone (a raw file of records, summed block by block as it is
        appended to: ``zlib.crc32(block, crc)`` over the blocks gives the same).

    Returns
    -------
    str

    Examples
    --------
    >>> array_digest(np.arange(3)) == array_digest(np.arange(3.0))
    False
    >>> first, rest = np.arange(5)[:2], np.arange(5)[2:]
    >>> f"{zlib.crc32(rest, zlib.crc32(first)):08x}" == array_digest(np.arange(5), False)
    True
    """
    import numpy as np

    a = np.ascontiguousarray(a)
    crc = zlib.crc32(f"{a.dtype.descr}{a.shape}".encode()) if described else 0
    return f"{zlib.crc32(a.reshape(-1).view(np.uint8), crc):08x}"


def load_checked(path, digest: str | None, dtype=None, *, mapped: bool = False):
    """An array read back from a work file, refused unless it is the one written there.

    Parameters
    ----------
    path : str or os.PathLike
        A ``.npy`` file, or with ``dtype`` raw records of that dtype.
    digest : str or None
        Its :func:`array_digest` when written (None: nothing to check against, refused).
    dtype : numpy.dtype, optional
        The records' dtype of a raw file (whose digest is of its bytes alone:
        ``described=False``).
    mapped : bool, default False
        With ``dtype``: the file mapped read-only into memory (``np.memmap``), not copied
        into a new array: a caller that keeps a part of it copies only that part (the
        digest still reads every byte, from the system's file cache).

    A file found as written is not summed again in this process while its state on disk
    (device, inode, size, modification and change times) stays the same: a work file
    replaced, written again or touched since is read in full again.

    Returns
    -------
    ndarray
        Read-only where ``mapped``.

    Raises
    ------
    SuperfacetsError
        If the array read is not the one written (its bytes, dtype or shape changed, or the
        file no longer reads): the compiled kernels trust the arrays they are given.
    OSError
        If the file cannot be read.

    Examples
    --------
    >>> np.save("a.npy", np.arange(4))
    >>> load_checked("a.npy", array_digest(np.arange(4))).tolist()
    [0, 1, 2, 3]
    """
    import numpy as np

    seen = _file_state(path, digest, dtype)
    try:
        if dtype is not None and mapped:
            a = (np.memmap(path, dtype=dtype, mode="r") if os.path.getsize(path)
                 else np.empty(0, dtype=dtype))  # (an empty file cannot be mapped)
        else:
            a = np.fromfile(path, dtype=dtype) if dtype is not None else (
                np.load(path, allow_pickle=False) if _npy_fits(path) else None)
    except ValueError:  # (a header that no longer reads; a size not whole records)
        a = None
    if a is None or digest is None or (
            (seen is None or seen not in _CHECKED) and array_digest(a, dtype is None) != digest):
        raise SuperfacetsError(f"{path}: changed since this run wrote it (the work "
                               "folder's files belong to the run): refused")
    if seen is not None:
        if len(_CHECKED) >= _MOST_CHECKED:
            _CHECKED.clear()
        _CHECKED.add(seen)
    return a


#: The work files :func:`load_checked` found as written, by their state on disk (a file
#: written again, replaced or touched is another state, read in full again): a tile's file
#: is read by each box that overlaps it (0.37 s of CRC-32 a run of 10M points in 8 tiles).
_CHECKED: set = set()
_MOST_CHECKED = 4096


def _file_state(path, digest, dtype) -> tuple | None:
    """A file's identity, size and times with the digest and dtype it is read with (None
    where it cannot be read: :func:`load_checked` reads it and says so)."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return (os.fspath(path), st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns,
            digest, None if dtype is None else str(dtype))


def _npy_fits(path) -> bool:
    """Whether a ``.npy`` file's header describes exactly the bytes that follow it (a
    changed shape would have ``np.load`` ask for any amount of memory before the digest
    is checked)."""
    from numpy.lib import format as npy

    try:
        with open(path, "rb") as f:
            version = npy.read_magic(f)
            read = {(1, 0): npy.read_array_header_1_0, (2, 0): npy.read_array_header_2_0}
            if version not in read:
                return False
            shape, _, dtype = read[version](f)
            size = os.fstat(f.fileno()).st_size
            return not dtype.hasobject and \
                f.tell() + math.prod(shape) * dtype.itemsize == size
    except (ValueError, TypeError, SyntaxError):
        return False


def number_table(lines: list, dtype=None):
    """Lines of numbers as an ``(n, width)`` array, by :func:`numpy.loadtxt` (no comments),
    without its warning on lines that hold no number: those give ``(0, 1)``, as it does.

    Readers run on many threads at once (a Dask worker's, a user's pool): a reader that
    silenced numpy's warning with :class:`warnings.catch_warnings` changed the filters of
    every thread meanwhile, and two such readers ending out of order left every warning of
    the process ignored.

    Parameters
    ----------
    lines : list of str
    dtype : numpy dtype, optional
        float64 by default.

    Returns
    -------
    (n, width) ndarray

    Raises
    ------
    ValueError
        Where numpy cannot read the lines whole (ragged rows, a word that is no number).

    Examples
    --------
    >>> number_table(["1 2 3", "4 5 6"]).shape, number_table(["  ", ""]).shape
    ((2, 3), (0, 1))
    """
    import numpy as np

    dtype = np.float64 if dtype is None else dtype
    if not any(line.strip() for line in lines):
        return np.zeros((0, 1), dtype=dtype)
    return np.loadtxt(lines, dtype=dtype, comments=None, ndmin=2)


#: The byte-order marks of UTF-16 text (little and big endian).
UTF16_MARKS = (b"\xff\xfe", b"\xfe\xff")


def utf8_text(data: bytes, path: Path) -> bytes:
    r"""``data`` as UTF-8 where it is UTF-16 text with its byte-order mark (Windows
    PowerShell's ``>`` writes it), else as it is.

    Parameters
    ----------
    data : bytes
    path : pathlib.Path
        Named in errors.

    Returns
    -------
    bytes

    Raises
    ------
    MeshFormatError
        Where the mark is followed by something UTF-16 does not encode.

    Examples
    --------
    >>> utf8_text("0 0 1\n".encode("utf-16"), Path("p.xyz"))
    b'0 0 1\n'
    """
    if bytes(data[:2]) not in UTF16_MARKS:
        return data
    try:
        return bytes(data).decode("utf-16").encode("utf-8")
    except UnicodeDecodeError:
        raise MeshFormatError(f"{path}: begins as UTF-16 text, and is not") from None


def not_a_folder(path) -> str:
    """Why ``path``, named as a file's folder, is none: ``'does not exist'``, or ``'is a
    file, not a folder'``.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    str

    Raises
    ------
    OSError
        Never: a path that cannot be looked at does not exist.

    Examples
    --------
    >>> not_a_folder("no/such/folder")
    'does not exist'
    """
    return "is a file, not a folder" if Path(path).is_file() else "does not exist"


def text_lines(data: bytes, path: Path) -> list[str]:
    """Non-empty lines with comments (``#`` to end of line) removed (UTF-8, or UTF-16 with
    its byte-order mark: :func:`utf8_text`)."""
    data = utf8_text(data, path)
    try:
        text = data.decode("utf-8-sig")  # (a BOM, as Windows tools write it)
    except UnicodeDecodeError:
        raise MeshFormatError(f"{path}: not a text file (binary data in a text format)") from None
    if "#" in text:
        text = "\n".join(line.split("#", 1)[0] for line in text.splitlines())
    return list(filter(None, map(str.strip, text.split("\n"))))  # (the loop in C)


def text_chunks(data: bytes, path: Path, size: int = 1 << 23) -> Iterator[list[str]]:
    """:func:`text_lines` in pieces of about ``size`` bytes, each cut at a line's end: the
    lines of a large text are never all held as Python strings at once.

    Parameters
    ----------
    data : bytes
        The text (UTF-8, or UTF-16 with its byte-order mark: :func:`utf8_text`).
    path : pathlib.Path
        Named in errors.
    size : int
        Bytes per piece (the last line of a piece runs on to its end).

    Yields
    ------
    list of str
        The piece's non-empty lines, comments removed, stripped (a piece without any
        is skipped).

    Raises
    ------
    MeshFormatError
        If a piece is not UTF-8 text.

    Examples
    --------
    >>> [len(p) for p in text_chunks(b"1\\n2\\n# c\\n3\\n", Path("t.txt"), size=2)]
    [1, 1, 1]
    """
    data = utf8_text(data, path)
    start, n = 0, len(data)
    while start < n:
        end = data.find(b"\n", min(start + size, n) - 1)
        end = n if end < 0 else end + 1
        if lines := text_lines(data[start:end], path):
            yield lines
        start = end


class Outputs:
    """Several output files written all or nothing.

    :meth:`write` puts each content in a temporary file beside its target;
    :meth:`commit` (on leaving the ``with`` block without an error) renames
    them all over their targets; on an error, an interruption (``Ctrl-C``;
    the command line turns ``SIGTERM`` into the same) or :meth:`abort`, the
    temporary files are removed and no target is touched.

    Targets: ``-`` is standard output; a symbolic link is followed and the
    file it points to is replaced (the link stays); an existing target that
    is not a regular file (a device such as ``/dev/stdout``, a FIFO) is
    written in place at commit, never replaced. A replaced file keeps its
    permissions; a new one gets ``0o644``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> with Outputs() as out:
    ...     _ = out.write(d / "a.txt", b"one")
    ...     _ = out.write(d / "b.txt", b"two")
    >>> sorted(p.name for p in d.iterdir())
    ['a.txt', 'b.txt']
    """

    def __init__(self) -> None:
        self._temps: list[tuple[str, Path]] = []  # (temporary file, regular target)
        self._direct: list[tuple[Path | None, bytes]] = []  # (special target or stdout, data)

    def __enter__(self) -> "Outputs":
        return self

    def __exit__(self, kind, exc, tb) -> None:
        if kind is None:
            self.commit()
        else:
            self.abort()

    def write(self, path, content: Callable[[io.BufferedWriter], None] | bytes) -> Path:
        """Stage ``content`` (bytes, or a function writing to a binary file) for ``path``.

        A ``.gz``/``.xz``/``.bz2`` suffix on ``path`` compresses the content.

        Raises
        ------
        FileNotFoundError
            If the target's folder does not exist.
        IsADirectoryError
            If the target is a folder.
        """
        path = Path(path)
        if str(path) == "-":
            self._direct.append((None, _render(content, None)))
            return path
        real = Path(os.path.realpath(path))
        folder = real.parent
        if not folder.is_dir():
            raise FileNotFoundError(f"{path}: folder {path.parent} {not_a_folder(folder)}")
        if real.is_dir():
            raise IsADirectoryError(f"{path}: is a directory")
        comp = path.suffix.lower() if path.suffix.lower() in _COMPRESSORS else None
        if real.exists() and not real.is_file():  # a device or a FIFO: written in place
            self._direct.append((real, _render(content, comp)))
            return path
        try:  # (the staged file's own name is ours: an error names the target)
            fd, tmp = tempfile.mkstemp(prefix=f".{real.name}.", suffix=".tmp", dir=folder)
        except OSError as exc:
            raise OSError(exc.errno, f"cannot write there ({exc.strerror})", str(path)) \
                from None
        self._temps.append((tmp, real))
        try:
            with os.fdopen(fd, "wb") as fh:
                if comp is None and callable(content):
                    content(fh)
                else:
                    fh.write(_render(content, comp))
        except OSError as exc:
            if exc.filename not in (None, tmp):
                raise
            raise OSError(exc.errno, exc.strerror, str(path)) from None
        os.chmod(tmp, (os.stat(real).st_mode & 0o7777) if real.exists() else 0o644)
        return path

    def commit(self) -> None:
        """Rename every staged file over its target; write the special targets (a Ctrl-C
        waits for the end: :func:`superfacets._runtime.interrupts.committing`)."""
        from .._runtime import interrupts

        with interrupts.committing():
            self._commit()

    def _commit(self) -> None:
        try:
            for tmp, real in self._temps:
                os.replace(tmp, real)
            self._temps = []
            for real, data in self._direct:
                if real is None:
                    import sys

                    try:
                        sys.stdout.flush()
                        sys.stdout.buffer.write(data)
                        sys.stdout.buffer.flush()
                    except BrokenPipeError:
                        raise
                    except OSError as exc:  # (a full disk behind a redirection: named)
                        raise OSError(exc.errno, exc.strerror, "standard output") from None
                else:
                    try:
                        with open(real, "wb") as fh:
                            fh.write(data)
                    except OSError as exc:  # a write's error names no file: name it
                        raise OSError(exc.errno, exc.strerror, str(real)) from None
            self._direct = []
        finally:
            self.abort()

    def abort(self) -> None:
        """Remove the staged temporary files; touch no target."""
        for tmp, _ in self._temps:
            try:
                os.unlink(tmp)
            except FileNotFoundError:
                pass
        self._temps = []
        self._direct = []


def _render(content, comp: str | None) -> bytes:
    if callable(content):
        buf = io.BytesIO()
        content(buf)
        data = buf.getvalue()
    else:
        data = bytes(content)
    return _COMPRESSORS[comp](data) if comp is not None else data


def atomic_write(path, write: Callable[[io.BufferedWriter], None] | bytes) -> Path:
    """Write one file atomically (see :class:`Outputs`, which this uses alone).

    Parameters
    ----------
    path : str or os.PathLike
        Target file (``-``: standard output). Its folder must exist.
    write : bytes or callable
        The content, or a function writing it to a binary file object.
        A ``.gz``/``.xz``/``.bz2`` suffix on ``path`` compresses the content.

    Returns
    -------
    pathlib.Path
        The target path.

    Raises
    ------
    FileNotFoundError
        If the folder does not exist.
    IsADirectoryError
        If the target is a folder.
    """
    with Outputs() as out:
        return out.write(path, write)


def save(path, content, outputs: Outputs | None = None) -> Path:
    """Write ``content`` to ``path`` atomically, or stage it in ``outputs`` when given
    (a :class:`TypeError` where ``outputs`` is something else)."""
    if outputs is not None and not isinstance(outputs, Outputs):
        raise TypeError(f"outputs must be a superfacets.io.files.Outputs, got "
                        f"{type(outputs).__name__}")
    path = path if str(path) == "-" else user_path(path)  # (~/out.seg: the home's)
    return atomic_write(path, content) if outputs is None else outputs.write(path, content)


def user_path(path) -> Path:
    """A path as a user gives it to a reader: ``~`` expanded (a notebook's
    ``read_cloud("~/scans/tile.laz")``; a shell expands it, Python does not), a URL
    refused in words.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    pathlib.Path

    Raises
    ------
    FileNotFoundError
        If ``path`` is a URL (``https://...``): the readers read files; download it first.

    Examples
    --------
    >>> user_path("~/scan.las") == Path.home() / "scan.las"
    True
    """
    text = os.fspath(path)
    if isinstance(text, str) and re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*://", text):
        raise FileNotFoundError(f"{text}: a URL; the readers read files: download it first "
                                "(e.g. curl -O, or urllib.request.urlretrieve in Python)")
    return Path(text).expanduser() if str(text).startswith("~") else Path(text)

