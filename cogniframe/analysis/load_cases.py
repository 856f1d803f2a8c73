"""The frame's load cases, for `check`: the payload case's k comes from the frame model
(stiffness.py); here the wall, full thrust, free vibration modes, Euler buckling of every rod and
the TPU strain, all at the design drop (docs/stiffness-model.md).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from .. import numfmt
from . import framefe as ff
from .constants import G, RHO_AIR
from .framefe import euler_loads, lowest_eigenvalues
from .stiffness import (DEFAULT_LOAD_N, PLAY_REFERENCE_N, Layout, Model, SecantSolution, _across, _dof,
                        _drop_unconnected, _play, _solve_payload, build_model, joint_models,
                        joint_parts, masses_g, model_layout, socket_loads)

TIE = 1e-6  # relative: results this close are equal (symmetric members; the solver's round-off)


# Propeller thrust coefficient C_T = T / (rho n^2 D^4) of small two-blade props (3-4 in) at
# hover Reynolds numbers: about 0.10 (UIUC propeller database, small-prop static tests 0.08-0.12).
PROP_CT = 0.10


MODE_WARN_BAND = 0.15  # a mode within 15 % of the hover rotor frequency is flagged


N_MODES = 8


def damped_peak_factor(zeta: float) -> float:
    """x_max * w0 / v0 for a damped oscillator started at x = 0 with speed v0 (no other force)."""
    if zeta <= 0:
        return 1.0
    if zeta < 1:
        s = math.sqrt(1 - zeta * zeta)
        return math.exp(-zeta / s * math.atan2(s, zeta))
    if zeta == 1:
        return math.exp(-1.0)
    s = math.sqrt(zeta * zeta - 1)
    return math.exp(-zeta / s * math.atanh(s / zeta))


def hover_rotor_hz(spec, total_mass_g: float) -> float:
    """Rotor speed at hover, rev/s: thrust per rotor T = m g / 4 = C_T rho n^2 D^4."""
    t = total_mass_g / 1000.0 * G / 4
    d = spec.motors.prop_diameter / 1000.0
    return math.sqrt(t / (PROP_CT * RHO_AIR * d**4))


@dataclass(frozen=True)
class LoadCases:
    """Everything `check --json` reports under `stiffness` (units in the names)."""

    k_n_per_m: float
    joint_model: str
    tpu_factor: float
    k_lateral_n_per_m: float
    wall: dict
    thrust: dict
    modes_hz: tuple[float, ...]
    hover_rotor_hz: float
    mode_near_rotor: dict | None
    buckling: dict
    strain: dict
    joints: dict
    seconds: float
    survival_per_n: dict | None = None

    def to_dict(self) -> dict:
        return {
            "k_n_per_m": self.k_n_per_m, "joint_model": self.joint_model, "tpu_modulus_factor": self.tpu_factor,
            "k_lateral_n_per_m": self.k_lateral_n_per_m, "wall": self.wall, "thrust": self.thrust,
            "modes_hz": list(self.modes_hz), "hover_rotor_hz": self.hover_rotor_hz, "mode_near_rotor": self.mode_near_rotor,
            "min_buckling_margin": self.buckling["min_margin"], "critical_rod": self.buckling["critical_rod"],
            "buckling": self.buckling["rods"],
            "strain": self.strain, "joints": self.joints, "survival_per_n": self.survival_per_n,
        }


def load_cases(spec, frame, parts, total_mass_g: float, *, joint_model: str = "fe", damping_ratio: float = 0.558,
               design_force_n: float | None = None, joints: dict | None = None, play: dict | None = None,
               solved: SecantSolution | None = None, modes: bool = True, layout: Layout | None = None) -> LoadCases:
    """All load cases of the design (see the module docstring). ``design_force_n``: the spring
    force at the design drop's maximum compression (k x_max), for buckling and strain. ``play``:
    the play springs at PLAY_REFERENCE_N if already known (`secant_k_and_play`; {} = no play),
    else iterated here; ``solved``: the secant's solution with those springs (`secant_solution`),
    whose payload case is this one's. ``modes=False`` lists no modes (``modes_hz`` empty) and
    decides ``mode_near_rotor`` by counting the eigenvalues below the band instead of solving for
    them (`_no_mode_near_rotor`); when the count cannot rule a mode out, the modes are solved as
    by default, so ``mode_near_rotor`` is the default's either way. ``layout``: the frame's
    `stiffness.model_layout` with ``joints`` when the caller has it (every model here shares it).

    The payload, wall and full-thrust cases share one model and one assembled K (they differ in
    supports and loads only); the arms-only thrust case and the modes (rods in 4 elements, with
    masses) build their own."""
    from .joints import TPU_ELONGATION_AT_BREAK, hinge_geometry, hinged_socket, interface

    t0 = time.perf_counter()
    joints = joints if joints is not None else joint_models(spec, parts, joint_model)
    from .joints import TPU_PRINTED_MODULUS_FACTOR

    masses = masses_g(spec, frame, parts, total_mass_g)
    if layout is None:
        layout = model_layout(frame, parts, joints)

    # 1. payload vertical
    f_design = design_force_n if design_force_n is not None else 95.0
    if solved is not None:
        play, mdl, K0, u = solved.play or None, solved.model, solved.K, solved.u
    else:
        if play is None:
            play = _play(spec, frame, parts, joints, PLAY_REFERENCE_N, layout=layout)[0]
        play = play or None
        # built afresh with the final springs, as `secant_solution` builds it: the same bits of k
        mdl = build_model(spec, frame, parts, joints, play=play, layout=layout)
        K0 = mdl.fe.stiffness(sparse=True)
        mdl, _, u = _solve_payload(spec, frame, parts, joints, play=play, mdl=mdl, K0=K0)
    fe = mdl.fe
    d_pay = -u[_dof(fe, mdl.payload, 2)]
    k = 1000.0 * DEFAULT_LOAD_N / d_pay

    # 2. wall: each side face against a wall (joints on that face held, sticking contact); the worst
    wall = _wall_case(spec, frame, mdl, K0, masses, damping_ratio)

    # 3. thrust
    thrust = _thrust_case(spec, frame, parts, joints, masses, play, full=(mdl, K0), layout=layout)

    # 4. modes (free flight)
    n_rot = hover_rotor_hz(spec, total_mass_g)
    if modes or not _no_mode_near_rotor(spec, frame, parts, joints, masses, n_rot, play=play, layout=layout):
        hz = _modes(spec, frame, parts, joints, masses, play=play, layout=layout)
    else:  # modes=False and none of them near the rotor: not listed
        hz = []
    near = None
    for i, fhz in enumerate(hz):
        if abs(fhz - n_rot) <= MODE_WARN_BAND * n_rot:
            near = {"mode": i + 1, "hz": fhz, "rotor_hz": n_rot}
            break

    # 5. buckling at the design drop
    scale = f_design / DEFAULT_LOAD_N
    axial = fe.axial_forces(u)
    by_rod: dict[str, list[float]] = {}
    for b in fe.beams:
        if b.group:
            by_rod.setdefault(b.group, []).append(axial[b.name])
    names = list(frame.rods)
    ei = [spec.material(frame.rods[rn].material).e_mpa * math.pi * frame.rods[rn].diameter**4 / 64 for rn in names]
    lengths = [float(np.linalg.norm(layout.mouths[rn][1] - layout.mouths[rn][0])) for rn in names]
    known: dict = {}
    p_crs = euler_loads(lengths, ei, [_end_rot(mdl, frame, rn, "a", known) for rn in names],
                        [_end_rot(mdl, frame, rn, "b", known) for rn in names])
    rods_out = []
    for rn, length, p_cr in zip(names, lengths, p_crs):
        n_ax = min(by_rod[rn]) * scale  # most compressive segment
        p_cr = float(p_cr)
        margin = p_cr / -n_ax if n_ax < 0 else math.inf
        rods_out.append({"rod": rn, "length_mm": round(length, 2), "axial_n": round(n_ax, 3), "euler_n": round(p_cr, 2),
                         "margin": round(margin, 3) if math.isfinite(margin) else None})
    finite = [x for x in rods_out if x["margin"] is not None]
    # ordered by the margin as check.json states it (numfmt), then by name: mirror-image rods' margins
    # differ only in their noise, which must not decide which one is named critical or listed first
    worst = min(finite, key=lambda x: (numfmt.sig(x["margin"], numfmt.CHECK_FIGURES), x["rod"])) if finite else None
    buckling = {"design_force_n": round(f_design, 2), "min_margin": worst["margin"] if worst else None,
                "critical_rod": worst["rod"] if worst else None,
                "rods": sorted(rods_out, key=lambda x: (True, 0.0, "") if x["margin"] is None else
                               (False, numfmt.sig(x["margin"], numfmt.CHECK_FIGURES), x["rod"]))}

    # 6. TPU strain at the design drop
    knees = knee_hinges(parts, hinged_socket, hinge_geometry)
    strain = _strain(frame, mdl, u * scale, TPU_ELONGATION_AT_BREAK, interface(spec), knees)

    # 7. what each part carries per newton of payload force: the survival sweep scales it
    per_n = survival_influence(spec, frame, mdl, u / DEFAULT_LOAD_N, {x["rod"]: x["euler_n"] for x in rods_out},
                               interface(spec), knees)

    jinfo = {name: {"method": js.method, "dofs": js.n_dofs} for name, js in joints.items()}  # no timings: byte-stable output
    return LoadCases(k, joint_model, TPU_PRINTED_MODULUS_FACTOR, wall["k_lateral_n_per_m"], wall, thrust, tuple(hz), n_rot, near,
                     buckling, strain, jinfo, time.perf_counter() - t0, per_n)


def _end_rot(mdl: Model, frame, rn: str, tag: str, known: dict | None = None) -> float:
    """The rotational restraint of rod `rn`'s end `tag` in its joint (`socket_rotational_stiffness`).
    ``known``: {(joint part, socket label): restraint} of the ends taken so far, filled in here (every
    placement of a part restrains its sockets alike)."""
    r = frame.rods[rn]
    end = r.a if tag == "a" else r.b
    part = mdl.instance_part[end.node]
    node = mdl.rod_nodes[rn][0 if tag == "a" else 1]
    lab = next(l for l, n in mdl.joint_nodes[end.node].items() if n in (node, node + ":sock"))
    if known is None:
        return mdl.joints[part].socket_rotational_stiffness(lab)
    if (part, lab) not in known:
        known[part, lab] = mdl.joints[part].socket_rotational_stiffness(lab)
    return known[part, lab]


# The side faces a wall can meet: (axis, sign), +x first (the worst face is reported; on a tie, to
# round-off, the first).
WALL_FACES = ((0, 1), (0, -1), (1, 1), (1, -1))


FACE_NAMES = {(0, 1): "+x (right)", (0, -1): "-x (left)", (1, 1): "+y (front)", (1, -1): "-y (rear)"}


def _wall_case(spec, frame, mdl: Model, K, masses, zeta: float) -> dict:
    """Each side face against a wall, in turn; the face that allows the lowest wall speed.
    ``K``: the model's assembled stiffness (no supports)."""
    loose = _drop_unconnected(K, np.zeros(K.shape[0], dtype=bool))  # held on every face: K's diagonal read once
    return lowest_wall_speed([_wall_face(spec, frame, mdl, K, masses, zeta, axis, sign, loose) for axis, sign in WALL_FACES])


