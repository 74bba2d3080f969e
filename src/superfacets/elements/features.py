"""Per-element features of an input: the colours (or features) a run with ``beta > 0``
weighs, one row per element from one row per input row."""

from __future__ import annotations

import numpy as np

from ..checks import check_unmasked
from ..errors import ParameterError

__all__ = ["features_of", "per_element", "colors_or_features"]


def colors_or_features(src, features):
    """What a run with ``beta=None`` may weigh: ``features`` (one row per input row), else
    the input's colours (a cloud's, a mesh's vertex or face colours), else None.

    Parameters
    ----------
    src : ElementInput
    features : (N, d) float ndarray or None

    Returns
    -------
    (N, d) float ndarray or None
        One row per input row (:func:`per_element` makes them one per element).

    Raises
    ------
    ParameterError
        Never (a tetrahedral mesh's materials are read only with ``beta > 0``).

    Examples
    --------
    >>> from superfacets.elements.builders import elements_of
    >>> colors_or_features(elements_of(trimesh.creation.box()), None) is None
    True
    """
    return features if features is not None else src.colors()


def features_of(src, features):
    """The per-element features of a run with ``beta > 0``: ``features`` (one row per
    input row), else the input's colours (or a tetrahedral mesh's materials, one-hot).

    Parameters
    ----------
    src : ElementInput
    features : (N, d) float ndarray or None

    Returns
    -------
    (n, d) float64 ndarray
        One row per element.

    Raises
    ------
    ParameterError
        Without features and without colours, or with one row per input row missing.

    Examples
    --------
    >>> from superfacets.elements.builders import elements_of
    >>> src = elements_of(trimesh.creation.box())
    >>> features_of(src, np.arange(12.0)).shape
    (12, 1)
    """
    if features is None:
        features = src.colors()
        materials = getattr(src.source, "materials", None)
        if features is None and materials is not None:  # a volume's regions, one-hot
            features = (materials[:, None] == np.unique(materials)[None, :]).astype(float)
        if features is None:
            raise ParameterError("beta > 0 needs features: pass features=(one row per "
                                 f"{src.graph.element}), or an input with colours (PLY, PCD "
                                 "or LAS points with RGB, a mesh with vertex or face colours) "
                                 "or materials (a tetrahedral mesh)")
    return per_element(src, features)


def per_element(src, features):
    """Per-row features of an input -> per-element features (the first row of each).

    Parameters
    ----------
    src : ElementInput
    features : (N, d) or (N,) float ndarray or None
        One row per input row.

    Returns
    -------
    (n, d) float64 ndarray or None

    Raises
    ------
    ParameterError
        If ``features`` does not have one row per input row.

    Examples
    --------
    >>> from superfacets.elements.builders import elements_of
    >>> src = elements_of(np.random.default_rng(0).random((30, 3)))
    >>> per_element(src, np.ones(30)).shape
    (30, 1)
    """
    if features is None:
        return None

    raw = check_unmasked(features, "features")
    if raw.dtype == object or not (np.issubdtype(raw.dtype, np.number) or raw.dtype == bool) \
            or np.issubdtype(raw.dtype, np.complexfloating):  # (complex: a cast drops a part)
        raise ParameterError(f"features must be real numbers, got dtype {raw.dtype}")
    f = raw.astype(np.float64)
    f = f.reshape(-1, 1) if f.ndim == 1 else f
    if f.ndim != 2 or f.shape[0] != src.n_rows:
        raise ParameterError(f"features must have one row per input row ({src.n_rows}), "
                             f"got shape {np.shape(features)}")
    rows = src.first_rows(np.arange(src.graph.n_elements))
    return f[rows]
