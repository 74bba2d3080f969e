"""The project's malformed-input corpus: every reader, every command, every option.

Each :class:`Case` is a set of input files (made here, in memory), a command
line, and what must happen: ``"error"`` (exit status 2, one line
``superfacets: error: ...`` on stderr, no traceback, no file written) or
``"ok"`` (exit status 0 and the named outputs written). ``tests/test_malformed.py``
runs every case in a folder of its own.
"""

from __future__ import annotations

import bz2
import gzip
import lzma
import struct
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Case:
    name: str
    files: dict  # file name -> bytes
    argv: list  # command line; "{d}" is replaced by the case's folder
    expect: str = "error"  # "error", "usage" (argparse: exit 2 with usage) or "ok"
    match: str = ""  # a piece of the error line
    outputs: list = field(default_factory=list)  # files an "ok" case must write


def _npy(arr) -> bytes:
    import io

    buf = io.BytesIO()
    np.save(buf, arr)
    return buf.getvalue()


def _tetra_off(extra: str = "") -> bytes:
    return (b"OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
            b"3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n" + extra.encode())


def _grid(n: int = 10):  # 200 faces: the default k = 150 fits
    xs = np.linspace(0, 1, n + 1)
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    v = np.stack([X.ravel(), Y.ravel(), 0.3 * np.abs(X.ravel() - 0.5)], 1)
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    f = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return v, f


def grid_off() -> bytes:
    v, f = _grid()
    lines = [f"OFF\n{len(v)} {len(f)} 0"] + [f"{x:.6f} {y:.6f} {z:.6f}" for x, y, z in v]
    lines += [f"3 {a} {b} {c}" for a, b, c in f]
    return ("\n".join(lines) + "\n").encode()


def grid_obj(sep: str = " ") -> bytes:
    v, f = _grid()
    lines = [f"v{sep}{x:.6f}{sep}{y:.6f}{sep}{z:.6f}" for x, y, z in v]
    lines += [f"f{sep}{a + 1}{sep}{b + 1}{sep}{c + 1}" for a, b, c in f]
    return ("\n".join(lines) + "\n").encode()


def grid_tri() -> bytes:
    v, f = _grid()
    lines = [str(len(v))] + [f"{x:.6f} {y:.6f} {z:.6f}" for x, y, z in v]
    lines += [str(len(f))] + [f"{a} {b} {c}" for a, b, c in f]
    return ("\n".join(lines) + "\n").encode()


def grid_ply_binary() -> bytes:
    v, f = _grid()
    head = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\n"
            "property float x\nproperty float y\nproperty float z\n"
            f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n")
    body = v.astype("<f4").tobytes()
    body += b"".join(struct.pack("<Biii", 3, *map(int, t)) for t in f)
    return head.encode() + body


def grid_stl_ascii() -> bytes:
    v, f = _grid()
    out = ["solid g"]
    for t in f:
        out.append(" facet normal 0 0 1\n  outer loop")
        out += [f"   vertex {v[i, 0]:.6f} {v[i, 1]:.6f} {v[i, 2]:.6f}" for i in t]
        out.append("  endloop\n endfacet")
    out.append("endsolid g")
    return ("\n".join(out) + "\n").encode()


