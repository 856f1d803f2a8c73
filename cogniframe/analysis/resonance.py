"""The frame's vibration against the motors: a Campbell diagram in numbers.

Excitations: each rotor turns at n (rev/s) and shakes the frame at n (1x, imbalance), 2 n (blade
pass of a two-blade propeller) and 3 n; from hover to full throttle each is a band. The attitude
controller works from ATTITUDE_BAND_HZ's lower to its upper edge: a frame mode there is fed back
by the rate loop. A mode within FLAG_MARGIN (15 %, `check`'s rule for the hover rotor) of any
band is flagged.

How much the flight controller sees of a mode (`fc_participation`, 0-1): the rotation of the
payload node (the rigid core that carries the FC, whose gyro measures rotation) over the largest
tilt of a motor's thrust axis in the same mode shape, capped at 1. A mode that bends the arms and
leaves the core still is one the gyro cannot see (participation near 0): it matters less to the
controller, though it still shakes the motors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

FLAG_MARGIN = 0.15
# The rate loop's band: from about 1 Hz to the derivative path's low-pass, PX4's default
# IMU_DGYRO_CUTOFF = 30 Hz (src/modules/sensors/vehicle_angular_velocity/imu_gyro_parameters.c):
# above it the controller's D term no longer acts.
ATTITUDE_BAND_HZ = (1.0, 30.0)
HARMONICS = (1, 2, 3)


@dataclass(frozen=True)
class Mode:
    number: int  # 1 = the first elastic mode
    hz: float
    fc_participation: float | None  # None: not computed (check lists frequencies only)


@dataclass(frozen=True)
class Band:
    name: str  # "rotor 1x" ... | "attitude controller"
    lo_hz: float
    hi_hz: float


@dataclass(frozen=True)
class Flag:
    mode: int
    hz: float
    band: str
    fc_participation: float | None
    why: str


@dataclass(frozen=True)
class Resonance:
    modes: tuple[Mode, ...]
    bands: tuple[Band, ...]
    flags: tuple[Flag, ...]
    advice: tuple[tuple[str, tuple[str, ...]], ...]  # firmware -> lines
    filters: tuple[tuple[str, float], ...]  # gyro_lpf_hz, dterm_lpf_hz, rotor_notch_min_hz, ...

    def filter(self, key: str) -> float:
        return dict(self.filters)[key]

    def to_dict(self) -> dict:
        return {"modes": [{"mode": m.number, "hz": m.hz, "fc_participation": m.fc_participation} for m in self.modes],
                "bands": [{"name": b.name, "lo_hz": round(b.lo_hz, 2), "hi_hz": round(b.hi_hz, 2)} for b in self.bands],
                "flag_margin": FLAG_MARGIN,
                "flags": [{"mode": f.mode, "hz": f.hz, "band": f.band, "fc_participation": f.fc_participation, "why": f.why}
                          for f in self.flags],
                "filters": {k: round(v, 1) for k, v in self.filters},
                "advice": {fw: list(lines) for fw, lines in self.advice}}


def bands(hover_rotor_hz: float, max_rotor_hz: float) -> tuple[Band, ...]:
    out = [Band("attitude controller", *ATTITUDE_BAND_HZ)]
    out += [Band(f"rotor {h}x", h * hover_rotor_hz, h * max_rotor_hz) for h in HARMONICS]
    return tuple(out)


def assess(modes_hz, hover_rotor_hz: float, max_rotor_hz: float, participation=None) -> Resonance:
    """Bands, flags and filter advice for modes `modes_hz` (Hz, first elastic first);
    `participation` the flight controller's share of each (None: not known)."""
    part = list(participation) if participation is not None else [None] * len(modes_hz)
    modes = tuple(Mode(i + 1, float(f), None if p is None else round(float(p), 3)) for i, (f, p) in enumerate(zip(modes_hz, part)))
    bs = bands(hover_rotor_hz, max_rotor_hz)
    flags = []
    for m in modes:
        for b in bs:
            if b.lo_hz * (1 - FLAG_MARGIN) <= m.hz <= b.hi_hz * (1 + FLAG_MARGIN):
                seen = "" if m.fc_participation is None else f"; the flight controller sees {m.fc_participation:.0%} of it"
                if b.name == "attitude controller":
                    why = (f"mode {m.number} at {m.hz:.1f} Hz lies in the attitude controller's band "
                           f"({b.lo_hz:g}-{b.hi_hz:g} Hz): the rate loop feeds it back{seen}")
                else:
                    why = (f"mode {m.number} at {m.hz:.1f} Hz is within {FLAG_MARGIN:.0%} of the {b.name} band "
                           f"({b.lo_hz:.0f}-{b.hi_hz:.0f} Hz, hover to full throttle): the rotors excite it{seen}")
                flags.append(Flag(m.number, m.hz, b.name, m.fc_participation, why))
    filters = _filters(hover_rotor_hz, max_rotor_hz)
    return Resonance(modes, bs, tuple(flags), _advice(tuple(flags), dict(filters)), filters)


