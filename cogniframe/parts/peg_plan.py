"""The pegged core link's geometry in print (core.link: pegs), without the CAD kernel: where its
pegs, columns, arch and strut sleeve stand (`pegged_plan`), and its pegs' axes in the link's own
frame (`peg_axes`), which the core plate's tubes follow.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..frame import PEG_ARCH_LIFT, PEG_SLEEVE_FLOOR, peg_column_r
from .record import PARALLEL_TOL

# The authors' connector: per arm socket a TPU column round the socket with a solid peg beyond its
# bottom, coaxial with the rod, pressed into a bore of the ABS core; an arch joins the two columns.
# The strut hangs on the arch, as the authors' third column does: its sleeve starts inside the arch
# (frame.py `pegged_strut_port` puts its socket there), so the strut's load goes round the arch into
# the arm pegs, and the arch reaches down the columns to hold the sleeve's back end. It prints
# standing: the arms' direction up, the pegs' ends on the bed (families/joint_kinds/core_link_pegs.py `PEGS` has the
# dimensions).
STACK_SNAP_MM = 1e-3  # mm: the most the two columns are moved to stand level (rounding noise is ~1e-5)
ARCH_CLEAR = 0.2  # mm: the arch's depth never within this of the column's diameter (no tangent faces)
ARCH_WEB = 0.5  # mm: the arch's underside between a column and the opening (the opening touches no column)
SLEEVE_TOL = 1e-4  # mm: the strut's sleeve on the crown as planned (ports and unit directions are stored to 1e-6)


@dataclass(frozen=True)
class PegColumn:
    """One arm's peg and column in print: a vertical axis at `axis` (xy), the peg from the bed
    (`peg0`) to `col0`, the column from there to `col1` (its socket's mouth) of radius `col_r`.
    `socket`: the index of the socket it holds."""

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
    """The strut's sleeve: a cylinder of the columns' radius along its socket from `start` to
    `end` (along it from the port), `lean_cos` = its direction . up in print; its back end lies in
    the arch, the rest leans out of it. `back`, `mouth`: its axis's ends in print (mm)."""

    index: int
    start: float
    end: float
    lean_cos: float
    back: tuple[float, float, float]
    mouth: tuple[float, float, float]


@dataclass(frozen=True)
class ArchOpening:
    """The opening under the arch's crown, through its depth (print y): a trapezoid in print x, z
    centred at `x`, `half` wide each side at its floor `z0` (the arch's underside), its sides at
    45 deg or steeper up to its roof `z1`, `top_half` wide each side (0: an apex)."""

    x: float
    half: float
    top_half: float
    z0: float
    z1: float

    def outline(self, below: float = 0.0) -> list[tuple[float, float]]:
        """Its corners (x, z) counter-clockwise, the floor `below` lower (a cutter's overshoot,
        the sides carried on down)."""
        x, h, th = self.x, self.half, self.top_half
        floor = [(x - h - below, self.z0 - below), (x + h + below, self.z0 - below)]
        return floor + ([(x, self.z1)] if th == 0 else [(x + th, self.z1), (x - th, self.z1)])

    @property
    def area(self) -> float:
        return (self.half + self.top_half) * (self.z1 - self.z0)

    def faces(self) -> tuple[np.ndarray, np.ndarray]:
        """Its half-spaces n . p <= c in print (x, y, z): (normals, offsets); through the arch's
        whole depth, so none faces y. `contains` holds where all of them do."""
        slope = (self.half - self.top_half) / (self.z1 - self.z0)
        normals = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0], [1.0, 0.0, slope], [-1.0, 0.0, slope]])
        return normals, np.array([-self.z0, self.z1, self.half + self.x + slope * self.z0,
                                  self.half - self.x + slope * self.z0])

    def contains(self, x, z):
        """Whether print points (x, z) lie inside (arrays)."""
        slope = (self.half - self.top_half) / (self.z1 - self.z0)
        return (z > self.z0) & (z < self.z1) & (np.abs(x - self.x) < self.half - slope * (z - self.z0))


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
    opening: ArchOpening | None
    block: tuple | None  # the crown's block over the mouths' plane under the strut's sleeve: (lo, hi) print corners
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
    peg_r = float(params["peg_d"]) / 2
    # one rule with the frame, which places the strut's sleeve by it
    col_r = peg_column_r(sockets[arms[0]].bore, float(params["column_wall"]), float(params["peg_d"]))
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
    crown = arch_hi - float(params["arch_len"])
    shoulder = cols[0].col0
    arch_lo = shoulder + PEG_ARCH_LIFT
    h = float(params["arch_depth"]) / 2
    x0, x1 = sorted(float(c.axis[0]) for c in cols)
    # the opening under the crown: its sides rise at 45 deg from the arch's underside, ARCH_WEB in
    # from each column (a web there: the opening touches no column), to a flat roof at the crown
    # (a bridge, as the authors print theirs), or to an apex below it where the span is short
    half = (x1 - x0) / 2 - col_r - ARCH_WEB
    rise = crown - arch_lo
    if half <= rise:  # the 45 deg sides meet below the crown: an apex
        opening = ArchOpening((x0 + x1) / 2, half, 0.0, arch_lo, arch_lo + half)
    elif half - rise < ARCH_WEB:  # a roof narrower than a web: an apex at the crown, the sides steeper
        opening = ArchOpening((x0 + x1) / 2, half, 0.0, arch_lo, crown)
    else:
        opening = ArchOpening((x0 + x1) / 2, half, half - rise, arch_lo, crown)
    if min(half, rise) <= ARCH_WEB:
        opening = None
    # each strut's sleeve: its back end's disc lies in the crown (frame.py `pegged_strut_port`), the
    # arch deep enough across the pair to hold the disc seen from above
    sleeves = []
    for i in [i for i in range(len(sockets)) if i not in arms]:
        s = sockets[i]
        ds = rot @ dirs[i]
        t0, t1 = s.seat - float(params["column_wall"]), s.seat + s.depth
        back = rot @ np.asarray(s.port, float) + shift + ds * t0
        spread = col_r * np.sqrt(np.clip(1 - ds**2, 0.0, 1.0))  # the disc's half-extent along x, y, z
        if float(back[2] - spread[2]) < crown + PEG_SLEEVE_FLOOR - SLEEVE_TOL:
            raise ValueError(f"the strut's sleeve of a pegged core link starts {crown - float(back[2] - spread[2]):.3g} mm "
                             "below the arch's crown (frame.py `pegged_strut_port` puts it on the crown)")
        h = max(h, abs(float(back[1]) - y_c) + float(spread[1]))
        sleeves.append((i, ds, t0, t1, back, spread))
    # the arch keeps off the columns' outline (no tangent faces)
    if abs(h - col_r) < ARCH_CLEAR / 2:
        h = col_r + ARCH_CLEAR / 2
    arch_n = (y_c - h, y_c + h)
    # the crown's block: the strut's back-end disc leans up past the mouths' plane, so the crown
    # rises under it, as the authors' does under their third column, to PEG_SLEEVE_FLOOR over the
    # disc's top: no part of the disc faces the bed unsupported
    block = None
    for i, ds, t0, t1, back, spread in sleeves:
        top = float(back[2] + spread[2]) + PEG_SLEEVE_FLOOR
        if top > arch_hi:
            w = float(spread[0]) + ARCH_CLEAR / 2
            lo_b = (float(back[0]) - w, arch_n[0], arch_hi)
            hi_b = (float(back[0]) + w, arch_n[1], top)
            block = (lo_b, hi_b) if block is None else (tuple(map(min, block[0], lo_b)), tuple(map(max, block[1], hi_b)))
    lo = [min(x0, x1) - max(peg_r, col_r), y_c - max(peg_r, col_r, h), 0.0]
    hi = [max(x0, x1) + max(peg_r, col_r), y_c + max(peg_r, col_r, h), max(c.col1 for c in cols)]
    struts = []
    for i, ds, t0, t1, back, spread in sleeves:
        p0 = back - ds * t0
        mouth = p0 + ds * t1
        struts.append(PegStrut(i, t0, t1, float(ds[2]), tuple(map(float, back)), tuple(map(float, mouth))))
        lo = [min(a, float(c)) for a, c in zip(lo, np.minimum(back - spread, mouth - spread))]
        hi = [max(a, float(c)) for a, c in zip(hi, np.maximum(back + spread, mouth + spread))]
    if block is not None:
        hi[2] = max(hi[2], block[1][2])
    ext = tuple(float(b - a) for a, b in zip(lo, hi))
    return PeggedPlan(rot, shift, tuple(cols), peg_r, peg_len, col_r, x1 - x0, (x0, x1), arch_n, arch_lo, arch_hi,
                      opening, block, tuple(struts), ext)


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


