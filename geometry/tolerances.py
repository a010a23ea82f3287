"""Tolerance bands of the as-built Monte Carlo ([tolerances] of a case file; read by dynamics.tolerance).

Kept beside geometry.params (which validates the case and re-exports them) as geometry.params_assembly
keeps the assembly sections: one section's fields and the grade each stands for.
"""
from __future__ import annotations

from dataclasses import dataclass

from geometry.case_fields import ranged as _f

# half of geometry.params.ERROR_UM_MAX: the difference of two draws (e.g. two eccentrics) stays an
# error (tests/test_params.py holds the two together)
TOLERANCE_UM_MAX = 50.0


@dataclass(frozen=True)
class Tolerances:
    """Tolerance bands of the as-built Monte Carlo (`tolerance --model full`, dynamics.tolerance),
    um: +- half-width of a symmetric band (uniform, or normal with band = 3 sigma), or a maximum
    (clearances, runouts, lobe amplitudes: uniform in [0, max], phase uniform). Defaults: an
    RV-40E-sized precision reducer; the grade each stands for is in the comment. Only the
    tolerance stage reads them: they are left out of the case fingerprint (ReducerCase.to_dict),
    so a band change does not make the FE stale; the tolerance artifacts record the bands."""
    # each eccentric centre, radial and tangential: ISO 286 IT5 at <= 3 mm (the eccentricity) = 4 um
    eccentricity_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=2.0)
    # crank timing at the planet pitch circle: ISO 1328-1 grade 5 single pitch f_pt (m 2, d 48: 5.5 um)
    crank_timing_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=5.5)
    # disc crank holes, carrier crank seats, radial and tangential: ISO 286 IT5 at 30-50 mm = 11 um
    crank_hole_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=5.5)
    bearing_hole_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=5.5)
    # each pin's groove, radial and tangential: half ISO 1328-1 grade 5 f_pt of the pin ring read as
    # an internal gear (m 3.2, d 128: 6.3 um), so neighbouring pins differ by up to f_pt
    pin_position_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=3.0)
    # each pin's radius: ISO 3096 grade G2 rollers (2 um diameter variation in a lot)
    pin_radius_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=0.5)
    # max amplitude of each pin-ring lobe m = 1..4 (radial): housing roundness, ASSUMED IT3 at
    # 120-180 mm (5 um) shared by the lobes, a P5 bearing seat's form grade
    pin_ring_lobes_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=1.2)
    # max 1-lobe cumulative pitch amplitude per disc: ISO 1328-1 grade 5 F_p (m 3.2, d 128: 22 um) / 2
    disc_pitch_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=11.0)
    # each disc's profile (material +-): ASSUMED half the grade 5 profile form f_f_alpha (~7 um)
    disc_profile_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=3.5)
    # disc 2 against disc 1 at R: ASSUMED, discs ground as a stacked pair (one f_pt / 3)
    disc_phase_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=2.0)
    # max radial clearances: needle bearing ASSUMED C2-class (0-5 um), preloaded tapered supports 0-2 um
    turning_arm_clearance_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=5.0)
    support_clearance_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=2.0)
    # max main-bearing runout (eccentricity): ISO 492 class 5 inner ring K_ia (d 80-120: 5 um) / 2
    main_bearing_runout_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=2.5)
    # max encoder/mounting eccentricity on the bench (a reading, not the reducer): ASSUMED a
    # dial-indicated mount, 20 um TIR
    output_coaxiality_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=10.0)
    # max tilt of the pin ring's axis against the carrier's, as the pin circle's centre offset at each
    # disc plane (Errors.pin_ring_tilt_um): ASSUMED the pin ring and the main-bearing seats bored in one
    # setting, a coaxiality of IT3 at 120-180 mm (5 um) over the housing, shared by the two planes
    pin_ring_tilt_um: float = _f(0.0, TOLERANCE_UM_MAX, open_lo=False, default=2.5)
