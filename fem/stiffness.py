"""The stiffness artifact: what the FEM stage hands the dynamics stage (`stiffness.json`).

Schema `rv-stiffness/4`, SI units in every key. Every compliance is an FE result of this project's
own geometry or a closed form applied to stated geometry; `sources` says which, `checks` gives each
one's FE-vs-closed-form comparison. No entry is scaled or fitted to a target.

pin_contact        one cycloid tooth against one pin, 2D plane strain times the disc width:
  position_deg       (P,) pin phase from the line of centres (0 = towards the eccentric, deg)
  load_N             (L,) normal contact force levels
  approach_m         (P, L) normal approach of pin centre towards disc body (both bodies + pin)
  peak_pressure_Pa   (P, L) FE peak contact pressure
  half_width_m       (P, L) FE contact half-width
  law_k_N_per_m_pow  (P,)  fitted F = k * approach**n at each position
  law_n              (P,)  exponent of that fit
turning_arm          needle bearing between eccentric and disc crank hole, radial:
  load_N (L,), deflection_m (L,), law_k_N_per_m_pow, law_n
crankshaft           eccentric-centre compliance of the shaft on its support bearings:
  bending_stiffness_N_per_m (lateral, at an eccentric), torsional_stiffness_Nm_per_rad (planet to eccentric)
support_bearings     one crank support bearing (a standard tapered roller bearing, fem.tapered_roller):
  designation, roller_count, roller_length_m, roller_diameter_m, contact_angle_deg, preload_N,
  load_N (L,), deflection_m (L,) its radial load-deflection (preloaded pair, per bearing),
  operating_load_N (per bearing at rated torque), stiffness_N_per_m (tangent there: the model's
  linear spring per bearing, isotropic)
crank_bending        the shaft alone between its two eccentrics (fem.crank_tilt, 3D FE), pinned at the
  support bearings' pressure centres: compliance_m_per_N (2, 2) lateral displacement of eccentric i per N on
  eccentric j (mean of x and y), journal_force (2, 2) reaction at journal s (0: J1, end-plate side;
  1: J2, flange side) per N on eccentric i
carrier              seat flexibility of the carrier (fem.carrier, 3D FE): compliance_m_per_N
  (4 nc, 4 nc), order crank j, seat (flange, end plate), direction (x, y), carrier frame with
  crank j at angle 2 pi j / nc
pin_series           what lies in series with each cycloid-pin contact besides the tooth-pair FE:
  disc_body_compliance_m_per_N (fem.disc_body: tooth ring against crank holes, per pin, energy-
  equivalent under the classical sharing), groove_load_N (G,), groove_approach_m (G,) (fem.pin_groove:
  housing behind the pin's groove)
checks               per entry, the FE figure beside its closed form (free form, reported)
involute_mesh        mean_stiffness_N_per_m, stiffness_variation (peak-to-peak / mean), contact_ratio
made_from            what it was made from (geometry.fingerprint.Provenance: case fingerprint, input
                     mesh fingerprint); null only for models built in memory (tests). Read for a case
                     (`for_case`, `path_for_case`, `load(path, case)`), a file made from another case
                     or another version of it is refused. Schema 2 added made_from; schema 3 the support bearings,
                     crank bending matrix, carrier and pin series parts (issue 11); schema 4 `parts`: the
                     entries of the components registered without a field of their own (joints,
                     main_bearings, housing: fem.components, each with its to_json / from_json).

Composition for the lumped model (pure functions of this file, so that the dynamics and the
compliance budget read one definition): `support_compliance_parts` (crank-axis displacement per
disc plane, carrier frame) and `pin_law` (tooth-pin law with the series parts, refitted).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fem.components import COMPONENTS, REGISTRY, by_name, in_coupling
from fem.components.entries import CarrierSeats, CrankBending, PinContact, PinSeries, SupportBearings, TurningArm
from geometry.artifacts import InputError, read_json, write_json_atomic
from geometry.fingerprint import Provenance

SCHEMA = "rv-stiffness/4"

# components of the compliance path, in path order: fem.components.REGISTRY (one module each)


class StiffnessError(InputError):
    """A stiffness.json that does not follow the schema."""


@dataclass(frozen=True)
class StiffnessModel:
    case_name: str
    pin_contact: PinContact
    turning_arm: TurningArm
    crankshaft_bending_stiffness_N_per_m: float
    crankshaft_torsional_stiffness_Nm_per_rad: float
    involute_mesh_mean_stiffness_N_per_m: float
    involute_mesh_stiffness_variation: float
    involute_mesh_contact_ratio: float
    support_bearings: SupportBearings = None
    crank_bending: CrankBending = None
    carrier: CarrierSeats = None
    pin_series: PinSeries = None
    parts: dict = field(default_factory=dict)     # component name -> its entry, for the components without a
                                                  # field above (fem.components: to_json / from_json)
    sources: dict = field(default_factory=dict)   # quantity -> where it comes from
    checks: dict = field(default_factory=dict)    # entry -> FE figure beside its closed form
    extras: dict = field(default_factory=dict)    # mesh sizes, convergence (free form)
    made_from: Provenance | None = None           # case and input fingerprints (None: in memory only)

    @property
    def support_bearing_radial_stiffness_N_per_m(self) -> float:
        return float(self.support_bearings.stiffness_N_per_m)

    def stiffened(self, component: str, factor: float) -> "StiffnessModel":
        """A copy with one component's compliance divided by `factor` (component in COMPONENTS, or
        "all"): what-if studies and the diagnosis' located compliances."""
        f = float(factor)
        if not (np.isfinite(f) and f > 0):
            raise ValueError(f"stiffening factor {factor!r}: must be finite and > 0")
        if component == "all":
            m = self
            for c in REGISTRY:
                m = c.stiffen(m, f)
            return m
        try:
            comp = by_name(component)
        except ValueError:
            raise ValueError(f"component {component!r}: allowed {', '.join(COMPONENTS)} or 'all'") from None
        return comp.stiffen(self, f)

    def to_json(self) -> dict:
        pc, ta = self.pin_contact, self.turning_arm
        arr = lambda a: np.asarray(a, dtype=float).tolist()  # noqa: E731
        return {
            "schema": SCHEMA,
            "case": self.case_name,
            "pin_contact": {k: arr(getattr(pc, k)) for k in
                            ("position_deg", "load_N", "approach_m", "peak_pressure_Pa",
                             "half_width_m", "law_k_N_per_m_pow", "law_n")},
            "turning_arm": {"load_N": arr(ta.load_N), "deflection_m": arr(ta.deflection_m),
                            "law_k_N_per_m_pow": float(ta.law_k_N_per_m_pow),
                            "law_n": float(ta.law_n)},
            "crankshaft": {"bending_stiffness_N_per_m": float(self.crankshaft_bending_stiffness_N_per_m),
                           "torsional_stiffness_Nm_per_rad":
                               float(self.crankshaft_torsional_stiffness_Nm_per_rad)},
            "support_bearings": {k: (arr(v) if isinstance(v, np.ndarray) else v)
                                 for k, v in vars(self.support_bearings).items()},
            "crank_bending": {"compliance_m_per_N": arr(self.crank_bending.compliance_m_per_N),
                              "journal_force": arr(self.crank_bending.journal_force)},
            "carrier": {"compliance_m_per_N": arr(self.carrier.compliance_m_per_N)},
            "pin_series": {"disc_body_compliance_m_per_N": float(self.pin_series.disc_body_compliance_m_per_N),
                           "groove_load_N": arr(self.pin_series.groove_load_N),
                           "groove_approach_m": arr(self.pin_series.groove_approach_m)},
            "involute_mesh": {"mean_stiffness_N_per_m": float(self.involute_mesh_mean_stiffness_N_per_m),
                              "stiffness_variation": float(self.involute_mesh_stiffness_variation),
                              "contact_ratio": float(self.involute_mesh_contact_ratio)},
            "parts": {k: by_name(k).to_json(v) for k, v in self.parts.items()},
            "sources": self.sources,
            "checks": self.checks,
            "extras": self.extras,
            "made_from": None if self.made_from is None else self.made_from.to_json(),
        }

    @classmethod
    def from_json(cls, data: dict, where: str = "stiffness.json") -> "StiffnessModel":
        if data.get("schema") != SCHEMA:
            raise StiffnessError(f"{where}: schema {data.get('schema')!r}, expected {SCHEMA!r}: "
                                 f"rebuild it with `python -m pipeline fem`")
        made = data.get("made_from")
        made = None if made is None else Provenance.from_json(made, where)
        try:
            pc = {k: np.asarray(v, dtype=float) for k, v in data["pin_contact"].items()}
            ta = data["turning_arm"]
            model = cls(
                case_name=data["case"],
                pin_contact=PinContact(**pc),
                turning_arm=TurningArm(np.asarray(ta["load_N"], float),
                                       np.asarray(ta["deflection_m"], float),
                                       float(ta["law_k_N_per_m_pow"]), float(ta["law_n"])),
                crankshaft_bending_stiffness_N_per_m=float(data["crankshaft"]["bending_stiffness_N_per_m"]),
                crankshaft_torsional_stiffness_Nm_per_rad=float(
                    data["crankshaft"]["torsional_stiffness_Nm_per_rad"]),
                involute_mesh_mean_stiffness_N_per_m=float(data["involute_mesh"]["mean_stiffness_N_per_m"]),
                involute_mesh_stiffness_variation=float(data["involute_mesh"]["stiffness_variation"]),
                involute_mesh_contact_ratio=float(data["involute_mesh"]["contact_ratio"]),
                support_bearings=_support_bearings(data["support_bearings"]),
                crank_bending=CrankBending(np.asarray(data["crank_bending"]["compliance_m_per_N"], float),
                                           np.asarray(data["crank_bending"]["journal_force"], float)),
                carrier=CarrierSeats(np.asarray(data["carrier"]["compliance_m_per_N"], float)),
                pin_series=PinSeries(float(data["pin_series"]["disc_body_compliance_m_per_N"]),
                                     np.asarray(data["pin_series"]["groove_load_N"], float),
                                     np.asarray(data["pin_series"]["groove_approach_m"], float)),
                parts={k: by_name(k).from_json(v) for k, v in data.get("parts", {}).items()},
                sources=data.get("sources", {}), checks=data.get("checks", {}), extras=data.get("extras", {}),
                made_from=made)
        except (KeyError, TypeError, ValueError) as exc:
            raise StiffnessError(f"{where}: missing or malformed entry {exc}") from None
        missing = [c.NAME for c in REGISTRY if hasattr(c, "to_json") and c.NAME not in model.parts]
        if missing:
            raise StiffnessError(f"{where}: no parts entry for {', '.join(missing)} (schema {SCHEMA} needs every "
                                 f"component of the path): rebuild it with `python -m pipeline fem`")
        model.check(where)
        return model

    def check(self, where: str = "stiffness") -> None:
        pc = self.pin_contact
        P, L = len(pc.position_deg), len(pc.load_N)
        for name in ("approach_m", "peak_pressure_Pa", "half_width_m"):
            if getattr(pc, name).shape != (P, L):
                raise StiffnessError(f"{where}: pin_contact.{name} has shape "
                                     f"{getattr(pc, name).shape}, expected ({P}, {L})")
        if np.any(np.diff(pc.position_deg) <= 0):
            raise StiffnessError(f"{where}: pin_contact.position_deg must increase")
        for name in ("support_bearings", "crank_bending", "carrier", "pin_series"):
            if getattr(self, name) is None:
                raise StiffnessError(f"{where}: no {name} entry (schema {SCHEMA} needs every part of the path)")
        sb, cb, ps = self.support_bearings, self.crank_bending, self.pin_series
        scalars = [self.crankshaft_bending_stiffness_N_per_m, self.crankshaft_torsional_stiffness_Nm_per_rad,
                   sb.stiffness_N_per_m, self.involute_mesh_mean_stiffness_N_per_m,
                   self.turning_arm.law_k_N_per_m_pow, *pc.law_k_N_per_m_pow]
        if not all(np.isfinite(v) and v > 0 for v in scalars):
            raise StiffnessError(f"{where}: every stiffness must be finite and positive")
        if cb.compliance_m_per_N.shape != (2, 2) or cb.journal_force.shape != (2, 2):
            raise StiffnessError(f"{where}: crank_bending needs (2, 2) compliance and journal_force "
                                 f"(two eccentrics, two journals)")
        Cc = self.carrier.compliance_m_per_N
        if Cc.ndim != 2 or Cc.shape[0] != Cc.shape[1] or Cc.shape[0] % 4:
            raise StiffnessError(f"{where}: carrier.compliance_m_per_N has shape {Cc.shape}, expected (4 nc, 4 nc)")
        for name, M in (("crank_bending", cb.compliance_m_per_N), ("carrier", Cc)):
            if not np.all(np.isfinite(M)) or np.linalg.eigvalsh(0.5 * (M + M.T)).min() < -1e-9 * np.abs(M).max():
                raise StiffnessError(f"{where}: {name} compliance must be finite, symmetric positive semidefinite")
        if not (np.isfinite(ps.disc_body_compliance_m_per_N) and ps.disc_body_compliance_m_per_N >= 0):
            raise StiffnessError(f"{where}: pin_series.disc_body_compliance_m_per_N must be finite and >= 0")
        for name, a in (("support_bearings.load_N", sb.load_N), ("pin_series.groove_load_N", ps.groove_load_N)):
            if len(a) < 2 or np.any(np.diff(a) <= 0) or a[0] <= 0:
                raise StiffnessError(f"{where}: {name} must be >= 2 increasing positive loads")
        if np.any(ps.groove_approach_m <= 0) or np.any(np.diff(ps.groove_approach_m) <= 0):
            raise StiffnessError(f"{where}: pin_series.groove_approach_m must be positive and increasing")


