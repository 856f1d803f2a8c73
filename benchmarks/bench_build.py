"""Build timings: cold build of each preset (imports included, fresh process), rebuild with nothing
changed (cache hit), rebuild after one parameter changes (rods.material: no part changes;
frame.width: the joints whose socket angles move).

    python benchmarks/bench_build.py [--jobs N]

Each measurement runs `build_parts` (+ the assembly) in a fresh Python process, so imports count.
Targets on a 2-core machine: cold < 10 s, cache hit < 2 s.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, sys, time
t0 = time.perf_counter()
from pathlib import Path
from cogniframe import frame as frame_mod, partlist, spec as spec_mod
from cogniframe.export.part_files import build_parts
spec = spec_mod.load(sys.argv[1])
data = spec.model_dump(mode="json")
for key, value in json.loads(sys.argv[4]).items():
    section, name = key.split(".")
    data[section][name] = value
spec = spec_mod.from_dict(data)
fr = frame_mod.frame_of(spec)
parts = partlist.part_list(spec, fr)
t1 = time.perf_counter()
built_names = []
import cogniframe.export.part_files as b
real = b.build_part_files
b.build_part_files = lambda p, *a: built_names.append(p.name) or real(p, *a)
jobs = 1 if sys.argv[5] == "auto" else int(sys.argv[5])
from cogniframe.runtime.pools import cad_workers

if jobs > 1:
    with cad_workers(jobs) as submit:
        built = build_parts(spec, fr, parts, Path(sys.argv[2]), submit=submit, cache_dir=Path(sys.argv[3]))
else:
    built = build_parts(spec, fr, parts, Path(sys.argv[2]), cache_dir=Path(sys.argv[3]))
t2 = time.perf_counter()
assembly = 0.0
if sys.argv[6] == "1":
    from cogniframe.export.assembly import write_assembly
    write_assembly(spec, fr, parts, built, Path(sys.argv[2]))
    assembly = time.perf_counter() - t2
print(json.dumps({"design_s": t1 - t0, "parts_s": t2 - t1, "assembly_s": assembly, "rebuilt": built_names,
                  "total_s": time.perf_counter() - t0}))
"""


def run(params: Path, out: Path, cache: Path, changes: dict, jobs: str, assembly: bool) -> dict:
    t = time.perf_counter()
    res = subprocess.run([sys.executable, "-c", CHILD, str(params), str(out), str(cache), json.dumps(changes), jobs,
                          "1" if assembly else "0"], capture_output=True, text=True, cwd=ROOT, check=True)
    wall = time.perf_counter() - t
    data = json.loads(res.stdout.strip().splitlines()[-1])
    data["wall_s"] = wall
    return data


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--jobs", default="auto", help="worker processes for build_parts (default: auto)")
    args = ap.parse_args()
    print(f"{'preset':8s} {'case':28s} {'wall s':>7s} {'parts s':>8s} {'asm s':>6s}  rebuilt")
    for preset in ("carbon", "bamboo"):
        params = ROOT / "params" / f"{preset}.yaml"
        with tempfile.TemporaryDirectory() as tmp:
            tmp = Path(tmp)
            cache = tmp / "cache"
            cases = [("cold (no cache, + assembly)", {}, True), ("cache hit (parts only)", {}, False),
                     ("cache hit (+ assembly)", {}, True), ("rods.material changed", {"rods.material": "bamboo" if preset == "carbon" else "carbon_rod"}, False),
                     ("frame.width + 20 mm", {"frame.width": 262 if preset == "bamboo" else 230}, False)]
            for i, (label, changes, asm) in enumerate(cases):
                r = run(params, tmp / f"out{i}", cache, changes, args.jobs, asm)
                print(f"{preset:8s} {label:28s} {r['wall_s']:7.2f} {r['parts_s']:8.2f} {r['assembly_s']:6.2f}  "
                      f"{len(r['rebuilt'])}: {', '.join(r['rebuilt']) or '-'}")


if __name__ == "__main__":
    main()
