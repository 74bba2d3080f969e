"""Exception types raised by superfacets.

Every error caused by bad input is a :class:`SuperfacetsError`, which is also a
:class:`ValueError`, so callers can catch either. The command line turns these
(and :class:`OSError`) into one clear line and a non-zero exit status.
"""

__all__ = ["SuperfacetsError", "MeshFormatError", "InvalidMeshError", "InvalidCloudError",
           "ParameterError",
           "SchedulerError", "MemoryLimitError", "MissingExtraError", "KernelsMissingError",
           "NoDisplayError"]


class SuperfacetsError(ValueError):
    """Base class of every input error raised by this package."""


class MeshFormatError(SuperfacetsError):
    """A mesh or label file is malformed, truncated or of an unknown format."""


class InvalidMeshError(SuperfacetsError):
    """Mesh arrays are unusable: wrong shape, NaN/inf, indices out of range, empty."""


class InvalidCloudError(InvalidMeshError):
    """Point arrays are unusable: wrong shape, NaN/inf rows, empty, collinear."""


class ParameterError(SuperfacetsError):
    """A parameter of a method is out of its valid range."""


class MemoryLimitError(SuperfacetsError, MemoryError):
    """A method would need more memory than its limit allows (raised before allocating).

    Attributes
    ----------
    required : int
        Estimated bytes needed.
    limit : int
        The limit in bytes.
    """

    def __init__(self, message: str, required: int = 0, limit: int = 0):
        super().__init__(message)
        self.required = int(required)
        self.limit = int(limit)


class MissingExtraError(SuperfacetsError, ImportError):
    """A feature needs an optional dependency (an *extra*) that is not installed.

    The message names the ``pip install 'superfacets[EXTRA]'`` command to run.
    """


class KernelsMissingError(SuperfacetsError, ImportError):
    """The compiled kernels are not built: the package's source folder was imported
    without installing it (``pip install .`` builds them)."""


class SchedulerError(SuperfacetsError):
    """A Dask scheduler cannot be reached, or has no worker to run the tasks, or the local
    workers cannot start."""


class NoDisplayError(RuntimeError):
    """An interactive window was asked for, but there is no display."""
