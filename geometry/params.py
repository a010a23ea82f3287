"""Reducer parameters: one validated source for every stage.

A case file (TOML, read with the standard library) maps one-to-one onto the frozen dataclasses
below. Every physical field is required in the case file (the case file says where each figure
comes from: a paper, the catalog, or an assumption); only the error sources default to zero.
Units are in the field names (mm, deg, GPa, ...); stages convert to SI at their own edges.

Limits: the checks here are necessary conditions for a buildable second stage (conjugate cycloid,
no cusp, no undercut of the modified profile, from the closed-form curvature of
`geometry.pin_profile`), not a design code; sizes are bounded where a stage's cost grows with them
(pin count `ZP_MAX`, case file size).
"""
from __future__ import annotations

import dataclasses
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from geometry.artifacts import InputError
from geometry.pin_profile import min_convex_radius_mm

# Largest pin count accepted. Real cycloid reducers stay below it: RV reducers carry ~40 pins and
# the finest single-stage cycloid drives (Sumitomo Cyclo, 119:1) have zc = 119, zp = 120. The
# geometry stage's CAD outline is one spline per tooth and its deviation check samples each tooth,
# so cost grows with zp; a 400-pin case asked for 30 GiB before the seed search was windowed.
ZP_MAX = 120
NAME_PATTERN = re.compile(r"[A-Za-z0-9._-]{1,100}")   # the name becomes the build folder's name
CASE_FILE_MAX_BYTES = 1 << 20                           # a case file is a few kB of TOML


class CaseError(InputError):
    """A case file that cannot describe a buildable reducer; the message names key, value, range."""


def _f(lo: float | None = None, hi: float | None = None, *, open_lo: bool = True,
       open_hi: bool = False, why: str = "", default: Any = dataclasses.MISSING) -> Any:
    """A field with an allowed range (open at lo by default: sizes must be positive); `why` is
    added to the message when a value falls outside."""
    md = {"lo": lo, "hi": hi, "open_lo": open_lo, "open_hi": open_hi, "why": why}
    if default is dataclasses.MISSING:
        return field(metadata=md)
    if isinstance(default, (list, tuple)):
        return field(default=tuple(default), metadata=md)
    return field(default=default, metadata=md)


@dataclass(frozen=True)
class Cycloid:
    pin_circle_radius_mm: float = _f(0.0)      # R
    pin_radius_mm: float = _f(0.0)             # Rr
    zc: int = _f(2, open_lo=False)              # cycloid teeth
    zp: int = _f(3, ZP_MAX, open_lo=False,      # pins
                 why=f"the largest pin count of real cycloid reducers is ~{ZP_MAX} (Sumitomo Cyclo "
                     f"119:1); the geometry stage's cost grows with zp")
    eccentricity_mm: float = _f(0.0)           # E
    width_mm: float = _f(0.0)                  # one disc's face width
    disc_count: int = _f(1, 2, open_lo=False)   # discs, 180 deg apart when 2


@dataclass(frozen=True)
class Modification:
    offset_mm: float = _f(-5.0, 5.0)           # dR (moved distance), < 0 opens clearance
    equidistant_mm: float = _f(-5.0, 5.0)      # dRr, > 0 opens clearance
    rotation_deg: float = _f(-5.0, 5.0)        # delta, profile rotation


@dataclass(frozen=True)
class Stage1:
    z1: int = _f(6, open_lo=False)              # sun (input) teeth
    z2: int = _f(6, open_lo=False)              # planet teeth
    module_mm: float = _f(0.0)
    face_width_mm: float = _f(0.0)
    pressure_angle_deg: float = _f(10.0, 35.0)


@dataclass(frozen=True)
class Carrier:
    crank_count: int = _f(1, 6, open_lo=False)
    crank_circle_radius_mm: float = _f(0.0)     # radius of the crankshaft axes on the carrier
    pillar_count: int = _f(0, 6, open_lo=False)
    pillar_circle_radius_mm: float = _f(0.0)
    pillar_radius_mm: float = _f(0.0)
    output_flange_radius_mm: float = _f(0.0)    # lever arm of a mounting (coaxiality) offset


