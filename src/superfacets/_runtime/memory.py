"""Memory a run will need, estimated before it is spent, against what the process may use.

A run's peak grows with its elements (the element graph and the passes' records; the
table of kinds holds the bytes per element of each kind, with a margin, from
``benchmarks/memory_check.py``). Where the
estimate exceeds what this process may still allocate (the machine's available memory,
or an address-space limit set with ``ulimit -v``), the run is refused with
:class:`~superfacets.errors.MemoryLimitError` in one line, before reading or building
anything large, instead of ending in a ``MemoryError`` traceback or the kernel's kill.
"""

from __future__ import annotations

import os
import resource
import sys

from ..errors import MemoryLimitError

__all__ = ["ARENAS", "BASE_BYTES", "available_bytes", "check_memory", "estimated_peak",
           "resident_bytes", "address_space_left", "tiles_that_fit", "limit_arenas",
           "give_back_free_memory", "discard_pages"]

_found: dict = {}  # the C library's functions, once looked up (False: not available)
_DONTNEED = 4  # MADV_DONTNEED (Linux)


def _libc(name: str, argtypes: tuple):
    """glibc's function ``name`` (``argtypes``: ctypes type names; returns an int), or
    False where there is none (another system or C library: nothing to do)."""
    if name not in _found:
        _found[name] = False
        if sys.platform.startswith("linux"):
            try:
                import ctypes

                f = getattr(ctypes.CDLL("libc.so.6"), name)
                f.argtypes = [getattr(ctypes, t) for t in argtypes]
                f.restype = ctypes.c_int
                _found[name] = f
            except (OSError, AttributeError):
                pass
    return _found[name]


def available_bytes() -> int | None:
    """Bytes this process may still allocate: the machine's available memory
    (``MemAvailable``), and under an address-space limit what is left of it; None when
    neither can be read.

    Examples
    --------
    >>> n = available_bytes()
    >>> n is None or n > 0
    True
    """
    avail = None
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    avail = int(line.split()[1]) * 1024
                    break
    except OSError:
        pass
    left = address_space_left()
    if left is not None:
        avail = left if avail is None else min(avail, left)
    return avail


