"""The frame model of an exoskeleton read from CAD (`cadread`): the physics half of issue 43,
`cogniframe analyse`.

The same model as `stiffness` builds for a cogniframe design (docs/stiffness-model.md), from
what the reader finds instead of from params:

- every rod is an Euler-Bernoulli beam of its free span, socket mouth to socket mouth, of the
  rods' real diameter (``rod_diameter``: the authors draw 3.0 mm rods at 3.2) and material; a rod
  through a motor mount's sleeves (an arm) is split at the sleeve, which ties it rigidly to the
  motor node (the mean of the mount's sleeve stations: the motor axis level with the rods);
- every part that holds a rod end is a joint: its own read B-rep solid, meshed (`joints.meshing`,
  the check's mesh size and curvature) and condensed (`joints.solid_fe`, P2 elasticity) onto
  rigid bodies, exactly as `joints.fe` does for a cogniframe part:
  * each rod end, tied to its bore wall and floor (the read bore, bottom, direction, depth)
    through the interface layer h_i = max(bore - rod, 0) / 2 + layer / 2 (`joints.model.interface`
    with the socket's own clearance: a bore drawn for a thicker rod than the real one is a
    looser, softer fit), referenced at the socket's mouth;
  * a foot (a joint whose lowest point along ``down`` is within `FLOOR_TOL` of the lowest
    joint's) tied stiffly by its faces on the floor plane to a support body above its centroid
    on the floor plane, which stands on a rigid, frictionless floor (as `stiffness`);
  * a joint touching a rigid attached part (the core: ABS/PLA/PETG by its name, e.g. the
    connectors' pegs in `MainBase`, cogniframe's core links on `core_plate`) tied stiffly by its
    faces within `CONTACT_TIE_TOL` of that part to a support body rigidly tied to the payload;
  * two joints that touch (the authors' knee snapped to its arm bracket) each tied stiffly by
    their touching faces to one shared rigid body: glued, one node;
- the core (the rigid attached parts touching the joints) is rigid, the payload node at their
  centroid.

Every stiffness of a joint's FE is proportional to the TPU factor (`TPU_PRINTED_MODULUS_FACTOR`),
so each joint is solved once at factor 1 and cached (by its B-rep text and its ties), and
scaled: a factor sweep or a calibration only re-solves the beam model.

Not modelled here (the check's model has them): the fit's play (a bore looser than the rod
makes k a secant; here the clearance only thickens the interface layer) and the modes. The
survival sweep of a read frame is `exosurvival`'s.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field

import numpy as np

from . import framefe as ff
from .constants import G
from .load_cases import thrust_figures

DOWN = {"+z": (0.0, 0.0, 1.0), "-z": (0.0, 0.0, -1.0)}
FLOOR_TOL = 0.5  # mm: a joint whose lowest point is this close to the lowest joint's stands on the floor
CONTACT_TIE_TOL = 0.25  # mm: the cadread contact tolerance (0.1) + a facet's sagitta on a curved face (<= 0.15 at 1.5 mm, 8/circle)
_TIE_STIFF = 1.0e4  # support ties, per unit area x E: effectively rigid (as joints.fe)
_RIGID_E_MPA, _RIGID_G_MPA, _RIGID_D_MM = 1.0e6, 4.0e5, 20.0  # as stiffness
_FLOOR_SPRING_N_PER_MM = 1.0e6
LOAD_N = 10.0
# A joint whose outside lies this close to a side face's plane touches the wall (the cage's corner
# joints; the knees, bowed in by the hourglass, do not), mm
WALL_TOUCH_MM = 3.0
RIGID_MATERIALS = ("abs", "pla", "petg", "asa", "pc", "nylon")


@dataclass(frozen=True)
class Layout:
    """What the model is built from: the read exoskeleton sorted into the model's roles."""

    exo: object  # cadread.Exoskeleton
    down: tuple[float, float, float]
    rod_diameter: float | None  # None: each rod's read diameter
    rod_material: str
    fe_joints: tuple[str, ...]  # joints holding a rod end: solid FE super-elements
    mounts: tuple[str, ...]  # joints holding only sleeves: motor mounts
    feet: tuple[str, ...]
    core: tuple[str, ...]  # rigid attached parts touching a joint
    links: tuple[str, ...]  # joints touching the core
    glue: tuple[tuple[str, str], ...]  # pairs of FE joints that touch
    rods: tuple[str, ...]  # rods with both ends in a socket
    arms: tuple[str, ...]  # rods through a motor mount's sleeve
    notes: tuple[str, ...] = ()
    feet_low: tuple[float, ...] = ()  # each foot's lowest point along `down` (its floor level)

    def rod_d(self, rod) -> float:
        return float(self.rod_diameter if self.rod_diameter is not None else rod.diameter)


