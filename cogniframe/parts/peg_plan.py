"""The pegged core link's geometry in print (core.link: pegs), without the CAD kernel: where its
pegs, columns, arch and strut sleeve stand (`pegged_plan`), and its pegs' axes in the link's own
frame (`peg_axes`), which the core plate's tubes follow.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .record import PARALLEL_TOL, PartSpec

# The authors' connector: per arm socket a TPU column round the socket with a solid peg beyond its
# bottom, coaxial with the rod, pressed into a bore of the ABS core; an arch joins the two columns
# at their mouths. The strut has its own peg, parallel to the arms' (the link presses in along one
# direction), standing under where the strut's socket crosses the pegs' shoulder, and a column on
# it up into the arch; the strut's sleeve leans out of that column, so the strut's load goes into
# the core through its own peg rather than round the arch. It prints standing: the arms' direction
# up, the pegs' ends on the bed (families/joint.py `PEGS` has the dimensions).
PEG_SNAP = 0.2  # mm: a peg and its column closer than this in diameter are one cylinder (no sliver shoulder)
STACK_SNAP_MM = 1e-3  # mm: the most the two columns are moved to stand level (rounding noise is ~1e-5)
ARCH_CLEAR = 0.2  # mm: the arch's depth never within this of the column's diameter (no tangent faces)


def is_pegged(part: PartSpec) -> bool:
    """Whether a core link is the pegged connector (core.link: pegs)."""
    return dict(part.params).get("link") == "pegs"


@dataclass(frozen=True)
class PegColumn:
    """One peg and its column in print: a vertical axis at `axis` (xy), the peg from the bed
    (`peg0`) to `col0`, the column from there to `col1` (an arm's: its socket's mouth; the
    strut's: into the arch, below the strut's mouth) of radius `col_r`. `socket`: the index of the
    socket it holds."""

    axis: np.ndarray
    peg0: float
    col0: float
    col1: float
    socket: int
    col_r: float

    @property
    def col_len(self) -> float:
        return self.col1 - self.col0


@dataclass(frozen=True)
class PegStrut:
    """The strut's sleeve: a cylinder along its socket from `start` to `end` (along it from the
    port), `lean_cos` = its direction . up in print, kept above its peg's shoulder and inside the
    45 deg cone that rises from the peg's top rim (`cone_r0`: the cone's radius at the shoulder,
    `cone_h` its height): its first layers stand on the peg. `column`: its peg's index in
    `PeggedPlan.columns`; `overlap`: the sleeve's volume that is not its own (below the shoulder,
    outside the cone, inside its column or the arch; mm^3); `wall`: the least TPU, across the
    axis of the pegs, round the part of its bore below the shoulder (in the peg)."""

    index: int
    start: float
    end: float
    lean_cos: float
    column: int
    cone_r0: float
    cone_h: float
    overlap: float
    wall: float


@dataclass(frozen=True, eq=False)
class PeggedPlan:
    rot: np.ndarray  # print <- local rotation: x across the pair (arm 0 to arm 1), z along the arms
    shift: np.ndarray  # print <- local offset: the pegs' ends on the bed
    columns: tuple[PegColumn, ...]
    peg_r: float
    peg_len: float
    col_r: float
    spacing: float  # between the columns' axes
    arch_x: tuple[float, float]  # print x of the two axes
    arch_n: tuple[float, float]  # print y: the arch's depth
    arch_lo: float  # print z
    arch_hi: float
    struts: tuple[PegStrut, ...]
    extents: tuple[float, float, float]  # print x, y, z sizes


def pegged_plan(sockets, params: dict) -> PeggedPlan:
    """The pegged link's pieces in print coordinates, from its sockets (local frame) and params."""
    dirs = [np.asarray(s.direction, float) for s in sockets]
    arms = [i for i in range(len(dirs)) if sum(float(dirs[i] @ e) > 1 - PARALLEL_TOL for e in dirs) > 1]
    if len(arms) != 2:
        raise ValueError(f"a pegged core link needs two parallel arm sockets, got {len(arms)}")
    d = dirs[arms[0]] / np.linalg.norm(dirs[arms[0]])
    ports = [np.asarray(sockets[i].port, float) for i in arms]
    lat = ports[1] - ports[0]
    lat = lat - d * float(lat @ d)
    lat /= np.linalg.norm(lat)
    rot = np.vstack([lat, np.cross(d, lat), d])
    peg_len = float(params["peg_len"])
    gap = float(params["peg_gap"])
    col_r = sockets[arms[0]].bore / 2 + float(params["column_wall"])
    peg_r = float(params["peg_d"]) / 2
    if abs(peg_r - col_r) < PEG_SNAP / 2:
        peg_r = col_r
    z_end = float(ports[0] @ d) + sockets[arms[0]].seat - gap - peg_len
    shift = np.array([0.0, 0.0, -z_end])
    cols = []
    # Both columns at the first's heights: stored to 1e-6 mm, a rectangle's pair lies up to ~1e-5
    # apart along the arms, steps of that size between the columns' and the arch's end faces (an
    # STL with open edges). The sockets are cut where they are.
    q0 = rot @ ports[0] + shift
    for p, i in zip(ports, arms):
        q = rot @ p + shift
        if abs(float(q[2] - q0[2])) > STACK_SNAP_MM:
            raise ValueError(f"the arm sockets of a pegged core link are {float(q[2] - q0[2]):.3g} mm apart along the arms")
        s = sockets[i]
        c0 = float(q0[2]) + s.seat - gap
        cols.append(PegColumn(q[:2].copy(), c0 - peg_len, c0, float(q0[2]) + s.seat + s.depth, i, col_r))
    y_c = float(cols[0].axis[1])
    arch_hi = min(c.col1 for c in cols)
    arch_lo = arch_hi - float(params["arch_len"])
    h = float(params["arch_depth"]) / 2
    if abs(h - col_r) < ARCH_CLEAR / 2:
        h = col_r + ARCH_CLEAR / 2
    n0, n1 = -h, h
    struts_at = [i for i in range(len(sockets)) if i not in arms]
    for i in struts_at:  # the arch reaches the strut's sleeve: at least half its radius into it at the mouth
        s = sockets[i]
        m = rot @ (np.asarray(s.port, float) + dirs[i] * (s.seat + s.depth)) + shift
        n0, n1 = min(n0, float(m[1]) - y_c + col_r / 2), max(n1, float(m[1]) - y_c - col_r / 2)
        arch_lo = min(arch_lo, float(m[2]) - col_r / 2)
    # the strut's mouth sets the depth anywhere: it too keeps off the columns' outline
    if abs(n0 + col_r) < ARCH_CLEAR / 2:
        n0 = -col_r - ARCH_CLEAR / 2
    if abs(n1 - col_r) < ARCH_CLEAR / 2:
        n1 = col_r + ARCH_CLEAR / 2
    x0, x1 = sorted(float(c.axis[0]) for c in cols)
    arch_n = (y_c + n0, y_c + n1)
    struts = []
    lo = [min(x0, x1) - max(peg_r, col_r), y_c - max(peg_r, col_r, -n0), 0.0]
    hi = [max(x0, x1) + max(peg_r, col_r), y_c + max(peg_r, col_r, n1), max(c.col1 for c in cols)]
    shoulder = cols[0].col0
    box = ((x0, arch_n[0], arch_lo), (x1, arch_n[1], arch_hi))
    for i in struts_at:
        s = sockets[i]
        ds = rot @ dirs[i]
        t0, t1 = s.seat - float(params["column_wall"]), s.seat + s.depth
        p0 = rot @ np.asarray(s.port, float) + shift
        axis, reach = _peg_under(p0, ds, s.seat, t1, s.bore / 2, shoulder)
        # the column rises into the arch, and no higher than the strut's mouth plane over its disc
        # (past the mouth it would lengthen the socket on one side and bury its chamfer). It is as
        # wide as its peg, one cylinder: a column as wide as the sleeve, whose axis crosses the
        # sleeve's, meets it in two crossing ellipses, a singular intersection that OCC's boolean
        # resolves differently in a link and its mirror image.
        strut_r = peg_r
        m = p0 + ds * t1
        flat = math.hypot(float(ds[0]), float(ds[1]))
        below_mouth = float(m[2]) - (float((axis - m[:2]) @ ds[:2]) + strut_r * flat) / float(ds[2])
        top = min(arch_hi, max(below_mouth, arch_lo + 0.5 * (arch_hi - arch_lo)))
        cols.append(PegColumn(axis, shoulder - peg_len, shoulder, top, i, strut_r))
        cone_h = max(float((p0 + ds * t1)[2]) - shoulder + col_r, 1.0)
        overlap, rim = _sleeve_overlap(p0, ds, t0, t1, col_r, shoulder, axis, peg_r, cols[-1].col1, strut_r, box)
        struts.append(PegStrut(i, t0, t1, float(ds[2]), len(cols) - 1, peg_r, cone_h, overlap, peg_r - reach))
        e = p0 + ds * t1
        pad = col_r * np.sqrt(np.clip(1 - ds**2, 0.0, 1.0))
        lo = [min(a, b, c) for a, b, c in zip(lo, e - pad, rim[0])]
        hi = [max(a, b, c) for a, b, c in zip(hi, e + pad, rim[1])]
        lo = [min(lo[0], float(axis[0]) - peg_r), min(lo[1], float(axis[1]) - peg_r), lo[2]]
        hi = [max(hi[0], float(axis[0]) + peg_r), max(hi[1], float(axis[1]) + peg_r), max(hi[2], top)]
    ext = tuple(float(b - a) for a, b in zip(lo, hi))
    return PeggedPlan(rot, shift, tuple(cols), peg_r, peg_len, col_r, x1 - x0, (x0, x1), arch_n, arch_lo, arch_hi,
                      tuple(struts), ext)


