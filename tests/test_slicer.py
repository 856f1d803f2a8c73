"""Slicer check: profiles from params, plate checks before slicing, real PrusaSlicer runs.

Tests that run PrusaSlicer are skipped only when `prusa-slicer` is not on PATH (CI installs it).
"""

from __future__ import annotations

import shutil
import time

import pytest
import trimesh

from cogniframe import spec as spec_mod
from cogniframe.errors import UserError
from cogniframe.export import slicer
from cogniframe.export.plates import PlateItem, pack_plates, write_plates
from meshes import box as _box

needs_slicer = pytest.mark.skipif(shutil.which("prusa-slicer") is None, reason="prusa-slicer is not installed")


@pytest.fixture(scope="module")
def spec():
    return spec_mod.from_dict({"name": "t"})


def _cyl(r, h):
    m = trimesh.creation.cylinder(radius=r, height=h, sections=48)
    m.apply_translation(-m.bounds[0])
    return m


def _ini(text: str) -> dict[str, str]:
    return dict(line.split(" = ", 1) for line in text.splitlines() if " = " in line)


def test_profile_from_params(spec):
    tpu = _ini(slicer.profile_ini(spec, "tpu_95a", 1.0))
    assert tpu["fill_density"] == "100%" and tpu["fill_pattern"] == "rectilinear"
    assert tpu["support_material"] == "0" and tpu["brim_width"] == "0" and tpu["skirts"] == "0"
    assert tpu["temperature"] == "228" and tpu["seam_position"] == "rear"
    assert 25 <= float(tpu["perimeter_speed"]) <= 35 and 25 <= float(tpu["infill_speed"]) <= 35
    assert tpu["filament_density"] == "1.22"
    assert tpu["bed_shape"] == "0x0,120x0,120x120,0x120" and tpu["max_print_height"] == "120"
    assert tpu["nozzle_diameter"] == "0.4" and tpu["layer_height"] == "0.2"
    assert tpu["perimeters"] == "2" and tpu["top_solid_layers"] == "4" and tpu["bottom_solid_layers"] == "4"
    core = _ini(slicer.profile_ini(spec, "abs", spec.core.infill))
    assert core["fill_density"] == "10%" and core["filament_density"] == "1.1" and core["filament_type"] == "ABS"
    custom = spec_mod.from_dict({"printer": {"bed": [180, 150, 100], "nozzle": 0.6, "layer_height": 0.3, "perimeters": 3}})
    c = _ini(slicer.profile_ini(custom, "pla", 0.15))
    assert c["bed_shape"] == "0x0,180x0,180x150,0x150" and c["max_print_height"] == "100"
    assert c["nozzle_diameter"] == "0.6" and c["layer_height"] == "0.3" and c["perimeters"] == "3"
    assert c["fill_density"] == "15%" and c["filament_density"] == "1.24"
    assert slicer.default_infill(spec) == {"abs": 0.1, "tpu_95a": 1.0}


def test_durations_and_gcode_stats(tmp_path):
    assert slicer.parse_duration("13m 22s") == 802
    assert slicer.parse_duration("1d 2h 3m 4s") == 93784
    assert slicer.format_duration(802) == "13 min" and slicer.format_duration(3 * 3600 + 65) == "3h 01m"
    assert slicer.format_duration(3 * 3600 + 59 * 60 + 50) == "4h 00m"
    g = tmp_path / "x.gcode"
    g.write_text("G1 X1\n; filament used [mm] = 800.81\n; filament used [g] = 2.35\n"
                 "; estimated printing time (normal mode) = 13m 22s\n")
    assert slicer.read_gcode_stats(g) == (2.35, 802.0)
    g.write_text("G1 X1\n")
    with pytest.raises(UserError, match="filament used"):
        slicer.read_gcode_stats(g)


