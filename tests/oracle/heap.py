"""A binary min-heap of (float key, int value) with lazy deletion, in numba.

Private kernels, shared by the searches of the split-and-merge swaps
(:mod:`.splitmerge`), the clean-up's band distances (:mod:`.cleanup`) and the
VSA baseline's flooding. ``hkey`` (float64) and ``hval`` (int) are the heap
arrays, ``size`` the number of entries; both functions return the new size.
The caller sizes the arrays for every push it can make. :func:`pop_min`
removes and returns the root (the loop head of every Dijkstra here).
"""

from numba import njit


@njit(cache=True, error_model="numpy", inline="always")
def push(hkey, hval, size, key, val):
    i = size
    while i > 0:
        p = (i - 1) >> 1
        if hkey[p] <= key:
            break
        hkey[i] = hkey[p]
        hval[i] = hval[p]
        i = p
    hkey[i] = key
    hval[i] = val
    return size + 1


@njit(cache=True, error_model="numpy", inline="always")
def pop(hkey, hval, size):
    """Remove the root (read it before calling); return the new size."""
    size -= 1
    if size == 0:
        return 0
    key = hkey[size]
    val = hval[size]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= size:
            break
        if c + 1 < size and hkey[c + 1] < hkey[c]:
            c += 1
        if hkey[c] >= key:
            break
        hkey[i] = hkey[c]
        hval[i] = hval[c]
        i = c
    hkey[i] = key
    hval[i] = val
    return size


@njit(cache=True, error_model="numpy", inline="always")
def pop_min(hkey, hval, size):
    """Remove the root; return ``(key, value, new size)``."""
    key = hkey[0]
    val = hval[0]
    return key, val, pop(hkey, hval, size)
