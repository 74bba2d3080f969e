"""One table of element kinds (superfacets.elements.kinds): every rule that differs by kind
is read from it, no module branches on a kind's name, and a new kind is one builder and
one row."""

from __future__ import annotations

import ast
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import trimesh

from superfacets import segment
from superfacets.elements import kinds
from superfacets.elements.builders import BUILDERS, Builder, elements_of, kind_for
from superfacets.elements.kinds import KINDS, kind_of
from superfacets.errors import ParameterError

SRC = Path(__file__).resolve().parents[2] / "src" / "superfacets"

#: Where a kind's name may be compared, and why: the table itself and the builders
#: (which decide what the elements of an input are); code that reads and writes files,
#: whose ``kind`` is the layout of a file (faces with their vertices, or points); the
#: command line's wording; a mesh's own per-face and per-vertex arrays and the pictures
#: that draw either; the benchmark's per-face ground truth carried to each kind.
ALLOWED = {
    "elements/": "the table and the builders",
    "io/": "file layouts",
    "cli/": "the command line's wording",
}


def _is_kind_literal(node) -> bool:
    if isinstance(node, ast.Constant):
        return node.value in KINDS
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return bool(node.elts) and all(_is_kind_literal(e) for e in node.elts)
    return False


def _branches(path: Path) -> list[str]:
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Compare) and any(
                _is_kind_literal(x) for x in [node.left, *node.comparators]):
            out.append(f"{path.relative_to(SRC)}:{node.lineno}")
        if isinstance(node, ast.Dict) and len(node.keys) > 1 and all(
                k is not None and _is_kind_literal(k) for k in node.keys):
            out.append(f"{path.relative_to(SRC)}:{node.lineno} (a dict by kind)")
    return out


