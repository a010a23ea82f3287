"""Crank support bearings: a preloaded pair of standard metric tapered roller bearings, roller by
roller (Jones / Harris load distribution with ISO/TS 16281 slices), from catalogue geometry.

Catalogue (CATALOGUE): ISO 355 boundary dimensions d, D, T, B, C with the NTN metric tapered
roller bearing table (bore 15..35 mm: dimensions, C_r, C_0r, ISO 355 dimension series) and the
catalogue factor e (contact angle alpha = atan(e / 1.5), ISO 281: e = 1.5 tan alpha,
Y = 0.4 cot alpha). The series' angle digit (ISO 355: 2 = 10..13deg52', 3 = ..15deg59',
4 = ..18deg55') bounds e; tests hold every row to it. Catalogues do not publish the internal
geometry, so it is DERIVED from the section by one stated rule (every row, no per-row tuning):
  pitch diameter  D_pw = (d + D) / 2
  roller diameter D_we = 0.25 (D - d)          (half the ring section height)
  roller length   l_we = 0.8 C                 (cup raceway less the roller end chamfers)
  roller count    Z = floor(0.85 pi D_pw / D_we)  (cage fill 85 % of the pitch circle)
and checked against the catalogue static rating through ISO 76 (C_0r = 44 (1 - D_we cos a / D_pw)
Z l_we D_we cos a): the rule lands within -13..+13 % of NTN's C_0r on all 20 rows (mean -2 %).

Roller-raceway law (fem.hertz): Palmgren, 3.84e-5 Q^0.9 / l^0.8 mm per contact, two contacts per
roller in series: Q = K_n delta^(10/9), K_n = 3.73e4 l^(8/9) N/mm^(10/9); the roller is cut into
`slices` equal slices of K_n / slices each (ISO/TS 16281), so a tilt between the rings loads the
roller unevenly. One contact angle alpha (the cup's) for both raceways: the cone angle is a few
degrees smaller and its difference goes into the cone rib (Harris), which is left out. Rollers
uncrowned (the support tilt is small; fem.needle_edge treats crowning), rings rigid, no fits:
ring, seat and carrier deformation are NOT in this figure (the carrier is its own FE body), so it
is the roller-raceway part of the support compliance only, an upper bound on the stiffness.

Pair (PairSetup): two bearings on a rigid shaft, contact mid-planes `spacing` apart, outer rings
fixed in the carrier. Shaft DOFs at the pair centre: lateral u, axial w, tilt theta. A roller at
azimuth psi, slice at s along the roller, in bearing b (axial position z_b, axial sense s_b):
  delta = cos a cos psi u + s_b sin a w + theta cos psi (lambda_b + s) + delta_pre,
  lambda_b = z_b cos a - s_b R_m sin a  (= cos a times the bearing's pressure-centre position).
O (back-to-back): pressure centres outside the pair, s_b = -sign z_b; X (face-to-face): inside.
An RV crankshaft's cones are slid on from the ends and seat their back faces on the eccentric
shoulders, and the carrier halves set the preload through the cups: that is face-to-face (X).
For a radial load at the pair centre O and X give the same radial stiffness; they differ in tilt.
Preload: fixed-position (spacer) preload, stated as the axial force F_pre each bearing carries
at zero external load; `operating_preload_N` = the induced axial force 0.5 F_r / Y at the
operating radial load (ISO 281 induced thrust), so neither bearing's load zone falls below 180
degrees at that load: the usual 'light preload' reasoning for a pair that must carry F_r rigidly.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fem import hertz
from geometry.artifacts import InputError

EXP = 10.0 / 9.0              # line-contact load exponent, Q ~ delta^(10/9)
CRANK_ARRANGEMENT = "X"       # an RV crank's pair is face-to-face (module doc)
MIN_BAND_SHARE = 0.25         # smallest crank reaction band, share of the half seat (a steep bearing)
FILL = 0.85                   # cage fill of the pitch circle (derivation rule, module doc)
ROLLER_DIAMETER_RULE = 0.25   # D_we / (D - d)
ROLLER_LENGTH_RULE = 0.8      # l_we / C
ANGLE_SERIES_DEG = {"2": (10.0, 13.0 + 52 / 60), "3": (13.0 + 52 / 60, 15.0 + 59 / 60),
                    "4": (15.0 + 59 / 60, 18.0 + 55 / 60)}   # ISO 355 angle series bounds
NTN_SOURCE = ("NTN Tapered Roller Bearings, metric series, bore 15-35 mm (catalogue pp. 227-228): "
              "d, D, T, B, C, C_r, C_0r, ISO 355 series; e: maker's catalogue factor")


@dataclass(frozen=True)
class TaperedRollerBearing:
    designation: str
    d_mm: float
    D_mm: float
    T_mm: float
    B_mm: float
    C_mm: float
    e: float                  # catalogue factor, e = 1.5 tan(alpha)
    Cr_N: float               # catalogue dynamic rating (reference only)
    C0r_N: float              # catalogue static rating: checks the derived geometry (ISO 76)
    iso355: str               # ISO 355 dimension series, e.g. "2DB" (angle series first)
    source: str = NTN_SOURCE

    @property
    def alpha_rad(self) -> float:
        return math.atan(self.e / 1.5)

    @property
    def Y(self) -> float:
        """ISO 281 axial factor 0.4 cot(alpha)."""
        return 0.4 / math.tan(self.alpha_rad)

    @property
    def pressure_centre_offset_mm(self) -> float:   # DERIVED
        """Distance from the contact mid-plane to the pressure centre, where the rollers' load lines
        (normal to the cup raceway) cross the axis: (D_pw / 2) tan(alpha), toward the rollers' large
        ends (lambda_b below / cos a). A radial load acts on the shaft there (the catalogues' load
        centre 'a'), so a shaft on a pair is pinned at the pressure centres: inside the pair for X
        (face-to-face), outside for O."""
        return 0.5 * self.pitch_diameter_mm * math.tan(self.alpha_rad)

    @property
    def pitch_diameter_mm(self) -> float:        # DERIVED
        return 0.5 * (self.d_mm + self.D_mm)

    @property
    def roller_diameter_mm(self) -> float:       # DERIVED
        return ROLLER_DIAMETER_RULE * (self.D_mm - self.d_mm)

    @property
    def roller_length_mm(self) -> float:         # DERIVED
        return ROLLER_LENGTH_RULE * self.C_mm

    @property
    def roller_count(self) -> int:               # DERIVED
        return int(math.floor(FILL * math.pi * self.pitch_diameter_mm / self.roller_diameter_mm))

    @property
    def derived_C0r_N(self) -> float:
        """ISO 76 static rating of the derived geometry (compare with C0r_N)."""
        ca = math.cos(self.alpha_rad)
        g = self.roller_diameter_mm * ca / self.pitch_diameter_mm
        return 44.0 * (1 - g) * self.roller_count * self.roller_length_mm * self.roller_diameter_mm * ca

    @property
    def roller_constant_N_per_mm_pow(self) -> float:
        """K_n [N/mm^(10/9)] of one roller, both contacts (Palmgren, fem.hertz)."""
        return hertz.palmgren_roller_constant(self.roller_length_mm * 1e-3) / 1e3 ** EXP


def _row(name, d, D, T, B, C, Cr, C0r, e, series):
    return TaperedRollerBearing(name, d, D, T, B, C, e, Cr, C0r, series)


# name, d, D, T, B, C [mm], C_r, C_0r [N] (NTN), e, ISO 355 dimension series
CATALOGUE: tuple[TaperedRollerBearing, ...] = (
    _row("30302", 15, 42, 14.25, 13, 11, 21900, 19200, 0.28, "2FB"),
    _row("30203", 17, 40, 13.25, 12, 11, 20400, 20200, 0.35, "2DB"),
    _row("30303", 17, 47, 15.25, 14, 12, 30000, 27600, 0.28, "2FB"),
    _row("32004X", 20, 42, 15, 15, 12, 25100, 28200, 0.37, "3CC"),
    _row("30204", 20, 47, 15.25, 14, 12, 29500, 30500, 0.35, "2DB"),
    _row("30304", 20, 52, 16.25, 15, 13, 35000, 35500, 0.30, "2FB"),
    _row("32005X", 25, 47, 15, 15, 11.5, 28000, 34000, 0.43, "4CC"),
    _row("33005", 25, 47, 17, 17, 14, 27500, 37000, 0.29, "2CE"),
    _row("30205", 25, 52, 16.25, 15, 13, 31500, 33700, 0.37, "3CC"),
    _row("30305", 25, 62, 18.25, 17, 15, 48200, 46900, 0.30, "2FB"),
    _row("32006X", 30, 55, 17, 17, 13, 37500, 46500, 0.43, "4CC"),
    _row("33006", 30, 55, 20, 20, 16, 39500, 59500, 0.29, "2CE"),
    _row("30206", 30, 62, 17.25, 16, 14, 43500, 48000, 0.37, "3DB"),
    _row("32206", 30, 62, 21.25, 20, 17, 53000, 61500, 0.37, "3DC"),
    _row("30306", 30, 72, 20.75, 19, 16, 59600, 60100, 0.31, "2FB"),
    _row("32907", 35, 55, 14, 14, 11.5, 26200, 40000, 0.29, "2BD"),
    _row("32007X", 35, 62, 18, 18, 14, 44500, 57500, 0.46, "4CC"),
    _row("33007", 35, 62, 21, 21, 17, 46000, 71000, 0.31, "2CE"),
    _row("30207", 35, 72, 18.25, 17, 15, 54500, 60500, 0.37, "3DB"),
    _row("32207", 35, 72, 24.25, 23, 19, 70000, 86000, 0.37, "3DC"),
)
CATALOGUE_BORES_MM = tuple(sorted({b.d_mm for b in CATALOGUE}))


@dataclass(frozen=True)
class Envelope:
    max_outer_diameter_mm: float     # room in the carrier's crank bore
    max_width_mm: float              # room on the journal


def case_envelope(case, *, wall_mm: float = 2.0) -> Envelope:
    """The space a case gives each support bearing. Outer diameter: the carrier ligament of
    `wall_mm` (ASSUMED minimum) must remain to the centre hole (disc centre-hole radius stands in
    for the carrier's), to the neighbouring crank bore and to the pillars; width: the journal length."""
    cr, k, dc = case.carrier, case.crankshaft, case.disc
    a = cr.crank_circle_radius_mm
    limits = [2 * (a - dc.centre_hole_radius_mm - wall_mm),
              2 * a * math.sin(math.pi / cr.crank_count) - wall_mm]
    if cr.pillar_count:
        # pillars sit midway between cranks on their own circle
        gap = math.hypot(a - cr.pillar_circle_radius_mm * math.cos(math.pi / cr.pillar_count),
                         cr.pillar_circle_radius_mm * math.sin(math.pi / cr.pillar_count))
        limits.append(2 * (gap - cr.pillar_radius_mm - wall_mm))
    return Envelope(max(min(limits), 0.0), k.journal_length_mm)


def catalogue_bore_mm(journal_radius_mm: float) -> float:
    """The catalogue bore nearest the journal diameter (within 15 % of it)."""
    dj = 2.0 * journal_radius_mm
    bore = min(CATALOGUE_BORES_MM, key=lambda b: (abs(b - dj), b))
    if not (dj > 0 and abs(bore - dj) <= 0.15 * dj):
        raise InputError(f"journal_radius_mm = {journal_radius_mm!r}: the catalogue holds bores "
                         f"{CATALOGUE_BORES_MM[0]:g}..{CATALOGUE_BORES_MM[-1]:g} mm (journal diameter "
                         f"within 15 % of one)")
    return bore


def select_bearing(journal_radius_mm: float, envelope: Envelope) -> TaperedRollerBearing:
    """The catalogue bearing for a journal: bore = journal diameter rounded to a catalogue bore;
    among the sizes within the envelope (D, T), the largest static rating C_0r (the most rollers x
    length x diameter, hence the stiffest). No fit raises InputError naming what it would take."""
    bore = catalogue_bore_mm(journal_radius_mm)
    sizes = [b for b in CATALOGUE if b.d_mm == bore]
    fits = [b for b in sizes if b.D_mm <= envelope.max_outer_diameter_mm + 1e-9
            and b.T_mm <= envelope.max_width_mm + 1e-9]
    if not fits:
        listing = ", ".join(f"{b.designation} (D {b.D_mm:g}, T {b.T_mm:g})" for b in sizes)
        raise InputError(f"support bearing for journal_radius_mm = {journal_radius_mm:g} (bore {bore:g} mm): "
                         f"no catalogue size fits outer diameter <= {envelope.max_outer_diameter_mm:g} mm "
                         f"and width <= {envelope.max_width_mm:g} mm (journal_length_mm); sizes: {listing}")
    return max(fits, key=lambda b: (b.C0r_N, -b.D_mm))


def closest_bearing(journal_radius_mm: float, envelope: Envelope) -> tuple[TaperedRollerBearing, str]:
    """select_bearing, or when nothing fits: the narrowest size within the outer-diameter limit
    (then the smaller D), with a note saying by how much it overruns the width (the case's
    journal length is ASSUMED; this is the size the case would have to make room for)."""
    try:
        return select_bearing(journal_radius_mm, envelope), "fits"
    except InputError:
        pass
    bore = catalogue_bore_mm(journal_radius_mm)
    sizes = [b for b in CATALOGUE if b.d_mm == bore and b.D_mm <= envelope.max_outer_diameter_mm + 1e-9] or \
        [b for b in CATALOGUE if b.d_mm == bore]
    b = min(sizes, key=lambda b: (b.T_mm, b.D_mm))
    over = [f"width {b.T_mm:g} > {envelope.max_width_mm:g} mm"] if b.T_mm > envelope.max_width_mm + 1e-9 else []
    if b.D_mm > envelope.max_outer_diameter_mm + 1e-9:
        over.append(f"outer diameter {b.D_mm:g} > {envelope.max_outer_diameter_mm:g} mm")
    return b, "does not fit: " + ", ".join(over)


def operating_preload_N(bearing: TaperedRollerBearing, radial_load_N: float) -> float:
    """Axial preload = the induced thrust 0.5 F_r / Y of the operating radial load (module doc)."""
    return 0.5 * radial_load_N / bearing.Y


# ---------------------------------------------------------------- roller-by-roller model
@dataclass(frozen=True)
class PairSetup:
    bearing: TaperedRollerBearing
    spacing_m: float                 # axial distance of the two bearings' contact mid-planes
    preload_N: float                 # axial force in each bearing at zero external load
    arrangement: str = "X"           # "O" back-to-back, "X" face-to-face (module doc)
    slices: int = 9
    roller_phase_rad: float = 0.0    # azimuth of roller 0 from the load direction


@dataclass(frozen=True)
class PairState:
    q: np.ndarray                    # (3,) u [m], w [m], theta [rad] at the pair centre
    stiffness: np.ndarray            # (3, 3) tangent, SI (N/m, N/rad, N m/rad)
    roller_load_N: np.ndarray        # (2, Z) per bearing (bearing 0 at z = -spacing/2)
    radial_force_N: np.ndarray       # (2,) per-bearing reaction along the load
    axial_force_N: np.ndarray        # (2,) per-bearing axial force (compressive)


def _geometry(setup: PairSetup):
    b = setup.bearing
    a = b.alpha_rad
    Z, l, n = b.roller_count, b.roller_length_mm, int(setup.slices)
    psi = setup.roller_phase_rad + 2 * math.pi * np.arange(Z) / Z
    s = (np.arange(n) + 0.5) / n * l - l / 2
    half = setup.spacing_m * 1e3 / 2
    if setup.arrangement not in ("O", "X"):
        raise InputError(f"tapered roller pair arrangement = {setup.arrangement!r}: allowed 'O' or 'X'")
    zs = np.array([-half, half])
    sense = -np.sign(zs) if setup.arrangement == "O" else np.sign(zs)
    lam = zs * math.cos(a) - sense * b.pitch_diameter_mm / 2 * math.sin(a)
    q0 = setup.preload_N / (Z * math.sin(a))
    d0 = (q0 / b.roller_constant_N_per_mm_pow) ** (1 / EXP) if q0 > 0 else 0.0
    return a, psi, s, sense, lam, d0, b.roller_constant_N_per_mm_pow / n


def _forces(setup: PairSetup, q_mm: np.ndarray, geo=None):
    """Force on the shaft [N, N, N mm] from both bearings, its Jacobian, roller loads (mm, N)."""
    a, psi, s, sense, lam, d0, cs = geo or _geometry(setup)
    u, w, th = q_mm
    ca, sa = math.cos(a), math.sin(a)
    F, J = np.zeros(3), np.zeros((3, 3))
    Q = np.zeros((2, len(psi)))
    c = np.cos(psi)
    for k in range(2):
        # slice approach (Z, n) and its gradient w.r.t. (u, w, theta)
        lever = lam[k] + s[None, :]
        d = ca * c[:, None] * u + sense[k] * sa * w + th * c[:, None] * lever + d0
        dp = np.maximum(d, 0.0)
        q = cs * dp ** EXP
        kq = cs * EXP * dp ** (EXP - 1)
        g = [np.broadcast_to(ca * c[:, None], d.shape), np.full(d.shape, sense[k] * sa), c[:, None] * lever]
        for i in range(3):
            F[i] -= np.sum(q * g[i])
            for j in range(3):
                J[i, j] -= np.sum(kq * g[i] * g[j])
        Q[k] = q.sum(axis=1)
    return F, J, Q


def solve_pair(setup: PairSetup, Fx_N: float, My_Nm: float = 0.0, Fz_N: float = 0.0,
               *, fixed: tuple[int, ...] = (), q_start_m=None) -> PairState:
    """Equilibrium of the shaft under Fx (at the pair centre, along psi = 0), My and Fz; DOFs in
    `fixed` (0 u, 1 w, 2 theta) are held at zero. Newton with step halving on the residual."""
    geo = _geometry(setup)
    ext = np.array([Fx_N, Fz_N, My_Nm * 1e3])          # N, N, N mm
    free = [i for i in range(3) if i not in fixed]
    q = np.zeros(3) if q_start_m is None else np.asarray(q_start_m, float) * np.array([1e3, 1e3, 1.0])
    if q_start_m is None and Fx_N > 0:
        b = setup.bearing
        q[0] = 0.5 * rigid_ring_radial_deflection_m(b, Fx_N) * 1e3   # a start inside the load zone
    scale = np.array([1.0, 1.0, 1.0 / max(setup.spacing_m * 1e3, 1.0)])
    for _ in range(200):
        F, J, Q = _forces(setup, q, geo)
        r = (F + ext)[free]
        if np.linalg.norm(r * scale[free]) < 1e-9 * max(abs(Fx_N) + abs(Fz_N) + setup.preload_N, 1.0):
            break
        Jf = J[np.ix_(free, free)]
        try:
            dq = -np.linalg.solve(Jf, r)
        except np.linalg.LinAlgError:
            dq = -r / (np.abs(np.diag(Jf)) + 1e3)
        t, base = 1.0, np.linalg.norm(r * scale[free])
        while t > 1e-6:
            trial = q.copy()
            trial[free] += t * dq
            Ft = _forces(setup, trial, geo)[0]
            if np.linalg.norm((Ft + ext)[free] * scale[free]) < base:
                break
            t *= 0.5
        q = trial
    else:
        raise InputError(f"tapered roller pair {setup.bearing.designation}: no equilibrium for Fx = {Fx_N:g} N, "
                         f"My = {My_Nm:g} N m, Fz = {Fz_N:g} N (loads beyond the bearing's reach?)")
    F, J, Q = _forces(setup, q, geo)
    conv = np.array([1e3, 1e3, 1.0])                    # q: mm -> m for u, w
    K = -J * np.array([1.0, 1.0, 1e-3])[:, None] * conv[None, :]    # rows N, N, N m; columns per m, m, rad
    a = geo[0]
    c = np.cos(geo[1])
    radial = np.array([np.sum(Q[k] * c) * math.cos(a) for k in range(2)])
    axial = Q.sum(axis=1) * math.sin(a)
    return PairState(q / conv, K, Q, radial, axial)


def condensed_stiffness(K: np.ndarray) -> np.ndarray:
    """(u, theta) tangent stiffness with the axial DOF free (no external axial load)."""
    idx = [0, 2]
    return K[np.ix_(idx, idx)] - np.outer(K[idx, 1], K[1, idx]) / K[1, 1]


@dataclass(frozen=True)
class PairCurve:
    setup: PairSetup
    load_N: np.ndarray                      # (L,) radial load at the pair centre
    deflection_m: np.ndarray                # (L,) lateral shaft deflection at the pair centre
    seat_stiffness_N_per_m: np.ndarray      # (L,) tangent radial stiffness per bearing (axial free)
    tilt_stiffness_Nm_per_rad: np.ndarray   # (L,) tangent tilt stiffness of the pair (axial free)
    max_roller_load_N: np.ndarray           # (L,)
    loaded_rollers: np.ndarray              # (L, 2) rollers carrying load, per bearing

    @property
    def pair_stiffness_N_per_m(self) -> np.ndarray:
        return 2.0 * self.seat_stiffness_N_per_m

    def effective_spread_m(self) -> np.ndarray:
        """2 sqrt(K_tilt / K_radial): the distance of two springs that give the pair's tilt
        stiffness (> spacing for O, < spacing for X)."""
        return 2 * np.sqrt(self.tilt_stiffness_Nm_per_rad / self.pair_stiffness_N_per_m)


def pair_radial_curve(setup: PairSetup, loads_N) -> PairCurve:
    """Radial load-deflection of the pair for loads at its centre (each bearing carries half)."""
    loads = np.asarray(loads_N, float)
    if loads.size == 0 or np.any(loads < 0):
        raise InputError(f"tapered roller pair loads = {loads.tolist()}: must be >= 0")
    out = {k: [] for k in ("u", "k", "kt", "qm", "nl")}
    q_prev = None
    for F in loads:
        st = solve_pair(setup, F, q_start_m=q_prev)
        q_prev = st.q
        K2 = condensed_stiffness(st.stiffness)
        out["u"].append(st.q[0])
        out["k"].append(K2[0, 0] / 2)
        out["kt"].append(K2[1, 1])
        out["qm"].append(st.roller_load_N.max())
        out["nl"].append((st.roller_load_N > 1e-9).sum(axis=1))
    return PairCurve(setup, loads, np.array(out["u"]), np.array(out["k"]), np.array(out["kt"]),
                     np.array(out["qm"]), np.array(out["nl"]))


# ---------------------------------------------------------------- closed forms (cross-checks)
def stribeck_qmax_N(bearing: TaperedRollerBearing, radial_load_N: float) -> float:
    """Most loaded roller, zero clearance, line contact, axial ring shift held: 4.08 F_r / (Z cos a)."""
    return 4.08 * radial_load_N / (bearing.roller_count * math.cos(bearing.alpha_rad))


def rigid_ring_radial_deflection_m(bearing: TaperedRollerBearing, radial_load_N: float) -> float:
    """Our linearisation for one bearing, zero clearance, axial shift held: the most loaded roller
    (Stribeck) approaches by 7.68e-5 Q_max^0.9 / l^0.8 mm along its normal, i.e. by that / cos a
    radially: delta_r = 7.68e-5 (4.08 F_r / (Z cos a))^0.9 / (l^0.8 cos a)."""
    q = stribeck_qmax_N(bearing, radial_load_N)
    return float(hertz.palmgren_needle_approach(q, bearing.roller_length_mm * 1e-3)) / math.cos(bearing.alpha_rad)


def preloaded_pair_closed_form(setup: PairSetup) -> tuple[float, float]:
    """(pair radial [N/m], pair tilt [N m/rad]) tangent stiffness at zero external load: every
    roller at Q0 = F_pre / (Z sin a), k_n = (10/9) Q0 / delta0 per roller; radial sum over the
    two bearings Z k_n cos^2 a (sum cos^2 psi = Z / 2 each), tilt sum of k_n cos^2 psi
    (lambda_b^2 + mean slice lever^2), mean s^2 = l^2 (1 - 1/n^2) / 12 for n midpoint slices."""
    a, psi, s, sense, lam, d0, cs = _geometry(setup)
    b = setup.bearing
    Z, l, n = b.roller_count, b.roller_length_mm, setup.slices
    q0 = setup.preload_N / (Z * math.sin(a))
    kn = EXP * q0 / d0                                      # N/mm
    k_rad = Z * kn * math.cos(a) ** 2                       # N/mm, both bearings
    k_tilt = sum(Z / 2 * kn * (lk ** 2 + l ** 2 * (1 - 1 / n ** 2) / 12) for lk in lam)   # N mm
    return k_rad * 1e3, k_tilt * 1e-3


# ---------------------------------------------------------------- the RV crank's supports
def crank_support_load_N(case, torque_Nm: float) -> dict:
    """Estimate of one support bearing's radial load at output torque T (SI, N):
      torque part: the cranks carry the output torque as tangential forces at the crank circle,
      T / (n_c a) per crank (both discs together), split evenly by the two supports: T / (2 n_c a);
      couple part: each disc also pushes its cranks along the pins' resultant, R = T_d / (z_c e)
      perpendicular to the eccentric (its line of action passes through the pitch point, z_c e
      from the disc centre), T_d = 0.55 T (the more loaded disc); the two discs' R oppose, so they
      only form a couple, reacted as +-R / n_c * w / s at the supports (w = disc width: the
      discs' mid-planes one width apart; s the distance of the pair's pressure centres,
      crank_support_positions_m). The couple turns with the crank; `radial_N` is the
      torque part, `couple_N` the amplitude of the rotating part."""
    cr, cy = case.carrier, case.cycloid
    a = cr.crank_circle_radius_mm * 1e-3
    tangential = torque_Nm / (2 * cr.crank_count * a)
    share = 0.55 if cy.disc_count == 2 else 1.0
    R = share * torque_Nm / (cy.zc * cy.eccentricity_mm * 1e-3)
    z1, z2 = crank_support_positions_m(case)[0]
    couple = R / cr.crank_count * cy.width_mm * 1e-3 / (z2 - z1) if cy.disc_count == 2 else 0.0
    return {"radial_N": tangential, "couple_N": couple, "disc_resultant_N": R,
            "crank_tangential_N": 2 * tangential}


def support_torsional_stiffness_Nm_per_rad(pair_stiffness_N_per_m: float, crank_count: int,
                                           crank_circle_radius_m: float) -> float:
    """Output torsional stiffness of the support bearings alone: a lateral (tangential) shift u of
    every crank moves the discs, hence the output, by u / a; n_c cranks in parallel, each the pair
    stiffness (its two bearings): K = n_c a^2 k_pair."""
    return crank_count * crank_circle_radius_m ** 2 * pair_stiffness_N_per_m


# ---------------------------------------------------------------- the case's support bearings
def operating_radial_load_N(case, torque_Nm: float) -> float:
    """One support bearing's radial load at output torque T for a linear spring: the rms over a crank
    turn of the torque part (fixed in the carrier) plus the couple part (turning with the crank,
    crank_support_load_N), sqrt(F_t^2 + F_c^2): the two add at a relative angle that runs uniformly
    over a turn, so the mean square of their sum is F_t^2 + F_c^2."""
    ld = crank_support_load_N(case, torque_Nm)
    return math.hypot(ld["radial_N"], ld["couple_N"])


def case_support_setup(case) -> PairSetup:
    """The case's pair: the catalogue size that fits the envelope (select_bearing: the case's journal
    must hold it), contact mid-planes one support span apart, face-to-face (X, module doc), the
    operating preload of the rated torque's bearing load."""
    b = case_bearing(case)
    pre = operating_preload_N(b, operating_radial_load_N(case, case.rated_torque_Nm))
    return PairSetup(b, case.crankshaft.support_span_mm * 1e-3, pre, CRANK_ARRANGEMENT)


def case_bearing(case) -> TaperedRollerBearing:
    """The catalogue size the case's journal and envelope hold (select_bearing)."""
    return select_bearing(case.crankshaft.journal_radius_mm, case_envelope(case))


def case_support_bearings(case, max_load_N: float, points: int = 12) -> dict:
    """Per-bearing radial load-deflection of the case's pair (loads at the pair centre: each bearing
    carries half) from 2 % of max_load_N to max_load_N, the operating load of the rated torque among
    them; the tangent there is the lumped model's spring. Checks: the preloaded pair at zero load
    against its linearised closed form, the unpreloaded pair against Palmgren-Stribeck (rigid
    rings, axial shift held), the derived geometry against the catalogue static rating."""
    su = case_support_setup(case)
    b = su.bearing
    op = operating_radial_load_N(case, case.rated_torque_Nm)
    loads = np.unique(np.append(np.geomspace(0.02 * max_load_N, max_load_N, points), op))
    cur = pair_radial_curve(su, 2 * loads)
    i_op = int(np.flatnonzero(loads == op)[0])
    k_rad, _ = preloaded_pair_closed_form(su)
    k0 = pair_radial_curve(su, [1e-3 * op]).pair_stiffness_N_per_m[0]
    loose = solve_pair(PairSetup(b, su.spacing_m, 0.0, su.arrangement), 2 * op, fixed=(1, 2))
    ld = crank_support_load_N(case, case.rated_torque_Nm)
    span = [abs(ld["radial_N"] - ld["couple_N"]), ld["radial_N"] + ld["couple_N"]]
    k_span = pair_radial_curve(su, 2 * np.array(span)).seat_stiffness_N_per_m
    return {
        "bearing": b, "setup": su, "load_N": loads, "deflection_m": cur.deflection_m,
        "tangent_N_per_m": cur.seat_stiffness_N_per_m, "operating_load_N": op,
        "stiffness_N_per_m": float(cur.seat_stiffness_N_per_m[i_op]),
        "source": (f"{b.designation} ({b.source}); internal geometry derived by the stated rule; roller by "
                   f"roller with ISO/TS 16281 slices, Palmgren line contact, rigid rings (fem.tapered_roller); "
                   f"face-to-face pair {su.spacing_m * 1e3:g} mm apart, preload {su.preload_N:.0f} N = induced "
                   f"thrust 0.5 F_r / Y at the operating load; operating load = rms of the rated torque's "
                   f"part and the rotating couple part, sqrt(F_t^2 + F_c^2); stiffness = tangent there"),
        "check": {"preloaded_pair_zero_load_N_per_m": float(k0), "closed_form_N_per_m": float(k_rad),
                  "preloaded_error": float(k0 / k_rad - 1),
                  "unpreloaded_deflection_at_operating_m": float(loose.q[0]),
                  "palmgren_stribeck_deflection_m": rigid_ring_radial_deflection_m(b, op),
                  "unpreloaded_error": float(loose.q[0] / rigid_ring_radial_deflection_m(b, op) - 1),
                  "max_roller_load_at_operating_N": float(cur.max_roller_load_N[i_op]),
                  "loaded_rollers_at_operating": cur.loaded_rollers[i_op].tolist(),
                  "derived_C0r_over_catalogue": b.derived_C0r_N / b.C0r_N,
                  "torque_part_N": ld["radial_N"], "couple_part_N": ld["couple_N"],
                  "tangent_at_torque_minus_couple_N_per_m": float(k_span[0]),
                  "tangent_at_torque_plus_couple_N_per_m": float(k_span[1])}}


def crank_support_positions_m(case, at: str = "pressure") -> tuple[tuple[float, float], float]:
    """Where the crank is pinned (crank frame, z of J1 and J2) and the half-width of the band the
    reaction spreads over. at='pressure' (the model, fem.crank_tilt): the support pair's pressure
    centres (X: R_m tan(alpha) inside each bearing centre, 3.3 mm for the RV-40E's 30203), a band
    centred there and kept on the seat (the seat's inner part: half_seat - offset,
    at least MIN_BAND_SHARE of the half seat). at='bearing': the bearing centres, the whole seat
    (the pin of fem.shaft's single-load check)."""
    from geometry.solids import crankshaft_layout
    lay = crankshaft_layout(case)
    span = lay.support_span_mm * 1e-3
    half_seat = 0.5 * (lay.journals_mm[0][1] - lay.journals_mm[0][0]) * 1e-3
    if at == "bearing":
        return (0.0, span), half_seat
    if at != "pressure":
        raise ValueError(f"at = {at!r}: 'pressure' or 'bearing'")
    off = case_bearing(case).pressure_centre_offset_mm * 1e-3 * (1.0 if CRANK_ARRANGEMENT == "X" else -1.0)
    band = max(half_seat - abs(off), MIN_BAND_SHARE * half_seat)
    shift = math.copysign(min(abs(off), half_seat - band), off)
    return (shift, span - shift), band
