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
import functools
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from geometry import clearance_limits, params_assembly, spur
from geometry.artifacts import read_text
from geometry.case_fields import CaseError, ranged as _f, where as _where
from geometry.case_si import CaseSI, case_si
from geometry.lubrication import Lubrication
from geometry.params_assembly import Joints, MainBearings
from geometry.tolerances import TOLERANCE_UM_MAX, Tolerances  # noqa: F401 (TOLERANCE_UM_MAX: re-exported)
from geometry.pin_profile import min_convex_radius_mm

# Largest pin count accepted. Real cycloid reducers stay below it: RV reducers carry ~40 pins and
# the finest single-stage cycloid drives (Sumitomo Cyclo, 119:1) have zc = 119, zp = 120. The
# geometry stage's CAD outline is one spline per tooth and its deviation check samples each tooth,
# so cost grows with zp; a 400-pin case asked for 30 GiB before the seed search was windowed.
ZP_MAX = 120
NAME_PATTERN = re.compile(r"[A-Za-z0-9._-]{1,100}")   # the name becomes the build folder's name
CASE_FILE_MAX_BYTES = 1 << 20                           # a case file is a few kB of TOML


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
    # x1 of the sun; the planets get x2 = -x1 (zero-sum: the centre distance, hence the crank
    # circle, stays m (z1 + z2) / 2); checked against undercut and pointed teeth (geometry.spur)
    profile_shift: float = _f(-1.0, 1.0, open_lo=False,
                              why="|x| > 1 module is no practical spur gear: the tooth turns pointed or "
                                  "deeply undercut")

    @property
    def planet_profile_shift(self) -> float:
        return 0.0 - self.profile_shift      # x2 = -x1 (0.0, not -0.0, for an unshifted pair)


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


@dataclass(frozen=True)
class Housing:
    """The pin ring as an elastic body (fem.housing): wall, mounting flange, bolts (clamped)."""
    pin_ring_outer_radius_mm: float = _f(0.0)   # housing wall outside the groove circle
    pin_ring_length_mm: float = _f(0.0)         # axial length of the pin ring: both discs plus spacing
    flange_outer_radius_mm: float = _f(0.0)     # mounting flange
    bolt_count: int = _f(3, 64, open_lo=False, why="fewer than 3 do not clamp a flange in its plane")
    bolt_circle_radius_mm: float = _f(0.0)
    bolt_hole_radius_mm: float = _f(0.0)        # clearance hole (the clamped edge)


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
    momentary_torque_Nm: float = _f(0.0)        # catalog momentary maximum: the FE tables' range
    rated_output_speed_rpm: float = _f(0.0)
    # what the predicted rigidity is set beside (catalog or bench; 0: none); never fed to the model
    reference_rigidity_Nm_per_arcmin: float = _f(0.0, open_lo=False, default=0.0)


@dataclass(frozen=True)
class Dynamics:
    damping_ratio: float = _f(0.0, 1.0, open_lo=False)   # modal, all couplings
    load_inertia_kg_m2: float = _f(0.0, open_lo=False)    # on the output, beyond the carrier
    input_inertia_kg_m2: float = _f(0.0)                  # motor + sun shaft


# Limits of the as-built errors: an error beyond them is a wrong or mis-assembled part, not a
# tolerance (ISO 1328 grade 12, the coarsest, allows ~100 um of cumulative pitch on a 130 mm gear)
ERROR_UM_MAX = 100.0
ANGLE_ERROR_ARCMIN_MAX = 60.0
LOBE_ROWS_MAX = 16                # Fourier lobes per pattern (a measured pattern needs a few)
STIFFNESS_FACTOR_MIN = 0.1        # a pin support below a tenth of its law is a broken groove


def _rows(*columns) -> Any:
    """A table of rows [column, ...] (TOML array of arrays): columns (name, whole?, lo, hi), closed."""
    return field(default=(), metadata={"columns": columns})


_LOBE = (("amplitude_um", False, 0.0, ERROR_UM_MAX), ("phase_deg", False, -360.0, 360.0))


