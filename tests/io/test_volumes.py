"""Tetrahedral meshes: validation, the cell graph, the method on volumes, meshio files, the CLI."""

from __future__ import annotations

import re

import numpy as np
import pytest

from superfacets import segment
from superfacets.elements.cells import cell_graph
from superfacets.errors import InvalidMeshError, MeshFormatError, ParameterError
from superfacets.evaluation.metrics import compactness, undersegmentation_error
from superfacets.inputs.tetmesh import TetMesh, cut_surface
from superfacets.method.connectivity import label_components

CORNERS = np.array(np.meshgrid([0.0, 1.0], [0.0, 1.0], [0.0, 1.0])).reshape(3, -1).T


def delaunay_cube(n=3000, seed=0, split=0.6) -> TetMesh:
    from scipy.spatial import Delaunay

    p = np.r_[np.random.default_rng(seed).random((n, 3)), CORNERS]
    tets = Delaunay(p).simplices
    material = (p[tets].mean(axis=1)[:, 0] > split).astype(np.int64)
    return TetMesh(p, tets, materials=material)


def test_tetmesh_validation():
    v = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    with pytest.raises(InvalidMeshError, match="shape \\(m, 4\\)"):
        TetMesh(v, [[0, 1, 2]])
    with pytest.raises(InvalidMeshError, match="refers to vertex 7"):
        TetMesh(v, [[0, 1, 2, 7]])
    with pytest.raises(InvalidMeshError, match="repeats a vertex"):
        TetMesh(v, [[0, 1, 1, 2]])
    with pytest.raises(InvalidMeshError, match="vertex 1 has a non-finite"):
        TetMesh([[0, 0, 0], [np.nan, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 1, 2, 3]])
    with pytest.raises(InvalidMeshError, match="no tetrahedron"):
        TetMesh(v, np.zeros((0, 4), int))
    with pytest.raises(InvalidMeshError, match="materials"):
        TetMesh(v, [[0, 1, 2, 3]], materials=[1, 2])
    flat = TetMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2, 3]])
    with pytest.raises(InvalidMeshError, match="flat"):
        segment(flat, 1)
    # areas and volumes of such tetrahedra overflow: refused as meshes and clouds are
    huge = TetMesh(np.array(v) * 1e100, [[0, 1, 2, 3]], name="huge.msh")
    with pytest.raises(InvalidMeshError, match="huge.msh: coordinates up to 1e.100.*rescale"):
        segment(huge, 1)
    tiny = TetMesh(np.array(v) * 1e-80, [[0, 1, 2, 3]])
    with pytest.raises(InvalidMeshError, match="spans only 1e-80"):
        segment(tiny, 1)
    far = TetMesh(np.r_[v, [[1e100, 0, 0]]], [[0, 1, 2, 3]])  # an unused vertex: no matter
    assert segment(far, 1).n_segments == 1


def test_cell_graph_known_answer():
    t = TetMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]],
                [[0, 1, 2, 3], [1, 2, 3, 4]])
    g = cell_graph(t)
    assert g.kind == "cells" and g.element == "tetrahedron" and g.n_elements == 2
    assert g.pairs.tolist() == [[0, 1]]
    assert g.lengths[0] == pytest.approx(np.sqrt(3) / 2)  # the triangle 1-2-3
    np.testing.assert_allclose(g.sizes, [1 / 6, 1 / 3])
    mid = np.array([1, 1, 1]) / 3
    geo = np.linalg.norm(t.centroids[0] - mid) + np.linalg.norm(mid - t.centroids[1])
    assert g.terms.geo[0] == pytest.approx(geo)
    assert g.terms.cos[0] == 1 and not g.terms.concave[0]  # no angle inside a solid
    assert g.boundary_elements.shape == (6,)  # the other six triangles are on the surface
    assert cell_graph(t) is g  # kept with the mesh


def test_volumes_segmented_connected_and_measured():
    t = delaunay_cube()
    g = cell_graph(t)
    r = segment(t, 20)
    k = r.n_segments
    assert r.params["elements"] == "cells" and r.labels.shape == (t.n_tets,)
    assert abs(k - 20) <= 2 and np.unique(r.labels).size == k
    assert np.unique(label_components(g, r.labels)).size == k  # each one connected
    assert r.mesh_radius == pytest.approx((3 * 1.0 / (4 * np.pi * 20)) ** (1 / 3))
    assert not r.params["cleanup"] and not r.params["split_merge"]  # surfaces only
    # compactness area / volume^(2/3): the whole cube is 6 (area 6, volume 1)
    assert compactness(g, np.zeros(t.n_tets, int)) == pytest.approx(6.0)
    # a material jump is what a concave crease is on a surface (beta)
    blind = undersegmentation_error(g, r.labels, t.materials)
    seeing = segment(t, 20, beta=50)
    assert undersegmentation_error(g, seeing.labels, t.materials) < 0.01 < blind
    np.testing.assert_array_equal(segment(t, 20, n_threads=1).labels, r.labels)


