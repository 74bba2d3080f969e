"""Defaults, choices and validation (superfacets.method.params): one place, checked before
any work."""

import math

import numpy as np
import pytest

from superfacets import DEFAULTS, ParameterError, segment
from superfacets.method.params import (
    ASSIGNMENTS,
    INITS,
    WEIGHTINGS,
    check_bool,
    check_choice,
    check_int,
    check_n_segments,
    check_nonneg,
    check_number,
    check_positive,
    check_threads,
    resolve,
)


def test_defaults_are_the_api_and_cli_defaults():
    import inspect

    from superfacets import superfacets
    from superfacets.cli import build_parser

    sig = inspect.signature(superfacets).parameters
    for name in ("alpha", "eta_convex", "window", "max_iter", "weighting", "assignment",
                 "n_segments", "init", "enforce_connectivity"):
        assert sig[name].default == getattr(DEFAULTS, name)
    args = build_parser().parse_args(["segment", "m.off"])
    for name in ("eta_convex", "window", "max_iter", "weighting", "assignment", "init"):
        assert getattr(args, name) == getattr(DEFAULTS, name)
    # alpha: the weighting's own (the paper's 200, Shlafman's 0.5), chosen with it
    from superfacets.cli.parameters import parameter_kwargs

    assert args.alpha is None
    assert parameter_kwargs(args, ("alpha", "weighting"))["alpha"] == DEFAULTS.alpha
    shlafman = build_parser().parse_args(["segment", "m.off", "--weighting", "shlafman"])
    assert parameter_kwargs(shlafman, ("alpha", "weighting"))["alpha"] == 0.5
    choices = {a.dest: a.choices for a in build_parser()._subparsers._group_actions[0]
               .choices["segment"]._actions}
    assert tuple(choices["init"]) == INITS and tuple(choices["assignment"]) == ASSIGNMENTS
    assert tuple(choices["weighting"]) == WEIGHTINGS


def test_the_registry_reads_the_same_defaults():
    from superfacets.evaluation.methods import get_method

    d = get_method("superfacets").defaults
    assert (d["alpha"], d["eta_convex"], d["window"], d["max_iter"]) == (
        DEFAULTS.alpha, DEFAULTS.eta_convex, DEFAULTS.window, DEFAULTS.max_iter)
    assert get_method("shlafman").defaults["alpha"] == 0.5


@pytest.mark.parametrize("value, ok", [(3, 3), (np.int32(4), 4), (True, None), (2.0, None),
                                       ("3", None), (0, None), (11, None)])
def test_check_int(value, ok):
    if ok is None:
        with pytest.raises(ParameterError, match="n must be an integer"):
            check_int("n", value, lo=1, hi=10)
    else:
        assert check_int("n", value, lo=1, hi=10) == ok


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -1.0, "x", None, True])
def test_check_nonneg_refuses(value):
    with pytest.raises(ParameterError, match="x must be a"):
        check_nonneg("x", value)


def test_check_number_ranges():
    assert check_nonneg("a", 0) == 0.0 and check_positive("a", "2.5") == 2.5
    with pytest.raises(ParameterError, match=r"a must be a finite number > 0, got 0"):
        check_positive("a", 0)
    with pytest.raises(ParameterError, match=r"in \[0, 1\]"):
        check_number("a", 1.5, 0, 1)
    assert check_number("a", 1, 0, 1) == 1.0 and math.isfinite(check_number("a", -3))


def test_check_choice_bool_threads_and_n_segments():
    assert check_choice("init", "grid", INITS) == "grid"
    with pytest.raises(ParameterError, match="init must be one of farthest, flood, grid"):
        check_choice("init", "Grid", INITS)
    assert check_bool("b", np.bool_(True)) is True
    with pytest.raises(ParameterError, match="b must be True or False"):
        check_bool("b", 1)
    assert check_threads(3) == 3 and check_threads(None) >= 1
    with pytest.raises(ParameterError, match="n_threads"):
        check_threads(0)
    assert check_n_segments(5, 5) == 5
    with pytest.raises(ParameterError, match=r"larger than the number of points \(4\)"):
        check_n_segments(5, 4, "points")


def test_thread_count_default_reads_the_environment(monkeypatch):
    monkeypatch.setenv("SUPERFACETS_NUM_THREADS", "3")
    assert check_threads(None) == 3
    monkeypatch.setenv("SUPERFACETS_NUM_THREADS", "many")  # not a count: said, as --threads
    with pytest.raises(ParameterError, match="SUPERFACETS_NUM_THREADS='many'"):
        check_threads(None)
    monkeypatch.setenv("SUPERFACETS_NUM_THREADS", " ")  # empty: as unset
    assert check_threads(None) == len(__import__("os").sched_getaffinity(0))
    monkeypatch.delenv("SUPERFACETS_NUM_THREADS")
    assert check_threads(None) == len(__import__("os").sched_getaffinity(0))


