"""Labelled rooms made here: an S3DIS-like indoor benchmark that needs no download.

A room is a box (floor, ceiling, four walls) with what S3DIS rooms hold: boards, doors and
windows set into the walls, **in the wall's plane** (they differ from the wall in colour
only, as a whiteboard or a closed door does in a scan), tables with legs, chairs, a
bookcase against a wall, a sofa, and objects on the tables (simple solids: books, mugs,
balls, cones; and meshes, scaled to 12-35 cm: :func:`load_room` puts the paper's Table-1
meshes there where a source checkout has them beside it, :func:`statues`). Its
surfaces are sampled densely, thinned to one point per 3 cm voxel (S3DIS's subsampling),
given sensor noise (5 mm in position, 0.02 in each colour channel) and cut where a solid
hides them (the floor under a bookcase, the wall behind it, a leg's top under its
table). Every point knows
its object (an instance) and its class (S3DIS's names), so superpoints are judged
against both (:func:`superfacets.evaluation.datasets.scans.evaluate_scan`).

The rooms are random but fixed by their seed (numpy's ``default_rng``); nothing here is
tuned to any method. ``benchmarks/real_scans.py --rooms N`` and ``superfacets experiment
--dataset rooms`` run on them.

Examples
--------
>>> scan = make_room(0)
>>> scan.cloud.colors is not None, scan.ground_truth.shape == (scan.cloud.n_total,)
(True, True)
>>> sorted(CLASSES)[:3]
['board', 'bookcase', 'ceiling']
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from ...checks import check_int
from ...errors import ParameterError
from ...inputs.cloud import PointCloud
from ...io import read_mesh
from .psb import default_archive
from .scans import Scan, ScanSource

__all__ = ["CLASSES", "make_room", "room_names", "load_room", "statues", "RoomEntry",
           "room_entries"]

#: S3DIS's classes (its numbering) that the rooms hold.
CLASSES = {"ceiling": 0, "floor": 1, "wall": 2, "window": 5, "door": 6, "table": 7,
           "chair": 8, "sofa": 9, "bookcase": 10, "board": 11, "clutter": 12}

#: The most rooms an experiment may ask for (each a few seconds to make).
MAX_ROOMS = 100_000
_SPACING = 0.03  # the voxel, metres (S3DIS's usual subsampling)
_NOISE = 0.005  # sensor noise in position, metres (one standard deviation)
_COLOR_NOISE = 0.02  # and in each colour channel (colours in [0, 1])
_OVERSAMPLE = 6  # points drawn per voxel's area, before the thinning


@dataclass
class _Room:
    """Surfaces sampled so far: points, colours, classes and instances, and the solids
    that hide what lies inside them."""

    rng: np.random.Generator
    points: list = field(default_factory=list)
    colors: list = field(default_factory=list)
    classes: list = field(default_factory=list)
    instances: list = field(default_factory=list)
    solids: list = field(default_factory=list)  # (lower, upper, instance)
    statues: bool = False  # meshes among the objects

    def add(self, pts: np.ndarray, color, cls: str, inst: int) -> None:
        self.points.append(pts)
        self.colors.append(np.broadcast_to(np.asarray(color, dtype=np.float64), pts.shape))
        self.classes.append(np.full(len(pts), CLASSES[cls], dtype=np.int64))
        self.instances.append(np.full(len(pts), inst, dtype=np.int64))

    def rect(self, origin, u, v, color, cls: str, inst: int) -> None:
        """A rectangle ``origin + s u + t v``, ``s, t`` in [0, 1], sampled."""
        u, v = np.asarray(u, dtype=np.float64), np.asarray(v, dtype=np.float64)
        n = _count(np.linalg.norm(np.cross(u, v)))
        st = self.rng.random((n, 2))
        self.add(np.asarray(origin, dtype=np.float64) + st[:, :1] * u + st[:, 1:] * v,
                 color, cls, inst)

    def box(self, lower, upper, color, cls: str, inst: int, floor: bool = True) -> None:
        """An axis-aligned box's faces (not the bottom where it stands on the floor)."""
        lo, hi = np.asarray(lower, dtype=np.float64), np.asarray(upper, dtype=np.float64)
        d = hi - lo
        ex, ey, ez = np.diag(d)
        faces = [(lo, ex, ey), (lo + ez, ex, ey), (lo, ex, ez), (lo + ey, ex, ez),
                 (lo, ey, ez), (lo + ex, ey, ez)]
        for i, (o, u, v) in enumerate(faces):
            if i == 0 and floor and lo[2] <= 1e-9:
                continue
            self.rect(o, u, v, color, cls, inst)
        self.solids.append((lo, hi, inst))

    def mesh(self, vertices, faces, color, cls: str, inst: int) -> None:
        """A triangle mesh's surface, sampled uniformly by area."""
        tri = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)]
        area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]),
                                    axis=1)
        n = _count(float(area.sum()))
        f = self.rng.choice(len(tri), size=n, p=area / area.sum())
        a, b = self.rng.random((2, n))
        flip = a + b > 1
        a[flip], b[flip] = 1 - a[flip], 1 - b[flip]
        t = tri[f]
        self.add(t[:, 0] + a[:, None] * (t[:, 1] - t[:, 0]) + b[:, None] * (t[:, 2] - t[:, 0]),
                 color, cls, inst)


