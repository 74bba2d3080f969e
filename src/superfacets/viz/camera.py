"""Camera placement for pictures of a mesh: a view direction and an up vector."""

from __future__ import annotations

import numpy as np

from ..checks import AXES
from ..errors import InvalidMeshError, ParameterError

__all__ = ["view_frame", "check_camera", "AXES", "VIEWS"]

#: Named views: direction from the mesh to the camera.
VIEWS = {"front": (0, 0, 1), "back": (0, 0, -1), "left": (-1, 0, 0), "right": (1, 0, 0),
         "top": (0, 1, 0), "bottom": (0, -1, 0)}



def _direction(value, what: str) -> np.ndarray:
    """``value`` as a unit 3-vector, or ParameterError naming ``what``."""
    try:
        v = np.asarray(value, dtype=float).reshape(3)
    except (TypeError, ValueError):
        v = np.zeros(3)
    norm = np.linalg.norm(v) if np.all(np.isfinite(v)) else 0.0
    if not norm > 0:
        raise ParameterError(f"{what} must be a non-zero finite 3-vector, got {value!r}")
    return v / norm


def check_camera(view=None, up="y") -> None:
    """Check a view and an up axis before any mesh is read (the same rules as
    :func:`view_frame`).

    Raises
    ------
    ParameterError
        On an unknown view name or up axis, or a zero/non-finite direction.

    Examples
    --------
    >>> check_camera("front", "z")
    >>> check_camera("sideways")
    Traceback (most recent call last):
    ...
    superfacets.errors.ParameterError: unknown view 'sideways'; use auto, front, ...
    """
    if isinstance(up, str):
        if up not in AXES:
            raise ParameterError(f"unknown up axis {up!r}; use one of {', '.join(AXES)}")
    else:
        _direction(up, "up")
    if isinstance(view, str):
        if view != "auto" and view not in VIEWS:
            raise ParameterError(f"unknown view {view!r}; use auto, {', '.join(VIEWS)} or x,y,z")
    elif view is not None:
        _direction(view, "view direction")


def _turn_to(up: np.ndarray) -> np.ndarray:
    """The rotation taking +y (the up of the named views) to the unit vector ``up``, about
    the axis perpendicular to both (z up: front is seen from -y, the south, top from +z
    with +y, the north, at the top of the picture)."""
    y = np.array([0.0, 1.0, 0.0])
    u = up / np.linalg.norm(up)
    c = float(y @ u)
    if c > 1 - 1e-12:
        return np.eye(3)
    if c < -1 + 1e-12:  # half a turn about x
        return np.diag([1.0, -1.0, -1.0])
    k = np.cross(y, u)
    s = np.linalg.norm(k)
    k /= s
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * K + (1 - c) * (K @ K)


def view_frame(mesh, view=None, elevation: float = 20.0,
               up="y") -> tuple[np.ndarray, np.ndarray]:
    """A camera direction and up vector that show a mesh well.

    Automatic (``view=None``): look along the principal axis of least
    area-weighted spread of the face centroids (so the widest silhouette
    faces the camera), tilted up by ``elevation`` degrees. Up is the ``up``
    axis made perpendicular to the view, or the principal axis of largest
    spread when ``up`` is along the view.

    Parameters
    ----------
    mesh : Mesh
    view : str or (3,) float, optional
        ``'auto'``, ``'front'`` (+z), ``'back'``, ``'left'``, ``'right'``,
        ``'top'`` (+y), ``'bottom'``, or a direction from the mesh to the camera.
        The names are those of a y-up input, turned with ``up``: with z up,
        ``'front'`` is seen from -y (the south) and ``'top'`` looks straight down
        with +y (the north) at the top of the picture, a map.
    elevation : float, default 20
        Degrees of upward tilt of an automatic or named side view (none for
        ``'top'`` and ``'bottom'``).
    up : {'y', 'z', 'x', '-y', '-z', '-x'} or (3,) float, default 'y'
        The mesh's up direction (most benchmark meshes: +y).

    Returns
    -------
    direction : (3,) float64 ndarray
        Unit vector from the mesh center to the camera.
    up : (3,) float64 ndarray
        Unit up vector, perpendicular to ``direction``.

    Raises
    ------
    ParameterError
        On an unknown view name or a zero/non-finite direction.
    InvalidMeshError
        If the mesh's coordinates are too large to measure its spread.
    """
    check_camera(view, up)
    c = mesh.centroids
    with np.errstate(over="ignore", invalid="ignore"):
        w = mesh.areas / max(mesh.area, 1e-300)
        mean = w @ c
        cov = (c - mean).T @ ((c - mean) * w[:, None])
    if not np.isfinite(cov).all():  # coordinates whose squares overflow
        name = getattr(mesh, "name", "")
        raise InvalidMeshError(f"{name + ': ' if name else ''}coordinates too large to place "
                               "a camera (their squares overflow double precision); rescale "
                               "the mesh (e.g. to unit size)")
    evals, evecs = np.linalg.eigh(cov)
    up_axis = np.array(AXES[up], dtype=float) if isinstance(up, str) else _direction(up, "up")
    if view is None or (isinstance(view, str) and view == "auto"):
        d = evecs[:, 0]  # the axis of least spread: the widest silhouette
        # face the camera from the positive side of the dominant world axis of d
        if d[np.argmax(np.abs(d))] < 0:
            d = -d
    elif isinstance(view, str):  # named from the input's up: 'top' looks down along it
        turn = _turn_to(up_axis)
        d = turn @ np.array(VIEWS[view], dtype=float)
        if view in ("top", "bottom"):  # straight down (up), the far side (north) at the top
            elevation = 0.0
            return d, turn @ np.array((0.0, 0.0, -1.0 if view == "top" else 1.0))
    else:
        d = _direction(view, "view direction")
        elevation = 0.0 if view is not None else elevation
    d = d / np.linalg.norm(d)
    up = up_axis.copy()
    if abs(up @ d) > 0.95:  # looking along y: use the longest principal axis
        up = evecs[:, 2] if abs(evecs[:, 2] @ d) < 0.95 else np.array([0.0, 0.0, -1.0])
    up = up - (up @ d) * d
    up /= np.linalg.norm(up)
    if elevation:
        t = np.radians(elevation)
        d, up = np.cos(t) * d + np.sin(t) * up, np.cos(t) * up - np.sin(t) * d
    return d / np.linalg.norm(d), up / np.linalg.norm(up)
