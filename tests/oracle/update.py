"""The center update of the paper (section 3.1), a numba kernel (private)."""

import numpy as np
from numba import njit

_INF = np.inf


@njit(cache=True, error_model="numpy")
def update_centers(label, k, areas, centroids, old_centers, new_centers):
    """Center update of the paper (section 3.1).

    For each superfacet ``s < k``: the area-weighted mean of its face
    centroids (plain mean if its area is zero), then the face of ``s`` whose
    centroid is nearest to that mean; the old center stays on ties, else the
    lowest face index wins. Writes ``new_centers[s]``, -1 for an empty
    superfacet.
    """
    m = label.shape[0]
    sums = np.zeros((k, 3))
    plain = np.zeros((k, 3))
    wsum = np.zeros(k)
    cnt = np.zeros(k, dtype=np.int64)
    for f in range(m):
        s = label[f]
        a = areas[f]
        for t in range(3):
            sums[s, t] += a * centroids[f, t]
            plain[s, t] += centroids[f, t]
        wsum[s] += a
        cnt[s] += 1
    for s in range(k):
        if wsum[s] > 0.0:
            for t in range(3):
                sums[s, t] /= wsum[s]
        elif cnt[s] > 0:
            for t in range(3):
                sums[s, t] = plain[s, t] / cnt[s]
    best = np.full(k, _INF)
    for s in range(k):
        new_centers[s] = -1
        c = old_centers[s]
        if c >= 0 and label[c] == s:
            d = 0.0
            for t in range(3):
                x = centroids[c, t] - sums[s, t]
                d += x * x
            best[s] = d
            new_centers[s] = c
    for f in range(m):
        s = label[f]
        d = 0.0
        for t in range(3):
            x = centroids[f, t] - sums[s, t]
            d += x * x
        if d < best[s]:
            best[s] = d
            new_centers[s] = f
