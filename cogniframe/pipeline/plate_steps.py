"""The print plates: laid out per material (3MF with their slicer settings inside), sliced by
PrusaSlicer, and drawn as previews. Each step's row sits beside its make and key functions.

The printer preset's slicer picks the 3MF: PrusaSlicer's (settings in Slic3r_PE.config) or
OrcaSlicer / Bambu Studio's (settings per object in model_settings.config, `export/bambu3mf.py`).
Either is sliced by PrusaSlicer with the same generated profile for the grams and time: there is
no OrcaSlicer or Bambu Studio command line to run here, and the geometry is the same."""

from __future__ import annotations

import tempfile
from pathlib import Path

from ..cache import file_sha256
from .graph import Made, Step


def plates_key(ctx, material: str):
    return [[[p.name, p.qty, ctx.part_value(p.name)["stl_sha256"]] for p in ctx.parts_of(material)],
            ctx.bed, float(ctx.spec.printer.margin), _config(ctx, material)]

def _orca(ctx) -> bool:
    """Plates for OrcaSlicer / Bambu Studio (the printer preset's slicer), else for PrusaSlicer."""
    from ..printers import orca_family, slicer_of

    return orca_family(slicer_of(ctx.spec.printer.preset))

def _config(ctx, material: str) -> str:
    """The settings embedded in this material's plates: the .ini's values for PrusaSlicer, the
    per-object settings for OrcaSlicer / Bambu Studio."""
    from ..export import slicer

    if _orca(ctx):
        from ..export import bambu3mf

        return bambu3mf.settings_text(bambu3mf.object_settings(ctx.spec, material, _infill(ctx, material)))
    return slicer.project_config(ctx.spec, material, _infill(ctx, material))

def _plate_3mf(ctx, plate, material: str):
    from ..export import plates as pl

    if _orca(ctx):
        from ..export import bambu3mf

        return bambu3mf.plate_3mf(plate, bambu3mf.object_settings(ctx.spec, material, _infill(ctx, material)))
    return pl.plate_3mf(plate, _config(ctx, material))

def make_plates(ctx, material: str) -> Made:
    from ..export import plates as pl

    items = [pl.PlateItem(p.name, p.material, p.qty, ctx.mesh(p.name)) for p in ctx.parts_of(material)]
    folder = ctx.out / "plates"
    folder.mkdir(parents=True, exist_ok=True)
    value = []
    for plate in pl.pack_plates(items, ctx.spec.printer.bed, ctx.spec.printer.margin):
        f3 = folder / f"{plate.name}.3mf"
        data, read = _plate_3mf(ctx, plate, material)
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
    from ..export import plates as pl

    files = []
    for v in ctx[f"plates:{material}"]:
        plate = pl.read_plate(ctx.out / v["threemf"], ctx.spec.printer.bed, ctx.spec.printer.margin,
                              items=ctx.plate_items(v))
        pl.plot_plate(plate, ctx.out / v["preview"])
        files.append(v["preview"])
    return Made(tuple(files))

def _infill(ctx, material: str) -> float:
    from ..partlist import infill_by_material

    return infill_by_material(ctx.design.parts)[material]

def _profile(ctx, material: str) -> str:
    from ..export import slicer

    return slicer.profile_ini(ctx.spec, material, _infill(ctx, material))

def _keep_gcode(ctx) -> bool:
    """`build --gcode`: keep each plate's G-code beside it (not byte-stable; the manifest says so)."""
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
    from ..export import slicer

    found = ctx.slicer.get()
    if not found:
        return Made()
    exe, version = found
    ini = ctx.out / "plates" / f"{material}.ini"
    ini.write_text(_profile(ctx, material), encoding="utf-8")
    plates = []
    kept = []
    # each material's slicer on a CPU of its own. PrusaSlicer runs on one (`slicer.slice_plate`), so
    # it runs at the build's priority, not behind it as the CAD workers do: it cannot take the main
    # thread's core, and it heads the chain a one-part rebuild waits for (part -> plates -> slice)
    cpu = sorted({p.material for p in ctx.design.parts}).index(material)
    with tempfile.TemporaryDirectory(prefix="cogniframe-gcode-") as tmp:
        for v in ctx[f"plates:{material}"]:
            where = ctx.out / "plates" if _keep_gcode(ctx) else Path(tmp)
            items = ctx.plate_items(v)
            if ctx.use_cache and not _keep_gcode(ctx):  # per plate: a plate whose bytes did not change is not sliced again
                r = slicer._slice_cached(ctx.out / v["threemf"], ini, ctx.spec.printer.bed, exe, version,
                                         where / f"{v['name']}.gcode", items=items, cpu=cpu)
            else:
                r = slicer.slice_plate(ctx.out / v["threemf"], ini, ctx.spec.printer.bed, exe,
                                       gcode=where / f"{v['name']}.gcode", items=items, cpu=cpu)
            plates.append({"plate": r.plate, "material": r.material, "grams": r.grams, "time_s": r.time_s,
                           "objects": [list(o) for o in r.objects]})
            if _keep_gcode(ctx):
                kept.append(f"plates/{v['name']}.gcode")
    if _orca(ctx):  # say whose numbers these are: the plates are for another slicer
        version = f"{version}, measuring plates written for Bambu Studio / OrcaSlicer with cogniframe's profile"
    return Made((f"plates/{material}.ini", *kept), {"slicer": version, "plates": plates})


PLATES = Step("plates:{material}", ("part:{material}/*",), make_plates, plates_key,
              ("export/plates.py", "export/bambu3mf.py", "export/slicer.py", "partlist.py", "printers.py", "numfmt.py"),
              reads="each part's STL hash and qty, bed, margin, print settings")
SLICE = Step("slice:{material}", ("plates:{material}",), make_slice, slice_key,
             ("export/slicer.py", "partlist.py", "printers.py"), "wait",
             reads="plate files, profile, PrusaSlicer version (each plate on its own key)")
PREVIEWS = Step("previews:{material}", ("plates:{material}",), make_previews, previews_key, ("export/plates.py", "numfmt.py"),
                reads="plate layouts")
