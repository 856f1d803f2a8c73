"""`cogniframe printers` (the printer presets) and `cogniframe new` (start a design from a preset).

`new NAME [--from carbon|bamboo]` copies a commented preset shipped inside the package
(`cogniframe/data/presets/*.yaml`, the same text as the repo's `params/*.yaml`) to `NAME.yaml`
(NAME may include a folder, e.g. `params/mydrone`), with `name:` set to the file's stem and the
first line pointing the YAML language server at the schema shipped in the package, by a path
relative to the new file. It never overwrites a file (exit 2).
``register(app)`` adds both commands to a Typer app.
"""

from __future__ import annotations

import json
import os
import re
import sys
from importlib import resources
from pathlib import Path
from typing import Annotated

import typer

from cogniframe.errors import UserError

PRESETS = ("carbon", "bamboo")
SCHEMA_LINE = "# yaml-language-server: $schema="


def printers_cmd(json_out: Annotated[bool, typer.Option("--json", help="print JSON instead of a table")] = False) -> None:
    """List the printer presets for `printer: {preset: NAME}`: build volume, nozzle, slicer (sources with --json)."""
    from cogniframe.printers import PRINTERS

    if json_out:
        data = [{"preset": p.key, "name": p.name, "bed_mm": list(p.bed), "nozzle_mm": p.nozzle, "slicer": p.slicer,
                 "url": p.url, "source": p.source}
                for p in PRINTERS.values()]
        sys.stdout.write(json.dumps(data, indent=2) + "\n")
        return
    from rich.console import Console

    Console().print(printers_table())


def printers_table():
    """The presets as a rich Table that fits an 80-column terminal: the specification pages and
    sources are long, so they are in `printers --json`, not in the table."""
    from rich.table import Table

    from cogniframe.printers import PRINTERS

    t = Table(title="Printer presets: put `preset: NAME` under `printer:`; keys beside it override the preset",
              caption="Plates are written for the slicer named here. Specification pages and sources: "
                      "`cogniframe printers --json`.")
    for col, just in (("preset", "left"), ("printer", "left"), ("bed x y z mm", "right"), ("nozzle", "right"),
                      ("slicer", "left")):
        t.add_column(col, justify=just, overflow="fold", no_wrap=col != "printer")
    for p in PRINTERS.values():
        t.add_row(p.key, p.name, " x ".join(f"{v:g}" for v in p.bed), f"{p.nozzle:g}", p.slicer)
    return t


def preset_text(preset: str) -> str:
    """The shipped copy of params/<preset>.yaml."""
    return resources.files("cogniframe").joinpath(f"data/presets/{preset}.yaml").read_text(encoding="utf-8")


def schema_path() -> Path:
    """The params JSON Schema shipped in the package."""
    return Path(str(resources.files("cogniframe").joinpath("data/params.schema.json")))


def new_params_text(preset: str, name: str, target_dir: Path) -> str:
    """The preset's text with its schema line pointing (relatively) at the package's schema and `name:` set."""
    lines = preset_text(preset).splitlines(keepends=True)
    rel = Path(os.path.relpath(schema_path().resolve(), Path(target_dir).resolve())).as_posix()
    if lines and lines[0].startswith(SCHEMA_LINE):
        lines = lines[1:]
    head = [f"{SCHEMA_LINE}{rel}\n", f"# Started from the {preset} preset by `cogniframe new`; edit any value below.\n"]
    text = "".join(head + lines).replace(f"params/{preset}.yaml", (Path(target_dir) / f"{name}.yaml").as_posix())
    text, n = re.subn(r"(?m)^name:[ \t]*\S+[ \t]*(#.*)?$", f"name: {name}            # output goes to out/{name}/", text, count=1)
    if n != 1:  # a shipped preset always has a top-level name: key
        raise RuntimeError(f"preset {preset} has no top-level `name:` line")
    return text


def new_cmd(
    name: Annotated[str, typer.Argument(help="design name or path without .yaml, e.g. mydrone or params/mydrone", show_default=False)],
    from_: Annotated[str, typer.Option("--from", help="preset to start from: carbon (the paper's) or bamboo")] = "carbon",
) -> None:
    """Write NAME.yaml: a commented params file to start a design from (never overwrites)."""
    from rich.console import Console

    if from_ not in PRESETS:
        raise UserError(f"--from {from_}: unknown preset. Fix: use one of {', '.join(PRESETS)}.")
    path = Path(name)
    if path.suffix in (".yaml", ".yml"):
        path = path.with_suffix("")
    stem = path.name
    from cogniframe.spec import NAME_RE, slug

    if not NAME_RE.fullmatch(stem):
        raise UserError(f"{name}: not a usable design name (it names the file and the output folder out/{stem}). "
                        f"Fix: use letters, digits, '-', '_' and '.', not starting with '.', at most 64 characters, "
                        f"e.g. {slug(stem)}.")
    target = path.with_name(stem + ".yaml")
    if target.exists():
        raise UserError(f"{target}: already exists; `cogniframe new` never overwrites a file. Fix: choose another "
                        f"name, or delete or rename {target} first.")
    if not target.parent.is_dir():
        raise UserError(f"{target.parent}: no such folder. Fix: create it first or give a NAME in an existing folder.")
    text = new_params_text(from_, stem, target.parent)
    with open(target, "x", encoding="utf-8") as f:  # "x": fail rather than overwrite, even in a race
        f.write(text)
    Console().print(f"wrote {target} (from the {from_} preset). Next: edit it, then `cogniframe check {target}`.",
                    markup=False, highlight=False)


def register(app: typer.Typer) -> None:
    app.command("printers")(printers_cmd)
    app.command("new")(new_cmd)
