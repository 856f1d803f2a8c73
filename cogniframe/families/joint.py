"""The TPU joints (corner_top, corner_bottom, knee, core_link): which parts, where their sockets
are, and their closed-form volume and surfaces. Pure numpy. The plan geometry the closed forms
share with the solid (print orientation, the knee's and the core link's pieces in plan) is
parts/joint_plan.py; the solid is parts/joint_solid.py (the joint CAD and the helpers the motor mount
shares), imported only when a solid is asked for.

Rectangular boxes. A corner's sockets are the rotation of the fl corner's only when they are
symmetric about the corner's 45 deg diagonal. In a square box they are (one part per kind); in a
rectangle the arms (knee -> core link) and the struts (bottom corner -> core link) run off the
diagonal, so the fr and rl corners are the MIRROR image of fl and rr (fl and rr are always a
180 deg rotation apart: the box is symmetric about both centre planes). Which corners a part
serves is tested on the frame graph itself (`_fit_error`): a kind whose fr corner is not the
rotation of its fl corner gets a second part `<kind>_mirrored` (params kind + mirror, prototype
fr) for fr and rl, as the core link always does.
"""

from __future__ import annotations

import math

import numpy as np

from ..frame import CORNER_SIGN, CORNERS, PEG_ARCH_LEN, PEG_COLUMN_WALL, PEG_D, PEG_GAP, PEG_TUBE_WALL, STACK_BOTTOM, Frame
from ..materials import SCREWS, STACK_PATTERNS
from ..parts import joint_plan
from ..parts.joint_plan import (
    BAND_PAST,
    PARALLEL_TOL,
    TEAR_MIN,
    TEAR_WEB,
    PSocket,
    convex_hull,
    footprint_rect,
    hull_ccw,
    link_bands,
    link_bed_z,
    link_is_flat,
    link_plate_corner,
    link_plate_region,
    rigid_leg_start,
    seat_plan,
)
from ..spec import Spec
from ..parts.peg_plan import pegged_plan, sleeve_in_arch
from ..parts.record import Estimate, HardwareLine, PartSpec, Placement, Socket
from .base import CORNER_ROTATION, FIT_TOL, link_hole, polygon_area, rot_z, rounded

NAME = "joint"
SIZE_KEY = "joints.socket_depth"  # the params key that drives its size (for "does not fit the bed" errors)
DOC = "TPU joint (corner_top, corner_bottom, knee, core_link) generated from its sockets"


