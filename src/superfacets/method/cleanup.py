"""Boundary clean-up after the iteration: boundaries straightened and moved onto creases.

The paper leaves it as "a priority next step": superfacets are assigned by
distance alone, so their boundaries are stair-stepped along the element
graph and may run a few elements beside a concave crease instead of on it.
:func:`clean_boundaries` re-decides, for each pair of adjacent superfacets,
the elements of a band along their shared boundary by an exact two-label
graph cut (a minimum s-t cut by push-relabel, a compiled kernel) of the energy

``E = sum_f smoothness * a_f * |p_f - mu_{L_f}|^2 / r^2 + sum_{ij cut} r * c_ij``

with ``c_ij`` of :func:`cut_costs` (the border length, cheaper on creases as
the paper's weights make crossing them dearer), ``mu_s`` the area-weighted
mean position of superfacet ``s`` and ``r`` the superfacet radius. Bands of
different pairs are disjoint, so they are cut independently (in parallel, the
result independent of the thread count); a few sweeps recompute the bands;
each superfacet keeps its center, and the connectivity step runs last, so the
number of superfacets is unchanged and each is connected.

``docs/notes/cleanup.md`` has the measurements behind each choice.
"""

from __future__ import annotations

import math

import numpy as np

from .._kernels import native
from .._runtime.memory import give_back_free_memory
from .._runtime.threads import using
from ..elements.builders import as_element_graph
from ..elements.graph import chunked
from ..elements.kinds import kind_of
from ..elements.labels import check_labels, relabel_dense
from ..errors import ParameterError
from .connectivity import enforce_connectivity
from .params import DEFAULTS, check_int, check_nonneg, check_number, check_positive, check_threads
from .passes import final_centers
from .weights import check_features, feature_jumps

__all__ = ["clean_boundaries", "cut_costs",
           "CREASE", "CREASE_SMOOTH_NORMALS", "SMOOTHNESS", "SMOOTHNESS_FACES", "BAND",
           "BAND_VERTICES", "SWEEPS"]

#: The clean-up's weights on faces and elsewhere, from the table of kinds
#: (:mod:`superfacets.elements.kinds`, where each value's measurement is noted):
#: the crease weight in the cut cost, a fraction of ``alpha`` (:func:`cut_costs`) ...
CREASE = kind_of("faces").crease
#: ... the same on vertices and points, whose normals are neighbourhood averages ...
CREASE_SMOOTH_NORMALS = kind_of("vertices").crease
#: ... the weight of the compactness (data) term against the boundary length ...
SMOOTHNESS = kind_of("vertices").smoothness
SMOOTHNESS_FACES = kind_of("faces").smoothness
#: ... and the half-width of the band along each boundary, a fraction of the radius ``r``.
BAND = kind_of("faces").band
BAND_VERTICES = kind_of("vertices").band
#: Most sweeps (bands recomputed, every band cut).
SWEEPS = 1


