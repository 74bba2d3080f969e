"""Which way is up in an input, as its data or its format says (for pictures).

A picture stands on the input's up axis: the one its data declares (a LAS cloud: z; an
organized PCD scan: its sensor's up, the camera's -y turned by the header's
``VIEWPOINT`` orientation), else its format's convention (glTF: y, by its specification;
STL: z, as CAD and 3D printing write it), else y, the convention of OBJ, PLY and OFF
meshes in graphics (no mesh format of these says more; ``--up`` chooses another). An
organized scan is seen from its sensor (:func:`sensor_view`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .files import split_suffix

__all__ = ["FORMAT_UP", "up_axis", "sensor_up", "sensor_view", "default_view", "is_map",
           "image_up", "thinnest_axis"]

#: A scan whose height is at most this fraction of its smaller horizontal side is a map
#: (an airborne or street tile): its pictures look straight down, north up.
MAP_HEIGHT = 0.5

#: Up axes by format convention, where a format has one.
FORMAT_UP = {"stl": "z", "glb": "y", "gltf": "y", "las": "z", "laz": "z"}


def sensor_up(viewpoint) -> np.ndarray:
    """The up direction of a camera frame: its -y (x right, y down, z forward) turned by
    the sensor's orientation.

    Parameters
    ----------
    viewpoint : sequence of 7 floats
        A PCD header's ``VIEWPOINT``: the translation ``tx ty tz``, then the unit
        quaternion ``qw qx qy qz`` of the sensor's orientation.

    Returns
    -------
    (3,) float64 ndarray
        A unit vector (the camera's -y where the quaternion is not a rotation).

    Raises
    ------
    ValueError
        If ``viewpoint`` has fewer than 7 numbers.

    Examples
    --------
    >>> sensor_up([0, 0, 0, 1, 0, 0, 0]).tolist()  # no rotation: the camera's -y
    [0.0, -1.0, 0.0]
    >>> sensor_up([0, 0, 0, 0, 1, 0, 0]).tolist()  # turned half a turn about x
    [0.0, 1.0, 0.0]
    """
    v = np.asarray(viewpoint, dtype=np.float64).reshape(-1)
    if v.size < 7:
        raise ValueError(f"a viewpoint has 7 numbers, got {v.size}")
    w, x, y, z = v[3:7]
    norm = np.sqrt(w * w + x * x + y * y + z * z)
    if not np.isfinite(norm) or norm == 0:
        return np.array([0.0, -1.0, 0.0])
    w, x, y, z = v[3:7] / norm
    column_y = np.array([2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)])
    return -column_y + 0.0  # (no negative zeros)


def image_up(data) -> np.ndarray | None:
    """The up of an organized scan's picture: from the points of its image's bottom half
    to those of its top half (row 0 is the top of a sensor's image), made perpendicular
    to the direction from the points to the sensor. None for other inputs.

    The image's own layout is what makes it upright as its sensor saw it; a file's
    declared orientation (a PCD ``VIEWPOINT`` quaternion) is often left at a default
    that does not match its data.

    Parameters
    ----------
    data : PointCloud, Mesh or TetMesh

    Returns
    -------
    (3,) float64 ndarray or None
        A unit vector.

    Raises
    ------
    ValueError
        Never for inputs read by this package.

    Examples
    --------
    >>> rows, cols = np.mgrid[0:4, 0:5]  # a camera's image: x right, y down, z ahead
    >>> pts = np.stack([cols, rows, np.full(rows.shape, 3)], -1).reshape(-1, 3) * 1.0
    >>> image_up(PointCloud(pts, shape=(4, 5), viewpoint=(2, 1.5, 0))).round(6).tolist()
    [0.0, -1.0, 0.0]
    """
    shape = getattr(data, "shape", None)
    if shape is None or len(shape) != 2 or shape[0] < 2:
        return None
    pts = np.asarray(data.points, dtype=np.float64).reshape(shape[0], shape[1], 3)
    half = shape[0] // 2
    top, bottom = pts[:half].reshape(-1, 3), pts[shape[0] - half:].reshape(-1, 3)
    top, bottom = (a[np.isfinite(a).all(axis=1)] for a in (top, bottom))
    if not top.shape[0] or not bottom.shape[0]:
        return None
    up = top.mean(axis=0) - bottom.mean(axis=0)
    view = sensor_view(data)
    if view is not None:
        up = up - (up @ view) * view
    norm = np.linalg.norm(up)
    return up / norm if np.isfinite(norm) and norm > 0 else None


def up_axis(data, path=None) -> tuple[str, str]:
    """The axis a picture of ``data`` stands on, and what said so.

    Parameters
    ----------
    data : Mesh, PointCloud or TetMesh
        Read from ``path``; its ``up`` (a point cloud's, where its file declares one)
        comes first.
    path : str or os.PathLike, optional
        The file, for its format's convention (:data:`FORMAT_UP`).

    Returns
    -------
    axis : str
        ``"x"``, ``"y"``, ``"z"``, ``"-x"``, ``"-y"`` or ``"-z"`` (the nearest axis to a
        declared direction).
    source : str
        What said so, for messages: ``"the image's"`` (an organized scan: from its
        bottom rows to its top rows, :func:`image_up`), ``"the file's"``, ``"STL's
        convention"``, or ``"the default"``.

    Raises
    ------
    ValueError
        Never for inputs read by this package.

    Examples
    --------
    >>> up_axis(as_mesh(trimesh.creation.box()), "part.stl")
    ('z', "STL's convention")
    >>> up_axis(as_mesh(trimesh.creation.box()), "box.off")
    ('y', 'the default')
    """
    up = image_up(data)
    if up is not None:
        return ("-" if up[int(np.argmax(np.abs(up)))] < 0 else "") + "xyz"[
            int(np.argmax(np.abs(up)))], "the image's"
    up = getattr(data, "up", None)
    if up is not None:
        up = np.asarray(up, dtype=np.float64).reshape(-1)
        i = int(np.argmax(np.abs(up)))
        return ("-" if up[i] < 0 else "") + "xyz"[i], "the file's"
    fmt = split_suffix(Path(path))[0] if path is not None else ""
    if fmt in FORMAT_UP:
        return FORMAT_UP[fmt], f"{fmt.upper()}'s convention"
    return "y", "the default"


def sensor_view(data) -> np.ndarray | None:
    """The direction from an organized scan to the sensor that took it, for its pictures'
    default view (the scene as the camera saw it); None for other inputs.

    Parameters
    ----------
    data : PointCloud, Mesh or TetMesh
        A cloud with an image ``shape`` (an organized PCD) and a ``viewpoint``.

    Returns
    -------
    (3,) float64 ndarray or None
        ``viewpoint`` minus the mean of the valid points, unit length.

    Raises
    ------
    ValueError
        Never for inputs read by this package.

    Examples
    --------
    >>> pts = np.array([[0.0, 0, 2], [1, 0, 2], [0, 1, 2], [1, 1, 2]])
    >>> sensor_view(PointCloud(pts, viewpoint=(0.5, 0.5, 0), shape=(2, 2))).tolist()
    [0.0, 0.0, -1.0]
    """
    viewpoint = getattr(data, "viewpoint", None)
    if viewpoint is None or getattr(data, "shape", None) is None:
        return None
    pts = np.asarray(data.points, dtype=np.float64)
    pts = pts[np.isfinite(pts).all(axis=1)]
    if not len(pts):
        return None
    d = np.asarray(viewpoint, dtype=np.float64) - pts.mean(axis=0)
    n = float(np.linalg.norm(d))
    return d / n + 0.0 if np.isfinite(n) and n > 0 else None


def is_map(data) -> bool:
    """Whether a picture of ``data`` is best a map: a point cloud whose file declares an
    elevation axis (a LAS/LAZ or E57 scan: z) and whose height is at most
    :data:`MAP_HEIGHT` of its smaller horizontal side (an airborne tile, a street).

    Parameters
    ----------
    data : PointCloud, Mesh or TetMesh

    Returns
    -------
    bool

    Raises
    ------
    ValueError
        Never for inputs read by this package.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> tile = rng.random((500, 3)) * (200.0, 100.0, 10.0)
    >>> is_map(PointCloud(tile, up=(0, 0, 1))), is_map(PointCloud(tile))
    (True, False)
    """
    up = getattr(data, "up", None)
    if up is None or hasattr(data, "faces") or getattr(data, "shape", None) is not None:
        return False
    up = np.asarray(up, dtype=np.float64).reshape(-1)
    axis = int(np.argmax(np.abs(up)))
    pts = np.asarray(data.points, dtype=np.float64)
    pts = pts[np.isfinite(pts).all(axis=1)]
    if pts.shape[0] < 2:
        return False
    extent = pts.max(axis=0) - pts.min(axis=0)
    sides = np.delete(extent, axis)
    return bool(sides.min() > 0 and extent[axis] <= MAP_HEIGHT * sides.min())


def default_view(data):
    """The view a picture or page of ``data`` takes when none is asked for.

    An organized scan is seen from its sensor (:func:`sensor_view`); a map-like scan
    (:func:`is_map`: an airborne or street tile) from straight above, north up
    (``'top'``); anything else from the automatic view
    (:func:`superfacets.viz.camera.view_frame`).

    Parameters
    ----------
    data : PointCloud, Mesh or TetMesh

    Returns
    -------
    (3,) float64 ndarray, ``'top'`` or None

    Raises
    ------
    ValueError
        Never for inputs read by this package.

    Examples
    --------
    >>> default_view(as_mesh(trimesh.creation.box())) is None
    True
    """
    sensor = sensor_view(data)
    if sensor is not None:
        return sensor
    return "top" if is_map(data) else None


def thinnest_axis(data, extent=None) -> str | None:
    """The axis a point cloud with no up direction is thinnest along, as a map's height is
    (:data:`MAP_HEIGHT` of the next side: a street, a room or terrain in a format that names
    no up: XYZ, NPY, PLY), where it has one: ``--seen-from`` that axis segments it as a scan.

    Parameters
    ----------
    data : PointCloud or Mesh, or None
    extent : (3,) array_like, optional
        With ``data`` None: the box's sides (a tiled run's, read without the whole cloud),
        of a cloud with no up direction.

    Returns
    -------
    str or None
        ``'x'``, ``'y'`` or ``'z'``: its valid points' box is at most :data:`MAP_HEIGHT` as
        deep along it as along the next; None for a mesh, a cloud with an up direction, or a
        box not that flat.

    Raises
    ------
    None

    Examples
    --------
    >>> from superfacets import PointCloud
    >>> street = np.random.default_rng(0).random((500, 3)) * [60.0, 40.0, 4.0]
    >>> thinnest_axis(PointCloud(street)), thinnest_axis(PointCloud(street, up="z"))
    ('z', None)
    >>> thinnest_axis(None, extent=(60.0, 4.0, 40.0))
    'y'
    """
    if data is not None:
        if not hasattr(data, "valid") or getattr(data, "up", None) is not None or \
                not data.n_points:
            return None
        points = np.asarray(data.points)[np.asarray(data.valid)]
        extent = points.max(axis=0) - points.min(axis=0)
    extent = np.asarray(extent, dtype=np.float64).reshape(3)
    order = np.argsort(extent, kind="stable")
    if not extent[order[1]] > 0 or extent[order[0]] > MAP_HEIGHT * extent[order[1]]:
        return None
    return "xyz"[order[0]]
