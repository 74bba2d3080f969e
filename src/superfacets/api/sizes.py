"""Sizes in the data's units: a superpoint size instead of a count, distances instead of
fractions of the diagonal, and a default count that grows with the input.

A scan's users think in metres (PCL's VCCS asks for a voxel and a seed resolution, lidR
and PDAL for distances): :func:`count_for_resolution` turns a seed resolution ``R`` into
the count ``k = A / R^2`` that gives superpoints of about ``R`` by ``R`` on a surface of
area ``A`` (the paper's surface area of a mesh, the points' estimated areas of a cloud,
section 3.1: ``A = k pi r^2``); :func:`diagonal_fraction` turns a distance into the
fraction of the bounding-box diagonal the method's options take.
"""

from __future__ import annotations

import numpy as np

from ..elements.builders import elements_of, is_cloud
from ..elements.kinds import kind_of
from ..errors import ParameterError
from ..inputs.cloud import PointCloud, as_cloud
from ..inputs.convert import as_mesh
from ..inputs.mesh import Mesh
from ..inputs.tetmesh import TetMesh

__all__ = ["count_for_resolution", "resolution_count", "default_count", "default_count_of",
           "diagonal_fraction", "POINTS_PER_SEGMENT", "MIN_ELEMENTS_PER_SEGMENT"]

#: A cloud given no count gets one superpoint per this many valid points, and never
#: fewer than the method's default count where it has enough points.
POINTS_PER_SEGMENT = 1000

#: A default or derived count leaves at least this many elements per segment (the
#: method's first superpoints hold at least as many: ``method.rules``).
MIN_ELEMENTS_PER_SEGMENT = 12


def _rows(data, elements: str) -> int:
    """The elements of a kind: a cloud's valid points, a mesh's faces or vertices."""
    return int(data.n_points if kind_of(elements).cloud else kind_of(elements).n_rows(data))


def _data(obj):
    """``obj`` as a Mesh, PointCloud or TetMesh (a trimesh, an array, ... as
    :func:`superfacets.segment` takes them)."""
    if isinstance(obj, (Mesh, PointCloud, TetMesh)):
        return obj
    return as_cloud(obj) if is_cloud(obj) else as_mesh(obj)


def _kind(data, elements: str | None) -> str:
    if elements is not None:
        return elements
    if hasattr(data, "tets"):
        return "cells"
    return "faces" if hasattr(data, "faces") else "points"


def default_count(data, elements: str | None = None, default: int = 150) -> int:
    """The number of segments a run takes when none is given.

    A mesh takes the paper's ``default`` (150); a point cloud one superpoint per
    :data:`POINTS_PER_SEGMENT` valid points, at least ``default``; either at most one
    segment per :data:`MIN_ELEMENTS_PER_SEGMENT` elements (a small input) and at least 1.

    Parameters
    ----------
    data : Mesh, PointCloud or TetMesh, or what :func:`superfacets.segment` takes
    elements : {'faces', 'vertices', 'points', 'cells'}, optional
        What is segmented (default: the input's own kind).
    default : int, default 150

    Returns
    -------
    int

    Raises
    ------
    KeyError
        If ``elements`` is no kind of element.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> default_count(PointCloud(rng.random((3_000_000, 3))))
    3000
    >>> default_count(PointCloud(rng.random((70, 3))))
    5
    """
    data = _data(data)
    kind = _kind(data, elements)
    return default_count_of(_rows(data, kind), kind_of(kind).cloud, default)


