"""The DOF layout: named blocks of generalized coordinates instead of index arithmetic.

A block is `count` identical items (cranks, discs) of `components` DOFs each, stored item after
item. Couplings turn the layout into their own index tables when they are built
(`dynamics.couplings`), the kinematics address DOFs by block and component name, and the solvers
only see vectors of length n: a later model adds a block (e.g. the crank axis displacement per
disc plane) here and in the couplings that attach to it, not in the solvers.

Standard layout (n = 1 + nc + 2 nc nd + 3 nd):
  carrier         1 x (rot)         output rotation [rad]; the load torque acts here
  crank_rotation  nc x (rot)        crank angle = eccentric angle of disc 1 in the ground frame [rad]
  crank_axis      nc nd x (x, y)    crank j's axis displacement at disc plane d (item j nd + d) from
                                    its unloaded position, CARRIER frame [m]: the support path
                                    (bearings, crank bending, carrier racking) is a stiffness matrix
                                    of the carrier, so it is written where that matrix is constant
  disc            nd x (x, y, rot)  disc centre [m] and rotation [rad]
  housing         nh x (a)          the housing's modal coordinates [m] (dynamics.couplings.housing;
                                    none without a housing entry in the stiffness)
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Block:
    name: str
    start: int
    count: int                 # items
    components: tuple          # DOF names of one item
    rotational: tuple          # per component: True for an angle [rad], False for a length [m]
    item_label: str = ""       # label prefix of item i: f"{item_label}{i + 1}"; "" for one body
    names: tuple = ()          # per item, overrides the item label (e.g. "crank1_plane2")

    @property
    def width(self) -> int:
        return len(self.components)

    @property
    def size(self) -> int:
        return self.count * self.width

    @property
    def slice(self) -> slice:
        return slice(self.start, self.start + self.size)

    def index(self, item: int = 0, component: int | str = 0) -> int:
        """Global DOF index of `component` (position or name) of `item`."""
        c = self.components.index(component) if isinstance(component, str) else component
        if not (0 <= item < self.count and 0 <= c < self.width):
            raise IndexError(f"block {self.name}: item {item}, component {component!r} out of range")
        return self.start + item * self.width + c

    def indices(self, component: int | str = 0) -> np.ndarray:
        """Global indices of `component` of every item."""
        return np.array([self.index(i, component) for i in range(self.count)], dtype=np.int64)

    def labels(self) -> tuple:
        if self.names:
            return tuple(f"{self.names[i]}_{c}" for i in range(self.count) for c in self.components)
        if not self.item_label:           # a single body: the block name (with the component if several)
            return (self.name,) if self.size == 1 else tuple(f"{self.name}_{c}" for c in self.components)
        return tuple(f"{self.item_label}{i + 1}_{c}" for i in range(self.count) for c in self.components)


@dataclass(frozen=True)
class DofLayout:
    blocks: tuple

    @classmethod
    def build(cls, spec) -> DofLayout:
        """From (name, count, components, rotational, item_label[, names]) tuples, in storage order."""
        blocks, start = [], 0
        for name, count, comps, rot, label, *names in spec:
            blocks.append(Block(name, start, count, tuple(comps), tuple(rot), label,
                                tuple(names[0]) if names else ()))
            start += blocks[-1].size
        return cls(tuple(blocks))

    @classmethod
    def standard(cls, n_crank: int, n_disc: int, n_housing: int = 0) -> DofLayout:
        return cls.build([("carrier", 1, ("rot",), (True,), ""),
                          ("crank_rotation", n_crank, ("rot",), (True,), "crank"),
                          ("crank_axis", n_crank * n_disc, ("x", "y"), (False, False), "crank",
                           [f"crank{j + 1}_plane{d + 1}" for j in range(n_crank) for d in range(n_disc)]),
                          ("disc", n_disc, ("x", "y", "rot"), (False, False, True), "disc"),
                          ("housing", n_housing, ("a",), (False,), "housing_mode")])

    def __getitem__(self, name: str) -> Block:
        for b in self.blocks:
            if b.name == name:
                return b
        raise KeyError(f"no DOF block {name!r}; blocks: {', '.join(b.name for b in self.blocks)}")

    @property
    def n(self) -> int:
        return sum(b.size for b in self.blocks)

    @property
    def labels(self) -> tuple:
        return sum((b.labels() for b in self.blocks), ())

    def vector(self, per_block: dict) -> np.ndarray:
        """n-vector from one value per component of each block's item (repeated over its items), or
        one value per DOF of the block (items that differ, e.g. the housing's modal masses)."""
        missing = {b.name for b in self.blocks if b.size} - set(per_block)
        if missing:
            raise KeyError(f"vector: no values for blocks {sorted(missing)}")
        out = []
        for b in self.blocks:
            v = np.asarray(per_block.get(b.name, ()), dtype=float).reshape(-1)
            out.append(v if len(v) == b.size and b.count > 1 else np.tile(v, b.count) if b.size else np.zeros(0))
        return np.concatenate(out)

    def scale(self, rotation_m: float) -> np.ndarray:
        """Solver scaling: rotation_m (a lever arm) for angles, 1 for lengths, so that scale * q
        is in metres everywhere."""
        return self.vector({b.name: [rotation_m if r else 1.0 for r in b.rotational] for b in self.blocks})
