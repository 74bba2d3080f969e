"""PCA normals of point neighbourhoods, in numba (private kernel of
:mod:`superfacets.elements.points`).

For each point: the covariance of its neighbourhood, its smallest eigenvalue
by the closed form of a symmetric 3x3 matrix (the trigonometric solution of
the characteristic cubic), and the eigenvector as the largest cross product of
two rows of ``C - lambda I``. And the covariances of graph neighbourhoods that the
superpoint merges' noise estimate reads (:func:`neighbourhood_moments`).
"""

import math

import numpy as np
from numba import njit, prange


@njit(cache=True, error_model="numpy", inline="always")
def _spectrum(a00, a01, a02, a11, a12, a22):
    """``(q, p, phi)`` of the trigonometric solution: the eigenvalues of the symmetric
    matrix are ``q + 2 p cos(phi + 2 pi j / 3)``, ``j = 0`` the largest, ``j = 1`` the
    smallest; ``p = 0`` when it is isotropic (all three equal)."""
    p1 = a01 * a01 + a02 * a02 + a12 * a12
    q = (a00 + a11 + a22) / 3.0
    p2 = (a00 - q) ** 2 + (a11 - q) ** 2 + (a22 - q) ** 2 + 2.0 * p1
    if p2 <= 0.0:
        return q, 0.0, 0.0
    p = math.sqrt(p2 / 6.0)
    b00, b11, b22 = (a00 - q) / p, (a11 - q) / p, (a22 - q) / p
    b01, b02, b12 = a01 / p, a02 / p, a12 / p
    r = 0.5 * (b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02)
               + b02 * (b01 * b12 - b11 * b02))
    r = min(1.0, max(-1.0, r))
    return q, p, math.acos(r) / 3.0


@njit(cache=True, error_model="numpy", inline="always")
def _smallest_eigenvector(a00, a01, a02, a11, a12, a22, out, i):
    q, p, phi = _spectrum(a00, a01, a02, a11, a12, a22)
    if p <= 0.0:  # isotropic (or one point): no preferred direction
        out[i, 0], out[i, 1], out[i, 2] = 0.0, 0.0, 1.0
        return
    lam = q + 2.0 * p * math.cos(phi + 2.0 * math.pi / 3.0)  # the smallest eigenvalue
    r0x, r0y, r0z = a00 - lam, a01, a02
    r1x, r1y, r1z = a01, a11 - lam, a12
    r2x, r2y, r2z = a02, a12, a22 - lam
    c0x, c0y, c0z = r0y * r1z - r0z * r1y, r0z * r1x - r0x * r1z, r0x * r1y - r0y * r1x
    c1x, c1y, c1z = r0y * r2z - r0z * r2y, r0z * r2x - r0x * r2z, r0x * r2y - r0y * r2x
    c2x, c2y, c2z = r1y * r2z - r1z * r2y, r1z * r2x - r1x * r2z, r1x * r2y - r1y * r2x
    d0 = c0x * c0x + c0y * c0y + c0z * c0z
    d1 = c1x * c1x + c1y * c1y + c1z * c1z
    d2 = c2x * c2x + c2y * c2y + c2z * c2z
    if d0 >= d1 and d0 >= d2:
        x, y, z, d = c0x, c0y, c0z, d0
    elif d1 >= d2:
        x, y, z, d = c1x, c1y, c1z, d1
    else:
        x, y, z, d = c2x, c2y, c2z, d2
    if d <= 0.0:  # two smallest eigenvalues equal: a line-like neighbourhood
        out[i, 0], out[i, 1], out[i, 2] = 0.0, 0.0, 1.0
        return
    s = 1.0 / math.sqrt(d)
    out[i, 0], out[i, 1], out[i, 2] = x * s, y * s, z * s


