"""report.html (self-contained, images embedded as base64 PNG) and report.md (images beside it).

Every number about the design comes from `verdict.check_dict(result)`, the same dict that
`cogniframe check --json` prints, formatted with fixed rounding (see `FORMATS`); key figures
carry a `data-key` attribute (`mass.total_g`, `drop.k_n_per_m` ...) so tests and scripts can
read them back. Sections: verdicts, the interactive 3D view (`report/viewer/`), mass budget (+ chart), stiffness and drop model (+ plots),
cut list and stock plan, BOM, print plates and slicer check, assembly steps, renders.
No timestamps: the same inputs give the same files.
"""

from __future__ import annotations

import base64
import html
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Mapping, Sequence

from ..analysis.constants import G

if TYPE_CHECKING:
    from ..export.plates import PlateFile
    from ..export.slicer import SliceReport
    from ..analysis.verdict import Findings
    from .assembly_steps import Step
    from .bom import BomLine
    from .viewer import ViewerItem

# data-key -> format of the value taken from check_dict (dotted path)
FORMATS: dict[str, str] = {
    "mass.total_g": "{:.2f}",
    "mass.limit_g": "{:g}",
    "mass.margin_g": "{:+.2f}",
    "drop.k_n_per_m": "{:.0f}",
    "drop.c_n_s_per_m": "{:.1f}",
    "drop.damping_ratio": "{:.3f}",
    "drop.mass_kg": "{:.3f}",
    "drop.clearance_mm": "{:.1f}",
    "drop.max_safe_height_cm": "{:.1f}",
    "frame.clearance_mm": "{:.1f}",
}
FILES_DIR = "report_files"


def lookup(d: Mapping, dotted: str):
    cur = d
    for k in dotted.split("."):
        cur = cur[k]
    return cur


def fmt_key(d: Mapping, dotted: str) -> str:
    """A check_dict value formatted as the report shows it ('-' when missing or infinite)."""
    try:
        v = lookup(d, dotted)
    except (KeyError, TypeError):
        return "-"
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return FORMATS[dotted].format(v)


@dataclass(frozen=True)
class Table:
    id: str
    title: str
    headers: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    numeric: tuple[int, ...] = ()  # right-aligned columns
    footer: tuple[str, ...] | None = None
    # a last column of pictures, one tuple of (caption, PNG) per row (the assembly steps' views)
    pictures: tuple[tuple[tuple[str, Path], ...], ...] = ()


@dataclass(frozen=True)
class Verdict:
    key: str  # mass | crash | printability | overall
    label: str
    status: str  # PASS | FAIL | WARN | N/A
    detail_html: str
    detail_md: str


# -- figures ---------------------------------------------------------------------------------

def plot_mass_groups(mass: Mapping, path: Path) -> Path:
    """Bar chart of the mass budget by group, with the total against the limit. 700 x 400 px."""
    from .drop_plots import _figure, _save

    fig, axes = _figure(7.0, 4.0)
    ax = axes[0, 0]
    groups = list(mass["groups"].items())
    names = [g for g, _ in groups] + ["total"]
    vals = [v for _, v in groups] + [mass["total_g"]]
    colours = ["#d62728", "#404040", "#1f77b4", "#ff7f0e", "#2ca02c" if mass["margin_g"] >= 0 else "#b00000"]
    bars = ax.bar(names, vals, color=colours[: len(vals) - 1] + [colours[-1]])
    for b, v in zip(bars, vals):
        ax.text(b.get_x() + b.get_width() / 2, v, f"{v:.1f} g", ha="center", va="bottom", fontsize=9)
    ax.axhline(mass["limit_g"], color="k", linestyle="--", linewidth=1, label=f"limit {mass['limit_g']:g} g")
    ax.set_ylabel("mass (g)")
    ax.set_ylim(0, max(max(vals), mass["limit_g"]) * 1.15)
    ax.set_title(f"Mass budget: {mass['total_g']:.2f} g of {mass['limit_g']:g} g (margin {mass['margin_g']:+.2f} g)")
    ax.legend(loc="upper left", fontsize="small")
    ax.grid(True, axis="y", alpha=0.3)
    return _save(fig, path)


