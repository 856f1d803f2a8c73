"""`cogniframe printers` (the printer presets) and `cogniframe new` (start a design from a preset).

`new NAME [--from carbon|bamboo]` writes NAME.yaml (NAME may include a folder, e.g.
`params/mydrone`) from a commented preset; it never overwrites a file (exit 2). The work is the
API's (`api.presets`); these parse the arguments and print. ``register(app)`` adds both commands
to a Typer app.
"""

from __future__ import annotations

import json
import sys
from typing import Annotated

import typer

from cogniframe.errors import UserError


def printers_cmd(json_out: Annotated[bool, typer.Option("--json", help="print JSON instead of a table")] = False) -> None:
    """List the printer presets for `printer: {preset: NAME}`: build volume, nozzle, slicer (sources with --json)."""
    from cogniframe.api.presets import printer_presets

    if json_out:
        data = [{"preset": p.key, "name": p.name, "bed_mm": list(p.bed), "nozzle_mm": p.nozzle, "slicer": p.slicer,
                 "url": p.url, "source": p.source}
                for p in printer_presets()]
        sys.stdout.write(json.dumps(data, indent=2) + "\n")
        return
    from rich.console import Console

    Console().print(printers_table())


def printers_table():
    """The presets as a rich Table that fits an 80-column terminal: the specification pages and
    sources are long, so they are in `printers --json`, not in the table."""
    from rich.table import Table

    from cogniframe.api.presets import printer_presets

    t = Table(title="Printer presets: put `preset: NAME` under `printer:`; keys beside it override the preset",
              caption="Plates are written for the slicer named here. Specification pages and sources: "
                      "`cogniframe printers --json`.")
    for col, just in (("preset", "left"), ("printer", "left"), ("bed x y z mm", "right"), ("nozzle", "right"),
                      ("slicer", "left")):
        t.add_column(col, justify=just, overflow="fold", no_wrap=col != "printer")
    for p in printer_presets():
        t.add_row(p.key, p.name, " x ".join(f"{v:g}" for v in p.bed), f"{p.nozzle:g}", p.slicer)
    return t


def new_cmd(
    name: Annotated[str, typer.Argument(help="design name or path without .yaml, e.g. mydrone or params/mydrone", show_default=False)],
    from_: Annotated[str, typer.Option("--from", help="preset to start from: carbon (the paper's) or bamboo")] = "carbon",
) -> None:
    """Write NAME.yaml: a commented params file to start a design from (never overwrites)."""
    from rich.console import Console

    from cogniframe.api.presets import PRESETS, new_params

    if from_ not in PRESETS:
        raise UserError(f"--from {from_}: unknown preset. Fix: use one of {', '.join(PRESETS)}.")
    target = new_params(name, from_).path
    Console().print(f"wrote {target} (from the {from_} preset). Next: edit it, then `cogniframe check {target}`.",
                    markup=False, highlight=False)


def register(app: typer.Typer) -> None:
    app.command("printers")(printers_cmd)
    app.command("new")(new_cmd)