def layout(exo, down: str = "-z", rod_diameter: float | None = None, rod_material: str = "carbon_rod",
           solids: dict | None = None) -> Layout:
    from ..cadread.geometry import vertices

    dvec = np.asarray(DOWN[down])
    fe_joints = tuple(j.name for j in exo.joints if any(s.end is not None for s in exo.sockets_of(j.name)))
    mounts = tuple(j.name for j in exo.joints if j.name not in fe_joints)
    notes = []
    # the floor: the lowest joints along `down`
    if solids is not None:
        low = {n: float(np.max(vertices(solids[n]) @ dvec)) for n in fe_joints}
    else:
        low = {n: float(max(np.asarray(c) @ dvec for c in exo.joint(n).bbox)) for n in fe_joints}
    floor = max(low.values()) if low else 0.0
    feet = tuple(n for n in fe_joints if low[n] >= floor - FLOOR_TOL)
    feet_low = tuple(low[n] for n in feet)
    att = {a.name: a for a in exo.attached}
    core_parts = set()
    links, glue = [], []
    for c in exo.contacts:
        for j, o in ((c.a, c.b), (c.b, c.a)):
            if j in fe_joints and o in att and att[o].material in RIGID_MATERIALS:
                core_parts.add(o)
                if j not in links:
                    links.append(j)
        if c.a in fe_joints and c.b in fe_joints:
            glue.append(tuple(sorted((c.a, c.b))))
    held = {(s.rod, s.end) for s in exo.sockets if s.end is not None}
    rods = tuple(r.name for r in exo.rods if (r.name, "a") in held and (r.name, "b") in held)
    arms = tuple(sorted({s.rod for s in exo.sockets if s.end is None and s.joint in mounts and s.rod in rods}))
    if not core_parts:
        notes.append("no rigid core part (ABS/PLA/PETG by its name) touches a joint: the payload has nothing to sit on")
    return Layout(exo, tuple(dvec), rod_diameter, rod_material, fe_joints, mounts, feet, tuple(sorted(core_parts)),
                  tuple(sorted(links)), tuple(sorted(set(glue))), rods, arms, tuple(notes), feet_low)


# -- the joints' super-elements ------------------------------------------------------------------

@dataclass(frozen=True)
class Unit:
    """A joint's condensed stiffness at TPU factor 1, world axes: bodies `labels` at `refs`."""

    joint: str
    labels: tuple[str, ...]
    refs: tuple[tuple[float, float, float], ...]
    K: np.ndarray = field(repr=False)
    material: str = ""
    n_dofs: int = 0
    tied_area: tuple[float, ...] = ()


def _centroid(exo, name: str) -> np.ndarray:
    for p in (*exo.joints, *exo.attached):
        if p.name == name:
            return np.asarray(p.centroid, float)
    raise KeyError(name)


def body_refs(lay: Layout) -> dict[str, tuple[str, np.ndarray]]:
    """label -> (node name, reference point) of every support body a joint may tie to."""
    exo = lay.exo
    d = np.asarray(lay.down)
    out = {}
    for n, level in zip(lay.feet, lay.feet_low):
        c = _centroid(exo, n)
        out[f"floor:{n}"] = (f"floor:{n}", c + d * (level - c @ d))
    for n in lay.links:
        out[f"body:{n}"] = (f"body:{n}", _centroid(exo, n))
    for a, b in lay.glue:
        out[f"glue:{a}|{b}"] = (f"glue:{a}|{b}", 0.5 * (_centroid(exo, a) + _centroid(exo, b)))
    return out


