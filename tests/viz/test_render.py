"""Pictures: off-screen PNG, panels, the HTML page (checked in headless Chromium), the CLI."""

from __future__ import annotations

import base64
import json
import re
import shutil
import subprocess

import numpy as np
import pytest
from conftest import grid_mesh
from PIL import Image

from superfacets import ParameterError, superfacets, write_labels, write_mesh
from superfacets.cli import main
from superfacets.elements import face_graph
from superfacets.io.colors import PALETTE, boundary_edges
from superfacets.viz.camera import view_frame
from superfacets.viz.html import html_page, write_html
from superfacets.viz.render import render, render_panel


def _foreground(img: np.ndarray, bg=(255, 255, 255)) -> np.ndarray:
    return np.any(np.abs(img.astype(int) - np.array(bg)) > 30, axis=-1)


def _palette_colours_seen(img: np.ndarray, min_pixels: int = 50) -> int:
    """How many palette colours cover at least ``min_pixels`` pixels (shading allowed)."""
    px = img.reshape(-1, 3).astype(float)
    fg = px[_foreground(img).ravel()]
    # compare chromaticity: shading scales a colour, so normalize by brightness
    pal = PALETTE.astype(float)
    pc = pal / np.maximum(pal.sum(1, keepdims=True), 1)
    fc = fg / np.maximum(fg.sum(1, keepdims=True), 1)
    d = np.linalg.norm(fc[:, None, :] - pc[None, :, :], axis=2)
    best = d.argmin(1)[d.min(1) < 0.02]
    return int((np.bincount(best, minlength=len(pal)) >= min_pixels).sum())


def test_render_draws_several_superfacet_colours(sphere, tmp_path):
    labels = superfacets(sphere, 12)
    out = tmp_path / "s.png"
    img = render(sphere, labels, out, size=(320, 240))
    assert img.shape == (240, 320, 3) and img.dtype == np.uint8
    saved = np.asarray(Image.open(out).convert("RGB"))
    assert np.array_equal(saved, img)
    fg = _foreground(img)
    assert 0.1 < fg.mean() < 0.9  # the sphere fills part of the frame, not all
    assert _palette_colours_seen(img) >= 4
    # boundaries: where the picture differs from the one without them, it is dark lines
    plain = render(sphere, labels, size=(320, 240), boundaries=False)
    lines = np.any(np.abs(img.astype(int) - plain.astype(int)) > 60, axis=-1)
    assert lines.sum() > 100
    with_lines = np.median(img[lines].astype(int).sum(-1))
    without = np.median(plain[lines].astype(int).sum(-1))
    assert with_lines < 0.6 * without
    # grey when no labels
    grey = render(sphere, None, size=(320, 240), background="black")
    assert _foreground(grey, bg=(0, 0, 0)).mean() > 0.1 and _palette_colours_seen(grey) == 0


def test_render_rejects_bad_input(sphere):
    with pytest.raises(ParameterError, match="one per face"):
        render(sphere, np.zeros(3, np.int64))
    with pytest.raises(ParameterError, match="size"):
        render(sphere, None, size=(5, 5))
    with pytest.raises(ParameterError, match="unknown view"):
        render(sphere, None, view="sideways")


def test_panel_places_panels_side_by_side(sphere):
    a, b = superfacets(sphere, 6), superfacets(sphere, 30)
    img = render_panel([(sphere, a, "six"), (sphere, b, "thirty")], size=(200, 180))
    assert img.shape == (180, 400, 3)
    for half in (img[:, :200], img[:, 200:]):
        assert _foreground(half).mean() > 0.1
    with pytest.raises(ParameterError, match="no panel"):
        render_panel([])


def test_view_frame_looks_along_the_thinnest_axis():
    slab = grid_mesh(10, 10)  # flat in z
    d, up = view_frame(slab, elevation=0)
    assert abs(d[2]) == pytest.approx(1.0) and up @ d == pytest.approx(0.0, abs=1e-12)
    assert up[1] == pytest.approx(1.0)
    d, up = view_frame(slab, "top", elevation=0)  # along the up axis: another up is chosen
    assert d[1] == pytest.approx(1.0) and abs(up @ d) < 1e-12
    d, up = view_frame(slab, (1, 1, 0), up="z")
    assert np.allclose(d, np.array([1, 1, 0]) / np.sqrt(2)) and up[2] == pytest.approx(1.0)
    with pytest.raises(ValueError, match="up axis"):
        view_frame(slab, up="w")