@dataclass(frozen=True)
class Errors:
    """As-built error sources (DESIGN.md "An as-built reducer"); zero or empty means ideal. Each
    acts through the contact mechanics of the coupling that reads it (dynamics.couplings.needle:
    crank, hole and main-bearing errors; .pin: pin and disc errors; .support: support clearance),
    never as an added TE curve; output_coaxiality_um and output_reading_lobes are the reading errors
    (dynamics.reducer).
    Per crank: one value (all cranks) or one per crank j (seat at 360 j / n deg on the carrier).
    Per pin: empty or zp values, pin k at 360 k / zp deg. Per disc: one value or one per disc.
    Lobes (rows [m, amplitude, phase_deg]): amplitude cos(m theta - phase) at the pin angle theta;
    disc lobes (rows [disc, m, amplitude_um, phase_deg], disc 1-based) at the polar angle theta
    in that disc's own profile frame (disc 2's turned 180 deg)."""
    # --- cranks, holes, main bearing (needle.py)
    crank_eccentricity_um: tuple = _f(-500.0, 500.0, default=(0.0,))   # both eccentrics of crank j
    # error of the eccentric under disc 1 only (e.g. a grinding error of one eccentric journal):
    # disc 1's eccentric radius on crank j is E + crank_eccentricity_um[j] + eccentric_error_um[j],
    # disc 2's stays E + crank_eccentricity_um[j]; unlike crank_eccentricity_um it does not cancel
    # between the two discs and puts a line at the crankshaft order zp x in the TE
    eccentric_error_um: tuple = _f(-500.0, 500.0, default=(0.0,))
    # angle between crank j's two eccentrics minus 180 deg (disc 2's eccentric turned, + forward)
    eccentric_phase_arcmin: tuple = _f(-ANGLE_ERROR_ARCMIN_MAX, ANGLE_ERROR_ARCMIN_MAX, open_lo=False,
                                       default=(0.0,))
    # timing: crank j's eccentrics turned against its planet gear (spline/key indexing), + forward
    crank_timing_arcmin: tuple = _f(-ANGLE_ERROR_ARCMIN_MAX, ANGLE_ERROR_ARCMIN_MAX, open_lo=False,
                                    default=(0.0,))
    crank_hole_position_um: tuple = _f(-500.0, 500.0, default=(0.0,))     # radial, both discs
    crank_hole_tangential_um: tuple = _f(-ERROR_UM_MAX, ERROR_UM_MAX, open_lo=False, default=(0.0,))
    output_bearing_hole_um: tuple = _f(-500.0, 500.0, default=(0.0,))     # radial, crank seat in the carrier
    output_bearing_hole_tangential_um: tuple = _f(-ERROR_UM_MAX, ERROR_UM_MAX, open_lo=False, default=(0.0,))
    # radial runout of the main (output) bearing that turns with the carrier: the carrier axis,
    # and with it every crank seat, displaced by this much at the phase from crank 1's seat
    main_bearing_runout_um: float = _f(0.0, ERROR_UM_MAX, open_lo=False, default=0.0)
    main_bearing_runout_phase_deg: float = _f(-360.0, 360.0, default=0.0)
    # --- pins (pin.py): uniform, per pin, pin-ring lobes
    pin_radius_um: float = _f(-500.0, 500.0, default=0.0)
    pin_circle_radius_um: float = _f(-500.0, 500.0, default=0.0)
    per_pin_radial_um: tuple = _f(-ERROR_UM_MAX, ERROR_UM_MAX, open_lo=False, default=())
    per_pin_tangential_um: tuple = _f(-ERROR_UM_MAX, ERROR_UM_MAX, open_lo=False, default=())  # + forward
    per_pin_radius_um: tuple = _f(-ERROR_UM_MAX, ERROR_UM_MAX, open_lo=False, default=())
    pin_radial_lobes: tuple = _rows(("m", True, 1, None), *_LOBE)
    # pin ring axis tilted against the carrier's: the pin circle's centre moved by +t at disc 1's plane, -t at
    # disc 2's, toward the phase (ground frame, from pin 1); its zc x lines add between the discs (pin.py)
    pin_ring_tilt_um: float = _f(-ERROR_UM_MAX, ERROR_UM_MAX, open_lo=False, default=0.0)
    pin_ring_tilt_phase_deg: float = _f(-360.0, 360.0, default=0.0)
    # pin support (housing groove) stiffness: each pin's law multiplied by 1 + sum a cos(m theta - phase)
    pin_stiffness_lobes: tuple = _rows(("m", True, 1, None), ("amplitude", False, 0.0, 0.9),
                                       ("phase_deg", False, -360.0, 360.0))
    # --- discs (pin.py)
    disc_phase_um: float = _f(-ERROR_UM_MAX, ERROR_UM_MAX, open_lo=False, default=0.0)  # disc 2 turned, at R
    disc_profile_um: tuple = _f(-ERROR_UM_MAX, ERROR_UM_MAX, open_lo=False, default=(0.0,))  # + material added
    # cumulative pitch: the teeth turned by amplitude / R (tangential at the pin circle R, + forward);
    # one lobe (m = 1) is the disc's cumulative pitch error, F_p = 2 amplitude
    disc_pitch_lobes: tuple = _rows(("disc", True, 1, None), ("m", True, 1, None), *_LOBE)
    disc_profile_lobes: tuple = _rows(("disc", True, 1, None), ("m", True, 1, None), *_LOBE)  # normal, + material
    # --- reading error and clearances
    output_coaxiality_um: float = _f(0.0, 1000.0, open_lo=False, default=0.0)   # encoder/mounting runout
    output_coaxiality_phase_deg: float = _f(-360.0, 360.0, default=0.0)
    # the output encoder's reading error in m >= 2 lobes (its ring or hub deformed by the mounting
    # screws, graduation error): rows [m, amplitude_um, phase_deg], a tangential amplitude at the
    # output flange radius r, read as amplitude / r cos(m theta_out - phase) (dynamics.reducer)
    output_reading_lobes: tuple = _rows(("m", True, 2, None), *_LOBE)
    turning_arm_clearance_um: float = _f(0.0, 200.0, open_lo=False, default=0.0)
    support_clearance_um: float = _f(0.0, 200.0, open_lo=False, default=0.0)