def _support_bearings(d: dict) -> SupportBearings:
    return SupportBearings(str(d["designation"]), int(d["roller_count"]), float(d["roller_length_m"]),
                           float(d["roller_diameter_m"]), float(d["contact_angle_deg"]), float(d["preload_N"]),
                           np.asarray(d["load_N"], float), np.asarray(d["deflection_m"], float),
                           float(d["operating_load_N"]), float(d["stiffness_N_per_m"]))


# ----------------------------------------------------------------------------- composition
SEAT_OF_JOURNAL = (1, 0)   # journal J1 (end-plate side) -> carrier seat 1, J2 (flange side) -> seat 0


def seat_transfer(model: StiffnessModel, n_crank: int) -> np.ndarray:
    """(4 nc, 2 nc nd) seat forces (crank j, seat (flange, end plate), x, y) per eccentric force
    (crank j, disc plane d, x, y): the crank a beam pinned at its supports' pressure centres (statics)."""
    P = model.crank_bending.journal_force          # (journal s, eccentric d)
    nd = P.shape[1]
    T = np.zeros((4 * n_crank, 2 * n_crank * nd))
    for j in range(n_crank):
        for s in range(2):
            for d in range(nd):
                for c in range(2):
                    T[4 * j + 2 * SEAT_OF_JOURNAL[s] + c, 2 * (j * nd + d) + c] = P[s, d]
    return T


