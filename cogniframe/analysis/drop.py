"""The design's crash prediction: stiffness (predicted or measured), damping, clearance -> drop model.

Glue between the frame FE model (`stiffness`), the paper's impact model (`impact`) and the
params' `model:` section; the mass is the all-up weight from the mass budget.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from .. import cache
from ..frame import Frame
from ..spec import Spec
from . import impact


def evaluate_design(spec: Spec, frame: Frame, total_mass_g: float) -> impact.DropResult:
    """Drop results over `requirements.drop_heights_cm` for this design (SI inside, see impact)."""
    m = total_mass_g / 1000.0
    if spec.model.k_n_per_m is not None:
        k, k_source = spec.model.k_n_per_m, "measured"
    else:
        k, k_source = predicted_k_n_per_m(spec, frame), "predicted"
    if spec.model.c_n_s_per_m is not None:
        c, c_source = spec.model.c_n_s_per_m, "measured"
    else:
        c, c_source = impact.damping_from_ratio(spec.model.damping_ratio, k, m), "predicted"
    clearance = spec.requirements.clearance if spec.requirements.clearance is not None else frame.clearance_mm
    return impact.evaluate(m, c, k, spec.requirements.drop_heights_cm, clearance_mm=clearance,
                           k_source=k_source, c_source=c_source)


def predicted_k_n_per_m(spec: Spec, frame: Frame) -> float:
    """FE stiffness, cached by a hash of everything the model reads and of the model's source.

    PyNite's import alone takes ~0.45 s (it loads matplotlib.pyplot), so `check` reuses the
    answer for a frame it has already solved.
    """
    key = _stiffness_key(spec)
    hit = cache.load_json("stiffness", key)
    if hit is not None:
        return float(hit["k_n_per_m"])
    from .stiffness import predict_stiffness

    k = predict_stiffness(spec, frame).k_n_per_m
    cache.store_json("stiffness", key, {"k_n_per_m": k})
    return k


def _stiffness_key(spec: Spec) -> str:
    from importlib.util import find_spec

    data = spec.model_dump(mode="json")
    inputs = {s: data[s] for s in ("materials", "frame", "rods", "joints", "core", "motors")}
    h = hashlib.sha256(json.dumps(inputs, sort_keys=True).encode())
    # every module the FE model reads from: library moduli live in materials.py, bore in spec.py
    for mod in ("cogniframe.analysis.stiffness", "cogniframe.frame", "cogniframe.materials", "cogniframe.spec"):
        h.update(Path(find_spec(mod).origin).read_bytes())
    return h.hexdigest()[:24]
