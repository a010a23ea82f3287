"""Losses, lubrication and the operating map (DESIGN.md "Losses, lubrication and the operating map").

lubricant   viscosity-temperature law, EHL film of the line contact, film parameter, mixed friction
bearings    Palmgren friction moments, lip seals, ISO 281 ratings, L10 and the modified life
contacts    friction force, moment and power loss at every contact of a static state
operating   `operating_point(model, lubricant, input_speed_rpm, torque_Nm, oil_temperature_C)`:
            TE per direction over one output revolution, gap, efficiency, input torque;
            `simulate_condition(model, lubricant, input_angle_deg, torque_Nm, direction, input_speed_rpm,
            oil_temperature_C)`: the TE with friction at given input angles (a record's condition)
life        ISO 281 lives of the needle and crank support bearings at rated torque and speed
"""
from dynamics.losses.lubricant import Lubricant  # noqa: F401
from dynamics.losses.operating import OperatingPoint, operating_point, simulate_condition  # noqa: F401