def support_compliance_parts(model: StiffnessModel, n_crank: int) -> dict:
    """The crank support path as compliances between the eccentric forces and the crank axis
    displacement at each disc plane (crank j, plane d, x, y; carrier frame), one matrix per
    component of the support coupling (fem.components: `support_part`), summing to the path's
    compliance (loads reach the carrier through the bearings; T the crank statics, seat_transfer)."""
    if model.carrier.compliance_m_per_N.shape != (4 * n_crank, 4 * n_crank):
        raise StiffnessError(f"carrier compliance has shape {model.carrier.compliance_m_per_N.shape}: "
                             f"expected ({4 * n_crank}, {4 * n_crank}) for {n_crank} cranks")
    T = seat_transfer(model, n_crank)
    return {c.NAME: c.support_part(model, T, n_crank) for c in in_coupling("support")}


def support_stiffness_matrix(model: StiffnessModel, n_crank: int) -> np.ndarray:
    """Inverse of the summed support compliance (symmetric positive definite)."""
    C = sum(support_compliance_parts(model, n_crank).values())
    K = np.linalg.inv(0.5 * (C + C.T))
    return 0.5 * (K + K.T)


def pin_series_tangents(model: StiffnessModel, force_N, law_k, law_n) -> dict:
    """Tangent compliances d(approach)/dF [m/N] of the parts in series at one cycloid-pin contact:
    the tooth pair on its law (k, n at the contact's phase) and every other pin component's
    `series_approach_m` (central difference)."""
    F = np.maximum(np.asarray(force_N, float), 1e-9)
    dF = 1e-3 * F
    out = {}
    for c in in_coupling("pin"):
        if c.NAME == "pin_contact":
            out[c.NAME] = c.tangent_m_per_N(F, law_k, law_n)
        else:
            out[c.NAME] = (c.series_approach_m(model, F + dF) - c.series_approach_m(model, F - dF)) / (2 * dF)
    return out


