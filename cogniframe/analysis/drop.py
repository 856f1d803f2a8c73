"""The design's crash prediction: stiffness (predicted or measured), damping, clearance -> drop model;
and the frame's other load cases (wall, thrust, modes, buckling, strain) and peak deceleration.

Glue between the frame model (`stiffness`, joints from `joints`), the paper's impact
model (`impact`), the peak-deceleration model (`impact_nl`) and the params' `model:` section;
the mass is the all-up weight from the mass budget. Every expensive result is cached on disk by
a hash of exactly its inputs and of the source of the modules that compute it, so a repeated
`check` reads JSON and imports neither PyNite, gmsh, scikit-fem nor CadQuery.
"""

from __future__ import annotations

import copy
import json

from .. import cache
from ..frame import Frame
from ..spec import Spec
from . import impact

# the sources the frame model, the load cases and the peaks are made by (their cache keys)
_MODULES = ("analysis/stiffness.py", "analysis/load_cases.py", "analysis/peaks.py", "analysis/impact_nl.py",
            "analysis/single_drop.py", "analysis/impact.py", "analysis/framefe.py",
            "analysis/joints/*.py", "analysis/flight.py", "analysis/constants.py",
            "frame.py", "partlist.py", "families/*.py", "families/joint_kinds/*.py", "parts/joint_solid.py", "parts/joint_plan.py", "materials.py", "spec.py")


class Session:
    """One design's frame model as one `check` uses it: the part list, the joint models and the
    secant solution (k, play springs, the solved payload model), each computed at most once and
    shared by the drop (k) and the load cases (which start from the same solved model). Made
    per check by the caller and dropped with it: no state outlives the check. Stages called
    without one make their own."""

    def __init__(self, spec: Spec, frame: Frame, parts=None):
        self.spec, self.frame, self._parts = spec, frame, parts
        self._joints = None
        self._outside = None
        self._tests = None
        self._layout = None
        self.solution = None  # stiffness.SecantSolution once solved in this check

    @property
    def parts(self):
        if self._parts is None:
            from .. import partlist

            self._parts = partlist.part_list(self.spec, self.frame)
        return self._parts

    @property
    def box_tests(self) -> dict:
        """The joints' features and whether each is inside the surrogate's training box
        (`surrogate.box_tests`): what `outside` and the surrogate's predictions both read."""
        if self._tests is None:
            from .joints.surrogate import box_tests
            from .stiffness import joint_parts

            self._tests = box_tests(self.spec, joint_parts(self.parts))
        return self._tests

    @property
    def outside(self) -> dict[str, str]:
        """The joints outside the surrogate's training box, {name: why} (`surrogate.outside_reasons`):
        what the joint models, `check`'s notes and its question whether a joint needs its FE first read."""
        if self._outside is None:
            from .joints.surrogate import outside_reasons
            from .stiffness import joint_parts

            self._outside = outside_reasons(self.spec, joint_parts(self.parts), self.box_tests)
        return self._outside

    @property
    def joints(self) -> dict:
        if self._joints is None:
            from .stiffness import joint_models

            surrogate = self.spec.model.stiffness_model == "surrogate"
            self._joints = joint_models(self.spec, self.parts, self.spec.model.stiffness_model,
                                        outside=self.outside if surrogate else None,
                                        tests=self.box_tests if surrogate else None)
        return self._joints

    @property
    def layout(self):
        """The frame model's `stiffness.Layout` with these joints: what every model of this check shares."""
        if self._layout is None:
            from .stiffness import model_layout

            self._layout = model_layout(self.frame, self.parts, self.joints)
        return self._layout

    def solve(self):
        if self.solution is None:
            from .stiffness import secant_solution

            self.solution = secant_solution(self.spec, self.frame, self.parts, self.joints, self.layout)
        return self.solution


def evaluate_design(spec: Spec, frame: Frame, total_mass_g: float, session: Session | None = None) -> impact.DropResult:
    """Drop results over `requirements.drop_heights_cm` for this design (SI inside, see impact)."""
    m = total_mass_g / 1000.0
    if spec.model.k_n_per_m is not None:
        k, k_source = spec.model.k_n_per_m, "measured"
    else:
        k, k_source = predicted_k_n_per_m(spec, frame, total_mass_g, session), "predicted"
    if spec.model.c_n_s_per_m is not None:
        c, c_source = spec.model.c_n_s_per_m, "measured"
    else:
        c, c_source = impact.damping_from_ratio(spec.model.damping_ratio, k, m), "predicted"
    clearance = spec.requirements.clearance if spec.requirements.clearance is not None else frame.clearance_mm
    return impact.evaluate(m, c, k, spec.requirements.drop_heights_cm, clearance_mm=clearance,
                           k_source=k_source, c_source=c_source)


def predicted_k_n_per_m(spec: Spec, frame: Frame, total_mass_g: float | None = None, session: Session | None = None) -> float:
    """Frame-model stiffness (the secant with the fit's play, `stiffness.secant_k`), cached by a
    hash of everything the model reads and of its source. It does not depend on the mass."""
    return float(_secant(spec, frame, session)["k_n_per_m"])


def _secant(spec: Spec, frame: Frame, session: Session | None = None) -> dict:
    """{"k_n_per_m", "play"}: the secant k and the play springs it was taken with (rod end node ->
    6x6 as nested lists; JSON keeps every float's digits), cached. `load_cases` reuses the play
    springs instead of iterating them again."""
    key = _stiffness_key(spec)
    hit = cache.load_json("stiffness", key)
    if hit is not None and "play" in hit:
        return hit
    sol = (session or Session(spec, frame)).solve()
    out = {"k_n_per_m": sol.k_n_per_m, "play": {n: p.tolist() for n, p in sol.play.items()}}
    cache.store_json("stiffness", key, out)
    return out


