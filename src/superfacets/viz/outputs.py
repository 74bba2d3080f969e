"""The files of one segmentation: labels, coloured mesh or cloud, picture, page.

:func:`write_result` is what ``superfacets segment`` and ``superfacets
batch`` write for one input, all or nothing (:class:`~superfacets.io.files.Outputs`).
"""

from __future__ import annotations

import numpy as np

from ..api.result import describe_stop
from ..elements.builders import elements_of
from ..elements.kinds import kind_of
from ..io.export import write_colored_elements, write_colored_mesh
from ..io.files import Outputs
from ..io.labels import write_labels, write_segindices
from ..io.records import level_field, scan_output, write_cloud_with_labels, write_scan_labels
from .html import write_html
from .render import render, render_points

__all__ = ["write_result", "result_header", "graph_arrays", "JoinedResult"]


class JoinedResult:
    """The result of segmenting a scene object by object
    (:func:`superfacets.api.scenes.segment_objects`), for messages and headers.

    Parameters
    ----------
    labels : (m,) int64 ndarray
    results : list of SegmentationResult
    """

    def __init__(self, labels, results):
        self.results = list(results)
        self.labels = np.asarray(labels)
        self.n_segments = int(self.labels.max()) + 1
        self.n_iter = max(r.n_iter for r in results)
        self.converged = all(r.converged for r in results)
        self.params = dict(results[0].params, per_object=True)
        self.timings = {"total": sum(r.timings["total"] for r in results)}

    def hierarchy(self, levels, *, cost: str = "ward", extent_weight: float | None = None):
        """Coarser levels, each object's own
        (:func:`~superfacets.api.scenes.objects_hierarchy`)."""
        from ..api.scenes import objects_hierarchy

        return objects_hierarchy(self.results, levels, cost=cost, extent_weight=extent_weight)


def _object_lines(mesh) -> list[str]:
    """``object NAME: faces A-B`` lines of a scene (several objects), else none."""
    if len(getattr(mesh, "objects", ())) < 2:
        return []
    return [f"object {name}: faces {a}-{b - 1}" for name, a, b in mesh.objects]


def result_header(data, result, source: str) -> dict:
    """The ``#`` header lines of a ``.seg`` file: what, how many, parameters, time.

    Parameters
    ----------
    data : Mesh or PointCloud
    result : SegmentationResult or JoinedResult
    source : str
        The input's name.

    Returns
    -------
    dict
    """
    p = result.params
    kind = p.get("elements", "faces")
    return {
        "superfacets": f"labels of {source}",
        kind: kind_of(kind).n_rows(data),
        "superfacets_count": result.n_segments,
        "parameters": " ".join(f"{k}={v}" for k, v in p.items()),
        "iterations": f"{result.n_iter} "
                      f"({describe_stop(result)})",
        "seconds": f"{result.timings['total']:.3f}",
    }


def graph_arrays(result, hierarchy=None) -> dict:
    """The arrays ``segment --graph OUT.npz`` writes of one segmentation.

    Parameters
    ----------
    result : SegmentationResult
        Of any input (faces, vertices, points or tetrahedra).
    hierarchy : Hierarchy, optional
        Its coarser levels (:meth:`SegmentationResult.hierarchy`), written too.

    Returns
    -------
    dict of str to ndarray
        PyTorch Geometric's layout (:meth:`SegmentationResult.learning_graph`: ``x``,
        ``pos``, ``edge_index``, ...), the nodes' own ``area``, ``centroid``, ``normal``
        (and ``feature`` where the input has features), the element ``labels``; with a
        hierarchy its ``levels`` and ``parent_<i>`` and each level's element labels
        ``labels_<i>``.

    Examples
    --------
    >>> from superfacets import segment
    >>> from superfacets.inputs.shapes import creature
    >>> result = segment(creature(), 20)
    >>> arrays = graph_arrays(result, result.hierarchy([5]))
    >>> arrays["edge_index"].shape[0], int(arrays["labels_0"].max())
    (2, 4)
    """
    sg = result.graph()
    arrays = {**{k: v for k, v in sg.arrays().items() if k in ("area", "centroid", "normal",
                                                              "feature")},
              **result.learning_graph(), "labels": result.labels}
    if hierarchy is not None:
        arrays.update(hierarchy.arrays())
        for i in range(len(hierarchy.levels)):
            arrays[f"labels_{i}"] = hierarchy.labels(i, result.labels)
    return arrays