def plot_stiffness(drop: Mapping, path: Path) -> Path:
    """The lumped spring of the drop model: force vs payload deflection up to past the
    clearance, the payload's weight, and each drop height's peak compression. 700 x 450 px."""
    from .drop_plots import _figure, _save

    fig, axes = _figure(7.0, 4.5)
    ax = axes[0, 0]
    k = drop["k_n_per_m"]
    clear = drop["clearance_mm"]
    xs = [h["x_max_mm"] for h in drop["heights"]]
    x_end = max([clear * 1.3] + [x * 1.05 for x in xs])
    ax.plot([0, x_end], [0, k * x_end / 1000], color="tab:blue", label=f"k = {k:.0f} N/m ({drop['k_source']})")
    w = drop["mass_kg"] * G
    ax.axhline(w, color="0.5", linestyle=":", label=f"payload weight {w:.2f} N")
    ax.axvline(clear, color="k", linestyle="--", linewidth=1, label=f"clearance {clear:.1f} mm")
    for h in drop["heights"]:
        ax.plot([h["x_max_mm"]], [k * h["x_max_mm"] / 1000], "o", color="tab:red" if h["strikes"] else "tab:green")
        ax.annotate(f"{h['height_cm']:g} cm", (h["x_max_mm"], k * h["x_max_mm"] / 1000), textcoords="offset points",
                    xytext=(4, -10), fontsize=8)
    ax.set_xlabel("payload deflection x (mm)")
    ax.set_ylabel("spring force k x (N)")
    ax.set_title("Frame stiffness and peak compression per drop height")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize="small")
    return _save(fig, path)


def plot_survival(surv: Mapping, path: Path) -> Path:
    """Each part's margin (strength / load) against the flat-drop height, log scale, with the
    damage line at 1 and the first failure marked. 700 x 450 px."""
    from .drop_plots import _figure, _save

    fig, axes = _figure(7.0, 4.5)
    ax = axes[0, 0]
    hs = surv["heights_cm"]
    colours = ("tab:red", "tab:blue", "tab:green", "tab:orange", "tab:purple", "tab:brown", "tab:pink", "tab:olive")
    shown = surv["margins"][:len(colours)]  # the weakest: the series are sorted worst first
    for colour, m in zip(colours, shown):
        pts = [(h, v) for h, v in zip(hs, m["margin"]) if v is not None]
        if pts:
            ax.plot([h for h, _ in pts], [v for _, v in pts], color=colour, linewidth=1.4, label=f"{m['part']}: {m['mode']}")
    ax.axhline(1.0, color="k", linestyle="--", linewidth=1, label="damage (margin 1)")
    f = surv["first_failure"]
    if f is not None:
        ax.axvline(f["at_drop_cm"], color="0.4", linestyle=":", linewidth=1)
    ax.set_yscale("log")
    ax.set_xlabel("flat drop height (cm)")
    ax.set_ylabel("margin = strength / load")
    ax.set_title("What breaks first: " + (f"{f['part']} ({f['mode']}) at {f['at_drop_cm']:g} cm" if f is not None
                                          else f"nothing up to {surv['max_undamaged_drop_cm']:g} cm"))
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper right", fontsize="x-small")
    return _save(fig, path)


def survival_words(surv: Mapping) -> str:
    """The survival sweep in one sentence."""
    f = surv["first_failure"]
    if f is None:
        worst = surv["margins"][0] if surv["margins"] else None
        tail = (f"; the weakest is {worst['part']} ({worst['mode']}), margin "
                f"{min(x for x in worst['margin'] if x is not None):.2f}" if worst and any(x is not None for x in worst["margin"]) else "")
        return f"nothing fails in flat drops up to {surv['max_undamaged_drop_cm']:g} cm{tail}"
    return f"first to fail: {f['part']} ({f['mode']}) at {f['at_drop_cm']:g} cm"


def draw_figures(result: "Findings", files: Path) -> dict[str, list[tuple[str, Path]]]:
    """Draw the report's charts into `files` (FIGURES: section -> (caption, file name))."""
    from ..analysis.verdict import check_dict

    cd = check_dict(result)
    files = Path(files)
    figs: dict[str, list[tuple[str, Path]]] = {"mass": [("mass by group", plot_mass_groups(cd["mass"], files / "mass_by_group.png"))]}
    if result.drop is not None:
        from .drop_plots import plot_drop_response, plot_energy_split

        figs["drop"] = [("stiffness", plot_stiffness(cd["drop"], files / "stiffness.png")),
                        ("drop response", plot_drop_response(result.drop, files / "drop_response.png")),
                        ("energy split", plot_energy_split(result.drop, files / "energy_split.png"))]
    if "survival" in cd:
        figs["survival"] = [("survival margins", plot_survival(cd["survival"], files / "survival_margins.png"))]
    return figs


# -- content ---------------------------------------------------------------------------------

