"""A scene segmented object by object, with labels unique over the scene."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..errors import ParameterError
from ..inputs.convert import as_mesh
from ..method.params import DEFAULTS as _D

if TYPE_CHECKING:
    from .segmentation import SegmentationResult

__all__ = ["segment_objects"]


def segment_objects(mesh, n_segments: int = _D.n_segments, **options
                    ) -> tuple[np.ndarray, list[SegmentationResult]]:
    """Segment each object of a scene on its own, with labels unique over the scene.

    The ``n_segments`` superfacets are shared out among the objects by area
    (largest remainders; at least one per object, at most its faces), each
    object is segmented alone (its own bounding box, radius and centers),
    and its labels are offset by the superfacets of the objects before it.

    Parameters
    ----------
    mesh : Mesh or any form :func:`superfacets.inputs.convert.as_mesh` accepts
        With ``mesh.objects`` (a scene); a mesh without is one object.
    n_segments : int, default 150
        Superfacets in all (more when there are more objects than that).
    **options
        Keyword arguments of :func:`segment` (``alpha``, ``init``, ...; not
        ``radius``).

    Returns
    -------
    labels : (m,) int64 ndarray
        Dense over the whole mesh; object ``i``'s labels follow object ``i-1``'s.
    results : list of SegmentationResult
        One per object, in order.

    Raises
    ------
    ParameterError, InvalidMeshError
        As :func:`segment`, the message naming the object.

    Examples
    --------
    >>> import trimesh
    >>> scene = trimesh.Scene([trimesh.creation.icosphere(), trimesh.creation.box()])
    >>> labels, parts = segment_objects(scene, 20)
    >>> [r.n_segments for r in parts], int(labels.max()) + 1
    ([14, 6], 20)
    """
    from ..errors import SuperfacetsError
    from ..inputs.mesh import Mesh
    from ..method.params import check_int
    from .segmentation import segment

    if options.get("radius") is not None:
        raise ParameterError("segmenting per object takes n_segments, not radius")
    mesh = as_mesh(mesh)
    k = check_int("n_segments", n_segments, lo=1)
    objects = mesh.objects or ((mesh.name or "mesh", 0, mesh.n_faces),)
    areas = np.array([mesh.areas[a:b].sum() for _, a, b in objects])
    faces = np.array([b - a for _, a, b in objects])
    share = k * areas / areas.sum() if areas.sum() > 0 else np.full(len(objects), k / len(objects))
    ks = np.floor(share).astype(np.int64)
    extra = int(k - ks.sum())
    if extra > 0:
        ks[np.argsort(-(share - ks), kind="stable")[:extra]] += 1
    ks = np.minimum(np.maximum(ks, 1), faces)
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