def lowest_wall_speed(cases: list[dict]) -> dict:
    """The face that allows the lowest wall speed; faces that tie (symmetric, to round-off): the first."""
    best = cases[0]
    for c in cases[1:]:
        if c["max_wall_speed_m_s"] < best["max_wall_speed_m_s"] * (1 - TIE):
            best = c
    return best


def _wall_face(spec, frame, mdl: Model, K, masses, zeta: float, axis: int, sign: int, loose=None) -> dict:
    """The side face at ``sign`` along ``axis`` against a wall (its corner joints held, sticking
    contact), the payload pushed towards it. ``loose``: the DOFs nothing connects
    (`_drop_unconnected` of K) when the caller has them."""
    fe = mdl.fe
    half = (spec.frame.width if axis == 0 else spec.frame.depth) / 2
    side = [inst for inst in mdl.joint_nodes if inst.startswith("corner_") and sign * frame.nodes[inst].pos[axis] > 0]
    fixed = np.zeros(K.shape[0], dtype=bool)
    idx = fe.index()
    for inst in side:
        for n in mdl.joint_nodes[inst].values():
            fixed[6 * idx[n]:6 * idx[n] + 3] = True
    fixed = _drop_unconnected(K, fixed) if loose is None else fixed | loose
    f = np.zeros(K.shape[0])
    f[_dof(fe, mdl.payload, axis)] = sign * DEFAULT_LOAD_N
    u = ff.solve(K, f, fixed)
    d_pay = sign * u[_dof(fe, mdl.payload, axis)]
    k_lat = 1000.0 * DEFAULT_LOAD_N / d_pay
    # what reaches the wall first, per mm of payload travel
    radius = spec.motors.prop_diameter / 2
    limits = []
    for m in frame.motors:
        if sign * m.axis[axis] <= 0:
            continue
        gap = half - (sign * m.axis[axis] + radius)
        ratio = sign * u[_dof(fe, m.name, axis)] / d_pay
        if ratio > 0:
            limits.append((gap / ratio, f"propeller of {m.name}", gap))
    core_out = max((b.hi[axis] if sign > 0 else -b.lo[axis]) for b in frame.core.boxes)
    gap_core = half - core_out
    limits.append((gap_core, "core", gap_core))
    # the first to reach the wall; symmetric motors tie (to round-off): the first by name, so
    # the answer does not hang on the solver's last digits
    t_min = min(x[0] for x in limits)
    travel, what, gap = min((x for x in limits if x[0] <= t_min + TIE * abs(t_min)), key=lambda x: x[1])
    w0 = math.sqrt(k_lat / (masses["total"] / 1000.0))
    v_max = travel / 1000.0 * w0 / damped_peak_factor(zeta)
    return {"k_lateral_n_per_m": k_lat, "max_wall_speed_m_s": v_max, "limited_by": what, "payload_travel_mm": travel,
            "gap_mm": gap, "damping_ratio": zeta, "face": FACE_NAMES[(axis, sign)]}