def _verdicts(result: "Findings", cd: Mapping, plates, slice_report) -> list[Verdict]:
    out = []
    m = cd["mass"]
    total, limit, margin = (fmt_key(cd, k) for k in ("mass.total_g", "mass.limit_g", "mass.margin_g"))
    ok = m["total_g"] <= m["limit_g"]
    out.append(Verdict("mass", "Mass", "PASS" if ok else "FAIL",
                       f'all-up weight <b data-key="mass.total_g">{total}</b> g vs limit <span data-key="mass.limit_g">{limit}</span> g '
                       f'(margin <span data-key="mass.margin_g">{margin}</span> g)',
                       f"all-up weight {total} g vs limit {limit} g (margin {margin} g)"))
    spec = result.design.spec
    if "drop" in cd:
        d = cd["drop"]
        design_h = spec.requirements.design_drop_height_cm
        safe = d["max_safe_height_cm"]
        ok = safe is None or design_h <= safe
        at = [h for h in d["heights"] if h["height_cm"] == design_h]
        xm = f"; at {design_h:g} cm the payload travels {at[0]['x_max_mm']:.2f} mm" if at else ""
        h_safe, clr, k = (fmt_key(cd, key) for key in ("drop.max_safe_height_cm", "drop.clearance_mm", "drop.k_n_per_m"))
        out.append(Verdict("crash", "Crash margin", "PASS" if ok else "FAIL",
                           f'max safe drop <b data-key="drop.max_safe_height_cm">{h_safe}</b> cm vs design drop {design_h:g} cm '
                           f'(clearance <span data-key="drop.clearance_mm">{clr}</span> mm{html.escape(xm)}; '
                           f'k = <span data-key="drop.k_n_per_m">{k}</span> N/m)',
                           f"max safe drop {h_safe} cm vs design drop {design_h:g} cm (clearance {clr} mm{xm}; k = {k} N/m)"))
    else:
        out.append(Verdict("crash", "Crash margin", "N/A", "drop model not evaluated", "drop model not evaluated"))
    if plates:
        n = len(plates)
        copies = sum(len(p.copies) for p in plates)
        text = f"{copies} printed parts fit on {n} plate{'s' if n != 1 else ''} of the {spec.printer.bed[0]:g} x {spec.printer.bed[1]:g} x {spec.printer.bed[2]:g} mm bed"
        status = "PASS"
        if slice_report is None:
            text += "; not sliced (no prusa-slicer)"
        else:
            text += f"; PrusaSlicer sliced every plate: {slice_report.total_g:.1f} g, {_dur(slice_report.total_time_s)}"
            if slice_report.warnings:
                status = "WARN"
                text += f"; {len(slice_report.warnings)} warning(s) below"
        out.append(Verdict("printability", "Printability", status, html.escape(text), text))
    else:
        out.append(Verdict("printability", "Printability", "N/A", "no print plates (run `cogniframe build`)",
                           "no print plates (run `cogniframe build`)"))
    if "survival" in cd:
        words = survival_words(cd["survival"])
        f = cd["survival"]["first_failure"]
        ok = f is None or f["at_drop_cm"] > spec.requirements.design_drop_height_cm
        if not ok:
            words += f", below the {spec.requirements.design_drop_height_cm:g} cm design drop"
        out.append(Verdict("survival", "What breaks first", "PASS" if ok else "WARN", html.escape(words), words))
    flags = cd.get("flight", {}).get("resonance_flags")
    if flags is not None:  # the frame's modes against the rotors and the attitude loop: WARN, never FAIL
        text = (f"{len(flags)} frame mode(s) within 15 % of a rotor or attitude-controller band: "
                + ", ".join(f"{f['hz']:.1f} Hz ({f['band']})" for f in flags) if flags else
                "no frame mode within 15 % of a rotor or attitude-controller band")
        out.append(Verdict("resonance", "Vibration against the motors", "WARN" if flags else "PASS", html.escape(text), text))
    out.append(Verdict("overall", "Design verdict", cd["verdict"],
                       html.escape("; ".join(cd["problems"]) or "all requirements met"),
                       "; ".join(cd["problems"]) or "all requirements met"))
    return out


def _dur(s: float) -> str:
    from ..export.slicer import format_duration

    return format_duration(s)


