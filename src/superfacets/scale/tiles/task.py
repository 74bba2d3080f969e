"""One tile's task: what a worker runs for each tile and phase of a tiled run.

:func:`tile_task` is a module-level function, so that Dask workers import it by
reference; :func:`superfacets.scale.tiles.run.segment_tiled` hands it one dict per tile
and phase, and gathers what it returns (its errors as text, never raised).
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..._runtime.arrays import ranked
from ...errors import MemoryLimitError
from ...inputs.bounds import column_bounds
from ...inputs.mesh import Mesh
from ..runner.engine import PeakMemory, error_text
from . import phases
from .buckets import TileBuckets, keep_box, mesh_records
from .graphs import (
    keep_classification,
    kept_graph,
    save_face_topology,
    save_graph,
    tile_face_graph,
    tile_graph,
)
from .held import held_box, hold_box, release_held, worker_address
from .layout import in_box
from .phases import core_sizes, point_sizes, size_moments, tile_centers, tile_labels

__all__ = ["tile_task"]


def tile_task(task: dict) -> dict:
    """One tile's work (a module-level function: Dask workers import it by reference).

    ``task`` holds ``phase`` ('areas', 'centers', 'refine', 'labels' or 'connect'),
    ``reader``, ``layout`` (:class:`~superfacets.scale.tiles.layout.Tiles`), ``tile``,
    ``margin``, ``params``, ``r``, ``diagonal``, ``orient_like`` (optional: the oriented
    sample, or its file), ``frame`` (optional: the whole cloud's box, whose frame
    numbers a tile's points), for 'refine' and 'labels' the ``centers`` (rows) within
    reach, for 'labels' a ``ring`` (a width), for 'connect' the stitched ``labels`` and
    optionally the ``suspects`` (the only superfacets, by name, to repair).
    Returns a dict; an error is returned as ``error`` (text), never raised.

    Parameters
    ----------
    task : dict
        As above.

    Returns
    -------
    dict
        The phase's output for this tile (centers, labels or areas) and its seconds and peak
        memory.

    Raises
    ------
    SuperfacetsError
        As the method on the tile's input (the engine names the tile).

    Examples
    --------
    >>> m = trimesh.creation.icosphere(subdivisions=4)
    >>> from superfacets.scale.tiles.run import segment_tiled
    >>> segment_tiled((m.vertices, m.faces), 40, tiles=2, workers=1).tiles[0]["tile"]
    0
    """

    probe = PeakMemory()
    t0 = time.perf_counter()
    out = {"tile": task["tile"], "phase": task["phase"]}
    try:
        try:
            _phase(task, out)
        except (MemoryLimitError, MemoryError):
            if not release_held():  # (nothing held: the tile alone does not fit)
                raise
            _phase(task, out)  # again, with the memory the held tiles took
    except Exception as exc:  # noqa: BLE001 - reported by the driver, with the tile
        out["error"] = error_text(exc)
    except MemoryError as exc:  # pragma: no cover - depends on the machine
        out["error"] = error_text(exc)
    out["seconds"] = time.perf_counter() - t0
    peak = probe.peak_mib(above_start=False)
    out["peak_mib"] = None if peak is None else round(peak, 1)
    return out



def _phase(task: dict, out: dict) -> None:
    """One tile's phase (:func:`tile_task`), its output into ``out``."""
    layout = task["layout"]
    lo, hi = layout.box(task["tile"], task["margin"])
    key = _hold_key(task, lo, hi)
    held = None if key is None else held_box(key)  # (the phase before, in memory)
    if held is None:
        rows, pos, inp, owed_box = _box(task, lo, hi, write=key is None)
        inp = _framed(task, layout, inp)
        if owed_box is not None:  # (written when the tile is let go: _write_owed)
            _owe(inp, "box", owed_box)
    else:
        rows, pos, inp = held
    out["worker"] = worker_address()
    core = layout.holds(pos, task["tile"])
    out.update(rows=int(rows.size), core=int(core.sum()))
    if not core.any():  # no element of its own: nothing to do
        return out
    low, high = column_bounds(pos)
    spread = bool((high > low).any())
    graph_area = task.get("graph_area", False) and spread
    if task.get("graphs") and (task["phase"] != "areas" or graph_area) and spread:
        # (built once, read by the later phases; saved when the tile is let go)
        n, step = task["params"].n_neighbors, _step(task["params"])
        if tile_graph(inp, _graph_folder(task), n, save=False, step=step) == "built":
            _owe(inp, "graph", (save_graph, kept_graph(inp, n, step), _graph_folder(task)))
    elif task.get("boxes") and isinstance(inp, Mesh) and _face_elements(task["params"]):
        made = tile_face_graph(inp, _faces_folder(task), save=False)
        if not isinstance(made, str):
            _owe(inp, "faces", (save_face_topology, made, _faces_folder(task)))
    else:
        key = None  # (held only with its kept graph)
    if key is not None:  # (its weights made once: kept from this phase on)
        graph = _element_graph(inp, task["params"])
        if graph is not None:
            graph.__dict__.setdefault("weights_kept", {})
    p, r, d = task["params"], task["r"], task["diagonal"]
    if task["phase"] == "areas":
        _areas(task, inp, pos, core, graph_area, out)
    elif task["phase"] == "connect":
        given = task["labels"]
        if isinstance(given, str):  # the stitched labels, in a file every worker reads
            given = np.load(given, mmap_mode="r")[rows]
        given = np.asarray(given, dtype=np.int64)
        owned, at = _owned(given, rows, core)
        if task.get("suspects") is not None:  # (the only ones that can be in pieces)
            keep = np.isin(owned, task["suspects"])
            owned, at = owned[keep], at[keep]
        fixed = phases.tile_connect(inp, given, owned, at, p)
        moved = np.zeros(0, dtype=bool) if fixed is None else fixed != given
        out.update(moved_rows=rows[moved] if moved.size else rows[:0],
                   moved_labels=fixed[moved] if moved.size else rows[:0])
    elif task["phase"] == "colours":  # what the colour term's weight and floor read
        out["colour_sample"] = phases.tile_colour_sample(inp, p, r, d)
    elif task["phase"] == "centers":  # (with refine rounds to come: the start, one pass)
        found, _ = tile_centers(inp, core, replace(p, max_iter=task.get("passes")
                                                   or p.max_iter), r, d,
                                floor=task.get("floor"))
        out.update(centers=rows[found], positions=pos[found])
    else:
        want = np.asarray(task["centers"], dtype=np.int64)
        at = np.searchsorted(rows, want)
        ok = at < rows.size
        ok[ok] = rows[at[ok]] == want[ok]
        if task["phase"] == "refine":
            found = phases.tile_refine(inp, core, at[ok], p, r, d,
                                       folder=_graph_folder(task), floor=task.get("floor"))
            out.update(centers=rows[found], positions=pos[found])
            last = _last_classification(inp, p)
            if last is not None:  # (for the labels phase: held, or written when let go)
                _owe(inp, "classification", (keep_classification, _graph_folder(task),
                                             *last))
        else:
            _labelled(task, out, (rows, pos, inp, core), at[ok])
    if key is not None:
        _hold(key, (rows, pos, inp), task["params"])
    else:
        _write_owed(inp)


def _face_elements(params) -> bool:
    """Whether a mesh's run segments its faces (its default elements)."""
    return params.elements in (None, "faces")


def _owned(labels: np.ndarray, rows: np.ndarray, core: np.ndarray):
    """The labels (each its center's row) whose center is a row of the tile's core, and
    the box row of each: the superfacets the tile repairs. A table of the labels' values,
    not ``np.intersect1d`` (whose hashing of a box's millions of labels took 0.5 s a tile
    on 10M points)."""
    names = ranked(labels, int(labels.max(initial=-1)) + 1)[0]
    at = np.searchsorted(rows, names)
    ok = at < rows.size
    ok[ok] = rows[at[ok]] == names[ok]
    ok[ok] = core[at[ok]]
    return names[ok], at[ok]


def _labelled(task: dict, out: dict, box: tuple, centers: np.ndarray) -> None:
    """The labels phase of one tile (``box``: its rows, positions, input and core) from
    the ``centers`` (rows of the box) within reach: its core's and its ring's labels in
    ``out``, each named by its center's row in the input, and the merges' sums."""

    rows, pos, inp, core = box
    p, r, d = task["params"], task["r"], task["diagonal"]
    folder = _graph_folder(task)
    floor = task.get("floor")  # (the colour term's, read once over every tile)
    if task.get("n_noise") is not None:  # the merges to the count follow
        named, out["merge_stats"] = tile_labels(
            inp, centers, p, r, d, merging=(core, rows, task["n_noise"]), folder=folder,
            floor=floor, frame=task.get("frame_of_ground"), unweighted=task.get("unweighted"))
    else:
        named = tile_labels(inp, centers, p, r, d, folder=folder, floor=floor)
    gid = np.where(named >= 0, rows[np.maximum(named, 0)], -1)
    lo_c, hi_c = task["layout"].box(task["tile"])
    near = ~core & ((pos >= lo_c - task["ring"]) & (pos <= hi_c + task["ring"])).all(1)
    out.update(core_rows=rows[core], core_labels=gid[core], ring_rows=rows[near],
               ring_labels=gid[near])
    if task.get("box_rows", True):  # for the connect phase, unless read from a file
        out["box_rows"] = rows


def _graph_folder(task: dict) -> Path | None:
    """The folder of the tile's kept point graph (and its refine round's last
    classification), or None where the run keeps none."""
    return Path(task["graphs"]) / f"tile-{task['tile']}" if task.get("graphs") else None


def _hold_key(task: dict, lo, hi) -> tuple | None:
    """The key a tile's box is held under between its phases (:mod:`.held`): the run's
    folder of graphs (a mesh's: of boxes), the tile and its box; None where the run keeps
    no graphs. The folder is made here: its removal at the run's end ends the hold."""
    folder = task.get("graphs") or task.get("boxes")
    if folder is None:
        return None
    Path(folder).mkdir(parents=True, exist_ok=True)
    return (str(folder), task["tile"], np.asarray(lo).tobytes(), np.asarray(hi).tobytes())


def _owe(inp, name: str, write: tuple) -> None:
    """Note a write a tile's box owes the work folder for its later phases (``write``: a
    function and its arguments), made when the tile is let go (:func:`_write_owed`)."""
    inp.__dict__.setdefault("_owed_writes", {})[name] = write


def _write_owed(inp) -> None:
    """Make the writes noted on a tile's box (:func:`_owe`), each once."""
    owed = inp.__dict__.pop("_owed_writes", {}) if inp is not None else {}
    for write, *args in owed.values():
        write(*args)


def _areas(task: dict, inp, pos: np.ndarray, core: np.ndarray, graph_area: bool,
           out: dict) -> None:
    """The areas phase of a tile: its core points' sizes on the run's graph, summed, and
    their moments; where a seed resolution asks for the count and steps are weighed, also
    the surface's area as one run measures it (by each point's nearest neighbours)."""
    p = task["params"]
    sizes = (core_sizes(inp, core, p.n_neighbors, _step(p)) if graph_area
             else point_sizes(pos, core, p.n_neighbors, _step(p)))
    out["area"], out["size_moments"] = float(sizes.sum()), size_moments(sizes)
    if task.get("surface_area") and _step(p) != 1:
        out["surface_area"] = float(point_sizes(pos, core, p.n_neighbors).sum())


def _step(params) -> float:
    """The run's ``step_weight`` (resolved by the driver; 1 where not)."""
    return float(params.step_weight or 1.0)


def _last_classification(inp, params):
    """The refine round's last classification kept with a cloud tile's point graph
    (:func:`~superfacets.scale.tiles.phases.tile_refine`), or None."""
    el = None if isinstance(inp, Mesh) else kept_graph(inp, params.n_neighbors, _step(params))
    return None if el is None else el.graph.__dict__.get("last_classification")


def _element_graph(inp, params):
    """The element graph kept with a tile's box (a cloud's point graph, a mesh's face
    graph), or None."""
    if isinstance(inp, Mesh):
        return inp.__dict__.get("_face_graph")
    el = kept_graph(inp, params.n_neighbors, _step(params))
    return None if el is None else el.graph


def _faces_folder(task: dict) -> Path:
    """The folder of a mesh tile's kept face graph topology (beside its kept box)."""
    return Path(task["boxes"]) / f"faces-{task['tile']}"


def _hold(key: tuple, box: tuple, params) -> None:
    """Hold a tile's box (rows, positions, input) with its element graph (a cloud's point
    graph, a mesh's face graph), which keeps the weights it is given from now on
    (``weights_kept``: :func:`~superfacets.method.stages.weigh`) and a mesh's refine round's
    classifier with its recorded expansions (``last_classifier``), for the tile's next
    phase in this process; counted as every array these hold (the weights and the
    records four levels down)."""
    g = _element_graph(box[2], params)
    if g is None:
        return
    g.__dict__.setdefault("weights_kept", {})
    hold_box(key, box, _arrays_in((*box[:2], vars(g), vars(box[2]))),
             write=lambda: _write_owed(box[2]))


def _arrays_in(obj, depth: int = 4) -> list:
    """The arrays ``obj`` holds (in its tuples, lists, dictionaries and attributes, to
    ``depth`` levels), each once: what a held tile takes."""
    found: dict = {}

    def walk(o, d):
        if isinstance(o, np.ndarray):
            base = o if o.base is None or not isinstance(o.base, np.ndarray) else o.base
            found[id(base)] = base
        elif d > 0 and isinstance(o, (tuple, list)):
            for x in o:
                walk(x, d - 1)
        elif d > 0 and isinstance(o, dict):
            for x in o.values():
                walk(x, d - 1)
        elif d > 0 and hasattr(o, "__dict__") and not callable(o):
            walk(vars(o), d - 1)

    walk(obj, depth)
    return list(found.values())


def _framed(task: dict, layout, inp):
    """A task's input with the run's orientation reference and frame, where it has them
    (``inp`` None, a box without an element, stays None)."""
    if inp is None:
        return None
    changes = {}
    ref = task.get("orient_like")
    if ref is not None:  # every tile orients like one sample (a file, or its part)
        if isinstance(ref, str):
            ref = in_box(np.load(ref, mmap_mode="r"), *layout.box(task["tile"],
                                                                    1.5 * task["margin"]))
        changes["orient_like"] = (ref[:, :3], ref[:, 3:])
    if task.get("frame") is not None:
        changes["frame"] = task["frame"]  # numbered as the whole cloud numbers them
    return replace(inp, **changes) if changes else inp  # (one check of the input, not two)


def _box(task: dict, lo, hi, write: bool = True):
    """A task's box: its rows, positions and input, and the write it owes (or None); the
    first phase of a tile keeps the box's records in the run's ``boxes`` folder, where it
    has one, for the later phases (one file, not the tiles the box overlaps: a mesh's
    faces read from 4 tiles' files took 2.9 s a box of 3M faces, against 0.4 s). Unless
    ``write``, the box is written when its tile is let go (:func:`_write_owed`; never,
    where its phases all run on it held): a mesh's from what is held
    (:func:`~superfacets.scale.tiles.buckets.mesh_records`), a cloud's from its records,
    held with it (0.34 s of writes a run of 10M points in 8 tiles, 32 bytes a point held)."""

    reader, name = task["reader"], f"tile {task['tile']}"
    if not (task.get("boxes") and isinstance(reader, TileBuckets)):
        return (*reader.read_box(lo, hi, name=name), None)
    Path(task["boxes"]).mkdir(parents=True, exist_ok=True)
    keep = Path(task["boxes"]) / f"box-{task['tile']}"
    if write or reader.kept(keep, lo, hi):
        return (*reader.read_box(lo, hi, name=name, keep=keep), None)
    if "tri" not in reader.dtype.names:  # a cloud's records, held until the write
        rows, pos, inp, owed = reader.read_box(lo, hi, name=name, keep=keep, owe=True)
        return rows, pos, inp, None if inp is None else owed
    rows, pos, inp = reader.read_box(lo, hi, name=name)
    if inp is None:
        return rows, pos, inp, None
    return rows, pos, inp, (_keep_mesh_box, keep, reader.dtype, (rows, pos, inp), lo, hi)


def _keep_mesh_box(keep, dtype, box: tuple, lo, hi) -> None:
    """Write a mesh tile's box at ``keep`` from its rows, positions and mesh."""
    keep_box(keep, mesh_records(dtype, *box), np.asarray(lo, dtype=np.float64),
             np.asarray(hi, dtype=np.float64))