def address_space_left() -> int | None:
    """Bytes of address space this process has left under a limit (``ulimit -v``), or
    None where it has none.

    Examples
    --------
    >>> n = address_space_left()
    >>> n is None or n >= 0
    True
    """
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft == resource.RLIM_INFINITY:
        return None
    try:
        with open("/proc/self/statm") as f:
            used = int(f.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        used = 0
    return max(0, soft - used)


#: A run's memory beyond its elements': the interpreter, numpy, scipy and the kernels
#: (the per-element figures, ``ElementKind.peak_bytes``, were fitted with this base:
#: ``benchmarks/memory_check.py``)
BASE_BYTES = 80 * 2**20

#: A tile's elements with its halo, as a share of its core's (3M points in 3 tiles:
#: 1.13; room for uneven tiles)
_HALO_SHARE = 1.25


def resident_bytes() -> int:
    """This process's resident memory now (0 where it cannot be read)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


def estimated_peak(n_elements: int, bytes_per_element: int, *, held: int = 0,
                   input_bytes: int = 0) -> int:
    """A run's estimated peak, in bytes, beyond what the process holds now (``held``):
    what :data:`BASE_BYTES` has left beyond it, and ``bytes_per_element`` for each
    element, less the input's own arrays where they are held already (``input_bytes``:
    the bytes per element count them).

    Examples
    --------
    >>> estimated_peak(1_000_000, 250) // 2**20
    318
    >>> estimated_peak(1_000_000, 250, held=2**30) // 2**20   # (the interpreter held)
    238
    >>> estimated_peak(1_000_000, 250, held=2**30, input_bytes=24_000_000) // 2**20
    215
    """
    per_element = max(int(n_elements) * int(bytes_per_element) - int(input_bytes), 0)
    return max(BASE_BYTES - int(held), 0) + per_element


def tiles_that_fit(n_elements: int, bytes_per_element: int, avail: int, *,
                   input_bytes: int = 0, most: int = 4096) -> int | None:
    """The fewest tiles (2 .. ``most``) whose run fits in ``avail`` bytes: one tile's
    elements and its halo at a time, beside ``input_bytes`` for each element of the
    whole input (what the tiled run holds of it: ``ElementKind.tiled_bytes``, and the
    input's own arrays where it is read whole); None where none does (that alone does not
    fit, or tiles of 50 elements would not).

    Examples
    --------
    >>> tiles_that_fit(10_000_000, 250, 2 * 2**30, input_bytes=100)
    3
    >>> tiles_that_fit(10_000_000, 250, 2**30, input_bytes=200) is None
    True
    """
    left = avail - int(n_elements) * int(input_bytes)
    if left <= 0:
        return None
    t = -(-int(n_elements * bytes_per_element * _HALO_SHARE) // left)
    t = max(t, 2)
    return t if t <= most and n_elements // t >= 50 else None


def check_memory(n_elements: int, bytes_per_element: int, what: str, *,
                 tiles_help: bool = False, input_bytes: int = 0, held_input: int = 0) -> None:
    """Refuse a run whose estimated peak (:func:`estimated_peak`) exceeds what this
    process may still allocate (:func:`available_bytes`).

    ``SUPERFACETS_MEMORY_CHECK=off`` in the environment runs it anyway (where the
    estimate reads high for an input, or the machine's swap is meant to be used).

    Parameters
    ----------
    n_elements : int
    bytes_per_element : int
        The run's peak per element beyond :data:`BASE_BYTES` (``ElementKind.peak_bytes``).
    what : str
        The input and its elements, for the message (``"m.ply: 5,000,000 faces"``).
    tiles_help : bool, default False
        Whether a tiled run could take this input (faces or points): the message then
        names the tile count that would fit (:func:`tiles_that_fit`), where one does.
        A peak that one edge's faces make, or an input that alone does not fit, is
        never sent to tiles.
    input_bytes : int, default 0
        Bytes a tiled run holds for each element of the whole input (:func:`tiles_that_fit`).
    held_input : int, default 0
        Bytes of the input's own arrays, where it is read already (counted in
        ``bytes_per_element``: not twice).

    Raises
    ------
    MemoryLimitError
        Naming the estimate, what is available, and what would fit.

    Examples
    --------
    >>> check_memory(1000, 250, "a small mesh")   # fits anywhere
    """
    if os.environ.get("SUPERFACETS_MEMORY_CHECK", "").strip().lower() in ("off", "0", "no"):
        return
    avail = available_bytes()
    if int(n_elements) * int(bytes_per_element) > 256 * 2**20:  # what the read freed: given
        give_back_free_memory()  # back, so that it is not taken for held
    need = estimated_peak(n_elements, bytes_per_element, held=resident_bytes(),
                          input_bytes=held_input)
    if avail is None or need <= avail:
        return
    tiles = tiles_that_fit(n_elements, bytes_per_element, avail,
                           input_bytes=input_bytes) if tiles_help else None
    advice = (f"segment it in {tiles} tiles (--tiles {tiles}, superfacets.segment_tiled) or "
              "on a larger machine" if tiles else "segment it on a larger machine")
    raise MemoryLimitError(
        f"{what} need about {_amount(need)} at the run's peak, and this process "
        f"may use {_amount(avail)}: {advice} (SUPERFACETS_MEMORY_CHECK=off runs it "
        "anyway)", need, avail)


def _amount(n: float) -> str:
    """Bytes in the unit that shows them with three figures: ``1.23 GiB``, ``96.0 MiB``,
    ``412 KiB`` (a refusal that read "0.1 GiB" for both its figures hid its reason).

    Examples
    --------
    >>> _amount(1.5 * 2**30), _amount(96 * 2**20), _amount(412 * 2**10)
    ('1.50 GiB', '96.0 MiB', '412 KiB')
    """
    for unit, size in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= size:
            return f"{_three(n / size)} {unit}"
    return f"{int(n)} bytes"


def _three(v: float) -> str:
    """``v`` with three significant figures, trailing zeros kept (1.50, 96.0, 412)."""
    return f"{v:.2f}" if v < 10 else f"{v:.1f}" if v < 100 else f"{v:.0f}"


def give_back_free_memory() -> None:
    """Hand the memory the allocator holds free back to the operating system
    (glibc's ``malloc_trim``; nothing elsewhere).

    Arrays below the allocator's mmap threshold (which grows to 32 MiB once such
    blocks are freed) come from its heap, and a freed one in the middle of that heap
    stays in the process's resident memory until the allocator trims it. A run calls
    this between its stages on large inputs: the passes then start without the
    graph build's freed temporaries.
    The arrays themselves are untouched.

    Examples
    --------
    >>> give_back_free_memory()
    """
    trim = _libc("malloc_trim", ("c_size_t",))
    if trim:
        trim(0)


#: Allocator arenas a command-line run keeps (:func:`limit_arenas`)
ARENAS = 2


def limit_arenas(n: int = ARENAS) -> None:
    """Have the allocator keep at most ``n`` arenas (glibc's ``mallopt(M_ARENA_MAX)``;
    nothing elsewhere), as the environment variable ``MALLOC_ARENA_MAX`` would.

    glibc gives each thread that allocates an arena of its own, up to 8 per core, and
    each keeps the memory its thread freed: a run's kernels, on each of its threads,
    free buffers of tens of MiB (their searches' queues and scratch tables), so a run on
    many threads held more than one on two, for the same time (the kernels allocate once
    per call; ``docs/notes/code-measurements.md``). The
    command line calls it before any thread starts; a program that imports the package
    may set ``MALLOC_ARENA_MAX=2`` itself.

    Examples
    --------
    >>> limit_arenas()
    """
    mallopt = _libc("mallopt", ("c_int", "c_int"))
    if mallopt:
        mallopt(-8, int(n))  # (M_ARENA_MAX in glibc's malloc.h)


#: The BLAS libraries' thread counts, by environment variable (read when they load).
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def limit_blas_threads() -> bool:
    """Under an address-space limit (``ulimit -v``: ``RLIMIT_AS``), have the BLAS that numpy
    and scipy load start one thread (the variables of :data:`BLAS_THREADS` the user left
    unset): OpenBLAS maps a buffer of tens of MiB per thread as it starts them, and where
    the limit refuses one it retries for ever, deaf to SIGTERM. The package's own threads
    are its kernels'; its BLAS calls are small. Call it before numpy is imported (the
    command line does, first).

    Returns
    -------
    bool
        Whether a limit was found (and the variables set where unset).

    Examples
    --------
    >>> limit_blas_threads() in (True, False)
    True
    """
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    except (ImportError, ValueError, OSError):  # pragma: no cover - not POSIX
        return False
    if soft == resource.RLIM_INFINITY:
        return False
    for name in BLAS_THREADS:
        os.environ.setdefault(name, "1")
    return True


def discard_pages(a) -> None:
    """Hand back to the operating system the whole pages of ``a`` (C-contiguous), whose
    contents are no longer needed: they read as zeros after, and cost memory only once
    written again (``madvise(MADV_DONTNEED)`` on Linux; nothing elsewhere). The passes'
    record arena past its last record: the threads' records land there before they
    are moved down, and the pages they left would stay resident.

    Examples
    --------
    >>> a = np.ones(1 << 20)
    >>> discard_pages(a[1 << 19:])   # (whole pages only: the first and last may stay)
    >>> float(a[:1 << 19].min()), float(a[3 << 18])   # past the cut: zeros
    (1.0, 0.0)
    """
    _advise(a, _DONTNEED)


def _advise(a, advice: int) -> None:
    """``madvise(advice)`` on the whole pages of the C-contiguous array ``a``."""
    madvise = _libc("madvise", ("c_void_p", "c_size_t", "c_int"))
    if not madvise or not a.flags.c_contiguous:
        return
    page = os.sysconf("SC_PAGE_SIZE")
    start = a.ctypes.data
    lo = -(-start // page) * page
    hi = (start + a.nbytes) // page * page
    if hi > lo:
        madvise(lo, hi - lo, advice)
