"""The compiled kernels (``superfacets._kernels._cxx``) against the numba kernels, bit for bit.

Every call a run makes to a compiled kernel is made again to the numba kernel of the
same name on copies of its arguments: the outputs, and every array either updates in
place, must be the same bytes. The runs cover every compiled kernel (asserted), on
triangles and polygons, closed and open meshes, small and large ``m k`` (the plain and
the blocked farthest-point sampling), the default (clean-up, split-and-merge) and the
paper's run, content-sensitive windows. One thread: calls on threads share arrays, so
the copies of one call would see another's writes.
"""

from __future__ import annotations

import hashlib
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from oracle import reference

import superfacets
from superfacets import Mesh
from superfacets._kernels import native
from superfacets.inputs.shapes import creature


def _implementation(which: str):
    """The compiled kernel (``"kernel"``) or its numba reference (``"reference"``)."""
    from superfacets._kernels import native

    return native.kernel if which == "kernel" else reference

CXX = Path(native.__file__).parent / "cxx"


def test_the_compiled_kernels_are_built_from_these_sources():
    """The extension is required (an install stops without a C++ compiler), and an
    editable install not rebuilt after a change to the sources would test old kernels:
    where the sources are at hand, the module was built from them."""
    assert native.available(), native.missing_because()
    if CXX.is_dir():  # a checkout: the module was built from these sources
        # as CMakeLists.txt hashes them: "name sha256" lines in name order
        paths = sorted([*CXX.glob("*.cpp"), *CXX.glob("*.hpp")], key=lambda p: p.name)
        listing = "".join(f"{p.name} {hashlib.sha256(p.read_bytes()).hexdigest()}\n"
                          for p in paths)
        assert native.sources_digest() == hashlib.sha256(listing.encode()).hexdigest(), \
            "the compiled kernels are older than their sources: pip install -e . again"


needs_cxx = pytest.mark.skipif(not native.available(),
                               reason="the compiled kernels are not built here")


#: The compiled kernels off the default path (tested in the options' and baselines' test)
OPTION_KERNELS = {"flood", "felzenszwalb", "csr_covariances", "vsa_partition", "vsa_sums",
                  "vsa_assess", "vsa_worst_faces"}

#: The compiled kernels of the point graph's build (the others serve faces and points)
POINT_KERNELS = {"knn_csr", "pca_normals", "pca_linearity", "propagate_signs",
                 "turn_outwards", "local_morton_keys", "distinct_in_order",
                 "order_ties",
                 "point_terms_csr", "point_terms", "combine_weights", "feature_weights_csr",
                 "step_terms_csr",
                 "neighbour_mean",
                 "crossing_pairs", "label_pair_sums", "label_sums", "label_scatter",
                 "tree_nodes", "closest_in_tree",
                 "nearest_in_tree", "sort_keys", "rows_apart", "neighbourhood_moments",
                 "extreme_eigenvalues", "label_pairs"}
#: Those of the vertex graph and of the exact assignment (the default on vertices)
VERTEX_KERNELS = {"vertex_cells", "mesh_edges", "classify_exact", "reclassify_exact"}
#: Those used on large inputs alone (numpy's own below 65,536 rows): tested on their own
LARGE_KERNELS = {"column_bounds", "finite_rows", "gather", "border_shares", "key_window",
                 "column_means", "nearest_row"}


#: Scratch arguments of the numba kernels that the compiled ones do not use (their heaps
#: keep each key beside its value, in an array of their own; the exact assignment's and
#: the Voronoi cells' searches keep a queue per block): not compared.
SCRATCH = {"cleanup.band_distances": {10, 11}, "splitmerge.energies": {14, 15},
           "splitmerge.split_candidates": {19, 20}, "splitmerge.merge_energies": {19, 20},
           "exact.classify_exact": {7, 8}, "exact.reclassify_exact": {7, 8},
           "voronoi.nearest_seed": {7}, "expand.classify_bounded": {9},
           "expand.seed_orphans": {9}, "expand.expand_many": {7}, "expand.flood": {7}}

def _roomy_queue(args):
    """The exact assignment's arguments with a node pool numba's search cannot outgrow (the
    run passes the compiled search, which keeps its own queues, a small one)."""
    indices, dist = args[1], args[5]
    cap = indices.shape[0] + 2 * dist.shape[0] + 1
    args[7] = (np.empty(cap, args[7][0].dtype), np.empty(cap), np.empty(cap, np.int64),
               args[7][3])
    args[8] = np.empty(cap, args[8].dtype)
    return args


def _dense_scratch(at: int):
    """The expansions' arguments with the dense scratch (one zero per element) the numba
    kernels keep their distances in, at ``at`` (the run gives none: the compiled
    expansions keep a table of their own)."""
    def given(args):
        args[at] = np.zeros(args[0].shape[0] - 1)
        return args
    return given


#: Arguments the numba kernel is given in place of the run's.
FOR_REFERENCE = {"exact.classify_exact": _roomy_queue, "exact.reclassify_exact": _roomy_queue,
                 "expand.classify_bounded": _dense_scratch(9),
                 "expand.seed_orphans": _dense_scratch(9),
                 "expand.expand_many": _dense_scratch(7), "expand.flood": _dense_scratch(7)}

#: Results of which only a part is defined: compared on that part. knn_csr returns a
#: buffer whose first ``indptr[n]`` entries are the indices (``indptr``: argument 2).
DEFINED = {"adjacency.knn_csr": lambda result, args: result[:args[2][-1]]}


def _copy(x):
    if isinstance(x, np.ndarray):
        return x.copy()
    if isinstance(x, tuple):
        return tuple(_copy(y) for y in x)
    return x


def _same(a, b) -> bool:
    if isinstance(a, np.ndarray):
        return (isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape
                and a.tobytes() == b.tobytes())
    if isinstance(a, tuple):
        return isinstance(b, tuple) and len(a) == len(b) and all(map(_same, a, b))
    return a == b


@pytest.fixture
def shadowed(monkeypatch):
    """Every compiled-kernel call checked against numba's; yields the calls made."""
    calls: dict[str, int] = {}
    bad: list[str] = []
    plain = native.kernel

    def kernel(path):
        fast, ref = plain(path), reference(path)

        def both(*args, **kwargs):
            a2, k2 = [_copy(a) for a in args], {k: _copy(v) for k, v in kwargs.items()}
            if path in FOR_REFERENCE:
                a2 = FOR_REFERENCE[path](a2)
            expected = ref(*a2, **k2)
            got = fast(*args, **kwargs)
            calls[path] = calls.get(path, 0) + 1
            moved = [i for i, (x, y) in enumerate(zip(args, a2))
                     if i not in SCRATCH.get(path, ()) and not _same(x, y)]
            part = DEFINED.get(path)
            same = (_same(part(got, args), part(expected, a2)) if part
                    else _same(got, expected))
            if not same or moved:
                bad.append(f"{path}: result {'differs' if not same else 'same'}"
                           f", arguments {moved} differ")
            return got
        return both

    monkeypatch.setattr(native, "kernel", kernel)
    yield calls, bad
    assert not bad, bad


@needs_cxx
def test_options_and_baselines_give_numba_results_call_by_call(shadowed):
    """The kernels off the default path, compiled too: the flood initialization (faces
    and points), the graph segmentation (the Segmentator's method), the features of cut
    pursuit and VSA (both metrics, with region insertion), each call numba's to the bit."""
    from superfacets.evaluation.baselines.cut_pursuit import dimensionality_features
    from superfacets.evaluation.baselines.graph_segmentation import graph_segmentation
    from superfacets.evaluation.baselines.vsa import vsa

    calls, _ = shadowed
    mesh = creature(24)
    superfacets.segment(mesh, None, radius=0.08, init="flood", n_threads=1)
    superfacets.segment(mesh.centroids, None, radius=0.08, init="flood", n_threads=1)
    graph_segmentation(mesh, n_segments=30)
    for metric in ("l21", "l2"):
        vsa(mesh, 12, metric=metric, init="incremental", rng=0)
    from superfacets.elements.builders import elements_of

    dimensionality_features(elements_of(mesh.centroids, "points").graph)
    assert {"expand.flood", "baselines.felzenszwalb", "baselines.csr_covariances",
            "baselines.vsa_partition", "baselines.vsa_sums", "baselines.vsa_assess",
            "baselines.vsa_worst_faces"} <= set(calls), calls


def _quad_cube(n: int) -> Mesh:
    """A cube's surface in ``6 n^2`` quads (a polygon mesh)."""
    g = np.linspace(-1.0, 1.0, n + 1)
    verts, faces = [], []
    for axis in range(3):
        for side in (-1.0, 1.0):
            base = len(verts)
            for i in range(n + 1):
                for j in range(n + 1):
                    p = [0.0, 0.0, 0.0]
                    p[axis], p[(axis + 1) % 3], p[(axis + 2) % 3] = side, g[i], g[j]
                    verts.append(p)
            for i in range(n):
                for j in range(n):
                    a = base + i * (n + 1) + j
                    q = [a, a + n + 1, a + n + 2, a + 1]
                    faces.append(q if side > 0 else q[::-1])
    v = np.asarray(verts)
    _, first, inverse = np.unique(v.round(9), axis=0, return_index=True, return_inverse=True)
    return Mesh(v[first], [[int(inverse.ravel()[c]) for c in f] for f in faces])


@needs_cxx
def test_runs_on_faces_give_numba_results_call_by_call(shadowed):
    calls, _ = shadowed
    big = creature(40)
    small = creature(20)
    half = big.faces[big.centroids[:, 2] > np.median(big.centroids[:, 2])]
    used = np.unique(half)
    remap = np.full(big.n_vertices, -1)
    remap[used] = np.arange(used.shape[0])
    open_mesh = Mesh(big.vertices[used], remap[half])  # a boundary: open-boundary edges
    runs = [
        (big, 120, {}),
        (small, 12, {}),  # m k small: the plain farthest-point sampling
        (open_mesh, 60, {}),
        (big, 80, {"cleanup": False, "split_merge": False}),  # the paper's run
        (big, 60, {"roughness": 1.0}),  # content-sensitive windows and sampling
        (_quad_cube(12), 40, {}),  # polygons: their own half-edges and geometry
        (creature(58), 4, {}),  # 5,500 faces per superfacet: coarse-to-fine (Voronoi cells)
    ]
    for mesh, k, params in runs:
        r = superfacets.segment(mesh, k, n_threads=1, **params)
        assert r.labels.shape[0] == mesh.n_faces
    compiled = {name for name in dir(native._cxx)
                if callable(getattr(native._cxx, name)) and not name.startswith("_")} - {
        "Mismatch", "OutOfRange", "set_thread_limit", "threads", "Interrupted",
        "interrupt"}  # (below)
    compiled -= POINT_KERNELS | VERTEX_KERNELS | LARGE_KERNELS | OPTION_KERNELS
    missing = {name for name in compiled if not any(p.endswith("." + name) for p in calls)}
    # run only on several threads, by the plain replay-less classifier, by a lazy graph's
    # rebuild (a coarse graph's lengths too), by hierarchies and the exact count on
    # points: tested below
    assert missing <= {"classify_bounded", "number_pairs", "merge_levels", "coarse_lengths"}, \
        missing


@needs_cxx
def test_swap_searches_by_buckets_give_numba_distances_under_any_weights(shadowed):
    """The swaps' energies and split candidates search by a circular bucket queue: the
    same distances, stamps, energies and splits as numba's heap, call by call, under
    weights spread over six orders of magnitude (entries landing thousands of buckets
    ahead, around the circle many times) and with zero weights (ties everywhere)."""
    from superfacets.elements import face_graph
    from superfacets.method.splitmerge import swap_round

    calls, _ = shadowed
    mesh = creature(30)
    g = face_graph(mesh)
    labels = superfacets.segment(mesh, 40, n_threads=1).labels
    rng = np.random.default_rng(4)
    for pair_w in (np.exp(rng.normal(0.0, 3.0, g.n_edges)),
                   np.where(rng.random(g.n_edges) < 0.3, 0.0, rng.random(g.n_edges))):
        w = np.ascontiguousarray(pair_w[g.dual_edge])
        new, _ = swap_round(g, w, labels, n_threads=1, pruned=False)
        assert new.shape == labels.shape
    assert calls["splitmerge.energies"] >= 2 and calls["splitmerge.split_candidates"] >= 2


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "3"])
def test_clean_up_bands_taken_in_turn_on_threads_give_numba_labels(shadowed, monkeypatch,
                                                                   threads):
    """The clean-up's cuts, its bands taken by the threads in turn (largest first), give
    numba's labels call by call: a sphere of 81,920 faces in 300 superfacets, tens of
    thousands of faces in its bands (several bands a thread)."""
    import trimesh

    from superfacets.method.cleanup import clean_boundaries

    calls, _ = shadowed
    ball = trimesh.creation.icosphere(subdivisions=6)
    mesh = Mesh(ball.vertices * [1.0, 1.3, 0.8], ball.faces)
    r = superfacets.segment(mesh, 300, cleanup=False, n_threads=1)
    clean_boundaries(mesh, r.labels, r.centers, n_threads=1)  # (numba's kernels compiled)
    with monkeypatch.context() as mp:  # (the compiled kernels alone read it)
        mp.setenv("SUPERFACETS_KERNEL_THREADS", threads)
        labels = clean_boundaries(mesh, r.labels, r.centers, n_threads=int(threads))
    assert calls["cleanup.solve_bands"] >= 1
    assert labels.shape == r.labels.shape and (labels != r.labels).any()


