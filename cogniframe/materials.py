"""Materials library and the small hardware tables the params refer to by name.

Densities in g/cm^3, moduli in MPa (N/mm^2). Values are typical datasheet or literature
figures, each with its source noted; a params file can add or override materials under
`materials:`. Hardware tables follow cq_warehouse's pattern: a dict of sizes and a lookup that
raises ValueError listing the valid choices.
"""

from __future__ import annotations

import math
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
    """Metric socket-head cap screw (ISO 4762) of one size: nominal diameter d, thread pitch, the
    clearance hole a printed part gives it, head diameter and height, the hex nut's width across
    flats and thickness (ISO 4032), mass per 6 mm screw (g), and the stock lengths sold."""

    name: str
    d: float
    clearance_d: float
    head_d: float
    nut_af: float
    mass_g: float
    pitch: float = 0.4
    head_h: float = 2.0
    nut_m: float = 1.6
    lengths: tuple[float, ...] = (3, 4, 5, 6, 8, 10, 12, 16, 20)
    source: str = ""

    def mass_of(self, length: float) -> float:
        """Catalogue mass of one screw `length` mm long (g): the table's 6 mm screw, the shank scaled."""
        return round(self.mass_g * length / 6.0, 3)


SCREWS: dict[str, Screw] = {
    # ISO 273 medium clearance holes; ISO 4762 heads (dk, k); ISO 4032 nuts (s, m); ISO 261 pitch;
    # stock lengths: the ISO 4762 preferred lengths sold for these sizes.
    "M1.4": Screw("M1.4", 1.4, 1.6, 2.6, 3.0, 0.12, 0.3, 1.4, 1.2, (3, 4, 5, 6, 8),
                  "ISO 4762 M1.4: dk 2.6, k 1.4; ISO 4032 (DIN 934) M1.4 nut s 3.0, m 1.2; ISO 273 medium clearance 1.6; pitch 0.3"),
    "M2": Screw("M2", 2.0, 2.4, 3.8, 4.0, 0.25, 0.4, 2.0, 1.6, (3, 4, 5, 6, 8, 10, 12, 16, 20, 25, 30),
                "ISO 4762 M2: dk 3.8, k 2.0; ISO 4032 M2 nut s 4.0, m 1.6; ISO 273 medium clearance 2.4; pitch 0.4; "
                "25 and 30 mm: DIN 912's M2 lengths, an FC stack's screws"),
    "M2.5": Screw("M2.5", 2.5, 2.9, 4.5, 5.0, 0.4, 0.45, 2.5, 2.0, (4, 5, 6, 8, 10, 12, 16, 20, 25),
                  "ISO 4762 M2.5: dk 4.5, k 2.5; ISO 4032 M2.5 nut s 5.0, m 2.0; ISO 273 medium clearance 2.9; pitch 0.45"),
    "M3": Screw("M3", 3.0, 3.4, 5.5, 5.5, 0.6, 0.5, 3.0, 2.4, (4, 5, 6, 8, 10, 12, 16, 20, 25, 30),
                "ISO 4762 M3: dk 5.5, k 3.0; ISO 4032 M3 nut s 5.5, m 2.4; ISO 273 medium clearance 3.4; pitch 0.5"),
}

# ISO 7046-1 (cross-recessed countersunk, 90 deg) head diameter dk and height k, mm: the M2 head
# is 3.8 across and 1.2 tall, so it sits flush in a 1.6 mm wall (ISO 7046-1 starts at M1.6: the
# M1.4 row scales its M1.6 head, 3.0 x 0.96, to the thread).
COUNTERSUNK = {"M1.4": (2.6, 0.84), "M2": (3.8, 1.2), "M2.5": (4.7, 1.5), "M3": (5.5, 1.65)}
COUNTERSINK_SLACK = 0.2  # mm: a printed countersink's mouth is this much wider than the head

