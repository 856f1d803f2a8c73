"""Printer presets, the shipped params schema, the presets' schema line, and `cogniframe new`."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from cogniframe import spec as spec_mod
from cogniframe.api import presets
from cogniframe.commands import maker
from cogniframe.errors import UserError
from cogniframe.printers import PRINTERS

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "cogniframe"
SCHEMA = PKG / "data" / "params.schema.json"


# -- printer presets ----------------------------------------------------------------------------

def test_preset_tables_build_volumes_from_the_makers_specs():
    # The makers' published build volumes (mm) and stock nozzles; sources in cogniframe/data/printers.yaml.
    expected = {"monoprice_mini_v2": (120, 120, 120), "prusa_mini": (180, 180, 180), "bambu_a1_mini": (180, 180, 180),
                "ender3": (220, 220, 250), "prusa_mk4": (250, 210, 220),
                # Bambu Lab's A1, P1S / P1P and X1-Carbon specification pages: 256 x 256 x 256 mm
                "bambu_a1": (256, 256, 256), "bambu_p1s": (256, 256, 256), "bambu_p1p": (256, 256, 256),
                "bambu_x1c": (256, 256, 256)}
    assert {k: p.bed for k, p in PRINTERS.items()} == expected
    assert {p.nozzle for p in PRINTERS.values()} == {0.4}
    # the Bambu Lab machines' plates are for Bambu Studio (OrcaSlicer reads the same files); the others PrusaSlicer
    assert {k for k, p in PRINTERS.items() if p.slicer == "bambustudio"} == {"bambu_a1_mini", "bambu_a1", "bambu_p1s",
                                                                            "bambu_p1p", "bambu_x1c"}
    assert {p.slicer for p in PRINTERS.values()} == {"bambustudio", "prusaslicer"}
    for p in PRINTERS.values():
        assert p.url.startswith("https://") and len(p.source) > 20, p.key


def test_preset_sets_bed_and_nozzle_and_explicit_keys_win():
    mini = spec_mod.from_dict({"printer": {"preset": "prusa_mini"}}).printer
    assert mini.bed == (180.0, 180.0, 180.0) and mini.nozzle == 0.4 and mini.preset == "prusa_mini"
    assert mini.layer_height == 0.2 and mini.margin == 4  # untouched keys keep their defaults
    mk4 = spec_mod.from_dict({"printer": {"preset": "prusa_mk4", "bed": [240, 200, 210], "nozzle": 0.6}}).printer
    assert mk4.bed == (240.0, 200.0, 210.0) and mk4.nozzle == 0.6
    # no preset: the old defaults
    assert spec_mod.from_dict({}).printer.bed == (120.0, 120.0, 120.0)


def test_unknown_preset_names_the_key_line_and_a_guess(tmp_path):
    p = tmp_path / "x.yaml"
    p.write_text("name: x\nprinter:\n  preset: prusa_mni\n", encoding="utf-8")
    with pytest.raises(UserError) as e:
        spec_mod.load(p)
    msg = str(e.value)
    assert "printer.preset (line 3)" in msg and "'prusa_mini'" in msg and "cogniframe printers" in msg


def test_printers_command_lists_every_preset(run_cli):
    code, out, _ = run_cli("printers", "--json")
    assert code == 0
    rows = {r["preset"]: r for r in json.loads(out)}
    assert set(rows) == set(PRINTERS)
    assert rows["bambu_a1_mini"]["bed_mm"] == [180.0, 180.0, 180.0]
    assert rows["bambu_a1_mini"]["slicer"] == "bambustudio" and rows["prusa_mk4"]["slicer"] == "prusaslicer"
    code, out, _ = run_cli("printers")
    assert code == 0 and "prusa_mk4" in out and "250 x 210 x 220" in out


def test_printers_table_fits_an_80_column_terminal():
    """Every line of the table is at most 80 characters wide and nothing is cut short (no ellipsis)."""
    from rich.console import Console

    con = Console(width=80, record=True, color_system=None)
    con.print(maker.printers_table())
    text = con.export_text()
    assert max(len(line) for line in text.splitlines()) <= 80
    assert "\u2026" not in text
    for p in PRINTERS.values():  # every preset key and bed whole, on one line
        assert p.key in text and " x ".join(f"{v:g}" for v in p.bed) in text, p.key


@pytest.mark.process
def test_printers_command_at_80_columns(tmp_path):
    """The command itself in a terminal of 80 columns (rich reads COLUMNS)."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "COLUMNS": "80", "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-m", "cogniframe", "printers"], capture_output=True, text=True, env=env,
                         cwd=tmp_path, timeout=120)
    assert out.returncode == 0, out.stderr
    assert max(len(line) for line in out.stdout.splitlines()) <= 80
    assert "bambu_x1c" in out.stdout and "bambustudio" in out.stdout