def _sampled(mesh: Mesh, n: int, seed: int) -> np.ndarray:
    """``n`` points drawn uniformly on the surface of ``mesh``."""
    rng = np.random.default_rng(seed)
    tri = mesh.vertices[mesh.faces]
    idx = rng.choice(mesh.n_faces, n, p=mesh.areas / mesh.areas.sum())
    u, v = rng.random((2, n))
    s = np.sqrt(u)
    return ((1 - s)[:, None] * tri[idx, 0] + (s * (1 - v))[:, None] * tri[idx, 1]
            + (s * v)[:, None] * tri[idx, 2])


@needs_cxx
def test_runs_on_points_give_numba_results_call_by_call(shadowed):
    calls, _ = shadowed
    body = creature(30)
    p = _sampled(body, 20_000, 1)
    dup = np.r_[p, p[:500]]  # repeated positions: merged into distinct points first
    uneven = np.r_[_sampled(body, 4_000, 2), p[p[:, 0] > np.median(p[:, 0])]]
    apart = np.r_[p[:6000], p[:6000] + [50.0, 0, 0]]  # two pieces
    from superfacets.inputs.cloud import as_cloud

    runs = [(p, 60, None, {}), (dup, 40, None, {}), (uneven, 50, None, {}),
            (p, 8, None, {"merge_from": 1}),  # 2,500 points per superpoint: coarse-to-fine
            (apart, 30, None, {}),  # two pieces
            # the paper's windows (the exact search is the default), small: orphans, the
            # exact count's merges
            (p, 60, None, {"window": 1.0, "assignment": "bounded"}),
            (p, 60, None, {"roughness": 1.0}),  # content-sensitive: neighbour averages
            (p, 40, None, {"neighbor_radius": 0.01}),  # neighbours masked by a radius
            (p[:8000], 30, np.tile([0.0, 0.0, 1.0], (8000, 1)), {}),  # normals given
            # colours, the default's colour term: the weights' feature kernel
            (p, 40, None, {"features": np.c_[p[:, :1] > 0, p[:, 1:] > 0] * 0.5}),
            (p, 40, None, {"step_weight": 4.0})]  # a scene's: steps off the surface
    for pts, k, normals, params in runs:
        r = superfacets.segment(as_cloud(pts, normals), k, n_threads=1, **params)
        assert r.labels.shape[0] == pts.shape[0] and r.labels.max() + 1 == k
    assert r.graph().n_segments == 40  # the superpoint graph: its crossing pairs listed
    # normals turned like an oriented sample (a tile's): the nearest sample point
    ref = superfacets.segment(as_cloud(p[::9]), 10, n_threads=1).elements.graph
    superfacets.segment(superfacets.PointCloud(p[:5000], orient_like=(
        np.array(ref.positions), np.array(ref.normals, dtype=np.float64))), 20, n_threads=1)
    # a cloud that alone holds its points (as one read from a file) lends them to its graph
    r = superfacets.segment(as_cloud(dup.copy()), 40, n_threads=1)
    assert r.labels.shape[0] == dup.shape[0]
    missing = {name for name in POINT_KERNELS | {"expand_many", "nearest_seed", "coarse_pairs",
                                                 "merge_levels"}
               if not any(path.endswith("." + name) for path in calls)}
    assert not missing, missing


@needs_cxx
def test_runs_on_vertices_give_numba_results_call_by_call(shadowed):
    calls, _ = shadowed
    body = creature(30)
    half = body.faces[body.centroids[:, 2] > np.median(body.centroids[:, 2])]
    used = np.unique(half)
    remap = np.full(body.n_vertices, -1)
    remap[used] = np.arange(used.shape[0])
    for mesh, k in ((body, 60), (Mesh(body.vertices[used], remap[half]), 30),
                    (_quad_cube(12), 40)):
        r = superfacets.segment(mesh, k, n_threads=1, elements="vertices")
        assert r.labels.shape[0] == mesh.n_vertices
    missing = {name for name in VERTEX_KERNELS if not any(p.endswith("." + name) for p in calls)}
    assert not missing, missing


@needs_cxx
@pytest.mark.parametrize("params", [{}, {"cost": "planarity", "extent_weight": 0.5},
                                    {"beta": 1.0}])
def test_hierarchies_give_numba_results(shadowed, params):
    calls, _ = shadowed
    from superfacets.elements import face_graph
    from superfacets.graph.adjacency import superfacet_graph
    from superfacets.graph.hierarchy import hierarchy

    mesh = creature(30)
    labels = superfacets.segment(mesh, 60, n_threads=1).labels
    feats = np.c_[mesh.centroids[:, 2], mesh.normals[:, 0]] if params.get("beta") else None
    sg = superfacet_graph(face_graph(mesh), labels, feats)
    h = hierarchy(sg, [40, 20, 5], **params)
    assert h.levels == (40, 20, 5) and "hierarchy.merge_levels" in calls


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "2", "3", "5"])
def test_sorted_keys_are_the_stable_argsort_on_any_thread_count(monkeypatch, threads):
    """Known answer: the compiled sort (runs sorted by radix on threads, merged two by two
    at equal output places) is numpy's stable argsort, equal keys in row order: many ties,
    keys sharing digits (skipped passes), an odd number of runs to merge."""
    rng = np.random.default_rng(5)
    n = 300_007
    for keys in (rng.integers(0, 2**64 - 1, n, dtype=np.uint64),
                 rng.integers(0, 40, n).astype(np.uint64) << np.uint64(20),
                 np.full(n, 7, dtype=np.uint64), np.arange(n, 0, -1, dtype=np.uint64)):
        expected = np.argsort(keys, kind="stable")
        ref_order, ref_sorted = np.empty(n, dtype=np.int64), np.empty_like(keys)
        reference("geometry.sort_keys")(keys, ref_order, ref_sorted)
        order, ordered = np.empty(n, dtype=np.int64), np.empty_like(keys)
        with monkeypatch.context() as m:  # (numba, above, compiled with its own count)
            m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
            native.kernel("geometry.sort_keys")(keys, order, ordered)
        assert np.array_equal(order, expected) and np.array_equal(ref_order, expected)
        assert np.array_equal(ordered, keys[expected]) and np.array_equal(ref_sorted, ordered)


@needs_cxx
@pytest.mark.parametrize("index_dtype", [np.int32, np.int64])
def test_rows_apart_match_numba_and_stop_at_their_room(monkeypatch, index_dtype):
    """Known answer: the rows whose distinct point does not give back their bits (an
    invalid row, -0.0 for 0.0), ascending, found on threads; past the room, -1 and the
    first rows that fit (the compiled and the numba kernel write the same bytes)."""
    rng = np.random.default_rng(8)
    n = 100_000
    pts = rng.random((n, 3))
    index = rng.permutation(n).astype(index_dtype)
    at = np.empty_like(pts)
    at[index] = pts
    odd = np.sort(rng.choice(n, 900, replace=False))
    index[odd[:300]] = -1
    pts[odd[300:], 1] = 0.0
    at[index[odd[300:]], 1] = -0.0
    for room in (n, 900, 899, 0):
        outs = []
        for fn in ("kernel", "reference"):
            rows = np.full(room, -7, dtype=np.int64)
            with monkeypatch.context() as m:
                if fn == "kernel":
                    m.setenv("SUPERFACETS_KERNEL_THREADS", "3")
                got = _implementation(fn)("geometry.rows_apart")(
                    pts.view(np.uint64), at.view(np.uint64), index, rows)
            outs.append((got, rows))
        assert outs[0][0] == outs[1][0] == (900 if room >= 900 else -1)
        assert np.array_equal(outs[0][1], outs[1][1])
        assert np.array_equal(outs[0][1][:min(room, 900)], odd[:room])


