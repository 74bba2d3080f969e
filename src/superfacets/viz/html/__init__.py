"""A self-contained web page showing a segmented mesh, interactive, no network.

The page (``viewer.html``) and its WebGL script (``viewer.js``) are package
data files beside this module; :func:`html_page` fills them in.

:func:`write_html` writes one HTML file holding the mesh as compact binary
buffers (base64 of float32 vertices, uint32 faces, one palette index per
face, uint32 boundary edges) and a small WebGL viewer: drag to rotate,
wheel or pinch to zoom, right-drag or shift-drag to pan, ``b`` toggles the
superfacet boundaries, ``r`` resets the view. Nothing is fetched from the
network, so the page opens from a file, offline, in any browser with WebGL.
"""

from __future__ import annotations

import base64
import html as _html
import json
import os
import re
from importlib import resources
from pathlib import Path

import numpy as np

from ...elements.builders import elements_of, is_cloud
from ...elements.kinds import kind_of
from ...elements.labels import check_labels, relabel_dense
from ...errors import ParameterError
from ...inputs.cloud import as_cloud
from ...inputs.convert import as_mesh
from ...inputs.tetmesh import as_drawn
from ...io.colors import boundary_edges, labelled_colors
from ...io.export import point_colors
from ...io.files import save
from ..camera import view_frame
from ..render import PointsFrame, class_swatches, drawn_share, faces_to_draw, label_colours

__all__ = ["NotebookView", "write_html", "html_page", "check_page_size",
           "MAX_PAGE_POINTS", "MAX_PAGE_TRIANGLES"]


def _template() -> str:
    files = resources.files(__package__)
    page = files.joinpath("viewer.html").read_text(encoding="utf-8")
    return page.replace("%SCRIPT%", files.joinpath("viewer.js").read_text(encoding="utf-8"))


#: A CSS colour as the page may hold it: a name, ``#rgb(a)`` or ``#rrggbb(aa)`` hex, or
#: ``rgb()``-style.
_COLOUR = re.compile(r"^(#([0-9a-fA-F]{3,4}|[0-9a-fA-F]{6}|[0-9a-fA-F]{8})|[a-zA-Z]{1,30}"
                     r"|(rgb|rgba|hsl|hsla)\([0-9., %]{1,60}\))$")

#: The named colours of CSS Color Module Level 4 (a browser draws any other word as no
#: colour at all).
_CSS_NAMES = frozenset("""
aliceblue antiquewhite aqua aquamarine azure beige bisque black blanchedalmond blue
blueviolet brown burlywood cadetblue chartreuse chocolate coral cornflowerblue cornsilk
crimson cyan darkblue darkcyan darkgoldenrod darkgray darkgreen darkgrey darkkhaki
darkmagenta darkolivegreen darkorange darkorchid darkred darksalmon darkseagreen
darkslateblue darkslategray darkslategrey darkturquoise darkviolet deeppink deepskyblue
dimgray dimgrey dodgerblue firebrick floralwhite forestgreen fuchsia gainsboro ghostwhite
gold goldenrod gray green greenyellow grey honeydew hotpink indianred indigo ivory khaki
lavender lavenderblush lawngreen lemonchiffon lightblue lightcoral lightcyan
lightgoldenrodyellow lightgray lightgreen lightgrey lightpink lightsalmon lightseagreen
lightskyblue lightslategray lightslategrey lightsteelblue lightyellow lime limegreen linen
magenta maroon mediumaquamarine mediumblue mediumorchid mediumpurple mediumseagreen
mediumslateblue mediumspringgreen mediumturquoise mediumvioletred midnightblue mintcream
mistyrose moccasin navajowhite navy oldlace olive olivedrab orange orangered orchid
palegoldenrod palegreen paleturquoise palevioletred papayawhip peachpuff peru pink plum
powderblue purple rebeccapurple red rosybrown royalblue saddlebrown salmon sandybrown
seagreen seashell sienna silver skyblue slateblue slategray slategrey snow springgreen
steelblue tan teal thistle tomato turquoise violet wheat white whitesmoke yellow
yellowgreen transparent""".split())


