"""Connected superfacets: merge stray pieces into their neighbours.

The bounded expansion can leave a superfacet in several connected pieces
of the element graph. :func:`enforce_connectivity` keeps one piece per superfacet (the one
holding its center, else the largest by area) and merges every other piece
into the neighbouring region with which it shares the longest boundary, as
scikit-image's ``slic(enforce_connectivity=True)`` does for superpixels.
With ``min_elements``, a superfacet of fewer elements goes the same way (as
scikit-image's ``min_size_factor``; ``segment(..., min_elements=N)`` applies
it after a run): on a LiDAR sweep the sparse far range gets superpoints of
one or two points (``docs/notes/superpoints.md``, "Superpoints of one point").
"""

from __future__ import annotations

import numpy as np

from .._kernels import native
from ..elements.builders import as_element_graph
from ..elements.labels import check_labels, relabel_dense
from .params import check_int

__all__ = ["enforce_connectivity", "label_components"]


def label_components(graph, labels: np.ndarray) -> np.ndarray:
    """Connected pieces of every superfacet.

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
    labels : (m,) int ndarray

    Raises
    ------
    ParameterError
        If ``labels`` is not one integer per element.

    Returns
    -------
    pieces : (m,) int64 ndarray
        Piece id of each face; two faces share a piece id iff they have the
        same label and are connected through faces of that label.
    """
    graph = as_element_graph(graph)
    labels = check_labels(labels, graph.n_elements, per=graph.element)
    same_label_components = native.kernel("connectivity.same_label_components")

    # a depth-first search per piece over the graph's CSR, pieces numbered by their
    # lowest element (as scipy's connected_components of the same-label subgraph)
    return same_label_components(graph.indptr, graph.indices, np.ascontiguousarray(labels))


def _summed_csr(rows: np.ndarray, cols: np.ndarray, vals: np.ndarray,
                n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ``n x n`` sparse matrix of the entries ``(rows, cols, vals)``, duplicates
    summed, as CSR arrays with sorted columns (scipy's ``coo_array(...).tocsr()``
    without importing scipy.sparse, about 0.15 s of a new process)."""
    key, inv = np.unique(rows * np.int64(n) + cols, return_inverse=True)
    # (float64 even when empty: numpy's bincount of no entries is int64)
    data = np.bincount(inv.ravel(), weights=vals, minlength=key.shape[0]).astype(np.float64)
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(key // n, minlength=n), out=indptr[1:])
    return indptr, key % n, data


def enforce_connectivity(graph, labels: np.ndarray, centers: np.ndarray | None = None, *,
                         min_elements: int = 1) -> np.ndarray:
    """Make every superfacet connected in the element graph (and, optionally, not tiny).

    Parameters
    ----------
    graph : ElementGraph, Mesh, trimesh.Trimesh or (vertices, faces)
        Its adjacency, sizes and border lengths are used; the boundary length
        between two pieces is the total length of the borders they share
        (for a mesh: of the mesh edges).
    labels : (m,) int ndarray
        Labels ``0..K-1``, one per element.
    centers : (K,) int ndarray, optional
        Center face of each label; the piece holding it keeps the label.
        Without it (or for a label whose center lies elsewhere) the piece of
        largest area keeps it.
    min_elements : int, default 1
        A superfacet whose kept piece holds fewer elements is merged as a
        stray too (into the neighbour with the longest shared border), unless
        it has no neighbour (a connected component of the graph of its own) or
        smaller strays merged into it first have made it that large; it joins a
        small superfacet still below that size where it touches one: where most
        superfacets are small, they join each other into pieces of about
        ``min_elements``, not into one. 1 merges none.

    Returns
    -------
    labels : (m,) int64 ndarray
        Dense labels ``0..K'-1`` with ``K' <= K``, each superfacet one
        connected piece of the face graph. Labels that keep their main piece
        keep their relative order.

    Raises
    ------
    ParameterError
        If ``labels`` is not one integer per element, or ``min_elements < 1``.

    Examples
    --------
    A strip of 8 triangles, each adjacent to the next:

    >>> v = np.c_[np.r_[0:5, 0:5], np.repeat([0, 1], 5), np.zeros(10)].astype(float)
    >>> f = np.concatenate([[[i, i + 1, i + 5], [i + 1, i + 6, i + 5]] for i in range(4)])
    >>> labels = np.array([0, 0, 0, 1, 0, 2, 2, 2])  # 0 in two pieces, 1 a single face
    >>> enforce_connectivity((v, f), labels, np.array([0, 3, 6]))
    array([0, 0, 0, 1, 2, 2, 2, 2])
    >>> enforce_connectivity((v, f), labels, np.array([0, 3, 6]), min_elements=2)
    array([0, 0, 0, 0, 1, 1, 1, 1])

    (Face 4 shares a diagonal with face 5 and a shorter edge with face 3.)

    Notes
    -----
    Stray pieces are merged smallest first; each goes to the adjacent piece
    (after earlier merges) with the longest shared boundary, ties to the
    lowest piece id. A piece with no neighbour cannot occur for labels made
    by the method (expansions never leave a connected component of the
    mesh); if one does, it becomes a superfacet of its own.
    """
    merge_strays = native.kernel("connectivity.merge_strays")
    stray_borders = native.kernel("connectivity.stray_borders")

    g = as_element_graph(graph)
    labels = check_labels(labels, g.n_elements, per=g.element)
    min_elements = check_int("min_elements", min_elements, lo=1)
    piece = label_components(g, labels)
    n_pieces = int(piece.max()) + 1
    piece_label = np.empty(n_pieces, dtype=np.int64)
    piece_label[piece] = labels
    k = int(labels.max()) + 1
    dense = relabel_dense(labels)
    count = np.bincount(piece, minlength=n_pieces)
    if n_pieces == int(dense.max()) + 1 and count.min() >= min_elements:  # nothing to merge
        return dense
    del dense

    area = np.bincount(piece, weights=g.sizes, minlength=n_pieces)
    # main piece of each label: the one holding the center, else the largest
    main = np.full(k, -1, dtype=np.int64)
    if centers is not None:
        centers = np.asarray(centers, dtype=np.int64)[:k]
        s = np.arange(centers.size)
        ok = (centers >= 0) & (centers < g.n_elements)
        ok[ok] = labels[centers[ok]] == s[ok]
        main[s[ok]] = piece[centers[ok]]
    order = np.lexsort((np.arange(n_pieces), -area))  # largest first, then lowest id
    present, first = np.unique(piece_label[order], return_index=True)
    free = main[present] < 0  # no center's piece: the first in that order
    main[present[free]] = order[first[free]]
    is_main = np.zeros(n_pieces, dtype=bool)
    is_main[main[main >= 0]] = True
    tiny = is_main & (count < min_elements)  # merges like a stray while it is small
    is_main &= ~tiny

    # boundary length between a stray and each adjacent piece (the rows of the strays
    # alone, entries in the order of the whole matrix's: the same sums)
    nb_indptr, nb_indices, nb_data = _summed_csr(
        *stray_borders(g.indptr, g.indices, piece, is_main, *g.border_arrays()), n_pieces)

    strays = np.flatnonzero(~is_main)
    strays = strays[np.lexsort((strays, area[strays]))]  # smallest first
    root = merge_strays(strays, nb_indptr, nb_indices, nb_data, n_pieces,
                        count.astype(np.int64), tiny, min_elements)
    # final label of a root: its label if it is a main piece, else a new one (after them)
    final = np.where(is_main[root], piece_label[root], k + root)
    return relabel_dense(final[piece])
