"""Slice a build folder's print plates with PrusaSlicer: what `cogniframe slice` does, from Python.

    r = slice_build("params/bamboo.yaml")     # SliceResult: grams and time per plate, per material
    r.report.total_g, r.estimate_source

Reads `<out>/plates/*.3mf` (written by `build`), slices each with a profile made from the params,
compares the filament per material with the mass budget (the build's check.json when it is there,
else the part list's estimate), writes `<out>/plates/slice.json` and the G-code, and records them
in the folder's manifest: `slice` writes only into a folder cogniframe made. Problems the user can
fix raise UserError.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import UserError

if TYPE_CHECKING:  # pragma: no cover
    from ..export.slicer import SliceReport


@dataclass(frozen=True)
class SliceResult:
    name: str  # the design's
    report: SliceReport  # plates (grams, time, objects), materials against the budget, warnings
    folder: Path  # the build folder
    plate_dir: Path  # where the G-code, the profiles and slice.json are
    estimate_source: str  # what the sliced grams are compared with


def slice_build(params: str | Path, out: str | Path | None = None) -> SliceResult:
    """Slice the plates of the build folder of `params` (`out`, default out/<name>) under the
    folder's lock; slice.json and the G-code join the folder's manifest."""
    from .. import outdir
    from . import _load

    design = _load(params, validate=False)
    out = None if out is None else Path(out)
    folder = outdir.output_dir(design.spec, out)
    plate_dir = folder / "plates"
    plates = sorted(plate_dir.glob("*.3mf")) if plate_dir.is_dir() else []
    again = f"`cogniframe build {params}" + (f" -o {out}" if out is not None else "") + "`"
    if not plates:
        raise UserError(f"{plate_dir}: no print plates (*.3mf) there. Fix: run {again} first, then `cogniframe slice` again.")
    if outdir.manifest_files(folder) is None:
        raise UserError(f"{folder} is not a cogniframe build folder (no manifest.json written by cogniframe), so "
                        f"`slice` will not write into it. Fix: run {again} to make one.")
    with outdir.lock(folder):
        return _slice_locked(design, folder, plate_dir, plates)


def _slice_locked(design, folder: Path, plate_dir: Path, plates: list[Path]) -> SliceResult:
    from .. import outdir
    from ..export import slicer
    from ..partlist import infill_by_material

    exe = slicer.find_slicer()
    if exe is None:
        raise UserError(f"{slicer.SLICER} is not on PATH, so the plates cannot be sliced. Fix: install PrusaSlicer "
                        f"(Debian/Ubuntu: apt-get install prusa-slicer) or open the 3MF files in {plate_dir} in its GUI.")
    d = design.derived
    estimated, source = _estimated_grams(folder, design.spec, d)
    report = slicer.slice_plates(plates, design.spec, estimated, infill=infill_by_material(d.parts), exe=exe)
    assert report is not None  # exe was found
    (plate_dir / "slice.json").write_text(json.dumps(report.to_dict(), indent=2) + "\n", encoding="utf-8")
    # What slice wrote becomes part of the build folder's manifest: still cogniframe's files.
    outdir.record(folder, sorted(p for p in plate_dir.rglob("*") if p.is_file()))
    return SliceResult(design.name, report, folder, plate_dir, source)


def _estimated_grams(folder: Path, spec, design) -> tuple[dict[str, float], str]:
    """Printed grams per material from the build's check.json (CAD volumes), else the analytic estimate."""
    from ..analysis import mass as mass_mod

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


def format_duration(seconds: float) -> str:
    """A print time as slice.json and the `slice` table write it (whole minutes, '5h 23m')."""
    from ..export.slicer import format_duration as fmt

    return fmt(seconds)
