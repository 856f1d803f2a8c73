#!/usr/bin/env python3
"""The presets' stiffness figures as docs/stiffness-model.md's "Results" table, from `check --json`.

    python tools/stiffness_results.py           # print the table
    python tools/stiffness_results.py --write   # replace the table in docs/stiffness-model.md

The table sits between the markers `<!-- results:begin -->` and `<!-- results:end -->`;
tests/test_docs_tables.py fails when it differs from what this prints.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "stiffness-model.md"
BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"
PRESETS = ("carbon", "bamboo")


def _first_failure(sv: dict) -> str:
    f = sv["first_failure"]
    where = "none up to the sweep's top" if f is None else f"{f['part']} ({f['mode']})"
    return f"{sv['max_undamaged_drop_cm']:.1f}, {where}"


def rows(checks: dict[str, dict]) -> list[tuple[str, ...]]:
    """(label, one cell per preset) from each preset's `check --json` object."""
    from cogniframe.analysis.stiffness import PAPER_K_N_PER_M

    def each(fn):
        return tuple(fn(d) for d in checks.values())

    def th(d):
        return d["stiffness"]["thrust"]

    return [
        ("all-up mass (g)", *each(lambda d: f"{d['mass']['total_g']:.1f}")),
        ("k (N/m), secant: a prediction", *each(lambda d: f"{d['stiffness']['k_n_per_m']:.0f}")),
        ("k against the paper's 7040 (the authors' carbon frame)",
         *each(lambda d: f"{d['stiffness']['k_n_per_m'] / PAPER_K_N_PER_M - 1:+.1%}")),
        ("k_lateral (N/m), worst face", *each(lambda d: f"{d['stiffness']['k_lateral_n_per_m']:.0f}")),
        ("highest wall speed (m/s), limited by",
         *each(lambda d: f"{d['stiffness']['wall']['max_wall_speed_m_s']:.2f}, {d['stiffness']['wall']['limited_by']}")),
        ("full thrust per motor (g)", *each(lambda d: f"{th(d)['max_thrust_g']:.0f}")),
        ("motor deflection (mm/N) / tilt (deg/N)",
         *each(lambda d: f"{th(d)['motor_deflection_mm_per_n']:.3f} / {th(d)['motor_tilt_deg_per_n']:.2f}")),
        ("full thrust: motor deflection (mm) / tilt (deg)",
         *each(lambda d: f"{th(d)['motor_deflection_mm']:.2f} / {th(d)['motor_tilt_deg']:.2f}")),
        ("bare arms, full thrust (mm) / tilt (deg)",
         *each(lambda d: f"{th(d)['arms_only_motor_deflection_mm']:.2f} / {th(d)['arms_only_motor_tilt_deg']:.2f}")),
        ("core link hinge (N mm/rad)", *each(lambda d: f"{th(d)['arms_only_core_link_hinge_n_mm_per_rad']:.1f}")),
        ("exoskeleton stiffens the arms", *each(lambda d: f"{th(d)['exoskeleton_stiffening']:.1f}x")),
        ("first modes (Hz)", *each(lambda d: ", ".join(f"{h:.1f}" for h in d["stiffness"]["modes_hz"][:8]))),
        ("min buckling margin (rod)",
         *each(lambda d: f"{d['stiffness']['min_buckling_margin']:.2f} ({d['stiffness']['critical_rod']})")),
        ("max safe drop (cm)", *each(lambda d: f"{d['drop']['max_safe_height_cm']:.1f}")),
        ("max undamaged drop (cm), first failure", *each(lambda d: _first_failure(d["survival"]))),
    ]


def table(checks: dict[str, dict]) -> str:
    head = "| | " + " | ".join(checks) + " |"
    sep = "|---|" + "---|" * len(checks)
    return "\n".join([head, sep] + ["| " + " | ".join(r) + " |" for r in rows(checks)])


def preset_checks() -> dict[str, dict]:
    import cogniframe as cf

    return {name: cf.load(ROOT / "params" / f"{name}.yaml").check().to_dict() for name in PRESETS}


def in_doc(text: str) -> str:
    """The table between the markers in the doc's text."""
    return text.split(BEGIN, 1)[1].split(END, 1)[0].strip("\n")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", action="store_true", help="replace the table in docs/stiffness-model.md")
    a = ap.parse_args(argv)
    from doctable import emit  # tools/, beside this script

    return emit(table(preset_checks()), DOC, BEGIN, END, a.write)


if __name__ == "__main__":
    sys.exit(main())
