"""Cut pursuit run as Superpoint Transformer runs its partition: a faithful baseline.

Superpoint Transformer (Robert, Raguet and Landrieu, ICCV 2023) takes its
superpoints from the finest level of a hierarchical partition computed by
``cp_d0_dist``, the parallel l0 cut pursuit of Raguet and Landrieu. This
module rebuilds that level from the public description of the method and the
dataset settings its authors publish, so that the comparison tables in the
documentation set the project against cut pursuit at its strongest:

1. **Voxels** (its ``GridSampling3D``): the points are averaged per voxel of
   side ``voxel`` (positions and colours); every voxel weighs 1 in the
   partition, and each input point takes its voxel's superpoint.
2. **Neighbours** (its ``KNN``): the ``knn`` nearest voxels of each voxel
   within ``knn_r``, itself excluded.
3. **Point features** (its ``PointFeatures``, through ``pgeof``): linearity,
   planarity and scattering from the square roots of the covariance
   eigenvalues of each voxel's neighbourhood (itself and its ``knn``
   neighbours), verticality doubled ("to increase its importance in the
   partition"), colour as RGB or HSV (hue divided by 360), and
   **elevation** (its ``GroundElevation``): the height above a RANSAC plane
   fitted to the points within ``ground_threshold`` of the lowest one,
   divided by ``ground_scale``.
4. **Graph** (its ``AdjacencyGraph``): the first ``k_adjacency`` = 10
   neighbours of each voxel, edge weights ``1 / (1 + d / mean(d))`` (mean
   over the directed neighbour list), each undirected edge once (its trimmed
   graph; the two directions share ``d``, so their mean is the same weight);
   a voxel with no edge is joined to its nearest voxel (``ConnectIsolated``).
5. **Partition** (its ``CutPursuitPartition``, first level): minimise
   ``sum_v ||x_v - y_v||^2_M + sum_(uv cut) reg * w_uv`` where ``y_v`` is
   the voxel's centred position and its features, ``M`` weighs positions by
   ``spatial_weight`` and features by 1, with ``min_comp_weight = cutoff``
   (superpoints of fewer voxels merged into a neighbour), 15 iterations,
   ``cp_dif_tol = 1e-2``, ``split_damp_ratio = 0.7``.

The settings of each dataset are :data:`PRESETS` (ScanNet, S3DIS, KITTI-360,
DALES): its voxel, neighbours, ground model, features and the first level's
regularisation, spatial weight and cut-off. Given ``n_segments`` the
regularisation is searched instead (bisection in log scale) so that methods
are compared at equal counts; the other settings stay the dataset's.

Positions are centred on their mean before the features are computed in
float32 (as ``pgeof`` takes them): georeferenced coordinates in float32
would otherwise lose the centimetres.

The solver is ``pycut-pursuit``, which is GPL-3: it is never a dependency of
this MIT package, only an optional baseline installed by hand: its one wheel
(0.1.4) does not import beside NumPy 2, so build 0.1.3 from source (``pip install
setuptools wheel``, then ``pip install --no-build-isolation --no-binary
pycut-pursuit "pycut-pursuit==0.1.3"``; ``docs/guide/install.md``). ``pgeof`` (MIT)
and scikit-learn come with the ``baselines`` extra.

References
----------
D. Robert, H. Raguet, L. Landrieu, "Efficient 3D Semantic Segmentation with
Superpoint Transformer", ICCV 2023. H. Raguet, L. Landrieu, "Parallel Cut
Pursuit For Minimization of the Graph Total Variation", ICML workshop 2019.
L. Landrieu, G. Obozinski, "Cut Pursuit: fast algorithms to learn piecewise
constant functions on general weighted graphs", SIAM J. Imaging Sci. 10(4),
2017.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from functools import partial

import numpy as np

from ..._runtime import extras
from ...errors import MissingExtraError, ParameterError
from ...inputs.cloud import as_cloud
from ...method.params import check_int
from ._count import search_count

__all__ = ["SPTSettings", "PRESETS", "spt_problem", "spt_partition", "SPTProblem"]


@dataclass(frozen=True)
class SPTSettings:
    """One dataset's partition settings in Superpoint Transformer.

    Attributes
    ----------
    voxel : float
        Voxel side, in the cloud's units (metres); 0: no voxels.
    knn, knn_r : int, float
        Neighbours of each voxel for the features, and their largest distance.
    ground_threshold, ground_scale : float
        The ground plane is fitted to the points within ``ground_threshold``
        of the lowest; elevation is divided by ``ground_scale``.
    features : tuple of str
        Among ``rgb``, ``hsv``, ``linearity``, ``planarity``, ``scattering``,
        ``verticality``, ``elevation``; colours are left out on a cloud
        without them.
    regularization, spatial_weight, cutoff : float, float, int
        The first partition level's.
    spatial_weight_2, cutoff_2 : float, int
        The second level's (it partitions the first level's superpoints).
    k_adjacency, iterations : int
        Neighbours in the partition graph; cut pursuit's iterations.
    """

    voxel: float
    knn: int
    knn_r: float
    ground_threshold: float
    ground_scale: float
    features: tuple
    regularization: float
    spatial_weight: float
    spatial_weight_2: float
    cutoff: int = 10
    cutoff_2: int = 10
    k_adjacency: int = 10
    iterations: int = 15


_INDOOR = ("rgb", "linearity", "planarity", "scattering", "verticality", "elevation")

#: The datasets' settings, as Superpoint Transformer's configuration files give them.
PRESETS: dict[str, SPTSettings] = {
    "scannet": SPTSettings(0.02, 45, 2.0, 1.5, 4.0, _INDOOR, 0.01, 0.1, 0.1),
    "s3dis": SPTSettings(0.03, 45, 2.0, 1.5, 4.0, _INDOOR, 0.01, 0.1, 0.1),
    "kitti360": SPTSettings(0.1, 50, 10.0, 5.0, 20.0, ("hsv",) + _INDOOR[1:], 0.1, 1.0, 0.1,
                            cutoff_2=30),
    "dales": SPTSettings(0.1, 25, 10.0, 5.0, 20.0,
                         ("linearity", "planarity", "scattering", "elevation"), 0.1, 0.1, 0.01,
                         cutoff_2=30),
}


@dataclass
class SPTProblem:
    """The cut pursuit problem of :func:`spt_problem`.

    Attributes
    ----------
    observations : (V, 3 + F) float32 ndarray
        Each voxel's centred position, then its features.
    coor_weights : (3 + F,) float32 ndarray
        ``spatial_weight`` for the positions, 1 for the features.
    first_edge : (V + 1,) uint32 ndarray
    adj_vertices : (E,) uint32 ndarray
        The graph in forward-star form, each undirected edge once.
    edge_weights : (E,) float32 ndarray
        ``1 / (1 + d / mean(d))``, before the regularisation.
    voxel_of : (N,) int64 ndarray
        The voxel of each valid input point.
    feature_names : tuple of str
    """

    observations: np.ndarray
    coor_weights: np.ndarray
    first_edge: np.ndarray
    adj_vertices: np.ndarray
    edge_weights: np.ndarray
    voxel_of: np.ndarray
    feature_names: tuple


#: A cloud whose points lie this far apart or more, in voxel sides (the median distance to
#: each point's nearest other), is voxelized already: it is used as given (voxelized again
#: at a shifted grid, a room of 3 cm voxels lost a third of its points, 41,568 -> 27,571)
VOXELIZED = 0.8


def _voxelized_already(points: np.ndarray, size: float) -> bool:
    """Whether the points are spaced as voxels of side ``size`` (or more) already."""
    from scipy.spatial import cKDTree

    if points.shape[0] < 2:
        return True
    sample = points[np.linspace(0, points.shape[0] - 1, min(points.shape[0], 20_000))
                    .astype(np.int64)]
    d, _ = cKDTree(points).query(sample, k=2)
    return bool(np.median(d[:, 1]) >= VOXELIZED * size)


def _voxels(points: np.ndarray, colors, size: float):
    """Mean position (and colour) per voxel, and each point's voxel (the points as given
    where they are voxels of that side already)."""
    if size <= 0 or _voxelized_already(points, size):
        return points, colors, np.arange(points.shape[0])
    keys = np.floor(points / size).astype(np.int64)  # the grid of the input's coordinates
    _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.reshape(-1)

    def mean(a):
        out = np.zeros((counts.size, a.shape[1]))
        np.add.at(out, inverse, a)
        return out / counts[:, None]

    return mean(points), None if colors is None else mean(colors), inverse


def _elevation(xyz: np.ndarray, threshold: float, scale: float) -> np.ndarray:
    linear = extras.require("sklearn.linear_model", "the Superpoint Transformer partition")
    # the ground's candidates: within the threshold of a low quantile, not of the lowest
    # point (a sweep's lowest point was an outlier 8.6 m under the ground: alone, it left
    # RANSAC nothing to fit)
    z = xyz[:, 2]
    ref = float(np.quantile(z, 0.005))
    low = np.flatnonzero(np.abs(z - ref) < threshold)
    if low.size < 3:  # no plane to fit: heights above that level
        return (z - ref) / scale
    ransac = linear.RANSACRegressor(random_state=0, residual_threshold=1e-3)
    try:
        ransac.fit(xyz[low, :2], xyz[low, 2])
    except ValueError:  # (no consensus within the residual threshold)
        return (z - ref) / scale
    return (z - ransac.predict(xyz[:, :2])) / scale


def _hsv(rgb: np.ndarray) -> np.ndarray:
    """HSV of RGB in ``[0, 1]``, hue in ``[0, 1)`` (SPT's degrees divided by 360)."""
    mx, mn = rgb.max(axis=1), rgb.min(axis=1)
    delta = mx - mn
    safe = np.where(delta > 0, delta, 1.0)
    r, g, b = rgb.T
    h = np.where(mx == r, ((g - b) / safe) % 6.0,
                 np.where(mx == g, (b - r) / safe + 2.0, (r - g) / safe + 4.0)) / 6.0
    s = np.where(mx > 0, delta / np.where(mx > 0, mx, 1.0), 0.0)
    return np.c_[np.where(delta > 0, h, 0.0), s, mx]


def spt_problem(obj, settings: SPTSettings | str = "scannet") -> SPTProblem:
    """The observations, graph and weights Superpoint Transformer's partition solves.

    Parameters
    ----------
    obj : point cloud
        A :class:`~superfacets.PointCloud`, an ``(N, 3)`` array, or anything
        :func:`superfacets.segment` takes as a cloud; z is up.
    settings : SPTSettings or str, default "scannet"
        Or a key of :data:`PRESETS`.

    Returns
    -------
    SPTProblem

    Raises
    ------
    MissingExtraError
        If ``pgeof`` or scikit-learn is missing (the ``baselines`` extra).
    ParameterError
        On an unknown preset or a cloud of fewer than two voxels.

    Examples
    --------
    >>> xyz = np.random.default_rng(0).random((2000, 3))
    >>> spt_problem(xyz).observations.shape[1]      # doctest: +SKIP
    9
    """
    from scipy.spatial import cKDTree

    s = _settings(settings)
    pgeof = extras.require("pgeof", "the Superpoint Transformer partition")
    cloud = as_cloud(obj)
    valid = cloud.valid
    points = np.asarray(cloud.points, dtype=np.float64)[valid]
    colors = None if cloud.colors is None else np.asarray(cloud.colors, np.float64)[valid]
    xyz, rgb, voxel_of = _voxels(points, colors, s.voxel)
    xyz = xyz - xyz.mean(axis=0)
    n = xyz.shape[0]
    if n < 2:
        raise ParameterError(f"the Superpoint Transformer partition needs two voxels or more; "
                             f"the cloud has {n} at voxel {s.voxel:g}")
    k = min(s.knn, n - 1)
    dist, idx = cKDTree(xyz).query(xyz, k=k + 1, distance_upper_bound=s.knn_r)
    own = idx == np.arange(n)[:, None]  # itself, wherever the tie put it
    drop = np.where(own.any(axis=1), own.argmax(axis=1), k)
    keep = np.ones_like(own)
    keep[np.arange(n), drop] = False
    dist, idx = dist[keep].reshape(n, k), idx[keep].reshape(n, k)
    found = idx < n
    # features: itself and its neighbours (pgeof; zeros below one neighbour)
    nn = np.c_[np.arange(n), np.where(found, idx, 0)][np.c_[np.ones(n, bool), found]]
    nn_ptr = np.r_[0, np.cumsum(1 + found.sum(axis=1))]
    geof = pgeof.compute_features(np.ascontiguousarray(xyz, dtype=np.float32),
                                  nn.astype(np.uint32), nn_ptr.astype(np.uint32), 1, False)
    cols, names = [], []
    for name in s.features:
        if name in ("rgb", "hsv"):
            if rgb is None:
                continue
            cols.append(rgb if name == "rgb" else _hsv(rgb))
        elif name == "elevation":
            cols.append(_elevation(xyz, s.ground_threshold, s.ground_scale)[:, None])
        else:
            col = ("linearity", "planarity", "scattering", "verticality").index(name)
            cols.append(geof[:, col:col + 1] * (2.0 if name == "verticality" else 1.0))
        names.append(name)
    obs = np.ascontiguousarray(np.hstack([xyz] + cols), dtype=np.float32)
    coor = np.ones(obs.shape[1], dtype=np.float32)
    coor[:3] = s.spatial_weight
    # the adjacency graph: the first k_adjacency neighbours, one weight per undirected edge
    ka = min(s.k_adjacency, k)
    src = np.repeat(np.arange(n), ka)
    tgt, d = idx[:, :ka].reshape(-1), dist[:, :ka].reshape(-1)
    ok = tgt < n
    src, tgt, d = src[ok], tgt[ok], d[ok]
    mean = float(d.mean()) if d.size and d.mean() > 0 else 1.0
    alone = np.setdiff1d(np.arange(n), np.r_[src, tgt])
    if alone.size:  # ConnectIsolated: each to its nearest voxel, whatever the distance
        dd, jj = cKDTree(xyz).query(xyz[alone], k=2)
        src, tgt, d = np.r_[src, alone], np.r_[tgt, jj[:, 1]], np.r_[d, dd[:, 1]]
    w = 1.0 / (1.0 + d / mean)
    lo, hi = np.minimum(src, tgt), np.maximum(src, tgt)
    key = lo.astype(np.int64) * n + hi
    key, first = np.unique(key, return_index=True)
    lo, hi, w = key // n, key % n, w[first]
    first_edge = np.r_[0, np.cumsum(np.bincount(lo, minlength=n))].astype(np.uint32)
    return SPTProblem(obs, coor, first_edge, hi.astype(np.uint32), w.astype(np.float32),
                      voxel_of, tuple(names))


def _settings(settings) -> SPTSettings:
    if isinstance(settings, SPTSettings):
        return settings
    if settings not in PRESETS:
        raise ParameterError(f"unknown Superpoint Transformer preset {settings!r}; "
                             f"one of {', '.join(PRESETS)}")
    return PRESETS[settings]


def _cut_pursuit(cp_d0_dist, y, first, adj, w, vertex_w, coor, cutoff, reg, *, iterations,
                 threads):
    """One run of ``cp_d0_dist`` with SPT's options: the component of each vertex (numbered
    0..n-1, the columns of the values), the components' values and their graph."""
    comp, values, graph = cp_d0_dist(
        y.shape[0], y, first, adj, edge_weights=w * np.float32(reg), vert_weights=vertex_w,
        coor_weights=coor, min_comp_weight=cutoff, cp_dif_tol=1e-2, cp_it_max=iterations,
        split_damp_ratio=0.7, verbose=False, max_num_threads=threads,
        balance_parallel_split=True, compute_Graph=True)
    return np.asarray(comp, dtype=np.int64), values, graph


def spt_partition(obj, n_segments: int | None = None, *, preset: str = "scannet",
                  level: int | str = "auto", max_num_threads: int = 0,
                  **overrides) -> np.ndarray:
    """Superpoints as Superpoint Transformer's partition makes them (module notes).

    Parameters
    ----------
    obj : point cloud
        As :func:`spt_problem` takes it.
    n_segments : int, optional
        Search a regularisation (bisection in log scale, 16 runs at most)
        for the count nearest this one; without it, the preset's level 1.
    level : {'auto', 1, 2}, default 'auto'
        With ``n_segments``, which level's regularisation is searched: 1, the
        voxels' partition; 2, the partition of the level-1 superpoints that
        the preset's regularisation makes (as Superpoint Transformer makes
        its coarser levels; only below their count); 'auto': 2 when
        ``n_segments`` is at most half the level-1 count, else 1.
    preset : {'scannet', 's3dis', 'kitti360', 'dales'}, default 'scannet'
        The dataset whose settings are used (:data:`PRESETS`).
    max_num_threads : int, default 0
        Cut pursuit's threads (0: all).
    **overrides
        Fields of :class:`SPTSettings` to change (``voxel=0.05``).

    Returns
    -------
    labels : (N,) int64 ndarray
        Dense, one per input point (-1 for invalid points).

    Raises
    ------
    MissingExtraError
        If ``pycut-pursuit`` (GPL-3, installed by hand), ``pgeof`` or
        scikit-learn is missing.
    ParameterError
        On an unknown preset or setting.

    Examples
    --------
    >>> xyz = np.random.default_rng(0).random((5000, 3))
    >>> labels = spt_partition(xyz, 50)             # doctest: +SKIP
    """

    try:
        cp = extras.require("pycut_pursuit.cp_d0_dist", "the Superpoint Transformer partition")
    except MissingExtraError as exc:
        raise MissingExtraError(
            f"{str(exc).split(';')[0]}; it is GPL-3, so never installed with superfacets, and "
            "its wheel (0.1.4) does not import beside NumPy 2: pip install setuptools wheel && "
            "pip install --no-build-isolation --no-binary pycut-pursuit "
            "'pycut-pursuit==0.1.3' (docs/guide/install.md)") from None
    known = {f.name for f in fields(SPTSettings)}
    unknown = sorted(set(overrides) - known)
    if unknown:
        word = "setting" if len(unknown) == 1 else "settings"
        raise ParameterError(f"unknown {word} {', '.join(unknown)}; known: "
                             f"{', '.join(sorted(known))}")
    s = replace(_settings(preset), **overrides)
    cloud = as_cloud(obj)
    prob = spt_problem(cloud, s)
    y = np.asfortranarray(prob.observations.T)
    solve = partial(_cut_pursuit, cp.cp_d0_dist, iterations=s.iterations,
                    threads=max_num_threads)
    # level 1: the voxels, each weighing 1
    comp, values, graph = solve(y, prob.first_edge, prob.adj_vertices, prob.edge_weights,
                                np.ones(y.shape[1], dtype=np.float32), prob.coor_weights,
                                s.cutoff, s.regularization)
    if n_segments is not None:
        n_segments = check_int("n_segments", n_segments, lo=1, hi=y.shape[1])

        n_first = int(comp.max()) + 1
        if level == "auto":
            level = 2 if 2 * n_segments <= n_first else 1
        if level not in (1, 2):
            raise ParameterError(f"level must be 'auto', 1 or 2, got {level!r}")
        if level == 2 and n_segments < n_first:  # the level-1 superpoints, by their size
            first, adj, w = (np.asarray(a) for a in graph)
            coor = prob.coor_weights.copy()
            coor[:3] = s.spatial_weight_2
            args = (np.asfortranarray(values, dtype=np.float32), first.astype(np.uint32),
                    adj.astype(np.uint32), (w / s.regularization).astype(np.float32),
                    np.bincount(comp).astype(np.float32), coor, s.cutoff_2)
            comp = search_count(lambda reg: solve(*args, reg)[0], n_segments,
                                -6.0, 3.0, 16, "the Superpoint Transformer partition")[comp]
        else:  # level 1's regularisation searched
            args = (y, prob.first_edge, prob.adj_vertices, prob.edge_weights,
                    np.ones(y.shape[1], dtype=np.float32), prob.coor_weights, s.cutoff)
            comp = search_count(lambda reg: solve(*args, reg)[0], n_segments, -6.0, 2.0, 16,
                                "the Superpoint Transformer partition")
    voxel_labels = comp
    out = np.full(cloud.n_total, -1, dtype=np.int64)
    out[cloud.valid] = voxel_labels[prob.voxel_of]
    return out