def test_cut_surface():
    t = delaunay_cube(500)
    whole, _ = cut_surface(t, at=1.0)
    assert whole.areas.sum() == pytest.approx(6.0)  # the cube's surface, closed
    half, lab = cut_surface(t, np.arange(t.n_tets), at=0.5)
    assert lab.shape == (half.n_faces,)
    # closed and turned outwards: the volume it encloses (divergence theorem) is that of
    # the tetrahedra kept, those with their centroid at x <= 0.5
    kept = t.volumes[t.centroids[:, 0] <= 0.5].sum()
    enclosed = np.sum(np.einsum("ij,ij->i", half.centroids, half.normals) * half.areas) / 3
    assert enclosed == pytest.approx(kept, rel=1e-9) and 0.3 < kept < 0.7
    assert set(lab) <= set(range(t.n_tets)) and np.all(t.centroids[lab, 0] <= 0.5)
    with pytest.raises(ParameterError, match="at"):
        cut_surface(t, at=2)


def test_meshio_files_round_trip(tmp_path):
    meshio = pytest.importorskip("meshio")
    from superfacets.io import read_volume, write_volume_labels

    t = delaunay_cube(800)
    meshio.Mesh(t.vertices, [("triangle", np.array([[0, 1, 2]])), ("tetra", t.tets)],
                cell_data={"gmsh:physical": [np.array([7]), t.materials.astype(np.int32)]}
                ).write(tmp_path / "c.msh", file_format="gmsh22", binary=False)
    back = read_volume(tmp_path / "c.msh")  # the surface triangle is left out
    np.testing.assert_array_equal(back.tets, t.tets)
    np.testing.assert_array_equal(back.materials, t.materials)
    labels = segment(back, 10).labels
    write_volume_labels(tmp_path / "out.vtu", back, labels)
    got = meshio.read(tmp_path / "out.vtu")
    np.testing.assert_array_equal(got.cell_data["superfacet"][0], labels)
    (tmp_path / "tri.vtu").write_bytes(b"")
    meshio.Mesh(t.vertices, [("triangle", np.array([[0, 1, 2]]))]).write(tmp_path / "tri.vtu")
    with pytest.raises(MeshFormatError, match="no tetrahedra"):
        read_volume(tmp_path / "tri.vtu")
    (tmp_path / "bad.msh").write_text("not a mesh")
    with pytest.raises(MeshFormatError, match="cannot read it"):
        read_volume(tmp_path / "bad.msh")


def test_cli_segments_a_volume(tmp_path, capsys):
    meshio = pytest.importorskip("meshio")
    from superfacets.cli import main

    t = delaunay_cube(800)
    meshio.Mesh(t.vertices, [("tetra", t.tets)]).write(tmp_path / "c.vtu")
    assert main(["segment", str(tmp_path / "c.vtu"), "-k", "8", "-o", str(tmp_path / "c.seg"),
                 "--colored-mesh", str(tmp_path / "o.vtu")]) == 0
    out = capsys.readouterr().out
    assert f"{t.n_tets:,} tetrahedra, 8 superfacets, " in out and "o.vtu (volume" in out
    labels = np.loadtxt(tmp_path / "c.seg", dtype=int)
    # the sizes as a surface's summary says them: each the diameter of a ball of the median
    # superfacet's volume (the cube's eighth: about 0.62 of its side)
    median = np.median(np.bincount(labels, weights=t.volumes))
    wide = float(re.search(r"about ([0-9.]+) wide in the data's units", out).group(1))
    assert wide == pytest.approx(np.cbrt(6 * median / np.pi), rel=2e-3)
    assert re.search(r"[0-9,]+ to [0-9,]+ tetrahedra each \(median [0-9,]+", out)
    assert labels.shape == (t.n_tets,)
    np.testing.assert_array_equal(meshio.read(tmp_path / "o.vtu").cell_data["superfacet"][0],
                                  labels)
    assert main(["segment", str(tmp_path / "c.vtu"), "--per-object"]) == 2
    assert "not available for tetrahedral meshes" in capsys.readouterr().err
    assert main(["segment", str(tmp_path / "c.vtu"), "--beta", "5"]) == 2
    assert "materials" in capsys.readouterr().err
    assert main(["segment", str(tmp_path / "c.vtu"), "--elements", "points"]) == 2
    assert "segmented by its tetrahedra" in capsys.readouterr().err
    (tmp_path / "bad.msh").write_text("garbage\n")
    assert main(["segment", str(tmp_path / "bad.msh"), "-o", str(tmp_path / "b.seg")]) == 2
    assert "cannot read it as a volume mesh" in capsys.readouterr().err
    assert not (tmp_path / "b.seg").exists()


