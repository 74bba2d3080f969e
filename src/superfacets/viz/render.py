"""Pictures of segmented meshes: off-screen PNG, side-by-side panels, a viewer window.

Rendering is done by PyVista (VTK). With no X display, VTK renders
off-screen through EGL (Mesa's software renderer on a machine without a
GPU), so no display server and no GPU are needed: Debian's ``libegl1`` and
``libgl1-mesa-dri`` provide it (present on most systems; the Makefile's
set-up does not need root for it when they are).

Faces are coloured by superfacet (adjacent superfacets always in clearly
different colours, :func:`superfacets.io.colors.superfacet_colors`), flat shaded,
with the superfacet boundaries drawn as dark lines.
"""

from __future__ import annotations

import functools
import io
import os
from pathlib import Path
from typing import Sequence

import numpy as np

from .._runtime.extras import require
from ..elements.builders import elements_of, kind_for
from ..elements.kinds import kind_of
from ..elements.labels import check_labels, size_summary
from ..errors import NoDisplayError, ParameterError
from ..inputs.convert import as_mesh
from ..inputs.mesh import Mesh
from ..inputs.tetmesh import as_drawn
from ..io.colors import boundary_edges
from ..io.export import point_colors, to_pyvista
from ..io.files import save
from ..method.params import check_choice, check_int, check_number
from .camera import view_frame

__all__ = ["render", "render_points", "render_panel", "show", "has_display", "size_legend",
           "class_legend", "class_swatches", "label_colours",
           "NoDisplayError", "no_display", "drawn_share", "PICTURE_SIZE", "VIEW_POINTS"]

#: A picture's width and height in pixels where none is given.
PICTURE_SIZE = (1200, 900)


def has_display() -> bool:
    """True when an X or Wayland display is available for a window: ``$WAYLAND_DISPLAY``
    set, or ``$DISPLAY`` set and, for a display of this machine (``:0``), an X server
    answering there (a stale ``$DISPLAY``, as an ssh session or a terminal multiplexer can
    keep, made VTK warn "bad X server connection" and a window never open).

    Examples
    --------
    >>> isinstance(has_display(), bool)
    True
    """
    if os.environ.get("WAYLAND_DISPLAY"):
        return True
    name = os.environ.get("DISPLAY", "")
    return bool(name) and _x_server_answers(name)


def no_display() -> NoDisplayError:
    """The error of a window asked for where :func:`has_display` is False, saying why.

    Examples
    --------
    >>> isinstance(no_display(), NoDisplayError)
    True
    """
    name = os.environ.get("DISPLAY")
    why = (f"no X server answers at $DISPLAY={name}" if name else
           "no display available ($DISPLAY is not set)")
    return NoDisplayError(f"{why}: use 'superfacets render' for a PNG or 'superfacets html' "
                          "for a page to open in a browser")


@functools.lru_cache(maxsize=8)
def _x_server_answers(name: str) -> bool:
    """Whether libX11 opens the local display ``name``; True where it cannot be asked
    (no libX11, or a display on another host, whose connection could wait long)."""
    import ctypes
    import ctypes.util

    if name.split(":")[0] not in ("", "unix"):
        return True
    lib = ctypes.util.find_library("X11")
    if lib is None:
        return True
    try:
        x11 = ctypes.cdll.LoadLibrary(lib)
        x11.XOpenDisplay.restype = ctypes.c_void_p
        x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
        x11.XCloseDisplay.argtypes = [ctypes.c_void_p]
        display = x11.XOpenDisplay(name.encode())
    except (OSError, AttributeError):
        return True
    if not display:
        return False
    x11.XCloseDisplay(display)
    return True


def _pyvista(off_screen: bool):
    if off_screen and not has_display():
        # skip VTK's attempt at an X connection (and its warning): go straight to EGL
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    pv = require("pyvista", "drawing pictures")

    return pv


def _polydata(pv, mesh, labels):
    """The mesh as PolyData cells (triangles or polygons), one colour per cell."""

    return to_pyvista(mesh, labels)


def _boundary_lines(pv, mesh, labels, lift: float):
    e = boundary_edges(mesh, labels)
    if e.shape[0] == 0:
        return None
    # lift the lines off the surface along the vertex normals so they are not z-fought
    vn = np.zeros((mesh.n_vertices, 3))
    fn = mesh.normals * mesh.areas[:, None]
    np.add.at(vn, mesh.corners, np.repeat(fn, mesh.face_sizes, axis=0))
    vn /= np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-300)
    used, inv = np.unique(e.ravel(), return_inverse=True)
    pts = mesh.vertices[used] + lift * vn[used]
    lines = np.empty((e.shape[0], 3), dtype=np.int64)
    lines[:, 0] = 2
    lines[:, 1:] = inv.reshape(-1, 2)
    return pv.PolyData(pts, lines=lines.ravel())


