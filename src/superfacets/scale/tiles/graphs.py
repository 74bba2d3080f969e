"""A tiled run's element graphs: built once per tile, read back by its later phases.

Every phase of a tiled run on a cloud (centers, refine, labels, and the connectivity
repair) reads the same box of the input, and each built its point graph again: on 2M
points in 16 tiles, 49 of the run's 101 s. Where the tasks share a work folder, the
first phase of a tile builds its graph once: its worker holds it in memory for the later
phases (:mod:`.held`), and writes it there when it lets the tile go while the run goes
on, or at once where it cannot hold it (:func:`save_graph`: the arrays
:func:`~superfacets.elements.points.point_graph` builds: positions, sizes, normals, the
CSR adjacency, the element of each row; about 110 bytes per point of the box); a later
phase that does not find the tile held reads it back: the same arrays, so the same
labels. The labels phase starts from the refine round's last classification, kept the
same way (:func:`keep_classification`). A mesh's tiles keep their face graphs' topology
beside their boxes (:func:`tile_face_graph`).
"""

from __future__ import annotations

import json
import os
import shutil
import uuid
from pathlib import Path

import numpy as np

from ...elements import points
from ...elements.builders import prepared
from ...elements.faces import FaceAdjacency, face_adjacency, face_graph_from
from ...elements.graph import cached_on
from ...elements.kinds import kind_of
from ...elements.points import point_elements
from ...io.files import array_digest, load_checked

__all__ = ["GRAPH_FILES", "FACE_FILES", "BYTES_PER_POINT", "graph_folder", "drop_graphs",
           "tile_graph", "save_graph", "kept_graph", "keep_classification",
           "kept_classification", "tile_face_graph", "save_face_topology", "room_for_graphs"]

#: The arrays a tile's graph is saved as, one ``.npy`` file each.
GRAPH_FILES = ("positions", "sizes", "normals", "indptr", "indices", "index")
#: Disk per point of a box (positions 24, size 8, normal 12, adjacency about 60, row 4,
#: the refine round's last classification 12).
BYTES_PER_POINT = 122
#: The arrays of a mesh tile's face graph topology (:class:`~superfacets.elements.faces.
#: FaceAdjacency`), one ``.npy`` file each; about 60 bytes a face.
FACE_FILES = ("pairs", "edges", "indptr", "indices", "dual_edge", "boundary_edges",
              "boundary_faces")


def graph_folder(work, n_points: int, kind: str, shared: bool, params) -> Path | None:
    """The (emptied) folder of a tiled run's graphs in its work folder ``work``, or None
    where they are not kept: elements other than points, tasks that share no folder,
    a ``neighbor_radius`` (sized per tile), or too little room on the disk
    (:func:`room_for_graphs`)."""

    if not kind_of(kind).cloud or not shared or params.neighbor_radius is not None \
            or not room_for_graphs(work, n_points):
        return None
    folder = Path(work) / "graphs"
    shutil.rmtree(folder, ignore_errors=True)  # (an earlier run's, in a kept work folder)
    return folder


def drop_graphs(folder) -> None:
    """Remove a run's graphs (``folder`` from :func:`graph_folder`; None: nothing)."""
    if folder is not None:
        shutil.rmtree(folder, ignore_errors=True)


def room_for_graphs(folder, n_points: int, overlap: float = 2.0) -> bool:
    """Whether ``folder`` has room, twice over, for the graphs of ``n_points`` points
    read ``overlap`` times (the tiles' halos)."""
    try:
        free = shutil.disk_usage(folder).free
    except OSError:
        return False
    return free > 2 * overlap * BYTES_PER_POINT * n_points