@dataclass(frozen=True)
class Disc:
    crank_hole_radius_mm: float = _f(0.0)       # bore for the needle bearing outer race (= disc itself)
    centre_hole_radius_mm: float = _f(0.0, open_lo=False)
    pillar_hole_clearance_mm: float = _f(0.0)   # radial play of pillars in their disc holes


@dataclass(frozen=True)
class Crankshaft:
    eccentric_radius_mm: float = _f(0.0)        # needle inner race
    journal_radius_mm: float = _f(0.0)          # support-bearing seats
    journal_length_mm: float = _f(0.0)
    support_span_mm: float = _f(0.0)            # between support-bearing centres
    needle_diameter_mm: float = _f(0.0)
    needle_length_mm: float = _f(0.0)
    needle_count: int = _f(4, open_lo=False)
    support_bearing_stiffness_N_per_um: float = _f(0.0)   # radial, per bearing (catalog/assumed)


@dataclass(frozen=True)
class Material:
    youngs_modulus_GPa: float = _f(0.0)
    poisson_ratio: float = _f(0.0, 0.5, open_lo=False, open_hi=True,
                              why="0.5 is incompressible: plane-strain FE divides by 1 - 2 nu")
    density_kg_per_m3: float = _f(0.0)


@dataclass(frozen=True)
class Operation:
    input_speed_rpm: float = _f(0.0)
    rated_torque_Nm: float = _f(0.0)
    rated_output_speed_rpm: float = _f(0.0)


@dataclass(frozen=True)
class Dynamics:
    damping_ratio: float = _f(0.0, 1.0, open_lo=False)   # modal, all couplings
    load_inertia_kg_m2: float = _f(0.0, open_lo=False)    # on the output, beyond the carrier
    input_inertia_kg_m2: float = _f(0.0)                  # motor + sun shaft


@dataclass(frozen=True)
class Errors:
    """Manufacturing/assembly error sources; zero means ideal. Tuples are per crankshaft."""
    crank_eccentricity_um: tuple = _f(-500.0, 500.0, default=(0.0,))   # both eccentrics of crank j
    # error of the eccentric under disc 1 only (e.g. a grinding error of one eccentric journal):
    # disc 1's eccentric radius on crank j is E + crank_eccentricity_um[j] + eccentric_error_um[j],
    # disc 2's stays E + crank_eccentricity_um[j]; unlike crank_eccentricity_um it does not cancel
    # between the two discs and puts a line at the crankshaft order zp x in the TE
    eccentric_error_um: tuple = _f(-500.0, 500.0, default=(0.0,))
    crank_hole_position_um: tuple = _f(-500.0, 500.0, default=(0.0,))
    output_bearing_hole_um: tuple = _f(-500.0, 500.0, default=(0.0,))
    pin_radius_um: float = _f(-500.0, 500.0, default=0.0)
    pin_circle_radius_um: float = _f(-500.0, 500.0, default=0.0)
    output_coaxiality_um: float = _f(0.0, 1000.0, open_lo=False, default=0.0)
    output_coaxiality_phase_deg: float = _f(-360.0, 360.0, default=0.0)
    turning_arm_clearance_um: float = _f(0.0, 200.0, open_lo=False, default=0.0)
    support_clearance_um: float = _f(0.0, 200.0, open_lo=False, default=0.0)


SECTIONS: dict[str, type] = {
    "cycloid": Cycloid, "modification": Modification, "stage1": Stage1, "carrier": Carrier,
    "disc": Disc, "crankshaft": Crankshaft, "material": Material, "operation": Operation,
    "dynamics": Dynamics, "errors": Errors,
}