@needs_cxx
@pytest.mark.parametrize("shared", [False, True])
def test_coarse_pairs_on_threads_give_numba_pairs(monkeypatch, shared):
    """The coarse adjacency's weights and summed lengths on several threads (each thread
    the pairs of a range of clusters, every adjacency read in order): the numba kernel's
    bytes, lengths given per pair or as shares, float32 weights, large enough to split."""
    from superfacets.elements.points import point_graph
    from superfacets.inputs.cloud import PointCloud

    rng = np.random.default_rng(4)
    g = point_graph(PointCloud(rng.random((150_000, 3)) * [1.0, 1.0, 0.05])).graph
    n = g.n_elements
    cluster = (np.arange(n) // 6).astype(np.int32)  # runs of the Z-order: compact clusters
    cluster[rng.random(n) < 0.05] = rng.integers(0, n // 6, 1)[0]  # and a scattered one
    n_c = int(cluster.max()) + 1
    dist = rng.random(n) * 0.01
    csr_w = rng.random(g.indices.shape[0]).astype(np.float32)
    n_pairs = int((g.indices > np.repeat(np.arange(n), np.diff(g.indptr))).sum())
    border = (np.empty(0), rng.random(n)) if shared else (rng.random(n_pairs), np.empty(0))
    args = (g.indptr, g.indices, cluster, dist, csr_w, *border, n_c)
    expected = reference("voronoi.coarse_pairs")(*args)
    with monkeypatch.context() as m:  # (numba, above, compiled with its own count)
        m.setenv("SUPERFACETS_KERNEL_THREADS", "3")
        got = native.kernel("voronoi.coarse_pairs")(*args)
    assert all(a.tobytes() == b.tobytes() for a, b in zip(got, expected))
    assert got[0].shape[0] > n_c  # many pairs, each cluster's
    # the lengths made apart, as a run makes them once the distances and weights are let
    # go: the same sums, bit for bit; and the pairs and weights without them the same
    with monkeypatch.context() as m:
        m.setenv("SUPERFACETS_KERNEL_THREADS", "3")
        apart = native.kernel("voronoi.coarse_lengths")(g.indptr, g.indices, cluster, got[0],
                                                         *border, n_c)
        none = np.empty(0)
        bare = native.kernel("voronoi.coarse_pairs")(*args[:5], none, none, n_c)
    assert apart.tobytes() == got[2].tobytes()
    assert bare[0].tobytes() == got[0].tobytes() and bare[1].tobytes() == got[1].tobytes()
    assert bare[2].shape == (0,)
    assert reference("voronoi.coarse_lengths")(g.indptr, g.indices, cluster, got[0], *border,
                                               n_c).tobytes() == got[2].tobytes()


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "2", "3"])
def test_pieces_of_labels_on_threads_give_numba_numbers(monkeypatch, threads):
    """Each label's connected pieces found by a union-find on threads are numbered as one
    depth-first pass numbers them (in the order of their lowest element): labels in
    blobs broken by scattered ones (many pieces, one-element pieces), and one label."""
    from superfacets.elements.points import point_graph
    from superfacets.inputs.cloud import PointCloud

    rng = np.random.default_rng(6)
    g = point_graph(PointCloud(rng.random((120_000, 3)) * [1.0, 1.0, 0.02])).graph
    n = g.n_elements
    blobs = (np.arange(n) // 500).astype(np.int64) % 37  # runs of the Z-order
    noisy = np.where(rng.random(n) < 0.2, rng.integers(0, 37, n), blobs)
    pieces = []
    for labels in (noisy, np.zeros(n, dtype=np.int64)):
        expected = reference("connectivity.same_label_components")(g.indptr, g.indices,
                                                                        labels)
        with monkeypatch.context() as m:
            m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
            got = native.kernel("connectivity.same_label_components")(g.indptr, g.indices, labels)
        assert got.dtype == np.int64 and np.array_equal(got, expected)
        pieces.append(int(got.max()) + 1)
    assert pieces[0] > 5_000 and pieces[1] == 1


@needs_cxx
@pytest.mark.parametrize("shared", [False, True])
def test_stray_borders_on_threads_give_numba_entries(monkeypatch, shared):
    """The stray pieces' border entries gathered on threads (each a range of rows, counted
    then written at its places): numba's arrays in numba's order, lengths per pair or as
    shares."""
    from superfacets.elements.points import point_graph
    from superfacets.inputs.cloud import PointCloud

    rng = np.random.default_rng(9)
    g = point_graph(PointCloud(rng.random((100_000, 3)) * [1.0, 1.0, 0.02])).graph
    n = g.n_elements
    piece = np.where(rng.random(n) < 0.1, rng.integers(0, 3000, n), np.arange(n) // 400)
    is_main = rng.random(int(piece.max()) + 1) < 0.6
    n_pairs = int((g.indices > np.repeat(np.arange(n), np.diff(g.indptr))).sum())
    border = (np.empty(0), rng.random(n)) if shared else (rng.random(n_pairs), np.empty(0))
    args = (g.indptr, g.indices, piece, is_main, *border)
    expected = reference("connectivity.stray_borders")(*args)
    with monkeypatch.context() as m:
        m.setenv("SUPERFACETS_KERNEL_THREADS", "3")
        got = native.kernel("connectivity.stray_borders")(*args)
    assert all(x.tobytes() == y.tobytes() for x, y in zip(got, expected))
    assert got[0].shape[0] > 10_000


@needs_cxx
def test_center_update_on_threads_gives_numba_centers():
    # enough elements for a thread per range; quantized positions: many equal distances,
    # so the rule on ties (old center, else lowest index) decides many centers
    rng = np.random.default_rng(11)
    m, k = 300_000, 70
    label = np.repeat(rng.permutation(k - 2), rng.multinomial(m, np.full(k - 2, 1 / (k - 2))))
    label = label.astype(np.int32)  # runs of one label, as Z-ordered superfacets; two empty
    pos = rng.integers(0, 4, (m, 3)).astype(np.float64)
    sizes = rng.integers(0, 3, m).astype(np.float64)
    sizes[label == 5] = 0.0  # a superfacet of zero size: the plain mean
    old = np.array([np.flatnonzero(label == s)[-1] if s % 3 else -1 for s in range(k - 2)]
                   + [-1, 7], dtype=np.int64)
    outs = []
    for fn in (native.kernel("update.update_centers"), reference("update.update_centers")):
        new = np.empty(k, dtype=np.int64)
        fn(label, k, sizes, pos, old, new)
        outs.append(new)
    assert (outs[0] == outs[1]).all()
    assert (outs[0][-2:] == -1).all() and (outs[0][:-2] >= 0).all()
    assert (outs[0] != old).any() and (outs[0] == old).any()


def _mean_probed(label, pos, s, rng, half):
    """Superfacet ``s`` made of 2,000 elements spread over the whole array (x over six
    orders of magnitude, y = z = 0) and two probes, the array's last elements, placed
    about its mean so that the mean of one pass in index order has the first probe
    nearest, and the mean added by the ranges below and from ``half`` (each from 0, then
    summed), the second."""
    m = label.shape[0]
    idx = np.r_[np.sort(rng.choice(m - 2, 2000, replace=False)), m - 2, m - 1]
    label[idx] = s
    pos[idx] = 0.0
    pos[idx[:-2], 0] = rng.standard_normal(2000) * 10.0 ** rng.integers(-3, 4, 2000)
    for _ in range(20):  # the probes move the means a little: placed again until still
        x = pos[idx, 0]
        seq = np.add.accumulate(x)[-1] / x.size  # (accumulate: in order)
        ranges = np.add.accumulate(x[idx < half])[-1] + np.add.accumulate(x[idx >= half])[-1]
        mid, h = 0.5 * (seq + ranges / x.size), abs(seq - ranges / x.size) / 8
        probes = [mid + h, mid - h] if seq > ranges / x.size else [mid - h, mid + h]
        if pos[m - 2, 0] == probes[0] and pos[m - 1, 0] == probes[1]:
            break
        pos[[m - 2, m - 1], 0] = probes
    assert seq != ranges / x.size


@needs_cxx
@pytest.mark.parametrize("threads,k", [("1", 300), ("2", 300), ("3", 300), ("4", 20_000)])
def test_center_update_sums_in_index_order_on_threads(monkeypatch, threads, k):
    """The means of the center update added by ranges of elements on threads: a superfacet
    within one range, or spanning ranges (its elements scattered over the whole array),
    gets the sums of one pass in index order, to the bit: numba's centers, with positions
    over twelve orders of magnitude, a superfacet of zero size (the plain mean) and one
    whose center the last bit of its mean decides (:func:`_mean_probed`: the ranges'
    partial sums added together fail it on two threads). With 20,000 superfacets the
    ranges' sums and choices are also merged on threads."""
    rng = np.random.default_rng(16)
    m = 400_000
    label = (np.arange(m) * (k - 20) // m).astype(np.int32)  # runs: most in one range
    scattered = rng.random(m) < 0.05
    label[scattered] = rng.integers(0, k - 1, int(scattered.sum()))  # and 19 scattered alone
    pos = rng.standard_normal((m, 3)) * 10.0 ** rng.integers(-6, 7, (m, 1))
    sizes = rng.random(m) * 10.0 ** rng.integers(-3, 3, m)
    sizes[label == 7] = 0.0
    _mean_probed(label, pos, k - 1, rng, m // 2)
    sizes[label == k - 1] = 1.0
    present, at = np.unique(label, return_index=True)  # each superfacet's first element
    old = np.full(k, -1, dtype=np.int64)
    old[present] = at
    old[::2] = -1
    old[k - 1] = -1
    ref = np.empty(k, dtype=np.int64)
    reference("update.update_centers")(label, k, sizes, pos, old, ref)
    assert ref[k - 1] == m - 2
    new = np.empty(k, dtype=np.int64)
    with monkeypatch.context() as mp:
        mp.setenv("SUPERFACETS_KERNEL_THREADS", threads)
        native.kernel("update.update_centers")(label, k, sizes, pos, old, new)
    np.testing.assert_array_equal(new, ref)
    assert (new != old).sum() > k // 2  # (the means decide: most centers move)


@needs_cxx
@pytest.mark.parametrize("ptype,dtype", [(np.int32, np.int32), (np.int64, np.int64),
                                         (np.int32, np.int64)])
def test_csr_of_pairs_and_their_numbering_match_numba(ptype, dtype):
    """The graph's CSR from pairs (rows of 40+ entries sorted stably by merge sort) and the
    pairs numbered again from it (a lazy graph's rebuild), in every dtype the runs use."""
    rng = np.random.default_rng(3)
    n = 300
    lo = rng.integers(0, n - 1, 5000)
    hi = np.minimum(lo + rng.integers(1, 4, 5000), n - 1)
    lo[:60], hi[:60] = 7, np.arange(100, 160)  # a row longer than the insertion sort's 32
    keep = lo < hi
    lo, hi = lo[keep].astype(ptype), hi[keep].astype(ptype)
    out = []
    for path in ("adjacency.csr_of_pairs", "adjacency.number_pairs"):
        got = []
        for fn in (native.kernel(path), reference(path)):
            ind = np.empty(2 * lo.shape[0], dtype=np.int32)
            de = np.empty(2 * lo.shape[0], dtype=dtype)
            indptr = reference("adjacency.csr_of_pairs")(lo, hi, n, ind, de)
            if path.endswith("csr_of_pairs"):
                indptr = fn(lo, hi, n, ind, de)
                got.append((indptr, ind, de))
            else:
                pairs = np.empty((ind.shape[0] // 2, 2), dtype=ptype)
                kept = np.empty(ind.shape[0] // 2, dtype=np.int64)
                fn(indptr, ind, n, de, kept, pairs)
                got.append((de, kept, pairs))
        assert _same(got[0], got[1]), path
        out.append(got[0])
    # strided columns of an (e, 2) array are refused (the caller makes them contiguous)
    both = np.stack([lo, hi], axis=1)
    ind, de = np.empty(2 * lo.shape[0], dtype=np.int32), np.empty(2 * lo.shape[0], dtype=dtype)
    with pytest.raises(TypeError, match="lo"):
        native.kernel("adjacency.csr_of_pairs")(both[:, 0], both[:, 1], n, ind, de)


@needs_cxx
@pytest.mark.parametrize("ftype,ptype,etype", [(np.int64, np.int32, np.int32),
                                               (np.int32, np.int64, np.int64)])
def test_shared_edges_match_numba_and_count_what_is_not_one_edge(ftype, ptype, etype):
    """The edge two triangles share (a triangle mesh's edges made again): known answers,
    numba's results in every dtype, and the pairs that share no edge, or three vertices,
    or (checking) another edge, counted."""
    faces = np.array([[0, 1, 2], [2, 1, 3], [4, 2, 3], [0, 1, 2], [2, 3, 3], [6, 7, 8]],
                     dtype=ftype)
    pairs = np.array([[0, 1], [1, 2], [1, 4], [0, 3], [0, 5], [2, 4]], dtype=ptype)
    got = []
    for fn in (native.kernel("adjacency.shared_edges"), reference("adjacency.shared_edges")):
        edges = np.full((6, 2), -1, dtype=etype)
        bad = fn(faces, pairs, edges, False)
        wrong = edges.copy()
        wrong[0] = [0, 2]
        got.append((bad, edges[[0, 1, 2, 5]], fn(faces, pairs, edges, True),
                    fn(faces, pairs, wrong, True)))
    assert got[0][0] == got[1][0] == 2  # (0, 3): three vertices; (0, 5): none
    assert got[0][1].tolist() == got[1][1].tolist() == [[1, 2], [2, 3], [2, 3], [2, 3]]
    assert got[0][2:] == got[1][2:] == (2, 3)
    with pytest.raises(ValueError, match="pairs"):  # (OutOfRange: no face read)
        native.kernel("adjacency.shared_edges")(faces, pairs + 6, edges, False)


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "2", "3"])
def test_csr_of_pairs_on_threads_keeps_the_pairs_order_in_each_row(monkeypatch, threads):
    """Known answer on threads (each owns a range of rows, reads every pair): 400,000
    pairs over 150,000 rows, repeated pairs whose order in a row is the pairs' order (the
    stable sort keeps it, so a thread that wrote them out of order would fail), rows that
    cross the threads' bounds; the face pairs' CSR (repeats dropped, the first kept by
    its edge keys) and the pairs numbered again on threads, the same as numba's."""
    rng = np.random.default_rng(11)
    n, e = 150_000, 400_000
    lo = rng.integers(0, n - 1, e)
    hi = np.minimum(lo + rng.integers(1, 3, e), n - 1)
    lo[:2000], hi[:2000] = np.repeat(np.arange(74_990, 75_010), 100), 75_020  # repeats
    keep = lo < hi
    lo, hi = lo[keep].astype(np.int32), hi[keep].astype(np.int32)
    ka = rng.integers(0, 50, lo.shape[0]).astype(np.int32)
    kb = rng.integers(0, 50, lo.shape[0]).astype(np.int32)
    with monkeypatch.context() as m:
        m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
        got = []
        for fn in (native.kernel("adjacency.csr_of_pairs"),
                   reference("adjacency.csr_of_pairs")):
            ind = np.empty(2 * lo.shape[0], dtype=np.int32)
            de = np.empty(2 * lo.shape[0], dtype=np.int32)
            got.append((fn(lo, hi, n, ind, de), ind, de))
        faces = []
        for fn in (native.kernel("adjacency.csr_of_face_pairs"),
                   reference("adjacency.csr_of_face_pairs")):
            ind = np.empty(2 * lo.shape[0], dtype=np.int32)
            de = np.empty(2 * lo.shape[0], dtype=np.int32)
            indptr, first = fn(lo, hi, ka, kb, n, ind, de)
            faces.append((indptr, first, ind[:indptr[-1]], de[:indptr[-1]]))
        numbered = []  # the pairs numbered again (rows with repeated entries)
        for fn in (native.kernel("adjacency.number_pairs"),
                   reference("adjacency.number_pairs")):
            indptr, ind, de = (x.copy() for x in got[1])
            kept = np.empty(ind.shape[0] // 2, dtype=np.int64)
            pairs = np.empty((ind.shape[0] // 2, 2), dtype=np.int32)
            fn(indptr, ind, n, de, kept, pairs)
            numbered.append((de, kept, pairs))
    assert _same(got[0], got[1]) and _same(faces[0], faces[1])
    assert _same(numbered[0], numbered[1])
    de, kept, pairs = numbered[0]  # known answer: both entries of pair t hold t
    assert np.array_equal(np.bincount(de), np.full(pairs.shape[0], 2))
    assert np.array_equal(pairs, np.stack([lo, hi], axis=1)[kept])
    indptr, ind, de = got[0]
    # known answer: each row's entries ascending, equal ones in the pairs' order
    rows = np.repeat(np.arange(n), np.diff(indptr))
    other = np.where(lo[de] == rows, hi[de], lo[de])
    assert np.array_equal(other, ind)
    o = np.lexsort((de, ind, rows))
    assert np.array_equal(o, np.arange(o.shape[0]))
    assert np.array_equal(np.diff(faces[0][0]) > 0, np.diff(indptr) > 0)


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "2", "3"])
@pytest.mark.parametrize("polygons", [False, True])
def test_face_pairs_grouped_on_threads_match_numba(monkeypatch, threads, polygons):
    """The edges' grouping on threads (ranges cut at edge starts, each counted, then
    written from its place): 70,000 triangles over 400 vertices, so that edges of 2-12
    half-edges (non-manifold), duplicated faces (paired with themselves: left out) and
    open boundaries cross the ranges' bounds; one set of arrays, numba's to the bit, and
    the known answer of its counts."""
    from superfacets.elements.faces import order_by_two_keys

    rng = np.random.default_rng(5)
    m, nv = 70_000, 400
    faces = rng.integers(0, nv, size=(m, 3)).astype(np.int32)
    faces[:3000] = faces[3000:6000]  # duplicated faces
    faces[6000:6600, 1] = faces[6000:6600, 0]  # collapsed edges
    a = np.minimum(faces, np.roll(faces, -1, axis=1)).ravel()
    b = np.maximum(faces, np.roll(faces, -1, axis=1)).ravel()
    owner = (np.arange(3 * m, dtype=np.int32) // 3 if polygons
             else np.empty(0, dtype=np.int32))
    half, _ = order_by_two_keys(a, b, nv, a == b)
    with monkeypatch.context() as mp:
        mp.setenv("SUPERFACETS_KERNEL_THREADS", threads)
        got = native.kernel("adjacency.group_pairs")(half, owner, a, b)
    want = reference("adjacency.group_pairs")(half, owner, a, b)
    assert _same(got, want)
    # known answer: per edge of s half-edges, s == 1 is a boundary, else its pairs of
    # distinct faces: every two up to 8, each and the next (cyclically) beyond
    key = a[half].astype(np.int64) * nv + b[half]
    start = np.r_[0, np.flatnonzero(np.diff(key)) + 1]
    size = np.diff(np.r_[start, half.shape[0]])
    assert np.array_equal(got[0], start[size == 1])
    face = half // 3
    n_pairs = sum(int(face[s + i] != face[s + j]) for s, z in zip(start, size) if z > 1
                  for i in range(z)
                  for j in (range(i + 1, z) if z <= 8 else [(i + 1) % z]))
    assert got[1].shape[0] == n_pairs and (size > 2).any() and (size > 8).any()
    assert n_pairs < (size * (size - 1) // 2).sum()  # (self-pairs left out)
    assert (got[1] < got[2]).all()


@needs_cxx
def test_values_per_entry_on_threads_are_numpys_take(monkeypatch):
    """A value per adjacency laid out per CSR entry on threads: numba's and numpy's
    gather, bit for bit, for float64 and float32 weights and int32 or int64 adjacency
    numbers; float32 values into a float64 output are refused."""
    rng = np.random.default_rng(8)
    values = rng.random(40_000)
    dual_edge = rng.integers(0, values.shape[0], 90_000).astype(np.int32)
    outs = [np.empty(dual_edge.shape[0]) for _ in range(2)]
    reference("terms.per_entry")(values, dual_edge, outs[1])
    with monkeypatch.context() as mp:  # (the compiled kernels alone read it)
        mp.setenv("SUPERFACETS_KERNEL_THREADS", "3")
        native.kernel("terms.per_entry")(values, dual_edge, outs[0])
    assert _same(outs[0], outs[1]) and _same(outs[0], values[dual_edge])
    v32, out32 = values.astype(np.float32), np.empty(dual_edge.shape[0], dtype=np.float32)
    ref32 = np.empty_like(out32)
    native.kernel("terms.per_entry")(v32, dual_edge, out32)
    reference("terms.per_entry")(v32, dual_edge, ref32)
    assert _same(out32, ref32) and _same(out32, v32[dual_edge])
    wide = np.empty_like(outs[0])
    native.kernel("terms.per_entry")(values, dual_edge.astype(np.int64), wide)
    assert _same(wide, outs[1])
    with pytest.raises(TypeError, match="dual_edge"):
        native.kernel("terms.per_entry")(values, dual_edge.astype(np.int16), outs[0])
    with pytest.raises(TypeError, match="out"):
        native.kernel("terms.per_entry")(v32, dual_edge, outs[0])


@needs_cxx
def test_kept_pairs_taken_on_threads_are_the_gathered_columns(monkeypatch):
    """The face pairs and edges kept after the CSR's deduplication, gathered on threads:
    numba's to the bit and numpy's fancy indexing (the known answer)."""
    rng = np.random.default_rng(2)
    e = 50_000
    lo, hi, ka, kb = (rng.integers(0, 10**6, e).astype(np.int32) for _ in range(4))
    first = np.sort(rng.choice(e, 30_000, replace=False)).astype(np.int64)
    first[:100] = first[:100][::-1]  # (any order)
    got = [(np.empty((first.shape[0], 2), dtype=np.int32),
            np.empty((first.shape[0], 2), dtype=np.int32)) for _ in range(2)]
    reference("adjacency.take_pairs")(first, lo, hi, ka, kb, *got[1])
    with monkeypatch.context() as mp:  # (the compiled kernels alone read it)
        mp.setenv("SUPERFACETS_KERNEL_THREADS", "3")
        native.kernel("adjacency.take_pairs")(first, lo, hi, ka, kb, *got[0])
    assert _same(got[0], got[1])
    assert np.array_equal(got[0][0], np.stack([lo[first], hi[first]], axis=1))
    assert np.array_equal(got[0][1], np.stack([ka[first], kb[first]], axis=1))


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "2", "3"])
def test_first_in_cells_on_threads_are_the_lowest_of_each_cell(monkeypatch, threads):
    """Known answer on threads (one table, cells taken by compare-and-swap): the lowest
    element of each occupied cell, ascending, as numba's and as ``np.unique`` (a table
    that kept the last element offered, or the first to arrive, fails); an empty array
    once more than half the table would fill."""
    rng = np.random.default_rng(2)
    pos = rng.random((120_000, 3)) * 7.0
    lo, h = np.zeros(3), 0.5
    dims = np.floor((pos.max(0) - lo) / h).astype(np.int64) + 1
    cell = np.floor((pos - lo) / h).astype(np.int64)
    expected = np.sort(np.unique(cell, axis=0, return_index=True)[1])
    with monkeypatch.context() as m:
        m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
        for cap in (8192, 1024):
            got = native.kernel("voronoi.first_in_cells")(pos, lo, h, dims, cap)
            ref = reference("voronoi.first_in_cells")(pos, lo, h, dims, cap)
            assert np.array_equal(got, ref)
            if cap == 8192:
                assert np.array_equal(got, expected) and expected.shape[0] == 2744
            else:  # 2,744 cells do not fit half of 1,024 slots
                assert got.shape[0] == 0


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "2"])
def test_point_tree_on_threads_matches_numba(monkeypatch, threads):
    """The k-d tree of 200,000 points (the leaves' boxes on threads, the others' from
    their children): numba's nodes and boxes, every box the least holding its points."""
    from superfacets.elements.neighbors import point_tree

    rng = np.random.default_rng(4)
    pts = np.round(rng.random((200_000, 3)), 3)  # (ties in every coordinate)
    with monkeypatch.context() as m:
        m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
        got = point_tree(pts)
        m.setattr(native, "kernel", reference)
        ref = point_tree(pts)
    for name in ("start", "end", "left", "boxes", "ids", "rows", "points"):
        assert np.array_equal(getattr(got, name), getattr(ref, name)), name
    leaf = np.flatnonzero(got.left < 0)
    v = leaf[len(leaf) // 2]
    inside = got.points[got.start[v]:got.end[v]]
    assert np.array_equal(got.boxes[v], np.r_[inside.min(0), inside.max(0)])
    assert np.array_equal(got.boxes[0], np.r_[pts.min(0), pts.max(0)])


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "2", "3"])
def test_label_sums_on_threads_are_numbas_to_the_bit(monkeypatch, threads):
    """Per-label sums on threads (each owns a range of labels and reads every element in
    order): numba's bit for bit, so each label's terms are added in element order (sums of
    values of mixed scales, where another order rounds otherwise)."""
    rng = np.random.default_rng(6)
    n, k = 300_000, 37
    labels = rng.integers(0, k, n)
    w = rng.random(n) * 10.0 ** rng.integers(-8, 8, n)
    pos, nor = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    cen = rng.normal(size=(k, 3))
    out = []
    for get in (reference, native.kernel):  # (numba compiles outside the context)
        area, wpos, wnrm, sc = np.zeros(k), np.zeros((k, 3)), np.zeros((k, 3)), np.zeros((k, 9))
        with monkeypatch.context() as m:
            if get is native.kernel:
                m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
            get("geometry.label_sums")(labels, w, pos, nor, area, wpos, wnrm)
            get("geometry.label_scatter")(labels, w, pos, cen, sc)
        out.insert(0, (area, wpos, wnrm, sc))
    assert _same(out[0], out[1])
    # element order is bincount's; the other order rounds otherwise on these values
    assert np.array_equal(out[0][0], np.bincount(labels, weights=w, minlength=k))
    assert not np.array_equal(out[0][0], np.bincount(labels[::-1], weights=w[::-1], minlength=k))


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "2", "3"])
def test_knn_layout_on_threads_is_numbas(monkeypatch, threads):
    """The symmetric layout of k-nearest-neighbour lists on threads (each owns a range of
    rows; the reverse entries a thread's lists make in another's rows are posted to it):
    numba's layout, for lists mostly near their row and some anywhere (posted both ways),
    repeated entries, rows listing themselves, a mask and longer lists for some rows."""
    rng = np.random.default_rng(9)
    n, k = 30_000, 8
    near = np.arange(n)[:, None] + rng.integers(-60, 60, (n, k))
    far = rng.integers(0, n, (n, k))
    nbr = np.where(rng.random((n, k)) < 0.05, far, near).clip(0, n - 1).astype(np.int32)
    keep = rng.random((n, k)) < 0.9
    rows = np.sort(rng.choice(n, 300, replace=False)).astype(np.int64)
    more = np.where(rng.random((300, 2 * k)) < 0.5, rng.integers(0, n, (300, 2 * k)),
                    nbr[rows].repeat(2, axis=1)).astype(np.int32)
    more_keep = rng.random(more.shape) < 0.8
    cases = [  # the first: a strided view, as the point graph passes it
             (nbr[:, 1:], np.ascontiguousarray(keep[:, 1:]), rows, more, more_keep),
             (nbr, np.zeros((0, k), dtype=bool), rows[:0], more[:0], more_keep[:0])]
    for args in cases:
        want_ptr = np.empty(n + 1, dtype=np.int64)
        want = reference("adjacency.knn_csr")(args[0], args[1], want_ptr, *args[2:])
        got_ptr = np.empty(n + 1, dtype=np.int64)
        with monkeypatch.context() as m:
            m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
            got = native.kernel("adjacency.knn_csr")(args[0], args[1], got_ptr, *args[2:])
        np.testing.assert_array_equal(got_ptr, want_ptr)
        np.testing.assert_array_equal(got[:got_ptr[-1]], want[:want_ptr[-1]])
        assert got_ptr[-1] > 2 * n * (k - 2)


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "2", "3"])
def test_bounds_and_finite_rows_of_large_arrays_are_numpys(monkeypatch, threads):
    """The columns' bounds and the finite rows of a large array, by row ranges on
    threads: numpy's values and numba's, with infinities and NaNs (a NaN column's bounds
    are NaN) at the ends of the threads' ranges and inside them; the columns' means are
    ``mean(axis=0)``'s to the bit (rows added in order), also over ten orders of
    magnitude, where a pairwise sum differs."""
    from superfacets.inputs.bounds import column_bounds, column_means, finite_rows, rows_in_box

    rng = np.random.default_rng(11)
    n = 200_000
    a = rng.normal(size=(n, 3)) * [1.0, 1e-3, 1e6]
    b = a.copy()
    b[[0, n // 2, n // 3, n - 1], [0, 1, 1, 0]] = [np.inf, -np.inf, 5e6, -7e6]
    c = b.copy()
    c[[n // 2 - 1, 17], [2, 1]] = np.nan
    for x in (a, b, c):
        want = (np.array([x[:, j].min() for j in range(3)]),
                np.array([x[:, j].max() for j in range(3)]),
                np.isfinite(x).all(axis=1))
        ref = np.empty(3), np.empty(3), np.empty(n, dtype=bool)
        reference("columns.column_bounds")(x, ref[0], ref[1])
        reference("columns.finite_rows")(x, ref[2])
        with monkeypatch.context() as m:
            m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
            got = (*column_bounds(x), finite_rows(x))
        for g, w, r in zip(got, want, ref):
            np.testing.assert_array_equal(g, w)
            np.testing.assert_array_equal(r, w)
        lo, hi = np.array([-1.0, -1e-3, -1e6]), np.array([0.5, np.inf, 5e5])
        inside = ((x >= lo) & (x <= hi)).all(axis=1)  # (NaN rows outside; some of each)
        assert 0 < inside.sum() < n
        np.testing.assert_array_equal(rows_in_box(x, lo, hi), inside)
        means, ref_means = column_means(x), np.empty(3)  # (one thread: the rows in order)
        reference("columns.column_means")(x, ref_means)
        np.testing.assert_array_equal(means, x.mean(axis=0))
        np.testing.assert_array_equal(ref_means, x.mean(axis=0))
    assert np.isnan(got[0][1:]).all() and got[0][0] == -7e6 and not got[2][[0, 17]].any()
    # magnitudes over ten orders, where a pairwise sum gives other last bits
    y = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-5, 6, (n, 3))
    np.testing.assert_array_equal(column_means(y), y.mean(axis=0))
    assert not np.array_equal(column_means(y), np.array([np.sum(y[:, j]) for j in
                                                         range(3)]) / n)


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "2", "3"])
def test_gathers_of_large_index_arrays_are_numpys_take(monkeypatch, threads):
    """Known answer: ``values[index]`` of int32 and int64 values and indices, gathered by
    ranges on threads, is numpy's take and numba's, into a new array and into ``out``
    (as the passes renumber their previous labels); an index out of range is refused
    with IndexError, counted alike by both kernels."""
    from superfacets._runtime.arrays import GATHER_MIN, gather

    rng = np.random.default_rng(12)
    n = 3 * GATHER_MIN + 17
    for vt in (np.int32, np.int64):
        values = rng.integers(-2**31, 2**31 - 1, 5_000).astype(vt)
        for it in (np.int32, np.int64):
            index = rng.integers(0, values.shape[0], n).astype(it)
            index[[0, n // 2, n - 1]] = [values.shape[0] - 1, 0, 1]
            want = np.take(values, index)
            ref = np.zeros(n, dtype=vt)
            assert reference("columns.gather")(values, index, ref) == 0
            out = np.zeros(n, dtype=vt)
            with monkeypatch.context() as m:
                m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
                got = gather(values, index)
                into = gather(values, index, out=out)
            assert got.dtype == vt and into is out
            for a in (got, into, ref):
                np.testing.assert_array_equal(a, want)
            bad = index.copy()
            bad[[5, n - 2]] = [-1, values.shape[0]]
            with monkeypatch.context() as m, pytest.raises(IndexError, match="2 of"):
                m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
                gather(values, bad)
            assert reference("columns.gather")(values, bad, ref) == 2


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "3"])
def test_border_shares_of_a_large_point_graph_are_numpys(monkeypatch, threads):
    """Known answer: a large point graph's border shares (``2 sqrt(pi a) / max(deg, 1)``,
    rebuilt whenever asked after a release) by one pass on threads are numpy's
    expression's values to the bit, and numba's, with degrees of 0 and 1 and zero areas."""
    from superfacets.elements.points import _shares

    rng = np.random.default_rng(13)
    n = 150_000
    deg = rng.integers(0, 25, n)
    deg[[0, 7, n - 1]] = [0, 1, 0]
    indptr = np.r_[0, np.cumsum(deg)].astype(np.int64)
    area = rng.random(n) * 10.0 ** rng.integers(-12, 6, n)
    area[[3, n // 2]] = 0.0

    class Graph:  # (what _shares reads of the graph)
        pass

    g = Graph()
    g.indptr = indptr
    want = 2.0 * np.sqrt(np.pi * area) / np.maximum(np.diff(indptr).astype(np.float64), 1.0)
    ref = np.empty(n)
    reference("geometry.border_shares")(indptr, area, ref)
    with monkeypatch.context() as m:
        m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
        got = _shares(area, g)["border_shares"]
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(ref, want)


@needs_cxx
@pytest.mark.parametrize("dtype", [np.int32, np.int64])
def test_label_pairs_are_numpys_unique_with_inverse(monkeypatch, dtype):
    """Known answer: the superfacet graph's borders (each crossing's two labels, lower
    first, grouped) are ``np.unique(lo * k + hi, return_inverse=True)``, compiled and
    numba, with pairs listed either way round, repeated, of equal labels, and none."""
    rng = np.random.default_rng(18)
    n, k = 50_000, 700
    labels = rng.integers(0, k, n)
    for m in (0, 1, 200_000):
        pairs = rng.integers(0, n, (m, 2)).astype(dtype)
        pairs[: m // 10] = pairs[m // 10: 2 * (m // 10)]  # repeats
        a, b = labels[pairs[:, 0]], labels[pairs[:, 1]]
        want, want_inv = np.unique(np.minimum(a, b) * k + np.maximum(a, b), return_inverse=True)
        for fn in (native.kernel("borders.label_pairs"), reference("borders.label_pairs")):
            inv = np.empty(m, dtype=np.int64)
            key = fn(labels, pairs, k, inv)
            np.testing.assert_array_equal(key, want)
            np.testing.assert_array_equal(inv, want_inv)
            assert key.dtype == np.int64
    assert (a == b).any() and want.size > 1000


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "3"])
def test_nearest_row_of_a_large_array_is_numpys_argmin(monkeypatch, threads):
    """Known answer: the first center's row (the element nearest the centroid) by one pass
    on threads is ``np.argmin`` of numpy's squared distances, compiled and numba: the
    first of equal distances, where they lie in different threads' ranges too, and
    numpy's first NaN where a distance is NaN."""
    from superfacets.inputs.bounds import nearest_row

    rng = np.random.default_rng(19)
    n = 300_000
    a = rng.integers(-3, 4, (n, 3)).astype(np.float64)  # many equal distances
    point = np.array([0.25, -0.5, 0.0])
    a[[n - 5, n // 2 + 7, 123_456]] = point  # three at distance 0: the first wins
    cases = [(a, point, 123_456)]
    b = rng.standard_normal((n, 3)) * 10.0 ** rng.integers(-6, 6, (n, 1))
    cases.append((b, b.mean(axis=0), None))
    c = b.copy()
    c[[200_000, 250_000], 1] = np.nan
    cases.append((c, b.mean(axis=0), 200_000))  # numpy's argmin: the first NaN
    for arr, p, want in cases:
        expected = int(np.argmin(((arr - p) ** 2).sum(axis=1)))
        assert want is None or expected == want
        with monkeypatch.context() as m:
            m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
            assert nearest_row(arr, p) == expected
        ref = reference("columns.nearest_row")(arr, p)
        assert ref == (-1 if np.isnan(arr).any() else expected)


def _ball_moments_by_numpy(indptr, indices, pos, pick, rings):
    """The neighbourhoods' covariances and mean distances by numpy: every (picked
    element, member) key, sorted, then sums by ``bincount`` in that order."""
    n = indptr.shape[0] - 1
    owner, member = np.arange(pick.size), pick.astype(np.int64)
    for _ in range(rings):
        count = indptr[member + 1] - indptr[member]
        start = np.repeat(indptr[member] - np.cumsum(count) + count, count)
        owner = np.concatenate([owner, np.repeat(owner, count)])
        member = np.concatenate([member, indices[start + np.arange(start.size)]])
        key = np.unique(owner * n + member)
        owner, member = key // n, key % n
    pts = pos[member]
    size = np.bincount(owner, minlength=pick.size).astype(np.float64)
    mean = np.stack([np.bincount(owner, pts[:, j], pick.size) for j in range(3)], 1) / \
        size[:, None]
    d = pts - mean[owner]
    cov = np.empty((pick.size, 3, 3))
    for i in range(3):
        for j in range(i, 3):
            cov[:, i, j] = cov[:, j, i] = np.bincount(owner, d[:, i] * d[:, j], pick.size)
    cov /= size[:, None, None]
    radius = np.bincount(owner, np.sqrt(((pts - pos[pick][owner]) ** 2).sum(axis=1)),
                         pick.size) / np.maximum(size - 1.0, 1.0)
    return cov, radius


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "3"])
def test_neighbourhood_moments_are_numpys_sums_in_order(monkeypatch, threads):
    """Known answer: the noise estimate's neighbourhoods (the elements within one and two
    graph steps of each picked one) give numpy's covariances and mean distances to the
    bit, compiled on threads and numba, with 4- and 8-byte neighbours, repeated entries,
    an isolated element and coordinates over twelve orders of magnitude (where a sum in
    another order differs)."""
    from superfacets.method.merges import PLANE_ROUNDING, _plane_residual

    rng = np.random.default_rng(15)
    n = 40_000
    deg = rng.integers(0, 14, n)
    deg[[5, 9]] = 0  # 5: isolated (no one lists it either: below)
    indptr = np.r_[0, np.cumsum(deg)].astype(np.int64)
    indices = ((np.repeat(np.arange(n), deg) + rng.integers(-300, 300, deg.sum())) % n)
    indices[indices == 5] = 6
    indices[: 40] = indices[0]  # repeats
    pos = rng.standard_normal((n, 3)) * 10.0 ** rng.integers(-6, 6, (n, 1))
    pick = np.r_[5, 9, rng.choice(n, 3000, replace=False)].astype(np.int64)
    kernel = native.kernel("normals.neighbourhood_moments")
    for idx in (indices.astype(np.int32), indices.astype(np.int64)):
        for rings in (0, 1, 2):
            want_cov, want_radius = _ball_moments_by_numpy(indptr, idx.astype(np.int64), pos,
                                                           pick, rings)
            cov, radius = np.empty((pick.size, 3, 3)), np.empty(pick.size)
            ref_cov, ref_radius = np.empty_like(cov), np.empty_like(radius)
            with monkeypatch.context() as m:
                m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
                kernel(indptr, idx, pos, pick, rings, cov, radius)
            reference("normals.neighbourhood_moments")(indptr, idx, pos, pick, rings,
                                                              ref_cov, ref_radius)
            for got in ((cov, radius), (ref_cov, ref_radius)):
                np.testing.assert_array_equal(got[0], want_cov)
                np.testing.assert_array_equal(got[1], want_radius)
    assert radius[0] == 0.0 and not cov[0].any()  # the isolated element: itself alone
    assert radius[1] == 0.0  # (9 lists no one: its ball, read from its own row, is itself)

    class Graph:  # (what _plane_residual reads of the graph)
        pass

    g = Graph()
    g.indptr, g.indices, g.positions = indptr, indices.astype(np.int32), pos
    low, radius = _plane_residual(g, pick, 2)
    values = np.linalg.eigvalsh(want_cov)  # the smallest, 0 within the rounding of the largest
    kept = values[:, 0] > 2 * PLANE_ROUNDING * values[:, 2]
    assert np.all(np.abs(low[kept] - values[kept, 0]) <= 16 * EPS * values[kept, 2])
    assert not low[values[:, 0] <= 0.5 * PLANE_ROUNDING * values[:, 2]].any()


EPS = float(np.finfo(np.float64).eps)


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "3"])
def test_extreme_eigenvalues_are_numpys_to_the_rounding(monkeypatch, threads):
    """Known answers: the smallest and the largest eigenvalue of symmetric 3x3 matrices by
    Jacobi's rotations, compiled on threads and numba bit for bit, numpy's within a few
    machine epsilons of the largest, over twelve orders of magnitude; an exact plane's
    covariance (points at 1,000 from the origin on a tilted plane) has its smallest within
    4 epsilons of its largest; diagonal, zero, isotropic and repeated spectra exact."""
    rng = np.random.default_rng(3)
    m = 6000
    a = rng.standard_normal((m, 3, 3)) * 10.0 ** rng.integers(-6, 6, (m, 1, 1))
    cov = np.einsum("mij,mkj->mik", a, a)
    n = np.array([0.3, -0.5, 1.0]) / np.linalg.norm([0.3, -0.5, 1.0])
    u = np.cross(n, [1.0, 0, 0])
    u /= np.linalg.norm(u)
    xy = rng.standard_normal((1000, 30, 2))
    pts = xy[..., :1] * u + xy[..., 1:] * np.cross(n, u) + 1000.0
    centred = pts - pts.mean(1, keepdims=True)
    cov[:1000] = np.einsum("mpi,mpj->mij", centred, centred) / 30
    special = [np.zeros((3, 3)), np.eye(3), np.diag([3.0, 1e-30, 2.0]),
               np.diag([2.0, 2.0, 5.0]), np.full((3, 3), 1.0)]  # the last: 0, 0, 3
    cov[-len(special):] = special
    cov = np.ascontiguousarray(cov)
    low, high = np.empty(m), np.empty(m)
    ref_low, ref_high = np.empty(m), np.empty(m)
    with monkeypatch.context() as mp:
        mp.setenv("SUPERFACETS_KERNEL_THREADS", threads)
        native.kernel("normals.extreme_eigenvalues")(cov, low, high)
    reference("normals.extreme_eigenvalues")(cov, ref_low, ref_high)
    np.testing.assert_array_equal(low, ref_low)
    np.testing.assert_array_equal(high, ref_high)
    values = np.linalg.eigvalsh(cov)
    scale = np.abs(values).max(axis=1)
    assert np.all(np.abs(low - values[:, 0]) <= 8 * EPS * scale)
    assert np.all(np.abs(high - values[:, 2]) <= 8 * EPS * scale)
    assert np.all(np.abs(low[:1000]) <= 4 * EPS * high[:1000])
    assert low[-5:].tolist()[:4] == [0.0, 1.0, 1e-30, 2.0]
    assert high[-5:].tolist()[:4] == [0.0, 1.0, 3.0, 5.0]
    assert abs(low[-1]) <= 4 * EPS and high[-1] == pytest.approx(3.0, rel=4 * EPS)


