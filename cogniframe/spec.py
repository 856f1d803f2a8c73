"""Stage 1: a params YAML file -> a validated, frozen `Spec`.

Millimetres, grams, newtons, seconds unless a key's name says otherwise (`k_n_per_m`,
`design_drop_height_cm`). Unknown keys are errors that suggest the closest valid key; every
error names the file, the key path (and line) and the fix, and is raised as `UserError`.
"""

from __future__ import annotations

import difflib
import hashlib
import json
import re
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, ValidationError, field_validator, model_validator

from .errors import UserError
from .materials import BOARDS, CONNECTORS, MATERIALS, MOTOR_PRESETS, PROPS, SCREWS, STACK_PATTERNS, VITAMIN_KINDS, Material, MotorPreset
from .printers import PRINTERS

Pos = Annotated[float, Field(gt=0)]
Frac = Annotated[float, Field(ge=0, le=1)]


class _M(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class MaterialDef(_M):
    """A user-defined material (same fields as the built-in library)."""

    density_g_cm3: Annotated[float, Field(gt=0, le=25, description="density, g/cm^3")]
    e_mpa: Annotated[float, Field(gt=0, description="Young's modulus, MPa")]
    g_mpa: Annotated[float, Field(gt=0, description="shear modulus, MPa")]
    printed: bool = Field(False, description="true for filaments (joints, core)")
    source: str = Field("user-defined in the params file", description="where the numbers come from")


class FrameSection(_M):
    width: Annotated[float, Field(ge=80, le=600, description="outside size along x (left-right), mm")] = 210
    depth: Annotated[float, Field(ge=80, le=600, description="outside size along y (front-rear), mm")] = 210
    height: Annotated[float, Field(ge=50, le=400, description="outside height, mm")] = 120
    knee_inset: Annotated[float, Field(ge=0, le=80, description="how far each mid-height knee sits inside the corner, mm (the hourglass bow): along x and along y in a square box; in a rectangle the same distance (x sqrt 2) towards its core link, so that each corner folds in one plane; 0 = straight sides")] = 12
    knee_height: Annotated[float, Field(gt=0.2, lt=0.8, description="knee height as a fraction of the frame height")] = 0.5
    level_arms: bool = Field(True, description="true: the core plate hangs at the knees' height (to the nearest mm, on M2 standoffs above the battery holder) and the arms run level, as the authors build it; false: the plate sits on the holder and the arms climb to the knees")
    arm_spacing: Annotated[float, Field(ge=6, le=40, description="centre distance between the two parallel rods of an arm, mm")] = 12
    struts: bool = Field(True, description="damping struts from the bottom corners to the core")
    rear_net: bool = Field(False, description="the authors' thin net (CogniFly-STL v8 Flex_net_thin): a flat 0.5 mm web of the joints' TPU across the cage's rear face (the battery slides in at the front), tied with cable ties to the rear top and bottom cage rods, rings and spokes round a 68 mm window; it keeps fingers, twigs and cables out of the rear propellers' reach. 1.11 cm^3 (1.35 g) whole on the carbon preset's cage, as the authors'; on a bed under 162 mm it prints as two halves with a seam rim each (2 x 0.60 cm^3, 1.47 g)")


class RodsSection(_M):
    material: str = Field("carbon_rod", description="material name (library or `materials:`)")
    diameter: Annotated[float, Field(ge=1.0, le=8.0, description="rod diameter, mm")] = 3.0
    stock_length: Annotated[float, Field(ge=50, le=3000, description="length of the rods you buy, mm")] = 1000
    kerf: Annotated[float, Field(ge=0, le=5, description="material lost per cut, mm")] = 1.0


class JointsSection(_M):
    material: str = Field("tpu_95a", description="joint filament (TPU 95A in the paper)")
    wall: Annotated[float, Field(ge=0.8, le=6, description="wall around every rod socket, mm")] = 1.6
    socket_depth: Annotated[float, Field(ge=4, le=40, description="how deep a rod goes into its socket, mm")] = 10
    seat: Annotated[float, Field(ge=0, le=20, description="minimum distance from a joint's centre to a socket bottom, mm (raised automatically where sockets meet at sharp angles)")] = 3.0
    fit_clearance: dict[str, Annotated[float, Field(ge=-0.4, le=1.0)]] = Field(
        default_factory=lambda: {"tpu_95a": -0.15},
        description="blind socket hole = rod diameter + this, per joint material, mm: negative is a press fit, the "
                    "TPU stretches round the rod and grips it (the authors' sockets: 2.70 mm for 3 mm rods, -0.30; "
                    "the presets too; a file without this key: -0.15, a lighter press); "
                    "tune with `cogniframe coupon`",
    )
    sleeve_clearance: Annotated[float, Field(ge=0.0, le=1.0, description="through-sleeve hole (a motor mount's sleeves, which a rod slides through) = rod diameter + this, mm (the authors' 3.20 mm for 3 mm rods: 0.20); tune with `cogniframe coupon`")] = 0.2
    hinge_thickness: Annotated[float, Field(ge=0.6, le=4, description="thickness of the living-hinge web where the frame folds, mm")] = 1.2


class BatterySection(_M):
    length: Annotated[float, Field(gt=10, le=200, description="mm")] = 70
    width: Annotated[float, Field(gt=10, le=100, description="mm")] = 35
    height: Annotated[float, Field(gt=3, le=60, description="mm")] = 15
    mass: Annotated[float, Field(gt=0, le=500, description="g")] = 58
    cells: Annotated[int, Field(ge=1, le=12, description="LiPo cells in series (3 = 3S, 11.1 V nominal)")] = 3
    capacity_mah: Annotated[float, Field(gt=0, le=100000, description="rated capacity, mAh")] = 650
    usable_fraction: Annotated[float, Field(gt=0, le=1, description="share of the capacity a flight may use (0.8 keeps a LiPo healthy)")] = 0.8
    connector: str = Field("XT30", description="battery lead connector; the holder leaves an exit for it: XT30, XT60 or JST-PH")


class ComputerSection(_M):
    name: str = "Raspberry Pi Zero"
    hole_spacing: tuple[Pos, Pos] = Field((58.0, 23.0), description="mounting hole rectangle, mm")
    screw: str = "M2.5"


class CameraSection(_M):
    model: str = Field("pi_camera_v2", description="camera vitamin (see cogniframe/vitamins.py)")
    tilt_deg: Annotated[float, Field(ge=-30, le=45, description="camera tilt above the horizon, degrees (0 = looking straight forward; the upright prints leaning, so at most 45)")] = 0.0


class FlowSensorSection(_M):
    model: str = Field("matek_3901_l0x", description="downward optical-flow + time-of-flight board (see cogniframe/vitamins.py)")


class CoreSection(_M):
    material: str = Field("abs", description="rigid core filament (ABS or PLA)")
    infill: Frac = Field(0.10, description="infill fraction of the core parts (0.10 = 10 %)")
    plate_size: Annotated[float, Field(ge=30, le=200, description="side of the square core plate, mm; the TPU core links sit just outside its corners")] = 40
    plate_thickness: Annotated[float, Field(ge=1.5, le=8, description="mm")] = 3.0
    holder_wall: Annotated[float, Field(ge=1.0, le=6, description="battery holder wall and floor thickness, mm")] = 2.0
    stack_pattern: str = Field("20x20", description="flight-controller/ESC stack hole pattern: 20x20 or 30.5x30.5")
    stack_screw: str = "M2"
    battery: BatterySection = BatterySection()
    battery_clearance: Annotated[float, Field(ge=3, le=80, description="height of the battery holder's underside above the ground when the frame stands, mm (the crash clearance)")] = 16
    computer: ComputerSection | None = ComputerSection()
    spacer_thickness: Annotated[float, Field(ge=0, le=10, description="the sensor mount / spacer between the battery holder and the core plate, mm: lifts the plate and its TPU links clear of the holder")] = 2.0
    strap_width: Annotated[float, Field(ge=5, le=30, description="hook-and-loop battery strap width, mm: sets the strap slots at the holder mouth")] = 10
    battery_lock: Literal["strap", "magnetic"] = Field("strap", description="what holds the pack in the holder: strap = a hook-and-loop strap across the mouth through two slots; magnetic = the authors' magnetic holder (CogniFly-STL v8 Battery_holder_magnetic_*): a lid (battery_lid) across the mouth held by four 6 x 2 mm N38 disc magnets glued into pockets in two bosses on the holder's mouth and in the lid, no strap and no slots; a swap is one pull, nothing to thread (+3.9 cm^3 of core material and 1.7 g of magnets on the carbon preset, less the 1.6 g strap)")
    camera: CameraSection | None = Field(None, description="camera bracket at the front of the core (needs a components line with vitamin: pi_camera_v2)")
    flow_sensor: FlowSensorSection | None = Field(None, description="downward optical-flow + ToF board behind the holder (needs a components line with vitamin: matek_3901_l0x)")
    support_holes: bool = Field(False, description="the authors' four 3.0 mm mounting holes on a 25.4 mm radius on the core's axes (CogniFly-STL v8 MainBase), where their Pi support (RPI_Support_new) and battery supports fix to the base: each in a 7 mm boss as deep as the pegs' tubes (the authors' 9.2 mm block), on a 7 mm bar from the pegged plate's centre (core.link: pegs); +3.2 cm^3 of core material on the carbon preset (+2.4 g printed)")
    link: Literal["tab", "pegs"] = Field("tab", description="how each arm's rod pair joins the core plate: pegs (the presets) = the authors' connector, one TPU peg per arm rod pressed into an ABS tube on the core plate, the strut on the link's arch (level arms only); tab = a flat TPU link bolted on the plate corner")


class MotorsSection(_M):
    model: str = Field("1104", description="motor preset (sets hole pattern, screw, size, mass): " + ", ".join(MOTOR_PRESETS))
    bolt_spacing: Annotated[float, Field(gt=3, le=40, description="override the preset's hole pattern: the distance between OPPOSITE holes, across the shaft, mm (a '9x9' motor reads 9: four holes on a 9 mm circle)")] | None = None
    screw: str | None = Field(None, description="override the preset's screw size")
    thread_depth: Annotated[float, Field(gt=0.5, le=10, description="override the preset's thread depth in the motor base, mm: how far a mounting screw may enter before it reaches the windings (measure yours)")] | None = None
    mass: Annotated[float, Field(gt=0, le=100, description="override the preset's mass, g each")] | None = None
    radius: Annotated[float, Field(ge=20, le=300, description="motor axis distance from the frame centre, in plan, mm")] = 82
    seat_raise: Annotated[float, Field(ge=0, le=15, description="raise each motor's seat (and its propeller) this far above the least the mount needs, mm: the authors' taller motor bases for 1106 and larger motors, whose bigger propellers reach over the core (CogniFly-STL v8 MotorBase_Shorter_Taller +5 mm, _Tallest +10 mm); the mount's webs grow by as much")] = 0
    prop_diameter: Annotated[float, Field(ge=25, le=260, description="propeller diameter, mm (3 in = 76.2)")] = 76.2
    prop_mass: Annotated[float, Field(ge=0, le=30, description="g each")] = 1.0
    max_thrust_g: Annotated[float, Field(gt=0, le=5000, description="static thrust of one motor at full throttle, g (thrust load case and thrust-to-weight); null = the flight tables' value for motors.model, kv, prop and the pack, else the motor class's typical value (1104 on 3S with 3025 props: 190 g; 1404 on 2S with 4 in props: 200 g)")] | None = None
    kv: Annotated[int, Field(ge=100, le=50000, description="motor KV (rpm per volt); null = the preset's")] | None = None
    prop: str | None = Field(None, description="propeller for the flight tables, e.g. 3025 or 4024; null = the one matching prop_diameter")
    props_out: bool = Field(False, description="propeller spin for the flight-controller mix and the simulator models (`cogniframe fly`): false = props in, Betaflight's and INAV's quad-X default (rear right and front left clockwise seen from above); true = props out, every motor reversed")


class Component(_M):
    name: str
    mass: Annotated[float, Field(ge=0, le=1000, description="g")]
    qty: Annotated[int, Field(ge=1, le=100)] = 1
    vitamin: str | None = Field(None, description="the bought part this line is, drawn in the assembly with this line's mass (see cogniframe/vitamins.py)")


class PrinterSection(_M):
    preset: Literal[tuple(PRINTERS)] | None = Field(  # type: ignore[valid-type]
        None, description="printer preset, sets bed and nozzle (keys given here override it): "
        + ", ".join(f"{k} ({p.name}, {p.bed[0]:g} x {p.bed[1]:g} x {p.bed[2]:g} mm)" for k, p in PRINTERS.items()))
    bed: tuple[Pos, Pos, Pos] = Field((120.0, 120.0, 120.0), description="build volume x, y, z, mm")
    nozzle: Annotated[float, Field(ge=0.1, le=1.2)] = 0.4
    layer_height: Annotated[float, Field(ge=0.05, le=0.6)] = 0.2
    perimeters: Annotated[int, Field(ge=1, le=10)] = 2
    top_bottom_layers: Annotated[int, Field(ge=1, le=20)] = 4
    margin: Annotated[float, Field(ge=0, le=20, description="gap between parts on a plate, mm")] = 4

    @model_validator(mode="before")
    @classmethod
    def _apply_preset(cls, data: Any) -> Any:
        """`preset: NAME` fills bed and nozzle from `printers.yaml`; keys written beside it win."""
        if not isinstance(data, dict) or data.get("preset") is None:
            return data
        name = data["preset"]
        if not isinstance(name, str) or name not in PRINTERS:
            guess = difflib.get_close_matches(str(name), list(PRINTERS), n=1, cutoff=0.4)
            hint = f"did you mean {guess[0]!r}? " if guess else ""
            raise _KeyProblem("printer.preset", f"unknown printer preset {name!r}",
                              f"{hint}use one of {', '.join(PRINTERS)} (`cogniframe printers` lists them), or remove "
                              f"`preset:` and give printer.bed and printer.nozzle yourself")
        return {**PRINTERS[name].fields(), **data}


class RequirementsSection(_M):
    mass_limit: Annotated[float, Field(gt=0, le=25000, description="all-up weight limit, g")] = 250
    design_drop_height_cm: Annotated[float, Field(ge=0, le=2000, description="the drop the frame must survive without a battery-holder strike, cm")] = 100
    clearance: Annotated[float, Field(gt=0, le=200, description="payload travel before the battery holder hits the ground, mm; null = from the geometry")] | None = None
    drop_heights_cm: tuple[Annotated[float, Field(gt=0, le=2000)], ...] = (50, 100, 150, 262)
    wall_impact_speed_m_s: Annotated[float, Field(ge=0, le=50, description="side-on wall impact speed the frame must take with no propeller or core part reaching the wall, m/s (the paper flew into walls at up to 7 m/s; this conservative linear model gives the presets 3.0 and 4.1 m/s, see docs/stiffness-model.md)")] = 2.5
    max_peak_g: Annotated[float, Field(gt=0, le=10000, description="highest predicted peak deceleration allowed at the design drop, G (as the logger sees it); null = no limit")] | None = None
    prop_margin: Annotated[float, Field(ge=0, le=100, description="every propeller disc clears every rod, part and vitamin by this, mm (the build's clash check)")] = 5.0
    min_thrust_to_weight: Annotated[float, Field(gt=0, le=20, description="full-throttle thrust over weight below this is a FAIL")] = 2.0


class ModelSection(_M):
    k_n_per_m: Annotated[float, Field(gt=0, le=1e7, description="measured stiffness (from `cogniframe fit`); null = predict from the frame")] | None = None
    c_n_s_per_m: Annotated[float, Field(gt=0, le=1e5, description="measured damping; null = from damping_ratio")] | None = None
    damping_ratio: Annotated[float, Field(gt=0, le=5, description="used when c_n_s_per_m is null (paper: 0.558)")] = 0.558
    stiffness_model: Literal["fe", "analytic", "surrogate"] = Field("fe", description="joint stiffness: fe = solid finite elements of each joint's CAD (cached, seconds per new joint), surrogate = a fit of that FE over the joint geometry (milliseconds, within a few per cent of the FE; the solid FE outside its training box; the sweeps' default), analytic = closed forms (trends only)")


class Spec(_M):
    """The whole design. Load with `load(path)`; derived lookups are methods."""

    name: str = Field("frame", description="design name, a file-name-safe slug (letters, digits, '-', '_', '.', "
                                            "not starting with '.', at most 64 characters); the output folder is out/<name>")
    materials: dict[str, MaterialDef] = Field(default_factory=dict, description="extra or overriding materials")
    frame: FrameSection = FrameSection()
    rods: RodsSection = RodsSection()
    joints: JointsSection = JointsSection()
    core: CoreSection = CoreSection()
    motors: MotorsSection = MotorsSection()
    components: tuple[Component, ...] = ()
    printer: PrinterSection = PrinterSection()
    requirements: RequirementsSection = RequirementsSection()
    model: ModelSection = ModelSection()

    _source: tuple[str, str | None] = PrivateAttr(default=("<params>", None))  # (file, its text): for error lines

    @field_validator("name")
    @classmethod
    def _name_is_a_slug(cls, v: str) -> str:
        if not NAME_RE.fullmatch(v):
            raise _KeyProblem("name", f"{v!r} is not a safe folder name (it becomes out/<name>/)",
                              f"use letters, digits, '-', '_' and '.', not starting with '.', at most 64 characters, "
                              f"for example `name: {slug(v)}`")
        return v

    @model_validator(mode="after")
    def _names_resolve(self) -> "Spec":
        lib = {**MATERIALS, **self.materials}
        for path, value in (("rods.material", self.rods.material), ("joints.material", self.joints.material),
                            ("core.material", self.core.material)):
            if value not in lib:
                raise _KeyProblem(path, f"unknown material {value!r}", f"use one of {', '.join(sorted(lib))}, or define it under `materials:`")
        if self.joints.material not in self.joints.fit_clearance:
            raise _KeyProblem("joints.fit_clearance", f"no fit clearance for the joint material {self.joints.material!r}",
                              f"add `{self.joints.material}: 0.1` under joints.fit_clearance (print `cogniframe coupon` to find yours)")
        for path, value, table in (("core.stack_pattern", self.core.stack_pattern, STACK_PATTERNS),
                                   ("core.stack_screw", self.core.stack_screw, SCREWS),
                                   ("motors.model", self.motors.model, MOTOR_PRESETS),
                                   ("motors.screw", self.motors.screw or "M2", SCREWS),
                                   ("core.computer.screw", self.core.computer.screw if self.core.computer else "M2", SCREWS)):
            if value not in table:
                raise _KeyProblem(path, f"unknown value {value!r}", f"use one of {', '.join(table)}")
        if self.core.battery.connector not in CONNECTORS:
            raise _KeyProblem("core.battery.connector", f"unknown connector {self.core.battery.connector!r}", f"use one of {', '.join(CONNECTORS)}")
        if self.motors.prop is not None and self.motors.prop not in PROPS:
            raise _KeyProblem("motors.prop", f"unknown propeller {self.motors.prop!r}", f"use one of {', '.join(PROPS)} (materials.PROPS), or null")
        for i, c in enumerate(self.components):
            if c.vitamin is not None and c.vitamin not in VITAMIN_KINDS:
                raise _KeyProblem(f"components.{i}.vitamin", f"unknown vitamin {c.vitamin!r}", f"use one of {', '.join(VITAMIN_KINDS)}, or leave it out")
        named = {c.vitamin for c in self.components if c.vitamin}
        for path, section in (("core.camera", self.core.camera), ("core.flow_sensor", self.core.flow_sensor)):
            if section is None:
                continue
            if section.model not in BOARDS or section.model not in VITAMIN_KINDS:
                raise _KeyProblem(f"{path}.model", f"unknown board {section.model!r}", "use pi_camera_v2 (camera) or matek_3901_l0x (flow sensor)")
            if section.model not in named:
                raise _KeyProblem(path, f"{section.model} is mounted on the core but no components line carries its mass",
                                  f"add `- {{name: {BOARDS[section.model].bom}, mass: {BOARDS[section.model].mass_g:g}, vitamin: {section.model}}}` under components, or set {path}: null")
        # A socket wall thinner than two extrusion lines prints as a single fragile line.
        min_wall = 2 * self.printer.nozzle
        if self.joints.wall < min_wall - 1e-9:
            raise _KeyProblem("joints.wall", f"{self.joints.wall} mm is thinner than two extrusion lines of the {self.printer.nozzle} mm nozzle",
                              f"set joints.wall to at least {min_wall:g}")
        if self.joints.socket_depth < 2 * self.rods.diameter - 1e-9:
            raise _KeyProblem("joints.socket_depth", f"{self.joints.socket_depth} mm holds a {self.rods.diameter} mm rod by less than two diameters and will let go on impact",
                              f"set joints.socket_depth to at least {2 * self.rods.diameter:g}")
        if self.joints.wall < 0.4 * self.rods.diameter - 1e-9:
            raise _KeyProblem("joints.wall", f"{self.joints.wall} mm of TPU around a {self.rods.diameter} mm rod splits on impact (needs 40 % of the rod diameter)",
                              f"set joints.wall to at least {0.4 * self.rods.diameter:.2f}")
        pr = self.printer
        if pr.layer_height > 0.8 * pr.nozzle + 1e-9:
            raise _KeyProblem("printer.layer_height", f"{pr.layer_height} mm layers are more than 80 % of the {pr.nozzle} mm nozzle; "
                              "slicers refuse or under-extrude them", f"set printer.layer_height to at most {0.8 * pr.nozzle:.2f}")
        if pr.layer_height < 0.15 * pr.nozzle - 1e-9:
            raise _KeyProblem("printer.layer_height", f"{pr.layer_height} mm layers are under 15 % of the {pr.nozzle} mm nozzle; "
                              "the slicer cannot extrude that little", f"set printer.layer_height to at least {0.15 * pr.nozzle:.2f}")
        if self.joints.hinge_thickness < 2 * pr.layer_height - 1e-9:
            raise _KeyProblem("joints.hinge_thickness", f"{self.joints.hinge_thickness} mm is less than two "
                              f"{pr.layer_height} mm layers: the living hinge would print as a single layer and tear",
                              f"set joints.hinge_thickness to at least {2 * pr.layer_height:g} or lower printer.layer_height")
        if self.core.holder_wall < 2 * pr.nozzle - 1e-9:
            raise _KeyProblem("core.holder_wall", f"{self.core.holder_wall} mm is thinner than two extrusion lines of the "
                              f"{pr.nozzle} mm nozzle", f"set core.holder_wall to at least {2 * pr.nozzle:g}")
        if pr.perimeters * pr.nozzle > 2 * self.joints.wall + 1e-9:
            raise _KeyProblem("printer.perimeters", f"{pr.perimeters} perimeters of the {pr.nozzle} mm nozzle are "
                              f"{pr.perimeters * pr.nozzle:.2f} mm thick, more than twice the {self.joints.wall} mm socket wall: the "
                              "slicer cannot place them and would print something other than what the mass model assumes",
                              f"set printer.perimeters to at most {max(1, int(2 * self.joints.wall / pr.nozzle + 1e-9))} or thicken joints.wall")
        if self.material(self.rods.material).printed:
            raise _KeyProblem("rods.material", f"{self.rods.material!r} is a printed filament; rods are never printed", "use carbon_rod or bamboo")
        if self.core.link == "pegs" and self.model.stiffness_model == "analytic":
            raise _KeyProblem("model.stiffness_model", "the analytic joint model has no closed form for the pegged core link (core.link: pegs)",
                              "set model.stiffness_model to fe or surrogate, or core.link to tab")
        if self.core.link == "pegs" and not self.frame.level_arms:
            raise _KeyProblem("core.link", "the pegged core link's pegs press into ABS tubes that lie on the bed under the "
                              "upside-down core plate, level with the arms; climbing arms (frame.level_arms: false) would "
                              "tilt them off the bed", "set frame.level_arms: true, or core.link: tab")
        if self.core.support_holes and self.core.link != "pegs":
            raise _KeyProblem("core.support_holes", "the mounting holes' bosses hang on the pegged core plate's X (the square "
                              "plate of core.link: tab has no bar out to a 25.4 mm radius)", "set core.link: pegs, or core.support_holes: false")
        core_half = self.core.plate_size / 2
        inner_half = min(self.frame.width, self.frame.depth) / 2 - self.frame.knee_inset - self.rods.diameter - 2 * self.joints.wall
        if core_half >= inner_half:
            raise _KeyProblem("core.plate_size", f"a {self.core.plate_size} mm core does not fit inside the {self.frame.width} x {self.frame.depth} mm frame with its knees",
                              f"make core.plate_size smaller than {2 * inner_half:.0f} or the frame larger")
        return self

    # -- derived lookups (pure) -------------------------------------------------------------
    def material(self, name: str) -> Material:
        if name in self.materials:
            d = self.materials[name]
            return Material(name, d.density_g_cm3, d.e_mpa, d.g_mpa, d.printed, d.source)
        return MATERIALS[name]

    @property
    def fit_clearance(self) -> float:
        """Socket hole clearance for the joint material, mm."""
        return self.joints.fit_clearance[self.joints.material]

    @property
    def bore(self) -> float:
        """Blind socket hole diameter, mm."""
        return self.rods.diameter + self.fit_clearance

    @property
    def sleeve_bore(self) -> float:
        """Through-sleeve hole diameter (a rod slides through), mm."""
        return self.rods.diameter + self.joints.sleeve_clearance

    @property
    def motor(self) -> MotorPreset:
        p = MOTOR_PRESETS[self.motors.model]
        holes = (self.motors.bolt_spacing,) * 2 if self.motors.bolt_spacing else p.holes
        return replace(p, holes=holes, screw=self.motors.screw or p.screw, mass_g=self.motors.mass or p.mass_g,
                       thread_depth=self.motors.thread_depth or p.thread_depth)

    @property
    def source(self) -> str:
        """The params file this spec was loaded from (or what `from_dict` was told)."""
        return self._source[0]

    def key_line(self, key: str) -> int | None:
        """Line of a dotted key path in the params file, or None (not written there: a default)."""
        return _line_no(self._source[1], tuple(key.split(".")))

    def error(self, key: str, problem: str, fix: str) -> UserError:
        """A UserError for a problem found after validation: names the file, the key with its line, the fix."""
        return UserError(f"{self.source}: {key}{_where(self, key)}: {problem}. Fix: {fix}.", key=key, located=True)

    def located(self, err: UserError) -> UserError:
        """`err` prefixed with the params file and, when it names one, its key and line (once)."""
        if err.located:
            return err
        key = f"{err.key}{_where(self, err.key)}: " if err.key else ""
        return UserError(f"{self.source}: {key}{err}", key=err.key, located=True)

    @contextmanager
    def blamed(self):
        """Inside it, a UserError that names a params key (from any later stage) gains the file and line."""
        try:
            yield self
        except UserError as e:
            if e.key is None or e.located:
                raise
            raise self.located(e) from None

    def digest(self, *sections: str) -> str:
        """sha256 of the named sections (all when none): a cache key for what a part uses."""
        data = self.model_dump(mode="json")
        if sections:
            data = {s: data[s] for s in sections}
        return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()


class _KeyProblem(ValueError):
    """A cross-field problem tied to one key path (turned into a UserError by `load`)."""

    def __init__(self, path: str, problem: str, fix: str):
        super().__init__(f"{problem}; fix: {fix}")
        self.path, self.problem, self.fix = path, problem, fix


NAME_RE = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9._-]{0,63}")


