"""The TPU joints (corner_top, corner_bottom, knee, core_link): which parts, where their sockets
are, and which kind each part is. Pure numpy. What a kind of joint is (its params, closed form,
print orientation, solid, FE support, surrogate family) is its module in families/joint_kinds/,
registered in `joint_kinds.kinds.KINDS`; this module places one part per frame node kind and
asks the kind the design makes there.

Rectangular boxes. A corner's sockets are the rotation of the fl corner's only when they are
symmetric about the corner's 45 deg diagonal. In a square box they are (one part per kind); in a
rectangle the arms (knee -> core link) and the struts (bottom corner -> core link) run off the
diagonal, so the fr and rl corners are the MIRROR image of fl and rr (fl and rr are always a
180 deg rotation apart: the box is symmetric about both centre planes). Which corners a part
serves is tested on the frame graph itself (`_fit_error`): a kind whose fr corner is not the
rotation of its fl corner gets a second part `<kind>_mirrored` (params kind + mirror, prototype
fr) for fr and rl, as a chiral kind (the core link) always does.
"""

from __future__ import annotations

import math

import numpy as np

from ..frame import CORNERS, Frame
from ..numfmt import norm
from ..parts.record import PartSpec, Placement, Socket
from ..spec import Spec
from .base import CORNER_ROTATION, FIT_TOL, rot_z, rounded
from .joint_kinds import kinds
from .joint_kinds.kind import JointKind

NAME = "joint"
SIZE_KEY = "joints.socket_depth"  # the params key that drives its size (for "does not fit the bed" errors)
DOC = "TPU joint (corner_top, corner_bottom, knee, core_link) generated from its sockets"


def plan(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    """The joint parts, in a stable order: per node kind, the part(s) of the kind the design makes there."""
    return tuple(p for node in kinds.NODES for p in _joints(spec, frame, kinds.planned(spec, node)))


def core_links(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    """The core link parts: the fl/rr link and its mirror image for fr and rl. The core plate's
    peg tubes (core.link: pegs) are placed from these same parts."""
    return tuple(_joints(spec, frame, kinds.core_link(spec)))


def solid(part: PartSpec):
    """The joint's solid in print orientation (a `parts.joint_solid.Built`)."""
    return kinds.solid(part)


def print_from_local(part: PartSpec) -> np.ndarray:
    """The joint's 4x4 print <- local transform (bed at z = 0), from its plan: no CAD kernel."""
    return kinds.print_from_local(part)


def node_sockets(spec: Spec, frame: Frame, node: str) -> list[Socket]:
    """The sockets of a joint node, in the frame's axes with the node at the origin (from the graph)."""
    n = frame.nodes[node]
    origin = np.asarray(n.pos)
    sockets = []
    for rname in n.rods:
        rod = frame.rods[rname]
        end = rod.end_at(node)
        sockets.append(Socket(rname, rounded(np.asarray(end.port) - origin), rounded(rod.socket_direction(node)),
                              end.seat, end.depth, round(spec.bore, 4)))
    return sockets


def _fit_error(sockets, rotation_deg: float, target) -> float:
    """How far `sockets` turned about z by `rotation_deg` are from the sockets `target` (both in
    their node's axes): the worst port (mm) + direction error of the best one-to-one matching,
    inf when the counts or the seats, depths or bores differ."""
    if len(sockets) != len(target):
        return math.inf
    left = list(target)
    worst = 0.0

    for s in sockets:
        p, d = rot_z(np.asarray(s.port, float), rotation_deg), rot_z(np.asarray(s.direction, float), rotation_deg)
        errs = [norm(p - np.asarray(t.port)) + norm(d - np.asarray(t.direction))
                if (t.seat, t.depth, t.bore) == (s.seat, s.depth, s.bore) else math.inf for t in left]
        i = int(np.argmin(errs))
        worst = max(worst, errs[i])
        left.pop(i)
    return worst


def _joints(spec: Spec, frame: Frame, kind: JointKind) -> list[PartSpec]:
    """The part(s) of one joint kind: one for all four corners when each corner is the fl corner
    turned about z (a square box) and the kind is not chiral, else the part for fl and rr and its
    mirror image `<node>_mirrored` for fr and rl (a rectangle: module docstring)."""
    node = kind.node
    fl = node_sockets(spec, frame, f"{node}_fl")
    if not kind.chiral and all(_fit_error(fl, CORNER_ROTATION[k], node_sockets(spec, frame, f"{node}_{k}")) <= FIT_TOL
                               for k in CORNERS):
        return [_joint(spec, frame, node, kind)]
    return [_joint(spec, frame, node, kind, corners=("fl", "rr")),
            _joint(spec, frame, f"{node}_mirrored", kind, proto="fr", corners=("fr", "rl"))]


def _joint(spec: Spec, frame: Frame, name: str, kind: JointKind, proto: str = "fl",
           corners: tuple[str, ...] = CORNERS) -> PartSpec:
    """A joint part: the `proto` corner's node in its own axes, placed at `corners` by rotation about z.
    A prototype other than fl is the mirror image of the fl part (its side normal is mirrored too).
    Its params, hardware and estimate are its kind's (the kind that claims the planned part: a tab
    link on level arms is the flat one). Raises RuntimeError (a bug) if a placed copy's sockets
    miss the rods of its node, the spec's error if the kind cannot make it."""
    node, corner = kind.node, proto
    proto = frame.nodes[f"{node}_{corner}"]
    origin = np.asarray(proto.pos)
    sockets = node_sockets(spec, frame, proto.name)
    base = CORNER_ROTATION[corner]
    placements = tuple(Placement(f"{node}_{k}", (CORNER_ROTATION[k] - base + 180.0) % 360.0 - 180.0,
                                 rounded(frame.nodes[f"{node}_{k}"].pos)) for k in corners)
    for pl in placements:
        err = _fit_error(sockets, pl.rotation_deg, node_sockets(spec, frame, pl.instance))
        if err > FIT_TOL:
            raise RuntimeError(f"part {name}: its sockets placed at {pl.instance} miss the frame's rods by {err:.3g} mm")
    params: list[tuple[str, object]] = [("hinge_thickness", spec.joints.hinge_thickness)]
    if name != node:
        params += [("kind", node), ("mirror", corner != "fl")]
    params += kind.params(spec, frame, corner, origin, sockets)
    kind.refuse(spec, sockets, dict(params))
    estimate = kinds.resolve(node, dict(params), sockets).estimate(spec, sockets, dict(params))
    return PartSpec(name, "joint", "exoskeleton", spec.joints.material, 1.0, placements, tuple(sockets),
                    spec.joints.wall, estimate, tuple(params), kind.hardware(spec, frame))