SECTIONS: dict[str, type] = {
    "cycloid": Cycloid, "modification": Modification, "stage1": Stage1, "carrier": Carrier,
    "disc": Disc, "crankshaft": Crankshaft, "housing": Housing, "material": Material,
    "operation": Operation, "dynamics": Dynamics, "joints": Joints, "main_bearings": MainBearings,
    "errors": Errors, "tolerances": Tolerances, "lubrication": Lubrication,
}
OPTIONAL_SECTIONS = ("errors", "tolerances", "lubrication")


@dataclass(frozen=True)
class ReducerCase:
    name: str
    cycloid: Cycloid
    modification: Modification
    stage1: Stage1
    carrier: Carrier
    disc: Disc
    crankshaft: Crankshaft
    housing: Housing
    material: Material
    operation: Operation
    dynamics: Dynamics
    joints: Joints
    main_bearings: MainBearings
    errors: Errors = Errors()
    tolerances: Tolerances = Tolerances()
    lubrication: Lubrication = Lubrication()   # read by dynamics.losses only: not fingerprinted
    source: str = ""   # path the case was read from, for messages

    @property
    def ratio(self) -> float:
        """i = 1 + (z2/z1)*zp (pin housing fixed, output = carrier)."""
        return 1.0 + self.stage1.z2 / self.stage1.z1 * self.cycloid.zp

    @property
    def rated_torque_Nm(self) -> float:
        return self.operation.rated_torque_Nm

    @functools.cached_property
    def si(self) -> CaseSI:
        """The sizes in SI units (m, Pa), converted once (geometry.case_si)."""
        return case_si(self)

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
        """The content the case fingerprint hashes: every section but `tolerances` and `lubrication`."""
        return {k: v for k, v in dataclasses.asdict(self).items() if k not in ("source", "tolerances", "lubrication")}


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
        check = _check_rows if "columns" in f.metadata else _check_value
        values[name] = check(f, data[name], _where(section, name, source))
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


def _check_rows(f: dataclasses.Field, value: Any, where: str) -> tuple:
    """A table of rows (f.metadata["columns"]: (name, whole?, lo, hi), closed) -> tuple of tuples."""
    cols = f.metadata["columns"]
    shape = "[" + ", ".join(c[0] for c in cols) + "]"
    if not isinstance(value, (list, tuple)) or any(not isinstance(r, (list, tuple)) for r in value):
        raise CaseError(f"{where} = {value!r}: must be a list of rows {shape}, e.g. "
                        f"[{', '.join('1' for _ in cols)}]")
    if len(value) > LOBE_ROWS_MAX:
        raise CaseError(f"{where}: {len(value)} rows; allowed at most {LOBE_ROWS_MAX}")
    rows = []
    for i, row in enumerate(value, 1):
        if len(row) != len(cols):
            raise CaseError(f"{where} row {i} = {list(row)!r}: needs {len(cols)} numbers {shape}")
        out = []
        for (name, whole, lo, hi), v in zip(cols, row):
            here = f"{where} row {i} {name}"
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise CaseError(f"{here} = {v!r}: must be a finite number")
            if whole and not float(v).is_integer():
                raise CaseError(f"{here} = {v!r}: must be a whole number")
            if (lo is not None and v < lo) or (hi is not None and v > hi):
                raise CaseError(f"{here} = {v!r}: outside the allowed range [{lo}, "
                                f"{hi if hi is not None else 'inf'}]")
            out.append(int(v) if whole else float(v))
        rows.append(tuple(out))
    return tuple(rows)