def grid_seg(value=None, n=None) -> bytes:
    _, f = _grid()
    m = len(f) if n is None else n
    lab = (np.arange(m) * 7 // m) if value is None else [value] * m
    return ("\n".join(str(x) for x in lab) + "\n").encode()


def _tetra_ply_labels() -> bytes:
    from superfacets.io.ply import ply_bytes

    v = np.eye(4, 3)
    return ply_bytes(v, np.array([0, 2, 1, 0, 1, 3]), np.array([0, 3, 6]), labels=np.array([0, 1]))


RESULTS = (b"mesh,mesh_id,category,n_faces,method,n_segments,alpha,seed,status,segments,"
           b"undersegmentation_error,compactness,boundary_recall,achievable_accuracy\n")


def cases() -> list[Case]:
    g = {"g.off": grid_off()}
    out: list[Case] = []

    def mesh_case(name, fname, data, match="", expect="error", extra=()):
        out.append(Case(name, {fname: data}, ["segment", "{d}/" + fname, "-k", "4",
                                               "-o", "{d}/o.seg", *extra], expect, match,
                        ["o.seg"] if expect == "ok" else []))

    # --- OFF
    mesh_case("off-empty", "m.off", b"", "empty file")
    mesh_case("off-magic-only", "m.off", b"OFF\n", "counts")
    mesh_case("off-bad-magic", "m.off", b"OFX\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "not an OFF")
    mesh_case("off-counts-text", "m.off", b"OFF\na b c\n", "count")
    mesh_case("off-counts-negative", "m.off", b"OFF\n3 -1 0\n", "negative")
    mesh_case("off-truncated-vertices", "m.off", b"OFF\n4 1 0\n0 0 0\n1 0 0\n", "truncated")
    mesh_case("off-truncated-faces", "m.off", b"OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
              "truncated")
    mesh_case("off-two-coordinates", "m.off", b"OFF\n3 1 0\n0 0\n1 0\n0 1\n3 0 1 2\n",
              "coordinates")
    mesh_case("off-text-coordinate", "m.off", b"OFF\n3 1 0\n0 0 x\n1 0 0\n0 1 0\n3 0 1 2\n",
              "malformed")
    mesh_case("off-nan", "m.off", _tetra_off().replace(b"1 0 0\n", b"nan 0 0\n", 1), "NaN")
    mesh_case("off-inf", "m.off", _tetra_off().replace(b"1 0 0\n", b"inf 0 0\n", 1),
              "NaN or infinite")
    mesh_case("off-index-out-of-range", "m.off", _tetra_off().replace(b"3 1 2 3", b"3 1 2 9"),
              "out of range")
    mesh_case("off-index-negative", "m.off", _tetra_off().replace(b"3 1 2 3", b"3 1 2 -1"),
              "out of range")
    mesh_case("off-index-huge", "m.off",
              _tetra_off().replace(b"3 1 2 3", b"3 1 2 99999999999999999999999"), "")
    mesh_case("off-index-float", "m.off", _tetra_off().replace(b"3 1 2 3", b"3 1 2 2.5"), "")
    mesh_case("off-face-two-vertices", "m.off", _tetra_off().replace(b"3 1 2 3", b"2 1 2"), "")
    mesh_case("off-face-count-mismatch", "m.off", _tetra_off().replace(b"3 1 2 3", b"3 1 2"), "")
    # (vertices and no face: a point cloud, of 3 points here, fewer than -k 4)
    mesh_case("off-no-faces", "m.off", b"OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n",
              "larger than the number of points (3)")
    mesh_case("off-no-vertices", "m.off", b"OFF\n0 0 0\n", "no faces")
    mesh_case("off-binary-junk", "m.off", bytes(range(256)) * 4, "")
    mesh_case("off-zero-extent", "m.off", b"OFF\n3 1 0\n1 1 1\n1 1 1\n1 1 1\n3 0 1 2\n",
              "zero extent")
    mesh_case("off-zero-area", "m.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n",
              "zero total area")
    mesh_case("off-huge-coordinates", "m.off",
              _tetra_off().replace(b"1 0 0\n", b"1e300 0 0\n", 1).replace(b"0 1 0\n",
                                                                          b"0 -1e300 0\n", 1),
              "rescale")
    mesh_case("off-tiny-coordinates", "m.off",
              b"OFF\n4 4 0\n0 0 0\n1e-200 0 0\n0 1e-200 0\n0 0 1e-200\n"
              b"3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
              "rescale")
    mesh_case("off-k-too-large", "m.off", _tetra_off(), "larger than the number of faces",
              extra=("-k", "9"))
    mesh_case("off-crlf-ok", "m.off", grid_off().replace(b"\n", b"\r\n"), expect="ok")
    mesh_case("off-comments-ok", "m.off", b"# a comment\n" + grid_off(), expect="ok")
    mesh_case("off-bom", "m.off", b"\xef\xbb\xbf" + grid_off(), expect="ok")
    mesh_case("off-utf16", "m.off", grid_off().decode().encode("utf-16"), expect="ok")
    # --- .tri
    mesh_case("tri-empty", "m.tri", b"", "empty")
    mesh_case("tri-truncated", "m.tri", b"4\n0 0 0\n1 0 0\n", "truncated")
    mesh_case("tri-no-face-count", "m.tri", b"3\n0 0 0\n1 0 0\n0 1 0\n", "face count")
    mesh_case("tri-bad-count", "m.tri", b"x\n", "count")
    mesh_case("tri-four-indices", "m.tri", b"4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1\n0 1 2 3\n", "")
    mesh_case("tri-out-of-range", "m.tri", b"3\n0 0 0\n1 0 0\n0 1 0\n1\n0 1 5\n", "out of range")
    mesh_case("tri-nan", "m.tri", b"3\n0 0 nan\n1 0 0\n0 1 0\n1\n0 1 2\n", "NaN")
    mesh_case("tri-ok", "m.tri", grid_tri(), expect="ok")
    # --- PLY
    ply = grid_ply_binary()
    mesh_case("ply-empty", "m.ply", b"", "empty file")
    mesh_case("ply-header-only", "m.ply", ply[:ply.index(b"end_header") + 11], "")
    mesh_case("ply-truncated-body", "m.ply", ply[:len(ply) // 2], "")
    mesh_case("ply-billions-declared", "m.ply",  # refused from the header, nothing read
              ply.replace(b"element face ", b"element face 4000000000 ", 1)
              if b"element face " in ply else ply, "")
    mesh_case("ply-ascii-faces-missing", "m.ply",  # the header declares a face, none follows
              b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
              b"property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
              b"end_header\n0 0 0\n1 0 0\n", "declares 3 vertex, 1 face")
    mesh_case("ply-garbage", "m.ply", b"ply\nformat nonsense 1.0\nend_header\n", "")
    mesh_case("ply-huge-count", "m.ply",
              ply.replace(b"element vertex 121", b"element vertex 999999999999"), "")
    mesh_case("ply-points-only", "m.ply",
              b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
              b"property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n",
              "larger than the number of points")  # a PLY of points is a cloud
    # --- point clouds
    mesh_case("xyz-nan-row", "c.xyz", b"0 0 0\n1 0 0\n0 1 0\nnan 1 1\n0 0 1\n",
              "point 3 has a non-finite")
    mesh_case("xyz-ragged", "c.xyz", b"0 0 0\n1 0\n", "columns")
    mesh_case("xyz-words", "c.xyz", b"a b c\n0 0 0\n", "not numbers")  # (x y z: a header)
    mesh_case("xyz-unknown-columns", "c.txt", b"# a b c\n0 0 0\n1 0 0\n0 1 0\n",
              "unknown columns")
    mesh_case("xyz-empty", "c.xyz", b"", "empty file")
    mesh_case("xyz-collinear", "c.xyz", b"0 0 0\n1 1 1\n2 2 2\n3 3 3\n4 4 4\n",
              "one line", extra=("-k", "1"))
    mesh_case("xyz-identical", "c.xyz", b"1 1 1\n1 1 1\n1 1 1\n", "coincide",
              extra=("-k", "1"))
    mesh_case("pts-short", "c.pts", b"9\n0 0 0\n1 0 0\n", "declares 9 points")
    mesh_case("npy-garbage", "c.npy", b"\x93NUMPY garbage", "cannot read NPY")
    mesh_case("npy-bad-shape", "c.npy", _npy(np.zeros((4, 4))), "expected (N, 3)")
    mesh_case("pcd-garbage", "c.pcd", b"# .PCD v0.7\nVERSION 0.7\nFIELDS x y\n",
              "PCD")
    _pcd = (b"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            b"WIDTH 5\nHEIGHT 1\nPOINTS 5\n")
    mesh_case("pcd-no-data-line", "c.pcd", b"# .PCD v0.7\nFIELDS x y z\n",
              "no SIZE, TYPE, COUNT, WIDTH, POINTS, DATA lines")
    mesh_case("pcd-ascii-short-row", "c.pcd", _pcd + b"DATA ascii\n0 0 0\n1 0\n0 1 0\n1 1 0\n"
              b"0 0 1\n", "line 2 of its ASCII data has 2 values, 3 expected")
    mesh_case("pcd-compressed-cut", "c.pcd", _pcd + b"DATA binary_compressed\n"
              + struct.pack("<II", 16, 60) + b"garbage", "7 bytes of it follow (truncated?)")
    mesh_case("ply-ascii-two-corners", "m.ply",  # (not "truncated?": the file is whole)
              b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
              b"property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
              b"end_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n2 1 3\n", "face 1 has 2 vertices")
    mesh_case("pcd-unknown-type", "c.pcd",  # (pydantic said "1 validation error for ...")
              _pcd.replace(b"TYPE F F F", b"TYPE Q F F") + b"DATA ascii\n" + b"0 0 1\n" * 5,
              "its TYPE line's value 1 is 'Q'")
    mesh_case("ply-negative-count", "m.ply",  # (numpy said "negative dimensions ...")
              b"ply\nformat ascii 1.0\nelement vertex -3\nproperty float x\nproperty float y"
              b"\nproperty float z\nend_header\n", "declares -3 vertex elements")
    mesh_case("las-garbage", "c.las", b"LASF" + b"\0" * 50, "LAS")
    mesh_case("xyz-ok", "c.xyz", b"".join(f"{x} {y} {x * y}\n".encode()
                                          for x in range(6) for y in range(6)), expect="ok")
    mesh_case("ply-ascii-quads", "m.ply",
              b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
              b"property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
              b"end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n", "")
    mesh_case("ply-ok", "m.ply", ply, expect="ok")
    # --- colours of a mesh (COFF, PLY, OBJ)
    mesh_case("coff-no-colour", "m.off", b"COFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
              "need 6 numbers")
    mesh_case("coff-text-colour", "m.off",
              b"COFF\n3 1 0\n0 0 0 9 0 x 1\n1 0 0 0 9 0 1\n0 1 0 0 0 9 1\n3 0 1 2\n",
              "malformed")
    mesh_case("ply-nan-colour", "m.ply", b"ply\nformat ascii 1.0\nelement vertex 3\n"
              b"property float x\nproperty float y\nproperty float z\nproperty float red\n"
              b"property float green\nproperty float blue\nelement face 1\n"
              b"property list uchar int vertex_indices\nend_header\n0 0 0 0.5 0 0\n"
              b"1 0 0 nan 0 0\n0 1 0 0 0 1\n3 0 1 2\n", "colour 1 is not finite")
    mesh_case("obj-text-colour", "m.obj", b"v 0 0 0 1 0 0\nv 1 0 0 red 1 0\nv 0 1 0 0 0 1\n"
              b"f 1 2 3\n", "malformed vertex colour 1")
    mesh_case("beta-without-colours", "m.off", _tetra_off(), "vertex or face colours",
              extra=("--beta", "5"))
    # --- OBJ
    mesh_case("obj-empty", "m.obj", b"", "empty file")
    mesh_case("obj-index-zero", "m.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "0")
    mesh_case("obj-index-out-of-range", "m.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "range")
    mesh_case("obj-negative-too-far", "m.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", "range")
    mesh_case("obj-nan", "m.obj", b"v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "NaN")
    mesh_case("obj-text-coordinate", "m.obj", b"v 0 0 a\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "")
    mesh_case("obj-text-index", "m.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "")
    mesh_case("obj-face-two-vertices", "m.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "")
    mesh_case("obj-two-coordinates", "m.obj", b"v 0 0\nv 1 0\nv 0 1\nf 1 2 3\n", "")
    mesh_case("obj-binary-junk", "m.obj", bytes(range(256)) * 4, "")
    mesh_case("obj-tabs-ok", "m.obj", grid_obj("\t"), expect="ok")
    mesh_case("obj-slashes-ok", "m.obj",
              grid_obj().replace(b"f ", b"f ").replace(b"\nf", b"\nf"), expect="ok")
    mesh_case("obj-ok", "m.obj", grid_obj(), expect="ok")
    mesh_case("obj-relative-ok", "m.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\n"
              b"f -4 -3 -1\nf -4 -1 -2\nf -3 -1 -2\n", expect="ok", extra=("-k", "2"))
    mesh_case("obj-quad-ok", "m.obj", b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
              expect="ok", extra=("-k", "1"))
    # --- STL
    mesh_case("stl-empty", "m.stl", b"", "empty file")
    mesh_case("stl-ascii-no-facet", "m.stl", b"solid x\nendsolid x\n", "an ASCII STL of no facet")
    mesh_case("stl-truncated-binary", "m.stl", b"\0" * 80 + struct.pack("<I", 10) + b"\0" * 60, "")
    mesh_case("stl-ascii-malformed", "m.stl", b"solid x\n facet normal 0 0 1\n  outer loop\n"
              b"   vertex 0 0\n  endloop\n endfacet\nendsolid x\n", "")
    mesh_case("stl-ascii-ok", "m.stl", grid_stl_ascii(), expect="ok")
    # --- polygons and scenes
    quads = (b"OFF\n6 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n2 1 0.5\n"
             b"4 0 1 2 3\n4 1 4 5 2\n")
    mesh_case("off-quads-ok", "m.off", quads, expect="ok", extra=("-k", "2"))
    mesh_case("off-repeated-vertex-ok", "m.off", quads.replace(b"4 0 1 2 3", b"4 0 1 1 2"),
              expect="ok", extra=("-k", "1"))
    mesh_case("off-face-one-vertex", "m.off", quads.replace(b"4 0 1 2 3", b"1 0"), "3 or more")
    mesh_case("off-polygon-out-of-range", "m.off", quads.replace(b"4 1 4 5 2", b"4 1 4 5 9"),
              "out of range")
    mesh_case("ply-mixed-polygons-ok", "m.ply",
              b"ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
              b"property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
              b"end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n4 0 1 2 3\n3 1 4 2\n",
              expect="ok", extra=("-k", "2"))
    mesh_case("glb-garbage", "m.glb", b"glTF" + bytes(range(200)), "")
    mesh_case("gltf-not-json", "m.gltf", b"{ this is not json", "")
    out.append(Case("segment-vertex-colors-not-ply", g, ["segment", "{d}/g.off", "-k", "4",
                                                         "--vertex-colors", "--colored-mesh",
                                                         "{d}/c.glb"], match="--vertex-colors"))
    out.append(Case("segment-per-object-radius", g, ["segment", "{d}/g.off", "--per-object",
                                                     "--radius", "0.1"], match="--per-object"))
    out.append(Case("segment-glb-output-ok", g, ["segment", "{d}/g.off", "-k", "4",
                                                 "--colored-mesh", "{d}/c.glb"], "ok",
                    outputs=["c.glb"]))
    out.append(Case("segment-obj-output-ok", g, ["segment", "{d}/g.off", "-k", "4",
                                                 "--colored-mesh", "{d}/c.obj"], "ok",
                    outputs=["c.obj", "c.mtl"]))
    out.append(Case("evaluate-labels-from-ply-short", {**g, "gt.seg": grid_seg(),
                                                       "l.ply": _tetra_ply_labels()},
                    ["evaluate", "{d}/g.off", "{d}/l.ply", "{d}/gt.seg"], match="labels"))
    # --- compression and files
    good = grid_off()
    mesh_case("gz-corrupt", "m.off.gz", gzip.compress(good)[:20] + b"\0" * 30, "decompress")
    mesh_case("gz-truncated", "m.off.gz", gzip.compress(good)[:-40], "decompress")
    mesh_case("gz-not-gzip", "m.off.gz", good, "decompress")
    mesh_case("xz-corrupt", "m.off.xz", lzma.compress(good)[:30] + b"\x01" * 30, "decompress")
    mesh_case("bz2-corrupt", "m.off.bz2", bz2.compress(good)[:30] + b"\x01" * 30, "decompress")
    mesh_case("gz-ok", "m.off.gz", gzip.compress(good), expect="ok")
    mesh_case("xz-garbage-inside", "m.off.xz", lzma.compress(b"\x00\xff" * 100), "")
    mesh_case("unknown-suffix", "m.abc", good, "unknown format .abc; meshes: .off")
    mesh_case("no-suffix", "m", good, "unknown format (no suffix)")
    out.append(Case("experiment-workers-huge", {"psb/off/1.off": grid_off(),
                                                "psb/seg/Benchmark/1/1_0.seg": grid_seg()},
                    ["experiment", "-o", "{d}/r.csv", "-q", "--psb", "{d}/psb", "-j", "100000"],
                    match="workers"))
    out.append(Case("segment-output-is-input", g, ["segment", "{d}/g.off", "-o", "{d}/g.off"],
                    match="overwrite"))
    out.append(Case("html-overwrites-labels", {**g, "l.html": grid_seg()},
                    ["html", "{d}/g.off", "{d}/l.html", "-o", "{d}/l.html"], match="overwrite"))
    out.append(Case("missing-mesh", {}, ["segment", "{d}/none.off", "-o", "{d}/o.seg"],
                    match="no such file"))
    out.append(Case("mesh-is-folder", {"dir.off/x": b""}, ["segment", "{d}/dir.off"],
                    match="directory"))
    # --- segment options
    for name, opts, match in [
            ("k-zero", ["-k", "0"], "n_segments"), ("k-negative", ["-k", "-5"], "n_segments"),
            ("alpha-negative", ["--alpha", "-1"], "alpha"), ("alpha-nan", ["--alpha", "nan"],
                                                             "alpha"),
            ("alpha-inf", ["--alpha", "inf"], "alpha"),
            ("eta-negative", ["--eta-convex", "-1"], "eta_convex"),
            ("window-zero", ["--window", "0"], "window"), ("max-iter-zero", ["--max-iter", "0"],
                                                           "max_iter"),
            ("threads-zero", ["--threads", "0"], "n_threads"),
            ("threads-huge", ["--threads", "100000"], "n_threads"),
            ("shlafman-alpha", ["--weighting", "shlafman", "--alpha", "5"], "[0, 1]"),
            ("alpha-huge", ["--alpha", "1e308"], "alpha"),
            ("eta-huge", ["--eta-convex", "1e300"], "eta_convex"),
            ("window-huge", ["--window", "1e308"], "window"),
            ("colored-is-input", ["--colored-mesh", "{d}/g.off"], ".ply")]:
        out.append(Case(f"segment-{name}", g, ["segment", "{d}/g.off", *opts, "-o", "{d}/o.seg"],
                        match=match))
    out.append(Case("segment-radius-zero", g, ["segment", "{d}/g.off", "--radius", "0"],
                    match="radius"))
    for name, opts in [("k-text", ["-k", "abc"]), ("radius-and-k", ["-k", "3", "--radius", "0.1"]),
                       ("init-bogus", ["--init", "bogus"]), ("weighting-bogus", ["--weighting",
                                                                                 "x"]),
                       ("unknown-option", ["--bogus"]), ("alpha-text", ["--alpha", "x"])]:
        out.append(Case(f"segment-{name}", g, ["segment", "{d}/g.off", *opts], "usage"))
    out.append(Case("segment-output-folder-missing", g,
                    ["segment", "{d}/g.off", "-k", "4", "-o", "{d}/no/o.seg"],
                    match="does not exist"))
    out.append(Case("segment-output-is-folder", {**g, "od/x": b""},
                    ["segment", "{d}/g.off", "-k", "4", "-o", "{d}/od"], match="directory"))
    out.append(Case("segment-colored-wrong-suffix", g,
                    ["segment", "{d}/g.off", "-k", "4", "--colored-mesh", "{d}/c.stl"],
                    match=".ply"))
    out.append(Case("segment-colored-to-stdout", g,
                    ["segment", "{d}/g.off", "-k", "4", "--colored-mesh", "-"],
                    match="standard output"))
    out.append(Case("segment-both-outputs-ok", g,
                    ["segment", "{d}/g.off", "-k", "4", "-o", "{d}/o.seg", "--colored-mesh",
                     "{d}/c.ply"], "ok", outputs=["o.seg", "c.ply"]))
    out.append(Case("segment-second-output-fails", g,
                    ["segment", "{d}/g.off", "-k", "4", "-o", "{d}/o.seg", "--colored-mesh",
                     "{d}/missing/c.ply"], match="does not exist"))
    # --- evaluate and label files
    def ev(lab, *gts):
        return ["evaluate", "{d}/g.off", "{d}/" + lab, *["{d}/" + x for x in gts]]
    for name, data, match in [
            ("seg-short", grid_seg(n=10), "labels"), ("seg-long", grid_seg(n=500), "labels"),
            ("seg-text", b"a\nb\n", "malformed"), ("seg-float", grid_seg().replace(b"\n", b".5\n"),
                                                   ""),
            ("seg-empty", b"", "labels"), ("seg-binary", bytes(range(256)), ""),
            ("seg-two-columns", b"1 2\n3 4\n", ""),
            ("seg-gz-corrupt", None, "decompress")]:
        fname = "l.seg.gz" if data is None else "l.seg"
        body = (gzip.compress(grid_seg())[:15] + b"\0" * 10) if data is None else data
        out.append(Case(f"evaluate-{name}", {**g, fname: body, "gt.seg": grid_seg()},
                        ev(fname, "gt.seg"), match=match))
    out.append(Case("evaluate-gt-short", {**g, "l.seg": grid_seg(), "gt.seg": grid_seg(n=3)},
                    ev("l.seg", "gt.seg"), match="labels"))
    out.append(Case("evaluate-tau", {**g, "l.seg": grid_seg(), "gt.seg": grid_seg()},
                    ev("l.seg", "gt.seg") + ["--tau", "2"], match="tau"))
    out.append(Case("evaluate-tau-nan", {**g, "l.seg": grid_seg(), "gt.seg": grid_seg()},
                    ev("l.seg", "gt.seg") + ["--tau", "nan"], match="tau"))
    out.append(Case("evaluate-zero-area", {"z.off": b"OFF\n3 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n",
                                            "l.seg": b"0\n", "gt.seg": b"0\n"},
                    ["evaluate", "{d}/z.off", "{d}/l.seg", "{d}/gt.seg"], match="zero total area"))
    out.append(Case("evaluate-huge-coordinates",
                    {"h.off": _tetra_off().replace(b"0 0 1\n", b"0 0 1e290\n", 1),
                     "l.seg": b"0\n0\n1\n1\n", "gt.seg": b"0\n0\n0\n1\n"},
                    ["evaluate", "{d}/h.off", "{d}/l.seg", "{d}/gt.seg"], match="rescale"))
    out.append(Case("evaluate-ok", {**g, "l.seg": grid_seg(), "gt.seg": grid_seg(0)},
                    ev("l.seg", "gt.seg"), "ok"))
    # --- coordinates no command can handle: each command refuses them in one line
    huge = {"h.off": _tetra_off().replace(b"1 0 0\n", b"1e300 0 0\n", 1)
            .replace(b"0 1 0\n", b"0 -1e300 0\n", 1)}
    flat = {"h.off": b"OFF\n3 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n"}
    for what, files, match in [("huge-coordinates", huge, "rescale"),
                               ("zero-area", flat, "zero total area")]:
        for argv in (["render", "{d}/h.off", "--plain", "-o", "{d}/o.png"],
                     ["render", "{d}/h.off", "-o", "{d}/o.png"],
                     ["html", "{d}/h.off", "--plain", "-o", "{d}/o.html"],
                     ["panel", "{d}/h.off", "-k", "2", "-o", "{d}/o.png"],
                     ["view", "{d}/h.off", "--plain"],
                     ["baseline", "{d}/h.off", "-m", "vsa", "-k", "2", "-o", "{d}/o.seg"],
                     ["segment", "{d}/h.off", "-k", "2", "--picture", "{d}/o.png"]):
            out.append(Case(f"{argv[0]}-{what}{'-plain' if '--plain' in argv else ''}", files,
                            argv, match=match if argv[0] != "view" else ""))
    # --- pictures (options are checked before anything is drawn)
    for name, opts, match in [
            ("zoom-zero", ["--zoom", "0"], "zoom"), ("zoom-nan", ["--zoom", "nan"], "zoom"),
            ("line-width-negative", ["--line-width", "-1"], "line_width"),
            ("background-bogus", ["--background", "notacolour"], "colour"),
            ("size-zero", ["--size", "0x0"], "size"), ("view-bogus", ["--view", "sideways"],
                                                       "view"),
            ("view-zero", ["--view", "0,0,0"], "view"), ("wrong-suffix", ["-o", "{d}/p.jpg"],
                                                         ".png"),
            ("labels-short", ["{d}/l.seg"], "labels")]:
        argv = ["render", "{d}/g.off", *([] if name == "wrong-suffix" else ["-o", "{d}/p.png"]),
                *opts]
        if name == "labels-short":
            argv = ["render", "{d}/g.off", "{d}/l.seg", "-o", "{d}/p.png"]
        out.append(Case(f"render-{name}", {**g, "l.seg": grid_seg(n=5)}, argv, match=match))
    for name, opts in [("size-text", ["--size", "big"]), ("up-bogus", ["--up", "w"]),
                       ("no-output", [])]:
        out.append(Case(f"render-{name}", g, ["render", "{d}/g.off",
                                              *([] if name == "no-output" else ["-o", "{d}/p.png"]),
                                              *opts], "usage"))
    for name, opts, match in [("wrong-suffix", ["-o", "{d}/p.txt"], ".html"),
                              ("view-bogus", ["-o", "{d}/p.html", "--view", "nowhere"], "view"),
                              ("k-zero", ["-o", "{d}/p.html", "-k", "0"], "n_segments")]:
        out.append(Case(f"html-{name}", g, ["html", "{d}/g.off", *opts], match=match))
    out.append(Case("html-labels-long", {**g, "l.seg": grid_seg(n=999)},
                    ["html", "{d}/g.off", "{d}/l.seg", "-o", "{d}/p.html"], match="labels"))
    out.append(Case("html-ok", g, ["html", "{d}/g.off", "-k", "4", "-o", "{d}/p.html", "-q"],
                    "ok", outputs=["p.html"]))
    for name, opts, match in [("k-zero", ["-k", "0"], "n_segments"),
                              ("titles-count", ["--titles", "a", "b", "c"], "titles"),
                              ("param-unknown", ["--param", "beta=1"], "beta"),
                              ("method-unknown", ["-m", "nope"], "nope")]:
        out.append(Case(f"panel-{name}", g, ["panel", "{d}/g.off", "-o", "{d}/p.png", *opts],
                        match=match))
    # --- demo
    for name, opts, match in [("resolution-small", ["--resolution", "5"], "resolution"),
                              ("resolution-huge", ["--resolution", "100000"], "resolution"),
                              ("k-zero", ["-k", "0"], "n_segments"),
                              ("alpha-negative", ["--alpha", "-3"], "alpha")]:
        out.append(Case(f"demo-{name}", {}, ["demo", "--output-dir", "{d}/out", *opts],
                        match=match))
    out.append(Case("demo-output-is-file", {"out": b"x"}, ["demo", "--output-dir", "{d}/out"],
                    match="not a folder"))
    # --- report
    for name, data, match in [("not-utf8", b"\xff\xfe\x00garbage\xff\n", ""),
                              ("not-results", b"a,b\n1,2\n", "not a superfacets results file"),
                              ("no-category", b"mesh,method,n_segments,status\nx,superfacets,10,"
                                              b"ok\n", "no category column"),
                              ("empty", b"", "no rows"), ("header-only", RESULTS, "no rows"),
                              ("binary", bytes(range(256)), ""),
                              ("k-infinite", RESULTS + b"a,1,Ant,10,superfacets,inf,200,0,ok,5,"
                                             b"0.1,5.0,0.8,0.9\n", "n_segments = inf")]:
        out.append(Case(f"report-{name}", {"r.csv": data},
                        ["report", "{d}/r.csv", "-o", "{d}/rep"], match=match))
    out.append(Case("report-missing", {}, ["report", "{d}/none.csv"], match="none.csv"))
    # --- experiment and baseline
    for name, opts, match in [("psb-missing", ["--psb", "{d}/nope"], "Princeton"),
                              ("ids-text", ["--ids", "x"], "--ids"),
                              ("method-unknown", ["-m", "nope"], "nope"),
                              ("per-category-zero", ["--per-category", "0"], "per-category"),
                              ("param-unknown", ["--param", "bogus=1"], "bogus"),
                              ("param-no-value", ["--param", "alpha"], "NAME=V1,V2"),
                              ("tau", ["--tau", "2"], "tau"), ("k-zero", ["-k", "0"], "n_segments"),
                              ("workers-zero", ["-j", "0"], "workers")]:
        argv = ["experiment", "-o", "{d}/r.csv", "-q", *opts]
        if name != "psb-missing":
            argv += ["--psb", "{d}/psb"]
        out.append(Case(f"experiment-{name}", {"psb/off/1.off": grid_off(),
                                               "psb/seg/Benchmark/1/1_0.seg": grid_seg()},
                        argv, match=match))
    for name, opts, match in [("method-unknown", ["-m", "nope"], "nope"),
                              ("param-unknown", ["-m", "vsa", "--param", "alpha=1"], "alpha"),
                              ("param-two-values", ["-m", "vsa", "--param", "metric=l2,l21"],
                               "one value"),
                              ("param-bad-value", ["-m", "vsa", "--param", "metric=l7"], "metric"),
                              ("k-zero", ["-m", "vsa", "-k", "0"], "n_segments")]:
        out.append(Case(f"baseline-{name}", g, ["baseline", "{d}/g.off", "-o", "{d}/o.seg", *opts],
                        match=match))
    out.append(Case("baseline-ok", g, ["baseline", "{d}/g.off", "-m", "vsa", "-k", "4", "-o",
                                       "{d}/o.seg", "-q"], "ok", outputs=["o.seg"]))
    return out


@dataclass
class Interrupt:
    """A command interrupted by Ctrl-C (SIGINT to its whole process group, as a terminal
    sends it) at each of ``delays`` seconds after its start."""
    name: str
    argv: list  # "{d}" is the case's folder, "{big}" a 405,000-face mesh in it
    delays: tuple
    outputs: list  # files that must be whole or absent


def interrupts() -> list[Interrupt]:
    return [
        # the imports, the reading, the face graph, the passes, the writing (from 0.3 s:
        # before, the interpreter itself is starting)
        Interrupt("segment", ["segment", "{big}", "-k", "100", "-o", "{d}/o.seg",
                              "--colored-mesh", "{d}/o.ply"],
                  (0.3, 0.6, 1.0, 1.8, 2.6), ["o.seg", "o.ply"]),
        # Dask workers in the same process group: they must stay silent
        Interrupt("batch", ["batch", "{big}", "{d}/more", "-o", "{d}/out", "-k", "50",
                            "-j", "2"], (1.5, 4.0), []),
    ]
