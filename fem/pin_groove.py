"""The pin in its housing groove: conformal contact (pin radius R in a groove of radius R + dR),
pin bending along the groove, and the series law the lead adds to the cycloid-pin contact law.

Conformal contact, plane strain, frictionless, pin and housing of one material (elastic
similarity, as in Persson 1964 and Ciavarella & Decuzzi 2001, Int. J. Solids Struct. 38; Johnson,
Contact Mechanics, sec. 5.6). Both boundaries are treated at radius R (dR << R) and loaded by the
same pressure p(theta) = a0 + sum a_n cos(n theta) (theta from the load direction). Michell's
solutions give each Fourier mode's radial displacement (kappa = 3 - 4 nu, mu = shear modulus):
  solid pin, inward:         n = 0: (kappa - 1) a0 R / (4 mu);   n >= 2: a_n R [(kappa+1) n - (kappa-1)] / (4 mu (n^2-1))
  hole in a plate, outward:  n = 0: a0 R / (2 mu);                n >= 2: a_n R [(kappa+1) n + (kappa-1)] / (4 mu (n^2-1))
so the gap opens by a0 R / E* and a_n R (2 / E*) n / (n^2 - 1) (1/E* = 2 (1 - nu^2) / E); the
n = 1 mode (the net force P' = pi R a1) only moves the pin as a body and joins the rigid approach.
The mode sums are summed in closed form (n/(n^2-1) = (1/(n-1) + 1/(n+1))/2 and
sum cos(n x)/n = -ln|2 sin(x/2)|): sum_{n>=2} n/(n^2-1) cos(n x) = -cos x ln|2 sin(x/2)| - 1/2
- cos(x)/4 and sum_{n>=2} cos(n x)/(n^2-1) = (1 + cos(x)/2 - (pi - |x|) sin|x|)/2, so the gap
is an integral of p against a log kernel: no Fourier truncation, any contact angle.
Contact over |theta| <= eps: gap dR (1 - cos theta) - delta cos theta + deformation = 0. For a
given eps the problem is linear: pressure on graded nodes (piecewise linear, zero at eps; the log
part integrated exactly), the gap collocated at every node including eps; P'(eps) is monotonic
and is inverted for a load. This is the exact 2D elasticity solution of the linearised geometry
to the discretisation (48 nodes: 1e-4). Checks (tests/test_fem_rolling.py): small eps -> Hertz
with R' = R (R + dR) / dR, P' / (E* dR) -> pi tan^2(eps / 2), and Johnson eq. 5.36 for the pin;
pressure >= 0 inside, gap >= 0 outside; conformity makes the contact stiffer than that Hertz
figure as eps grows (+3.5 % load at 17 deg, +66 % at 57 deg); the load grows without bound as eps
nears about 84.5 deg, this model's zero-clearance contact angle.
Approaches (2D needs a datum, as in fem.hertz):
  pin: centre to the groove-side surface, the pin loaded symmetrically on both sides (the
    analogue of Johnson eq. 5.36, to which it tends at small eps);
  housing: groove bottom to a point at depth d behind it, hole in an infinite plate, all modes
    (n = 1 from Michell's r log r, r theta sin theta and 1/r terms with single-valued
    displacement; the analogue of fem.hertz.half_plane_approach, its limit at small eps and d).
  DATUM: d = one pin pitch, the same rule the tooth-pin FE uses for its clamped disc arc.
Fit: ISO 286 H7 groove / h6 pin at the pin diameter, mean clearance (IT7 + IT6) / 2 diametral.
Bending: with a continuous groove the pin is a beam on a compression-only elastic foundation
(the conformal contact's tangent modulus) loaded by one disc over its width: bending spreads the
load and lowers the pin's approach under the disc (no extra compliance); an interrupted groove
(pin held at its ends) bends over its span: `span_bending_deflection_m`.
Series law for the lead: the project's tooth-pin FE (fem.pin_contact) clamps the pin's back half,
so it already holds the pin body; what it lacks is the housing behind the groove:
`PinGrooveLaw.housing_approach_m` (+ the bending term), added in series per pin.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import solve_banded

from geometry.artifacts import InputError

NODES = 48              # pressure nodes on [0, eps], graded towards eps
GAUSS = 8               # Gauss points per panel for the smooth parts of the kernels
# ISO 286-1 standard tolerance grades [um] for nominal sizes (over, up to and including] [mm]
IT_TABLE = ((3, 6, 10), (6, 8, 12), (10, 9, 15), (18, 11, 18), (30, 13, 21), (50, 16, 25), (80, 19, 30))


def iso286_h7_h6_radial_clearance_m(diameter_mm: float) -> tuple[float, float, float]:
    """(min, mean, max) RADIAL clearance of an H7 hole on an h6 shaft [m]: H7 = 0..+IT7,
    h6 = -IT6..0, so the diametral clearance runs 0..IT7 + IT6 (ISO 286-1 table of IT grades)."""
    for upto, it6, it7 in IT_TABLE:
        if 0 < diameter_mm <= upto:
            dmax = (it6 + it7) * 1e-6
            return 0.0, dmax / 4, dmax / 2
    raise InputError(f"pin diameter = {diameter_mm!r} mm: the ISO 286 table here covers 0 < d <= 80 mm")


def _material(E_Pa: float, nu: float):
    mu = E_Pa / (2 * (1 + nu))
    return mu, 3 - 4 * nu, E_Pa / (2 * (1 - nu * nu))          # mu, kappa, E* of two like bodies


@dataclass(frozen=True)
class ConformalState:
    eps_rad: float                   # contact half-angle
    load_per_length_N_per_m: float   # P'
    theta_rad: np.ndarray            # nodes on [0, eps]
    pressure_Pa: np.ndarray          # nodal pressure
    pin_approach_m: float            # pin centre to groove-side surface (symmetric datum)
    housing_approach_m: float        # groove bottom to the datum at depth d
    min_gap_outside_m: float         # >= 0 for an admissible solution
    min_pressure_Pa: float


def _K(x):
    """sum_{n>=2} n / (n^2 - 1) cos(n x) = -cos x ln|2 sin(x/2)| - 1/2 - cos(x) / 4
    (n / (n^2 - 1) = (1/(n-1) + 1/(n+1)) / 2 and sum cos(n x) / n = -ln|2 sin(x/2)|)."""
    return -np.cos(x) * np.log(np.abs(2 * np.sin(x / 2))) - 0.5 - 0.25 * np.cos(x)


def _K_regular(x):
    """_K(x) + ln|x|: continuous at 0 (value -3/4); the log is integrated exactly."""
    ax = np.maximum(np.abs(x), 1e-300)
    sinc = np.where(ax < 1e-8, 1.0, np.abs(2 * np.sin(x / 2)) / ax)
    return -np.cos(x) * np.log(sinc) - (np.cos(x) - 1) * np.log(ax) - 0.5 - 0.25 * np.cos(x)


def _T(x):
    """sum_{n>=2} cos(n x) / (n^2 - 1) = (1 + cos(x)/2 - (pi - |x|) sin|x|) / 2, |x| <= 2 pi."""
    ax = np.mod(np.abs(x), 2 * np.pi)
    return 0.5 * (1 + 0.5 * np.cos(x) - (np.pi - ax) * np.sin(ax))


def _log_hat(a: np.ndarray, b: np.ndarray, c: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact (left hat, right hat) integrals of ln|phi - c| over the panels [a, b] (arrays)."""
    def F(u):
        au = np.abs(u)
        lg = np.where(au > 0, np.log(np.where(au > 0, au, 1.0)), 0.0)
        return u * lg - u, u * u / 2 * lg - u * u / 4
    F0b, F1b = F(b - c)
    F0a, F1a = F(a - c)
    J0, J1 = F0b - F0a, F1b - F1a
    right = (J1 + (c - a) * J0) / (b - a)
    return J0 - right, right