def _check_labels(mesh, labels):
    return None if labels is None else check_labels(labels, mesh.n_faces, per="face")


def vertex_regions(mesh, labels) -> tuple:
    """What a picture of per-vertex labels draws: each face cut into one region per corner.

    Each triangle (polygons: the triangles of their fans) is cut, through its
    centroid and the midpoints of its edges, into three quads, one at each
    corner, which take the label of that corner's vertex. A vertex's regions
    together are the barycentric area it stands for (the size of a vertex
    element, a third of each incident triangle), so superpoints of vertices are
    drawn as patches with crisp borders, like superfacets.

    Parameters
    ----------
    mesh : Mesh
    labels : (n,) int ndarray
        Label of each vertex (-1 for vertices used by no face).

    Returns
    -------
    regions : Mesh
        ``3 t`` quads, ``t`` the triangles of ``mesh.triangulated()``.
    region_labels : (3 t,) int64 ndarray

    Raises
    ------
    ParameterError
        If ``labels`` is not one integer per vertex.

    Examples
    --------
    >>> regions, lab = vertex_regions(Mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]),
    ...                               [7, 8, 9])
    >>> regions.n_faces, lab.tolist(), round(float(regions.area), 6)
    (3, [7, 8, 9], 0.5)
    """

    labels = check_labels(labels, mesh.n_vertices, per="vertex")
    tri, _ = mesh.triangulated()
    tri = np.asarray(tri)
    t, n = tri.shape[0], mesh.n_vertices
    v = np.asarray(mesh.vertices)
    half = np.stack([tri, np.roll(tri, -1, axis=1)], axis=2).reshape(-1, 2)  # (a, b) per corner
    edges, edge_of = np.unique(np.sort(half, axis=1), axis=0, return_inverse=True)
    edge_of = edge_of.reshape(t, 3)  # edge (corner i, corner i+1) of each triangle
    points = np.concatenate([v, 0.5 * (v[edges[:, 0]] + v[edges[:, 1]]), v[tri].mean(axis=1)])
    mid = n + edge_of
    center = n + edges.shape[0] + np.arange(t)
    quads = np.concatenate([np.stack([tri[:, i], mid[:, i], center, mid[:, (i + 2) % 3]], 1)
                            for i in range(3)])
    return Mesh(points, quads, name=mesh.name), np.concatenate([labels[tri[:, i]]
                                                                for i in range(3)])


def _add(plotter, pv, mesh, labels, *, boundaries: bool, line_width: float,
         boundary_color, surface_color):
    poly = _polydata(pv, mesh, labels)
    if labels is None:
        plotter.add_mesh(poly, color=surface_color, smooth_shading=False, lighting=True)
    else:
        plotter.add_mesh(poly, scalars="rgb", rgb=True, smooth_shading=False, lighting=True,
                         show_scalar_bar=False)
        if boundaries:
            lines = _boundary_lines(pv, mesh, labels, lift=2e-4 * mesh.diagonal)
            if lines is not None:
                plotter.add_mesh(lines, color=boundary_color, line_width=line_width,
                                 lighting=False)


def _place_camera(plotter, mesh, view, zoom: float = 1.0, up="y", margin: float = 0.06,
                  top_margin: float = 0.0):
    """Orthographic camera from ``view_frame``, framing the mesh's silhouette tightly."""
    d, up = view_frame(mesh, view, up=up)
    v = mesh.vertices[mesh.referenced_vertices]
    right = np.cross(up, d)
    x, y = v @ right, v @ up
    cx, cy = (x.min() + x.max()) / 2, (y.min() + y.max()) / 2
    half_w, half_h = (x.max() - x.min()) / 2, (y.max() - y.min()) / 2
    w, h = plotter.window_size if plotter.shape == (1, 1) else _subplot_size(plotter)
    aspect = w / max(h, 1)
    scale = max(half_h, half_w / aspect) * (1 + 2 * margin) / max(zoom, 1e-6)
    scale /= max(1e-6, 1 - top_margin)
    depth = v @ d
    center = cx * right + cy * up + ((depth.min() + depth.max()) / 2) * d
    # shift the frame down a little when a title takes the top
    center = center + up * scale * top_margin
    dist = mesh.diagonal * 2 + 1e-12
    plotter.enable_parallel_projection()
    plotter.camera_position = [tuple(center + dist * d), tuple(center), tuple(up)]
    plotter.camera.parallel_scale = scale
    plotter.reset_camera_clipping_range()


def _subplot_size(plotter) -> tuple[int, int]:
    w, h = plotter.window_size
    rows, cols = plotter.shape
    return w / cols, h / rows