def test_resolve_resolves_init_and_refuses_unknown_names():
    assert resolve().init == "farthest" and resolve(radius=0.1).init == "flood"
    assert resolve(radius=0.1, n_segments=None).n_segments is None
    with pytest.raises(ParameterError, match="unknown parameter"):
        resolve(alhpa=3)
    with pytest.raises(ParameterError, match=r"Shlafman weighting must be in \[0, 1\]"):
        resolve(weighting="shlafman", alpha=2)
    with pytest.raises(ParameterError, match="enforce_connectivity must be True or False"):
        resolve(enforce_connectivity="yes")


def test_parameters_are_checked_before_the_mesh_is_touched():
    # a mesh argument that would fail to load: the parameter error comes first
    for kw, match in [(dict(alpha=-1), "alpha"), (dict(weighting="x"), "weighting"),
                      (dict(eta_convex=float("nan")), "eta_convex"),
                      (dict(init="random"), "init")]:
        with pytest.raises(ParameterError, match=match):
            segment(object(), 10, **kw)


@pytest.mark.parametrize("init", ["flood", "farthest"])
def test_a_radius_whose_area_underflows_is_refused(init):
    """r^2 of a subnormal radius is 0: a clear error, not a division by zero later."""
    import trimesh

    mesh = trimesh.creation.icosphere(2)
    with pytest.raises(ParameterError, match="too small: a superfacet's area would be 0"):
        segment(mesh, None, radius=1e-320, init=init)
    assert segment(mesh, None, radius=1e-100, init=init).n_segments >= 1  # tiny but fine


# --- each parameter declared once (superfacets.method.params.PARAMETERS) ---------------------

def test_the_declarations_are_the_fields_and_the_signatures():
    import inspect

    from superfacets import superfacets
    from superfacets.api.segmentation import segment as seg
    from superfacets.method.params import PARAMETERS, SegmentParams

    names = [p.name for p in PARAMETERS]
    assert len(set(names)) == len(names) == 30
    assert list(SegmentParams.__dataclass_fields__) == names
    assert [getattr(DEFAULTS, n) for n in names] == [p.default for p in PARAMETERS]
    for f, own in ((superfacets, []), (seg, ["adaptive", "extent_weight"])):
        sig = inspect.signature(f).parameters  # (segment's own keywords shown too)
        assert list(sig) == ["data"] + names + ["features"] + own
        assert all(sig[p.name].default == p.default for p in PARAMETERS)
        assert set(own) <= set(f.__code__.co_varnames)  # (keywords the function takes)


def test_the_input_is_data_and_the_keyword_of_before_still_works_with_a_warning():
    """``segment(data, ...)``: the input is named for what it may be (a mesh, a cloud, a
    tetrahedral mesh); ``mesh=`` of before gives the same labels with a FutureWarning, and
    no input, or two, is a TypeError in words."""
    import trimesh

    from superfacets import segment, superfacets

    ball = trimesh.creation.icosphere(subdivisions=2)
    want = segment(ball, 10).labels
    with pytest.warns(FutureWarning, match=r"segment\(data=\.\.\.\)"):
        np.testing.assert_array_equal(segment(mesh=ball, n_segments=10).labels, want)
    with pytest.warns(FutureWarning, match="superfacets"):
        np.testing.assert_array_equal(superfacets(mesh=ball, n_segments=10), want)
    np.testing.assert_array_equal(segment(data=ball, n_segments=10).labels, want)
    with pytest.raises(TypeError, match="needs the input"):
        segment(n_segments=10)
    with pytest.raises(TypeError, match="twice"):
        segment(ball, 10, mesh=ball)



def test_a_file_path_is_an_input_read_as_the_command_line_reads_it(tmp_path):
    """``segment("scan.las", k)`` was a TypeError naming meshes only: a path (str or
    ``os.PathLike``) is read by ``read_input``, with the labels of the object it reads; a
    missing file is a FileNotFoundError, and a list of points is a cloud (as its array)."""
    import trimesh

    from superfacets import segment, superfacets
    from superfacets.io import read_input

    trimesh.creation.icosphere(subdivisions=2).export(tmp_path / "ball.ply")
    np.save(tmp_path / "pts.npy", np.random.default_rng(1).random((600, 3)))
    for name, k in (("ball.ply", 12), ("pts.npy", 20)):
        path = tmp_path / name
        want = segment(read_input(path), k).labels
        np.testing.assert_array_equal(segment(path, k).labels, want)
        np.testing.assert_array_equal(superfacets(str(path), k), want)
    with pytest.raises(FileNotFoundError, match="no such file"):
        segment(tmp_path / "missing.ply", 5)
    from superfacets.errors import InvalidCloudError

    with pytest.raises(InvalidCloudError, match="all 5 points coincide"):
        segment([[0.0, 0.0, 0.0]] * 5, 2)


