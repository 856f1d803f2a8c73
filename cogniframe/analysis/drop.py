"""The design's crash prediction: stiffness (predicted or measured), damping, clearance -> drop model;
and the frame's other load cases (wall, thrust, modes, buckling, strain) and peak deceleration.

Glue between the frame model (`stiffness`, joints from `joint_stiffness`), the paper's impact
model (`impact`), the peak-deceleration model (`impact_nl`) and the params' `model:` section;
the mass is the all-up weight from the mass budget. Every expensive result is cached on disk by
a hash of exactly its inputs and of the source of the modules that compute it, so a repeated
`check` reads JSON and imports neither PyNite, gmsh, scikit-fem nor CadQuery.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from .. import cache
from ..frame import Frame
from ..spec import Spec
from . import impact

_MODULES = ("cogniframe.analysis.stiffness", "cogniframe.analysis.impact_nl", "cogniframe.analysis.impact", "cogniframe.analysis.framefe", "cogniframe.analysis.joint_stiffness",
            "cogniframe.analysis.joint_fe", "cogniframe.frame", "cogniframe.partlist", "cogniframe.parts.joint",
            "cogniframe.materials", "cogniframe.spec")


def evaluate_design(spec: Spec, frame: Frame, total_mass_g: float) -> impact.DropResult:
    """Drop results over `requirements.drop_heights_cm` for this design (SI inside, see impact)."""
    m = total_mass_g / 1000.0
    if spec.model.k_n_per_m is not None:
        k, k_source = spec.model.k_n_per_m, "measured"
    else:
        k, k_source = predicted_k_n_per_m(spec, frame, total_mass_g), "predicted"
    if spec.model.c_n_s_per_m is not None:
        c, c_source = spec.model.c_n_s_per_m, "measured"
    else:
        c, c_source = impact.damping_from_ratio(spec.model.damping_ratio, k, m), "predicted"
    clearance = spec.requirements.clearance if spec.requirements.clearance is not None else frame.clearance_mm
    return impact.evaluate(m, c, k, spec.requirements.drop_heights_cm, clearance_mm=clearance,
                           k_source=k_source, c_source=c_source)


def predicted_k_n_per_m(spec: Spec, frame: Frame, total_mass_g: float | None = None) -> float:
    """Frame-model stiffness (the secant with the fit's play, `stiffness.secant_k`), cached by a
    hash of everything the model reads and of its source. It does not depend on the mass."""
    key = _stiffness_key(spec)
    hit = cache.load_json("stiffness", key)
    if hit is not None:
        return float(hit["k_n_per_m"])
    from .. import partlist
    from .stiffness import joint_models, secant_k

    parts = partlist.build(spec, frame)
    joints = joint_models(spec, parts, spec.model.stiffness_model)
    k = secant_k(spec, frame, parts, joints)
    cache.store_json("stiffness", key, {"k_n_per_m": k})
    return k


def _stiffness_key(spec: Spec, *extra) -> str:
    from importlib.util import find_spec

    data = spec.model_dump(mode="json")
    inputs = {s: data[s] for s in ("materials", "frame", "rods", "joints", "core", "motors", "printer")}
    inputs["stiffness_model"] = data["model"].get("stiffness_model", "fe")
    h = hashlib.sha256(json.dumps([inputs, extra], sort_keys=True, default=str).encode())
    # every module the model reads from: library moduli live in materials.py, bore in spec.py
    for mod in _MODULES:
        h.update(Path(find_spec(mod).origin).read_bytes())
    return h.hexdigest()[:24]


def load_cases(spec: Spec, frame: Frame, total_mass_g: float, drop: impact.DropResult) -> dict:
    """`check --json`'s `stiffness` section: every load case of `stiffness.load_cases`, cached.

    The design drop's force is the spring force at its maximum compression, k x_max (the
    strike clearance caps x_max: beyond it the battery holder carries the rest)."""
    h_design = spec.requirements.design_drop_height_cm
    m = total_mass_g / 1000.0
    r = impact.simulate_height(m, drop.c_n_s_per_m, drop.k_n_per_m, h_design, drop.clearance_mm)
    x = min(r.x_max_mm, drop.clearance_mm)
    k_model = drop.k_n_per_m
    zeta = drop.damping_ratio
    key = _stiffness_key(spec, "cases", round(total_mass_g, 6), round(k_model, 6), round(x, 9), round(zeta, 9),
                         spec.requirements.wall_impact_speed_m_s)
    hit = cache.load_json("cases", key)
    if hit is not None:
        return hit
    from .. import partlist
    from .stiffness import load_cases as cases

    parts = partlist.build(spec, frame)
    lc = cases(spec, frame, parts, total_mass_g, joint_model=spec.model.stiffness_model, damping_ratio=zeta,
               design_force_n=k_model * x / 1000.0)
    out = lc.to_dict()
    out["design_drop_height_cm"] = h_design
    out["design_force_n"] = k_model * x / 1000.0
    # key order as the cache stores it (sorted), so a fresh and a cached answer print the same bytes
    out = json.loads(json.dumps(out, default=float, sort_keys=True))
    cache.store_json("cases", key, out)
    return out


def peak_prediction(spec: Spec, total_mass_g: float, drop: impact.DropResult, exo_mass_g: float) -> dict:
    """Predicted peak |a| (G, as the logger sees it) per drop height, from the better-validated model."""
    heights = sorted({*spec.requirements.drop_heights_cm, spec.requirements.design_drop_height_cm})
    key = _stiffness_key(spec, "peaks", total_mass_g, drop.k_n_per_m, drop.c_n_s_per_m, exo_mass_g, heights, drop.clearance_mm)
    hit = cache.load_json("peaks", key)
    if hit is not None:
        return hit
    from . import impact_nl

    out = impact_nl.design_peaks(total_mass_g / 1000.0, drop.k_n_per_m, drop.c_n_s_per_m, exo_mass_g / 1000.0,
                                  heights, drop.clearance_mm)
    out = json.loads(json.dumps(out, sort_keys=True))  # as the cache stores it: same bytes fresh or cached
    cache.store_json("peaks", key, out)
    return out