def _check_background(background) -> str:
    colour = background.strip() if isinstance(background, str) else ""
    if not _COLOUR.match(colour):
        raise ParameterError(f"background must be a CSS colour (a name, #hex or rgb()), "
                             f"got {background!r}")
    if colour.isalpha() and colour.lower() not in _CSS_NAMES:
        raise ParameterError(f"background {background!r} is not a CSS colour name (white, "
                             "black, lightgray, ...: CSS Color Module Level 4), nor #hex "
                             "or rgb()")
    return colour


def _page(title: str, background: str, meta: dict, data: dict) -> str:
    """The viewer page, its template filled in one pass, each value escaped for where it
    stands: the title as HTML text, the colour checked as a CSS colour, the metadata as
    JSON inside a script element (``<``, ``>``, ``&`` as ``\\u`` escapes, so no name can
    close the element or open a comment), the arrays as base64."""
    background = _check_background(background)
    meta_json = (json.dumps(meta, ensure_ascii=False).replace("<", "\\u003c")
                 .replace(">", "\\u003e").replace("&", "\\u0026")
                 .replace("\u2028", "\\u2028").replace("\u2029", "\\u2029"))
    blobs = "\n".join(f'<script type="application/octet-stream" id="{k}">{b}</script>'
                      for k, b in data.items())  # base64: no character to escape
    values = {"TITLE": _html.escape(title), "BACKGROUND": background,
              "META": meta_json, "BLOBS": blobs}
    return re.sub(r"%(TITLE|BACKGROUND|META|BLOBS)%", lambda m: values[m.group(1)],
                  _template())


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def html_page(mesh, labels=None, *, title: str | None = None, info: dict | None = None,
              background: str = "#ffffff", view=None, up="y", elements: str = "faces",
              class_names: dict | None = None) -> str:
    """The HTML text of the viewer page (see :func:`write_html`).

    Parameters
    ----------
    mesh, labels, title, info, background, view, up, elements, class_names
        As :func:`write_html`.

    Returns
    -------
    str
        The page, one self-contained HTML file.

    Raises
    ------
    ParameterError
        As :func:`write_html` (labels, view, a background that is not a CSS colour, a
        mesh of more than :data:`MAX_PAGE_TRIANGLES` triangles).

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=3)
    >>> labels = segment(ball, 12).labels
    >>> page = html_page(ball, labels, title="ball")
    >>> page.startswith("<!DOCTYPE html>"), "ball - superfacets" in page
    (True, True)
    """

    if info is not None and not hasattr(info, "items"):
        raise ParameterError(f"info must be a dict of names and values, got "
                             f"{type(info).__name__}")
    mesh, labels, cut = as_drawn(mesh, labels)  # (a volume: its cut)
    elements = "faces" if cut else elements
    if is_cloud(mesh):
        return _points_page(mesh, labels, title=title, info=info, background=background,
                            view=view, up=up, class_names=class_names)
    mesh = as_mesh(mesh)
    if kind_of(elements).rows != "n_faces":  # labels of the vertices: drawn on faces
        mesh, labels = faces_to_draw(mesh, labels, elements)
    check_page_size(mesh)
    m = mesh.n_faces
    if labels is not None:
        checked = check_labels(labels, m, per="face")
        dense = relabel_dense(checked)
        colors = labelled_colors(mesh, checked)  # (m, 3) uint8 (unassigned faces grey)
        palette, color_index = np.unique(colors, axis=0, return_inverse=True)
        face_index = color_index.ravel()
        edges = boundary_edges(mesh, dense)
        n_sf = int(np.unique(checked[checked >= 0]).size)
    else:
        palette = np.array([[200, 200, 200]], dtype=np.uint8)
        face_index = np.zeros(m, dtype=np.int64)
        edges = np.zeros((0, 2), dtype=np.int64)
        n_sf = 0
    if palette.shape[0] > 65535:  # pragma: no cover - greedy colouring uses ~12 colours
        raise ParameterError("too many distinct colours for the page")
    index_dtype = np.uint8 if palette.shape[0] <= 256 else np.uint16
    # polygons drawn as the triangles of their fans, each in its polygon's colour
    triangles, owner = mesh.triangulated()
    face_index = face_index[owner]
    # used vertices only, centred and scaled to the unit ball (float32 keeps the precision)
    used, faces = np.unique(triangles, return_inverse=True)
    faces = faces.reshape(-1, 3)
    v = mesh.vertices[used]
    center = (v.min(axis=0) + v.max(axis=0)) / 2
    scale = float(np.linalg.norm(v - center, axis=1).max()) or 1.0
    v = ((v - center) / scale).astype("<f4")
    if edges.size:
        edges = np.searchsorted(used, edges)
    d, upv = view_frame(mesh, view, up=up)
    rot = np.stack([np.cross(upv, d), upv, d])  # rows: camera x, y, z in mesh coordinates
    name = title or mesh.name or "mesh"
    meta = {"name": name, "faces": m, "vertices": int(used.size), "superfacets": n_sf,
            "info": {str(k): str(v_) for k, v_ in (info or {}).items()},
            "palette": palette.astype(int).tolist(), "indexBytes": np.dtype(index_dtype).itemsize,
            "nVertices": int(used.size), "nFaces": int(faces.shape[0]),
            "nEdges": int(edges.shape[0]),
            "background": background, "rotation": rot.T.ravel().round(6).tolist()}
    data = {"vertices": _b64(v), "faces": _b64(faces.astype("<u4")),
            "colors": _b64(face_index.astype(index_dtype)),
            "edges": _b64(np.asarray(edges, dtype="<u4"))}
    return _page(f"{name} - superfacets", background, meta, data)


