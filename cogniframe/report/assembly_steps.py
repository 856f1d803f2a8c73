"""Assembly instructions: numbered steps derived from the frame graph, "fold as you assemble".

The paper's order: top and bottom rings, corners, connect and fold the sides, then arms and
struts; here followed by the core and the electronics. Each step names the part copies it uses
(`corner_top_fl` ...), the rods it inserts with their cut lengths (from the cut list) and what
to glue. Every rod and every part copy appears in exactly one step: a rod in the step that
first pushes it into a socket, a part in the step that first uses it.

Glue policy (docs/fabrication.md explains why):
- cage ring, leg, the knee end of each arm and the corner end of each strut: one drop of thin
  CA at the socket mouth once the rod is fully seated. These joints are never taken apart and
  a rod that pulls out on impact defeats the frame.
- core links: NO glue. The arm and strut ends only push in, and the links are bolted to the
  core plate, so the core (and its electronics) comes out as one unit.
- motor mounts: no glue; they are threaded onto the arm rods and held by the motor screws.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Sequence

from ..families import camera_mount, motor_mount, sensor_mount
from ..fasteners import STAGES
from ..families.joint_kinds.kinds import core_link

if TYPE_CHECKING:
    from ..partlist import PartSpec
    from ..design import Derived

GLUE_CA = "one drop of thin CA glue at each socket mouth once the rod is fully seated"


@dataclass(frozen=True)
class Step:
    number: int
    title: str
    parts: tuple[str, ...]  # part copies used, e.g. corner_top_fl
    rods: tuple[tuple[str, float], ...]  # (rod name, cut length mm) inserted in this step
    glue: str  # what to glue, or "none"
    text: str  # what to do
    hardware: tuple[str, ...] = ()
    # the fasteners' and bought parts' stages fitted in this step (fasteners.STAGES): each stage in one step
    stages: tuple[str, ...] = ()
    # earlier steps whose sub-assembly this step puts in place (the core, built off the frame, then hung in it)
    places: tuple[int, ...] = ()
    apart: bool = False  # built off the frame: its picture shows this step's parts alone

    def as_dict(self) -> dict:
        return {"number": self.number, "title": self.title, "parts": list(self.parts),
                "rods": [{"rod": r, "cut_length_mm": length} for r, length in self.rods], "glue": self.glue,
                "text": self.text, "hardware": list(self.hardware)}


def copy_labels(part: "PartSpec") -> tuple[str, ...]:
    """Names of a part's copies: the placement instance when it names the part (knee_fl),
    else part + corner (motor_mount_fl), or the part name for a single copy (core_plate)."""
    out = []
    for pl in part.placements:
        if pl.instance.startswith(part.name):
            out.append(pl.instance)
        elif part.qty == 1:
            out.append(part.name)
        else:
            out.append(f"{part.name}_{pl.instance.rsplit('_', 1)[-1]}")
    return tuple(out)


def assembly_steps(design: "Derived") -> tuple[Step, ...]:
    """The numbered steps for a design (frame graph + part list + cut list)."""
    frame, spec = design.frame, design.spec
    cut = {name: row.length_mm for row in design.cut.rows for name in row.rods}
    rods_by_role = _rods_by_role(frame)
    parts = {p.name: p for p in design.parts}
    labels = {p.name: copy_labels(p) for p in design.parts}
    used_parts: set[str] = set()
    used_rods: set[str] = set()
    steps: list[Step] = []

    def take_parts(*names: str) -> tuple[str, ...]:
        out = []
        for n in names:
            if n in labels and n not in used_parts:
                used_parts.add(n)
                out.extend(labels[n])
        return tuple(out)

    def take_rods(names: Sequence[str]) -> tuple[tuple[str, float], ...]:
        out = []
        for n in names:
            if n in frame.rods and n not in used_rods:
                used_rods.add(n)
                out.append((n, cut[n]))
        return tuple(out)

    def hw(*names: str) -> tuple[str, ...]:
        count: dict[str, int] = {}
        for n in names:
            p = parts.get(n)
            if p:
                for h in p.hardware:
                    count[h.item] = count.get(h.item, 0) + h.qty * p.qty
        return tuple(f"{q} x {item}" for item, q in count.items())

    def add(title: str, part_names: Sequence[str], rod_names: Sequence[str], glue: str, text: str,
            hardware: Sequence[str] = (), stages: Sequence[str] = (), places: Sequence[int] = (), apart: bool = False) -> None:
        steps.append(Step(len(steps) + 1, title, take_parts(*part_names), take_rods(rod_names), glue, text, tuple(hardware),
                          tuple(stages), tuple(places), apart))

    def ring(level: str) -> list[str]:
        return [n for n in rods_by_role.get("cage", []) if n.startswith(f"rod_cage_{level}_")]

    def mirror_note(kind: str) -> str:
        """A rectangle's fr/rl joints are the mirror image of its fl/rr ones (partlist): which goes where."""
        return (f"{kind} at front-left and rear-right, its mirror image {kind}_mirrored at front-right and rear-left: "
                "they do not swap") if f"{kind}_mirrored" in parts else ""

    def aside(kind: str) -> str:
        note = mirror_note(kind)
        return f" ({note})" if note else ""

    ring_text = _ring_text(spec)
    add("Top ring", ["corner_top", "corner_top_mirrored"], ring("top"), f"ring sockets: {GLUE_CA}",
        f"Lay the four top corners flat, open side up{aside('corner_top')}. Push the four top cage rods into them "
        f"{ring_text} before the glue sets.")
    bottom = mirror_note("corner_bottom")
    add("Bottom ring", ["corner_bottom", "corner_bottom_mirrored"], ring("bottom"), f"ring sockets: {GLUE_CA}",
        f"Build the bottom ring the same way with the four bottom corners (feet pads down{'; ' + bottom if bottom else ''}) "
        "and the bottom cage rods.")
    upper = [n for n in rods_by_role.get("leg", []) if "_upper_" in n]
    lower = [n for n in rods_by_role.get("leg", []) if "_lower_" in n]
    add("Knees and upper legs", ["knee", "knee_mirrored"], upper, "none yet (glue after folding, step 4)",
        "Push an upper leg rod into the downward socket of each top corner and put a knee on its lower end, arm "
        f"sockets pointing inwards to the centre{aside('knee')}.")
    add("Fold the sides", [], lower, f"leg sockets (top corners, knees, bottom corners): {GLUE_CA}",
        "Push a lower leg rod into each knee. Stand the top ring over the bottom ring, then fold each side inwards "
        "at the knees (the hourglass) and push the lower legs into the bottom corners one corner at a time. "
        + _knee_text(spec))
    arms = rods_by_role.get("arm", [])
    add("Arms, motor mounts and motors", ["motor_mount"], arms, f"knee end of each arm rod only: {GLUE_CA}; motor mounts: none",
        motor_mount.fitting(spec).replace("{screws}", motor_mount.screw_words(parts.get("motor_mount"))), hw("motor_mount"),
        stages=("frame",))  # the motors and their screws: the frame's only bought parts
    struts = rods_by_role.get("strut", [])
    if struts:
        add("Struts", [], struts, f"bottom-corner end of each strut: {GLUE_CA}",
            "Push a damping strut into the inward socket of each bottom corner; leave the inner end free.", stages=("struts",))
    spacer = next((n for n in ("sensor_mount", "core_spacer") if n in parts), None)
    core_parts = [n for n in ("core_plate", spacer, "battery_holder", "core_link", "core_link_mirrored") if n and n in parts]
    mirrored = "core_link_mirrored" in parts
    link = core_link(spec)
    add("Core", core_parts, [], f"none: the core links are {link.fitted}, so the core stays removable", _core_text(spacer, mirrored, link),
        hw("core_link", "core_link_mirrored", "core_plate", "battery_holder", *([spacer] if spacer else [])),
        stages=("core",), apart=True)
    add("Hang the core", [], [], "none: arm and strut ends are only pushed into the core links",
        "Hold the core in the middle of the frame and push the free ends of both arm rods" + (" and the strut" if struts else "")
        + " of each corner into its core link. To remove the core later, pull the rods out of the links.", places=(len(steps),))
    if "front_camera_mount" in parts or spec.core.flow_sensor:
        add("Camera and sensors", [n for n in ("front_camera_mount",) if n in parts], [], "none", _sensors_text(spec, parts),
            hw("front_camera_mount"), stages=("sensors",))
    if "rear_net" in parts:  # the frame is whole: tie the net on before the electronics
        add("Rear net", ["rear_net"], [], "none", _net_text(parts["rear_net"]))
    rest = [n for n in parts if n not in used_parts]
    claimed = {st for s in steps for st in s.stages}  # the stack, the computer, props and battery: the rest
    add("Electronics", rest, [], "none", _electronics_text(spec, parts), hw(*rest), stages=[st for st in STAGES if st not in claimed])
    leftover = [n for n in frame.rods if n not in used_rods]
    if leftover:  # a rod role this module does not know yet: still tell the builder to fit it
        add("Remaining rods", [], leftover, "none", "Fit these rods where the assembly drawing shows them.")
    return tuple(steps)



