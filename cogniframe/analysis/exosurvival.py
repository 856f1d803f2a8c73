"""The survival sweep of an exoskeleton read from CAD (`cogniframe analyse`): `survival`'s flat
drops of increasing height on `exoframe`'s model, each part against its own material's strength
(`materials.STRENGTHS`, never fitted to a drop outcome).

Per newton of payload force (the payload case: the feet on the floor, the force on the core),
scaled by each drop's force as `survival.drop_loads` gives it:

- each rod's peak bending + axial stress, |N|/A + |M| (d/2)/I over its segments' ends, against
  its flexural strength, and its compression against its Euler load: the free span, socket mouth
  to mouth, each end held by its socket's rotational stiffness (the smaller across the rod, every
  other body of the joint held), as the check's buckling case. The rods are grouped as the check
  groups them by role: the arms (the rods through a motor mount's sleeve) and the others by their
  span to 1 mm (mirror images share a span), and each group's worst is reported;
- each joint's peak socket load: its super-element's force and moment on the rod across the
  rod's axis, borne over the socket's depth by the interface layer (a rigid rod on a linear
  bearing loaded at the mouth, the check's formula: peak line load q = V/L + 6 (M + V L/2)/L^2),
  as a strain q / (d E_itf) against an elastomer's elongation at break, or as a bearing pressure
  q / d against a rigid plastic's yield; the joints' strain is driven by the drop model's spring
  force (capped where the core reaches the floor), rods by its whole force (spring and damper);
- the core's strike on the floor once the clearance is used up, a plane-wave bound sqrt(E rho)
  v_s, against its yield (the core's material: the rigid parts' by their names).

Not checked, as the read frame does not say: the core's own bending (the core is rigid in this
model; its strength needs its design: `check` has it for a cogniframe design), a living hinge's
strain (which web of a read joint is a hinge is not known) and the payload's peak G.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .survival import SWEEP_CM, Survival, drop_loads, margin_series, rod_series, strike_impedance_mpa_per_m_s, summarise

NOTE = ("flat drops on the read frame; sockets strained by the drop model's spring force (capped where the core "
        "reaches the floor), rods loaded by its whole force (spring and damper), both quasi-static in the payload "
        "case's pattern; the core's strike as a plane-wave bound; not checked: the core's bending (read as rigid), "
        "living hinges, the payload's peak G; no fatigue, no tumbling, no edge landings")


@dataclass(frozen=True)
class DropModel:
    """The drop model's parameters `survival.drop_loads` reads."""

    mass_kg: float
    c_n_s_per_m: float
    k_n_per_m: float
    clearance_mm: float


def _rod_group(lay, rn: str, span: float) -> str:
    return "arm" if rn in lay.arms else f"{span:.0f} mm rod"