def _save_png(image: np.ndarray, out, outputs=None) -> Path:
    Image = require("PIL.Image", "writing PNG pictures")
    buf = io.BytesIO()
    Image.fromarray(image).save(buf, format="PNG")
    return save(Path(out), buf.getvalue(), outputs)


def _finish(plotter, out, outputs=None, legend=None) -> np.ndarray:
    """Take the picture, close the plotter, draw the ``legend`` on it (``(labels, word,
    elements)``: :func:`size_legend`; a function of the image: that), write the PNG if
    asked."""
    try:
        image = np.asarray(plotter.screenshot(return_img=True))[:, :, :3].copy()
    finally:
        plotter.close()
    if callable(legend):
        image = legend(image)
    elif legend is not None:
        image = size_legend(image, *legend)
    if out is not None:
        _save_png(image, out, outputs)
    return image


def _check_style(pv, background, boundary_color, line_width, zoom) -> None:
    """Colours, line width and zoom, checked before anything is drawn."""
    check_number("line_width", line_width, 0.0, 100.0, lo_open=True)
    check_number("zoom", zoom, 1e-3, 1e3)
    for name, color in (("background", background), ("boundary_color", boundary_color)):
        try:
            pv.Color(color)
        except (ValueError, TypeError):
            raise ParameterError(f"{name}: not a colour: {color!r} (a colour name such as "
                                 f"'white', or '#rrggbb')") from None


def _size(size) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in size)
    except (TypeError, ValueError):
        raise ParameterError(f"size must be (width, height), got {size!r}") from None
    if not (16 <= w <= 8192 and 16 <= h <= 8192):
        raise ParameterError(f"size must be between 16 and 8192 pixels, got {w}x{h}")
    return w, h


def render(mesh, labels=None, out=None, *, size=PICTURE_SIZE, view=None,
           background="white", boundaries: bool = True, boundary_color="black",
           line_width: float = 1.0, title: str | None = None, zoom: float = 1.0,
           up="y", outputs=None, elements: str = "faces", legend: bool = False
           ) -> np.ndarray:
    """Render a mesh off-screen, faces coloured by superfacet (a point cloud: its points,
    as :func:`render_points` draws them).

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or (vertices, faces), or PointCloud
    labels : (m,) int ndarray, optional
        Superfacet of each face (with ``elements='vertices'``: ``(n,)``, the
        superpoint of each vertex, drawn by :func:`vertex_regions`); without it
        the mesh is drawn in grey.
    out : path, optional
        Write the image here as PNG (atomically).
    size : (int, int), default (1200, 900)
        Width and height in pixels.
    view : str or (3,) float, optional
        See :func:`superfacets.viz.camera.view_frame` (default automatic).
    background : color, default 'white'
        Any colour PyVista accepts (name, hex, RGB).
    boundaries : bool, default True
        Draw the superfacet boundaries as lines.
    boundary_color : color, default 'black'
    line_width : float, default 1
        Boundary line width in pixels.
    title : str, optional
        Text drawn at the top.
    zoom : float, default 1
        Camera zoom factor (> 1 magnifies).
    up : {'y', 'z', 'x', '-y', '-z', '-x'} or (3,) float, default 'y'
        The mesh's up direction.
    outputs : superfacets.io.files.Outputs, optional
        Stage the PNG there (all or nothing with the others).
    elements : {'faces', 'vertices'}, default 'faces'
        What ``labels`` label.
    legend : bool, default False
        Draw the segments' count and sizes in a corner (:func:`size_legend`).

    Returns
    -------
    image : (height, width, 3) uint8 ndarray

    Raises
    ------
    ParameterError
        On labels that are not one integer per face (vertex), a bad size, view,
        up axis, colour, line width or zoom.
    MissingExtraError
        Without the ``render`` extra (pyvista, Pillow).
    """
    if kind_of(kind_for(mesh)).cloud:  # (points coloured by superpoint; no border lines)
        return render_points(mesh, labels, out, size=size, view=view, background=background,
                             title=title, zoom=zoom, up=up, outputs=outputs, legend=legend)
    mesh, labels, cut = as_drawn(mesh, labels)  # (a volume: its cut at the middle of x)
    elements = "faces" if cut else elements
    mesh = as_mesh(mesh)
    given = labels
    mesh, labels = faces_to_draw(mesh, labels, elements)
    w, h = _size(size)
    pv = _pyvista(off_screen=True)
    _check_style(pv, background, boundary_color, line_width, zoom)
    view_frame(mesh, view, up=up)  # a bad view or up axis fails before any drawing
    return _picture(pv, (w, h), background, mesh, view, zoom, up, title, out, outputs,
                    lambda p: _add(p, pv, mesh, labels, boundaries=boundaries,
                                   line_width=line_width, boundary_color=boundary_color,
                                   surface_color="lightgrey"),
                    legend=(given, kind_of(elements).segment_word, kind_of(elements).name)
                    if legend and given is not None else None)


