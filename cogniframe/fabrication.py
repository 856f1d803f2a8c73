"""Fabrication steps of `build` (issue 6): print plates, slicer check, previews, renders, BOM,
assembly steps and the report, from the built part files and the check result.

Each function here is one step of the build graph (the list is in steps.py): `make_*(ctx, ...)`
writes files under ctx.out and returns graph.Made; `*_key(ctx, ...)` returns exactly what that
step reads, so it reruns only when that changes. Add a fabrication output as a new step here
and one line in steps.STEPS.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

from .cache import file_sha256
from .graph import Made


def plates_key(ctx, material: str):
    return [[[p.name, p.qty, ctx.part_value(p.name)["stl_sha256"]] for p in ctx.parts_of(material)],
            ctx.bed, float(ctx.spec.printer.margin), _config(ctx, material)]


def _config(ctx, material: str) -> str:
    """PrusaSlicer settings embedded in this material's plates (issue 14): the .ini's values."""
    from .export import slicer

    return slicer.project_config(ctx.spec, material, _infill(ctx, material))


def make_plates(ctx, material: str) -> Made:
    from .export import plates as pl

    items = [pl.PlateItem(p.name, p.material, p.qty, ctx.mesh(p.name)) for p in ctx.parts_of(material)]
    folder = ctx.out / "plates"
    folder.mkdir(parents=True, exist_ok=True)
    value = []
    for plate in pl.pack_plates(items, ctx.spec.printer.bed, ctx.spec.printer.margin):
        f3 = folder / f"{plate.name}.3mf"
        data, read = pl.plate_3mf(plate, _config(ctx, material))
        f3.write_bytes(data)
        model = pl.model_sha256(data)
        ctx.keep_plate_items(model, read)  # what reading the file back gives: its readers need not read it
        value.append({"name": plate.name, "material": plate.material, "threemf": f"plates/{f3.name}",
                      "preview": f"plates/{plate.name}.png", "copies": [c.name for c in plate.copies],
                      "volume_mm3": plate.volume_mm3, "sha256": file_sha256(f3), "model_sha256": model})
    return Made(tuple(v["threemf"] for v in value), value)


def previews_key(ctx, material: str):
    # the layout only (3D/3dmodel.model): a print setting inside the 3MF does not change the picture
    return [[v["name"], v["model_sha256"]] for v in ctx[f"plates:{material}"]] + [ctx.bed, float(ctx.spec.printer.margin)]


def make_previews(ctx, material: str) -> Made:
    from .export import plates as pl

    files = []
    for v in ctx[f"plates:{material}"]:
        plate = pl.read_plate(ctx.out / v["threemf"], ctx.spec.printer.bed, ctx.spec.printer.margin,
                              items=ctx.plate_items(v))
        pl.plot_plate(plate, ctx.out / v["preview"])
        files.append(v["preview"])
    return Made(tuple(files))


def _infill(ctx, material: str) -> float:
    infill = {}
    for p in ctx.design.parts:
        infill[p.material] = max(infill.get(p.material, 0.0), p.infill)
    return infill.get(material, ctx.spec.core.infill)


def _profile(ctx, material: str) -> str:
    from .export import slicer

    return slicer.profile_ini(ctx.spec, material, _infill(ctx, material))


def _keep_gcode(ctx) -> bool:
    """`build --gcode` (issue 14): keep each plate's G-code beside it (not byte-stable; the manifest says so)."""
    return bool(getattr(ctx, "gcode", False))


def slice_key(ctx, material: str):
    found = ctx.slicer.get()
    if not found:
        return None  # no PrusaSlicer: nothing to slice or store
    return [found[1], [v["sha256"] for v in ctx[f"plates:{material}"]], _profile(ctx, material), ctx.bed] + (
        ["gcode"] if _keep_gcode(ctx) else [])


def make_slice(ctx, material: str) -> Made:
    """Slice this material's plates (G-code in a temp folder: it is not byte-stable; keep the numbers,
    and with `build --gcode` the G-code too, as plates/<plate>.gcode)."""
    from .export import slicer

    found = ctx.slicer.get()
    if not found:
        return Made()
    exe, version = found
    ini = ctx.out / "plates" / f"{material}.ini"
    ini.write_text(_profile(ctx, material), encoding="utf-8")
    plates = []
    kept = []
    with tempfile.TemporaryDirectory(prefix="cogniframe-gcode-") as tmp:
        for v in ctx[f"plates:{material}"]:
            where = ctx.out / "plates" if _keep_gcode(ctx) else Path(tmp)
            items = ctx.plate_items(v)
            if ctx.use_cache and not _keep_gcode(ctx):  # per plate: a plate whose bytes did not change is not sliced again
                r = slicer._slice_cached(ctx.out / v["threemf"], ini, ctx.spec.printer.bed, exe, version,
                                         where / f"{v['name']}.gcode", items=items)
            else:
                r = slicer.slice_plate(ctx.out / v["threemf"], ini, ctx.spec.printer.bed, exe,
                                       gcode=where / f"{v['name']}.gcode", items=items)
            plates.append({"plate": r.plate, "material": r.material, "grams": r.grams, "time_s": r.time_s,
                           "objects": [list(o) for o in r.objects]})
            if _keep_gcode(ctx):
                kept.append(f"plates/{v['name']}.gcode")
    return Made((f"plates/{material}.ini", *kept), {"slicer": version, "plates": plates})


def _mass_and_drop(ctx) -> tuple[dict, dict | None]:
    """The mass budget and drop model as check.json shows them (from the `budget` step)."""
    b = ctx["budget"]
    return b["mass"].as_dict(), None if b["drop"] is None else b["drop"].to_dict()