def _near(solid, pts: np.ndarray, tol: float) -> np.ndarray:
    """Mask of the points (3, n) within `tol` of the solid (inside it included)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape
    from OCP.gp import gp_Pnt

    from ..cadread.geometry import face_boxes

    out = np.zeros(pts.shape[1], bool)
    if pts.shape[1] == 0:
        return out
    lo_p, hi_p = pts.min(axis=1), pts.max(axis=1)
    faces, lo, hi = face_boxes(solid)
    # only the other part's faces near these points, each tested against the points in its box
    near = np.all(lo <= hi_p + tol, axis=1) & np.all(lo_p <= hi + tol, axis=1)
    for fi in np.nonzero(near)[0]:
        cand = np.all((pts.T >= lo[fi] - tol) & (pts.T <= hi[fi] + tol), axis=1) & ~out
        for i in np.nonzero(cand)[0]:
            v = BRepBuilderAPI_MakeVertex(gp_Pnt(*map(float, pts[:, i]))).Vertex()
            dd = BRepExtrema_DistShapeShape(v, faces[fi].wrapped)
            out[i] = dd.IsDone() and dd.Value() <= tol
    return out


def joint_ties(lay: Layout, name: str, solids: dict, e: float, g: float, layer_height: float):
    """The `solid_fe.Tie`s of joint `name` (world coordinates) at E, G; and a description of them
    (for the cache key)."""
    from .joints import solid_fe
    from .joints.fe import socket_faces

    exo = lay.exo
    d = np.asarray(lay.down)
    refs = body_refs(lay)
    ties, desc = [], []
    for s in exo.sockets_of(name):
        if s.end is None or s.rod not in lay.rods:
            continue
        rod = exo.rod(s.rod)
        h = max(s.bore - lay.rod_d(rod), 0.0) / 2 + layer_height / 2
        tol = 0.1 + 0.5 * s.bore * (1 - math.cos(math.pi / 8))
        sel = socket_faces(np.asarray(s.bottom, float), np.asarray(s.direction, float), s.bore / 2, s.gap + s.depth, tol)
        ties.append(solid_fe.Tie(f"{s.rod}:{s.end}", sel, tuple(map(float, s.mouth)), e / h, g / h))
        desc.append((ties[-1].name, s.bottom, s.direction, s.bore, s.gap + s.depth, h))
    stiff = _TIE_STIFF * e
    if name in lay.feet:
        lab = f"floor:{name}"
        level = float(refs[lab][1] @ d)

        def sel_floor(c, n, level=level):
            # the faces on the floor: flat faces at the foot's lowest level; a rounded foot
            # (no flat face there) stands on what lies within FLOOR_TOL of it, facing down
            flat = (np.abs(d @ c - level) < 0.05) & ((d @ n) > 0.99)
            return flat if flat.any() else (d @ c > level - FLOOR_TOL) & ((d @ n) > 0.5)

        ties.append(solid_fe.Tie(lab, sel_floor, tuple(map(float, refs[lab][1])), stiff, stiff))
        desc.append((lab, level))
    others = []
    if name in lay.links:
        core = [solids[p] for p in lay.core if any({c.a, c.b} == {name, p} for c in exo.contacts)]
        others.append((f"body:{name}", core))
    for a, b in lay.glue:
        if name in (a, b):
            others.append((f"glue:{a}|{b}", [solids[b if name == a else a]]))
    for lab, parts in others:
        def sel_contact(c, n, parts=parts):
            m = np.zeros(c.shape[1], bool)
            for p in parts:
                m |= _near(p, c, CONTACT_TIE_TOL)
            return m

        ties.append(solid_fe.Tie(lab, sel_contact, tuple(map(float, refs[lab][1])), stiff, stiff))
        desc.append((lab, [_brep_hash(p) for p in parts]))
    return ties, desc


def _brep_text(solid) -> str:
    from ..parts.shapes import brep_text

    return brep_text(solid)


def _brep_hash(solid) -> str:
    return hashlib.sha256(_brep_text(solid).encode()).hexdigest()


def joint_unit(lay: Layout, name: str, solids: dict, layer_height: float = 0.2, use_cache: bool = True) -> Unit:
    """The solid FE of one read joint at factor 1 (cached by its B-rep, ties and material)."""
    from .. import cache
    from ..materials import MATERIALS
    from .joints import FE_MESH_MM
    from .joints.fe import FE_CURVATURE, _nu
    from .numerics import one_blas_thread

    j = lay.exo.joint(name)
    mat = MATERIALS[j.material or "tpu_95a"]
    e, g = mat.e_mpa, mat.g_mpa
    text = _brep_text(solids[name])
    ties, desc = joint_ties(lay, name, solids, e, g, layer_height)
    key = cache.key(["exo-joint-1", hashlib.sha256(text.encode()).hexdigest(), desc, e, g, FE_MESH_MM, FE_CURVATURE],
                    ("analysis/exoframe.py", "analysis/joints/solid_fe.py", "analysis/joints/meshing.py"))
    hit = cache.load_json("exojoint", key) if use_cache else None
    if hit is None:
        from .joints import meshing, solid_fe

        with one_blas_thread():
            pts, tets = meshing.mesh_brep_text(text, FE_MESH_MM, FE_CURVATURE)
            c = solid_fe.condense(pts, tets, e, _nu(e, g), ties)
        hit = {"labels": list(c.names), "refs": c.refs.tolist(), "K": c.K.tolist(), "n_dofs": c.n_dofs,
               "tied_area": list(c.tied_area)}
        if use_cache:
            cache.store_json("exojoint", key, hit)
    return Unit(name, tuple(hit["labels"]), tuple(map(tuple, hit["refs"])), np.asarray(hit["K"], float), j.material,
                int(hit["n_dofs"]), tuple(hit["tied_area"]))


def joint_units(lay: Layout, solids: dict, layer_height: float = 0.2, progress=None) -> dict[str, Unit]:
    out = {}
    for i, n in enumerate(lay.fe_joints):
        out[n] = joint_unit(lay, n, solids, layer_height)
        if progress is not None:
            progress(f"joint FE {i + 1}/{len(lay.fe_joints)}: {n} ({out[n].n_dofs} DOF)")
    return out


# -- the frame model ---------------------------------------------------------------------------

@dataclass
class Model:
    fe: ff.Frame3D
    payload: str
    feet: list[str]
    motors: list[str]
    joint_nodes: dict[str, tuple[str, ...]] = field(default_factory=dict)  # each FE joint's reference bodies


def model_of(lay: Layout, units: dict[str, Unit], factor: float, only: tuple[str, ...] | None = None) -> Model:
    """The beam-and-super-element model at TPU factor `factor`; ``only``: keep only these rods
    (and the joints holding one of them; a removed rod's socket body is left free)."""
    from ..materials import MATERIALS

    exo = lay.exo
    fe = ff.Frame3D()
    rods = [r for r in lay.rods if only is None or r in only]
    rm = MATERIALS[lay.rod_material]
    # motor stations: each mount's sleeves
    stations: dict[str, list[tuple[float, str]]] = {}
    motors = []
    for m in lay.mounts:
        socks = [s for s in exo.sockets_of(m) if s.rod in rods and s.station is not None]
        if not socks:
            continue
        pts = []
        for s in socks:
            r = exo.rod(s.rod)
            p = np.asarray(r.a) + np.asarray(r.axis) * s.station
            pts.append(p)
            stations.setdefault(s.rod, []).append((s.station, m))
        motors.append((m, np.mean(pts, axis=0), [s.rod for s in socks]))
    for rn in rods:
        r = exo.rod(rn)
        sa, sb = exo.socket_at(rn, "a"), exo.socket_at(rn, "b")
        pa, pb = np.asarray(sa.mouth, float), np.asarray(sb.mouth, float)
        chain = [fe.add_node(f"{rn}:a", pa)]
        for st, m in sorted(stations.get(rn, [])):
            p = np.asarray(r.a) + np.asarray(r.axis) * st
            chain.append(fe.add_node(f"{rn}:{m}", p))
        chain.append(fe.add_node(f"{rn}:b", pb))
        rho = rm.density_g_mm3 * 1e-6
        for i in range(len(chain) - 1):
            fe.add_beam(rn if len(chain) == 2 else f"{rn}#{i}", chain[i], chain[i + 1], rm.e_mpa, rm.g_mpa, lay.rod_d(r),
                        rho=rho, group=rn)
    mnodes = []
    for m, p, mrods in motors:
        fe.add_node(m, p)
        mnodes.append(m)
        for rn in mrods:
            fe.add_beam(f"mount:{m}:{rn}", m, f"{rn}:{m}", _RIGID_E_MPA, _RIGID_G_MPA, _RIGID_D_MM)
    # the joints
    kept = set(rods)
    joint_nodes: dict[str, tuple[str, ...]] = {}
    for n in lay.fe_joints:
        u = units[n]
        rod_labels = [lab for lab in u.labels if not lab.startswith(("floor:", "body:", "glue:"))]
        if only is not None and not any(lab.rsplit(":", 1)[0] in kept for lab in rod_labels):
            continue
        names = []
        for lab, ref in zip(u.labels, u.refs):
            if lab.startswith(("floor:", "body:", "glue:")):
                if lab not in fe.nodes:
                    fe.add_node(lab, ref)
                names.append(lab)
            elif lab.rsplit(":", 1)[0] in kept:
                if math.dist(fe.nodes[lab], ref) > 1e-6:
                    raise RuntimeError(f"exoframe: the socket of {lab} in {n} is off its rod's mouth")
                names.append(lab)
            else:
                names.append(fe.add_node(f"{n}:{lab}:free", ref))
        fe.add_spring(tuple(names), factor * u.K)
        joint_nodes[n] = tuple(names)
    # the core: rigid, the payload at the core parts' centroid
    if lay.core:
        vols = np.array([next(a.volume for a in exo.attached if a.name == c) for c in lay.core])
        cs = np.array([_centroid(exo, c) for c in lay.core])
        pay = (vols[:, None] * cs).sum(axis=0) / vols.sum()
    else:
        pay = np.mean([np.asarray(j.centroid) for j in exo.joints], axis=0)
    fe.add_node("payload", pay)
    for n in lay.links:
        if f"body:{n}" in fe.nodes:
            fe.add_beam(f"core:{n}", "payload", f"body:{n}", _RIGID_E_MPA, _RIGID_G_MPA, _RIGID_D_MM)
    feet = [f"floor:{n}" for n in lay.feet if f"floor:{n}" in fe.nodes]
    return Model(fe, "payload", feet, mnodes, joint_nodes)


def _unconnected(K, fixed: np.ndarray) -> np.ndarray:
    return fixed | (np.abs(K.diagonal()) < 1e-12)


def _vertical(down) -> int:
    return int(np.argmax(np.abs(np.asarray(down))))


def payload_k(lay: Layout, mdl: Model, load_n: float = LOAD_N) -> float:
    """k (N/m): a force along `down` on the payload over its deflection, the feet on a rigid,
    frictionless floor (vertical held, one tangential spring each against the in-plane rigid-body
    modes: as `stiffness`)."""
    return payload_case(lay, mdl, load_n)[0]


def payload_case(lay: Layout, mdl: Model, load_n: float = LOAD_N) -> tuple[float, np.ndarray]:
    """(k in N/m, the displacements under `load_n` newtons): `payload_k`'s solve."""
    from scipy.sparse import coo_matrix

    fe = mdl.fe
    if not mdl.feet:
        raise RuntimeError("exoframe: no joint stands on the floor")
    idx = fe.index()
    K = fe.stiffness(sparse=True)
    vz = _vertical(lay.down)
    up = -np.asarray(lay.down)
    centre = fe.nodes[mdl.payload]
    fixed = np.zeros(K.shape[0], bool)
    rows, cols, vals = [], [], []
    for f in mdl.feet:
        i = 6 * idx[f]
        fixed[i + vz] = True
        r = fe.nodes[f] - centre
        r = r - up * (r @ up)
        t = np.cross(up, r)
        t /= np.linalg.norm(t)
        dd = np.arange(i, i + 3)
        rows.append(np.repeat(dd, 3))
        cols.append(np.tile(dd, 3))
        vals.append((_FLOOR_SPRING_N_PER_MM * np.outer(t, t)).ravel())
    K = (K + coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=K.shape)).tocsc()
    fixed = _unconnected(K, fixed)
    f = np.zeros(K.shape[0])
    f[6 * idx[mdl.payload]:6 * idx[mdl.payload] + 3] = load_n * np.asarray(lay.down)
    u = ff.solve(K, f, fixed)
    d = float(u[6 * idx[mdl.payload]:6 * idx[mdl.payload] + 3] @ np.asarray(lay.down))
    if not (d > 0 and math.isfinite(d)):
        raise RuntimeError(f"exoframe: payload deflection {d!r} mm is not a positive number (a mechanism?)")
    return 1000.0 * load_n / d, u