def faces_to_draw(mesh, labels, elements: str):
    """The mesh and per-face labels a picture draws for labels of ``elements``."""

    check_choice("elements", elements, ("faces", "vertices"))
    if kind_of(elements).rows == "n_vertices" and labels is not None:  # one per vertex
        return vertex_regions(mesh, labels)
    return mesh, _check_labels(mesh, labels)


def size_legend(image: np.ndarray, labels, word: str = "superfacets",
                elements: str = "faces") -> np.ndarray:
    """The picture with its segments' count and sizes drawn in a lower corner (the left one,
    or the right one where the box hides fewer drawn pixels there): the count, the
    smallest, median and largest segment in elements, and a histogram of the segments by
    size in powers of two (:func:`superfacets.elements.labels.size_summary`), so that a
    picture says how even its segments are.

    Parameters
    ----------
    image : (height, width, 3) uint8 ndarray
    labels : (n,) int ndarray
        One per element (below 0: not counted).
    word : str, default 'superfacets'
        What the segments are called.
    elements : str, default 'faces'
        What the elements are called (``"points"``, ...).

    Returns
    -------
    (height, width, 3) uint8 ndarray
        A new picture; the same one where no element has a label or the picture is
        too small to hold the legend (under 320 x 200 pixels).

    Raises
    ------
    MissingExtraError
        Without Pillow (the ``render`` extra).

    Examples
    --------
    >>> img = np.full((600, 800, 3), 255, dtype=np.uint8)
    >>> out = size_legend(img, np.repeat(np.arange(50), np.arange(1, 51)))
    >>> out.shape, bool((out != 255).any()), bool((img == 255).all())
    ((600, 800, 3), True, True)
    """
    tools = _legend_text(image, labels)
    if tools is None:
        return image
    lab, unit, font = tools
    s = size_summary(lab)
    hist = np.asarray(s["size_histogram"], dtype=np.float64)
    k = int(np.unique(lab[lab >= 0]).size)
    lines = [f"{k:,} {word}",  # (narrow and tall: a centred drawing leaves its sides free)
             f"{elements} each: {s['size_min']:,} / {s['size_median']:,.0f} / "
             f"{s['size_max']:,}", "(min / median / max)"]
    bar_w = max(6, unit)
    caption = "by size (powers of 2)"
    step = unit + 4  # (a line of text)
    box_w = max(max(font.getlength(t) for t in [*lines, caption]), hist.size * bar_w) \
        + 2 * unit
    box_h = (len(lines) + 2) * step + 5 * unit
    pic, draw, x0, y0 = _legend_box(image, box_w, box_h, unit)
    y = y0 + unit
    for t in lines:
        draw.text((x0 + unit, y), t, fill=(0, 0, 0), font=font)
        y += step
    base, tall = y + 4 * unit, 4 * unit - 4  # bars: segments per size, in powers of two
    top = hist.max()
    for i, c in enumerate(hist):
        if c > 0:
            bh = max(1.0, tall * np.sqrt(c / top))
            draw.rectangle([x0 + unit + i * bar_w, base - bh,
                            x0 + unit + (i + 1) * bar_w - 2, base], fill=(60, 90, 160))
    draw.text((x0 + unit, base + 2), "1", fill=(0, 0, 0), font=font)
    right = f"{2 ** hist.size:,}"
    draw.text((x0 + unit + hist.size * bar_w - font.getlength(right), base + 2), right,
              fill=(0, 0, 0), font=font)
    draw.text((x0 + unit, base + 2 + step), caption, fill=(0, 0, 0), font=font)
    return np.asarray(pic)


#: The most classes :func:`class_legend` lists (the commonest; the rest counted in a line).
LEGEND_CLASSES = 12


