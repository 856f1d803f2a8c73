"""`cogniframe slice`: slice the print plates of an existing build folder with PrusaSlicer.

Reads `<out>/plates/*.3mf` (written by `cogniframe build`), slices each with a profile made
from the params (`<out>/plates/<material>.ini`), prints a table (plate, material, grams, time)
and the per-material comparison with the mass budget, and writes `<out>/plates/slice.json`.
The work is the API's (`api.slicing.slice_build`); this module parses the arguments and prints.
``register(app)`` adds the command to a Typer app. User-fixable problems raise UserError.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer


def slice_cmd(
    params: Annotated[Path, typer.Argument(help="params YAML file, e.g. params/bamboo.yaml", show_default=False)],
    out: Annotated[Optional[Path], typer.Option("-o", "--out", help="build folder (default out/<name>)")] = None,
) -> None:
    """Slice the print plates of a build folder with PrusaSlicer: grams and print time per plate."""
    from rich.console import Console
    from rich.table import Table

    from cogniframe.api.slicing import format_duration, slice_build

    r = slice_build(params, out)
    report = r.report
    con = Console()
    t = Table(title=f"{r.name}: {len(report.plates)} plates sliced with {report.slicer}")
    for col, just in (("plate", "left"), ("material", "left"), ("parts", "right"), ("grams", "right"),
                      ("time", "right"), ("slice s", "right")):
        t.add_column(col, justify=just)
    for p in report.plates:
        t.add_row(p.plate, p.material, str(len(p.objects)), f"{p.grams:.1f}", format_duration(p.time_s), f"{p.elapsed_s:.1f}")
    t.add_row("total", "", str(sum(len(p.objects) for p in report.plates)), f"{report.total_g:.1f}",
              format_duration(report.total_time_s), "", style="bold")
    con.print(t)
    m = Table(title=f"Filament vs mass budget ({r.estimate_source})")
    for col in ("material", "sliced g", "estimated g", "difference"):
        m.add_column(col, justify="left" if col == "material" else "right")
    for c in report.materials:
        diff = "" if c.diff_pct is None else f"{c.diff_pct:+.1f} %"
        m.add_row(c.material, f"{c.sliced_g:.1f}", "" if c.estimated_g is None else f"{c.estimated_g:.1f}",
                  f"[yellow]{diff}[/]" if c.flagged else diff)
    con.print(m)
    for w in report.warnings:
        con.print(f"[yellow]warning:[/] {w}")
    con.print(f"wrote G-code and profiles to {r.plate_dir}")


def register(app: typer.Typer) -> None:
    app.command("slice")(slice_cmd)
