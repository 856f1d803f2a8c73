"""Mass budget: every item of the design, grouped, against the limit. Grams throughout.

Printed parts use an FDM model: the shell (perimeters on vertical surfaces, solid top/bottom
layers on horizontal ones) is solid, the rest of the volume is filled at the infill fraction.
Volumes and surface areas come from the part list's analytic estimates (`check`) or from the
CAD meshes (`build`), passed in as `geometry`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

from ..cutlist import CutList
from ..frame import Frame
from ..partlist import PartSpec
from ..spec import PrinterSection, Spec

GROUPS = ("exoskeleton", "core", "electronics", "battery")
# Extrusion width as a multiple of the nozzle diameter (PrusaSlicer's default for perimeters).
LINE_WIDTH_FACTOR = 1.125


@dataclass(frozen=True)
class PartGeometry:
    """What the mass model needs from a printed part: volume (mm^3), horizontal and vertical area (mm^2)."""

    volume_mm3: float
    area_h_mm2: float
    area_v_mm2: float
    source: str  # "estimate" | "cad"


@dataclass(frozen=True)
class MassItem:
    name: str
    group: str
    qty: int
    mass_g_each: float
    material: str | None = None  # for printed parts and rods
    source: str = "params"  # params | estimate | cad | geometry

    @property
    def mass_g(self) -> float:
        return self.qty * self.mass_g_each

    def as_dict(self) -> dict:
        return {"name": self.name, "group": self.group, "qty": self.qty, "mass_g": round(self.mass_g, 2),
                "mass_g_each": round(self.mass_g_each, 3), "material": self.material, "source": self.source}


@dataclass(frozen=True)
class MassBudget:
    items: tuple[MassItem, ...]
    limit_g: float

    @property
    def total_g(self) -> float:
        return sum(i.mass_g for i in self.items)

    @property
    def margin_g(self) -> float:
        return self.limit_g - self.total_g

    @property
    def groups(self) -> dict[str, float]:
        return {g: sum(i.mass_g for i in self.items if i.group == g) for g in GROUPS}

    @property
    def by_material(self) -> dict[str, float]:
        """Grams of each printed filament and rod material."""
        out: dict[str, float] = {}
        for i in self.items:
            if i.material:
                out[i.material] = out.get(i.material, 0.0) + i.mass_g
        return dict(sorted(out.items()))

    def as_dict(self) -> dict:
        return {"total_g": round(self.total_g, 2), "limit_g": self.limit_g, "margin_g": round(self.margin_g, 2),
                "groups": {k: round(v, 2) for k, v in self.groups.items()},
                "by_material": {k: round(v, 2) for k, v in self.by_material.items()},
                "items": [i.as_dict() for i in self.items]}


def printed_mass_g(geom: PartGeometry, density_g_cm3: float, infill: float, printer: PrinterSection) -> float:
    """FDM part mass (g): solid shell + infill fraction of the inside."""
    line = printer.nozzle * LINE_WIDTH_FACTOR
    shell = geom.area_v_mm2 * printer.perimeters * line + geom.area_h_mm2 * printer.top_bottom_layers * printer.layer_height
    solid = min(geom.volume_mm3, shell)
    return density_g_cm3 / 1000.0 * (solid + infill * (geom.volume_mm3 - solid))


def estimate_geometry(parts: tuple[PartSpec, ...]) -> dict[str, PartGeometry]:
    return {p.name: PartGeometry(p.estimate.volume, p.estimate.area_h, p.estimate.area_v, "estimate") for p in parts}


def budget(spec: Spec, frame: Frame, cut: CutList, parts: tuple[PartSpec, ...],
           geometry: Mapping[str, PartGeometry] | None = None) -> MassBudget:
    """The whole mass budget. `geometry` overrides the analytic estimate per part name (CAD volumes)."""
    geom = {**estimate_geometry(parts), **(geometry or {})}
    items: list[MassItem] = []
    for row in cut.rows:
        items.append(MassItem(f"rod {row.role} {row.length_mm:g} mm", "exoskeleton", row.qty, row.mass_g, row.material, "geometry"))
    for p in parts:
        g = geom[p.name]
        mat = spec.material(p.material)
        items.append(MassItem(p.name, p.group, p.qty, printed_mass_g(g, mat.density_g_cm3, p.infill, spec.printer), p.material, g.source))
    hardware: dict[str, list] = {}
    for p in parts:
        for h in p.hardware:
            entry = hardware.setdefault(h.item, [0, h.mass_g])
            entry[0] += h.qty * p.qty
    for name, (qty, each) in hardware.items():
        items.append(MassItem(name, "core", qty, each))
    motor = spec.motor
    items.append(MassItem(f"motor {motor.name}", "electronics", len(frame.motors), motor.mass_g))
    items.append(MassItem(f"propeller {spec.motors.prop_diameter:g} mm", "electronics", len(frame.motors), spec.motors.prop_mass))
    for c in spec.components:
        items.append(MassItem(c.name, "electronics", c.qty, c.mass))
    items.append(MassItem("battery", "battery", 1, spec.core.battery.mass))
    return MassBudget(tuple(items), spec.requirements.mass_limit)
