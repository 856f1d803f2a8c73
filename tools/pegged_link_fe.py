#!/usr/bin/env python3
"""The authors' arm-to-core connector against cogniframe's flat core link, in one joint FE.

The authors join each arm to their rigid base with a TPU connector whose two columns each carry
an arm rod's socket at one end and a solid peg at the other, coaxial with it, pressed into a
bore of the ABS base (dimensions measured on `Flex_Main_connector_new_bumper.stl` of
thecognifly/CogniFly-STL, docs/authors-parts.md). This script builds that shape from those
numbers (never the file), meshes it like every joint, ties each rod to its socket through the
preset's interface layer and the pegs' sides and ends rigidly to the base (ABS is ~100x stiffer
than the calibrated TPU), and reports the arm pair's hinge about the axis through both rods: the
figure `check --json` reports as `stiffness.thrust.arms_only_core_link_hinge_n_mm_per_rad` for
cogniframe's link, computed here by the same condensation. The flat link's figure comes from the
preset's own part through the build's joint FE.

    python tools/pegged_link_fe.py [--preset carbon] [--spacing 25] [--lugs] [--thrust]

About a minute of CPU. The table goes to stdout, as docs/stiffness-model.md quotes it.
"""

from __future__ import annotations

import argparse
import copy
import math
import sys
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


AUTHORS_WALL = 1.8  # the connector's columns: (6.79 - 3.19) / 2


@dataclass(frozen=True)
class Connector:
    """The authors' connector, print frame (z up, the pegs down, the sockets open at the top).

    Defaults: Flex_Main_connector_new_bumper.stl, axis sections every mm (tools/compare_parts.py):
    pegs 6.79 across, z -9..0, solid; columns 6.79 across, z 0..8.6, a 3.19 socket from the top
    down to z 0.3; an arch joining the columns over z 6..9, 6.7 deep; the columns' axes 25.3 apart;
    a middle column for the strut, 6.79 across, from the arch up to z 21.4, its 3.19 socket 7.4
    deep (the strut is free in the hinge, so its socket carries no tie). The fillets where the
    columns meet the arch are left out: 1.94 cm^3 here against the file's 2.10.
    """

    spacing: float = 25.3
    peg_d: float = 6.79
    peg_len: float = 9.0
    column_d: float = 6.79
    column_len: float = 8.6
    bore: float = 3.19
    depth: float = 8.3
    arch_z: tuple = (6.0, 9.0)
    arch_w: float = 6.7
    strut_top: float = 21.4
    strut_depth: float = 7.4
    # cogniframe's pegged link gives the strut its own peg: None is the authors' connector (none);
    # a number y puts a peg (peg_d x peg_len) and a column (column_d) up to the arch's top under
    # the middle, y off the arms' plane, held in the base like the others
    mid_peg_y: float | None = None

    def solid(self):
        import cadquery as cq

        shape = None
        for x in (0.0, self.spacing):
            peg = cq.Workplane("XY").workplane(offset=-self.peg_len).center(x, 0).circle(self.peg_d / 2).extrude(self.peg_len)
            col = cq.Workplane("XY").center(x, 0).circle(self.column_d / 2).extrude(self.column_len)
            shape = peg.union(col) if shape is None else shape.union(peg).union(col)
        z0, z1 = self.arch_z
        arch = cq.Workplane("XY").box(self.spacing, self.arch_w, z1 - z0, centered=(False, True, False)).translate((0, 0, z0))
        mid = cq.Workplane("XY").workplane(offset=z1).center(self.spacing / 2, 0).circle(self.column_d / 2).extrude(self.strut_top - z1)
        shape = shape.union(arch).union(mid)
        if self.mid_peg_y is not None:
            x, y = self.spacing / 2, self.mid_peg_y
            peg = cq.Workplane("XY").workplane(offset=-self.peg_len).center(x, y).circle(self.peg_d / 2).extrude(self.peg_len)
            col = cq.Workplane("XY").center(x, y).circle(self.column_d / 2).extrude(z1)
            shape = shape.union(peg).union(col)
        for x, top, depth in ((0.0, self.column_len, self.depth), (self.spacing, self.column_len, self.depth),
                              (self.spacing / 2, self.strut_top, self.strut_depth)):
            cut = cq.Workplane("XY").workplane(offset=top - depth).center(x, 0).circle(self.bore / 2).extrude(depth + 1)
            shape = shape.cut(cut)
        return shape

    def volume_mm3(self) -> float:
        return float(self.solid().val().Volume())


def with_cogniframe_socket(spec, conn: Connector) -> Connector:
    """The connector with the preset's blind socket (bore, depth) and joint wall instead of the authors'."""
    return replace(conn, bore=spec.bore, depth=spec.joints.socket_depth, column_d=spec.bore + 2 * spec.joints.wall)


