"""Pictures of scans a person can read: a tile from above as a map (north up, x to the
right, its aspect kept), an organised frame upright as its sensor saw it, ``--view top``
true to its name whatever the up axis."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import SHARED, need

from superfacets import PointCloud, read_cloud
from superfacets.io.orientation import default_view, image_up, is_map, up_axis
from superfacets.viz.camera import view_frame


def _ink(image: np.ndarray) -> np.ndarray:
    """The pixels that are not the white background."""
    return (image < 235).any(axis=2)


def _box(mask: np.ndarray) -> tuple[int, int, int, int]:
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    return rows[0], rows[-1], cols[0], cols[-1]


def _tile(seed=0) -> PointCloud:
    """A 2:1 airborne tile (200 m east, 100 m north, 6 m of relief), z up as LAS is read."""
    rng = np.random.default_rng(seed)
    p = rng.random((20000, 3)) * (200.0, 100.0, 6.0) + (500000.0, 4000000.0, 50.0)
    return PointCloud(p, up=(0.0, 0.0, 1.0))


def test_view_frame_top_looks_straight_down_the_up_axis_north_up():
    cloud = _tile()
    for up, down, north in (("z", (0, 0, 1), (0, 1, 0)), ("y", (0, 1, 0), (0, 0, -1)),
                            ("-y", (0, -1, 0), (0, 0, 1))):
        d, screen_up = view_frame(_Frame(cloud), "top", up=up)
        assert np.allclose(d, down) and np.allclose(screen_up, north), up
    d, screen_up = view_frame(_Frame(cloud), "front", up="z", elevation=0)
    assert np.allclose(d, (0, -1, 0)) and np.allclose(screen_up, (0, 0, 1))  # from the south


class _Frame:
    """The centroids and areas view_frame reads, of points (each of area 1)."""

    def __init__(self, cloud):
        self.centroids = cloud.points
        self.areas = np.ones(cloud.points.shape[0])
        self.area = float(self.areas.sum())


def test_a_tile_is_drawn_as_a_map_keeping_its_aspect():
    pytest.importorskip("pyvista")
    from superfacets.viz.render import render_points

    cloud = _tile()
    assert is_map(cloud) and default_view(cloud) == "top"
    p = cloud.points
    north_east = (p[:, 0] > 500100) & (p[:, 1] > 4000050)  # a quarter left empty
    cloud = PointCloud(p[~north_east], up=(0.0, 0.0, 1.0))
    image = render_points(cloud, None, size=(800, 800), view=default_view(cloud), up="z")
    ink = _ink(image)
    top, bottom, left, right = _box(ink)
    aspect = (right - left + 1) / (bottom - top + 1)
    assert 1.85 < aspect < 2.15, aspect  # 200 m by 100 m, seen orthographically from above
    mid_row, mid_col = (top + bottom) // 2, (left + right) // 2
    # the empty quarter is the top right one: north up, east to the right
    assert ink[top:mid_row, mid_col:right].mean() < 0.1
    assert min(ink[top:mid_row, left:mid_col].mean(), ink[mid_row:bottom, left:right].mean()) > 0.5


def test_a_terrestrial_or_object_scan_is_no_map():
    rng = np.random.default_rng(1)
    facade = rng.random((3000, 3)) * (30.0, 2.0, 15.0)
    assert not is_map(PointCloud(facade, up=(0, 0, 1)))
    assert default_view(PointCloud(facade)) is None


def test_an_organised_frame_is_upright_whatever_its_declared_orientation():
    rows, cols = np.mgrid[0:40, 0:60]
    # a camera frame (x right, y down, z ahead): a floor below, a wall behind
    pts = np.stack([cols * 0.01, rows * 0.01, 1.0 + rows[::-1] * 0.02], -1).reshape(-1, 3)
    for declared in ((0, -1, 0), (0, 1, 0)):  # (a PCD VIEWPOINT's default quaternion)
        cloud = PointCloud(pts, shape=(40, 60), viewpoint=(0.3, 0.2, 0), up=declared)
        assert image_up(cloud)[1] < -0.9
        assert up_axis(cloud) == ("-y", "the image's")


def test_the_real_rgbd_frames_are_upright():
    for name in ("table_scene_mug_stereo_textured.pcd", "milk_cartoon_all_small_clorox.pcd"):
        path = need(SHARED / "data" / "clouds" / name)
        pytest.importorskip("pypcd4")
        cloud = read_cloud(path)
        # the sensor's image: the rows at its top are further up than those at its bottom
        assert up_axis(cloud)[0] == "-y", name
        d = default_view(cloud)
        assert d is not None and d[2] < -0.9  # seen from the sensor, before the points
