#!/usr/bin/env python3
"""Train the joint surrogate (`model.stiffness_model: surrogate`) from the solid FE.

    python tools/train_joint_surrogate.py [--work DIR] [--train 96] [--holdout 16] [--seed 26]
                                          [--jobs 2] [--scheduler ADDR]

1. Design of experiments: a Latin hypercube (scipy.stats.qmc, fixed seed) over the design box
   `BOX` around the carbon preset -- everything that shapes a joint: rod diameter, wall, socket
   depth, fit clearance, layer height, hinge thickness, and the frame's shape, which sets the
   socket angles (height, knee inset and height, width, depth, arm spacing, core plate size).
   Designs that do not validate are skipped. A second hypercube (another seed) is the held-out
   set: joints the fit never sees.
2. The solid FE (`joints.fe_joint`, factor 1) of every distinct, non-mirrored joint of every
   design: on `--jobs` local processes, or on a Dask cluster (`--scheduler tcp://host:8786`; the
   workers write into --work and read this checkout's params/carbon.yaml: a shared filesystem).
   Each result is kept in DIR/fe/<hash>.json (the hash of the part's geometry and interface), so
   a rerun solves only what is missing.
3. The fit (`joints.surrogate.fit`), written to cogniframe/data/joint_surrogate.json, and the
   held-out set (each held-out design's overrides, its joints' FE matrices, and the frame k with
   the FE joints) to tests/data/joint_surrogate_holdout.json, with the surrogate's errors on it.

Same inputs, same bytes: the designs, the FE (one BLAS thread) and the fit are deterministic.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

BASE = ROOT / "params" / "carbon.yaml"
# The training box: every sweep of the examples and both presets lie inside it.
BOX = {
    "rods.diameter": (2.5, 4.0),
    "joints.wall": (1.2, 2.2),
    "joints.socket_depth": (8.0, 14.0),
    "joints.fit_clearance.tpu_95a": (-0.30, 0.25),
    "printer.layer_height": (0.12, 0.28),
    "joints.hinge_thickness": (0.8, 2.0),
    "frame.height": (100.0, 145.0),
    "frame.knee_inset": (4.0, 16.0),
    "frame.knee_height": (0.42, 0.58),
    "frame.width": (200.0, 250.0),
    "frame.depth": (200.0, 250.0),
    "frame.arm_spacing": (10.0, 30.0),
    "core.plate_size": (36.0, 44.0),
}
HOLDOUT_SEED_OFFSET = 1000
TRAIN_BATCH = 96


def base_params() -> dict:
    import yaml

    return yaml.safe_load(BASE.read_text())


def designs(n: int, seed: int) -> list[dict]:
    """`n` valid designs (overrides of the base) from a Latin hypercube over `BOX`: drawn in
    rounds of 2n until n validate (the first n valid ones, in order)."""
    from scipy.stats import qmc

    keys = list(BOX)
    lo = [BOX[k][0] for k in keys]
    hi = [BOX[k][1] for k in keys]
    out: list[dict] = []
    rnd = 0
    while len(out) < n:
        u = qmc.LatinHypercube(d=len(keys), seed=seed + 7919 * rnd).random(2 * n)
        for row in qmc.scale(u, lo, hi):
            ov = {k: round(float(v), 3) for k, v in zip(keys, row)}
            if valid(ov):
                out.append(ov)
                if len(out) == n:
                    break
        rnd += 1
    return out


def design_parts(overrides: dict):
    from cogniframe import frame, partlist, spec
    from cogniframe.sweep.evaluate import apply_overrides

    s = spec.from_dict(apply_overrides(base_params(), overrides))
    f = frame.frame_of(s)
    return s, f, partlist.part_list(s, f)


def valid(overrides: dict) -> bool:
    try:
        design_parts(overrides)
    except Exception:  # noqa: BLE001 - any refusal (validation, a frame that does not close) skips the design
        return False
    return True


def fe_key(s, part) -> str:
    from cogniframe.analysis.joints.model import interface

    itf = interface(s, 1.0)
    return hashlib.sha256(json.dumps([part.digest, itf.e, itf.g, itf.h, s.rods.diameter]).encode()).hexdigest()[:24]


def solve_design(overrides: dict, work: str) -> list[str]:
    """A task: the FE of every distinct non-mirrored joint of one design, into work/fe/ (skips
    what is there). Returns the keys."""
    from cogniframe.analysis.joints import fe_joint, is_mirror

    s, _, parts = design_parts(overrides)
    keys = []
    for p in parts:
        if p.family != "joint" or is_mirror(p):
            continue
        key = fe_key(s, p)
        path = Path(work) / "fe" / f"{key}.json"
        keys.append(key)
        if path.exists():
            continue
        try:
            unit = fe_joint(s, p, 1.0).to_json()
        except RuntimeError as exc:
            unit = {"error": str(exc)}
        unit["overrides"] = overrides
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps(unit, sort_keys=True))
        tmp.replace(path)
    return keys


def solved(overrides: dict, work: Path) -> bool:
    from cogniframe.analysis.joints import is_mirror

    s, _, parts = design_parts(overrides)
    return all((work / "fe" / f"{fe_key(s, p)}.json").exists() for p in parts if p.family == "joint" and not is_mirror(p))


def run_doe(todo: list[dict], work: Path, jobs: int, scheduler: str | None) -> None:
    t0 = time.perf_counter()
    if scheduler:
        from distributed import Client, as_completed

        with Client(scheduler) as client:
            futs = [client.submit(solve_design, ov, str(work), pure=False) for ov in todo]
            for i, f in enumerate(as_completed(futs), 1):
                f.result()
                print(f"doe {i}/{len(todo)} designs, {time.perf_counter() - t0:.0f} s", flush=True)
        return
    if jobs <= 1:
        for i, ov in enumerate(todo, 1):
            solve_design(ov, str(work))
            print(f"doe {i}/{len(todo)} designs, {time.perf_counter() - t0:.0f} s", flush=True)
        return
    from concurrent.futures import ProcessPoolExecutor, as_completed as done
    import multiprocessing as mp

    with ProcessPoolExecutor(jobs, mp_context=mp.get_context("spawn")) as ex:
        futs = [ex.submit(solve_design, ov, str(work)) for ov in todo]
        for i, f in enumerate(done(futs), 1):
            f.result()
            print(f"doe {i}/{len(todo)} designs, {time.perf_counter() - t0:.0f} s", flush=True)


def samples(overrides_list: list[dict], work: Path) -> list[dict]:
    """Per design and non-mirrored joint: its part, features, FE unit (factor 1) and log target."""
    from cogniframe.analysis.joints import is_mirror
    from cogniframe.analysis.joints import surrogate as sg
    from cogniframe.analysis.joints.model import JointStiffness, tpu_moduli

    out = []
    for ov in overrides_list:
        s, f, parts = design_parts(ov)
        for p in parts:
            if p.family != "joint" or is_mirror(p):
                continue
            path = work / "fe" / f"{fe_key(s, p)}.json"
            if not path.exists():
                raise SystemExit(f"{path}: not solved (run without --fit-only)")
            d = json.loads(path.read_text())
            if "error" in d:
                print(f"skipped {p.name} of {ov}: {d['error']}")
                continue
            unit = JointStiffness.from_json(d)
            names, x = sg.features(s, p)
            e = tpu_moduli(s, 1.0)[0]
            out.append({"overrides": ov, "kind": sg.family_of(p), "part": p, "spec": s, "unit": unit, "names": names,
                        "x": x, "y": sg.log_target(unit, p, e), "e": e})
    return out


def joint_error(k_pred, k_fe) -> dict:
    """Relative errors of a predicted super-element against the FE's, rotations scaled by
    surrogate.LENGTH_MM: Frobenius, the worst diagonal entry, and the energy bound (the largest
    |u^T K_pred u / u^T K_fe u - 1| over the deformations, rigid motions excluded)."""
    from cogniframe.analysis.joints import surrogate as sg
    import numpy as np

    n = k_fe.shape[0] // 6
    sc = sg._scaling(n)
    a, b = k_pred / np.outer(sc, sc), k_fe / np.outer(sc, sc)
    m = 6 * (n - 1)
    aa, bb = a[:m, :m], b[:m, :m]  # the last body held: the rigid modes drop out
    w, v = np.linalg.eigh(bb)
    ih = (v / np.sqrt(w)) @ v.T
    ev = np.linalg.eigvalsh(ih @ aa @ ih)
    return {"frobenius": float(np.linalg.norm(a - b) / np.linalg.norm(b)),
            "diagonal": float(np.max(np.abs(np.diag(a) / np.diag(b) - 1))),
            "energy": float(np.max(np.abs(ev - 1)))}


def frame_k(s, f, parts, units: dict) -> float:
    """The frame's secant k (N/m) with the given factor-1 originals' units; mirrors reflected from them."""
    from cogniframe.analysis import stiffness
    from cogniframe.analysis.joints import is_mirror, mirror_original, reflect_unit
    from cogniframe.analysis.joints.model import TPU_PRINTED_MODULUS_FACTOR, JointStiffness

    joints = {}
    fac = TPU_PRINTED_MODULUS_FACTOR
    for p in parts:
        if p.family != "joint":
            continue
        if is_mirror(p):
            o, P, order = mirror_original(p, parts)
            u = reflect_unit(units[o.name], p, P, order, [x.rod for x in o.sockets])
        else:
            u = units[p.name]
        joints[p.name] = JointStiffness(u.name, u.method, u.labels, u.refs, tuple(map(tuple, (fac * u.matrix).tolist())),
                                        u.n_dofs, 0.0)
    return stiffness.secant_solution(s, f, parts, joints).k_n_per_m


def fit_and_write(train: list[dict], hold: list[dict], work: Path, data_out: Path | None = None,
                  holdout_out: Path | None = None) -> int:
    import numpy as np

    from cogniframe.analysis.joints import surrogate as sg

    data_out = data_out or sg.DATA_FILE
    holdout_out = holdout_out or ROOT / "tests" / "data" / "joint_surrogate_holdout.json"
    tr = samples(train, work)
    kinds = sorted({r["kind"] for r in tr})
    fams = {}
    for kind in kinds:
        rows = [r for r in tr if r["kind"] == kind]
        names = rows[0]["names"]
        rows = [r for r in rows if r["names"] == names]
        X = np.array([r["x"] for r in rows])
        Y = np.array([r["y"] for r in rows])
        fam, loo = sg.fit_family(kind, rows[0]["unit"].labels, names, X, Y)
        fams[kind] = fam
        print(f"{kind}: {len(rows)} samples, {sum(f is None for f in fam.fixed)} varying features, "
              f"{len(fam.scale)} components, quadratic in the first {fam.quadratic}, ridge {fam.ridge:g}, "
              f"LOO RMS of the log entries {min(loo.values()):.4f}")
    meta = {"base": "params/carbon.yaml", "box": BOX, "train_designs": len(train), "length_mm": sg.LENGTH_MM,
            "tool": "tools/train_joint_surrogate.py"}
    # 7 significant digits: log-stiffness coefficients to 1e-7, far below the FE's own scatter
    doc = {"meta": meta, "families": {k: _rounded(fams[k].to_json()) for k in kinds}}
    text = json.dumps(doc, sort_keys=True, indent=None, separators=(",", ":")) + "\n"
    data_out.write_text(text)
    digest = hashlib.sha256(text.encode()).hexdigest()
    _pin_digest(digest)
    sg._load.cache_clear()
    print(f"wrote {data_out} ({len(text) / 1024:.0f} kB, sha256 {digest[:16]})")
    fams = sg.families(data_out)  # what the package reads: the rounded numbers
    # held-out: per joint and frame k
    ho = samples(hold, work)
    per_joint, frames = [], []
    by_design: dict[str, dict] = {}
    for r in ho:
        fam = fams[r["kind"]]
        pred = fam.basis(r["x"][None, :]) @ np.asarray(fam.coef)
        kp = sg.matrix_from_log(pred[0], r["part"], r["unit"].labels, r["e"])
        err = joint_error(kp, r["unit"].matrix)
        why = sg.out_of_box(fam, r["names"], r["x"])
        per_joint.append({"design": hold.index(r["overrides"]), "part": r["part"].name, "outside": why, **err})
        by_design.setdefault(json.dumps(r["overrides"], sort_keys=True), {})[r["part"].name] = (r["unit"], kp)
    for i, ov in enumerate(hold):
        got = by_design.get(json.dumps(ov, sort_keys=True))
        if not got:
            continue
        s, f, parts = design_parts(ov)
        from cogniframe.analysis.joints.model import JointStiffness

        fe_units = {n: u for n, (u, _) in got.items()}
        sur_units = {n: JointStiffness(u.name, "surrogate", u.labels, u.refs, tuple(map(tuple, kp.tolist())))
                     for n, (u, kp) in got.items()}
        k_fe, k_sur = frame_k(s, f, parts, fe_units), frame_k(s, f, parts, sur_units)
        frames.append({"design": i, "overrides": ov, "k_fe": k_fe, "k_surrogate": k_sur, "error": k_sur / k_fe - 1,
                       "joints": {n: compact(u) for n, u in fe_units.items()}})
    inside = [j for j in per_joint if j["outside"] is None]
    for key in ("frobenius", "diagonal", "energy"):
        v = np.array([j[key] for j in inside])
        print(f"held-out joints ({len(v)} inside the box), {key}: median {np.median(v):.4f}, worst {v.max():.4f}")
    ke = np.abs([fr["error"] for fr in frames])
    print(f"held-out frame k ({len(ke)} designs): median |error| {np.median(ke):.4f}, worst {ke.max():.4f}")
    holdout_out.parent.mkdir(parents=True, exist_ok=True)
    hd = {"meta": {**meta, "holdout_designs": len(hold), "data_sha256": digest}, "designs": frames,
          "joint_errors": per_joint}
    holdout_out.write_text(json.dumps(hd, sort_keys=True, separators=(",", ":")) + "\n")
    print(f"wrote {holdout_out}")
    return 0


def _rounded(v):
    if isinstance(v, float):
        return float(f"{v:.7g}")
    if isinstance(v, (list, tuple)):
        return [_rounded(x) for x in v]
    if isinstance(v, dict):
        return {k: _rounded(x) for k, x in v.items()}
    return v


def compact(unit) -> dict:
    """A factor-1 FE unit for the held-out file: labels, refs and the upper triangle of K to 7
    significant digits (the tests compare at per cent level)."""
    import numpy as np

    K = unit.matrix
    tri = K[np.triu_indices(K.shape[0])]
    return {"name": unit.name, "labels": list(unit.labels), "refs": [list(r) for r in unit.refs],
            "triu": [float(f"{v:.7g}") for v in tri]}


def _pin_digest(digest: str) -> None:
    """Write the data file's sha256 into surrogate.py: the package refuses a data file that is not
    the one its code was released with, and every cache key over the package's source changes."""
    import re

    from cogniframe.analysis.joints import surrogate as sg

    src = Path(sg.__file__)
    text = src.read_text()
    new = re.sub(r'^DATA_SHA256 = "[0-9a-f]*"', f'DATA_SHA256 = "{digest}"', text, count=1, flags=re.M)
    if new != text:
        src.write_text(new)
    sg.DATA_SHA256 = digest  # this process's copy of the module too


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--work", type=Path, default=Path("/tmp/joint-surrogate"))
    ap.add_argument("--train", type=int, default=96)
    ap.add_argument("--holdout", type=int, default=16)
    ap.add_argument("--seed", type=int, default=26)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--scheduler", default=None)
    ap.add_argument("--doe-only", action="store_true", help="solve the FE, do not fit")
    ap.add_argument("--fit-only", action="store_true", help="fit on the solved designs only (skips the rest)")
    a = ap.parse_args(argv)
    a.work.mkdir(parents=True, exist_ok=True)
    # training designs in hypercubes of TRAIN_BATCH (seeds seed, seed + 1, ...): a larger --train
    # keeps every design a smaller one solved
    train = [ov for b in range(-(-a.train // TRAIN_BATCH)) for ov in designs(TRAIN_BATCH, a.seed + b)][:a.train]
    hold = designs(a.holdout, a.seed + HOLDOUT_SEED_OFFSET)
    # held-out designs first: the acceptance set is complete even when training is cut short
    if a.fit_only:
        train = [ov for ov in train if solved(ov, a.work)]
        print(f"fit on the {len(train)} solved training designs")
    else:
        run_doe(hold + train, a.work, a.jobs, a.scheduler)
    if a.doe_only:
        return 0
    from cogniframe.analysis.numerics import one_blas_thread

    with one_blas_thread():  # the same bits of the fit on any machine (BLAS sums in a fixed order)
        return fit_and_write(train, hold, a.work)


if __name__ == "__main__":
    raise SystemExit(main())
