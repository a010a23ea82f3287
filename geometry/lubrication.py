"""The case's `[lubrication]` section: lubricant grade, surface finish and friction constants.

Read only by the operating-map model (dynamics.losses): like `[tolerances]` it is left out of the
case fingerprint (geometry.params.ReducerCase.to_dict), so a lubricant change does not make the FE
stale; the `conditions` artifacts record the section they used. Defaults are the shipped cases'
ASSUMED lubricant (the bench does not name its oil): an ISO VG 68 mineral gear oil. Where a
published constant spans a range the default is its middle and the comment gives the ends.
Validated by geometry.params like every section (key, value and allowed range in the message).
"""
from __future__ import annotations

from dataclasses import dataclass

from geometry.case_fields import ranged


def _r(lo: float, hi: float, default: float, why: str = "", open_lo: bool = True) -> float:
    """A field with an allowed range (open at lo unless said) and a default."""
    return ranged(lo, hi, open_lo=open_lo, why=why, default=default)


@dataclass(frozen=True)
class Lubrication:
    # ISO 3448 VG 68: 61.2-74.8 cSt at 40 C; 8.7 cSt at 100 C (viscosity index ~100, a mineral gear oil)
    viscosity_40C_cSt: float = _r(1.0, 10000.0, 68.0)
    viscosity_100C_cSt: float = _r(0.5, 1000.0, 8.7)
    density_15C_kg_per_m3: float = _r(500.0, 2000.0, 880.0)        # mineral oil, 860-900
    # Barus pressure-viscosity coefficient of mineral oils: 15-25 /GPa (Hamrock 2004, table 4.2)
    pressure_viscosity_per_GPa: float = _r(1.0, 60.0, 20.0)
    # range where the Walther (ASTM D341) law is applied: above the pour point, below oxidation
    min_temperature_C: float = _r(-60.0, 200.0, -10.0)
    max_temperature_C: float = _r(-60.0, 250.0, 120.0)
    # roughness Ra [um]: ground cycloid profile 0.2-0.6 (ISO 1302 N5-N6), superfinished pins and
    # rollers 0.05-0.2, ground bearing races and eccentrics 0.1-0.3, ground involute flanks 0.3-0.5
    disc_Ra_um: float = _r(0.0, 10.0, 0.4)
    pin_Ra_um: float = _r(0.0, 10.0, 0.1)
    race_Ra_um: float = _r(0.0, 10.0, 0.2)
    gear_Ra_um: float = _r(0.0, 10.0, 0.4)
    # mixed-friction law: mu = phi(Lambda) mu_boundary + (1 - phi) mu_full_film (dynamics.losses.lubricant)
    # boundary friction of steel under additive films 0.08-0.15 (Spikes 2004, Lubr. Sci. 16); full-film
    # EHL traction of mineral oil at moderate slide-roll 0.02-0.06 (Johnson & Tevaarwerk 1977)
    boundary_friction: float = _r(0.0, 0.5, 0.115, "boundary friction of lubricated steel is 0.05-0.2")
    full_film_friction: float = _r(0.0, 0.2, 0.04, "EHL traction coefficients stay below ~0.1")
    # Palmgren no-load factor f0 (oil bath): needle roller 3-12, tapered roller 4-8, angular contact
    # ball pair 2-6.6 (Harris & Kotzalas 2007, Rolling Bearing Analysis, table 11.1)
    f0_needle: float = _r(0.0, 50.0, 7.5)
    f0_tapered: float = _r(0.0, 50.0, 6.0)
    f0_main: float = _r(0.0, 50.0, 4.3)
    # Palmgren load factor f1: needle 0.0005-0.001 (sliding guide of caged needles), tapered roller
    # 0.0004 (same table)
    f1_needle: float = _r(0.0, 0.05, 0.00075)
    f1_tapered: float = _r(0.0, 0.05, 0.0004)
    # ASSUMED sizes the case does not give: the output and input radial shaft seals (0 = none),
    # RV-160N-sized by default (the main bearings' size is the case's [main_bearings] section)
    output_seal_diameter_mm: float = _r(0.0, 2000.0, 260.0, open_lo=False)
    input_seal_diameter_mm: float = _r(0.0, 500.0, 30.0, open_lo=False)
    # the oil temperature of a run that states none (`simulate`'s records, a record without an
    # `# oil_temperature_C` comment): ASSUMED the real bench's 25 C operating map
    run_oil_temperature_C: float = _r(-60.0, 250.0, 25.0)
    # ISO 281 contamination factor: 0.5-0.6 "normal cleanliness" (ISO 281:2007 table 13)
    contamination_factor: float = _r(0.0, 1.0, 0.55)
