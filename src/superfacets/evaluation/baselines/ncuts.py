"""Normalized cuts on the face graph, set up as in the paper's comparison.

Simari et al. (2014, section 5) compare their method with normalized cuts
(Shi and Malik 1997/2000): the dense all-pairs shortest-path distance matrix
over the face graph, with the *same* edge weights as the method and no bound
on the expansion, handed to a k-way normalized cut. We do exactly that:

1. **Distances.** Dijkstra from every face (``scipy.sparse.csgraph.dijkstra``,
   a block of sources at a time), stored as one dense ``(m, m)`` float32
   matrix: ``4 m^2`` bytes, the quadratic memory the paper points at.
2. **Affinity.** A Gaussian kernel ``W_ij = exp(-D_ij^2 / (2 sigma^2))``.
   The bandwidth ``sigma`` is the *radius of one superfacet measured in the
   same metric*: for every face, the distance to its ``ceil(m / k_ref)``-th
   nearest face (``k_ref = reference_segments``, default 150, the paper's
   usual ``k``), then the median over faces, times ``bandwidth`` (default 1).
   Why: a kernel much wider than a superfacet blurs the eigenvectors that
   separate neighbouring superfacets (the spectrum collapses after a few
   dozen eigenvalues); a much narrower one makes faces near a region's
   border look unrelated to their own center. Measuring the radius in the
   weighted metric (not in Euclidean units) keeps the kernel meaningful at
   every ``alpha``: the angular term stretches distances across creases,
   and the kernel cuts there. ``sigma`` does not depend on ``k``, so one
   embedding serves every number of segments. Entries below ``cutoff``
   (default ``1e-4``, i.e. ``D > 4.3 sigma``) are dropped, which is how
   Shi and Malik's own affinities are built (zero beyond a radius); the
   row sums change by far less than 1 %.
3. **Embedding.** The leading eigenvectors of ``D^-1/2 W D^-1/2`` (ARPACK
   through ``scipy.sparse.linalg.eigsh``), scaled by ``D^-1/2``: the
   relaxed normalized-cut indicators (Shi and Malik, eq. 8), the same
   embedding scikit-learn's spectral clustering builds.
4. **Discretization.** Yu and Shi's (2003) multiclass rounding of the first
   ``k`` eigenvectors (:func:`discretize`, written from their paper; the
   results in ``docs/results`` were made with scikit-learn's version of the
   same algorithm, before it was replaced to avoid a private scikit-learn
   function).

Steps 1-3 are done once per mesh and weighting (:func:`ncut_embedding`);
:func:`normalized_cuts` then labels the mesh for any ``k`` up to the number
of eigenvectors computed.

Memory is checked against ``memory_limit`` before each large allocation:
the distance matrix (known from ``m``) and the sparse affinity (known once
its nonzeros are counted). A mesh that would not fit raises
:class:`~superfacets.errors.MemoryLimitError` stating both numbers, before
anything big is allocated. The paper's implementation skipped the 25
benchmark meshes of about 50k faces whose matrix did not fit in 64 GB.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass

import numpy as np

from ..._runtime.progress import new_bar
from ...elements.faces import face_graph
from ...elements.labels import relabel_dense
from ...errors import MemoryLimitError, ParameterError
from ...inputs.convert import as_mesh
from ...method.params import check_n_segments, check_positive
from ...method.weights import edge_weights

__all__ = ["discretize", "NcutEmbedding", "ncut_embedding", "normalized_cuts",
           "ncut_memory_estimate",
           "default_memory_limit"]

#: Fraction of physical memory one normalized-cuts run may use by default.
DEFAULT_MEMORY_FRACTION = 0.4


def default_memory_limit() -> int:
    """Default memory limit of :func:`ncut_embedding`, in bytes.

    ``DEFAULT_MEMORY_FRACTION`` (40 %) of the machine's physical memory, or
    4 GiB where that cannot be read.
    """
    try:
        total = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):  # pragma: no cover - not POSIX
        total = 10 * 2**30
    return int(DEFAULT_MEMORY_FRACTION * total)


def ncut_memory_estimate(n_faces: int, n_components: int = 300) -> int:
    """Bytes :func:`ncut_embedding` needs before the affinity is known.

    The dense float32 distance matrix (``4 m^2``), one block of Dijkstra
    rows in float64, the ARPACK work space (``2 c + 1`` Lanczos vectors)
    and the ``O(m)`` arrays.

    Parameters
    ----------
    n_faces : int
        ``m``.
    n_components : int, default 300
        Eigenvectors ``c``.

    Returns
    -------
    int
    """
    m = int(n_faces)
    c = min(int(n_components), m)
    return 4 * m * m + 8 * _block_rows(m) * m + 8 * m * (2 * c + 1) + 64 * m


def _block_rows(m: int) -> int:
    return max(1, min(m, (32 * 2**20) // (8 * max(m, 1))))  # 32 MiB of float64 rows


@dataclass(frozen=True, eq=False)
class NcutEmbedding:
    """The spectral embedding shared by every ``k`` of one mesh and weighting.

    Attributes
    ----------
    vectors : (m, c) float64 ndarray
        Generalized eigenvectors of ``(D - W) y = lambda D y``, i.e. the
        eigenvectors of ``D^-1/2 W D^-1/2`` scaled by ``D^-1/2``, by
        decreasing eigenvalue of ``D^-1/2 W D^-1/2``; signs fixed so the
        entry of largest magnitude of each column is positive.
    eigenvalues : (c,) float64 ndarray
        Eigenvalues of ``D^-1/2 W D^-1/2``, decreasing, in ``(-1, 1]``.
    sigma : float
        Kernel bandwidth used, in the units of the edge weights.
    nnz : int
        Nonzeros of the sparse affinity (both triangles, diagonal included).
    seconds : dict
        Wall-clock seconds of ``distances``, ``affinity`` and ``eigenvectors``.
    peak_bytes : int
        Bytes of the large arrays alive at the peak (distance matrix plus
        sparse affinity), as estimated for the memory check.
    """

    vectors: np.ndarray
    eigenvalues: np.ndarray
    sigma: float
    nnz: int
    seconds: dict
    peak_bytes: int

    @property
    def n_components(self) -> int:
        """Number of eigenvectors ``c``."""
        return int(self.vectors.shape[1])

    @property
    def total_seconds(self) -> float:
        """Seconds of the whole embedding (distances, affinity, eigenvectors)."""
        return float(sum(self.seconds.values()))


def _check_limit(what: str, required: int, limit: int, m: int) -> None:
    if required > limit:
        gib = 2.0**30
        raise MemoryLimitError(
            f"normalized cuts on {m} faces needs about {required / gib:.1f} GiB for the "
            f"{what} (limit {limit / gib:.1f} GiB); raise the limit (memory_limit; "
            f"memory_limit_gib in the runner and the command line) or use a smaller mesh",
            required, limit)


def _all_pair_distances(graph, m: int, nth: int, progress: bool):
    """Every face's graph distance to every other (float32, ``m x m``, a block of rows
    at a time) and each row's ``nth`` smallest (the bandwidth's reference)."""
    from scipy.sparse.csgraph import dijkstra

    dist = np.empty((m, m), dtype=np.float32)
    kth = np.empty(m, dtype=np.float64)
    b = _block_rows(m)
    starts = range(0, m, b)
    if progress:
        starts = new_bar(starts, desc="all-pairs distances", unit="block", leave=False)
    for s in starts:
        e = min(m, s + b)
        block = dijkstra(graph, directed=True, indices=np.arange(s, e))
        kth[s:e] = np.partition(block, nth, axis=1)[:, nth]
        dist[s:e] = block
    return dist, kth


def _leading_eigenvectors(affinity, c: int, dense_solver: bool, gen):
    """The ``c`` largest eigenvalues of the normalized affinity and their vectors (LAPACK
    on small problems, else ARPACK from a seeded start)."""
    m = affinity.shape[0]
    if dense_solver:
        from scipy.linalg import eigh

        return eigh(affinity.toarray(), subset_by_index=[m - c, m - 1])
    from scipy.sparse.linalg import eigsh

    v0 = gen.uniform(-1.0, 1.0, m)
    return eigsh(affinity, k=c, which="LA", v0=v0, tol=1e-6)


def ncut_embedding(mesh, n_components: int = 300, *, alpha: float = 100.0,
                   eta_convex: float = 0.2, weighting: str = "paper", bandwidth: float = 1.0,
                   reference_segments: int = 150, cutoff: float = 1e-4,
                   memory_limit: int | None = None, rng=None,
                   progress: bool = False) -> NcutEmbedding:
    """All-pairs distances, Gaussian affinity and spectral embedding of a mesh.

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or tuple of ((n, 3) float, (m, 3) int) ndarray
    n_components : int, default 300
        Eigenvectors to compute, ``c``; :func:`normalized_cuts` can then use
        any ``n_segments <= c``. Clipped to ``m``.
    alpha, eta_convex : float
        Edge weights of the paper (eqs. 1-3); ``alpha`` default 100, the
        paper's best trade-off for normalized cuts.
    weighting : {'paper', 'shlafman'}, default 'paper'
    bandwidth : float, default 1
        Multiplier of the kernel bandwidth (see the module notes), ``> 0``.
    reference_segments : int, default 150
        ``k_ref``: ``sigma`` is the median distance from a face to its
        ``ceil(m / k_ref)``-th nearest face.
    cutoff : float, default 1e-4
        Affinities below it are dropped, in ``[0, 1)``.
    memory_limit : int, optional
        Bytes this call may use; default :func:`default_memory_limit`
        (40 % of physical memory).
    rng : None, int or numpy.random.Generator
        Start vector of ARPACK.
    progress : bool, default False
        Progress bar over the Dijkstra sources.

    Returns
    -------
    NcutEmbedding

    Raises
    ------
    MemoryLimitError
        Before allocating, when the distance matrix or the sparse affinity
        would exceed ``memory_limit``; the message gives both numbers.
    ParameterError
        On a parameter out of range.
    InvalidMeshError, TypeError
        On a bad mesh.

    References
    ----------
    .. [1] J. Shi, J. Malik, "Normalized Cuts and Image Segmentation",
       IEEE TPAMI 22(8), 2000.
    .. [2] S. X. Yu, J. Shi, "Multiclass Spectral Clustering", ICCV 2003.
    .. [3] G. Simari, G. Picciau, L. De Floriani, "Fast and Scalable Mesh
       Superfacets", Computer Graphics Forum 33(7), 2014, section 5.
    """
    from scipy.sparse import csr_array

    mesh = as_mesh(mesh)
    mesh.check_usable()
    m = mesh.n_faces
    c = min(check_n_segments(n_components, 2**62), m)
    bandwidth = check_positive("bandwidth", bandwidth)
    k_ref = min(check_n_segments(reference_segments, 2**62), m)
    cutoff = float(cutoff)
    if not (0 <= cutoff < 1):
        raise ParameterError(f"cutoff must be in [0, 1), got {cutoff!r}")
    limit = default_memory_limit() if memory_limit is None else int(memory_limit)
    if limit <= 0:
        raise ParameterError(f"memory_limit must be > 0 bytes, got {memory_limit!r}")
    dense_solver = m <= 1500 or c >= m - 1
    need = ncut_memory_estimate(m, c) + (8 * m * m if dense_solver else 0)
    _check_limit("dense distance matrix", need, limit, m)
    gen = np.random.default_rng(rng)

    seconds = {}
    t0 = time.perf_counter()
    w = edge_weights(mesh, weighting, alpha=alpha, eta_convex=eta_convex)
    g = face_graph(mesh)
    graph = csr_array((w[g.dual_edge], g.indices, g.indptr),
                      shape=(m, m))
    dist, kth = _all_pair_distances(graph, m, min(m - 1, math.ceil(m / k_ref)), progress)
    b = _block_rows(m)
    seconds["distances"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    finite = kth[np.isfinite(kth) & (kth > 0)]
    sigma = bandwidth * (float(np.median(finite)) if finite.size else 1.0)
    scale = -0.5 / (sigma * sigma)
    counts = np.empty(m, dtype=np.int64)
    for s in range(0, m, b):  # affinity in place, row block by row block
        blk = dist[s:s + b]
        np.square(blk, out=blk)
        blk *= scale
        np.exp(blk, out=blk)  # exp(-inf) = 0 between components
        counts[s:s + b] = np.count_nonzero(blk > cutoff, axis=1)
    nnz = int(counts.sum())
    peak = 4 * m * m + 12 * nnz
    _check_limit("sparse affinity", need + 12 * nnz, limit, m)
    indptr = np.zeros(m + 1, dtype=np.int64)
    np.cumsum(counts, out=indptr[1:])
    indices = np.empty(nnz, dtype=np.int32)
    data = np.empty(nnz, dtype=np.float64)
    for s in range(0, m, b):
        blk = dist[s:s + b]
        r, col = np.nonzero(blk > cutoff)
        lo, hi = indptr[s], indptr[min(m, s + b)]
        indices[lo:hi] = col
        data[lo:hi] = blk[r, col]
    del dist
    degree = np.add.reduceat(data, indptr[:-1]) if nnz else np.ones(m)
    isd = 1.0 / np.sqrt(degree)  # the diagonal is 1, so every degree is >= 1
    for s in range(0, m, b):  # D^-1/2 W D^-1/2, a row block at a time (no nnz-sized index)
        e = min(m, s + b)
        lo, hi = indptr[s], indptr[e]
        data[lo:hi] *= np.repeat(isd[s:e], counts[s:e])
        data[lo:hi] *= isd[indices[lo:hi]]
    affinity = csr_array((data, indices, indptr), shape=(m, m))
    seconds["affinity"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    vals, vecs = _leading_eigenvectors(affinity, c, dense_solver, gen)
    order = np.argsort(-vals, kind="stable")
    vals = vals[order]
    vecs = vecs[:, order] * isd[:, None]
    big = np.argmax(np.abs(vecs), axis=0)
    vecs *= np.sign(vecs[big, np.arange(vecs.shape[1])])
    seconds["eigenvectors"] = time.perf_counter() - t0
    return NcutEmbedding(np.ascontiguousarray(vecs), vals, float(sigma), nnz, seconds, peak)


def normalized_cuts(mesh, n_segments: int = 150, *, embedding: NcutEmbedding | None = None,
                    rng=None, **embedding_options) -> np.ndarray:
    """k-way normalized cut of the face graph (the paper's baseline, section 5).

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or tuple of ((n, 3) float, (m, 3) int) ndarray
    n_segments : int, default 150
        Number of segments ``k``, ``1 <= k <= m``.
    embedding : NcutEmbedding, optional
        From :func:`ncut_embedding` on the same mesh, with at least
        ``n_segments`` eigenvectors; computed (with ``n_components =
        n_segments``) when omitted.
    rng : None, int or numpy.random.Generator
        Seeds ARPACK (when the embedding is computed here) and the random
        rotations of the discretization.
    **embedding_options
        Passed to :func:`ncut_embedding` (``alpha``, ``bandwidth``,
        ``memory_limit``, ...) when ``embedding`` is omitted.

    Returns
    -------
    labels : (m,) int64 ndarray
        Dense ``0..K-1``, ``K <= n_segments`` (the discretization can leave
        a class empty). Segments are not forced to be face-connected.

    Raises
    ------
    MemoryLimitError
        When the embedding would not fit in ``memory_limit`` (see
        :func:`ncut_embedding`).
    ParameterError
        If ``n_segments`` is out of range, ``embedding`` has fewer than
        ``n_segments`` eigenvectors or was made for another mesh, or with
        both ``embedding`` and ``embedding_options``.

    Examples
    --------
    >>> from superfacets.evaluation.baselines import normalized_cuts
    >>> mesh = trimesh.creation.icosphere(subdivisions=2)
    >>> labels = normalized_cuts(mesh, 8, rng=0)
    >>> labels.shape, int(labels.max()) + 1
    ((320,), 8)
    """

    mesh = as_mesh(mesh)
    k = check_n_segments(n_segments, mesh.n_faces)
    gen = np.random.default_rng(rng)
    if embedding is None:
        embedding = ncut_embedding(mesh, k, rng=gen, **embedding_options)
    elif embedding_options:
        raise ParameterError("give either an embedding or options to compute one, not both: "
                             f"{sorted(embedding_options)}")
    if embedding.vectors.shape[0] != mesh.n_faces:
        raise ParameterError(f"embedding has {embedding.vectors.shape[0]} rows, the mesh "
                             f"{mesh.n_faces} faces")
    if embedding.n_components < k:
        raise ParameterError(f"embedding has {embedding.n_components} eigenvectors, "
                             f"n_segments={k} needs {k}")
    if k == 1:
        return np.zeros(mesh.n_faces, dtype=np.int64)
    return relabel_dense(discretize(embedding.vectors[:, :k], rng=gen))


def discretize(vectors: np.ndarray, rng=None, max_iter: int = 50) -> np.ndarray:
    """Discrete labels from a k-way spectral embedding (Yu and Shi 2003).

    The rows of ``vectors`` are normalized to unit length; an orthonormal
    rotation ``R`` and a partition are then found in turn: each row takes the
    column of ``vectors R`` where it is largest, and ``R`` is the rotation that
    best aligns the embedding with that partition (an orthogonal Procrustes
    problem, solved by one SVD), until the objective stops improving. ``R``
    starts from ``k`` rows as far from orthogonal to each other as possible,
    the first drawn at random.

    Parameters
    ----------
    vectors : (n, k) float ndarray
        Eigenvectors of the normalized affinity, one row per element.
    rng : None, int or numpy.random.Generator
        Draws the first row of the initial rotation.
    max_iter : int, default 50
        Rotations at most.

    Returns
    -------
    labels : (n,) int64 ndarray
        In ``0..k-1`` (a class may stay empty).

    References
    ----------
    S. X. Yu, J. Shi, "Multiclass spectral clustering", ICCV 2003, section 4.

    Examples
    --------
    >>> v = np.repeat(np.eye(3), 4, axis=0) + 0.01
    >>> discretize(v, rng=0).reshape(3, 4)[:, 0].size
    3
    """
    gen = np.random.default_rng(rng)
    x = np.asarray(vectors, dtype=np.float64)
    n, k = x.shape
    norm = np.linalg.norm(x, axis=1, keepdims=True)
    x = x / np.where(norm > 0, norm, 1.0)
    rot = np.empty((k, k))
    rot[:, 0] = x[gen.integers(n)]
    overlap = np.zeros(n)
    for j in range(1, k):  # each next column: the row least aligned with those chosen
        overlap += np.abs(x @ rot[:, j - 1])
        rot[:, j] = x[np.argmin(overlap)]
    best = -np.inf
    labels = np.argmax(x @ rot, axis=1)
    for _ in range(max_iter):
        labels = np.argmax(x @ rot, axis=1)
        onehot = np.zeros((n, k))
        onehot[np.arange(n), labels] = 1.0
        u, s, vt = np.linalg.svd(onehot.T @ x)
        score = float(s.sum())  # the objective: trace of the aligned embedding
        if score <= best * (1 + 1e-12):
            break
        best = score
        rot = vt.T @ u.T
    return labels.astype(np.int64)
