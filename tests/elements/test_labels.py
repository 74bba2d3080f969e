"""The one label-array check, and dense relabelling."""

import numpy as np
import pytest

from superfacets import ParameterError
from superfacets.elements.labels import check_labels, relabel_dense


def test_check_labels_accepts_one_integer_per_element():
    out = check_labels(np.array([2, 0, 2], dtype=np.int16), 3)
    assert out.dtype == np.int64 and out.tolist() == [2, 0, 2]
    assert check_labels([1, 2], None).tolist() == [1, 2]


@pytest.mark.parametrize("labels, n, match", [
    ([0, 1], 3, "3 integers, one per face"), ([0.0, 1.0, 2.0], 3, "dtype float64"),
    ([[0, 1, 2]], 3, r"shape \(1, 3\)"), (np.zeros((2, 2), int), None, "1-D array")])
def test_check_labels_refuses_with_one_error_type(labels, n, match):
    with pytest.raises(ParameterError, match=match):
        check_labels(labels, n, per="face")


def test_relabel_dense_keeps_order():
    np.testing.assert_array_equal(relabel_dense(np.array([7, -1, 7, 3])), [2, 0, 2, 1])


def test_relabel_dense_equals_the_sorted_ranks_on_every_kind_of_input():
    # small non-negative labels take a table, others a sort: the same ranks either way
    rng = np.random.default_rng(3)
    cases = [rng.integers(0, 40, 100), rng.integers(0, 40, 100).astype(np.int32),
             rng.integers(-5, 40, 100), rng.integers(0, 10**12, 100),
             rng.integers(0, 40, (4, 25)), np.array([0]), np.array([5, 5, 5])]
    for a in cases:
        ranks = np.unique(a, return_inverse=True)[1].ravel()
        out = relabel_dense(a)
        assert out.dtype == np.int64
        np.testing.assert_array_equal(out, ranks)