def default_count_of(n_elements: int, cloud: bool, default: int = 150) -> int:
    """:func:`default_count` of an input of ``n_elements`` (a cloud's valid points where
    ``cloud``), read without the input (a tiled run's count from a file's header).

    Parameters
    ----------
    n_elements : int
    cloud : bool
        Whether they are a point cloud's points.
    default : int, default 150

    Returns
    -------
    int

    Raises
    ------
    TypeError, ValueError
        If ``n_elements`` is not an integer.

    Examples
    --------
    >>> default_count_of(3_000_000, True), default_count_of(3_000_000, False)
    (3000, 150)
    """
    n = int(n_elements)
    k = max(default, n // POINTS_PER_SEGMENT) if cloud else default
    return int(max(1, min(k, n // MIN_ELEMENTS_PER_SEGMENT)))


def count_for_resolution(data, resolution: float, elements: str | None = None,
                         **element_options) -> tuple[int, float]:
    """The count of superpoints (superfacets) of about ``resolution`` by ``resolution``,
    in the data's units: ``k = A / resolution^2`` for a surface of area ``A``.

    As VCCS's seed resolution: a plane of 10 m by 10 m at 0.5 gives about 400.

    Parameters
    ----------
    data : Mesh or PointCloud, or what :func:`superfacets.segment` takes
    resolution : float
        A length in the data's units (metres for most scans), ``> 0``.
    elements : {'faces', 'vertices', 'points'}, optional
        What is segmented (default: the input's own kind).
    **element_options
        ``n_neighbors``, ``neighbor_radius`` of a cloud's point graph (whose point
        areas add up to its surface area; the graph is kept for the run).

    Returns
    -------
    k : int
        At least 1, at most one per :data:`MIN_ELEMENTS_PER_SEGMENT` elements.
    area : float
        The surface area it was computed from, in the data's units squared.

    Raises
    ------
    ParameterError
        If ``resolution`` is not a finite number > 0, or the input is a tetrahedral
        mesh (a volume: give a count).

    Examples
    --------
    >>> xy = np.random.default_rng(0).random((10000, 2)) * 10  # 10 m by 10 m
    >>> k, area = count_for_resolution(PointCloud(np.c_[xy, np.zeros(len(xy))]), 0.5)
    >>> 300 < k < 500, 90 < area < 110
    (True, True)
    """

    r = _checked_resolution(resolution)
    data = _data(data)
    kind = _kind(data, elements)
    if kind_of(kind).dim != 2:
        raise ParameterError("a seed resolution is a size on a surface; a tetrahedral mesh "
                             "takes a count (-k)")
    if kind_of(kind).cloud:
        area = float(elements_of(data, "points", **element_options).graph.sizes.sum())
    else:
        area = float(data.area)
    return resolution_count(area, r, _rows(data, kind)), area


def _checked_resolution(resolution) -> float:
    try:
        r = float(resolution)
    except (TypeError, ValueError):
        raise ParameterError(f"the seed resolution must be a number, got {resolution!r}") \
            from None
    if not (np.isfinite(r) and r > 0):
        raise ParameterError(f"the seed resolution must be a finite length > 0, got {r}")
    return r


def resolution_count(area: float, resolution: float, n_elements: int) -> int:
    """The count of superpoints of ``resolution`` by ``resolution`` on a surface of
    ``area``: :func:`count_for_resolution` once the area is measured (a tiled run sums it
    over its tiles).

    Parameters
    ----------
    area : float
        The surface's area, in the data's units squared.
    resolution : float
        A length in the data's units, ``> 0``.
    n_elements : int
        The elements segmented (a cloud's valid points, a mesh's faces or vertices).

    Returns
    -------
    int
        ``round(area / resolution^2)``, at least 1 and at most one per
        :data:`MIN_ELEMENTS_PER_SEGMENT` elements.

    Raises
    ------
    ParameterError
        If ``resolution`` is not a finite number > 0.

    Examples
    --------
    >>> resolution_count(100.0, 0.5, 10000), resolution_count(100.0, 0.01, 10000)
    (400, 833)
    """
    r = _checked_resolution(resolution)
    most = max(1, int(n_elements) // MIN_ELEMENTS_PER_SEGMENT)
    with np.errstate(over="ignore", under="ignore", divide="ignore"):
        share = np.float64(area) / np.float64(r) / np.float64(r)  # (r * r can underflow to 0)
    k = most if not share < most else round(float(share))  # (inf and nan: the most)
    return int(max(1, k))


def diagonal_fraction(data, distance: float, what: str = "distance") -> float:
    """A distance in the data's units as the fraction of the bounding-box diagonal that
    the method's options (``radius``, ``neighbor_radius``) take.

    Parameters
    ----------
    data : Mesh or PointCloud, or what :func:`superfacets.segment` takes
    distance : float
        ``> 0``, in the data's units.
    what : str
        The option's name, for the message.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        If ``distance`` is not finite and ``> 0``, or the input has no extent.

    Examples
    --------
    >>> cloud = PointCloud(np.array([[0.0, 0, 0], [3, 4, 0], [1, 1, 0]]))
    >>> diagonal_fraction(cloud, 0.5)
    0.1
    """
    try:
        d = float(distance)
    except (TypeError, ValueError):
        d = float("nan")
    if not (np.isfinite(d) and d > 0):
        raise ParameterError(f"{what} must be a finite length > 0, got {distance!r}")
    data = _data(data)
    pts = np.asarray(data.points if hasattr(data, "points") else data.vertices,
                     dtype=np.float64)
    pts = pts[np.isfinite(pts).all(axis=1)]
    diag = float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0))) if len(pts) else 0.0
    if not diag > 0:
        raise ParameterError(f"{what}: the input has no extent to measure it against")
    return d / diag
