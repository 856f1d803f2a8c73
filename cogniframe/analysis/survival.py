"""What breaks first: flat drops of increasing height against each part's strength.

For each height of the sweep the drop model (`impact.simulate_height`) gives two loads: what
deforms the joints, the spring's force k min(x_max, clearance) (the payload's compression stops
at the clearance, where the battery holder reaches the floor and takes the rest as a rigid
strike), and what the frame carries to the floor, spring and damper together, the payload's peak
deceleration times its mass, F = m (|a|max + g) (the damper's force is the TPU's viscous stress:
it goes through the rods and the core as the spring's does). The frame model
(`load_cases.survival_influence`: the payload case per newton, the damping taken to load the
frame as its stiffness does) turns them into

- each TPU joint's peak strain (sockets' bearing, the knee's living hinge; from k x) against
  the elastomer's elongation at break;
- each rod's peak bending + axial stress against its flexural strength, and its compression
  against its Euler load (from F);
- the core plate's bending stress where a core link loads its corner, against the core
  plastic's yield stress (from F);

and, once the holder strikes with the speed v_s left at the clearance, the holder's contact
stress as a flat plane-wave impact on a rigid floor, sigma = v_s sqrt(E rho) (an elastic bar
meeting a rigid wall: the largest stress a flat face sees before it yields), against the same
yield stress. The payload's peak G (the peak model's single-drop median when it has one, else
its mean-pulse peak) is checked against `requirements.max_peak_g` when set. Strengths are
`materials.STRENGTHS` (datasheet and handbook values), never fitted to a drop outcome.

A margin is strength / load (>= 1: undamaged). ``max_undamaged_drop_cm`` is the highest sweep
height below which every margin stays >= 1; ``first_failure`` the first part to reach 1, at
the height interpolated between sweep points (linearly in the margin), None if none does
within the sweep.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .. import numfmt

SWEEP_CM = tuple(float(h) for h in range(10, 610, 10))  # 10 cm to 6 m (11 m/s at touch-down)


@dataclass(frozen=True)
class Survival:
    heights_cm: tuple[float, ...]
    max_undamaged_drop_cm: float  # the sweep's top when nothing fails within it
    first_failure: dict | None  # {part, mode, at_drop_cm}
    margins: tuple[dict, ...]  # {part, mode, limit, unit, margin: [per height]}, worst first
    note: str

    def to_dict(self) -> dict:
        return {"heights_cm": list(self.heights_cm), "max_undamaged_drop_cm": self.max_undamaged_drop_cm,
                "first_failure": self.first_failure, "margins": list(self.margins), "note": self.note}


def _m(x: float) -> float | None:
    """A margin for JSON: rounded, None when the load is zero (nothing to fail)."""
    return round(x, 4) if math.isfinite(x) else None


def crossing(heights, margins) -> float | None:
    """The height at which a margin series first falls to 1, linear between sweep points; None
    if it never does (a series that starts below 1 fails at its first height)."""
    prev = None
    for h, m in zip(heights, margins):
        if m is not None and m < 1.0:
            if prev is None:
                return float(h)
            h0, m0 = prev
            return float(h0 + (h - h0) * (m0 - 1.0) / (m0 - m))
        prev = (h, m) if m is not None else prev
    return None


def payload_peaks(spec, drop, exo_mass_g: float, heights_cm=SWEEP_CM) -> list[dict]:
    """The peak model's entries over the sweep (`peaks.design_peaks`, the feet at the corners
    of the frame's footprint as `drop.peak_prediction` puts them), cached on disk: a single-drop
    distribution per height is a second or two for the whole sweep."""
    from .. import cache

    footprint = (float(spec.frame.width), float(spec.frame.depth))
    args = (drop.mass_kg, drop.k_n_per_m, drop.c_n_s_per_m, exo_mass_g / 1000.0, list(heights_cm), drop.clearance_mm, footprint)
    key = cache.key(["survival-peaks", args], ("analysis/peaks.py", "analysis/impact_nl.py", "analysis/impact.py", "analysis/single_drop.py",
                                               "analysis/survival.py"))
    hit = cache.load_json("peaks", key)
    if hit is not None:
        return hit["heights"]
    from . import peaks

    out = peaks.design_peaks(*args[:6], footprint_mm=footprint)
    out = {"heights": out["heights"]}
    cache.store_json("peaks", key, out)
    return out["heights"]


def evaluate(spec, frame, drop, stiffness: dict, peaks: list[dict] | None = None, heights_cm=SWEEP_CM) -> Survival:
    """The survival sweep for a design: ``frame`` its frame (each rod's strength is its own
    material's), ``drop`` its `impact.DropResult` (m, c, k, clearance),
    ``stiffness`` its load cases (`check --json`'s stiffness section, with ``survival_per_n``),
    ``peaks`` the peak model's entries for ``heights_cm`` (None: payload G not assessed)."""
    from ..materials import strength

    per_n = stiffness["survival_per_n"]
    springs, forces, strikes = drop_loads(drop, heights_cm)
    series: list[dict] = []

    def add(part: str, mode: str, limit: float, unit: str, loads: list[float]):
        series.append(margin_series(part, mode, limit, unit, loads))

    tpu = strength(spec.joints.material)
    if tpu is not None:
        for part, j in sorted(per_n["joints"].items()):
            add(f"joint {part} ({j['at']})", "TPU strain", tpu.value, "strain", [j["strain_per_n"] * f for f in springs])
    series.extend(rod_series(per_n["rods"], lambda name: strength(frame.rods[name].material), forces))
    core = strength(spec.core.material)
    if core is not None:
        add("core plate", "bending at a core link", core.value, "MPa", [per_n["core_plate_mpa_per_n"] * f for f in forces])
        impedance = strike_impedance_mpa_per_m_s(spec.material(spec.core.material))
        add("battery holder", "strike on the floor", core.value, "MPa", [impedance * v for v in strikes])
    max_g = spec.requirements.max_peak_g
    if max_g is not None and peaks is not None:
        add("payload", "peak G", float(max_g), "G", [p.get("peak_g_drop_median", p["peak_g"]) for p in peaks])

    note = ("flat drops; joints strained by the drop model's spring force (capped where the battery holder reaches the "
            "floor), rods and core loaded by its whole force (spring and damper), both quasi-static in the payload "
            "case's pattern; the holder strike as a plane-wave bound; no fatigue, no tumbling, no edge landings")
    return summarise(series, heights_cm, note)


def drop_loads(drop, heights_cm=SWEEP_CM) -> tuple[list[float], list[float], list[float]]:
    """Per height of the sweep, from the drop model (`drop`: m, c, k, clearance): the spring's
    force that deforms the joints, k min(x_max, clearance) (N); the whole force the frame carries
    to the floor, spring and damper, m (|a|max + g) (N); and the speed at which the holder strikes
    the floor once the clearance is used up (m/s, 0 when it is not)."""
    from .constants import G
    from .impact import simulate_height

    m, k, c, clear = drop.mass_kg, drop.k_n_per_m, drop.c_n_s_per_m, drop.clearance_mm
    springs, forces, strikes = [], [], []
    for h in heights_cm:
        r = simulate_height(m, c, k, h, clear)
        springs.append(k * min(r.x_max_mm, clear) / 1000.0)
        forces.append(m * G * (r.peak_g + 1.0))
        strikes.append(math.sqrt(2 * r.energy_j * r.energy_rigid_pct / 100.0 / m) if r.strikes else 0.0)
    return springs, forces, strikes


def rod_series(rods_per_n: dict, strength_of, forces: list[float]) -> list[dict]:
    """The rods' margin series: per role, its most stressed rod in bending (against
    ``strength_of(name)``, a `materials.Strength` or None) and its rod nearest its Euler load.
    ``rods_per_n``: {rod: {role, stress_mpa_per_n, axial_n_per_n, euler_n}} per newton of ``forces``."""
    out = []
    by_role: dict[str, list[tuple[str, dict]]] = {}
    for name, r in sorted(rods_per_n.items()):
        by_role.setdefault(r["role"], []).append((name, r))
    for role, rods in sorted(by_role.items()):
        # the role's most stressed rod; ties (symmetric rods) go to the first by name: compared at the
        # precision check.json states (numfmt), so the last bits of the solve, which differ between
        # mirror images, do not choose
        name, r = min(rods, key=lambda x: (-numfmt.sig(x[1]["stress_mpa_per_n"]), x[0]))
        rod = strength_of(name)
        if rod is not None:
            out.append(margin_series(f"rod {name}", "bending", rod.value, "MPa", [r["stress_mpa_per_n"] * f for f in forces]))
        buck = [(n, r) for n, r in rods if r["euler_n"] and r["axial_n_per_n"] < 0]
        if buck:
            name, r = min(buck, key=lambda x: (-numfmt.sig(-x[1]["axial_n_per_n"] / x[1]["euler_n"]), x[0]))
            out.append(margin_series(f"rod {name}", "buckling", r["euler_n"], "N", [-r["axial_n_per_n"] * f for f in forces]))
    return out


def margin_series(part: str, mode: str, limit: float, unit: str, loads: list[float]) -> dict:
    """One part's margins over the sweep: strength / load per height (None where it carries nothing)."""
    return {"part": part, "mode": mode, "limit": limit, "unit": unit,
            "margin": [_m(limit / x) if x > 0 else None for x in loads]}


def strike_impedance_mpa_per_m_s(material) -> float:
    """sqrt(E rho) of a `materials.Material`, MPa per m/s: a flat face's plane-wave stress per unit
    strike speed on a rigid floor."""
    return math.sqrt(material.e_mpa * 1e6 * material.density_g_cm3 * 1000.0) / 1e6


def summarise(series: list[dict], heights_cm, note: str) -> Survival:
    """The sweep's verdict from its margin series: the first part to fail (at the stated 0.1 cm,
    then by name), the highest undamaged drop, the series worst first."""
    fails = [(crossing(heights_cm, s["margin"]), s) for s in series]
    failing = [(h, s) for h, s in fails if h is not None]
    if failing:
        h, s = min(failing, key=lambda x: (round(x[0], 1), x[1]["part"]))
        first = {"part": s["part"], "mode": s["mode"], "at_drop_cm": round(h, 1)}
        top = round(h, 1)
    else:
        first, top = None, float(heights_cm[-1])
    for (h, s) in fails:
        s["fails_at_drop_cm"] = round(h, 1) if h is not None else None
    worst = sorted(series, key=lambda s: (s["fails_at_drop_cm"] is None, s["fails_at_drop_cm"] or 0.0,
                                          numfmt.sig(min((x for x in s["margin"] if x is not None), default=math.inf)),
                                          s["part"]))
    return Survival(tuple(heights_cm), top, first, tuple(worst), note)
