import numpy as np
import pytest
from conftest import grid_mesh

from superfacets import Mesh, read_labels, read_mesh, superfacets
from superfacets.evaluation.metrics import (
    achievable_segmentation_accuracy,
    boundary_precision,
    boundary_recall,
    compactness,
    contingency,
    evaluate,
    mean_over_ground_truths,
    undersegmentation_error,
    undersegmentation_error_np,
)


@pytest.fixture
def plane():
    return grid_mesh(20, 20, size=1.0)  # [-1, 1]^2, area 4, 800 faces


def by_x(mesh, cuts):
    return np.searchsorted(np.asarray(cuts), mesh.centroids[:, 0]).astype(np.int64)


def test_ue_zero_when_superfacets_nest_in_ground_truth(plane):
    gt = by_x(plane, [0.0])
    sf = by_x(plane, [-0.5, 0.0, 0.5])
    assert undersegmentation_error(plane, sf, gt) == 0.0
    assert achievable_segmentation_accuracy(plane, sf, gt) == pytest.approx(1.0)


def test_ue_straddling_superfacet_contributes_expected_area(plane):
    gt = by_x(plane, [0.0])          # two halves, area 2 each
    sf = by_x(plane, [-0.5, 0.5])    # middle superfacet x in [-0.5, 0.5] (area 2) straddles
    # middle superfacet: inside left half area 1, outside 1; same for right half:
    # leaks 1 + 1 = 2 over total ground-truth area 4
    assert undersegmentation_error(plane, sf, gt) == pytest.approx(0.5)
    assert achievable_segmentation_accuracy(plane, sf, gt) == pytest.approx(3 / 4)


def test_tau_keeps_a_small_sliver_out(plane):
    gt = by_x(plane, [0.0])
    # cut at x = 0.05: the left superfacet takes the 20 triangles of the column [0, 0.1]
    # whose centroid is at x = 0.033 (area 0.1): 0.1 / 2.1 = 4.8% of it lies in the right half
    sf = by_x(plane, [0.05])
    # it counts for the left half (leaks 0.1), not for the right half (4.8% < tau = 5%)
    assert undersegmentation_error(plane, sf, gt) == pytest.approx(0.1 / 4)
    # with tau = 0 it also counts for the right half, leaking its 2.0 outside it
    assert undersegmentation_error(plane, sf, gt, tau=0.0) == pytest.approx((0.1 + 2.0) / 4)


def test_compactness_square_and_disk():
    plane = grid_mesh(40, 40, size=1.0)
    c = plane.centroids
    square = ((np.abs(c[:, 0]) < 0.5) & (np.abs(c[:, 1]) < 0.5)).astype(np.int64)
    # the square region has perimeter 4 * 1 and area 1 -> 4; the outer frame is 2 x 2 with a
    # 1 x 1 hole: perimeter 8 + 4 = 12, area 3 -> 12 / sqrt(3)
    assert compactness(plane, square) == pytest.approx((4 + 12 / np.sqrt(3)) / 2)
    single = np.zeros(plane.n_faces, np.int64)
    assert compactness(plane, single) == pytest.approx(4.0)  # the whole 2 x 2 square


def test_compactness_of_disk_approaches_two_sqrt_pi():
    import trimesh

    disk = trimesh.creation.cylinder(radius=1.0, height=1e-3, sections=256)
    top = disk.face_normals[:, 2] > 0.9
    m = Mesh(disk.vertices, disk.faces[top])
    assert compactness(m, np.zeros(m.n_faces, np.int64)) == pytest.approx(2 * np.sqrt(np.pi),
                                                                          rel=1e-3)


def test_boundary_recall(plane):
    gt = by_x(plane, [0.0])
    assert boundary_recall(plane, gt, gt) == 1.0
    far = by_x(plane, [0.5])
    assert boundary_recall(plane, far, gt) == 0.0
    near = by_x(plane, [0.1])  # one column of cells (0.1 wide) away: within one ring
    assert boundary_recall(plane, near, gt, tolerance=0) == 0.0
    assert boundary_recall(plane, near, gt, tolerance=1) == 1.0
    assert boundary_recall(plane, gt, np.zeros(plane.n_faces, np.int64)) == 1.0


def test_boundary_precision(plane):
    gt = by_x(plane, [0.0])
    assert boundary_precision(plane, gt, gt) == 1.0
    # two borders of equal length, one on the ground truth's, one 5 cells away
    two = by_x(plane, [0.0, 0.5])
    assert boundary_precision(plane, two, gt) == pytest.approx(0.5)
    assert boundary_recall(plane, two, gt) == 1.0  # the extra border costs no recall
    near = by_x(plane, [0.1])  # one column away: within one ring
    assert boundary_precision(plane, near, gt, tolerance=0) == 0.0
    assert boundary_precision(plane, near, gt, tolerance=1) == 1.0
    assert boundary_precision(plane, np.zeros(plane.n_faces, np.int64), gt) == 1.0  # no border