def slug(text: str) -> str:
    """A safe design name made from any text: 'My Frame v2/..' -> 'My-Frame-v2'."""
    s = re.sub(r"[^A-Za-z0-9._-]+", "-", text).strip("-.")[:64].strip("-.")
    return s or "frame"


def _where(spec: "Spec", key: str) -> str:
    line = spec.key_line(key)
    return f" (line {line})" if line else " (not set in the file: its default applies)"


# -- loading and error messages ------------------------------------------------------------

def load(path: str | Path) -> Spec:
    """Read and validate a params file. Raises UserError with a plain message on any problem."""
    path = Path(path)
    if not path.is_file():
        raise UserError(f"{path}: no such params file. Give the path of a YAML file such as params/bamboo.yaml.")
    text = decode(path.read_bytes(), path)
    data = parse_yaml(text, path)
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise UserError(f"{path}: the file must be a mapping of sections (frame:, rods:, joints: ...), not a "
                        f"{type(data).__name__}. Fix: start from a preset such as params/carbon.yaml (`cogniframe schema` lists every key).")
    data.setdefault("name", slug(path.stem))
    return from_dict(data, source=str(path), text=text)


def decode(raw: bytes, path: Path | str) -> str:
    """UTF-8 text of a file (a UTF-8 byte-order mark is fine); anything else is a UserError naming line and byte."""
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = raw.count(b"\n", 0, e.start) + 1
        col = e.start - (raw.rfind(b"\n", 0, e.start) + 1) + 1
        raise UserError(f"{path}: line {line}, column {col}: byte 0x{raw[e.start]:02x} is not UTF-8 (the file was probably "
                        f"saved as Latin-1 or Windows-1252). Fix: save the file as UTF-8 in your editor "
                        f"(or run `iconv -f latin1 -t utf-8`).") from None