#: Points a page draws at most (about 18 bytes each in the page): a larger cloud is drawn
#: from an even random share of its points (:func:`~superfacets.viz.render.drawn_share`,
#: taken before its point graph is built). At 10M points a page of every point was 173 MB;
#: past about 30M one is longer than the longest string a browser's script engine holds,
#: and does not open.
MAX_PAGE_POINTS = 2_000_000


#: Triangles a page of a mesh draws at most: their vertex indices are one base64 element
#: of the page, 16 characters a triangle, and a browser's script engine holds no string
#: longer than about 2**29 characters (33.5M triangles), so a larger page would not open.
MAX_PAGE_TRIANGLES = 30_000_000


def check_page_size(mesh) -> None:
    """Refuse a page of a mesh with more than :data:`MAX_PAGE_TRIANGLES` triangles (its
    polygons as the fans it draws): such a page would not open. Checked before a run
    writes one (``segment --html``), so that nothing is lost.

    Parameters
    ----------
    mesh : Mesh
        The surface drawn (a volume's cut, the faces its vertices' labels are drawn on).

    Returns
    -------
    None

    Raises
    ------
    ParameterError
        If the mesh has more triangles than a page can hold.

    Examples
    --------
    >>> check_page_size(Mesh(np.eye(3), np.array([[0, 1, 2]])))  # (one triangle: fine)
    """
    n = mesh.n_faces if mesh.is_triangular else int(mesh.face_sizes.sum()) - 2 * mesh.n_faces
    if n > MAX_PAGE_TRIANGLES:
        raise ParameterError(f"a page of {n:,} triangles would not open in a browser (at "
                             f"most {MAX_PAGE_TRIANGLES:,}: a browser holds no longer "
                             "string); draw it with --picture OUT.png "
                             "(superfacets.viz.render), or segment a decimated mesh")


