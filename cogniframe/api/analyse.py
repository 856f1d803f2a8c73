"""`cogniframe analyse`: the physics of any rod-and-joint exoskeleton read from CAD (issue 43).

    a = analyse("out/carbon/assembly.step")                 # Analysis: k, thrust case, safe drop, survival
    a = analyse("CogniFly-Flex.FCStd", down="+z", rod_diameter=3.0)

The reading is `cadread`'s (rods, joints, sockets, contacts); the frame model is
`analysis.exoframe` (each joint's read solid meshed and condensed at its sockets as the check's
joint FE, rods as beams); the drop model is the paper's (`analysis.impact`: m = 0.241 kg,
c = 46 N s/m, 16 mm clearance unless given). A file that is missing, not a STEP/FCStd or holds
no rod-and-joint frame raises `UserError` (the CLI's exit 2, one paragraph).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..errors import UserError

PAPER_MASS_KG = 0.241  # the crash-test build with its data logger
PAPER_C_N_S_PER_M = 46.0  # fitted to the drop tests
PAPER_CLEARANCE_MM = 16.0  # battery holder above the ground
DEFAULT_MAX_THRUST_G = 175.0  # per motor: cogniframe's figure for the paper's 1104 6000KV on 3025 props (the carbon preset)
DEFAULT_PROP_DIAMETER_MM = 76.2  # the paper's 3 inch propellers
DROP_HEIGHTS_CM = (50.0, 100.0, 150.0)


@dataclass(frozen=True)
class Analysis:
    """What `cogniframe analyse` reports (units in the names)."""

    source: str
    down: str
    rods: int
    joints: int
    rod_diameter_mm: float | None  # the beams' diameter (None: each rod's read diameter)
    rod_material: str
    tpu_factor: float
    k_n_per_m: float
    thrust: dict
    wall: dict  # the side faces against a wall: `check --json`'s stiffness.wall keys
    drop: dict
    model: dict  # which parts play which role: feet, core, links, glued pairs, motor mounts, arms, joints' DOFs
    survival: dict  # `survival.Survival.to_dict()`: the flat-drop sweep of the read frame (`exosurvival`)
    unplaced: tuple[str, ...] = ()
    loose_ends: tuple[str, ...] = ()
    warnings: tuple[str, ...] = field(default=())

    def to_dict(self) -> dict:
        from dataclasses import asdict

        return asdict(self)


@dataclass(frozen=True)
class FrameModel:
    """A read exoskeleton's frame model before a factor is chosen: its layout and its joints'
    super-elements at TPU factor 1 (`exoframe.k_at(layout, units, f)` is k at factor f)."""

    exo: object
    layout: object
    units: dict


def frame_model(path=None, *, solids=None, source: str = "", materials=None, down: str = "-z",
                rod_diameter: float | None = None, layer_height: float = 0.2, progress=None) -> FrameModel:
    """Read the assembly (or take named `solids`, e.g. identified by `cadread.identify`) and solve
    every joint's FE (cached). Raises UserError when no frame can be modelled."""
    from ..analysis import exoframe
    from ..cadread.load import load_solids
    from ..cadread.part_materials import MaterialMap, load_material_map
    from ..cadread.read import exoskeleton_of

    if down not in exoframe.DOWN:
        raise UserError(f"--down {down!r}: give +z (the assembly's +z points to the ground, like the authors' FreeCAD "
                        f"document) or -z (+z up, like cogniframe's own STEP)")
    mm = materials if isinstance(materials, MaterialMap) else (load_material_map(materials) if materials else MaterialMap())
    if solids is None:
        solids = load_solids(path)
        source = source or str(path)
    exo = exoskeleton_of(solids, source, mm)
    name = source or "the assembly"
    if not exo.rods:
        raise UserError(f"{name}: no rods found (straight solid cylinders much longer than thick): nothing to analyse. "
                        f"Fix: export the rods as solids with the joints, in one assembly")
    by_name = {s.name: s.solid for s in solids}
    lay = exoframe.layout(exo, down, rod_diameter, mm.rods, by_name)
    if not lay.fe_joints:
        raise UserError(f"{name}: {len(exo.rods)} rods but no part holds a rod end in a socket: no frame to analyse")
    if not lay.core:
        raise UserError(f"{name}: no rigid core part touches a joint, so the payload has nothing to sit on "
                        f"(parts named base/holder/core/plate are ABS; attached parts: "
                        f"{', '.join(a.name for a in exo.attached) or 'none'}). Fix: give the core's material with "
                        f"--materials FILE (parts: {{NAME: abs}})")
    if not lay.feet:
        raise UserError(f"{name}: no joint stands on the floor")
    units = {}
    for i, n in enumerate(lay.fe_joints):
        try:
            units[n] = exoframe.joint_unit(lay, n, by_name, layer_height)
        except RuntimeError as exc:
            raise UserError(f"{name}: the joint {n} could not be modelled by its solid FE ({exc}). Fix: check that "
                            f"{n} is a closed solid and that its sockets hold their rods") from None
        if progress is not None:
            progress(f"joint FE {i + 1}/{len(lay.fe_joints)}: {n} ({units[n].n_dofs} DOF)")
    return FrameModel(exo, lay, units)