def figures_key(ctx):
    return list(_mass_and_drop(ctx))


def make_figures(ctx) -> Made:
    from .report import html

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
    from .report import renders

    p = ctx.part(part)
    renders.render_parts({p.name: (p.material, ctx.mesh(p.name))}, ctx.out / "renders" / "parts",
                         plotter=_part_plotter(ctx))
    return Made((f"renders/parts/{p.name}.png",))


def _part_plotter(ctx):
    """One off-screen plotter for every part render of this build (the render:{part} steps all run
    on the main thread), made by the first that runs and closed by the report: a plotter per part
    costs a render context and a first render each; the images are the same bytes
    (renders.render_parts)."""
    from .report import renders

    plotter = ctx.__dict__.get("_part_plotter")
    if plotter is None:
        plotter = ctx.__dict__["_part_plotter"] = renders.part_plotter()
    return plotter


def _close_part_plotter(ctx) -> None:
    plotter = ctx.__dict__.pop("_part_plotter", None)
    if plotter is not None:
        plotter.close()


def renders_key(ctx):
    from .report import renders

    from .export.assembly import _vitamin_key

    return [[[p.name, p.material, p.placements, ctx.part_value(p.name)["stl_sha256"],
              ctx.part_value(p.name)["print_from_local"]] for p in ctx.design.parts],
            renders.rod_segments(ctx.design.frame), ctx.spec.name, _vitamin_key(ctx.spec, ctx.design.frame)]


def make_renders(ctx) -> Made:
    from .report import renders

    d = ctx.design
    meshes = {p.name: ctx.mesh(p.name) for p in d.parts}
    pfl = {p.name: ctx.part_value(p.name)["print_from_local"] for p in d.parts}
    views = renders.render_assembly(renders.world_meshes(d.parts, meshes, pfl), renders.rod_segments(d.frame),
                                    ctx.out / "renders", title=ctx.spec.name,
                                    vitamins=renders.vitamin_meshes(ctx.spec, d.frame))  # issue 13: the bought parts
    return Made(tuple(p.relative_to(ctx.out).as_posix() for p in views.values()), list(views))


def _slice_report(ctx):
    from .export import slicer

    found = [v for v in ctx.each("slice:*").values() if v]
    if not found:
        return None
    results = [slicer.PlateSlice(p["plate"], p["material"], ctx.out / "plates" / f"{p['plate']}.3mf",
                                 Path(os.devnull), p["grams"], p["time_s"], tuple((n, v) for n, v in p["objects"]), 0.0)
               for v in found for p in v["plates"]]
    return slicer.summarize(found[0]["slicer"], results, ctx["check"].mass.by_material)


def bom(ctx) -> Made:
    from .report import assembly_steps, bom as bom_mod

    sliced = _slice_report(ctx)
    lines = bom_mod.build_bom(ctx.spec, ctx.design, ctx["check"].mass, sliced,
                              sizes={b.name: b.bbox_mm for b in ctx.built_parts()})
    bom_mod.write_bom(lines, ctx.out)
    steps = assembly_steps.assembly_steps(ctx.design)
    (ctx.out / "assembly.md").write_text(assembly_steps.to_markdown(steps), encoding="utf-8")
    return Made(("bom.csv", "bom.md", "assembly.md"), (lines, steps, sliced))


def report(ctx) -> Made:
    from .report import html

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
    html.write_report(ctx["check"], ctx.out, images, lines, steps, plates, sliced, figures=figures,
                      viewer_html=ctx["viewer"])
    return Made(("report.html", "report.md"))


def _plate_files(ctx):
    from .export.plates import PlateFile

    plates = [PlateFile(v["name"], v["material"], ctx.out / v["threemf"], ctx.out / v["preview"], tuple(v["copies"]),
                        v["volume_mm3"]) for vs in ctx.each("plates:*").values() for v in vs]
    return sorted(plates, key=lambda p: (p.material, p.name))


def viewer_key(ctx):
    """What the 3D view shows: each part's mesh (STL hash), copies, placement and grams each, the plates'
    copies, the rods and the cut list."""
    from .export.assembly import _vitamin_key

    d = ctx.design
    grams = {i.name: i.mass_g_each for i in ctx["check"].mass.items}
    return [[[p.name, p.material, p.qty, p.placements, ctx.part_value(p.name)["stl_sha256"],
              ctx.part_value(p.name)["print_from_local"], grams.get(p.name)] for p in d.parts],
            [[p.name, p.copies] for p in _plate_files(ctx)], list(d.frame.rods.values()), d.cut.rows,
            _vitamin_key(ctx.spec, d.frame)]  # issue 13: the vitamins' solids (their grams are not shown in the view)


def make_viewer(ctx) -> Made:
    """The report's interactive 3D view (issue 14) as one HTML section, kept as this step's value."""
    from .report.viewer import design_items, read_stl, viewer_section

    d = ctx.design
    # numpy's STL reader, not trimesh: the 3D view never needs the mesh library
    items = design_items(d, {p.name: read_stl(ctx.out / ctx.part_value(p.name)["stl"]) for p in d.parts},
                         {p.name: ctx.part_value(p.name)["print_from_local"] for p in d.parts}, ctx["check"].mass,
                         _plate_files(ctx))
    from .report.renders import vitamin_viewer_items

    items += vitamin_viewer_items(ctx.spec, d.frame)  # issue 13: the bought parts (geometry in viewer_key)
    return Made((), viewer_section(items))
