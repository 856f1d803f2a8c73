"""Read a build's own `assembly.step` back with cogniframe.cadread and compare with its frame graph.

    python -m cogniframe build params/carbon.yaml -o /tmp/x --no-server
    python tools/cadread_roundtrip.py params/carbon.yaml /tmp/x/assembly.step

Prints the worst differences: rod lengths, rod ends, socket directions, depths (chamfer included),
bores against the params' bore, the mouths `toframe` gives against `stiffness.mouth`, and the
reader's warnings. Exit code 1 when a rod or a socket does not match (1e-3 mm / 1e-6)."""

from __future__ import annotations

import sys

import numpy as np


def main(argv=None) -> int:
    from cogniframe import frame as frame_mod
    from cogniframe import spec as spec_mod
    from cogniframe.analysis.stiffness import mouth
    from cogniframe.cadread import read_exoskeleton
    from cogniframe.cadread.toframe import frame_rods

    params, step = (argv or sys.argv[1:])[:2]
    spec = spec_mod.load(params)
    fr = frame_mod.frame_of(spec)
    exo = read_exoskeleton(step)
    ok = sorted(r.name for r in exo.rods) == sorted(fr.rods)
    print(f"rods: {len(exo.rods)} read, {len(fr.rods)} in the frame, names {'match' if ok else 'DIFFER'}")
    if not ok:
        return 1
    dl = max(abs(exo.rod(n).length - r.length) for n, r in fr.rods.items())
    worst = dict(end=0.0, direction=0.0, depth=0.0, bore=0.0)
    n_sockets, joints_ok = 0, True
    for n, r in fr.rods.items():
        for end, point in ((r.a, r.start), (r.b, r.end)):
            cands = [s for s in exo.sockets if s.rod == n and s.joint == end.node and s.end is not None]
            if len(cands) != 1:
                joints_ok = False
                continue
            s = cands[0]
            n_sockets += 1
            worst["end"] = max(worst["end"], float(np.linalg.norm(np.subtract(s.rod_end, point))))
            worst["direction"] = max(worst["direction"], float(np.linalg.norm(np.subtract(s.direction, r.socket_direction(end.node)))))
            worst["depth"] = max(worst["depth"], abs(s.depth - end.depth))
            worst["bore"] = max(worst["bore"], abs(s.bore - spec.bore))
    mine = frame_rods(exo)
    dm = max(float(np.linalg.norm(mouth(mine[n], t if mine[n].a.node == r.a.node else {"a": "b", "b": "a"}[t]) - mouth(r, t)))
             for n, r in fr.rods.items() for t in "ab")
    print(f"rod lengths: worst difference {dl:.2e} mm")
    print(f"sockets: {n_sockets} of {2 * len(fr.rods)} rod ends in their frame joint; worst rod end {worst['end']:.2e} mm, "
          f"direction {worst['direction']:.2e}, depth {worst['depth']:.2e} mm, bore {worst['bore']:.2e} mm")
    print(f"toframe: worst socket mouth vs stiffness.mouth {dm:.2e} mm")
    ds, n_sleeves = 0.0, 0
    for m in fr.motors:  # the mounts' sleeves: the motor's station on each arm rod
        for rn in m.arm:
            r, rd = fr.rods[rn], exo.rod(rn)
            sl = [s for s in exo.sockets if s.rod == rn and s.end is None]
            if len(sl) != 1:
                joints_ok = False
                continue
            n_sleeves += 1
            t_frame = float(np.dot(np.asarray(m.axis) - np.asarray(rd.a), rd.axis))
            ds = max(ds, abs(sl[0].station - t_frame))
    print(f"sleeves: {n_sleeves} of {2 * len(fr.motors)} motor-mount clips found; worst station vs the motor axis {ds:.2e} mm")
    for w in exo.warnings:
        print("warning:", w)
    good = joints_ok and dl < 1e-3 and worst["end"] < 1e-3 and worst["direction"] < 1e-6 and worst["depth"] < 1e-3 \
        and worst["bore"] < 1e-3 and dm < 1e-3 and ds < 1e-3
    print("round trip:", "OK" if good else "MISMATCH")
    return 0 if good else 1


if __name__ == "__main__":
    sys.exit(main())