def _rods_by_role(frame) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for r in frame.rods.values():
        out.setdefault(r.role, []).append(r.name)
    return out


def _core_text(spacer: str | None, mirrored: bool, link) -> str:
    """Fixing the core links to the plate (the link kind's words: bolted, or their pegs pressed
    into the plate's tubes) and stacking plate, spacer and holder."""
    which = (" (core_link at front-left and rear-right, its mirror image core_link_mirrored at front-right and rear-left)"
             if mirrored else "")
    fix = link.fixing_words(which, spacer)
    stacking = link.stacking_words(spacer)
    if stacking is not None:
        return fix + stacking
    return (fix
            + (f"Lay the {spacer} on the battery holder and the plate on it; " if spacer else "Put the plate on the battery holder; ")
            + "the stack's long countersunk screws hold them together: they go up from inside the holder (heads flush in its "
            "ceiling's countersinks) with the stack. The holder's open end faces the front so the battery slides in.")


def _net_text(net) -> str:
    """Tying the net (frame.rear_net) across the rear face: whole, or its two halves."""
    halves = bool(net.param("halves"))
    return ("Lay the TPU net" + (" (two halves, printed from one file: turn one over)" if halves else "")
            + " across the rear face of the cage (the battery slides in at the front), its long edges along the top and "
            "bottom rear cage rods and its round window in the middle of the face, and tie it to both rods with thin cable "
            "ties through the cells next to the rims" + (", and the two halves to each other along their middle rims." if halves else "."))