def _points_page(cloud, labels, *, title, info, background, view, up, class_names=None
                 ) -> str:
    """The viewer page of a point cloud: points coloured by superpoint (invalid ones left
    out; past :data:`MAX_PAGE_POINTS`, an even share of them, said on the page); labels
    that are classes with ``class_names``: counted as classes, named beside their colours."""

    whole = as_cloud(cloud)
    if labels is not None:
        labels = check_labels(labels, whole.n_total, per="point")
    n_sp = 0 if labels is None else int(np.unique(labels[labels >= 0]).size)
    cloud, labels, n_drawn = drawn_share(whole, labels, MAX_PAGE_POINTS)
    source = elements_of(cloud, "points")
    g = source.graph
    rgb = point_colors(source, labels)
    palette, color_index = np.unique(rgb, axis=0, return_inverse=True)
    index_dtype = np.uint8 if palette.shape[0] <= 256 else np.uint16
    v = g.positions
    center = (v.min(axis=0) + v.max(axis=0)) / 2
    scale = float(np.linalg.norm(v - center, axis=1).max()) or 1.0
    v = ((v - center) / scale).astype("<f4")
    d, upv = view_frame(PointsFrame(g), view, up=up)
    rot = np.stack([np.cross(upv, d), upv, d])
    name = title or getattr(source.source, "name", "") or "point cloud"
    spacing = float(np.sqrt(np.percentile(g.sizes, 90))) / scale
    info = {str(k): str(v_) for k, v_ in (info or {}).items()}
    if n_drawn < whole.n_points:
        info["drawn"] = f"{n_drawn:,} of {whole.n_points:,} points (an even share)"
    meta = {"name": name, "points": int(v.shape[0]), "faces": 0, "superfacets": n_sp,
            "info": info, **_class_meta(source, labels, rgb, class_names),
            "palette": palette.astype(int).tolist(), "indexBytes": np.dtype(index_dtype).itemsize,
            "nVertices": int(v.shape[0]), "nFaces": 0, "nEdges": 0, "spacing": spacing,
            "background": background, "rotation": rot.T.ravel().round(6).tolist()}
    data = {"vertices": _b64(v), "faces": "", "colors": _b64(color_index.ravel()
                                                                 .astype(index_dtype)),
            "edges": ""}
    return _page(f"{name} - superpoints", background, meta, data)


def _class_meta(source, labels, rgb, class_names) -> dict:
    """What a page of classes shows of them (``word``, ``legend``: each class's name and
    colour, :func:`~superfacets.viz.render.class_swatches`, and ``legendRest``); nothing
    for labels that are no named classes."""
    if labels is None or not class_names:
        return {}
    lines, rest = class_swatches(labels, label_colours(source, labels, rgb), class_names)
    return {"word": "classes", "legend": [[t, list(c)] for t, c in lines], "legendRest": rest}


def write_html(path, mesh, labels=None, *, title: str | None = None, info: dict | None = None,
               background: str = "#ffffff", view=None, up="y", outputs=None,
               elements: str = "faces", class_names: dict | None = None) -> Path:
    """Write a self-contained interactive HTML page of a (segmented) mesh.

    Parameters
    ----------
    path : path
        Output file (``.html``), written atomically.
    mesh : Mesh, trimesh.Trimesh or (vertices, faces)
    labels : (m,) int ndarray, optional
        Superfacet of each face; without it the mesh is grey.
    title : str, optional
        Shown on the page (default: the mesh name).
    info : dict, optional
        Extra lines shown on the page (e.g. the parameters of the run).
    background : str, default '#ffffff'
        CSS colour of the page.
    view, up
        Initial camera, as in :func:`superfacets.viz.camera.view_frame`.
    outputs : superfacets.io.files.Outputs, optional
        Stage the page there (all or nothing with the others).
    elements : {'faces', 'vertices'}, default 'faces'
        What ``labels`` label (vertices: drawn as in
        :func:`superfacets.viz.render.vertex_regions`).
    class_names : dict of int to str, optional
        A point cloud's labels are classes with these names (a LAS file's ASPRS classes:
        :func:`superfacets.io.labels.class_names`): the page counts them as classes and
        names each beside its colour.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ParameterError
        If ``labels`` is not one integer per face, on a bad view, or if the mesh has more
        than :data:`MAX_PAGE_TRIANGLES` triangles (a page that would not open).
    FileNotFoundError
        If the output folder does not exist.

    Notes
    -----
    Size is about 32 bytes of base64 per face (a 1M-face mesh gives a
    ~35 MB page); the browser builds flat-shaded triangles from it. A point cloud takes
    about 18 bytes a point, and one of more than :data:`MAX_PAGE_POINTS` points is drawn
    from an even random share of them, as the page says.

    Examples
    --------
    >>> ball = trimesh.creation.icosphere(subdivisions=3)
    >>> labels = segment(ball, 12).labels
    >>> write_html("ball.html", ball, labels, title="ball").name
    'ball.html'
    """

    text = html_page(mesh, labels, title=title, info=info, background=background, view=view,
                     up=up, elements=elements, class_names=class_names)
    return save(path, text.encode("utf-8"), outputs)