def _count(area: float) -> int:
    return max(1, int(round(_OVERSAMPLE * area / _SPACING ** 2)))


def _shade(rng, base, spread: float = 0.06) -> np.ndarray:
    """An object's colour: ``base`` (RGB in [0, 1]) moved a little, per object."""
    return np.clip(np.asarray(base) + rng.uniform(-spread, spread, 3), 0.0, 1.0)


def _walls(room: _Room, size) -> list:
    """Floor, ceiling and walls; returns the walls as ``(origin, along, normal, length)``."""
    rng = room.rng
    L, W, H = size
    room.rect((0, 0, 0), (L, 0, 0), (0, W, 0), _shade(rng, (0.45, 0.42, 0.40)), "floor", 0)
    room.rect((0, 0, H), (L, 0, 0), (0, W, 0), _shade(rng, (0.90, 0.90, 0.88), 0.03),
              "ceiling", 1)
    wall = _shade(rng, (0.80, 0.78, 0.72))
    walls = [((0, 0, 0), (1, 0, 0), (0, 1, 0), L), ((L, 0, 0), (0, 1, 0), (-1, 0, 0), W),
             ((L, W, 0), (-1, 0, 0), (0, -1, 0), L), ((0, W, 0), (0, -1, 0), (1, 0, 0), W)]
    for i, (o, a, _, length) in enumerate(walls):
        room.rect(o, np.asarray(a, dtype=float) * length, (0, 0, H), wall, "wall", 2 + i)
    return [(np.asarray(o, float), np.asarray(a, float), np.asarray(nrm, float), length)
            for o, a, nrm, length in walls]


#: What is set into the walls: (class, width range, height range, bottom range, colours)
_OPENINGS = (("door", (0.85, 1.0), (2.0, 2.1), (0.0, 0.0),
              ((0.55, 0.38, 0.22), (0.35, 0.35, 0.38), (0.92, 0.92, 0.90))),
             ("board", (1.2, 2.4), (0.9, 1.2), (0.85, 1.0),
              ((0.97, 0.97, 0.97), (0.15, 0.30, 0.20), (0.12, 0.12, 0.14))),
             ("window", (1.0, 1.6), (1.0, 1.4), (0.85, 1.1),
              ((0.70, 0.80, 0.90), (0.55, 0.60, 0.65))))


