"""Content-adaptive superpoints: many superpoints, then the level of ``k`` that merges
the flattest neighbours first.

The method's superpoints have equal areas (the paper's); a room or an aerial
tile wants its count spent where the surface holds something, its floors,
walls and ground left in large pieces. :func:`adaptive_superpoints`
segments ``start`` times the superpoints wanted with :func:`superfacets.segment`
and keeps the level of ``n_segments`` of their hierarchy with the planarity
cost (:func:`superfacets.graph.hierarchy.hierarchy`, ``cost='planarity'``; on a
point cloud each point weighs one, and on a scan of uneven density the
segments' extent also costs, ``compactness``). Measured
on labelled scans in ``docs/notes/superpoints.md``, "Content-adaptive levels".
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..checks import check_int, check_nonneg
from ..elements.builders import elements_of
from ..errors import ParameterError
from ..method import pipeline
from ..method.params import resolve
from .result import SegmentationResult

__all__ = ["adaptive_superpoints", "adaptive_segment", "START"]

#: Superpoints segmented per superpoint wanted (docs/notes/superpoints.md: from 3 to 20 times,
#: the more the lower the undersegmentation error; 10 times the superpoints take about
#: as long to merge as to segment).
START = 10


def adaptive_superpoints(obj, n_segments: int, *, start: int = START,
                         extent_weight: float | None = None, **options) -> np.ndarray:
    """Superpoints (or superfacets) sized by what the surface holds: flat regions merged.

    Parameters
    ----------
    obj : point cloud or mesh
        What :func:`superfacets.segment` takes.
    n_segments : int
        Number of superpoints ``k`` (``>= 1``; at least the input's number of
        separate pieces).
    start : int, default 10
        Segment ``start * n_segments`` first (``>= 1``; capped at the input's
        elements); 1 returns the method's own superpoints.
    extent_weight : float, optional
        Weight of the segments' extent in the merge cost (``>= 0``;
        :func:`superfacets.graph.hierarchy.hierarchy`). Default: 0.01 on a scan of
        uneven density (a LiDAR sweep), else 0
        (:func:`~superfacets.graph.hierarchy.level_extent_weight`).
    **options
        The other keyword arguments of :func:`superfacets.segment` (``beta``
        also weighs the colour difference of a merge).

    Returns
    -------
    labels : (N,) int64 ndarray
        One label per input row, dense ``0..k-1``, -1 for invalid points; each
        superpoint connected.

    Raises
    ------
    ParameterError
        If ``n_segments`` or ``start`` is out of range (fewer than the input's
        separate pieces, or more than its elements).

    References
    ----------
    Landrieu and Simonovsky, "Large-scale point cloud semantic segmentation with
    superpoint graphs", CVPR 2018 (superpoints that follow the geometry);
    ``docs/notes/superpoints.md``.

    Examples
    --------
    >>> mesh = trimesh.creation.box().subdivide().subdivide()
    >>> labels = adaptive_superpoints(mesh, 6, start=4)
    >>> int(labels.max()) + 1
    6
    """
    return np.asarray(adaptive_segment(obj, n_segments, start=start, extent_weight=extent_weight,
                                       **options).labels)


def _one_run(obj, n_segments, *, features=None, **options):
    """One plain run (``superfacets.segment`` without a level: the public door calls this
    module for ``adaptive=``, so this module runs the pipeline itself)."""

    run = pipeline.pipeline(obj, resolve(n_segments=n_segments, **options), features=features)
    return SegmentationResult(**run.result_fields())


def adaptive_segment(obj, n_segments: int, *, start: int = START,
                     extent_weight: float | None = None, **options):
    """:func:`adaptive_superpoints` with details: a
    :class:`~superfacets.api.result.SegmentationResult` of the level.

    Its ``centers`` are, for each segment, the center of its lowest-numbered
    superpoint of the first run; ``n_iter``, ``converged``, ``timings`` and
    ``params`` are the first run's (``params['n_segments']`` the level's,
    ``params['start']`` the factor); its :meth:`graph` and :meth:`hierarchy`
    are of the level's segments.

    Parameters
    ----------
    obj, n_segments, start, extent_weight, **options
        As :func:`adaptive_superpoints`.

    Returns
    -------
    SegmentationResult

    Raises
    ------
    ParameterError
        As :func:`adaptive_superpoints`.

    Examples
    --------
    >>> mesh = trimesh.creation.box().subdivide().subdivide()
    >>> r = adaptive_segment(mesh, 6, start=4)
    >>> r.n_segments, r.params["start"]
    (6, 4)
    """

    k = check_int("n_segments", n_segments, lo=1)
    start = check_int("start", start, lo=1)
    if extent_weight is not None:
        check_nonneg("extent_weight", extent_weight)
    if options.get("merge_from") is None:  # its own many superpoints, merged its own way
        options["merge_from"] = 1
    if start == 1:
        return _one_run(obj, k, **options)
    try:
        result = _one_run(obj, k * start, **options)
    except ParameterError as exc:  # more than the elements: start from every element
        if "is larger than the number of" not in str(exc):
            raise
        result = _one_run(obj, max(k, _elements(obj, options)), **options)
    beta = float(result.params.get("beta") or 0.0)
    level = result.hierarchy([k], cost="planarity", beta=beta, extent_weight=extent_weight)
    top = level.of_superfacets(0)  # the level's segment of each superpoint
    first = np.full(k, -1, dtype=np.int64)
    first[top[::-1]] = np.arange(top.size - 1, -1, -1)  # its lowest-numbered superpoint
    return replace(result, labels=level.labels(0, result.labels),
                   centers=np.asarray(result.centers)[first],
                   element_labels=level.labels(0, result.element_labels),
                   params={**result.params, "n_segments": k, "start": start})


def _elements(obj, options: dict) -> int:
    """The number of elements of the input (the most superpoints it can have)."""

    return int(elements_of(obj, options.get("elements")).graph.n_elements)
