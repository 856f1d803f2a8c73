"""Physics of the frame: a 3D beam model whose joints come from their own geometry.

Pure (no CAD unless a joint's FE result is not cached): Spec + Frame + parts -> `framefe.Frame3D`
-> stiffness, load cases, modes, buckling. Units N, mm, t (tonnes) inside; results name their
units (k in N/m = 1000 N/mm).

The model (docs/stiffness-model.md):
- every rod is an Euler-Bernoulli beam of its free span, mouth to mouth (the part inside a
  socket belongs to the joint model); arm rods are split at the motor mounts, which tie the two
  rods of an arm to the motor node rigidly;
- every distinct printed joint is a super-element from `joint_stiffness` (solid FE of its CAD
  by default, closed forms with ``joint_model="analytic"``): a stiffness over the rigid bodies of
  the rods in its sockets (at their mouths) and, for the feet and core links, a support body at
  the joint centre. The prototype's matrix is rotated to each of the four corners;
- the core (core links' support bodies and the payload node at the core-plate centre) is rigid;
- feet: the support bodies of the bottom corners stand on a rigid, frictionless floor (vertical
  restraint, rotations free, one stiff tangential spring each against the in-plane rigid-body
  modes; ``feet="pinned"`` for full friction).

Load cases: `payload` (k, the drop model's spring), `wall` (a side face against a wall),
`thrust` (full thrust on every motor, battery holder clamped; arms alone for comparison), free
vibration modes, Euler buckling of every rod at the design drop, TPU strain at the design drop.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from . import framefe as ff
from .constants import G, RHO_AIR

PAPER_K_N_PER_M = 7040.0  # carbon build, static dynamometer test (static_stiffness_carbon.csv)
DEFAULT_LOAD_N = 10.0  # the model is linear

_RIGID_E_MPA = 1.0e6
_RIGID_G_MPA = 4.0e5
_RIGID_D_MM = 20.0
_FLOOR_SPRING_N_PER_MM = 1.0e6
# Propeller thrust coefficient C_T = T / (rho n^2 D^4) of small two-blade props (3-4 in) at
# hover Reynolds numbers: about 0.10 (UIUC propeller database, small-prop static tests 0.08-0.12).
PROP_CT = 0.10
MODE_WARN_BAND = 0.15  # a mode within 15 % of the hover rotor frequency is flagged
N_MODES = 8
# -- the model ---------------------------------------------------------------------------------

@dataclass
class Model:
    fe: ff.Frame3D
    payload: str
    feet: list[str] = field(default_factory=list)
    links: list[str] = field(default_factory=list)
    motors: list[str] = field(default_factory=list)
    rod_nodes: dict[str, tuple[str, str]] = field(default_factory=dict)  # rod -> (mouth a node, mouth b node)
    joint_nodes: dict[str, dict[str, str]] = field(default_factory=dict)  # joint instance -> label -> node
    joints: dict[str, object] = field(default_factory=dict)  # part name -> JointStiffness
    instance_part: dict[str, str] = field(default_factory=dict)
    instance_rot: dict[str, np.ndarray] = field(default_factory=dict)
    play_slots: dict[str, int] = field(default_factory=dict)  # rod end node -> its play spring's index in fe.springs
    socket_refs: dict[str, np.ndarray] = field(default_factory=dict)  # rod end node -> its socket body's reference point


def _rz(deg: float) -> np.ndarray:
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def joint_parts(parts) -> list:
    return [p for p in parts if p.family == "joint"]


def joint_models(spec, parts, method: str = "fe", factor: float | None = None) -> dict:
    """The super-element of every distinct joint (cached FE, or closed forms)."""
    from .joint_stiffness import joint_stiffness, solve_missing

    out = {}
    # new geometries first, all at once (in parallel); then every joint comes from the cache
    failed = solve_missing(spec, joint_parts(parts)) if method == "fe" else {}
    for p in joint_parts(parts):
        if p.name not in failed:
            try:
                out[p.name] = joint_stiffness(spec, p, method, factor)
                continue
            except RuntimeError:
                if method != "fe":
                    raise
        # a solid the mesher cannot handle (reported by gmsh/joint_fe as RuntimeError, or a bore
        # whose surface was not found): the closed forms for this joint rather than failing the
        # whole check; the method is reported per joint
        out[p.name] = joint_stiffness(spec, p, "analytic", factor)
    return out


def _rod_ends(frame) -> dict[str, tuple[list[str], np.ndarray, np.ndarray]]:
    """Per joint node: its rods, their ports (k, 3) and socket directions (k, 3)."""
    out = {}
    for name, node in frame.nodes.items():
        ports, dirs = [], []
        for rn in node.rods:
            r = frame.rods[rn]
            ports.append(r.end_at(name).port)
            dirs.append(r.socket_direction(name))
        out[name] = (list(node.rods), np.asarray(ports, float).reshape(-1, 3), np.asarray(dirs, float).reshape(-1, 3))
    return out


def _match_rod(ends, node_name: str, port_w: np.ndarray, dir_w: np.ndarray) -> str:
    """The rod of `node_name` whose socket port and direction match (ends: `_rod_ends`)."""
    rods, ports, dirs = ends[node_name]
    dp, dd = ports - port_w, dirs - dir_w
    e = np.sqrt(np.einsum("ij,ij->i", dp, dp)) + np.sqrt(np.einsum("ij,ij->i", dd, dd))
    i = int(np.argmin(e)) if len(rods) else -1
    if i < 0 or e[i] > 1e-3:
        err = e[i] if i >= 0 else math.inf
        raise RuntimeError(f"stiffness model: no rod of {node_name} matches a socket of its part (error {err:.3g})")
    return rods[i]


def mouth(rod, tag: str) -> np.ndarray:
    end = rod.a if tag == "a" else rod.b
    sgn = 1.0 if tag == "a" else -1.0
    return np.asarray(end.port, float) + sgn * rod.axis * (end.seat + end.depth)


def masses_g(spec, frame, parts, total_mass_g: float | None) -> dict:
    """Mass split used by the dynamic cases, g: rods (distributed), joints, motors (+props, mounts),
    and the payload (everything else: core, battery, electronics) at the core-plate centre."""
    rod_mat = spec.material(spec.rods.material)
    a = math.pi * spec.rods.diameter**2 / 4
    rods = sum(r.length * a * rod_mat.density_g_mm3 for r in frame.rods.values())
    tpu = spec.material(spec.joints.material)
    joints = {p.name: p.estimate.volume * tpu.density_g_mm3 for p in joint_parts(parts)}
    mount = next((p for p in parts if p.family == "motor_mount"), None)
    motor_each = spec.motor.mass_g + spec.motors.prop_mass + (mount.estimate.volume * tpu.density_g_mm3 if mount else 0.0)
    fixed = rods + sum(p.qty * joints[p.name] for p in joint_parts(parts)) + 4 * motor_each
    total = total_mass_g if total_mass_g is not None else fixed + 150.0
    return {"rods": rods, "joints": joints, "motor_each": motor_each, "payload": max(total - fixed, 1.0), "total": total}


def build_model(spec, frame, parts, joints: dict, *, feet: str = "sliding", rod_segments: int = 1,
                masses: dict | None = None, only_roles: tuple[str, ...] | None = None,
                play: dict | None = None) -> Model:
    """The frame model. ``only_roles`` keeps only rods of those roles (and joints they touch)."""
    if feet not in ("sliding", "pinned"):
        raise ValueError(f"feet must be 'sliding' or 'pinned', got {feet!r}")
    if rod_segments < 1:
        raise ValueError(f"rod_segments must be >= 1, got {rod_segments}")
    fe = ff.Frame3D()
    mdl = Model(fe, "payload", joints=joints)
    rods = {n: r for n, r in frame.rods.items() if only_roles is None or r.role in only_roles}
    rod_mat = spec.material(spec.rods.material)
    rho_rod = rod_mat.density_g_mm3 * 1e-6  # t/mm^3

    mouths = {rn: (mouth(r, "a"), mouth(r, "b")) for rn, r in frame.rods.items()}

    # Motor stations on the arm rods (where the mount clips both rods).
    stations: dict[str, float] = {}
    for m in frame.motors:
        for rn in m.arm:
            pa, pb = mouths[rn]
            d = pb - pa
            t = float(np.dot(np.asarray(m.axis) - pa, d) / np.dot(d, d))
            stations[rn] = min(max(t, 0.05), 0.95)

    for rn, r in rods.items():
        pa, pb = mouths[rn]
        na, nb = fe.add_node(f"{rn}:a", pa), fe.add_node(f"{rn}:b", pb)
        mdl.rod_nodes[rn] = (na, nb)
        ts = sorted({i / rod_segments for i in range(1, rod_segments)} | ({stations[rn]} if rn in stations else set()))
        chain = [na]
        for i, t in enumerate(ts):
            name = f"{rn}:motor" if rn in stations and abs(t - stations[rn]) < 1e-12 else f"{rn}:{i + 1}"
            chain.append(fe.add_node(name, pa + (pb - pa) * t))
        chain.append(nb)
        for i in range(len(chain) - 1):
            fe.add_beam(f"{rn}" if len(chain) == 2 else f"{rn}#{i}", chain[i], chain[i + 1], rod_mat.e_mpa, rod_mat.g_mpa,
                        r.diameter, rho=rho_rod, group=rn)

    # Joints: rotate each prototype super-element to its corner.
    ends = _rod_ends(frame)
    for part in joint_parts(parts):
        js = joints[part.name]
        K = js.matrix
        for pl in part.placements:
            R = _rz(pl.rotation_deg)
            origin = np.asarray(pl.origin, float)
            node_names = []
            keep = []
            for li, lab in enumerate(js.labels):
                ref_w = R @ np.asarray(js.refs[li]) + origin
                if lab == "body":
                    name = pl.instance
                    if name not in fe.nodes:
                        fe.add_node(name, ref_w)
                    node_names.append(name)
                    keep.append(li)
                    continue
                sock = next(s for s in part.sockets if s.rod == lab)
                rn = _match_rod(ends, pl.instance, R @ np.asarray(sock.port) + origin, R @ np.asarray(sock.direction))
                if rn not in rods:
                    # rod removed (arms-only case): its socket body stays, free, on the joint
                    name = f"{pl.instance}:{lab}:free"
                    fe.add_node(name, ref_w)
                else:
                    r = frame.rods[rn]
                    tag = "a" if r.a.node == pl.instance else "b"
                    name = mdl.rod_nodes[rn][0 if tag == "a" else 1]
                    off = math.dist(fe.nodes[name], ref_w)
                    if off > 1e-3:
                        raise RuntimeError(f"stiffness model: socket mouth of {rn} at {pl.instance} is off by {off:.3g} mm")
                    mdl.socket_refs[name] = ref_w
                    if play and name in play:  # the fit's play: a secant spring rod end <-> socket body
                        body = fe.add_node(f"{name}:sock", ref_w)
                        mdl.play_slots[name] = len(fe.springs)
                        fe.add_spring((name, body), _play_block(play[name]))
                        name = body
                node_names.append(name)
                keep.append(li)
            if only_roles is not None and not any(":free" not in n for n in node_names if n != pl.instance):
                continue  # no rod of this joint is kept
            nb = len(js.labels)  # Q^T K Q with Q = diag(R^T, ...): each 3x3 block R K_ab R^T
            Kw = np.einsum("ij,ajbk,lk->aibl", R, K.reshape(2 * nb, 3, 2 * nb, 3), R).reshape(6 * nb, 6 * nb)
            fe.add_spring(tuple(node_names), Kw)
            mdl.joint_nodes[pl.instance] = dict(zip(js.labels, node_names))
            mdl.instance_part[pl.instance] = part.name
            mdl.instance_rot[pl.instance] = R

    # Motors: a node at the motor axis, rigidly tied to the arm rods' stations (the clip mount).
    for m in frame.motors:
        if not all(rn in rods for rn in m.arm):
            continue
        name = fe.add_node(m.name, np.asarray(m.axis, float))
        mdl.motors.append(name)
        for rn in m.arm:
            fe.add_beam(f"mount:{m.name}:{rn}", name, f"{rn}:motor", _RIGID_E_MPA, _RIGID_G_MPA, _RIGID_D_MM)

    # Core: rigid star from the payload node to the core links' support bodies.
    fe.add_node(mdl.payload, np.asarray(frame.core.plate.centre, float))
    mdl.links = sorted(n for n in fe.nodes if n.startswith("core_link_") and ":" not in n)
    for name in mdl.links:
        fe.add_beam(f"core:{name}", mdl.payload, name, _RIGID_E_MPA, _RIGID_G_MPA, _RIGID_D_MM)
    mdl.feet = sorted(n for n in fe.nodes if n.startswith("corner_bottom_") and ":" not in n)

    if masses is not None:
        _add_masses(spec, frame, mdl, masses)
    return mdl


def _play_block(p: np.ndarray) -> np.ndarray:
    """The 12x12 spring matrix of a 6x6 play stiffness between a rod end and its socket body."""
    b = np.empty((12, 12))
    b[:6, :6] = b[6:, 6:] = p
    b[:6, 6:] = b[6:, :6] = -p
    return b


def add_play(mdl: Model, play: dict) -> None:
    """Turn a model built without play into the one `build_model(..., play=play)` builds, in place:
    a socket body node behind each rod end of `play` (at the socket's reference point), the play
    spring between the two, and the joint's super-element moved from the rod end to the body."""
    if mdl.play_slots:
        raise ValueError("add_play: the model has play already (set_play changes it)")
    fe = mdl.fe
    body = {}
    for name in play:
        body[name] = fe.add_node(f"{name}:sock", mdl.socket_refs[name])
    fe.springs = [(tuple(body.get(n, n) for n in nodes), k) for nodes, k in fe.springs]
    for name in play:
        mdl.play_slots[name] = len(fe.springs)
        fe.add_spring((name, body[name]), _play_block(play[name]))
    for labs in mdl.joint_nodes.values():
        for lab, n in labs.items():
            labs[lab] = body.get(n, n)


def set_play(mdl: Model, play: dict) -> None:
    """Put new play stiffnesses into a model built with play at the same rod ends (the play
    iteration changes only these springs, not the model's structure)."""
    if set(play) != set(mdl.play_slots):
        raise ValueError("set_play: the model was built with play at other rod ends")
    for name, i in mdl.play_slots.items():
        mdl.fe.set_spring(i, _play_block(play[name]))


def _add_masses(spec, frame, mdl: Model, masses: dict) -> None:
    fe = mdl.fe
    # joints: their mass shared by their bodies (g -> t)
    for inst, labs in mdl.joint_nodes.items():
        m = masses["joints"][mdl.instance_part[inst]] * 1e-6
        nodes = list(labs.values())
        r_g = 3.0  # mm, radius of gyration of a joint's share (a few mm of TPU)
        for n in nodes:
            fe.add_mass(n, m / len(nodes), (m / len(nodes) * r_g**2,) * 3)
    for name in mdl.motors:
        m = masses["motor_each"] * 1e-6
        r = spec.motor.bell_d / 2
        fe.add_mass(name, m, (0.25 * m * r * r, 0.25 * m * r * r, 0.5 * m * r * r))
    m = masses["payload"] * 1e-6
    core = frame.core
    lo = np.min([b.lo for b in (core.plate, core.holder, core.battery, core.stack)], axis=0)
    hi = np.max([b.hi for b in (core.plate, core.holder, core.battery, core.stack)], axis=0)
    sx, sy, sz = hi - lo
    fe.add_mass(mdl.payload, m, (m * (sy * sy + sz * sz) / 12, m * (sx * sx + sz * sz) / 12, m * (sx * sx + sy * sy) / 12))


def _dof(fe: ff.Frame3D, node: str, comp: int) -> int:
    return 6 * list(fe.nodes).index(node) + comp


def _floor_bc(mdl: Model, K, feet: str):
    """(K with the tangential floor springs added, fixed-DOF mask for the feet on the floor).
    K dense or scipy sparse; a dense K is changed in place."""
    fe = mdl.fe
    idx = fe.index()
    fixed = np.zeros(K.shape[0], dtype=bool)
    rows, cols, vals = [], [], []
    for name in mdl.feet:
        i = 6 * idx[name]
        fixed[i + 2] = True
        if feet == "pinned":
            fixed[i:i + 2] = True
            continue
        p = fe.nodes[name]
        t = np.cross([0.0, 0.0, 1.0], [p[0], p[1], 0.0])
        t /= np.linalg.norm(t)
        d = np.arange(i, i + 3)
        rows.append(np.repeat(d, 3))
        cols.append(np.tile(d, 3))
        vals.append((_FLOOR_SPRING_N_PER_MM * np.outer(t, t)).ravel())
    if rows:
        r, c, v = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
        if isinstance(K, np.ndarray):
            np.add.at(K, (r, c), v)
        else:
            from scipy.sparse import coo_matrix

            K = (K + coo_matrix((v, (r, c)), shape=K.shape)).tocsc()
    return K, fixed


def _drop_unconnected(K, fixed: np.ndarray) -> np.ndarray:
    """Hold DOFs that nothing connects (e.g. rotations of a node tied only by normal springs)."""
    return fixed | (np.abs(K.diagonal()) < 1e-12)


# -- results ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class StiffnessResult:
    k_n_per_m: float  # payload vertical stiffness: force on the payload / its deflection vs the ground
    load_n: float
    deflection_mm: float
    joint_model: str  # "fe" | "analytic"
    tpu_factor: float  # the one calibration: printed / datasheet TPU modulus
    n_nodes: int
    n_dofs: int
    max_joint_rotation_deg: float | None = None
    solve_s: float | None = None
    rod_axial_per_n: tuple[tuple[str, float], ...] = ()  # rod axial force per N on the payload (tension +)


def _solve_payload(spec, frame, parts, joints, feet: str = "sliding", load_n: float = DEFAULT_LOAD_N, play=None,
                   mdl: Model | None = None, K0=None):
    """(model, K with the floor, u) for a vertical load on the payload, the feet on the floor.
    ``mdl``: a model already built (with ``play``); ``K0``: its assembled stiffness (sparse)."""
    if feet not in ("sliding", "pinned"):
        raise ValueError(f"feet must be 'sliding' or 'pinned', got {feet!r}")
    mdl = mdl if mdl is not None else build_model(spec, frame, parts, joints, feet=feet, play=play)
    fe = mdl.fe
    K = K0 if K0 is not None else fe.stiffness(sparse=True)
    K, fixed = _floor_bc(mdl, K, feet)
    fixed = _drop_unconnected(K, fixed)
    f = np.zeros(K.shape[0])
    f[_dof(fe, mdl.payload, 2)] = -load_n
    u = ff.solve(K, f, fixed)
    return mdl, K, u


# The fit's play makes k a secant stiffness, which depends on the force it is taken at. It is
# taken where the paper's static k was: a least-squares line through F = 0..115 N of a response
# F/k + (play) equals the secant at 2/3 of the top force, 76.7 N. Fixed, so k depends on the
# geometry alone (not on the mass or the design drop), and the calibration target is like for like.
STATIC_TEST_MAX_N = 115.0
PLAY_REFERENCE_N = 2.0 / 3.0 * STATIC_TEST_MAX_N
PLAY_FRICTION_N = 1.0  # a rod in a printed socket holds ~1 N by friction before it slides into its play
_PLAY_BIG = 1.0e6


def play_springs(spec, frame, parts, joints, design_force_n: float, iterations: int = 3) -> dict:
    """Secant springs of the fit's play at the design drop's force, per rod end node.

    A rod in a bore with radial clearance g = fit_clearance / 2 moves g sideways and tilts
    2 g / L (L the socket depth) before it bears; under a socket load F (moment M) across the
    rod that play is a series compliance g / F (2 g / L / M). Evaluated at the forces the
    sockets carry at the design drop (iterated, the play redistributes them), floored at
    PLAY_FRICTION_N. An interference fit (clearance <= 0) has no play. This is the one place
    the model is not linear: k becomes a secant stiffness at the design drop's force, as the
    paper's static k is a secant over its 0-115 N test."""
    return _play(spec, frame, parts, joints, design_force_n, iterations)[0]


def _play(spec, frame, parts, joints, design_force_n: float, iterations: int = 3) -> tuple[dict, Model | None]:
    """(`play_springs`, the frame model built with them), the model None without play.

    One build: the first iteration solves the model without play, which `add_play` then turns
    into the model with play; the later iterations replace the play matrices in place
    (`set_play`). Every rod end at once: T^T D T with T the socket frame (x along the rod) and
    D = diag(stiff, k_lat, k_lat, stiff, k_rot, k_rot)."""
    g = max(spec.fit_clearance, 0.0) / 2
    if g <= 0 or design_force_n <= 0:
        return {}, None
    play: dict = {}
    mdl = build_model(spec, frame, parts, joints)  # first without play, then with it (add_play)
    T = None  # socket frames of the rod ends: fixed by the geometry
    for _ in range(iterations):
        if play and not mdl.play_slots:
            add_play(mdl, play)
        elif play:
            set_play(mdl, play)
        m, K, u = _solve_payload(spec, frame, parts, joints, load_n=design_force_n, mdl=mdl)
        sl = socket_loads(m.fe, frame, u)
        depth = np.array([e.depth for e in sl.ends])
        f_lat = np.maximum(_across(sl.forces, sl.axes), PLAY_FRICTION_N)
        m_lat = np.maximum(_across(sl.moments, sl.axes), PLAY_FRICTION_N * depth / 2)
        k_lat, k_rot = f_lat / g, m_lat / (2 * g / depth)
        if T is None:
            R = ff.member_axes(sl.axes)
            T = np.zeros((len(depth), 6, 6))
            T[:, :3, :3] = T[:, 3:, 3:] = R
        D = np.zeros((len(depth), 6, 6))
        for i, v in enumerate((_PLAY_BIG, k_lat, k_lat, _PLAY_BIG * 1e3, k_rot, k_rot)):
            D[:, i, i] = v
        play = dict(zip(sl.nodes, np.matmul(np.matmul(T.transpose(0, 2, 1), D), T)))
    if play and not mdl.play_slots:
        add_play(mdl, play)
    elif play:
        set_play(mdl, play)
    return play, mdl


def _across(v: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """|v - a (v . a)| row by row: the part of each vector across its (unit) axis."""
    w = v - axes * np.einsum("ij,ij->i", v, axes)[:, None]
    return np.sqrt(np.einsum("ij,ij->i", w, w))


@dataclass(frozen=True)
class SocketLoads:
    """What every joint super-element puts on each rod body in its sockets (world axes)."""

    nodes: tuple[str, ...]  # rod end node (a rod end behind play is named by its rod node)
    rods: tuple[str, ...]
    ends: tuple  # frame.RodEnd of each
    axes: np.ndarray  # (n, 3) socket axis, out along the rod
    forces: np.ndarray  # (n, 3) N
    moments: np.ndarray  # (n, 3) N mm


def socket_loads(fe: ff.Frame3D, frame, u: np.ndarray) -> SocketLoads:
    """`SocketLoads` for displacements u (the play springs themselves are skipped)."""
    idx = fe.index()
    axis: dict[str, np.ndarray] = {}
    nodes, rods, ends, axes, loads = [], [], [], [], []
    for names, Ks in fe.springs:
        if len(names) == 2 and names[1] == names[0] + ":sock":
            continue  # a play spring
        f = None
        for j, n in enumerate(names):
            base = n[:-5] if n.endswith(":sock") else n
            if base.count(":") != 1 or base.endswith(":free"):
                continue
            if f is None:
                dofs = (6 * np.array([idx[x] for x in names])[:, None] + np.arange(6)).ravel()
                f = Ks @ u[dofs]
            rn, tag = base.split(":")
            r = frame.rods[rn]
            end = r.a if tag == "a" else r.b
            if rn not in axis:
                axis[rn] = r.axis
            nodes.append(base)
            rods.append(rn)
            ends.append(end)
            axes.append(axis[rn] if tag == "a" else -axis[rn])  # Rod.socket_direction
            loads.append(f[6 * j:6 * j + 6])
    loads = np.array(loads, float).reshape(-1, 6)
    return SocketLoads(tuple(nodes), tuple(rods), tuple(ends), np.array(axes, float).reshape(-1, 3), loads[:, :3], loads[:, 3:])


def predict_stiffness(spec, frame, parts=None, *, joint_model: str = "fe", factor: float | None = None,
                      load_n: float = DEFAULT_LOAD_N, feet: str = "sliding", joints: dict | None = None,
                      design_force_n: float | None = None) -> StiffnessResult:
    """Payload vertical stiffness of the design; with ``design_force_n`` the secant stiffness at
    that force, the fit's play included (`play_springs`)."""
    from .joint_stiffness import TPU_PRINTED_MODULUS_FACTOR

    if not (load_n > 0 and math.isfinite(load_n)):
        raise ValueError(f"load_n must be a positive number, got {load_n}")
    t0 = time.perf_counter()
    if parts is None:
        from .. import partlist

        parts = partlist.build(spec, frame)
    joints = joints if joints is not None else joint_models(spec, parts, joint_model, factor)
    play, mdl = _play(spec, frame, parts, joints, design_force_n) if design_force_n else ({}, None)
    mdl, K, u = _solve_payload(spec, frame, parts, joints, feet, load_n, play or None, mdl=mdl)
    fe = mdl.fe
    d = -u[_dof(fe, mdl.payload, 2)]
    if not (d > 0 and math.isfinite(d)):
        raise RuntimeError(f"stiffness model: payload deflection {d!r} mm is not a positive number")
    idx = fe.index()
    rot = 0.0
    for inst, labs in mdl.joint_nodes.items():
        rs = [u[6 * idx[n] + 3:6 * idx[n] + 6] for n in labs.values()]
        for a in rs:
            for b in rs:
                rot = max(rot, float(np.linalg.norm(a - b)))
    axial = fe.axial_forces(u)
    per_rod = {}
    for b in fe.beams:
        if b.group:
            per_rod.setdefault(b.group, []).append(axial[b.name] / load_n)
    return StiffnessResult(
        k_n_per_m=float(1000.0 * load_n / d), load_n=float(load_n), deflection_mm=float(d), joint_model=joint_model,
        tpu_factor=float(TPU_PRINTED_MODULUS_FACTOR if factor is None else factor), n_nodes=len(fe.nodes),
        n_dofs=6 * len(fe.nodes), max_joint_rotation_deg=math.degrees(rot), solve_s=time.perf_counter() - t0,
        rod_axial_per_n=tuple((k, float(min(v))) for k, v in sorted(per_rod.items())))


def design_force(spec, frame, total_mass_g: float, k: float) -> float:
    """Spring force k x_max at the design drop (x_max capped at the clearance), N."""
    from . import impact

    m = total_mass_g / 1000.0
    c = spec.model.c_n_s_per_m if spec.model.c_n_s_per_m is not None else impact.damping_from_ratio(spec.model.damping_ratio, k, m)
    clearance = spec.requirements.clearance if spec.requirements.clearance is not None else frame.clearance_mm
    r = impact.simulate_height(m, c, k, spec.requirements.design_drop_height_cm, clearance)
    return k * min(r.x_max_mm, clearance) / 1000.0


def secant_k(spec, frame, parts, joints) -> float:
    """k with the fit's play, as the secant at PLAY_REFERENCE_N (N/m)."""
    return secant_k_and_play(spec, frame, parts, joints)[0]


def secant_k_and_play(spec, frame, parts, joints) -> tuple[float, dict]:
    """(`secant_k`, the play springs at PLAY_REFERENCE_N): `load_cases` takes the play springs
    (``play=``) instead of iterating them again."""
    sol = secant_solution(spec, frame, parts, joints)
    return sol.k_n_per_m, sol.play


@dataclass(frozen=True)
class SecantSolution:
    """The secant k's solve: k, the play springs, the model with them, its assembled K (no
    supports) and the payload displacements under DEFAULT_LOAD_N (what `load_cases` starts from)."""

    k_n_per_m: float
    play: dict
    model: Model
    K: object  # scipy sparse
    u: np.ndarray


def secant_solution(spec, frame, parts, joints) -> SecantSolution:
    play, mdl = _play(spec, frame, parts, joints, PLAY_REFERENCE_N)
    if mdl is None:
        mdl = build_model(spec, frame, parts, joints)
    K0 = mdl.fe.stiffness(sparse=True)
    mdl, _, u = _solve_payload(spec, frame, parts, joints, play=play or None, mdl=mdl, K0=K0)
    d = -u[_dof(mdl.fe, mdl.payload, 2)]
    if not (d > 0 and math.isfinite(d)):
        raise RuntimeError(f"stiffness model: payload deflection {d!r} mm is not a positive number")
    return SecantSolution(float(1000.0 * DEFAULT_LOAD_N / d), play, mdl, K0, u)


def calibrate_tpu_factor(spec, frame, target_n_per_m: float = PAPER_K_N_PER_M,
                         joint_model: str = "fe", start: float = 0.3, rtol: float = 1e-4) -> float:
    """The printed-TPU modulus factor that makes `frame` reach `target_n_per_m` (set once, carbon).

    k is nearly proportional to the factor (the rods are ~1000x stiffer than the TPU), so a
    fixed-point iteration f <- f * target / k converges in a few steps."""
    from .. import partlist

    parts = partlist.build(spec, frame)
    f = start
    for _ in range(12):
        k = secant_k(spec, frame, parts, joint_models(spec, parts, joint_model, f))
        nf = f * target_n_per_m / k
        if abs(nf - f) < rtol * f:
            return nf
        f = nf
    return f


# -- load cases ---------------------------------------------------------------------------------

def _damped_peak_factor(zeta: float) -> float:
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


def euler_load(length: float, ei: float, k_rot_a: float, k_rot_b: float, n_el: int = 8) -> float:
    """Critical axial load (N) of a rod pinned in translation at both ends with rotational springs
    k_rot_a, k_rot_b (N mm/rad) at its ends (beam FE with geometric stiffness, n_el elements).
    k_rot = 0: pi^2 EI / L^2; k_rot -> inf: 4 pi^2 EI / L^2."""
    return float(euler_loads([length], ei, [k_rot_a], [k_rot_b], n_el)[0])


def euler_loads(lengths, ei, k_rot_a, k_rot_b, n_el: int = 8) -> np.ndarray:
    """`euler_load` of many rods at once (arrays over the rods; ``ei`` may be one number).

    A round rod bends alike in both planes, so one plane is solved: DOFs (v, theta) per node,
    the ends' v held, the rotational springs on the end thetas; the textbook cubic element's K
    and geometric stiffness G for a unit compression (`framefe.beam_local_k` / `beam_local_kg`,
    their x-y bending terms). K x = P G x for all rods together: G = C C^T, then the ordinary
    symmetric eigenproblem of C^-1 K C^-T (numpy's batched eigvalsh); the smallest positive P."""
    L = np.atleast_1d(np.asarray(lengths, float))
    nr = L.size
    ei = np.broadcast_to(np.asarray(ei, float), (nr,))
    ka, kb = (np.broadcast_to(np.asarray(k, float), (nr,)) for k in (k_rot_a, k_rot_b))
    le = L / n_el
    # element matrices over (v1, t1, v2, t2): framefe's x-y bending terms (indices 1, 5, 7, 11)
    sel = [1, 5, 7, 11]
    ke = ff.beam_local_k_batch(le, ei, 1.0, 1.0, 1.0, 1.0, 1.0)[:, sel][:, :, sel]  # E I_z = ei
    ge = -ff.beam_local_kg_batch(le, -1.0)[:, sel][:, :, sel]
    nd = 2 * (n_el + 1)
    K = np.zeros((nr, nd, nd))
    Gm = np.zeros((nr, nd, nd))
    for e in range(n_el):
        s_ = slice(2 * e, 2 * e + 4)
        K[:, s_, s_] += ke
        Gm[:, s_, s_] += ge
    K[:, 1, 1] += ka
    K[:, nd - 1, nd - 1] += kb
    free = [i for i in range(nd) if i not in (0, nd - 2)]  # v held at both ends
    K, Gm = K[:, free][:, :, free], Gm[:, free][:, :, free]
    C = np.linalg.cholesky(Gm)
    Ci = np.linalg.inv(C)
    A = Ci @ K @ Ci.transpose(0, 2, 1)
    w = np.linalg.eigvalsh(0.5 * (A + A.transpose(0, 2, 1)))
    return np.array([min(x for x in row if x > 0) for row in w])


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

    def to_dict(self) -> dict:
        return {
            "k_n_per_m": self.k_n_per_m, "joint_model": self.joint_model, "tpu_modulus_factor": self.tpu_factor,
            "k_lateral_n_per_m": self.k_lateral_n_per_m, "wall": self.wall, "thrust": self.thrust,
            "modes_hz": list(self.modes_hz), "hover_rotor_hz": self.hover_rotor_hz, "mode_near_rotor": self.mode_near_rotor,
            "min_buckling_margin": self.buckling["min_margin"], "critical_rod": self.buckling["critical_rod"],
            "buckling": self.buckling["rods"],
            "strain": self.strain, "joints": self.joints,
        }


def load_cases(spec, frame, parts, total_mass_g: float, *, joint_model: str = "fe", damping_ratio: float = 0.558,
               design_force_n: float | None = None, joints: dict | None = None, play: dict | None = None,
               solved: SecantSolution | None = None) -> LoadCases:
    """All load cases of the design (see the module docstring). ``design_force_n``: the spring
    force at the design drop's maximum compression (k x_max), for buckling and strain. ``play``:
    the play springs at PLAY_REFERENCE_N if already known (`secant_k_and_play`; {} = no play),
    else iterated here; ``solved``: the secant's solution with those springs (`secant_solution`),
    whose payload case is this one's.

    The payload, wall and full-thrust cases share one model and one assembled K (they differ in
    supports and loads only); the arms-only thrust case and the modes (rods in 4 elements, with
    masses) build their own."""
    from .joint_stiffness import TPU_ELONGATION_AT_BREAK, hinge_geometry, hinged_socket, interface

    t0 = time.perf_counter()
    joints = joints if joints is not None else joint_models(spec, parts, joint_model)
    from .joint_stiffness import TPU_PRINTED_MODULUS_FACTOR

    masses = masses_g(spec, frame, parts, total_mass_g)

    # 1. payload vertical
    f_design = design_force_n if design_force_n is not None else 95.0
    if solved is not None:
        play, mdl, K0, u = solved.play or None, solved.model, solved.K, solved.u
    else:
        mdl = None
        if play is None:
            play, mdl = _play(spec, frame, parts, joints, PLAY_REFERENCE_N)
        play = play or None
        if mdl is None:
            mdl = build_model(spec, frame, parts, joints, play=play)
        K0 = mdl.fe.stiffness(sparse=True)
        mdl, _, u = _solve_payload(spec, frame, parts, joints, play=play, mdl=mdl, K0=K0)
    fe = mdl.fe
    d_pay = -u[_dof(fe, mdl.payload, 2)]
    k = 1000.0 * DEFAULT_LOAD_N / d_pay

    # 2. wall: each side face against a wall (joints on that face held, sticking contact); the worst
    wall = _wall_case(spec, frame, mdl, K0, masses, damping_ratio)

    # 3. thrust
    thrust = _thrust_case(spec, frame, parts, joints, masses, play, full=(mdl, K0))

    # 4. modes (free flight)
    modes = _modes(spec, frame, parts, joints, masses, play=play)
    n_rot = hover_rotor_hz(spec, total_mass_g)
    near = None
    for i, fhz in enumerate(modes):
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
    rod_mat = spec.material(spec.rods.material)
    ei = rod_mat.e_mpa * math.pi * spec.rods.diameter**4 / 64
    names = list(frame.rods)
    lengths = [float(np.linalg.norm(mouth(frame.rods[rn], "b") - mouth(frame.rods[rn], "a"))) for rn in names]
    p_crs = euler_loads(lengths, ei, [_end_rot(mdl, frame, rn, "a") for rn in names],
                        [_end_rot(mdl, frame, rn, "b") for rn in names])
    rods_out = []
    for rn, length, p_cr in zip(names, lengths, p_crs):
        n_ax = min(by_rod[rn]) * scale  # most compressive segment
        p_cr = float(p_cr)
        margin = p_cr / -n_ax if n_ax < 0 else math.inf
        rods_out.append({"rod": rn, "length_mm": round(length, 2), "axial_n": round(n_ax, 3), "euler_n": round(p_cr, 2),
                         "margin": round(margin, 3) if math.isfinite(margin) else None})
    finite = [x for x in rods_out if x["margin"] is not None]
    worst = min(finite, key=lambda x: x["margin"]) if finite else None
    buckling = {"design_force_n": round(f_design, 2), "min_margin": worst["margin"] if worst else None,
                "critical_rod": worst["rod"] if worst else None,
                "rods": sorted(rods_out, key=lambda x: (x["margin"] is None, x["margin"] or 0.0))}

    # 6. TPU strain at the design drop
    strain = _strain(spec, frame, parts, joints, mdl, u * scale, TPU_ELONGATION_AT_BREAK, interface(spec), hinged_socket, hinge_geometry)

    jinfo = {name: {"method": js.method, "dofs": js.n_dofs} for name, js in joints.items()}  # no timings: byte-stable output
    return LoadCases(k, joint_model, TPU_PRINTED_MODULUS_FACTOR, wall["k_lateral_n_per_m"], wall, thrust, tuple(modes), n_rot, near,
                     buckling, strain, jinfo, time.perf_counter() - t0)


def _end_rot(mdl: Model, frame, rn: str, tag: str) -> float:
    r = frame.rods[rn]
    end = r.a if tag == "a" else r.b
    js = mdl.joints[mdl.instance_part[end.node]]
    node = mdl.rod_nodes[rn][0 if tag == "a" else 1]
    lab = next(l for l, n in mdl.joint_nodes[end.node].items() if n in (node, node + ":sock"))
    return js.socket_rotational_stiffness(lab)


# The side faces a wall can meet: (axis, sign), +x first (the worst face is reported; on a tie, to
# round-off, the first).
WALL_FACES = ((0, 1), (0, -1), (1, 1), (1, -1))
FACE_NAMES = {(0, 1): "+x (right)", (0, -1): "-x (left)", (1, 1): "+y (front)", (1, -1): "-y (rear)"}


def _wall_case(spec, frame, mdl: Model, K, masses, zeta: float) -> dict:
    """Each side face against a wall, in turn; the face that allows the lowest wall speed.
    ``K``: the model's assembled stiffness (no supports)."""
    cases = [_wall_face(spec, frame, mdl, K, masses, zeta, axis, sign) for axis, sign in WALL_FACES]
    best = cases[0]
    for c in cases[1:]:
        if c["max_wall_speed_m_s"] < best["max_wall_speed_m_s"] * (1 - _TIE):
            best = c
    return best


def _wall_face(spec, frame, mdl: Model, K, masses, zeta: float, axis: int, sign: int) -> dict:
    """The side face at ``sign`` along ``axis`` against a wall (its corner joints held, sticking
    contact), the payload pushed towards it."""
    fe = mdl.fe
    half = (spec.frame.width if axis == 0 else spec.frame.depth) / 2
    side = [inst for inst in mdl.joint_nodes if inst.startswith("corner_") and sign * frame.nodes[inst].pos[axis] > 0]
    fixed = np.zeros(K.shape[0], dtype=bool)
    idx = fe.index()
    for inst in side:
        for n in mdl.joint_nodes[inst].values():
            fixed[6 * idx[n]:6 * idx[n] + 3] = True
    fixed = _drop_unconnected(K, fixed)
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
    travel, what, gap = min((x for x in limits if x[0] <= t_min + _TIE * abs(t_min)), key=lambda x: x[1])
    w0 = math.sqrt(k_lat / (masses["total"] / 1000.0))
    v_max = travel / 1000.0 * w0 / _damped_peak_factor(zeta)
    return {"k_lateral_n_per_m": k_lat, "max_wall_speed_m_s": v_max, "limited_by": what, "payload_travel_mm": travel,
            "gap_mm": gap, "damping_ratio": zeta, "face": FACE_NAMES[(axis, sign)]}


def _thrust_case(spec, frame, parts, joints, masses, play=None, full: tuple | None = None) -> dict:
    """Full thrust on every motor, the battery holder clamped; the frame whole and the arms alone.
    ``full``: (model, assembled K) of the whole frame with ``play`` if already built."""
    from .flight import max_thrust_g

    thrust_g = max_thrust_g(spec)
    thrust_n = thrust_g * G / 1000.0
    out = {"max_thrust_g": thrust_g}
    for label, roles in (("full", None), ("arms_only", ("arm",))):
        if label == "full" and full is not None:
            mdl, K = full
        else:
            mdl = build_model(spec, frame, parts, joints, only_roles=roles, play=play)
            K = mdl.fe.stiffness(sparse=True)
        fe = mdl.fe
        idx = fe.index()
        fixed = np.zeros(K.shape[0], dtype=bool)
        i = 6 * idx[mdl.payload]
        fixed[i:i + 6] = True
        fixed = _drop_unconnected(K, fixed)
        f = np.zeros(K.shape[0])
        for m in mdl.motors:
            f[6 * idx[m] + 2] = thrust_n
        u = ff.solve(K, f, fixed)
        dz = [u[6 * idx[m] + 2] for m in mdl.motors]
        tilt = [math.degrees(math.hypot(u[6 * idx[m] + 3], u[6 * idx[m] + 4])) for m in mdl.motors]
        if label == "full":
            out["motor_deflection_mm_per_n"] = float(np.mean(dz)) / thrust_n
            out["motor_tilt_deg"] = float(np.max(tilt))
            out["motor_deflection_mm"] = float(np.mean(dz))
        else:
            # per newton only: at full thrust the linear model would tilt the bare arms by ~130 deg,
            # far outside its small-rotation range (the arms alone are nearly a mechanism)
            out["arms_only_motor_deflection_mm_per_n"] = float(np.mean(dz)) / thrust_n
            out["arms_only_motor_tilt_deg_per_n"] = float(np.max(tilt)) / thrust_n
    out["exoskeleton_stiffening"] = out["arms_only_motor_deflection_mm_per_n"] / out["motor_deflection_mm_per_n"]
    return out


def _modes(spec, frame, parts, joints, masses, n: int = N_MODES, rod_segments: int = 4, play=None) -> list[float]:
    """The first n elastic natural frequencies in free flight (Hz, rounded to 0.01)."""
    from scipy.sparse import diags

    mdl = build_model(spec, frame, parts, joints, rod_segments=rod_segments, masses=masses, play=play)
    fe = mdl.fe
    K = fe.stiffness(sparse=True)
    M = fe.mass(sparse=True)
    keep = np.abs(K.diagonal()) > 1e-12
    if not keep.all():
        K, M = K[keep][:, keep].tocsc(), M[keep][:, keep].tocsc()
    # massless DOFs (rigid-link ends) get a tiny inertia so M is positive definite
    M = (M + diags(np.where(M.diagonal() <= 0, 1e-12, 0.0))).tocsc()
    w2 = lowest_eigenvalues(K, M, 6 + n)
    hz = [math.sqrt(max(x, 0.0)) / (2 * math.pi) for x in w2]
    elastic = hz[6:]  # free flight: six rigid-body modes first
    return [round(x, 2) for x in elastic]


_TIE = 1e-6  # relative: results this close are equal (symmetric members; the solver's round-off)
MODES_EXTRA = 8  # eigsh asks for this many modes beyond those wanted (a degenerate pair at the edge)


def lowest_eigenvalues(K, M, count: int) -> np.ndarray:
    """The `count` smallest eigenvalues of K x = lambda M x (K symmetric positive semi-definite,
    M positive definite; scipy sparse), ascending.

    Sparse shift-invert Lanczos (ARPACK `eigsh`, shift below zero so that K - sigma M is positive
    definite even with the rigid-body modes) for count + MODES_EXTRA eigenvalues, then checked
    by Sylvester's law of inertia: the LDL^T factors of K - s M (s in the first gap above the
    count-th eigenvalue) have exactly as many negative pivots as there are eigenvalues below s.
    A missed mode (Lanczos can skip one of a near-degenerate cluster) fails that count, and the
    dense generalized solver (`scipy.linalg.eigh`) answers instead. Small problems go dense."""
    n = K.shape[0]
    want = count + MODES_EXTRA
    if n <= max(200, 3 * want):
        return _dense_lowest(K, M, count)
    from scipy.sparse.linalg import ArpackNoConvergence, LinearOperator, eigsh

    sigma = _shift(K, M)
    lu = ff.factor(K - sigma * M)
    op = LinearOperator(K.shape, matvec=lambda x: lu.solve(np.ravel(x)), dtype=float)
    v0 = np.random.default_rng(0).standard_normal(n)  # deterministic, and no symmetry of the frame
    try:
        # tol: Ritz values to 1e-10 relative (the modes are reported to 0.01 Hz; 0 = machine
        # precision costs ~15 % more iterations for nothing the conditioning (~1e-8) keeps)
        w = eigsh(K, k=want, M=M, sigma=sigma, OPinv=op, which="LM", v0=v0, tol=1e-10, return_eigenvectors=False)
    except ArpackNoConvergence:
        return _dense_lowest(K, M, count)
    w = np.sort(w)
    # the first gap above the count-th eigenvalue (a pair straddling the edge moves it up)
    tol = 1e-9 * max(abs(w[-1]), 1.0)
    j = next((i for i in range(count, want) if w[i] - w[i - 1] > tol), None)
    if j is None or _count_below(K, M, 0.5 * (w[j - 1] + w[j])) != j:
        return _dense_lowest(K, M, count)
    return w[:count]


def _shift(K, M) -> float:
    """The shift-invert shift: below the rigid-body modes (0), so that K - sigma M is positive
    definite, by 1e-7 of the median diagonal ratio K_ii / M_ii (a single element's frequency
    squared; the frame's first modes sit some 1e-7 below it). Much closer to 0 (sigma = -1
    (rad/s)^2) the factors are near-singular (condition ~1e15 with the rigid links) and modes go
    missing; much further, Lanczos needs more restarts."""
    return -1e-7 * float(np.median(K.diagonal() / M.diagonal()))


def _count_below(K, M, s: float) -> int:
    """How many eigenvalues of (K, M) lie below s: the negative pivots of an LDL^T of K - s M
    (Sylvester's law of inertia; M positive definite); -1 if it has no such factors."""
    return ff.negative_pivots(K - s * M)


def _dense_lowest(K, M, count: int) -> np.ndarray:
    """Dense reference: the largest eigenvalues nu = 1 / (lambda - sigma) of M x = nu (K - sigma M) x.
    (eigh(K, M) directly loses ~1e-4 of the low modes to the stiff rigid links: its absolute
    error is eps x the largest eigenvalue; shift-inverted, the wanted end is the large one.)"""
    from scipy.linalg import eigh

    K = K.toarray() if hasattr(K, "toarray") else np.asarray(K)
    M = M.toarray() if hasattr(M, "toarray") else np.asarray(M)
    n = K.shape[0]
    sigma = _shift(K, M)
    nu = eigh(M, K - sigma * M, eigvals_only=True, subset_by_index=[n - count, n - 1])
    return np.sort(1.0 / nu + sigma)


def _strain(spec, frame, parts, joints, mdl: Model, u: np.ndarray, eps_break: float, itf, hinged_socket, hinge_geometry) -> dict:
    """Peak TPU strain at the design drop: the knee hinge (all the relative rotation of the hinged
    leg against the arms in the web, an upper bound) and the sockets (interface bearing)."""
    fe = mdl.fe
    idx = fe.index()
    knees = {p.name: p for p in joint_parts(parts) if hinged_socket(p) is not None}  # knee (and knee_mirrored)
    eps_h = 0.0
    for inst, labs in mdl.joint_nodes.items():
        knee_part = knees.get(mdl.instance_part[inst])
        if knee_part is None:
            continue
        l_web, _, t_web = hinge_geometry(knee_part)
        leg = labs[knee_part.sockets[hinged_socket(knee_part)].rod]
        arms = [n for l, n in labs.items() if "arm" in l]
        th_leg = u[6 * idx[leg] + 3:6 * idx[leg] + 6]
        th_arm = np.mean([u[6 * idx[n] + 3:6 * idx[n] + 6] for n in arms], axis=0)
        eps_h = max(eps_h, t_web / 2 * float(np.linalg.norm(th_leg - th_arm)) / l_web)
    # sockets: the super-element's force on each rod body, as bearing over the socket depth
    sl = socket_loads(fe, frame, u)
    v, mm = _across(sl.forces, sl.axes), _across(sl.moments, sl.axes)
    L = np.array([e.depth for e in sl.ends])
    # rigid rod on a linear (Winkler) bearing over L, loads at the mouth: peak line load
    q = v / L + 6 * (mm + v * L / 2) / L**2
    eps = q / spec.rods.diameter / itf.e
    eps_s = float(eps.max()) if eps.size else 0.0
    # symmetric sockets tie (to round-off): the first by name
    where = min((f"{e.node}/{rn}" for x, e, rn in zip(eps, sl.ends, sl.rods) if x >= eps_s * (1 - _TIE) and x > 0), default=None)
    return {"hinge": round(eps_h, 4), "socket": round(eps_s, 4), "socket_at": where, "elongation_at_break": eps_break,
            "peak": round(max(eps_h, eps_s), 4), "ratio_to_break": round(max(eps_h, eps_s) / eps_break, 4)}