def class_legend(image: np.ndarray, labels, colours: dict, names: dict) -> np.ndarray:
    """The picture with its classes named in a lower corner (as :func:`size_legend` places
    its box): each class's colour, code and name, the commonest first, at most
    :data:`LEGEND_CLASSES` of them.

    Parameters
    ----------
    image : (height, width, 3) uint8 ndarray
    labels : (n,) int ndarray
        The classes drawn, one per element (below 0: not counted).
    colours : dict of int to (int, int, int)
        Each class's colour in the picture.
    names : dict of int to str
        Each class's name (:func:`superfacets.io.labels.class_names`).

    Returns
    -------
    (height, width, 3) uint8 ndarray
        A new picture; the same one where no element has a class or the picture is too
        small (under 320 x 200 pixels).

    Raises
    ------
    MissingExtraError
        Without Pillow (the ``render`` extra).

    Examples
    --------
    >>> img = np.full((600, 800, 3), 255, dtype=np.uint8)
    >>> out = class_legend(img, np.r_[[2] * 9, [6] * 3], {2: (200, 40, 40), 6: (40, 40, 200)},
    ...                    {2: "ground", 6: "building"})
    >>> bool((out == [200, 40, 40]).all(axis=-1).any()), bool((img == 255).all())
    (True, True)
    """
    tools = _legend_text(image, labels)
    if tools is None:
        return image
    lab, unit, font = tools
    swatches, rest = class_swatches(lab, colours, names)
    lines = [t for t, _ in swatches] + ([f"and {rest} more"] if rest > 0 else [])
    step = unit + 6
    box_w = int(max(font.getlength(t) for t in lines) + 4 * unit)
    box_h = len(lines) * step + 2 * unit
    pic, draw, x0, y0 = _legend_box(image, box_w, box_h, unit)
    y = y0 + unit
    for i, t in enumerate(lines):
        if i < len(swatches):  # (a swatch of the class's colour)
            draw.rectangle([x0 + unit, y + 1, x0 + 2 * unit, y + unit], fill=swatches[i][1],
                           outline=(60, 60, 60))
        draw.text((x0 + 3 * unit, y), t, fill=(0, 0, 0), font=font)
        y += step
    return np.asarray(pic)


def class_swatches(labels, colours: dict, names: dict, most: int = LEGEND_CLASSES
                   ) -> tuple[list, int]:
    """A class legend's lines: ``'2 ground'`` and the class's colour, the commonest class
    first, at most ``most`` of them; and how many classes are left out.

    Parameters
    ----------
    labels : (n,) int ndarray
        The classes drawn (below 0: not counted).
    colours : dict of int to (int, int, int)
    names : dict of int to str
    most : int, default :data:`LEGEND_CLASSES`

    Returns
    -------
    lines : list of (str, (int, int, int))
    rest : int

    Raises
    ------
    TypeError
        Never for integer labels.

    Examples
    --------
    >>> class_swatches(np.r_[2, 6, 6, 9], {2: (1, 2, 3), 6: (4, 5, 6)}, {6: "building"}, 2)
    ([('6 building', (4, 5, 6)), ('2', (1, 2, 3))], 1)
    """
    lab = np.asarray(labels)
    found, counts = np.unique(lab[lab >= 0], return_counts=True)
    order = [int(found[i]) for i in np.argsort(-counts, kind="stable")]
    lines = [(f"{c} {names.get(c, '')}".rstrip(), tuple(colours.get(c, (200, 200, 200))))
             for c in order[:most]]
    return lines, max(0, len(order) - most)


def label_colours(source, labels, rgb: np.ndarray) -> dict:
    """Each label's colour in a drawing of a cloud's points: its first point's (a label's
    points share one colour, :func:`superfacets.io.colors.labelled_colors`).

    Parameters
    ----------
    source : ElementInput
        The cloud's points (:func:`~superfacets.elements.builders.elements_of`).
    labels : (N,) int ndarray
        One per row of the cloud.
    rgb : (n_elements, 3) uint8 ndarray
        Each point's colour (:func:`superfacets.io.export.point_colors`).

    Returns
    -------
    dict of int to (int, int, int)

    Raises
    ------
    IndexError
        Where ``labels`` or ``rgb`` do not fit ``source``.

    Examples
    --------
    >>> src = elements_of(np.random.default_rng(0).random((40, 3)), "points")
    >>> labels = np.repeat([3, 7], 20)
    >>> sorted(label_colours(src, labels, point_colors(src, labels)))
    [3, 7]
    """
    lab = np.asarray(labels)
    rows = np.flatnonzero((source.index >= 0) & (lab >= 0))
    found, first = np.unique(lab[rows], return_index=True)
    return {int(c): tuple(int(v) for v in rgb[source.index[rows[i]]])
            for c, i in zip(found, first)}


