"""Per-CSR-entry values from the per-adjacency terms of an element graph (private
kernels of :mod:`superfacets.method.weights` and :mod:`superfacets.method.cleanup`): one pass
over the CSR entries instead of numpy temporaries per adjacency and a gather."""

import math

import numpy as np
from numba import njit

from .geometry import pair_terms


@njit(cache=True, error_model="numpy", nogil=True)
def per_entry(values, dual_edge, out):
    """``out[e] = values[dual_edge[e]]``: a value per adjacency laid out per CSR entry
    (``np.take``'s result, its float64 values into ``out``'s dtype)."""
    for e in range(dual_edge.shape[0]):
        out[e] = values[dual_edge[e]]


@njit(cache=True, error_model="numpy", nogil=True)
def convex_scaled_csr(weights, dual_edge, concave, cos, span, coef):
    """``weights[e] - coef * span * arccos(cos)`` (at least 0) on the entries of
    convex adjacencies, ``weights[e]`` on concave ones (adjacency ``dual_edge[e]``)."""
    # (no array of one delta per adjacency: 8 B each); in the weights' dtype, each value
    # computed in float64 and rounded
    out = np.empty(weights.shape[0], dtype=weights.dtype)
    for e in range(weights.shape[0]):
        d = dual_edge[e]
        out[e] = weights[e] if concave[d] else max(
            weights[e] - coef * span[d] * math.acos(cos[d]), 0.0)
    return out


@njit(cache=True, error_model="numpy", nogil=True)
def cut_costs_csr(dual_edge, concave, cos, lengths, factor, eta_convex, scale):
    """``scale * lengths / (1 + factor * eta * arccos(cos))`` per CSR entry,
    ``eta`` 1 on concave adjacencies and ``eta_convex`` on convex ones."""
    cost = np.empty(cos.shape[0])  # one arccos per adjacency
    for d in range(cos.shape[0]):
        eta = 1.0 if concave[d] else eta_convex
        cost[d] = lengths[d] / (1.0 + factor * eta * math.acos(cos[d])) * scale
    out = np.empty(dual_edge.shape[0])
    for e in range(dual_edge.shape[0]):
        out[e] = cost[dual_edge[e]]
    return out


@njit(cache=True, error_model="numpy", nogil=True)
def step_terms_csr(positions, normals, indptr, indices, r0, r1, step, geo):
    """``geo`` of the CSR entries of rows ``r0:r1`` (from index 0) with the offset ``d =
    p_j - p_i`` along the two normals weighed ``step`` times: ``sqrt(geo^2 + (step^2 - 1)
    off^2)``, ``off = (|n_i . d| + |n_j . d|) / 2``."""
    grow = step * step - 1.0
    u = 0
    for i in range(r0, r1):
        for x in range(indptr[i], indptr[i + 1]):
            j = np.int64(indices[x])
            dx = positions[j, 0] - positions[i, 0]
            dy = positions[j, 1] - positions[i, 1]
            dz = positions[j, 2] - positions[i, 2]
            a = abs((dx * np.float64(normals[i, 0]) + dy * np.float64(normals[i, 1]))
                    + dz * np.float64(normals[i, 2]))
            b = abs((dx * np.float64(normals[j, 0]) + dy * np.float64(normals[j, 1]))
                    + dz * np.float64(normals[j, 2]))
            off = 0.5 * (a + b)
            geo[u] = math.sqrt(geo[u] * geo[u] + grow * off * off)
            u += 1


@njit(cache=True, error_model="numpy", nogil=True)
def point_terms_csr(positions, normals, indptr, indices, r0, r1, geo, cos, concave):
    """:func:`~superfacets._kernels.geometry.point_terms` per CSR entry of the rows
    ``r0:r1`` (written from index 0): entry ``(i, j)`` gets the terms of the pair
    ``(min, max)`` (:func:`~superfacets._kernels.geometry.pair_terms`)."""
    u = 0
    for i in range(r0, r1):
        for x in range(indptr[i], indptr[i + 1]):
            j = np.int64(indices[x])
            geo[u], cos[u], concave[u] = pair_terms(positions, normals, min(i, j), max(i, j))
            u += 1


@njit(cache=True, error_model="numpy", nogil=True)
def combine_weights(geo, theta, concave, eta_convex, alpha, diagonal, out):
    """``out = (geo + alpha * ang) / diagonal`` with ``ang = eta * geo * theta / pi``
    (``eta`` 1 where ``concave``, else ``eta_convex``), as numpy evaluates the same
    expression over the arrays, the float64 value rounded to ``out``'s dtype."""
    for u in range(geo.shape[0]):
        eta = 1.0 if concave[u] else eta_convex
        ang = eta * geo[u] * theta[u] / np.pi
        out[u] = (geo[u] + alpha * ang) / diagonal


@njit(cache=True, error_model="numpy", nogil=True)
def feature_weights_csr(geo, theta, concave, features, indptr, indices, r0, r1, eta_convex,
                        alpha, beta, floor, diagonal, out):
    """The weights of the CSR entries of rows ``r0:r1`` with the feature term:
    ``((geo + alpha * ang) + (beta * geo) * jump) / diagonal``, ``ang`` as
    :func:`combine_weights`, ``jump`` the distance of the rows' features (squares added in
    column order) less ``floor``, at least 0, where ``floor > 0``."""
    u = 0
    for i in range(r0, r1):
        for x in range(indptr[i], indptr[i + 1]):
            j = indices[x]
            s = 0.0
            for c in range(features.shape[1]):
                t = features[i, c] - features[j, c]
                s += t * t
            jump = np.sqrt(s)
            if floor > 0:
                over = jump - floor
                jump = over if over >= 0.0 else 0.0
            eta = 1.0 if concave[u] else eta_convex
            ang = eta * geo[u] * theta[u] / np.pi
            out[u] = (geo[u] + alpha * ang + beta * geo[u] * jump) / diagonal
            u += 1


@njit(cache=True, error_model="numpy", nogil=True)
def neighbour_mean(indptr, indices, x, out):
    """``out[i] = ((x_i + above) + below) / (1 + degree)``: ``above`` the sum of ``x_j``
    over the neighbours ``j > i``, ``below`` over ``j < i``, each added in ascending
    ``j`` from 0.0 (the order of ``np.bincount`` over the pairs ``(lo, hi)``)."""
    for i in range(indptr.shape[0] - 1):
        above = 0.0
        below = 0.0
        for e in range(indptr[i], indptr[i + 1]):
            j = indices[e]
            if j > i:
                above += x[j]
            else:
                below += x[j]
        out[i] = (x[i] + above + below) / (1.0 + (indptr[i + 1] - indptr[i]))