def test_boundary_edges_of_a_straight_cut():
    m = grid_mesh(8, 6)
    labels = (m.centroids[:, 0] > 0).astype(np.int64)
    e = boundary_edges(m, labels)
    assert e.shape == (6, 2)  # one grid edge per row along x = 0
    assert np.allclose(m.vertices[e.ravel(), 0], 0.0)


def _decode(page: str, name: str, dtype) -> np.ndarray:
    blob = re.search(f'id="{name}">([^<]*)<', page).group(1)
    return np.frombuffer(base64.b64decode(blob), dtype=dtype)


def test_html_page_is_self_contained_and_holds_the_mesh(sphere):
    labels = superfacets(sphere, 12)
    page = html_page(sphere, labels, title="ball", info={"alpha": 200})
    # nothing fetched from anywhere: no src/href attributes, no URLs
    assert not re.search(r"\b(src|href)\s*=", page) and "http" not in page
    meta = json.loads(re.search(r'id="meta">(.*?)</script>', page, re.S).group(1))
    assert meta["name"] == "ball" and meta["faces"] == sphere.n_faces and meta["superfacets"] == 12
    assert meta["info"] == {"alpha": "200"}
    v = _decode(page, "vertices", "<f4").reshape(-1, 3)
    f = _decode(page, "faces", "<u4").reshape(-1, 3)
    c = _decode(page, "colors", np.uint8)
    assert f.shape == sphere.faces.shape and c.shape == (sphere.n_faces,)
    assert np.abs(v).max() <= 1.0 + 1e-6  # unit ball
    # same geometry up to the centring and scaling
    src = sphere.vertices[sphere.faces]
    got = v[f]
    scale = np.ptp(src) / np.ptp(got)
    assert np.allclose((got - got.mean((0, 1))) * scale, src - src.mean((0, 1)), atol=1e-5)
    # one colour per superfacet, adjacent superfacets different
    pal = np.array(meta["palette"])[c]
    per_sf = {int(s): {tuple(x) for x in pal[labels == s]} for s in range(12)}
    assert all(len(v_) == 1 for v_ in per_sf.values())
    g = face_graph(sphere).pairs
    diff = labels[g[:, 0]] != labels[g[:, 1]]
    assert np.all(np.any(pal[g[diff, 0]] != pal[g[diff, 1]], axis=1))
    with pytest.raises(ParameterError, match="one per face"):
        html_page(sphere, labels[:-1])


def _chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.skip("chromium not found: install Debian's 'chromium' package "
                    "(.ci/run does: apt-get install chromium)")
    return exe


def _screenshot(page, tmp_path) -> np.ndarray:
    """A 640x480 screenshot of ``page`` in headless Chromium (skips without Chromium)."""
    exe = _chromium()
    shot = tmp_path / "shot.png"
    cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           f"--user-data-dir={tmp_path / 'profile'}", "--use-angle=swiftshader",
           "--enable-unsafe-swiftshader", "--window-size=640,480",
           "--virtual-time-budget=10000", f"--screenshot={shot}", page.as_uri()]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert shot.exists(), proc.stderr[-2000:]
    img = np.asarray(Image.open(shot).convert("RGB"))
    return img


def test_html_page_draws_the_mesh_in_headless_chromium(sphere, tmp_path):
    labels = superfacets(sphere, 12)
    page = write_html(tmp_path / "ball.html", sphere, labels, title="ball")
    img = _screenshot(page, tmp_path)
    assert img.shape == (480, 640, 3)
    centre = img[160:320, 240:400]
    assert _foreground(centre).mean() > 0.9, "the mesh is not drawn"
    assert _palette_colours_seen(img, min_pixels=30) >= 4