# A screw holds in a thread by at least this many full turns of its pitch (4 pitches: 1.6 mm of
# an M2). Motor bases are thin aluminium: their thread is what limits the screw, so the fit check
# asks for this much and never more than the motor's thread depth.
MIN_THREAD_TURNS = 4


@dataclass(frozen=True)
class Insert:
    """A heat-set threaded insert: thread, the hole a printed part gives it, its length (mm), mass (g)."""

    name: str
    screw: str
    hole_d: float
    length: float
    outer_d: float
    mass_g: float
    source: str


INSERTS: dict[str, Insert] = {i.name: i for i in (
    Insert("insert_M2", "M2", 3.2, 4.0, 3.6, 0.1, "Ruthex RX-M2x4 heat-set insert datasheet: hole 3.2 mm, length 4.0 mm, outer 3.6 mm"),
    Insert("insert_M2.5", "M2.5", 3.6, 5.7, 4.6, 0.15, "Ruthex RX-M2.5x5.7 heat-set insert datasheet: hole 3.6 mm, length 5.7 mm, outer 4.6 mm"),
    Insert("insert_M3", "M3", 4.0, 5.7, 4.6, 0.2, "Ruthex RX-M3x5.7 heat-set insert datasheet: hole 4.0 mm, length 5.7 mm, outer 4.6 mm"),
)}


# Flight-controller stack hole spacing and the board outline it implies (mm). Stacks are quoted
# as a SQUARE: "20x20" is four holes on the corners of a 20 mm square (28.3 mm across the
# diagonal), unlike a motor's pattern (MotorPreset.holes).
STACK_PATTERNS: dict[str, tuple[float, float]] = {
    "20x20": (20.0, 27.0),
    "30.5x30.5": (30.5, 36.0),
}


@dataclass(frozen=True)
class MotorPreset:
    """A brushless motor class as its makers quote it.

    `holes`: the mounting pattern the FPV way, centre to centre ACROSS THE SHAFT: "9x9" is one
    opposite pair of holes 9 mm apart and the other pair, at 90 deg to it, 9 mm apart too -- four
    holes on a 9 mm circle, 4.5 mm from the shaft axis (not a 9 mm square). A two-pair pattern
    such as "16x19" is (16, 19): the first pair 16 mm apart, the second 19 mm. `screw`: the
    thread in the motor's base; `thread_depth`: how far a screw may enter it before it reaches
    the windings (the screw must engage the thread and stop short of this). Bell diameter and
    height over the base (mm), mass (g), shaft boss diameter (mm), typical full-throttle thrust
    of one motor on its usual propeller and pack (g), and the source of the numbers."""

    name: str
    holes: tuple[float, float]
    screw: str
    bell_d: float
    height: float
    mass_g: float
    shaft_boss_d: float
    thread_depth: float = 2.5
    thrust_g: float = 190.0
    source: str = ""

    @property
    def bolt_spacing(self) -> float:
        """The first pair's centre-to-centre distance across the shaft (mm)."""
        return self.holes[0]

    @property
    def pattern(self) -> str:
        """The pattern as makers print it: 9x9, 16x19."""
        return "x".join(f"{h:g}" for h in self.holes)

    def hole_points(self, turn_deg: float = 0.0) -> tuple[tuple[float, float], ...]:
        """The four hole centres (x, y) about the shaft axis (mm): the first pair on the line at
        `turn_deg` from x, the second pair across it."""
        a = math.radians(turn_deg)
        u, v = (math.cos(a), math.sin(a)), (-math.sin(a), math.cos(a))
        out = []
        for r, w in ((self.holes[0] / 2, u), (self.holes[1] / 2, v)):
            out += [(r * w[0], r * w[1]), (-r * w[0], -r * w[1])]
        return tuple((round(x, 9) + 0.0, round(y, 9) + 0.0) for x, y in out)