class _UniqueKeys:
    """A SafeLoader mixin that refuses a key written twice in one mapping (PyYAML silently keeps the last)."""

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            seen: dict[object, int] = {}
            for k, _ in node.value:
                if k.tag == "tag:yaml.org,2002:merge":
                    continue
                key = self.construct_object(k, deep=True)
                line = k.start_mark.line + 1
                try:
                    first = seen.setdefault(key, line)
                except TypeError:  # unhashable key: let the normal constructor say so
                    continue
                if first != line:
                    raise _DuplicateKey(key, first, line)
        return super().construct_mapping(node, deep)


class _UniqueKeyLoader(_UniqueKeys, yaml.SafeLoader):
    """The pure-Python loader: its error messages are the ones `parse_yaml` reports (tests/bad_inputs/)."""


# libyaml's parser (PyYAML's C extension) reads a params file about five times faster; its
# constructor and resolver are the pure loader's, so a valid document gives the same data. Its
# error texts differ, so a document it refuses is parsed again by the pure loader for the message.
if getattr(yaml, "__with_libyaml__", False):
    class _FastUniqueKeyLoader(_UniqueKeys, yaml.CSafeLoader):
        """The libyaml loader (a valid document only: see `parse_yaml`)."""
else:  # a PyYAML built without libyaml: the pure loader alone
    _FastUniqueKeyLoader = None


