"""The stiffness-path components: every compliance between input and output, one module each
(interface: fem.components.base), in path order. The FE stage (fem.reduce) runs each one's
`compute`, stiffness.json carries each one's sources and checks, `StiffnessModel.stiffened`, the
lumped model's series compositions (fem.stiffness) and the compliance budget (dynamics.budget)
iterate this list; nothing elsewhere branches on a component's name. A new component is one
module plus one line here."""
from __future__ import annotations

from fem.components import (carrier, crank_bending, crank_torsion, disc_body, housing, involute_mesh, joints,
                            main_bearings, needle_bearings, pin_contact, pin_groove, support_bearings)

REGISTRY = (involute_mesh, crank_torsion, support_bearings, crank_bending, carrier, joints, main_bearings,
            needle_bearings, pin_contact, disc_body, pin_groove, housing)
COMPONENTS = tuple(m.NAME for m in REGISTRY)


def by_name(name: str):
    for m in REGISTRY:
        if m.NAME == name:
            return m
    raise ValueError(f"component {name!r}: allowed {', '.join(COMPONENTS)}")


def in_coupling(coupling: str) -> tuple:
    """The components a lumped-model coupling carries, path order."""
    return tuple(m for m in REGISTRY if m.COUPLING == coupling or coupling in getattr(m, "ALSO", ()))
