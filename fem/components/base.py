"""What a stiffness-path component is: one module, one entry in `fem.components.REGISTRY`.

A component module has
  NAME       its name in stiffness.json `sources`/`checks`, the compliance budget and `stiffened`;
  COUPLING   the lumped-model coupling it sits in (dynamics.couplings: mesh, support, needle, pin,
             housing); the budget splits that coupling's energy over the components that name it;
  COST       rough seconds of `compute` (the FE stage's pool takes the longest first);
  compute(case, ctx) -> Result
             its FE or closed form on the case's stated geometry (a pure task: picklable in and out,
             so `--workers`/Dask run the components in parallel); ctx: `fem.reduce.task_context`;
  parts(case, ctx) -> [(cost, part)], compute_part(case, ctx, part), combine(case, ctx, [(part, out)]) -> Result
             (optional) a compute made of independent pieces (the carrier's two meshes): the stage
             runs each part as its own task and `combine` makes the Result; `compute` stays the
             whole in one process;
  refine(case, results) -> Result | None   (optional)
             a step that needs other components' results (run in the stage's process afterwards);
  stiffen(model, factor) -> StiffnessModel
             a copy with this component's compliance divided by `factor` (what-ifs, the diagnosis'
             located compliance);
and, by coupling, how its compliance enters the coupling (read by fem.stiffness and dynamics.budget):
  support    support_part(model, T, n_crank) -> (2 nc nd, 2 nc nd) compliance on the crank-axis
             displacement per disc plane (T: fem.stiffness.seat_transfer);
  pin        series_approach_m(model, F) -> the approach it adds in series with each tooth-pin
             contact at normal force F (vectorised);
  mesh       line_compliance_m_per_N(p, h) -> its compliance along the involute line of action
             (p: the mesh coupling's Params, h: the number of pairs in contact beyond one).
A component that is a whole coupling (needle, housing) needs no hook.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Result:
    """One component's contribution to stiffness.json: keyword fields of fem.stiffness.StiffnessModel
    (`parts` entries for the components that have no legacy field), sources, checks, extras, and
    in-memory artifacts for the stage's pictures (meshes, fields; never written to the JSON)."""
    name: str
    fields: dict
    sources: dict
    checks: dict
    extras: dict = field(default_factory=dict)
    artifacts: dict = field(default_factory=dict)
    seconds: float = 0.0


def timed(func):
    """Wrap compute(case, ctx) so its Result carries its own wall time."""
    def run(case, ctx):
        t0 = time.perf_counter()
        r = func(case, ctx)
        return Result(r.name, r.fields, r.sources, r.checks, r.extras, r.artifacts, time.perf_counter() - t0)
    run.__doc__, run.__name__, run.__wrapped__ = func.__doc__, func.__name__, func
    return run
