"""``step_weight``: a step off a cloud's surface weighed more in the choice of neighbours and
in the method's distances (not in the paper): 4 on a scene by default, 1 elsewhere; known
answers on floors and planes, the compiled choice against numpy's, clear refusals."""

from __future__ import annotations

import numpy as np
import pytest

from superfacets import ParameterError, PointCloud, segment
from superfacets.elements import points as P
from superfacets.elements.neighbors import point_tree
from superfacets.method.weights import csr_point_weights

UP = np.array([0.0, 0.0, 1.0])


def _floors(step: float = 0.9, seed: int = 0):
    """Two floors of a 12 x 12 grid (spacing 1, jittered), ``step`` apart in height."""
    rng = np.random.default_rng(seed)
    xy = np.stack(np.meshgrid(np.arange(12.0), np.arange(12.0)), -1).reshape(-1, 2)
    xy = xy + rng.uniform(-0.1, 0.1, xy.shape)
    return np.r_[np.c_[xy, np.zeros(144)], np.c_[xy, np.full(144, step)]]


def test_neighbours_stay_on_their_floor():
    """Floors 0.9 apart on a grid of spacing 1: each point's ten nearest reach the other
    floor (1,270 of 2,880 listed); its ten along its surface seldom do (152, where the
    grid's edges leave too few on its own floor among the candidates; 6 inside), and the
    weights of a flat floor's neighbours are the plain ones (their offsets lie in it)."""
    pts = _floors()
    tree = point_tree(pts)
    plain = P.nearest(tree, 10)[0]
    floor = np.arange(288) >= 144
    assert (floor[plain[:, 1:]] != floor[:, None]).any(axis=1).all()
    nbr, kth, keep = P.surface_neighbours(pts, tree, 10, 4.0)
    crossing = floor[nbr[:, 1:]] != floor[:, None]
    inner = np.all((pts[:, :2] > 2) & (pts[:, :2] < 9), axis=1)
    assert crossing.sum() < 0.15 * (floor[plain[:, 1:]] != floor[:, None]).sum()
    assert crossing[inner].sum() <= 0.01 * crossing[inner].size and keep is None
    assert np.array_equal(nbr[:, 0], np.arange(288))
    d = np.linalg.norm(pts[nbr[:, 1:]] - pts[:, None], axis=2)
    np.testing.assert_array_equal(kth, d.max(axis=1))
    g = P.point_graph(PointCloud(pts[:144]), step=4.0).graph  # one flat floor
    np.testing.assert_array_equal(csr_point_weights(g, step=4.0), csr_point_weights(g))


@pytest.mark.parametrize("grid", [False, True])
@pytest.mark.parametrize("limit", [None, 0.08])
def test_the_compiled_choice_is_numpy_s(limit, grid):
    """The compiled choice (int32 neighbours) gives numpy's (the int64 path of clouds of
    2**31 points and more), bit for bit, with and without a neighbour radius; on a
    quantized grid too, three floors of it, where distances and keys tie (the compiled
    choice stops at the first candidate farther than the tenth key: ties go to the lower
    index all the same)."""
    rng = np.random.default_rng(4)
    pts = rng.random((6000, 3)) * [1.0, 1.0, 0.1]
    pts[::7, 2] += 0.05  # a step here and there
    if grid:
        xy = np.stack(np.meshgrid(np.arange(15.0), np.arange(15.0)), -1).reshape(-1, 2) / 15
        pts = np.r_[np.c_[xy, np.zeros(225)], np.c_[xy, np.full(225, 0.07)],
                    np.c_[xy[::3], np.full(75, 0.14)]]
    tree = point_tree(pts)
    got = P.surface_neighbours(pts, tree, 10, 3.0, limit)
    cand, _, keep_c = P.nearest(tree, int(P.STEP_CANDIDATES * 10), limit=limit)
    normals = P.estimate_normals(pts, np.ascontiguousarray(cand[:, :11]))
    want = P._surface_neighbours_numpy(pts, cand.astype(np.int64), keep_c, normals, 10, 3.0)
    for a, b in zip(got, want):
        assert (a is None) == (b is None)
        if a is not None:
            np.testing.assert_array_equal(a, b)