def test_gcode_stats_come_from_the_closing_comments_and_else_from_the_whole_file(tmp_path):
    moves = "G1 X10.123 Y20.456 E0.01234\n" * 20_000  # 560 kB, as a plate's layers
    footer = "; filament used [g] = 1.5, 0.25\n; estimated printing time (normal mode) = 1h 2m 3s\n"
    g = tmp_path / "big.gcode"
    # a line at the top that a read of the whole file would choke on: only the last 64 kB are read
    g.write_text("; filament used [g] = n/a\n" + moves + footer + "; prusaslicer_config = begin\n" + "; k = v\n" * 300)
    assert g.stat().st_size > 8 * slicer.GCODE_TAIL_BYTES
    assert slicer.read_gcode_stats(g) == (1.75, 3723.0)
    # the closing comments elsewhere (not in the last 64 kB): found by reading the whole file
    g.write_text(footer + moves)
    assert slicer.read_gcode_stats(g) == (1.75, 3723.0)


def _scene_3mf(path, meshes: dict):
    s = trimesh.Scene()
    for n, m in meshes.items():
        s.add_geometry(m, geom_name=n, node_name=n)
    path.write_bytes(s.export(file_type="3mf"))
    return path


def test_checks_before_slicing(tmp_path):
    bed = (120, 120, 120)
    ok = _box(10, 10, 5)
    ok.apply_translation([10, 10, 0])
    objs = slicer.check_plate(_scene_3mf(tmp_path / "abs_1.3mf", {"a_1": ok}), bed)
    assert [o.name for o in objs] == ["a_1"] and objs[0].volume_mm3 == pytest.approx(500)

    off = _box(30, 10, 5)
    off.apply_translation([100, 10, 0])
    with pytest.raises(UserError, match=r"b_1 spans x 100.0\.\.130.0.*printer.bed"):
        slicer.check_plate(_scene_3mf(tmp_path / "abs_2.3mf", {"a_1": ok, "b_1": off}), bed)

    tall = _box(10, 10, 130)
    tall.apply_translation([40, 40, 0])
    with pytest.raises(UserError, match="height 130.0"):
        slicer.check_plate(_scene_3mf(tmp_path / "abs_3.3mf", {"t_1": tall}), bed)

    broken = _box(10, 10, 5)
    broken.apply_translation([40, 40, 0])
    broken = trimesh.Trimesh(broken.vertices, broken.faces[:-1], process=False)  # one triangle missing
    with pytest.raises(UserError, match="o_1 is not a closed solid"):
        slicer.check_plate(_scene_3mf(tmp_path / "abs_4.3mf", {"o_1": broken}), bed)

    other = _box(10, 10, 5)
    other.apply_translation([15, 15, 0])
    with pytest.raises(UserError, match="a_1 and c_1 overlap"):
        slicer.check_plate(_scene_3mf(tmp_path / "abs_5.3mf", {"a_1": ok, "c_1": other}), bed)


@needs_slicer
@pytest.mark.slicer
def test_a_plate_that_fails_its_check_stops_the_slicer_started_beside_it(tmp_path, spec):
    """slice_plate starts PrusaSlicer while it checks the plate: a failed check still raises its
    own message, and leaves no G-code and no slicer process behind."""
    import os

    a, c = _box(10, 10, 5), _box(10, 10, 5)  # overlapping copies: PrusaSlicer itself would slice them
    a.apply_translation([10, 10, 0])
    c.apply_translation([15, 15, 0])
    plate = _scene_3mf(tmp_path / "abs_1.3mf", {"a_1": a, "c_1": c})
    ini = tmp_path / "abs.ini"
    ini.write_text(slicer.profile_ini(spec, "abs", 0.2), encoding="utf-8")
    before = {p.name for p in __import__("pathlib").Path("/proc").iterdir() if p.name.isdigit()}
    with pytest.raises(UserError, match="a_1 and c_1 overlap"):
        slicer.slice_plate(plate, ini, (120, 120, 120), gcode=tmp_path / "abs_1.gcode")
    time.sleep(2.0)  # a slicer left running would write its G-code by now
    assert not (tmp_path / "abs_1.gcode").exists()
    for pid in {p.name for p in __import__("pathlib").Path("/proc").iterdir() if p.name.isdigit()} - before:
        try:
            cmd = open(f"/proc/{pid}/cmdline", "rb").read()
        except OSError:
            continue
        assert str(plate).encode() not in cmd, f"a slicer is still running: {cmd!r} ({os.getpid()})"