def test_cli_render_panel_html_and_view(tmp_path, sphere, capsys, monkeypatch):
    mesh = tmp_path / "ball.off"
    write_mesh(mesh, sphere)
    seg = tmp_path / "ball.seg"
    write_labels(seg, superfacets(sphere, 10))
    png = tmp_path / "a.png"
    assert main(["render", str(mesh), str(seg), "-o", str(png), "--size", "300x200",
                 "--view", "front"]) == 0
    assert np.asarray(Image.open(png)).shape[:2] == (200, 300)
    assert main(["render", str(mesh), "-o", str(png), "-k", "8", "--alpha", "0", "-q"]) == 0
    assert _palette_colours_seen(np.asarray(Image.open(png).convert("RGB"))) >= 3
    pan = tmp_path / "p.png"
    assert main(["panel", str(mesh), "-o", str(pan), "--alpha", "0", "500", "-k", "6", "12",
                 "--size", "160x120"]) == 0
    assert np.asarray(Image.open(pan)).shape[:2] == (120, 640)  # 4 panels in one row
    # method-scoped parameters: superfacets once, vsa for each metric (the paper's Fig. 8)
    assert main(["panel", str(mesh), "-o", str(pan), "-m", "superfacets", "vsa", "-k", "6",
                 "--param", "vsa.metric=l21,l2", "--size", "100x90"]) == 0
    assert np.asarray(Image.open(pan)).shape[:2] == (90, 300)
    assert "3 panels" in capsys.readouterr().out
    assert main(["panel", str(mesh), "-o", str(pan), "-m", "vsa", "--param", "window=2"]) == 2
    assert "--param window: no method given has it" in capsys.readouterr().err
    page = tmp_path / "b.html"
    assert main(["html", str(mesh), "-o", str(page), "-k", "9"]) == 0
    assert '"superfacets": 9' in page.read_text()
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["view", str(mesh)]) == 2
    assert main(["render", str(mesh), "-o", str(tmp_path / "x.jpg")]) == 2
    assert main(["html", str(mesh), str(tmp_path / "missing.seg"), "-o", str(page)]) == 2
    err = capsys.readouterr().err
    assert "no display available" in err and "must end in .png" in err and "missing.seg" in err


def _sphere_cloud(n=3000):
    x = np.random.default_rng(0).normal(size=(n, 3))
    return x / np.linalg.norm(x, axis=1, keepdims=True)


def test_render_points_colours_a_cloud_by_superpoint(tmp_path):
    from superfacets import superpoints
    from superfacets.viz.render import render_points

    pts = _sphere_cloud()
    labels = superpoints(pts, 12)
    img = render_points(pts, labels, tmp_path / "c.png", size=(320, 240))
    assert img.shape == (240, 320, 3) and (tmp_path / "c.png").exists()
    assert _foreground(img[80:160, 120:200]).mean() > 0.9, "the points are not drawn"
    assert _palette_colours_seen(img, min_pixels=30) >= 4
    with pytest.raises(ParameterError, match="one per point"):
        render_points(pts, labels[:-1])
    # render() of a cloud draws it as render_points does (a TypeError naming the
    # PointCloud it was given before)
    from superfacets import PointCloud
    from superfacets.viz.render import render

    assert np.array_equal(render(PointCloud(pts), labels, size=(320, 240)), img)