class _Discretisation:
    """Graded nodes on [0, eps] (dense at eps, where p ~ sqrt(eps - theta)), piecewise-linear
    pressure with p(eps) = 0, and the kernel integrals each needs."""

    def __init__(self, eps: float, nodes: int):
        m = nodes
        self.t = eps * np.sin(0.5 * np.pi * np.arange(m + 1) / m)
        gx, gw = np.polynomial.legendre.leggauss(GAUSS)
        lo, hi = self.t[:-1], self.t[1:]
        self.x = (0.5 * (hi - lo)[:, None] * gx + 0.5 * (hi + lo)[:, None]).ravel()     # (m*G,)
        w = (0.5 * (hi - lo)[:, None] * gw).ravel()
        left = ((np.repeat(hi, GAUSS) - self.x) / np.repeat(hi - lo, GAUSS))
        panel = np.repeat(np.arange(m), GAUSS)
        # W[i, q]: weight of quadrature point q for nodal value i (int N_i f = W[i] @ f(x))
        self.W = np.zeros((m, m * GAUSS))
        self.W[panel, np.arange(m * GAUSS)] += w * left
        nxt = panel + 1 < m
        self.W[panel[nxt] + 1, np.arange(m * GAUSS)[nxt]] += (w * (1 - left))[nxt]
        self.m = m

    def integral(self, regular, c: float, log_coeff: float) -> np.ndarray:
        """(m,) int N_i(phi) [regular(phi) + log_coeff ln|phi - c|] dphi over [0, eps]."""
        out = self.W @ regular(self.x)
        if log_coeff:
            left, right = _log_hat(self.t[:-1], self.t[1:], c)
            out += log_coeff * left
            out[1:] += log_coeff * right[:-1]      # the hat of node m (at eps) carries no pressure
        return out

    def cosine(self, n: np.ndarray) -> np.ndarray:
        """(m, len(n)) with a_n = p @ result: a_0 = (1/pi) int p, a_n = (2/pi) int p cos(n phi)."""
        C = self.W @ np.cos(np.outer(self.x, n)) * (2 / np.pi)
        C[:, np.asarray(n) == 0] *= 0.5
        return C


