"""What every coupling kernel shares: the cached-compile decorator, two small numba helpers and the
compiled pin-profile foot point.

`kernel` is `numba.njit(cache=True)` with one fix. Numba keys a cached function on the content of
its own source file only, while a caller's cache also holds the machine code of every kernel it
calls: edit `pin.py` and the cached `integrate` in `dynamics/kernels.py` would keep running the old
pin code (numba issue #6845). So the stamp of every kernel also covers the content of all files
of the compiled unit (KERNEL_SOURCES): editing any of them recompiles them all (60-90 s, once).
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


def kernel(fn=None, *, inline: bool = False):
    """`numba.njit(cache=True)(fn)` whose cache is also invalidated by any file of KERNEL_SOURCES.
    inline=True inlines the function into its numba callers (numba IR, `inline="always"`): the
    couplings and the solver steps, so the hot loop is one function as in the single kernel it
    replaced (measured per time step against that kernel: +14 % without, +3..5 % with; a cold
    compile of everything takes 60-90 s instead of 50-60 s on the 2-core machine).
    Falls back to an uncached kernel (correct, compiled per process) if numba's cache internals
    moved; tests/test_couplings.py fails then, so the fallback cannot go unnoticed."""
    if fn is None:
        return lambda f: kernel(f, inline=inline)
    opts = {"inline": "always"} if inline else {}
    disp = numba.njit(cache=True, **opts)(fn)
    cache_file = getattr(getattr(disp, "_cache", None), "_cache_file", None)
    if cache_file is None or not hasattr(cache_file, "_source_stamp"):
        warnings.warn(f"numba cache internals changed: {fn.__qualname__} compiled without cache")
        return numba.njit(**opts)(fn)
    cache_file._source_stamp = (cache_file._source_stamp, KERNEL_DIGEST)
    return disp


def cache_stamp(disp):
    """The source stamp a cached kernel is checked against (for the tests)."""
    return disp._cache._cache_file._source_stamp


DAMP_RAMP_M = 1e-7   # contact damping ramps in over 0.1 um of approach (ADAMS IMPACT convention)


@kernel(inline=True)
def ramp(x):
    """Cubic STEP(x, 0, 0, DAMP_RAMP_M, 1): damping that vanishes at first touch (no force jump)."""
    if x >= DAMP_RAMP_M:
        return 1.0
    if x <= 0.0:
        return 0.0
    d = x / DAMP_RAMP_M
    return d * d * (3.0 - 2.0 * d)


@kernel(inline=True)
def interp2(x, table):
    """np.interp of columns 1 and 2 of `table` over its column 0 at one point (clamped at the
    ends), by bisection: one search for both (a law's k and n)."""
    n = table.shape[0]
    if x <= table[0, 0]:
        return table[0, 1], table[0, 2]
    if x >= table[n - 1, 0]:
        return table[n - 1, 1], table[n - 1, 2]
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if table[mid, 0] <= x:
            lo = mid
        else:
            hi = mid
    w = (x - table[lo, 0]) / (table[hi, 0] - table[lo, 0])
    return table[lo, 1] * (1.0 - w) + table[hi, 1] * w, table[lo, 2] * (1.0 - w) + table[hi, 2] * w


foot_point = kernel(geometry.pin_profile.foot_point, inline=True)   # the one pin-to-profile kernel