@pytest.mark.slicer
@pytest.mark.parametrize("cpu", [0, 1])
def test_the_slicer_runs_on_one_cpu_and_started_gets_its_pid(tmp_path, cpu):
    """PrusaSlicer (here a stand-in that writes down the CPUs it may use and its nice value, then
    its G-code) runs on one CPU, the `cpu`-th of this process's (modulo their number): its G-code
    is then the same every run. `started(pid)` gets the slicer's own pid through the launcher,
    before it has started its work: given `runtime.pools.behind_the_build`, it runs
    BACKGROUND_NICE steps nicer than the caller."""
    import os

    from cogniframe.runtime.pools import BACKGROUND_NICE, behind_the_build

    ok = _box(10, 10, 5)
    ok.apply_translation([10, 10, 0])
    plate = _scene_3mf(tmp_path / "abs_1.3mf", {"a_1": ok})
    fake = tmp_path / "prusa-slicer"
    seen = tmp_path / "seen.txt"
    # (the last argument is the G-code path; the nice value is read once the caller has set it)
    fake.write_text(f"#!/bin/sh\nsleep 0.5\nnice > {seen}\ngrep Cpus_allowed_list /proc/$$/status >> {seen}\n"
                    "for a; do out=$a; done\n"
                    "printf '; filament used [g] = 0.5\\n; estimated printing time (normal mode) = 1m 0s\\n' > $out\n")
    fake.chmod(0o755)
    ini = tmp_path / "abs.ini"
    ini.write_text("layer_height = 0.2\n")
    got = slicer.slice_plate(plate, ini, (120, 120, 120), exe=str(fake), gcode=tmp_path / "abs_1.gcode",
                             started=behind_the_build, cpu=cpu)
    assert (got.grams, got.time_s) == (0.5, 60.0)
    nice, allowed = seen.read_text().splitlines()
    assert int(nice) == min(19, os.nice(0) + BACKGROUND_NICE)
    cpus = sorted(os.sched_getaffinity(0))
    assert allowed.split()[-1] == str(cpus[cpu % len(cpus)])


def test_slicer_messages_are_explained(tmp_path):
    msg = slicer._explain_failure(tmp_path / "abs_1.3mf", 134, "[2026] [trace] init\nObjects could not fit on the bed\n")
    assert "exit code 134" in msg and "printer.bed" in msg
    msg = slicer._explain_failure(tmp_path / "abs_1.3mf", 1, "No layers were detected. You might want to repair")
    assert "thinner than one layer" in msg
    msg = slicer._explain_failure(tmp_path / "abs_1.3mf", 1, "[2026-11] [trace] x\nsomething odd happened\n")
    assert "something odd happened" in msg and "[trace]" not in msg


def test_without_a_slicer_says_so_once(monkeypatch, spec, tmp_path):
    monkeypatch.setattr(slicer, "find_slicer", lambda: None)
    monkeypatch.setattr(slicer, "_said_missing", False)
    said = []
    assert slicer.slice_plates([tmp_path / "tpu_95a_1.3mf"], spec, log=said.append) is None
    assert slicer.slice_plates([tmp_path / "tpu_95a_1.3mf"], spec, log=said.append) is None
    assert len(said) == 1 and "prusa-slicer" in said[0]


def _plates(tmp_path, spec):
    items = [PlateItem("cube", "tpu_95a", 3, _box(10, 10, 10)), PlateItem("puck", "tpu_95a", 2, _cyl(6, 4)),
             PlateItem("plate", "abs", 1, _box(30, 20, 3))]
    return write_plates(pack_plates(items, spec.printer.bed, spec.printer.margin), tmp_path)


