"""A scene segmented object by object, with labels unique over the scene."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..checks import check_n_segments
from ..errors import ParameterError, SuperfacetsError
from ..graph.hierarchy import Hierarchy, wanted_levels
from ..inputs.cloud import PointCloud
from ..inputs.convert import as_mesh
from ..inputs.mesh import Mesh
from ..method.params import DEFAULTS as _D
from ..method.params import check_int
from .segmentation import segment

if TYPE_CHECKING:
    from .segmentation import SegmentationResult

__all__ = ["segment_objects", "objects_hierarchy"]


def segment_objects(mesh, n_segments: int = _D.n_segments, **options
                    ) -> tuple[np.ndarray, list[SegmentationResult]]:
    """Segment each object of a scene on its own, with labels unique over the scene.

    The ``n_segments`` superfacets are shared out among the objects by area
    (largest remainders; at least one per object, at most its faces), each
    object is segmented alone (its own bounding box, radius and centers),
    and its labels are offset by the superfacets of the objects before it.

    Parameters
    ----------
    mesh : Mesh, PointCloud, or any form :func:`superfacets.inputs.convert.as_mesh` accepts
        With ``mesh.objects`` (a scene; the scans of an E57 file); an input without is
        one object. A cloud's count is shared out by valid points, each scan's normals
        facing its own scanner (``object_viewpoints``).
    n_segments : int, default 150
        Superfacets in all (more when there are more objects than that).
    **options
        Keyword arguments of :func:`segment` (``alpha``, ``init``, ...; not
        ``radius``).

    Returns
    -------
    labels : (m,) int64 ndarray
        Dense over the whole mesh; object ``i``'s labels follow object ``i-1``'s
        (a cloud's invalid points: -1).
    results : list of SegmentationResult
        One per object, in order.

    Raises
    ------
    ParameterError, InvalidMeshError
        As :func:`segment`, the message naming the object; ``n_segments`` above the
        scene's faces (a cloud's valid points).

    Examples
    --------
    >>> scene = trimesh.Scene([trimesh.creation.icosphere(), trimesh.creation.box()])
    >>> labels, parts = segment_objects(scene, 20)
    >>> [r.n_segments for r in parts], int(labels.max()) + 1
    ([14, 6], 20)
    """

    if options.get("radius") is not None:
        raise ParameterError("segmenting per object takes n_segments, not radius")
    k = check_int("n_segments", n_segments, lo=1)
    if isinstance(mesh, PointCloud):
        return _cloud_objects(mesh, check_n_segments(k, mesh.n_points, "points"), options)
    mesh = as_mesh(mesh)
    check_n_segments(k, mesh.n_faces)  # (as one run refuses it: no object's count silently cut)
    objects = mesh.objects or ((mesh.name or "mesh", 0, mesh.n_faces),)
    areas = np.array([mesh.areas[a:b].sum() for _, a, b in objects])
    faces = np.array([b - a for _, a, b in objects])
    ks = _shares(k, areas, faces)
    labels = np.empty(mesh.n_faces, dtype=np.int64)
    results, base = [], 0
    for (name, a, b), k_i in zip(objects, ks.tolist()):
        part = Mesh(mesh.vertices, mesh.faces[a:b], name=f"{mesh.name or 'mesh'}:{name}",
                    colors=mesh.colors,
                    face_colors=None if mesh.face_colors is None else mesh.face_colors[a:b])
        try:
            r = segment(part, k_i, **options)
        except SuperfacetsError as exc:
            raise type(exc)(f"object {name!r} (faces {a}-{b - 1}): {exc}") from None
        labels[a:b] = r.labels + base
        base += r.n_segments
        results.append(r)
    return labels, results


def objects_hierarchy(results, levels, *, cost: str = "ward",
                      extent_weight: float | None = None) -> Hierarchy:
    """Nested coarser levels of a scene segmented object by object
    (:func:`segment_objects`), numbered over the scene as its labels are.

    Each level's segments are shared out among the objects in proportion to their
    superfacets (largest remainders, at least one each, never more than the finer level
    gave the object), and each object's are its own hierarchy's
    (:meth:`~superfacets.api.result.SegmentationResult.hierarchy`): no segment joins two
    objects.

    Parameters
    ----------
    results : list of SegmentationResult
        :func:`segment_objects`' results, in order.
    levels : int or sequence of int
        Numbers of segments of the levels, each at least the number of objects and at
        most the superfacets in all.
    cost, extent_weight
        As :meth:`~superfacets.api.result.SegmentationResult.hierarchy`.

    Returns
    -------
    Hierarchy
        Over the scene's labels: ``h.labels(i, labels)``.

    Raises
    ------
    ParameterError
        If a level is below the number of objects or above the superfacets in all.

    Examples
    --------
    >>> scene = trimesh.Scene([trimesh.creation.icosphere(), trimesh.creation.box()])
    >>> labels, parts = segment_objects(scene, 20)
    >>> h = objects_hierarchy(parts, [6, 2])
    >>> [int(h.labels(i, labels).max()) + 1 for i in range(2)]
    [6, 2]
    """
    wanted = wanted_levels(levels)
    counts = np.array([r.n_segments for r in results], dtype=np.int64)
    if wanted[0] > counts.sum() or wanted[-1] < len(results):
        raise ParameterError(f"levels of a scene segmented per object have between one "
                             f"segment per object ({len(results)}) and its "
                             f"{int(counts.sum())} segments; got {wanted}")
    shares, caps = [], counts
    for n in wanted:  # (each object's share at most its share of the finer level)
        caps = _shares(n, counts.astype(np.float64), caps)
        shares.append(caps)
    tops = []  # per object: each level's segment of each of its superfacets
    for j, r in enumerate(results):
        mine = sorted({int(sh[j]) for sh in shares if sh[j] < counts[j]}, reverse=True)
        h = r.hierarchy(mine, cost=cost, extent_weight=extent_weight) if mine else None
        ident = np.arange(counts[j])
        tops.append([h.of_superfacets(mine.index(int(sh[j]))) if sh[j] < counts[j]
                     else ident for sh in shares])
    parents, below = [], [np.arange(counts.sum())]
    for i, sh in enumerate(shares):  # the scene's segments: each object's, offset
        off = np.r_[0, np.cumsum(sh)[:-1]]
        top = np.concatenate([tops[j][i] + off[j] for j in range(len(results))])
        parent = np.empty(int(below[-1].max()) + 1, dtype=np.int64)
        parent[below[-1]] = top
        parents.append(parent)
        below.append(top)
    return Hierarchy(tuple(int(sh.sum()) for sh in shares), tuple(parents))


def _shares(k: int, sizes: np.ndarray, caps: np.ndarray) -> np.ndarray:
    """``k`` shared out in proportion to ``sizes`` (largest remainders), at least one
    each, at most each one's cap."""
    share = k * sizes / sizes.sum() if sizes.sum() > 0 else np.full(len(sizes), k / len(sizes))
    ks = np.floor(share).astype(np.int64)
    extra = int(k - ks.sum())
    if extra > 0:
        ks[np.argsort(-(share - ks), kind="stable")[:extra]] += 1
    return np.minimum(np.maximum(ks, 1), caps)


