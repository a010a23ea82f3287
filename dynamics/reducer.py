"""The lumped reducer model object: DOF layout, packed coupling arrays, masses (physics: dynamics.model).

`build_model` checks the stiffness against the case, lays out the DOFs (`dynamics.layout`), asks
every registered coupling (`dynamics.couplings.REGISTRY`) for its parameters and takes the body
inertias from `dynamics.bodies`. `evaluate` is the Python entry to the assembler.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dynamics import bodies, couplings
from dynamics.couplings import ModelArrays, Slots, Work
from dynamics.layout import DofLayout
from fem.stiffness import StiffnessModel
from geometry.artifacts import InputError
from geometry.params import ReducerCase

ROT_SCALE_M = 0.05           # lever arm that makes rotations comparable with translations [m]


class DynamicsError(InputError):
    """A model that cannot be built or a solver that did not converge on the user's input."""


@dataclass(frozen=True)
class ReducerModel:
    case: ReducerCase
    stiffness: StiffnessModel
    layout: DofLayout
    arrays: ModelArrays      # what the numba kernels take (dynamics.couplings)
    slots: Slots             # where each coupling's outputs and contacts sit in a Work
    mass: np.ndarray         # (n,) diagonal mass matrix [kg | kg m^2]
    scale: np.ndarray        # (n,) ROT_SCALE_M for rotations, 1 for translations
    ratio: float
    coaxiality_rad: float    # e / r of the output mounting offset
    coaxiality_phase_rad: float
    reading_lobes: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))   # rows (m, a / r, phase rad)

    @property
    def n_dof(self) -> int:
        return self.layout.n

    @property
    def n_disc(self) -> int:
        return self.layout["disc"].count

    @property
    def n_crank(self) -> int:
        return self.layout["crank_rotation"].count

    @property
    def labels(self) -> tuple:
        return self.layout.labels

    @property
    def i_out(self) -> int:
        """Index of the output (carrier) rotation in q."""
        return self.arrays.i_out

    def disc_index(self, d: int) -> int:
        """Index of disc d's centre x in q (then y, rotation)."""
        return self.layout["disc"].index(d)

    def params(self, coupling: str):
        """Parameters of a registered coupling (e.g. "pin", "needle")."""
        return couplings.params_of(self.arrays, coupling)

    def work(self) -> Work:
        return couplings.make_work(self.arrays, self.slots)

    def output(self, w: Work, name: str) -> np.ndarray:
        """A coupling's named output (e.g. "bearing_force_N") from a Work, shaped, copied."""
        off, shape = self.slots.outputs[name]
        return w.out[off:off + int(np.prod(shape))].reshape(shape).copy()

    def contacts(self, arr: np.ndarray, name: str = "pin") -> np.ndarray:
        """A contact set's part (shaped) of a per-contact array (Work.gap / .force or a sample row)."""
        off, shape = self.slots.contact_sets[name]
        return arr[..., off:off + int(np.prod(shape))].reshape(arr.shape[:-1] + shape).copy()

    def measured_output_rad(self, carrier_rad):
        """What an output encoder reads: carrier angle + coaxiality (e/r) sin(theta + phase)
        + the reading lobes (a/r) cos(m theta - phase)."""
        out = carrier_rad + self.coaxiality_rad * np.sin(carrier_rad + self.coaxiality_phase_rad)
        for m, a, ph in self.reading_lobes:
            out = out + a * np.cos(m * carrier_rad - ph)
        return out


def build_model(case: ReducerCase, stiffness: StiffnessModel) -> ReducerModel:
    """Precompute the arrays of the lumped model (cheap: no solve)."""
    if stiffness.case_name != case.name:
        raise DynamicsError(f"stiffness for case {stiffness.case_name!r} given to case {case.name!r}: "
                            f"run `python -m pipeline fem --case` on this case")
    stiffness.check()
    hm = stiffness.parts.get("housing")
    layout = DofLayout.standard(case.carrier.crank_count, case.cycloid.disc_count,
                                0 if hm is None else len(hm.stiffness_N_per_m))
    arrays, slots = couplings.build(case, stiffness, layout)
    er = case.errors
    return ReducerModel(case=case, stiffness=stiffness, layout=layout, arrays=arrays, slots=slots,
                        mass=layout.vector(bodies.inertias(case, stiffness)), scale=layout.scale(ROT_SCALE_M),
                        ratio=case.ratio,
                        coaxiality_rad=er.output_coaxiality_um * 1e-6 / case.si.output_flange_radius_m,
                        coaxiality_phase_rad=np.deg2rad(er.output_coaxiality_phase_deg),
                        reading_lobes=np.array([(m, a * 1e-3 / case.carrier.output_flange_radius_mm, np.deg2rad(ph))
                                                for m, a, ph in er.output_reading_lobes], float).reshape(-1, 3))


def evaluate(model: ReducerModel, q: np.ndarray, input_rad: float, want_k: bool = False,
             w: Work | None = None) -> tuple[Work, float]:
    """Forces (and tangent) of every coupling at rest at state q, every contact evaluated:
    (the filled Work, input torque). Undamped (beta = 0)."""
    w = model.work() if w is None else w
    couplings.start_solve(w)
    _, tau, _ = couplings.assemble(np.asarray(q, float), np.zeros(model.n_dof), float(input_rad), 0.0, 0.0,
                                   bool(want_k), model.arrays, w, couplings.ALL)
    return w, float(tau)
