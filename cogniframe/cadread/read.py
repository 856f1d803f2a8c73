"""The reader: a CAD assembly -> `Exoskeleton` (rods, joints, sockets, contacts, what it could not place).

Steps: `load.load_solids` (named solids in one frame) -> `rods.find_rods` -> `sockets.find_sockets`
-> contacts between the other solids (closest distance <= `CONTACT_TOL`, for those whose boxes
come that close) -> the parts holding a rod are the joints, the parts connected to them through contacts are
attached (payload, vitamins); the rest, and each rod end in no socket, are reported by name.
"""

from __future__ import annotations

import numpy as np

from .geometry import MESH_TOL, bbox, face_boxes, mass_props, touching
from .load import NamedSolid, load_solids
from .part_materials import MaterialMap
from .found import Contact, Exoskeleton, Joint
from .rods import find_rods
from .sockets import find_sockets, nearest_hole

CONTACT_TOL = 0.1  # mm: two printed parts this close snap together (the authors' knees sit 0.02-0.05 mm off their arm brackets)


def _boxes_near(b1, b2, tol: float) -> bool:
    return bool(np.all(b1[0] <= b2[1] + tol) and np.all(b2[0] <= b1[1] + tol))


def read_exoskeleton(path, materials: MaterialMap | None = None, rod_diameter: float | None = None) -> Exoskeleton:
    return exoskeleton_of(load_solids(path), str(path), materials, rod_diameter)


def exoskeleton_of(solids: list[NamedSolid], source: str = "", materials: MaterialMap | None = None,
                   rod_diameter: float | None = None) -> Exoskeleton:
    materials = materials or MaterialMap()
    rods, others = find_rods(solids, rod_diameter)
    boxes = {ns.name: bbox(ns.solid) for ns in others}
    sockets = find_sockets(rods, others, boxes)
    contacts = []
    fboxes: dict[str, tuple] = {}
    for i, s1 in enumerate(others):
        for s2 in others[i + 1:]:
            if _boxes_near(boxes[s1.name], boxes[s2.name], CONTACT_TOL + 2 * MESH_TOL):
                for ns in (s1, s2):
                    if ns.name not in fboxes:
                        fboxes[ns.name] = face_boxes(ns.solid)
                d = touching(fboxes[s1.name], fboxes[s2.name], CONTACT_TOL)
                if d is not None:
                    contacts.append(Contact(s1.name, s2.name, d))
    # parts connected to the rods: through sockets, then through contacts
    placed = {s.joint for s in sockets}
    grew = True
    while grew:
        grew = False
        for c in contacts:
            if (c.a in placed) != (c.b in placed):
                placed |= {c.a, c.b}
                grew = True
    holders = {s.joint for s in sockets}
    joints, attached = [], []
    for ns in others:
        if ns.name in placed:
            mat, src = materials.of(ns.name)
            if src == "default" and ns.name not in holders:
                mat = ""  # a payload part or vitamin the patterns do not name
            lo, hi = boxes[ns.name]
            vol, cm = mass_props(ns.solid)
            (joints if ns.name in holders else attached).append(
                Joint(ns.name, mat, cm, vol, (tuple(map(float, lo)), tuple(map(float, hi))), src))
    unplaced = tuple(ns.name for ns in others if ns.name not in placed)
    held = {(s.rod, s.end) for s in sockets if s.end is not None}
    loose = tuple(f"{r.name}:{e}" for r in rods for e in ("a", "b") if (r.name, e) not in held)
    warnings = []
    if unplaced:
        warnings.append(f"{len(unplaced)} part(s) neither a rod nor connected to one, left out: {', '.join(unplaced)}")
    if loose:
        warnings.append(f"{len(loose)} rod end(s) in no joint's socket: {', '.join(loose)}")
        by_name = {r.name: r for r in rods}
        for le in loose:
            rn, e = le.rsplit(":", 1)
            hole = nearest_hole(by_name[rn], e, others)
            if hole is not None:
                warnings.append(f"  {le}: the nearest hole is in {hole[0]} (bore {hole[1]:.2f} mm), its axis "
                                f"{hole[2]:.2f} mm from the rod's end and {hole[3]:.1f} deg off the rod's")
    multi = {}
    for s in sockets:
        if s.end is not None:
            multi.setdefault((s.rod, s.end), []).append(s.joint)
    for (rn, e), js in multi.items():
        if len(js) > 1:
            warnings.append(f"rod end {rn}:{e} sits in {len(js)} parts' sockets: {', '.join(js)}")
    return Exoskeleton(source, tuple(rods), tuple(joints), tuple(sockets), tuple(attached), tuple(contacts), unplaced, loose, tuple(warnings))
