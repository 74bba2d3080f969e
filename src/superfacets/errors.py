"""Exception types raised by superfacets.

Every error caused by bad input is a :class:`SuperfacetsError`, which is also a
:class:`ValueError`, so callers can catch either. The command line turns these
(and :class:`OSError`) into one clear line and a non-zero exit status.
"""

__all__ = ["SuperfacetsError", "MeshFormatError", "InvalidMeshError", "ParameterError"]


class SuperfacetsError(ValueError):
    """Base class of every input error raised by this package."""


class MeshFormatError(SuperfacetsError):
    """A mesh or label file is malformed, truncated or of an unknown format."""


class InvalidMeshError(SuperfacetsError):
    """Mesh arrays are unusable: wrong shape, NaN/inf, indices out of range, empty."""


class ParameterError(SuperfacetsError):
    """A parameter of a method is out of its valid range."""
