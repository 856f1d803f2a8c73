"""Bill of materials: everything to buy, cut or print, with masses that add up to the mass budget.

One `BomLine` per mass-budget item, in shopping order: printed parts, rods, hardware, motors,
propellers, electronics, battery. Quantities and details come from the design (part list,
cut list, `PartSpec.hardware`, params); every mass is the budget's own number, and any budget
item this module does not know is still listed (category "other"), so the BOM total always
equals the budget total. Printed parts get the slicer's grams and print time when a slice
report is given (shared out by volume across the plate; see export/slicer.py).
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Mapping, Sequence

if TYPE_CHECKING:
    from ..analysis.mass import MassBudget
    from ..export.slicer import SliceReport
    from ..design import Derived
    from ..spec import Spec

from .assembly_steps import copy_labels

CATEGORIES = ("printed", "rod", "hardware", "motor", "propeller", "electronics", "battery", "other")
_SIZE = re.compile(r"\b(M\d+(?:\.\d+)?)\s*x\s*(\d+(?:\.\d+)?)")


@dataclass(frozen=True)
class BomLine:
    category: str  # one of CATEGORIES
    item: str
    qty: int
    size: str  # e.g. "M2 x 8", "197.5 mm x 3 mm", "70 x 35 x 15 mm"
    material: str  # filament / rod material, or ""
    mass_g_each: float
    mass_g: float  # qty x each, as in the mass budget
    sliced_g: float | None = None  # printed parts: slicer grams for all copies
    print_time_s: float | None = None  # printed parts: slicer time for all copies (files show whole minutes)
    notes: str = ""

    def as_dict(self) -> dict:
        return {"category": self.category, "item": self.item, "qty": self.qty, "size": self.size,
                "material": self.material, "mass_g_each": round(self.mass_g_each, 3), "mass_g": round(self.mass_g, 2),
                "sliced_g": None if self.sliced_g is None else round(self.sliced_g, 2),
                "print_time_min": None if self.print_time_s is None else round(self.print_time_s / 60.0),
                "notes": self.notes}


def _screw_size(item: str) -> str:
    m = _SIZE.search(item)
    if m:
        return f"{m.group(1)} x {m.group(2)}"
    m = re.search(r"(\d+(?:\.\d+)?)(?: mm)? x (\d+(?:\.\d+)?) mm", item)  # straps, zip ties: width x length
    return f"{m.group(1)} x {m.group(2)} mm" if m else ""


def build_bom(spec: "Spec", design: "Derived", budget: "MassBudget",
              slice_report: "SliceReport | None" = None,
              sizes: Mapping[str, Sequence[float]] | None = None) -> tuple[BomLine, ...]:
    """The bill of materials for a design; masses from `budget` (estimate or CAD volumes).

    `sizes` (part name -> print bounding box, mm, e.g. BuiltPart.bbox_mm) replaces the part
    list's analytic envelope in the size column."""
    items = {i.name: i for i in budget.items}
    used: set[str] = set()
    lines: list[BomLine] = []
    sliced = slice_report.part_totals() if slice_report is not None else {}

    def take(name: str):
        it = items.get(name)
        if it is not None:
            used.add(name)
        return it

    for p in design.parts:
        it = take(p.name)
        if it is None:
            continue
        env = tuple(sizes[p.name]) if sizes and p.name in sizes else p.estimate.envelope
        g_t = sliced.get(p.name)
        lines.append(BomLine(
            "printed", p.name, it.qty, " x ".join(_mm(v) for v in env) + " mm", p.material, it.mass_g_each, it.mass_g,
            None if g_t is None else g_t[0], None if g_t is None else g_t[1],
            f"{p.infill * 100:.0f} % infill; {', '.join(copy_labels(p))}"))

    for row in design.cut.rows:
        it = take(f"rod {row.role} {row.length_mm:g} mm")
        if it is None:
            continue
        lines.append(BomLine("rod", f"{row.role} rod", it.qty, f"{row.length_mm:g} mm x {row.diameter_mm:g} mm", row.material,
                             it.mass_g_each, it.mass_g, notes=f"cut from {design.cut.stock.stock_length_mm:g} mm stock; "
                             + ", ".join(row.rods)))

    hardware: dict[str, list[str]] = {}
    for p in design.parts:
        for h in p.hardware:
            hardware.setdefault(h.item, []).append(p.name)
    for name, owners in hardware.items():
        it = take(name)
        if it is None:
            continue
        lines.append(BomLine("hardware", name, it.qty, _screw_size(name), "", it.mass_g_each, it.mass_g,
                             notes="for " + ", ".join(dict.fromkeys(owners))))

    motor = spec.motor
    it = take(f"motor {motor.name}")
    if it is not None:
        lines.append(BomLine("motor", f"brushless motor {motor.name}", it.qty, f"{motor.pattern} mm {motor.screw} holes (opposite holes across the shaft)",
                             "", it.mass_g_each, it.mass_g,
                             notes=f"bell {motor.bell_d:g} mm" + (f"; {spec.motors.kv} KV" if spec.motors.kv else "")))
    it = take(f"propeller {spec.motors.prop_diameter:g} mm")
    if it is not None:
        lines.append(BomLine("propeller", "propeller", it.qty, f"{spec.motors.prop_diameter:g} mm ({spec.motors.prop_diameter / 25.4:.1f} in)",
                             "", it.mass_g_each, it.mass_g, notes="2 CW + 2 CCW"))
    from ..materials import BOARDS, VITAMIN_KINDS

    for c in spec.components:
        it = take(c.name)
        if it is not None:
            boards = [BOARDS[_board_key(k, spec)] for k in VITAMIN_KINDS.get(c.vitamin or "", ())]
            size = "; ".join(f"{b.size[0]:g} x {b.size[1]:g} mm board" for b in boards)
            notes = "; ".join(f"{b.bom}: {b.mass_g:g} g in the catalogue (budget uses this line)" for b in boards)
            lines.append(BomLine("electronics", c.name, it.qty, size, "", it.mass_g_each, it.mass_g,
                                 notes=(f"drawn as vitamin {c.vitamin}; " + notes) if c.vitamin else ""))
    it = take("battery")
    if it is not None:
        b = spec.core.battery
        lines.append(BomLine("battery", "battery (LiPo)", it.qty, f"{b.length:g} x {b.width:g} x {b.height:g} mm", "",
                             it.mass_g_each, it.mass_g,
                             notes=f"{b.cells}S {b.capacity_mah:g} mAh, {b.connector} lead; held by "
                             + (f"a {spec.core.strap_width:g} mm strap across the holder mouth" if spec.core.battery_lock == "strap"
                                else "the magnetic lid across the holder mouth")))
    for name, it in items.items():
        if name not in used:
            lines.append(BomLine("other", name, it.qty, "", it.material or "", it.mass_g_each, it.mass_g))
    order = {c: i for i, c in enumerate(CATEGORIES)}
    return tuple(sorted(lines, key=lambda ln: order[ln.category]))  # stable within a category