def _thrust_case(spec, frame, parts, joints, masses, play=None, full: tuple | None = None,
                 layout: Layout | None = None) -> dict:
    """Thrust on every motor, the battery holder clamped (the core held); the frame whole and the
    arms alone (cage, legs and struts removed: the paper's x-frame). Per newton, at hover (the
    all-up weight over four motors) and at full thrust. ``full``: (model, assembled K) of the
    whole frame with ``play`` if already built; ``layout``: the frame's `stiffness.model_layout`.

    The model is linear: the thrust turns with the motor (a follower force), so on arms that
    rotate as rigid bodies about a joint the linear rotation T L / k is also the large-rotation
    one; the tilts are reported as computed, with ``arms_only_small_rotation`` saying whether the
    full-thrust tilt is inside the model's small-rotation range (10 degrees)."""
    from .flight import max_thrust_g

    thrust_g = max_thrust_g(spec)
    hover_g = masses["total"] / 4
    per_n_full, per_n_hover = thrust_g * G / 1000.0, hover_g * G / 1000.0
    out = {"max_thrust_g": thrust_g, "hover_thrust_g": hover_g}
    for label, roles in (("full", None), ("arms_only", ("arm",))):
        if label == "full" and full is not None:
            mdl, K = full
        else:
            mdl = build_model(spec, frame, parts, joints, only_roles=roles, play=play, layout=layout)
            K = mdl.fe.stiffness(sparse=True)
        dz, tilt = _motors_under_thrust(mdl, K, 1.0)  # 1 N up on each motor: linear, scaled below
        out.update(thrust_figures(dz, tilt, per_n_hover, per_n_full, "" if label == "full" else "arms_only_"))
    out["arms_only_small_rotation"] = out["arms_only_motor_tilt_deg"] <= SMALL_ROTATION_DEG
    # the bracket's other end: the joints at printed TPU's datasheet modulus instead of the
    # calibrated fraction of it (the calibration lumps the rod-bore interface's idealisation, which
    # the bare arms' hinge -- bulk TPU bending in the print's layer plane -- does not have)
    from .joints import TPU_PRINTED_MODULUS_FACTOR

    stiff = {n: replace(js, K=tuple(map(tuple, (js.matrix / TPU_PRINTED_MODULUS_FACTOR).tolist()))) for n, js in joints.items()}
    mdl = build_model(spec, frame, parts, stiff, only_roles=("arm",), layout=layout)
    dz, tilt = _motors_under_thrust(mdl, mdl.fe.stiffness(sparse=True), per_n_full)
    out["arms_only_motor_deflection_mm_tpu_datasheet"] = dz
    out["arms_only_motor_tilt_deg_tpu_datasheet"] = math.degrees(tilt)
    hinge = arm_pair_hinge(joints, parts)
    if hinge is not None:
        out["arms_only_core_link_hinge_n_mm_per_rad"] = hinge
    out["exoskeleton_stiffening"] = out["arms_only_motor_deflection_mm_per_n"] / out["motor_deflection_mm_per_n"]
    return out


