"""Starting a design: the printer presets, the params presets `cogniframe new` copies, and the
params file's JSON Schema. What `cogniframe printers`, `new` and `schema` do, from Python.

    printer_presets()                         # (PrinterPreset, ...): bed, nozzle, slicer, source
    new_params("params/mydrone", "bamboo")    # NewParams: params/mydrone.yaml written, never over a file
    params_schema()                           # the JSON Schema editors complete params files with

A new params file is the commented preset shipped inside the package
(`cogniframe/data/presets/*.yaml`, the same text as the repo's `params/*.yaml`), with `name:` set
to the file's stem and a first line pointing the YAML language server at the schema shipped in
the package, by a path relative to the new file.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import UserError

if TYPE_CHECKING:  # pragma: no cover
    from ..printers import PrinterPreset

PRESETS = ("carbon", "bamboo")
SCHEMA_LINE = "# yaml-language-server: $schema="


def printer_presets() -> tuple[PrinterPreset, ...]:
    """The printer presets for `printer: {preset: NAME}`, in the table's order."""
    from ..printers import PRINTERS

    return tuple(PRINTERS.values())


def params_schema() -> dict:
    """The JSON Schema of a params file (for editor autocompletion)."""
    from .. import spec as spec_mod

    return spec_mod.json_schema()


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


@dataclass(frozen=True)
class NewParams:
    path: Path  # the params file written
    preset: str  # the preset it started from


def new_params(name: str | Path, preset: str = "carbon") -> NewParams:
    """Write `name`.yaml (`name` may include a folder and may end in .yaml) from a preset. Never
    overwrites a file: UserError when it exists, when the name is not a usable design name (it
    names the output folder too), or when its folder does not exist."""
    from ..spec import NAME_RE, slug

    if preset not in PRESETS:
        raise UserError(f"{preset}: unknown preset. Fix: use one of {', '.join(PRESETS)}.")
    path = Path(name)
    if path.suffix in (".yaml", ".yml"):
        path = path.with_suffix("")
    stem = path.name
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
    text = new_params_text(preset, stem, target.parent)
    with open(target, "x", encoding="utf-8") as f:  # "x": fail rather than overwrite, even in a race
        f.write(text)
    return NewParams(target, preset)
