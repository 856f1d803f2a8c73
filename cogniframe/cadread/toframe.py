"""How a read `Exoskeleton` maps onto cogniframe's frame graph (`cogniframe.frame`) - what the
physics half (stiffness, load cases, drop model) builds its model from.

- `cadread.Rod` -> `frame.Rod`: name, diameter; end ``a``/``b`` -> `frame.RodEnd` with
  ``node`` = the joint whose socket holds that end; ``port`` = the foot of the perpendicular from
  that joint's centroid on the rod's axis (cogniframe's port is "the point on the rod axis level
  with the joint centre"); ``seat`` = port -> rod end along the rod (so `frame.Rod.start/end` are
  the read rod's end faces and `frame.Rod.length` its read length, exactly); ``depth`` = the
  socket's depth (mouth -> rod end). `stiffness.mouth(rod, tag)` (port + axis (seat + depth)) is
  then the socket's mouth, where the rod's free span (the beam) starts. ``role`` is not in the CAD:
  "rod" unless given; ``material`` from the `MaterialMap` (`rods:`).
- `cadread.Joint` -> `frame.Node`: name, ``pos`` = the centroid, ``rods`` = the rods with an end in
  it, ``seat`` = the mean seat of its sockets; ``kind`` = "joint" (cogniframe's kinds name its own
  layout's places; the physics half needs only which joints stand on the floor and which carry the
  payload: the lowest joints along gravity, and the joints touching the attached core parts).
- `cadread.Socket` -> `parts.record.Socket` in world coordinates (``port``/``direction``/``seat``
  /``depth``/``bore``): what `stiffness._add_joints` matches a joint's super-element sockets with
  (`_match_rod`: by port and direction); the joint's solid itself (`load.load_solids`) is what the
  joint FE meshes. A sleeve (``end=None``, a motor mount's clip) is a station on the rod
  (`frame.Motor.arm` / the rod's ``station``), not a rod end.
- `Exoskeleton.attached` (core plate, battery holder, motors, screws) -> the payload and lumped
  masses (volume x density of the material its name gives).
"""

from __future__ import annotations

import numpy as np

from ..frame import Node, Rod as FrameRod, RodEnd
from ..parts.record import Socket as PartSocket
from .found import Exoskeleton, Socket


def _port(exo: Exoskeleton, s: Socket) -> tuple[np.ndarray, float]:
    """(port, seat) of a rod-end socket: the joint centroid's foot on the rod axis, and the signed
    distance from it to the rod's end along the socket direction."""
    c = np.asarray(exo.joint(s.joint).centroid)
    e, d = np.asarray(s.rod_end), np.asarray(s.direction)
    port = e + d * np.dot(c - e, d)
    return port, float(np.dot(e - port, d))


def frame_rods(exo: Exoskeleton, role: str = "rod", material: str = "carbon_rod") -> dict[str, FrameRod]:
    """The rods with both ends in a joint, as `frame.Rod`s (a rod with a loose end is left out)."""
    out = {}
    for r in exo.rods:
        ends = []
        for tag in ("a", "b"):
            s = exo.socket_at(r.name, tag)
            if s is None:
                break
            port, seat = _port(exo, s)
            ends.append(RodEnd(s.joint, tuple(float(x) for x in port), seat, float(s.depth)))
        if len(ends) == 2:
            out[r.name] = FrameRod(r.name, role, ends[0], ends[1], r.diameter, material)
    return out


def frame_nodes(exo: Exoskeleton) -> dict[str, Node]:
    out = {}
    for j in exo.joints:
        socks = [s for s in exo.sockets_of(j.name) if s.end is not None]
        seats = [_port(exo, s)[1] for s in socks]
        out[j.name] = Node(j.name, "joint", j.centroid, tuple(s.rod for s in socks),
                           float(np.mean(seats)) if seats else 0.0)
    return out


def part_sockets(exo: Exoskeleton, joint: str) -> tuple[PartSocket, ...]:
    """A joint's rod-end sockets as `parts.record.Socket`s, in world coordinates (mm)."""
    out = []
    for s in exo.sockets_of(joint):
        if s.end is None:
            continue
        port, seat = _port(exo, s)
        out.append(PartSocket(s.rod, tuple(float(x) for x in port), s.direction, seat, s.depth, s.bore))
    return tuple(out)