# What of the params the frame model (k, and the play springs) reads: the geometry and the
# materials. Left out: what only weighs (the battery's and the motors' masses; the core's
# infill and material: the core is rigid in the model) or only flies (cells, capacity, kv, prop,
# thrust). The load cases' key adds the mass and the drop; the peaks' key every number it uses.
_NOT_READ_BY_K = {"core": ("infill", "material"), "core.battery": ("mass", "cells", "capacity_mah", "usable_fraction"),
                  "motors": ("prop_mass", "kv", "prop", "max_thrust_g")}


def _k_inputs(data: dict) -> dict:
    inputs = {s: copy.deepcopy(data[s]) for s in ("materials", "frame", "rods", "joints", "core", "motors", "printer")}
    for dotted, keys in _NOT_READ_BY_K.items():
        node = inputs
        for part in dotted.split("."):
            node = node.get(part) if isinstance(node, dict) else None
        if isinstance(node, dict):
            for k in keys:
                node.pop(k, None)
    return inputs


def _stiffness_key(spec: Spec, *extra, scope: str = "k") -> str:
    """Cache key: a hash of the inputs and of the source of every module the model reads (library
    moduli live in materials.py, the bore in spec.py). ``scope="k"``: only what the frame model
    reads (`_k_inputs`); ``"all"``: every section the load cases and peaks may read."""

    data = spec.model_dump(mode="json")
    if scope == "k":
        inputs = _k_inputs(data)
    else:
        inputs = {s: data[s] for s in ("materials", "frame", "rods", "joints", "core", "motors", "printer")}
    inputs["stiffness_model"] = data["model"].get("stiffness_model", "fe")
    from .. import cache

    return cache.key([inputs, extra], _MODULES)


def load_cases(spec: Spec, frame: Frame, total_mass_g: float, drop: impact.DropResult, session: Session | None = None,
               modes: bool = True) -> dict:
    """`check --json`'s `stiffness` section: every load case of `load_cases.load_cases`, cached.
    ``modes=False``: no mode list, `mode_near_rotor` as with it (`load_cases.load_cases`'s option;
    a separate cache entry, so a full `check` never reads a section without its modes).

    The design drop's force is the spring force at its maximum compression, k x_max (the
    strike clearance caps x_max: beyond it the battery holder carries the rest)."""
    h_design = spec.requirements.design_drop_height_cm
    m = total_mass_g / 1000.0
    r = impact.simulate_height(m, drop.c_n_s_per_m, drop.k_n_per_m, h_design, drop.clearance_mm)
    x = min(r.x_max_mm, drop.clearance_mm)
    k_model = drop.k_n_per_m
    zeta = drop.damping_ratio
    key = _stiffness_key(spec, "cases", round(total_mass_g, 6), round(k_model, 6), round(x, 9), round(zeta, 9),
                         spec.requirements.wall_impact_speed_m_s, *(() if modes else ("no mode list",)), scope="all")
    hit = cache.load_json("cases", key)
    if hit is not None:
        return hit
    from .load_cases import load_cases as cases

    session = session or Session(spec, frame)
    play, solved = None, None
    if spec.model.k_n_per_m is None:  # the predicted k's play springs: not iterated again
        if session.solution is not None:  # solved in this check: its model and payload solution too
            play, solved = session.solution.play, session.solution
        else:  # k came from the cache, with its play springs
            import numpy as np

            play = {n: np.asarray(p, float) for n, p in _secant(spec, frame, session)["play"].items()}
    lc = cases(spec, frame, session.parts, total_mass_g, joint_model=spec.model.stiffness_model, damping_ratio=zeta,
               design_force_n=k_model * x / 1000.0, joints=session.joints, play=play, solved=solved, modes=modes,
               layout=session.layout)
    out = lc.to_dict()
    out["design_drop_height_cm"] = h_design
    out["design_force_n"] = k_model * x / 1000.0
    # key order as the cache stores it (sorted), so a fresh and a cached answer print the same bytes;
    # that text is what `cache.store_json` writes (the JSON of the plain tree read back from it)
    text = json.dumps(out, default=float, sort_keys=True)
    cache.store_text("cases", key, text, ".json")
    return json.loads(text)


def peak_prediction(spec: Spec, total_mass_g: float, drop: impact.DropResult, exo_mass_g: float) -> dict:
    """Predicted peak |a| (G, as the logger sees it) per drop height, from the better-validated model:
    the mean pulse's peak (`peak_g`) and one drop's median and 90th percentile (`peak_g_drop_median`,
    `peak_g_drop_p90`), the feet at the corners of the frame's outside footprint."""
    heights = sorted({*spec.requirements.drop_heights_cm, spec.requirements.design_drop_height_cm})
    footprint = (float(spec.frame.width), float(spec.frame.depth))
    key = _stiffness_key(spec, "peaks", total_mass_g, drop.k_n_per_m, drop.c_n_s_per_m, exo_mass_g, heights, drop.clearance_mm,
                         footprint, scope="all")
    hit = cache.load_json("peaks", key)
    if hit is not None:
        return hit
    from . import peaks

    out = peaks.design_peaks(total_mass_g / 1000.0, drop.k_n_per_m, drop.c_n_s_per_m, exo_mass_g / 1000.0,
                             heights, drop.clearance_mm, footprint_mm=footprint)
    text = json.dumps(out, sort_keys=True)  # as the cache stores it (`cache.store_json`): same bytes fresh or cached
    cache.store_text("peaks", key, text, ".json")
    return json.loads(text)