@njit(cache=True, error_model="numpy", inline="always")
def _scatter(points, idx):
    """The scatter matrix (sums of centred outer products) of the points ``idx``:
    ``(a00, a01, a02, a11, a12, a22)``; zeros for no point."""
    k = idx.shape[0]
    if k == 0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    mx = my = mz = 0.0
    for t in range(k):
        j = idx[t]
        mx += points[j, 0]
        my += points[j, 1]
        mz += points[j, 2]
    mx /= k
    my /= k
    mz /= k
    a00 = a01 = a02 = a11 = a12 = a22 = 0.0
    for t in range(k):
        j = idx[t]
        x, y, z = points[j, 0] - mx, points[j, 1] - my, points[j, 2] - mz
        a00 += x * x
        a01 += x * y
        a02 += x * z
        a11 += y * y
        a12 += y * z
        a22 += z * z
    return a00, a01, a02, a11, a12, a22


@njit(cache=True, error_model="numpy", inline="always")
def _linearity(a00, a01, a02, a11, a12, a22):
    """``(l1 - l2) / l1`` of the eigenvalues ``l1 >= l2 >= l3`` of a symmetric 3x3
    matrix (the same trigonometric solution): 1 for points on a line, near 0 for a
    round patch of a surface; 0 for no spread at all."""
    q, p, phi = _spectrum(a00, a01, a02, a11, a12, a22)
    if p <= 0.0 or q <= 0.0:  # isotropic, or one point
        return 0.0
    l1 = q + 2.0 * p * math.cos(phi)
    l3 = q + 2.0 * p * math.cos(phi + 2.0 * math.pi / 3.0)
    l2 = 3.0 * q - l1 - l3
    return (l1 - l2) / l1 if l1 > 0.0 else 0.0


@njit(cache=True, error_model="numpy", parallel=True)
def pca_normals(points, neighbors, out, linearity):
    """``out[i]``: unit normal of the points ``neighbors[i]`` (their least-variance axis);
    ``linearity[i]``: how much that neighbourhood is a line (:func:`_linearity`)."""
    n = neighbors.shape[0]
    for i in prange(n):
        a00, a01, a02, a11, a12, a22 = _scatter(points, neighbors[i])
        scale = a00 + a11 + a22
        if scale > 0.0:
            a00 /= scale
            a01 /= scale
            a02 /= scale
            a11 /= scale
            a12 /= scale
            a22 /= scale
        _smallest_eigenvector(a00, a01, a02, a11, a12, a22, out, i)
        linearity[i] = _linearity(a00, a01, a02, a11, a12, a22)


@njit(cache=True, error_model="numpy", parallel=True)
def pca_linearity(points, neighbors, linearity):
    """``linearity[i]`` of the points ``neighbors[i]`` alone (:func:`pca_normals`' second
    output, for clouds whose normals are given)."""
    n = neighbors.shape[0]
    for i in prange(n):
        a00, a01, a02, a11, a12, a22 = _scatter(points, neighbors[i])
        scale = a00 + a11 + a22
        if scale > 0.0:
            linearity[i] = _linearity(a00 / scale, a01 / scale, a02 / scale, a11 / scale,
                                      a12 / scale, a22 / scale)
        else:
            linearity[i] = 0.0


@njit(cache=True, error_model="numpy", inline="always")
def _put_covariance(out, i, a, m):
    """``out[i]``: the scatter ``a`` (:func:`_scatter`'s six sums) divided by ``m``."""
    out[i, 0, 0] = a[0] / m
    out[i, 0, 1] = out[i, 1, 0] = a[1] / m
    out[i, 0, 2] = out[i, 2, 0] = a[2] / m
    out[i, 1, 1] = a[3] / m
    out[i, 1, 2] = out[i, 2, 1] = a[4] / m
    out[i, 2, 2] = a[5] / m


@njit(cache=True, error_model="numpy", parallel=True)
def csr_covariances(indptr, indices, points, out):
    """``out[i]``: the 3x3 covariance of the CSR neighbours of point ``i`` (zeros for none)."""
    n = indptr.shape[0] - 1
    for i in prange(n):
        idx = indices[indptr[i]:indptr[i + 1]]
        m = max(idx.shape[0], 1)
        _put_covariance(out, i, _scatter(points, idx), m)


