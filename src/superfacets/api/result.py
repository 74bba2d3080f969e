"""The result of one run: labels and the details of the run (``SegmentationResult``,
and ``TiledResult`` for a tiled run).

:func:`superfacets.segment` returns it; :func:`superfacets.method.pipeline.pipeline` makes it.
Its :meth:`~SegmentationResult.graph` and :meth:`~SegmentationResult.hierarchy` give
the superfacet graph and coarser levels of the run's superfacets.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._runtime import extras
from ..elements.builders import elements_of, per_element
from ..elements.graph import cached_on
from ..elements.kinds import kind_of
from ..errors import ParameterError
from ..graph import hierarchy
from ..graph.adjacency import superfacet_graph
from ..graph.hierarchy import level_extent_weight, planarity_graph
from ..graph.learning import learning_arrays
from ..inputs.cloud import up_weighted
from ..method.params import DEFAULTS

__all__ = ["SegmentationResult", "TiledResult", "stop_reason", "describe_stop"]

_D = DEFAULTS


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
        True if the run stopped by its rule: the last center update moved no
        center, a pass changed at most ``tol`` of the area, or the passes
        after the split-and-merge swaps were done; False if ``max_iter``
        stopped it.
    mesh_radius : float
        Superfacet radius ``r`` used, in the input's units (the ``radius``
        parameter, ``params['radius']``, is a fraction of the bounding-box
        diagonal; with ``up_weight``, of the cloud it weighs). :meth:`graph` and
        :meth:`learning_graph` are in the input's own units.
    n_orphan_seeds : int
        Centers created on orphan faces over the whole run.
    timings : dict of str to float
        Seconds per stage: ``graph`` (face graph and per-face geometry,
        zero when already cached on the mesh), ``weights``, ``init``,
        ``iterations``, ``connectivity``, ``cleanup`` (with ``cleanup=True``),
        ``total``; and, not times,
        ``expansions`` (Dijkstra expansions run), ``passes``
        (classifications actually run: fewer than ``n_iter`` when a cycle
        was skipped) and ``cycle_period`` (0, or the period of the cycle of
        center sets that was detected).
    params : dict
        The parameters of the run, resolved (``n_segments``, ``radius``,
        ``init``, ...).

    Examples
    --------
    >>> r = segment(trimesh.creation.icosphere(subdivisions=3), 20)
    >>> r.n_segments, r.labels.shape, r.params["elements"], r.mesh_radius > 0
    (20, (1280,), 'faces', True)
    """

    labels: np.ndarray
    centers: np.ndarray
    n_iter: int
    converged: bool
    mesh_radius: float
    n_orphan_seeds: int
    timings: dict = field(default_factory=dict)
    params: dict = field(default_factory=dict)
    #: The input's element graph and the label of each element (not of each row),
    #: for :meth:`graph` and :meth:`hierarchy`.
    elements: object = field(default=None, repr=False, compare=False)
    element_labels: np.ndarray | None = field(default=None, repr=False, compare=False)

    @property
    def n_segments(self) -> int:
        """Number of superfacets ``K`` produced."""
        return int(self.centers.shape[0])

    @property
    def stop_reason(self) -> str:
        """Why the passes stopped: ``'converged'`` (no center moved, or the passes after
        the split-and-merge swaps were done), ``'tolerance'`` (a pass changed at most
        ``tol`` of the area), ``'cycle'`` (the center lists repeated with a period; the
        labels are those of pass ``max_iter``, as running every pass gives) or
        ``'max_iter'`` (:func:`stop_reason`).

        Examples
        --------
        >>> segment(trimesh.creation.icosphere(subdivisions=3), 12).stop_reason
        'tolerance'
        """
        return stop_reason(self)

    def graph(self, features=None):
        """The superfacet (superpoint) adjacency graph of this result.

        Parameters
        ----------
        features : (N, d) float ndarray, optional
            One feature per input row (face, vertex or point, e.g. RGB
            colour); ``feature`` of the graph is its area-weighted mean per
            superfacet (rows that are not elements are left out). Default:
            the input's colours if it has any (a cloud read with RGB), else none.

        Returns
        -------
        SuperfacetGraph
            ``edge_index`` (2, E), ``border_length``, ``mean_angle``,
            ``concave``, ``area``, ``centroid``, ``normal``, ``feature``;
            ``to_scipy()``, ``to_networkx()``, ``save(path)``
            (:mod:`superfacets.graph.adjacency`).

        Raises
        ------
        ParameterError
            If ``features`` does not have one finite row per input row.

        Examples
        --------
        >>> r = segment(trimesh.creation.icosphere(subdivisions=3), 12)
        >>> g = r.graph()
        >>> g.n_segments, g.edge_index.shape[0], bool((g.border_length > 0).all())
        (12, 2, True)
        """

        src, element_labels = self._elements()
        if features is None:
            features = src.colors()
        return superfacet_graph(src.graph, element_labels, per_element(src, features))

    def hierarchy(self, levels, *, beta: float = 0.0, features=None, cost: str = "ward",
                  extent_weight: float | None = None):
        """Nested coarser levels of these superfacets, each segment connected
        (:func:`superfacets.graph.hierarchy.hierarchy`, with this run's ``alpha`` and
        ``eta_convex``).

        Parameters
        ----------
        levels : int or sequence of int
            Numbers of segments of the levels, each at most ``K``.
        beta : float, default 0
            Weight of the feature difference (needs ``features``).
        features : (N, d) float ndarray, optional
            One feature per input row, as :meth:`graph`.
        cost : {'ward', 'planarity'}, default 'ward'
            Compact segments, or flat regions merged first
            (:func:`superfacets.graph.hierarchy.hierarchy`; on a point cloud each point
            weighs one, :func:`~superfacets.graph.hierarchy.planarity_graph`).
        extent_weight : float, optional
            With ``cost='planarity'``, the weight of the segments' extent
            (:func:`superfacets.graph.hierarchy.hierarchy`). Default: left to the
            method, :func:`~superfacets.graph.hierarchy.level_extent_weight` (0.01 on
            a scan of uneven density, else 0).

        Returns
        -------
        Hierarchy
            ``.parents[i]``: the parent of each segment of the level below;
            ``.labels(i, result.labels)``: one label per input row at level ``i``.

        Raises
        ------
        ParameterError
            If a level is out of range.

        Examples
        --------
        >>> r = segment(trimesh.creation.icosphere(subdivisions=4), 40)
        >>> h = r.hierarchy([10, 3])
        >>> [int(h.labels(i, r.labels).max()) + 1 for i in range(2)]
        [10, 3]
        """

        if cost == "planarity":
            src, element_labels = self._elements()
            graph = planarity_graph(src.graph, element_labels, per_element(
                src, src.colors() if features is None else features))
            if extent_weight is None:
                extent_weight = level_extent_weight(src.graph)
        else:
            graph = self.graph(features)
        return hierarchy.hierarchy(graph, levels, alpha=self.params.get("alpha", _D.alpha),
                         eta_convex=self.params.get("eta_convex", _D.eta_convex), beta=beta,
                         cost=cost, extent_weight=extent_weight or 0.0)

    def learning_graph(self, features=None, up=None) -> dict:
        """The superpoint graph in the layout learning pipelines read (PyTorch Geometric):
        ``edge_index`` with each edge in both directions, per superpoint the handcrafted
        features Superpoint Transformer uses (linearity, planarity, scattering,
        verticality, elevation, size, normal, mean colour), per edge its offsets.

        Parameters
        ----------
        features : (N, d) float ndarray, optional
            As :meth:`graph` (default: the input's colours).
        up : (3,) float or {'x', 'y', 'z', '-x', '-y', '-z'}, optional
            The vertical (default: the input's own ``up``, a LAS or E57 scan's z; else z).

        Returns
        -------
        dict of ndarray
            ``x``, ``pos``, ``edge_index`` (2, 2E), ``edge_attr``, ``super_index``,
            ``node_features``, ``edge_features``
            (:func:`superfacets.graph.learning.learning_arrays`).

        Raises
        ------
        ParameterError
            As :meth:`graph`; for an ``up`` that is neither an axis nor 3 finite numbers
            not all zero.

        Examples
        --------
        >>> xyz = np.random.default_rng(0).random((3000, 3)) * (10, 10, 0.01)
        >>> a = segment(xyz, 20).learning_graph()
        >>> names = list(a["node_features"])
        >>> bool(a["x"][:, names.index("scattering")].max() < 0.01)  # flat superpoints
        True
        """

        src, element_labels = self._elements()
        if up is None:
            up = getattr(src.source, "up", None)
        return learning_arrays(self.graph(features), src.graph.positions, element_labels,
                               self.labels, (0.0, 0.0, 1.0) if up is None else up)

    def to_pyg(self, features=None, up=None):
        """The superpoint graph as a ``torch_geometric.data.Data`` (``x``, ``pos``,
        ``edge_index`` in both directions, ``edge_attr``, ``super_index``), for learning
        pipelines; needs torch_geometric (not a dependency of this package).

        Parameters
        ----------
        features, up
            As :meth:`learning_graph`.

        Returns
        -------
        torch_geometric.data.Data

        Raises
        ------
        MissingExtraError
            Without torch_geometric (``pip install torch_geometric``).

        Examples
        --------
        >>> data = result.to_pyg()  # doctest: +SKIP
        >>> data.edge_index.shape  # doctest: +SKIP
        torch.Size([2, 52])
        """

        torch = extras.require("torch", "to_pyg (torch_geometric)")
        pyg = extras.require("torch_geometric.data", "to_pyg")
        a = self.learning_graph(features, up)
        return pyg.Data(**{k: torch.from_numpy(np.ascontiguousarray(a[k])) for k in
                           ("x", "pos", "edge_index", "edge_attr", "super_index")},
                        node_features=list(a["node_features"]),
                        edge_features=list(a["edge_features"]))

    def _source(self):
        if self.elements is None or self.element_labels is None:
            raise ParameterError("this result holds no element graph (made by hand?): use "
                                 "superfacets.graph.adjacency.superfacet_graph(graph, labels)")
        return self.elements

    def _elements(self):
        """The input's elements in its own units and each one's label: the run's, or, where
        the run weighed the up coordinate (``up_weight``), the graph of the cloud as given
        (built once, kept with the run's), so that sizes and positions are the data's."""
        src = self._source()
        weighted = src.source
        weight = (self.params or {}).get("up_weight", 1.0)
        if weight == 1 or not kind_of(src.graph.kind).cloud:
            return src, self.element_labels
        original = weighted.__dict__.get("unweighted")  # (not pickled: unstretched again)
        if original is None:
            original = up_weighted(weighted, 1.0 / weight)

        def build():  # (kept with the run's cloud: shared by the results made from it)
            e = elements_of(original, "points", n_neighbors=self.params.get(
                "n_neighbors", _D.n_neighbors), neighbor_radius=self.params.get(
                "neighbor_radius"), step_weight=self.params.get("step_weight") or 1.0)
            return e, e.first_rows(np.arange(e.graph.n_elements))

        e, rows = cached_on(weighted, "unweighted_elements", build)
        return e, np.asarray(self.labels).reshape(-1)[rows]  # (this result's own labels)


