"""The closed-form joint super-element (``method="analytic"``): microseconds, for sweeps and as a
cross-check of the solid FE.

Per socket, a 6 x 6 spring from the rod at the socket mouth to the joint centre: the rod as a
beam on an elastic (Winkler) foundation -- the interface layer -- over the socket depth
(Hetenyi's finite beam, `bef_end_flexibility`), in series with the sleeve as a TPU cantilever
from the joint centre to the mouth (the knee's hinged leg: through the living-hinge web), axial
grip by interface shear and bearing on the socket bottom, torsion likewise. The centre is kept
as the support body where the joint has one, else condensed out.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .model import Interface, JointStiffness, _block_rot, _has_body, hinge_geometry, hinged_socket, interface, joint_kind


def bef_end_flexibility(length: float, ei: float, k_found: float) -> np.ndarray:
    """Hetenyi: 2x2 flexibility [[w/P, w/M], [phi/P, phi/M]] at one end of a free-free beam of
    `length` (mm) and bending stiffness `ei` (N mm^2) on a Winkler foundation of modulus
    `k_found` (N/mm per mm), loaded at that end by a force P and a moment M (w and phi the end's
    deflection and slope, same sense as the load). lambda = (k / 4 EI)^(1/4).

        w/P   = 2 lam / k      (sinh L cosh L - sin L cos L) / (sinh^2 L - sin^2 L)
        w/M   = 2 lam^2 / k    (sinh^2 L + sin^2 L)          / (sinh^2 L - sin^2 L)
        phi/M = 4 lam^3 / k    (sinh L cosh L + sin L cos L) / (sinh^2 L - sin^2 L)

    with L standing for lam * length (Hetenyi, Beams on Elastic Foundation, 1946, ch. 5).
    """
    lam = (k_found / (4 * ei)) ** 0.25
    x = lam * length
    if x < 1e-3:  # rigid limit (series to avoid 0/0): 4/(kL), 6/(kL^2), 12/(kL^3)
        L = length
        return np.array([[4 / (k_found * L), 6 / (k_found * L**2)], [6 / (k_found * L**2), 12 / (k_found * L**3)]])
    sh, ch, s, c = math.sinh(x), math.cosh(x), math.sin(x), math.cos(x)
    den = sh * sh - s * s
    f_wp = 2 * lam / k_found * (sh * ch - s * c) / den
    f_wm = 2 * lam**2 / k_found * (sh * sh + s * s) / den
    f_pm = 4 * lam**3 / k_found * (sh * ch + s * c) / den
    return np.array([[f_wp, f_wm], [f_wm, f_pm]])


def cantilever_flexibility(segments: list[tuple[float, float]], e: float) -> np.ndarray:
    """2x2 end flexibility [[w/P, w/M], [phi/P, phi/M]] at the free end of a clamped beam made
    of `segments` (length, I) from the clamp outwards (unit-load integrals, exact)."""
    total = sum(l for l, _ in segments)
    f = np.zeros((2, 2))
    s0 = 0.0
    for l, i in segments:
        a, b = total - s0 - l, total - s0  # distance from the free end, at segment's ends
        f[0, 0] += (b**3 - a**3) / 3 / (e * i)
        f[0, 1] += (b**2 - a**2) / 2 / (e * i)
        f[1, 1] += l / (e * i)
        s0 += l
    f[1, 0] = f[0, 1]
    return f


def _socket_local_k(spec, sock, itf: Interface, hinge: tuple[float, float, float] | None,
                    rod_e: float, rod_d: float, wall: float) -> np.ndarray:
    """6x6 stiffness of one socket at its mouth, in the socket frame (x out along the rod).

    In bending the joint body behind the socket bottom (hub, neighbouring sleeves) and the sleeve
    wall are taken as rigid; axially the sleeve and the seat carry the load back to the centre.
    The rod bears on the sleeve over the socket depth through a Winkler foundation, the
    interface layer: k_f = E d / h_i (N/mm per mm: the rod's projected width d pressing a layer
    h_i thick). (A pad of h_i + wall was tried: it makes a thicker wall softer in bending, the
    wrong trend, because the real wall is not backed by anything rigid.) Lateral/rotation: Hetenyi's
    finite beam (the rod, EI of the rod) on that foundation; axial: interface shear over the
    bore wall and bearing on the socket bottom; torsion: interface shear. The knee's hinged leg
    adds the living-hinge web (a strip bending about the fold axis) in series.
    """
    L = sock.depth
    i_rod = math.pi * rod_d**4 / 64
    e, g = itf.e, itf.g
    k_found = e * rod_d / itf.h
    f = bef_end_flexibility(L, rod_e * i_rod, k_found)
    if hinge is not None:  # the leg hangs on the living-hinge web
        l_web, width, t = hinge
        f_web = cantilever_flexibility([(l_web, width * t**3 / 12)], e)
        lever = sock.seat + L  # the web's end flexibility seen at the mouth through the rigid sleeve
        tr = np.array([[1.0, lever], [0.0, 1.0]])
        f = f + tr @ f_web @ tr.T
    k_lat = np.linalg.inv(f)
    # axial: grip (interface + wall shear over the bore, bearing on the bottom) in series with the
    # sleeve carrying it back to the bottom (a tube over half the depth on average) and the solid
    # seat between the socket bottom and the joint centre
    bore, od = sock.bore, sock.bore + 2 * wall
    k_grip = g * math.pi * rod_d * L / (itf.h + wall) + e * math.pi * rod_d**2 / 4 / (itf.h + wall)
    a_tube, a_disc = math.pi * (od**2 - bore**2) / 4, math.pi * od**2 / 4
    k_ax = 1.0 / (1.0 / k_grip + (L / 2) / (e * a_tube) + max(sock.seat, 1e-6) / (e * a_disc))
    k_tor = g * math.pi * rod_d * L * (rod_d / 2) ** 2 / (itf.h + wall)
    if hinge is not None:
        l_web, width, t = hinge
        j_web = width * t**3 / 3 * (1 - 0.63 * t / width)
        k_ax = 1.0 / (1.0 / k_ax + l_web / (e * width * t))
        k_tor = 1.0 / (1.0 / k_tor + l_web / (g * j_web))
    K = np.zeros((6, 6))
    K[0, 0] = k_ax
    K[3, 3] = k_tor
    # x-y plane: v (1), rz (5); a lateral force +y at the mouth tilts it with +rz
    K[np.ix_([1, 5], [1, 5])] = k_lat
    # x-z plane: w (2), ry (4); ry = -dw/dx
    K[np.ix_([2, 4], [2, 4])] = k_lat * np.array([[1, -1], [-1, 1]])
    return K


def _socket_frame(direction) -> np.ndarray:
    """Rows: socket x (out along the rod), y, z in the part frame."""
    x = np.asarray(direction, float)
    x = x / np.linalg.norm(x)
    ref = np.array([0.0, 0.0, 1.0]) if abs(x[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    y = np.cross(ref, x)
    y /= np.linalg.norm(y)
    return np.vstack([x, y, np.cross(x, y)])


def analytic_joint(spec, part, factor: float | None = None) -> JointStiffness:
    """Super-element from closed forms: per socket a 6x6 spring mouth <-> joint centre, the
    centre kept as the "body" (condensed out when the joint has no support)."""
    if not joint_kind(part).closed_form_stiffness:
        # the pegged link: its sleeves are the pegs' columns, held by the core's bores
        raise ValueError(f"joint {part.name}: the analytic joint model has no closed form for the pegged core link "
                         "(core.link: pegs); use model.stiffness_model: fe or surrogate")
    t0 = time.perf_counter()
    itf = interface(spec, factor)
    rod = spec.material(spec.rods.material)
    hi = hinged_socket(part)
    hinge = hinge_geometry(part) if hi is not None else None
    n = len(part.sockets)
    N = 6 * (n + 1)
    K = np.zeros((N, N))
    refs = []
    for i, s in enumerate(part.sockets):
        kl = _socket_local_k(spec, s, itf, hinge if i == hi else None, rod.e_mpa, spec.rods.diameter, part.wall)
        R = _block_rot(_socket_frame(s.direction))
        kg = R.T @ kl @ R  # part frame, at the mouth
        mouth = np.asarray(s.port, float) + np.asarray(s.direction, float) * (s.seat + s.depth)
        refs.append(tuple(float(v) for v in mouth))
        # spring between the rod body (at the mouth) and the centre body: the centre's motion
        # seen at the mouth is T u_c.
        from ..framefe import rigid_transfer

        T = rigid_transfer(np.zeros(3), mouth)
        B = np.hstack([np.eye(6), -T])  # relative motion at the mouth
        ks = B.T @ kg @ B
        idx = np.r_[6 * i:6 * i + 6, 6 * n:6 * n + 6]
        K[np.ix_(idx, idx)] += ks
    labels = tuple(s.rod for s in part.sockets)
    if _has_body(part):
        labels += ("body",)
        refs.append((0.0, 0.0, 0.0))
    else:  # condense the centre out
        a, b = slice(0, 6 * n), slice(6 * n, N)
        K = K[a, a] - K[a, b] @ np.linalg.solve(K[b, b], K[b, a])
    K = 0.5 * (K + K.T)
    return JointStiffness(part.name, "analytic", labels, tuple(refs), tuple(map(tuple, K.tolist())), N,
                          time.perf_counter() - t0)