# Where the numbers come from. The stored sources reachable here hold no maker's product page for
# these motors; what they hold are public build notes and part records that quote a maker's page
# (named in each `source` with the page they cite). A figure no source gives stays as the class's
# estimate and the source says so. Thread depth: no maker of these motors prints one; it is the
# motor base's tapped depth the class leaves under the stator (the authors warn that long screws
# reach the windings). Bell diameter and height over the base and the shaft boss: no source found
# gives them, so they stay estimates for every class. Typical thrust: the class on its usual
# propeller and pack, for motors.max_thrust_g's default when analysis/flight.py has no bench table.
_EST = "bell, height, shaft boss and thread depth are estimates (no maker figure found)"
# The 6.6 mm class: tiny-whoop motors commonly carry THREE M1.4 holes at 120 deg on a 6.6 mm
# circle (a public FPV glossary's motor-mounting entry; a public CadQuery tiny-whoop frame puts
# n_holes = 3 on a 6.6 mm circle), while hole_points draws four: a plate drilled from these
# entries must be checked against the motor in hand.
_WHOOP = ("pattern NOT confirmed by any maker's page in the stored sources: whoop-class motors are "
          "commonly three M1.4 holes on a 6.6 mm circle, and hole_points draws four -- measure the motor")

# fmt: off
MOTOR_PRESETS: dict[str, MotorPreset] = {m.name: m for m in (
    MotorPreset("1103", (6.6, 6.6), "M1.4", 13.5, 11.0, 3.7, 4.0, 1.5, 90.0,
                f"reference Happymodel EX1103 / BetaFPV 1103 (not found in the stored sources); {_WHOOP}; "
                f"mass 3.7 g and thrust 90 g are estimates; {_EST}"),
    # 1104 class (the paper's carbon build): the authors' motor base (CogniFly_v8 Flex_MotorBase_Shorter)
    # has its four 2.0 mm holes 4.5 mm from the centre -- the 9x9 pattern read across the shaft -- and a
    # 4.1 mm shaft hole; the seat under the motor is 2.5 mm thick there.
    MotorPreset("1104", (9.0, 9.0), "M2", 14.0, 13.0, 5.3, 5.0, 2.5, 190.0,
                "the authors' motor base (CogniFly-STL v8 Flex_MotorBase_Shorter: holes 4.5 mm from the axis); "
                "reference BetaFPV LAVA 1104 5500KV: 4 x M2 on a 9 mm circle, 1.5 mm shaft, 5.3 g (BetaFPV page "
                "betafpv.com/products/lava-series-1104-brushless-motors as quoted in a public Pavo20 Pro motor survey); "
                "thrust 190 g is an estimate for 3025 on 3S (BetaFPV's only figure, >230 g, is on 4S with a Gemfan "
                "D2.2-3); not every 1104 is 9x9 M2 (the same survey: DarwinFPV Bling 1104 is 8.5 mm M1.6); " + _EST),
    MotorPreset("1105", (9.0, 9.0), "M2", 14.0, 13.5, 5.2, 5.0, 2.5, 210.0,
                "reference BetaFPV 1105 5000KV: 9 mm, M2, 5.2 g (BetaFPV page betafpv.com/products/1105-6000kv-motors-4-pcs "
                "as quoted in a public Pavo20 Pro motor survey); thrust 210 g is an estimate (no published figure "
                f"found); {_EST}"),
    MotorPreset("1106", (9.0, 9.0), "M2", 14.4, 14.0, 6.6, 5.0, 2.5, 240.0,
                "reference BetaFPV 1106 / EMAX RS1106: pattern NOT confirmed by any maker's page in the stored "
                "sources (9x9 M2 is the class's recollection); mass 6.6 g and thrust 240 g are estimates (a public "
                f"script puts an EMAX RS1106 7500KV at 7 g, not a maker's figure); {_EST}"),
    MotorPreset("1202", (6.6, 6.6), "M1.4", 15.0, 10.5, 3.6, 4.0, 1.5, 110.0,
                f"reference BetaFPV 1202.5 (not found in the stored sources); {_WHOOP}; mass 3.6 g and thrust "
                f"110 g are estimates; {_EST}"),
    MotorPreset("1203", (6.6, 6.6), "M1.4", 15.0, 11.5, 4.0, 4.0, 1.5, 130.0,
                f"reference Happymodel EX1203 (not found in the stored sources); {_WHOOP}; mass 4 g and thrust "
                f"130 g are estimates; {_EST}"),
    MotorPreset("1204", (9.0, 9.0), "M2", 15.5, 12.5, 6.2, 5.0, 2.5, 200.0,
                "reference Flashhobby A1204 5200KV: 9 mm, M2, 6.2 g (Rotorama's product page "
                "rotorama.com/product/flashhobby-a1204-5200kv as quoted in a public Pavo20 Pro motor survey; a "
                "retailer's page, not the maker's); thrust 200 g is an estimate (no published figure found); " + _EST),
    # 1404 class (the bamboo build): iFlight XING2 1404 (product page via its part record): 9x9 mm M2
    # base pattern, 1.5 mm shaft.
    MotorPreset("1404", (9.0, 9.0), "M2", 18.0, 15.0, 9.34, 5.5, 3.0, 200.0,
                "reference iFlight XING2 1404 3800KV Unibell: 9 x 9 mm M2 base pattern, 1.5 mm shaft (protoboard.xyz "
                "part record iflight-xing2-1404-3800kv-unibell, citing shop.iflight.com/xing2-1404-toothpick-ultralight-"
                "build-unibell-pro1482); mass from T-Motor F1404 3800KV: 9.34 g with leads, 7.75 g without (Pyrodrone's "
                "product page as quoted in a public sub-250 g build survey; no XING2 1404 mass found); thrust 200 g is "
                f"an estimate (no published figure found); {_EST}"),
    MotorPreset("1406", (9.0, 9.0), "M2", 18.5, 16.0, 10.5, 5.5, 3.0, 260.0,
                "reference BrotherHobby 1406 (not found in the stored sources): pattern NOT confirmed by any maker's "
                f"page (9x9 M2 is the class's recollection); mass 10.5 g and thrust 260 g are estimates; {_EST}"),
    MotorPreset("1407", (9.0, 9.0), "M2", 18.5, 16.5, 11.0, 5.5, 3.0, 290.0,
                "reference T-Motor F1407 (not found in the stored sources): pattern NOT confirmed by any maker's page "
                f"(9x9 M2 is the class's recollection); mass 11 g and thrust 290 g are estimates; {_EST}"),
    MotorPreset("1408", (12.0, 12.0), "M2", 19.0, 17.0, 12.5, 6.0, 3.0, 330.0,
                "reference iFlight XING 1408 (not found in the stored sources): pattern NOT confirmed by any maker's "
                f"page (12x12 M2 is the class's recollection); mass 12.5 g and thrust 330 g are estimates; {_EST}"),
    MotorPreset("1505", (12.0, 12.0), "M2", 20.0, 16.5, 12.8, 6.0, 3.0, 554.0,
                "reference Diatone MAMBA TOKA 1505 3800KV: 12 x 12 mm M2, 1.5 mm shaft (Diatone's page), 12.8 g "
                "(retail listings), both as quoted in a public sub-250 g build's compatibility notes (an earlier "
                "revision of the same notes said 9 mm and 6.5 g and was corrected); thrust: DeepSpace Aether 1505 "
                "4000KV, 554 g at full throttle on a 3.5 in prop and 4S (the maker's bench test, as quoted in the "
                f"same notes; no Diatone thrust found); {_EST}"),
)}
# fmt: on


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
    top (x, y, height), the mounting holes as a RECTANGLE's sides, centre to centre (mm: a stack's
    "20x20" is a 20 mm square, the Pi Zero's 58 x 23 a rectangle; not a motor's across-the-shaft
    reading), hole diameter, catalogue mass (g)."""

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