@needs_cxx
@pytest.mark.parametrize("threads", ["1", "3"])
def test_key_windows_of_a_large_cloud_are_numpys(monkeypatch, threads):
    """Known answer: the 64 bits of the Z-order's key strings from any start (the sort's
    window past the bits every point shares), one pass on threads for a large cloud, are
    numpy's shifts and masks of the key words and numba's, across word boundaries and
    past the string's end."""
    from superfacets.elements import neighbors

    rng = np.random.default_rng(14)
    n = 70_000
    keys = rng.integers(0, 2**63, (n, 3), dtype=np.int64).view(np.uint64)
    keys[:5] = [[0, 0, 0], [2**63 - 1] * 3, [1, 0, 2**62], [2**62, 1, 0], [0, 2**63 - 1, 1]]
    small = keys[:1000].copy()  # (numpy's path below 65,536 rows)
    for start in (0, 1, 30, 62, 63, 64, 100, 125, 126, 127, 150, 188):
        want = neighbors.key_window(small, start)
        ref = np.empty(n, dtype=np.uint64)
        reference("geometry.key_window")(keys, start, ref)
        with monkeypatch.context() as m:
            m.setenv("SUPERFACETS_KERNEL_THREADS", threads)
            got = neighbors.key_window(keys, start)
        np.testing.assert_array_equal(got[:1000], want, err_msg=str(start))
        np.testing.assert_array_equal(ref, got, err_msg=str(start))
        bits = "".join(format(int(w), "063b") for w in keys[2]) + "0" * 64  # row 2's
        assert int(got[2]) == int(bits[start:start + 64], 2), start


