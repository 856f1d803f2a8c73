"""How much the core link's linear tab tie overstates the hinge the bare arms hang on.

The joint FE (`fe.py`) ties the tab's whole underside on the plate to the core, both ways. Under
thrust the arm block turns nose-up: near the plate corner the tab pulls away from the plate, and
only the bolt holds it there, so a real plate carries less. Here the same mesh is solved with
the underside as a one-sided contact (an active set: facets that lift are released, released
facets that would sink into the plate come back, until neither happens or a few facets flip to
and fro, when the softest state of the cycle counts), the facets under the screw head kept tied
(the head clamps them), for the couple thrust puts on an arm pair. The arm pair's rotational
stiffness from both solves says how far the linear model is from the contact.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

MAX_ITERATIONS = 12


@dataclass(frozen=True)
class TabContact:
    hinge_tied: float  # N mm/rad, the whole underside tied (what the joint FE gives)
    hinge_contact: float  # N mm/rad, the underside in one-sided contact under the thrust couple
    underside_mm2: float  # the tab's underside on the plate
    contact_mm2: float  # of which in contact at the end
    iterations: int

    @property
    def overstatement(self) -> float:
        """hinge_tied / hinge_contact - 1."""
        return self.hinge_tied / self.hinge_contact - 1.0


def tab_contact(spec, part, factor: float | None = None) -> TabContact:
    """The core link `part`'s arm-pair hinge with its tab tied and in contact (module docstring)."""
    import scipy.sparse.linalg as sla
    from skfem import MeshTet

    from ...materials import SCREWS
    from .. import framefe as ff
    from . import solid_fe
    from .fe import joint_problem

    pb = joint_problem(spec, part, factor)
    R, o = pb.rotation, pb.offset
    ties = list(pb.ties)
    body = pb.labels.index("body")
    arms = [i for i, lab in enumerate(pb.labels) if "arm" in lab]
    others = [i for i in range(len(ties)) if i not in arms and i != body]

    mesh = MeshTet(pb.points, pb.tets)
    bf, cen, nrm, area = solid_fe.boundary_facets(mesh)  # print coordinates

    axis = R @ np.array([0.0, 0.0, 1.0])
    z0 = float(part.param("plate_top_z"))
    select = ties[body].select
    underside = np.asarray(select(cen, nrm), bool) & (np.abs(axis @ (cen - o[:, None]) - z0) < 1e-3)
    bolt = R @ np.asarray(part.param("bolt_hole"), float) + o
    rel = cen - bolt[:, None]
    radial = np.linalg.norm(rel - np.outer(axis, axis @ rel), axis=0)
    clamped = underside & (radial < SCREWS[str(part.param("screw"))].head_d / 2)

    refs = np.array([t.ref for t in ties])
    centre = refs[arms].mean(axis=0)
    T = np.vstack([ff.rigid_transfer(centre, refs[i]) for i in arms])
    lateral = refs[arms[1]] - refs[arms[0]]
    lateral /= np.linalg.norm(lateral)
    # the thrust sense: the couple that lifts the arms' outer ends (towards their knees)
    out = R @ np.asarray(part.sockets[arms[0]].direction, float)  # out of the socket, along the rod
    sign = 1.0 if np.cross(out, axis) @ lateral > 0 else -1.0

    released = np.zeros(bf.size, bool)
    hinges: list[float] = []
    seen = [released.tobytes()]
    for it in range(1, MAX_ITERATIONS + 1):
        keys = {tuple(k) for k in np.round(cen[:, released].T, 6)}

        def sel(c, n, keys=keys):
            mask = np.asarray(select(c, n), bool)
            if keys:
                mask &= ~np.array([tuple(k) in keys for k in np.round(c.T, 6)])
            return mask

        ties[body] = dataclasses.replace(ties[body], select=sel)
        sysm = solid_fe.assemble(pb.points, pb.tets, pb.e, pb.nu, ties)  # condensed, then the motion recovered from it
        c = solid_fe.condense_system(sysm, ties)
        a = [6 * i + k for i in arms for k in range(6)]
        b = [6 * i + k for i in others for k in range(6)]
        K = c.K
        # arm pair rigid and free, the other rods free, the body held: a unit couple
        Kpp = T.T @ K[np.ix_(a, a)] @ T
        Kpo = T.T @ K[np.ix_(a, b)]
        Koo = K[np.ix_(b, b)]
        M = np.block([[Kpp, Kpo], [Kpo.T, Koo]])
        f = np.zeros(M.shape[0])
        f[3:6] = sign * lateral
        q = np.linalg.solve(M, f)
        hinges.append(1.0 / abs(q[3:6] @ lateral))
        # the mesh's motion for those rigid-body motions, and each underside facet's normal motion
        ur = np.zeros(K.shape[0])
        pair = T @ q[:6]
        for j, i in enumerate(arms):
            ur[6 * i:6 * i + 6] = pair[6 * j:6 * j + 6]
        for j, i in enumerate(others):
            ur[6 * i:6 * i + 6] = q[6 + 6 * j:12 + 6 * j]
        u = sla.spsolve(sysm.Kuu().tocsc(), -(sysm.Kur @ ur))
        U = u.reshape(-1, 3)[:pb.points.shape[1]].T
        into = np.einsum("ij,ij->j", U[:, mesh.facets[:, bf]].mean(axis=1), nrm)  # > 0: into the plate
        lifting = underside & ~released & ~clamped & (into < 0)
        back = released & (into > 0)
        if not lifting.any() and not back.any():
            break
        released = (released | lifting) & ~back
        state = released.tobytes()
        if state in seen:  # a few facets flip to and fro: the cycle's softest state
            cycle = hinges[seen.index(state):]
            return TabContact(float(hinges[0]), float(min(cycle)), float(area[underside].sum()),
                              float(area[underside & ~released].sum()), it)
        seen.append(state)
    return TabContact(float(hinges[0]), float(hinges[-1]), float(area[underside].sum()),
                      float(area[underside & ~released].sum()), it)