def conformal_state(eps_rad: float, *, radius_m: float, clearance_m: float, E_Pa: float, nu: float,
                    datum_depth_m: float, nodes: int = NODES) -> ConformalState:
    """The conformal contact with half-angle eps (module doc): linear in the clearance dR."""
    R, dR, eps = radius_m, clearance_m, float(eps_rad)
    if not (0 < eps < 0.5 * math.pi):
        raise InputError(f"conformal contact half-angle = {eps!r} rad: allowed 0 < eps < pi/2")
    mu, kap, Es = _material(E_Pa, nu)
    D = _Discretisation(eps, nodes)
    t = D.t
    C01 = D.cosine(np.array([0, 1]))
    # gap deformation at node j: (R/E*) a0 + (2R/(pi E*)) int p(phi) [K(t_j - phi) + K(t_j + phi)]
    A = np.zeros((nodes + 1, nodes + 1))
    for j, tj in enumerate(t):
        kint = (D.integral(lambda x: _K_regular(tj - x), tj, -1.0)
                + D.integral(lambda x: _K_regular(tj + x), -tj, -1.0))
        A[j, :nodes] = R / Es * C01[:, 0] + 2 * R / (math.pi * Es) * kint
    A[:, nodes] = -np.cos(t)                     # rigid approach delta
    sol = np.linalg.solve(A, -dR * (1 - np.cos(t)))
    p, delta = sol[:nodes], sol[nodes]
    a0, a1 = p @ C01[:, 0], p @ C01[:, 1]
    # pin (symmetric load, even modes doubled), inward at theta = 0
    k_even = D.integral(lambda x: 0.5 * (_K_regular(x) + _K(x + np.pi)), 0.0, -0.5)
    t_even = D.W @ (0.5 * (_T(D.x) + _T(D.x + np.pi)))
    pin = (kap - 1) * R * 2 * a0 / (4 * mu) + 2 * R / (4 * mu) * (2 / np.pi) * p @ ((kap + 1) * k_even - (kap - 1) * t_even)
    # housing: groove bottom outward (n >= 2 boundary, closed form) minus the same at depth d
    k0 = D.integral(_K_regular, 0.0, -1.0)
    t0 = D.W @ _T(D.x)
    boundary = R / (4 * mu) * (2 / np.pi) * p @ ((kap + 1) * k0 + (kap - 1) * t0)
    rho = R / (R + datum_depth_m)
    nmax = int(min(20000, max(50, math.log(1e-14) / math.log(rho) + 10)))
    n = np.arange(2, nmax + 1, dtype=float)
    a_n = p @ D.cosine(n)
    at_d = (kap + n - 1) * rho ** (n - 1) / (2 * (n - 1)) - n * rho ** (n + 1) / (2 * (n + 1))
    housing = (boundary - R / (2 * mu) * float(a_n @ at_d) + a0 * R / (2 * mu) * (1 - rho)
               + a1 * R / ((kap + 1) * 2 * mu) * (kap * math.log(1 + datum_depth_m / R) + (kap - 1) / 4 * (1 - rho ** 2)))
    # admissibility: the gap outside the contact, up to pi
    th = np.linspace(eps, math.pi, 120)[1:]
    g = np.array([R / Es * a0 + 2 * R / (math.pi * Es) * p @ (D.W @ (_K(tt - D.x) + _K(tt + D.x))) for tt in th])
    g += dR * (1 - np.cos(th)) - delta * np.cos(th)
    return ConformalState(eps, math.pi * R * a1, t, np.append(p, 0.0), float(pin), float(housing),
                          float(g.min()), float(p.min()))