def _filters(hover_hz: float, max_hz: float) -> tuple[tuple[str, float], ...]:
    """Gyro and D-term low-pass below the rotors' 1x at hover (the lowest rotor line in flight),
    above the attitude band; the rotor notch tracks from 15 % below hover up to 3x full throttle."""
    top = ATTITUDE_BAND_HZ[1]
    gyro = max(2 * top, min(250.0, round(0.6 * hover_hz)))
    dterm = max(top * 1.5, min(110.0, round(0.3 * hover_hz)))
    return (("gyro_lpf_hz", float(gyro)), ("dterm_lpf_hz", float(dterm)),
            ("rotor_notch_min_hz", float(round(hover_hz * (1 - FLAG_MARGIN)))),
            ("rotor_notch_max_hz", float(round(3 * max_hz))), ("hover_rotor_hz", round(hover_hz, 1)))


def _advice(flags: tuple[Flag, ...], f: dict) -> tuple[tuple[str, tuple[str, ...]], ...]:
    rotor = [x for x in flags if x.band.startswith("rotor")]
    ctrl = [x for x in flags if x.band == "attitude controller"]
    common = []
    if ctrl:
        seen = [x for x in ctrl if x.fc_participation is None or x.fc_participation >= 0.3]
        common.append(f"{len(ctrl)} frame mode(s) sit in the attitude controller's band ({', '.join(f'{x.hz:.1f}' for x in ctrl)} Hz), "
                      f"{len(seen)} of them seen by the gyro: a notch there would cost the loop its phase margin, so "
                      "none is set. Tune with low rate D gains and watch for a wobble at those frequencies in the blackbox "
                      "log; a stiffer core link or arm moves them up.")
    if rotor:
        common.append("mode(s) " + ", ".join(f"{x.hz:.1f} Hz ({x.band})" for x in rotor)
                      + " meet the rotors: a static gyro notch sits on each below.")
    if not flags:
        common.append("no frame mode within 15 % of a rotor band or the attitude controller's band")
    notch = rotor[0] if rotor else None
    inav = [*common, f"rotor noise from {f['rotor_notch_min_hz']:.0f} Hz (1x at hover, less 15 %) up: dynamic gyro notch and, "
            "with ESC telemetry, the RPM filter"]
    bf = [*common, "bidirectional DShot and the RPM filter (3 harmonics) follow the rotors; the dynamic notch covers the rest"]
    ap = [*common, f"throttle-based harmonic notch at the hover rotor frequency {f['hover_rotor_hz']:.0f} Hz, the harmonics and "
                    "gyro rate the flight files' params.parm sets (INS_HNTCH_HMNCS, INS_GYRO_RATE)"]
    px4 = [*common, "PX4: IMU_GYRO_CUTOFF / IMU_DGYRO_CUTOFF as below; dynamic notch from ESC RPM (IMU_GYRO_DNF_EN)"]
    if notch is not None:
        inav.append(f"static notch at {notch.hz:.0f} Hz")
        bf.append(f"static notch at {notch.hz:.0f} Hz")
        ap.append(f"second (fixed) notch at {notch.hz:.0f} Hz")
        px4.append(f"static notch IMU_GYRO_NF0_FRQ = {notch.hz:.0f} Hz")
    return (("inav", tuple(inav)), ("betaflight", tuple(bf)), ("ardupilot", tuple(ap)), ("px4", tuple(px4)))