@needs_slicer
@pytest.mark.slicer
def test_real_slice_grams_and_time(tmp_path, spec):
    files = _plates(tmp_path, spec)
    tpu_volume = 3 * 1000 + 2 * _cyl(6, 4).volume
    report = slicer.slice_plates([f.threemf for f in files], spec, {"tpu_95a": tpu_volume * 1.22e-3, "abs": 5.0})
    assert [p.plate for p in report.plates] == ["abs_1", "tpu_95a_1"]
    tpu = report.plates[1]
    assert tpu.gcode.is_file() and (tmp_path / "tpu_95a.ini").is_file() and (tmp_path / "abs.ini").is_file()
    # 100 % infill: the filament is the solid volume, within a few per cent
    assert tpu.grams == pytest.approx(tpu_volume * 1.22e-3, rel=0.06)
    assert tpu.time_s > 60
    assert sorted(n for n, _ in tpu.objects) == ["cube_1", "cube_2", "cube_3", "puck_1", "puck_2"]
    checks = {c.material: c for c in report.materials}
    assert not checks["tpu_95a"].flagged
    # 10 % infill ABS plate (1.8 cm^3 solid) against a 5 g estimate: flagged as a warning
    assert checks["abs"].flagged and checks["abs"].sliced_g < 2.0
    assert len(report.warnings) == 1 and report.warnings[0].startswith("abs:")
    parts = report.part_totals()
    assert sum(g for g, _ in parts.values()) == pytest.approx(report.total_g)
    assert parts["cube"][0] > parts["puck"][0]
    g = slicer.read_gcode_stats(tpu.gcode)
    assert g == (tpu.grams, tpu.time_s)
    assert report.to_dict()["plates"][1]["objects"] == [n for n, _ in tpu.objects]
    # numbers only: no G-code left behind
    again = slicer.slice_plates([files[1].threemf], spec, keep_gcode=False)
    assert not again.plates[0].gcode.exists() and again.plates[0].gcode.parent != tmp_path
    assert again.plates[0].grams == pytest.approx(tpu.grams, rel=0.01)


@needs_slicer
@pytest.mark.slicer
def test_real_slicer_error_becomes_a_user_error(tmp_path, spec):
    flat = _box(10, 10, 0.05)  # thinner than a layer
    (f,) = write_plates(pack_plates([PlateItem("flat", "tpu_95a", 1, flat)], spec.printer.bed, 4), tmp_path)
    with pytest.raises(UserError, match="thinner than one layer"):
        slicer.slice_plates([f.threemf], spec)


def test_slice_command_without_plates(run_cli, tmp_path):
    from pathlib import Path

    params = Path(__file__).resolve().parents[1] / "params" / "carbon.yaml"
    code, out, err = run_cli("slice", params, "-o", tmp_path / "empty")
    assert code == 2
    assert "no print plates" in err and "cogniframe build" in err


