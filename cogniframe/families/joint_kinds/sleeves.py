"""The closed forms' shared pieces: a joint's sockets as arrays, its sleeves' D section, the
side-printed joints' layout (the knee and the tab core link lie on their side: every socket level,
the arm pair stacked), and the estimate's ending (the bores' walls, the envelope sorted). Pure
numpy: the kinds' closed forms add their own pieces in between, in the order they always did (the
estimates are compared to the last bit)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...parts.joint_plan import PARALLEL_TOL
from ...parts.record import Estimate


@dataclass(frozen=True, eq=False)
class Arrays:
    """A joint's sockets as arrays, and its sleeves' radius and bore section."""

    r: float  # sleeve radius: bore / 2 + wall
    hole: float  # a bore's section, mm^2
    dirs: np.ndarray
    ports: np.ndarray
    L: np.ndarray  # seat + depth of each socket

    def d_area(self, h: float) -> float:
        """A D-section sleeve's section, its axis `h` above the bed (flat on the bed, round top)."""
        r = self.r
        return 2 * r * h + math.pi * r**2 / 2


def arrays(spec, sockets) -> Arrays:
    return Arrays(spec.bore / 2 + spec.joints.wall, math.pi / 4 * spec.bore**2,
                  np.array([s.direction for s in sockets], float), np.array([s.port for s in sockets], float),
                  np.array([s.seat + s.depth for s in sockets], float))


def less_bores(a: Arrays, sockets) -> float:
    """The running volume's start: minus the bores."""
    return -sum(a.hole * s.depth for s in sockets)


def closed(spec, sockets, vol: float, a_h: float, a_v: float, ext) -> Estimate:
    """The estimate: the bores' walls added to the vertical area, the envelope largest first."""
    a_v += sum(math.pi * spec.bore * s.depth for s in sockets)
    env = tuple(sorted(float(x) for x in ext))
    return Estimate(vol, a_h, a_v, (env[2], env[1], env[0]))


@dataclass(frozen=True, eq=False)
class Side:
    """A side-printed joint's layout: the print plane's normal `w`, the sockets' heights along it
    (`zc`) and their axis heights in print (`z`), the parallel arm sockets `par`, the others
    `rest`, each socket's sleeve length `sleeve_l` (depth + wall)."""

    w: np.ndarray
    zc: np.ndarray
    z: np.ndarray
    par: list[int]
    rest: list[int]
    sleeve_l: list[float]

    def top(self, r: float) -> float:
        """The highest sleeve top other than the arms' (the arms' with arm sockets only)."""
        return float(self.z[self.rest].max() + r) if self.rest else float(self.z[self.par].max() + r)


def side(spec, sockets, a: Arrays) -> Side:
    _, sv, vt = np.linalg.svd(a.dirs)
    w = vt[-1]
    if sv[1] < 1e-6 * sv[0]:  # parallel arm sockets only (no strut): the SVD's normal is arbitrary;
        off = a.ports[1] - a.ports[0]  # use the one across the pair, as the solid prints it
        w = np.cross(a.dirs[0], np.cross(a.dirs[0], off))
        w /= np.linalg.norm(w)
    zc = a.ports @ w
    z = zc - zc.min() + a.r  # axis heights in print orientation
    n = len(sockets)
    par = [i for i in range(n) if sum(a.dirs[i] @ a.dirs[k] > 1 - PARALLEL_TOL for k in range(n)) > 1]
    rest = [i for i in range(n) if i not in par]
    return Side(w, zc, z, par, rest, [sockets[i].depth + spec.joints.wall for i in range(n)])


def side_extents(a: Arrays, s: Side) -> np.ndarray:
    """A side-printed joint's envelope (unsorted)."""
    return np.array([np.ptp(np.vstack([a.ports, a.ports + a.dirs * a.L[:, None]]) @ np.eye(3), axis=0).max() + 2 * a.r,
                     2 * a.r + float(a.L.max()), float(s.z.max() + a.r)])
