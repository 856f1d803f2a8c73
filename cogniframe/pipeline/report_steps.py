"""The report's steps: drop plots, figures, part and assembly renders, the 3D view, the BOM with
the assembly order, and the report itself. Each step's row sits beside its make and key functions."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from .graph import Made, Step


def plots_key(ctx):
    return ctx["budget"]["drop"]

def make_plots(ctx) -> Made:
    drop = ctx["budget"]["drop"]
    if drop is None:
        return Made()
    from ..report import drop_plots

    drop_plots.plot_drop_response(drop, ctx.out / "plots" / "drop_response.png")
    drop_plots.plot_energy_split(drop, ctx.out / "plots" / "energy_split.png")
    return Made(("plots/drop_response.png", "plots/energy_split.png"))

def _mass_and_drop(ctx) -> tuple[dict, dict | None]:
    """The mass budget and drop model as check.json shows them (from the `budget` step)."""
    b = ctx["budget"]
    return b["mass"].as_dict(), None if b["drop"] is None else b["drop"].to_dict()

def figures_key(ctx):
    return list(_mass_and_drop(ctx))

def make_figures(ctx) -> Made:
    from ..report import html

    mass, drop = _mass_and_drop(ctx)
    files = ctx.out / html.FILES_DIR
    html.plot_mass_groups(mass, files / "mass_by_group.png")
    made = [f"{html.FILES_DIR}/mass_by_group.png"]
    if drop is not None:
        html.plot_stiffness(drop, files / "stiffness.png")
        made.append(f"{html.FILES_DIR}/stiffness.png")
    return Made(tuple(made))

def render_part_key(ctx, part: str):
    p = ctx.part(part)
    return [p.name, p.material, ctx.part_value(part)["stl_sha256"]]

def make_render_part(ctx, part: str) -> Made:
    from ..report import renders

    p = ctx.part(part)
    renders.render_parts({p.name: (p.material, ctx.mesh(p.name))}, ctx.out / "renders" / "parts",
                         plotter=_part_plotter(ctx))
    return Made((f"renders/parts/{p.name}.png",))

def _part_plotter(ctx):
    """One off-screen plotter for every part render of this build (the render:{part} steps all run
    on the main thread), made by the first that runs and closed by the report: a plotter per part
    costs a render context and a first render each; the images are the same bytes
    (renders.render_parts)."""
    from ..report import renders

    if ctx.part_plotter is None:
        ctx.part_plotter = renders.part_plotter()
    return ctx.part_plotter

def _close_part_plotter(ctx) -> None:
    plotter, ctx.part_plotter = ctx.part_plotter, None
    if plotter is not None:
        plotter.close()

def renders_key(ctx):
    from ..report import renders

    return [[[p.name, p.material, p.placements, ctx.part_value(p.name)["stl_sha256"],
              ctx.part_value(p.name)["print_from_local"]] for p in ctx.design.parts],
            renders.rod_segments(ctx.design.frame), ctx.spec.name, ctx.vitamin_key()]

def make_renders(ctx) -> Made:
    from ..report import renders

    d = ctx.design
    meshes = {p.name: ctx.mesh(p.name) for p in d.parts}
    pfl = {p.name: ctx.part_value(p.name)["print_from_local"] for p in d.parts}
    views = renders.render_assembly(renders.world_meshes(d.parts, meshes, pfl), renders.rod_segments(d.frame),
                                    ctx.out / "renders", title=ctx.spec.name,
                                    vitamins=renders.vitamin_meshes(ctx.spec, d.frame, ctx.vitamins()))  # the bought parts
    return Made(tuple(p.relative_to(ctx.out).as_posix() for p in views.values()), list(views))

def step_views_key(ctx):
    """The guide's pictures read what the assembly renders read and the views themselves (each
    step's title, what it shows, what is new, the exploded offsets; not the steps' texts)."""
    import dataclasses

    from ..report import assembly_steps, step_views

    views = step_views.step_views(ctx.design, assembly_steps.assembly_steps(ctx.design))
    return [renders_key(ctx), [dataclasses.asdict(v) for v in views]]

def make_step_views(ctx) -> Made:
    """A picture per assembly step, and an exploded one where its parts go in along a line
    (report/step_views.py); the value maps each step's number to its pictures."""
    from ..report import assembly_steps, step_views

    d = ctx.design
    views = step_views.step_views(d, assembly_steps.assembly_steps(d))
    items = step_views.scene_items(d, {p.name: ctx.mesh(p.name) for p in d.parts},
                                   {p.name: ctx.part_value(p.name)["print_from_local"] for p in d.parts})
    known = None
    if ctx.use_cache:  # each picture by what it shows (step_views.picture_key): an edit draws only those it changes
        from .. import cache

        known = cache.BytesMemo("step_view", f"{cache.code_hash(*STEP_VIEWS.code)}/{ctx.stack}", ".png")
    step_views.render_step_views(views, items, ctx.out, known=known)
    return Made(tuple(f for v in views for f in v.files()), {str(v.number): list(v.files()) for v in views})