@needs_cxx
def test_float32_normals_are_read_as_their_float64_copy():
    """A cloud's normals stay float32: the point terms (per pair and per CSR entry) and
    the per-label sums read them as float64, giving what a float64 copy gives, compiled
    and numba alike (products of float32 values rounded in float32 would differ)."""
    rng = np.random.default_rng(8)
    n, k = 5_000, 23
    pos = rng.normal(size=(n, 3))
    nor32 = rng.normal(size=(n, 3)).astype(np.float32)
    nor32 /= np.linalg.norm(nor32, axis=1, keepdims=True)
    nor64 = nor32.astype(np.float64)
    nbr = (np.arange(n)[:, None] + rng.integers(1, 40, (n, 6))) % n
    pairs = np.sort(np.c_[np.repeat(np.arange(n), 6), nbr.ravel()], axis=1)
    pairs = np.unique(pairs[pairs[:, 0] != pairs[:, 1]], axis=0)
    indptr = np.r_[0, np.cumsum(np.bincount(pairs[:, 0], minlength=n))].astype(np.int64)
    indices = pairs[:, 1].astype(np.int32)
    labels = rng.integers(0, k, n)
    w = rng.random(n)
    m = pairs.shape[0]
    out = {}
    for get in (native.kernel, reference):
        for nor in (nor32, nor64):
            terms = [np.empty(m), np.empty(m), np.empty(m, dtype=bool)]
            get("geometry.point_terms")(pos, nor, pairs, 0, m, *terms)
            csr = [np.empty(m), np.empty(m), np.empty(m, dtype=bool)]
            get("terms.point_terms_csr")(pos, nor, indptr, indices, 0, n, *csr)
            sums = [np.zeros(k), np.zeros((k, 3)), np.zeros((k, 3))]
            get("geometry.label_sums")(labels, w, pos, nor, *sums)
            out[get, nor.dtype.name] = (tuple(terms), tuple(csr), tuple(sums))
    first = out[reference, "float64"]
    for got in out.values():
        assert _same(got, first)
    # the float32 products would round otherwise
    c32 = (nor32[pairs[:, 0]] * nor32[pairs[:, 1]]).sum(axis=1, dtype=np.float32)
    assert not np.array_equal(np.clip(c32.astype(np.float64), -1, 1), first[0][1])


