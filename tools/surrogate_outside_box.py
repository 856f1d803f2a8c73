#!/usr/bin/env python3
"""How far off the joint surrogate would be on the joints a sweep puts outside its training box.

    python tools/surrogate_outside_box.py [SWEEP.yaml]

Draws the sweep's designs (default: benchmarks/bench_sweep.py's sweep with rods up to 4 mm,
`--wide`, seed 11), and for every design with a joint outside the surrogate's box
(`surrogate.outside_reasons`) solves that joint's solid FE (factor 1, one BLAS thread) and
compares it with the fit's prediction taken anyway (the box not checked, as the training tool's
held-out errors are): the joint's relative errors (`train_joint_surrogate.joint_error`:
Frobenius, worst diagonal entry, energy bound) and the frame's secant k with the predicted joint
against the FE's (every other joint from the surrogate). The documented held-out errors to compare
with are in docs/stiffness-model.md ("Accuracy on held-out joints"). Seconds of FE per joint.
"""

from __future__ import annotations

import statistics
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tools"))
sys.path.insert(0, str(ROOT / "benchmarks"))


def main(argv=None) -> int:
    import yaml

    import train_joint_surrogate as T
    from cogniframe import frame as frame_mod
    from cogniframe import partlist
    from cogniframe import spec as spec_mod
    from cogniframe.analysis.joints import fe_joint, is_mirror
    from cogniframe.analysis.joints import surrogate as sg
    from cogniframe.analysis.joints.model import JointStiffness, tpu_moduli
    from cogniframe.analysis.numerics import one_blas_thread
    from cogniframe.sweep import sample, sweepfile
    from cogniframe.sweep import evaluate as ev

    argv = sys.argv[1:] if argv is None else argv
    if argv:
        sweep = sweepfile.load(Path(argv[0]))
    else:
        import bench_sweep

        path = Path(tempfile.mkdtemp(prefix="outside-box-")) / "sweep.yaml"
        path.write_text(bench_sweep.sweep_text(300, 11, wide=True))
        sweep = sweepfile.load(path)
    base = sweep.base_data
    fams = sg.families()
    joint_err, frame_err = [], []
    for ov in sample.designs(sweep):
        data = ev.apply_overrides(base, ov)
        data.setdefault("model", {})["stiffness_model"] = "surrogate"
        try:
            s = spec_mod.from_dict(data)
            f = frame_mod.frame_of(s)
            parts = partlist.part_list(s, f)
        except Exception:  # noqa: BLE001 - a design the validation refuses has no joints to compare
            continue
        joints = [p for p in parts if p.family == "joint"]
        why = sg.outside_reasons(s, joints)
        if not why:
            continue
        predicted, solved = {}, {}
        with one_blas_thread():
            for p in joints:
                if is_mirror(p):
                    continue
                fam = fams[sg.family_of(p)]
                labels = tuple(x.rod for x in p.sockets) + (("body",) if len(fam.labels) > len(p.sockets) else ())
                K = T.predicted(fam, s, p, labels, tpu_moduli(s, 1.0)[0])
                predicted[p.name] = JointStiffness(p.name, "surrogate", labels, tuple(tuple(r) for r in sg._refs(p, labels)),
                                                   tuple(map(tuple, K.tolist())), 0, 0.0)
                solved[p.name] = predicted[p.name]
                if p.name in why:
                    solved[p.name] = fe_joint(s, p, 1.0)
                    err = T.joint_error(K, solved[p.name].matrix)
                    joint_err.append(err)
                    print(f"{ov}: {p.name}: {why[p.name]}; error Frobenius {err['frobenius']:.4f}, diagonal "
                          f"{err['diagonal']:.4f}, energy {err['energy']:.4f}", flush=True)
            k_pred, k_fe = T.frame_k(s, f, parts, predicted), T.frame_k(s, f, parts, solved)
        frame_err.append(abs(k_pred / k_fe - 1))
        print(f"  frame k {k_pred:.1f} N/m with the prediction, {k_fe:.1f} with the FE ({k_pred / k_fe - 1:+.3%})", flush=True)
    if not joint_err:
        print("no joint of the sweep's designs is outside the surrogate's box")
        return 0
    med = statistics.median
    fro = [e["frobenius"] for e in joint_err]
    print(f"{len(joint_err)} joints outside the box in {len(frame_err)} designs: Frobenius median {med(fro):.2%}, "
          f"worst {max(fro):.2%}; energy bound worst {max(e['energy'] for e in joint_err):.2%}; frame k median "
          f"{med(frame_err):.3%}, worst {max(frame_err):.3%}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
