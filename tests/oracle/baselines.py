"""The reference kernels of the baselines' compiled kernels (``baselines.*``), in the
compiled kernels' call shapes: the Felzenszwalb-Huttenlocher segmentation, the
covariances of cut pursuit's features and Variational Shape Approximation's kernels."""

import numpy as np
from numba import njit

from . import felzenszwalb as _fh
from . import normals as _normals
from . import vsa as _vsa

csr_covariances = _normals.csr_covariances
vsa_assess = _vsa.assess
vsa_worst_faces = _vsa.worst_faces


def felzenszwalb(n, lo, hi, w, order, k_thresh, min_size, labels):
    """:func:`.felzenszwalb.felzenszwalb` with its threshold as float32 (the compiled
    kernel takes it as a float holding a float32 value)."""
    return _fh.felzenszwalb(n, lo, hi, w, order, np.float32(k_thresh), min_size, labels)


def vsa_partition(indptr, indices, metric, areas, normals, corners, X, N, seeds, n_proxies,
                  label):
    """:func:`.vsa.partition` with its heap arrays made here."""
    cap = indices.shape[0] + 1
    _vsa.partition(indptr, indices, metric, areas, normals, corners, X, N, seeds, n_proxies,
                   label, np.empty(cap), np.empty(cap, dtype=np.int64))


@njit(cache=True)
def vsa_sums(label, n_proxies, metric, areas, normals, centroids, corners, area, nsum, csum,
             mom):
    """The sums of :func:`.vsa.fit`, in its order: area, area-weighted normals and
    centroids, and (L2) the integral of x x^T over the triangles of each region."""
    area[:] = 0.0
    nsum[:] = 0.0
    csum[:] = 0.0
    mom[:] = 0.0
    for f in range(label.shape[0]):
        p = label[f]
        a = areas[f]
        area[p] += a
        for i in range(3):
            nsum[p, i] += a * normals[f, i]
            csum[p, i] += a * centroids[f, i]
        if metric == 1:
            for r in range(3):
                sr = corners[f, 0, r] + corners[f, 1, r] + corners[f, 2, r]
                for c in range(3):
                    sc = corners[f, 0, c] + corners[f, 1, c] + corners[f, 2, c]
                    vv = (corners[f, 0, r] * corners[f, 0, c] + corners[f, 1, r] * corners[f, 1, c]
                          + corners[f, 2, r] * corners[f, 2, c])
                    mom[p, r, c] += a / 12.0 * (vv + sr * sc)