def test_a_picture_of_classes_names_them_beside_their_colours(tmp_path, capsys):
    """Classes with names (a LAS file's ASPRS classes) get a legend of swatches in the
    classes' own colours and their names, not the superpoints' sizes; ``render
    --labels-from classification`` draws it."""
    from superfacets.viz.render import render_points

    rng = np.random.default_rng(2)
    xy = rng.random((4000, 2)) * [40.0, 20.0]
    pts = np.c_[xy, np.where(xy[:, 0] > 20, 3.0, 0.0)]
    classes = np.where(xy[:, 0] > 20, 6, 2)
    kw = dict(size=(640, 480), view="top", up="z")
    plain = render_points(pts, classes, legend=False, **kw)
    named = render_points(pts, classes, legend=True, class_names={2: "ground", 6: "building"},
                          **kw)
    sized = render_points(pts, classes, legend=True, **kw)
    drawn = plain.reshape(-1, 3)
    colours, counts = np.unique(drawn[(drawn < 250).any(axis=1)], axis=0, return_counts=True)
    top2 = colours[np.argsort(-counts)[:2]]  # (the two classes' colours)
    legend = named[(named != plain).any(axis=-1)]
    assert all((legend == c).all(axis=1).sum() > 20 for c in top2)  # (a swatch each)
    assert not np.array_equal(named, sized)
    laspy = pytest.importorskip("laspy")
    las = laspy.LasData(laspy.LasHeader(point_format=3, version="1.2"))
    las.x, las.y, las.z = pts.T
    las.classification = classes.astype(np.uint8)
    las.write(tmp_path / "tile.las")
    assert main(["render", str(tmp_path / "tile.las"), "--labels-from", "classification",
                 "-o", str(tmp_path / "c.png"), "--size", "640x480"]) == 0
    assert (tmp_path / "c.png").is_file()
    # the page: counted as classes, each named beside its colour (in the browser's DOM)
    assert main(["html", str(tmp_path / "tile.las"), "--labels-from", "classification",
                 "-o", str(tmp_path / "c.html")]) == 0
    meta = json.loads(re.search(r'id="meta"[^>]*>(.*?)</script>',
                                (tmp_path / "c.html").read_text(), re.S).group(1))
    assert meta["word"] == "classes" and sorted(t for t, _ in meta["legend"]) == [
        "2 ground", "6 building"]
    assert "legend" not in json.loads(re.search(r'id="meta"[^>]*>(.*?)</script>', html_page(
        pts, classes), re.S).group(1))  # (labels with no names: superpoints, as before)
    exe = _chromium()
    dom = subprocess.run([exe, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                          f"--user-data-dir={tmp_path / 'profile-dom'}",
                          "--virtual-time-budget=5000", "--dump-dom",
                          (tmp_path / "c.html").as_uri()],
                         capture_output=True, text=True, timeout=120).stdout
    assert re.search(r"[\d,]+ points, 2 classes", dom) and "</span>2 ground</div>" in dom, \
        re.search(r'<div id="info">.{0,300}', dom, re.S)


def test_cli_panel_draws_a_cloud_at_several_counts_and_from_label_files(tmp_path, capsys):
    """``panel`` read meshes only ("unknown mesh format .npy"): a cloud's panels are its
    points coloured by superpoint, for the methods that segment points (graph segmentation
    here); one that does not (VSA) is refused in one line naming those that do; a
    tetrahedral mesh is drawn from its label files."""
    from superfacets import superpoints

    pts = _sphere_cloud(2000)
    np.save(tmp_path / "c.npy", pts)
    write_labels(tmp_path / "c.seg", superpoints(pts, 9))
    pan = tmp_path / "p.png"
    assert main(["panel", str(tmp_path / "c.npy"), "-o", str(pan), "-k", "6", "12",
                 "-m", "superfacets", "graph_segmentation", "--size", "160x120"]) == 0
    img = np.asarray(Image.open(pan).convert("RGB"))
    assert img.shape[:2] == (120, 640) and "4 panels" in capsys.readouterr().out
    for i in range(4):  # every panel shows its points, in several colours
        one = img[:, 160 * i:160 * (i + 1)]
        assert _foreground(one[40:90, 50:110]).mean() > 0.8, i
        assert _palette_colours_seen(one, min_pixels=10) >= 3, i
    assert main(["panel", str(tmp_path / "c.npy"), "--labels", str(tmp_path / "c.seg"),
                 "-o", str(pan), "--size", "160x120"]) == 0
    assert "1 panel," in capsys.readouterr().out
    assert main(["panel", str(tmp_path / "c.npy"), "-m", "vsa", "-o", str(pan)]) == 2
    assert "vsa segments faces, not points; methods that segment points: superfacets" in \
        capsys.readouterr().err
    meshio = pytest.importorskip("meshio")
    from scipy.spatial import Delaunay

    ball = np.random.default_rng(2).random((300, 3))
    meshio.write(tmp_path / "v.vtu", meshio.Mesh(ball, [("tetra", Delaunay(ball).simplices)]))
    assert main(["segment", str(tmp_path / "v.vtu"), "-k", "6", "-o",
                 str(tmp_path / "v.seg")]) == 0
    assert main(["panel", str(tmp_path / "v.vtu"), "--labels", str(tmp_path / "v.seg"),
                 "-o", str(pan), "--size", "160x120"]) == 0
    capsys.readouterr()
    assert main(["panel", str(tmp_path / "v.vtu"), "-k", "3", "6", "-o", str(pan), "--size",
                 "160x120"]) == 0  # the method on the tetrahedra
    assert "2 panels" in capsys.readouterr().out
    assert main(["panel", str(tmp_path / "v.vtu"), "-m", "vsa", "-o", str(pan)]) == 2
    assert "vsa segments faces, not cells; methods that segment cells: superfacets" in \
        capsys.readouterr().err


