"""The preset tables of docs/flight-files.md (mass properties, rotors, modes), from the flight
files `cogniframe fly` writes (each preset's resonance.json), so that they cannot go stale:
tests/test_flight_files.py compares the doc with `tables()` of the files it flies.

    python tools/flight_tables.py [--write]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "flight-files.md"
PRESETS = ("carbon", "bamboo")
MARKS = {k: (f"<!-- flight-table:{k} -->", f"<!-- /flight-table:{k} -->") for k in ("mass", "rotors", "modes")}


def tables(folders: dict[str, Path]) -> dict[str, str]:
    """{"mass", "rotors", "modes"}: the Markdown tables for the presets' flight folders."""
    mass = ["| preset | mass g | CG mm (x, y, z) | Ixx, Iyy, Izz kg m^2 |", "|---|---:|---|---|"]
    rot = ["| preset | k_eta N/(rad/s)^2 | k_m N m/(rad/s)^2 | k_m/k_eta m | hover / full rev/s | T_max N "
           "| hover thrust / full | ESC throttle at hover | expo |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    modes = ["| preset | modes Hz (FC participation) | flagged |", "|---|---|---|"]
    for name, folder in folders.items():
        r = json.loads((folder / "resonance.json").read_text(encoding="utf-8"))
        m, ro = r["mass"], r["rotor"]
        i = m["inertia_kg_m2"]
        cg = ", ".join(f"{c:.2f}" for c in m["cg_mm"])
        mass.append(f"| {name} | {m['mass_kg'] * 1000:.2f} | {cg} | {i[0][0]:.3e}, {i[1][1]:.3e}, {i[2][2]:.3e} |")
        fraction = (ro["omega_hover_rad_s"] / ro["omega_max_rad_s"]) ** 2
        rot.append(f"| {name} | {ro['k_eta_n_per_rad_s2']:.4g} | {ro['k_m_nm_per_rad_s2']:.3g} | {ro['km_over_kt_m']:.4f} "
                   f"| {ro['hover_rotor_hz']:.0f} / {ro['max_rotor_hz']:.0f} | {ro['thrust_max_n']:.3f} | {fraction:.3f} "
                   f"| {ro['hover_throttle']:.3f} | {ro['thrust_expo']:.3f} |")
        listed = ", ".join(f"{x['hz']:.2f} ({x['fc_participation']:.2f})" for x in r["modes"])
        bands = sorted({f["band"] for f in r["flags"]})
        flagged = f"{len({f['mode'] for f in r['flags']})} of {len(r['modes'])}: {', '.join(bands)}" if r["flags"] else "none"
        modes.append(f"| {name} | {listed} | {flagged} |")
    return {"mass": "\n".join(mass), "rotors": "\n".join(rot), "modes": "\n".join(modes)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="write the tables into docs/flight-files.md (else print)")
    a = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    from cogniframe import api
    from doctable import write_between

    with tempfile.TemporaryDirectory() as tmp:
        folders = {n: api.load(ROOT / "params" / f"{n}.yaml").fly(Path(tmp) / n) for n in PRESETS}
        out = tables(folders)
    for key, table in out.items():
        if a.write:
            write_between(DOC, *MARKS[key], table)
        else:
            print(table + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