def stop_reason(result) -> str:
    """:attr:`SegmentationResult.stop_reason` of any result with ``converged`` and
    ``timings`` (a joined or adaptive result too).

    Parameters
    ----------
    result : SegmentationResult or a result with ``converged`` and ``timings``

    Returns
    -------
    str
        ``'converged'``, ``'tolerance'``, ``'cycle'`` or ``'max_iter'``.

    Raises
    ------
    AttributeError
        Never: a result without ``timings`` reads as one without a cycle or tolerance.

    Examples
    --------
    >>> stop_reason(segment(trimesh.creation.icosphere(subdivisions=3), 12, paper=True))
    'converged'
    """
    timings = getattr(result, "timings", None) or {}
    if timings.get("stopped_by_tol"):
        return "tolerance"
    if getattr(result, "converged", False):
        return "converged"
    if timings.get("cycle_period"):
        return "cycle"
    return "max_iter"


def describe_stop(result) -> str:
    """The stop in words, for summaries: ``converged: no label changed``, ``converged:
    centers moved less than tol`` (with ``; 3 oscillating centers frozen`` where centers
    that went back and forth were held), ``stopped: the centers oscillate with period 4
    (the labels of pass 50, ...)``, ``stopped at max-iter``.

    Parameters
    ----------
    result : SegmentationResult

    Returns
    -------
    str

    Raises
    ------
    KeyError
        Never for a result of :func:`superfacets.segment`.

    Examples
    --------
    >>> describe_stop(segment(trimesh.creation.icosphere(subdivisions=3), 12, max_iter=1,
    ...                       paper=True))
    'stopped at max-iter'
    """
    reason = stop_reason(result)
    held = int(result.timings.get("settled", 0)) if reason != "max_iter" else 0
    done = {"tolerance": "converged: centers moved less than tol",
            "converged": "converged: no label changed", "max_iter": "stopped at max-iter"}
    if held:  # (a cycle settled: the run went on to converge)
        word = "center" if held == 1 else "centers"
        return done.get(reason, "converged") + f"; {held} oscillating {word} frozen"
    if reason == "cycle":
        period = int(result.timings["cycle_period"])
        return (f"stopped: the centers oscillate with period {period} (the labels of pass "
                f"{result.n_iter}, as running every pass)")
    return done[reason]


