"""The pegged core link (core.link: pegs): the authors' connector, measured on
Flex_Main_connector_new_bumper.stl of thecognifly/CogniFly-STL (docs/authors-parts.md,
tools/pegged_link_fe.py `Connector`). Each arm socket sits in a TPU column whose far end is a
solid peg, pressed into a bore of the ABS core; an arch joins the two columns, and the strut
hangs on it. It prints standing, the arms' direction up and the pegs' ends on the bed; its plan
in print is parts/peg_plan.py's `pegged_plan`. The core's bores hold the pegs (its support body);
no closed form models its stiffness (the joint surrogate does, fitted on its FE)."""

from __future__ import annotations

import math

import numpy as np

from ...frame import PEG_ARCH_LEN, PEG_COLUMN_WALL, PEG_D, PEG_GAP, PEG_TUBE_WALL
from ...parts.joint_plan import PARALLEL_TOL, PSocket, transform
from ...parts.peg_plan import peg_axes, pegged_plan, sleeve_in_arch
from ...parts.record import Estimate, PartSpec
from .kind import JointKind

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


class CoreLinkPegs(JointKind):
    node = "core_link"
    variant = "pegs"
    has_body = True
    chiral = True
    closed_form_stiffness = False  # its sleeves are the pegs' columns, held by the core's bores
    surrogate_reads_wall = False  # the columns have the connector's own wall, not joints.wall
    fitted = "pressed in"

    @property
    def surrogate_family(self) -> str:
        return self.label

    def plans(self, spec) -> bool:
        return spec.core.link == "pegs"

    def claims(self, params: dict, sockets) -> bool:
        return params.get("link") == "pegs"

    def params(self, spec, frame, corner, origin, sockets) -> list[tuple[str, object]]:
        return list(PEGS)  # no screw: the pegs are pressed into the core's bores

    def refuse(self, spec, sockets, params: dict) -> None:
        """A strut leaning more than `PEG_LEAN_MAX` from the arms (its sleeve would need
        supports), pegs whose bores would run into each other in the core, or a strut sleeve that
        would run into an arm's column: the spec's error naming core.link."""
        dirs = [np.asarray(s.direction, float) for s in sockets]
        arm = next(d for d in dirs if sum(float(d @ e) > 1 - PARALLEL_TOL for e in dirs) > 1)  # the arm pair's
        for s in sockets:
            lean = math.degrees(math.acos(min(1.0, float(np.asarray(s.direction, float) @ arm))))
            if lean > PEG_LEAN_MAX + 1e-6:
                raise spec.error("core.link", f"the pegged core link prints standing on its pegs, the arms upright, and the strut "
                                 f"leaves the arms at {lean:.0f} deg: its sleeve would overhang more than {PEG_LEAN_MAX:g} deg "
                                 "and need supports", "set core.link: tab, or shape the frame so the struts leave the core "
                                 f"within {PEG_LEAN_MAX:g} deg of the arms (level arms, a lower or wider box)")
        _pegs_fit(spec, pegged_plan(sockets, params))

    def estimate(self, spec, sockets, params: dict) -> Estimate:
        return _pegged_link_estimate(spec, sockets, params)

    def peg_axes(self, part: PartSpec) -> tuple:
        return peg_axes(part.sockets, dict(part.params))

    def fixing_words(self, which: str, spacer: str | None) -> str:
        return (f"Press a TPU core link onto each corner of the core plate{which}: push its two pegs all the way into the "
                "pair of tubes under the plate's arm there, up to the columns' shoulders (no screw). ")

    def stacking_words(self, spacer: str | None) -> str | None:
        """The plate hangs on standoffs (no link bolt clamps it to the spacer)."""
        if not spacer:
            return None
        return (f"Lay the {spacer}'s bar on the battery holder's rear stack holes. Screw the four standoffs onto the holder "
                "with the countersunk screws from inside it (the driver comes up through the floor window; each head sits "
                f"flush in its countersink in the ceiling): the two rear ones through the {spacer}'s bar, the two longer front "
                "ones straight on the holder. Set the plate on them; the stack's screws clamp it to them later. The holder's "
                "open end faces the front so the battery slides in.")

    def print_from_local(self, part: PartSpec) -> np.ndarray:
        pl = pegged_plan(part.sockets, dict(part.params))
        return transform(pl.rot, pl.shift)

    def solid(self, part: PartSpec):
        _, socks, _ = self.in_print(part)
        return _core_link_pegged(part, socks)

    def support_faces(self, part: PartSpec, m: np.ndarray, tol: float, curvature: int):
        """The pegs' sides and inner ends (on the bed in print): the ABS bores hold them both ways."""
        pl = pegged_plan(part.sockets, dict(part.params))
        tol_peg = 0.1 + pl.peg_r * (1 - math.cos(math.pi / curvature))  # the facets' sagitta on the peg

        def sel_pegs(c, n, pl=pl):
            on_peg = np.zeros(c.shape[1], bool)
            for col in pl.columns:
                radial = np.hypot(c[0] - col.axis[0], c[1] - col.axis[1])
                side = (np.abs(radial - pl.peg_r) < tol_peg) & (c[2] < col.col0 + 1e-3) & (np.abs(n[2]) < 0.1)
                end = (np.abs(c[2] - col.peg0) < 1e-3) & (radial < pl.peg_r + tol) & (n[2] < -0.99)
                on_peg |= side | end
            return on_peg

        return sel_pegs

    def surrogate_features(self, part: PartSpec) -> tuple[list[str], list[float]]:
        """The link's shape as its plan builds it: the sizes its stiffness follows as power laws
        (the arch's span, depth and height, the columns' length and radius, the strut sleeve's
        length), the strut's lean, and the opening's and the crown block's extents, which change
        the arch's section."""
        pl = pegged_plan(part.sockets, dict(part.params))
        col = pl.columns[0]
        names = ["g_log_span", "g_log_arch_depth", "g_log_arch_height", "g_log_col_len", "g_log_col_r"]
        vals = [math.log(pl.spacing), math.log(pl.arch_n[1] - pl.arch_n[0]), math.log(pl.arch_hi - pl.arch_lo),
                math.log(col.col_len), math.log(pl.col_r)]
        o = pl.opening
        names += ["g_open_half", "g_open_top_half", "g_open_rise"]
        vals += [o.half, o.top_half, o.z1 - o.z0] if o is not None else [0.0, 0.0, 0.0]
        names.append("g_block_h")
        vals.append(pl.block[1][2] - pl.block[0][2] if pl.block is not None else 0.0)
        for i, st in enumerate(pl.struts):
            names += [f"g_strut{i}_lean_cos", f"g_strut{i}_log_len"]
            vals += [st.lean_cos, math.log(st.end - st.start)]
        return names, vals


