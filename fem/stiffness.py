"""The stiffness artifact: what the FEM stage hands the dynamics stage (`stiffness.json`).

Schema `rv-stiffness/2`, SI units in every key. All compliances are FE results of this project's
own geometry except where `sources` says otherwise (the involute mesh uses ISO 6336-1's single-
tooth stiffness, the support bearings the case file's assumed catalog figure).

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
support_bearing      radial_stiffness_N_per_m (per bearing)
involute_mesh        mean_stiffness_N_per_m, stiffness_variation (peak-to-peak / mean), contact_ratio
made_from            what it was made from (geometry.fingerprint.Provenance: case fingerprint, input
                     mesh fingerprint); null only for models built in memory (tests). Read for a case
                     (`for_case`, `path_for_case`, `load(path, case)`), a file made from another case
                     or another version of it is refused. Schema 2 added made_from.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from geometry.artifacts import InputError, write_json_atomic
from geometry.fingerprint import Provenance

SCHEMA = "rv-stiffness/2"


class StiffnessError(InputError):
    """A stiffness.json that does not follow the schema."""


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
class StiffnessModel:
    case_name: str
    pin_contact: PinContact
    turning_arm: TurningArm
    crankshaft_bending_stiffness_N_per_m: float
    crankshaft_torsional_stiffness_Nm_per_rad: float
    support_bearing_radial_stiffness_N_per_m: float
    involute_mesh_mean_stiffness_N_per_m: float
    involute_mesh_stiffness_variation: float
    involute_mesh_contact_ratio: float
    sources: dict = field(default_factory=dict)   # quantity -> where it comes from
    extras: dict = field(default_factory=dict)    # mesh sizes, convergence, checks (free form)
    made_from: Provenance | None = None           # case and input fingerprints (None: in memory only)

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
            "support_bearing": {"radial_stiffness_N_per_m":
                                float(self.support_bearing_radial_stiffness_N_per_m)},
            "involute_mesh": {"mean_stiffness_N_per_m": float(self.involute_mesh_mean_stiffness_N_per_m),
                              "stiffness_variation": float(self.involute_mesh_stiffness_variation),
                              "contact_ratio": float(self.involute_mesh_contact_ratio)},
            "sources": self.sources,
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
                support_bearing_radial_stiffness_N_per_m=float(
                    data["support_bearing"]["radial_stiffness_N_per_m"]),
                involute_mesh_mean_stiffness_N_per_m=float(data["involute_mesh"]["mean_stiffness_N_per_m"]),
                involute_mesh_stiffness_variation=float(data["involute_mesh"]["stiffness_variation"]),
                involute_mesh_contact_ratio=float(data["involute_mesh"]["contact_ratio"]),
                sources=data.get("sources", {}), extras=data.get("extras", {}), made_from=made)
        except (KeyError, TypeError) as exc:
            raise StiffnessError(f"{where}: missing or malformed entry {exc}") from None
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
        scalars = [self.crankshaft_bending_stiffness_N_per_m, self.crankshaft_torsional_stiffness_Nm_per_rad,
                   self.support_bearing_radial_stiffness_N_per_m, self.involute_mesh_mean_stiffness_N_per_m,
                   self.turning_arm.law_k_N_per_m_pow, *pc.law_k_N_per_m_pow]
        if not all(np.isfinite(v) and v > 0 for v in scalars):
            raise StiffnessError(f"{where}: every stiffness must be finite and positive")


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
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise StiffnessError(f"{path}: not found (run `python -m pipeline fem` first)") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise StiffnessError(f"{path}: not valid JSON ({exc})") from None
    except OSError as exc:
        raise StiffnessError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    if not isinstance(data, dict) or data.get("schema") != SCHEMA:
        got = data.get("schema") if isinstance(data, dict) else type(data).__name__
        raise StiffnessError(f"{path}: schema {got!r}, expected {SCHEMA!r}: rebuild it with "
                             f"`python -m pipeline fem`")
    return data


__all__ = ["SCHEMA", "StiffnessModel", "PinContact", "TurningArm", "StiffnessError", "save", "load",
           "for_case", "path_for_case", "check_made_from"]
