"""The verdict of `check`: the mass budget, the drop model, the load cases, peaks and flight for a
design, the requirements they must meet (PASS or FAIL with the problems), and `check --json`.

    design -> mass budget -> drop model -> load cases, peaks, flight -> problems -> verdict
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from ..design import Derived, design
from ..spec import Spec
from . import mass as mass_mod
from .. import numfmt
from .numerics import one_blas_thread


@dataclass(frozen=True)

class Findings:
    design: Derived
    mass: mass_mod.MassBudget
    drop: object | None  # analysis.impact.DropResult once the physics stage is available
    problems: tuple[str, ...]
    stiffness: dict | None = None  # analysis.drop.load_cases: wall, thrust, modes, buckling, strain
    peak: dict | None = None  # analysis.peaks.design_peaks: predicted peak G per drop height
    flight: object | None = None  # analysis.flight.FlightResult
    clash: object | None = None  # analysis.clash.ClashResult, from `build` only
    notes: tuple[str, ...] = ()  # warnings that do not fail the design (joints outside the surrogate's training box)
    survival: object | None = None  # analysis.survival.Survival: what breaks first, at what drop height
    fit: object | None = None  # analysis.fit_check.FitResult: the screws, holes and motor patterns
    flight_model: dict | None = None  # _flight_model: centre of gravity, inertia, resonance flags
    warnings: tuple[str, ...] = ()  # WARN, not FAIL: frame modes near the rotors or in the attitude loop's band

    @property
    def verdict(self) -> str:
        return "FAIL" if self.problems else "PASS"


def check(spec: Spec, geometry: dict | None = None, clash=None, design_: Derived | None = None,
          peaks: bool = True, modes: bool = True, survival_margins: bool = True, session=None) -> Findings:
    """Mass budget, crash margin, flight and requirements; `geometry` = CAD volumes when known,
    `clash` = the build's clash check (analysis.clash.ClashResult) when known, `design_` = this
    spec's design when the caller has it. ``peaks=False`` leaves out the predicted peak
    deceleration per drop height unless `requirements.max_peak_g` needs it for the verdict (a
    sweep records no per-height list: the same verdict, a third of a design's time saved).
    ``modes=False`` leaves out the list of natural frequencies (`stiffness.modes_hz`) and
    decides `stiffness.mode_near_rotor` by counting eigenvalues (load_cases.load_cases): the
    same flag and verdict, the modes' eigensolver saved. ``survival_margins=False`` ends the
    survival sweep's per-height margins at the first failure (`_survival`): the same
    `max_undamaged_drop_cm` and `first_failure`, shorter lists. ``session``: this check's frame
    model (`drop.Session` of this spec and design) when the caller made it (`api.Design.check`
    asks it first which joints need their FE)."""
    return with_clash(complete(spec, *mass_and_drop(spec, geometry, design_, session), peaks=peaks, modes=modes,
                               survival_margins=survival_margins), clash)


def mass_and_drop(spec: Spec, geometry: dict | None = None, design_: Derived | None = None, session=None):
    """The first, cheap part of `check`: (design, mass budget, drop model, frame session): what the
    build's mass and drop figures draw while the load cases are still being solved. ``session``:
    as in `check`."""
    d = design(spec) if design_ is None else design_
    budget = mass_mod.budget(spec, d.frame, d.cut, d.parts, geometry)
    from . import drop as drop_mod

    if session is None:
        session = drop_mod.Session(spec, d.frame, d.parts)  # the frame model, solved at most once per check
    with one_blas_thread():  # the same bits whoever calls, on any machine (and in the disk caches)
        drop = _drop(spec, d, budget, session)
    return d, budget, drop, session


def complete(spec: Spec, d: Derived, budget: mass_mod.MassBudget, drop, session=None, peaks: bool = True,
             modes: bool = True, survival_margins: bool = True) -> Findings:
    """The rest of `check` for that mass budget and drop model: load cases, peaks, flight and the
    verdict (no clash check: `with_clash` adds the build's). ``peaks``, ``modes``,
    ``survival_margins``: as in `check`."""
    with one_blas_thread():
        stiffness, peak = _physics(spec, d, budget, drop, session, peaks or spec.requirements.max_peak_g is not None, modes)
    from . import flight as flight_mod

    from ..fasteners import fasteners

    flight = flight_mod.evaluate(spec, budget.total_g)
    surv = _survival(spec, d.frame, budget, drop, stiffness, survival_margins)
    screws = fasteners(spec, d.frame, d.parts)  # the fit check's and the mass properties'
    fit = fit_of(spec, d, screws)
    # the survival sweep informs (the report warns when a part fails below the design drop); the
    # PASS/FAIL stays with the requirements' own checks
    problems = (_problems(spec, budget, drop) + _physics_problems(spec, stiffness, peak) + _aircraft_problems(spec, flight)
                + fit.messages())
    # the mass properties and resonance flags the flight files are written from: a flagged mode
    # WARNs, never FAILs
    model, warn = _flight_model(spec, d, budget, stiffness, screws)
    return Findings(d, budget, drop, tuple(problems), stiffness, peak, flight, survival=surv, notes=tuple(_notes(spec, d, session)),
                       fit=fit, flight_model=model, warnings=warn)


def _flight_model(spec: Spec, design: Derived, budget, stiffness: dict | None, fasteners=None) -> tuple[dict, tuple[str, ...]]:
    """What `check` adds to its `flight` section: (cg_mm, inertia_kg_m2 and the resonance flags from
    the estimates and `stiffness.modes_hz`; the warnings of flagged modes: WARN, not FAIL). No flags
    when the flight tables have no entry for the motor (the flight files need one; `check` does not).
    The flight files (`cogniframe.flight`) are written from the same figures, a floor above.
    `fasteners`: the design's `fasteners.fasteners` when the caller has them."""
    from ..errors import UserError
    from . import massprops, resonance, rotors

    mp = massprops.estimate(spec, design, budget, fasteners)
    out = {"cg_mm": [round(c, 3) + 0.0 for c in mp.cg_mm],
           "inertia_kg_m2": [[float(f"{x:.6g}") + 0.0 for x in row] for row in mp.inertia_kg_m2]}
    try:
        rm = rotors.model(spec, mp.mass_kg, len(design.frame.motors))
    except UserError:
        return out, ()
    hz = (stiffness or {}).get("modes_hz") or []
    res = resonance.assess(hz, rm.hover_rotor_hz, rm.max_rotor_hz)
    out["resonance_flags"] = [{"mode": f.mode, "hz": f.hz, "band": f.band} for f in res.flags]
    notes = []
    for band in [b.name for b in res.bands]:
        fl = [f for f in res.flags if f.band == band]
        if fl:
            b = next(x for x in res.bands if x.name == band)
            notes.append(f"resonance: mode{'s' if len(fl) > 1 else ''} {', '.join(str(f.mode) for f in fl)} "
                         f"({', '.join(f'{f.hz:.1f}' for f in fl)} Hz) within {resonance.FLAG_MARGIN:.0%} of the {band} band "
                         f"({b.lo_hz:.0f}-{b.hi_hz:.0f} Hz); `cogniframe fly` writes the filter advice and resonance.png")
    return out, tuple(notes)


def fit_of(spec: Spec, d: Derived, fasteners=None):
    """The fit check of the design (analysis/fit_check.py): screws through their holes into their
    threads, holes clear of the rods, motor holes on the motor's pattern. `fasteners`: the
    design's `fasteners.fasteners` when the caller has them."""
    from . import fit_check

    if fasteners is None:
        from ..fasteners import fasteners as fasteners_of

        fasteners = fasteners_of(spec, d.frame, d.parts)
    return fit_check.check(spec, d.parts, fasteners)


def _notes(spec: Spec, d: Derived, session=None) -> list[str]:
    """Joints the surrogate model does not cover (solved by FE instead): a note, not a FAIL.
    ``session``: the check's frame model (`drop.Session`), whose joint models asked the same."""
    if spec.model.stiffness_model != "surrogate" or spec.model.k_n_per_m is not None:
        return []
    from .joints import surrogate_notes

    return surrogate_notes(spec, [p for p in d.parts if p.family == "joint"],
                           session.outside if session is not None and session.parts is d.parts else None)


# ``survival_margins=False``: the survival sweep's heights tried first (10 to 400 cm, two thirds
# of them): the example sweeps' and the benchmark's frames all fail between 40 and 360 cm
_SURVIVAL_FIRST_CM = 400.0


def _survival(spec: Spec, frame, budget: mass_mod.MassBudget, drop, stiffness: dict | None, margins: bool = True):
    """The survival sweep (analysis/survival.py) when the load cases carry their loads per newton;
    the payload's peak G over the sweep only when `requirements.max_peak_g` asks for it.

    ``margins=False``: the sweep's heights up to _SURVIVAL_FIRST_CM first, and the whole sweep
    only when nothing fails there. A part failing within them fails first in the whole sweep
    too (a failure further up crosses 1 above the last height tried, one within below it), so
    `first_failure` and `max_undamaged_drop_cm` are the whole sweep's; the per-height lists end
    there. With the payload's peak G (max_peak_g set) the whole sweep, as by default."""
    if drop is None or not stiffness or not stiffness.get("survival_per_n"):
        return None
    from . import survival

    peaks = survival.payload_peaks(spec, drop, budget.groups["exoskeleton"]) if spec.requirements.max_peak_g is not None else None
    if not margins and peaks is None:
        first = tuple(h for h in survival.SWEEP_CM if h <= _SURVIVAL_FIRST_CM)
        if len(first) >= 2:
            short = survival.evaluate(spec, frame, drop, stiffness, None, first)
            if short.first_failure is not None:
                return short
    return survival.evaluate(spec, frame, drop, stiffness, peaks)


def with_clash(result: Findings, clash) -> Findings:
    """`result` with the build's clash check: its clashes are FAIL problems, after the others."""
    if clash is None:
        return result
    return replace(result, problems=result.problems + tuple(clash.messages()), clash=clash)


def _aircraft_problems(spec: Spec, flight) -> list[str]:
    """Thrust-to-weight below requirements.min_thrust_to_weight."""
    out = []
    if flight is not None and flight.thrust_to_weight < spec.requirements.min_thrust_to_weight:
        out.append(f"thrust-to-weight {flight.thrust_to_weight:.2f} is below {spec.requirements.min_thrust_to_weight:g} "
                   f"(requirements.min_thrust_to_weight): {flight.max_thrust_g_per_motor:.0f} g per motor lifts "
                   f"{flight.mass_g:.0f} g; choose stronger motors, bigger props, more cells or a lighter design")
    return out


def _drop(spec: Spec, d: Derived, budget: mass_mod.MassBudget, session=None):
    from . import drop as drop_mod

    return drop_mod.evaluate_design(spec, d.frame, budget.total_g, session)


def _physics(spec: Spec, d: Derived, budget: mass_mod.MassBudget, drop, session=None, peaks: bool = True,
             modes: bool = True):
    """The frame's load cases and the predicted peak deceleration (both cached on disk)."""
    from . import drop as drop_mod

    if drop is None:
        return None, None
    cases = drop_mod.load_cases(spec, d.frame, budget.total_g, drop, session, modes=modes)
    peak = drop_mod.peak_prediction(spec, budget.total_g, drop, budget.groups["exoskeleton"]) if peaks else None
    return cases, peak


def _physics_problems(spec: Spec, stiffness: dict | None, peak: dict | None) -> list[str]:
    out = []
    req = spec.requirements
    if stiffness is not None:
        wall = stiffness["wall"]
        if wall["max_wall_speed_m_s"] < req.wall_impact_speed_m_s:
            out.append(f"side-on wall impact: the {wall['limited_by']} reaches the wall from "
                       f"{wall['max_wall_speed_m_s']:.1f} m/s, below the required {req.wall_impact_speed_m_s:g} m/s "
                       f"(requirements.wall_impact_speed_m_s; stiffer or wider frame, smaller props)")
        b = stiffness.get("min_buckling_margin")
        if b is not None and b < 1.0:
            out.append(f"{stiffness['critical_rod']} buckles at the {stiffness['design_drop_height_cm']:g} cm design drop "
                       f"(Euler margin {b:.2f} < 1: axial {stiffness['buckling'][0]['axial_n']:.0f} N vs "
                       f"{stiffness['buckling'][0]['euler_n']:.0f} N; thicker or stiffer rods, shorter spans)")
        st = stiffness.get("strain") or {}
        if st and st["peak"] >= st["elongation_at_break"]:
            out.append(f"TPU strain {100 * st['peak']:.0f} % at the design drop exceeds TPU's elongation at break "
                       f"{100 * st['elongation_at_break']:.0f} % (thicker hinge/walls, softer landing)")
    if peak is not None and req.max_peak_g is not None:
        worst = next(h for h in peak["heights"] if h["height_cm"] == req.design_drop_height_cm)
        # one drop's median peak: what the electronics see in a typical crash, not the mean pulse
        g = worst.get("peak_g_drop_median", worst["peak_g"])
        if g > req.max_peak_g:
            out.append(f"predicted single-drop median peak deceleration {g:.0f} G at the {req.design_drop_height_cm:g} cm design drop "
                       f"({peak['model']}; 90th percentile {worst.get('peak_g_drop_p90', g):.0f} G) is above "
                       f"requirements.max_peak_g = {req.max_peak_g:g} G")
    return out


def _problems(spec: Spec, budget: mass_mod.MassBudget, drop) -> list[str]:
    out = []
    if budget.total_g > spec.requirements.mass_limit:
        out.append(f"all-up weight {budget.total_g:.1f} g is over the {spec.requirements.mass_limit:g} g limit "
                   f"by {-budget.margin_g:.1f} g (requirements.mass_limit)")
    if drop is not None and spec.requirements.design_drop_height_cm > drop.max_safe_height_cm:
        out.append(f"design drop height {spec.requirements.design_drop_height_cm:g} cm exceeds the max safe drop height "
                   f"{drop.max_safe_height_cm:.1f} cm: the battery holder would hit the ground (requirements.design_drop_height_cm)")
    return out


def check_dict(result: Findings) -> dict:
    """The stable JSON of `cogniframe check --json` (its numbers at numfmt's stated precision)."""
    return numfmt.check_figures(check_values(result))


def check_values(result: Findings) -> dict:
    """`check_dict`'s tree at the model's full precision: what the model computed, before the
    output rounds it (tests of the model's own identities read this)."""
    d = result.design
    out = {
        "name": d.spec.name,
        "verdict": result.verdict,
        "problems": list(result.problems),
        "mass": result.mass.as_dict(),
        "cutlist": [r.as_dict() for r in d.cut.rows],
        "stock": {"stock_length_mm": d.cut.stock.stock_length_mm, "kerf_mm": d.cut.stock.kerf_mm,
                  "count": d.cut.stock.count, "lower_bound": d.cut.stock.lower_bound,
                  "rods": [{"index": s.index, "cuts_mm": [c for _, c in s.cuts], "offcut_mm": s.offcut_mm} for s in d.cut.stock.rods]},
        "frame": {"clearance_mm": round(d.frame.clearance_mm, 2), "rods": len(d.frame.rods), "joints": len(d.frame.nodes),
                  "prop_margin_mm": [{"motor": p.motor, "to_cage_mm": p.to_cage_mm, "to_core_mm": p.to_core_mm,
                                      "to_neighbour_mm": p.to_neighbour_mm} for p in d.frame.prop_clearances]},
        "parts": [{"name": p.name, "material": p.material, "qty": p.qty} for p in d.parts],
    }
    if result.drop is not None:
        out["drop"] = result.drop.to_dict()
    if result.stiffness is not None:
        out["stiffness"] = result.stiffness
    if result.peak is not None:
        out["peak_g"] = result.peak
    if result.flight is not None:
        out["flight"] = result.flight.summary() | (result.flight_model or {})
    if result.survival is not None:
        out["survival"] = result.survival.to_dict()
    if result.clash is not None:
        out["clash"] = result.clash.to_dict()
    if result.fit is not None:
        out["fit"] = result.fit.to_dict()
    if result.notes:
        out["notes"] = list(result.notes)
    if result.warnings:
        out["warnings"] = list(result.warnings)
    return out