@dataclass(frozen=True)
class ReducerCase:
    name: str
    cycloid: Cycloid
    modification: Modification
    stage1: Stage1
    carrier: Carrier
    disc: Disc
    crankshaft: Crankshaft
    material: Material
    operation: Operation
    dynamics: Dynamics
    errors: Errors = Errors()
    source: str = ""   # path the case was read from, for messages

    @property
    def ratio(self) -> float:
        """i = 1 + (z2/z1)*zp (pin housing fixed, output = carrier)."""
        return 1.0 + self.stage1.z2 / self.stage1.z1 * self.cycloid.zp

    @property
    def rated_torque_Nm(self) -> float:
        return self.operation.rated_torque_Nm

    def with_errors(self, **changes: Any) -> "ReducerCase":
        """A copy with some error sources changed (validated like the case file)."""
        data = dataclasses.asdict(self.errors) | changes
        errors = _build(Errors, data, "errors", self.source)
        out = dataclasses.replace(self, errors=errors)
        _check_errors(out)
        return out

    def replace(self, section: str, **changes: Any) -> "ReducerCase":
        """A copy with fields of one section changed, re-validated as a whole."""
        old = getattr(self, section)
        new = _build(type(old), dataclasses.asdict(old) | changes, section, self.source)
        out = dataclasses.replace(self, **{section: new})
        validate(out)
        return out

    def to_dict(self) -> dict:
        return {k: v for k, v in dataclasses.asdict(self).items() if k != "source"}


def _where(section: str, key: str, source: str) -> str:
    return f"{source + ': ' if source else ''}[{section}] {key}"


def _build(cls: type, data: dict, section: str, source: str) -> Any:
    if not isinstance(data, dict):
        raise CaseError(f"{_where(section, '', source)} must be a table, got {data!r}")
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise CaseError(f"{_where(section, unknown[0], source)}: unknown key; "
                        f"allowed keys: {', '.join(fields)}")
    values = {}
    for name, f in fields.items():
        if name not in data:
            if f.default is dataclasses.MISSING:
                raise CaseError(f"{_where(section, name, source)}: missing (required)")
            continue
        values[name] = _check_value(f, data[name], _where(section, name, source))
    return cls(**values)


def _check_value(f: dataclasses.Field, value: Any, where: str) -> Any:
    lo, hi, open_lo = f.metadata.get("lo"), f.metadata.get("hi"), f.metadata.get("open_lo", True)
    open_hi, why = f.metadata.get("open_hi", False), f.metadata.get("why", "")
    want_int = f.type in ("int", int)
    want_tuple = f.type in ("tuple", tuple)
    items = value if want_tuple and isinstance(value, (list, tuple)) else [value]
    if want_tuple and not isinstance(value, (list, tuple)):
        items = [value]
    checked = []
    for v in items:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise CaseError(f"{where} = {v!r}: must be a number")
        if want_int and not float(v).is_integer():
            raise CaseError(f"{where} = {v!r}: must be a whole number")
        if not math.isfinite(v):
            raise CaseError(f"{where} = {v!r}: must be finite")
        rng = f"{'(' if open_lo else '['}{lo}, {hi if hi is not None else 'inf'}{')' if open_hi else ']'}"
        if lo is not None and (v < lo or (open_lo and v == lo)) \
                or hi is not None and (v > hi or (open_hi and v == hi)):
            raise CaseError(f"{where} = {v!r}: outside the allowed range {rng}"
                            + (f" ({why})" if why else ""))
        checked.append(int(v) if want_int else float(v))
    return tuple(checked) if want_tuple else checked[0]


def _check_errors(case: ReducerCase) -> None:
    n = case.carrier.crank_count
    for key in ("crank_eccentricity_um", "eccentric_error_um", "crank_hole_position_um",
                "output_bearing_hole_um"):
        v = getattr(case.errors, key)
        if len(v) not in (1, n):
            raise CaseError(f"{_where('errors', key, case.source)} = {list(v)}: give one value "
                            f"(all cranks) or {n} (one per crank)")