def test_html_page_draws_a_point_cloud_in_headless_chromium(tmp_path):
    from superfacets import superpoints

    pts = _sphere_cloud(20000)
    labels = superpoints(pts, 15)
    page = write_html(tmp_path / "cloud.html", pts, labels, title="cloud")
    meta = json.loads(re.search(r'id="meta"[^>]*>(.*?)</script>', page.read_text(), re.S)
                      .group(1))
    assert meta["points"] == 20000 and meta["superfacets"] == 15 and meta["nFaces"] == 0
    img = _screenshot(page, tmp_path)
    assert _foreground(img[200:280, 280:360]).mean() > 0.5, "the points are not drawn"
    assert _palette_colours_seen(img, min_pixels=30) >= 4


def test_a_page_of_a_large_cloud_draws_an_even_share_of_its_points(tmp_path, monkeypatch,
                                                                    capsys):
    from superfacets import superpoints
    from superfacets.viz import html as pages

    monkeypatch.setattr(pages, "MAX_PAGE_POINTS", 5000)  # (2M: a 10M-point page was 173 MB)
    pts = _sphere_cloud(20000)
    labels = superpoints(pts, 15)
    page = pages.write_html(tmp_path / "cloud.html", pts, labels, title="cloud")
    text = page.read_text()
    meta = json.loads(re.search(r'id="meta"[^>]*>(.*?)</script>', text, re.S).group(1))
    assert meta["points"] == meta["nVertices"] == 5000 and meta["superfacets"] == 15
    assert meta["info"]["drawn"] == "5,000 of 20,000 points (an even share)"
    assert _decode(text, "vertices", "<f4").size == 3 * 5000
    img = _screenshot(page, tmp_path)  # (each point drawn four times as large: a surface)
    assert _foreground(img[200:280, 280:360]).mean() > 0.5, "the points are not drawn"
    np.save(tmp_path / "c.npy", pts)
    assert main(["html", str(tmp_path / "c.npy"), "-k", "15", "-o",
                 str(tmp_path / "c.html")]) == 0
    assert "5,000 of 20,000 points drawn: a page of all would not open" in \
        capsys.readouterr().out


def test_cli_segment_pictures_a_cloud(tmp_path):
    pts = _sphere_cloud(2000)
    np.save(tmp_path / "c.npy", pts)
    png, page = tmp_path / "c.png", tmp_path / "c.html"
    assert main(["segment", str(tmp_path / "c.npy"), "-k", "10", "--picture", str(png),
                 "--html", str(page), "-q"]) == 0
    assert _palette_colours_seen(np.asarray(Image.open(png).convert("RGB"))) >= 3
    assert '"points": 2000' in page.read_text()
    assert main(["segment", str(tmp_path / "c.npy"), "--picture", str(page)]) == 2


def test_vertex_regions_cut_each_triangle_at_its_corners(sphere):
    from superfacets.elements.vertices import vertex_graph
    from superfacets.viz.render import vertex_regions

    labels = np.arange(sphere.n_vertices) % 7
    regions, lab = vertex_regions(sphere, labels)
    assert regions.n_faces == 3 * sphere.n_faces and regions.is_triangular is False
    assert regions.area == pytest.approx(sphere.area)
    # each vertex's regions hold the area its vertex element stands for
    g, index = vertex_graph(sphere)
    owner = np.concatenate([sphere.faces[:, i] for i in range(3)])
    per_vertex = np.bincount(owner, weights=regions.areas, minlength=sphere.n_vertices)
    np.testing.assert_allclose(per_vertex, g.sizes[index], rtol=1e-9)
    np.testing.assert_array_equal(lab, labels[owner])
    # midpoints are shared: the regions of one mesh form one closed surface
    assert face_graph(regions).boundary_elements.size == 0
    with pytest.raises(ParameterError, match="vertex"):
        vertex_regions(sphere, labels[:-1])


def test_vertex_labels_render_like_superfacets(sphere, tmp_path):
    pytest.importorskip("pyvista")
    from superfacets import segment

    r = segment(sphere, 12, elements="vertices")
    img = render(sphere, r.labels, tmp_path / "v.png", size=(300, 240), elements="vertices")
    assert _palette_colours_seen(img) >= 5
    with pytest.raises(ParameterError, match="elements"):
        render(sphere, r.labels, elements="points")
    page = html_page(sphere, r.labels, elements="vertices")
    assert '"superfacets": 12' in page