def _openings(room: _Room, walls, size, next_inst: int) -> int:
    """Doors, boards and windows in the walls' plane: the wall's points inside each take
    its colour, class and instance (they differ from the wall in colour only)."""
    rng, H = room.rng, size[2]
    pts, cols = room.points, room.colors
    taken = {i: [] for i in range(4)}
    for cls, (w0, w1), (h0, h1), (b0, b1), palette in _OPENINGS:
        for _ in range(rng.integers(1, 3)):
            i = int(rng.integers(0, 4))
            o, a, _, length = walls[i]
            w, h = rng.uniform(w0, w1), min(rng.uniform(h0, h1), H - 0.3)
            for _try in range(20):
                s = rng.uniform(0.2, max(0.21, length - w - 0.2))
                if all(s + w + 0.2 < t0 or s > t1 + 0.2 for t0, t1 in taken[i]):
                    break
            else:
                continue
            taken[i].append((s, s + w))
            bottom = rng.uniform(b0, b1)
            wall_pts = pts[2 + i]  # (the walls' arrays, in order, after floor and ceiling)
            along = (wall_pts - o) @ a
            inside = (along >= s) & (along <= s + w) & (wall_pts[:, 2] >= bottom) & (
                wall_pts[:, 2] <= bottom + h)
            color = _shade(rng, palette[rng.integers(0, len(palette))], 0.03)
            cols[2 + i] = np.where(inside[:, None], color, cols[2 + i])
            room.classes[2 + i] = np.where(inside, CLASSES[cls], room.classes[2 + i])
            room.instances[2 + i] = np.where(inside, next_inst, room.instances[2 + i])
            next_inst += 1
    return next_inst


def _table(room: _Room, x, y, inst: int) -> tuple:
    """A table at ``(x, y)`` (its lower corner): top and four legs; returns its top."""
    rng = room.rng
    w, d, h = rng.uniform(1.2, 1.8), rng.uniform(0.7, 0.9), rng.uniform(0.72, 0.76)
    color = _shade(rng, ((0.60, 0.45, 0.30), (0.85, 0.85, 0.82))[rng.integers(0, 2)])
    room.box((x, y, h - 0.04), (x + w, y + d, h), color, "table", inst, floor=False)
    for lx, ly in ((x + 0.03, y + 0.03), (x + w - 0.08, y + 0.03), (x + 0.03, y + d - 0.08),
                   (x + w - 0.08, y + d - 0.08)):
        room.box((lx, ly, 0), (lx + 0.05, ly + 0.05, h - 0.04), color, "table", inst)
    return (x, y, w, d, h)


def _chair(room: _Room, x, y, inst: int) -> None:
    rng = room.rng
    color = _shade(rng, ((0.20, 0.20, 0.25), (0.55, 0.15, 0.12), (0.25, 0.35, 0.55))[
        rng.integers(0, 3)])
    s = 0.45
    room.box((x, y, 0.42), (x + s, y + s, 0.46), color, "chair", inst, floor=False)
    room.box((x, y + s - 0.04, 0.46), (x + s, y + s, 0.90), color, "chair", inst, floor=False)
    for lx, ly in ((x, y), (x + s - 0.04, y), (x, y + s - 0.04), (x + s - 0.04, y + s - 0.04)):
        room.box((lx, ly, 0), (lx + 0.04, ly + 0.04, 0.42), color, "chair", inst)


def _clutter(room: _Room, top, meshes, next_inst: int) -> int:
    """Objects on a table top: books, mugs, balls, cones, and the given meshes."""
    import trimesh

    rng = room.rng
    x, y, w, d, h = top
    for _ in range(rng.integers(2, 6)):
        pick = int(rng.integers(0, 4 + (1 if meshes else 0)))
        if pick == 0:
            m = trimesh.creation.box((rng.uniform(0.15, 0.3), rng.uniform(0.1, 0.22),
                                      rng.uniform(0.02, 0.06)))
        elif pick == 1:
            m = trimesh.creation.cylinder(rng.uniform(0.035, 0.05), rng.uniform(0.08, 0.12),
                                          sections=24)
        elif pick == 2:
            m = trimesh.creation.icosphere(2, rng.uniform(0.05, 0.1))
        elif pick == 3:
            m = trimesh.creation.cone(rng.uniform(0.05, 0.1), rng.uniform(0.12, 0.3),
                                      sections=24)
        else:
            src = meshes[int(rng.integers(0, len(meshes)))]
            m = trimesh.Trimesh(np.asarray(src.vertices), np.asarray(src.faces), process=False)
            m.apply_scale(rng.uniform(0.12, 0.35) / max(float(m.extents.max()), 1e-12))
        m.apply_transform(trimesh.transformations.rotation_matrix(rng.uniform(0, 2 * np.pi),
                                                                  (0, 0, 1)))
        lo, hi = m.bounds
        if hi[0] - lo[0] > w - 0.1 or hi[1] - lo[1] > d - 0.1:
            continue
        at = (rng.uniform(x + 0.05 - lo[0], x + w - 0.05 - hi[0]),
              rng.uniform(y + 0.05 - lo[1], y + d - 0.05 - hi[1]), h - lo[2])
        m.apply_translation(at)
        color = _shade(rng, rng.uniform(0.1, 0.9, 3), 0.0)
        room.mesh(m.vertices, m.faces, color, "clutter", next_inst)
        next_inst += 1
    return next_inst


