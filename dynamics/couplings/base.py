"""What every coupling kernel shares: the cached-compile decorator and two small numba helpers.

`kernel` is `numba.njit(cache=True)` with one fix. Numba keys a cached function on the content of
its own source file only, while a caller's cache also holds the machine code of every kernel it
calls: edit `pin.py` and the cached `integrate` in `dynamics/kernels.py` would keep running the old
pin code (numba issue #6845). So the stamp of every kernel also covers the content of all files
of the compiled unit (KERNEL_SOURCES): editing any of them recompiles them all (~40 s, once).
"""
from __future__ import annotations

import hashlib
import warnings
from pathlib import Path

import numba

import geometry.pin_profile

_HERE = Path(__file__).resolve().parent
# the compiled unit: coupling kernels, the solvers and the one pin-profile kernel they call
KERNEL_SOURCES = tuple(sorted(_HERE.glob("*.py"))) + (_HERE.parent / "kernels.py",
                                                      Path(geometry.pin_profile.__file__).resolve())


def sources_digest(paths) -> bytes:
    """SHA-256 over the names and contents of `paths` (a change anywhere changes it)."""
    h = hashlib.sha256()
    for p in paths:
        h.update(Path(p).name.encode())
        h.update(Path(p).read_bytes())
    return h.digest()


KERNEL_DIGEST = sources_digest(KERNEL_SOURCES)


def kernel(fn):
    """`numba.njit(cache=True)(fn)` whose cache is also invalidated by any file of KERNEL_SOURCES.
    Falls back to an uncached kernel (correct, compiled per process) if numba's cache internals
    moved; tests/test_couplings.py fails then, so the fallback cannot go unnoticed."""
    disp = numba.njit(cache=True)(fn)
    cache_file = getattr(getattr(disp, "_cache", None), "_cache_file", None)
    if cache_file is None or not hasattr(cache_file, "_source_stamp"):
        warnings.warn(f"numba cache internals changed: {fn.__qualname__} compiled without cache")
        return numba.njit(fn)
    cache_file._source_stamp = (cache_file._source_stamp, KERNEL_DIGEST)
    return disp


def cache_stamp(disp):
    """The source stamp a cached kernel is checked against (for the tests)."""
    return disp._cache._cache_file._source_stamp


DAMP_RAMP_M = 1e-7   # contact damping ramps in over 0.1 um of approach (ADAMS IMPACT convention)


@kernel
def ramp(x):
    """Cubic STEP(x, 0, 0, DAMP_RAMP_M, 1): damping that vanishes at first touch (no force jump)."""
    if x >= DAMP_RAMP_M:
        return 1.0
    if x <= 0.0:
        return 0.0
    d = x / DAMP_RAMP_M
    return d * d * (3.0 - 2.0 * d)


@kernel
def interp(x, xs, ys):
    """np.interp for one point (clamped at the ends), by bisection."""
    if x <= xs[0]:
        return ys[0]
    n = xs.shape[0]
    if x >= xs[n - 1]:
        return ys[n - 1]
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if xs[mid] <= x:
            lo = mid
        else:
            hi = mid
    w = (x - xs[lo]) / (xs[hi] - xs[lo])
    return ys[lo] * (1.0 - w) + ys[hi] * w


foot_point = kernel(geometry.pin_profile.foot_point)   # the one pin-to-profile kernel (compiled here)