def test_boundary_precision_is_recall_with_the_roles_swapped(psb):
    mesh = read_mesh(psb / "off" / "1.off")
    gt = read_labels(psb / "seg" / "Benchmark" / "1" / "1_0.seg", n_faces=mesh.n_faces)
    labels = superfacets(mesh, 150, alpha=200)
    for tol in (0, 1, 2):
        p = boundary_precision(mesh, labels, gt, tolerance=tol)
        assert p == pytest.approx(boundary_recall(mesh, gt, labels, tolerance=tol), abs=1e-12)
        assert 0.0 < p < 1.0
    # 150 superfacets draw far more border than the few parts: precision below recall
    assert boundary_precision(mesh, labels, gt) < boundary_recall(mesh, labels, gt)
    m = evaluate(mesh, labels, [gt], precision=True)
    assert m["boundary_precision"] == pytest.approx(boundary_precision(mesh, labels, gt))


def test_all_metrics_invariant_to_scaling(plane):
    rng = np.random.default_rng(3)
    gt = by_x(plane, [0.0, 0.4])
    sf = rng.integers(0, 12, plane.n_faces)
    big = Mesh(plane.vertices * 123.0 + 5, plane.faces)
    for f in (undersegmentation_error, achievable_segmentation_accuracy, boundary_recall):
        assert f(big, sf, gt) == pytest.approx(f(plane, sf, gt))
    assert compactness(big, sf) == pytest.approx(compactness(plane, sf))


def test_contingency_areas_add_up(plane):
    rng = np.random.default_rng(0)
    sf, gt = rng.integers(0, 9, plane.n_faces), rng.integers(0, 4, plane.n_faces)
    t = contingency(plane, sf, gt)
    assert t.area.sum() == pytest.approx(plane.area)
    assert t.s_area.sum() == pytest.approx(plane.area) == t.g_area.sum()


def test_tau_keeps_a_3_percent_sliver_out(plane):
    gt = by_x(plane, [0.0])
    sf = gt.copy()
    # give the left superfacet 12 faces (area 0.06) of the right half: 0.06 / 2.06 = 2.9 %
    right = np.flatnonzero(gt == 1)
    sliver = right[np.lexsort((plane.centroids[right, 1], plane.centroids[right, 0]))[:12]]
    sf[sliver] = 0
    assert plane.areas[sliver].sum() == pytest.approx(0.06)
    assert undersegmentation_error(plane, sf, gt) == pytest.approx(0.06 / 4)
    assert undersegmentation_error(plane, sf, gt, tau=0.0) == pytest.approx((0.06 + 2.0) / 4)


def test_mean_over_ground_truths_and_errors(plane):
    gts = [by_x(plane, [0.0]), by_x(plane, [0.5])]
    sf = by_x(plane, [0.0])
    v = mean_over_ground_truths(boundary_recall, plane, sf, gts)
    assert v == pytest.approx(0.5)
    with pytest.raises(ValueError, match="no ground-truth"):
        mean_over_ground_truths(boundary_recall, plane, sf, [])
    with pytest.raises(ValueError, match="shape"):
        undersegmentation_error(plane, sf[:-1], gts[0])


def test_real_mesh_ranges(psb):
    mesh = read_mesh(psb / "off" / "1.off")
    gts = [read_labels(p,
                       n_faces=mesh.n_faces)
           for p in sorted((psb / "seg" / "Benchmark" / "1").glob("*.seg"))]
    labels = superfacets(mesh, 150, alpha=200)
    ue = mean_over_ground_truths(undersegmentation_error, mesh, labels, gts)
    asa = mean_over_ground_truths(achievable_segmentation_accuracy, mesh, labels, gts)
    br = mean_over_ground_truths(boundary_recall, mesh, labels, gts)
    assert 0 <= ue < 0.5 and 0.8 < asa <= 1 and 0.5 < br <= 1
    assert 2 * np.sqrt(np.pi) * 0.9 < compactness(mesh, labels) < 20
    # alpha = 0 ignores concavities: its undersegmentation error is higher
    ue0 = mean_over_ground_truths(undersegmentation_error, mesh, superfacets(mesh, 150, alpha=0),
                                  gts)
    assert ue0 > ue

    # evaluate() gives exactly the five metrics, each averaged over the ground truths
    m = evaluate(mesh, labels, gts)
    ue_np = mean_over_ground_truths(undersegmentation_error_np, mesh, labels, gts)
    assert 0 < ue_np < ue  # (a border missed by a few faces: its superfacet's whole area)
    assert m == {"undersegmentation_error": pytest.approx(ue, abs=1e-12),
                 "undersegmentation_error_np": pytest.approx(ue_np, abs=1e-12),
                 "compactness": pytest.approx(compactness(mesh, labels), abs=1e-12),
                 "boundary_recall": pytest.approx(br, abs=1e-12),
                 "achievable_accuracy": pytest.approx(asa, abs=1e-12)}