def _slice_report(ctx):
    from ..export import slicer

    found = [v for v in ctx.each("slice:*").values() if v]
    if not found:
        return None
    results = [slicer.PlateSlice(p["plate"], p["material"], ctx.out / "plates" / f"{p['plate']}.3mf",
                                 Path(os.devnull), p["grams"], p["time_s"], tuple((n, v) for n, v in p["objects"]), 0.0)
               for v in found for p in v["plates"]]
    return slicer.summarize(found[0]["slicer"], results, ctx["check"].mass.by_material)

def bom(ctx) -> Made:
    from ..report import assembly_steps, bom as bom_mod

    sliced = _slice_report(ctx)
    lines = bom_mod.build_bom(ctx.spec, ctx.design, ctx["check"].mass, sliced,
                              sizes={b.name: b.bbox_mm for b in ctx.built_parts()})
    bom_mod.write_bom(lines, ctx.out)
    steps = assembly_steps.assembly_steps(ctx.design)
    pictures = {int(n): files for n, files in ctx["step_views"].items()}
    (ctx.out / "assembly.md").write_text(assembly_steps.to_markdown(steps, pictures=pictures), encoding="utf-8")
    return Made(("bom.csv", "bom.md", "assembly.md"), (lines, steps, sliced))

def report(ctx) -> Made:
    from ..report import html

    _close_part_plotter(ctx)  # every render:{part} is done (the report needs them)
    lines, steps, sliced = ctx["bom"]
    files = ctx.out / html.FILES_DIR
    figures = {"mass": [("mass by group", files / "mass_by_group.png")]}
    if ctx["check"].drop is not None:
        for name in ("drop_response.png", "energy_split.png"):  # the same figures as plots/: copy, do not redraw
            shutil.copyfile(ctx.out / "plots" / name, files / name)
        figures["drop"] = [("stiffness", files / "stiffness.png"), ("drop response", files / "drop_response.png"),
                           ("energy split", files / "energy_split.png")]
    plates = _plate_files(ctx)
    images = {f"assembly {v}": ctx.out / "renders" / f"assembly_{v}.png" for v in ctx["renders"]}
    images |= {f"part {p}": ctx.out / "renders" / "parts" / f"{p}.png" for p in sorted(x.name for x in ctx.design.parts)}
    from ..flight import FILES as FLIGHT_FILES

    flown = "skipped" not in ctx["flight"]  # no flight files without a thrust table for the motor
    if flown:
        figures["flight"] = [("Campbell diagram: frame modes against the rotors and the attitude controller",
                              ctx.out / "flight" / "resonance.png")]
    html.write_report(ctx["check"], ctx.out, images, lines, steps, plates, sliced, figures=figures,
                      viewer_html=ctx["viewer"], flight_files=tuple(f"flight/{f}" for f in FLIGHT_FILES) if flown else (),
                      step_pictures={int(n): [ctx.out / f for f in files] for n, files in ctx["step_views"].items()})
    return Made(("report.html", "report.md"))

