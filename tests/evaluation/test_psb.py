import pytest
from conftest import grid_mesh

from superfacets import MeshFormatError, write_mesh
from superfacets.evaluation.datasets.psb import category, list_meshes


def test_category_ranges():
    assert category(1) == "Human" and category(20) == "Human" and category(21) == "Cup"
    assert category(281) == "Armadillo" and category(361) == "Vase" and category(330) == "Mech"
    assert category(270) == "other" and category(999) == "other"


def test_list_meshes_reads_what_is_present(tmp_path):
    mesh = grid_mesh(2, 2)
    (tmp_path / "off").mkdir()
    for mid in (5, 42):
        write_mesh(tmp_path / "off" / f"{mid}.off", mesh)
    d = tmp_path / "seg" / "Benchmark" / "42"
    d.mkdir(parents=True)
    for j in (0, 1, 10, 2):
        (d / f"42_{j}.seg").write_text("\n".join(["0"] * mesh.n_faces) + "\n")
    items = list_meshes(tmp_path)
    assert [b.id for b in items] == [5, 42]
    assert items[0].seg_paths == () and items[1].category == "Glasses"
    assert [p.name for p in items[1].seg_paths] == ["42_0.seg", "42_1.seg", "42_2.seg", "42_10.seg"]
    assert len(items[1].ground_truths(mesh.n_faces)) == 4
    (d / "42_3.seg").write_text("0\n0\n")
    with pytest.raises(MeshFormatError,
                       match=r"42_3.seg: has 2 labels but the input has 8 elements"):
        list_meshes(tmp_path)[1].ground_truths(mesh.n_faces)
    with pytest.raises(FileNotFoundError, match="not a benchmark folder"):
        list_meshes(tmp_path / "seg")


def test_real_benchmark_is_consistent(psb):
    items = list_meshes(psb)
    assert len(items) == 300
    assert {b.category for b in items} >= {"Human", "Mech", "Vase", "Armadillo"}
    assert "other" not in {b.category for b in items}
    b = items[0]
    mesh = b.load()
    gts = b.ground_truths(mesh.n_faces)
    assert len(gts) >= 1 and all(g.shape == (mesh.n_faces,) for g in gts)
    assert all(len(x.seg_paths) >= 1 for x in items)