def _knee_text(spec) -> str:
    """Where each knee sits, from its corner."""
    square = spec.frame.width == spec.frame.depth
    return ("The sides are straight (frame.knee_inset 0): each knee sits on the line between its two corners."
            if spec.frame.knee_inset == 0 else f"Each knee sits {spec.frame.knee_inset:g} mm inside its corner." if square else
            f"Each knee sits {spec.frame.knee_inset * 2 ** 0.5:.1f} mm in from its corner, towards its core link.")


def _sensors_text(spec, parts: dict) -> str:
    """The camera (its mount's words) and the flow sensor (the sensor mount's)."""
    text = []
    if "front_camera_mount" in parts:
        text.append(camera_mount.fitting(spec))
    if spec.core.flow_sensor:
        text.append(sensor_mount.fitting(spec))
    return " ".join(text)


def _ring_text(spec) -> str:
    """How the four cage rods of a ring go round it, square or rectangular."""
    square = spec.frame.width == spec.frame.depth
    return ("to form a square ring (rod_cage_top_front between corner_top_fl and corner_top_fr, and so on round the "
            "square). Check the ring is square (equal diagonals)" if square else
            f"to form a {spec.frame.width:g} x {spec.frame.depth:g} mm rectangular ring: the front and rear rods are "
            f"the {'longer' if spec.frame.width > spec.frame.depth else 'shorter'} pair (rod_cage_top_front between "
            "corner_top_fl and corner_top_fr, and so on round the ring). Check the corners are square (equal diagonals)")