SMALL_ROTATION_DEG = 10.0  # sin x = x within 0.5 %: the linear frame's range


def thrust_figures(dz: float, tilt: float, per_n_hover: float, per_n_full: float, pre: str = "") -> dict:
    """The thrust case's figures from the motors' deflection (mm) and tilt (rad) under 1 N each
    (the frame is linear): per newton, at hover and at full thrust; `pre` names the frame variant."""
    return {f"{pre}motor_deflection_mm_per_n": dz, f"{pre}motor_tilt_deg_per_n": math.degrees(tilt),
            f"{pre}motor_deflection_hover_mm": dz * per_n_hover, f"{pre}motor_deflection_mm": dz * per_n_full,
            f"{pre}motor_tilt_hover_deg": math.degrees(tilt * per_n_hover), f"{pre}motor_tilt_deg": math.degrees(tilt * per_n_full)}


def _motors_under_thrust(mdl: Model, K, thrust_n: float) -> tuple[float, float]:
    """(mean vertical deflection mm, largest tilt rad) of the motors with ``thrust_n`` up on each
    and the core (the payload node) held."""
    idx = mdl.fe.index()
    fixed = np.zeros(K.shape[0], dtype=bool)
    i = 6 * idx[mdl.payload]
    fixed[i:i + 6] = True
    fixed = _drop_unconnected(K, fixed)
    f = np.zeros(K.shape[0])
    for m in mdl.motors:
        f[6 * idx[m] + 2] = thrust_n
    u = ff.solve(K, f, fixed)
    dz = float(np.mean([u[6 * idx[m] + 2] for m in mdl.motors]))
    tilt = float(np.max([math.hypot(u[6 * idx[m] + 3], u[6 * idx[m] + 4]) for m in mdl.motors]))
    return dz, tilt