def connector_hinge(spec, conn: Connector, factor: float | None = None) -> tuple[float, int]:
    """(the arm pair's hinge N mm/rad, tetrahedra) of the connector: each rod tied to its socket's
    wall and floor through the preset's interface layer, the pegs' sides and ends to the base
    (held), the pair free to translate (`load_cases.pair_hinge`, as `check` condenses its link)."""
    from cogniframe.analysis.joints import meshing, solid_fe
    from cogniframe.analysis.joints.fe import FE_CURVATURE, FE_MESH_MM, _TIE_STIFF, _nu, socket_faces
    from cogniframe.analysis.joints.model import interface
    from cogniframe.analysis.load_cases import pair_hinge
    from cogniframe.parts.shapes import brep_text

    itf = interface(spec, factor)
    pts, tets = meshing.mesh_brep_text(brep_text(conn.solid().val()), FE_MESH_MM, FE_CURVATURE)
    tol = 0.1 + 0.5 * conn.bore * (1 - math.cos(math.pi / FE_CURVATURE))
    ties = []
    up = np.array([0.0, 0.0, 1.0])
    for x in (0.0, conn.spacing):
        sel = socket_faces(np.array([x, 0.0, conn.column_len - conn.depth]), up, conn.bore / 2, conn.depth, tol)
        ties.append(solid_fe.Tie(f"arm{x:g}", sel, (x, 0.0, conn.column_len), itf.e / itf.h, itf.g / itf.h))

    def pegs(c, n):
        side = (c[2] < 1e-3) & (np.abs(n[2]) < 0.1)
        end = (np.abs(c[2] + conn.peg_len) < 1e-3) & (n[2] < -0.99)
        return side | end

    ties.append(solid_fe.Tie("body", pegs, (conn.spacing / 2, 0.0, 0.0), _TIE_STIFF * itf.e, _TIE_STIFF * itf.e))
    cond = solid_fe.condense(pts, tets, itf.e, _nu(itf.e, itf.g), ties)
    return pair_hinge(cond.K, cond.refs, [0, 1], []), cond.n_elements


def flat_link_hinge(spec) -> tuple[float, float]:
    """(hinge N mm/rad, TPU volume mm^3) of `spec`'s core link (the flat one with `core.link: tab`)
    through the build's FE."""
    from cogniframe import frame as frame_mod, partlist
    from cogniframe.analysis.joints.fe import fe_joint
    from cogniframe.analysis.load_cases import arm_pair_hinge
    from cogniframe.families.joint_kinds.kinds import node_of, solid

    f = frame_mod.frame_of(spec)
    parts = partlist.part_list(spec, f)
    link = next(p for p in parts if p.family == "joint" and node_of(p) == "core_link")
    js = fe_joint(spec, link)
    return arm_pair_hinge({link.name: js}, [link]), float(solid(link).shape.Volume())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--preset", default="carbon")
    ap.add_argument("--spacing", type=float, default=None, help="the arm pair's spacing (default: the preset's)")
    ap.add_argument("--lugs", action="store_true", help="also where the pegs' ABS tubes would sit on today's layout")
    ap.add_argument("--thrust", action="store_true", help="also the thrust case with the link scaled to the connector's hinge")
    args = ap.parse_args(argv)
    import yaml
    from cogniframe import spec as spec_mod

    doc = yaml.safe_load((ROOT / "params" / f"{args.preset}.yaml").read_text(encoding="utf-8"))
    if args.spacing is not None:
        doc["frame"]["arm_spacing"] = args.spacing
    doc["core"]["link"] = "tab"  # the flat link, against which the authors' connector is measured
    spec = spec_mod.from_dict(doc, f"{args.preset}.yaml")
    rho = spec.material(spec.joints.material).density_g_mm3
    s = spec.frame.arm_spacing
    rows = []
    hinge, vol = flat_link_hinge(spec)
    rows.append(("cogniframe's flat core link (the preset's part)", s, hinge, vol))
    thick = copy.deepcopy(doc)
    thick["joints"]["wall"] = AUTHORS_WALL
    hinge, vol = flat_link_hinge(spec_mod.from_dict(thick, f"{args.preset}.yaml"))
    rows.append((f"the same with the authors' {AUTHORS_WALL} mm walls (joints.wall)", s, hinge, vol))
    for label, conn in (
        ("the authors' connector (their dimensions)", Connector(spacing=s)),
        ("the same, cogniframe's blind socket and wall", with_cogniframe_socket(spec, Connector(spacing=s))),
    ):
        h, _ = connector_hinge(spec, conn)
        rows.append((label, s, h, conn.volume_mm3()))
    print(f"{args.preset}, TPU factor from the model, arm pair {s:g} mm apart")
    print("| link | hinge (N mm/rad) | TPU (cm^3, g) |")
    print("|---|---|---|")
    for label, _, h, v in rows:
        print(f"| {label} | {h:.1f} | {v / 1000:.2f}, {v * rho:.2f} |")
    if args.lugs:
        print(f"\nthe pegs' ABS tubes ({Connector().peg_d:g} mm bores, {LUG_WALL:g} mm walls) with no node moved")
        # printed flat, a tube stands on the bed, so its axis sits its outer radius from the
        # plate's underside (the plate printed as it sits) or its top (printed upside down)
        rise = Connector().peg_d / 2 + LUG_WALL - spec.core.plate_thickness / 2
        for label, up in (("at today's rod height", 0.0),
                          (f"flush with the plate's underside: the rods {rise:.1f} mm higher", rise),
                          (f"flush with the plate's top (printed upside down): the rods {rise:.1f} mm lower", -rise)):
            print(f"  {label}")
            for corner, hits, past in lug_study(spec, Connector(spacing=s), up):
                print(f"    {corner}: runs into {', '.join(hits) or 'nothing'}; inner end {', '.join(f'{p:.1f}' for p in past)} mm beyond the plate's edge")
    if args.thrust:
        print(f"\nthe thrust case with the core link's super-element scaled by {rows[2][2]:.1f} / {rows[0][2]:.1f}")
        print("| core link | k (N/m) | hinge (N mm/rad) | bare arms, full thrust: mm, deg | full frame (mm) | bare / full |")
        print("|---|---|---|---|---|---|")
        for label, scale in (("the flat link", 1.0), ("scaled to the authors' connector", rows[2][2] / rows[0][2])):
            k, t = scaled_link_thrust(spec, scale)
            print(f"| {label} | {k:.0f} | {t['arms_only_core_link_hinge_n_mm_per_rad']:.1f} | "
                  f"{t['arms_only_motor_deflection_mm']:.1f}, {t['arms_only_motor_tilt_deg']:.1f} | "
                  f"{t['motor_deflection_mm']:.2f} | {t['exoskeleton_stiffening']:.1f}x |")
    return 0