def tile_graph(cloud, folder, n_neighbors: int, *, save: bool = True,
               step: float = 1.0) -> str:
    """Give ``cloud`` its point graph (``n_neighbors``, no ``neighbor_radius``) from
    ``folder``, or build it and save it there.

    Parameters
    ----------
    cloud : PointCloud
        A tile's box, as every phase reads it (the same rows, the same orientation
        reference).
    folder : str or os.PathLike
        The tile's folder in the run's work folder (created when saved).
    n_neighbors : int
    step : float, default 1
        The run's ``step_weight`` (its neighbours along the surface where above 1:
        :func:`~superfacets.elements.points.point_graph`).
    save : bool, default True
        Save a graph built here (False: the caller saves it later, if ever, with
        :func:`save_graph`: a tile held in its worker's memory).

    Returns
    -------
    str
        ``'read'``, ``'built'`` (and saved, with ``save``) or ``'kept'`` (already with
        the cloud).

    Raises
    ------
    InvalidCloudError, MemoryLimitError
        As :func:`superfacets.elements.builders.elements_of`.
    OSError
        If the folder cannot be written or read.

    Examples
    --------
    >>> import tempfile
    >>> xyz = np.random.default_rng(0).random((500, 3))
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     first = tile_graph(PointCloud(xyz), Path(tmp) / "tile0", 10)
    ...     again = PointCloud(xyz)
    ...     print(first, tile_graph(again, Path(tmp) / "tile0", 10), tile_graph(again, "", 10))
    built read kept
    """

    folder = Path(folder)
    _, data = prepared(cloud, "points")
    graphs = cached_on(data, "_point_graphs", dict)
    key = points.graph_key(n_neighbors, None, step)
    if key in graphs:
        return "kept"
    done = folder / "graph.json"
    if done.is_file():
        meta = json.loads(done.read_text(encoding="utf-8"))
        arrays = _read_checked(folder, meta)
        el = point_elements(arrays["positions"], arrays["sizes"], arrays["normals"],
                            arrays["indptr"], arrays["indices"], arrays["index"],
                            np.dtype(meta["pair_dtype"]))
        data.lend_points(el.graph.positions, el.index)  # as the build does
        graphs[key] = el
        return "read"
    el = points.point_graph(data, n_neighbors, step=step)
    if save:
        save_graph(el, folder)
    return "built"


def save_graph(el, folder) -> None:
    """Save a tile's point elements ``el`` (:func:`tile_graph`'s, built) in ``folder``,
    whole or not at all, for its later phases to read.

    Raises
    ------
    OSError
        If the folder cannot be written.
    """
    g = el.graph
    pair_dtype = g.rebuild["pairs"].keywords["pair_dtype"]
    _save(Path(folder), "graph.json", dict(
        positions=g.positions, sizes=g.sizes, normals=g.normals, indptr=g.indptr,
        indices=g.indices, index=el.index), {"pair_dtype": np.dtype(pair_dtype).name})


def kept_graph(cloud, n_neighbors: int, step: float = 1.0):
    """The point elements (``n_neighbors``, no radius, ``step``) kept with ``cloud`` by
    :func:`tile_graph`, or None."""
    if cloud is None:
        return None
    _, data = prepared(cloud, "points")
    return data.__dict__.get("_point_graphs", {}).get(points.graph_key(n_neighbors, None,
                                                                        step))


#: The files of a refine round's last classification (:func:`keep_classification`).
CLASSIFICATION_FILES = ("classification-label", "classification-centers",
                        "classification-dist")


