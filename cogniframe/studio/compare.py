"""The studio's compare table: its rows, and each design's figures from its `check --json`."""

from __future__ import annotations

from typing import Any


# the compare's rows: label, unit, digits, which is better ("lower", "higher", None)
COMPARE_ROWS = (
    ("mass_g", "all-up weight", "g", 1),
    ("margin_g", "margin to the limit", "g", 1),
    ("k_n_per_m", "stiffness k", "N/m", 0),
    ("safe_drop_cm", "max safe drop", "cm", 1),
    ("one_drop_peak_g", "one drop's peak at the design drop (median)", "G", 0),
    ("hover_time_min", "hover time", "min", 1),
    ("thrust_to_weight", "thrust / weight", "", 2),
    ("first_mode_hz", "first mode", "Hz", 1),
    ("verdict", "verdict", "", None),
)


def compare_figures(check: dict) -> dict[str, Any]:
    """The compare's figures from a `check --json` object (None where the check has none)."""

    def at(*path):
        node: Any = check
        for p in path:
            if isinstance(node, list) and isinstance(p, int) and p < len(node):
                node = node[p]
            elif isinstance(node, dict) and p in node:
                node = node[p]
            else:
                return None
        return node

    design = at("stiffness", "design_drop_height_cm")
    peak = next((h.get("peak_g_drop_median") for h in at("peak_g", "heights") or [] if h.get("height_cm") == design), None)
    return {"mass_g": at("mass", "total_g"), "margin_g": at("mass", "margin_g"), "k_n_per_m": at("stiffness", "k_n_per_m"),
            "safe_drop_cm": at("drop", "max_safe_height_cm"), "one_drop_peak_g": peak,
            "hover_time_min": at("flight", "hover_time_min"), "thrust_to_weight": at("flight", "thrust_to_weight"),
            "first_mode_hz": at("stiffness", "modes_hz", 0), "verdict": check.get("verdict")}