LUG_WALL = 1.2  # ABS round a peg's bore: three 0.4 mm lines


def lug_study(spec, conn: Connector, rise: float = 0.0) -> list[tuple[str, list[str], list[float]]]:
    """Where the pegs' ABS tubes would sit with no node moved: per corner, the core boxes a tube
    (bore = peg, `LUG_WALL` round it, the peg's length inward from the rod's end along the arm,
    at the rod's height) runs into, sampled over its outside, and how far its inner end lies
    beyond the plate's edge (mm, each rod of the pair). ``rise``: the rods (and tubes) that much
    higher against the core than today."""
    from cogniframe.design import design

    f = design(spec).frame
    core = f.core
    names = ("holder", "battery", "stack", "computer", "spacer", "flow_sensor", "camera", "camera_base")
    boxes = {k: getattr(core, k) for k in names if getattr(core, k, None) is not None}
    r = conn.peg_d / 2 + LUG_WALL
    up = np.array([0.0, 0.0, 1.0])
    out = []
    for corner in ("fl", "fr", "rl", "rr"):
        pos = np.asarray(f.nodes[f"core_link_{corner}"].pos, float)
        e = np.array([pos[0], pos[1], 0.0]) / math.hypot(pos[0], pos[1])
        lat = np.cross(up, e)
        hits, past = set(), []
        for side in (-1, 1):
            top = pos + lat * side * spec.frame.arm_spacing / 2 + e * (spec.joints.seat - conn.column_len + conn.depth) + up * rise
            for t in np.linspace(0.0, conn.peg_len, 10):
                for a in np.linspace(0.0, 2 * math.pi, 24, endpoint=False):
                    p = top - e * t + r * (math.cos(a) * lat + math.sin(a) * up)
                    hits |= {k for k, b in boxes.items() if np.all(np.abs(p - np.asarray(b.centre)) < np.asarray(b.size) / 2)}
            inner = top - e * conn.peg_len - np.asarray(core.plate.centre)
            past.append(float(max(abs(inner[0]), abs(inner[1])) - core.plate.size[0] / 2))
        out.append((corner, sorted(hits), past))
    return out


def scaled_link_thrust(spec, scale: float) -> tuple[float, dict]:
    """(secant k N/m, `check`'s thrust case) with the core links' FE super-elements times `scale`:
    a what-if for a stiffer link, which stiffens its every path (the strut's too) alike."""
    from cogniframe.analysis.load_cases import _thrust_case
    from cogniframe.analysis.stiffness import joint_models, masses_g, secant_k
    from cogniframe.design import design
    from cogniframe.families.joint_kinds.kinds import node_of

    d = design(spec)
    kinds = {p.name: node_of(p) for p in d.parts}
    joints = {n: replace(js, K=tuple(map(tuple, (js.matrix * scale).tolist()))) if kinds[n] == "core_link" else js
              for n, js in joint_models(spec, d.parts, "fe").items()}
    return (secant_k(spec, d.frame, d.parts, joints),
            _thrust_case(spec, d.frame, d.parts, joints, masses_g(spec, d.frame, d.parts, None)))


if __name__ == "__main__":
    raise SystemExit(main())
