"""Materials library and the small hardware tables the params refer to by name.

Densities in g/cm^3, moduli in MPa (N/mm^2). Values are typical datasheet or literature
figures, each with its source noted; a params file can add or override materials under
`materials:`. Hardware tables follow cq_warehouse's pattern: a dict of sizes and a lookup that
raises ValueError listing the valid choices.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Material:
    """A material: density_g_cm3 (g/cm^3), e_mpa (Young's modulus), g_mpa (shear modulus)."""

    name: str
    density_g_cm3: float
    e_mpa: float
    g_mpa: float
    printed: bool
    source: str

    @property
    def density_g_mm3(self) -> float:
        return self.density_g_cm3 / 1000.0


# fmt: off
MATERIALS: dict[str, Material] = {m.name: m for m in (
    # Pultruded carbon rod, ~60 % fibre volume: rho 1.55-1.60, E 120-140 GPa along the rod,
    # in-plane shear 4-6 GPa (typical pultruded CFRP rod datasheets).
    Material("carbon_rod", 1.55, 125_000.0, 5_000.0, False,
             "typical pultruded CFRP rod datasheet (rho 1.55, E 120-140 GPa, G 4-6 GPa)"),
    # Bamboo along the grain (BBQ skewers are culm wall): rho 0.6-0.8, E 15-20 GPa, G ~1 GPa.
    Material("bamboo", 0.70, 15_000.0, 1_000.0, False,
             "bamboo culm, along grain: rho 0.6-0.8, E 15-20 GPa (Janssen, Mechanical properties of bamboo)"),
    # TPU 95A: Ultimaker TPU 95A TDS: 1.22 g/cm^3, tensile modulus 26 MPa; nu ~0.48 -> G = E/2.96.
    Material("tpu_95a", 1.22, 26.0, 8.8, True,
             "Ultimaker TPU 95A technical data sheet (1.22 g/cm^3, E 26 MPa); G from nu = 0.48"),
    # ABS: Ultimaker ABS TDS 1.10 g/cm^3, tensile modulus 1681 MPa (printed); nu 0.35.
    Material("abs", 1.10, 1681.0, 623.0, True,
             "Ultimaker ABS technical data sheet (1.10 g/cm^3, E 1681 MPa printed); G from nu = 0.35"),
    # PLA: Ultimaker PLA TDS 1.24 g/cm^3, tensile modulus 2346 MPa (printed); nu 0.36.
    Material("pla", 1.24, 2346.0, 862.0, True,
             "Ultimaker PLA technical data sheet (1.24 g/cm^3, E 2346 MPa printed); G from nu = 0.36"),
    # PETG: typical filament TDS 1.27 g/cm^3, E ~2100 MPa; nu 0.38.
    Material("petg", 1.27, 2100.0, 761.0, True,
             "typical PETG filament data sheet (1.27 g/cm^3, E 2.0-2.2 GPa); G from nu = 0.38"),
)}
# fmt: on


@dataclass(frozen=True)
class Strength:
    """What a material takes before it is damaged, for `check`'s survival sweep: a stress (MPa)
    for rods and the rigid core, or a strain (elongation at break, 1 = 100 %) for the joints'
    elastomer. Handbook or datasheet values, never fitted to a drop outcome."""

    name: str
    mode: str  # "bending" (flexural strength), "yield" (tensile yield), "elongation" (strain at break)
    value: float  # MPa for stresses; a strain for "elongation"
    source: str


# fmt: off
STRENGTHS: dict[str, Strength] = {s.name: s for s in (
    # Pultruded carbon/epoxy rod along the fibres: flexural strength 1.4-2.0 GPa in rod makers'
    # datasheets (unidirectional ~60 % fibre volume); the low end, as the rods are cut and
    # clamped in sockets.
    Strength("carbon_rod", "bending", 1400.0,
             "pultruded CFRP rod datasheets: flexural strength 1.4-2.0 GPa (the low end)"),
    # Bamboo along the grain: modulus of rupture 80-250 MPa, rising with density (Dixon & Gibson,
    # J. R. Soc. Interface 2014, Moso bamboo; Janssen, Mechanical properties of bamboo); skewers
    # are thin culm wall of ~0.7 g/cm^3: about 140 MPa.
    Strength("bamboo", "bending", 140.0,
             "bamboo along the grain, modulus of rupture 80-250 MPa by density (Dixon & Gibson 2014; Janssen): 140 MPa at 0.7 g/cm^3"),
    # TPU 95A: Ultimaker TPU 95A TDS, elongation at break 580 % (ISO 527).
    Strength("tpu_95a", "elongation", 5.8, "Ultimaker TPU 95A technical data sheet: elongation at break 580 % (ISO 527)"),
    # Printed ABS / PLA / PETG: tensile stress at yield of printed test bars (Ultimaker TDS: ABS
    # 39 MPa, PLA 49.5 MPa; PETG typical 45-50 MPa). Solid bars: a 10 % infill part is weaker.
    Strength("abs", "yield", 39.0, "Ultimaker ABS technical data sheet: tensile stress at yield 39 MPa (printed bars)"),
    Strength("pla", "yield", 49.5, "Ultimaker PLA technical data sheet: tensile stress at yield 49.5 MPa (printed bars)"),
    Strength("petg", "yield", 45.0, "typical PETG filament data sheets: tensile yield 45-50 MPa (the low end)"),
)}
# fmt: on


def strength(material: str) -> Strength | None:
    """The library strength of a material by name; None for a material the library does not know
    (a params file's own material: its parts are then not assessed for damage)."""
    return STRENGTHS.get(material)


@dataclass(frozen=True)
class Screw:
    """Metric machine screw: nominal diameter, clearance hole and head diameter (mm), mass per 6 mm screw (g)."""

    name: str
    d: float
    clearance_d: float
    head_d: float
    nut_af: float
    mass_g: float


SCREWS: dict[str, Screw] = {
    # ISO 273 medium clearance holes; ISO 4762 heads; ISO 4032 nut widths across flats.
    "M2": Screw("M2", 2.0, 2.4, 3.8, 4.0, 0.25),
    "M2.5": Screw("M2.5", 2.5, 2.9, 4.5, 5.0, 0.4),
    "M3": Screw("M3", 3.0, 3.4, 5.5, 5.5, 0.6),
}

# Flight-controller stack hole spacing (square, mm) and the board outline it implies (mm).
STACK_PATTERNS: dict[str, tuple[float, float]] = {
    "20x20": (20.0, 27.0),
    "30.5x30.5": (30.5, 36.0),
}


@dataclass(frozen=True)
class MotorPreset:
    """Brushless motor: square bolt spacing (mm), screw, bell diameter and height (mm), mass (g)."""

    name: str
    bolt_spacing: float
    screw: str
    bell_d: float
    height: float
    mass_g: float
    shaft_boss_d: float


MOTOR_PRESETS: dict[str, MotorPreset] = {
    # 1104 class (paper's carbon build): 9 x 9 mm M2 pattern, ~14 mm bell, ~6 g.
    "1104": MotorPreset("1104", 9.0, "M2", 14.0, 13.0, 6.0, 5.0),
    # 1404 class (bamboo build): 9 x 9 mm M2 pattern, ~18 mm bell, ~9 g.
    "1404": MotorPreset("1404", 9.0, "M2", 18.0, 15.0, 9.0, 5.5),
}


def lookup(table: dict, name: str, what: str):
    """Return table[name] or raise ValueError listing the valid choices."""
    try:
        return table[name]
    except KeyError:
        raise ValueError(
            f"unknown {what} {name!r}; valid choices: {', '.join(sorted(table))}"
        ) from None


# -- vitamins: the bought parts the aircraft carries ---------------------------------
# NopSCADlib / cq_warehouse style: one table per family, each entry its own dimensions and BOM
# line. Masses here are the catalogue figures shown in the BOM; the mass budget uses the params'
# `components:` line that names the vitamin (`vitamin: pi_zero`), so nothing is counted twice.


@dataclass(frozen=True)
class Board:
    """A bought circuit board: outline (x across, y along, thickness), the component block on
    top (x, y, height), square-ish mounting-hole rectangle (mm), hole diameter, catalogue mass (g)."""

    name: str
    bom: str
    size: tuple[float, float, float]
    parts_block: tuple[float, float, float]
    holes: tuple[float, float]
    hole_d: float
    mass_g: float
    lens: tuple[float, float] | None = None  # camera: lens barrel diameter, height above the board (mm)
    source: str = ""


BOARDS: dict[str, Board] = {b.name: b for b in (
    # Raspberry Pi Zero / Zero W mechanical drawing: 65 x 30 mm, 1.4 mm PCB, M2.5 holes on 58 x 23 mm.
    Board("pi_zero", "Raspberry Pi Zero W", (65.0, 30.0, 1.4), (50.0, 24.0, 3.5), (58.0, 23.0), 2.75, 9.0,
          source="Raspberry Pi Zero mechanical drawing (65 x 30 mm, holes 58 x 23 mm, 9 g)"),
    # Raspberry Pi camera module v2: 25 x 24 x 1 mm board, M2 holes on 21 x 12.5 mm, 8.5 mm lens module ~5 mm tall.
    Board("pi_camera_v2", "Raspberry Pi camera module v2", (25.0, 24.0, 1.0), (8.5, 8.5, 1.0), (21.0, 12.5), 2.2, 3.0,
          lens=(8.5, 5.0), source="Raspberry Pi camera v2 mechanical drawing (25 x 24 mm, holes 21 x 12.5 mm, 3 g)"),
    # Matek 3901-L0X: PMW3901 optical flow (42 deg FOV, > 80 mm) + VL53L0X ToF (27 deg, 20-2000 mm), 36 x 13 mm, 2 g.
    Board("matek_3901_l0x", "Matek 3901-L0X optical flow + ToF", (36.0, 13.0, 1.0), (20.0, 9.0, 2.5), (0.0, 0.0), 0.0, 2.0,
          source="Matek 3901-L0X product page: 36 x 13 mm, 2 g; PMW3901 FOV 42 deg, VL53L0X FOV 27 deg"),
    # 20 x 20 mm stack boards (Kakute F7 Mini class FC, 4-in-1 ESC): 27 x 27 mm outline, M2 on 20 x 20 mm.
    Board("fc_20x20", "flight controller (20 x 20 mm stack)", (27.0, 27.0, 1.6), (22.0, 22.0, 2.0), (20.0, 20.0), 2.2, 6.0,
          source="Holybro Kakute F7 Mini outline: 27 x 27 mm board, 20 x 20 mm M2 holes"),
    Board("esc_20x20", "4-in-1 ESC (20 x 20 mm stack)", (27.0, 27.0, 1.6), (22.0, 22.0, 3.0), (20.0, 20.0), 2.2, 8.0,
          source="typical 20 x 20 4-in-1 ESC: 27 x 27 mm, 20 x 20 mm M2 holes"),
    Board("fc_30x30", "flight controller (30.5 x 30.5 mm stack)", (36.0, 36.0, 1.6), (30.0, 30.0, 2.0), (30.5, 30.5), 3.2, 8.0,
          source="typical 30.5 x 30.5 FC: 36 x 36 mm board"),
    Board("esc_30x30", "4-in-1 ESC (30.5 x 30.5 mm stack)", (36.0, 36.0, 1.6), (30.0, 30.0, 3.5), (30.5, 30.5), 3.2, 12.0,
          source="typical 30.5 x 30.5 4-in-1 ESC: 36 x 36 mm board"),
)}

# What a `components:` line may name as its vitamin, and the board(s) drawn for it.
VITAMIN_KINDS: dict[str, tuple[str, ...]] = {
    "pi_zero": ("pi_zero",), "pi_camera_v2": ("pi_camera_v2",), "matek_3901_l0x": ("matek_3901_l0x",),
    "fc": ("fc",), "esc": ("esc",), "fc_esc_stack": ("fc", "esc"),
}


@dataclass(frozen=True)
class Connector:
    """Battery lead connector: housing width x height (mm) the lead exit must pass, mass (g)."""

    name: str
    width: float
    height: float
    length: float
    source: str


CONNECTORS: dict[str, Connector] = {
    "XT30": Connector("XT30", 10.2, 5.2, 15.4, "AMASS XT30 drawing: 10.2 x 5.2 mm housing"),
    "XT60": Connector("XT60", 15.8, 8.2, 16.0, "AMASS XT60 drawing: 15.8 x 8.2 mm housing"),
    "JST-PH": Connector("JST-PH", 6.0, 4.5, 8.0, "JST PH 2-pin housing, about 6 x 4.5 mm"),
}


@dataclass(frozen=True)
class Propeller:
    """A propeller: diameter and pitch (mm), blades, the height its blades sweep (the disc drawn in
    the assembly and kept clear by requirements.prop_margin), catalogue mass (g)."""

    name: str
    bom: str
    diameter_mm: float
    pitch_mm: float
    blades: int
    swept_height_mm: float
    mass_g: float
    source: str


PROPS: dict[str, Propeller] = {p.name: p for p in (
    # The paper's carbon build: 3 x 2.5 in two-blade polycarbonate props on 1104 motors.
    Propeller("3025", "3 x 2.5 in two-blade propeller (polycarbonate)", 76.2, 63.5, 2, 3.0, 1.5,
              "the authors' BOM (3025 two-blade PC); swept height: a 2.5 in pitch blade at 75 % radius, ~8 mm chord"),
    # The bamboo build's 4 in props.
    Propeller("4024", "4 x 2.4 in two-blade propeller", 101.6, 61.0, 2, 3.0, 2.5,
              "the bamboo build's 4 in props; 2.4 in pitch class"),
)}
