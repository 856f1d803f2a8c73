"""The design's crash prediction: stiffness (predicted or measured), damping, clearance -> drop model.

Glue between the frame FE model (`stiffness`), the paper's impact model (`impact`) and the
params' `model:` section; the mass is the all-up weight from the mass budget.
"""

from __future__ import annotations

from ..frame import Frame
from ..spec import Spec
from . import impact


def evaluate_design(spec: Spec, frame: Frame, total_mass_g: float) -> impact.DropResult:
    """Drop results over `requirements.drop_heights_cm` for this design (SI inside, see impact)."""
    m = total_mass_g / 1000.0
    if spec.model.k_n_per_m is not None:
        k, k_source = spec.model.k_n_per_m, "measured"
    else:
        from .stiffness import predict_stiffness

        k, k_source = predict_stiffness(spec, frame).k_n_per_m, "predicted"
    if spec.model.c_n_s_per_m is not None:
        c, c_source = spec.model.c_n_s_per_m, "measured"
    else:
        c, c_source = impact.damping_from_ratio(spec.model.damping_ratio, k, m), "predicted"
    clearance = spec.requirements.clearance if spec.requirements.clearance is not None else frame.clearance_mm
    return impact.evaluate(m, c, k, spec.requirements.drop_heights_cm, clearance_mm=clearance,
                           k_source=k_source, c_source=c_source)