def _doc_parameters(doc: str) -> dict[str, str]:
    """name -> its type line, from a numpydoc Parameters section."""
    import re

    section = doc.split("Parameters\n    ----------\n")[1].split("\n    Returns\n")[0]
    return {m.group(1): m.group(2) for m in re.finditer(r"^    (\w+) : (.*)$", section, re.M)}


def test_the_docstring_documents_every_declared_parameter_with_its_default():
    from superfacets import superfacets
    from superfacets.method.params import PARAMETERS

    doc = _doc_parameters(superfacets.__doc__)
    missing = [p.name for p in PARAMETERS if p.name not in doc]
    assert not missing, f"not in superfacets' Parameters: {missing}"
    for p in PARAMETERS:
        said = doc[p.name].split("default ")
        if len(said) > 1:  # "alpha : float, default 200": the declared default
            value = said[1].strip()
            assert value in (repr(p.default), f"{p.default:g}" if isinstance(
                p.default, float) else str(p.default), str(p.default)), (p.name, value)
        else:  # optional or None: the method decides
            assert p.default in (None, False, 0.0) or p.name == "n_segments", p.name


def test_every_declared_option_of_the_command_line_has_the_declared_default_and_choices():
    from superfacets.cli import build_parser
    from superfacets.method.params import PARAMETERS

    sub = build_parser()._subparsers._group_actions[0].choices["segment"]
    actions = {s: a for a in sub._actions for s in a.option_strings}
    # the command line's own defaults, and why: -k and --radius exclude each other (None
    # is "150 unless --radius"); --no-connectivity is the negation; --progress is on
    # for large meshes at a terminal; --threads None is all cores, as the API's None;
    # --alpha None is the weighting's own (200 for the paper's, 0.5 for Shlafman's)
    own = {"n_segments": None, "enforce_connectivity": False, "progress": None,
           "alpha": None}
    for p in PARAMETERS:
        assert p.cli in actions, f"{p.name}: no option {p.cli}"
        a = actions[p.cli]
        assert a.default == own.get(p.name, p.default), (p.name, a.default, p.default)
        if a.choices is not None:
            from superfacets.method.params import KINDS, MERGE_COSTS

            check = [c for c in list(INITS) + list(ASSIGNMENTS) + list(WEIGHTINGS) +
                     list(KINDS) + list(MERGE_COSTS)]
            assert set(a.choices) <= set(check)
            with pytest.raises(ParameterError):
                p.check("not-a-choice")


def test_the_registry_uses_the_declared_defaults():
    from superfacets.evaluation.methods import get_method
    from superfacets.method.params import PARAMETER

    d = get_method("superfacets").defaults
    for name, value in d.items():
        if name in PARAMETER:
            declared = PARAMETER[name].default
            want = "auto" if declared is None else declared
            if name == "init":
                want = INITS[0]  # the registry's runs give n_segments: farthest
            assert value == want, (name, value, declared)


def test_n_segments_above_the_elements_is_refused_before_the_graph(monkeypatch):
    """segment(icosphere, 10**7) is refused from the mesh's counts: no graph built."""
    import trimesh

    import superfacets.elements.faces as faces
    import superfacets.elements.vertices as vertices

    def no_graph(*args, **kwargs):
        raise AssertionError("the element graph was built")

    monkeypatch.setattr(faces, "face_graph", no_graph)
    monkeypatch.setattr(vertices, "vertex_graph", no_graph)
    mesh = trimesh.creation.icosphere(subdivisions=2)
    with pytest.raises(ParameterError, match=r"n_segments \(10000000\) is larger than the "
                                             r"number of faces \(320\)"):
        segment(mesh, 10**7)
    with pytest.raises(ParameterError, match=r"larger than the number of vertices \(162\)"):
        segment(mesh, 163, elements="vertices")
    with pytest.raises(ParameterError, match=r"larger than the number of points \(50\)"):
        segment(np.random.default_rng(0).random((50, 3)), 51)


def test_features_are_checked_before_the_graph(monkeypatch):
    import trimesh

    import superfacets.elements.faces as faces

    def no_graph(*args, **kwargs):
        raise AssertionError("the element graph was built")

    monkeypatch.setattr(faces, "face_graph", no_graph)
    mesh = trimesh.creation.icosphere(subdivisions=2)
    with pytest.raises(ParameterError, match=r"one row per input row \(320\), got shape"):
        segment(mesh, 10, beta=1.0, features=np.zeros((5, 3)))
    with pytest.raises(ParameterError, match="beta > 0 needs features"):
        segment(mesh, 10, beta=1.0)
