"""Rich tables for the terminal: the check summary (mass budget, cut list, drop model, verdict)."""

from __future__ import annotations

from rich.console import Console
from rich.table import Table

from ..analysis.verdict import Findings


def print_check(result: Findings, console: Console) -> None:
    d, m = result.design, result.mass
    spec = d.spec
    t = Table(title=f"Mass budget: {spec.name}", show_footer=True)
    t.add_column("item", footer="all-up weight")
    t.add_column("group")
    t.add_column("qty", justify="right")
    t.add_column("g", justify="right", footer=f"{m.total_g:.1f}")
    for i in m.items:
        t.add_row(i.name, i.group, str(i.qty), f"{i.mass_g:.1f}")
    console.print(t)
    g = Table(title="By group")
    for col in ("exoskeleton", "core", "electronics", "battery", "total", "limit", "margin"):
        g.add_column(col, justify="right")
    groups = m.groups
    margin_style = "green" if m.margin_g >= 0 else "red"
    g.add_row(*(f"{groups[k]:.1f}" for k in ("exoskeleton", "core", "electronics", "battery")),
              f"{m.total_g:.1f}", f"{m.limit_g:g}", f"[{margin_style}]{m.margin_g:+.1f}[/]")
    console.print(g)

    c = Table(title=f"Cut list: {d.cut.count} rods, {d.cut.total_length_mm:.0f} mm, {d.cut.total_mass_g:.1f} g; "
                    f"{d.cut.stock.count} x {d.cut.stock.stock_length_mm:g} mm stock")
    for col in ("role", "cut mm", "qty", "dia mm", "material"):
        c.add_column(col, justify="right" if col in ("cut mm", "qty", "dia mm") else "left")
    for r in d.cut.rows:
        c.add_row(r.role, f"{r.length_mm:g}", str(r.qty), f"{r.diameter_mm:g}", r.material)
    console.print(c)
    console.print(f"Propeller margin: {d.frame.min_prop_margin:.1f} mm (nearest cage rod, core box or propeller). "
                  f"Clearance: {d.frame.clearance_mm:.1f} mm battery holder to ground.")

    if result.drop is not None:
        print_drop(result.drop, console)
    f = getattr(result, "flight", None)
    if f is not None:  # docs/flight.md
        console.print(f"Flight ({f.table}): thrust-to-weight {f.thrust_to_weight:.2f}, hover at {f.hover_throttle * 100:.0f} % "
                      f"throttle, {f.hover_current_a:.1f} A, {f.hover_time_min:.1f} min on {f.usable_mah:.0f} mAh usable")
    for n in getattr(result, "notes", ()):
        console.print(f"[yellow]note:[/] {n}")
    for w in getattr(result, "warnings", ()):
        console.print(f"[yellow]WARN:[/] {w}")
    if result.problems:
        for p in result.problems:
            console.print(f"[red]problem:[/] {p}")
    style = "bold green" if result.verdict == "PASS" else "bold red"
    console.print(f"[{style}]{result.verdict}[/]")


def print_drop(drop, console: Console) -> None:
    console.print(f"Drop model: k = {drop.k_n_per_m:.0f} N/m ({drop.k_source}), c = {drop.c_n_s_per_m:.1f} N s/m "
                  f"({drop.c_source}), damping ratio {drop.damping_ratio:.3f}, m = {drop.mass_kg:.3f} kg, "
                  f"clearance {drop.clearance_mm:.1f} mm")
    t = Table()
    for col in ("drop cm", "x_max mm", "peak G", "spring %", "damper %", "rigid %", "holder strikes"):
        t.add_column(col, justify="right")
    for h in drop.heights:
        t.add_row(f"{h.height_cm:g}", f"{h.x_max_mm:.2f}", f"{h.peak_g:.1f}", f"{h.energy_spring_pct:.1f}",
                  f"{h.energy_damper_pct:.1f}", f"{h.energy_rigid_pct:.1f}", "[red]yes[/]" if h.strikes else "no")
    console.print(t)
    console.print(f"Max safe drop height: {drop.max_safe_height_cm:.1f} cm")
