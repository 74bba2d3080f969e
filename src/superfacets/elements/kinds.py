"""One table of element kinds: every rule of the method that differs by kind.

The method is written once for every kind of element (faces of a triangle or
polygon mesh, mesh vertices, points of a cloud, tetrahedral cells). What
differs between them is either how the element graph is built (the builders
of :mod:`superfacets.elements`, registered by kind in
:mod:`superfacets.elements.builders`) or a rule held here, in one frozen
:class:`ElementKind` per kind. No other module branches on a kind's name
(``tests/elements/test_kinds.py`` fails when one does), so adding a kind is one
builder and one row of :data:`KINDS`.

This module imports nothing of the package: the parameter checks
(:mod:`superfacets.method.params`) read it before any graph exists.

Examples
--------
>>> kind_of("faces").crease, kind_of("points").crease
(0.1, 1.0)
>>> kind_of("cells").dim, kind_of("vertices").singular
(3, 'vertex')
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["ElementKind", "KINDS", "kind_of"]


@dataclass(frozen=True)
class ElementKind:
    """The rules of the method on one kind of element.

    Attributes
    ----------
    name : str
        ``"faces"``, ``"vertices"``, ``"points"`` or ``"cells"`` (the graph's ``kind``).
    singular : str
        One element, in messages: ``"face"``, ``"vertex"``, ..., ``"tetrahedron"``.
    plural : str
        Several, in messages: ``"faces"``, ``"vertices"``, ``"points"``, ``"tetrahedra"``
        (the name, but for cells).
    dim : int
        Dimension of an element's size: 2 (an area, surfaces) or 3 (a volume,
        tetrahedra). The superfacet radius is that of a disc (``A = k pi r^2``,
        paper section 3.1) or of a ball (``V = k 4/3 pi r^3``); the compactness
        metric divides by ``size^((dim - 1) / dim)``; content-sensitive sizes
        scale by ``s^dim``.
    better_method : bool
        Clean-up and split-and-merge on by default (``cleanup=None``,
        ``split_merge=None``) with the paper's weighting: faces and vertices, where
        both lower the error and the compactness; not points, whose error they raise;
        cells unmeasured (``docs/notes/cleanup.md``).
    exact_assignment : bool
        The exact nearest-center classification by default (``assignment=None``)
        with the paper's weighting: vertices and points, where it gives the windows'
        quality in less time (``docs/notes/cleanup.md``,
        ``docs/notes/superpoints-defaults.md``).
    crease : float
        Weight of creases in the clean-up's cut cost, a fraction of ``alpha``
        (:func:`superfacets.method.cleanup.cut_costs`). Faces 0.1; vertices, points and
        cells 1.0: their normals are neighbourhood averages, a crease's angle is
        spread over a few adjacencies (``docs/notes/cleanup.md``).
    smoothness : float
        Weight of the clean-up's data (compactness) term against the boundary
        length: 0.7 on faces, whose swap energies weigh convex folds less, else 0.3.
    band : float
        Half-width of the clean-up's band along each boundary, a fraction of
        ``r``: 0.2 on vertices (the quality of 0.3 in less time), else 0.3.
    swap_eta_convex : float
        Factor of ``eta_convex`` in the split-and-merge swap energies: 0.5 on
        faces (convex folds count half), else 1.
    passes_after : int
        Most passes after the swaps (with ``tol > 0``): 1 on faces, else 2.
    hold_after : float
        How many times ``center_tol * r`` a center must move, in the passes after
        the swaps, to be expanded again: 4 on faces, else 1.
    coarse_min_per_segment : int
        Automatic coarse-to-fine runs where a superfacet holds at least this
        many elements (:func:`superfacets.method.coarse_to_fine.coarse_ratio`) ...
    coarse_per_segment : int
        ... and leaves about this many clusters per superfacet.
    coarse_neighbor_cap : bool
        Clusters of at most ``n_neighbors // 2`` elements (points: no wider than
        the neighbourhood that estimates a normal).
    equal_weight : bool
        The metrics weigh every element alike (vertices, points, cells) rather
        than by its size (faces: by area, as the benchmark's ground truth).
    auto_density : bool
        ``density=None`` looks at the spread of the element sizes
        (:func:`superfacets.elements.density.density_for`): points, whose density may be
        uneven (LiDAR sweeps, RGB-D frames); 0 on the other kinds.
    unit_sizes_in_levels : bool
        In planarity levels (:func:`superfacets.graph.hierarchy.planarity_graph`) each
        element weighs one (points: their size estimates are noisy).
    neighborhood : bool
        The graph is built from a neighbourhood search (``n_neighbors``,
        ``neighbor_radius`` apply and are recorded in the result's parameters).
    cloud : bool
        The elements are the points of a cloud: written as a point PLY, drawn
        as points, with no faces and no scene objects.
    rows : str
        The input's attribute that counts the labels of a run (one per face, per
        vertex, per point of the cloud including invalid ones, per tetrahedron).
    segment_word : str
        What the segments are called in summaries: superfacets (faces and tetrahedra),
        superpoints (vertices and points).
    peak_bytes : int
        A run's peak memory per element with the defaults, the input's own arrays
        included, beyond the interpreter's (:data:`superfacets._runtime.memory.BASE_BYTES`):
        chosen so that the estimate is within 25 % of a new process's peak and at most
        1.2 times it (``benchmarks/memory_check.py``, its table in
        ``docs/benchmarks.md``). A run whose estimate exceeds what the process
        may use is refused before its graph is built
        (:func:`superfacets._runtime.memory.check_memory`).
    tiled_bytes : int or None
        Bytes a tiled run (:func:`superfacets.segment_tiled`) holds for each element of
        the whole input beside one tile's run (its buckets, rows and labels); the memory
        check names tiles only for kinds that have it. None where tiles do not lower the
        peak: a tiled run of a mesh peaks higher than one run
        (``docs/notes/scale-design.md``).
    exact_count : bool
        A run asked for ``n_segments`` returns exactly that many (points, cells): segments made
        beyond it (regions no window reached) are merged, cheapest first
        (:func:`superfacets.method.stages.exact_count`), down to the input's number of
        separate pieces at the least.
    single_weights : bool
        The run's weights per CSR entry are float32 instead of float64 (each computed in
        float64, then rounded; the distances still add up in float64): the largest
        array of a cloud's run, a tenth of a mesh's; the benchmark's error and
        compactness unchanged (``docs/notes/scale-design.md``). ``paper=True`` keeps
        float64 on every kind.
    merge_from : int
        A run with ``merge_from=None`` segments this many times ``k`` superpoints and
        merges them down to ``k``, flat neighbours first (:mod:`superfacets.method.merges`),
        where its superpoints have equal areas (:func:`superfacets.method.rules.merge_from_of`):
        5 on points, whose undersegmentation error it lowers on rooms, airborne tiles and
        the benchmark's sampled clouds (``docs/notes/superpoints-defaults.md``); 1 (off)
        on the other kinds.
    settle_cycles : bool
        Centers that oscillate are held and the passes go on to convergence
        (:mod:`superfacets.method.passes`: a cycle of center lists settled at its pass of
        lowest energy, a center sent back to a recent place held), instead of a cycle
        being jumped over as the paper's passes would run (``paper=True`` keeps the
        jump): points, where cycles stopped a share of the benchmark's sampled clouds
        (``docs/notes/superpoints-defaults.md``).
    face_truth : str
        How a ground truth given per face (the benchmark's) reaches these elements:
        ``"same"`` (faces), ``"vote"`` (vertices: the area-weighted majority of the
        incident faces), ``"sample"`` (points: sampled on the surface, each with its
        face's label), ``""`` (none: cells).
    objects : bool
        The elements are what a scene's objects are made of (faces): a run may
        share ``k`` among the objects (``--per-object``), the objects are named
        in label files, and a coloured copy may be written in any mesh format
        (the other kinds: a coloured PLY).

    Examples
    --------
    >>> k = kind_of("points")
    >>> k.cloud, k.exact_count, k.coarse_min_per_segment, k.segment_word
    (True, True, 1200, 'superpoints')
    """

    name: str
    singular: str
    plural: str = ""
    dim: int = 2
    better_method: bool = False
    exact_assignment: bool = False
    crease: float = 1.0
    smoothness: float = 0.3
    band: float = 0.3
    swap_eta_convex: float = 1.0
    passes_after: int = 2
    hold_after: float = 1.0
    coarse_min_per_segment: int = 4000
    coarse_per_segment: int = 1000
    coarse_neighbor_cap: bool = False
    equal_weight: bool = True
    auto_density: bool = False
    unit_sizes_in_levels: bool = False
    neighborhood: bool = False
    cloud: bool = False
    rows: str = "n_faces"
    segment_word: str = "superpoints"
    objects: bool = False
    face_truth: str = ""
    peak_bytes: int = 215
    tiled_bytes: int | None = None
    exact_count: bool = False
    single_weights: bool = False
    merge_from: int = 1
    settle_cycles: bool = False

    def n_rows(self, data) -> int:
        """Number of labels a run on ``data`` (a mesh, cloud or tetrahedral mesh) returns.

        Examples
        --------
        >>> m = as_mesh(trimesh.creation.box())
        >>> kind_of("faces").n_rows(m), kind_of("vertices").n_rows(m)
        (12, 8)
        """
        return int(getattr(data, self.rows))

    def counted(self, n: int) -> str:
        """``n`` of these elements in words: ``'1 vertex'``, ``'642 vertices'``, ``'2,418
        tetrahedra'``.

        Examples
        --------
        >>> kind_of("vertices").counted(642), kind_of("cells").counted(1)
        ('642 vertices', '1 tetrahedron')
        """
        return f"{n:,} {self.singular if n == 1 else self.noun}"

    @property
    def noun(self) -> str:
        """The elements in the plural, in messages (:attr:`plural`, else the name)."""
        return self.plural or self.name

    @property
    def size_word(self) -> str:
        """``"area"`` or ``"volume"``: what an element's size is."""
        return "volume" if self.dim == 3 else "area"


#: The kinds of element, by name (the rows of the table).
KINDS = {k.name: k for k in (
    ElementKind("faces", "face", better_method=True, crease=0.1, smoothness=0.7,
                swap_eta_convex=0.5, passes_after=1, hold_after=4.0, equal_weight=False,
                segment_word="superfacets", objects=True, single_weights=True, face_truth="same"),
    ElementKind("vertices", "vertex", better_method=True, exact_assignment=True, band=0.2,
                rows="n_vertices", peak_bytes=620, face_truth="vote"),
    ElementKind("points", "point", exact_assignment=True, coarse_min_per_segment=1200,
                coarse_per_segment=400,
                coarse_neighbor_cap=True, auto_density=True, unit_sizes_in_levels=True,
                neighborhood=True, cloud=True, rows="n_total", peak_bytes=220, tiled_bytes=100,
                exact_count=True, single_weights=True, merge_from=5, settle_cycles=True,
                face_truth="sample"),
    ElementKind("cells", "tetrahedron", "tetrahedra", dim=3, rows="n_tets",
                segment_word="superfacets",
                exact_count=True),
)}


def kind_of(name) -> ElementKind:
    """The :class:`ElementKind` named ``name`` (or ``name`` itself if it is one).

    Parameters
    ----------
    name : str or ElementKind
        ``"faces"``, ``"vertices"``, ``"points"`` or ``"cells"``.

    Returns
    -------
    ElementKind

    Raises
    ------
    ValueError
        For an unknown kind, listing the known ones.

    Examples
    --------
    >>> kind_of("vertices").band
    0.2
    """
    if isinstance(name, ElementKind):
        return name
    try:
        return KINDS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown kind of element {name!r}; known: "
                         f"{', '.join(KINDS)}") from None
