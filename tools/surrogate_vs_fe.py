#!/usr/bin/env python3
"""What a sweep row loses to the joint surrogate: `check` of the held-out designs of
tests/data/joint_surrogate_holdout.json (designs the fit never saw) with `model.stiffness_model:
surrogate` and with `fe`, and the relative difference of every headline figure.

    python tools/surrogate_vs_fe.py [--designs 16] [--cache DIR]

About 15 s of CPU per design for the FE (its joints are cached in the usual cache, or --cache);
the table goes to stdout, as docs/stiffness-model.md quotes it.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

FIGURES = (  # (label, dotted key of check --json)
    ("verdict", "verdict"),
    ("k (N/m)", "drop.k_n_per_m"),
    ("max safe drop (cm)", "drop.max_safe_height_cm"),
    ("first failure (cm)", "survival.first_failure.at_drop_cm"),
    ("k lateral (N/m)", "stiffness.k_lateral_n_per_m"),
    ("wall speed (m/s)", "stiffness.wall.max_wall_speed_m_s"),
    ("TPU strain, peak", "stiffness.strain.peak"),
    ("bare arms' hinge (N mm/rad)", "stiffness.thrust.arms_only_core_link_hinge_n_mm_per_rad"),
    ("bare arms' tilt at full thrust (deg)", "stiffness.thrust.arms_only_motor_tilt_deg"),
    ("full frame's motor deflection (mm)", "stiffness.thrust.motor_deflection_mm"),
    ("full frame's motor tilt (deg)", "stiffness.thrust.motor_tilt_deg"),
)


def dig(d: dict, key: str):
    """A dotted key of `check --json` (the report's lookup), None where a design has no such figure."""
    from cogniframe.report.html import lookup

    try:
        return lookup(d, key)
    except (KeyError, TypeError):
        return None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--designs", type=int, default=16)
    ap.add_argument("--cache", type=Path, default=None)
    a = ap.parse_args(argv)
    if a.cache:
        os.environ["COGNIFRAME_CACHE"] = str(a.cache)
    import numpy as np

    import cogniframe as cf

    hold = json.loads((ROOT / "tests" / "data" / "joint_surrogate_holdout.json").read_text())["designs"][:a.designs]
    base = cf.load(ROOT / "params" / "carbon.yaml")
    rows = []
    for i, d in enumerate(hold):
        got = {m: base.with_values({**d["overrides"], "model.stiffness_model": m}).check().to_dict()
               for m in ("surrogate", "fe")}
        rows.append(got)
        print(f"design {i + 1}/{len(hold)}: {got['surrogate']['verdict']} / {got['fe']['verdict']}", file=sys.stderr,
              flush=True)
    print(f"{len(rows)} held-out designs, check with the surrogate's joints against the FE's\n")
    print("| figure | median | worst |")
    print("|---|---|---|")
    for label, key in FIGURES:
        pairs = [(dig(r["surrogate"], key), dig(r["fe"], key)) for r in rows]
        if key == "verdict":
            same = sum(x == y for x, y in pairs)
            print(f"| {label} | the same in {same} of {len(pairs)} | |")
            continue
        e = np.abs([x / y - 1 for x, y in pairs if x is not None and y])
        if len(e):
            print(f"| {label} | {100 * np.median(e):.1f} % | {100 * e.max():.1f} % |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
