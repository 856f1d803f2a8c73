"""Fabrication package step of `build` (issue 6): print plates, slicer check, BOM, assembly
steps, renders and the report, from the built part meshes and the check result."""

from __future__ import annotations

from pathlib import Path

from rich.console import Console


def write_fabrication(spec, check, built, out: Path, console: Console) -> None:
    import trimesh

    from .export import plates as plates_mod
    from .export import slicer
    from .report import assembly_steps, bom, renders
    from .report.html import write_report

    d = check.design
    meshes = {b.name: trimesh.load(out / b.stl, force="mesh") for b in built}
    items = [plates_mod.PlateItem(b.name, b.material, b.qty, meshes[b.name]) for b in built]
    plates = plates_mod.write_plates(plates_mod.pack_plates(items, spec.printer.bed, spec.printer.margin), out / "plates")
    infill: dict[str, float] = {}
    for p in d.parts:
        infill[p.material] = max(infill.get(p.material, 0.0), p.infill)
    console.print(f"slicing {len(plates)} plates", markup=False)
    # G-code is not byte-stable (timestamp, threaded path order): keep its numbers, not the file.
    sliced = slicer.slice_plates([p.threemf for p in plates], spec, check.mass.by_material, infill=infill,
                                 log=lambda m: console.print(m, markup=False), keep_gcode=False)
    lines = bom.build_bom(spec, d, check.mass, sliced, sizes={b.name: b.bbox_mm for b in built})
    bom.write_bom(lines, out)
    steps = assembly_steps.assembly_steps(d)
    (out / "assembly.md").write_text(assembly_steps.to_markdown(steps), encoding="utf-8")
    console.print("rendering", markup=False)
    world = renders.world_meshes(d.parts, meshes, {b.name: b.print_from_local for b in built})
    views = renders.render_assembly(world, renders.rod_segments(d.frame), out / "renders", title=spec.name,
                                    vitamins=renders.vitamin_meshes(spec, d.frame))
    part_pngs = renders.render_parts({b.name: (b.material, meshes[b.name]) for b in built}, out / "renders" / "parts")
    images = {f"assembly {v}": p for v, p in views.items()} | {f"part {n}": p for n, p in part_pngs.items()}
    write_report(check, out, images, lines, steps, plates, sliced)
