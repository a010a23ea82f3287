"""Losses, lubrication and the operating map (DESIGN.md "Losses, lubrication and the operating map").

lubricant   viscosity-temperature law, EHL film of the line contact, film parameter, mixed friction
bearings    Palmgren friction moments, lip seals, ISO 281 ratings, L10 and the modified life
contacts    friction force, moment and power loss at every contact of a static state
operating   `operating_point(model, lubricant, input_speed_rpm, torque_Nm, oil_temperature_C)`:
            TE per direction, gap, efficiency, input torque (the diagnosis simulates records with it)
"""
from dynamics.losses.lubricant import Lubricant  # noqa: F401
from dynamics.losses.operating import OperatingPoint, operating_point  # noqa: F401
