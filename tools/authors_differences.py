#!/usr/bin/env python3
"""What each of the authors' dimensions does to a preset: k, thrust case, safe drop and mass.

    python tools/authors_differences.py [params/carbon.yaml] [--write]

For each dimension where cogniframe and the authors' frame differ (measured on their crash-test
frame, thecognifly/CogniFly-STL `CogniFly_v8_Crash_Tests/`: `tools/authors_frame.py` for the
assembled frame, `tools/compare_parts.py` for the parts), the preset is checked with the authors'
value and with cogniframe's other one (the preset's, or its former value where the preset has
taken the authors'), the rest as the preset: `cogniframe check --json` of each (the preset's joint
model, the package's TPU calibration), k, the full-thrust motor deflection (full frame, bare
arms), the safe drop and the all-up and TPU masses. `--write` puts the table in
docs/authors-parts.md, "What each difference does to k".

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
# key: (the authors' value, cogniframe's other value: the preset's, or its former one where the
# preset now has the authors', what was measured)
AUTHORS = {
    "joints.fit_clearance.tpu_95a": (-0.30, -0.15, "blind sockets 2.70 for 3.0 rods"),
    "joints.wall": (1.5, 1.2, "walls 1.45-1.55"),
    "frame.knee_inset": (15.0, 12.0, "knees 15 in from the cage"),
    "motors.radius": (67.6, 82.0, "motor axes 67.6 from the centre"),
}
FORMER_BOX = {"frame.width": 210.0, "frame.depth": 210.0, "frame.height": 120.0}
BEGIN, END = "<!-- differences:begin -->", "<!-- differences:end -->"
DOC = ROOT / "docs" / "authors-parts.md"


def box_values(design) -> dict:
    """The outside sizes that put the cage's rod axes where the authors' are (0.1 mm)."""
    lo, hi = design.derived.frame.bbox()  # the joints' centres: the cage's rod axes span it
    sx, sy, sz = (float(v) for v in hi - lo)
    s = design.spec.frame
    return {"frame.width": round(s.width + AUTHORS_RING_SPAN - sx, 1),
            "frame.depth": round(s.depth + AUTHORS_RING_SPAN - sy, 1),
            "frame.height": round(s.height + AUTHORS_RING_HEIGHT - sz, 1)}


def figures(design) -> dict:
    d = design.check().to_dict()
    st, t = d["stiffness"], d["stiffness"]["thrust"]
    return {"k": st["k_n_per_m"], "frame_mm": t["motor_deflection_mm"], "arms_mm": t["arms_only_motor_deflection_mm"],
            "safe_cm": d["drop"]["max_safe_height_cm"], "mass_g": d["mass"]["total_g"],
            "tpu_g": d["mass"]["by_material"].get("tpu_95a")}


def differences(design) -> list[tuple[str, dict, dict, bool]]:
    """(label, the authors' values, cogniframe's other values, adopted by the preset) per difference."""
    spec_values = {k: design.get(k) for k in AUTHORS}
    out = [(f"`{k}` {a:g} ({why}; cogniframe {spec_values[k]:g}" + (f", formerly {o:g})" if spec_values[k] == a else ")"),
            {k: a}, {k: o if spec_values[k] == a else spec_values[k]}, spec_values[k] == a)
           for k, (a, o, why) in AUTHORS.items()]
    box = box_values(design)
    ours = {k: design.get(k) for k in box}
    adopted = all(abs(ours[k] - v) <= 0.2 for k, v in box.items())  # their rods' ends read to 0.1 mm
    box = ours if adopted else box
    out.append(("the cage's rod axes 204.4 x 106.6 (outside " + " x ".join(f"{v:g}" for v in box.values())
                + (f"; formerly {' x '.join(f'{v:g}' for v in FORMER_BOX.values())})" if adopted else ")"),
                box, FORMER_BOX if adopted else ours, adopted))
    return out


def table(preset: Path) -> str:
    import cogniframe as cf

    design = cf.load(preset)
    rows = ["| the authors' value | adopted | k N/m, the authors' / the other | change of k | full thrust, frame / bare arms mm "
            "| safe drop cm | all-up g | TPU g |",
            "|---|---|---|---|---|---|---|---|"]
    for label, theirs, other, adopted in differences(design):
        a, o = figures(design.with_values(theirs)), figures(design.with_values(other))
        rows.append(f"| {label} | {'yes' if adopted else 'no'} | {a['k']:.0f} / {o['k']:.0f} | {a['k'] / o['k'] - 1:+.1%} "
                    f"| {a['frame_mm']:.2f} / {a['arms_mm']:.2f} (other {o['frame_mm']:.2f} / {o['arms_mm']:.2f}) "
                    f"| {a['safe_cm']:.1f} / {o['safe_cm']:.1f} | {a['mass_g']:.1f} / {o['mass_g']:.1f} "
                    f"| {a['tpu_g']:.1f} / {o['tpu_g']:.1f} |")
    return "\n".join(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("preset", nargs="?", type=Path, default=ROOT / "params" / "carbon.yaml")
    ap.add_argument("--write", action="store_true", help="replace the table in docs/authors-parts.md")
    a = ap.parse_args(argv)
    from doctable import emit  # tools/, beside this script

    return emit(table(a.preset), DOC, BEGIN, END, a.write)


if __name__ == "__main__":
    sys.exit(main())