def pin_law(model: StiffnessModel) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The cycloid-pin law the lumped model uses, per pin phase: F = k a^n refitted (log-log least
    squares over the tabulated loads) to the total approach: tooth pair FE + every pin component in
    series (fem.components, `series_approach_m`). Returns (position_deg, k, n, max relative force
    error of the refit over the table)."""
    pc = model.pin_contact
    L = pc.load_N
    total = pc.approach_m + sum(np.asarray(c.series_approach_m(model, L), float)[None, :]
                                for c in in_coupling("pin") if c.NAME != "pin_contact")
    k, n, err = np.zeros(len(pc.position_deg)), np.zeros(len(pc.position_deg)), np.zeros(len(pc.position_deg))
    for i, a in enumerate(total):
        nn, lk = np.polyfit(np.log(a), np.log(L), 1)
        k[i], n[i] = np.exp(lk), nn
        err[i] = np.max(np.abs(k[i] * a ** nn / L - 1.0))
    return pc.position_deg, k, n, err


def save(model: StiffnessModel, path: str | Path) -> None:
    write_json_atomic(path, model.to_json())


def rerun_command(case, path: str | Path) -> str:
    return f"python -m pipeline fem --case {case.source or case.name} --out {Path(path).parent}"


def check_made_from(model_or_json, case, path: str | Path) -> None:
    """Refuse a stiffness (model or its JSON) not made from `case` as it is now (its fingerprint)."""
    made = model_or_json.get("made_from") if isinstance(model_or_json, dict) else model_or_json.made_from
    where = str(path)
    if not isinstance(made, Provenance):
        made = Provenance.from_json(made, where)
    made.check(case, where, rerun_command(case, path), artifact=SCHEMA)


def _existing(case, path: str | Path | None) -> Path:
    path = Path(path) if path else Path("build") / case.name / "fem" / "stiffness.json"
    if not path.exists():
        raise StiffnessError(f"--stiffness {path}: not found; run `{rerun_command(case, path)}` first "
                             f"(or pass --stiffness PATH)")
    return path


def path_for_case(case, path: str | Path | None = None) -> Path:
    """`path`, or the fem stage's artifact build/<case name>/fem/stiffness.json under the current
    folder, checked to be made from this case (schema and fingerprint); a missing or foreign file
    names the command that makes it."""
    path = _existing(case, path)
    check_made_from(_read_json(path), case, path)
    return path


def for_case(case, path: str | Path | None = None) -> StiffnessModel:
    """The stiffness of a case (see `path_for_case`)."""
    return load(_existing(case, path), case)


def load(path: str | Path, case=None) -> StiffnessModel:
    """Read a stiffness.json; with `case`, refuse one made from another case or case version."""
    path = Path(path)
    data = _read_json(path)
    model = StiffnessModel.from_json(data, str(path))
    if case is not None:
        check_made_from(model, case, path)
    return model


def _read_json(path: Path) -> dict:
    data = read_json(path, name=str(path), missing_hint="run `python -m pipeline fem` first", error=StiffnessError)
    if not isinstance(data, dict) or data.get("schema") != SCHEMA:
        got = data.get("schema") if isinstance(data, dict) else type(data).__name__
        raise StiffnessError(f"{path}: schema {got!r}, expected {SCHEMA!r}: rebuild it with "
                             f"`python -m pipeline fem`")
    return data


__all__ = ["SCHEMA", "COMPONENTS", "REGISTRY", "in_coupling", "StiffnessModel", "PinContact", "TurningArm", "SupportBearings",
           "CrankBending", "CarrierSeats", "PinSeries", "support_compliance_parts", "support_stiffness_matrix",
           "pin_law", "pin_series_tangents", "StiffnessError", "save", "load",
           "for_case", "path_for_case", "check_made_from"]
