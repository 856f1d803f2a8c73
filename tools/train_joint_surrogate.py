#!/usr/bin/env python3
"""Train the joint surrogate (`model.stiffness_model: surrogate`) from the solid FE.

    python tools/train_joint_surrogate.py [--work DIR] [--train 96] [--holdout 16] [--seed 26]
                                          [--jobs 2] [--scheduler ADDR] [--core-link tab|pegs]
                                          [--family NAME ...] [--data FILE] [--holdout-file FILE]
    python tools/train_joint_surrogate.py --refresh-k

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

`--core-link` sets the base's `core.link` for every design (default: the base file's own).
`--family NAME` (repeatable; a `surrogate.family_of` name, e.g. `core_link_pegs`) trains only those
families: the same hypercubes, but only their joints are solved and fitted, and the result is
merged into the existing data file (`--data`): every other family's fit is copied as it is, and
`meta.families` records per family the base, core link, box, seed and number of designs it was
trained on. The held-out file (`--holdout-file`) keeps the full run's designs, predicted again
where they have a joint of a retrained family, and gains the family's own section (`families`):
its held-out joints' FE and errors, and the frame k it gives with the other joints from the
surrogate (they are not solved). A family's DOE solves one joint per design, not four:

    python tools/train_joint_surrogate.py --family core_link_pegs --core-link pegs --train 192

`--refresh-k` only recomputes every held-out design's frame k (the full run's and each family
section's) at the package's TPU factor, from the stored FE matrices and the shipped fit: frame k
is the one held-out figure that depends on the factor, so after a new calibration this is all that
needs to run (the file records the factor it was computed at, and a test holds it to the package's).

The package's sha256 pin (`surrogate.DATA_SHA256`) is rewritten only when `--data` is the package's
data file: a copy elsewhere (the tests') leaves the package as it is.

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


def base_params(core_link: str | None = None) -> dict:
    """The base file, its core link set to `core_link` (None: the file's own)."""
    import yaml

    data = yaml.safe_load(BASE.read_text())
    if core_link is not None:
        data.setdefault("core", {})["link"] = core_link
    return data


def base_link(core_link: str | None = None) -> str:
    """The core link the DOE's designs have: `core_link`, else the base file's, else the spec's default."""
    from cogniframe.spec import CoreSection

    if core_link is not None:
        return core_link
    return str((base_params().get("core") or {}).get("link", CoreSection.model_fields["link"].default))


def known_families() -> tuple[str, ...]:
    """Every family `surrogate.family_of` can name: each registered joint kind's (the tab and the
    flat core link share one)."""
    from cogniframe.families.joint_kinds.kinds import KINDS

    return tuple(dict.fromkeys(k.surrogate_family for k in KINDS))


def designs(n: int, seed: int, core_link: str | None = None) -> list[dict]:
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
            if valid(ov, core_link):
                out.append(ov)
                if len(out) == n:
                    break
        rnd += 1
    return out


def design_parts(overrides: dict, core_link: str | None = None):
    from cogniframe import frame, partlist, spec
    from cogniframe.sweep.evaluate import apply_overrides

    s = spec.from_dict(apply_overrides(base_params(core_link), overrides))
    f = frame.frame_of(s)
    return s, f, partlist.part_list(s, f)


def valid(overrides: dict, core_link: str | None = None) -> bool:
    try:
        design_parts(overrides, core_link)
    except Exception:  # noqa: BLE001 - any refusal (validation, a frame that does not close) skips the design
        return False
    return True


def fe_key(s, part) -> str:
    from cogniframe.analysis.joints.model import interface

    itf = interface(s, 1.0)
    return hashlib.sha256(json.dumps([part.digest, itf.e, itf.g, itf.h, s.rods.diameter]).encode()).hexdigest()[:24]


def wanted(part, fams) -> bool:
    """Whether the DOE solves and fits `part`: a non-mirrored joint of a requested family (None: all)."""
    from cogniframe.analysis.joints import is_mirror
    from cogniframe.analysis.joints.surrogate import family_of

    return part.family == "joint" and not is_mirror(part) and (fams is None or family_of(part) in fams)


def solve_design(overrides: dict, work: str, core_link: str | None = None, fams=None) -> list[str]:
    """A task: the FE of every distinct non-mirrored joint of one design (of the families `fams`,
    None: all), into work/fe/ (skips what is there). Returns the keys."""
    from cogniframe.analysis.joints import fe_joint

    s, _, parts = design_parts(overrides, core_link)
    keys = []
    for p in parts:
        if not wanted(p, fams):
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


def solved(overrides: dict, work: Path, core_link: str | None = None, fams=None) -> bool:
    s, _, parts = design_parts(overrides, core_link)
    return all((work / "fe" / f"{fe_key(s, p)}.json").exists() for p in parts if wanted(p, fams))


def run_doe(todo: list[dict], work: Path, jobs: int, scheduler: str | None, core_link: str | None = None,
            fams=None) -> None:
    t0 = time.perf_counter()
    if scheduler:
        from distributed import Client, as_completed

        with Client(scheduler) as client:
            futs = [client.submit(solve_design, ov, str(work), core_link, fams, pure=False) for ov in todo]
            for i, f in enumerate(as_completed(futs), 1):
                f.result()
                print(f"doe {i}/{len(todo)} designs, {time.perf_counter() - t0:.0f} s", flush=True)
        return
    if jobs <= 1:
        for i, ov in enumerate(todo, 1):
            solve_design(ov, str(work), core_link, fams)
            print(f"doe {i}/{len(todo)} designs, {time.perf_counter() - t0:.0f} s", flush=True)
        return
    from concurrent.futures import ProcessPoolExecutor, as_completed as done
    import multiprocessing as mp

    with ProcessPoolExecutor(jobs, mp_context=mp.get_context("spawn")) as ex:
        futs = [ex.submit(solve_design, ov, str(work), core_link, fams) for ov in todo]
        for i, f in enumerate(done(futs), 1):
            f.result()
            print(f"doe {i}/{len(todo)} designs, {time.perf_counter() - t0:.0f} s", flush=True)


def samples(overrides_list: list[dict], work: Path, core_link: str | None = None, fams=None) -> list[dict]:
    """Per design and non-mirrored joint (of the families `fams`, None: all): its part, features,
    FE unit (factor 1) and log target."""
    from cogniframe.analysis.joints import surrogate as sg
    from cogniframe.analysis.joints.model import JointStiffness, tpu_moduli

    out = []
    for ov in overrides_list:
        s, f, parts = design_parts(ov, core_link)
        for p in parts:
            if not wanted(p, fams):
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


def fit_families(tr: list[dict]) -> dict:
    """{family: its fit} from training samples (`samples`), each on the samples with the first one's features."""
    import numpy as np

    from cogniframe.analysis.joints import surrogate as sg

    fams = {}
    for kind in sorted({r["kind"] for r in tr}):
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
    return fams


def legacy_record(meta: dict) -> dict:
    """The training record of a family in a data file written before per-family records: every
    family of such a file was trained in one run on the file's base with the bolted tab, the only
    core link there was."""
    return {"base": meta["base"], "box": meta["box"], "core_link": meta.get("core_link", "tab"),
            "train_designs": meta["train_designs"]}


def merge_data(old: dict, new: dict, record: dict) -> dict:
    """The data file's document with the families `new` ({name: fit as JSON}) fitted now and every
    other family of `old` as it was (the same JSON values); `meta.families` says per family what
    it was trained on (`record` for the new ones). The top-level meta stays the full run's."""
    meta = dict(old["meta"])
    per = dict(meta.get("families") or {k: legacy_record(meta) for k in old["families"]})
    per.update(dict.fromkeys(new, record))
    families = {**old["families"], **new}
    meta["families"] = {k: per[k] for k in families}
    return {"meta": meta, "families": families}


def merge_holdout(old: dict, sections: dict, digest: str) -> dict:
    """The held-out document with a section per family trained on its own (`sections`: {name:
    {"meta", "joints", "designs"}}, replacing any earlier one) and the data file's new sha256; the
    full run's designs and joint errors as `old` has them (`refresh_main` updates the ones a new fit
    predicts)."""
    import copy

    out = copy.deepcopy(old)
    out["meta"] = {**old["meta"], "data_sha256": digest}
    out["families"] = {**old.get("families", {}), **sections}
    return out


def predicted(fam, s, part, labels, e: float):
    """A family's super-element for a joint (factor 1), the box not checked: what the held-out
    errors measure."""
    import numpy as np

    from cogniframe.analysis.joints import surrogate as sg

    _, x = sg.features(s, part)
    return sg.matrix_from_log((fam.basis(x[None, :]) @ np.asarray(fam.coef))[0], part, labels, e)


def family_frames(hold: list[dict], mine: dict, kind: str, data_out: Path, core_link: str | None) -> list[dict]:
    """Per held-out design, the frame k with the `kind` joints (`mine`: {(design, family): {part:
    (FE unit, predicted K)}}) from the FE and from the new fit, every other joint from the data
    file's surrogate in both: what the family's own error does to the frame k. A design with another
    joint outside its family's box (it would need the FE) is left out."""
    from cogniframe.analysis.joints import surrogate as sg
    from cogniframe.analysis.joints.model import JointStiffness

    out = []
    for i, ov in enumerate(hold):
        own = mine.get((i, kind))
        if not own:
            continue
        s, f, parts = design_parts(ov, core_link)
        others = {p.name: sg.predict(s, p, 1.0, path=data_out)[0] for p in parts if wanted(p, None) and p.name not in own}
        if any(u is None for u in others.values()):
            continue
        fe = {**others, **{n: u for n, (u, _) in own.items()}}
        sur = {**others, **{n: JointStiffness(u.name, "surrogate", u.labels, u.refs, tuple(map(tuple, kp.tolist())))
                            for n, (u, kp) in own.items()}}
        k_fe, k_sur = frame_k(s, f, parts, fe), frame_k(s, f, parts, sur)
        out.append({"design": i, "k_family_fe": k_fe, "k_surrogate": k_sur, "error": k_sur / k_fe - 1})
    return out


def refresh_main(hd: dict, fams: dict, requested) -> None:
    """Predict again, with the new fits `fams`, the full run's held-out joints of the `requested`
    families (from their stored FE matrices), and the frame k of every design that has one, from
    the FE and from the fits, at the package's TPU factor: the held-out set keeps describing the
    shipped fit."""
    from cogniframe.analysis.joints import surrogate as sg
    from cogniframe.analysis.joints.model import JointStiffness, tpu_moduli

    link = hd["meta"].get("core_link", "tab")
    rows = {(j["design"], j["part"]): j for j in hd["joint_errors"]}
    for fr in hd["designs"]:
        s, f, parts = design_parts(fr["overrides"], link)
        by_name = {p.name: p for p in parts if wanted(p, None)}
        if not any(sg.family_of(by_name[n]) in requested for n in fr["joints"]):
            continue
        e = tpu_moduli(s, 1.0)[0]
        sur, fes = {}, {}
        for n, c in fr["joints"].items():
            p, kind = by_name[n], sg.family_of(by_name[n])
            fe = fes[n] = unpacked(c)
            kp = predicted(fams[kind], s, p, fe.labels, e)
            sur[n] = JointStiffness(n, "surrogate", fe.labels, fe.refs, tuple(map(tuple, kp.tolist())))
            if kind in requested and (fr["design"], n) in rows:
                row = rows[(fr["design"], n)]
                row.update(joint_error(kp, fe.matrix), outside=sg.out_of_box(fams[kind], *sg.features(s, p)))
        # both at today's TPU factor: frame k is the held-out figure a new calibration moves
        fr["k_fe"] = frame_k(s, f, parts, fes)
        fr["k_surrogate"] = frame_k(s, f, parts, sur)
        fr["error"] = fr["k_surrogate"] / fr["k_fe"] - 1


def refresh_k(hd: dict, data: Path | None = None) -> None:
    """Every held-out design's frame k again, at the package's TPU factor, from its stored FE
    matrices and the fit in `data` (no FE solved, nothing refitted): frame k is the one held-out
    figure that depends on the factor, so a new calibration needs this and nothing else. Records
    the factor in the file's meta."""
    from cogniframe.analysis.joints import surrogate as sg
    from cogniframe.analysis.joints.model import TPU_PRINTED_MODULUS_FACTOR, tpu_moduli

    fams = sg.families(data or sg.DATA_FILE)
    refresh_main(hd, fams, set(fams))
    for kind, sec in hd.get("families", {}).items():
        link = sec["meta"]["core_link"]
        hold: list = [None] * sec["meta"]["holdout_designs"]
        mine: dict = {}
        for j in sec["joints"]:
            s, _, parts = design_parts(j["overrides"], link)
            p = next(p for p in parts if p.name == j["part"])
            u = unpacked(j["fe"])
            hold[j["design"]] = j["overrides"]
            mine.setdefault((j["design"], kind), {})[p.name] = (u, predicted(fams[kind], s, p, u.labels, tpu_moduli(s, 1.0)[0]))
        sec["designs"] = family_frames(hold, mine, kind, data or sg.DATA_FILE, link)
    hd["meta"]["tpu_factor"] = TPU_PRINTED_MODULUS_FACTOR


def fit_and_write(train: list[dict], hold: list[dict], work: Path, data_out: Path | None = None,
                  holdout_out: Path | None = None, core_link: str | None = None, fams=None, seed: int | None = None) -> int:
    """Fit, write the data file (pinning its sha256 when it is the package's) and the held-out file.
    With `fams` (family names) only those are fitted, from their joints alone, and merged into the
    existing files (`merge_data`, `merge_holdout`)."""
    from cogniframe.analysis.joints import surrogate as sg
    from cogniframe.analysis.joints.model import TPU_PRINTED_MODULUS_FACTOR

    data_out = Path(data_out or sg.DATA_FILE)
    holdout_out = Path(holdout_out or ROOT / "tests" / "data" / "joint_surrogate_holdout.json")
    try:
        fitted = fit_families(samples(train, work, core_link, fams))
    except ValueError as exc:  # too few designs for a family (a short --train)
        print(f"train_joint_surrogate: {exc}; raise --train; nothing written", file=sys.stderr)
        return 2
    if fams is not None and set(fams) - set(fitted):
        print(f"train_joint_surrogate: no FE solve of a {', '.join(sorted(set(fams) - set(fitted)))} joint succeeded "
              f"(see the errors in {work / 'fe'}); nothing written", file=sys.stderr)
        return 2
    link = base_link(core_link)
    base = BASE.relative_to(ROOT).as_posix()
    record = {"base": base, "box": BOX, "core_link": link, "seed": seed, "train_designs": len(train)}
    # 7 significant digits: log-stiffness coefficients to 1e-7, far below the FE's own scatter
    new = {k: _rounded(v.to_json()) for k, v in fitted.items()}
    if fams is None:
        meta = {"base": base, "box": BOX, "core_link": link, "train_designs": len(train), "length_mm": sg.LENGTH_MM,
                "tool": "tools/train_joint_surrogate.py", "families": dict.fromkeys(new, record)}
        doc = {"meta": meta, "families": new}
    else:
        doc = merge_data(json.loads(data_out.read_text()), new, record)
    text = json.dumps(doc, sort_keys=True, indent=None, separators=(",", ":")) + "\n"
    data_out.write_text(text)
    digest = hashlib.sha256(text.encode()).hexdigest()
    if data_out.resolve() == Path(sg.DATA_FILE).resolve():  # a copy elsewhere is not what the package reads
        _pin_digest(digest)
    sg._load.cache_clear()
    print(f"wrote {data_out} ({len(text) / 1024:.0f} kB, sha256 {digest[:16]})")
    loaded = sg.families(data_out)  # what the package reads: the rounded numbers
    # held-out: per joint and frame k
    ho = samples(hold, work, core_link, fams)
    per_joint, frames = [], []
    by_design: dict[str, dict] = {}
    mine: dict[tuple, dict] = {}  # {(design, family): {part: (FE unit, predicted K)}}
    for r in ho:
        fam = loaded[r["kind"]]
        kp = predicted(fam, r["spec"], r["part"], r["unit"].labels, r["e"])
        err = joint_error(kp, r["unit"].matrix)
        why = sg.out_of_box(fam, r["names"], r["x"])
        per_joint.append({"design": hold.index(r["overrides"]), "part": r["part"].name, "outside": why, **err})
        by_design.setdefault(json.dumps(r["overrides"], sort_keys=True), {})[r["part"].name] = (r["unit"], kp)
        mine.setdefault((per_joint[-1]["design"], r["kind"]), {})[r["part"].name] = (r["unit"], kp)
    if fams is not None:
        # a family's own section: its joints' FE and errors, and the frame k it gives (the other
        # joints of these designs are not solved: they come from the surrogate)
        sections = {k: {"meta": {**record, "holdout_designs": len(hold)},
                        "joints": [{**j, "overrides": hold[j["design"]], "fe": compact(r["unit"])}
                                   for j, r in zip(per_joint, ho) if r["kind"] == k],
                        "designs": family_frames(hold, mine, k, data_out, core_link)} for k in fams}
        hd = merge_holdout(json.loads(holdout_out.read_text()), sections, digest)
        refresh_main(hd, loaded, set(fams))
        hd["meta"]["tpu_factor"] = TPU_PRINTED_MODULUS_FACTOR
        _report(per_joint, [fr for sec in sections.values() for fr in sec["designs"]])
        holdout_out.write_text(json.dumps(hd, sort_keys=True, separators=(",", ":")) + "\n")
        print(f"wrote {holdout_out}")
        return 0
    for i, ov in enumerate(hold):
        got = by_design.get(json.dumps(ov, sort_keys=True))
        if not got:
            continue
        s, f, parts = design_parts(ov, core_link)
        from cogniframe.analysis.joints.model import JointStiffness

        fe_units = {n: u for n, (u, _) in got.items()}
        sur_units = {n: JointStiffness(u.name, "surrogate", u.labels, u.refs, tuple(map(tuple, kp.tolist())))
                     for n, (u, kp) in got.items()}
        k_fe, k_sur = frame_k(s, f, parts, fe_units), frame_k(s, f, parts, sur_units)
        frames.append({"design": i, "overrides": ov, "k_fe": k_fe, "k_surrogate": k_sur, "error": k_sur / k_fe - 1,
                       "joints": {n: compact(u) for n, u in fe_units.items()}})
    _report(per_joint, frames)
    holdout_out.parent.mkdir(parents=True, exist_ok=True)
    hd = {"meta": {**{k: v for k, v in meta.items() if k != "families"}, "holdout_designs": len(hold),
                   "data_sha256": digest, "tpu_factor": TPU_PRINTED_MODULUS_FACTOR}, "designs": frames,
          "joint_errors": per_joint}
    holdout_out.write_text(json.dumps(hd, sort_keys=True, separators=(",", ":")) + "\n")
    print(f"wrote {holdout_out}")
    return 0


def _report(per_joint: list[dict], frames: list[dict]) -> None:
    import numpy as np

    inside = [j for j in per_joint if j["outside"] is None]
    for key in ("frobenius", "diagonal", "energy"):
        v = np.array([j[key] for j in inside])
        if len(v):
            print(f"held-out joints ({len(v)} inside the box), {key}: median {np.median(v):.4f}, worst {v.max():.4f}")
    if frames:
        ke = np.abs([fr["error"] for fr in frames])
        print(f"held-out frame k ({len(ke)} designs): median |error| {np.median(ke):.4f}, worst {ke.max():.4f}")


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


def unpacked(c: dict):
    """The FE unit (factor 1) of a `compact` one."""
    import numpy as np

    from cogniframe.analysis.joints.model import JointStiffness

    n = 6 * len(c["labels"])
    K = np.zeros((n, n))
    K[np.triu_indices(n)] = c["triu"]
    K = K + np.triu(K, 1).T
    return JointStiffness(c["name"], "fe", tuple(c["labels"]), tuple(map(tuple, c["refs"])), tuple(map(tuple, K.tolist())))


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


def refusal(a) -> str | None:
    """Why the --family / --core-link request cannot be trained (one line), or None."""
    from cogniframe.analysis.joints.surrogate import family_of

    known = known_families()
    for name in a.family:
        if name not in known:
            return f"--family {name}: not a joint family; use one of {', '.join(known)}"
    link = base_link(a.core_link)
    have = {family_of(p) for p in design_parts({}, a.core_link)[2] if wanted(p, None)}
    for name in a.family:
        if name not in have:
            need = name.removeprefix("core_link").removeprefix("_") or "tab"
            return (f"--family {name}: the designs of {BASE.relative_to(ROOT).as_posix()} with core.link {link} have no "
                    f"{name} joint; add --core-link {need}")
    for path in (a.data, a.holdout_file):
        if not path.is_file():
            return (f"{path}: not found; --family merges into the existing data and held-out files "
                    "(train every family once without --family first)")
    return None


def main(argv=None) -> int:
    import typing

    from cogniframe.analysis.joints import surrogate as sg
    from cogniframe.spec import CoreSection

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--work", type=Path, default=Path("/tmp/joint-surrogate"))
    ap.add_argument("--train", type=int, default=96)
    ap.add_argument("--holdout", type=int, default=16)
    ap.add_argument("--seed", type=int, default=26)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--scheduler", default=None)
    ap.add_argument("--doe-only", action="store_true", help="solve the FE, do not fit")
    ap.add_argument("--fit-only", action="store_true", help="fit on the solved designs only (skips the rest)")
    ap.add_argument("--family", action="append", default=[], metavar="NAME",
                    help="solve and fit only this family (repeatable); the data file's other families stay as they are")
    ap.add_argument("--core-link", choices=typing.get_args(CoreSection.model_fields["link"].annotation), default=None,
                    help="the base's core.link for the DOE (default: the base file's own)")
    ap.add_argument("--data", type=Path, default=sg.DATA_FILE,
                    help="the data file to write (the package's, default, has its sha256 pinned in surrogate.py)")
    ap.add_argument("--holdout-file", type=Path, default=ROOT / "tests" / "data" / "joint_surrogate_holdout.json")
    ap.add_argument("--refresh-k", action="store_true",
                    help="only recompute the held-out frame k at the package's TPU factor (after a new calibration)")
    a = ap.parse_args(argv)
    if a.refresh_k:
        from cogniframe.analysis.numerics import one_blas_thread

        hd = json.loads(a.holdout_file.read_text())
        with one_blas_thread():
            refresh_k(hd, a.data)
        a.holdout_file.write_text(json.dumps(hd, sort_keys=True, separators=(",", ":")) + "\n")
        print(f"wrote {a.holdout_file} (frame k at TPU factor {hd['meta']['tpu_factor']:g})")
        return 0
    fams = tuple(sorted(set(a.family))) or None
    if fams is not None:
        why = refusal(a)
        if why is not None:
            print(f"train_joint_surrogate: {why}", file=sys.stderr)
            return 2
    a.work.mkdir(parents=True, exist_ok=True)
    # training designs in hypercubes of TRAIN_BATCH (seeds seed, seed + 1, ...): a larger --train
    # keeps every design a smaller one solved
    train = [ov for b in range(-(-a.train // TRAIN_BATCH))
             for ov in designs(TRAIN_BATCH, a.seed + b, a.core_link)][:a.train]
    hold = designs(a.holdout, a.seed + HOLDOUT_SEED_OFFSET, a.core_link)
    # held-out designs first: the acceptance set is complete even when training is cut short
    if a.fit_only:
        train = [ov for ov in train if solved(ov, a.work, a.core_link, fams)]
        print(f"fit on the {len(train)} solved training designs")
    else:
        run_doe(hold + train, a.work, a.jobs, a.scheduler, a.core_link, fams)
    if a.doe_only:
        return 0
    from cogniframe.analysis.numerics import one_blas_thread

    with one_blas_thread():  # the same bits of the fit on any machine (BLAS sums in a fixed order)
        return fit_and_write(train, hold, a.work, a.data, a.holdout_file, a.core_link, fams, a.seed)


if __name__ == "__main__":
    raise SystemExit(main())