class _DuplicateKey(Exception):
    def __init__(self, key, first: int, second: int):
        self.key, self.first, self.second = key, first, second


def parse_yaml(text: str, path: Path | str):
    """YAML -> Python, with plain UserErrors for syntax errors and duplicate keys."""
    if _FastUniqueKeyLoader is not None:
        try:
            return yaml.load(text, Loader=_FastUniqueKeyLoader)  # noqa: S506 (a CSafeLoader subclass)
        except (yaml.YAMLError, _DuplicateKey):
            pass  # the pure loader below says what is wrong, in its words
    try:
        return yaml.load(text, Loader=_UniqueKeyLoader)  # noqa: S506 (a SafeLoader subclass)
    except _DuplicateKey as e:
        raise UserError(f"{path}: key '{e.key}' is written twice in the same section, on line {e.first} and line {e.second}; "
                        f"only one value can count. Fix: delete one of the two lines.") from None
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise UserError(f"{path}: not valid YAML{where} ({getattr(e, 'problem', e)}). Fix the indentation or quoting there.") from None


def from_dict(data: dict[str, Any], source: str = "<params>", text: str | None = None) -> Spec:
    """Validate a params mapping; errors name `source` and the key path."""
    try:
        spec = Spec.model_validate(data)
    except ValidationError as e:
        raise UserError(_explain(e, source, text), located=True) from None
    spec._source = (source, text)
    return spec