@needs_cxx
def test_plain_classification_matches_numba():
    from superfacets.elements import face_graph
    from superfacets.method.expansion import Workspaces, with_room
    from superfacets.method.weights import csr_weights, paper_weights

    mesh = creature(30)
    g = face_graph(mesh)
    w = csr_weights(g, paper_weights(g, alpha=200.0))
    centers = np.zeros(g.n_elements, dtype=np.int64)
    centers[:25] = np.linspace(0, g.n_elements - 1, 25).astype(np.int64)
    out = []
    for fn in (native.kernel("expand.classify_bounded"),
               reference("expand.classify_bounded")):
        spaces = Workspaces(g.n_elements, w)
        c, dist = centers.copy(), np.empty(g.n_elements)
        label = np.empty(g.n_elements, dtype=np.int32)
        local = np.zeros(g.n_elements)  # (the reference's dense scratch; the compiled
        k = with_room(spaces.get(0), lambda ws: fn(  # kernel ignores it)
            g.indptr, g.indices, w, np.ascontiguousarray(g.positions), c, 25,
            float((0.1 * g.diagonal) ** 2), dist, label, local, ws.queue, spaces.inv_width,
            ws.vis, np.empty(0)))
        out.append((k, c, dist, label))
    assert out[0][0] >= 25 and _same(out[0][1:], out[1][1:]) and out[0][0] == out[1][0]


@needs_cxx
def test_other_dtypes_and_layouts_are_refused_before_any_work():
    """A compiled kernel takes the run's dtypes and C-contiguous arrays only; anything
    else (another width, a strided view, a read-only output, a non-array) raises its
    Mismatch, a TypeError naming the argument, and writes nothing."""
    edges = np.array([[0, 1], [1, 2]], dtype=np.int64)
    v = np.array([[0.0, 0, 0], [3, 4, 0], [3, 4, 12]])
    out = np.empty(2)
    native.kernel("geometry.edge_lengths")(v, edges, out)  # int64 edges: compiled too
    assert out.tolist() == [5.0, 12.0]
    out32 = np.full(2, 7.0, dtype=np.float32)
    with pytest.raises(native.require().Mismatch, match="vertices"):
        native.kernel("geometry.edge_lengths")(v.astype(np.float32), edges, out32)
    assert out32.tolist() == [7.0, 7.0]
    assert issubclass(native.require().Mismatch, TypeError)
    strided = np.arange(10, dtype=np.int64)[::2]
    with pytest.raises(TypeError, match="labels"):
        native.kernel("connectivity.same_label_components")(
            np.array([0, 1, 2, 3, 4, 4]), np.array([1, 0, 3, 2], dtype=np.int32), strided)
    ro = np.empty(2)
    ro.setflags(write=False)
    with pytest.raises(TypeError, match="read-only"):
        native.kernel("geometry.edge_lengths")(v, edges, ro)
    with pytest.raises(TypeError, match="vertices"):
        native.kernel("geometry.edge_lengths")(v.tolist(), edges, out)
    big_endian = v.astype(">f8")
    with pytest.raises(TypeError, match="vertices"):
        native.kernel("geometry.edge_lengths")(big_endian, edges, out)


