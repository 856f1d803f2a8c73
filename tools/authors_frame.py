"""Read the authors' crash-test frame (thecognifly/CogniFly-STL) with cogniframe.cadread and print
what it finds: rods by length, joints by name with their sockets, what it could not place.

    python tools/authors_frame.py CogniFly-STL                                 # a clone (or bare git dir) of their repository
    python tools/authors_frame.py CogniFly-Flex.FCStd --refs DIR                 # the document + part files
    python tools/authors_frame.py CogniFly-STL --analyse                       # + the physics

`--analyse` runs `cogniframe analyse`'s model on it (api.analyse: +z down, the rods' real 3.0 mm
carbon for the beams and the fits): k at the datasheet TPU modulus (factor 1) and at the package's
calibration, the thrust case and the drop model, and the TPU factor at which the frame's k is the
paper's measured 7040 N/m (a 1-D root find), with the carbon preset's k at that factor.

From a git directory it reads `CogniFly_v8_Crash_Tests/STEP_and_SAT/For_Visualization_Dimensions/
CogniFly-Flex.FCStd` and the v8 part STLs (`git show`, into a temporary folder: nothing of
theirs is written into this repository). The document is one unnamed compound of 82 solids; the
solids are named after the part STLs whose volume and radii of gyration match (cadread.identify),
the rest keep `CogniFly_Flex_full_STEP#k` with their nearest part file in the table.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from collections import Counter, defaultdict
from pathlib import Path

FCSTD = "CogniFly_v8_Crash_Tests/STEP_and_SAT/For_Visualization_Dimensions/CogniFly-Flex.FCStd"
PARTS_DIR = "CogniFly_v8_Crash_Tests/"


def _git(gd: Path, *args: str) -> bytes:
    return subprocess.run(["git", f"--git-dir={gd}", *args], check=True, capture_output=True).stdout


def from_git(gd: Path, tmp: Path) -> tuple[Path, Path]:
    if (gd / ".git").is_dir():
        gd = gd / ".git"
    doc = tmp / "CogniFly-Flex.FCStd"
    doc.write_bytes(_git(gd, "show", f"HEAD:{FCSTD}"))
    refs = tmp / "refs"
    refs.mkdir()
    for name in _git(gd, "ls-tree", "--name-only", "HEAD", PARTS_DIR).decode().split("\n"):
        if name.lower().endswith(".stl"):
            (refs / Path(name).name).write_bytes(_git(gd, "show", f"HEAD:{name}"))
    return doc, refs


def base(name: str) -> str:
    head, _, tail = name.rpartition("_")
    return head if tail.isdigit() and head else name


def report(doc: Path, refs: Path | None, rod_diameter: float | None = None) -> str:
    from cogniframe.cadread.identify import best_match, file_signature, identify
    from cogniframe.cadread.load import load_solids
    from cogniframe.cadread.read import exoskeleton_of

    solids = load_solids(doc)
    references = {}
    if refs is not None:
        for f in sorted(refs.iterdir()):
            if f.suffix.lower() in (".stl", ".step", ".stp"):
                references[f.stem] = file_signature(f)
        solids, _ = identify(solids, references)
    exo = exoskeleton_of(solids, str(doc), rod_diameter=rod_diameter)
    by_name = {s.name: s.solid for s in solids}
    out = [f"{doc.name}: {len(solids)} solids -> {len(exo.rods)} rods, {len(exo.joints)} joints, "
           f"{len(exo.sockets)} sockets/sleeves, {len(exo.attached)} attached parts, {len(exo.unplaced)} unplaced", ""]
    out.append("Rods (length from the end faces, diameter from the cylindrical face):")
    groups = Counter((round(r.length, 1), round(r.diameter, 2)) for r in exo.rods)
    nominal = rod_diameter or 3.0
    out.append(f"  count  length mm  diameter mm  volume / (pi {nominal / 2:g}^2) mm")
    for (length, d), n in sorted(groups.items(), key=lambda x: -x[0][0]):
        out.append(f"  {n:5d}  {length:9.1f}  {d:11.2f}  {length * (d / nominal) ** 2:9.1f}")
    out.append("")
    out.append("Joints (by part; sockets per copy: kind bore x depth mm, gap = rod end to the socket's bottom):")
    per = defaultdict(list)
    for j in exo.joints:  # an identified part by its name, an unnamed one by its shape
        key = base(j.name) if (not references or base(j.name) in references) else f"~{j.volume:.0f}"
        per[key].append(j)
    for key, js in sorted(per.items()):
        b = key if not key.startswith("~") else "unnamed " + " ".join("#" + j.name.rsplit("#", 1)[-1] for j in js)
        socks = Counter()
        for j in js:
            for s in exo.sockets_of(j.name):
                socks[(s.kind, round(s.bore, 2), round(s.depth, 1), round(s.gap, 1))] += 1
        named = b
        if references and key.startswith("~"):
            m = best_match(by_name[js[0].name], references)
            named = f"{b} (no part file within 2 %; nearest {m[0]}, {100 * m[1]:.0f} % off)" if m else b
        out.append(f"  {len(js)} x {named}: {js[0].material}, {js[0].volume / 1000:.2f} cm^3 each")
        for (kind, bore, depth, gap), n in sorted(socks.items()):
            each = n / len(js)
            out.append(f"      {each:4.2g} x {kind:7s} {bore:5.2f} x {depth:4.1f}" + (f"  gap {gap:+.1f}" if kind == "blind" else ""))
    out.append("")
    label = {j.name: (base(j.name) if (not references or base(j.name) in references) else f"unnamed {j.volume / 1000:.2f} cm^3")
             for j in (*exo.joints, *exo.attached)}
    pairs = Counter(tuple(sorted((label[c.a], label[c.b]))) + (round(c.distance, 3),) for c in exo.contacts
                    if c.a in label and c.b in label)
    if pairs:
        out.append("Contacts (parts within 0.1 mm of each other; the first gap found, mm):")
        for (p, q, d), n in sorted(pairs.items()):
            out.append(f"  {n} x {p} - {q} ({d:g})")
        out.append("")
    if exo.attached:
        out.append("Attached (touching a joint, no rod): " + ", ".join(sorted(Counter(base(a.name) for a in exo.attached))))
    if exo.unplaced:
        out.append("Unplaced (neither a rod nor connected to one): "
                   + ", ".join(f"{n} ({abs(by_name[n].Volume()):.1f} mm^3)" for n in exo.unplaced))
    if exo.loose_ends:
        out.append("")
        out.append("Warnings:")
        out.extend("  " + w for w in exo.warnings)
    return "\n".join(out)


def analyse_report(doc: Path, refs: Path | None, rod_diameter: float = 3.0, preset: str = "params/carbon.yaml") -> str:
    """The physics of the authors' frame (see the module docstring), as text."""
    from cogniframe.analysis.exoframe import k_at
    from cogniframe.analysis.joints import TPU_PRINTED_MODULUS_FACTOR
    from cogniframe.analysis.stiffness import PAPER_K_N_PER_M
    from cogniframe.api.analyse import analyse, calibrate, frame_model, summary
    from cogniframe.cadread.identify import file_signature, identify
    from cogniframe.cadread.load import load_solids

    solids = load_solids(doc)
    if refs is not None:
        references = {f.stem: file_signature(f) for f in sorted(refs.iterdir()) if f.suffix.lower() in (".stl", ".step", ".stp")}
        solids, _ = identify(solids, references)
    fm = frame_model(solids=solids, source=doc.name, down="+z", rod_diameter=rod_diameter,
                     progress=lambda m: print(m, file=sys.stderr, flush=True))
    out = []
    for f in (1.0, TPU_PRINTED_MODULUS_FACTOR):
        a = analyse(model=fm, source=doc.name, down="+z", rod_diameter=rod_diameter, factor=f)
        out += [f"-- TPU factor {f:g}"] + summary(a) + [""]
    f_cal = calibrate(fm, PAPER_K_N_PER_M)
    out.append(f"-- calibration: the TPU factor at which the authors' frame gives the paper's {PAPER_K_N_PER_M:.0f} N/m: "
               f"f = {f_cal:.4f} (k(f) = {k_at(fm.layout, fm.units, f_cal):.1f} N/m; k(1) / 7040 = "
               f"{k_at(fm.layout, fm.units, 1.0) / PAPER_K_N_PER_M:.4f}: k is not quite proportional to f, the rods bend too)")
    a = analyse(model=fm, source=doc.name, down="+z", rod_diameter=rod_diameter, factor=f_cal)
    out += summary(a)
    k_preset = preset_k(preset, f_cal)
    out.append(f"-- {preset} at f = {f_cal:.4f}: k = {k_preset:.0f} N/m (the check's frame model; the paper's 7040), "
               f"at f = {TPU_PRINTED_MODULUS_FACTOR:g}: {preset_k(preset, TPU_PRINTED_MODULUS_FACTOR):.0f} N/m")
    return "\n".join(out)


def preset_k(preset: str, factor: float) -> float:
    """A preset's k (the check's secant k, its joints' FE from the cache) at TPU factor `factor`."""
    import cogniframe as cf
    from cogniframe.analysis.stiffness import joint_models, secant_k

    d = cf.load(preset)
    spec, der = d.spec, d.derived
    return secant_k(spec, der.frame, der.parts, joint_models(spec, der.parts, "fe", factor))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("source", type=Path, help="the authors' repository (a clone or bare git dir) or the .FCStd")
    ap.add_argument("--refs", type=Path, help="folder of part files (STL/STEP) to name the solids by")
    ap.add_argument("--rod-diameter", type=float, default=None)
    ap.add_argument("--analyse", action="store_true", help="the physics: k, thrust case, safe drop, the calibration")
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        doc, refs = (from_git(a.source, Path(tmp)) if a.source.is_dir() else (a.source, a.refs))
        if a.analyse:
            print(analyse_report(doc, refs, a.rod_diameter or 3.0))
        else:
            print(report(doc, refs, a.rod_diameter))
    return 0


if __name__ == "__main__":
    sys.exit(main())