def sleeve_in_arch(pl: PeggedPlan, st: PegStrut, n: int = 96) -> float:
    """The strut sleeve's volume inside the arch (its box less the opening, and the crown's block),
    mm^3: the midpoint rule in the sleeve's coordinates (n steps along and round it, n / 3 across
    its radius: ~0.1 % of the volume). Only the closed form needs it, so the plan does not carry it."""
    back, mouth = np.asarray(st.back, float), np.asarray(st.mouth, float)
    d = (mouth - back) / np.linalg.norm(mouth - back)
    p0 = back - d * st.start
    (x0, x1), (n0, n1) = pl.arch_x, pl.arch_n
    box = ((x0, n0, pl.arch_lo), (x1, n1, pl.arch_hi))
    return _sleeve_in_arch(p0, d, st.start, st.end, pl.col_r, box, pl.opening, pl.block, n)


def _sleeve_in_arch(p0, d, t0: float, t1: float, r: float, box, opening, block, n: int = 96) -> float:
    """`sleeve_in_arch` for a sleeve of radius `r` along unit `d` from p0 + d t0 to p0 + d t1, the
    box lo..hi, the `ArchOpening` and the block (lo, hi) or None.

    The midpoint rule's points lie on n x n / 3 lines along the sleeve (one per radius and angle),
    n points each, a line's points of one weight. Box, block and opening are convex, so each
    holds a run of consecutive points of a line, found from where the line crosses its faces
    (`_runs`): a line's points inside are those of box or block, less those of the opening, counted
    by inclusion-exclusion over the runs' overlaps. The same sum as testing every point, without
    the points."""
    d = np.asarray(d, float)
    a, b = _frame_of(d)
    nr = max(4, n // 3)
    rho = (np.arange(nr) + 0.5) * r / nr
    phi = (np.arange(n) + 0.5) * 2 * math.pi / n
    radial = np.cos(phi)[:, None] * a + np.sin(phi)[:, None] * b  # (n, 3)
    start = (np.asarray(p0, float) + rho[:, None, None] * radial[None]).reshape(-1, 3)  # each line's point at t = 0
    step = (t1 - t0) / n
    box_run = _runs(start, d, _box_faces(box), t0, step, n)
    block_run = _runs(start, d, _box_faces(block), t0, step, n) if block is not None else None
    open_run = _runs(start, d, opening.faces(), t0, step, n) if opening is not None else None

    def count(*runs):
        first = np.max([f for f, _ in runs], axis=0)
        last = np.min([last for _, last in runs], axis=0)
        return np.maximum(last - first + 1, 0)

    inside = count(box_run)
    if block_run is not None:
        inside = inside + count(block_run) - count(box_run, block_run)
    if open_run is not None:
        inside = inside - count(box_run, open_run)
        if block_run is not None:
            inside = inside - count(block_run, open_run) + count(box_run, block_run, open_run)
    w = rho * (r / nr) * (2 * math.pi / n) * step  # a point's weight on each radius
    return float((inside.reshape(nr, n).sum(axis=1) * w).sum())


def _box_faces(box) -> tuple[np.ndarray, np.ndarray]:
    """The half-spaces n . x <= c of an axis-aligned box (lo, hi): (normals, offsets)."""
    lo, hi = (np.asarray(v, float) for v in box)
    eye = np.eye(3)
    return np.vstack([-eye, eye]), np.concatenate([-lo, hi])


def _runs(start: np.ndarray, d: np.ndarray, faces, t0: float, step: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Per line x = start + d t, the first and last index i of its points t_i = t0 + (i + 1/2) step,
    i < n, inside the convex region n . x <= c (`faces`); first > last where none is."""
    normals, c = faces
    along = normals @ d  # (faces,): how fast each line approaches a face
    gap = c[None, :] - start @ normals.T  # (lines, faces)
    lo = np.full(len(start), -np.inf)
    hi = np.full(len(start), np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        cross = gap / along[None, :]
    for k, v in enumerate(along):
        if v > 0:
            hi = np.minimum(hi, cross[:, k])
        elif v < 0:
            lo = np.maximum(lo, cross[:, k])
        else:  # parallel to the face: the whole line on one side of it
            hi = np.where(gap[:, k] >= 0, hi, -np.inf)
    with np.errstate(invalid="ignore"):
        first = np.clip(np.ceil((lo - t0) / step - 0.5), 0, n).astype(int)
        last = np.clip(np.floor((hi - t0) / step - 0.5), -1, n - 1).astype(int)
    return first, last