def cut_costs(graph, *, alpha: float = DEFAULTS.alpha, eta_convex: float = DEFAULTS.eta_convex,
              crease: float = CREASE, features: np.ndarray | None = None,
              beta: float = 0.0, floor: float = 0.0) -> np.ndarray:
    """Cost of a superfacet boundary along each adjacency: its length, less on creases.

    ``c_ij = |e_ij| / (1 + crease * alpha * eta * theta / pi)``, with
    ``theta`` the angle of the two normals (faces: the unsigned dihedral
    angle) and ``eta`` as in the paper's eq. 2 (1 on concave adjacencies,
    ``eta_convex`` on convex ones). ``1 + alpha * eta * theta / pi`` is the
    factor by which the paper's weight (eq. 3) makes crossing a face edge
    dearer than its length alone; ``crease`` tempers it for boundaries (at
    ``crease = 1`` a one-degree fold already halves the cost at
    ``alpha = 200``, and boundaries chase noise: ``docs/notes/cleanup.md``).

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    alpha, eta_convex : float
        The method's (``>= 0``).
    crease : float, default 0.1
        ``>= 0``; 0 weighs every boundary by its length alone.
    features : (n, d) float ndarray, optional
    beta, floor : float, default 0
        The feature term of the weights (:func:`~superfacets.method.weights.paper_weights`):
        with ``beta > 0`` a feature jump (``||f_i - f_j||`` beyond ``floor``:
        :func:`~superfacets.method.weights.feature_jumps`) lowers the cost as
        the crease does, ``c_ij = |e_ij| / (1 + crease * (alpha * eta * theta
        / pi + beta * jump))``.

    Returns
    -------
    (e,) float64 ndarray
        One cost per adjacency (``graph.pairs`` order), in mesh units,
        ``0 <= c_ij <= |e_ij|``.

    Raises
    ------
    ParameterError
        If a factor is negative or not finite.

    Examples
    --------
    >>> g = face_graph(as_mesh(trimesh.creation.box()))
    >>> bool(np.allclose(cut_costs(g, alpha=0), g.lengths))   # no crease: the lengths
    True
    >>> bool((cut_costs(g) < g.lengths).any())                # the box's folds are cheaper
    True
    """
    alpha = check_nonneg("alpha", alpha)
    eta_convex = check_nonneg("eta_convex", eta_convex)
    crease = check_nonneg("crease", crease)
    beta = check_nonneg("beta", beta)
    g = as_element_graph(graph)
    t = g.terms
    g.lengths, g.pairs  # noqa: B018 (made here if released: the chunks run on threads)
    factor = crease * alpha / np.pi
    f = None
    if beta > 0:
        f = check_features(features, g)

    def cost(sl):
        eta = np.where(t.concave[sl], 1.0, eta_convex)
        if f is None:
            return g.lengths[sl] / (1.0 + factor * eta * np.arccos(t.cos[sl]))
        jump = feature_jumps(f, g.pairs[sl], floor)
        return g.lengths[sl] / (1.0 + factor * eta * np.arccos(t.cos[sl])
                                + crease * beta * jump)

    return chunked(g.n_edges, cost)


def _checked_centers(labels, centers, sizes, positions) -> np.ndarray:
    """The centers given (one element of each superfacet, in label order: checked), or
    each superfacet's element nearest its mean position."""

    k, n = int(labels.max()) + 1, labels.shape[0]
    if centers is None:
        return final_centers(labels, np.empty(0, dtype=np.int64), sizes, positions)
    centers = np.asarray(centers)
    if (centers.shape != (k,) or not np.issubdtype(centers.dtype, np.integer)
            or centers.min() < 0 or centers.max() >= n
            or not np.array_equal(labels[centers], np.arange(k))):
        raise ParameterError(f"centers must hold one element of each of the {k} superfacets, "
                             "in label order")
    return centers


def _cut_costs_per_entry(g, alpha, eta_convex, crease, features, beta, r,
                         floor: float = 0.0) -> np.ndarray:
    """The cost of cutting each CSR entry's adjacency, times the radius ``r``."""
    if beta > 0:
        return np.ascontiguousarray(
            cut_costs(g, alpha=alpha, eta_convex=eta_convex, crease=crease, features=features,
                      beta=beta, floor=floor)[g.dual_edge] * r)
    cut_costs_csr = native.kernel("terms.cut_costs_csr")  # the same values, in one pass

    t = g.terms
    return cut_costs_csr(g.dual_edge, t.concave, t.cos, g.lengths, crease * alpha / np.pi,
                         eta_convex, r)


def _means(labels, sizes, positions, k: int) -> np.ndarray:
    """The superfacets' area-weighted mean positions, in one compiled pass (each sum
    added in element order, as np.bincount adds them)."""
    label_sums = native.kernel("geometry.label_sums")

    area, means, spare = np.zeros(k), np.zeros((k, 3)), np.zeros((k, 3))
    label_sums(labels, sizes, positions, positions, area, means, spare)
    area = np.maximum(area, 1e-300)
    means /= area[:, None]
    return means


def _band_members(g, labels, pinned, width: float, dirty, k: int):
    """The elements within ``width`` of a boundary (along the graph, inside their
    superfacet; with ``dirty``, only the bands of superfacets that changed), grouped by
    band as :func:`_bands` gives them; None where there are none. (Each work array is let
    go as soon as read: a run's clean-up peaks here.)"""
    band_distances = native.kernel("cleanup.band_distances")

    n = g.n_elements
    heap = g.indices.shape[0] + n + 1
    partner = np.empty(n, dtype=np.int64)
    band_distances(g.indptr, g.indices, g.dual_edge, g.terms.geo, g.lengths, labels,
                   pinned, width, np.empty(n), partner, np.empty(heap),
                   np.empty(heap, dtype=np.int64))
    members = np.flatnonzero(partner >= 0)
    if dirty is not None:  # later sweeps: only bands of superfacets that changed
        members = members[dirty[labels[members]] | dirty[partner[members]]]
    if members.size == 0:
        return None
    return _bands(members, labels, partner, k)


