"""Params files: presets load, every validation path gives a plain message naming file, key and fix."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from cogniframe import spec as spec_mod
from cogniframe.errors import UserError
from cogniframe.materials import MATERIALS, MOTOR_PRESETS, lookup

PARAMS = Path(__file__).resolve().parents[1] / "params"


def write(tmp_path: Path, data: dict, name: str = "x.yaml") -> Path:
    p = tmp_path / name
    p.write_text(yaml.safe_dump(data))
    return p


def load_error(tmp_path: Path, data: dict) -> str:
    with pytest.raises(UserError) as e:
        spec_mod.load(write(tmp_path, data))
    return str(e.value)


def test_presets_load_with_their_names(preset):
    assert preset.name in ("carbon", "bamboo")
    assert preset.rods.diameter == 3.0
    assert preset.printer.bed == (120, 120, 120)


def test_carbon_preset_is_the_papers_build(carbon):
    """The box is the authors' frame as their CAD draws it (thecognifly/CogniFly-STL,
    CogniFly_v8_Crash_Tests, CogniFly-Flex.FCStd, read by tools/authors_frame.py): the cage's rod
    axes 204.4 apart across and 106.6 apart in height (their rods' end faces, to 0.1 mm; the paper's
    text rounds the frame to 210 x 210 x 120). Blind sockets 2.70 mm for the 3 mm rods."""
    from cogniframe import frame as frame_mod

    lo, hi = frame_mod.frame_of(carbon).bbox()
    assert hi - lo == pytest.approx((204.4, 204.4, 106.6), abs=0.2)
    assert carbon.bore == pytest.approx(2.70)
    assert carbon.rods.material == "carbon_rod" and carbon.joints.material == "tpu_95a"
    assert carbon.core.material == "abs" and carbon.core.battery.mass == 58
    assert carbon.motors.model == "1104" and carbon.requirements.mass_limit == 250


def test_bamboo_preset_uses_skewers_and_1404(bamboo):
    assert bamboo.rods.material == "bamboo" and bamboo.motors.model == "1404"
    assert bamboo.rods.stock_length == 250


def test_presets_are_commented_for_makers():
    for name in ("carbon", "bamboo"):
        text = (PARAMS / f"{name}.yaml").read_text()
        # every "key: value" line (not section headers, not list items) explains itself
        valued = [ln for ln in text.splitlines() if re.match(r"^\s*[a-z_]+:\s*[^#\s]", ln)]
        bare = [ln for ln in valued if "#" not in ln]
        assert len(valued) > 40 and not bare, (name, bare)


def test_unknown_key_suggests_the_closest(tmp_path):
    msg = load_error(tmp_path, {"joints": {"wal": 2}})
    assert "x.yaml" in msg and "joints.wal" in msg and "did you mean 'wall'" in msg
    assert "(line 2)" in msg


def test_unknown_section_suggests_the_closest(tmp_path):
    msg = load_error(tmp_path, {"rod": {"diameter": 3}})
    assert "rod" in msg and "did you mean 'rods'" in msg


def test_negative_diameter_names_key_and_range(tmp_path):
    msg = load_error(tmp_path, {"rods": {"diameter": -3}})
    assert "rods.diameter" in msg and "got -3" in msg and ">= 1.0" in msg


def test_unknown_material_lists_choices(tmp_path):
    msg = load_error(tmp_path, {"rods": {"material": "steel"}})
    assert "rods.material" in msg and "carbon_rod" in msg and "materials:" in msg


def test_user_material_is_accepted(tmp_path):
    s = spec_mod.load(write(tmp_path, {"materials": {"oak": {"density_g_cm3": 0.75, "e_mpa": 11000, "g_mpa": 700}},
                                       "rods": {"material": "oak"}}))
    assert s.material("oak").density_g_cm3 == 0.75 and not s.material("oak").printed


def test_printed_material_cannot_be_a_rod(tmp_path):
    msg = load_error(tmp_path, {"rods": {"material": "pla"}})
    assert "rods are never printed" in msg


def test_missing_fit_clearance_for_joint_material(tmp_path):
    msg = load_error(tmp_path, {"joints": {"material": "petg"}})
    assert "joints.fit_clearance" in msg and "petg: 0.1" in msg


def test_wall_too_thin_for_the_nozzle(tmp_path):
    msg = load_error(tmp_path, {"joints": {"wall": 0.9}, "printer": {"nozzle": 0.6}})
    assert "joints.wall" in msg and "1.2" in msg


def test_wall_too_thin_for_a_thick_rod(tmp_path):
    msg = load_error(tmp_path, {"rods": {"diameter": 6}, "joints": {"wall": 1.6, "socket_depth": 14}})
    assert "joints.wall" in msg and "2.40" in msg


def test_shallow_socket_rejected(tmp_path):
    msg = load_error(tmp_path, {"rods": {"diameter": 4}, "joints": {"socket_depth": 6}})
    assert "joints.socket_depth" in msg and "at least 8" in msg


def test_core_too_big_for_the_box(tmp_path):
    msg = load_error(tmp_path, {"core": {"plate_size": 190}})
    assert "core.plate_size" in msg and "smaller than" in msg


def test_bad_stack_pattern_lists_choices(tmp_path):
    msg = load_error(tmp_path, {"core": {"stack_pattern": "25x25"}})
    assert "core.stack_pattern" in msg and "20x20" in msg and "30.5x30.5" in msg


def test_not_yaml(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text("frame:\n  width: [210\n")
    with pytest.raises(UserError) as e:
        spec_mod.load(p)
    assert "bad.yaml" in str(e.value) and "line" in str(e.value)


def test_missing_file(tmp_path):
    with pytest.raises(UserError) as e:
        spec_mod.load(tmp_path / "nope.yaml")
    assert "nope.yaml" in str(e.value) and "no such params file" in str(e.value)


def test_top_level_list_rejected(tmp_path):
    p = tmp_path / "list.yaml"
    p.write_text("- 1\n- 2\n")
    with pytest.raises(UserError) as e:
        spec_mod.load(p)
    assert "mapping of sections" in str(e.value)


def test_several_problems_reported_together(tmp_path):
    msg = load_error(tmp_path, {"rods": {"diameter": -1}, "frame": {"widht": 200}})
    assert "rods.diameter" in msg and "frame.widht" in msg


def test_digest_tracks_only_named_sections(carbon):
    other = carbon.model_copy(update={"rods": carbon.rods.model_copy(update={"material": "bamboo"})})
    assert carbon.digest("joints") == other.digest("joints")
    assert carbon.digest("rods") != other.digest("rods")


def test_json_schema_lists_sections():
    schema = spec_mod.json_schema()
    assert set(schema["properties"]) >= {"frame", "rods", "joints", "core", "motors", "printer", "requirements", "model"}
    assert schema["additionalProperties"] is False


def test_materials_library_has_sources():
    assert set(MATERIALS) >= {"carbon_rod", "bamboo", "tpu_95a", "abs", "pla", "petg"}
    for m in MATERIALS.values():
        assert m.density_g_cm3 > 0 and m.e_mpa > m.g_mpa > 0 and m.source


def test_lookup_lists_valid_choices():
    assert lookup(MOTOR_PRESETS, "1104", "motor").bolt_spacing == 9.0
    with pytest.raises(ValueError, match="valid choices: 1103, 1104, 1105, 1106, 1202, 1203, 1204, 1404, 1406, 1407, 1408, 1505"):
        lookup(MOTOR_PRESETS, "2207", "motor")


@pytest.mark.process
def test_check_does_not_import_cadquery(tmp_path):
    """Cold (the joints' FE solved on worker processes, which build their CAD there) and warm:
    the checking process itself never imports the CAD kernel."""
    code = "import sys; from cogniframe import api; " \
           "api.load('params/carbon.yaml').check(); print('cadquery' in sys.modules, 'OCP' in sys.modules)"
    env = {**os.environ, "COGNIFRAME_CACHE": str(tmp_path / "cache")}
    for _ in ("cold", "warm"):
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=PARAMS.parent, check=True, env=env)
        assert out.stdout.strip() == "False False"


def test_schema_command_prints_json(run_cli):
    code, out, _ = run_cli("schema")
    assert code == 0 and json.loads(out)["title"] == "Spec"
