"""Printer presets (`printer: {preset: NAME}`): build volume and stock nozzle of common hobby printers.

The table is `cogniframe/data/printers.yaml` (shipped in the package), one entry per preset with
the maker's published build volume and the source it was taken from. `spec.PrinterSection` applies
a preset before validation, so explicit keys next to `preset:` override it.
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
    url: str  # the maker's specification page
    source: str  # what the numbers were taken from and checked against

    def fields(self) -> dict:
        """The PrinterSection keys this preset sets."""
        return {"bed": list(self.bed), "nozzle": self.nozzle}


def _load() -> dict[str, PrinterPreset]:
    text = resources.files("cogniframe").joinpath("data/printers.yaml").read_text(encoding="utf-8")
    out = {}
    for key, d in yaml.safe_load(text).items():
        out[key] = PrinterPreset(key, str(d["name"]), tuple(float(v) for v in d["bed"]), float(d["nozzle"]), str(d["url"]),
                                     str(d["source"]))
    return out


PRINTERS: dict[str, PrinterPreset] = _load()
