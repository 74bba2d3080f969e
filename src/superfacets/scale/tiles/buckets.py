"""A large input sorted once into one file per tile, for a tiled run.

:func:`bucket` reads a :class:`~superfacets.io.regions.RegionReader`'s file
once, in chunks, and writes each element to the file of the tile that holds
it (:meth:`superfacets.scale.tiles.layout.Tiles.of`); the :class:`TileBuckets` it returns
reads a box as the reader does, from the files of the tiles the box
overlaps. So a tiled run (:mod:`superfacets.scale.tiles.run`) reads the input
file twice in all (its survey, this sorting), not once per task.
"""

from __future__ import annotations

import shutil
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..._runtime.arrays import ranked
from ..._runtime.progress import new_bar
from ...elements.kinds import KINDS
from ...inputs.bounds import column_bounds, rows_in_box
from ...inputs.mesh import Mesh
from ...io.files import array_digest, load_checked
from ...io.regions import face_centroids, point_cloud_of

__all__ = ["bucket", "TileBuckets", "box_folder", "keep_box", "mesh_records", "positions"]


def bucket(reader, tiles, folder, *, progress: bool = False) -> TileBuckets:
    """Sort the elements into one file per tile, in one pass.

    Each tile's file (``tile-T.bin`` in ``folder``) holds the elements whose
    position lies in that tile (:meth:`superfacets.scale.tiles.layout.Tiles.of`) in
    file order, with what a box of them needs: the row, the position, colour and
    normal of a point, the vertex indices and corner positions of a face (its
    position, the corners' mean, is computed again: :func:`positions`). A box is
    then read from the tiles it overlaps (:meth:`TileBuckets.read_box`), the same
    elements, in the same order,
    as :meth:`RegionReader.read_box <superfacets.io.regions.RegionReader.read_box>` gives.

    Parameters
    ----------
    reader : RegionReader
        The input, read in chunks.
    tiles : Tiles
        The tiles (:mod:`superfacets.scale.tiles.layout`).
    folder : str or os.PathLike
        Where the files go (every worker must reach it by that path);
        files of an earlier bucketing there are replaced.
    progress : bool, default False
        A progress bar over the rows.

    Returns
    -------
    TileBuckets

    Raises
    ------
    MeshFormatError
        As :meth:`survey`.
    OSError
        If ``folder`` cannot be written.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    n_tiles = tiles.n_tiles
    for old in folder.glob("tile-*.bin"):
        old.unlink()
    lo = np.full((n_tiles, 3), np.inf)
    hi = np.full((n_tiles, 3), -np.inf)
    counts = np.zeros(n_tiles, dtype=np.int64)
    crcs = [0] * n_tiles  # (each file's digest, summed as it is written)
    dtype = None
    bar = None
    if progress:
        bar = new_bar(total=reader.n_rows, desc="tiles: bucket", unit="row", leave=False)
    try:
        for s, pos, _, extra in reader.chunks():
            if not KINDS[reader.kind].cloud:  # faces, with their vertices
                tri, verts, col = extra
                fields = dict(tri=tri, corners=verts[tri])
                if col is not None:
                    fields["colors"] = col
            else:
                fields = {n: a for n, a in zip(("colors", "normals"), extra) if a is not None}
            if dtype is None:  # (a face's position is its corners' mean: not stored)
                dtype = np.dtype([("row", "<i8")] + ([("pos", "<f8", (3,))] if "corners"
                                                      not in fields else []) + [
                    (n, "<i8" if n == "tri" else "<f8", a.shape[1:])
                    for n, a in fields.items()])
            rec = np.empty(pos.shape[0], dtype=dtype)
            rec["row"] = np.arange(s, s + pos.shape[0])
            if "pos" in dtype.names:
                rec["pos"] = pos
            for n, a in fields.items():
                rec[n] = a
            tile = tiles.of(pos)
            # (a stable sort of 16-bit keys is numpy's radix sort: one pass, not a merge sort)
            order = np.argsort(tile.astype(np.int16) if n_tiles < 2**15 else tile,
                               kind="stable")
            bounds = np.searchsorted(tile[order], np.arange(-1, n_tiles + 1))
            for t in np.flatnonzero(np.diff(bounds[1:])):
                these = order[bounds[t + 1]:bounds[t + 2]]
                block = rec[these]
                try:
                    with open(folder / f"tile-{t}.bin", "ab") as f:
                        block.tofile(f)
                except OSError as exc:  # a full disk: numpy's "50000 requested and ..."
                    raise OSError(exc.errno or 28, f"{folder}: the tiles' files of the input "
                                  f"could not be written ({exc}): the work folder needs about "
                                  "the input's size free; give --workdir a folder with room"
                                  ) from None
                counts[t] += block.size
                crcs[t] = zlib.crc32(block.view(np.uint8), crcs[t])
                low, high = column_bounds(pos[these])
                lo[t] = np.minimum(lo[t], low)
                hi[t] = np.maximum(hi[t], high)
            if bar is not None:
                bar.update(pos.shape[0])
    finally:
        if bar is not None:
            bar.close()
    if dtype is None:  # no rows: nothing is ever read
        dtype = np.dtype([("row", "<i8"), ("pos", "<f8", (3,))])
    digests = tuple(f"{crc:08x}" if c else "" for crc, c in zip(crcs, counts))
    return TileBuckets(str(folder), reader.kind, reader.n_rows, dtype, lo, hi, counts,
                       reader.viewpoint, reader.path, digests)


def positions(rec: np.ndarray) -> np.ndarray:
    """The positions of a tile's records ((n, 3) float64): points keep theirs, faces are
    given their corners' mean again (:func:`~superfacets.io.regions.face_centroids`, the
    same bits as the reader's: 24 of a face record's 128 bytes not written)."""
    return rec["pos"] if "pos" in rec.dtype.names else face_centroids(rec["corners"])


@dataclass(frozen=True)
class TileBuckets:
    """A large input sorted into one file per tile (:func:`bucket`).

    Small and picklable like :class:`~superfacets.io.regions.RegionReader`, and read the same way
    (:meth:`read_box`), but a box costs the tiles it overlaps instead of a
    pass over the whole file.

    Attributes
    ----------
    folder : str
        Where the tiles' files are.
    kind : {'faces', 'points'}
    n_rows : int
        Faces or points in the file.
    dtype : numpy.dtype
        The record of one element.
    lo, hi : (T, 3) float64 ndarray
        Bounds of each tile's element positions (inf, -inf where empty).
    counts : (T,) int64 ndarray
        Elements in each tile.
    viewpoint : tuple or None
        Sensor position of a scan, as :class:`~superfacets.io.regions.RegionReader`.
    source : str
        The file they came from (for messages).
    digests : tuple of str
        Each tile file's digest (:func:`~superfacets.io.files.array_digest` of its bytes),
        checked before it is read (the work folder may be
        shared with other machines, and a changed file gave other elements' rows).
    """

    folder: str
    kind: str
    n_rows: int
    dtype: np.dtype
    lo: np.ndarray
    hi: np.ndarray
    counts: np.ndarray
    viewpoint: tuple | None = None
    source: str = ""
    digests: tuple = ()

    def read_box(self, lo, hi, name: str = "", keep=None, owe: bool = False):
        """The elements whose position lies in ``[lo, hi]``: the same rows, positions
        and input as :meth:`RegionReader.read_box
        <superfacets.io.regions.RegionReader.read_box>` gives.

        ``keep`` (a path without suffix, optional): the box's records are saved there
        (``keep.npy``, with ``keep.json``: the box and the array's digest) and read from
        there when the same box is asked for again (a tile's later phases), instead of
        from the tiles it overlaps. With ``owe``, a box not kept yet is not saved: a fourth
        item, the write (:func:`keep_box` and its arguments, the records among them), is
        returned for the caller to make when it lets the box go (None where kept)."""
        lo = np.asarray(lo, dtype=np.float64)
        hi = np.asarray(hi, dtype=np.float64)
        rec = None if keep is None else _kept_box(keep, lo, hi, self.dtype)
        owed = None
        if rec is None:
            rec = self._records(lo, hi)
            if keep is not None and owe:
                owed = (keep_box, keep, rec, lo, hi)
            elif keep is not None:
                keep_box(keep, rec, lo, hi)
        box = self._of_records(rec, name)
        return (*box, owed) if owe else box

    def kept(self, keep, lo, hi) -> bool:
        """Whether :meth:`read_box` finds the records of box ``[lo, hi]`` kept at
        ``keep`` (described there; their digest is checked when read)."""
        return _kept_meta(keep, np.asarray(lo, dtype=np.float64),
                          np.asarray(hi, dtype=np.float64)) is not None

    def _records(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """The records of the elements in ``[lo, hi]``, in the order of their rows: the
        rows alone are sorted, and each record is copied into its place once (not joined
        and then sorted: a copy fewer of a mesh box's 104-byte records, 1.77 -> 0.81 s a
        box of 3M faces from 4 tiles' files)."""
        parts = []
        near = (self.counts > 0) & (self.lo <= hi).all(axis=1) & (self.hi >= lo).all(axis=1)
        inside = ((self.lo >= lo) & (self.hi <= hi)).all(axis=1)
        for t in np.flatnonzero(near):
            rec = self._tile(int(t))
            # (a tile wholly in the box is taken as read; another's elements in the box are
            # a copy, not of the file's bytes, which are let go here)
            parts.append(rec if inside[t] else rec[rows_in_box(positions(rec), lo, hi)])
            del rec
        if len(parts) < 2:  # (one file: in the order of its rows already; a copy of a
            # mapped file, as a box's records are the box's own)
            return np.array(parts[0]) if parts else np.empty(0, dtype=self.dtype)
        # each file is in the order of its rows: a stable sort of them all keeps each
        # file's order, so a file's records fill its places in the box in turn
        order = np.argsort(np.concatenate([rec["row"] for rec in parts]), kind="stable")
        part = np.repeat(np.arange(len(parts), dtype=np.int32), [rec.size for rec in parts])
        part = part[order]
        del order
        out = np.empty(part.size, dtype=self.dtype)
        for i in range(len(parts)):
            out[np.flatnonzero(part == i)] = parts[i]
            parts[i] = None  # (let go as soon as placed)
        return out

    def _of_records(self, rec: np.ndarray, name: str):
        """The rows, positions and input of a box's records."""

        rows = np.ascontiguousarray(rec["row"])
        where = np.ascontiguousarray(positions(rec))
        if rows.size == 0:
            return rows, where, None
        if not KINDS[self.kind].cloud:  # faces, with their vertices
            tri = rec["tri"]
            # the box's vertices numbered by a table of the file's, not np.unique's sort
            # of 3 entries a face (0.6 s a box of 3M faces); a vertex's corners are alike
            _, local = ranked(tri.ravel(), int(tri.max()) + 1)
            first = np.empty(int(local.max()) + 1, dtype=np.int64)
            first[local] = np.arange(local.size)
            verts = rec["corners"][first // 3, first % 3]  # (the (n, 3, 3) field, no copy)
            return rows, where, Mesh(np.ascontiguousarray(verts), local.reshape(tri.shape),
                                     name=name, face_colors=np.ascontiguousarray(rec["colors"])
                                     if "colors" in self.dtype.names else None)
        names = self.dtype.names
        col, nrm = (np.ascontiguousarray(rec[n]) if n in names else None
                    for n in ("colors", "normals"))
        # (the cloud reads the positions the caller is given: one array, not a copy for the
        # cloud to lend to its graph, which the caller's array keeps from being freed)
        return rows, where, point_cloud_of(where, col, nrm, self.viewpoint, name)

    def _tile(self, t: int) -> np.ndarray:
        """Tile ``t``'s records, its file checked against the digest written with it (of
        its bytes: the same bytes, so the same count)."""
        path = Path(self.folder) / f"tile-{t}.bin"
        # (mapped: a box keeps a sliver of most tiles it overlaps, and copies only that)
        return load_checked(path, self.digests[t] if self.digests else None, self.dtype,
                            mapped=True)


#: Disk a mesh tile's face graph topology takes, per face of its box (its pairs, edges,
#: CSR adjacency and dual edges: :func:`~superfacets.scale.tiles.graphs.tile_face_graph`).
FACE_BYTES = 64


def box_folder(work, reader, n_elements: int) -> Path | None:
    """The folder where a tiled run's tiles keep their boxes' records for their later
    phases (:meth:`~superfacets.scale.tiles.buckets.TileBuckets.read_box`'s ``keep``; a
    mesh's tiles, their face graphs' topology too), in
    its work folder ``work``; None where the input was not sorted into tiles, or the disk
    has less than twice the room for boxes of twice the elements (the halos)."""
    dtype = getattr(reader, "dtype", None)
    if dtype is None:
        return None
    try:
        free = shutil.disk_usage(work).free
    except OSError:
        return None
    # (a mesh's tiles keep their face graphs' topology beside: about 60 bytes a face)
    each = dtype.itemsize + (0 if KINDS[reader.kind].cloud else FACE_BYTES)
    return Path(work) / "boxes" if free > 4 * each * n_elements else None


def mesh_records(dtype: np.dtype, rows: np.ndarray, pos: np.ndarray, mesh: Mesh
                 ) -> np.ndarray:
    """The records (``dtype``: :func:`bucket`'s, of faces) of a mesh box that
    :meth:`TileBuckets.read_box` gave as ``rows``, ``pos`` and ``mesh``: read back, the
    same rows, positions and mesh (its vertices numbered as the box numbers them, which
    the reading keeps; ``pos``, the corners' mean, is not stored: :func:`positions`)."""
    rec = np.empty(rows.shape[0], dtype=dtype)
    rec["row"] = rows
    rec["tri"] = mesh.faces
    rec["corners"] = mesh.vertices[mesh.faces]
    if "colors" in dtype.names:
        rec["colors"] = mesh.face_colors
    return rec


def keep_box(keep, rec: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> None:
    """Save a box's records at ``keep`` (whole or not at all: the files are renamed into
    place, the description last); a full disk leaves nothing there."""
    import json
    import os

    keep = Path(keep)
    part = keep.with_name(f"{keep.name}.{os.getpid()}.part")
    try:
        np.save(f"{part}.npy", rec, allow_pickle=False)
        meta = {"lo": lo.tolist(), "hi": hi.tolist(), "digest": array_digest(rec)}
        Path(f"{part}.json").write_text(json.dumps(meta), encoding="utf-8")
        os.replace(f"{part}.npy", f"{keep}.npy")
        os.replace(f"{part}.json", f"{keep}.json")
    except OSError:  # (a full disk: the later phases read the tiles again)
        for suffix in (".npy", ".json"):
            Path(f"{part}{suffix}").unlink(missing_ok=True)


def _kept_box(keep, lo: np.ndarray, hi: np.ndarray, dtype: np.dtype):
    """The records :func:`keep_box` saved for this very box, else None; a file changed
    since is refused, as the tiles' files are."""
    meta = _kept_meta(keep, lo, hi)
    if meta is None:
        return None
    try:
        rec = load_checked(f"{keep}.npy", meta.get("digest"))
    except FileNotFoundError:
        return None
    return rec if rec.dtype == dtype else None


def _kept_meta(keep, lo: np.ndarray, hi: np.ndarray) -> dict | None:
    """The description :func:`keep_box` wrote at ``keep`` for this very box, else None."""
    import json

    try:
        meta = json.loads(Path(f"{keep}.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(meta, dict) or meta.get("lo") != lo.tolist() \
            or meta.get("hi") != hi.tolist():
        return None
    return meta