def analyse(path=None, *, solids=None, source: str = "", materials=None, down: str = "-z",
            rod_diameter: float | None = None, factor: float | None = None, mass_kg: float = PAPER_MASS_KG,
            c_n_s_per_m: float = PAPER_C_N_S_PER_M, clearance_mm: float = PAPER_CLEARANCE_MM,
            max_thrust_g: float = DEFAULT_MAX_THRUST_G, prop_diameter_mm: float = DEFAULT_PROP_DIAMETER_MM,
            layer_height: float = 0.2, progress=None, model: FrameModel | None = None) -> Analysis:
    """k, the thrust case and the drop model of the exoskeleton at `path` (see the module)."""
    from ..analysis import exoframe, exosurvival, impact
    from ..analysis.joints import TPU_PRINTED_MODULUS_FACTOR

    for label, v in (("mass_kg", mass_kg), ("c_n_s_per_m", c_n_s_per_m), ("clearance_mm", clearance_mm),
                     ("max_thrust_g", max_thrust_g), ("prop_diameter_mm", prop_diameter_mm)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise UserError(f"--{label.replace('_', '-')} {v!r}: give a positive number")
    fm = model or frame_model(path, solids=solids, source=source, materials=materials, down=down,
                              rod_diameter=rod_diameter, layer_height=layer_height, progress=progress)
    lay, units, exo = fm.layout, fm.units, fm.exo
    f = TPU_PRINTED_MODULUS_FACTOR if factor is None else float(factor)
    full = exoframe.model_of(lay, units, f)
    k, u = exoframe.payload_case(lay, full)
    thrust = exoframe.thrust_case(lay, units, f, max_thrust_g, mass_kg * 1000.0, full=full)
    zeta = impact.damping_ratio(c_n_s_per_m, k, mass_kg)
    wall = exoframe.wall_case(lay, full, mass_kg, zeta, prop_diameter_mm)
    safe = impact.max_safe_height_cm(mass_kg, c_n_s_per_m, k, clearance_mm)
    heights = []
    for h in DROP_HEIGHTS_CM:
        r = impact.simulate_height(mass_kg, c_n_s_per_m, k, h, clearance_mm)
        heights.append({"height_cm": h, "x_max_mm": r.x_max_mm, "strikes": r.x_max_mm > clearance_mm})
    drop = {"mass_kg": mass_kg, "c_n_s_per_m": c_n_s_per_m, "clearance_mm": clearance_mm, "k_n_per_m": k,
            "damping_ratio": zeta,
            "max_safe_height_cm": safe if math.isfinite(safe) else None, "heights": heights}
    mdl = {"feet": list(lay.feet), "core": list(lay.core), "links": list(lay.links), "glued": [list(p) for p in lay.glue],
           "motor_mounts": list(lay.mounts), "arms": list(lay.arms), "rods_modelled": len(lay.rods),
           "joint_dofs": {n: u.n_dofs for n, u in units.items()},
           "interface": "h_i = max(bore - rod, 0) / 2 + layer / 2 per socket (layer 0.2 mm); no play"}
    survival = exosurvival.evaluate(lay, full, units, f, u / exoframe.LOAD_N,
                                    exosurvival.DropModel(mass_kg, c_n_s_per_m, k, clearance_mm)).to_dict()
    warnings = tuple(exo.warnings) + tuple(lay.notes)
    left = [r.name for r in exo.rods if r.name not in lay.rods]
    if left:
        warnings += (f"{len(left)} rod(s) with an end in no socket left out of the model: {', '.join(left)}",)
    return Analysis(source or str(path), down, len(exo.rods), len(exo.joints), rod_diameter, lay.rod_material, f, k, thrust,
                    wall, drop, mdl, survival,
                    tuple(exo.unplaced), tuple(exo.loose_ends), warnings)


def calibrate(model: FrameModel, target_n_per_m: float) -> float:
    """The TPU factor at which this frame's k is `target_n_per_m` (`exoframe.calibrate`)."""
    from ..analysis import exoframe

    return exoframe.calibrate(model.layout, model.units, target_n_per_m)


def summary(a: Analysis) -> list[str]:
    """The lines `cogniframe analyse` prints."""
    m, t, d = a.model, a.thrust, a.drop
    beams = f"{a.rod_diameter_mm:.2f} mm" if a.rod_diameter_mm else "their read diameter"
    out = [f"{a.source}: {a.rods} rods, {a.joints} joints ({len(m['joint_dofs'])} by solid FE of their read solids, "
           f"{len(m['motor_mounts'])} motor mounts); core {', '.join(m['core'])}; feet {', '.join(m['feet'])}"
           + (f"; glued {', '.join('+'.join(p) for p in m['glued'])}" if m["glued"] else ""),
           f"frame stiffness k = {a.k_n_per_m:.0f} N/m (TPU factor {a.tpu_factor:g}; rods as {a.rod_material} beams, {beams})"]
    if "motor_deflection_mm_per_n" in t:
        out.append(f"thrust ({t['max_thrust_g']:g} g per motor, core held): full frame {t['motor_deflection_mm']:.2f} mm, "
                   f"tilt {t['motor_tilt_deg']:.2f} deg; bare arms {t['arms_only_motor_deflection_mm']:.2f} mm, tilt "
                   f"{t['arms_only_motor_tilt_deg']:.2f} deg; the exoskeleton stiffens the arms "
                   f"{t['exoskeleton_stiffening']:.1f}x")
    else:
        out.append(f"thrust: {t.get('note')}")
    w = a.wall
    if "max_wall_speed_m_s" in w:
        out.append(f"wall ({w['face']} face, joints on the wall: {', '.join(w['joints_on_the_wall'])}): k_lateral "
                   f"{w['k_lateral_n_per_m']:.0f} N/m, highest wall speed {w['max_wall_speed_m_s']:.2f} m/s, limited by the "
                   f"{w['limited_by']}")
    else:
        out.append(f"wall: {w['note']}")
    safe = d["max_safe_height_cm"]
    out.append(f"drop model (m {d['mass_kg']:g} kg, c {d['c_n_s_per_m']:g} N s/m, zeta {d['damping_ratio']:.3f}, "
               f"clearance {d['clearance_mm']:g} mm): safe drop height {'unbounded' if safe is None else f'{safe:.1f} cm'}; "
               + ", ".join(f"x_max {h['x_max_mm']:.2f} mm at {h['height_cm']:g} cm" for h in d["heights"]))
    sv = a.survival
    first = sv["first_failure"]
    out.append("survival (flat drops; not checked: the core's bending, living hinges): "
               + (f"undamaged up to {sv['max_undamaged_drop_cm']:.1f} cm, then the {first['part']} ({first['mode']})"
                  if first else f"nothing fails up to {sv['max_undamaged_drop_cm']:g} cm"
                  + "".join(f"; the nearest, the {s['part']} ({s['mode']}): margin {min(x for x in s['margin'] if x):.2f} at "
                            f"{sv['heights_cm'][-1]:g} cm" for s in sv["margins"][:1]))
               + "".join(f"; {s['part']} ({s['mode']}) at {s['fails_at_drop_cm']:.1f} cm"
                         for s in sv["margins"][1:4] if s["fails_at_drop_cm"] is not None))
    out.extend(f"warning: {w}" for w in a.warnings)
    return out
