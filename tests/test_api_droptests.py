"""`cogniframe.api.droptests`, the functions `drop` and `fit` call: the impact model against the
paper's numbers and its closed form, the drop-test folders' heights and masses, and a fit of
synthetic drops that recovers the c and k they were made with."""

from __future__ import annotations

import math

import pytest

from cogniframe.api import droptests
from cogniframe.errors import UserError
from droplogs import write_drops


def test_drop_with_zeta_uses_c_equal_2_zeta_sqrt_km_and_reproduces_the_paper():
    run = droptests.drop(0.241, 7040.0, [50, 100, 150], 16.0, zeta=0.558)
    assert run.c_n_s_per_m == pytest.approx(2 * 0.558 * math.sqrt(7040.0 * 0.241), rel=1e-12)
    by_c = droptests.drop(0.241, 7040.0, [50, 100, 150], 16.0, c=46.0).result
    # the paper's crash-test build (c = 46 N s/m): x_max per height, the holder strikes at 150 cm
    assert [round(h.x_max_mm, 2) for h in by_c.heights] == [9.63, 13.56, 16.57]
    assert [h.strikes for h in by_c.heights] == [False, False, True]
    assert run.written == ()
    with pytest.raises(ValueError):
        droptests.drop(0.241, 7040.0, [50], 16.0, c=46.0, zeta=0.558)


def test_drop_sources_take_the_height_from_the_manifest_else_the_folder_name(tmp_path):
    named = tmp_path / "Soft_75cm"
    named.mkdir()
    declared = tmp_path / "run2"
    declared.mkdir()
    (declared / "drop.yaml").write_text("height_cm: 50\nmass_kg: 0.24\n")
    pairs, masses = droptests.drop_sources([named, declared], [])
    assert pairs == [(75.0, named), (50.0, declared)] and masses == [0.24]
    assert droptests.drop_sources([named], [120.0])[0] == [(120.0, named)]
    (declared / "drop.yaml").write_text("height: 50\n")
    with pytest.raises(UserError, match="unknown key"):
        droptests.drop_sources([declared], [])


def test_fit_recovers_the_c_and_k_the_drops_were_made_with_and_stores_them(tmp_path):
    write_drops(tmp_path / "low_60cm", 60, 40.0, 8000.0, n_trials=6, seed=1)
    write_drops(tmp_path / "high_120cm", 120, 40.0, 8000.0, n_trials=6, seed=2)
    params = tmp_path / "p.yaml"
    params.write_text("# my build\nname: p  # kept\nmodel:\n  stiffness_model: analytic\n")
    droptests.check_params_file(params)
    pairs, _ = droptests.drop_sources([tmp_path / "low_60cm", tmp_path / "high_120cm"], [])
    seen = []
    heights = droptests.read_drops(pairs, on_total=seen.append)
    assert seen == [12] and [h.height_cm for h in heights] == [60.0, 120.0]
    run = droptests.fit(heights, 0.241, write=params)
    assert run.result.c_n_s_per_m == pytest.approx(40.0, rel=0.05)
    assert run.result.k_n_per_m == pytest.approx(8000.0, rel=0.05)
    assert run.to_dict() == run.result.to_dict()  # no predictions asked: the fit's own JSON
    text = params.read_text()
    assert "# my build" in text and "# kept" in text and "stiffness_model: analytic" in text
    assert f"k_n_per_m: {float(f'{run.result.k_n_per_m:.6g}')}" in text