def _bands(members, labels, partner, k: int):
    """The band elements ``members`` grouped by the pair of superfacets they lie between
    (sorted by the pair, stably): the members, where each band starts, and each band's
    pair as ``lo * k + hi``."""
    key = np.minimum(labels[members], partner[members])
    key *= k
    key += np.maximum(labels[members], partner[members])
    o = np.argsort(key, kind="stable")
    key = key[o]
    members = members[o]
    del o
    starts = np.concatenate([[0], np.flatnonzero(np.diff(key)) + 1, [key.size]])
    return members, starts, key[starts[:-1]]


def clean_boundaries(graph, labels, centers=None, *, alpha: float = DEFAULTS.alpha,
                     eta_convex: float = DEFAULTS.eta_convex, radius: float | None = None,
                     crease: float | None = None, smoothness: float | None = None,
                     band: float | None = None, sweeps: int = SWEEPS,
                     connectivity: bool = True, n_threads: int | None = None,
                     features: np.ndarray | None = None, beta: float = 0.0,
                     floor: float = 0.0, bands_found=None) -> np.ndarray:
    """Straighten superfacet boundaries and move them onto nearby creases.

    For every pair of adjacent superfacets, the elements within ``band * r``
    of their shared boundary (along the graph, inside each superfacet) are
    relabelled between the two by a minimum cut of the energy in the module
    notes; up to ``sweeps`` rounds, stopping early when nothing changes.
    Then every superfacet is made connected
    (:func:`~superfacets.method.connectivity.enforce_connectivity`).

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
        Faces, vertices or points: only the graph's adjacency, sizes,
        positions, normals and border lengths are used.
    labels : (n,) int ndarray
        Superfacet of each element, ``0..K-1`` (e.g. the paper's labels).
    centers : (K,) int ndarray, optional
        An element of each superfacet that keeps its label (the method's
        centers). Default: the element nearest each superfacet's
        area-weighted mean.
    alpha, eta_convex : float
        The method's weights (eqs. 2-3), ``>= 0``: creases are found as the
        method finds them.
    radius : float, optional
        Superfacet radius ``r`` in mesh units (``> 0``); default
        ``sqrt(A / (K pi))`` (paper section 3.1).
    crease : float, optional
        Weight of creases in the boundary cost (:func:`cut_costs`); default
        the graph's kind's ``crease`` (:mod:`superfacets.elements.kinds`: 0.1 on faces,
        1.0 on vertices and points).
    smoothness : float, optional
        Weight of the data term (squared distance to the superfacet's mean
        position, in units of ``r^2``) against the boundary length, ``>= 0``;
        default the graph's kind's ``smoothness`` (0.7 on faces, 0.3 elsewhere).
    band : float, optional
        Half-width of each band, a fraction of ``r`` (``> 0``): no boundary
        moves farther; default the graph's kind's ``band`` (0.3, 0.2 on
        vertices).
    sweeps : int, default 1
        Most rounds (``>= 0``; 0 changes nothing but the connectivity).
    connectivity : bool, default True
        Make every superfacet connected at the end (a cut can split one).
    n_threads : int, optional
        Threads cutting bands at once (default: as :func:`superfacets.segment`);
        the labels do not depend on it.
    features, beta, floor
        The feature term (:func:`cut_costs`); ``beta = 0`` (default) ignores features.
    bands_found : callable, optional
        Called (no arguments) once the last sweep's bands are found: from then on the
        graph's terms, border lengths and dual-edge map are not read (a run forgets
        them there on a large graph: :meth:`superfacets.method.pipeline.Hooks.before`).

    Returns
    -------
    labels : (n,) int64 ndarray
        Dense ``0..K-1``, the same ``K``: no superfacet is lost (each keeps
        its center), each is connected (with ``connectivity``), deterministic
        and the same for any thread count.

    Raises
    ------
    ParameterError
        If ``labels`` or ``centers`` do not fit the graph, or a parameter
        is out of range.

    References
    ----------
    Simari, Picciau, De Floriani, "Fast and Scalable Mesh Superfacets", 2014,
    section 6 (clean-up as future work), eqs. 2-3 (the crease factor).
    Boykov, Veksler, Zabih, "Fast approximate energy minimization via graph
    cuts", PAMI 2001 (two-label moves solved as minimum cuts). Goldberg, Tarjan, "A new
    approach to the maximum-flow problem", J. ACM 1988 (push-relabel).
    ``docs/notes/cleanup.md``.

    Examples
    --------
    >>> mesh = trimesh.creation.icosphere(subdivisions=4)
    >>> r = segment(mesh, 30, cleanup=False)
    >>> clean = clean_boundaries((mesh.vertices, mesh.faces), r.labels, r.centers)
    >>> int(clean.max()) + 1
    30
    """
    solve_bands = native.kernel("cleanup.solve_bands")

    g = as_element_graph(graph)
    labels = relabel_dense(check_labels(labels, g.n_elements, per=g.element))
    crease = kind_of(g.kind).crease if crease is None else crease
    alpha, eta_convex = check_nonneg("alpha", alpha), check_nonneg("eta_convex", eta_convex)
    smoothness = check_nonneg("smoothness",
                              kind_of(g.kind).smoothness if smoothness is None else smoothness)
    band = check_positive("band", kind_of(g.kind).band if band is None else band)
    sweeps, n_threads = check_int("sweeps", sweeps, lo=0), check_threads(n_threads)
    k = int(labels.max()) + 1
    n = g.n_elements
    if radius is None:
        radius = math.sqrt(g.area / (k * math.pi)) if g.area > 0 else g.diagonal
    r = check_number("radius", radius, 0.0, lo_open=True)
    sizes = np.ascontiguousarray(g.sizes, dtype=np.float64)
    positions = np.ascontiguousarray(g.positions, dtype=np.float64)
    centers = _checked_centers(labels, centers, sizes, positions)
    # ties (a band's partner, a cut's side) go by label: number the superfacets by
    # their centers, so that the result depends on the partition and the centers alone
    # (a tiled run numbers them otherwise), and give the caller's numbers back at the end
    labels, centers, order = _numbered_by_centers(labels, centers)
    pinned = np.zeros(n, dtype=np.bool_)
    pinned[centers] = True
    cost_of = (alpha, eta_convex, check_nonneg("crease", crease), features,
               check_nonneg("beta", beta), r, check_nonneg("floor", floor))
    cut_csr = None  # (made once the first bands are found: not held while they are)
    smooth = smoothness / (r * r)
    dirty = None
    for sweep in range(sweeps):
        means = _means(labels, sizes, positions, k)
        found = _band_members(g, labels, pinned, band * r, dirty, k)
        if found is None:
            break
        members, starts, pair = found
        del found
        if cut_csr is None:
            if bands_found is not None:  # (a large graph: the bands' freed temporaries
                give_back_free_memory()  # handed back before the costs are made)
            cut_csr = _cut_costs_per_entry(g, *cost_of)
        if bands_found is not None and sweep == sweeps - 1:
            bands_found()
        band_of = np.full(n, -1, dtype=np.int64)
        band_of[members] = np.repeat(np.arange(starts.size - 1), np.diff(starts))
        out = labels.copy()
        args = (members, starts.astype(np.int64), pair // k, pair % k, band_of, g.indptr,
                g.indices, cut_csr, labels, sizes, positions, means, smooth, out)

        with using(n_threads):  # (the kernel takes the bands in turn on threads)
            solve_bands(0, starts.size - 1, *args)
        del args, band_of, members
        moved = np.flatnonzero(out != labels)
        if moved.size == 0:
            break
        dirty = np.zeros(k, dtype=bool)
        dirty[labels[moved]] = True
        dirty[out[moved]] = True
        labels = out
        del out, moved
    partner = cut_csr = pinned = None  # noqa: F841
    if connectivity:  # every superfacet keeps its center's piece: the same numbers
        labels = enforce_connectivity(g, labels, centers)
    # the caller's numbers back; a piece with no neighbour became a superfacet of its
    # own, numbered from k on, and keeps its number
    apart = labels >= k
    out = order.take(labels, mode="clip")
    out[apart] = labels[apart]
    return out


def _numbered_by_centers(labels, centers):
    """The superfacets numbered by their centers (ascending): the labels and centers so
    numbered, and the caller's number of each (``order``)."""
    k = centers.shape[0]
    order = np.argsort(centers, kind="stable").astype(np.int64)
    rank = np.empty(k, dtype=np.int64)
    rank[order] = np.arange(k)
    return rank[labels], centers[order].astype(np.int64), order