@dataclass(frozen=True, eq=False)
class PegAxis:
    """One peg of a pegged core link in the link's local frame: its axis from the free `end` to
    the `shoulder` where it meets its column, and its radius."""

    end: np.ndarray
    shoulder: np.ndarray
    radius: float


def peg_axes(sockets, params: dict) -> tuple[PegAxis, ...]:
    """The pegs of a pegged core link in its local frame, one per column of `pegged_plan` (each
    runs from `peg0` to `col0` along print z at the column's axis, taken back through the plan's
    print <- local transform): the core's bores that hold them (families/core_plate.py) follow
    every column the plan has."""
    pl = pegged_plan(sockets, params)

    def local(xy, z: float) -> np.ndarray:
        return pl.rot.T @ (np.array([float(xy[0]), float(xy[1]), z]) - pl.shift)

    return tuple(PegAxis(local(c.axis, c.peg0), local(c.axis, c.col0), pl.peg_r) for c in pl.columns)


def _frame_of(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors square to unit `d` and to each other."""
    a = np.cross(d, [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    return a, np.cross(d, a)


def _peg_under(p0, d, seat: float, t1: float, r: float, shoulder: float, n: int = 96):
    """Where the strut's peg stands (print xy) and the radius (mm) round that axis that holds the
    part of its bore below the pegs' shoulder: the centre of the smallest circle holding that
    part's outline seen from above, so the peg's TPU round it is as thick as it can be. Without
    such a part (a socket wholly above the shoulder), under where its axis crosses the shoulder."""
    from scipy.optimize import minimize_scalar  # where used: importing the plan stays light

    d = np.asarray(d, float)
    a, b = _frame_of(d)
    phi = np.arange(n) * 2 * math.pi / n
    ring = np.outer(a, np.cos(phi)) + np.outer(b, np.sin(phi))
    t = seat + np.arange(4 * n + 1) * (t1 - seat) / (4 * n)
    # the bore's outline: its floor's rim and its wall, cut at the shoulder; where the wall
    # crosses the shoulder, the crossing itself (the outline's edge on that plane)
    wall = np.asarray(p0, float)[:, None, None] + d[:, None, None] * t[None, :, None] + r * ring[:, None, :]
    pts = wall.reshape(3, -1)
    pts = pts[:, pts[2] <= shoulder]
    z_ring = np.asarray(p0, float)[2] + r * ring[2]
    if abs(d[2]) > 1e-9:
        tc = (shoulder - z_ring) / d[2]
        ok = (tc >= seat) & (tc <= t1)
        cross = np.asarray(p0, float)[:, None] + d[:, None] * tc[None, :] + r * ring
        pts = np.hstack([pts, cross[:, ok]])
    if pts.shape[1] == 0:
        t_axis = (shoulder - float(np.asarray(p0, float)[2])) / d[2] if abs(d[2]) > 1e-9 else 0.0
        return (np.asarray(p0, float) + d * t_axis)[:2].copy(), 0.0
    xy = np.unique(np.round(pts[:2].T, 9), axis=0)

    def worst(c):
        return float(np.max(np.hypot(xy[:, 0] - c[0], xy[:, 1] - c[1])))

    # the farthest point's distance is convex in the centre: nested one-dimensional minima
    span = float(np.ptp(xy, axis=0).max()) + 1.0
    mid = xy.mean(axis=0)

    def best_y(x):
        res = minimize_scalar(lambda y: worst((x, y)), bounds=(mid[1] - span, mid[1] + span), method="bounded",
                              options={"xatol": 1e-6})
        return float(res.x), float(res.fun)

    rx = minimize_scalar(lambda x: best_y(x)[1], bounds=(mid[0] - span, mid[0] + span), method="bounded",
                         options={"xatol": 1e-6})
    y, reach = best_y(float(rx.x))
    return np.array([float(rx.x), y]), reach


def _sleeve_overlap(p0, d, t0: float, t1: float, r: float, shoulder: float, axis, cone_r0: float, col_top: float,
                    col_r: float, box, n: int = 96):
    """The strut sleeve's (radius `r` along unit `d` from p0 + d t0 to p0 + d t1) volume that is not
    its own piece's (mm^3): below the shoulder, outside the 45 deg cone from the peg's rim, inside
    its column (radius `col_r` round `axis` up to `col_top`) or inside the arch (the box lo..hi);
    and the piece's bounds (lo, hi) from its wall. The midpoint rule in the sleeve's coordinates
    (n steps along and round it, n / 3 across its radius: ~0.1 % of the overlap)."""
    d = np.asarray(d, float)
    a, b = _frame_of(d)
    nr = max(4, n // 3)
    t = t0 + (np.arange(n) + 0.5) * (t1 - t0) / n
    rho = (np.arange(nr) + 0.5) * r / nr
    phi = (np.arange(n) + 0.5) * 2 * math.pi / n
    T, P, F = np.meshgrid(t, rho, phi, indexing="ij")

    def at(T, P, F):
        return (np.asarray(p0, float)[:, None] + d[:, None] * T.ravel() + a[:, None] * (P * np.cos(F)).ravel()
                + b[:, None] * (P * np.sin(F)).ravel())

    def own(pts):
        rxy = np.hypot(pts[0] - axis[0], pts[1] - axis[1])
        lo, hi = (np.asarray(v, float)[:, None] for v in box)
        in_box = np.all((pts >= lo) & (pts <= hi), axis=0)
        in_col = (rxy <= col_r) & (pts[2] <= col_top)
        return (pts[2] >= shoulder) & (rxy <= cone_r0 + (pts[2] - shoulder)) & ~in_box & ~in_col

    w = P.ravel() * (r / nr) * (2 * math.pi / n) * ((t1 - t0) / n)
    overlap = float(w[~own(at(T, P, F))].sum())
    # the piece's bounds from its wall inside the cone (its top end's rim is on the wall; where the
    # cone trims it, within a few tenths of the shoulder, the peg's disc bounds it to ~0.1 mm)
    tw = t0 + np.arange(4 * n + 1) * (t1 - t0) / (4 * n)
    Tw, Fw = np.meshgrid(tw, np.arange(2 * n) * math.pi / n, indexing="ij")
    wall = at(Tw, np.full(Tw.shape, r), Fw)
    rxy = np.hypot(wall[0] - axis[0], wall[1] - axis[1])
    keep = (wall[2] >= shoulder) & (rxy <= cone_r0 + (wall[2] - shoulder))
    wall = wall[:, keep]
    return overlap, (wall.min(axis=1), wall.max(axis=1))