@needs_cxx
def test_default_runs_load_no_numba():
    """Faces, vertices, points and tetrahedra: the compiled kernels alone."""
    code = ("import sys, numpy as np, superfacets; from scipy.spatial import Delaunay; "
            "from superfacets.inputs.shapes import creature; m = creature(24); "
            "superfacets.segment(m, 30); superfacets.segment(m, 30, elements='vertices'); "
            "superfacets.segment(m.centroids, 30); "
            "p = np.random.default_rng(0).random((400, 3)); "
            "superfacets.segment(superfacets.TetMesh(p, Delaunay(p).simplices), 10); "
            "print('numba' in sys.modules, 'superfacets._kernels._cxx' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["False", "True"]
    out = subprocess.run([sys.executable, "-m", "superfacets", "--version"],
                         capture_output=True, text=True, check=True).stdout
    assert "compiled kernels" in out and "C++" in out, out


def _grid_csr(side: int, order: np.ndarray | None = None):
    """A ``side x side`` 4-neighbour grid and a second, smaller one beside it, as CSR (the
    elements numbered row by row, or in ``order``), with weights in eighths: path sums are
    exact, so equal distances are real ties."""
    idx = np.arange(side * side).reshape(side, side)
    pairs = [np.c_[idx[:, :-1].ravel(), idx[:, 1:].ravel()],
             np.c_[idx[:-1].ravel(), idx[1:].ravel()]]
    small = 40
    sid = side * side + np.arange(small * small).reshape(small, small)
    pairs += [np.c_[sid[:, :-1].ravel(), sid[:, 1:].ravel()],
              np.c_[sid[:-1].ravel(), sid[1:].ravel()]]
    p = np.concatenate(pairs)
    m = side * side + small * small
    if order is not None:
        p = order[p]
    rng = np.random.default_rng(11)
    w = rng.integers(1, 5, p.shape[0]) / 8.0
    src, dst = np.r_[p[:, 0], p[:, 1]], np.r_[p[:, 1], p[:, 0]]
    ww = np.r_[w, w].astype(np.float32)
    o = np.lexsort((dst, src))
    indptr = np.zeros(m + 1, dtype=np.int64)
    np.cumsum(np.bincount(src, minlength=m), out=indptr[1:])
    return indptr, dst[o].astype(np.int32), ww[o], m


@needs_cxx
@pytest.mark.parametrize("layout", ["rows", "strips", "shuffled"])
def test_exact_search_by_blocks_matches_numba_pass_by_pass(monkeypatch, layout):
    """Known answer: the compiled exact assignment searches blocks of 2^15 elements on
    threads and hands the pairs across their edges between rounds; its labels, distances
    and orphan centers must be the numba kernels' one-queue search's, bit for bit, fresh
    and updated pass by pass, on 1, 2 and 3 threads: a grid of 3.3 blocks with real ties
    (weights in eighths), its elements in rows (few edges between blocks), in strips of 8
    rows shuffled (each block a dozen strips from all over the grid), or shuffled (nearly
    every edge between blocks: one block, one search), and a second grid no center
    reaches (orphans)."""
    side = 330
    rng = np.random.default_rng(4)
    order = None
    if layout == "strips":
        strips = np.array_split(np.arange(side), side // 8)  # rows, 8 by 8
        rows = np.concatenate([strips[i] for i in rng.permutation(len(strips))])
        new_row = np.argsort(rows)  # the place of each row in the new order
        order = np.r_[(new_row[:, None] * side + np.arange(side)).ravel(),
                      side * side + np.arange(1600)]
    elif layout == "shuffled":
        order = rng.permutation(side * side + 1600)
    indptr, indices, w, m = _grid_csr(side, order)
    inv_width, nb = 4.0, 64

    def state():
        cap = indices.shape[0] + 2 * m + 1
        queue = (np.empty(cap, np.int32), np.empty(cap), np.empty(cap, np.int64),
                 np.full(nb, -1, np.int64))
        return [np.empty(m), np.empty(m, np.int32), queue, np.empty(cap, np.int32),
                np.full(m, -1, np.int32), np.zeros(m, bool)]

    grid_elements = np.arange(side * side) if order is None else order[:side * side]
    centers = np.empty(m + 64, np.int64)
    n = 40
    centers[:n] = rng.choice(grid_elements, n, replace=False)
    states = {"kernel": state(), "reference": state()}
    prev = None
    for step in range(8):
        got = {}
        for fn, (dist, label, queue, qlab, first, mark) in states.items():
            cs = centers.copy()
            call = _implementation(fn)
            with monkeypatch.context() as mp:
                if fn == "kernel":  # (numba compiled with its own count)
                    mp.setenv("SUPERFACETS_KERNEL_THREADS", str(1 + step % 3))
                k = -100 if prev is None else call("exact.reclassify_exact")(
                    indptr, indices, w, cs, n, dist, label, queue, qlab, inv_width, prev,
                    first, mark)
                if k < 0:
                    k = call("exact.classify_exact")(indptr, indices, w, cs, n, dist, label,
                                                     queue, qlab, inv_width)
            got[fn] = (k, cs[:k].copy(), dist.copy(), label.copy())
        (k, cs, dist, label), ref = got["kernel"], got["reference"]
        assert k == ref[0] and np.array_equal(cs, ref[1])
        assert dist.tobytes() == ref[2].tobytes() and np.array_equal(label, ref[3])
        assert k > n and (label >= 0).all()  # the second grid's orphan centers
        assert (step > 0) == (prev is not None)
        prev = cs.copy()
        moved = rng.choice(n, int(rng.integers(3, 12)), replace=False)
        cs = cs[:n].copy()
        cs[moved] = rng.choice(grid_elements, moved.shape[0])
        centers[:n] = cs


@needs_cxx
@pytest.mark.parametrize("layout", ["rows", "strips", "shuffled"])
def test_orientation_by_blocks_matches_numbas_prim(monkeypatch, layout):
    """Known answer: the compiled orientation takes each block's minimum spanning forest
    (blocks of 2^15 elements, on threads) and then Kruskal's algorithm over the forests
    and the edges between blocks; its signs and components must be those of numba's Prim
    over the whole graph, on 1, 2 and 3 threads: a grid of 3.3 blocks and a second grid
    apart (two components), normals from a tetrahedron's four directions with random
    signs (two keys: 0 and the one of every pair of directions; the order of the edges'
    ends decides, and since every pair's product is negative, a cycle through three
    directions turns the sign over: the signs depend on the tree), in rows, in strips of
    8 rows shuffled, or shuffled (one block)."""
    side = 330
    rng = np.random.default_rng(6)
    order = None
    if layout == "strips":
        strips = np.array_split(np.arange(side), side // 8)
        rows = np.concatenate([strips[i] for i in rng.permutation(len(strips))])
        new_row = np.argsort(rows)
        order = np.r_[(new_row[:, None] * side + np.arange(side)).ravel(),
                      side * side + np.arange(1600)]
    elif layout == "shuffled":
        order = rng.permutation(side * side + 1600)
    indptr, indices, _, m = _grid_csr(side, order)
    # a tetrahedron's four directions: every pair's product exactly -1/3 as computed
    ways = np.array([[1.0, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) / np.sqrt(3.0)
    normals = ways[rng.integers(0, 4, m)] * rng.choice([-1.0, 1.0], (m, 1))
    ref_sign, ref_comp = np.empty(m, np.int8), np.empty(m, np.int64)
    n_ref = reference("orient.propagate_signs")(indptr, indices, normals, ref_sign,
                                                       ref_comp)
    assert n_ref == 2 and (ref_sign == -1).any() and (ref_sign == 1).any()
    for threads in ("1", "2", "3"):
        sign, comp = np.empty(m, np.int8), np.empty(m, np.int64)
        with monkeypatch.context() as mp:
            mp.setenv("SUPERFACETS_KERNEL_THREADS", threads)
            n_comp = native.kernel("orient.propagate_signs")(indptr, indices, normals, sign,
                                                             comp)
        assert n_comp == n_ref
        assert np.array_equal(sign, ref_sign) and np.array_equal(comp, ref_comp)


@needs_cxx
def test_voronoi_cells_by_blocks_go_to_the_first_seed_on_ties(monkeypatch):
    """Known answer: each element's nearest seed (scipy's Dijkstra from every seed), the
    first listed where distances tie (weights in eighths: real ties), for the compiled
    search by blocks on 1, 2, 3 threads and for numba's one search; a piece no seed reaches
    keeps -1 and inf."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import dijkstra

    side = 330
    indptr, indices, w, m = _grid_csr(side)
    rng = np.random.default_rng(9)
    seeds = rng.choice(side * side, 60, replace=False).astype(np.int64)
    d = dijkstra(csr_matrix((w.astype(np.float64), indices, indptr), shape=(m, m)),
                 indices=seeds)
    near = d.min(axis=0)
    first = np.where(np.isfinite(near), np.argmin(d, axis=0), -1)
    assert int(((d == near).sum(axis=0) > 1).sum()) > 1000  # real ties
    for fn, threads in (("reference", None), ("kernel", "1"), ("kernel", "2"), ("kernel", "3")):
        dist, label = np.full(m, np.inf), np.full(m, -1, np.int32)
        cap = indices.shape[0] + m + 1
        queue = (np.empty(cap, np.int32), np.empty(cap), np.empty(cap, np.int32),
                 np.full(64, -1, np.int64))
        with monkeypatch.context() as mp:
            if threads:
                mp.setenv("SUPERFACETS_KERNEL_THREADS", threads)
            assert _implementation(fn)("voronoi.nearest_seed")(
                indptr, indices, w, seeds, 0, dist, label, queue, 4.0) == 0
        assert np.array_equal(label, first) and np.array_equal(dist, near)


@needs_cxx
def test_a_runs_n_threads_bounds_the_compiled_kernels(monkeypatch):
    """A run's ``n_threads`` is the most threads any compiled kernel starts while it lasts
    (they read ``SUPERFACETS_NUM_THREADS`` or the CPUs otherwise), nested limits
    restored: a run asked for one thread uses one."""
    from superfacets._runtime.threads import using

    with monkeypatch.context() as m:
        m.setenv("SUPERFACETS_NUM_THREADS", "3")
        assert native._cxx.threads() == 3
        m.setenv("SUPERFACETS_KERNEL_THREADS", "5")  # the compiled kernels' own, first
        assert native._cxx.threads() == 5
        m.setenv("SUPERFACETS_KERNEL_THREADS", "0")
        assert native._cxx.threads() == 3
        with using(1):
            assert native._cxx.threads() == 1
            with using(2):
                assert native._cxx.threads() == 2
            assert native._cxx.threads() == 1
        assert native._cxx.threads() == 3
    from superfacets.inputs.cloud import as_cloud

    pts = _sampled(creature(30), 20_000, 3)
    unbounded = native._cxx.threads()
    seen = []
    plain = native.kernel

    def kernel(path):
        fast = plain(path)

        def counted(*args, **kwargs):
            seen.append(native._cxx.threads())
            return fast(*args, **kwargs)
        return counted

    monkeypatch.setattr(native, "kernel", kernel)
    one = superfacets.segment(as_cloud(pts), 40, n_threads=1).labels
    assert seen and set(seen) == {1}
    assert native._cxx.threads() == unbounded  # the limit ends with the run
    assert np.array_equal(one, superfacets.segment(as_cloud(pts), 40).labels)


@needs_cxx
@pytest.mark.parametrize("chords", [0.05, 0.2])
def test_orientation_by_blocks_with_long_cycles_matches_numba(chords):
    """Known answer: a ring of 150,000 elements with short hops and random chords between
    far blocks (6 % and 18 % of the edges between blocks: cycles through many blocks,
    paths of forests left out) and quantized normals (ties); the compiled signs and
    components must be numba's Prim's."""
    from scipy.sparse import coo_array

    rng = np.random.default_rng(5)
    n = 150_000
    a = np.arange(n)
    m = int(chords * 3 * n)
    i = np.r_[a, a, rng.integers(0, n, m)]
    j = np.r_[(a + 1) % n, (a + rng.integers(2, 40, n)) % n, rng.integers(0, n, m)]
    keep = i != j
    g = coo_array((np.ones(keep.sum()), (i[keep], j[keep])), shape=(n, n)).tocsr()
    g = (g + g.T).tocsr()
    g.sort_indices()
    indptr, indices = g.indptr.astype(np.int64), g.indices.astype(np.int32)
    normals = np.round(rng.normal(size=(n, 3)))
    normals[(normals == 0).all(axis=1)] = [0.0, 0.0, 1.0]
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    got = {}
    for fn in ("kernel", "reference"):
        sign, comp = np.empty(n, np.int8), np.empty(n, np.int64)
        k = _implementation(fn)("orient.propagate_signs")(indptr, indices, normals, sign, comp)
        got[fn] = (k, sign, comp)
    assert got["kernel"][0] == got["reference"][0] == 1
    assert np.array_equal(got["kernel"][1], got["reference"][1])
    assert np.array_equal(got["kernel"][2], got["reference"][2])
    assert (got["kernel"][1] < 0).sum() > n // 4  # signs that the tree had to turn


@needs_cxx
@pytest.mark.parametrize("source", ["grid", "noisy", "weighted"])
def test_farthest_points_by_groups_of_blocks_match_numba(source):
    """Known answer: the compiled farthest-point sampling skips whole groups of 32 blocks
    that a new center cannot change and takes the next center from the groups' bests; its
    centers must be numba's (every block tested, every block compared), on a grid of
    points with many exactly tied distances, the grid's points moved a little, and the
    same with a scale per point (content-sensitive runs), from 2,000 to 2,560 blocks."""
    rng = np.random.default_rng(8)
    x, y = np.meshgrid(np.arange(300.0), np.arange(240.0))
    c = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)]
    if source != "grid":
        c = c + rng.normal(0, 0.05, c.shape)
    c = np.ascontiguousarray(c)
    order, bstart, bcenter, bradius = native.kernel("farthest.spatial_blocks")(c, 60)
    extra = ()
    if source == "weighted":
        s2 = np.ascontiguousarray((rng.random(c.shape[0]) * 4 + 0.1)[order])
        extra = (s2, np.minimum.reduceat(s2, bstart[:-1]))
    assert bstart.shape[0] - 1 > 64 * 30
    got = {}
    for fn in ("kernel", "reference"):
        out = np.empty(1500, np.int64)
        _implementation(fn)("farthest.farthest_point_blocked")(c, 1500, 17, out, order, bstart,
                                                               bcenter, bradius, *extra)
        got[fn] = out
    assert np.array_equal(got["kernel"], got["reference"])
    assert np.unique(got["kernel"]).shape[0] == 1500
    # and both are the plain loop's centers: the blocks skipped only where no element
    # could get nearer (a scaled run bounds each block by its smallest scale)
    plain = np.empty(1500, np.int64)
    scale = None if not extra else np.ascontiguousarray(np.empty_like(extra[0]))
    if scale is not None:
        scale[order] = extra[0]
    native.kernel("farthest.farthest_point")(c, 1500, 17, plain, scale)
    assert np.array_equal(got["kernel"], plain)


@needs_cxx
def test_int64_adjacency_numbers_give_the_same_labels(monkeypatch):
    """From 2**31 CSR entries on (a cloud of about 100M points), adjacency numbers are
    int64: every kernel that reads them takes that layout too (no other implementation
    to fall back to), with the int32 layout's labels. Lowered here to every graph."""
    from scipy.spatial import Delaunay

    import superfacets.elements.graph as graph_module

    rng = np.random.default_rng(0)
    pts = rng.random((400, 3))
    runs = {
        "faces": lambda: superfacets.segment(creature(20), 20),
        "faces, paper": lambda: superfacets.segment(creature(20), 20, paper=True),
        "faces, flood": lambda: superfacets.segment(creature(20), None, radius=0.1),
        "polygons": lambda: superfacets.segment(_quad_cube(8), 12),
        "vertices": lambda: superfacets.segment(creature(20), 20, elements="vertices"),
        "points": lambda: superfacets.segment(creature(20).centroids, 20),
        "points, swaps and clean-up": lambda: superfacets.segment(
            creature(20).centroids, 20, split_merge=True, cleanup=True),
        "tetrahedra": lambda: superfacets.segment(
            superfacets.TetMesh(pts, Delaunay(pts).simplices), 10),
    }
    narrow = {name: run().labels for name, run in runs.items()}
    monkeypatch.setattr(graph_module, "WIDE_ENTRIES", 0)
    seen = []
    plain = native.kernel

    def kernel(path):  # (records the int64 layouts the kernels are given)
        fn = plain(path)

        def call(*args):
            seen.extend(a.dtype for a in args if isinstance(a, np.ndarray) and a.ndim == 1
                        and a.dtype == np.int64 and path.endswith(("per_entry", "pairs")))
            return fn(*args)
        return call

    monkeypatch.setattr(native, "kernel", kernel)
    for name, run in runs.items():
        np.testing.assert_array_equal(run().labels, narrow[name], err_msg=name)
    assert seen  # the int64 layouts were taken


def test_without_the_compiled_kernels_a_run_says_so_in_one_line(monkeypatch, capsys,
                                                                 tmp_path):
    """A source folder imported without installing (no ``_cxx``): the first kernel a
    run needs raises KernelsMissingError, one line from the command line (exit 2, no
    output written), naming the install to run; --version says so too."""
    from superfacets.cli import main
    from superfacets.errors import KernelsMissingError
    from superfacets.io import write_mesh

    path = tmp_path / "c.off"
    write_mesh(path, creature(16))
    monkeypatch.setattr(native, "_cxx", None)
    monkeypatch.setattr(native, "_why", "not built (no module)")
    monkeypatch.setattr(native, "_chosen", {})
    with pytest.raises(KernelsMissingError, match="pip install"):
        native.kernel("geometry.face_geometry")
    capsys.readouterr()
    assert main(["segment", str(path), "-k", "5", "-o", str(tmp_path / "c.seg")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "compiled kernels are not built" in err, err
    assert not (tmp_path / "c.seg").exists()
    with pytest.raises(SystemExit):
        main(["--version"])
    assert "no kernels: the compiled ones are not built" in capsys.readouterr().out


def test_threads_the_system_refuses_leave_the_same_labels(tmp_path):
    """Under ``ulimit -v`` a thread that could not start was a traceback (the swaps'
    pool) or an abort (the compiled kernels: std::system_error), and one that started
    where no room was left for its thread-local data an abort in glibc: a refused
    thread's share runs on the calling thread, and threads are started only while their
    stacks fit in half the room left. A new process, its address space limited to what it
    holds plus 200 MiB, 64 kernel threads asked for (their 8 MiB stacks cannot all fit):
    the same labels, or, where the arrays find no room, a MemoryError (never an abort)."""
    code = """
import os, re, resource
import numpy as np
import superfacets
from superfacets.inputs.shapes import creature
m = creature(80)
ref = superfacets.segment(m, 80, n_threads=1).labels
pts = m.centroids.copy()
refp = superfacets.segment(pts, 80, n_threads=1).labels
vm = int(re.search(r"VmSize:\\s+(\\d+)", open("/proc/self/status").read()).group(1)) * 1024
resource.setrlimit(resource.RLIMIT_AS, (vm + 200 * 2**20, resource.RLIM_INFINITY))
os.environ["SUPERFACETS_KERNEL_THREADS"] = "64"
try:
    got = superfacets.segment(m, 80, n_threads=16).labels
    gotp = superfacets.segment(pts, 80, n_threads=16).labels
    print(np.array_equal(ref, got), np.array_equal(refp, gotp))
except MemoryError as exc:  # (the threads that did start took the room: a clean error)
    print("MemoryError", exc)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]  # never an abort (terminate called)
    assert out.stdout.split() == ["True", "True"] or out.stdout.startswith("MemoryError")


def test_threads_start_only_while_their_stacks_fit_half_the_room_left():
    """Under an address-space limit the kernels and the Python ranges start as many
    threads as half the room left holds in stacks (the same rule on both sides of the
    seam); without one, as many as asked."""
    code = """
import os, re, resource
os.environ["SUPERFACETS_KERNEL_THREADS"] = "64"
from superfacets._kernels import native
from superfacets._runtime.threads import stack_room_threads
free = native.require().threads(), stack_room_threads()
vm = int(re.search(r"VmSize:\\s+(\\d+)", open("/proc/self/status").read()).group(1)) * 1024
resource.setrlimit(resource.RLIMIT_AS, (vm + 160 * 2**20, resource.RLIM_INFINITY))
stack = resource.getrlimit(resource.RLIMIT_STACK)[0]
stack = 8 * 2**20 if stack == resource.RLIM_INFINITY else max(stack, 65536)
print(*free, native.require().threads(), stack_room_threads(), 1 + int(80 * 2**20 / stack))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]
    free_cxx, free_py, cxx, py, expect = out.stdout.split()
    assert (free_cxx, free_py) == ("64", "None")
    assert abs(int(cxx) - int(expect)) <= 1 and abs(int(py) - int(expect)) <= 1, out.stdout
    assert int(expect) < 64


def test_python_threads_the_system_refuses_run_on_the_calling_thread(monkeypatch):
    """The swaps and the bounded classification start Python threads: where one is
    refused ("can't start new thread"), its call runs on the calling thread."""
    import threading

    from superfacets._runtime.threads import in_parallel

    mesh = creature(40)
    ref = superfacets.segment(mesh, 60, n_threads=1).labels
    refused = []

    def start(self):
        if self.name == "superfacets":
            refused.append(1)
            raise RuntimeError("can't start new thread")
        return real(self)

    real = threading.Thread.start
    monkeypatch.setattr(threading.Thread, "start", start)
    assert in_parallel(lambda t: t * t, 4) == [0, 1, 4, 9] and len(refused) == 3
    got = superfacets.segment(creature(40), 60, n_threads=2).labels
    np.testing.assert_array_equal(got, ref)
    assert len(refused) > 3


@needs_cxx
def test_an_interrupt_stops_the_compiled_kernels_at_once():
    """A compiled kernel holds no GIL, so Python's signal handlers wait for it to return:
    the kernels' long loops read an interrupt flag (``_cxx.interrupt``) and stop with a
    KeyboardInterrupt, for every kind of run."""
    cxx = native.require()
    m = creature(40)
    try:
        cxx.interrupt(1)
        for run in (lambda: superfacets.segment(creature(40), 20),  # graph, expansions
                    lambda: superfacets.segment(m.centroids, 20),  # kNN, PCA, orientation
                    lambda: superfacets.segment(m, 20, assignment="exact")):
            with pytest.raises(KeyboardInterrupt):
                run()
    finally:
        cxx.interrupt(0)
    assert superfacets.segment(m, 20).n_segments == 20  # the flag cleared: runs again


@pytest.mark.parametrize("sig, code", [("SIGTERM", 143), ("SIGINT", 130)])
def test_a_signal_stops_a_run_within_a_second_at_any_moment(tmp_path, sig, code):
    """A run of 1M points from the command line, signalled at several moments (reading,
    the graph build, the passes): it ends within a second (two on a busy machine), with
    130 or 143, one line, and no output file."""
    import signal
    import time

    pts = np.random.default_rng(0).random((1_000_000, 3))
    np.save(tmp_path / "p.npy", pts)
    for delay in (0.8, 2.0, 3.2):
        proc = subprocess.Popen([sys.executable, "-m", "superfacets", "segment",
                                 str(tmp_path / "p.npy"), "-k", "500", "-q",
                                 "-o", str(tmp_path / "p.seg")], stderr=subprocess.PIPE,
                                text=True)
        time.sleep(delay)
        if proc.poll() is not None:
            break  # (a fast machine finished first)
        t0 = time.perf_counter()
        proc.send_signal(getattr(signal, sig))
        err = proc.communicate(timeout=60)[1]
        took = time.perf_counter() - t0
        assert proc.returncode == code, err
        assert took < 2.0, (delay, took)
        assert err.strip().count("\n") == 0 and "Traceback" not in err
        assert not (tmp_path / "p.seg").exists()


@needs_cxx
def test_the_scene_merges_give_numba_results(shadowed):
    """``merge_cost='scene'`` (the merging kernel's fourth cost) on a terrain with bushes,
    ``'noise'`` on a noise-free one, and the default on an exact plane (the flat test's
    rounding): the compiled kernel's merges are numba's, call by call."""
    calls, _ = shadowed
    rng = np.random.default_rng(3)
    xy = rng.random((6000, 2))
    ground = np.c_[xy, 0.01 * np.sin(6 * xy[:, 0]) + 0.002 * rng.standard_normal(6000)]
    d = rng.standard_normal((1200, 3))
    d[:, 2] = np.abs(d[:, 2])
    bushes = 0.05 * d / np.linalg.norm(d, axis=1, keepdims=True) + np.repeat(
        rng.random((3, 3)) * [0.8, 0.8, 0] + [0.1, 0.1, 0], 400, axis=0)
    r = superfacets.segment(np.vstack([ground, bushes]), 10, n_threads=1, merge_cost="scene")
    assert r.n_segments == 10 and calls.get("hierarchy.merge_levels", 0) >= 2
    # ``'noise'`` on the ground without its noise: the rise's unit infinite, Ward's term alone
    before = calls.get("hierarchy.merge_levels", 0)
    r = superfacets.segment(np.c_[xy, 0.01 * np.sin(6 * xy[:, 0])], 10, n_threads=1,
                            merge_cost="noise")
    assert r.n_segments == 10 and calls["hierarchy.merge_levels"] > before
    # an exact plane: the flat test passes what lies within its union's rounding
    before = calls["hierarchy.merge_levels"]
    r = superfacets.segment(superfacets.PointCloud(np.c_[xy * 50, np.zeros(6000)],
                                                   up=(0, 0, 1)), 30, n_threads=1)
    assert r.n_segments == 30 and calls["hierarchy.merge_levels"] > before


@needs_cxx
@pytest.mark.parametrize("planarity,max_rise,max_size,min_count",
                         [(2, 1e-4, 0.0, 0.0), (2, 1e-3, 40.0, 0.0), (2, 1e-4, 0.0, 6.0),
                          (3, 1e-3, 40.0, 0.0), (1, 0.0, 25.0, 0.0)])
def test_merges_that_stop_short_give_numba_results(planarity, max_rise, max_size, min_count):
    """Known answer against the reference: the merging kernel where most pairs may not
    merge (the flat gate, read over the smaller node's elements or ``min_count``, the size
    bound) and the targets are not all reached. Pairs of no finite cost never enter the
    compiled kernel's heap; its merges, the nodes' sums it leaves and the roots at every
    target are numba's to the bit."""
    rng = np.random.default_rng(7)
    k = 400
    side = 20
    i, j = np.divmod(np.arange(k), side)
    ea = np.r_[np.flatnonzero(j < side - 1), np.flatnonzero(i < side - 1)]
    eb = np.r_[ea[:side * (side - 1)] + 1, ea[side * (side - 1):] + side]
    stats = np.c_[np.ones(ea.size), rng.random(ea.size), rng.random(ea.size)]
    area = rng.integers(1, 12, k).astype(np.float64)
    centre = np.c_[i, j, 0.02 * rng.standard_normal(k) * (i > 10)]
    wsum = centre * area[:, None]
    scatter = np.c_[area * 0.1, area * 0.1, area * rng.random(k) * 1e-3, np.zeros((k, 3))]
    fsum = np.zeros((k, 0))
    targets = np.array([300, 120, 40, 1], dtype=np.int64)
    out = []
    for f in (native.kernel("hierarchy.merge_levels"), reference("hierarchy.merge_levels")):
        arrays = [a.copy() for a in (area, wsum, fsum, scatter)]
        roots = f(k, ea.copy(), eb.copy(), stats.copy(), *arrays, planarity, 0.5, 0.2, 0.0,
                  1.0, max_rise, targets.copy(), max_size, min_count)
        out.append((np.asarray(roots), arrays))
    (got, got_arrays), (want, want_arrays) = out
    assert np.array_equal(got, want)
    assert all(np.array_equal(a, b) for a, b in zip(got_arrays, want_arrays))
    # the merging stopped short of the last target: the roots there are where it stopped
    assert np.unique(got[-1]).size > 1
