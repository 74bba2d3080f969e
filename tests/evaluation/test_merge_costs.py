"""``benchmarks/merge_costs.py``: the plane's rise scaled by the parts' own residual."""

from types import SimpleNamespace

import numpy as np
import pytest
from bench import benchmark


def _merge_costs():
    """``benchmarks/merge_costs.py`` as a module."""
    return benchmark("merge_costs")


def _plane(rng, x0, z, sigma, n=200):
    """``n`` points on the unit square at ``x0`` and height ``z``, noise ``sigma``."""
    p = rng.random((n, 3))
    p[:, 0] += x0
    p[:, 2] = z + sigma * rng.standard_normal(n)
    return p


def _street():
    """Road A, B (smooth, one plane), sidewalk C (12 cm up: a curb), two rough pieces of
    vegetation D, E (10 cm noise, 20 cm apart in height) 2 m above, in a chain."""
    rng = np.random.default_rng(0)
    parts = [_plane(rng, 0, 0.0, 0.005), _plane(rng, 1, 0.0, 0.005),
             _plane(rng, 2, 0.12, 0.005), _plane(rng, 3, 2.0, 0.1), _plane(rng, 4, 2.2, 0.1)]
    mean = np.array([p.mean(0) for p in parts])
    scatter = np.array([(p - m).T @ (p - m) for p, m in zip(parts, mean)])
    edges = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])
    return SimpleNamespace(n_segments=5, area=np.full(5, 200.0), centroid=mean,
                           scatter=scatter, edge_index=edges)


@pytest.mark.parametrize("scale, groups", [("rise", [0, 0, 0, 1, 2]),
                                           ("own", [0, 0, 1, 2, 2]),
                                           ("half", [0, 0, 1, 2, 2])])
def test_the_scaled_rise_keeps_the_curb_and_merges_the_vegetation(scale, groups):
    """Down to 3 of 5: the road's two pieces first (coplanar), then the plain rise merges
    the curb (a smaller rise than two rough pieces'), the scaled rise the vegetation (a
    small rise against its own roughness)."""
    bench = _merge_costs()
    labels = bench.scaled_rise_merges(_street(), 3, 0.0, 0.005 ** 2, scale)
    assert labels.tolist() == groups


def test_the_blend_charges_both_in_the_noises_units():
    """``blend``: the rise in units of the noise (both steps are many noise units: the
    curb's rise is the smaller) plus Ward's term in units of ``r^2``: the curb merges
    before the vegetation, as with the plain rise; a huge ``r^2`` changes nothing."""
    bench = _merge_costs()
    for size in (1.0, 1e9):
        labels = bench.scaled_rise_merges(_street(), 3, 0.0, 0.005 ** 2, "blend", size)
        assert labels.tolist() == [0, 0, 0, 1, 2]


def test_the_size_bound_holds_while_another_pair_may_merge():
    """With a bound of 450 points no union of three pieces forms while a pair may merge;
    below that the bound gives way (down to 2 of 5)."""
    bench = _merge_costs()
    g = _street()
    def points(target):
        return sorted(np.bincount(bench.scaled_rise_merges(g, target, 450.0, 0.0, "own"),
                                  weights=g.area).tolist())

    assert points(3) == [200, 400, 400]
    assert points(2) == [400, 600]


def test_auto_leaves_the_package_as_it_is():
    """``merge_cost('auto')`` replaces nothing; another cost is undone after its block."""
    from superfacets.method import merges

    bench = _merge_costs()
    before = merges.merge_nodes
    with bench.merge_cost("auto", False):
        assert merges.merge_nodes is before
    with bench.merge_cost("half", True):
        assert merges.merge_nodes is not before
    assert merges.merge_nodes is before


def test_the_plain_rise_gives_the_packages_labels(monkeypatch):
    """``rise`` (the heap here) on a made-up room gives the compiled kernel's labels, bit for
    bit: the script measures the cost, not a different merging."""
    from superfacets import segment
    from superfacets.evaluation.datasets.rooms import make_room

    bench = _merge_costs()
    ran = []
    heap = bench.scaled_rise_merges
    monkeypatch.setattr(bench, "scaled_rise_merges", lambda *a: ran.append(a[4]) or heap(*a))
    cloud = make_room(0).cloud
    auto = segment(cloud, 20, merge_cost="auto").labels
    with bench.merge_cost("rise", False):
        labels = segment(cloud, 20, merge_cost="auto").labels
    assert ran and set(ran) == {"rise"}  # the room merges by the plane's rise
    np.testing.assert_array_equal(labels, auto)