# -- mode shapes --------------------------------------------------------------------------------

def mode_shapes(spec, design, total_mass_g: float, n: int | None = None) -> tuple[list[float], list[float]]:
    """(frequencies Hz, flight-controller participation) of the first n elastic free-flight modes,
    from the same modal problem as `check`'s `stiffness.modes_hz` (analysis/load_cases._modes:
    rods in 4 elements, the joint models, the play springs of the predicted k), solved densely with
    its mode shapes."""
    from . import drop as drop_mod
    from . import stiffness as st
    from .load_cases import N_MODES

    n = N_MODES if n is None else n
    frame, parts = design.frame, design.parts
    session = drop_mod.Session(spec, frame, parts)
    play = None
    if spec.model.k_n_per_m is None:  # as drop.load_cases: the predicted k's play springs
        play = {k: np.asarray(v, float) for k, v in drop_mod._secant(spec, frame, session)["play"].items()} or None
    masses = st.masses_g(spec, frame, parts, total_mass_g)
    mdl = st.build_model(spec, frame, parts, session.joints, rod_segments=4, masses=masses, play=play)
    fe = mdl.fe
    K = fe.stiffness(sparse=True)
    M = fe.mass(sparse=True)
    keep = np.abs(K.diagonal()) > 1e-12
    K, M = K[keep][:, keep].tocsc(), M[keep][:, keep].tocsc()
    from scipy.sparse import diags

    M = (M + diags(np.where(M.diagonal() <= 0, 1e-12, 0.0))).tocsc()  # as load_cases._modal_matrices
    w2, vecs = _lowest_modes(K, M, 6 + n)
    full = np.zeros((keep.size, vecs.shape[1]))
    full[keep] = vecs
    idx = fe.index()

    def rot(node: str, j: int) -> np.ndarray:
        i = 6 * idx[node]
        return full[i + 3:i + 6, j]

    motor_nodes = [[f"{rn}:motor" for rn in m.arm if f"{rn}:motor" in idx] for m in frame.motors]
    hz, part = [], []
    for j in range(6, 6 + n):
        hz.append(round(math.sqrt(max(float(w2[j]), 0.0)) / (2 * math.pi), 2))
        fc = float(np.linalg.norm(rot(mdl.payload, j)))
        tilt = max(float(np.linalg.norm(np.mean([rot(nn, j)[:2] for nn in nodes], axis=0))) for nodes in motor_nodes)
        part.append(fc / max(fc, tilt) if max(fc, tilt) > 0 else 0.0)
    return hz, part


def _lowest_modes(K, M, count: int):
    """The `count` lowest eigenpairs of K x = lambda M x, ascending: shift-invert Lanczos with the
    shift and factors of framefe.lowest_eigenvalues (below the rigid-body modes, so the low end
    is the well-conditioned one), the dense solver where Lanczos does not converge."""
    from scipy.sparse.linalg import ArpackNoConvergence, LinearOperator, eigsh

    from .framefe import _shift, factor

    sigma = _shift(K, M)
    lu = factor(K - sigma * M)
    op = LinearOperator(K.shape, matvec=lambda x: lu.solve(np.ravel(x)), dtype=float)
    v0 = np.random.default_rng(0).standard_normal(K.shape[0])  # deterministic
    try:
        w, v = eigsh(K, k=count, M=M, sigma=sigma, OPinv=op, which="LM", v0=v0, tol=1e-10)
    except ArpackNoConvergence:
        import scipy.linalg

        return scipy.linalg.eigh(K.toarray(), M.toarray(), subset_by_index=[0, count - 1])
    order = np.argsort(w)
    return w[order], v[:, order]