def _tables(result: "Findings", cd: Mapping, bom, steps, plates, slice_report,
            step_pictures: Mapping[int, Sequence[Path]] | None = None) -> dict[str, Table]:
    t: dict[str, Table] = {}
    m = cd["mass"]
    t["mass-budget"] = Table("mass-budget", "Mass budget", ("item", "group", "qty", "g each", "g", "material", "source"),
                             tuple((i["name"], i["group"], str(i["qty"]), f"{i['mass_g_each']:.3f}", f"{i['mass_g']:.2f}",
                                    i["material"] or "", i["source"]) for i in m["items"]),
                             (2, 3, 4), ("all-up weight", "", "", "", f"{m['total_g']:.2f}", "", ""))
    t["mass-groups"] = Table("mass-groups", "By group and material", ("group", "g"),
                             tuple((g, f"{v:.2f}") for g, v in m["groups"].items())
                             + tuple((f"material: {k}", f"{v:.2f}") for k, v in m["by_material"].items()), (1,))
    if "drop" in cd:
        d = cd["drop"]
        t["drop-model"] = Table("drop-model", "Drop model parameters", ("quantity", "value"), (
            ("stiffness k (N/m)", f"{fmt_key(cd, 'drop.k_n_per_m')} ({d['k_source']})"),
            ("damping c (N s/m)", f"{fmt_key(cd, 'drop.c_n_s_per_m')} ({d['c_source']})"),
            ("damping ratio", fmt_key(cd, "drop.damping_ratio")),
            ("mass (kg)", fmt_key(cd, "drop.mass_kg")),
            ("clearance (mm)", fmt_key(cd, "drop.clearance_mm")),
            ("max safe drop (cm)", fmt_key(cd, "drop.max_safe_height_cm"))), (1,))
        t["drop"] = Table("drop", "Drop heights", ("drop cm", "v m/s", "x_max mm", "peak G", "spring %", "damper %", "rigid %", "holder strikes"),
                          tuple((f"{h['height_cm']:g}", f"{h['v_impact_m_per_s']:.2f}", f"{h['x_max_mm']:.2f}", f"{h['peak_g']:.1f}",
                                 f"{h['energy_spring_pct']:.1f}", f"{h['energy_damper_pct']:.1f}", f"{h['energy_rigid_pct']:.1f}",
                                 "yes" if h["strikes"] else "no") for h in d["heights"]), (0, 1, 2, 3, 4, 5, 6))
    t["props"] = Table("props", "Propeller margins", ("motor", "to cage mm", "to core mm", "to next prop mm"),
                       tuple((p["motor"], f"{p['to_cage_mm']:.1f}", f"{p['to_core_mm']:.1f}", f"{p['to_neighbour_mm']:.1f}")
                             for p in cd["frame"]["prop_margin_mm"]), (1, 2, 3))
    t["cutlist"] = Table("cutlist", "Cut list", ("role", "cut length mm", "qty", "diameter mm", "material", "g each", "rods"),
                         tuple((r["role"], f"{r['length_mm']:g}", str(r["qty"]), f"{r['diameter_mm']:g}", r["material"],
                                f"{r['mass_g_each']:.3f}", " ".join(r["rods"])) for r in cd["cutlist"]), (1, 2, 3, 5))
    st = cd["stock"]
    t["stock"] = Table("stock", f"Stock plan: {st['count']} x {st['stock_length_mm']:g} mm (kerf {st['kerf_mm']:g} mm, lower bound {st['lower_bound']})",
                       ("stock rod", "cuts mm", "offcut mm"),
                       tuple((str(r["index"]), " + ".join(f"{c:g}" for c in r["cuts_mm"]), f"{r['offcut_mm']:g}") for r in st["rods"]), (0, 2))
    if bom:
        from .bom import COLUMNS, _row, total_g

        t["bom"] = Table("bom", "Bill of materials", COLUMNS, tuple(tuple(_row(ln)) for ln in bom), (2, 5, 6, 7, 8),
                         ("total", "", str(sum(ln.qty for ln in bom)), "", "", "", f"{total_g(bom):.2f}", "", "", ""))
    if plates:
        sliced = {p.plate: p for p in slice_report.plates} if slice_report else {}
        t["plates"] = Table("plates", "Print plates", ("plate", "material", "parts", "file", "sliced g", "print time"),
                            tuple((p.name, p.material, ", ".join(p.copies), p.threemf.name,
                                   f"{sliced[p.name].grams:.1f}" if p.name in sliced else "",
                                   _dur(sliced[p.name].time_s) if p.name in sliced else "") for p in plates), (4, 5))
    if slice_report is not None:
        t["slicer"] = Table("slicer", f"Slicer check ({slice_report.slicer})", ("material", "sliced g", "estimated g", "difference", "print time", "flag"),
                            tuple((c.material, f"{c.sliced_g:.1f}", "" if c.estimated_g is None else f"{c.estimated_g:.1f}",
                                   "" if c.diff_pct is None else f"{c.diff_pct:+.1f} %", _dur(c.time_s),
                                   "over 10 %" if c.flagged else "ok") for c in slice_report.materials), (1, 2, 3, 4))
    if steps:
        pictures = tuple(tuple((f"step {s.number}: {s.title}" + (" (exploded)" if Path(f).stem.endswith("_exploded") else ""),
                                Path(f)) for f in step_pictures.get(s.number, ())) for s in steps) if step_pictures else ()
        t["assembly"] = Table("assembly", "Assembly steps", ("step", "what", "parts", "rods (cut length)", "glue")
                              + (("pictures (new parts in orange)",) if pictures else ()),
                              tuple((str(s.number), f"{s.title}: {s.text}", ", ".join(s.parts),
                                     ", ".join(f"{n} ({length:g} mm)" for n, length in s.rods), s.glue) for s in steps), (0,),
                              pictures=pictures)
    return t