def _explain(err: ValidationError, source: str, text: str | None) -> str:
    lines = []
    for item in err.errors():
        ctx_err = (item.get("ctx") or {}).get("error")
        if isinstance(ctx_err, _KeyProblem):
            loc = tuple(ctx_err.path.split("."))
            lines.append(f"{source}: {ctx_err.path}{_line(text, loc)}: {ctx_err.problem}. Fix: {ctx_err.fix}.")
            continue
        loc = tuple(str(p) for p in item["loc"])
        key = ".".join(loc) or "(top level)"
        if item["type"] == "extra_forbidden":
            valid = _valid_keys(loc[:-1])
            guess = difflib.get_close_matches(loc[-1], valid, n=1, cutoff=0.5)
            hint = f"did you mean '{guess[0]}'? " if guess else ""
            lines.append(f"{source}: {key}{_line(text, loc)}: unknown key. Fix: {hint}valid keys here are {', '.join(valid)}.")
        else:
            got = item.get("input")
            got_s = "" if isinstance(got, (dict, list)) else f" (got {got!r})"
            lines.append(f"{source}: {key}{_line(text, loc)}: {item['msg'].lower()}{got_s}. Fix: {_fix_hint(loc)}")
    return "\n".join(lines)


def _model_at(loc: tuple[str, ...]) -> type[BaseModel] | None:
    model: Any = Spec
    for part in loc:
        if part.isdigit():
            continue
        field = model.model_fields.get(part) if isinstance(model, type) and issubclass(model, BaseModel) else None
        if field is None:
            return None
        ann = field.annotation
        candidates = [ann, *getattr(ann, "__args__", ())]
        for c in candidates:
            for cc in (c, *getattr(c, "__args__", ())):
                if isinstance(cc, type) and issubclass(cc, BaseModel):
                    model = cc
                    break
            else:
                continue
            break
        else:
            return None
    return model if isinstance(model, type) and issubclass(model, BaseModel) else None


