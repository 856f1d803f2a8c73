"""Fit check: do the bought parts bolt on? Pure, on the part list, the fasteners and the motor
catalogue (no CAD, so `check` stays fast); `build` and `check` both run it and a failure FAILs
the verdict, naming both parts.

Rules:

* `screw_hole`: every screw passes through a hole of every part it joins, one wider than its
  thread (the part's plan puts a clearance hole where the screw goes);
* `thread`: every screw engages the thread it screws into (the motor's, a nut's) by at least
  MIN_THREAD_TURNS pitches and never deeper than that thread goes (a motor's thread depth: past
  it the screw reaches the windings);
* `rod_wall`: no hole of a part that clips onto rods cuts a rod bore or sleeve: in plan, a hole's
  axis keeps bore/2 + hole/2 + two extrusion lines from every rod's axis, and a screw head's seat
  (a counterbore through any sleeve under the plate) keeps two extrusion lines to the bore too;
* `pattern`: a motor mount's holes are where the motor's holes are: each on a hole of the
  catalogue pattern (opposite holes across the shaft, MotorPreset.hole_points) turned onto the
  arm by the mount's `pattern_turn` (the motor sits at any turn about its shaft; the pattern's
  shape does not change), and at least one opposite pair of them.

Two rules need the solids, so the build's clash check runs them on its bodies (`keepouts` says
what each keeps clear; analysis/clash.py tests them; clash.json lists a failure, and `check` of
a build FAILs with it):

* `driver`: every screw head and nut can be turned from outside: a driver, a cylinder as wide as
  the head (a nut: a nut driver round its corners) reaching DRIVER_REACH (NUT_DRIVER_REACH) mm
  along the screw's axis away from the part, meets no solid fitted by then (fasteners.STAGES:
  what comes later in the assembly guide is not there yet);
* `battery_path`: nothing sits in the battery's slide path: the pack at its catalogue size, swept
  from the holder's open end (its rear face at the mouth) to its seat, meets no solid but the pack
  (and the magnetic lock's lid, which goes on after it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..materials import MIN_THREAD_TURNS, SCREWS

PATTERN_TOL = 0.05  # mm: a mount hole within this of the catalogue hole is on it
SLACK = 0.1  # mm: the clearance hole is at least this much wider than the thread


@dataclass(frozen=True)
class FitProblem:
    rule: str  # screw_hole | thread | rod_wall | pattern
    a: str  # the part (copy) or screw
    b: str  # what it fails against: the screw, the motor, the rod
    message: str


@dataclass(frozen=True)
class FitResult:
    problems: tuple[FitProblem, ...]
    screws: int
    holes: int
    rules: tuple[str, ...] = ("screw_hole", "thread", "rod_wall", "pattern")  # `driver`, `battery_path`: the build's (keepouts)
    details: tuple[dict, ...] = ()

    @property
    def ok(self) -> bool:
        return not self.problems

    def messages(self) -> list[str]:
        return [p.message for p in self.problems]

    def to_dict(self) -> dict:
        return {"ok": self.ok, "screws": self.screws, "holes": self.holes, "rules": list(self.rules),
                "mounts": list(self.details),
                "problems": [{"rule": p.rule, "a": p.a, "b": p.b, "message": p.message} for p in self.problems]}


def plan_distance(xy, point, direction) -> float:
    """Plan distance from the vertical line through `xy` to a rod's axis (`point`, `direction`)."""
    d = np.asarray(direction, float)[:2]
    d = d / float(np.linalg.norm(d))
    v = np.asarray(xy, float)[:2] - np.asarray(point, float)[:2]
    return float(abs(v[0] * d[1] - v[1] * d[0]))


def check(spec, parts, fasteners) -> FitResult:
    """Every rule on every motor mount and every screw (see the module docstring)."""
    problems: list[FitProblem] = []
    details: list[dict] = []
    holes = 0
    for p in parts:
        if p.family != "motor_mount" or "holes" not in dict(p.params):
            continue
        holes += len(p.param("holes"))
        problems += _mount_rods(spec, p)
        problems += _mount_pattern(spec, p)
        details.append(_mount_detail(spec, p))
    for f in fasteners:
        problems += _screw(f)
    return FitResult(tuple(problems), sum(1 for f in fasteners if f.kind == "screw"), holes, details=tuple(details))