def arm_pair_hinge(joints: dict, parts) -> float | None:
    """Rotational stiffness (N mm/rad) of an arm's two rods, tied rigidly together, in the core
    link about the axis through both rods (the axis thrust bends the arm about), with the link's
    support body held, the strut's socket free and the pair free to translate: what the bare arm
    hangs on. None without a core link. The core link's super-element, condensed."""
    from .joints.model import joint_kind

    part = next((p for p in joint_parts(parts) if joint_kind(p).node == "core_link" and p.name in joints), None)
    if part is None:
        return None
    js = joints[part.name]
    labs = js.labels
    arms = [i for i, lab in enumerate(labs) if "arm" in lab]
    if len(arms) != 2 or "body" not in labs:
        return None
    free = [i for i, lab in enumerate(labs) if i not in arms and lab != "body"]
    try:
        return pair_hinge(js.matrix, np.asarray(js.refs, float), arms, free)
    except np.linalg.LinAlgError:  # a joint whose arm pair is not held (a mechanism): no figure, not a crash
        return None


def pair_hinge(K: np.ndarray, refs: np.ndarray, arms: list[int], free: list[int]) -> float:
    """Rotational stiffness (N mm/rad) about the line through two tied bodies' reference points of
    a condensed super-element ``K`` (6 DOF per body, body i referenced at ``refs[i]``): the two
    ``arms`` tied rigidly together and free to translate, the ``free`` bodies free, the rest held.
    Raises LinAlgError when the pair is not held."""
    a = [6 * i + k for i in arms for k in range(6)]
    b = [6 * i + k for i in free for k in range(6)]
    c = refs[arms].mean(axis=0)
    T = np.vstack([ff.rigid_transfer(c, refs[i]) for i in arms])
    Kaa = K[np.ix_(a, a)]
    if b:
        Kaa = Kaa - K[np.ix_(a, b)] @ np.linalg.solve(K[np.ix_(b, b)], K[np.ix_(b, a)])
    C = np.linalg.inv(T.T @ Kaa @ T)
    lat = refs[arms[1]] - refs[arms[0]]
    lat = lat / np.linalg.norm(lat)
    return float(1.0 / (lat @ C[3:, 3:] @ lat))


