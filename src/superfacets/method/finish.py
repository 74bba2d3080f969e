"""The stages after the passes: the labels made dense and connected, the boundaries
cleaned up, small segments merged, the count made exact (kinds that ask for it).

:func:`superfacets.method.pipeline.pipeline` runs them after the stages of
:mod:`superfacets.method.stages`; tiled runs call :func:`finish` and :func:`clean_up`.
"""

from __future__ import annotations

import numpy as np

from ..elements.labels import relabel_dense
from ..graph import hierarchy
from ..graph.adjacency import superfacet_graph
from ..graph.hierarchy import pieces
from ..method.params import DEFAULTS
from .cleanup import clean_boundaries
from .connectivity import enforce_connectivity as _enforce_connectivity
from .stages import Rules, check_stage

__all__ = ["finish", "clean_up", "merge_small", "exact_count"]

_D = DEFAULTS


def finish(graph, label: np.ndarray, centers: np.ndarray, rules: Rules
           ) -> tuple[np.ndarray, np.ndarray]:
    """Stage 6: the labels of the last classification made dense (superfacets left
    empty dropped) and, unless the clean-up follows (it ends with it), each
    superfacet made connected (stray pieces merged into the neighbour sharing the
    longest border).

    Returns
    -------
    labels : (n,) int64 ndarray
    centers : (K,) int64 ndarray
        The centers of the superfacets kept.

    Parameters
    ----------
    graph : ElementGraph
    label : (n,) int ndarray
        The last classification's labels.
    centers : (c,) int64 ndarray
        Its centers.
    rules : Rules

    Raises
    ------
    TypeError
        If an argument is not what the earlier stage gives (a word, an array).
    ParameterError
        If the labels do not fit the graph.

    Examples
    --------
    >>> s = passes_example()  # an icosphere's run up to its passes
    >>> labels, kept = finish(s.graph, s.it.label, s.it.centers, s.rules)
    >>> int(labels.max()) + 1 == kept.shape[0]
    True
    """
    check_stage("finish", graph=graph, rules=rules)
    present = np.zeros(centers.shape[0], dtype=bool)
    present[label] = True
    labels = relabel_dense(label)
    kept = centers[present]
    if rules.params.enforce_connectivity and not rules.cleanup:
        labels = _enforce_connectivity(graph, labels, kept)
    return labels, kept


def clean_up(graph, labels: np.ndarray, centers: np.ndarray, rules: Rules,
             features=None, bands_found=None) -> np.ndarray:
    """Stage 7: the boundaries re-placed by minimum cuts within a band
    (:func:`superfacets.method.cleanup.clean_boundaries`; not in the paper), with the run's
    ``eta_convex``, ``alpha`` (the paper's default under another weighting) and
    feature term. The number of superfacets does not change.

    Returns
    -------
    (n,) int64 ndarray

    Parameters
    ----------
    graph : ElementGraph
    labels : (n,) int64 ndarray
    centers : (K,) int64 ndarray
    rules : Rules
    features : (n, d) float ndarray, optional
    bands_found : callable, optional
        As :func:`~superfacets.method.cleanup.clean_boundaries`.

    Raises
    ------
    TypeError
        If an argument is not what the earlier stage gives (a word, an array).
    ParameterError
        If the labels do not fit the graph.

    Examples
    --------
    >>> s = passes_example()  # an icosphere's run up to its passes
    >>> cleaned = clean_up(s.graph, s.labels, s.kept, s.rules)  # (finished labels)
    >>> int(cleaned.max()) + 1 == int(s.labels.max()) + 1
    True
    """
    check_stage("clean_up", graph=graph, rules=rules)
    p = rules.params
    return clean_boundaries(graph, labels, centers, radius=rules.r, eta_convex=p.eta_convex,
                            alpha=p.alpha if p.weighting == "paper" else _D.alpha,
                            connectivity=p.enforce_connectivity, n_threads=p.n_threads,
                            features=features, beta=p.beta, floor=rules.feature_floor,
                            bands_found=bands_found)


def merge_small(graph, labels: np.ndarray, centers: np.ndarray, rules: Rules) -> np.ndarray:
    """Stage 8: superfacets of fewer than ``min_elements`` elements merged into the
    neighbour they share the longest border with (as stray pieces are; not in the
    paper).

    Returns
    -------
    (n,) int64 ndarray

    Parameters
    ----------
    graph : ElementGraph
    labels : (n,) int64 ndarray
    centers : (K,) int64 ndarray
    rules : Rules
        Its ``params.min_elements`` is the smallest size kept.

    Raises
    ------
    TypeError
        If an argument is not what the earlier stage gives (a word, an array).
    ParameterError
        If the labels do not fit the graph.

    Examples
    --------
    >>> s = passes_example()  # an icosphere's run up to its passes
    >>> merged = merge_small(s.graph, s.labels, s.kept, s.rules)  # (finished labels)
    >>> bool(merged.max() == s.labels.max())  # min 1 element: nothing merged
    True
    """
    check_stage("merge_small", graph=graph, rules=rules)
    return _enforce_connectivity(graph, labels, centers, min_elements=rules.params.min_elements)


def exact_count(graph, labels: np.ndarray, rules: Rules) -> tuple[np.ndarray, int]:
    """Stage 9 (kinds with ``exact_count``: points, cells): a run asked for ``k`` that made more
    segments (regions no window reached seed their own) merges adjacent ones, cheapest
    first (:func:`superfacets.graph.hierarchy.hierarchy`, Ward's cost with the run's
    crease factor), down to ``k``, or to the input's number of separate pieces where
    that is more: a region cannot cross from one piece to another.

    Returns
    -------
    labels : (n,) int64 ndarray
    fewest : int
        The count the run could reach: ``k``, or the pieces where there are more.

    Parameters
    ----------
    graph : ElementGraph
    labels : (n,) int64 ndarray
        Dense labels.
    rules : Rules
        Its ``target`` (else ``k``) is the count asked for.

    Raises
    ------
    TypeError
        If an argument is not what the earlier stage gives (a word, an array).
    ParameterError
        If the labels do not fit the graph.

    Examples
    --------
    >>> s = passes_example()  # an icosphere's run up to its passes
    >>> exact_count(s.graph, s.labels, s.rules)[1]  # (finished labels)
    12
    """
    check_stage("exact_count", graph=graph, rules=rules)

    k = rules.k if rules.target is None else rules.target
    n = int(labels.max()) + 1 if labels.size else 0
    if k is None or n <= k:
        return labels, n
    sg = superfacet_graph(graph, labels)
    fewest = max(k, pieces(sg))
    if n <= fewest:
        return labels, fewest
    p = rules.params
    level = hierarchy.hierarchy(sg, [fewest], alpha=p.alpha, eta_convex=p.eta_convex)
    return level.labels(0, labels).astype(np.int64), fewest