def _plate_files(ctx):
    from ..export.plates import PlateFile

    plates = [PlateFile(v["name"], v["material"], ctx.out / v["threemf"], ctx.out / v["preview"], tuple(v["copies"]),
                        v["volume_mm3"]) for vs in ctx.each("plates:*").values() for v in vs]
    return sorted(plates, key=lambda p: (p.material, p.name))

def viewer_key(ctx):
    """What the 3D view shows: each part's mesh (STL hash), copies, placement and grams each, the plates'
    copies, the rods and the cut list."""
    d = ctx.design
    grams = {i.name: i.mass_g_each for i in ctx["check"].mass.items}
    return [[[p.name, p.material, p.qty, p.placements, ctx.part_value(p.name)["stl_sha256"],
              ctx.part_value(p.name)["print_from_local"], grams.get(p.name)] for p in d.parts],
            [[p.name, p.copies] for p in _plate_files(ctx)], list(d.frame.rods.values()), d.cut.rows,
            ctx.vitamin_key()]  # the vitamins' solids (their grams are not shown in the view)

def make_viewer(ctx) -> Made:
    """The report's interactive 3D view as one HTML section, kept as this step's value."""
    from ..report.viewer import design_items, read_stl, viewer_section

    d = ctx.design
    # numpy's STL reader, not trimesh: the 3D view never needs the mesh library
    items = design_items(d, {p.name: read_stl(ctx.out / ctx.part_value(p.name)["stl"]) for p in d.parts},
                         {p.name: ctx.part_value(p.name)["print_from_local"] for p in d.parts}, ctx["check"].mass,
                         _plate_files(ctx))
    from ..report.renders import vitamin_viewer_items

    items += vitamin_viewer_items(ctx.spec, d.frame, vits=ctx.vitamins())  # the bought parts (geometry in viewer_key)
    return Made((), viewer_section(items))


PLOTS = Step("plots", ("budget",), make_plots, plots_key, ("report/drop_plots.py", "analysis/impact.py"),
             reads="the drop model's numbers")
FIGURES = Step("figures", ("budget",), make_figures, figures_key, ("report/html.py", "report/drop_plots.py"),
               reads="the mass budget's and drop model's numbers")
RENDER_PART = Step("render:{part}", ("part:*/{part}",), make_render_part, render_part_key,
                   ("report/renders.py", "export/plates.py"),
                   after=("plates:*",),  # a render never holds up the slicer
                   reads="the part's STL hash, material")
RENDERS = Step("renders", ("part:*",), make_renders, renders_key,
               ("report/renders.py", "export/plates.py", "report/assembly_steps.py", "vitamins.py", "fasteners.py"),
               reads="STL hashes, placements, rods, vitamins")
VIEWER = Step("viewer", ("check", "plates:*"), make_viewer, viewer_key,
              ("report/viewer/*", "export/plates.py", "report/assembly_steps.py", "report/renders.py", "vitamins.py", "fasteners.py"),
              reads="STL hashes, placements, grams each, plates, rods, cut list")
STEP_VIEWS = Step("step_views", ("part:*",), make_step_views, step_views_key,
                  ("report/step_views.py", "report/renders.py", "report/assembly_steps.py", "export/plates.py",
                   "export/assembly.py", "vitamins.py", "fasteners.py"),
                  after=("plates:*",),  # like the renders: the slicer's plates first
                  reads="STL hashes, placements, rods, vitamins, the assembly steps")
BOM = Step("bom", ("check", "slice:*", "step_views"), bom, reads="(always: BOM, assembly steps)")
REPORT = Step("report", ("check", "bom", "plots", "figures", "previews:*", "render:*", "renders", "step_views", "viewer", "flight"),
              report,
              reads="(always: HTML and Markdown from the files above)")
