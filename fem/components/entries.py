"""The frozen entries of stiffness.json that the lumped model reads (SI units in every name); one
home, imported by the components that make them and re-exported by fem.stiffness (the schema)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PinContact:
    position_deg: np.ndarray
    load_N: np.ndarray
    approach_m: np.ndarray
    peak_pressure_Pa: np.ndarray
    half_width_m: np.ndarray
    law_k_N_per_m_pow: np.ndarray
    law_n: np.ndarray

    def force_N(self, approach_m: np.ndarray, position_deg: np.ndarray) -> np.ndarray:
        """Normal force for an approach (<= 0 gives 0) at a pin phase, law interpolated in phase."""
        pos = np.clip(np.abs((np.asarray(position_deg) + 180.0) % 360.0 - 180.0),
                      self.position_deg[0], self.position_deg[-1])
        k = np.interp(pos, self.position_deg, self.law_k_N_per_m_pow)
        n = np.interp(pos, self.position_deg, self.law_n)
        d = np.maximum(np.asarray(approach_m, dtype=float), 0.0)
        return k * d ** n


@dataclass(frozen=True)
class TurningArm:
    load_N: np.ndarray
    deflection_m: np.ndarray
    law_k_N_per_m_pow: float
    law_n: float


@dataclass(frozen=True)
class SupportBearings:
    """One crank support bearing (two per crank, one at each journal), radial."""
    designation: str
    roller_count: int
    roller_length_m: float
    roller_diameter_m: float
    contact_angle_deg: float
    preload_N: float
    load_N: np.ndarray
    deflection_m: np.ndarray
    operating_load_N: float
    stiffness_N_per_m: float          # tangent at operating_load_N: the model's spring per bearing


@dataclass(frozen=True)
class CrankBending:
    compliance_m_per_N: np.ndarray    # (2, 2) eccentric i per N on eccentric j, shaft alone, pinned
    journal_force: np.ndarray         # (2, 2) journal s (J1 end plate, J2 flange) per N on eccentric i


@dataclass(frozen=True)
class CarrierSeats:
    compliance_m_per_N: np.ndarray    # (4 nc, 4 nc) crank, seat (flange, end plate), (x, y)


@dataclass(frozen=True)
class PinSeries:
    disc_body_compliance_m_per_N: float
    groove_load_N: np.ndarray
    groove_approach_m: np.ndarray

    def groove_m(self, force_N):
        """Housing approach at a pin force (power law through the table's ends beyond it)."""
        F = np.atleast_1d(np.maximum(np.asarray(force_N, float), 0.0))
        L, d = self.groove_load_N, self.groove_approach_m
        n = np.log(d[-1] / d[0]) / np.log(L[-1] / L[0])
        out = np.interp(F, L, d)
        lo, hi = F < L[0], F > L[-1]
        out[lo] = d[0] * (F[lo] / L[0]) ** n
        out[hi] = d[-1] * (F[hi] / L[-1]) ** n
        return out
