"""The couplings of the lumped model and the one assembler that sums them.

A coupling is one module with
  NAME                       its registry name;
  Params                     a NamedTuple of floats and arrays (what numba compiles against);
  params(case, stiffness, layout, slots) -> Params
                             builds its parameters from the case (`geometry.params.ReducerCase`,
                             including its as-built errors) and the FE stiffness
                             (`fem.stiffness.StiffnessModel`), its DOF index tables from the
                             `dynamics.layout.DofLayout`, and asks `slots` for its places in the
                             work arrays (named outputs, candidate contacts);
  add(q, v, th_in, w_in, beta, want_k, p, w, V, tau_in) -> (V, tau_in, ok)
                             a numba kernel: adds its generalized force (on the system) to w.f,
                             its tangent -df/dq to w.K and damping -df/dv to w.C when want_k, and
                             its potential and input torque to the running sums V, tau_in (passed
                             through, so the sums keep one fixed order of addition); ok False when
                             its geometry is lost. th_in, w_in: the prescribed input angle and
                             speed; beta: the stiffness-proportional damping coefficient [s].
A new coupling is one new module plus one line in REGISTRY. The assembler loops over the
registered couplings' parameters (`numba.literal_unroll`, one compiled body per coupling) and
calls `add`, which resolves at compile time to the coupling module owning that Params type and is
inlined there (so the assembled kernel is one function, as fast as the single one it replaced).
Chosen over generating the assembler's source from the registry: generated code has no source
file, so numba could not cache it and every process (12 in the load matrix) would recompile the
solvers; the registry tuple stays the only list. Order matters for bit-identical sums: mesh,
support, needle, pin (the order of the original single kernel), then housing.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import literal_unroll
from numba.extending import overload

from dynamics.couplings import housing, mesh, needle, pin, support
from dynamics.couplings.base import kernel

REGISTRY = (mesh, support, needle, pin, housing)
_ADD_BY_PARAMS = {mod.Params: mod.add for mod in REGISTRY}


class ModelArrays(NamedTuple):
    """Everything the kernels need of one model (one argument instead of the former eighteen)."""
    couplings: tuple           # each registered coupling's Params, REGISTRY order
    n_dof: int
    i_out: int                 # output (carrier) rotation: the load torque acts here
    contact_group: np.ndarray  # (n_contacts,) group counted as "in contact" (pins: the disc), -1 none
    n_groups: int


class Work(NamedTuple):
    """Mutable arrays one evaluation fills (allocate with `make_work`, reuse across calls)."""
    f: np.ndarray              # (n,) generalized force on the system
    K: np.ndarray              # (n, n) tangent stiffness -df/dq
    C: np.ndarray              # (n, n) damping -df/dv
    gap: np.ndarray            # (n_contacts,) candidate contacts' normal gap [m] (< 0: approach)
    force: np.ndarray          # (n_contacts,) their normal force [N]
    active: np.ndarray         # (n_contacts,) bool: evaluated (else known open: force 0)
    out: np.ndarray            # (n_out,) the couplings' named outputs, flat (see Slots)
    foot: np.ndarray           # (n_contacts,) a contact's last foot-point offset from its seed [rad]
    #                            (the next solve starts there: one Newton iteration fewer)
    K_rest: np.ndarray         # (n, n) the rest of the pins' -df/dq, filled when want_k at beta = 0 (the
    #                            statics' assemblies): the law's phase part (its k and n depend on the
    #                            pin's phase from the disc's line of centres, which the centre moves; not
    #                            symmetric) and the geometric part (the force times the gap's Hessian);
    #                            kept out of K, the tangent the budget, the eigenfrequencies and the time
    #                            integration use; the statics' Newton adds it (an exact tangent)


class Slots:
    """Places of the couplings' outputs and candidate contacts in the flat Work arrays."""

    def __init__(self):
        self.outputs: dict[str, tuple[int, tuple]] = {}
        self.contact_sets: dict[str, tuple[int, tuple]] = {}
        self.groups: list[np.ndarray] = []
        self.n_out = 0
        self.n_contacts = 0

    def output(self, name: str, shape: tuple) -> int:
        """Reserve a named output of `shape`; returns its offset in Work.out."""
        if name in self.outputs:
            raise ValueError(f"output {name!r} reserved twice")
        self.outputs[name] = (self.n_out, tuple(shape))
        self.n_out += int(np.prod(shape))
        return self.outputs[name][0]

    def contacts(self, name: str, shape: tuple, group: np.ndarray) -> int:
        """Reserve candidate contacts of `shape` (group: per contact, flat); returns the offset."""
        if name in self.contact_sets:
            raise ValueError(f"contacts {name!r} reserved twice")
        size = int(np.prod(shape))
        self.contact_sets[name] = (self.n_contacts, tuple(shape))
        self.groups.append(np.asarray(group, np.int64).reshape(size))
        self.n_contacts += size
        return self.contact_sets[name][0]


