"""The method registry: superfacets and the baselines, one call shape.

A *method* labels the elements of a mesh given a number of segments.
Methods are looked up by name in one registry (:data:`METHODS`,
:func:`register_method`), so new ones plug into ``superfacets experiment``,
``baseline`` and ``panel`` without any change there. Each declares its
parameters with their defaults (their types convert values given as text)
and the values ``superfacets experiment`` sweeps by default.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial
from typing import Callable

import numpy as np

from ..api.levels import adaptive_segment
from ..api.segmentation import segment
from ..checks import check_int, check_nonneg
from ..elements.kinds import kind_of
from ..errors import MemoryLimitError, ParameterError
from ..method.params import (
    ASSIGNMENTS,
    DEFAULT_ALPHAS,
    ELEMENTS,
    INITS,
    PARAMETER,
    WEIGHTING_ALPHA,
    resolve,
)
from .baselines.cut_pursuit import cut_pursuit
from .baselines.graph_segmentation import graph_segmentation
from .baselines.ncuts import ncut_embedding, normalized_cuts
from .baselines.spt_partition import spt_partition
from .baselines.vccs import vccs
from .baselines.vsa import variational_shape_approximation
from .metrics import METRICS

__all__ = ["Method", "MethodRun", "Skipped", "METHODS", "register_method", "get_method",
           "parse_bool"]


class Skipped(Exception):
    """Raised by a method that declines a mesh (e.g. it would not fit in memory).

    The runner records the row with status ``skipped`` and the message.
    """


@dataclass
class MethodRun:
    """What a method returns for one mesh and one number of segments.

    Attributes
    ----------
    labels : (m,) int ndarray
        One label per face.
    n_iter : int, optional
        Iterations run, where the method iterates.
    converged : bool, optional
    reused_seconds : float, default 0
        Seconds of work done by an earlier call and reused from ``cache``
        (e.g. the embedding of normalized cuts). The runner adds them to the
        row's ``seconds``, so ``seconds`` is the cost of one segmentation
        from scratch, and takes the row's ``peak_mib`` as the largest of the
        calls so far on that mesh and setting.
    """

    labels: np.ndarray
    n_iter: int | None = None
    converged: bool | None = None
    reused_seconds: float = 0.0


@dataclass(frozen=True)
class Method:
    """A segmentation method in the registry.

    Attributes
    ----------
    name : str
    run : callable
        ``run(mesh, n_segments, *, cache, seed, **params) -> MethodRun``.
        ``cache`` is a dict shared by the calls for one mesh and one setting
        of ``params`` over every ``n_segments`` (for work that does not depend
        on it, e.g. a distance matrix); ``seed`` an int for methods that draw
        random numbers. May raise :class:`Skipped`.
    defaults : dict
        Every parameter (besides ``n_segments``) and its default; a value
        given to the runner is converted to the type of the default.
    sweep : dict
        Default values swept by ``superfacets experiment`` per parameter.
    description : str
    progress : bool
        True when ``run`` also takes ``progress=`` (a progress bar on stderr).
    elements : tuple of str
        The element kinds it segments (``"faces"``, ``"vertices"``,
        ``"points"``). A method with more than faces takes ``elements=`` and
        is given a mesh (faces, vertices) or a point cloud (points).
    check : callable or None
        ``check(**params)`` raises :class:`~superfacets.errors.ParameterError` on values
        ``run`` would refuse, so that a grid is refused before any work (None: ``run``
        alone checks them).
    """

    name: str
    run: Callable[..., MethodRun]
    defaults: dict
    sweep: dict = field(default_factory=dict)
    description: str = ""
    progress: bool = False
    elements: tuple = ("faces",)
    check: Callable[..., None] | None = None

    @property
    def takes_elements(self) -> bool:
        """Whether ``run`` takes ``elements=``: a method that segments more than a mesh's
        faces (the kind scene objects are made of, :mod:`superfacets.elements.kinds`)."""
        return not all(kind_of(e).objects for e in self.elements)

    def resolve(self, params: dict) -> dict:
        """``defaults`` updated with ``params``, converted to the defaults' types.

        Raises
        ------
        ParameterError
            On an unknown parameter or a value of the wrong type.
        """
        out = dict(self.defaults)
        for k, v in params.items():
            if k not in self.defaults:
                raise ParameterError(f"method {self.name!r} has no parameter {k!r} "
                                     f"(it has: {', '.join(sorted(self.defaults)) or 'none'})")
            kind = type(self.defaults[k])
            if self.defaults[k] == "auto" and k in _AUTO:  # "auto", or a value of its kind
                text = str(v).strip().lower()
                try:
                    if text != "auto":
                        _AUTO[k](v)
                except (TypeError, ValueError):
                    raise ParameterError(f"method {self.name!r}: {k} must be auto or "
                                         f"{_AUTO[k].__name__.replace('parse_', '')}, "
                                         f"got {v!r}") from None
                out[k] = text if text == "auto" else str(v).strip()
                continue
            try:
                out[k] = kind(v) if kind is not bool or isinstance(v, bool) else parse_bool(v)
            except (TypeError, ValueError):
                raise ParameterError(f"method {self.name!r}: {k} must be "
                                     f"{kind.__name__}, got {v!r}") from None
        return out


def parse_bool(v) -> bool:
    t = str(v).strip().lower()
    if t in ("1", "true", "yes"):
        return True
    if t in ("0", "false", "no"):
        return False
    raise ValueError(v)


def parse_assignment(v) -> str:
    t = str(v).strip().lower()
    if t not in ASSIGNMENTS:
        raise ValueError(v)
    return t


parse_assignment.__name__ = " or ".join(ASSIGNMENTS)  # (named so in the error message)

#: Parameters whose default is ``"auto"``, and the kind of their other values.
_AUTO = {"center_tol": float, "coarsen": int, "cleanup": parse_bool, "split_merge": parse_bool,
         "merge_from": int, "assignment": parse_assignment, "max_size_ratio": float}

#: The registry: method name -> :class:`Method`.
METHODS: dict[str, Method] = {}


def register_method(name: str, run: Callable[..., MethodRun], *, defaults: dict,
                    sweep: dict | None = None, description: str = "",
                    progress: bool = False, elements: tuple = ("faces",),
                    check: Callable[..., None] | None = None) -> Method:
    """Add (or replace) a method in :data:`METHODS`.

    Parameters
    ----------
    name : str
        Registry key; letters, digits, ``_`` and ``-``.
    run : callable
        ``run(mesh, n_segments, *, cache, seed, **params) -> MethodRun``. It
        is sent to the worker processes by reference, so it must be a
        module-level function of an importable module (not a lambda).
    defaults : dict
        Parameter names and default values (int, float, str or bool).
    sweep : dict, optional
        Default sweep per parameter, e.g. ``{"alpha": (0, 200)}``.
    description : str, optional
    progress : bool, default False
        Whether ``run`` takes ``progress=`` (shown by ``superfacets baseline``).
    elements : tuple of str, default ('faces',)
        Element kinds the method segments (see :class:`Method`).
    check : callable, optional
        ``check(**params)``: the parameters' values checked before any work (see
        :class:`Method`).

    Returns
    -------
    Method

    Raises
    ------
    ParameterError
        On a name that is not a word, or a parameter named as a runner's argument or a
        metric's column.
    """
    if not name or not all(c.isalnum() or c in "_-" for c in name):
        raise ParameterError(f"invalid method name {name!r}")

    clash = set(defaults) & ({"n_segments", "seed", "cache"} | set(METRICS))
    if clash:  # the results file has one column of each name
        word = "name" if len(clash) == 1 else "names"
        raise ParameterError(f"parameter {word} reserved by the runner (its arguments and "
                             f"the metrics' columns): {sorted(clash)}")
    m = Method(name, run, dict(defaults), dict(sweep or {}), description, progress,
               tuple(elements), check)
    METHODS[name] = m
    return m


def get_method(name: str) -> Method:
    """The registered method ``name``.

    Raises
    ------
    ParameterError
        Naming the registered methods, if there is none of that name.
    """
    try:
        return METHODS[name]
    except KeyError:
        raise ParameterError(f"unknown method {name!r}; registered: "
                             f"{', '.join(sorted(METHODS))}") from None


# --- the built-in methods ------------------------------------------------------------


def _auto(value, kind):
    """A registry value of ``center_tol``, ``coarsen``, ``cleanup``, ``split_merge``,
    ``density``, ``merge_from``, ``assignment``, ``step_weight``, ``up_weight`` or
    ``extent_weight``:
    ``"auto"`` is None."""
    return None if value in (None, "auto") else kind(value)


def _segment_options(center_tol="auto", coarsen="auto", cleanup="auto", split_merge="auto",
                     density="auto", merge_from="auto", assignment="auto", beta="auto",
                     step_weight="auto", max_size_ratio="auto", up_weight="auto",
                     **params) -> dict:
    """The keyword arguments of :func:`superfacets.segment` from registry values."""
    return dict(center_tol=_auto(center_tol, float), coarsen=_auto(coarsen, int),
                beta=_auto(beta, float),
                cleanup=_auto(cleanup, parse_bool), split_merge=_auto(split_merge, parse_bool),
                step_weight=_auto(step_weight, float), up_weight=_auto(up_weight, float),
                max_size_ratio=_auto(max_size_ratio, float),
                density=_auto(density, float), merge_from=_auto(merge_from, int),
                assignment=_auto(assignment, parse_assignment), **params)


def _check_superfacets(weighting="paper", start=1, extent_weight="auto", **params) -> None:
    """The values of a superfacets, shlafman or adaptive setting, as :func:`segment` checks
    them (and the adaptive levels' ``start`` and ``extent_weight``)."""
    check_int("start", start, lo=1)
    if extent_weight != "auto":
        check_nonneg("extent_weight", _auto(extent_weight, float))
    resolve(weighting=weighting, **_segment_options(**params))


def _run_superfacets(mesh, n_segments, *, cache, seed, weighting="paper", **params):
    r = segment(mesh, n_segments, weighting=weighting, **_segment_options(**params))
    return MethodRun(r.labels, r.n_iter, r.converged)


def _run_adaptive(mesh, n_segments, *, cache, seed, start, extent_weight="auto",
                  **params):
    r = adaptive_segment(mesh, n_segments, start=start,
                         extent_weight=_auto(extent_weight, float),
                         **_segment_options(**params))
    return MethodRun(r.labels, r.n_iter, r.converged)


def _run_graph_segmentation(mesh, n_segments, *, cache, seed, elements="faces", k_thresh,
                            min_size):
    return MethodRun(graph_segmentation(mesh, k_thresh if k_thresh > 0 else 0.01, min_size,
                                        n_segments=n_segments if k_thresh <= 0 else None,
                                        elements=elements))


def _run_cut_pursuit(mesh, n_segments, *, cache, seed, elements="points", reg_strength):
    return MethodRun(cut_pursuit(mesh, n_segments if reg_strength <= 0 else None,
                                 reg_strength=reg_strength if reg_strength > 0 else 0.1,
                                 elements=elements))


def _run_spt_partition(mesh, n_segments, *, cache, seed, elements="points", preset, level):
    return MethodRun(spt_partition(mesh, n_segments, preset=preset,
                                   level="auto" if level <= 0 else level))


def _run_vccs(mesh, n_segments, *, cache, seed, elements="points", seed_resolution):
    return MethodRun(vccs(mesh, n_segments if seed_resolution <= 0 else None,
                          seed_resolution=seed_resolution if seed_resolution > 0 else 0.1))


def _run_shlafman(mesh, n_segments, *, cache, seed, progress=False, **params):
    return _run_superfacets(mesh, n_segments, cache=cache, seed=seed, weighting="shlafman",
                            progress=progress, **params)


def _run_ncuts(mesh, n_segments, *, cache, seed, components, memory_limit_gib, progress=False,
               **params):
    emb = cache.get("ncut_embedding")
    reused = 0.0
    if emb is None or emb.n_components < min(n_segments, mesh.n_faces):
        limit = int(memory_limit_gib * 2**30) if memory_limit_gib > 0 else None
        try:
            emb = ncut_embedding(mesh, max(components, n_segments), memory_limit=limit,
                                 rng=seed, progress=progress, **params)
        except MemoryLimitError as exc:
            raise Skipped(str(exc)) from None
        cache["ncut_embedding"] = emb
    else:
        reused = emb.total_seconds
    return MethodRun(normalized_cuts(mesh, n_segments, embedding=emb, rng=seed),
                     reused_seconds=reused)


def _run_vsa(mesh, n_segments, *, cache, seed, **params):
    r = variational_shape_approximation(mesh, n_segments, rng=seed, cache=cache, **params)
    return MethodRun(r.labels, r.n_iter, r.converged)


#: The method's parameters an experiment records and may vary (the others are the run's
#: own: the count, threads, progress, the elements), each at its declared default ("auto"
#: where the run decides; the start: farthest points, which "auto" is without a radius)
_SF_GRID = ("alpha", "eta_convex", "init", "window", "max_iter", "tol", "center_tol",
            "coarsen", "cleanup", "split_merge", "paper", "density", "roughness", "merge_from",
            "max_size_ratio", "merge_cost", "assignment", "beta", "up_weight", "step_weight")
_SF_DEFAULTS = {name: INITS[0] if name == "init" else
                "auto" if PARAMETER[name].default is None else PARAMETER[name].default
                for name in _SF_GRID}
register_method(
    "superfacets", _run_superfacets, defaults=_SF_DEFAULTS,
    sweep={"alpha": DEFAULT_ALPHAS},
    description="the paper's method: bounded Dijkstra k-means, weights of eqs. 1-3 (faces; "
                "on vertices, points and tetrahedra their analogues)",
    progress=True, elements=(*ELEMENTS, "cells"), check=_check_superfacets)
register_method(
    "adaptive", _run_adaptive,
    defaults=dict(_SF_DEFAULTS, start=10, extent_weight="auto"),
    description="content-adaptive superpoints: the method's start x n_segments superpoints, "
                "then the level of n_segments that merges the flattest neighbours first "
                "(superfacets.adaptive_superpoints; extent_weight=auto: 0.01 on scans of "
                "uneven density)",
    progress=True, elements=ELEMENTS, check=_check_superfacets)
register_method(
    "graph_segmentation", _run_graph_segmentation, defaults=dict(k_thresh=0.0, min_size=20),
    description="Felzenszwalb-Huttenlocher graph segmentation with the ScanNet Segmentator's "
                "weights (1 - n_i.n_j, squared on convex edges); k_thresh=0 searches the "
                "threshold for n_segments, > 0 uses it (the Segmentator's default is 0.01)",
    elements=ELEMENTS)
register_method(
    "cut_pursuit", _run_cut_pursuit, defaults=dict(reg_strength=0.0),
    description="l0 cut pursuit of dimensionality features on the same point graph "
                "(Superpoint Graph's partition; the cut-pursuit-py package, baselines extra); "
                "reg_strength=0 searches it for n_segments",
    elements=("vertices", "points"))
register_method(
    "spt_partition", _run_spt_partition, defaults=dict(preset="scannet", level=0),
    description="cut pursuit as Superpoint Transformer runs its partition (voxels, its point "
                "features with elevation and colour, its graph, regularisation and minimum "
                "size; preset: scannet, s3dis, kitti360 or dales); the regularisation of level "
                "1 or 2 (level=0: chosen by the count) searched for n_segments; needs "
                "pycut-pursuit (GPL-3, installed by hand) and the baselines extra",
    elements=("points",))
register_method(
    "vccs", _run_vccs, defaults=dict(seed_resolution=0.0),
    description="VCCS supervoxels (PCL's SupervoxelClustering) through the external module "
                "vccs_supervoxel, built from a public header-only port (not on the package "
                "index); seed_resolution=0 searches it for n_segments",
    elements=("points",))
register_method(
    "shlafman", _run_shlafman, defaults=dict(_SF_DEFAULTS, alpha=WEIGHTING_ALPHA["shlafman"][0]),
    sweep={"alpha": (0.0, 0.25, 0.5, 0.75, 1.0)},
    description="the same k-means with Shlafman et al.'s weights (eq. 6), alpha in [0, 1]",
    progress=True, check=partial(_check_superfacets, weighting="shlafman"))
register_method(
    "ncuts", _run_ncuts,
    defaults=dict(alpha=100.0, eta_convex=0.2, bandwidth=1.0, components=300,
                  memory_limit_gib=0.0),
    sweep={"alpha": (0.0, 100.0, 200.0)},
    description="normalized cuts: dense all-pairs distances (same weights), Gaussian affinity, "
                "k-way spectral cut (Shi-Malik / Yu-Shi); O(m^2) memory, refuses meshes over "
                "memory_limit_gib (0: 40% of RAM)",
    progress=True)
register_method(
    "vsa", _run_vsa, defaults=dict(metric="l21", init="random", max_iter=30, insert_iter=2),
    sweep={"metric": ("l21", "l2"), "init": ("random", "incremental")},
    description="Variational Shape Approximation (Cohen-Steiner et al. 2004): planar proxies, "
                "L2,1 or L2 metric, random or incremental proxy initialization")