def _pegs_fit(spec, pl) -> None:
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



def _disc_band(r: float, lo: float, hi: float) -> float:
    """Area of a disc of radius `r` (centred at 0) between the lines y = lo and y = hi."""
    def below(h: float) -> float:
        h = min(max(h, -r), r)
        return r * r * math.acos(-h / r) + h * math.sqrt(r * r - h * h)

    return max(0.0, below(hi) - below(lo))


def _pegged_link_estimate(spec, sockets, params: dict) -> Estimate:
    """Closed form of the pegged core link (`_core_link_pegged`), in print
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


def _core_link_pegged(part: PartSpec, socks: list[PSocket]):
    """The pegged core link (parts/peg_plan.py `pegged_plan`), standing in print: per arm a solid
    peg from the bed and a column round the socket above it, the arch joining the columns from
    their mouths down to the pegs' shoulder round its opening, the crown's block over the mouths,
    and the strut's sleeve along its socket, its back end in the crown; less the sockets."""
    from ...parts import joint_solid as cad

    cq = cad._cq()
    pl = pegged_plan(part.sockets, dict(part.params))
    pieces = []
    for c in pl.columns:
        x, y = float(c.axis[0]), float(c.axis[1])
        if pl.peg_r == c.col_r:  # one cylinder (frame.py `peg_column_r`)
            pieces.append(cad.cylinder((x, y, c.peg0), (0, 0, 1), c.col1 - c.peg0, c.col_r))
        else:
            pieces += [cad.cylinder((x, y, c.peg0), (0, 0, 1), c.col0 - c.peg0, pl.peg_r),
                       cad.cylinder((x, y, c.col0), (0, 0, 1), c.col_len, c.col_r)]
    (x0, x1), (n0, n1) = cad.exact(pl.arch_x), cad.exact(pl.arch_n)
    lo, hi = cad.exact(pl.arch_lo), cad.exact(pl.arch_hi)
    arch = cq.Solid.makeBox(cad.exact(x1 - x0), cad.exact(n1 - n0), cad.exact(hi - lo), cad.vec((x0, n0, lo)))
    if pl.opening is not None:
        # the opening's outline (x, z) extruded through the arch's depth, overshooting both faces
        xz = [tuple(map(float, p)) for p in cad.exact(pl.opening.outline(below=1.0))]
        hole = cq.Workplane("XZ", origin=(0, cad.exact(n1 + 1.0), 0)).polyline(xz).close().extrude(cad.exact(n1 - n0 + 2.0)).val()
        arch = arch.cut(hole)
    pieces.append(arch)
    if pl.block is not None:
        lo, hi = cad.exact(pl.block)
        pieces.append(cq.Solid.makeBox(*(float(v) for v in cad.exact(hi - lo)), cad.vec(lo)))
    for st in pl.struts:
        s = socks[st.index]
        pieces.append(cad.cylinder(s.at(st.start), s.direction, st.end - st.start, pl.col_r))
    return cad.finish(cad.fuse_all(pieces), [cad.socket_cutter(s) for s in socks])