def _electronics_text(spec, parts: dict) -> str:
    """The stack, the computer, the other components and the battery (the motors went on in the arms' step)."""
    comps = ", ".join(f"{c.qty} x {c.name}" if c.qty > 1 else c.name for c in spec.components)
    computer = spec.core.computer
    stack = ("Stack the FC/ESC on the core plate: the ESC on its grommets, the 8 mm nylon spacers, the FC"
             + (", the nylon spacers and the computer mount" if computer else "")
             + ("; screw the four stack screws down from the top into the standoffs under the plate" if spec.frame.level_arms else
                "; push the four long countersunk screws up from inside the battery holder through it all and nut them on top")
             + (f"; then the {computer.name} on its nylon spacers over the mount, screws down through board, spacer and mount, "
                "nuts underneath" if computer else ""))
    return (stack + (f"; fit {comps}" if comps else "") + ". Solder the motors to the ESC, route wires along the arm rods, fit "
            "the propellers (2 CW, 2 CCW) last. Battery: "
            f"slide the pack in from the front, lead last, lay its {spec.core.battery.connector} lead up through the notch at the "
            + (f"top of the holder's mouth, close the {spec.core.strap_width:g} mm hook-and-loop strap across the mouth through the two "
               "45 deg slots (no tools: open the strap to swap the pack)." if spec.core.battery_lock == "strap" else
               "top of the holder's mouth and put battery_lid on the mouth: its magnets meet the holder's (glue the four magnets "
               "into their pockets beforehand, flush, each lid magnet facing its holder magnet with the opposite pole; pull the lid "
               "off to swap the pack)."))


def unbuilt(step: Step, design: "Derived") -> list[str]:
    """What `step`'s text names that the build lacks: a material no part is printed in, a feature
    no part has (tubes, pegs, countersinks, standoffs, nut traps, a clip), a part copy or part that
    is not in the part list. Empty for every step this module writes (tests/test_assembly_steps.py):
    the words come from the same part list and joint kinds as the parts."""
    import re

    from ..fasteners import fasteners

    spec, parts = design.spec, design.parts
    text = f"{step.title} {step.text} {step.glue}"
    materials = {p.material.split("_")[0].upper() for p in parts}
    params = {k for p in parts for k, _ in p.params}
    kinds = {f.kind for f in fasteners(spec, design.frame, parts)} | {f.head for f in fasteners(spec, design.frame, parts)}
    has = {"ABS": "ABS" in materials, "PLA": "PLA" in materials, "TPU": "TPU" in materials,
           "tube": "tubes" in params and any(dict(p.params).get("tubes") for p in parts),
           "peg": core_link(spec).label == "core_link_pegs", "countersink": "countersink_d" in params,
           "countersunk": "countersunk" in kinds, "standoff": "standoff" in kinds, "nut trap": "link_holes" in params
           and any(dict(p.params).get("link_holes") for p in parts), "hex trap": any(dict(p.params).get("link_holes") for p in parts),
           "clip": False, "strut": spec.frame.struts, "camera": spec.core.camera is not None,
           "flow": spec.core.flow_sensor is not None, "computer": spec.core.computer is not None}
    out = [w for w, ok in has.items() if not ok and re.search(rf"\b{w}", text, flags=0 if w.isupper() else re.I)]
    names = {p.name for p in parts} | {label for p in parts for label in copy_labels(p)}
    for m in re.finditer(r"\b((?:corner_top|corner_bottom|knee|core_link|motor_mount|core_plate|battery_holder|sensor_mount|"
                         r"core_spacer|front_camera_mount|computer_mount)\w*)", text):
        if "_" in m.group(1) and m.group(1) not in names:  # an identifier, not the word "knees"
            out.append(m.group(1))
    return out


def to_markdown(steps: Sequence[Step], title: str = "Assembly", pictures: dict[int, Sequence[str]] | None = None) -> str:
    """The steps as Markdown; `pictures`: each step's pictures (paths relative to the file), linked
    under its text."""
    out = [f"# {title}", ""] if title else []
    for s in steps:
        out.append(f"## {s.number}. {s.title}")
        out.append("")
        out.append(s.text)
        out.append("")
        for path in (pictures or {}).get(s.number, ()):
            exploded = " (exploded)" if path.endswith("_exploded.png") else ""
            out.append(f"![step {s.number}: {s.title}{exploded}]({path})")
            out.append("")
        if s.parts:
            out.append(f"- Parts: {', '.join(s.parts)}")
        if s.rods:
            out.append("- Rods: " + ", ".join(f"{n} ({length:g} mm)" for n, length in s.rods))
        if s.hardware:
            out.append(f"- Hardware: {'; '.join(s.hardware)}")
        out.append(f"- Glue: {s.glue}")
        out.append("")
    return "\n".join(out)