def build(case, stiffness, layout) -> tuple[ModelArrays, Slots]:
    """Every registered coupling's parameters, packed for the kernels."""
    slots = Slots()
    ps = tuple(mod.params(case, stiffness, layout, slots) for mod in REGISTRY)
    group = np.concatenate(slots.groups) if slots.groups else np.zeros(0, np.int64)
    arrays = ModelArrays(couplings=ps, n_dof=layout.n, i_out=layout["carrier"].index(),
                         contact_group=group, n_groups=int(group.max()) + 1 if len(group) else 0)
    return arrays, slots


def make_work(arrays: ModelArrays, slots: Slots) -> Work:
    n = arrays.n_dof
    return Work(f=np.zeros(n), K=np.zeros((n, n)), C=np.zeros((n, n)), gap=np.zeros(slots.n_contacts),
                force=np.zeros(slots.n_contacts), active=np.ones(slots.n_contacts, np.bool_),
                out=np.zeros(slots.n_out), foot=np.zeros(slots.n_contacts), K_rest=np.zeros((n, n)))


def index_of(name: str) -> int:
    """Registry index of the coupling `name` (its place in ModelArrays.couplings, `assemble`'s only)."""
    for i, mod in enumerate(REGISTRY):
        if mod.NAME == name:
            return i
    raise KeyError(f"no coupling {name!r}; registered: {', '.join(m.NAME for m in REGISTRY)}")


def params_of(arrays: ModelArrays, name: str):
    """The Params of the registered coupling `name`."""
    return arrays.couplings[index_of(name)]


def add(q, v, th_in, w_in, beta, want_k, p, w, V, tau_in):
    """Dispatch to the `add` of the coupling owning type(p) (numba only; see `_add_overload`)."""
    raise NotImplementedError("couplings.add is resolved inside numba kernels")


@overload(add, inline="always")
def _add_overload(q, v, th_in, w_in, beta, want_k, p, w, V, tau_in):
    fn = _ADD_BY_PARAMS.get(getattr(p, "instance_class", None))
    if fn is None:
        return None

    def impl(q, v, th_in, w_in, beta, want_k, p, w, V, tau_in):
        return fn(q, v, th_in, w_in, beta, want_k, p, w, V, tau_in)
    return impl


ALL = -1        # assemble's `only`: every registered coupling


@kernel
def start_solve(w):
    """Start a solve on `w`: every contact evaluated, every foot point from its conjugate seed (no
    Work.foot offset), so no result depends on what the Work solved before (the pool, Dask and
    in-process runs agree bit for bit). Every solve's start calls it (statics, time integration,
    evaluate); a new per-solve field of Work is reset here."""
    w.active[:] = True
    w.foot[:] = 0.0


@kernel
def assemble(q, v, th_in, w_in, beta, want_k, m, w, only):
    """Internal generalized force w.f (on the system), tangent w.K = -df/dq and damping
    w.C = -df/dv (when want_k) of every coupling (only = ALL) or of the one at registry index
    `only` (the compliance budget's per-coupling tangents: the same model type, so the same
    compiled assembly; a model of one coupling would compile it again for each); fills the
    contacts' gap/force and the named outputs. Only contacts with w.active are evaluated.
    Returns (potential energy, input torque, ok)."""
    w.f[:] = 0.0
    if want_k:
        w.K[:, :] = 0.0
        w.C[:, :] = 0.0
        if beta == 0.0:
            w.K_rest[:, :] = 0.0
    V = 0.0
    tau_in = 0.0
    ok = True
    k = 0
    for p in literal_unroll(m.couplings):
        if only < 0 or k == only:
            V, tau_in, okc = add(q, v, th_in, w_in, beta, want_k, p, w, V, tau_in)
            ok = ok and okc
        k += 1
    return V, tau_in, ok