# -- writers ---------------------------------------------------------------------------------

CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}
h1{margin-bottom:.2em} h2{border-bottom:2px solid #ddd;padding-bottom:.2em;margin-top:2em}
table{border-collapse:collapse;margin:.8em 0;font-size:.9em} th,td{border:1px solid #ccc;padding:.25em .5em;vertical-align:top}
th{background:#f3f3f3;text-align:left} td.n{text-align:right;font-variant-numeric:tabular-nums} tfoot td{font-weight:bold}
.PASS{background:#d9f2d9} .FAIL{background:#f7d4d4} .WARN{background:#fbefc9} .N\\/A{background:#eee}
.status{font-weight:bold;padding:.1em .5em;border-radius:3px} img{max-width:100%;border:1px solid #ddd;margin:.3em 0}
figure{display:inline-block;margin:.5em;vertical-align:top} figcaption{font-size:.85em;color:#555}
td figure{margin:.2em} td img{width:320px}
.warn{color:#8a5a00}
"""


def _stiffness_blocks(cd: Mapping) -> list:
    """The `stiffness` section of check --json as one table and a note (wall, thrust, modes,
    buckling, TPU strain and its fatigue caveat, predicted peak deceleration)."""
    s = cd["stiffness"]
    t, w, st = s["thrust"], s["wall"], s["strain"]
    rows = [("payload stiffness k (N/m)", f"{s['k_n_per_m']:.0f} (joints: {s['joint_model']}, printed TPU at {s['tpu_modulus_factor']:g} x datasheet)"),
            ("side-on (wall) stiffness (N/m)", f"{s['k_lateral_n_per_m']:.0f}"),
            ("highest wall speed (m/s)", f"{w['max_wall_speed_m_s']:.1f} (then the {w['limited_by']} reaches the wall)"),
            ("motor deflection, hover / full thrust", f"{t['motor_deflection_hover_mm']:.2f} / {t['motor_deflection_mm']:.2f} mm, "
                                                      f"tilt {t['motor_tilt_hover_deg']:.2f} / {t['motor_tilt_deg']:.2f} deg"),
            ("arms alone, hover / full thrust", f"{t['arms_only_motor_deflection_hover_mm']:.1f} / {t['arms_only_motor_deflection_mm']:.1f} mm, "
                                                f"tilt {t['arms_only_motor_tilt_hover_deg']:.0f} / {t['arms_only_motor_tilt_deg']:.0f} deg"
                                                + ("" if t["arms_only_small_rotation"] else
                                                   " (beyond the linear model's small rotations: the arms fold on the core link's TPU tab"
                                                   + (f"; {t['arms_only_motor_tilt_deg_tpu_datasheet']:.0f} deg with datasheet TPU)"
                                                      if "arms_only_motor_tilt_deg_tpu_datasheet" in t else ")"))
                                                + f"; the exoskeleton stiffens the arms {t['exoskeleton_stiffening']:.0f} times"),
            ("first modes (Hz)", ", ".join(f"{f:.1f}" for f in s["modes_hz"][:6]) + f" (rotor at hover {s['hover_rotor_hz']:.0f} Hz"
             + (f"; mode {s['mode_near_rotor']['mode']} within 15 %)" if s["mode_near_rotor"] else ")")),
            ("min buckling margin", f"{s['min_buckling_margin']:.2f} ({s['critical_rod']}, at the {s['design_drop_height_cm']:g} cm design drop)"
             if s["min_buckling_margin"] is not None else "no rod in compression"),
            ("peak TPU strain at the design drop", f"hinge {100 * st['hinge']:.1f} %, sockets {100 * st['socket']:.1f} % "
                                                    f"(elongation at break {100 * st['elongation_at_break']:.0f} %)")]
    if "peak_g" in cd:
        pk = cd["peak_g"]
        rows.append((f"predicted peak |a| ({pk['model']}, logger), mean pulse", ", ".join(f"{h['height_cm']:g} cm: {h['peak_g']:.0f} G" for h in pk["heights"])))
        if all("peak_g_drop_median" in h for h in pk["heights"]):  # what one drop records: a distribution
            rows.append(("peak |a| of one drop, median (90th percentile)",
                         ", ".join(f"{h['height_cm']:g} cm: {h['peak_g_drop_median']:.0f} G ({h['peak_g_drop_p90']:.0f} G)" for h in pk["heights"])))
    note = ("Fatigue: TPU living hinges and sockets flex on every crash; the strain above is a single-event check against "
            "breaking. How many crashes a printed TPU hinge survives is not known (the paper names it as the open question): "
            "inspect the knee hinges after hard landings and reprint them when they whiten or crack.")
    return [Table("load-cases", "Load cases", ("quantity", "value"), tuple(rows), ()), ("p", note)]


def _survival_blocks(cd: Mapping) -> list:
    """The survival sweep: the sentence, and each part's margin at the design drop and where it
    reaches 1."""
    sv = cd["survival"]
    design_h = cd.get("stiffness", {}).get("design_drop_height_cm")
    i = sv["heights_cm"].index(design_h) if design_h in sv["heights_cm"] else None
    rows = []
    for m in sv["margins"]:
        at = m["margin"][i] if i is not None else None
        limit = f"{100 * m['limit']:.0f} % elongation" if m["unit"] == "strain" else f"{m['limit']:g} {m['unit']}"
        rows.append((m["part"], m["mode"], limit, "-" if at is None else f"{at:.2f}",
                     "-" if m["fails_at_drop_cm"] is None else f"{m['fails_at_drop_cm']:g}"))
    head = ("part", "mode", "strength", f"margin at {design_h:g} cm" if i is not None else "margin", "fails from (cm)")
    return [("p", survival_words(sv) + ". " + sv["note"] + "."), Table("survival-margins", "Margins", head, tuple(rows), ())]


def _html_table(t: Table) -> str:
    out = [f'<table id="{t.id}"><caption>{html.escape(t.title)}</caption><thead><tr>']
    out += [f"<th>{html.escape(h)}</th>" for h in t.headers]
    out.append("</tr></thead><tbody>")
    for r, row in enumerate(t.rows):
        pics = ("<td>" + "".join(_img_html(path, caption, "step-exploded" if caption.endswith("(exploded)") else "step-view")
                                 for caption, path in t.pictures[r]) + "</td>") if t.pictures else ""
        out.append("<tr>" + "".join(f'<td{" class=n" if i in t.numeric else ""}>{html.escape(c)}</td>' for i, c in enumerate(row))
                   + pics + "</tr>")
    out.append("</tbody>")
    if t.footer:
        out.append("<tfoot><tr>" + "".join(f'<td{" class=n" if i in t.numeric else ""}>{html.escape(c)}</td>' for i, c in enumerate(t.footer)) + "</tr></tfoot>")
    out.append("</table>")
    return "".join(out)


def _md_table(t: Table) -> str:
    def cell(c: str) -> str:
        return c.replace("|", "/").replace("\n", " ")

    out = [f"**{t.title}**", "", "| " + " | ".join(t.headers) + " |",
           "|" + "|".join("---:" if i in t.numeric else "---" for i in range(len(t.headers))) + "|"]
    out += ["| " + " | ".join(cell(c) for c in row) + " |" for row in t.rows]
    if t.footer:
        out.append("| " + " | ".join(cell(c) for c in t.footer) + " |")
    return "\n".join(out) + "\n"


def _img_html(path: Path, caption: str, css_class: str = "") -> str:
    data = base64.b64encode(Path(path).read_bytes()).decode("ascii")
    cls = f' class="{css_class}"' if css_class else ""
    return (f'<figure><img{cls} src="data:image/png;base64,{data}" alt="{html.escape(caption)}">'
            f"<figcaption>{html.escape(caption)}</figcaption></figure>")


def _img_md(path: Path, caption: str, base: Path) -> str:
    rel = Path(os.path.relpath(Path(path).resolve(), base.resolve())).as_posix()
    return f"![{caption}]({rel})"


def write_report(result: "Findings", out_dir: Path | str, images: Mapping[str, Path] | None = None,
                 bom: Sequence["BomLine"] = (), steps: Sequence["Step"] = (), plates: Sequence["PlateFile"] = (),
                 slice_report: "SliceReport | None" = None,
                 figures: Mapping[str, Sequence[tuple[str, Path]]] | None = None,
                 viewer_items: Sequence["ViewerItem"] = (), viewer_html: str | None = None,
                 flight_files: Sequence[str] = (), step_pictures: Mapping[int, Sequence[Path]] | None = None) -> tuple[Path, Path]:
    """Write `report.html` and `report.md` into out_dir (charts go to out_dir/report_files/).

    `figures`: {"mass": [(caption, png)], "drop": [...]} already drawn (the build draws and caches
    them as steps); None draws them here with `draw_figures`.

    `images`: caption -> PNG (renders of the assembly and parts), shown in the given order.
    `step_pictures`: each assembly step's pictures (report/step_views.py), beside its text.
    `plates`: what `write_plates` returned (their preview PNGs are shown).
    `viewer_items`: the assembly as named meshes (`viewer.design_items` + any vitamins): an
    interactive 3D view right under the verdicts (HTML only). `viewer_html`: that section already
    made (`viewer.viewer_section`; the build caches it as a step), instead of `viewer_items`.
    Returns (html, md)."""
    from ..analysis.verdict import check_dict

    out_dir = Path(out_dir)
    files = out_dir / FILES_DIR
    files.mkdir(parents=True, exist_ok=True)
    cd = check_dict(result)
    name = cd["name"]
    figs = dict(figures) if figures is not None else draw_figures(result, files)
    verdicts = _verdicts(result, cd, plates, slice_report)
    tables = _tables(result, cd, bom, steps, plates, slice_report, step_pictures)
    warnings = list(slice_report.warnings) if slice_report is not None else []
    if slice_report is not None:
        from ..export.slicer import sliced_total_g

        with_sliced = sliced_total_g(result.mass, slice_report)
        if with_sliced > result.mass.limit_g >= result.mass.total_g:  # (over by the budget already: the mass verdict says so)
            warnings.append(f"with the slicer's filament grams the all-up weight is {with_sliced:.1f} g, over the "
                            f"{result.mass.limit_g:g} g limit (the budget's estimate says {result.mass.total_g:.1f} g)")

    sections: list[tuple[str, str, list]] = []  # (id, title, blocks) ; block = Table | ("img", caption, path) | ("p", text)
    sections.append(("mass", "Mass budget", [tables["mass-budget"], tables["mass-groups"], *[("img", c, p) for c, p in figs["mass"]]]))
    if "drop" in tables:
        sections.append(("crash", "Stiffness and drop model", [tables["drop-model"], tables["drop"],
                                                               *[("img", c, p) for c, p in figs.get("drop", [])]]))
    if "stiffness" in cd:
        sections.append(("load-cases", "Frame load cases", _stiffness_blocks(cd)))
    if "survival" in cd:
        if "survival" not in figs:  # drawn here: the build's figure steps draw the mass and drop charts
            figs["survival"] = [("survival margins", plot_survival(cd["survival"], files / "survival_margins.png"))]
        sections.append(("survival", "What breaks first", _survival_blocks(cd) + [("img", c, p) for c, p in figs["survival"]]))
    sections.append(("frame", "Frame", [tables["props"], ("p", f"Battery holder clearance above the ground: {fmt_key(cd, 'frame.clearance_mm')} mm; "
                                                             f"{cd['frame']['rods']} rods, {cd['frame']['joints']} joints.")]))
    sections.append(("cuts", "Cut list and stock plan", [tables["cutlist"], tables["stock"]]))
    if "bom" in tables:
        sections.append(("bom-section", "Bill of materials", [tables["bom"]]))
    if plates:
        blocks: list = [tables["plates"]]
        if "slicer" in tables:
            blocks.append(tables["slicer"])
        blocks += [("warn", w) for w in warnings]
        blocks += [("img", f"plate {p.name}", p.preview) for p in plates]
        sections.append(("plates-section", "Print plates", blocks))
    if "assembly" in tables:
        sections.append(("assembly-section", "Assembly", [tables["assembly"]]))
    if flight_files or "flight" in figs:
        sections.append(("flight", "Fly it: flight-controller setup, simulator models, vibration", _flight_blocks(cd, flight_files, figs)))
    if images:
        sections.append(("renders", "Renders", [("img", c, p) for c, p in images.items()]))

    if viewer_html is None:
        viewer_html = ""
        if viewer_items:
            from .viewer import viewer_section

            viewer_html = viewer_section(viewer_items)
    html_path, md_path = out_dir / "report.html", out_dir / "report.md"
    html_path.write_text(_render_html(name, cd, verdicts, sections, warnings, viewer_html), encoding="utf-8")
    md = _render_md(name, cd, verdicts, sections, warnings, out_dir)
    if viewer_html:  # the 3D view needs a browser: point there from the Markdown twin
        md = md.replace("\n## ", "\nThe interactive 3D view of the assembly is in report.html (open it in a browser).\n\n## ", 1)
    md_path.write_text(md, encoding="utf-8")
    return html_path, md_path


FLIGHT_FILE_WHAT = {
    "inav.txt": "INAV CLI: motor mix and gyro filters (paste into the Configurator's CLI tab)",
    "betaflight.txt": "Betaflight CLI: motor mix and gyro filters",
    "ardupilot/frame.json": "ArduPilot SITL frame model (sim_vehicle.py -f quad --model quad:frame.json)",
    "ardupilot/params.parm": "ArduCopter frame, hover thrust, harmonic notch",
    "px4/sih.params": "PX4 SIH simulator: mass, inertia, thrust and torque limits, arm lengths",
    "px4/10090_sihsim_cogniframe": "PX4 SIH airframe: control allocation, motor outputs, SIH vehicle, hover thrust, gyro filters",
    "gazebo/model.sdf": "gz-sim (Harmonic) model with the multicopter motor model system", "gazebo/model.config": "Gazebo model description",
    "rotorpy.json": "rotorpy vehicle parameters (Multirotor, SE3Control)",
    "resonance.json": "frame modes, flight-controller participation, rotor and controller bands, flags, filter advice",
    "resonance.png": "Campbell diagram",
}


def _flight_blocks(cd: Mapping, files: Sequence[str], figs: Mapping) -> list:
    f = cd.get("flight", {})
    blocks: list = []
    if "cg_mm" in f:
        cg, i = f["cg_mm"], f["inertia_kg_m2"]
        blocks.append(("p", f"Centre of gravity (x, y, z) {cg[0]:.1f}, {cg[1]:.1f}, {cg[2]:.1f} mm; inertia about it "
                            f"Ixx {i[0][0]:.3g}, Iyy {i[1][1]:.3g}, Izz {i[2][2]:.3g} kg m^2 (part-list estimates; the files "
                            "below use the CAD solids)."))
    blocks += [("warn", w) for w in cd.get("warnings", [])]
    if files:
        blocks.append(("links", [(p, FLIGHT_FILE_WHAT.get(p.removeprefix("flight/"), "")) for p in files]))
    blocks += [("img", c, p) for c, p in figs.get("flight", [])]
    return blocks


def _render_html(name: str, cd: Mapping, verdicts: list[Verdict], sections, warnings: list[str], viewer_html: str = "") -> str:
    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
           f"<title>cogniframe report: {html.escape(name)}</title>", f"<style>{CSS}</style></head><body>",
           f"<h1>cogniframe report: {html.escape(name)}</h1>",
           f'<p>Verdict: <span class="status {cd["verdict"]}" data-key="verdict">{cd["verdict"]}</span></p>',
           '<table id="verdicts"><caption>Verdicts</caption><thead><tr><th>check</th><th>status</th><th>detail</th></tr></thead><tbody>']
    for v in verdicts:
        out.append(f'<tr id="verdict-{v.key}"><td>{html.escape(v.label)}</td><td class="status {v.status}">{v.status}</td><td>{v.detail_html}</td></tr>')
    out.append("</tbody></table>")
    for w in warnings:
        out.append(f'<p class="warn">warning: {html.escape(w)}</p>')
    if viewer_html:
        out.append(viewer_html)
    nav = ([("viewer-section", "3D view")] if viewer_html else []) + [(sid, title) for sid, title, _ in sections]
    out.append("<nav><ul>" + "".join(f'<li><a href="#{sid}">{html.escape(title)}</a></li>' for sid, title in nav) + "</ul></nav>")
    for sid, title, blocks in sections:
        out.append(f'<section id="{sid}"><h2>{html.escape(title)}</h2>')
        for b in blocks:
            if isinstance(b, Table):
                out.append(_html_table(b))
            elif b[0] == "img":
                out.append(_img_html(b[2], b[1]))
            elif b[0] == "warn":
                out.append(f'<p class="warn">warning: {html.escape(b[1])}</p>')
            elif b[0] == "links":
                out.append("<ul>" + "".join(f'<li><a href="{html.escape(p)}">{html.escape(p)}</a>: {html.escape(t)}</li>'
                                            for p, t in b[1]) + "</ul>")
            else:
                out.append(f"<p>{html.escape(b[1])}</p>")
        out.append("</section>")
    out.append("<footer><p>Generated by cogniframe from the params file; numbers as in <code>cogniframe check --json</code>.</p></footer>")
    out.append("</body></html>")
    return "\n".join(out) + "\n"


def _render_md(name: str, cd: Mapping, verdicts: list[Verdict], sections, warnings: list[str], base: Path) -> str:
    out = [f"# cogniframe report: {name}", "", f"Verdict: **{cd['verdict']}**", "", "| check | status | detail |", "|---|---|---|"]
    out += [f"| {v.label} | {v.status} | {v.detail_md.replace('|', '/')} |" for v in verdicts]
    out.append("")
    out += [f"> warning: {w}" for w in warnings]
    for sid, title, blocks in sections:
        out += ["", f"## {title}", ""]
        for b in blocks:
            if isinstance(b, Table):
                out.append(_md_table(b))
                for pics in b.pictures:  # a table cell holds no picture in Markdown: each step's under the table
                    out += [_img_md(path, caption, base) for caption, path in pics] + [""]
            elif b[0] == "img":
                out += [_img_md(b[2], b[1], base), ""]
            elif b[0] == "warn":
                out += [f"> warning: {b[1]}", ""]
            elif b[0] == "links":
                out += [f"- [{p}]({p}): {t}" for p, t in b[1]] + [""]
            else:
                out += [b[1], ""]
    return "\n".join(out).rstrip() + "\n"
