"""Printer presets (`printer: {preset: NAME}`): build volume, stock nozzle and slicer of common hobby printers.

The table is `cogniframe/data/printers.yaml` (shipped in the package), one entry per preset with
the maker's published build volume and the source it was taken from. `spec.PrinterSection` applies
a preset before validation, so explicit keys next to `preset:` override it. The preset's `slicer`
decides which kind of 3MF the print plates are written as (`slicer_of`).
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources

import yaml


@dataclass(frozen=True)
class PrinterPreset:
    key: str  # what goes after `preset:`, e.g. prusa_mini
    name: str  # the printer's name, e.g. Original Prusa MINI / MINI+
    bed: tuple[float, float, float]  # build volume x, y, z, mm
    nozzle: float  # mm
    slicer: str  # one of SLICERS: the slicer this printer's makers use, and so the plates' 3MF kind
    url: str  # the maker's specification page
    source: str  # what the numbers were taken from and checked against

    def fields(self) -> dict:
        """The PrinterSection keys this preset sets."""
        return {"bed": list(self.bed), "nozzle": self.nozzle}


SLICERS = ("prusaslicer", "orcaslicer", "bambustudio")
DEFAULT_SLICER = "prusaslicer"  # printers without a preset: PrusaSlicer's 3MF, as cogniframe always wrote


def _load() -> dict[str, PrinterPreset]:
    text = resources.files("cogniframe").joinpath("data/printers.yaml").read_text(encoding="utf-8")
    out = {}
    for key, d in yaml.safe_load(text).items():
        slicer = str(d["slicer"])
        if slicer not in SLICERS:  # the shipped table is ours: a typo there is a bug, not a user error
            raise ValueError(f"printers.yaml: {key}: slicer {slicer!r} is not one of {', '.join(SLICERS)}")
        out[key] = PrinterPreset(key, str(d["name"]), tuple(float(v) for v in d["bed"]), float(d["nozzle"]), slicer,
                                 str(d["url"]), str(d["source"]))
    return out


def slicer_of(preset: str | None) -> str:
    """The slicer a params file's plates are written for: its printer preset's, else PrusaSlicer."""
    return PRINTERS[preset].slicer if preset in PRINTERS else DEFAULT_SLICER


def orca_family(slicer: str) -> bool:
    """OrcaSlicer and Bambu Studio load the same 3MF (Bambu Studio's project format)."""
    return slicer in ("orcaslicer", "bambustudio")


PRINTERS: dict[str, PrinterPreset] = _load()