@dataclass(frozen=True)
class PinGrooveLaw:
    load_N: np.ndarray
    eps_rad: np.ndarray
    pin_approach_m: np.ndarray       # pin centre to groove-side surface
    housing_approach_m: np.ndarray   # groove bottom to the datum depth
    bending_factor: np.ndarray       # pin approach under the disc with bending / without (<= 1: spreads)
    clearance_m: float
    datum_depth_m: float
    loaded_length_m: float

    @property
    def centre_approach_m(self) -> np.ndarray:
        """Pin centre to housing datum (pin + housing), bending included."""
        return (self.pin_approach_m + self.housing_approach_m) * self.bending_factor

    @property
    def series_approach_m(self) -> np.ndarray:
        """What to add in series to the tooth-pin FE law (pin body already there): housing."""
        return self.housing_approach_m * self.bending_factor

    def tangent_stiffness_N_per_m(self, which: str = "series") -> np.ndarray:
        d = self.series_approach_m if which == "series" else self.centre_approach_m
        return np.gradient(self.load_N, d)


def conformal_law(loads_N, *, radius_m: float, clearance_m: float, loaded_length_m: float, E_Pa: float,
                  nu: float, datum_depth_m: float, nodes: int = 32) -> dict:
    """eps, pin and housing approach for each load (uniform along loaded_length_m): the contact is
    solved on a grid of half-angles (0.1 .. 80 deg; the load grows without bound towards
    about 84.5 deg, the zero-clearance angle of this model) and the loads are interpolated monotonically
    in log P' (PCHIP; the grid error is below 1e-4 relative, tests)."""
    from scipy.interpolate import PchipInterpolator
    loads = np.asarray(loads_N, float)
    if not (clearance_m > 0):
        raise InputError(f"pin groove clearance = {clearance_m!r} m: must be > 0 (zero clearance is the "
                         f"limit of a half-circle seat; use a small positive value)")
    if loads.size == 0 or np.any(loads <= 0):
        raise InputError(f"pin groove loads = {loads.tolist()}: must be positive")
    eps = np.radians(np.concatenate([np.geomspace(0.1, 10, 12, endpoint=False), np.linspace(10, 80, 25)]))
    st = [conformal_state(e, radius_m=radius_m, clearance_m=clearance_m, E_Pa=E_Pa, nu=nu,
                          datum_depth_m=datum_depth_m, nodes=nodes) for e in eps]
    logP = np.log([x.load_per_length_N_per_m for x in st])
    target = np.log(loads / loaded_length_m)
    if np.any(np.diff(logP) <= 0):
        raise RuntimeError("conformal contact: load not monotonic in the contact angle (discretisation)")
    if target.min() < logP[0] or target.max() > logP[-1]:
        raise InputError(f"pin groove loads {loads.min():g}..{loads.max():g} N over {loaded_length_m * 1e3:g} mm: "
                         f"outside the contact-angle range 0.1..80 deg of clearance {clearance_m * 1e6:g} um")
    out = {"eps_rad": PchipInterpolator(logP, eps)(target)}
    for key in ("pin_approach_m", "housing_approach_m"):
        vals = np.log([getattr(x, key) for x in st])
        out[key] = np.exp(PchipInterpolator(logP, vals)(target))
    return out