def _board_key(kind: str, spec: "Spec") -> str:
    """Vitamin kind -> BOARDS key (fc/esc follow the stack pattern)."""
    if kind in ("fc", "esc"):
        return f"{kind}_{'20x20' if spec.core.stack_pattern == '20x20' else '30x30'}"
    return kind


def total_g(lines: Sequence[BomLine]) -> float:
    return sum(ln.mass_g for ln in lines)


def _fmt_time(s: float | None) -> str:
    if s is None:
        return ""
    from ..export.slicer import format_duration

    return format_duration(s)


COLUMNS = ("category", "item", "qty", "size", "material", "g each", "g", "sliced g", "print time", "notes")


def _row(ln: BomLine) -> list[str]:
    return [ln.category, ln.item, str(ln.qty), ln.size, ln.material, f"{ln.mass_g_each:.2f}", f"{ln.mass_g:.2f}",
            "" if ln.sliced_g is None else f"{ln.sliced_g:.1f}", _fmt_time(ln.print_time_s), ln.notes]


def to_csv(lines: Sequence[BomLine]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["category", "item", "qty", "size", "material", "mass_g_each", "mass_g", "sliced_g", "print_time_min", "notes"])
    for ln in lines:
        d = ln.as_dict()
        w.writerow([d["category"], d["item"], d["qty"], d["size"], d["material"], f"{ln.mass_g_each:.3f}", f"{ln.mass_g:.2f}",
                    "" if d["sliced_g"] is None else f"{d['sliced_g']:.2f}",
                    "" if d["print_time_min"] is None else d["print_time_min"], d["notes"]])
    w.writerow(["total", "", sum(ln.qty for ln in lines), "", "", "", f"{total_g(lines):.2f}", "", "", ""])
    return buf.getvalue()


def to_markdown(lines: Sequence[BomLine], title: str = "Bill of materials") -> str:
    out = [f"# {title}", ""] if title else []
    out += ["| " + " | ".join(COLUMNS) + " |", "|---|---|---:|---|---|---:|---:|---:|---:|---|"]
    for ln in lines:
        out.append("| " + " | ".join(c.replace("|", "/") for c in _row(ln)) + " |")
    out += ["", f"Total: {total_g(lines):.2f} g (equals the mass budget's all-up weight)."]
    sub = {}
    for ln in lines:
        sub[ln.category] = sub.get(ln.category, 0.0) + ln.mass_g
    out.append("By category: " + ", ".join(f"{k} {v:.1f} g" for k, v in sub.items()) + ".")
    return "\n".join(out) + "\n"


def write_bom(lines: Sequence[BomLine], out_dir: Path | str) -> tuple[Path, Path]:
    """Write bom.csv and bom.md into out_dir; returns their paths."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    c, m = out_dir / "bom.csv", out_dir / "bom.md"
    c.write_text(to_csv(lines), encoding="utf-8")
    m.write_text(to_markdown(lines), encoding="utf-8")
    return c, m


def _mm(v: float) -> str:
    """A printed part's size, whole mm; under 1 mm (the net's 0.5 mm) to 0.1 mm, not 0."""
    return f"{v:.1f}" if v < 1 else f"{v:.0f}"
