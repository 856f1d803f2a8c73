"""Cut list and stock plan, derived from the frame graph's rods.

One row per distinct rod (role + cut length); a stock plan that packs the cuts into stock rods
(1-D cutting stock by best-fit decreasing, checked against the lower bound ceil(sum / stock)).
Lengths in mm, masses in g.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass

from .errors import UserError
from .frame import Frame
from .spec import Spec


@dataclass(frozen=True)
class CutRow:
    role: str
    length_mm: float
    qty: int
    diameter_mm: float
    material: str
    rods: tuple[str, ...]  # frame rod names cut to this length
    mass_g: float  # each

    def as_dict(self) -> dict:
        return {"role": self.role, "length_mm": self.length_mm, "qty": self.qty, "diameter_mm": self.diameter_mm,
                "material": self.material, "mass_g_each": round(self.mass_g, 3), "rods": list(self.rods)}


@dataclass(frozen=True)
class StockRod:
    index: int  # 1-based
    cuts: tuple[tuple[str, float], ...]  # (role, length) in cutting order
    used_mm: float  # cuts + kerfs
    offcut_mm: float


@dataclass(frozen=True)
class StockPlan:
    stock_length_mm: float
    kerf_mm: float
    rods: tuple[StockRod, ...]
    lower_bound: int  # no plan can use fewer stock rods than this

    @property
    def count(self) -> int:
        return len(self.rods)


@dataclass(frozen=True)
class CutList:
    rows: tuple[CutRow, ...]
    stock: StockPlan

    @property
    def total_length_mm(self) -> float:
        return sum(r.length_mm * r.qty for r in self.rows)

    @property
    def total_mass_g(self) -> float:
        return sum(r.mass_g * r.qty for r in self.rows)

    @property
    def count(self) -> int:
        return sum(r.qty for r in self.rows)


ROLE_ORDER = {"cage": 0, "leg": 1, "arm": 2, "strut": 3}


def cut_list(spec: Spec, frame: Frame) -> CutList:
    """Group the frame's rods by (role, cut length) and plan the stock. Each row's diameter and
    material are its rods' own (`frame.Rod`); the spec gives only what the frame does not carry:
    the materials' densities and the stock (`rods.stock_length`, `rods.kerf`)."""
    groups: dict[tuple[str, float, float, str], list[str]] = {}
    for rod in frame.rods.values():
        groups.setdefault((rod.role, rod.cut_length, rod.diameter, rod.material), []).append(rod.name)
    rows = tuple(
        CutRow(role, length, len(names), d, material, tuple(names),
               math.pi / 4 * d**2 * length * spec.material(material).density_g_mm3)
        for (role, length, d, material), names in sorted(groups.items(), key=lambda kv: (ROLE_ORDER[kv[0][0]], -kv[0][1]))
    )
    return CutList(rows, plan_stock(rows, spec.rods.stock_length, spec.rods.kerf))


def plan_stock(rows: tuple[CutRow, ...], stock_length: float, kerf: float) -> StockPlan:
    """Best-fit decreasing: each cut (plus one kerf) goes into the fullest stock rod it still fits."""
    pieces = sorted(((r.role, r.length_mm) for r in rows for _ in range(r.qty)), key=lambda p: (-p[1], p[0]))
    for role, length in pieces:
        if length + kerf > stock_length:
            raise UserError(
                f"a {role} rod of {length:g} mm (+ {kerf:g} mm kerf) is longer than the {stock_length:g} mm stock. "
                f"Fix: set rods.stock_length to at least {math.ceil(length + kerf)} mm, or make the frame smaller.",
                key="rods.stock_length")
    bins: list[list[tuple[str, float]]] = []
    used: list[float] = []
    for role, length in pieces:
        need = length + kerf
        best = None
        for i, u in enumerate(used):
            if u + need <= stock_length + 1e-9 and (best is None or u > used[best]):
                best = i
        if best is None:
            bins.append([(role, length)])
            used.append(need)
        else:
            bins[best].append((role, length))
            used[best] += need
    lower = math.ceil(sum(length + kerf for _, length in pieces) / stock_length)
    stock = tuple(StockRod(i + 1, tuple(b), round(u, 3), round(stock_length - u, 3)) for i, (b, u) in enumerate(zip(bins, used)))
    return StockPlan(stock_length, kerf, stock, lower)


# -- writers (pure: return text) -------------------------------------------------------------

def to_csv(cut: CutList) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["role", "length_mm", "qty", "diameter_mm", "material", "mass_g_each", "rods"])
    for r in cut.rows:
        w.writerow([r.role, f"{r.length_mm:g}", r.qty, f"{r.diameter_mm:g}", r.material, f"{r.mass_g:.2f}", " ".join(r.rods)])
    return buf.getvalue()


def to_markdown(cut: CutList) -> str:
    lines = ["# Cut list", "", "| role | cut length (mm) | qty | diameter (mm) | material | g each |", "|---|---:|---:|---:|---|---:|"]
    for r in cut.rows:
        lines.append(f"| {r.role} | {r.length_mm:g} | {r.qty} | {r.diameter_mm:g} | {r.material} | {r.mass_g:.2f} |")
    lines += ["", f"Total: {cut.count} rods, {cut.total_length_mm:.0f} mm, {cut.total_mass_g:.1f} g.", "",
              f"## Stock plan: {cut.stock.count} stock rods of {cut.stock.stock_length_mm:g} mm "
              f"(kerf {cut.stock.kerf_mm:g} mm; lower bound {cut.stock.lower_bound})", "",
              "| stock rod | cuts (mm) | offcut (mm) |", "|---:|---|---:|"]
    for s in cut.stock.rods:
        lines.append(f"| {s.index} | {' + '.join(f'{length:g} ({role})' for role, length in s.cuts)} | {s.offcut_mm:g} |")
    return "\n".join(lines) + "\n"