def _modal_matrices(spec, frame, parts, joints, masses, rod_segments: int = 4, play=None, layout: Layout | None = None):
    """(K, M) of the free-flight modal problem: rods in ``rod_segments`` elements, with masses."""
    from scipy.sparse import diags

    mdl = build_model(spec, frame, parts, joints, rod_segments=rod_segments, masses=masses, play=play, layout=layout)
    fe = mdl.fe
    K = fe.stiffness(sparse=True)
    M = fe.mass(sparse=True)
    keep = np.abs(K.diagonal()) > 1e-12
    if not keep.all():
        K, M = K[keep][:, keep].tocsc(), M[keep][:, keep].tocsc()
    # massless DOFs (rigid-link ends) get a tiny inertia so M is positive definite
    M = (M + diags(np.where(M.diagonal() <= 0, 1e-12, 0.0))).tocsc()
    return K, M


def _modes(spec, frame, parts, joints, masses, n: int = N_MODES, rod_segments: int = 4, play=None,
           layout: Layout | None = None) -> list[float]:
    """The first n elastic natural frequencies in free flight (Hz, rounded to 0.01)."""
    K, M = _modal_matrices(spec, frame, parts, joints, masses, rod_segments, play, layout)
    w2 = lowest_eigenvalues(K, M, 6 + n)
    hz = [math.sqrt(max(x, 0.0)) / (2 * math.pi) for x in w2]
    elastic = hz[6:]  # free flight: six rigid-body modes first
    return [round(x, 2) for x in elastic]


def _no_mode_near_rotor(spec, frame, parts, joints, masses, rotor_hz: float, n: int = N_MODES, rod_segments: int = 4,
                        play=None, layout: Layout | None = None) -> bool:
    """True when none of the first n elastic modes (those `_modes` reports) can lie within
    MODE_WARN_BAND of ``rotor_hz``, from the count of eigenvalues of the same modal problem below
    the band's lower edge (the negative pivots of an LDL^T of K - s M, Sylvester's law of
    inertia): when the 6 rigid-body and n elastic modes all sit below it, `_modes` flags none.
    One factorization instead of the eigensolver. The edge is lowered by the modes' rounding
    (0.01 Hz) and a relative 1e-6 for the eigenvalues' round-off, so a mode whose rounded value
    could reach the band is never ruled out; False (solve the modes) when the count cannot tell."""
    from .framefe import negative_pivots

    edge_hz = ((1 - MODE_WARN_BAND) * rotor_hz - 0.01) * (1 - 1e-6)
    if edge_hz <= 0:
        return False
    K, M = _modal_matrices(spec, frame, parts, joints, masses, rod_segments, play, layout)
    below = negative_pivots(K - (2 * math.pi * edge_hz) ** 2 * M)
    return below >= 6 + n


def knee_hinges(parts, hinged_socket, hinge_geometry) -> dict[str, tuple[str, float, float]]:
    """Per hinged joint part (the knee, knee_mirrored): (its hinged leg's socket label, the living
    hinge's web length and thickness, mm), what `_joint_strains` reads for each of its instances."""
    out = {}
    for p in joint_parts(parts):
        leg = hinged_socket(p)
        if leg is not None:
            l_web, _, t_web = hinge_geometry(p)
            out[p.name] = (p.sockets[leg].rod, l_web, t_web)
    return out


