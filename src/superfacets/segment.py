"""The superfacet iteration (paper section 3, SPEC section 3).

``superfacets(mesh, ...)`` returns one label per face; ``segment(mesh, ...)``
takes the same arguments and returns a :class:`SegmentationResult` with the
labels and the details (centers, iterations, convergence, time per stage).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from . import _kernels
from .connectivity import enforce_connectivity as _enforce_connectivity
from .connectivity import relabel_dense
from .errors import ParameterError
from .graph import edge_weights
from .mesh import as_mesh
from ._workspace import Replay, Workspaces, with_room
from .seeding import (INITS, check_n_segments, farthest_point_centers, flood_labels,
                      grid_labels)

__all__ = ["superfacets", "segment", "SegmentationResult", "ASSIGNMENTS"]

#: Names accepted by ``assignment=``.
ASSIGNMENTS = ("bounded", "exact")
_DEFAULT_K = 150


@dataclass(frozen=True)
class SegmentationResult:
    """Labels and details of one run of :func:`segment`.

    Attributes
    ----------
    labels : (m,) int64 ndarray
        Superfacet of each face, dense ``0..K-1``.
    centers : (K,) int64 ndarray
        Center face of each superfacet (the center of the last
        classification; for a superfacet that lost it to the connectivity
        step, its face nearest the area-weighted mean of its centroids).
    n_iter : int
        Number of classification passes run.
    converged : bool
        True if the last center update moved no center (else ``max_iter``
        stopped the run).
    radius : float
        Superfacet radius ``r`` used, in mesh units.
    n_orphan_seeds : int
        Centers created on orphan faces over the whole run.
    timings : dict of str to float
        Seconds per stage: ``graph`` (face graph and per-face geometry,
        zero when already cached on the mesh), ``weights``, ``init``,
        ``iterations``, ``connectivity``, ``total``; and, not times,
        ``expansions`` (Dijkstra expansions run), ``passes``
        (classifications actually run: fewer than ``n_iter`` when a cycle
        was skipped) and ``cycle_period`` (0, or the period of the cycle of
        center sets that was detected).
    params : dict
        The parameters of the run, resolved (``n_segments``, ``radius``,
        ``init``, ...).
    """

    labels: np.ndarray
    centers: np.ndarray
    n_iter: int
    converged: bool
    radius: float
    n_orphan_seeds: int
    timings: dict = field(default_factory=dict)
    params: dict = field(default_factory=dict)

    @property
    def n_segments(self) -> int:
        """Number of superfacets ``K`` produced."""
        return int(self.centers.shape[0])


def superfacets(mesh, n_segments: int | None = _DEFAULT_K, *, radius: float | None = None,
                alpha: float = 200.0, eta_convex: float = 0.2, window: float = 2.0,
                init: str | None = None, max_iter: int = 50, weighting: str = "paper",
                assignment: str = "bounded", enforce_connectivity: bool = True,
                progress: bool = False, n_threads: int | None = None) -> np.ndarray:
    """Over-segment a triangle mesh into superfacets.

    The k-means-style method of Simari, Picciau and De Floriani (2014):
    initialize centers, then alternate a classification (bounded Dijkstra
    expansions over the weighted face graph) and a center update until no
    center moves or ``max_iter`` passes have run.

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or tuple of ((n, 3) float, (m, 3) int) ndarray
        Triangle mesh. Degenerate faces, duplicate faces, unreferenced
        vertices, non-manifold edges and several connected components are
        accepted (each component gets its own superfacets).
    n_segments : int, default 150
        Desired number of superfacets ``k``, ``1 <= k <= m``. The radius is
        then ``r = sqrt(A / (k pi))`` (section 3.1). Ignored, and must be left
        at its default or None, when ``radius`` is given.
    radius : float, optional
        Desired superfacet radius as a fraction of the bounding-box diagonal
        ``d`` (``r = radius * d``), ``> 0``. With ``init='farthest'`` the
        number of centers is then ``round(A / (pi r^2))``.
    alpha : float, default 200
        Weight of the angular (concavity) term, eq. 3; ``>= 0``. 0 gives the
        most compact superfacets, larger values follow concavities more.
        With ``weighting='shlafman'`` it must lie in ``[0, 1]`` (eq. 6).
    eta_convex : float, default 0.2
        Factor of the angular term on convex edges (concave edges: 1), eq. 2.
    window : float, default 2
        Expansion multiple: an expansion only reaches faces whose centroid is
        within ``window * r`` of its center's centroid (section 3.1).
    init : {'farthest', 'flood', 'grid'}, optional
        Initialization: iterative farthest point (default when ``radius`` is
        not given), flood (default when it is) or regular grid of cell ``2 r``.
    max_iter : int, default 50
        Maximum number of classification passes (``>= 1``).
    weighting : {'paper', 'shlafman'}, default 'paper'
        Edge weights: the paper's eqs. 1-3 or Shlafman et al.'s eq. 6.
    assignment : {'bounded', 'exact'}, default 'bounded'
        ``'bounded'``: the paper's classification, one window-bounded
        Dijkstra per center, a face keeping the smallest distance seen.
        ``'exact'``: one multi-source Dijkstra from all centers, no window, so
        every face goes to its nearest center along the face graph (the
        bounded version differs only where the shortest path to the nearest
        center leaves that center's window, and may leave orphans).
    enforce_connectivity : bool, default True
        Merge stray pieces of a superfacet into the neighbour with which they
        share the longest boundary, so each superfacet is face-connected.
    progress : bool, default False
        Show a progress bar on stderr: the set-up stages by name (face graph,
        weights, init), then the iterations.
    n_threads : int, optional
        Threads that expand centers at the same time (``>= 1``; default:
        numba's thread count, ``NUMBA_NUM_THREADS``, normally the number of
        cores). The labels do not depend on it.

    Returns
    -------
    labels : (m,) int64 ndarray
        Superfacet of each face, dense ``0..K-1``. ``K`` may differ from
        ``n_segments``: orphan faces seed extra superfacets; stray pieces and
        centers left without faces reduce it.

    Raises
    ------
    TypeError
        If ``mesh`` is not a mesh, or ``faces`` not integer.
    InvalidMeshError
        If the mesh is empty, has NaN/inf coordinates, out-of-range indices,
        zero extent or zero area.
    ParameterError
        If a parameter is out of range (``n_segments`` < 1 or > m, negative
        ``alpha``, both ``n_segments`` and ``radius``, unknown ``init``, ...).

    See Also
    --------
    segment : same arguments, returns the labels with the run's details.

    References
    ----------
    .. [1] G. Simari, G. Picciau, L. De Floriani, "Fast and Scalable Mesh
       Superfacets", Computer Graphics Forum 33(7) (Pacific Graphics), 2014.

    Examples
    --------
    >>> import trimesh
    >>> from superfacets import superfacets
    >>> mesh = trimesh.creation.icosphere(subdivisions=3)
    >>> labels = superfacets(mesh, n_segments=20)
    >>> labels.shape, int(labels.max()) + 1
    ((1280,), 20)
    """
    return segment(mesh, n_segments, radius=radius, alpha=alpha, eta_convex=eta_convex,
                   window=window, init=init, max_iter=max_iter, weighting=weighting,
                   assignment=assignment, enforce_connectivity=enforce_connectivity,
                   progress=progress, n_threads=n_threads).labels


def _threads(n_threads) -> int:
    """Resolve ``n_threads`` (None: numba's thread count, NUMBA_NUM_THREADS)."""
    if n_threads is None:
        import numba

        return int(numba.config.NUMBA_NUM_THREADS)
    if isinstance(n_threads, (bool, np.bool_)) or not isinstance(n_threads, (int, np.integer)) \
            or n_threads < 1:
        raise ParameterError(f"n_threads must be an integer >= 1, got {n_threads!r}")
    return int(n_threads)


def _positive(name: str, value) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number, got {value!r}") from None
    if not (math.isfinite(x) and x > 0):
        raise ParameterError(f"{name} must be a finite number > 0, got {value!r}")
    return x


def _resolve(mesh, n_segments, radius, init, window, max_iter, assignment):
    """Validate the size parameters; return (k or None, r, init, window, max_iter)."""
    if radius is not None and n_segments not in (None, _DEFAULT_K):
        raise ParameterError("give either n_segments or radius, not both")
    if init is None:
        init = "farthest" if radius is None else "flood"
    if init not in INITS:
        raise ParameterError(f"init must be one of {', '.join(INITS)}; got {init!r}")
    if assignment not in ASSIGNMENTS:
        raise ParameterError(f"assignment must be one of {', '.join(ASSIGNMENTS)}; got {assignment!r}")
    window = _positive("window", window)
    if isinstance(max_iter, (bool, np.bool_)) or not isinstance(max_iter, (int, np.integer)) \
            or max_iter < 1:
        raise ParameterError(f"max_iter must be an integer >= 1, got {max_iter!r}")
    m = mesh.n_faces
    if radius is not None:
        r = _positive("radius", radius) * mesh.diagonal
        k = None
        if init == "farthest":
            k = int(min(m, max(1, round(mesh.area / (math.pi * r * r)))))
    else:
        if n_segments is None:
            n_segments = _DEFAULT_K
        k = check_n_segments(n_segments, m)
        r = math.sqrt(mesh.area / (k * math.pi))
    return k, r, init, window, int(max_iter)


def segment(mesh, n_segments: int | None = _DEFAULT_K, *, radius: float | None = None,
            alpha: float = 200.0, eta_convex: float = 0.2, window: float = 2.0,
            init: str | None = None, max_iter: int = 50, weighting: str = "paper",
            assignment: str = "bounded", enforce_connectivity: bool = True,
            progress: bool = False, n_threads: int | None = None,
            _reference: bool = False) -> SegmentationResult:
    """Superfacets with details: same parameters as :func:`superfacets`.

    Returns
    -------
    SegmentationResult
        ``.labels`` is what :func:`superfacets` returns; ``.centers``,
        ``.n_iter``, ``.converged``, ``.timings`` and ``.params`` describe
        the run.

    Raises
    ------
    TypeError, InvalidMeshError, ParameterError
        As :func:`superfacets`.

    Notes
    -----
    With ``assignment='bounded'`` the expansion of a center depends on its
    face alone, so a center that did not move since the previous pass is not
    expanded again: its recorded (face, distance) list is replayed through
    the same update, in the same center order. The labels are exactly those
    of expanding every center every pass (``_reference=True``, used by the
    tests), at the cost of about ``12 * 5`` bytes per face for the recorded
    lists (each face lies in about 4.4 windows with ``window = 2``). The
    centers that moved are expanded first, record only, on ``n_threads``
    threads at once (an expansion reads neither the labels nor the other
    expansions), then all records are replayed in center order, so the
    result does not depend on the number of threads.

    The ordered center list of a pass determines every later pass, so when
    it repeats the list of an earlier pass the run is periodic (the
    flip-flopping that keeps many runs from converging): the run then jumps
    to the center list that pass ``max_iter`` would have, and classifies it
    once. Labels, centers, ``n_iter`` and ``n_orphan_seeds`` are those of
    running every pass (tested against ``_reference=True``, which does
    neither optimization); ``timings['passes']`` counts the passes run.
    """
    t_start = time.perf_counter()
    mesh = as_mesh(mesh)
    mesh.check_usable()
    k, r, init, window, max_iter = _resolve(mesh, n_segments, radius, init, window, max_iter,
                                            assignment)
    n_threads = _threads(n_threads)
    m = mesh.n_faces
    timings: dict[str, float] = {}

    bar = None
    if progress:  # one bar: the set-up stages by name, then the passes
        from tqdm import tqdm

        bar = tqdm(total=max_iter, desc="face graph", unit="it", leave=False)
    t = time.perf_counter()
    g = mesh.graph
    _ = mesh.centroids, mesh.normals, mesh.areas
    timings["graph"] = time.perf_counter() - t
    if bar is not None:
        bar.set_description("weights")
    t = time.perf_counter()
    w = edge_weights(mesh, weighting, alpha=alpha, eta_convex=eta_convex)
    csr_w = np.ascontiguousarray(w[g.dual_edge], dtype=np.float64)
    del w
    timings["weights"] = time.perf_counter() - t

    # buffers, allocated once per run
    c = np.ascontiguousarray(mesh.centroids)
    areas = np.ascontiguousarray(mesh.areas)
    dist = np.empty(m)
    label = np.empty(m, dtype=np.int32)  # one kernel specialization for all label arrays
    spaces = Workspaces(m, csr_w, n_threads)
    centers = np.empty(m, dtype=np.int64)
    window_r2 = (window * r) ** 2

    if bar is not None:
        bar.set_description(f"init ({init})")
    t = time.perf_counter()
    if init == "farthest":
        n_centers = k
        centers[:k] = farthest_point_centers(mesh, k)
    else:
        init_labels = (flood_labels(mesh, csr_w, r, window) if init == "flood"
                       else grid_labels(mesh, r))
        n_centers = int(init_labels.max()) + 1
        _kernels.update_centers(init_labels.astype(np.int32), n_centers, areas, c,
                                np.full(n_centers, -1, dtype=np.int64), centers)
    timings["init"] = time.perf_counter() - t
    n_init = n_centers

    t = time.perf_counter()
    inc = Replay(m, spaces) if (assignment == "bounded" and not _reference) else None
    if assignment == "exact":
        hkey = np.empty(spaces.heap_bound)
        hval = np.empty(spaces.heap_bound, dtype=np.int32 if m < 2**31 - 1 else np.int64)
    n_iter = 0
    n_expanded = 0
    converged = False
    n_orphans = 0
    if bar is not None:
        bar.set_description("superfacets")
    # The centers of a pass determine everything after it, so once the ordered
    # center list of a pass repeats an earlier one the run is periodic: jump to the
    # state of pass max_iter and classify it once (same labels as running every pass).
    seen: dict[bytes, int] = {}
    states: list[np.ndarray] = []
    orphans_per_pass: list[int] = []
    n_passes = 0
    period = 0
    try:
        while True:
            key = centers[:n_centers].tobytes()
            if key in seen and not period and not _reference and n_iter < max_iter - 1:
                j = seen[key]  # pass j (0-based) had the same centers as pass n_iter
                period = n_iter - j
                last = max_iter - 1
                cyc = [j + ((t - j) % period) for t in range(n_iter, last)]
                n_orphans += sum(orphans_per_pass[q] for q in cyc)
                target = states[j + ((last - j) % period)]
                n_centers = target.shape[0]
                centers[:n_centers] = target
                if bar is not None:
                    bar.update(last - n_iter)
                n_iter = last
            elif not period:
                seen[key] = n_iter
                states.append(centers[:n_centers].copy())
            if inc is not None:
                k_now, n_exp = inc.classify(g.indptr, g.indices, csr_w, c, centers, n_centers,
                                            window_r2, dist, label)
                n_expanded += n_exp
            elif assignment == "bounded":
                sid = spaces.reserve(m + n_centers)
                k_now, next_sid = with_room(spaces.get(0), lambda ws: _kernels.classify_bounded(
                    g.indptr, g.indices, csr_w, c, centers, n_centers, window_r2, dist, label,
                    ws.local, ws.stamp, sid, ws.queue, spaces.inv_width, ws.vis))
                spaces.release(next_sid)
                n_expanded += k_now
            else:
                k_now = _kernels.classify_exact(g.indptr, g.indices, csr_w, centers, n_centers,
                                                dist, label, hkey, hval)
            n_iter += 1
            n_passes += 1
            n_orphans += k_now - n_centers
            orphans_per_pass.append(k_now - n_centers)
            used = centers[:k_now].copy()
            moved = np.empty(k_now, dtype=np.int64)
            _kernels.update_centers(label, k_now, areas, c, used, moved)
            n_moved = int((moved != used).sum())
            if bar is not None:
                bar.update(1)
                bar.set_postfix(centers=k_now, moved=n_moved)
            if k_now == n_centers and n_moved == 0:
                converged = True
                break
            if n_iter >= max_iter:
                break
            alive = moved[moved >= 0]
            n_centers = alive.shape[0]
            centers[:n_centers] = alive
    finally:
        spaces.close()
        if bar is not None:
            bar.close()
    timings["iterations"] = time.perf_counter() - t
    inc = spaces = dist = csr_w = None  # free the work buffers before the clean-up
    hkey = hval = None

    # labels of the last classification; drop superfacets left empty
    t = time.perf_counter()
    present = np.zeros(k_now, dtype=bool)
    present[label] = True
    final = relabel_dense(label)
    final_centers = used[present]
    if enforce_connectivity:
        final = _enforce_connectivity(mesh, final, final_centers)
    final_centers = _centers_of(final, final_centers, areas, c)
    timings["connectivity"] = time.perf_counter() - t
    timings["total"] = time.perf_counter() - t_start

    timings["expansions"] = n_expanded
    timings["passes"] = n_passes
    timings["cycle_period"] = period
    params = dict(n_segments=k, radius=r / mesh.diagonal, alpha=float(alpha),
                  eta_convex=float(eta_convex), window=window, init=init, max_iter=max_iter,
                  weighting=weighting, assignment=assignment,
                  enforce_connectivity=bool(enforce_connectivity), n_init_centers=n_init)
    return SegmentationResult(labels=final, centers=final_centers, n_iter=n_iter,
                              converged=converged, radius=r, n_orphan_seeds=n_orphans,
                              timings=timings, params=params)


def _centers_of(labels: np.ndarray, old_centers: np.ndarray, areas, centroids) -> np.ndarray:
    """Center of each final label: an old center that kept its label, else the
    face nearest the area-weighted mean."""
    k = int(labels.max()) + 1
    nearest = np.empty(k, dtype=np.int64)
    _kernels.update_centers(labels.astype(np.int32), k, areas, centroids,
                            np.full(k, -1, dtype=np.int64), nearest)
    out = nearest.copy()
    kept = labels[old_centers]
    # the first old center landing in a label wins
    first = np.unique(kept, return_index=True)[1]
    out[kept[first]] = old_centers[first]
    return out