def _legend_text(image: np.ndarray, labels):
    """``(labels, unit, font)`` for a legend on ``image``: the labels as an array, the text's
    size in pixels and Pillow's font of it; None where no element has a label or the
    picture is under 320 x 200 pixels."""
    lab = np.asarray(labels)
    h, w = image.shape[:2]
    if lab.size == 0 or (lab < 0).all() or w < 320 or h < 200:
        return None
    ImageFont = require("PIL.ImageFont", "drawing pictures")
    unit = max(10, min(w, h) // 45)
    return lab, unit, ImageFont.load_default(size=unit)


def _legend_box(image: np.ndarray, box_w: float, box_h: int, unit: int):
    """A legend's white box drawn on a copy of ``image`` in its lower corner
    (:func:`_legend_corner`): the picture, Pillow's drawing on it, and the box's corner."""
    Image = require("PIL.Image", "drawing pictures")
    ImageDraw = require("PIL.ImageDraw", "drawing pictures")
    x0, y0 = _legend_corner(image, int(box_w) + 1, box_h, unit)
    pic = Image.fromarray(image)
    draw = ImageDraw.Draw(pic)
    draw.rectangle([x0, y0, x0 + box_w, y0 + box_h], fill=(255, 255, 255),
                   outline=(90, 90, 90))
    return pic, draw, x0, y0


def _legend_corner(image: np.ndarray, box_w: int, box_h: int, margin: int) -> tuple[int, int]:
    """The upper left corner of the legend's box: of the picture's two lower corners (the
    title is at its top), the one where it hides the fewer drawn pixels (those not of the
    background, the commonest colour of the picture's edge; the left one on a tie)."""
    h, w = image.shape[:2]
    edge = np.concatenate([image[0], image[-1], image[:, 0], image[:, -1]])
    colours, counts = np.unique(edge.reshape(-1, image.shape[2]), axis=0, return_counts=True)
    drawn = (image != colours[np.argmax(counts)]).any(axis=-1)
    low = max(margin, h - margin - box_h)
    corners = [(margin, low), (max(margin, w - margin - box_w), low)]
    hidden = [int(drawn[y:y + box_h, x:x + box_w].sum()) for x, y in corners]
    return corners[int(np.argmin(hidden))]


def _picture(pv, size, background, frame, view, zoom, up, title, out, outputs, draw,
             legend=None):
    """One off-screen picture: background, ``draw(plotter)``, camera on ``frame``, title,
    the ``legend`` (as :func:`_finish` draws it, or None)."""
    w, h = size
    p = pv.Plotter(off_screen=True, window_size=(w, h))
    try:
        p.set_background(background)
        draw(p)
        _place_camera(p, frame, view, zoom, up, top_margin=0.08 if title else 0.0)
        if title:
            p.add_text(title, position="upper_edge", font_size=max(8, h // 60), color="black")
    except BaseException:
        p.close()
        raise
    return _finish(p, out, outputs, legend)


def render_panel(items: Sequence[tuple], out=None, *, ncols: int | None = None,
                 size=(600, 500), view=None, background="white", boundaries: bool = True,
                 line_width: float = 1.0, zoom: float = 1.0, up="y",
                 outputs=None) -> np.ndarray:
    """Several renders side by side with titles, like the paper's Figs. 2, 3 and 8.

    Parameters
    ----------
    items : sequence of (mesh, labels, title)
        One panel each: a mesh (labels of its faces) or a point cloud (a
        :class:`~superfacets.PointCloud`: labels of its points, drawn as
        :func:`render_points` draws them); ``labels`` may be None.
    out : path, optional
        Write the image here as PNG.
    ncols : int, optional
        Panels per row (default: all in one row, at most 4).
    size : (int, int), default (600, 500)
        Size of one panel in pixels.
    view, background, boundaries, line_width, zoom, up
        As in :func:`render` (every panel of the same mesh is seen from the
        same camera).

    Returns
    -------
    image : (H, W, 3) uint8 ndarray

    Raises
    ------
    ParameterError
        On an empty ``items`` or bad labels/size/view.
    """
    if not items:
        raise ParameterError("no panel to render")
    n = len(items)
    ncols = min(n, 4) if ncols is None else max(1, min(int(ncols), n))
    nrows = -(-n // ncols)
    w, h = _size(size)
    pv = _pyvista(off_screen=True)
    _check_style(pv, background, "black", line_width, zoom)
    p = pv.Plotter(off_screen=True, shape=(nrows, ncols), window_size=(w * ncols, h * nrows),
                   border=False)
    try:
        p.set_background(background)
        for i, (mesh, labels, title) in enumerate(items):
            p.subplot(i // ncols, i % ncols)
            if kind_of(kind_for(mesh)).cloud:  # (shaded spheres: eye-dome lighting is one
                mesh, draw, _ = _points_drawing(pv, mesh, labels, (w, h), view, zoom, up,
                                                eye_dome=False,  # (one pass of a whole
                                                limit=w * h)  # window, not a panel's)
                draw(p)
            else:
                mesh = as_mesh(mesh)
                labels = _check_labels(mesh, labels)
                _add(p, pv, mesh, labels, boundaries=boundaries, line_width=line_width,
                     boundary_color="black", surface_color="lightgrey")
            _place_camera(p, mesh, view, zoom, up, top_margin=0.1 if title else 0.0)
            if title:
                p.add_text(title, position="upper_edge", font_size=max(8, h // 40),
                           color="black")
    except BaseException:
        p.close()
        raise
    return _finish(p, out, outputs)


#: The most points :func:`show` draws of a cloud (an even share past it, as a picture's):
#: a window turns about this many smoothly on a laptop's graphics, and their point graph
#: (the colours' and the camera's) takes seconds, where that of 50 million takes minutes.
VIEW_POINTS = 4_000_000


def show(mesh, labels=None, *, title: str | None = None, boundaries: bool = True,
         view=None, up="y", max_points: int | None = VIEW_POINTS) -> None:
    """Open an interactive window (rotate: drag, zoom: wheel, quit: q) on a mesh (labels of
    its faces) or a point cloud (labels of its points, drawn as :func:`render_points` draws
    them).

    Parameters
    ----------
    mesh : Mesh, PointCloud or what :func:`render` takes
    labels : (n,) int ndarray, optional
        One per face (point).
    title : str, optional
    boundaries : bool, default True
        A mesh's superfacet borders drawn.
    view, up
        The camera (:func:`superfacets.viz.camera.view_frame`).
    max_points : int or None, default :data:`VIEW_POINTS`
        A cloud's points drawn at most: past it an even random share
        (:func:`drawn_share`); None: all.

    Raises
    ------
    NoDisplayError
        If no display is available (``$DISPLAY``/``$WAYLAND_DISPLAY`` unset).

    Examples
    --------
    >>> show(mesh, labels)  # doctest: +SKIP
    """
    if not has_display():
        raise no_display()
    pv = _pyvista(off_screen=False)
    p = pv.Plotter(title=title or "superfacets")
    if kind_of(kind_for(mesh)).cloud:  # (points coloured by superpoint, as render_points)
        mesh, draw, _ = _points_drawing(pv, mesh, labels, tuple(p.window_size), view, 1.0, up,
                                        limit=max_points)
        draw(p)
    else:
        mesh = as_mesh(mesh)
        labels = _check_labels(mesh, labels)
        _add(p, pv, mesh, labels, boundaries=boundaries, line_width=1.0,
             boundary_color="black", surface_color="lightgrey")
    _place_camera(p, mesh, view, up=up)
    if title:
        p.add_text(title, position="upper_edge", font_size=12, color="black")
    p.set_background("white")
    p.show()  # pragma: no cover - a window, until it is closed


class PointsFrame:
    """What the camera needs of a point cloud (the attributes it reads of a mesh)."""

    def __init__(self, graph):
        self.vertices = graph.positions
        self.referenced_vertices = np.ones(graph.n_elements, dtype=bool)
        self.diagonal = graph.diagonal
        self.centroids = graph.positions
        self.areas = graph.sizes
        self.area = graph.area


def render_points(cloud, labels=None, out=None, *, size=PICTURE_SIZE, view=None,
                  background="white", point_size: float | None = None,
                  title: str | None = None, zoom: float = 1.0, up="y",
                  outputs=None, eye_dome: bool | None = None, legend=False,
                  max_points: int | None = None, class_names: dict | None = None
                  ) -> np.ndarray:
    """Render a point cloud off-screen, points coloured by superpoint.

    Parameters
    ----------
    cloud : PointCloud or (N, 3) float ndarray
    labels : (N,) int ndarray, optional
        Superpoint of each point (-1: invalid, not drawn); grey without.
    out : path, optional
        Write the PNG here (atomically).
    size, view, background, title, zoom, up, outputs
        As :func:`render`.
    point_size : float, optional
        Pixels per point (default: from the point density and the image size).
    eye_dome : bool, optional
        Eye-dome lighting (as CloudCompare and Potree shade scans: edges in depth
        darkened) instead of points drawn as shaded spheres. Default: on for a view
        from straight above or below (``'top'``, ``'bottom'``: a map, whose relief
        spheres cannot show), off otherwise.
    legend : bool or (M,) int ndarray, default False
        Draw the superpoints' count and sizes in the lower left corner
        (:func:`size_legend`), read from ``labels`` (every point's, whatever share is
        drawn), or from this array: the labels of a whole cloud of which ``cloud`` is a
        sample (a tiled run's picture).
    max_points : int, optional
        Points drawn at most: past it an even random share of them
        (:func:`drawn_share`). Default: the picture's pixels (1,080,000 at 1200 x 900).
    class_names : dict of int to str, optional
        The labels are classes with these names (a LAS file's ASPRS classes:
        :func:`superfacets.io.labels.class_names`): with ``legend``, the legend names
        each class beside its colour (:func:`class_legend`) instead of the sizes.

    Returns
    -------
    image : (height, width, 3) uint8 ndarray

    Raises
    ------
    ParameterError
        On labels that are not one per point, a bad size, view, colour or zoom.
    InvalidCloudError
        If the cloud is unusable.
    MissingExtraError
        Without the ``render`` extra.
    """

    w, h = _size(size)
    pv = _pyvista(off_screen=True)
    _check_style(pv, background, "black", 1.0, zoom)
    frame, draw, colours = _points_drawing(pv, cloud, labels, (w, h), view, zoom, up,
                                           point_size, eye_dome,
                                           limit=w * h if max_points is None else max_points)
    sized = legend if isinstance(legend, np.ndarray) else labels if legend else None
    if sized is not None and class_names:
        return _picture(pv, (w, h), background, frame, view, zoom, up, title, out, outputs,
                        draw, legend=lambda image: class_legend(image, sized, colours,
                                                                class_names))
    return _picture(pv, (w, h), background, frame, view, zoom, up, title, out, outputs, draw,
                    legend=None if sized is None else (sized, "superpoints", "points"))


def drawn_share(cloud, labels=None, limit: int | None = None) -> tuple:
    """The points a picture draws of a cloud: all of them, or past ``limit`` an even random
    share of its valid ones (a fixed seed, so the same picture each time).

    A picture of 1200 x 900 pixels shows about a million points: drawing 10 or 50 million
    costs the point graph of all of them (most of a picture's time and memory) and gives a
    picture no better, greyer where several points of one pixel's depth are shaded apart.

    Parameters
    ----------
    cloud : PointCloud or (N, 3) float ndarray
    labels : (N,) int ndarray, optional
        One per point of the cloud (checked).
    limit : int, optional
        Points drawn at most (None: all).

    Returns
    -------
    cloud : PointCloud
        The cloud, or a new one of the drawn points (their normals and colours with them,
        its viewpoint and up kept).
    labels : (n,) int ndarray or None
        The drawn points' labels.
    n_drawn : int
        Valid points drawn.

    Raises
    ------
    ParameterError
        If ``labels`` is not one integer per point.
    InvalidCloudError, TypeError
        As :func:`superfacets.inputs.cloud.as_cloud`.

    Examples
    --------
    >>> xyz = np.random.default_rng(0).random((5000, 3))
    >>> c, lab, n = drawn_share(xyz, np.arange(5000) // 500, limit=1000)
    >>> c.n_points, lab.shape, n, int(lab.max())
    (1000, (1000,), 1000, 9)
    """
    from dataclasses import replace

    from ..inputs.cloud import as_cloud

    cloud = as_cloud(cloud)
    if limit is not None:
        limit = check_int("the points drawn", limit, 1)
    if labels is not None:
        labels = check_labels(labels, cloud.n_total, per="point")
    if limit is None or cloud.n_points <= limit:
        return cloud, labels, cloud.n_points
    rows = np.flatnonzero(cloud.valid)
    rows = np.sort(np.random.default_rng(0).choice(rows, int(limit), replace=False))

    def part(a):
        return None if a is None else np.asarray(a)[rows]

    share = replace(cloud, points=cloud.points[rows], normals=part(cloud.normals),
                    colors=part(cloud.colors), allow_invalid=False, shape=None, frame=None,
                    objects=(), object_viewpoints=None, fields=None)
    return share, part(labels), rows.size


def _points_drawing(pv, cloud, labels, size, view, zoom, up, point_size=None, eye_dome=None,
                    limit=None):
    """A point cloud's camera frame (:class:`PointsFrame`), ``draw(plotter)``, which adds
    its points coloured by ``labels`` (:func:`render_points`' options), at most ``limit``
    of them (:func:`drawn_share`), and each label's colour (``{label: (r, g, b)}``; empty
    without labels)."""
    cloud, labels, _ = drawn_share(cloud, labels, limit)
    source = elements_of(cloud, "points")
    g = source.graph
    rgb = point_colors(source, labels)
    colours = {} if labels is None else label_colours(source, labels, rgb)
    frame = PointsFrame(g)
    view_frame(frame, view, up=up)
    if point_size is None:  # about one point spacing on screen
        spacing = np.sqrt(np.percentile(g.sizes, 90))
        point_size = float(np.clip(1.6 * spacing / g.diagonal * max(size) * zoom, 1.0, 12.0))
    poly = pv.PolyData(np.ascontiguousarray(g.positions))
    poly["rgb"] = rgb
    if eye_dome is None:  # a map: seen from straight above, the relief is in the edges
        eye_dome = isinstance(view, str) and view in ("top", "bottom")

    def draw(p):  # (flat squares: a little larger, so that no background shows between)
        p.add_mesh(poly, scalars="rgb", rgb=True,
                   point_size=point_size * (1.6 if eye_dome else 1.0),
                   render_points_as_spheres=not eye_dome, show_scalar_bar=False)
        if eye_dome:
            p.enable_eye_dome_lighting()

    return frame, draw, colours