def write_result(data, result, kind: str, source: str, *, labels=None, header: bool = False,
                 colored=None, vertex_colors: bool = False, picture=None, html=None,
                 element_options: dict | None = None, up="y", view=None, graph=None,
                 levels=None, level_cost: str = "ward",
                 extent_weight: float | None = None, source_path=None,
                 new_scan: bool = False) -> None:
    """Write the files of one segmentation, all or nothing.

    Parameters
    ----------
    data : Mesh or PointCloud
        What was segmented.
    result : SegmentationResult or JoinedResult
    kind : {'faces', 'vertices', 'points'}
        The elements labelled.
    source : str
        The input's file name (headers, titles, the JSON's ``sceneId``).
    labels : path, optional
        ``.json``: ScanNet's ``segIndices``; ``.las``/``.laz``/``.ply`` of a
        LAS/LAZ or PLY ``source_path``: a copy of the input with the labels in
        its point (vertex) records (:func:`superfacets.io.records.write_labels_into`:
        ``ClusterID``); anything else (``-``: standard output): one label per
        line, with ``#`` header lines where ``header`` is True (and always the
        objects of a scene).
    colored : path, optional
        Coloured mesh (``.ply``, ``.glb``, ``.obj``) or, for vertices and
        points, coloured PLY.
    vertex_colors : bool, default False
        PLY of faces: colours per vertex instead of per face.
    picture : path, optional
        PNG (needs the ``render`` extra).
    html : path, optional
        Interactive page.
    element_options : dict, optional
        ``n_neighbors`` and ``neighbor_radius`` of the point graph (to find the
        cached elements again).
    up, view
        The picture's and the page's camera (:func:`superfacets.viz.camera.view_frame`).
    graph : path, optional
        ``.npz`` of the superfacet (superpoint) graph in PyTorch Geometric's layout
        (:meth:`SegmentationResult.learning_graph`: ``x``, ``pos``, ``edge_index``
        with each edge in both directions, ``edge_attr``, ``super_index``,
        ``node_features``, ``edge_features``), each node's ``area``, ``centroid``,
        ``normal`` and ``feature`` (the input's colours if it has any) and
        ``labels``; with
        ``levels``, also the hierarchy (``levels``, ``parent_<i>``) and the
        per-row labels of each level (``labels_<i>``).
    levels : sequence of int, optional
        Numbers of segments of the hierarchy's levels: written in ``graph``, and where
        ``labels`` holds the scan's records (or a new file of them), each level as a field
        after the labels (``ClusterID_<n>``, :func:`superfacets.io.records.level_field`).
    level_cost : {'ward', 'planarity'}, default 'ward'
        The hierarchy's merge cost (:func:`superfacets.graph.hierarchy.hierarchy`).
    extent_weight : float, optional
        Its ``extent_weight`` with ``'planarity'`` (default: left to the method,
        :meth:`SegmentationResult.hierarchy`).
    source_path : path, optional
        The input file (labels written into its records).
    new_scan : bool, default False
        ``labels`` (``.las``, ``.laz`` or ``.ply``) is a new file of the cloud's points with
        the labels, whatever the input's format (:func:`superfacets.io.records.
        write_cloud_with_labels`; ``batch --labels laz``).

    Raises
    ------
    OSError, MissingExtraError
        Nothing is written then.
    ParameterError
        If a level is out of range (before anything is written).
    """

    into = "new" if new_scan and labels is not None else \
        None if source_path is None else scan_output(labels, source_path)
    h = result.hierarchy(levels, cost=level_cost, extent_weight=extent_weight) if levels \
        and (graph is not None or into is not None) else None
    arrays = None if graph is None else graph_arrays(result, h)
    fields = {} if h is None or into is None else {
        level_field(n): h.labels(i, result.labels) for i, n in enumerate(h.levels)}
    with Outputs() as outputs:
        if arrays is not None:
            outputs.write(graph, lambda fh: np.savez_compressed(fh, **arrays))
        if into == "new":  # a new file of a cloud's points
            write_cloud_with_labels(labels, data, result.labels, levels=fields,
                                    outputs=outputs)
        elif into is not None:  # the input's records
            write_scan_labels(labels, source_path, result.labels, levels=fields,
                              outputs=outputs)
        elif labels is not None and str(labels).lower().endswith(".json"):
            write_segindices(labels, result.labels, result.params,
                             scene_id=source.split(".")[0], outputs=outputs)
        elif labels is not None:
            head = result_header(data, result, source) if header else None
            objects = [] if kind_of(kind).cloud else _object_lines(data)
            if objects:  # a scene: say which faces are which object
                head = [f"{k}: {v}" for k, v in (head or {}).items()] + objects
            write_labels(labels, result.labels, outputs=outputs, header=head)
        if colored is not None and kind_of(kind).objects:
            write_colored_mesh(colored, data, result.labels, outputs=outputs,
                               vertex_colors=vertex_colors)
        elif colored is not None:
            source_el = elements_of(data, kind, **(element_options or {}))  # cached
            write_colored_elements(colored, source_el, result.labels, outputs=outputs)
        title = f"{source}: {result.n_segments} {kind_of(kind).segment_word}"
        volume = kind_of(kind).dim == 3  # (drawn by its cut: no count of its superfacets)
        if volume:
            kind, title = "faces", title + ", cut at the middle of x"
        drawn = {} if kind_of(kind).cloud else {"elements": kind}  # faces or vertices
        if html is not None:
            write_html(html, data, result.labels, title=title, outputs=outputs, up=up,
                       view=view, **drawn)
        if picture is not None:
            draw = render_points if kind_of(kind).cloud else render
            draw(data, result.labels, picture, title=title, outputs=outputs, up=up, view=view,
                 legend=not volume, **drawn)