def _valid_keys(loc: tuple[str, ...]) -> list[str]:
    model = _model_at(loc)
    return list(model.model_fields) if model else []


def _fix_hint(loc: tuple[str, ...]) -> str:
    model = _model_at(loc[:-1])
    field = model.model_fields.get(loc[-1]) if model else None
    desc = field.description if field and field.description else None
    for meta in getattr(field, "metadata", []) if field else []:
        bounds = [f"{op} {getattr(meta, attr)}" for attr, op in (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<="))
                  if getattr(meta, attr, None) is not None]
        if bounds:
            desc = (desc + "; " if desc else "") + "must be " + " and ".join(bounds)
    return f"set {'.'.join(loc)} to a valid value ({desc})." if desc else f"check the value of {'.'.join(loc)}."


def _line(text: str | None, loc: tuple[str, ...]) -> str:
    """' (line N)' for a key path in the YAML source, when it can be found."""
    line = _line_no(text, loc, partial=True)
    return f" (line {line})" if line else ""


def _compose(text: str):
    """The YAML node tree of `text` (keys with their lines), None when it is not valid YAML. libyaml's
    composer first (a check that words a problem with a key's line asks for it: ~2 ms instead of
    ~15), the pure one for a document libyaml refuses."""
    for loader in ((yaml.CSafeLoader,) if _FastUniqueKeyLoader is not None else ()) + (yaml.SafeLoader,):
        try:
            return yaml.compose(text, Loader=loader)  # noqa: S506 (safe loaders)
        except yaml.YAMLError:
            continue
    return None


def _line_no(text: str | None, loc: tuple[str, ...], partial: bool = False) -> int | None:
    """Line of the key path `loc` in the YAML source; None if it is not written there (with `partial`,
    the line of the deepest part of the path that is)."""
    if not text:
        return None
    node = _compose(text)
    if node is None:
        return None
    line = None
    for part in loc:
        if isinstance(node, yaml.MappingNode):
            for k, v in node.value:
                if k.value == part:
                    line, node = k.start_mark.line + 1, v
                    break
            else:
                return line if partial else None
        elif isinstance(node, yaml.SequenceNode) and part.isdigit() and int(part) < len(node.value):
            node = node.value[int(part)]
            line = node.start_mark.line + 1
        else:
            return line if partial else None
    return line


def json_schema() -> dict:
    """JSON Schema of a params file, for editor autocompletion."""
    return Spec.model_json_schema()

