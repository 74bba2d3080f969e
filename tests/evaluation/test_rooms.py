"""The made-up labelled rooms (S3DIS-like), and the colour term judged on them."""

from dataclasses import replace

import numpy as np
import pytest

from superfacets import segment
from superfacets.errors import ParameterError
from superfacets.evaluation.datasets.rooms import CLASSES, load_room, make_room, room_entries
from superfacets.evaluation.datasets.scans import evaluate_scan


@pytest.fixture(scope="module")
def room():
    return make_room(4)


def test_a_room_is_fixed_by_its_seed_and_holds_what_s3dis_rooms_hold(room):
    again = make_room(4)
    np.testing.assert_array_equal(again.cloud.points, room.cloud.points)
    np.testing.assert_array_equal(again.instances, room.instances)
    assert not np.array_equal(make_room(5).cloud.points[:100], room.cloud.points[:100])
    present = set(np.unique(room.ground_truth).tolist())
    for cls in ("ceiling", "floor", "wall", "door", "board", "window", "bookcase", "sofa",
                "table", "chair"):
        assert CLASSES[cls] in present, cls
    assert room.ground_truth.shape == room.instances.shape == (room.cloud.n_total,)
    assert room.cloud.colors.shape == (room.cloud.n_total, 3)
    assert room.cloud.up.tolist() == [0.0, 0.0, 1.0]
    # one point per 3 cm voxel (before the noise): no two points closer than the noise
    from scipy.spatial import cKDTree

    d, _ = cKDTree(room.cloud.points).query(room.cloud.points, k=2)
    assert np.median(d[:, 1]) > 0.015


def test_boards_doors_and_windows_lie_in_their_walls_plane(room):
    # they differ from the wall in colour only: the same plane, within the noise
    pts, gt = room.cloud.points, room.ground_truth
    for cls in ("board", "window"):
        on = pts[gt == CLASSES[cls]]
        assert len(on)
        # each lies on one of the four walls: one coordinate at 0 or the room's extent
        lo, hi = np.quantile(pts, [0.001, 0.999], axis=0)
        near = np.minimum(np.abs(on[:, :2] - lo[:2]), np.abs(on[:, :2] - hi[:2])).min(axis=1)
        assert np.quantile(near, 0.99) < 0.03, cls
    wall = room.cloud.colors[gt == CLASSES["wall"]].mean(axis=0)
    board = room.cloud.colors[gt == CLASSES["board"]].mean(axis=0)
    assert np.linalg.norm(wall - board) > 0.05  # told apart by colour


def test_hidden_surfaces_are_not_sampled(room):
    # the floor under the bookcase and the wall behind it are cut (a scan does not see them)
    pts, inst = room.cloud.points, room.instances
    book = pts[room.ground_truth == CLASSES["bookcase"]]
    lo, hi = book.min(axis=0) + 0.05, book.max(axis=0) - 0.05
    within = (pts[:, 0] > lo[0]) & (pts[:, 0] < hi[0])
    under = within & (pts[:, 1] > lo[1]) & (pts[:, 1] < hi[1]) & (inst == 0)
    behind = within & (pts[:, 2] > lo[2]) & (pts[:, 2] < hi[2]) & (inst == 2)  # wall y = 0
    assert not under.any() and not behind.any()
    assert (within & (pts[:, 2] > hi[2] + 0.1) & (inst == 2)).any()  # the wall above it


def test_rooms_by_name_and_as_experiment_entries():
    assert load_room("room-2", meshes=()).name == "room-2"
    with pytest.raises(ParameterError, match="rooms are named room-0"):
        load_room("kitchen")
    assert [e.id for e in room_entries(3)] == [0, 1, 2]
    with pytest.raises(ParameterError, match="at least 1"):
        room_entries(0)


def test_the_default_reads_the_rooms_colours_and_finds_the_boards(room):
    # boards, doors and windows differ from the wall in colour only: without colour the
    # superpoints cross them; the default (beta read from the data) follows them
    blind = segment(replace(room.cloud), 1000, beta=0)
    seeing = segment(replace(room.cloud), 1000)
    assert seeing.params["beta"] > 0 and 0 < seeing.params["feature_floor"] < 0.1
    ue_blind = evaluate_scan(room, blind.labels)["undersegmentation_error"]
    ue = evaluate_scan(room, seeing.labels)["undersegmentation_error"]
    assert ue < 0.5 * ue_blind
    assert seeing.n_segments == 1000


def test_the_colour_floor_follows_the_noise():
    # noisier colours: a higher floor, read from the data (the median neighbour difference)
    from superfacets.elements.builders import elements_of
    from superfacets.elements.features import features_of
    from superfacets.method.weights import feature_scale

    floors = []
    for noise in (0.01, 0.05):
        scan = make_room(1, meshes=(), color_noise=noise)
        src = elements_of(scan.cloud)
        floors.append(feature_scale(src.graph, features_of(src, None))[1])
    assert floors[1] > 3 * floors[0]


def test_experiment_runs_on_the_rooms(tmp_path, capsys):
    import csv

    from superfacets.cli import main

    out = tmp_path / "rooms.csv"
    assert main(["experiment", "--dataset", "rooms", "--rooms", "1", "--elements", "points",
                 "-k", "200", "--alpha", "200", "--param", "superfacets.beta=0,auto", "-j",
                 "1", "-o", str(out), "-q"]) == 0
    rows = list(csv.DictReader(out.open()))
    assert [(r["mesh"], r["category"], r["beta"], r["status"]) for r in rows] == [
        ("room-0", "Room", "0", "ok"), ("room-0", "Room", "auto", "ok")]
    ue = {r["beta"]: float(r["undersegmentation_error"]) for r in rows}
    assert ue["auto"] < ue["0"]  # the boards and doors: told by colour only
    assert main(["experiment", "--dataset", "rooms", "-o", str(out)]) == 2  # (faces)
    assert "--elements points" in capsys.readouterr().err


def test_features_that_are_not_numbers_turn_the_default_term_off():
    from superfacets import PointCloud

    rng = np.random.default_rng(0)
    feats = rng.random((2000, 3))
    feats[5] = np.nan  # (a cloud's own colours are checked when it is made)
    cloud = PointCloud(np.c_[rng.random((2000, 2)), np.zeros(2000)])
    with pytest.warns(RuntimeWarning, match="colour term is off"):
        r = segment(cloud, 20, features=feats)
    assert r.params["beta"] == 0 and r.n_segments == 20
    with pytest.raises(ParameterError, match="not finite"):
        segment(cloud, 20, beta=10, features=feats)  # asked for: an error, not a warning
