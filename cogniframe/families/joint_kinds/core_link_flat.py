"""The flat core link: a tab link (core.link: tab) on level arms, whose sockets all but the strut
lie parallel to the plate. It prints flat and upside down (its top, the tab's top on the plate, on
the bed): the arm sleeves lie on the bed side by side, the strut rises on a web, and each socket's
sleeve joins the bolt pad through its own band (the tab, split); outside the plate the bands go on
down to the plate's bottom (the seat). Its bands and plate in plan are parts/joint_plan.py's. Its
params, screw and support are the tab link's."""

from __future__ import annotations

import math

import numpy as np

from ...parts.joint_plan import (BAND_PAST, TEAR_MIN, TEAR_WEB, PSocket, arm_direction, clear_of, horizontal, link_bands,
                                 link_bed_z, link_is_flat, link_plate_region, sleeve_levels, split_arms, transform)
from ...parts.record import Estimate, PartSpec
from .core_link_tab import CoreLinkTab
from .polygons import convex_clip, union_area


class CoreLinkFlat(CoreLinkTab):
    variant = "flat"

    def plans(self, spec) -> bool:
        return False  # planned as the tab link: its sockets make it flat

    def claims(self, params: dict, sockets) -> bool:
        return params.get("link", "tab") == "tab" and link_is_flat(sockets)

    def estimate(self, spec, sockets, params: dict) -> Estimate:
        return _flat_link_estimate(spec, params, sockets, spec.bore / 2 + spec.joints.wall)

    def print_from_local(self, part: PartSpec) -> np.ndarray:
        """Flat and upside down: the arm direction along x, the frame's up pointing into the bed."""
        r = (part.sockets[0].bore + 2 * part.wall) / 2
        x = horizontal(arm_direction(part))
        zp = np.array([0.0, 0.0, -1.0])
        rot = np.vstack([x, np.cross(zp, x), zp])
        return transform(rot, (0.0, 0.0, link_bed_z(dict(part.params), part.sockets, r)))

    def solid(self, part: PartSpec):
        m, socks, r = self.in_print(part)
        return _core_link_flat(part, socks, r, m)


def _flat_link_estimate(spec, params: dict, sockets, r: float) -> Estimate:
    """Closed form of the flat core link (`_core_link_flat`): the sleeves (arms:
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
            # its run inside the band (`_core_link_flat`: the band reaches BAND_PAST past the socket's
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



def _core_link_flat(part: PartSpec, socks: list[PSocket], r: float, m: np.ndarray):
    """The flat core link (level arms), printed upside down: each arm's sleeve lying on the bed (a
    teardrop on a thin web, or a D section where the axis stands low), the strut's sleeve rising on
    its web, and one band per socket from its sleeve's back end to the bolt pad, from the bed (the
    tab's top) down to the plate top: the tab, in as many strips as there are sockets, each as deep
    as the tab. Outside the plate the bands go on below the plate top, down to the plate's bottom:
    the seat, bearing on the plate's edges. Every face then looks up or sideways in print but
    the bores' ceilings (bridges of one bore) and the plate's imprint (the bands' undersides over
    the plate, which face up in print)."""
    from ...parts import joint_solid as cad

    params = dict(part.params)
    arms, others = split_arms(socks)
    rot, o = m[:3, :3], m[:3, 3]
    z_bed = float(o[2])  # the bed, as a height in the local frame (local z maps to z_bed - z)
    v0 = float(part.param("plate_top_z"))
    T = z_bed - v0
    pieces = []
    for s in socks:
        t0 = s.seat - part.wall
        if abs(float(s.direction[2])) >= cad.FLAT:
            # the strut: its web as wide as a sloped sleeve's (a teardrop on a thin web, 0.16 g
            # lighter, carries the payload worse: docs/stiffness-model.md)
            pieces.append(cad.sloped_sleeve(s.at(t0), s.direction, s.depth + part.wall, r))
        elif float(s.port[2]) - r * math.sqrt(2) >= TEAR_MIN:
            pieces.append(cad.teardrop(s.at(t0), s.direction, s.depth + part.wall, float(s.port[2]), r, TEAR_WEB))
        else:
            pieces.append(cad.sleeve(s, t0, r))

    def plan(poly):
        return [rot[:2, :2] @ np.asarray(p, float) + o[:2] for p in poly]

    levels = sleeve_levels(socks, r)
    bands = link_bands(params, part.sockets, part.wall, r)
    # each band from the bed to the plate's bottom (clear of the sleeves' levels); the plate's cut
    # leaves the tab over the plate and the seat beside it
    bottom = clear_of(z_bed + v0, levels)
    pieces += [cad.prism(plan(b), 0.0, bottom) for b in bands]
    body = cad.fuse_all(pieces)
    plate = cad.prism(plan(link_plate_region(params)), T, 1000.0)  # the plate, under its top
    c = np.asarray(part.param("esc_keepout"), float)
    h = float(part.param("esc_half"))
    # under the ESC board nothing stands above the board's underside (less 0.5 mm); cut through
    # the whole depth, so the cut faces are walls (a cut from the bed up would leave a ceiling)
    esc = cad.prism(plan([c[:2] + np.array([sx, sy]) * h for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]), -1.0, 1000.0) \
        if float(c[2]) < z_bed else None
    body = body.cut(plate) if esc is None else body.cut(plate).cut(esc)
    bolt = rot @ np.asarray(part.param("bolt_hole"), float) + o
    hole_d = float(part.param("screw_clearance"))
    bolt_hole = cad.cylinder((bolt[0], bolt[1], -1.0), (0.0, 0.0, 1.0), T + 2.0, hole_d / 2)
    return cad.finish(cad.above_bed(body), [cad.socket_cutter(s) for s in socks] + [bolt_hole])

