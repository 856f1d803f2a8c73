#!/usr/bin/env python3
"""Build every printed part of many in-schema designs and say which do not come out as one solid
with a watertight STL (the build's own checks: `registry.solid`, `export.mesh.write_stl`).

    python tools/cad_sweep.py random --n 600        # tests/design_space.py's random designs, seeds 0..n-1 (--first: from another)
    python tools/cad_sweep.py keys --n 11           # each geometry key alone across its schema bounds
    python tools/cad_sweep.py pairs --n 6           # pairs of keys on an n x n grid
    ... [--out results.jsonl] [--shard 0/2]

`--check-fuse` also checks every union the part builders make (`parts.joint_solid.fuse_all`): all pieces
at once, as built, against the pieces fused one by one, in order and in reverse. OCC's fuse of many
pieces can drop one and still give one watertight solid (a corner without its strut sleeve), which
the STL checks cannot see. The part fails when its union is smaller than its largest piece, or
more than 0.1 % smaller than a one-by-one union that is not (a one-by-one fuse can fail too).

Both presets are the base of `keys` and `pairs`. A design that `design()` refuses (a UserError
naming a key) is counted as refused; any other exception, from `design()` or from a part, is a
failure. A part whose shape was already built (same `geometry_digest`) is not built again. One
JSON line per design goes to --out; the summary groups the failures by part and message.
In-process and without the build's cache, so it measures the CAD code of this checkout.
"""

from __future__ import annotations

import argparse
import itertools
import json
import random
import sys
import tempfile
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(HERE / "tests"))

import design_space

# The keys that shape a printed part, with their schema bounds.
KEYS = {
    "frame.width": (80, 600), "frame.depth": (80, 600), "frame.height": (50, 400), "frame.knee_inset": (0, 80),
    "frame.knee_height": (0.2, 0.8), "frame.arm_spacing": (6, 40), "rods.diameter": (1.0, 8.0),
    "joints.wall": (0.8, 6), "joints.socket_depth": (4, 40), "joints.seat": (0, 20), "joints.hinge_thickness": (0.6, 4),
    "joints.fit_clearance.tpu_95a": (-0.3, 1.0), "core.plate_size": (30, 200), "core.plate_thickness": (1.5, 8),
    "core.holder_wall": (1.0, 6), "core.battery.length": (10, 200), "core.battery.width": (10, 100),
    "core.battery.height": (3, 60), "core.battery_clearance": (3, 80), "core.spacer_thickness": (0, 10),
    "core.strap_width": (5, 30), "core.camera.tilt_deg": (-30, 45), "motors.radius": (20, 300),
    "motors.bolt_spacing": (3, 40), "printer.layer_height": (0.05, 0.6), "printer.nozzle": (0.1, 1.2),
}
PAIRS = [("joints.seat", "frame.height"), ("joints.seat", "rods.diameter"), ("joints.seat", "frame.knee_inset"),
         ("joints.wall", "rods.diameter"), ("frame.knee_inset", "frame.height"), ("frame.arm_spacing", "rods.diameter"),
         ("joints.socket_depth", "joints.seat"), ("joints.hinge_thickness", "joints.wall"), ("frame.width", "frame.depth"),
         ("joints.seat", "frame.width"), ("frame.knee_height", "frame.height"), ("rods.diameter", "frame.height"),
         ("joints.seat", "joints.wall"), ("joints.seat", "frame.arm_spacing")]


def _grid(lo: float, hi: float, n: int) -> list[float]:
    return [round(lo + (hi - lo) * i / (n - 1), 3) for i in range(n)]


def designs(mode: str, n: int, first: int = 0):
    """(tag, params document) in a fixed order."""
    if mode == "random":
        for seed in range(first, first + n):
            yield f"r{seed}", design_space.random_design(random.Random(seed))
        return
    for base in design_space.PRESETS:
        if mode == "keys":
            combos = [((key, v),) for key, bounds in KEYS.items() for v in _grid(*bounds, n)]
        else:
            combos = [((k1, v1), (k2, v2)) for k1, k2 in PAIRS for v1, v2 in itertools.product(_grid(*KEYS[k1], n), _grid(*KEYS[k2], n))]
        for combo in combos:
            doc = design_space.preset(base)
            if all(design_space.put(doc, key, v) for key, v in combo):
                yield f"{base}:" + ",".join(f"{key}={v}" for key, v in combo), doc