def keep_classification(folder, label: np.ndarray, centers: np.ndarray,
                        dist: np.ndarray) -> None:
    """Keep in a tile's graph ``folder`` the last classification of its refine round: each
    element's superfacet ``label`` ((m,) int32, an index into ``centers``), the ``centers``
    ((K,) int64 elements, listed by row) and each element's ``dist`` to its center ((m,)
    float64); whole or not at all (a kept one is replaced).

    Raises
    ------
    OSError
        If the folder cannot be written.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     keep_classification(tmp, np.zeros(3, np.int32), np.array([1]), np.ones(3))
    ...     label, centers, dist = kept_classification(tmp, 3)
    ...     print(label.tolist(), centers.tolist(), kept_classification(tmp, 4))
    [0, 0, 0] [1] None
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    done = folder / "classification.json"
    done.unlink(missing_ok=True)  # (the one kept before: never read with the new files)
    arrays = dict(zip(CLASSIFICATION_FILES, (label, centers, dist)))
    part = uuid.uuid4().hex  # (another try of the same task may write beside this one)
    for name, a in arrays.items():
        np.save(folder / f"{name}.{part}.npy", a)
        os.replace(folder / f"{name}.{part}.npy", folder / f"{name}.npy")
    meta = {"elements": int(label.shape[0]),
            "digests": {name: array_digest(a) for name, a in arrays.items()}}
    (folder / f"classification.{part}.json").write_text(json.dumps(meta), encoding="utf-8")
    os.replace(folder / f"classification.{part}.json", done)


def kept_classification(folder, n_elements: int, graph=None) -> tuple | None:
    """The classification :func:`keep_classification` kept in ``folder`` for a graph of
    ``n_elements``, as ``(label, centers, dist)``, or None where there is none (or one
    of another graph); first the one ``graph`` carries (``last_classification``: a tile
    held in memory since its refine round). The caller reads it on the graph and weights
    it was made on (the tile's kept graph, weighed alike by its phases).

    Raises
    ------
    SuperfacetsError
        If a kept array changed since it was written.
    """
    last = None if graph is None else graph.__dict__.get("last_classification")
    if last is not None and last[0].shape[0] == n_elements:
        return last
    done = Path(folder) / "classification.json"
    if not done.is_file():
        return None
    meta = json.loads(done.read_text(encoding="utf-8"))
    if meta.get("elements") != int(n_elements):
        return None
    arrays = _read_checked(Path(folder), meta, CLASSIFICATION_FILES)
    return tuple(arrays[name] for name in CLASSIFICATION_FILES)


def tile_face_graph(mesh, folder, *, save: bool = True):
    """Give ``mesh`` (a tile's box of faces) its face graph from the topology saved in
    ``folder`` (:func:`~superfacets.elements.faces.face_graph_from`), or make the
    topology and save it there: the mesh's later phases read it back, not build it again
    (0.5 s a box of 3M faces, three times a tile). The same arrays, so the same labels.

    Parameters
    ----------
    mesh : Mesh
        A tile's box, as every phase reads it (the same faces, in the same order).
    folder : str or os.PathLike
        The tile's folder in the run's work folder (created when saved).
    save : bool, default True
        Save a topology made here (False: it is returned, for the caller to save later,
        if ever, with :func:`save_face_topology`).

    Returns
    -------
    str or FaceAdjacency
        ``'read'``, ``'built'`` (and saved) or ``'kept'`` (already with the mesh); the
        topology made, where not saved.

    Raises
    ------
    SuperfacetsError
        If a saved array changed since it was written.
    OSError
        If the folder cannot be written or read.

    Examples
    --------
    >>> import tempfile
    >>> ball = trimesh.creation.icosphere(subdivisions=2)
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     first = tile_face_graph(Mesh(ball.vertices, ball.faces), Path(tmp) / "t0")
    ...     again = Mesh(ball.vertices, ball.faces)
    ...     print(first, tile_face_graph(again, Path(tmp) / "t0"), face_graph(again).n_edges)
    built read 480
    """

    folder = Path(folder)
    if "_face_graph" in mesh.__dict__:
        return "kept"
    done = folder / "faces.json"
    if done.is_file():
        meta = json.loads(done.read_text(encoding="utf-8"))
        arrays = _read_checked(folder, meta, FACE_FILES)
        face_graph_from(mesh, FaceAdjacency(**arrays, repeated=int(meta["repeated"])))
        return "read"
    topo = face_adjacency(mesh)
    face_graph_from(mesh, topo)
    if not save:
        return topo
    save_face_topology(topo, folder)
    return "built"


def save_face_topology(topo: FaceAdjacency, folder) -> None:
    """Save a tile's face graph topology (:func:`tile_face_graph`'s) in ``folder``, whole
    or not at all.

    Raises
    ------
    OSError
        If the folder cannot be written.
    """
    _save(Path(folder), "faces.json", {n: getattr(topo, n) for n in FACE_FILES},
          {"repeated": int(topo.repeated)})


def _save(folder: Path, described: str, arrays: dict, meta: dict) -> None:
    """Save ``arrays`` (one ``.npy`` file each) and their digests with ``meta`` (in the
    file ``described``) into ``folder``, whole or not at all."""
    part = folder.with_name(folder.name + ".part")
    for old in (part, folder):  # (not whole: never read)
        shutil.rmtree(old, ignore_errors=True)
    part.mkdir(parents=True)
    digests = {}
    for name, a in arrays.items():
        np.save(part / f"{name}.npy", a)
        digests[name] = array_digest(a)  # (of the array in memory: not read back)
    (part / described).write_text(json.dumps({**meta, "digests": digests}), encoding="utf-8")
    try:  # whole or absent: a phase never reads half a graph
        os.replace(part, folder)
    except OSError:  # the same tile saved by another try of the task
        shutil.rmtree(part, ignore_errors=True)
        if not (folder / described).is_file():
            raise


def _read_checked(folder: Path, meta: dict, names=None) -> dict:
    """The graph's arrays, each checked against the digest written with it
    (:func:`~superfacets.io.files.load_checked`): the work folder may be shared with
    other machines, and the compiled kernels trust the arrays they are given (a changed
    index reads out of bounds)."""
    want = meta.get("digests", {}) if isinstance(meta, dict) else {}
    return {name: load_checked(folder / f"{name}.npy", want.get(name))
            for name in (GRAPH_FILES if names is None else names)}