@needs_slicer
@pytest.mark.slicer
def test_slice_command_table(run_cli, tmp_path):
    import json
    from pathlib import Path

    params = Path(__file__).resolve().parents[1] / "params" / "carbon.yaml"
    spec = spec_mod.load(params)
    _plates(tmp_path / "plates", spec)
    (tmp_path / "check.json").write_text(json.dumps({"name": "carbon", "mass": {"by_material": {"tpu_95a": 5.0, "abs": 0.5}}}))
    code, _, err = run_cli("slice", params, "-o", tmp_path)
    assert code == 2 and "not a cogniframe build folder" in err  # slice writes only into a build's folder
    files = sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*") if p.is_file())
    (tmp_path / "manifest.json").write_text(json.dumps({"generator": "cogniframe", "files": [{"path": f} for f in files]}))
    code, out, err = run_cli("slice", params, "-o", tmp_path)
    assert code == 0, err
    listed = {f["path"] for f in json.loads((tmp_path / "manifest.json").read_text())["files"]}
    on_disk = {p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*") if p.is_file()} - {"manifest.json"}
    assert "plates/slice.json" in listed and listed == on_disk  # what slice wrote stays cogniframe's
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert manifest["not_reproducible"] == ["plates/abs_1.gcode", "plates/tpu_95a_1.gcode"]
    assert "tpu_95a_1" in out and "abs_1" in out and "total" in out
    assert "check.json" in out  # compared with the build's own mass budget
    data = json.loads((tmp_path / "plates" / "slice.json").read_text())
    assert [p["plate"] for p in data["plates"]] == ["abs_1", "tpu_95a_1"]
    assert all(p["grams"] > 0 and p["time_s"] > 0 for p in data["plates"])


def _gcode_settings(path) -> dict[str, str]:
    """The `; key = value` settings block PrusaSlicer appends to its G-code."""
    out = {}
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            if line.startswith("; ") and " = " in line:
                k, v = line[2:].rstrip("\n").split(" = ", 1)
                out[k] = v
    return out


def test_project_config_is_the_profile_as_prusaslicer_3mf_comments(spec):
    ini = {k: v for k, v in _ini(slicer.profile_ini(spec, "tpu_95a", 1.0)).items() if not k.startswith("#")}
    cfg = slicer.project_config(spec, "tpu_95a", 1.0)
    lines = cfg.splitlines()
    assert all(ln.startswith("; ") for ln in lines)
    assert dict(ln[2:].split(" = ", 1) for ln in lines[1:]) == {"printer_technology": "FFF", **ini}
    custom = spec_mod.from_dict({"core": {"infill": 0.25}})
    assert slicer.project_configs(custom) == {"abs": slicer.project_config(custom, "abs", 0.25),
                                              "tpu_95a": slicer.project_config(custom, "tpu_95a", 1.0)}


@needs_slicer
@pytest.mark.slicer
def test_3mf_slices_with_its_own_settings_and_no_profile(tmp_path):
    """The acceptance line: a plate's 3MF sliced with no --load gives TPU 100 % rectilinear at the
    TPU temperature and speed, and the core at core.infill (25 % here, not PrusaSlicer's 20 % default)."""
    import subprocess

    spec = spec_mod.from_dict({"name": "t", "core": {"infill": 0.25}, "printer": {"preset": "prusa_mini"}})
    items = [PlateItem("cube", "tpu_95a", 2, _box(10, 10, 6)), PlateItem("plate", "abs", 1, _box(20, 20, 4))]
    files = write_plates(pack_plates(items, spec.printer.bed, spec.printer.margin), tmp_path,
                         configs=slicer.project_configs(spec))
    got = {}
    for f in files:
        gcode = tmp_path / f"{f.name}.gcode"
        proc = subprocess.run([shutil.which("prusa-slicer"), "--loglevel", "1", "--export-gcode", "--dont-arrange",
                               str(f.threemf), "-o", str(gcode)], capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, proc.stdout + proc.stderr
        got[f.material] = _gcode_settings(gcode)
    tpu, abs_ = got["tpu_95a"], got["abs"]
    assert tpu["fill_density"] == "100%" and tpu["fill_pattern"] == "rectilinear"
    assert tpu["temperature"] == "228" and tpu["filament_type"] == "FLEX"
    assert tpu["perimeter_speed"] == "30" and tpu["infill_speed"] == "30"
    assert tpu["bed_shape"] == "0x0,180x0,180x180,0x180" and tpu["nozzle_diameter"] == "0.4"
    assert abs_["fill_density"] == "25%" and abs_["temperature"] == "240" and abs_["filament_type"] == "ABS"
    # and PrusaSlicer's own defaults differ, so the settings really came from the 3MF
    bare = write_plates(pack_plates(items[:1], spec.printer.bed, spec.printer.margin), tmp_path / "bare")
    gcode = tmp_path / "bare.gcode"
    subprocess.run([shutil.which("prusa-slicer"), "--loglevel", "1", "--export-gcode", "--dont-arrange",
                    str(bare[0].threemf), "-o", str(gcode)], capture_output=True, text=True, timeout=300, check=True)
    assert _gcode_settings(gcode)["fill_density"] != "100%"


@needs_slicer
@pytest.mark.cad
@pytest.mark.slicer
@pytest.mark.fe
def test_build_gcode_keeps_gcode_per_plate_outside_the_promise(run_cli, tmp_path):
    import json
    from pathlib import Path

    PARAMS = Path(__file__).resolve().parents[1] / "params"
    out = tmp_path / "carbon"
    code, _, err = run_cli("build", PARAMS / "carbon.yaml", "-o", out, "--gcode")
    assert code == 0, err
    plates = sorted(p.stem for p in (out / "plates").glob("*.3mf"))
    gcodes = sorted(p.stem for p in (out / "plates").glob("*.gcode"))
    assert gcodes == plates and plates == ["abs_1", "tpu_95a_1"]
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["not_reproducible"] == [f"plates/{n}.gcode" for n in gcodes]
    assert set(manifest["not_reproducible"]) <= {f["path"] for f in manifest["files"]}
    tpu = _gcode_settings(out / "plates" / "tpu_95a_1.gcode")
    core = _gcode_settings(out / "plates" / "abs_1.gcode")
    assert tpu["fill_density"] == "100%" and core["fill_density"] == "10%"
    # the report's numbers come from these very files
    check = json.loads((out / "check.json").read_text())
    assert check["verdict"] == "PASS"
    grams, secs = slicer.read_gcode_stats(out / "plates" / "tpu_95a_1.gcode")
    row = next(ln for ln in (out / "report.md").read_text().splitlines() if ln.startswith("| tpu_95a_1 |"))
    assert row.endswith(f"| {grams:.1f} | {slicer.format_duration(secs)} |")
    # the slicer's grams against the mass budget's for the same material, within the slicer check's tolerance
    assert abs(grams / check["mass"]["by_material"]["tpu_95a"] - 1) < slicer.TOLERANCE
    code, _, err = run_cli("build", PARAMS / "carbon.yaml", "-o", out, "--gcode")
    assert code == 0 and "nothing rebuilt" in err  # a --gcode build is kept by the next --gcode build


@needs_slicer
@pytest.mark.slicer
def test_prusaslicer_reads_copies_as_instances_of_one_object(tmp_path):
    """Copies of a shape are one PrusaSlicer object with instances (sliced once, not once per copy),
    kept where cogniframe laid them out, and the grams are the copies' sum."""
    import re
    import subprocess
    import zipfile

    spec = spec_mod.from_dict({"name": "t"})
    exe = shutil.which("prusa-slicer")
    (four,) = write_plates(pack_plates([PlateItem("knee", "tpu_95a", 4, _cyl(6, 10))], spec.printer.bed,
                                       spec.printer.margin), tmp_path / "four", configs=slicer.project_configs(spec))
    (one,) = write_plates(pack_plates([PlateItem("knee", "tpu_95a", 1, _cyl(6, 10))], spec.printer.bed,
                                      spec.printer.margin), tmp_path / "one", configs=slicer.project_configs(spec))
    again = tmp_path / "again.3mf"
    subprocess.run([exe, "--loglevel", "1", "--export-3mf", "--dont-arrange", str(four.threemf), "-o", str(again)],
                   capture_output=True, text=True, timeout=300, check=True)
    config = zipfile.ZipFile(again).read("Metadata/Slic3r_PE_model.config").decode()
    assert re.findall(r'instances_count="(\d+)"', config) == ["4"]
    grams = {}
    for f in (four, one):
        gcode = tmp_path / f"{f.name}_{len(f.copies)}.gcode"
        subprocess.run([exe, "--loglevel", "1", "--export-gcode", "--dont-arrange", str(f.threemf), "-o", str(gcode)],
                       capture_output=True, text=True, timeout=300, check=True)
        grams[len(f.copies)], _ = slicer.read_gcode_stats(gcode)
        # the extrusions stay inside the copies' footprints as laid out (no re-centring by the slicer)
        xs, ys = [], []
        for line in gcode.read_text().splitlines():
            if line.startswith("G1 ") and " E" in line and " X" in line and " Y" in line and " E-" not in line:
                xs.append(float(re.search(r" X([-\d.]+)", line).group(1)))
                ys.append(float(re.search(r" Y([-\d.]+)", line).group(1)))
        plate = {o.name: o for o in slicer.load_plate_objects(f.threemf)}
        lo = min(o.lo[0] for o in plate.values()), min(o.lo[1] for o in plate.values())
        hi = max(o.hi[0] for o in plate.values()), max(o.hi[1] for o in plate.values())
        assert lo[0] - 0.3 < min(xs) < lo[0] + 1.0 and hi[0] - 1.0 < max(xs) < hi[0] + 0.3
        assert lo[1] - 0.3 < min(ys) < lo[1] + 1.0 and hi[1] - 1.0 < max(ys) < hi[1] + 0.3
    assert grams[4] == pytest.approx(4 * grams[1], rel=0.02)
