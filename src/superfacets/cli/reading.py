"""Reading a command's input: its header checked before the data, the data refused in
one line when no command can handle it, errors named after the file."""

from __future__ import annotations

from pathlib import Path

__all__ = ["named_after", "check_header", "read_usable", "reads_long", "shows_stages",
           "LONG_ELEMENTS"]

#: Inputs of this many elements or more show their long stages on a terminal
LONG_ELEMENTS = 500_000

#: Input files from this size on show a bar while they are read (on a terminal)
READING_BAR_BYTES = 32 << 20
#: ... compressed ones (LAZ, .gz, .xz, .bz2) from this size: they take longer a byte
#: (a LAZ tile of 3 MiB holds 0.7M points, read in 0.4 s)
COMPRESSED_BAR_BYTES = 4 << 20
_COMPRESSED = (".laz", ".gz", ".xz", ".bz2")


def reads_long(path) -> bool:
    """Whether reading the file ``path`` takes long enough to show a bar while it is read:
    :data:`READING_BAR_BYTES` or more, :data:`COMPRESSED_BAR_BYTES` for a compressed file.

    Examples
    --------
    >>> reads_long("no-such-file.laz")
    False
    """
    p = Path(path)
    size = p.stat().st_size if p.is_file() else 0
    return size >= (COMPRESSED_BAR_BYTES if p.suffix.lower() in _COMPRESSED
                    else READING_BAR_BYTES)


def named_after(path, exc: Exception) -> Exception:
    """``exc`` with its message led by the input's name, once (an error about the
    mesh may already start with it)."""
    message = str(exc)
    if any(message.startswith(f"{name}: ") for name in (str(path), Path(path).name)):
        return exc
    return type(exc)(f"{path}: {message}")


def check_header(path) -> None:
    """Before a file is read: refuse a header that declares more than the file holds, or
    elements whose run would not fit in what this process may use (one line, not a
    ``MemoryError`` after minutes of reading).

    Raises
    ------
    MeshFormatError, MemoryLimitError
    """
    from .._runtime.memory import check_memory
    from ..elements.kinds import kind_of
    from ..io.headers import header_counts

    counts = header_counts(path)
    # (binary PLY, LAS/LAZ and .npy files are read a region at a time by a tiled run;
    # any other file is read whole first: its points, 32 bytes each, beside the tiles)
    streamed = Path(path).suffix.lower() in (".ply", ".las", ".laz", ".npy")
    for kind in ("faces", "points"):
        if counts and counts.get(kind):
            rules = kind_of(kind)
            check_memory(counts[kind], rules.peak_bytes, f"{path}: {counts[kind]:,} {kind}",
                         tiles_help=rules.tiled_bytes is not None,
                         input_bytes=(rules.tiled_bytes or 0) + (0 if streamed else 32))


def read_usable(path, *, clouds: bool = False):
    """Read the input of a command and refuse, in one line, what no command can handle.

    Every command that reads a mesh (or, with ``clouds``, a mesh or a point
    cloud) comes through here, so that an input with coordinates that would
    overflow, a zero extent or a zero area is refused the same way by each
    (:meth:`superfacets.inputs.mesh.Mesh.check_usable`), before any picture, metric
    or segmentation is attempted.

    Raises
    ------
    SuperfacetsError, OSError
        Named after ``path``.
    """
    from ..errors import InvalidCloudError, InvalidMeshError, MeshFormatError, SuperfacetsError
    from ..io import read_input, read_mesh
    from ..io.files import format_hint

    try:
        check_header(path)
        data = read_input(path) if clouds else read_mesh(path)
    except (MeshFormatError, InvalidMeshError, InvalidCloudError) as exc:
        hint = format_hint(path)
        if hint and not str(exc).endswith(hint):
            raise type(exc)(str(exc) + hint) from None
        raise
    try:
        data.check_usable()
    except SuperfacetsError as exc:
        raise named_after(path, exc) from None
    return data



def shows_stages(args, n_elements: int | None = None, path=None) -> bool:
    """Whether a command shows a line for a long stage (reading, segmenting, rendering,
    writing): on a terminal, without ``-q``, for a file that reads long
    (:func:`reads_long`) or an input of :data:`LONG_ELEMENTS` elements or more.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> shows_stages(SimpleNamespace(quiet=True), 10**7)
    False
    """
    import sys

    if getattr(args, "quiet", False) or not sys.stderr.isatty():
        return False
    return reads_long(path) if n_elements is None else n_elements >= LONG_ELEMENTS