def validate(case: ReducerCase) -> ReducerCase:
    """Cross-field checks a reducer engineer would make before cutting metal."""
    c, s, m = case.cycloid, case.source, case.modification
    w = lambda sec, key: _where(sec, key, s)  # noqa: E731
    if c.zc != c.zp - 1:
        raise CaseError(f"{w('cycloid', 'zc')} = {c.zc}: a single-lobe cycloid drive needs "
                        f"zc = zp - 1 = {c.zp - 1}")
    R, Rr, E = c.pin_circle_radius_mm, c.pin_radius_mm, c.eccentricity_mm
    if E * c.zp >= R:
        raise CaseError(f"{w('cycloid', 'eccentricity_mm')} = {E}: E*zp = {E * c.zp:g} mm must be "
                        f"below the pin circle radius R = {R:g} mm (else the profile has cusps); "
                        f"allowed E < {R / c.zp:g} mm")
    pitch_half = R * math.sin(math.pi / c.zp)
    if Rr + m.equidistant_mm >= pitch_half:
        raise CaseError(f"{w('cycloid', 'pin_radius_mm')} = {Rr}: neighbouring pins overlap; "
                        f"allowed pin radius < {pitch_half:.4g} mm (half the pin pitch)")
    if R + m.offset_mm - E - Rr - m.equidistant_mm <= case.carrier.crank_circle_radius_mm \
            + case.disc.crank_hole_radius_mm:
        raise CaseError(f"{w('disc', 'crank_hole_radius_mm')} = {case.disc.crank_hole_radius_mm}: "
                        f"crank hole at radius {case.carrier.crank_circle_radius_mm} cuts the tooth root "
                        f"(root radius {R + m.offset_mm - E - Rr - m.equidistant_mm:.4g} mm)")
    ks = case.crankshaft
    if ks.eccentric_radius_mm + ks.needle_diameter_mm > case.disc.crank_hole_radius_mm + 1e-9:
        raise CaseError(f"{w('disc', 'crank_hole_radius_mm')} = {case.disc.crank_hole_radius_mm}: "
                        f"must hold the eccentric ({ks.eccentric_radius_mm} mm) plus needles "
                        f"({ks.needle_diameter_mm} mm)")
    if abs(case.disc.crank_hole_radius_mm - ks.eccentric_radius_mm - ks.needle_diameter_mm) > 0.05:
        raise CaseError(f"{w('disc', 'crank_hole_radius_mm')} = {case.disc.crank_hole_radius_mm}: "
                        f"the needles must fill the gap: expected eccentric radius + needle diameter "
                        f"= {ks.eccentric_radius_mm + ks.needle_diameter_mm:g} mm (within 0.05 mm)")
    if ks.needle_count * ks.needle_diameter_mm > 2 * math.pi * (ks.eccentric_radius_mm
                                                                 + ks.needle_diameter_mm / 2):
        raise CaseError(f"{w('crankshaft', 'needle_count')} = {ks.needle_count}: needles do not fit "
                        f"around the eccentric")
    cr, s1 = case.carrier, case.stage1
    centre_distance = s1.module_mm * (s1.z1 + s1.z2) / 2
    if abs(centre_distance - cr.crank_circle_radius_mm) > 0.5:
        raise CaseError(f"{w('carrier', 'crank_circle_radius_mm')} = {cr.crank_circle_radius_mm}: the "
                        f"planets sit on the crankshafts, so it must equal the sun-planet centre "
                        f"distance m(z1+z2)/2 = {centre_distance:g} mm (within 0.5 mm of profile shift)")
    if cr.pillar_count and cr.pillar_circle_radius_mm + cr.pillar_radius_mm \
            >= R - E - Rr + m.offset_mm - m.equidistant_mm:
        raise CaseError(f"{w('carrier', 'pillar_circle_radius_mm')} = {cr.pillar_circle_radius_mm}: "
                        f"pillar holes reach the tooth root")
    if case.disc.centre_hole_radius_mm >= cr.crank_circle_radius_mm - case.disc.crank_hole_radius_mm:
        raise CaseError(f"{w('disc', 'centre_hole_radius_mm')} = {case.disc.centre_hole_radius_mm}: "
                        f"cuts into the crank holes (allowed < "
                        f"{cr.crank_circle_radius_mm - case.disc.crank_hole_radius_mm:g} mm)")
    _check_errors(case)
    _check_undercut(case)
    return case


