"""Files: compression by suffix, text lines, and atomic writes.

A trailing ``.gz``, ``.xz`` or ``.bz2`` is decompressed on reading and
applied on writing. Every write is atomic: the data goes to a temporary file
in the target folder, which is then renamed over the target, so an
interrupted run never leaves a half-written file.
"""

from __future__ import annotations

import bz2
import gzip
import io
import lzma
import os
import tempfile
from pathlib import Path
from typing import Callable

from ..errors import MeshFormatError

__all__ = ["split_suffix", "read_bytes", "text_lines", "atomic_write", "COMPRESSIONS"]

#: Compression suffixes understood on reading and writing.
COMPRESSIONS = {".gz": gzip.decompress, ".xz": lzma.decompress, ".bz2": bz2.decompress}
_COMPRESSORS = {".gz": gzip.compress, ".xz": lzma.compress, ".bz2": bz2.compress}


def split_suffix(path: Path) -> tuple[str, str | None]:
    """Return (format, compression suffix or None) of a file name."""
    suffixes = [s.lower() for s in path.suffixes]
    comp = suffixes[-1] if suffixes and suffixes[-1] in COMPRESSIONS else None
    rest = suffixes[:-1] if comp else suffixes
    fmt = rest[-1].lstrip(".") if rest else ""
    return fmt, comp


def read_bytes(path: Path, comp: str | None) -> bytes:
    """The content of ``path``, decompressed when ``comp`` names a compression suffix."""
    data = path.read_bytes()
    if comp is None:
        return data
    try:
        return COMPRESSIONS[comp](data)
    except (OSError, EOFError, lzma.LZMAError, ValueError) as exc:
        raise MeshFormatError(f"{path}: cannot decompress ({comp[1:]}): {exc}") from None


def text_lines(data: bytes, path: Path) -> list[str]:
    """Non-empty lines with comments (``#`` to end of line) removed."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise MeshFormatError(f"{path}: not a text file (binary data in a text format)") from None
    if "#" in text:
        text = "\n".join(line.split("#", 1)[0] for line in text.splitlines())
    lines = text.split("\n")
    return [ln for ln in (ln.strip() for ln in lines) if ln]


def atomic_write(path, write: Callable[[io.BufferedWriter], None] | bytes) -> Path:
    """Write a file atomically: a temporary file in the same folder, then rename.

    Parameters
    ----------
    path : str or os.PathLike
        Target file. Its folder must exist.
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
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise FileNotFoundError(f"{path}: folder {folder} does not exist")
    comp = path.suffix.lower() if path.suffix.lower() in _COMPRESSORS else None
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as fh:
            if comp is not None:
                buf = io.BytesIO()
                write(buf) if callable(write) else buf.write(write)
                fh.write(_COMPRESSORS[comp](buf.getvalue()))
            elif callable(write):
                write(fh)
            else:
                fh.write(write)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return path