def test_no_module_branches_on_a_kind_name_outside_the_table():
    found = []
    for path in sorted(SRC.rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        if rel.startswith(tuple(ALLOWED)):
            continue
        found += _branches(path)
    assert not found, "rules by kind belong in superfacets.elements.kinds:\n" + "\n".join(found)


def test_the_scan_finds_a_branch():
    tree = "def f(g):\n    return 0.1 if g.kind == 'faces' else 1.0\n"
    path = SRC / "_probe_for_the_test.py"
    try:
        path.write_text(tree)
        assert _branches(path) == ["_probe_for_the_test.py:2"]
    finally:
        path.unlink()


def test_every_kind_has_a_builder_and_a_row():
    assert set(BUILDERS) == set(KINDS) == {"faces", "vertices", "points", "cells"}
    assert all(getattr(k, "singular") and k.dim in (2, 3) for k in KINDS.values())


def test_the_rules_read_the_table():
    from superfacets.method.cleanup import BAND, BAND_VERTICES, CREASE, SMOOTHNESS_FACES
    from superfacets.method.coarse_to_fine import coarse_ratio
    from superfacets.method.params import DEFAULTS, assignment_of, better_method
    from superfacets.method.splitmerge import HOLD_AFTER_FACES, SWAP_ETA_CONVEX_FACES

    assert (CREASE, SMOOTHNESS_FACES, BAND, SWAP_ETA_CONVEX_FACES, HOLD_AFTER_FACES) == (
        KINDS["faces"].crease, KINDS["faces"].smoothness, KINDS["faces"].band,
        KINDS["faces"].swap_eta_convex, KINDS["faces"].hold_after)
    assert BAND_VERTICES == KINDS["vertices"].band
    for name, k in KINDS.items():
        assert better_method(DEFAULTS, name) == (k.better_method, k.better_method)
        assert (assignment_of(DEFAULTS, name) == "exact") == k.exact_assignment
        per = k.coarse_min_per_segment
        assert coarse_ratio(per * 10 - 10, 10, name) == 1
        assert coarse_ratio(per * 10, 10, name) > 1 or k.coarse_neighbor_cap
    assert [n for n, k in KINDS.items() if k.better_method] == ["faces", "vertices"]


def test_the_superfacet_size_of_a_volume_is_a_ball():
    """Tetrahedra: r of a ball of volume V / k, in the run and in the coarse-to-fine
    estimate of k from a radius (which used a disc's area)."""
    from superfacets.method.params import resolve, superfacet_measure, superfacet_size

    k, r = superfacet_size(resolve(n_segments=10), 1.0, 2.0, 1000, "cells")
    assert superfacet_measure(r, 3) == pytest.approx(0.1)
    k, r = superfacet_size(resolve(radius=0.25, init="farthest"), 1.0, 2.0, 1000, "cells")
    assert (k, r) == (round(1.0 / superfacet_measure(0.5, 3)), 0.5)


def test_kind_for_and_its_errors():
    box = trimesh.creation.box()
    assert kind_for(box) == "faces" and kind_for(box, "vertices") == "vertices"
    assert kind_for(np.random.default_rng(0).random((20, 3))) == "points"
    with pytest.raises(ParameterError, match="elements='points' needs a point cloud"):
        kind_for(box, "points")
    with pytest.raises(ParameterError, match="elements='faces' needs a mesh"):
        kind_for(np.zeros((5, 3)), "faces")
    with pytest.raises(ParameterError, match="elements='cells' needs a tetrahedral mesh"):
        kind_for(box, "cells")
    with pytest.raises(ParameterError, match="elements must be one of"):
        kind_for(box, "edges")
    with pytest.raises(ValueError, match="unknown kind of element 'edges'"):
        kind_of("edges")


def test_a_new_kind_is_one_builder_and_one_row(monkeypatch):
    """A kind made of a row and a builder runs the whole method: here the faces again
    under another name, with the vertices' rules (exact classification, band 0.2)."""
    row = replace(KINDS["vertices"], name="facets", singular="facet", rows="n_faces")
    monkeypatch.setitem(KINDS, "facets", row)

    faces = BUILDERS["faces"]

    def build(mesh, n_neighbors, neighbor_radius):
        src = faces.build(mesh, n_neighbors, neighbor_radius)
        return src._replace(graph=replace(src.graph, kind="facets"))

    monkeypatch.setitem(BUILDERS, "facets", Builder(faces.accepts, False, faces.prepare,
                                                    faces.count, build, "a mesh"))
    mesh = trimesh.creation.icosphere(subdivisions=3)
    src = elements_of(mesh, "facets")
    assert src.graph.kind == "facets" and src.graph.element == "facet"
    r = segment(src.source, 12, elements="facets")
    assert r.params["elements"] == "facets" and r.params["assignment"] == "exact"
    assert r.n_segments == 12 and r.labels.shape == (1280,)
    assert kinds.kind_of("facets").n_rows(src.source) == 1280


def test_points_weigh_in_float32_and_keep_their_labels():
    """The kinds' table puts points' weights per CSR entry in float32 (half the largest
    array of a cloud's run); the paper's method and the other kinds keep float64; the
    per-pair weights are the float64 ones rounded, so labels stay those of float64."""
    import trimesh

    from superfacets import segment
    from superfacets.method.params import resolve
    from superfacets.method.stages import build_graph, resolve_rules, weigh
    from superfacets.method.weights import csr_weights, edge_weights, weight_dtype

    rng = np.random.default_rng(3)
    xyz = rng.normal(size=(6000, 3))
    xyz /= np.linalg.norm(xyz, axis=1, keepdims=True)
    for obj, kind, paper, want in ((xyz, "points", False, np.float32),
                                   (xyz, "points", True, np.float64),
                                   (trimesh.creation.icosphere(subdivisions=3), "faces",
                                    False, np.float32),
                                   (trimesh.creation.icosphere(subdivisions=3), "faces",
                                    True, np.float64)):
        assert weight_dtype(kind, paper) is want
        _, graph, p = build_graph(obj, resolve(n_segments=20, paper=paper))
        w, _ = weigh(graph, resolve_rules(graph, p))
        assert w.dtype == want
        ref = csr_weights(graph, edge_weights(graph, alpha=p.alpha, eta_convex=p.eta_convex))
        np.testing.assert_array_equal(w, ref.astype(want))  # float64 weights, rounded
    # the labels of a float64 run: the same weights in float64 through the same stages
    import superfacets.method.stages as stages

    a = segment(xyz, 30).labels
    orig = stages.weight_dtype
    try:
        stages.weight_dtype = lambda kind, paper=False: np.float64
        b = segment(xyz, 30).labels
    finally:
        stages.weight_dtype = orig
    np.testing.assert_array_equal(a, b)
