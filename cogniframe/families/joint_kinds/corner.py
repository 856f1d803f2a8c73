"""The corners (corner_top, corner_bottom): ring sleeves flat on the bed meeting in a round hub,
the leg (and at a bottom corner the strut) rising from it. The two kinds differ only in what the
bottom corner adds (corner_bottom.py: the foot pad and the floor's support body)."""

from __future__ import annotations

import math

import numpy as np

from ...parts.joint_plan import FLIP_X, TAB_CLEAR, PSocket, clear_of, sleeve_levels, transform
from ...parts.record import Estimate, PartSpec
from .kind import JointKind
from .sleeves import arrays, closed, less_bores


class Corner(JointKind):
    """Printed with its ring plane on the bed, the leg up: a top corner upside down (the flat bed
    face is the top of the frame), a bottom corner as in the frame."""

    def estimate(self, spec, sockets, params: dict) -> Estimate:
        """Closed-form volume/areas of the solid (`solid`), in print orientation (r = OD/2 = bore/2 +
        wall, L = seat + depth): a round hub; a sleeve parallel to the bed a D section (2r wide,
        flat on the bed up to its axis height h, round top: 2 r h + pi r^2 / 2); a steep one a
        cylinder; a sloped one half a cylinder on a 0.9 x OD web down to the bed; the foot pad.
        Minus the bores."""
        a = arrays(spec, sockets)
        r, dirs = a.r, a.dirs
        vol = less_bores(a, sockets)
        a_h = a_v = 0.0
        up = -1.0 if dirs[np.abs(dirs[:, 2]) > 1e-6, 2].sum() < 0 else 1.0
        vol += 2 * math.pi * r**3  # hub
        a_h += 2 * math.pi * r**2
        a_v += 4 * math.pi * r**2
        for d, n in zip(dirs, a.L):
            dz = d[2] * up
            if abs(dz) < 1e-6:
                vol += a.d_area(r) * n - math.pi * r**2 / 2 * (r + math.pi * r / 4)
                a_h += (2 * r + math.pi * r / 2) * n
                a_v += (2 * r + math.pi * r / 2) * n
            elif dz >= math.cos(math.radians(45)):
                vol += math.pi * r**2 * (n - r)
                a_v += 2 * math.pi * r * n
            else:
                run = n * math.sqrt(1 - dz * dz)
                h_mean = r + dz * n / 2
                vol += math.pi * r**2 / 2 * n + 1.8 * r * h_mean * run - math.pi * r**2 / 2 * r
                a_h += 1.8 * r * run + math.pi * r * n / 2
                a_v += 2 * h_mean * run + math.pi * r * n / 2
        if params.get("foot"):
            vol += 1.5 * math.pi * r**2 * spec.joints.wall
            a_h += 2.2 * math.pi * r**2
        ext = np.ptp(np.vstack([a.ports, a.ports + dirs * a.L[:, None]]), axis=0) + 2 * r
        return closed(spec, sockets, vol, a_h, a_v, ext)

    def print_from_local(self, part: PartSpec) -> np.ndarray:
        """Ring plane on the bed, the leg socket up (a top corner turned upside down)."""
        r = (part.sockets[0].bore + 2 * part.wall) / 2
        dirs = np.array([s.direction for s in part.sockets], float)
        vertical = dirs[np.abs(dirs[:, 2]) > 1e-6, 2]
        rot = FLIP_X if vertical.sum() < 0 else np.eye(3)
        return transform(rot, (0.0, 0.0, r))

    def solid(self, part: PartSpec):
        _, socks, r = self.in_print(part)
        return _corner(part, socks, r)


def _corner(part: PartSpec, socks: list[PSocket], r: float):
    """Ring sleeves flat on the bed meeting in a round hub, the leg (and strut) rising from it."""
    from ...parts import joint_solid as cad

    params = dict(part.params)
    port = socks[0].port
    # The hub stands TAB_CLEAR wider than the sleeves and clear of their top lines. Of the sleeves'
    # own radius, its axis through theirs, it met every sleeve in the degenerate equal-radius
    # intersection (two curves crossing where the surfaces touch), and OCC's fuse of all the pieces
    # at once dropped a piece: a bottom corner lost most of its strut sleeve (459 of 648 mm^3) and
    # still came out one watertight solid, its strut socket a hole in the air (8 of 249 random
    # designs, e.g. a carbon box 154.1 x 175.9 x 128.5), or lost everything ("0 solids").
    pieces = [cad.cylinder((port[0], port[1], 0.0), (0, 0, 1), clear_of(2 * r, sleeve_levels(socks, r)), r + TAB_CLEAR)]  # hub
    # Every sleeve starts TAB_CLEAR out from the port, its end inside the hub. All the sleeves share
    # the port and the radius r, and two equal cylinders whose axes cross touch at two points level
    # with the crossing: on the rim of a sleeve that started there. A leg and a strut so met made
    # OCC's fuse drop both (the mirrored bottom corner of a carbon 184.7 x 169.7 x 81.8 box: 781 of
    # 1534 mm^3). The leg (within 45 deg of vertical) used to run down through the bed, where its
    # cut ellipse could pass through the point where the hub's rim meets a ring sleeve's side (an
    # STL with a hole: carbon, 284.4 x 289.1 x 141.2); inside the hub its end hangs over nothing.
    cos45 = math.cos(math.radians(45))
    for s in socks:
        dz = s.direction[2]
        length = s.seat + s.depth
        if abs(dz) < 1e-6:
            pieces.append(cad.dsleeve(s.at(TAB_CLEAR), s.direction, length - TAB_CLEAR, s.port[2], r))
        elif dz >= cos45:
            pieces.append(cad.cylinder(s.at(TAB_CLEAR), s.direction, length - TAB_CLEAR, r))
        elif dz > 0:
            pieces.append(cad.sloped_sleeve(s.at(TAB_CLEAR), s.direction, length - TAB_CLEAR, r))
        else:
            raise ValueError(f"{part.name}: socket {s.rod} points into the bed in print orientation")
    if params.get("foot"):
        # The foot: a flat pad on the ground side, twice the sleeve OD across, one wall thick.
        pieces.append(cad.cylinder((port[0], port[1], 0.0), (0, 0, 1), part.wall, 2 * r))
    body = cad.above_bed(cad.fuse_all(pieces))
    return cad.finish(body, [cad.socket_cutter(s) for s in socks])

