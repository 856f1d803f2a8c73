"""The build, as a Makefile: every step in the order the main thread takes them.

Each step is declared once, in the module of what it makes (cad_steps, physics_steps,
plate_steps, report_steps, flight_steps), beside its make and key functions. `table()` prints this list as docs/build.md shows it (a test keeps the
two the same).

A step with a key runs only when its key changes; otherwise its files come from the cache
(graph.py). Waiting steps (`where="wait"`) run in threads and start the moment their needs are
done: part CAD, the clash check and the assembly wait for the CAD workers, the slicer for
PrusaSlicer, and `estimate`, `budget` and `physics` for LAPACK, which releases the GIL. The other
steps run on the main thread in this order (plates, previews, plots, figures, renders, the 3D view
and the report). Heavy imports (cadquery, trimesh, pyvista, matplotlib) happen only inside steps
that run.
"""

from __future__ import annotations

from . import cad_steps, flight_steps, physics_steps, plate_steps, report_steps


STEPS = (
    physics_steps.ESTIMATE,
    cad_steps.PART,
    plate_steps.PLATES,
    physics_steps.BUDGET,
    physics_steps.PHYSICS,
    cad_steps.CLASH,
    plate_steps.SLICE,
    cad_steps.ASSEMBLY,
    cad_steps.GLB,
    physics_steps.CHECK,
    flight_steps.FLIGHT,
    report_steps.PLOTS,
    report_steps.FIGURES,
    plate_steps.PREVIEWS,
    report_steps.RENDER_PART,
    report_steps.RENDERS,
    report_steps.STEP_VIEWS,
    report_steps.VIEWER,
    report_steps.BOM,
    report_steps.REPORT,
)


def rows(design) -> list[dict]:
    """What the {vars} of STEPS range over: one row per printed part."""
    return [{"material": p.material, "part": p.name} for p in design.parts]


def table(steps=STEPS) -> str:
    """The steps as a Makefile reads: target, needs, and what its cache key reads."""
    lines = [f"    {'target':<25} {'needs':<30} reads (its cache key)"]
    for s in steps:
        needs = " ".join(s.needs) if s.needs else "-"
        lines.append(f"    {s.name:<25} {needs:<30} {s.reads}".rstrip())
    return "\n".join(lines) + "\n"