def _joint_strains(frame, mdl: Model, u: np.ndarray, itf, knees: dict):
    """TPU strains for displacements u: ({knee instance: hinge strain}, [(joint instance, rod
    socket label, socket strain)]). The hinge: all the relative rotation of the hinged leg against
    the arms in the web (an upper bound); the sockets: the super-element's force on each rod body
    as bearing over the socket depth."""
    fe = mdl.fe
    idx = fe.index()
    hinge: dict[str, float] = {}
    for inst, labs in mdl.joint_nodes.items():
        knee = knees.get(mdl.instance_part[inst])  # knee (and knee_mirrored): `knee_hinges`
        if knee is None:
            continue
        leg_label, l_web, t_web = knee
        leg = labs[leg_label]
        arms = [n for l, n in labs.items() if "arm" in l]
        th_leg = u[6 * idx[leg] + 3:6 * idx[leg] + 6]
        th_arm = np.mean([u[6 * idx[n] + 3:6 * idx[n] + 6] for n in arms], axis=0)
        hinge[inst] = t_web / 2 * float(np.linalg.norm(th_leg - th_arm)) / l_web
    sl = socket_loads(fe, frame, u)
    v, mm = _across(sl.forces, sl.axes), _across(sl.moments, sl.axes)
    L = np.array([e.depth for e in sl.ends])
    # rigid rod on a linear (Winkler) bearing over L, loads at the mouth: peak line load
    q = v / L + 6 * (mm + v * L / 2) / L**2
    eps = q / np.array([frame.rods[rn].diameter for rn in sl.rods]) / itf.e
    return hinge, [(e.node, rn, float(x)) for e, rn, x in zip(sl.ends, sl.rods, eps)]


def _strain(frame, mdl: Model, u: np.ndarray, eps_break: float, itf, knees: dict) -> dict:
    """Peak TPU strain at the design drop: the knee hinge (all the relative rotation of the hinged
    leg against the arms in the web, an upper bound) and the sockets (interface bearing)."""
    hinge, socks = _joint_strains(frame, mdl, u, itf, knees)
    eps_h = max(hinge.values(), default=0.0)
    eps_s = max((x for _, _, x in socks), default=0.0)
    # symmetric sockets tie (to round-off): the first by name
    where = min((f"{n}/{rn}" for n, rn, x in socks if x >= eps_s * (1 - TIE) and x > 0), default=None)
    return {"hinge": round(eps_h, 4), "socket": round(eps_s, 4), "socket_at": where, "elongation_at_break": eps_break,
            "peak": round(max(eps_h, eps_s), 4), "ratio_to_break": round(max(eps_h, eps_s) / eps_break, 4)}