def _mount_detail(spec, p) -> dict:
    r = [round(math.hypot(x, y), 4) for x, y in p.param("holes")]
    return {"part": p.name, "motor": spec.motor.name, "pattern": spec.motor.pattern, "screw": p.param("screw"),
            "holes": len(p.param("holes")), "hole_radius_mm": sorted(set(r)),
            "screw_length_mm": p.param("screw_length"), "grip_mm": p.param("grip"),
            "engagement_mm": p.param("engagement"), "thread_depth_mm": spec.motor.thread_depth}


def _mount_rods(spec, p) -> list[FitProblem]:
    """rod_wall: each hole keeps two extrusion lines of wall to every bore, each head clears the sleeve."""
    out = []
    sc = SCREWS[str(p.param("screw"))]
    bore = float(p.param("bore"))
    hole_d = float(p.param("screw_clearance"))
    wall = 2 * spec.printer.nozzle
    need_hole = bore / 2 + hole_d / 2 + wall
    need_head = float(p.param("counterbore_d")) / 2 + bore / 2 + wall
    for i, xy in enumerate(p.param("holes"), start=1):
        for k, (pt, d) in enumerate(p.param("arm_rods"), start=1):
            dist = plan_distance(xy, pt, d)
            if dist < need_hole - 1e-6:
                out.append(FitProblem("rod_wall", f"{p.name} hole {i}", f"arm rod {k}",
                                      f"fit: {p.name} hole {i} ({hole_d:g} mm) is {dist:.2f} mm from arm rod {k}'s axis and "
                                      f"cuts its {bore:g} mm bore (needs {need_hole:.2f} mm: bore/2 + hole/2 + {wall:g} mm of wall); "
                                      f"the motor screw would pass through the rod (frame.arm_spacing)"))
            elif dist < need_head - 1e-6:
                out.append(FitProblem("rod_wall", f"{p.name} hole {i}", f"arm rod {k}",
                                      f"fit: the {sc.name} screw head's seat under {p.name} hole {i} cuts into arm rod {k}'s bore "
                                      f"({dist:.2f} mm from the rod's axis, needs {need_head:.2f} mm) (frame.arm_spacing)"))
    return out


def _mount_pattern(spec, p) -> list[FitProblem]:
    """pattern: the mount's holes on the catalogue pattern turned onto the arm, an opposite pair at least."""
    motor = spec.motor
    d0 = np.asarray(p.param("arm_rods")[0][1], float)
    turn = math.degrees(math.atan2(d0[1], d0[0])) + float(dict(p.params).get("pattern_turn", 0.0))
    cat = np.asarray(motor.hole_points(turn), float)
    got = np.asarray(p.param("holes"), float).reshape(-1, 2)
    out = []
    matched = []
    for i, xy in enumerate(got, start=1):
        dist = np.linalg.norm(cat - xy, axis=1)
        k = int(np.argmin(dist))
        if dist[k] > PATTERN_TOL:
            out.append(FitProblem("pattern", f"{p.name} hole {i}", f"motor {motor.name}",
                                  f"fit: {p.name} hole {i} at {math.hypot(*xy):.2f} mm from the shaft axis is not on a hole of "
                                  f"the {motor.name} motor ({motor.pattern} mm {motor.screw}: opposite holes across the shaft, "
                                  f"{motor.holes[0] / 2:g} mm from it; nearest {dist[k]:.2f} mm away)"))
        else:
            matched.append(k)
    pairs = sum(1 for a in (0, 2) if a in matched and a + 1 in matched)
    if not out and pairs == 0:
        out.append(FitProblem("pattern", p.name, f"motor {motor.name}",
                              f"fit: {p.name} carries no opposite pair of the {motor.name} motor's holes: the motor "
                              f"is held by fewer than two screws across its shaft (frame.arm_spacing)"))
    return out


