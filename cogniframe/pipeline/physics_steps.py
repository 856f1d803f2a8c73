"""The physics steps: the mass-independent stiffness while the parts are built, the mass budget
with the CAD volumes, the load cases for that mass, and the check that joins them to the clash
check. Each step's row sits beside its make function; pipeline/steps.py lists them in order."""

from __future__ import annotations

from ..runtime.pools import JOB_ORDER
from .graph import Made, Step


def estimate(ctx) -> Made:
    """Solve what the physics needs and the mass does not change (the frame stiffness k and the
    joint models, each cached on disk by its own inputs) while the CAD pool builds the parts; the
    mass-dependent load cases wait for the CAD volumes (`physics`)."""
    spec = ctx.spec
    if spec.model.stiffness_model != "analytic":
        # new joint FEs first, in parallel; the frame model below then reads every joint from the
        # cache. On the CAD server's workers after the parts (JOB_ORDER); a build's own process
        # pool runs its jobs in order, so there the FEs get workers of their own
        from ..analysis.joints import needs_fe, solve_fe

        parts = ctx.design.parts
        if ctx.cad.server:
            solve_fe(spec, parts, submit=lambda fn, *a: ctx.cad.submit(fn, *a, priority=JOB_ORDER["joint FE"]))
        elif needs_fe(spec, parts):
            from ..runtime.pools import joint_fe_workers

            with joint_fe_workers() as submit:
                solve_fe(spec, parts, submit=submit)
    if spec.model.k_n_per_m is None:
        from ..analysis.drop import predicted_k_n_per_m

        predicted_k_n_per_m(spec, ctx.design.frame)
    else:
        from ..analysis.stiffness import joint_models

        joint_models(spec, ctx.design.parts, spec.model.stiffness_model)
    return Made()


def _geometry(ctx) -> dict:
    from ..analysis.mass import PartGeometry

    return {b.name: PartGeometry(b.volume_mm3, b.area_h_mm2, b.area_v_mm2, "cad") for b in ctx.built_parts()}


def budget(ctx) -> Made:
    """The mass budget with the CAD volumes and the drop model: milliseconds once k is known; what
    the mass and drop figures draw, so they need not wait for the load cases."""
    from ..analysis import verdict

    design, mass, drop, session = verdict.mass_and_drop(ctx.spec, _geometry(ctx), ctx.design)
    return Made((), {"mass": mass, "drop": drop, "session": session})


def physics(ctx) -> Made:
    """The check's load cases, peak prediction and flight for the CAD mass: `check` takes this
    result as it is. A thread of its own: LAPACK holds no GIL, so the main thread's plates,
    figures and renders go on meanwhile."""
    from ..analysis import verdict

    b = ctx["budget"]
    return Made((), verdict.complete(ctx.spec, ctx.design, b["mass"], b["drop"], b["session"]))


def check(ctx) -> Made:
    import json

    from .. import cutlist
    from ..analysis import verdict
    from ..analysis import clash

    result = verdict.with_clash(ctx["physics"], clash.from_dict(ctx["clash"]))
    out = ctx.out
    files = {"check.json": json.dumps(verdict.check_dict(result), indent=2) + "\n",
             "cutlist.csv": cutlist.to_csv(ctx.design.cut), "cutlist.md": cutlist.to_markdown(ctx.design.cut),
             "mass.md": mass_markdown(result)}
    for rel, text in files.items():
        (out / rel).write_text(text, encoding="utf-8")
    return Made(tuple(files), result)


def mass_markdown(check) -> str:
    m = check.mass
    lines = [f"# Mass budget: {check.design.spec.name}", "", "| item | group | qty | g each | g | source |",
             "|---|---|---:|---:|---:|---|"]
    for i in m.items:
        lines.append(f"| {i.name} | {i.group} | {i.qty} | {i.mass_g_each:.2f} | {i.mass_g:.1f} | {i.source} |")
    lines += ["", "| group | g |", "|---|---:|"] + [f"| {g} | {v:.1f} |" for g, v in m.groups.items()]
    lines += [f"| **all-up weight** | **{m.total_g:.1f}** |", f"| limit | {m.limit_g:g} |", f"| margin | {m.margin_g:+.1f} |"]
    return "\n".join(lines) + "\n"


ESTIMATE = Step("estimate", (), estimate, where="wait",
                reads="(always, thread: k and the joint models, mass-independent, cached on disk)")
BUDGET = Step("budget", ("estimate", "part:*"), budget, where="wait",
              reads="(always, thread: mass with CAD volumes, drop model; milliseconds)")
PHYSICS = Step("physics", ("budget",), physics, where="wait",
               # its Python holds the GIL for a few tenths of a second: after the plates, whose
               # slicer heads the chain a one-part rebuild waits for, not beside them
               after=("plates:*",),
               reads="(always, thread: load cases, peaks and flight for that mass, cached on disk)")
CHECK = Step("check", ("budget", "physics", "clash"), check,
             reads="(always: the physics step's result with the clash check; check.json, cut list, mass.md)")
