"""The flight step: the flight-controller setup and simulator models (cogniframe/flight/) from
the CAD solids: each printed part's STL, placed as the assembly places it, carries its budget
mass; rods, vitamins and propellers as `fly` has them. Its row sits beside its make and key
functions; build/steps.py lists it."""

from __future__ import annotations

from .graph import Made, Step


def flight_key(ctx):
    """What the flight files read: the params, each part's mesh, copies and placements, the
    budget's lines, the modes and the flight numbers."""
    check = ctx["check"]
    d = ctx.design
    return [ctx.spec.model_dump(mode="json"),
            [[p.name, p.placements, ctx.part_value(p.name)["stl_sha256"], ctx.part_value(p.name)["print_from_local"]]
             for p in d.parts],
            check.mass.as_dict(), (check.stiffness or {}).get("modes_hz"),
            None if check.flight is None else check.flight.summary()]


def make_flight(ctx) -> Made:
    from .. import flight
    from ..report.renders import world_meshes

    d = ctx.design
    meshes = {p.name: ctx.mesh(p.name) for p in d.parts}
    pfl = {p.name: ctx.part_value(p.name)["print_from_local"] for p in d.parts}
    world: dict[str, list] = {}
    for p in d.parts:  # world_meshes keeps the part order and one mesh per placement
        world[p.name] = []
    for p, sm in zip([p for p in d.parts for _ in p.placements], world_meshes(d.parts, meshes, pfl)):
        world[p.name].append(sm.mesh)
    from ..errors import UserError

    try:
        v = flight.make_vehicle(ctx.spec, ctx["check"], world)
    except UserError as e:  # no thrust table for this motor: the build goes on without flight files
        return Made((), {"skipped": str(e)})
    files = flight.write(v, ctx.out / "flight")
    return Made(tuple(f"flight/{f}" for f in files), {"mass": v.mass.to_dict(), "flags": [f.why for f in v.resonance.flags]})


FLIGHT = Step("flight", ("check", "part:*"), make_flight, flight_key,
              ("flight/*", "vitamins.py", "analysis/flight.py", "analysis/stiffness.py", "analysis/load_cases.py",
               "report/renders.py"),
              reads="params, STL hashes, copies and placements, mass budget, modes, flight numbers")