def survival_influence(spec, frame, mdl: Model, u: np.ndarray, euler_n: dict, itf, knees: dict) -> dict:
    """What each part carries per newton of payload force (u: the payload case per newton), for
    the survival sweep (analysis/survival.py), which scales it by the force of each drop:

    - ``rods``: per rod, its role, the peak bending + axial stress (max over its segments' ends of
      |N|/A + |M| (d/2)/I, MPa per N), its most compressive axial force (N per N; negative in
      compression) and its Euler load (N, from the buckling case);
    - ``joints``: per joint part, the peak TPU strain per N over its instances, sockets and (the
      knee) the living hinge, with where;
    - ``core_plate_mpa_per_n``: the core plate's bending stress where a core link loads its
      corner: the link's vertical force times its lever to the nearest stack screw, plus the
      link's moment across the plate, on the section across the corner there, w = 2 sqrt 2
      (plate/2 - pitch/2) wide (the corner as a cantilever off the stack). Where the plate rests
      on the spacer and the tab link's bolt clamps the two, they bend together without shear
      transfer (the lower bound of their sharing): sigma = 6 M t_p / (w (t_p^3 + t_s^3)); hung on
      standoffs (level arms), t_s = 0.
      The pegged plate (core.link: pegs: a link kind with no plate bolt) hangs on standoffs with no spacer against it, and its
      link's pull reaches the stack hole along a ribbed stem: the section where the rib starts,
      RIB_START past the hole's centre (clear of the standoff clamping the plate there), w_r wide
      and t_p + rib deep, its lever the link's less RIB_START: sigma = 6 M / (w_r (t_p + rib)^2)."""
    from ..materials import STACK_PATTERNS

    fe = mdl.fe
    idx = fe.index()
    ends = fe.end_forces(u)
    rods: dict[str, dict] = {}
    for b in fe.beams:
        if not b.group:
            continue
        d = frame.rods[b.group].diameter
        a, i_sec = math.pi * d * d / 4, math.pi * d**4 / 64
        f = ends[b.name]
        sig = max(abs(f[0]) / a + math.hypot(f[4], f[5]) * d / 2 / i_sec, abs(f[6]) / a + math.hypot(f[10], f[11]) * d / 2 / i_sec)
        r = rods.setdefault(b.group, {"role": frame.rods[b.group].role, "stress_mpa_per_n": 0.0, "axial_n_per_n": math.inf,
                                      "euler_n": euler_n.get(b.group)})
        r["stress_mpa_per_n"] = max(r["stress_mpa_per_n"], sig)
        r["axial_n_per_n"] = min(r["axial_n_per_n"], float(-f[0]))  # tension positive (end 1's force is -N)
    hinge, socks = _joint_strains(frame, mdl, u, itf, knees)
    joints: dict[str, dict] = {}
    for inst, x in sorted(hinge.items()):
        part = mdl.instance_part[inst]
        j = joints.setdefault(part, {"strain_per_n": 0.0, "at": None})
        if x > j["strain_per_n"] * (1 + TIE):
            j["strain_per_n"], j["at"] = x, f"{inst} hinge"
    for inst, rn, x in sorted(socks):
        part = mdl.instance_part.get(inst)
        if part is None:
            continue
        j = joints.setdefault(part, {"strain_per_n": 0.0, "at": None})
        if x > j["strain_per_n"] * (1 + TIE):
            j["strain_per_n"], j["at"] = x, f"{inst}/{rn}"
    # the core links' pull on the core, at each link's support body
    c = spec.core
    s = STACK_PATTERNS[c.stack_pattern][0] / 2
    half = c.plate_size / 2
    w = 2 * math.sqrt(2) * max(half - s, 1.0)
    t_p = c.plate_thickness
    # the spacer bends with the plate only where the plate rests on it and the link's bolt clamps
    # the two (level arms hang the plate on standoffs above it)
    t_s = c.spacer_thickness if frame.core.hang == 0 else 0.0
    from ..families.joint_kinds.kinds import core_link

    stem = not core_link(spec).plate_bolts(spec)  # no link bolt on the plate: the pegs' tubes on its ribbed stems
    if stem:
        # the pegged plate's stem: no spacer against it (it hangs on standoffs), its section
        # where the rib starts, past the standoff clamping it (families/core_plate.py)
        from ..families.core_plate import PLATE_RAIL, RIB, RIB_START
    sig_core = 0.0
    for nodes, Ks in fe.springs:
        for j, n in enumerate(nodes):
            if n in mdl.links:
                dofs = (6 * np.array([idx[x] for x in nodes])[:, None] + np.arange(6)).ravel()
                f = Ks @ u[dofs]
                fz, mh = abs(f[6 * j + 2]), math.hypot(f[6 * j + 3], f[6 * j + 4])
                p = fe.nodes[n]
                lever = math.hypot(abs(p[0]) - s, abs(p[1]) - s)
                if stem:
                    sig_core = max(sig_core, 6 * (fz * (lever - RIB_START) + mh) / (PLATE_RAIL * (t_p + RIB) ** 2))
                else:
                    sig_core = max(sig_core, 6 * (fz * lever + mh) * t_p / (w * (t_p**3 + t_s**3)))
    return {"rods": rods, "joints": joints, "core_plate_mpa_per_n": sig_core}