@pytest.mark.cad
def test_180mm_printer_packs_the_carbon_parts_on_fewer_plates_than_120mm(tmp_path):
    """Real carbon part meshes (CAD), packed for the Monoprice Mini v2 (120 mm) and the Prusa MINI (180 mm).

    One frame's parts already fit one plate per material at 120 mm (2 plates: TPU, ABS), the
    fewest possible; the bed size shows once a maker prints a frame plus a spare set of parts."""
    import trimesh

    from cogniframe import design as design_mod
    from cogniframe.cache import cache_dir
    from cogniframe.export.part_files import build_parts
    from cogniframe.export.plates import PlateItem, pack_plates

    small = spec_mod.from_dict({**yaml.safe_load((ROOT / "params/carbon.yaml").read_text()), "printer": {"preset": "monoprice_mini_v2"}})
    big = spec_mod.from_dict({**yaml.safe_load((ROOT / "params/carbon.yaml").read_text()), "printer": {"preset": "prusa_mini"}})
    d = design_mod.design(small)
    built = build_parts(small, d.frame, d.parts, tmp_path, cache_dir=cache_dir())
    meshes = {b.name: trimesh.load(tmp_path / b.stl, force="mesh") for b in built}

    def plates(spec, sets):
        items = [PlateItem(b.name, b.material, b.qty * sets, meshes[b.name]) for b in built]
        return pack_plates(items, spec.printer.bed, spec.printer.margin)

    one_small, one_big = plates(small, 1), plates(big, 1)
    assert len(one_small) == len(one_big) == 2  # one per material: nothing to gain
    assert sum(p.fill for p in one_big) < 0.6 * sum(p.fill for p in one_small)  # same parts, 2.25x the bed area
    two_small, two_big = plates(small, 2), plates(big, 2)
    assert len(two_big) < len(two_small), ([p.name for p in two_small], [p.name for p in two_big])
    # 40 TPU copies need 2 small beds; two sets of the core (the sensor and camera mounts, the pegged
    # plate's X with its tubes) 2
    assert [p.name for p in two_small] == ["abs_1", "abs_2", "tpu_95a_1", "tpu_95a_2"]
    assert [p.name for p in two_big] == ["abs_1", "tpu_95a_1"]


# -- schema and presets -------------------------------------------------------------------------

def test_shipped_schema_is_the_generated_one_and_valid_json_schema():
    from jsonschema import Draft202012Validator

    shipped = json.loads(SCHEMA.read_text(encoding="utf-8"))
    assert shipped == spec_mod.json_schema(), ("cogniframe/data/params.schema.json is stale: regenerate it with "
                                               "`python -m cogniframe schema > cogniframe/data/params.schema.json`")
    assert SCHEMA.read_text(encoding="utf-8") == json.dumps(spec_mod.json_schema(), indent=2) + "\n"
    Draft202012Validator.check_schema(shipped)
    validator = Draft202012Validator(shipped)
    for name in ("carbon", "bamboo"):
        data = yaml.safe_load((ROOT / "params" / f"{name}.yaml").read_text(encoding="utf-8"))
        assert not list(validator.iter_errors(data)), name
    bad = list(validator.iter_errors({"printer": {"preset": "nope", "nozzle": 5}, "frame": {"widht": 200}}))
    assert len(bad) == 3  # unknown preset, nozzle over 1.2, misspelt key


@pytest.mark.parametrize("name", ["carbon", "bamboo"])
def test_presets_first_line_is_the_schema_line(name):
    repo = (ROOT / "params" / f"{name}.yaml").read_text(encoding="utf-8").splitlines(keepends=True)
    shipped = (PKG / "data" / "presets" / f"{name}.yaml").read_text(encoding="utf-8").splitlines(keepends=True)
    for path, lines in ((ROOT / "params" / f"{name}.yaml", repo), (PKG / "data" / "presets" / f"{name}.yaml", shipped)):
        assert lines[0].startswith(presets.SCHEMA_LINE), path
        target = (path.parent / lines[0][len(presets.SCHEMA_LINE):].strip()).resolve()
        assert target == SCHEMA.resolve(), f"{path}: the schema line points at {target}"
    assert repo[1:] == shipped[1:], (f"cogniframe/data/presets/{name}.yaml differs from params/{name}.yaml: copy it "
                                     f"over, keeping its first line (the schema path relative to the package)")


# -- new ----------------------------------------------------------------------------------------

def test_new_writes_a_commented_valid_params_file(run_cli, tmp_path):
    code, out, err = run_cli("new", "mydrone", "--from", "bamboo", cwd=tmp_path)
    assert code == 0, err
    path = tmp_path / "mydrone.yaml"
    text = path.read_text(encoding="utf-8")
    first = text.splitlines()[0]
    assert first.startswith(presets.SCHEMA_LINE)
    assert (tmp_path / first[len(presets.SCHEMA_LINE):]).resolve() == SCHEMA.resolve()
    assert text.count(" # ") > 30 and "params/bamboo.yaml" not in text
    spec = spec_mod.load(path)
    bamboo = spec_mod.load(ROOT / "params" / "bamboo.yaml")
    assert spec.name == "mydrone"
    assert spec.model_dump(exclude={"name"}) == bamboo.model_dump(exclude={"name"})
    code, _, _ = run_cli("new", "carbon2", cwd=tmp_path)
    assert code == 0 and spec_mod.load(tmp_path / "carbon2.yaml").printer.preset == "monoprice_mini_v2"


def test_new_refuses_to_overwrite(run_cli, tmp_path):
    path = tmp_path / "mine.yaml"
    path.write_text("keep me\n", encoding="utf-8")
    code, _, err = run_cli("new", "mine", cwd=tmp_path)
    assert code == 2 and "already exists" in err
    assert path.read_text(encoding="utf-8") == "keep me\n"
    code, _, err = run_cli("new", "x", "--from", "steel", cwd=tmp_path)
    assert code == 2 and "carbon, bamboo" in err and not (tmp_path / "x.yaml").exists()
    code, _, err = run_cli("new", ".hidden", cwd=tmp_path)  # the same name rule as spec.load
    assert code == 2 and "e.g. hidden" in err and not list(tmp_path.glob("*hidden*"))
