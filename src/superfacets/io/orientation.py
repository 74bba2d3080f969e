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

__all__ = ["FORMAT_UP", "up_axis", "sensor_up", "sensor_view"]

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
        What said so, for messages: ``"the file's"``, ``"STL's convention"``, or
        ``"the default"``.

    Raises
    ------
    ValueError
        Never for inputs read by this package.

    Examples
    --------
    >>> import trimesh
    >>> from superfacets import as_mesh
    >>> up_axis(as_mesh(trimesh.creation.box()), "part.stl")
    ('z', "STL's convention")
    >>> up_axis(as_mesh(trimesh.creation.box()), "box.off")
    ('y', 'the default')
    """
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
    >>> from superfacets import PointCloud
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
