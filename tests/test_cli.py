"""`cogniframe check`: tables, stable JSON keys, exit codes, plain errors without tracebacks."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.fe
def test_check_json_has_the_stable_keys(run_cli):
    code, out, _ = run_cli("check", ROOT / "params/carbon.yaml", "--json")
    data = json.loads(out)
    assert code == 0 and data["verdict"] == "PASS" and data["problems"] == []
    m = data["mass"]
    assert m["limit_g"] == 250 and set(m["groups"]) == {"exoskeleton", "core", "electronics", "battery"}
    assert m["total_g"] == pytest.approx(sum(i["mass_g"] for i in m["items"]), abs=0.05)
    assert {"name", "group", "qty", "mass_g"} <= set(m["items"][0])
    assert {"role", "length_mm", "qty", "diameter_mm", "material"} <= set(data["cutlist"][0])
    assert sum(r["qty"] for r in data["cutlist"]) == 28
    drop = data["drop"]
    assert {"k_n_per_m", "c_n_s_per_m", "damping_ratio", "mass_kg", "clearance_mm", "max_safe_height_cm",
            "k_source", "c_source", "heights"} <= set(drop)
    assert drop["k_source"] == "predicted" and drop["clearance_mm"] == pytest.approx(16.0)
    assert [h["height_cm"] for h in drop["heights"]] == [50, 100, 150, 262]
    assert {"x_max_mm", "peak_g", "energy_spring_pct", "energy_damper_pct", "energy_rigid_pct", "strikes"} <= set(drop["heights"][0])


@pytest.mark.fe
def test_check_table_shows_margin_and_verdict(run_cli):
    code, out, _ = run_cli("check", ROOT / "params/carbon.yaml")
    assert code == 0
    assert "Mass budget: carbon" in out and "margin" in out and "Cut list: 28 rods" in out
    assert "Max safe drop height" in out and out.rstrip().endswith("PASS")


def _variant(tmp_path: Path, base: str, **sections) -> Path:
    data = yaml.safe_load((ROOT / "params" / f"{base}.yaml").read_text())
    for sec, values in sections.items():
        if isinstance(values, dict):
            data.setdefault(sec, {}).update(values)
        else:
            data[sec] = values
    p = tmp_path / f"{base}_variant.yaml"
    p.write_text(yaml.safe_dump(data))
    return p


@pytest.mark.fe
def test_over_the_mass_limit_fails_with_exit_1(run_cli, tmp_path):
    p = _variant(tmp_path, "carbon", requirements={"mass_limit": 200})
    code, out, _ = run_cli("check", p, "--json")
    data = json.loads(out)
    assert code == 1 and data["verdict"] == "FAIL"
    assert any("over the 200 g limit" in s for s in data["problems"])


@pytest.mark.fe
def test_design_drop_above_max_safe_fails(run_cli, tmp_path):
    p = _variant(tmp_path, "carbon", requirements={"design_drop_height_cm": 200})
    code, out, _ = run_cli("check", p, "--json")
    data = json.loads(out)
    assert code == 1 and any("max safe drop height" in s for s in data["problems"])


@pytest.mark.fe
def test_measured_k_and_c_are_used_and_labelled(run_cli, tmp_path):
    p = _variant(tmp_path, "carbon", model={"k_n_per_m": 7040, "c_n_s_per_m": 46})
    _, out, _ = run_cli("check", p, "--json")
    drop = json.loads(out)["drop"]
    assert drop["k_source"] == drop["c_source"] == "measured"
    assert drop["k_n_per_m"] == 7040 and drop["c_n_s_per_m"] == 46


@pytest.mark.fe
def test_check_plots(run_cli, tmp_path):
    code, _, _ = run_cli("check", ROOT / "params/carbon.yaml", "--plots", tmp_path / "plots")
    assert code == 0
    for name in ("drop_response.png", "energy_split.png"):
        assert (tmp_path / "plots" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bad_key_is_exit_2_one_paragraph(run_cli, tmp_path):
    p = _variant(tmp_path, "bamboo", joints={"wal": 2})
    code, out, err = run_cli("check", p)
    assert code == 2 and out == ""
    assert "joints.wal" in err and "did you mean 'wall'" in err and p.name in err
    assert "Traceback" not in err


@pytest.mark.process
def test_errors_from_the_installed_command_have_no_traceback(tmp_path):
    p = _variant(tmp_path, "bamboo", rods={"diameter": -3})
    r = subprocess.run([sys.executable, "-m", "cogniframe", "check", str(p)], capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 2 and "rods.diameter" in r.stderr and "Traceback" not in r.stderr


def test_missing_file_is_exit_2(run_cli, tmp_path):
    code, _, err = run_cli("check", tmp_path / "missing.yaml")
    assert code == 2 and "no such params file" in err


@pytest.mark.parametrize("preset", ["carbon", "bamboo"])
@pytest.mark.fe
def test_both_presets_pass_their_requirements(run_cli, preset):
    code, out, _ = run_cli("check", ROOT / "params" / f"{preset}.yaml", "--json")
    data = json.loads(out)
    assert (code, data["verdict"], data["problems"]) == (0, "PASS", [])
    assert data["drop"]["max_safe_height_cm"] > 100 and data["mass"]["total_g"] < 250


def test_usage_error_is_exit_2_without_traceback(run_cli):
    code, out, err = run_cli("check", "--no-such-option")
    assert code == 2 and "Traceback" not in err and "no-such-option" in err


@pytest.mark.process
def test_cli_runs_without_a_top_level_click():
    # typer >= 0.29 vendors click: a fresh install has no `click` package, so nothing may import it
    code = ("import sys; sys.modules['click'] = None; from cogniframe.cli import main; "
            "sys.exit(main(['check', 'params/bamboo.yaml', '--json']))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["verdict"] == "PASS"


def test_part_too_big_for_the_printer_is_exit_2(run_cli, tmp_path):
    p = _variant(tmp_path, "bamboo", printer={"bed": [80, 80, 80]})
    code, out, err = run_cli("check", p)
    assert code == 2 and out == ""
    assert "battery_holder" in err and "printer.bed" in err and "80 x 80 x 80" in err


@pytest.mark.process
def test_leaving_runs_exit_handlers_flushes_output_and_keeps_the_code():
    """`cli._leave` ends the process with os._exit (no interpreter teardown): exit handlers still
    run, buffered output is not lost, the exit code is the command's."""
    code = ("import atexit; from cogniframe.cli import _leave; atexit.register(lambda: print('handler ran')); "
            "print('x' * 100000, end=''); _leave(3)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 3
    assert r.stdout == "x" * 100000 + "handler ran\n"


@pytest.mark.process
def test_leaving_skips_the_teardown_past_a_waiting_daemon_thread_but_waits_for_a_working_one(tmp_path):
    """A build that started a CAD server leaves a daemon thread waiting on it: `_leave` still ends
    with os._exit (no object is torn down: 0.5 s saved after a cold build). A thread that is not a
    daemon is waited for: its file gets written."""
    daemon = ("import threading; from cogniframe.cli import _leave\n"
              "class Noisy:\n    def __del__(self): print('torn down', flush=True)\n"
              "keep = Noisy()\n"
              "threading.Thread(target=threading.Event().wait, daemon=True).start()\n"
              "_leave(4)\n")
    r = subprocess.run([sys.executable, "-c", daemon], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert r.returncode == 4 and "torn down" not in r.stdout
    plain = daemon.replace("_leave(4)", "import sys; sys.exit(4)")
    r = subprocess.run([sys.executable, "-c", plain], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert r.returncode == 4 and r.stdout == "torn down\n"  # the probe works: a normal exit tears it down
    out = tmp_path / "written.txt"
    working = ("import threading, time; from pathlib import Path; from cogniframe.cli import _leave\n"
               f"threading.Thread(target=lambda: (time.sleep(0.3), Path({str(out)!r}).write_text('done'))).start()\n"
               "_leave(5)\n")
    r = subprocess.run([sys.executable, "-c", working], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert r.returncode == 5 and out.read_text() == "done"


def test_check_leaves_the_progress_log_as_it_found_it(run_cli, tmp_path):
    """`check` shows the joint FE's progress on stderr for its own run only: a handler left on the
    `cogniframe.progress` logger wrote to a closed stream later and hid its records from the
    caller (a test's caplog saw nothing)."""
    import logging

    log = logging.getLogger("cogniframe.progress")
    before = (list(log.handlers), log.propagate, log.level)
    p = _variant(tmp_path, "carbon", model={"stiffness_model": "analytic"}, core={"link": "tab"})
    code, out, _ = run_cli("check", p, "--json")
    assert code == 0 and json.loads(out)["verdict"] == "PASS"
    assert (list(log.handlers), log.propagate, log.level) == before


@pytest.mark.process
def test_leaving_with_a_closed_output_is_quiet():
    """A reader that went away (`cogniframe ... | head`) or a closed stdout: no traceback, the code kept."""
    code = "import sys; from cogniframe.cli import _leave; sys.stdout.write('x'); sys.stdout.close(); _leave(1)"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 1 and "Traceback" not in r.stderr and r.stderr == ""