def check_fuses() -> None:
    """Make `fuse_all` (in parts.joint_solid and where it is imported) raise when the union it makes of
    all the pieces at once has lost one (see the module docstring)."""
    from cogniframe.families import motor_mount
    from cogniframe.parts import joint_solid

    at_once = joint_solid.fuse_all

    def one_by_one(shapes):
        out = shapes[0]
        for s in shapes[1:]:
            out = out.fuse(s)
        return out.clean().Volume()

    def checked(shapes):
        shapes = list(shapes)
        union = at_once(shapes)
        if len(shapes) > 2:
            v, biggest = union.Volume(), max(s.Volume() for s in shapes)
            refs = [r for r in (one_by_one(shapes), one_by_one(shapes[::-1])) if r >= biggest * (1 - 1e-6)]
            if v < biggest * (1 - 1e-6) or any(v < r * (1 - 1e-3) for r in refs):
                raise RuntimeError(f"fuse of {len(shapes)} pieces lost one: all at once {v:.1f} mm^3, one by one "
                                   f"{', '.join(f'{r:.1f}' for r in refs) or 'failed'}, largest piece {biggest:.1f}")
        return union

    joint_solid.fuse_all = motor_mount.fuse_all = checked


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("mode", choices=("random", "keys", "pairs"))
    ap.add_argument("--n", type=int, default=None, help="designs (random) or grid points per key (keys: 11, pairs: 6)")
    ap.add_argument("--first", type=int, default=0, help="random: the first seed")
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--check-fuse", action="store_true", help="check each union against the pieces fused one by one")
    ap.add_argument("--shard", default="0/1", help="i/k: every k-th design from the i-th (to split a run over processes)")
    a = ap.parse_args()
    n = a.n or {"random": 200, "keys": 11, "pairs": 6}[a.mode]
    shard, shards = (int(x) for x in a.shard.split("/"))

    from cogniframe import spec as spec_mod
    from cogniframe.design import design
    from cogniframe.errors import UserError
    from cogniframe.export.mesh import write_stl
    from cogniframe.families import registry
    from cogniframe.parts.shapes import geometry_digest

    if a.check_fuse:
        check_fuses()
    seen: dict[str, str | None] = {}
    counts: Counter = Counter()
    failures: Counter = Counter()
    out = a.out.open("a", encoding="utf-8") if a.out else None
    with tempfile.TemporaryDirectory() as tmp:
        for i, (tag, doc) in enumerate(designs(a.mode, n, a.first)):
            if i % shards != shard:
                continue
            doc["name"] = "sweep"
            rec: dict = {"tag": tag}
            try:
                d = design(spec_mod.from_dict(doc))
            except UserError as e:
                rec["refused"] = str(e)
            except Exception as e:  # noqa: BLE001 -- a crash is what this looks for
                rec["crash"] = f"{type(e).__name__}: {e}"
            else:
                rec["fails"] = {}
                for p in d.parts:
                    g = geometry_digest(p)
                    if g not in seen:
                        try:
                            mesh = write_stl(registry.solid(p).shape, Path(tmp) / "part.stl", name=p.name)
                            seen[g] = None if mesh.body_count == 1 else f"{mesh.body_count} shells"
                        except Exception as e:  # noqa: BLE001
                            seen[g] = f"{type(e).__name__}: {e}".replace(tmp, "<tmp>")
                    if seen[g]:
                        rec["fails"][p.name] = seen[g]
            kind = "refused" if "refused" in rec else "crash" if "crash" in rec else "fail" if rec["fails"] else "ok"
            counts[kind] += 1
            for part, msg in rec.get("fails", {}).items():
                failures[(part, msg[:90])] += 1
            if "crash" in rec:
                failures[("design()", rec["crash"][:90])] += 1
            if out:
                out.write(json.dumps(rec) + "\n")
                out.flush()
            print(f"\r{sum(counts.values())} designs {dict(counts)}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    print(f"{a.mode} (n {n}, shard {a.shard}): {sum(counts.values())} designs: built {counts['ok']}, refused "
          f"{counts['refused']}, a part failed {counts['fail']}, design() crashed {counts['crash']}")
    for (part, msg), k in failures.most_common():
        print(f"  {k:4d} {part}: {msg}")
    return 1 if counts["fail"] or counts["crash"] else 0


if __name__ == "__main__":
    sys.exit(main())
