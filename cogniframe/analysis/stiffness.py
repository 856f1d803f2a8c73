"""Physics: the payload's vertical stiffness k from a 3D beam finite-element model of the frame.

Pure (no CAD): Spec + Frame -> PyNite `FEModel3D` -> `StiffnessResult`. Units: N and mm
(E, G in MPa = N/mm^2); k is reported in N/m (k_n_per_m = 1000 * F / delta).

The model (docs/stiffness-model.md explains why):
- every rod is an Euler-Bernoulli beam (solid circle of the rod diameter, E and G of the rod
  material) between its `start` and `end` points, i.e. between its two socket bottoms. Loads act
  only at nodes, where a cubic beam element is exact, so one element per rod is enough
  (`rod_segments` subdivides, for checking that claim);
- every rod end is tied to its joint's centre by a short TPU *joint element* along the rod axis,
  from the rod end to the rod's port (length = the joint's `seat`), made of the joint material
  scaled by `JOINT_CALIBRATION`. Its section is the socket sleeve: a tube of OD = bore + 2 * wall
  and ID = bore. Where the design folds (`HINGED`: the knee, between the upper and lower leg
  sockets) the leg's joint element is the living-hinge web instead: a strip as wide as the
  sleeve and `hinge_thickness` thick, thin across the fold axis (horizontal, normal to the plane
  of the two legs). Where a port is offset sideways from the joint centre (the two parallel arm
  rods) a rigid link joins port and centre: the joint body bridging two side-by-side sockets;
- the core (the four `core_link_*` centres and a payload node at the core-plate centre) is a
  rigid star of very stiff members;
- the feet (`corner_bottom_*`) stand on a rigid, frictionless floor: vertical support, rotations
  free, and a stiff horizontal spring per foot tangential to the frame, which removes the three
  in-plane rigid-body modes but lets the feet slide outwards as the frame squats
  (`feet="pinned"` models a floor with full friction instead);
- load case "payload" (the stiffness): a vertical force F down through the payload's centre of
  gravity, the core-plate centre -- the drop model's load, the payload's inertia pushing the core
  down on a frame standing on the ground. k = F / (payload deflection relative to the feet).
  Load case "top" (a diagnostic): F shared by the four top corners, as the paper's static rig
  pressed the top, with the same read-out; reported as `k_top_n_per_m`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

# ------------------------------------------------------------------------------------------
# The one global calibration factor: a multiplier on the moduli (E and G) of the TPU joint
# elements. 1.0 means "each joint behaves as a datasheet-modulus TPU sleeve tube (or hinge web)
# of the seat length, rigidly bonded to the rod". The factor stands for what that idealisation
# cannot see: the rod rocking and sliding in its socket (radial squash of the sleeve wall, the
# fit clearance, friction instead of a bond), load spreading into the joint body, and printed
# TPU versus the datasheet. Set ONCE (with `calibrate`) so that the carbon preset gives the
# paper's static k = 7040 N/m; never per preset. Everything else -- rod diameter and modulus,
# joint material, wall, bore, seats, geometry -- acts through the FE model itself.
JOINT_CALIBRATION = 0.5383  # recalibrated for the issue-13 core (plate and links 1.2 mm higher)
# ------------------------------------------------------------------------------------------

PAPER_K_N_PER_M = 7040.0  # carbon build, static dynamometer test (static_stiffness_carbon.csv)
DEFAULT_LOAD_N = 10.0  # the model is linear: k does not depend on it (the paper's rig went to 115 N)
HINGED = ("knee",)  # joint kinds whose leg sockets are joined by the living-hinge web (the fold)

# "Rigid" members (core star, port offsets): stiff enough that 10x stiffer changes k by < 1e-6
# relative, not so stiff that the stiffness matrix loses precision.
_RIGID_E_MPA = 1.0e6
_RIGID_G_MPA = 4.0e5
_RIGID_D_MM = 20.0
# Tangential floor springs at the feet, N/mm. They only remove rigid-body modes (by symmetry they
# carry no force under a vertical load on a symmetric frame).
_FLOOR_SPRING_N_PER_MM = 1.0e6
_GROUND_ARM_MM = 10.0


@dataclass(frozen=True)
class StiffnessResult:
    k_n_per_m: float  # payload vertical stiffness: force on the payload / its deflection vs the ground
    load_n: float  # force applied in the FE model (k does not depend on it: linear model)
    deflection_mm: float  # payload deflection relative to the ground under load_n
    calibration: float  # the global joint-modulus factor used (JOINT_CALIBRATION unless overridden)
    n_nodes: int
    n_members: int  # beam elements (rods, joint elements, rigid links); floor springs not counted
    max_joint_rotation_deg: float | None = None  # largest rod-vs-joint-centre rotation under load_n
    k_top_n_per_m: float | None = None  # the paper's rig: F on the top corners / payload deflection
    knee_spread_mm: float | None = None  # mean outward (radial, in plan) knee movement under load_n
    solve_s: float | None = None  # wall time of building + solving the FE model, s


# -- sections ------------------------------------------------------------------------------

def circle_section(d: float) -> tuple[float, float, float, float]:
    """(A, Iy, Iz, J) of a solid circle of diameter d, mm units."""
    a = math.pi * d**2 / 4
    i = math.pi * d**4 / 64
    return a, i, i, 2 * i


def tube_section(od: float, id_: float) -> tuple[float, float, float, float]:
    """(A, Iy, Iz, J) of a circular tube, mm units."""
    if not 0 <= id_ < od:
        raise ValueError(f"tube needs 0 <= ID < OD, got OD {od}, ID {id_}")
    a = math.pi * (od**2 - id_**2) / 4
    i = math.pi * (od**4 - id_**4) / 64
    return a, i, i, 2 * i


def strip_section(width: float, thickness: float) -> tuple[float, float, float, float]:
    """(A, I_strong, I_weak, J) of a thin rectangular strip (a living-hinge web), mm units.

    PyNite's order is (A, Iy, Iz, J): put the fold axis on the member's local z to use I_weak
    for folding. J is the thin-strip torsion constant b t^3 / 3 (1 - 0.63 t / b).
    """
    b, t = max(width, thickness), min(width, thickness)
    j = b * t**3 / 3 * (1 - 0.63 * t / b)
    return b * t, t * b**3 / 12, b * t**3 / 12, j


def _poisson(e: float, g: float) -> float:
    # PyNite uses nu only for plates; orthotropic rods (carbon: E/G = 25) give a meaningless nu.
    return float(min(max(e / (2 * g) - 1, 0.0), 0.499))


# -- benchmarks ------------------------------------------------------------------------------

def cantilever_stiffness(length_mm: float, diameter_mm: float, e_mpa: float, g_mpa: float) -> float:
    """Tip stiffness (N/mm) of a solid circular rod clamped at one end, from a PyNite model.

    Closed form (Euler-Bernoulli): 3 E I / L^3 with I = pi d^4 / 64.
    """
    from Pynite import FEModel3D

    m = FEModel3D()
    m.add_material("rod", e_mpa, g_mpa, _poisson(e_mpa, g_mpa), 1e-9)
    m.add_section("rod", *circle_section(diameter_mm))
    n = 4  # exact with one element for a tip load; four also exercise the assembly
    for i in range(n + 1):
        m.add_node(f"N{i}", length_mm * i / n, 0.0, 0.0)
    for i in range(n):
        m.add_member(f"M{i}", f"N{i}", f"N{i + 1}", "rod", "rod")
    m.def_support("N0", True, True, True, True, True, True)
    p = 1.0
    m.add_node_load(f"N{n}", "FZ", -p)
    m.analyze_linear(check_stability=False)
    return p / abs(m.nodes[f"N{n}"].DZ["Combo 1"])


# -- the frame model ---------------------------------------------------------------------------

@dataclass
class FrameModel:
    """The PyNite model and the names needed to read it."""

    fe: object  # Pynite.FEModel3D
    payload: str
    feet: list[str]
    links: list[str]
    knees: list[str]
    tops: list[str]
    joint_members: list[tuple[str, str, str]] = field(default_factory=list)  # (member, rod end, joint side)
    hinge_members: list[str] = field(default_factory=list)


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def _fold_axis(frame, node) -> np.ndarray:
    """Fold axis of a hinged joint: normal to the plane of its two leg rods (horizontal for the knee)."""
    legs = [frame.rods[r] for r in node.rods if frame.rods[r].role == "leg"]
    dirs = [r.socket_direction(node.name) for r in legs]
    if len(dirs) == 2:
        n = np.cross(dirs[0], dirs[1])
        if np.linalg.norm(n) > 1e-6:
            return _unit(n)
    # Straight legs (no knee inset): fold about the horizontal normal to the corner's diagonal.
    p = np.asarray(node.pos, dtype=float)
    return _unit(np.cross([p[0], p[1], 0.0], [0.0, 0.0, 1.0]))


def _orient_weak_axis(member, axis: np.ndarray) -> None:
    """Rotate a member about its own axis so that its local z (Iz = I_weak) lies along `axis`."""
    member.rotation = 0.0
    t = member.T()
    x, z0 = t[0, :3], t[2, :3]
    theta = math.atan2(float(np.dot(np.cross(x, z0), axis)), float(np.dot(z0, axis)))
    member.rotation = math.degrees(theta)


def build_model(spec, frame, *, calibration: float | None = None, load_n: float = DEFAULT_LOAD_N,
                feet: str = "sliding", rod_segments: int = 1, hinged: tuple[str, ...] = HINGED) -> FrameModel:
    """The PyNite model of `frame` with load cases/combos "payload" and "top" (module doc)."""
    from Pynite import FEModel3D

    if feet not in ("sliding", "pinned"):
        raise ValueError(f"feet must be 'sliding' or 'pinned', got {feet!r}")
    if rod_segments < 1:
        raise ValueError(f"rod_segments must be >= 1, got {rod_segments}")
    cal = JOINT_CALIBRATION if calibration is None else float(calibration)
    if not (cal > 0 and math.isfinite(cal)):
        raise ValueError(f"calibration must be a positive number, got {cal}")
    m = FEModel3D()

    # Materials and sections.
    rod_mat: dict[str, str] = {}
    rod_sec: dict[float, str] = {}
    for r in frame.rods.values():
        if r.material not in rod_mat:
            mat = spec.material(r.material)
            rod_mat[r.material] = f"rod:{r.material}"
            m.add_material(rod_mat[r.material], mat.e_mpa, mat.g_mpa, _poisson(mat.e_mpa, mat.g_mpa), mat.density_g_mm3)
        if r.diameter not in rod_sec:
            rod_sec[r.diameter] = f"rod:{r.diameter:g}"
            m.add_section(rod_sec[r.diameter], *circle_section(r.diameter))
    tpu = spec.material(spec.joints.material)
    m.add_material("joint", cal * tpu.e_mpa, cal * tpu.g_mpa, _poisson(tpu.e_mpa, tpu.g_mpa), tpu.density_g_mm3)
    m.add_material("rigid", _RIGID_E_MPA, _RIGID_G_MPA, 0.25, 1e-9)
    sleeve_od = spec.bore + 2 * spec.joints.wall
    m.add_section("sleeve", *tube_section(sleeve_od, spec.bore))
    m.add_section("hinge", *strip_section(sleeve_od, spec.joints.hinge_thickness))
    m.add_section("rigid", *circle_section(_RIGID_D_MM))

    for n in frame.nodes.values():
        m.add_node(n.name, *map(float, n.pos))

    out = FrameModel(m, "payload", [], [], [], [])
    for r in frame.rods.values():
        ends = {}
        for tag, end, point in (("a", r.a, r.start), ("b", r.b, r.end)):
            node = frame.nodes[end.node]
            rod_end = f"{r.name}:{tag}"
            m.add_node(rod_end, *map(float, point))
            port = np.asarray(end.port, dtype=float)
            joint_side = node.name
            if np.linalg.norm(port - np.asarray(node.pos)) > 1e-6:
                joint_side = f"{r.name}:{tag}:port"
                m.add_node(joint_side, *map(float, port))
                m.add_member(f"{r.name}:{tag}:body", joint_side, node.name, "rigid", "rigid")
            jm = f"{r.name}:{tag}:joint"
            hinge = node.kind in hinged and r.role == "leg"
            m.add_member(jm, rod_end, joint_side, "joint", "hinge" if hinge else "sleeve")
            if hinge:
                _orient_weak_axis(m.members[jm], _fold_axis(frame, node))
                out.hinge_members.append(jm)
            out.joint_members.append((jm, rod_end, joint_side))
            ends[tag] = rod_end
        chain = [ends["a"]]
        for i in range(1, rod_segments):
            p = r.start + (r.end - r.start) * i / rod_segments
            chain.append(m.add_node(f"{r.name}:{i}", *map(float, p)))
        chain.append(ends["b"])
        for i in range(rod_segments):
            name = r.name if rod_segments == 1 else f"{r.name}:{i}"
            m.add_member(name, chain[i], chain[i + 1], rod_mat[r.material], rod_sec[r.diameter])

    # Rigid core: a star from the payload node (core-plate centre) to the four link centres.
    m.add_node(out.payload, *map(float, frame.core.plate.centre))
    out.links = sorted(n.name for n in frame.nodes.values() if n.kind == "core_link")
    for name in out.links:
        m.add_member(f"core:{name}", out.payload, name, "rigid", "rigid")

    # Feet on the floor.
    out.feet = sorted(n.name for n in frame.nodes.values() if n.kind == "corner_bottom")
    for name in out.feet:
        if feet == "pinned":
            m.def_support(name, True, True, True, False, False, False)
            continue
        m.def_support(name, False, False, True, False, False, False)
        p = np.asarray(frame.nodes[name].pos, dtype=float)
        tangent = _unit(np.cross([0.0, 0.0, 1.0], [p[0], p[1], 0.0]))
        ground = f"ground:{name}"
        m.add_node(ground, *map(float, p + _GROUND_ARM_MM * tangent))
        m.def_support(ground, True, True, True, True, True, True)
        m.add_spring(f"floor:{name}", name, ground, _FLOOR_SPRING_N_PER_MM)

    # Loads.
    out.tops = sorted(n.name for n in frame.nodes.values() if n.kind == "corner_top")
    out.knees = sorted(n.name for n in frame.nodes.values() if n.kind == "knee")
    m.add_node_load(out.payload, "FZ", -load_n, case="payload")
    for name in out.tops:
        m.add_node_load(name, "FZ", -load_n / len(out.tops), case="top")
    m.add_load_combo("payload", {"payload": 1.0})
    m.add_load_combo("top", {"top": 1.0})
    return out


def _rotation(node, combo: str) -> np.ndarray:
    return np.array([node.RX[combo], node.RY[combo], node.RZ[combo]])


def payload_deflection(model: FrameModel, combo: str = "payload") -> float:
    """Payload deflection (mm, positive down) relative to the ground under a solved combo."""
    nodes = model.fe.nodes
    ground = float(np.mean([nodes[f].DZ[combo] for f in model.feet]))  # 0 on a rigid floor
    return ground - nodes[model.payload].DZ[combo]


def predict_stiffness(spec, frame, *, calibration: float | None = None, load_n: float = DEFAULT_LOAD_N,
                      feet: str = "sliding", rod_segments: int = 1, hinged: tuple[str, ...] = HINGED) -> StiffnessResult:
    """Payload vertical stiffness of `frame` (built from `spec`) from the FE model."""
    t0 = time.perf_counter()
    if not (load_n > 0 and math.isfinite(load_n)):
        raise ValueError(f"load_n must be a positive number, got {load_n}")
    mdl = build_model(spec, frame, calibration=calibration, load_n=load_n, feet=feet,
                      rod_segments=rod_segments, hinged=hinged)
    mdl.fe.analyze_linear(check_stability=False, sparse=False)
    nodes = mdl.fe.nodes
    d_pay = payload_deflection(mdl, "payload")
    d_top = payload_deflection(mdl, "top")
    if not (d_pay > 0 and math.isfinite(d_pay)):
        raise RuntimeError(f"stiffness model: payload deflection {d_pay!r} mm is not a positive number "
                           "(the frame model has a mechanism or is badly conditioned)")
    rot = max(float(np.linalg.norm(_rotation(nodes[a], "payload") - _rotation(nodes[b], "payload")))
              for _, a, b in mdl.joint_members)
    spread = []
    for k in mdl.knees:
        n = nodes[k]
        radial = np.array([n.X, n.Y]) / math.hypot(n.X, n.Y)
        spread.append(float(radial @ np.array([n.DX["payload"], n.DY["payload"]])))
    return StiffnessResult(
        k_n_per_m=float(1000.0 * load_n / d_pay),
        load_n=float(load_n),
        deflection_mm=float(d_pay),
        calibration=JOINT_CALIBRATION if calibration is None else float(calibration),
        n_nodes=len(nodes),
        n_members=len(mdl.fe.members),
        max_joint_rotation_deg=math.degrees(rot),
        k_top_n_per_m=float(1000.0 * load_n / d_top) if d_top > 0 else None,
        knee_spread_mm=float(np.mean(spread)),
        solve_s=time.perf_counter() - t0,
    )


def calibrate(spec, frame, target_n_per_m: float = PAPER_K_N_PER_M, **kw) -> float:
    """The joint-modulus factor that makes `frame` reach `target_n_per_m` (for setting
    JOINT_CALIBRATION once from the carbon preset; never call it per preset)."""
    from scipy.optimize import brentq

    def err(log_c: float) -> float:
        return math.log(predict_stiffness(spec, frame, calibration=math.exp(log_c), **kw).k_n_per_m / target_n_per_m)

    return math.exp(brentq(err, math.log(1e-3), math.log(1e3), xtol=1e-6))
