"""An error found by any later stage names the params file, the key with its line, and the fix.
The frame, part-list/printer-fit and cut-list stages are covered by the golden corpus
(tests/bad_inputs/); here the CAD stage, which runs in worker processes that only see a part."""

from __future__ import annotations


import pytest

from cogniframe import design as design_mod
from cogniframe import spec as spec_mod
from cogniframe.pipeline import run_build
from cogniframe.errors import UserError


@pytest.mark.cad
@pytest.mark.fe
@pytest.mark.slicer
def test_cad_stage_error_names_file_key_and_line(tmp_path, monkeypatch):
    params = tmp_path / "small_bed.yaml"
    params.write_text("name: small_bed\nprinter:\n  bed: [45, 45, 45]\n")
    spec = spec_mod.load(params)
    # Let the design through the analytic bed check so that the CAD stage is the one that finds it.
    monkeypatch.setattr(design_mod, "_check_printer_fit", lambda spec, parts: None)
    with pytest.raises(UserError) as e:
        run_build(spec, params, tmp_path / "out", jobs=1)
    msg = str(e.value)
    assert msg.startswith(f"{params}: printer.bed (line 3): ") and "Fix:" in msg, msg
    assert sorted(p.name for p in tmp_path.iterdir()) == ["small_bed.yaml"]  # nothing written


def test_stage_error_for_a_key_left_at_its_default_says_so(tmp_path):
    params = tmp_path / "bigprops.yaml"
    params.write_text("motors:\n  radius: 40\n")
    with pytest.raises(UserError) as e:
        design_mod.design(spec_mod.load(params))
    assert str(e.value).startswith(f"{params}: motors.prop_diameter (not set in the file: its default applies): ")


def test_located_errors_survive_a_process_pool():
    import pickle

    err = UserError("too big", key="printer.bed")
    back = pickle.loads(pickle.dumps(err))
    assert (str(back), back.key, back.located) == ("too big", "printer.bed", False)