def pin_groove_law(loads_N, *, radius_m: float, clearance_m: float, loaded_length_m: float,
                   pin_length_m: float, E_Pa: float, nu: float, datum_depth_m: float,
                   continuous_groove: bool = True) -> PinGrooveLaw:
    """Series law of one pin in its groove (module doc). The load acts over loaded_length_m (one
    disc width) at one end of a pin of pin_length_m (the other disc leaves it unloaded)."""
    loads = np.asarray(loads_N, float)
    st = conformal_law(loads, radius_m=radius_m, clearance_m=clearance_m, loaded_length_m=loaded_length_m,
                       E_Pa=E_Pa, nu=nu, datum_depth_m=datum_depth_m)
    pin, hou = st["pin_approach_m"], st["housing_approach_m"]
    if continuous_groove:
        # foundation modulus: tangent of P' against the pin-centre approach
        kf = np.gradient(loads / loaded_length_m, pin + hou) if loads.size > 1 else \
            loads / loaded_length_m / (pin + hou)
        bend = np.array([bef_factor(k, radius_m, E_Pa, pin_length_m, loaded_length_m) for k in kf])
    else:
        I = math.pi * radius_m ** 4 / 4
        extra = np.array([span_bending_deflection_m(F, pin_length_m, loaded_length_m, E_Pa * I) for F in loads])
        bend = 1 + extra / (pin + hou)
    return PinGrooveLaw(loads, st["eps_rad"], pin, hou, bend, clearance_m,
                        datum_depth_m, loaded_length_m)


