"""`python -m cogniframe.cadread.summary ASSEMBLY [--materials FILE] [--rod-diameter D] [--json]`: what the
reader finds in a STEP / FreeCAD assembly (the reading half of `cogniframe analyse`, issue 43).
A UserError prints its message and exits 2, like the cogniframe CLI."""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter

from ..errors import UserError
from .part_materials import load_material_map
from .found import as_dict
from .read import read_exoskeleton


def summary(exo) -> str:
    out = [f"{exo.source}: {len(exo.rods)} rods, {len(exo.joints)} joints, {len(exo.sockets)} sockets/sleeves, "
           f"{len(exo.attached)} attached parts"]
    for (length, d), n in sorted(Counter((round(r.length, 2), round(r.diameter, 2)) for r in exo.rods).items(), reverse=True):
        out.append(f"  {n} x rod {length:.2f} mm, diameter {d:.2f}")
    for j in exo.joints:
        socks = ", ".join(f"{s.rod}:{s.end or 'through'} {s.kind} {s.bore:.2f} x {s.depth:.2f}" for s in exo.sockets_of(j.name))
        out.append(f"  {j.name} ({j.material}, {j.volume / 1000:.2f} cm^3): {socks}")
    out.extend(f"warning: {w}" for w in exo.warnings)
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m cogniframe.cadread.summary", description=__doc__.split("\n\n")[0])
    ap.add_argument("assembly")
    ap.add_argument("--materials", help="YAML: parts: {name pattern: material}, default:, rods:")
    ap.add_argument("--rod-diameter", type=float, default=None, help="keep only rods of this diameter (+-10 %%), mm")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    try:
        exo = read_exoskeleton(a.assembly, load_material_map(a.materials), a.rod_diameter)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return e.exit_code
    print(json.dumps(as_dict(exo), indent=1) if a.json else summary(exo))
    return 0


if __name__ == "__main__":
    sys.exit(main())