def _screw(f) -> list[FitProblem]:
    """screw_hole and thread for one fastener."""
    if f.kind != "screw":
        return []
    out = []
    sc = SCREWS[f.size]
    for name, hole_d in f.joins:
        if hole_d < sc.d + SLACK - 1e-9:
            out.append(FitProblem("screw_hole", name, f.name,
                                  f"fit: {f.name} ({f.size}) does not pass through {name}: its hole is {hole_d:g} mm "
                                  f"(needs at least {sc.d + SLACK:g} mm)"))
    nut = f.thread.startswith("nut_")
    e_min = sc.nut_m if nut else MIN_THREAD_TURNS * sc.pitch  # a nut: the screw fills it
    if f.length <= f.grip + 1e-9:
        out.append(FitProblem("thread", f.name, f.thread,
                              f"fit: {f.name} ({f.size} x {f.length:g}) does not reach {f.thread}: the parts it joins are "
                              f"{f.grip:g} mm thick"))
    elif f.engagement < e_min - 1e-9:
        out.append(FitProblem("thread", f.name, f.thread,
                              f"fit: {f.name} ({f.size} x {f.length:g}) engages {f.thread}'s thread by {f.engagement:.2f} mm, "
                              + (f"less than the {e_min:g} mm nut: it does not fill the nut" if nut else
                                 f"less than {MIN_THREAD_TURNS} turns ({e_min:g} mm): it would strip")))
    if f.thread_depth is not None and f.engagement > f.thread_depth + 1e-9:
        out.append(FitProblem("thread", f.name, f.thread,
                              f"fit: {f.name} ({f.size} x {f.length:g}) enters {f.thread} {f.engagement:.2f} mm, past its "
                              f"{f.thread_depth:g} mm thread: it reaches the windings (motors.thread_depth)"))
    return out


# -- the build's rules: what must stay clear (tested on the solids by analysis/clash.py) ---------

DRIVER_REACH = 30.0  # mm: a screwdriver's or hex key's shaft, clear of everything along the screw's axis
NUT_DRIVER_REACH = 10.0  # mm: a nut driver's socket over the nut and the screw's end
NUT_DRIVER_WALL = 1.0  # mm: the nut driver's wall round the nut's corners


@dataclass(frozen=True)
class Keepout:
    """A volume that must stay empty: `prims` (vitamins.Prim, world mm), which `rule` asks for it,
    whose it is (`owner`: the screw, nut or the battery), the stage it is tested at (the solids
    fitted then or before: fasteners.STAGES) and the solids it may touch (`exempt`)."""

    name: str
    rule: str  # driver | battery_path
    owner: str
    prims: tuple
    stage: str
    exempt: frozenset


def keepouts(spec, frame, fasteners) -> tuple[Keepout, ...]:
    """Each screw head's and nut's driver, and the battery's slide path (module docstring)."""
    from ..materials import COUNTERSUNK
    from ..vitamins import box, cyl

    out = []
    partner = {f.thread: f.name for f in fasteners if f.kind == "screw" and f.thread}
    for f in fasteners:
        sc = SCREWS[f.size]
        base, axis = np.asarray(f.base, float), np.asarray(f.axis, float)
        if f.kind == "screw":
            if f.head == "countersunk":  # flush: the driver starts at the part's face
                start, r = base, COUNTERSUNK[f.size][0] / 2
            else:
                start, r = base - axis * sc.head_h, sc.head_d / 2
            prims = (cyl(start, -axis, r, DRIVER_REACH),)
            exempt = frozenset((f.name, f.thread))
        elif f.kind == "nut":
            r = sc.nut_af / math.sqrt(3) + NUT_DRIVER_WALL  # round the corners (af / cos 30 deg / 2)
            prims = (cyl(base + axis * f.length, axis, r, NUT_DRIVER_REACH),)
            exempt = frozenset((f.name, partner.get(f.name, "")))
        else:
            continue  # a standoff is turned by hand
        out.append(Keepout(f"driver_{f.name}", "driver", f.name, prims, f.stage, exempt))
    b, holder = frame.core.battery, frame.core.holder
    lo, hi = np.asarray(b.lo, float), np.asarray(b.hi, float)
    hi[1] = float(holder.hi[1]) + float(spec.core.battery.length)  # from its rear face at the mouth to its seat
    # the magnetic lock's lid closes the mouth once the pack is in: off while it slides
    lid = ("battery_lid",) if spec.core.battery_lock == "magnetic" else ()
    out.append(Keepout("battery_path", "battery_path", "battery", (box(lo, hi),), "last", frozenset(("battery", *lid))))
    return tuple(out)