def test_far_unused_vertices_do_not_size_the_superfacets():
    """A vertex of no tetrahedron (far away) set the bounding box: radius 0.1 gave one
    superfacet. The box is that of the used vertices, as on meshes."""
    vol = delaunay_cube(800)
    far = TetMesh(np.r_[vol.vertices, [[1e3, 1e3, 1e3]]], vol.tets)
    a, b = segment(vol, radius=0.1), segment(far, radius=0.1)
    assert a.n_segments == b.n_segments > 10
    np.testing.assert_array_equal(a.labels, b.labels)


def test_the_command_line_says_why_the_count_differs(tmp_path, capsys):
    pytest.importorskip("meshio")
    from superfacets import write_volume_labels
    from superfacets.cli import main

    vol = delaunay_cube(600)  # k = 5 made 9 (regions no window reached): merged to 5
    path = tmp_path / "cube.vtu"
    write_volume_labels(path, vol, np.zeros(vol.n_tets, dtype=int))
    assert main(["segment", str(path), "-k", "5", "-o", str(tmp_path / "c.seg")]) == 0
    assert "note:" not in capsys.readouterr().err
    assert segment(vol, 5).n_segments == 5
    # two blocks apart: at least one superfacet each, said in a note
    two = TetMesh(np.r_[vol.vertices, vol.vertices + [3.0, 0, 0]],
                  np.r_[vol.tets, vol.tets + len(vol.vertices)])
    write_volume_labels(path, two, np.zeros(two.n_tets, dtype=int))
    assert segment(two, 5).n_segments == 5
    assert main(["segment", str(path), "-k", "1", "-o", str(tmp_path / "c.seg")]) == 0
    assert "note: 2 superfacets for -k 1: the input has 2 separate pieces" in \
        capsys.readouterr().err


def test_a_compressed_volume_reads_as_the_file_inside_and_says_its_own_name(tmp_path, capsys):
    """``segment part.vtk.gz`` is a volume's run: the file decompressed (bomb-checked)
    under its inner suffix; a damaged one names the user's file, not a temporary one."""
    import gzip

    pytest.importorskip("meshio")
    from superfacets.cli import main
    from superfacets.io import input_kind, read_volume, write_volume_labels

    tet = delaunay_cube(300)
    plain = tmp_path / "part.vtu"
    write_volume_labels(plain, tet, np.zeros(tet.n_tets, dtype=np.int64))
    packed = tmp_path / "part.vtu.gz"
    packed.write_bytes(gzip.compress(plain.read_bytes()))
    assert [input_kind(p) for p in (packed, tmp_path / "s.laz", tmp_path / "m.off.xz")] == [
        "volume", "cloud", "mesh"]
    read = read_volume(packed)
    np.testing.assert_array_equal(read.tets, read_volume(plain).tets)
    assert main(["segment", str(packed), "-k", "6", "--colored-mesh", str(tmp_path / "o.vtu"),
                 "-q"]) == 0
    assert read_volume(tmp_path / "o.vtu").n_tets == tet.n_tets
    capsys.readouterr()
    # -o writes text labels: a volume's name there is refused, pointing at --colored-mesh
    assert main(["segment", str(packed), "-k", "6", "-o", str(tmp_path / "out.vtk")]) == 2
    assert "--colored-mesh out.vtk" in capsys.readouterr().err
    assert not (tmp_path / "out.vtk").exists()
    bad = tmp_path / "bad.vtk.gz"
    bad.write_bytes(gzip.compress(b"not a volume"))
    with pytest.raises(MeshFormatError, match="bad.vtk.gz") as info:
        read_volume(bad)
    assert "superfacets-" not in str(info.value)
    (tmp_path / "cut.vtk.gz").write_bytes(packed.read_bytes()[:60])
    with pytest.raises(MeshFormatError, match="cannot decompress"):
        read_volume(tmp_path / "cut.vtk.gz")
