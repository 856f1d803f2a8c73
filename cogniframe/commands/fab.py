"""`cogniframe slice`: slice the print plates of an existing build folder with PrusaSlicer.

Reads `<out>/plates/*.3mf` (written by `cogniframe build`), slices each with a profile made
from the params (`<out>/plates/<material>.ini`), prints a table (plate, material, grams, time)
and the per-material comparison with the mass budget, and writes `<out>/plates/slice.json`.
``register(app)`` adds the command to a Typer app. User-fixable problems raise UserError.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Optional

import typer

from cogniframe import outdir
from cogniframe.errors import UserError


def slice_cmd(
    params: Annotated[Path, typer.Argument(help="params YAML file, e.g. params/bamboo.yaml", show_default=False)],
    out: Annotated[Optional[Path], typer.Option("-o", "--out", help="build folder (default out/<name>)")] = None,
) -> None:
    """Slice the print plates of a build folder with PrusaSlicer: grams and print time per plate."""
    from cogniframe import design as design_mod
    from cogniframe import outdir
    from cogniframe import spec as spec_mod
    from cogniframe.analysis import mass as mass_mod
    from cogniframe.export import slicer

    spec = spec_mod.load(params)
    folder = outdir.output_dir(spec, out)
    plate_dir = folder / "plates"
    plates = sorted(plate_dir.glob("*.3mf")) if plate_dir.is_dir() else []
    if not plates:
        raise UserError(f"{plate_dir}: no print plates (*.3mf) there. Fix: run `cogniframe build {params}"
                        + (f" -o {out}" if out is not None else "") + "` first, then `cogniframe slice` again.")
    if outdir.manifest_files(folder) is None:
        raise UserError(f"{folder} is not a cogniframe build folder (no manifest.json written by cogniframe), so "
                        f"`slice` will not write into it. Fix: run `cogniframe build {params}"
                        + (f" -o {out}" if out is not None else "") + "` to make one.")
    with outdir.lock(folder):
        _slice_locked(params, spec, folder, plate_dir, plates, slicer, design_mod, mass_mod)


def _slice_locked(params, spec, folder: Path, plate_dir: Path, plates, slicer, design_mod, mass_mod) -> None:
    from rich.console import Console
    from rich.table import Table

    exe = slicer.find_slicer()
    if exe is None:
        raise UserError(f"{slicer.SLICER} is not on PATH, so the plates cannot be sliced. Fix: install PrusaSlicer "
                        f"(Debian/Ubuntu: apt-get install prusa-slicer) or open the 3MF files in {plate_dir} in its GUI.")
    d = design_mod.design(spec)
    estimated, source = _estimated_grams(folder, spec, d, mass_mod)
    from cogniframe.partlist import infill_by_material

    report = slicer.slice_plates(plates, spec, estimated, infill=infill_by_material(d.parts), exe=exe)
    assert report is not None  # exe was found

    con = Console()
    t = Table(title=f"{spec.name}: {len(report.plates)} plates sliced with {report.slicer}")
    for col, just in (("plate", "left"), ("material", "left"), ("parts", "right"), ("grams", "right"),
                      ("time", "right"), ("slice s", "right")):
        t.add_column(col, justify=just)
    for p in report.plates:
        t.add_row(p.plate, p.material, str(len(p.objects)), f"{p.grams:.1f}", slicer.format_duration(p.time_s), f"{p.elapsed_s:.1f}")
    t.add_row("total", "", str(sum(len(p.objects) for p in report.plates)), f"{report.total_g:.1f}",
              slicer.format_duration(report.total_time_s), "", style="bold")
    con.print(t)
    m = Table(title=f"Filament vs mass budget ({source})")
    for col in ("material", "sliced g", "estimated g", "difference"):
        m.add_column(col, justify="left" if col == "material" else "right")
    for c in report.materials:
        diff = "" if c.diff_pct is None else f"{c.diff_pct:+.1f} %"
        m.add_row(c.material, f"{c.sliced_g:.1f}", "" if c.estimated_g is None else f"{c.estimated_g:.1f}",
                  f"[yellow]{diff}[/]" if c.flagged else diff)
    con.print(m)
    for w in report.warnings:
        con.print(f"[yellow]warning:[/] {w}")
    (plate_dir / "slice.json").write_text(json.dumps(report.to_dict(), indent=2) + "\n", encoding="utf-8")
    # What slice wrote becomes part of the build folder's manifest: still cogniframe's files.
    outdir.record(folder, sorted(p for p in plate_dir.rglob("*") if p.is_file()))
    con.print(f"wrote G-code and profiles to {plate_dir}")


def _estimated_grams(folder: Path, spec, design, mass_mod) -> tuple[dict[str, float], str]:
    """Printed grams per material from the build's check.json (CAD volumes), else the analytic estimate."""
    path = folder / "check.json"
    if path.is_file():
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            by = {str(k): float(v) for k, v in data["mass"]["by_material"].items()}
            if data.get("name") == spec.name:
                return by, f"from {path.name}, the build's mass budget"
        except (ValueError, KeyError, TypeError, AttributeError):
            pass  # unreadable or from another version: fall back to the analytic estimate below
    budget = mass_mod.budget(spec, design.frame, design.cut, design.parts)
    return budget.by_material, "analytic estimate: no check.json from `cogniframe build` in the folder"


def register(app: typer.Typer) -> None:
    app.command("slice")(slice_cmd)
