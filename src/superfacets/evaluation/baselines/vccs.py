"""VCCS supervoxels (PCL's ``SupervoxelClustering``) through an external module.

Papon et al.'s Voxel Cloud Connectivity Segmentation voxelizes the cloud
(``voxel_resolution``), places seeds on a grid of pitch ``seed_resolution``,
and grows supervoxels over adjacent voxels by a distance mixing the voxel's
position (``spatial_importance``) and normal (``normal_importance``). It is
the supervoxel method of PCL, which is C++ with many dependencies and is not
on the package index. This baseline calls ``vccs_supervoxel``, the pybind11
build of a standalone header-only port (``segment_vccs``; sources:
https://github.com/cloneorcopy/py_vccs, which states no licence, so it is
never a dependency of this package and never installed by it). Build it with
a C++ compiler and ``pybind11`` and put the module on ``PYTHONPATH``
(docs/notes/superpoints.md says how). That port uses positions and normals only
(no colour) and estimates the normals itself.

Points that the port leaves unlabelled (voxels below its minimum) take the
label of their nearest labelled point, so every point has one. Given
``n_segments``, ``seed_resolution`` is found by bisection in log scale (the
count falls as it grows).

References
----------
J. Papon, A. Abramov, M. Schoeler, F. Woergoetter, "Voxel Cloud Connectivity
Segmentation - Supervoxels for Point Clouds", CVPR 2013.
"""

from __future__ import annotations

import importlib

import numpy as np

from ...elements.builders import elements_of
from ...elements.labels import relabel_dense
from ...errors import MissingExtraError
from ...method.params import DEFAULTS, check_int, check_nonneg, check_positive
from ._count import search_count

__all__ = ["vccs"]

#: Where the external module comes from, for the error message.
SOURCE = "https://github.com/cloneorcopy/py_vccs"


def _module():
    try:
        return importlib.import_module("vccs_supervoxel")
    except ImportError as exc:
        raise MissingExtraError(
            f"the VCCS baseline needs the external module vccs_supervoxel ({exc}); it is not "
            f"on the package index: build it from {SOURCE} (C++ compiler and pybind11; "
            "docs/notes/superpoints.md, 'VCCS') and put it on PYTHONPATH") from None


def vccs(obj, n_segments: int | None = None, *, seed_resolution: float = 0.1,
         voxel_resolution: float | None = None, spatial_importance: float = 1.0,
         normal_importance: float = 1.0, n_neighbors: int = DEFAULTS.n_neighbors) -> np.ndarray:
    """VCCS supervoxels of a point cloud (module notes).

    Parameters
    ----------
    obj : point cloud
        As :func:`superfacets.segment` accepts (invalid points get -1).
    n_segments : int, optional
        Search ``seed_resolution`` (bisection in log scale, 20 runs at most)
        for the count nearest this one.
    seed_resolution : float, default 0.1
        Seed pitch, as a fraction of the bounding-box diagonal; ignored with
        ``n_segments``.
    voxel_resolution : float, optional
        Voxel size, as a fraction of the diagonal (default: the median
        distance between neighbours of the point graph, so voxels are about
        one point wide and stay adjacent).
    spatial_importance, normal_importance : float, default 1
        The weights of VCCS's distance (``>= 0``).
    n_neighbors : int, default 10
        The point graph's neighbourhood (for the default voxel size).

    Returns
    -------
    labels : (N,) int64 ndarray
        Dense, one per input row; -1 for invalid points.

    Raises
    ------
    MissingExtraError
        If ``vccs_supervoxel`` cannot be imported.
    ParameterError
        On a parameter out of range.

    Examples
    --------
    >>> xyz = np.random.default_rng(0).normal(size=(3000, 3))
    >>> labels = vccs(xyz, 20)           # doctest: +SKIP
    """
    from scipy.spatial import cKDTree

    mod = _module()
    spatial_importance = check_nonneg("spatial_importance", spatial_importance)
    normal_importance = check_nonneg("normal_importance", normal_importance)
    source = elements_of(obj, "points", n_neighbors=n_neighbors)
    g = source.graph
    pts = np.asarray(g.positions, dtype=np.float64)
    diagonal = g.diagonal if g.diagonal > 0 else 1.0
    if voxel_resolution is None:
        voxel = float(np.median(g.span)) if g.n_edges else diagonal * 1e-3
    else:
        voxel = check_positive("voxel_resolution", voxel_resolution) * diagonal
    data = np.zeros((pts.shape[0], 9))
    data[:, :3] = pts

    def run(seed: float) -> np.ndarray:
        out = np.asarray(mod.segment_vccs(data, seed, voxel, spatial_importance,
                                          normal_importance))
        lab = out[:, 9].astype(np.int64)
        missing = lab < 0
        if missing.all():
            return np.zeros(pts.shape[0], dtype=np.int64)
        if missing.any():  # the nearest labelled point's label
            _, near = cKDTree(pts[~missing]).query(pts[missing])
            lab[missing] = lab[~missing][near]
        return relabel_dense(lab)

    if n_segments is None:
        labels = run(check_positive("seed_resolution", seed_resolution) * diagonal)
    else:
        n_segments = check_int("n_segments", n_segments, lo=1, hi=g.n_elements)

        # seeds from one voxel apart to the whole box apart
        labels = search_count(run, n_segments, np.log10(voxel), np.log10(diagonal), 20,
                              "VCCS")
    return source.to_rows(labels)