def test_evaluate_hand_worked(plane):
    gts = [by_x(plane, [0.0]), by_x(plane, [-0.5, 0.0, 0.5])]
    # the middle superfacet [-0.5, 0.5] straddles both halves and both middle quarters,
    # leaking area 2 of 4 against each ground truth, and taking 1 of its 2 correctly
    sf = by_x(plane, [-0.5, 0.5])
    m = evaluate(plane, sf, gts)
    assert m["undersegmentation_error"] == pytest.approx(0.5)
    assert m["undersegmentation_error_np"] == pytest.approx(0.5)  # min(1, 1) twice, of 4
    assert m["achievable_accuracy"] == pytest.approx(0.75)
    assert m["compactness"] == pytest.approx(compactness(plane, sf))
    with pytest.raises(ValueError, match="no ground-truth"):
        evaluate(plane, sf, [])


def test_evaluate_ignores_unlabelled_elements(plane):
    # three strips: x < -0.5 is unlabelled (-1), then two labelled halves of the rest
    gt = by_x(plane, [-0.5, 0.25]) - 1           # -1 | 0 | 1
    # superfacet 0 covers the unlabelled strip and the labelled strip [-0.5, 0.25]:
    # its labelled part lies in one class, so nothing leaks
    sf = by_x(plane, [0.25])
    m = evaluate(plane, sf, [gt], ignore_label=-1)
    assert m["undersegmentation_error"] == 0.0
    assert m["achievable_accuracy"] == pytest.approx(1.0)
    assert m["boundary_recall"] == pytest.approx(1.0)  # the -1|0 border is no boundary
    # without ignoring, the unlabelled strip is a class that superfacet 0 straddles
    plain = evaluate(plane, sf, [gt])
    assert plain["undersegmentation_error"] > 0.2
    assert plain["boundary_recall"] < 1.0
    # a superfacet straddling two labelled classes, measured on the labelled area (3)
    sf2 = by_x(plane, [-0.5, 0.5])                # [-1,-0.5) | [-0.5,0.5) | [0.5,1]
    m2 = evaluate(plane, sf2, [gt], ignore_label=-1)
    # middle superfacet (area 2, all labelled): 1.5 in class 0, 0.5 in class 1; both
    # overlaps exceed tau, so it leaks 0.5 + 1.5 = 2 over labelled area 3
    assert m2["undersegmentation_error"] == pytest.approx(2 / 3)
    # Neubert-Protzel's: each overlap its smaller part, min(1.5, 0.5) + min(0.5, 1.5)
    assert m2["undersegmentation_error_np"] == pytest.approx(1 / 3)
    assert m2["achievable_accuracy"] == pytest.approx((1.5 + 1.0) / 3)
    with pytest.raises(ValueError, match="unlabelled"):
        evaluate(plane, sf, [np.full(plane.n_faces, -1)], ignore_label=-1)


def test_evaluate_ignore_label_equal_weight_counts_labelled_elements(plane):
    gt = by_x(plane, [-0.5, 0.25]) - 1
    sf = by_x(plane, [0.0])
    a = evaluate(plane, sf, [gt], ignore_label=-1, equal_weight=True)
    b = evaluate(plane, sf, [gt], ignore_label=-1)
    # a uniform grid: every face has the same area, so counting equals weighing
    assert a["undersegmentation_error"] == pytest.approx(b["undersegmentation_error"])
    assert a["achievable_accuracy"] == pytest.approx(b["achievable_accuracy"])
    # the superfacet border at x = 0 is 2.5 cells from the only labelled boundary (0.25)
    assert a["boundary_recall"] == 0.0
    assert evaluate(plane, by_x(plane, [0.25]), [gt], ignore_label=-1,
                    equal_weight=True)["boundary_recall"] == 1.0
    # precision by elements: the border at x = 0 is near no labelled boundary (the -1|0
    # strip edge at -0.5 is none); a border on the -1|0 edge and one on the labelled
    # boundary: only the latter is judged (the former has an unlabelled side)
    assert evaluate(plane, sf, [gt], ignore_label=-1, equal_weight=True,
                    precision=True)["boundary_precision"] == 0.0
    p = evaluate(plane, by_x(plane, [-0.5, 0.25]), [gt], ignore_label=-1, equal_weight=True,
                 precision=True)
    assert p["boundary_precision"] == 1.0 and p["boundary_recall"] == 1.0
    p2 = evaluate(plane, by_x(plane, [0.25, 0.75]), [gt], ignore_label=-1, equal_weight=True,
                  precision=True)
    # two borders of 20 cells each side: the 40 elements along x = 0.25 are on the
    # truth's boundary, the 40 along x = 0.75 are 4 cells from it
    assert p2["boundary_precision"] == pytest.approx(0.5)
