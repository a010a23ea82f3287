"""What every coupling kernel shares: the cached-compile decorator, two small numba helpers and the
compiled pin-profile foot point.

`kernel` is `numba.njit` cached on disk for the whole compiled unit (KERNEL_SOURCES: the coupling
kernels, the solvers and the one pin-profile kernel they call), `dynamics.kernel_cache`: numba
alone keys a cached function on its own file, while the solvers' machine code holds the inlined
couplings, so editing `pin.py` would keep running the old pin code (numba issue #6845). Here
editing any file of the unit compiles them all afresh (60-90 s, once per machine: one process
compiles, the others load).
"""
from __future__ import annotations

from pathlib import Path

import geometry.pin_profile
from dynamics.kernel_cache import KernelUnit

_HERE = Path(__file__).resolve().parent
# the compiled unit: coupling kernels, the solvers, the one pin-profile kernel they call and the
# losses' pin-frame kernel (every file holding a `kernel`: KernelUnit.kernel refuses any other)
KERNEL_SOURCES = tuple(sorted(_HERE.glob("*.py"))) + (_HERE.parent / "kernels.py",
                                                      _HERE.parent / "losses" / "contacts.py",
                                                      Path(geometry.pin_profile.__file__).resolve())
UNIT = KernelUnit(KERNEL_SOURCES)


def kernel(fn=None, *, inline: bool = False):
    """A kernel of the unit (`KernelUnit.kernel`). inline=True inlines the function into its numba
    callers (numba IR, `inline="always"`): the couplings and the solver steps, so the hot loop is
    one function as in the single kernel it replaced (measured per time step against that kernel:
    +14 % without, +3..5 % with; a cold compile of everything takes 60-90 s instead of 50-60 s on
    the 2-core machine)."""
    return UNIT.kernel(fn, inline=inline)


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
    ends), by bisection: one search for both (a law's k and n); with their slopes d/dx (0 where
    clamped): (k, n, dk/dx, dn/dx)."""
    n = table.shape[0]
    if x <= table[0, 0]:
        return table[0, 1], table[0, 2], 0.0, 0.0
    if x >= table[n - 1, 0]:
        return table[n - 1, 1], table[n - 1, 2], 0.0, 0.0
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if table[mid, 0] <= x:
            lo = mid
        else:
            hi = mid
    span = table[hi, 0] - table[lo, 0]
    w = (x - table[lo, 0]) / span
    return (table[lo, 1] * (1.0 - w) + table[hi, 1] * w, table[lo, 2] * (1.0 - w) + table[hi, 2] * w,
            (table[hi, 1] - table[lo, 1]) / span, (table[hi, 2] - table[lo, 2]) / span)


foot_point = kernel(geometry.pin_profile.foot_point, inline=True)   # the one pin-to-profile kernel