def _cloud_objects(cloud: PointCloud, k: int, options: dict):
    """:func:`segment_objects` of a point cloud: each object (scan) alone, its rows'
    labels offset by the superpoints of the objects before it."""

    objects = cloud.objects or ((cloud.name or "cloud", 0, cloud.n_total),)
    valid = cloud.valid
    counts = np.array([int(valid[a:b].sum()) for _, a, b in objects])
    ks = _shares(k, counts.astype(float), np.maximum(counts, 1))
    labels = np.full(cloud.n_total, -1, dtype=np.int64)
    results, base = [], 0
    for i, ((name, a, b), k_i) in enumerate(zip(objects, ks.tolist())):
        if counts[i] == 0:
            continue  # a scan with no valid point: its rows stay -1
        view = (cloud.object_viewpoints[i] if cloud.object_viewpoints is not None
                else cloud.viewpoint)
        part = PointCloud(cloud.points[a:b], None if cloud.normals is None else
                          cloud.normals[a:b], name=f"{cloud.name or 'cloud'}:{name}",
                          viewpoint=view, allow_invalid=True, up=cloud.up,
                          colors=None if cloud.colors is None else cloud.colors[a:b])
        try:
            r = segment(part, k_i, **options)
        except SuperfacetsError as exc:
            raise type(exc)(f"object {name!r} (points {a}-{b - 1}): {exc}") from None
        mine = r.labels >= 0
        labels[a:b][mine] = r.labels[mine] + base
        base += r.n_segments
        results.append(r)
    return labels, results