def motors_under_thrust(lay: Layout, mdl: Model, thrust_n: float = 1.0) -> tuple[float, float]:
    """(mean motor deflection along up, mm; largest motor tilt, rad) with `thrust_n` up on every
    motor and the payload (core) held: as `load_cases._motors_under_thrust`."""
    fe = mdl.fe
    idx = fe.index()
    K = fe.stiffness(sparse=True)
    fixed = np.zeros(K.shape[0], bool)
    i = 6 * idx[mdl.payload]
    fixed[i:i + 6] = True
    fixed = _unconnected(K, fixed)
    up = -np.asarray(lay.down)
    f = np.zeros(K.shape[0])
    for m in mdl.motors:
        f[6 * idx[m]:6 * idx[m] + 3] = thrust_n * up
    u = ff.solve(K, f, fixed)
    dz = float(np.mean([u[6 * idx[m]:6 * idx[m] + 3] @ up for m in mdl.motors]))
    tilt = 0.0
    for m in mdl.motors:
        r = u[6 * idx[m] + 3:6 * idx[m] + 6]
        tilt = max(tilt, float(np.linalg.norm(r - up * (r @ up))))
    return dz, tilt


def thrust_case(lay: Layout, units: dict, factor: float, max_thrust_g: float, total_mass_g: float,
                full: Model | None = None) -> dict:
    """`check --json`'s `stiffness.thrust` keys for the read frame: the whole frame and the arms
    alone (the rods through a motor mount, the joints holding them), core held, per newton, at
    hover (the all-up weight over the motors) and at full thrust."""
    if not lay.mounts or not lay.arms:
        return {"note": "no motor mount (a part holding rods through sleeves only) found: no thrust case"}
    per_full, n_m = max_thrust_g * G / 1000.0, max(len(lay.mounts), 1)
    hover_g = total_mass_g / n_m
    per_hover = hover_g * G / 1000.0
    out = {"max_thrust_g": max_thrust_g, "hover_thrust_g": hover_g}
    for label, only in (("full", None), ("arms_only", lay.arms)):
        mdl = full if (label == "full" and full is not None) else model_of(lay, units, factor, only)
        dz, tilt = motors_under_thrust(lay, mdl, 1.0)
        out.update(thrust_figures(dz, tilt, per_hover, per_full, "" if label == "full" else "arms_only_"))
    out["exoskeleton_stiffening"] = out["arms_only_motor_deflection_mm_per_n"] / out["motor_deflection_mm_per_n"]
    return out