@njit(cache=True)
def _ball(indptr, indices, first, rings):
    """The elements within ``rings`` graph steps of ``first``, itself included, ascending."""
    ball = np.full(1, first, dtype=np.int64)
    for _ in range(rings):
        count = ball.shape[0]
        for t in range(ball.shape[0]):
            count += indptr[ball[t] + 1] - indptr[ball[t]]
        grown = np.empty(count, dtype=np.int64)
        grown[:ball.shape[0]] = ball
        at = ball.shape[0]
        for t in range(ball.shape[0]):
            for e in range(indptr[ball[t]], indptr[ball[t] + 1]):
                grown[at] = indices[e]
                at += 1
        ball = np.unique(grown)
    return ball


@njit(cache=True, error_model="numpy", parallel=True)
def neighbourhood_moments(indptr, indices, points, pick, rings, cov, radius):
    """For each element ``pick[i]``, over the elements within ``rings`` graph steps of it
    (itself included; each sum in their ascending order, from 0): ``cov[i]`` their
    covariance (the centred outer products' sum divided by their number) and
    ``radius[i]`` their mean distance to it (the sum divided by their number less one,
    at least 1)."""
    for i in prange(pick.shape[0]):
        p = pick[i]
        ball = _ball(indptr, indices, p, rings)
        size = float(ball.shape[0])
        _put_covariance(cov, i, _scatter(points, ball), size)
        s = 0.0
        for t in range(ball.shape[0]):
            j = ball[t]
            dx = points[j, 0] - points[p, 0]
            dy = points[j, 1] - points[p, 1]
            dz = points[j, 2] - points[p, 2]
            s += math.sqrt(dx * dx + dy * dy + dz * dz)
        radius[i] = s / max(size - 1.0, 1.0)


@njit(cache=True, error_model="numpy")
def _jacobi_extremes(a00, a01, a02, a11, a12, a22):
    """The smallest and the largest eigenvalue of the symmetric 3x3 matrix by cyclic Jacobi
    rotations (the pairs (0, 1), (0, 2), (1, 2) each sweep, at most 64 sweeps; an entry
    negligible beside both its diagonal ones is set to 0 without a rotation)."""
    d = np.array([a00, a11, a22])
    o = np.array([a01, a02, a12])
    P, Q, RP, RQ = (0, 0, 1), (1, 2, 2), (1, 0, 0), (2, 2, 1)
    for _ in range(64):
        if o[0] == 0.0 and o[1] == 0.0 and o[2] == 0.0:
            break
        for k in range(3):
            apq = o[k]
            if apq == 0.0:
                continue
            p, q = P[k], Q[k]
            g = 100.0 * abs(apq)
            if abs(d[p]) + g == abs(d[p]) and abs(d[q]) + g == abs(d[q]):
                o[k] = 0.0
                continue
            theta = (d[q] - d[p]) / (2.0 * apq)
            if abs(theta) > 1e150:
                t = 0.5 / theta
            else:
                t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + math.sqrt(theta * theta + 1.0))
            c = 1.0 / math.sqrt(t * t + 1.0)
            s = t * c
            d[p] -= t * apq
            d[q] += t * apq
            o[k] = 0.0
            arp, arq = o[RP[k]], o[RQ[k]]
            o[RP[k]] = c * arp - s * arq
            o[RQ[k]] = s * arp + c * arq
    low = min(min(d[0], d[1]), d[2])
    high = max(max(d[0], d[1]), d[2])
    return low, high


@njit(cache=True, parallel=True, error_model="numpy")
def extreme_eigenvalues(cov, low, high):
    """The smallest and the largest eigenvalue of each symmetric 3x3 matrix ``cov[i]`` (its
    upper triangle read)."""
    for i in prange(cov.shape[0]):
        a = cov[i]
        low[i], high[i] = _jacobi_extremes(a[0, 0], a[0, 1], a[0, 2], a[1, 1], a[1, 2],
                                           a[2, 2])