def _check_undercut(case: ReducerCase) -> None:
    """The modified profile must not loop: its pin radius Rr + dRr stays below the smallest convex
    radius of curvature of the (modified) pin-centre curve. (Where the disc is concave, at the
    roots, an inward offset never loops.)"""
    c, m = case.cycloid, case.modification
    rho = min_convex_radius_mm(c.pin_circle_radius_mm + m.offset_mm, c.eccentricity_mm, c.zp)
    if c.pin_radius_mm + m.equidistant_mm >= rho:
        raise CaseError(f"{_where('cycloid', 'pin_radius_mm', case.source)} = {c.pin_radius_mm} "
                        f"(+ equidistant {m.equidistant_mm}): the profile undercuts (loops) at the "
                        f"tooth tips; allowed modified pin radius < {rho:.4g} mm, the smallest "
                        f"convex radius of curvature of the pin-centre curve (lower E zp / R or Rr)")


def load_case(path: str | Path) -> ReducerCase:
    """Read and validate a case file; raise CaseError naming key, value and allowed range."""
    path = Path(path)
    try:
        if path.is_dir():
            raise CaseError(f"{path}: is a directory; expected a case file (TOML)")
        if path.exists() and not path.is_file():
            raise CaseError(f"{path}: not a regular file; expected a case file (TOML)")
        if path.exists() and path.stat().st_size > CASE_FILE_MAX_BYTES:
            raise CaseError(f"{path}: {path.stat().st_size} bytes; a case file is TOML text of at "
                            f"most {CASE_FILE_MAX_BYTES} bytes")
        text = path.read_bytes().decode("utf-8-sig")
        raw = tomllib.loads(text)
    except FileNotFoundError:
        raise CaseError(f"{path}: case file not found") from None
    except PermissionError:
        raise CaseError(f"{path}: cannot read the case file (permission denied)") from None
    except OSError as exc:
        raise CaseError(f"{path}: cannot read the case file ({exc.strerror or exc})") from None
    except UnicodeDecodeError as exc:
        raise CaseError(f"{path}: not a UTF-8 text file (byte {exc.start}); a case file is TOML "
                        f"text") from None
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(f"{path}: not valid TOML ({' '.join(str(exc).split())})") from None
    return case_from_dict(raw, source=str(path))


def case_from_dict(raw: dict, source: str = "") -> ReducerCase:
    allowed = {"name", *SECTIONS}
    unknown = sorted(set(raw) - allowed)
    if unknown:
        raise CaseError(f"{source + ': ' if source else ''}{unknown[0]}: unknown top-level key; "
                        f"allowed: {', '.join(sorted(allowed))}")
    name = raw.get("name")
    if not isinstance(name, str) or not name:
        raise CaseError(f"{source + ': ' if source else ''}name: missing or not a string")
    if not NAME_PATTERN.fullmatch(name) or name in (".", ".."):
        raise CaseError(f"{source + ': ' if source else ''}name = {name!r}: must be a plain file-name "
                        f"token of 1-100 letters, digits, '.', '_' or '-' (not '.' or '..'): it "
                        f"names the build folder")
    sections = {}
    for sec, cls in SECTIONS.items():
        if sec not in raw and sec != "errors":
            raise CaseError(f"{_where(sec, '', source)}: missing section")
        sections[sec] = _build(cls, raw.get(sec, {}), sec, source)
    return validate(ReducerCase(name=name, source=source, **sections))
