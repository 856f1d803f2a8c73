#!/usr/bin/env python3
"""What each of the authors' dimensions does to a preset: k, thrust case, safe drop and mass.

    python tools/authors_differences.py [params/carbon.yaml] [--markdown]

The preset is checked as it is, then with one of the authors' values at a time (measured on their
crash-test frame, thecognifly/CogniFly-STL `CogniFly_v8_Crash_Tests/`: `tools/authors_frame.py`
for the assembled frame, `tools/compare_parts.py` for the parts), then with all of them at once.
Each row is `cogniframe check --json` of that variant (the preset's joint model, the package's
TPU calibration): the change of k, of the full-thrust motor deflection (full frame, bare arms),
of the safe drop and of the all-up and TPU masses. docs/authors-parts.md "What each difference
does to k" is this script's `--markdown` output.

The authors' values, as measured (mm; +z down in their document):
- blind sockets 2.69-2.70 for the 3.0 rods: `joints.fit_clearance` -0.30;
- walls round the blind sockets 1.45-1.55: `joints.wall` 1.5;
- knee inset: the knees' rod ends at 87.0 from the centre in x and y against the cage's 102.2
  (15.2 in; the leg ends' centres 14.9 in): `frame.knee_inset` 15;
- the cage's rod axes 204.4 apart across, 106.6 apart in height (the presets' outside sizes are
  those plus the corner joints round them: `frame.width`, `frame.depth`, `frame.height` moved by the
  difference of the rod axes' spans);
- motor axes 67.6 from the centre in plan: `motors.radius` 67.6.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

AUTHORS_RING_SPAN = 204.4  # mm, cage rod axis to axis across (x and y)
AUTHORS_RING_HEIGHT = 106.6  # mm, top ring axis to bottom ring axis
AUTHORS = {  # key: (value, what was measured)
    "joints.fit_clearance.tpu_95a": (-0.30, "blind sockets 2.70 for 3.0 rods"),
    "joints.wall": (1.5, "walls 1.45-1.55"),
    "frame.knee_inset": (15.0, "knees 15 in from the cage"),
    "motors.radius": (67.6, "motor axes 67.6 from the centre"),
}


def ring_spans(design) -> tuple[float, float, float]:
    """(x span, y span, height) of the cage's rod axes: the top corners' ports, from the frame."""
    import numpy as np

    pts = np.array([p for r in design.derived.frame.rods.values() if r.role == "cage" for p in (r.a.port, r.b.port)])
    span = pts.max(axis=0) - pts.min(axis=0)
    return float(span[0]), float(span[1]), float(span[2])


def box_values(design) -> dict:
    """The outside sizes that put the cage's rod axes where the authors' are."""
    sx, sy, sz = ring_spans(design)
    s = design.spec.frame
    return {"frame.width": round(s.width + AUTHORS_RING_SPAN - sx, 1),
            "frame.depth": round(s.depth + AUTHORS_RING_SPAN - sy, 1),
            "frame.height": round(s.height + AUTHORS_RING_HEIGHT - sz, 1)}


def figures(design) -> dict:
    d = design.check().to_dict()
    st, t = d["stiffness"], d["stiffness"]["thrust"]
    return {"k": st["k_n_per_m"], "frame_mm": t["motor_deflection_mm"], "arms_mm": t["arms_only_motor_deflection_mm"],
            "safe_cm": d["drop"]["max_safe_height_cm"], "mass_g": d["mass"]["total_g"],
            "tpu_g": d["mass"]["by_material"].get("tpu_95a"), "verdict": d["verdict"]}


def variants(design) -> list[tuple[str, dict]]:
    out = [(f"`{k}` {v:g} ({why})", {k: v}) for k, (v, why) in AUTHORS.items()]
    box = box_values(design)
    out.append(("the cage's rod axes as the authors' (" + ", ".join(f"`{k}` {v:g}" for k, v in box.items()) + ")", box))
    every = {k: v for k, (v, _) in AUTHORS.items()} | box
    out.append(("all of the above", every))
    return out


def table(preset: Path) -> str:
    import cogniframe as cf

    base_design = cf.load(preset)
    base = figures(base_design)
    rows = ["| the authors' value | k N/m | change | full thrust: frame / bare arms mm | safe drop cm | all-up g | TPU g | verdict |",
            "|---|---|---|---|---|---|---|---|",
            _row(f"{preset.stem} as it is", base, base)]
    for label, values in variants(base_design):
        rows.append(_row(label, figures(base_design.with_values(values)), base))
    return "\n".join(rows)


def _row(label: str, f: dict, base: dict) -> str:
    change = f["k"] / base["k"] - 1
    return (f"| {label} | {f['k']:.0f} | {change:+.1%} | {f['frame_mm']:.2f} / {f['arms_mm']:.2f} | {f['safe_cm']:.1f} "
            f"| {f['mass_g']:.1f} | {f['tpu_g']:.1f} | {f['verdict']} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("preset", nargs="?", type=Path, default=ROOT / "params" / "carbon.yaml")
    a = ap.parse_args(argv)
    print(table(a.preset))
    return 0


if __name__ == "__main__":
    sys.exit(main())