def plan(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    """The joint parts, in a stable order."""
    return (
        *_joints(spec, frame, "corner_top"),
        *_joints(spec, frame, "corner_bottom"),
        *_joints(spec, frame, "knee"),
        *core_links(spec, frame),
    )


def core_links(spec: Spec, frame: Frame) -> tuple[PartSpec, PartSpec]:
    """The core link parts: the fl/rr link and its mirror image for fr and rl. The links are chiral
    (printed on their side or standing, sleeves on the bed), and the battery holder is a
    rectangle, not a square: a link rotated from fl to fr meets the holder differently. The core
    plate's peg tubes (core.link: pegs) are placed from these same parts."""
    return (_joint(spec, frame, "core_link", "core_link", corners=("fl", "rr")),
            _joint(spec, frame, "core_link_mirrored", "core_link", proto="fr", corners=("fr", "rl")))


def solid(part: PartSpec):
    """The joint's solid in print orientation (a `parts.joint_solid.Built`)."""
    from ..parts import joint_solid as cad

    return cad.solid(part)


def print_from_local(part: PartSpec) -> np.ndarray:
    """The joint's 4x4 print <- local transform (bed at z = 0), from its plan: no CAD kernel."""
    return joint_plan.print_from_local(part)


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
        errs = [float(np.linalg.norm(p - np.asarray(t.port)) + np.linalg.norm(d - np.asarray(t.direction)))
                if (t.seat, t.depth, t.bore) == (s.seat, s.depth, s.bore) else math.inf for t in left]
        i = int(np.argmin(errs))
        worst = max(worst, errs[i])
        left.pop(i)
    return worst


def _joints(spec: Spec, frame: Frame, kind: str) -> list[PartSpec]:
    """The part(s) of one joint kind: one for all four corners when each corner is the fl corner
    turned about z (a square box), else the part for fl and rr and its mirror image
    `<kind>_mirrored` for fr and rl (a rectangle: module docstring)."""
    fl = node_sockets(spec, frame, f"{kind}_fl")
    if all(_fit_error(fl, CORNER_ROTATION[k], node_sockets(spec, frame, f"{kind}_{k}")) <= FIT_TOL for k in CORNERS):
        return [_joint(spec, frame, kind, kind)]
    return [_joint(spec, frame, kind, kind, corners=("fl", "rr")),
            _joint(spec, frame, f"{kind}_mirrored", kind, proto="fr", corners=("fr", "rl"))]


def _joint(spec: Spec, frame: Frame, name: str, kind: str, proto: str = "fl", corners: tuple[str, ...] = CORNERS) -> PartSpec:
    """A joint part: the `proto` corner's node in its own axes, placed at `corners` by rotation about z.
    A prototype other than fl is the mirror image of the fl part (its side normal is mirrored too).
    Raises RuntimeError (a bug) if a placed copy's sockets miss the rods of its node."""
    corner = proto
    proto = frame.nodes[f"{kind}_{corner}"]
    origin = np.asarray(proto.pos)
    sockets = node_sockets(spec, frame, proto.name)
    base = CORNER_ROTATION[corner]
    placements = tuple(Placement(f"{kind}_{k}", (CORNER_ROTATION[k] - base + 180.0) % 360.0 - 180.0,
                                 rounded(frame.nodes[f"{kind}_{k}"].pos)) for k in corners)
    for pl in placements:
        err = _fit_error(sockets, pl.rotation_deg, node_sockets(spec, frame, pl.instance))
        if err > FIT_TOL:
            raise RuntimeError(f"part {name}: its sockets placed at {pl.instance} miss the frame's rods by {err:.3g} mm")
    hardware: tuple[HardwareLine, ...] = ()
    params: list[tuple[str, object]] = [("hinge_thickness", spec.joints.hinge_thickness)]
    if name != kind:
        params += [("kind", kind), ("mirror", corner != "fl")]
    if kind == "core_link" and spec.core.link == "pegs":
        params += list(PEGS)
        dirs = [np.asarray(s.direction, float) for s in sockets]
        arm = next(d for d in dirs if sum(float(d @ e) > 1 - PARALLEL_TOL for e in dirs) > 1)  # the arm pair's
        for s in sockets:
            lean = math.degrees(math.acos(min(1.0, float(np.asarray(s.direction, float) @ arm))))
            if lean > PEG_LEAN_MAX + 1e-6:
                raise spec.error("core.link", f"the pegged core link prints standing on its pegs, the arms upright, and the strut "
                                 f"leaves the arms at {lean:.0f} deg: its sleeve would overhang more than {PEG_LEAN_MAX:g} deg "
                                 "and need supports", "set core.link: tab, or shape the frame so the struts leave the core "
                                 f"within {PEG_LEAN_MAX:g} deg of the arms (level arms, a lower or wider box)")
        _pegs_fit(spec, pegged_plan(sockets, dict(params)))
        # no screw: the pegs are pressed into the core's bores
        return PartSpec(name, "joint", "exoskeleton", spec.joints.material, 1.0, placements, tuple(sockets),
                        spec.joints.wall, _pegged_link_estimate(spec, sockets, dict(params)), tuple(params), ())
    if kind == "core_link":
        # The link bolts onto the top of the core plate corner with one screw.
        screw = SCREWS[spec.core.stack_screw]
        hole = link_hole(spec)
        sx, sy = CORNER_SIGN[corner]
        params += [("screw", screw.name), ("screw_clearance", screw.clearance_d),
                   # plate-corner hole and plate top, in the link's local frame (its node is at plate mid-height)
                   ("bolt_hole", rounded(np.array([sx * hole, sy * hole, 0.0]) - np.array([origin[0], origin[1], 0.0]))),
                   ("plate_top_z", round(spec.core.plate_thickness / 2, 4)), ("tab_thickness", LINK_TAB),
                   # the plate corner the link seats against (its two edge faces), same frame
                   ("plate_corner", rounded(np.array([sx, sy, 0.0]) * spec.core.plate_size / 2 - np.array([origin[0], origin[1], 0.0]))),
                   # the ESC board's footprint (its centre, at the height of its underside less
                   # 0.5 mm) and half-side, same frame: the tab keeps below the board
                   ("esc_keepout", rounded(np.array([0.0, 0.0, float(frame.core.stack.lo[2]) + STACK_BOTTOM - 0.5]) - origin)),
                   ("esc_half", STACK_PATTERNS[spec.core.stack_pattern][1] / 2 + 0.5)]
        # tab + plate + spacer, nut in the spacer's nut trap (a hanging plate: the nut under the
        # plate): round up to a stock length
        grip = LINK_TAB + spec.core.plate_thickness + (spec.core.spacer_thickness if frame.core.hang == 0 else 2.0)
        length = next((n for n in (8, 10, 12, 14, 16, 20) if n >= grip), 20)
        hardware = (HardwareLine(f"{screw.name} x {length} socket-head screw + nut (core link to plate)", 1, screw.mass_g * length / 6 + 0.1),)
    if kind == "corner_bottom":
        params.append(("foot", True))  # the bottom corners are the feet: flat pad on the ground side
    return PartSpec(name, "joint", "exoskeleton", spec.joints.material, 1.0, placements, tuple(sockets),
                    spec.joints.wall, _joint_estimate(spec, sockets, kind, dict(params)), tuple(params), hardware)


# The pegged core link (core.link: pegs): the authors' connector, measured on
# Flex_Main_connector_new_bumper.stl of thecognifly/CogniFly-STL (docs/authors-parts.md,
# tools/pegged_link_fe.py `Connector`). Each arm socket sits in a TPU column whose far end is a
# solid peg, pressed into a bore of the ABS core; an arch joins the two columns, and the strut
# hangs on it (parts/peg_plan.py `pegged_plan`).
PEGS = (
    ("link", "pegs"),
    ("peg_d", PEG_D),  # peg diameter, mm (authors' 6.79): the core plate's tube bore (frame.py)
    ("peg_len", 9.0),  # peg length, mm (authors' 9.0)
    ("peg_gap", PEG_GAP),  # mm from the socket's bottom to the peg (authors' socket floor 0.3 above the peg)
    ("column_wall", PEG_COLUMN_WALL),  # TPU round the socket, mm (authors' (6.79 - 3.19) / 2)
    ("arch_len", PEG_ARCH_LEN),  # the crown's depth under the mouths, mm (authors' z 6.2..9 at mid-span); the
                                 # arch reaches down the columns to the pegs' shoulder round an opening
    ("arch_depth", 6.7),  # mm across the plane of the arm pair (authors' 6.7)
)
PEG_LEAN_MAX = 45.0  # deg: the most a socket of the standing pegged link leans from the arms (print overhang)
# mm: the least ABS between two of the core's peg bores: each bore's tube wall and a gap of one
# 0.4 mm line between the tubes, so the tubes never touch (a press fit's tube merged into its
# neighbour's splits as the pegs go in, and the plate's closed form counts each tube whole)
PEG_WEB = 2 * PEG_TUBE_WALL + 0.4
PEG_SLEEVE_GAP = 0.4  # mm: the least air between the strut's sleeve and an arm's column (one 0.4 mm line)


def _pegs_fit(spec: Spec, pl) -> None:
    """Refuse (naming core.link) a pegged link whose pegs' bores would run into each other in the
    core, or whose strut sleeve would run into an arm's column."""
    cols = pl.columns
    for i in range(len(cols)):
        for j in range(i):
            gap = float(np.linalg.norm(cols[i].axis - cols[j].axis)) - 2 * pl.peg_r
            if gap < PEG_WEB - 1e-6:
                raise spec.error("core.link", f"the pegged core link's pegs ({2 * pl.peg_r:g} mm, one per arm) stand "
                                 f"{gap:.1f} mm apart: the core's bores need {PEG_WEB:g} mm of ABS between them",
                                 "set core.link: tab, or space the arms wider (frame.arm_spacing)")
    for st in pl.struts:
        gap = _sleeve_clear(pl, st)
        if gap < PEG_SLEEVE_GAP - 1e-6:
            raise spec.error("core.link", f"the strut's sleeve on the pegged core link's arch passes {max(gap, 0.0):.1f} mm "
                             f"from an arm's column (it needs {PEG_SLEEVE_GAP:g} mm)",
                             "set core.link: tab, or space the arms wider (frame.arm_spacing)")


def _sleeve_clear(pl, st, n: int = 64) -> float:
    """The least air (mm) between the strut's sleeve and the arm columns: the columns stand
    upright, so it is the plan distance from the sleeve's axis to a column's, less the column's
    radius and the sleeve's (its full radius: a bound), over the stretch of the sleeve whose
    discs reach below the columns' tops."""
    back, mouth = np.asarray(st.back, float), np.asarray(st.mouth, float)
    d = (mouth - back) / np.linalg.norm(mouth - back)
    reach_z = pl.col_r * math.sqrt(max(0.0, 1.0 - float(d[2]) ** 2))
    best = math.inf
    for f in np.linspace(0.0, 1.0, n + 1):
        p = back + f * (mouth - back)
        for c in pl.columns:
            if float(p[2]) - reach_z > c.col1:
                continue
            best = min(best, float(np.hypot(p[0] - c.axis[0], p[1] - c.axis[1])) - c.col_r - pl.col_r)
    return best


# The core link's tab: it carries an arm's thrust moment from the arm block, across the seat at
# the plate corner, onto the plate top. Its bending there is the hinge the bare arms hang on
# (cubic in its depth: at 3 mm the bare arms folded at full thrust; docs/stiffness-model.md).
LINK_TAB = 6.0  # mm


def _joint_estimate(spec: Spec, sockets: list[Socket], kind: str, params: dict | None = None) -> Estimate:
    """Closed-form volume/areas of the joint as parts/joint_solid.py builds it, in print orientation.

    Pieces (r = OD/2 = bore/2 + wall, L = seat + depth): a sleeve parallel to the bed is a D
    section (2r wide, flat on the bed up to its axis height h, round top: 2 r h + pi r^2 / 2); a
    steep one a cylinder; a sloped one half a cylinder on a 0.9 x OD web down to the bed. Corners
    add a round hub (and the foot pad), the core link stacks the arm sockets in one block, the
    knee holds them in a U and its legs on webs (`_knee_sleeves`),
    the core link adds a hub between the sleeves and its bolt tab. Minus the bores.
    """
    params = params or {}
    j = spec.joints
    r = spec.bore / 2 + j.wall
    hole = math.pi / 4 * spec.bore**2
    dirs = np.array([s.direction for s in sockets], float)
    ports = np.array([s.port for s in sockets], float)
    L = np.array([s.seat + s.depth for s in sockets], float)

    def d_area(h: float) -> float:
        return 2 * r * h + math.pi * r**2 / 2

    vol = -sum(hole * s.depth for s in sockets)
    a_h = a_v = 0.0
    if kind in ("corner_top", "corner_bottom"):
        up = -1.0 if dirs[np.abs(dirs[:, 2]) > 1e-6, 2].sum() < 0 else 1.0
        vol += 2 * math.pi * r**3  # hub
        a_h += 2 * math.pi * r**2
        a_v += 4 * math.pi * r**2
        for d, n in zip(dirs, L):
            dz = d[2] * up
            if abs(dz) < 1e-6:
                vol += d_area(r) * n - math.pi * r**2 / 2 * (r + math.pi * r / 4)
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
            vol += 1.5 * math.pi * r**2 * j.wall
            a_h += 2.2 * math.pi * r**2
        ext = np.ptp(np.vstack([ports, ports + dirs * L[:, None]]), axis=0) + 2 * r
    else:
        _, sv, vt = np.linalg.svd(dirs)
        w = vt[-1]
        if sv[1] < 1e-6 * sv[0]:  # parallel arm sockets only (no strut): the SVD's normal is arbitrary;
            off = ports[1] - ports[0]  # use the one across the pair, as parts/joint_solid.py prints it
            w = np.cross(dirs[0], np.cross(dirs[0], off))
            w /= np.linalg.norm(w)
        zc = ports @ w
        z = zc - zc.min() + r  # axis heights in print orientation
        par = [i for i in range(len(sockets)) if sum(dirs[i] @ dirs[k] > 1 - PARALLEL_TOL for k in range(len(sockets))) > 1]
        rest = [i for i in range(len(sockets)) if i not in par]
        sleeve_l = [sockets[i].depth + j.wall for i in range(len(sockets))]
        if kind == "knee":
            vol, a_h, a_v = _knee_sleeves(r, j.wall, z, sleeve_l, par, rest, vol, a_h, a_v)
            hub = _knee_hub_area(sockets, dirs, ports, w, z, par, rest, r, j.wall)
            vol += hub[0] * hub[1]
            a_h += hub[0]
            a_v += 2 * 2 * r * hub[1]
        else:
            for h, n in [(z[par].max(), sleeve_l[par[0]])] + [(z[i], sleeve_l[i]) for i in rest]:
                vol += d_area(h) * n
                a_h += (2 * r + math.pi * r / 2) * n
                a_v += (2 * h + math.pi * r / 2) * n
        for i in (rest if kind == "core_link" else []):  # a sleeve leaving at a small angle to the arm block runs partly inside it
            sin_t = float(np.linalg.norm(np.cross(dirs[i], dirs[par[0]])))
            s0, s1 = sockets[i].seat - j.wall, sockets[i].seat + sockets[i].depth
            s_end = min(s1, 2 * r / sin_t) if sin_t > 1e-9 else s1
            if s_end > s0:
                overlap = 2 * r * (s_end - s0) - sin_t * (s_end**2 - s0**2) / 2
                vol -= overlap * (z[i] + math.pi * r / 4)
        top = float(z[rest].max() + r) if rest else float(z[par].max() + r)  # no strut: arm sockets only
        if kind == "knee":
            vol += j.hinge_thickness * 2.7 * top
            a_v += 2 * 2.7 * top
        elif link_is_flat(sockets):
            return _flat_link_estimate(spec, params, sockets, r)
        else:
            vol, a_h, a_v = _link_pieces(spec, params, sockets, dirs, ports, z, zc, w, par, rest, top, r,
                                         vol, a_h, a_v)
        ext = np.array([np.ptp(np.vstack([ports, ports + dirs * L[:, None]]) @ np.eye(3), axis=0).max() + 2 * r,
                        2 * r + float(L.max()), float(z.max() + r)])
    a_v += sum(math.pi * spec.bore * s.depth for s in sockets)
    env = tuple(sorted(float(x) for x in ext))
    return Estimate(vol, a_h, a_v, (env[2], env[1], env[0]))


def _knee_sleeves(r: float, wall: float, z: np.ndarray, sleeve_l: list[float], par: list[int], rest: list[int],
                  vol: float, a_h: float, a_v: float) -> tuple[float, float, float]:
    """A knee's sleeves added to the running volume and areas, as parts/joint_solid.py builds them
    (axis heights `z`): the arm pair's bridge (`knee_bridge`: the top arm's D-section, bed up, over
    one sleeve OD from the back; to the mouths where less than a millimetre would be left), the
    lowest arm's D-section sleeve past it, the higher arms' and the legs' teardrops on a `wall`
    thick web (`teardrop`). A rigid leg that joins past one OD lengthens the bridge a little: not
    counted."""
    def d_section(h: float, n: float) -> tuple[float, float, float]:
        return (2 * r * h + math.pi * r**2 / 2) * n, (2 * r + math.pi * r / 2) * n, (2 * h + math.pi * r / 2) * n

    def tear(h: float, n: float) -> tuple[float, float, float]:
        k = r / math.sqrt(2.0)
        z_web = h - r * math.sqrt(2.0) + wall / 2  # where the flanks meet the web, above the bed
        if wall / 2 >= k - 0.05 or z_web <= 0.2:
            return d_section(h, n)
        # round top and 45 deg flanks (3/4 of the circle + the kite r^2) less the kite's tip below
        # the web's top, plus the web
        area = 0.75 * math.pi * r**2 + r**2 - wall**2 / 4 + wall * z_web
        flank = r - wall / math.sqrt(2.0)  # one flank's length
        return area * n, (wall + 0.75 * math.pi * r + flank) * n, (2 * z_web + 0.75 * math.pi * r + flank) * n

    n_arm = sleeve_l[par[0]]
    bridge = 2 * r if 2 * r <= n_arm - 1.0 else n_arm
    low = min(par, key=lambda i: float(z[i]))
    pieces = [d_section(float(z[par].max()), bridge), d_section(float(z[low]), n_arm - bridge)]
    pieces += [tear(float(z[i]), n_arm - bridge) for i in par if i != low]
    pieces += [tear(float(z[i]), sleeve_l[i]) for i in rest]
    for v, ah, av in pieces:
        vol, a_h, a_v = vol + v, a_h + ah, a_v + av
    return vol, a_h, a_v


def _knee_hub_area(sockets: list[Socket], dirs: np.ndarray, ports: np.ndarray, w: np.ndarray, z: np.ndarray,
                   par: list[int], rest: list[int], r: float, wall: float) -> tuple[float, float]:
    """(plan area, height) of the hub that joins a knee's rigid leg to its arm bridge where no
    sleeve start can (parts/joint_plan.py `rigid_leg_start` is None: a large seat): the hull of the two
    back faces, from the bed to halfway up the leg's round top (the hinge-side clip not counted).
    (0, 0) where the leg's sleeve joins the bridge itself."""
    a_i = par[0]
    x = dirs[a_i] - w * (dirs[a_i] @ w)
    x /= np.linalg.norm(x)
    rot = np.vstack([x, np.cross(w, x), w])  # print-like axes: the side plane on the bed, as parts/joint_solid.py prints it

    def psock(i: int) -> PSocket:
        return PSocket(rot @ ports[i] + np.array([0.0, 0.0, z[i] - float(w @ ports[i])]), rot @ dirs[i], float(sockets[i].seat),
                       float(sockets[i].depth), float(sockets[i].bore), sockets[i].rod)

    a = psock(a_i)
    legs = [psock(i) for i in rest]
    if len(legs) < 2:
        return 0.0, 0.0
    hinged = min(legs, key=lambda s: float(s.direction @ a.direction))
    s_back = a.seat - wall
    area = height = 0.0
    for s in legs:
        if s is hinged or rigid_leg_start(a, s, r, s_back, wall) is not None:
            continue
        t0 = s.seat - wall
        pts = np.array(footprint_rect(a, s_back, s_back, r) + footprint_rect(s, t0, t0, r))
        area += polygon_area(convex_hull(pts))
        height = max(height, float(s.port[2]) + r / 2)
    return area, height


def _link_pieces(spec: Spec, params: dict, sockets: list[Socket], dirs: np.ndarray, ports: np.ndarray, z: np.ndarray,
                 zc: np.ndarray, w: np.ndarray, par: list[int], rest: list[int], top: float, r: float,
                 vol: float, a_h: float, a_v: float) -> tuple[float, float, float]:
    """A core link's bolt tab, hub and plate seat added to the running volume and areas (the
    arm block's print plane normal `w`, axis heights `z`, parallel arm sockets `par`)."""
    j = spec.joints
    s_back = sockets[par[0]].seat - j.wall
    t = float(params.get("tab_thickness", spec.core.plate_thickness))
    hole_d = float(params.get("screw_clearance", 2.4))
    bolt = np.asarray(params.get("bolt_hole", (0.0, 0.0, 0.0)), float)
    r_tab = hole_d / 2 + j.wall
    tab_len = float(np.hypot(bolt[0], bolt[1])) + r_tab + 1.0
    tab_h = float(bolt @ w - zc.min() + r + r_tab)
    vol += tab_len * t * tab_h - math.pi / 4 * hole_d**2 * t
    a_h += tab_len * t
    a_v += 2 * tab_len * tab_h
    # Hub: a prism over the convex hull of the sleeves' back faces and the tab root.
    x = dirs[par[0]] - w * (dirs[par[0]] @ w)
    x /= np.linalg.norm(x)
    y = np.cross(w, x)
    pts = []
    for i in [par[0]] + rest:
        d = dirs[i]
        lat = np.cross(w, d)
        lat /= np.linalg.norm(lat)
        c = ports[i] + d * (sockets[i].seat - j.wall)
        pts += [c + lat * r, c - lat * r]
    e_u = bolt - w * (bolt @ w)
    e_u[2] = 0.0
    e_u /= max(float(np.linalg.norm(e_u)), 1e-9)
    v0 = float(params.get("plate_top_z", 0.0))
    pts += [e_u * 0.5 + np.array([0, 0, v0]), e_u * 0.5 + np.array([0, 0, v0 + t])]
    hub_area = _hull_area(np.array([[p_ @ x, p_ @ y] for p_ in pts]))
    hub_h = max(top, tab_h)
    vol += hub_area * hub_h
    a_h += hub_area
    a_v += 2 * s_back * hub_h
    seat_area = _seat_area(params, ports[par], z[par], dirs[par[0]], sockets[par[0]].seat - j.wall, r,
                           min(float(z[par].max() + r - 0.5), tab_h))
    vol += seat_area * 2 * v0
    a_v += 2 * seat_area
    return vol, a_h, a_v


def _seat_area(params: dict, ports: np.ndarray, heights: np.ndarray, d: np.ndarray, s_back: float, r: float,
               height: float) -> float:
    """Plan area (mm^2) of a core link's seat as parts/joint_solid.py builds it (`seat_plan`, less the
    plate's corner quadrant), from the bed up to `height` in print (the arm pair's two `ports`
    print at `heights`: print height runs across the pair)."""
    corner, sign = link_plate_corner(params)
    quad = seat_plan(params, ports, d, s_back, r)
    across = ports[1, :2] - ports[0, :2]
    g = across * (heights[1] - heights[0]) / float(across @ across)  # print height per mm in plan
    h0 = float(heights[0] - ports[0, :2] @ g)  # print height = h0 + p . g
    band = _clip(_clip(quad, -g, h0), g, height - h0)
    inside = _clip(_clip(band, np.array([sign[0], 0.0]), sign[0] * corner[0]), np.array([0.0, sign[1]]), sign[1] * corner[1])
    return polygon_area(band) - polygon_area(inside) if len(band) > 2 else 0.0


def _clip(poly, a: np.ndarray, b: float) -> list:
    """The part of a convex polygon where a . p <= b (Sutherland-Hodgman, one edge)."""
    out = []
    for i, p in enumerate(poly):
        q = poly[i - 1]
        fp, fq = float(a @ p) - b, float(a @ q) - b
        if fp <= 0:
            if fq > 0:
                out.append(q + (p - q) * fq / (fq - fp))
            out.append(p)
        elif fq <= 0:
            out.append(q + (p - q) * fq / (fq - fp))
    return out


def _hull_area(pts: np.ndarray) -> float:
    """Area of the convex hull of 2-D points (`hull_ccw` + shoelace)."""
    hull = hull_ccw(pts)
    x, y = hull[:, 0], hull[:, 1]
    return float(abs(x @ np.roll(y, -1) - y @ np.roll(x, -1)) / 2)


# -- the flat core link's closed form (its plan, the bands and the plate: parts/joint_plan.py) ------

def convex_clip(poly, other) -> list:
    """The intersection of two convex polygons (`other` counter-clockwise)."""
    out = list(poly)
    q = np.asarray(other, float)
    for i in range(len(q)):
        if len(out) < 3:
            return []
        e = q[(i + 1) % len(q)] - q[i]
        a = np.array([e[1], -e[0]])  # outward normal of a counter-clockwise edge
        out = _clip(out, a, float(a @ q[i]))
    return out if len(out) >= 3 else []


def union_area(polys) -> float:
    """Area of the union of convex polygons (inclusion-exclusion over their intersections)."""
    from itertools import combinations

    total = 0.0
    for k in range(1, len(polys) + 1):
        for group in combinations(polys, k):
            inter = list(group[0])
            for q in group[1:]:
                inter = convex_clip(inter, hull_ccw(q)) if inter else []
            if len(inter) >= 3:
                total += (-1) ** (k + 1) * polygon_area(inter)
    return total


def _flat_link_estimate(spec: Spec, params: dict, sockets: list[Socket], r: float) -> Estimate:
    """Closed form of the flat core link (parts/joint_solid.py `_core_link_flat`): the sleeves (arms:
    a teardrop on a web, or a D section, from the bed up; the strut: half a cylinder on a 0.9 x OD
    web), the bands `T` deep (the bed down to the plate top), the seat (the bands outside the
    plate, on down to the plate's bottom), less the bores and the screw hole."""
    j = spec.joints
    hole = math.pi / 4 * spec.bore**2
    z_bed = link_bed_z(params, sockets, r)
    v0 = float(params["plate_top_z"])
    T = z_bed - v0
    hole_d = float(params["screw_clearance"])
    bands = link_bands(params, sockets, j.wall, r)
    plate = link_plate_region(params)
    a_band = union_area(bands)
    a_seat = a_band - union_area([p for p in (convex_clip(b, plate) for b in bands) if p])
    vol = a_band * T + a_seat * 2 * v0 - math.pi / 4 * hole_d**2 * T
    a_h = 2 * a_band
    a_v = 0.0
    for s in sockets:
        d = np.asarray(s.direction, float)
        n = s.depth + j.wall
        h = z_bed - float(s.port[2])  # the axis above the bed at the port
        vol -= hole * s.depth
        a_v += math.pi * spec.bore * s.depth
        if abs(d[2]) < 1e-5:
            # the band's run into the sleeve, less the sleeve's round top above the band's bottom
            seg = max(0.0, h + r - (z_bed + v0))
            seg_area = r * r * math.acos(1 - seg / r) - (r - seg) * math.sqrt(max(0.0, 2 * r * seg - seg * seg)) if seg < r else 0.0
            vol += link_sleeve_area(h, r) * n - (s.seat + BAND_PAST - (s.seat - j.wall)) * (link_sleeve_area(h, r) - seg_area)
            a_h += (2 * r + math.pi * r / 2) * n
            a_v += (2 * h + math.pi * r / 2) * n
        else:  # the strut, rising in print
            sin_a = abs(float(d[2]))
            cos_a = math.sqrt(1 - sin_a * sin_a)
            run = n * cos_a
            t0, t1 = s.seat - j.wall, s.seat + s.depth
            h_mean = h + sin_a * (t0 + t1) / 2
            # its run inside the band (parts/joint_solid.py: the band reaches BAND_PAST past the socket's
            # bottom and past where the web begins)
            t_in = min(t1, s.seat + BAND_PAST + r * sin_a / cos_a) - t0
            h_in = h + sin_a * (t0 + t_in / 2)  # the axis's mean height there
            # half a cylinder on a 0.9 x OD web, less the web inside the band
            vol += math.pi * r**2 / 2 * n + 1.8 * r * h_mean * run
            vol -= t_in * cos_a * 1.8 * r * min(h_in, z_bed + v0)
            a_h += 1.8 * r * run + math.pi * r * n / 2
            a_v += 2 * h_mean * run + math.pi * r * n / 2
    pts = np.vstack([np.vstack(bands)] + [(np.asarray(s.port, float) + np.asarray(s.direction, float) * (s.seat + s.depth))[:2] for s in sockets])
    ext = sorted([float(np.ptp(pts[:, 0])) + r, float(np.ptp(pts[:, 1])) + r, z_bed + r])
    return Estimate(vol, a_h, a_v, (ext[2], ext[1], ext[0]))


def link_sleeve_area(h: float, r: float) -> float:
    """Section of a flat link's arm sleeve whose axis stands `h` above the bed: a teardrop (the
    round top and two 45 deg flanks meeting r sqrt 2 below the axis) on a `TEAR_WEB` web, or a D
    section where the apex would be less than `TEAR_MIN` above the bed."""
    if h - r * math.sqrt(2) >= TEAR_MIN:
        return 0.75 * math.pi * r**2 + r**2 + TEAR_WEB * (h - r * math.sqrt(2)) + TEAR_WEB**2 / 4
    return 2 * r * h + math.pi * r**2 / 2


# -- the pegged core link's closed form (its plan: parts/peg_plan.py `pegged_plan`) -----------------

def _disc_band(r: float, lo: float, hi: float) -> float:
    """Area of a disc of radius `r` (centred at 0) between the lines y = lo and y = hi."""
    def below(h: float) -> float:
        h = min(max(h, -r), r)
        return r * r * math.acos(-h / r) + h * math.sqrt(r * r - h * h)

    return max(0.0, below(hi) - below(lo))


def _pegged_link_estimate(spec: Spec, sockets: list[Socket], params: dict) -> Estimate:
    """Closed form of the pegged core link (parts/joint_solid.py `_core_link_pegged`), in print
    orientation (the arms' direction up, the pegs' ends on the bed): per peg a peg and a column
    (cylinders: one cylinder where their diameters are within frame.PEG_SNAP), the arch (a box from
    axis to axis, less the half columns inside it and its opening; the crown's block), the strut's
    sleeve (a cylinder, less its part inside the arch: `peg_plan.sleeve_in_arch`), less the bores. Where the two arm ports' along-arm
    heights differ by rounding only, the columns stand level (`STACK_SNAP_MM`)."""
    pl = pegged_plan(sockets, params)
    hole = math.pi / 4 * spec.bore**2
    vol = a_h = a_v = 0.0
    for c in pl.columns:
        vol += math.pi * (pl.peg_r**2 * pl.peg_len + c.col_r**2 * c.col_len)
        a_h += 2 * math.pi * pl.peg_r**2  # the peg's end and the shoulder + the column's top
        a_v += 2 * math.pi * (pl.peg_r * pl.peg_len + c.col_r * c.col_len)
    arch_len = pl.arch_hi - pl.arch_lo
    depth = pl.arch_n[1] - pl.arch_n[0]
    inside = len(pl.columns) * 0.5 * _disc_band(pl.col_r, pl.arch_n[0], pl.arch_n[1]) * arch_len
    vol += pl.spacing * depth * arch_len - inside
    a_h += 2 * (pl.spacing - 2 * pl.col_r) * depth
    a_v += 2 * (pl.spacing - 2 * pl.col_r) * arch_len
    if pl.opening is not None:
        # the opening through the arch's depth: its floor's area goes, its roof's and its two sides'
        # (each projected once up and once across) come: up, the roof and sides span the floor
        o = pl.opening
        vol -= o.area * depth
        a_v += 2 * (o.z1 - o.z0) * depth
    if pl.block is not None:
        (bx0, by0, bz0), (bx1, by1, bz1) = pl.block
        vol += (bx1 - bx0) * (by1 - by0) * (bz1 - bz0)
        a_h += (bx1 - bx0) * (by1 - by0)  # its top (its floor is the arch's top)
        a_v += 2 * ((bx1 - bx0) + (by1 - by0)) * (bz1 - bz0)
    for st in pl.struts:
        n = st.end - st.start
        vol += math.pi * pl.col_r**2 * n - sleeve_in_arch(pl, st)
        sin_t = math.sqrt(max(0.0, 1 - st.lean_cos**2))
        a_h += 2 * math.pi * pl.col_r * n * sin_t
        a_v += 2 * math.pi * pl.col_r * n * st.lean_cos
    for s in sockets:
        vol -= hole * s.depth
        a_v += math.pi * spec.bore * s.depth
    env = tuple(sorted(pl.extents))
    return Estimate(vol, a_h, a_v, (env[2], env[1], env[0]))