def lobe_sum(rows, m_col: int, theta):
    """sum over rows of amplitude cos(m theta - phase) (amplitude, phase_deg after column m_col)."""
    return sum(r[m_col + 1] * np.cos(r[m_col] * theta - np.radians(r[m_col + 2])) for r in rows)


def _check_errors(case: ReducerCase) -> None:
    er, n, nd, zp, zc = case.errors, case.carrier.crank_count, case.cycloid.disc_count, case.cycloid.zp, \
        case.cycloid.zc
    w = lambda key: _where("errors", key, case.source)  # noqa: E731
    for key in ("crank_eccentricity_um", "eccentric_error_um", "eccentric_phase_arcmin", "crank_timing_arcmin",
                "crank_hole_position_um", "crank_hole_tangential_um", "output_bearing_hole_um",
                "output_bearing_hole_tangential_um"):
        if len(getattr(er, key)) not in (1, n):
            raise CaseError(f"{w(key)} = {list(getattr(er, key))}: give one value (all cranks) or {n} "
                            f"(one per crank)")
    for key in ("per_pin_radial_um", "per_pin_tangential_um", "per_pin_radius_um"):
        if len(getattr(er, key)) not in (0, zp):
            raise CaseError(f"{w(key)}: {len(getattr(er, key))} values; give none or zp = {zp} (pin k "
                            f"at 360 k / zp deg)")
    if len(er.disc_profile_um) not in (1, nd):
        raise CaseError(f"{w('disc_profile_um')} = {list(er.disc_profile_um)}: give one value (all discs) "
                        f"or {nd} (one per disc)")
    if nd == 1:
        for key in ("disc_phase_um", "eccentric_phase_arcmin"):
            if any(v != 0 for v in np.atleast_1d(getattr(er, key))):
                raise CaseError(f"{w(key)} = {getattr(er, key)}: acts between two discs; this case has "
                                f"disc_count = 1 (allowed 0)")
    # lobes beyond half the pins (teeth) alias onto fewer lobes of the same points
    for key, m_col, top, what in (("pin_radial_lobes", 0, zp // 2, "zp / 2"), ("pin_stiffness_lobes", 0, zp // 2, "zp / 2"),
                                  ("disc_pitch_lobes", 1, zc // 2, "zc / 2"),
                                  ("disc_profile_lobes", 1, zc // 2, "zc / 2")):
        for i, r in enumerate(getattr(er, key), 1):
            if r[m_col] > top:
                raise CaseError(f"{w(key)} row {i} m = {r[m_col]}: allowed 1 to {what} = {top} (more lobes "
                                f"than half the {'pins' if m_col == 0 else 'teeth'} alias onto fewer)")
            if m_col == 1 and r[0] > nd:
                raise CaseError(f"{w(key)} row {i} disc = {r[0]}: allowed 1 to {nd} (disc_count)")
    factor = 1.0 + lobe_sum(er.pin_stiffness_lobes, 0, 2 * np.pi * np.arange(zp) / zp)
    if np.min(factor) < STIFFNESS_FACTOR_MIN:
        raise CaseError(f"{w('pin_stiffness_lobes')} = {[list(r) for r in er.pin_stiffness_lobes]}: the "
                        f"support stiffness factor falls to {np.min(factor):.3g} at pin "
                        f"{int(np.argmin(factor)) + 1}; allowed >= {STIFFNESS_FACTOR_MIN} at every pin "
                        f"(lower the amplitudes)")


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
    op = case.operation
    if op.momentary_torque_Nm <= op.rated_torque_Nm:
        raise CaseError(f"{w('operation', 'momentary_torque_Nm')} = {op.momentary_torque_Nm:g}: the momentary "
                        f"maximum must exceed the rated torque ({op.rated_torque_Nm:g} N m); allowed > "
                        f"{op.rated_torque_Nm:g}")
    _check_housing(case)
    _check_errors(case)
    clearance_limits.check(case)
    bad = params_assembly.check(case.joints, case.main_bearings, w)
    if bad:
        raise CaseError(bad[0])
    _check_undercut(case)
    _check_stage1(case)
    return case


def _check_housing(case: ReducerCase) -> None:
    """Ring wall outside the grooves, as long as the disc stack; bolt holes apart, between wall and rim."""
    h, c, r = case.housing, case.cycloid, case.housing.bolt_hole_radius_mm
    groove, stack, b = c.pin_circle_radius_mm + c.pin_radius_mm, c.disc_count * c.width_mm, h.bolt_circle_radius_mm
    gap = b * math.sin(math.pi / h.bolt_count)
    for key, ok, why in (("pin_ring_outer_radius_mm", h.pin_ring_outer_radius_mm > groove, f"the wall must lie outside "
                          f"the groove bottoms (pin circle + pin radius); allowed > {groove:g}"),
                         ("pin_ring_length_mm", h.pin_ring_length_mm >= stack, f"the pin ring must span the disc "
                          f"stack (disc_count x width); allowed >= {stack:g}"),
                         ("bolt_circle_radius_mm", b - r > h.pin_ring_outer_radius_mm, f"the bolt holes (radius {r:g} "
                          f"mm) cut the ring wall; allowed > {h.pin_ring_outer_radius_mm + r:g}"),
                         ("flange_outer_radius_mm", h.flange_outer_radius_mm > b + r, f"the bolt holes reach the "
                          f"flange rim; allowed > {b + r:g} (bolt circle + hole radius)"),
                         ("bolt_hole_radius_mm", r < gap, f"{h.bolt_count} holes on the {b:g} mm circle overlap; "
                          f"allowed < {gap:.4g}")):
        if not ok:
            raise CaseError(f"{_where('housing', key, case.source)} = {getattr(h, key):g}: {why}")


def _check_stage1(case: ReducerCase) -> None:
    """Sun and planets cut by the ISO 53 rack: neither undercut nor pointed (geometry.spur), and
    at least one pair always in mesh."""
    s1, where = case.stage1, _where("stage1", "profile_shift", case.source)
    x, z1, z2, al = s1.profile_shift, s1.z1, s1.z2, s1.pressure_angle_deg
    lo, hi = spur.shift_range(z1, z2, al)
    if lo > hi:
        raise CaseError(f"{_where('stage1', 'z1', case.source)} = {z1}: no profile shift frees the z1 = {z1} "
                        f"sun and z2 = {z2} planets from undercut and pointed teeth at {al:g} deg "
                        f"(needs x1 >= {lo:.3f} and x1 <= {hi:.3f}); use more teeth or a larger pressure angle")
    if not lo <= x <= hi:
        why = (f"the z1 = {z1} sun is undercut below x1 = {spur.undercut_limit(z1, al):.3f} "
               f"(1.0 - z sin^2(alpha) / 2, ISO 53 rack)" if x < spur.undercut_limit(z1, al) else
               f"the z2 = {z2} planets (x2 = -x1) are undercut" if x > -spur.undercut_limit(z2, al) else
               f"a tooth tip is thinner than {spur.TIP_MIN_OF_MODULE:g} module (pointed)")
        raise CaseError(f"{where} = {x!r}: {why}; allowed x1 in [{lo:.3f}, {hi:.3f}] "
                        f"(the planets get x2 = -x1)")
    eps = spur.transverse_contact_ratio(z1, z2, s1.module_mm, al, x, -x)
    if eps < 1.0:
        raise CaseError(f"{where} = {x!r}: transverse contact ratio {eps:.3f} < 1 (the mesh would lose "
                        f"contact between pairs); lower |x1| or use more teeth")


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
    text = read_text(path, what="case", error=CaseError, allowed="a case file is TOML text",
                     max_bytes=CASE_FILE_MAX_BYTES,
                     wording={"missing": "case file not found", "folder": "is a directory, not a case file",
                              "not_utf8": "not a UTF-8 text file (byte {offset})"})
    try:
        raw = tomllib.loads(text)
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
        if sec not in raw and sec not in OPTIONAL_SECTIONS:
            raise CaseError(f"{_where(sec, '', source)}: missing section")
        sections[sec] = _build(cls, raw.get(sec, {}), sec, source)
    return validate(ReducerCase(name=name, source=source, **sections))