# ---------------------------------------------------------------- pin bending
def bef_factor(foundation_N_per_m2: float, radius_m: float, E_Pa: float, pin_length_m: float,
               loaded_length_m: float, elements: int = 80) -> float:
    """Mean deflection under the load of a free pin (Euler-Bernoulli, Hermite elements) on a
    compression-only Winkler foundation, load q over [0, loaded_length] at one end, divided by the
    no-bending value q / k. Lift-off of the unloaded end is found by an active set."""
    L, ne = pin_length_m, int(elements)
    h = L / ne
    EI = E_Pa * math.pi * radius_m ** 4 / 4
    k = foundation_N_per_m2
    Ke = EI / h ** 3 * np.array([[12, 6 * h, -12, 6 * h], [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                                 [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h * h, -6 * h, 4 * h * h]])
    Me = k * h / 420 * np.array([[156, 22 * h, 54, -13 * h], [22 * h, 4 * h * h, 13 * h, -3 * h * h],
                                 [54, 13 * h, 156, -22 * h], [-13 * h, -3 * h * h, -22 * h, 4 * h * h]])
    nd = 2 * (ne + 1)
    dof = 2 * np.arange(ne)[:, None] + np.arange(4)[None, :]          # (ne, 4)
    rows, cols = np.repeat(dof, 4, axis=1), np.tile(dof, (1, 4))      # (ne, 16)
    Kb = np.zeros((nd, nd))
    np.add.at(Kb, (rows, cols), np.broadcast_to(Ke.ravel(), (ne, 16)))
    loaded = (np.arange(ne) + 0.5) * h < loaded_length_m
    f = np.zeros(nd)
    np.add.at(f, dof[loaded], np.broadcast_to(h / 12 * np.array([6, h, 6, -h]), (int(loaded.sum()), 4)))
    active = np.ones(ne, bool)
    for _ in range(50):
        K = Kb.copy()
        np.add.at(K, (rows[active], cols[active]), np.broadcast_to(Me.ravel(), (int(active.sum()), 16)))
        ab = np.zeros((7, nd))                # banded storage (half-bandwidth 3): no dense BLAS
        for off in range(-3, 4):
            ab[3 - off, max(off, 0):nd + min(off, 0)] = np.diagonal(K, off)
        w = solve_banded((3, 3), ab, f)
        wc = 0.5 * (w[0:-2:2] + w[2::2])
        new = wc > 0
        if np.array_equal(new, active):
            break
        active = new
    return float(wc[loaded].mean() * k)       # mean deflection / (q / k), q = 1


def span_bending_deflection_m(load_N: float, span_m: float, loaded_length_m: float, EI_Nm2: float) -> float:
    """Mid-span deflection of a pin simply supported at its ends, load spread over a central length
    c: w = q c (8 L^3 - 4 L c^2 + c^3) / (384 EI) (c = L gives 5 q L^4 / 384 EI)."""
    L, c = span_m, min(loaded_length_m, span_m)
    q = load_N / c
    return q * c * (8 * L ** 3 - 4 * L * c * c + c ** 3) / (384 * EI_Nm2)


# ---------------------------------------------------------------- the case: pin forces, output stiffness
def pin_moment_arms_m(case, crank_angle_rad: float = 0.0) -> np.ndarray:
    """Moment arm of each pin's force about the disc centre (Blanche & Yang): the line of action
    runs from the pin centre through the pitch point, z_c e from the disc centre,
    l_i = z_c e sin(phi_i) / sqrt(1 + K1^2 - 2 K1 cos(phi_i)), K1 = e z_p / r_p; <= 0: unloaded."""
    cy = case.cycloid
    e, rp, zp, zc = cy.eccentricity_mm * 1e-3, cy.pin_circle_radius_mm * 1e-3, cy.zp, cy.zc
    K1 = e * zp / rp
    phi = 2 * np.pi * np.arange(zp) / zp - crank_angle_rad
    return zc * e * np.sin(phi) / np.sqrt(1 + K1 * K1 - 2 * K1 * np.cos(phi))


def pin_forces_N(case, torque_Nm: float, disc_share: float = 0.55) -> tuple[np.ndarray, np.ndarray]:
    """(forces, arms) of one disc's pins carrying disc_share * T with equal linear pin springs and
    a rigid disc (forces proportional to the arms; modifications ignored)."""
    arms = pin_moment_arms_m(case)
    arms = arms[arms > 1e-9]
    Fmax = disc_share * torque_Nm * arms.max() / np.sum(arms ** 2)
    return Fmax * arms / arms.max(), arms


def pin_torsional_stiffness_Nm_per_rad(pin_stiffness_N_per_m: np.ndarray, arms_m: np.ndarray) -> float:
    """A pin approach delta at arm l turns the disc (and the output: the disc turns with the
    carrier) by delta / l; pins act in parallel: K = sum k_i l_i^2 (one disc; add the discs)."""
    return float(np.sum(np.asarray(pin_stiffness_N_per_m) * np.asarray(arms_m) ** 2))


def case_pin_groove_law(case, loads_N, *, clearance: str = "mean") -> PinGrooveLaw:
    """The case's pin in an H7/h6 groove (ASSUMED fit), datum one pin pitch deep, continuous groove,
    loaded over one disc width at one end of a pin two disc widths long."""
    cy, mat = case.cycloid, case.material
    R = cy.pin_radius_mm * 1e-3
    lo, mean, hi = iso286_h7_h6_radial_clearance_m(2 * cy.pin_radius_mm)
    dR = {"min": max(lo, 1e-7), "mean": mean, "max": hi}[clearance]
    pitch = 2 * math.pi * cy.pin_circle_radius_mm * 1e-3 / cy.zp
    w = cy.width_mm * 1e-3
    return pin_groove_law(loads_N, radius_m=R, clearance_m=dR, loaded_length_m=w,
                          pin_length_m=cy.disc_count * w, E_Pa=mat.youngs_modulus_GPa * 1e9,
                          nu=mat.poisson_ratio, datum_depth_m=pitch)


def case_series(case, loads_N) -> dict:
    """The stiffness.json entry: the housing approach behind the groove plus the bending term
    (PinGrooveLaw.series_approach_m) over the pin table's loads, and its checks: the conformal
    contact at 1 deg against Hertz line contact with the clearance radius R' = R (R + dR) / dR
    (half-width, peak pressure, housing approach to a shallow datum d = R / 10, where the hole's
    curvature is negligible), and at the rated pin force the groove's tangent stiffness beside the
    Hertz-limit housing approach to the same datum (one pin pitch)."""
    from fem import hertz
    from fem.pin_contact import contact_force_at_torque
    loads = np.asarray(loads_N, float)
    law = case_pin_groove_law(case, loads)
    cy, mat = case.cycloid, case.material
    E, nu = mat.youngs_modulus_GPa * 1e9, mat.poisson_ratio
    R, w = cy.pin_radius_mm * 1e-3, cy.width_mm * 1e-3
    dR, pitch = law.clearance_m, law.datum_depth_m
    Es = hertz.contact_modulus(E, nu)
    Rp = R * (R + dR) / dR
    s = conformal_state(math.radians(1.0), radius_m=R, clearance_m=dR, E_Pa=E, nu=nu, datum_depth_m=R / 10)
    F1 = s.load_per_length_N_per_m * w
    p0, b = (float(v) for v in hertz.hertz_line(F1, w, Rp, Es))
    Fr = contact_force_at_torque(case, case.rated_torque_Nm)
    at = case_pin_groove_law(case, np.array([0.999, 1.0, 1.001]) * Fr)
    _, br = hertz.hertz_line(Fr, w, Rp, Es)
    hertz_housing = float(hertz.half_plane_approach(Fr, w, float(br), pitch, E, nu))
    check = {"hertz_limit_1deg": {"half_width_error": R * math.sin(s.eps_rad) / b - 1,
                                  "peak_pressure_error": float(s.pressure_Pa[0]) / p0 - 1,
                                  "housing_approach_error": s.housing_approach_m
                                  / float(hertz.half_plane_approach(F1, w, b, R / 10, E, nu)) - 1},
             "rated_pin_force_N": Fr, "contact_half_angle_at_rated_deg": math.degrees(float(at.eps_rad[1])),
             "series_approach_at_rated_m": float(at.series_approach_m[1]),
             "hertz_limit_housing_approach_at_rated_m": hertz_housing,
             "tangent_at_rated_N_per_m": float(at.tangent_stiffness_N_per_m()[1]),
             "bending_factor_at_rated": float(at.bending_factor[1]),
             "clearance_m": dR, "datum_depth_m": pitch,
             "max_contact_half_angle_deg": math.degrees(float(law.eps_rad.max()))}
    return {"load_N": loads, "series_approach_m": law.series_approach_m, "check": check,
            "source": (f"conformal contact of the pin in an H7/h6 groove (mean radial clearance {dR * 1e6:.1f} um, "
                       f"ISO 286), exact 2D Michell solution of the linearised geometry; series part = the "
                       f"housing behind the groove to one pin pitch depth, times the pin-bending factor of a "
                       f"continuous groove (fem.pin_groove); the pin body is in the tooth-pair FE")}