def _furniture(room: _Room, walls, size, meshes, next_inst: int) -> int:
    """Tables with chairs and objects, a bookcase against a wall, a sofa: placed on a
    grid of the floor so that none overlaps another."""
    rng = room.rng
    L, W, _ = size
    bx = rng.uniform(0.5, L - 1.5)  # the bookcase, against the wall y = 0
    bh = rng.uniform(1.8, 2.1)
    room.box((bx, 0, 0), (bx + 0.9, 0.35, bh), _shade(rng, (0.50, 0.35, 0.20)), "bookcase",
             next_inst)
    next_inst += 1
    sx = rng.uniform(0.3, max(0.31, L - 2.3))  # the sofa, against the wall y = W
    sofa = _shade(rng, ((0.30, 0.30, 0.32), (0.45, 0.25, 0.15))[rng.integers(0, 2)])
    room.box((sx, W - 0.9, 0), (sx + 2.0, W - 0.2, 0.42), sofa, "sofa", next_inst)
    room.box((sx, W - 0.2, 0), (sx + 2.0, W, 0.85), sofa, "sofa", next_inst)
    next_inst += 1
    n_tables = int(rng.integers(1, 3)) if L - 0.8 >= 4.0 else 1
    for t in range(n_tables):  # tables in the middle band, chairs beside them
        x0 = 0.4 + t * (L - 0.8) / n_tables
        span = (L - 0.8) / n_tables
        x, y = x0 + rng.uniform(0.0, span - 1.9), rng.uniform(1.2, max(1.21, W - 2.2))
        top = _table(room, x, y, next_inst)
        next_inst += 1
        for c in range(int(rng.integers(1, 3))):
            _chair(room, x + 0.1 + c * 0.6, y - 0.55, next_inst)
            next_inst += 1
        next_inst = _clutter(room, top, meshes, next_inst)
    return next_inst


def _finish(room: _Room, name: str, color_noise: float = _COLOR_NOISE):
    """Hidden points cut, one point per voxel, noise added: the scan."""

    rng = room.rng
    pts = np.concatenate(room.points)
    col = np.concatenate(room.colors)
    cls, inst = np.concatenate(room.classes), np.concatenate(room.instances)
    hidden = np.zeros(len(pts), dtype=bool)
    for lo, hi, owner in room.solids:  # in or on another object's solid: not seen (the
        # floor under a bookcase, the wall behind it, a leg's top under its table)
        inside = ((pts >= lo - 1e-9) & (pts <= hi + 1e-9)).all(axis=1) & (inst != owner)
        hidden |= inside
    keep = ~hidden
    pts, col, cls, inst = pts[keep], col[keep], cls[keep], inst[keep]
    order = rng.permutation(len(pts))  # one point per voxel, drawn at random
    keys = np.floor(pts[order] / _SPACING).astype(np.int64)
    _, first = np.unique(keys, axis=0, return_index=True)
    pick = np.sort(order[first])
    pts = pts[pick] + rng.normal(0.0, _NOISE, (len(pick), 3))
    col = np.clip(col[pick] + rng.normal(0.0, color_noise, (len(pick), 3)), 0.0, 1.0)
    cloud = PointCloud(pts, name=name, colors=col, up=np.array([0.0, 0.0, 1.0]))
    source = ScanSource(name, "made-up room (S3DIS-like, 3 cm voxels, RGB"
                        + (", statues)" if room.statues else ")"), (), "room",
                        "made here (superfacets.evaluation.datasets.rooms)", "s3dis")
    return Scan(name, cloud, cls[pick], source, inst[pick])