def test_a_scene_weighs_its_steps_and_an_object_does_not():
    """Resolved as the summary says: 4 on a cloud with an up direction (a scene), 1 on one
    without (an object: its labels those of ``step_weight=1``, bit for bit); the graph the
    evaluation reads stays the plain one."""
    pts = _floors(0.9, seed=1)
    obj = segment(PointCloud(pts), 6)
    assert obj.params["step_weight"] == 1.0
    np.testing.assert_array_equal(obj.labels, segment(PointCloud(pts), 6, step_weight=1).labels)
    scene = PointCloud(pts, up=UP)
    floor = np.arange(288) >= 144
    for k in (2, 4, 8):  # unweighed, every superpoint holds both floors; weighed, none
        plain = segment(scene, k, step_weight=1).labels
        assert all(len(set(floor[plain == s])) == 2 for s in range(k)), k
        r = segment(scene, k)
        assert r.params["step_weight"] == 4.0 and r.n_segments == k
        assert all(len(set(floor[r.labels == s])) == 1 for s in range(k)), k
    assert segment(scene, 2, step_weight=2.5).params["step_weight"] == 2.5
    keys = list(scene.__dict__["_point_graphs"])  # the plain graph and one per weight
    assert sorted(key[2][1] for key in keys if len(key) > 2) == [2.5, 4.0]
    assert sum(len(key) == 2 for key in keys) == 1
    assert P.point_graph(scene).graph is not P.point_graph(scene, step=4.0).graph


def test_refusals_say_what_is_taken():
    from superfacets import segment_tiled

    pts = _floors()
    for kwargs, said in (({"step_weight": 0.5}, "step_weight must be"),
                         ({"step_weight": 2.0, "paper": True}, "step_weight")):
        with pytest.raises(ParameterError, match=said):
            segment(PointCloud(pts, up=UP), 4, **kwargs)
    import trimesh

    with pytest.raises(ParameterError, match="step_weight"):
        segment(trimesh.creation.icosphere(2), 4, step_weight=2.0)
    with pytest.raises(ParameterError, match="step_weight weighs steps off a point cloud"):
        segment_tiled(trimesh.creation.icosphere(3), 4, tiles=2, step_weight=2.0)


def _terraces(n: int = 6000, seed: int = 2):
    """Ground and a terrace 0.5 above its east half, about 0.3 apart: a scene."""
    rng = np.random.default_rng(seed)
    xy = rng.random((n, 2)) * [24.0, 12.0]
    z = np.where(xy[:, 0] > 12, 0.5, 0.0) + 0.01 * rng.standard_normal(n)
    return np.c_[xy, z]


def test_a_tile_s_core_gets_one_run_s_neighbours_and_a_tiled_scene_weighs_its_steps():
    """The choice reads a point's 20 nearest and the normal of its 10 nearest: a box with a
    margin gives its core points the whole cloud's neighbours and sizes, so a tiled run of
    a scene reads what one run reads (its step weight 4), with no border disagreement."""
    from superfacets import segment_tiled

    pts = _terraces()
    tree = point_tree(pts)
    whole, kth, _ = P.surface_neighbours(pts, tree, 10, 4.0)
    box = pts[:, 0] < 14  # the west half and a margin of 2 (a few spacings of 0.3)
    core = pts[:, 0] < 12
    part = np.flatnonzero(box)
    nbr, kth_part, _ = P.surface_neighbours(pts[part], point_tree(pts[part]), 10, 4.0)
    inside = core[part]
    np.testing.assert_array_equal(part[nbr[inside]], whole[part[inside]])
    np.testing.assert_array_equal(kth_part[inside], kth[part[inside]])
    scene = PointCloud(pts, up=UP)
    r = segment_tiled(scene, 40, tiles=2, workers=1)
    assert r.params["step_weight"] == 4.0 and r.disagreements == 0
    assert len(np.unique(r.labels)) == 40
    plain = segment_tiled(scene, 40, tiles=2, workers=1, step_weight=1)
    assert plain.params["step_weight"] == 1.0