@dataclass(frozen=True)
class TiledResult:
    """Labels and details of a tiled run (:func:`~superfacets.scale.tiles.run.segment_tiled`).

    Attributes
    ----------
    labels : (N,) int64 ndarray
        Superfacet of each row of the input (face or point, file order),
        dense ``0..K-1``; -1 for an invalid point.
    centers : (K,) int64 ndarray
        Row of each superfacet's center.
    mesh_radius : float
        The superfacet radius ``r`` of the whole input (its units).
    grid : tuple of int
        Tiles along x, y and z for a regular grid (``tiles=(nx, ny, nz)``);
        ``(N,)`` for ``N`` balanced tiles.
    layout : Tiles
        The tiles' core boxes (:class:`~superfacets.scale.tiles.layout.Tiles`:
        ``layout.of(positions)``, ``layout.box(t)``).
    halo : float
        Width of each tile's halo, in the input's units: ``halo * window * r``, or on a
        cloud sized by ``n_segments`` up to 2 % more (the halo its survey's sample asked
        for, its graphs built once on it).
    disagreements : int
        Elements of the tiles' inner halos (within ``window * r`` of a core)
        whose label in that tile's run differs from the one their own tile
        gave them: 0 means every superfacet reaching a border was seen whole,
        the same way, from both sides.
    repaired : int
        Elements relabelled by the connectivity pass that runs after
        stitching when ``disagreements > 0`` (a superfacet left in pieces by
        two tiles' different borders: each stray piece joins its neighbour,
        :func:`~superfacets.scale.tiles.phases.tile_connect`).
    tiles : list of dict
        Per tile with work: ``tile``, ``core`` and ``rows`` (elements in the
        core, and with the halo), ``centers`` (in its core after the first phase that
        places them: ``centers``, or on a cloud the first ``refine`` round), the
        ``seconds`` and ``peak_mib`` of that phase and of ``labels`` (``centers_seconds``,
        ``labels_peak_mib``, ...), and ``peak_mib``, the larger peak.
    timings : dict of str to float
        Seconds: ``survey``, ``bucket`` (sorting the input into tiles),
        ``orientation`` (points without normals or viewpoint: the survey's
        sample oriented once,
        :func:`~superfacets.scale.tiles.phases.orientation_reference`), ``areas``,
        ``start`` (a cloud's centers found on that sample:
        :func:`~superfacets.scale.tiles.phases.sample_start`), ``centers`` (each tile's, where
        no sample start gave them),
        ``refine``, ``labels``, ``stitch``, ``connect`` (only with disagreements),
        ``merges``, ``levels`` (with ``levels``), ``graph`` (with ``graph``), ``total``.
    params : dict
        The run's parameters, resolved; ``up``: a cloud's up direction (its own or
        ``seen_from``'s unit vector), None where it has none.
    area : float
        The input's total area in its units squared (its faces', or its points' summed
        sizes, as one run's point graph sizes them); NaN where a tiled run does not measure
        it (a cloud sized by ``radius``, or read with ``up_weight``).
    size_spread : float
        The standard deviation of the log sizes of a cloud's points over the tiles' cores
        (:func:`~superfacets.elements.density.size_spread`): above
        :data:`~superfacets.elements.density.AUTO_SPREAD` one run sizes its superpoints by
        the density (``density=None``), which a tiled run does not; NaN where not read (a
        mesh, or a cloud sized by ``radius``).
    hierarchy : Hierarchy or None
        The coarser levels asked for (``segment_tiled(levels=...)``), over these ``K``
        superfacets: ``hierarchy.labels(i, result.labels)`` are level ``i``'s labels per
        row (:func:`~superfacets.scale.tiles.merges.tiled_hierarchy`); None without.
    learning : dict or None
        The superpoint graph in the layout learning pipelines read (``segment_tiled(graph=
        True)``): ``x``, ``pos``, ``edge_index``, ``edge_attr``, ``super_index``, ...
        as :meth:`SegmentationResult.learning_graph`, with ``area``, ``centroid``,
        ``normal`` and ``feature`` (:func:`~superfacets.scale.tiles.merges.
        tiled_learning`); None without.

    Examples
    --------
    >>> m = trimesh.creation.icosphere(subdivisions=4)
    >>> from superfacets import segment_tiled
    >>> r = segment_tiled((m.vertices, m.faces), 40, tiles=2, workers=1)
    >>> r.labels.shape, r.grid, r.disagreements >= 0
    ((5120,), (2,), True)
    """

    labels: np.ndarray
    centers: np.ndarray
    mesh_radius: float
    grid: tuple
    halo: float
    disagreements: int
    repaired: int = 0
    tiles: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    params: dict = field(default_factory=dict)
    layout: object = field(default=None, repr=False)
    area: float = math.nan
    size_spread: float = math.nan
    hierarchy: object = None
    learning: dict | None = None

    @property
    def n_segments(self) -> int:
        """Number of superfacets ``K``."""
        return int(self.centers.shape[0])

    @property
    def halo_ratio(self) -> float:
        """Elements the tiles' boxes hold with their halos over those of their cores
        (``>= 1``; 1.0 without tiles' details): each phase runs over the boxes, so a tiled
        run's work is about this many times one run's. It grows with the tiles and falls
        with the elements per superfacet (the halo is ``halo * window * r`` wide whatever
        the tile's size): fewer tiles, or a larger ``k``, cost less.

        Examples
        --------
        >>> r = TiledResult(np.zeros(4, np.int64), np.zeros(1, np.int64), 1.0, (2,), 0.1, 0,
        ...                 tiles=[dict(core=2, rows=3), dict(core=2, rows=3)])
        >>> r.halo_ratio
        1.5
        """
        core = sum(t.get("core", 0) for t in self.tiles)
        return sum(t.get("rows", 0) for t in self.tiles) / core if core else 1.0

