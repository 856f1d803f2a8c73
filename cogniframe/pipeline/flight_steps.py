"""The flight step: the flight-controller setup and simulator models (cogniframe/flight/) from
the CAD solids: each printed part's STL (read with numpy: no mesh library), placed as the
assembly places it, carries its budget mass; rods, vitamins and propellers as `fly` has them.
Its row sits beside its make and key functions; pipeline/steps.py lists it."""

from __future__ import annotations

from .graph import Made, Step


def flight_key(ctx):
    """What the flight files read: each part's mesh, copies and placements, the rods, the bought
    parts, the budget's lines, the modes, the flight numbers and the motors' params."""
    check = ctx["check"]
    d = ctx.design
    return [ctx.spec.name, ctx.spec.motors.model_dump(mode="json"), ctx.spec.core.battery.model_dump(mode="json"),
            [[p.name, p.placements, ctx.part_value(p.name)["stl_sha256"], ctx.part_value(p.name)["print_from_local"]]
             for p in d.parts],
            list(d.frame.rods.values()), d.frame.motors, d.frame.core, ctx.vitamin_key(),
            check.mass.as_dict(), (check.stiffness or {}).get("modes_hz"),
            None if check.flight is None else check.flight.summary()]


def make_flight(ctx) -> Made:
    from .. import flight
    from ..errors import UserError
    from ..analysis.massprops import read_stl_triangles, solid_props

    d = ctx.design
    solids = {p.name: (solid_props(read_stl_triangles(ctx.out / ctx.part_value(p.name)["stl"])),
                       ctx.part_value(p.name)["print_from_local"]) for p in d.parts}
    try:
        v = flight.make_vehicle(ctx.spec, ctx["check"], solids)
    except UserError as e:  # no thrust table for this motor: the build goes on without flight files
        return Made((), {"skipped": str(e)})
    files = flight.write(v, ctx.out / "flight")
    return Made(tuple(f"flight/{f}" for f in files), {"mass": v.mass.to_dict(), "flags": [f.why for f in v.resonance.flags]})


FLIGHT = Step("flight", ("check", "part:*"), make_flight, flight_key,
              ("flight/*", "vitamins.py", "errors.py", "analysis/flight.py", "analysis/stiffness.py", "analysis/load_cases.py",
               "analysis/massprops.py", "analysis/rotors.py", "analysis/resonance.py"),
              reads="STL hashes, copies and placements, rods, vitamins, mass budget, modes, flight numbers, motors")