def wall_case(lay: Layout, mdl: Model, mass_kg: float, zeta: float, prop_diameter_mm: float,
              touch_mm: float = WALL_TOUCH_MM) -> dict:
    """`check --json`'s `stiffness.wall` for the read frame: each side face against a wall in turn
    (the joints whose outside lies within `touch_mm` of the face's plane held, sticking contact),
    the payload pushed towards it; the face that allows the lowest speed before a propeller disc
    (`prop_diameter_mm`, centred on each motor mount's centroid) or the core reaches the wall's
    plane: as `load_cases._wall_face`, the faces and the touching joints read from the solids' boxes."""
    from .load_cases import lowest_wall_speed

    K = mdl.fe.stiffness(sparse=True).tocsc()
    vz = _vertical(lay.down)
    cases = [c for axis in range(3) if axis != vz for sign in (1, -1)
             if (c := _wall_face(lay, mdl, K, axis, sign, mass_kg, zeta, prop_diameter_mm / 2, touch_mm))]
    if not cases:
        return {"note": "no side face with joints on the wall round a plane (three or more not in a line): no wall case"}
    return lowest_wall_speed(cases)


def _wall_face(lay: Layout, mdl: Model, K, axis: int, sign: int, mass_kg: float, zeta: float, radius: float,
               touch_mm: float) -> dict | None:
    """The side face at `sign` along `axis` against a wall, or None when the joints on it lie in a line."""
    from .load_cases import TIE, damped_peak_factor

    exo, fe = lay.exo, mdl.fe
    idx = fe.index()
    joints = {j.name: j for j in exo.joints}

    def out(box):  # how far a box reaches towards the wall
        return max(sign * box[0][axis], sign * box[1][axis])

    plane = max(out(joints[n].bbox) for n in mdl.joint_nodes)
    side = [n for n in mdl.joint_nodes if out(joints[n].bbox) >= plane - touch_mm]
    held = np.array([fe.nodes[node] for n in side for node in mdl.joint_nodes[n]])
    if np.linalg.svd(held - held.mean(axis=0), compute_uv=False)[1] < 1.0:
        return None  # the joints on the wall lie on a line: the frame would turn about it
    fixed = np.zeros(K.shape[0], bool)
    for node in (node for n in side for node in mdl.joint_nodes[n]):
        fixed[6 * idx[node]:6 * idx[node] + 3] = True
    f = np.zeros(K.shape[0])
    f[6 * idx[mdl.payload] + axis] = sign * LOAD_N
    u = ff.solve(K, f, _unconnected(K, fixed))
    d_pay = sign * u[6 * idx[mdl.payload] + axis]
    if not (d_pay > 0 and math.isfinite(d_pay)):
        raise RuntimeError(f"exoframe: payload deflection {d_pay!r} mm towards a wall is not a positive number")
    limits = []
    for m in mdl.motors:  # the disc round the mount's centroid (the motor's axis), moving with the mount
        gap = plane - (sign * joints[m].centroid[axis] + radius)
        ratio = sign * u[6 * idx[m] + axis] / d_pay
        if ratio > 0:
            limits.append((gap / ratio, f"propeller of {m}", gap))
    gap_core = plane - max(out(a.bbox) for a in exo.attached if a.name in lay.core)
    limits.append((gap_core, "core", gap_core))
    t_min = min(x[0] for x in limits)
    travel, what, gap = min((x for x in limits if x[0] <= t_min + TIE * abs(t_min)), key=lambda x: x[1])
    k_lat = 1000.0 * LOAD_N / d_pay
    v_max = travel / 1000.0 * math.sqrt(k_lat / mass_kg) / damped_peak_factor(zeta)
    return {"k_lateral_n_per_m": k_lat, "max_wall_speed_m_s": v_max, "limited_by": what, "payload_travel_mm": travel,
            "gap_mm": gap, "damping_ratio": zeta, "face": f"{'+' if sign > 0 else '-'}{'xyz'[axis]}",
            "joints_on_the_wall": sorted(side)}


def k_at(lay: Layout, units: dict, factor: float) -> float:
    return payload_k(lay, model_of(lay, units, factor))


def calibrate(lay: Layout, units: dict, target_n_per_m: float, lo: float = 0.01, hi: float = 10.0) -> float:
    """The TPU factor f with k(f) = target: a 1-D root find (brentq on log k - log target; k grows
    with f monotonically, nearly in proportion, the rods' bending being the rest)."""
    from scipy.optimize import brentq

    return float(brentq(lambda f: math.log(k_at(lay, units, f) / target_n_per_m), lo, hi, xtol=1e-7, rtol=1e-9))