def make_room(seed: int = 0, meshes=(), *, color_noise: float = _COLOR_NOISE
              ) -> "Scan":  # noqa: F821 (scans.Scan)
    """One labelled room (see the module notes), fixed by ``seed``.

    Parameters
    ----------
    seed : int, default 0
        The room: its size, what it holds and where, its colours, its noise.
    meshes : sequence of Mesh, optional
        Meshes that may stand on the tables as objects (scaled to 12-35 cm).
    color_noise : float, default 0.02
        The sensor's colour noise, one standard deviation per channel (colours in
        [0, 1]).

    Returns
    -------
    Scan
        ``cloud``: a :class:`~superfacets.inputs.cloud.PointCloud` (metres, z up) with
        colours; ``ground_truth``: the S3DIS class of each point (:data:`CLASSES`);
        ``instances``: its object (floor 0, ceiling 1, walls 2-5, then the rest).

    Raises
    ------
    ValueError
        If ``seed`` is negative.

    Examples
    --------
    >>> a, b = make_room(3), make_room(3)
    >>> bool((a.cloud.points == b.cloud.points).all()), a.name
    (True, 'room-3')
    """
    rng = np.random.default_rng(seed)
    size = (rng.uniform(4.0, 6.5), rng.uniform(3.5, 5.5), rng.uniform(2.6, 3.1))
    room = _Room(rng, statues=bool(len(meshes)))
    walls = _walls(room, size)
    next_inst = _openings(room, walls, size, 6)
    _furniture(room, walls, size, list(meshes), next_inst)
    return _finish(room, f"room-{seed}", color_noise)


def room_names(n: int) -> list[str]:
    """The names of the first ``n`` rooms: ``room-0`` ... (what :func:`load_room` reads).

    Raises
    ------
    ParameterError
        If ``n`` is not an integer in ``[0, MAX_ROOMS]``.

    Examples
    --------
    >>> room_names(2)
    ['room-0', 'room-1']
    """
    return [f"room-{i}" for i in range(check_int("the number of rooms", n, 0, MAX_ROOMS))]


@lru_cache(maxsize=1)
def statues() -> tuple:
    """The meshes of the paper's Table 1 found beside a source checkout (the bunny, the
    horse, the hand: ``../shared/data/meshes/*.tri.xz``), to stand on the rooms' tables;
    empty elsewhere (the rooms then hold simple solids only).

    Examples
    --------
    >>> all(m.n_faces > 10_000 for m in statues())
    True
    """

    folder = default_archive().parent / "meshes"
    return tuple(read_mesh(p) for p in sorted(folder.glob("*.tri.xz")))


def load_room(name: str, meshes=None) -> "Scan":  # noqa: F821
    """The room called ``name`` (``room-<seed>``): :func:`make_room` of its seed, with
    ``meshes`` (default: :func:`statues`) among the objects on its tables.

    Raises
    ------
    ParameterError
        If ``name`` is not ``room-`` and a whole number.

    Examples
    --------
    >>> load_room("room-1").name
    'room-1'
    """

    head, _, seed = name.partition("-")
    if head != "room" or not seed.isdigit():
        raise ParameterError(f"unknown room {name!r}: rooms are named room-0, room-1, ...")
    return make_room(int(seed), statues() if meshes is None else meshes)


@dataclass(frozen=True)
class RoomEntry:
    """A room as an entry of ``superfacets experiment`` (beside the benchmark's meshes:
    :class:`~superfacets.evaluation.datasets.psb.BenchmarkMesh`): made, not read.

    Attributes
    ----------
    id : int
        Its seed.
    category : str
        ``"Room"``.
    path : pathlib.Path
        Its name, ``room-<id>`` (no file).
    seg_paths : tuple
        Empty (the ground truth comes with the room).
    room : bool
        True.
    """

    id: int
    category: str = "Room"
    path: object = None
    seg_paths: tuple = ()
    room: bool = True


def room_entries(n: int) -> list[RoomEntry]:
    """The first ``n`` rooms as entries of an experiment.

    Raises
    ------
    ParameterError
        If ``n`` is below 1.

    Examples
    --------
    >>> [str(e.path) for e in room_entries(2)]
    ['room-0', 'room-1']
    """
    from pathlib import Path


    if isinstance(n, int) and n < 1:
        raise ParameterError(f"--rooms must be at least 1, got {n}")
    return [RoomEntry(i, path=Path(name)) for i, name in enumerate(room_names(n))]