def test_render_and_html_read_vertex_label_files(sphere, tmp_path, capsys):
    pytest.importorskip("pyvista")
    from superfacets import segment

    off = write_mesh(tmp_path / "s.off", sphere)
    seg = write_labels(tmp_path / "v.seg", segment(sphere, 12, elements="vertices").labels)
    assert main(["render", str(off), str(seg), "-o", str(tmp_path / "v.png"), "--size",
                 "200x160"]) == 0
    assert f"{sphere.n_vertices:,} vertices," in capsys.readouterr().out  # ("vertexs")
    assert main(["html", str(off), str(seg), "-o", str(tmp_path / "v.html")]) == 0
    short = write_labels(tmp_path / "short.seg", np.zeros(5, dtype=int))
    assert main(["render", str(off), str(short), "-o", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert "one label per face or per vertex" in err
    assert f"{sphere.n_faces:,} faces and {sphere.n_vertices:,} vertices" in err
    assert not (tmp_path / "x.png").exists()


HOSTILE = ('x%BLOBS%%META%%TITLE%</script><script>document.documentElement.setAttribute('
           '"data-pwned","1")</script><!--<script>Tür "q" &amp;')


def test_hostile_names_stay_text_in_the_page(sphere, tmp_path):
    """A file name holding the template's placeholders, a closing script tag or a comment
    opener is text: one pass fills the template, each value escaped for its place."""
    import json
    import re

    from superfacets.viz.html import html_page

    labels = superfacets(sphere, 8)
    page = html_page(sphere, labels, title=HOSTILE, info={HOSTILE: HOSTILE})
    plain = html_page(sphere, labels, title="plain")
    assert page.count("<script") == plain.count("<script")  # no element was opened
    assert page.count("</script>") == plain.count("</script>")
    assert "<!--" not in page.split("<title>")[1]
    meta = json.loads(re.search(r'<script type="application/json" id="meta">(.*?)</script>',
                                page, re.S).group(1))
    assert meta["name"] == HOSTILE and meta["info"] == {HOSTILE: HOSTILE}
    with pytest.raises(ParameterError, match="background must be a CSS colour"):
        html_page(sphere, labels, background="red;}</style><script>alert(1)</script>")


def test_a_hostile_name_runs_no_script_in_a_browser(sphere, tmp_path):
    labels = superfacets(sphere, 12)
    page = write_html(tmp_path / "hostile.html", sphere, labels, title=HOSTILE)
    exe = _chromium()
    dom = subprocess.run([exe, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                          f"--user-data-dir={tmp_path / 'profile-dom'}",
                          "--virtual-time-budget=5000", "--dump-dom", page.as_uri()],
                         capture_output=True, text=True, timeout=120).stdout
    assert "<html" in dom and 'data-pwned="1"' not in dom  # the attribute was never set
    img = _screenshot(page, tmp_path)  # and the viewer still draws the mesh
    assert _foreground(img[160:320, 240:400]).mean() > 0.9


def test_the_notebook_view_is_the_page_inline():
    """A notebook shows ``_repr_html_``: the same self-contained page (drawn in Chromium
    above) in an isolated iframe whose scripts run (the notebook's own are untouched)."""
    import html

    from superfacets import segment, superpoints
    from superfacets.viz.html import NotebookView

    pts = _sphere_cloud(8000)
    result = segment(pts, 15)
    view = NotebookView(result, height=460)
    inline = view._repr_html_()
    assert inline.startswith("<iframe srcdoc=\"") and 'sandbox="allow-scripts"' in inline
    assert "height: 460px" in inline and inline.count("<") == 2  # the page is escaped
    srcdoc = html.unescape(re.search(r'srcdoc="([^"]*)"', inline).group(1))
    assert srcdoc == view.html() and srcdoc.startswith("<!DOCTYPE html>")
    meta = json.loads(re.search(r'id="meta"[^>]*>(.*?)</script>', srcdoc, re.S).group(1))
    assert meta["points"] == 8000 and meta["superfacets"] == 15
    assert np.array_equal(result.labels, superpoints(pts, 15))
    grey = NotebookView(pts).html()  # an input without labels: drawn grey
    assert json.loads(re.search(r'id="meta"[^>]*>(.*?)</script>', grey, re.S)
                      .group(1))["superfacets"] == 0


def test_a_notebook_view_reads_a_file_and_names_what_a_tiled_result_lacks(tmp_path):
    """``NotebookView(segment_tiled(...))`` said "mesh must be a superfacets.Mesh, ...,
    got TiledResult"; a tiled run's labels are drawn on its input, which may be a path."""
    from superfacets import segment_tiled
    from superfacets.viz.html import NotebookView

    pts = _sphere_cloud(3000)
    np.save(tmp_path / "c.npy", pts)
    tiled = segment_tiled(str(tmp_path / "c.npy"), 12, tiles=2, workers=1)
    with pytest.raises(ParameterError, match="NotebookView\\(path_or_cloud, result.labels\\)"):
        NotebookView(tiled)
    page = NotebookView(tmp_path / "c.npy", tiled.labels).html()
    meta = json.loads(re.search(r'id="meta"[^>]*>(.*?)</script>', page, re.S).group(1))
    assert meta["points"] == 3000 and meta["superfacets"] == 12


def test_a_notebook_view_draws_a_volume_cut_as_the_html_command_does(tmp_path):
    """``NotebookView(volume_result)`` said "mesh must be a superfacets.Mesh, ..., got
    TetMesh" (``superfacets html VOLUME`` drew its cut): the cut at the middle of x, each
    triangle its tetrahedron's label, from a result, a volume and labels, or a file;
    labels not one per tetrahedron are one line, not numpy's IndexError."""
    from scipy.spatial import Delaunay

    from superfacets import TetMesh, segment, write_volume_labels
    from superfacets.inputs.tetmesh import cut_surface
    from superfacets.viz.html import NotebookView, html_page

    p = np.random.default_rng(0).random((300, 3))
    vol = TetMesh(p, Delaunay(p).simplices)
    result = segment(vol, 9)
    surface, face_labels = cut_surface(vol, result.labels, axis=0, at=0.5)
    want = html_page(surface, face_labels, elements="faces", title="cut at the middle of x")
    write_volume_labels(tmp_path / "v.vtu", vol, result.labels)
    for view in (NotebookView(result), NotebookView(vol, result.labels),
                 NotebookView(tmp_path / "v.vtu", result.labels)):
        assert view.html() == want
    meta = json.loads(re.search(r'id="meta"[^>]*>(.*?)</script>', want, re.S).group(1))
    assert meta["superfacets"] == len(np.unique(face_labels)) > 1
    with pytest.raises(ParameterError, match="one integer per tetrahedron"):
        NotebookView(vol, result.labels[:5])


def test_the_picture_says_how_many_segments_and_how_even_they_are(tmp_path, sphere):
    """``render`` (and ``segment --picture``) draw the count and the sizes in the lower left
    corner (or the corner where they hide the fewest drawn pixels): the only pixels that
    differ from ``--no-legend``; a small picture has none."""
    from superfacets.viz.render import size_legend

    blank = np.full((400, 640, 3), 255, dtype=np.uint8)
    drawn = size_legend(blank, np.repeat(np.arange(20), np.arange(1, 21)), "superpoints",
                        "points")
    changed = np.argwhere((drawn != 255).any(-1))
    assert changed[:, 0].min() > 200 and changed[:, 1].max() < 400  # lower left only
    busy = blank.copy()  # (something drawn in the lower left: the legend goes where
    busy[250:, :300] = (200, 30, 30)  # it hides nothing, the lower right)
    moved = np.argwhere((size_legend(busy, np.repeat(np.arange(20), np.arange(1, 21)),
                                     "superpoints", "points") != busy).any(-1))
    assert moved[:, 0].min() > 200 and moved[:, 1].min() >= 300
    assert (size_legend(blank, -np.ones(30, int)) == blank).all()  # no labelled element
    assert (size_legend(blank[:150], np.zeros(30, int)) == blank[:150]).all()  # too small
    mesh = tmp_path / "ball.off"
    write_mesh(mesh, sphere)
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    assert main(["render", str(mesh), "-o", str(a), "-k", "8", "--size", "640x480", "-q"]) == 0
    assert main(["render", str(mesh), "-o", str(b), "-k", "8", "--size", "640x480", "-q",
                 "--no-legend"]) == 0
    differ = np.argwhere((np.asarray(Image.open(a).convert("RGB")).astype(int)
                          != np.asarray(Image.open(b).convert("RGB")).astype(int)).any(-1))
    assert differ.size and differ[:, 0].min() > 240  # (a lower corner: the sphere is in
    assert differ[:, 1].max() < 480 or differ[:, 1].min() > 160  # the middle)
    assert main(["segment", str(mesh), "-k", "8", "--picture", str(a), "-q"]) == 0
    shown = np.asarray(Image.open(a).convert("RGB"))
    assert (shown[-60:, :200] != 255).any() or (shown[-60:, -200:] != 255).any()


def test_a_picture_of_a_large_cloud_draws_an_even_share_and_sizes_every_label(
        tmp_path, monkeypatch):
    """A picture draws at most its pixels' worth of points (10M points cost the point graph
    of all of them for a picture no better): an even random share of the valid points,
    the same each time, while its legend counts every point's label."""
    from superfacets import PointCloud
    from superfacets.viz import render as rendering
    from superfacets.viz.render import drawn_share, render_points

    pts = _sphere_cloud(4000)
    pts[::7] = np.nan  # invalid points are never drawn
    labels = (np.arange(4000) % 40).astype(np.int64)
    labels[::7] = -1
    cloud = PointCloud(pts, allow_invalid=True, up=np.array([0.0, 0.0, 1.0]))
    share, drawn, n = drawn_share(cloud, labels, 600)
    assert n == share.n_points == 600 and drawn.shape == (600,)
    rows = np.flatnonzero(np.isin(pts[:, 0], share.points[:, 0]))
    assert rows.size == 600 and np.isfinite(pts[rows]).all()
    assert np.array_equal(share.points, pts[rows]) and np.array_equal(drawn, labels[rows])
    assert np.array_equal(share.up, cloud.up)
    assert np.array_equal(drawn_share(cloud, labels, 600)[0].points, share.points)
    assert drawn_share(cloud, labels, 4000)[0] is cloud  # (under the limit: all of it)
    with pytest.raises(ParameterError, match="one per point"):
        drawn_share(cloud, labels[:-1], 600)

    seen = {}
    real = rendering.size_legend

    def legend(img, lab, *args):
        seen["labels"] = lab
        return real(img, lab, *args)

    monkeypatch.setattr(rendering, "size_legend", legend)
    img = render_points(cloud, labels, tmp_path / "s.png", size=(320, 240), legend=True,
                        max_points=500)
    assert _foreground(img).mean() > 0.05
    assert seen["labels"] is labels  # (the legend counts all 3,428 labelled points)


def test_view_draws_an_even_share_of_a_large_cloud(monkeypatch, tmp_path, capsys):
    """The window draws at most VIEW_POINTS of a cloud (the point graph of 50 million
    took minutes before a window opened), and the command says so; a window stood in for
    by an off-screen plotter."""
    import types

    pv = pytest.importorskip("pyvista")
    from superfacets.viz import render as render_module

    drawn = []

    class Plotter(pv.Plotter):
        def __init__(self, **kw):
            super().__init__(off_screen=True, window_size=(300, 200), **kw)

        def add_mesh(self, poly, **kw):
            drawn.append(poly.n_points)
            return super().add_mesh(poly, **kw)

        def show(self, *args, **kw):
            drawn.append("shown")

    monkeypatch.setattr(render_module, "has_display", lambda: True)
    monkeypatch.setattr(render_module, "_pyvista", lambda off_screen: types.SimpleNamespace(
        Plotter=Plotter, PolyData=pv.PolyData))
    xyz = np.c_[np.random.default_rng(0).random((5000, 2)), np.zeros(5000)]
    render_module.show(xyz, np.arange(5000) // 500, max_points=1000)
    assert drawn == [1000, "shown"]
    drawn.clear()
    render_module.show(xyz, np.arange(5000) // 500, max_points=None)  # (all of them)
    assert drawn == [5000, "shown"]
    drawn.clear()
    monkeypatch.setattr(render_module, "VIEW_POINTS", 2000)
    np.save(tmp_path / "cloud.npy", xyz)
    assert main(["view", str(tmp_path / "cloud.npy"), "-k", "5"]) == 0
    assert drawn == [2000, "shown"]
    assert "drawing 2,000 of 5,000 points (an even share" in capsys.readouterr().err