def influence(lay, mdl, units: dict, factor: float, u_per_n: np.ndarray) -> dict:
    """What each rod and socket carries per newton of payload force (``u_per_n``: the payload
    case's displacements per newton, `exoframe.payload_case`): ``rods`` as
    `load_cases.survival_influence`'s (role, stress_mpa_per_n, axial_n_per_n, euler_n) and
    ``sockets`` [(joint, rod end, transverse line load per N, N/mm per N, rod diameter)]."""
    from ..materials import MATERIALS
    from .framefe import euler_loads
    from .stiffness import _across

    fe, exo = mdl.fe, lay.exo
    rm = MATERIALS[lay.rod_material]
    # each rod end's rotational restraint: its socket's unit, the smaller stiffness across the rod
    k_rot: dict[str, float] = {}
    for u in units.values():
        for i, lab in enumerate(u.labels):
            if not lab.startswith(("floor:", "body:", "glue:")):
                k_rot[lab] = float(np.linalg.eigvalsh(factor * u.K[6 * i + 3:6 * i + 6, 6 * i + 3:6 * i + 6])[1])
    names = [rn for rn in lay.rods if f"{rn}:a" in k_rot and f"{rn}:b" in k_rot]
    spans = {rn: math.dist(exo.socket_at(rn, "a").mouth, exo.socket_at(rn, "b").mouth) for rn in names}
    ds = {rn: lay.rod_d(exo.rod(rn)) for rn in names}
    p_cr = euler_loads([spans[rn] for rn in names], [rm.e_mpa * math.pi * ds[rn] ** 4 / 64 for rn in names],
                       [k_rot[f"{rn}:a"] for rn in names], [k_rot[f"{rn}:b"] for rn in names])
    euler = {rn: float(p) for rn, p in zip(names, p_cr)}
    ends = fe.end_forces(u_per_n)
    rods: dict[str, dict] = {}
    for b in fe.beams:
        if b.group not in euler:
            continue
        d = ds[b.group]
        a, i_sec = math.pi * d * d / 4, math.pi * d**4 / 64
        f = ends[b.name]
        sig = max(abs(f[0]) / a + math.hypot(f[4], f[5]) * d / 2 / i_sec, abs(f[6]) / a + math.hypot(f[10], f[11]) * d / 2 / i_sec)
        r = rods.setdefault(b.group, {"role": _rod_group(lay, b.group, spans[b.group]), "stress_mpa_per_n": 0.0,
                                      "axial_n_per_n": math.inf, "euler_n": euler[b.group]})
        r["stress_mpa_per_n"] = max(r["stress_mpa_per_n"], sig)
        r["axial_n_per_n"] = min(r["axial_n_per_n"], float(-f[0]))  # tension positive (end 1's force is -N)
    idx = fe.index()
    sockets = []
    for n, nodes in sorted(mdl.joint_nodes.items()):
        u = units[n]
        dofs = (6 * np.array([idx[x] for x in nodes])[:, None] + np.arange(6)).ravel()
        load = factor * u.K @ u_per_n[dofs]
        for j, lab in enumerate(u.labels):
            if lab.startswith(("floor:", "body:", "glue:")) or nodes[j].endswith(":free"):
                continue
            rn, end = lab.rsplit(":", 1)
            s = exo.socket_at(rn, end)
            axis = np.asarray(s.direction, float)[None, :]
            v = float(_across(load[None, 6 * j:6 * j + 3], axis)[0])
            m = float(_across(load[None, 6 * j + 3:6 * j + 6], axis)[0])
            depth = s.depth
            q = v / depth + 6 * (m + v * depth / 2) / depth**2
            sockets.append((n, lab, q, lay.rod_d(exo.rod(rn))))
    return {"rods": rods, "sockets": sockets}


def evaluate(lay, mdl, units: dict, factor: float, u_per_n: np.ndarray, drop: DropModel,
             heights_cm=SWEEP_CM) -> Survival:
    """The survival sweep of a read frame at TPU factor `factor` (see the module)."""
    from ..materials import MATERIALS, strength

    per_n = influence(lay, mdl, units, factor, u_per_n)
    springs, forces, strikes = drop_loads(drop, heights_cm)
    series = []
    worst: dict[str, tuple[float, str, object]] = {}  # per joint: its largest load, where, its strength
    for n, lab, q, d in per_n["sockets"]:
        mat = units[n].material or "tpu_95a"
        st = strength(mat)
        if st is None:
            continue
        # a strain for an elastomer (the interface layer's E at this factor), a pressure otherwise
        x = q / d / (factor * MATERIALS[mat].e_mpa) if st.mode == "elongation" else q / d
        if x > worst.get(n, (0.0,))[0]:
            worst[n] = (x, lab, st)
    for n, (x, lab, st) in sorted(worst.items()):
        if st.mode == "elongation":
            series.append(margin_series(f"joint {n} ({lab})", "TPU strain", st.value, "strain", [x * f for f in springs]))
        else:
            series.append(margin_series(f"joint {n} ({lab})", "socket bearing", st.value, "MPa", [x * f for f in forces]))
    series.extend(rod_series(per_n["rods"], lambda name: strength(lay.rod_material), forces))
    # the weakest of the core's materials that the library knows strikes (all alike in a one-material core)
    core = sorted((strength(m).value, m) for m in {a.material for a in lay.exo.attached if a.name in lay.core} if strength(m))
    if core:
        limit, mat = core[0]
        imp = strike_impedance_mpa_per_m_s(MATERIALS[mat])
        series.append(margin_series(f"core ({mat})", "strike on the floor", limit, "MPa", [imp * v for v in strikes]))
    return summarise(series, heights_cm, NOTE)