def _check_view_labels(data, labels, elements) -> None:
    """Refuse a view's labels when it is made, not when a notebook shows it (where the
    error is a traceback beside the cell): one integer per point, face or vertex."""
    if labels is None:
        return
    if is_cloud(data):
        check_labels(labels, as_cloud(data).points.shape[0], per="point")
        return
    kind = kind_of(elements or "faces")  # (faces, or the vertices drawn on them)
    check_labels(labels, kind.n_rows(as_mesh(data)), per=kind.singular)


class NotebookView:
    """The interactive viewer shown inline in a Jupyter notebook (or any front end that
    shows ``_repr_html_``: JupyterLab, VS Code, Colab): the page of :func:`html_page`,
    self-contained (no network), in an ``iframe`` of its own.

    Parameters
    ----------
    data : Mesh, PointCloud, TetMesh, SegmentationResult, path, or what :func:`html_page` takes
        A result draws its own input and labels; a file's path is read (:func:`~superfacets.
        io.read_input`), as for a tiled run's labels: ``NotebookView("scan.laz",
        tiled.labels)`` (a cloud of more than 2 million points drawn from an even share);
        a tetrahedral mesh is drawn cut at the middle of x, as ``superfacets html`` draws it.
    labels : (m,) int ndarray, optional
        Per face (``elements='vertices'``: per vertex), per point or per tetrahedron; a
        result's own by default.
    height : int, default 480
        The view's height in pixels (its width is the notebook's).
    **options
        ``title``, ``info``, ``background``, ``view``, ``up``, ``elements`` of
        :func:`html_page`.

    Raises
    ------
    ParameterError
        Given labels that are not one integer per element drawn, a height that is not a
        whole number of pixels in 1..10,000, a tiled run's result (it holds no input), or
        a volume's labels that are not one per tetrahedron; as :func:`html_page` when shown.
    MeshFormatError, FileNotFoundError
        As :func:`~superfacets.io.read_input`, given a path.

    Examples
    --------
    >>> view = NotebookView(segment(trimesh.creation.icosphere(subdivisions=3), 12))
    >>> view._repr_html_().startswith("<iframe")
    True
    """

    def __init__(self, data, labels=None, *, height: int = 480, **options) -> None:
        if isinstance(data, (str, os.PathLike)):  # a file: read as the commands read it
            from ...io import read_input

            data = read_input(data)
        elif hasattr(data, "halo_ratio"):  # a TiledResult: its labels, not its input
            raise ParameterError("a tiled run's result holds the labels, not the input: "
                                 "NotebookView(path_or_cloud, result.labels)")
        source = getattr(data, "elements", None)
        if source is not None and hasattr(data, "labels"):  # a SegmentationResult
            kind = source.graph.kind
            if labels is None:
                labels = data.labels
            if not kind_of(kind).cloud:  # faces, or vertices drawn on the faces
                options.setdefault("elements", kind)
            data = source.source
        data, labels, cut = as_drawn(data, labels)  # (a volume: its cut, as commands draw it)
        if cut:
            options["elements"] = "faces"
            options.setdefault("title", "cut at the middle of x")
        if isinstance(height, bool) or not isinstance(height, (int, np.integer)) or \
                not 1 <= height <= 10_000:
            raise ParameterError(f"height must be a whole number of pixels in 1..10000, got "
                                 f"{height!r}")
        _check_view_labels(data, labels, options.get("elements"))
        self.data, self.labels, self.height, self.options = data, labels, int(height), options

    def html(self) -> str:
        """The page (one self-contained HTML document)."""
        return html_page(self.data, self.labels, **self.options)

    def _repr_html_(self) -> str:
        import html as _html

        return (f'<iframe srcdoc="{_html.escape(self.html(), quote=True)}" '
                f'style="width: 100%; height: {self.height}px; border: 0" '
                'sandbox="allow-scripts"></iframe>')
