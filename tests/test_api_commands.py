"""The API functions `check`, `coupon`, `schema`, `printers` and `new` call (docs/api.md), on
their own: the check's tables and drop plots, the socket-fit coupon, the printer presets, a new
params file from a preset, the params schema. The commands' words and exit codes are
tests/test_cli.py's, tests/test_presets.py's and tests/test_outdir.py's.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import cogniframe as cf
from cogniframe import spec as spec_mod
from cogniframe.api import presets
from cogniframe.errors import OutputError, UserError

ROOT = Path(__file__).resolve().parents[1]
CARBON = ROOT / "params" / "carbon.yaml"


@pytest.fixture(scope="module")
def fast_check():
    """The carbon preset on the joints' closed forms (milliseconds; no joint FE in a fresh cache)."""
    return cf.load(CARBON).with_fast_model().check()


# -- check ----------------------------------------------------------------------------------

def test_check_tables_are_the_report_for_the_console_width(fast_check):
    from rich.console import Console

    narrow = fast_check.tables(Console(width=100, color_system=None))
    lines = narrow.splitlines()
    assert "Mass budget: carbon" in narrow and fast_check.verdict in narrow
    assert max(len(line) for line in lines) <= 100
    # the all-up weight the table prints is the JSON's, to the table's 0.1 g
    assert f"{fast_check.mass_g:.1f}" in narrow
    wide = fast_check.tables(Console(width=160, color_system=None))
    assert max(len(line) for line in wide.splitlines()) > 100  # rendered for the console given


def test_check_drop_plots_are_two_pngs_and_never_over_a_foreign_file(fast_check, tmp_path):
    written = fast_check.write_drop_plots(tmp_path / "plots")
    assert [p.name for p in written] == ["drop_response.png", "energy_split.png"]
    for p in written:
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and p.stat().st_size > 10_000
    again = fast_check.write_drop_plots(tmp_path / "plots")  # its own files: written again
    assert [p.name for p in again] == ["drop_response.png", "energy_split.png"]
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "energy_split.png").write_bytes(b"my own picture")
    with pytest.raises(OutputError, match="energy_split.png already exists and was not written by cogniframe"):
        fast_check.write_drop_plots(mine)
    # both are checked before either is written
    assert not (mine / "drop_response.png").exists()
    assert (mine / "energy_split.png").read_bytes() == b"my own picture"


# -- coupon ---------------------------------------------------------------------------------

@pytest.mark.cad
def test_coupon_file_writes_one_socket_per_clearance_in_the_joints_material(tmp_path):
    from cogniframe.api.coupons import coupon_file
    from cogniframe.export.mesh import load_stl

    c = coupon_file(CARBON, tmp_path / "c" / "coupon.stl")
    assert c.path == tmp_path / "c" / "coupon.stl"
    # -0.40 .. +0.30 mm in 0.05 mm steps: past the authors' blind sockets and sleeves (docs/authors-parts.md)
    assert c.clearances_mm == pytest.approx([round(-0.40 + 0.05 * i, 2) for i in range(15)])
    assert c.material == "tpu_95a"  # the carbon preset's joints
    mesh = load_stl(c.path)
    assert mesh.is_watertight and mesh.volume > 0
    assert all(e <= b for e, b in zip(mesh.extents, spec_mod.load(CARBON).printer.bed))


@pytest.mark.cad
def test_coupon_too_big_for_the_bed_names_the_key_and_writes_nothing(tmp_path):
    from cogniframe.api import ParamsError
    from cogniframe.api.coupons import coupon_file

    text = CARBON.read_text(encoding="utf-8").replace("  bed: [120, 120, 120]", "  bed: [40, 40, 40]")
    assert "  bed: [40, 40, 40]" in text
    params = tmp_path / "tiny.yaml"
    params.write_text(text, encoding="utf-8")
    line = text[:text.index("  bed: [40, 40, 40]")].count("\n") + 1
    with pytest.raises(ParamsError) as e:
        coupon_file(params, tmp_path / "coupon.stl")
    assert e.value.key == "printer.bed"
    assert str(e.value).startswith(f"{params}: printer.bed (line {line}): coupon: ")
    assert "does not fit the 40 x 40 x 40 mm bed. Fix: set printer.bed" in str(e.value)
    assert not (tmp_path / "coupon.stl").exists()


def test_coupon_never_over_a_foreign_file(tmp_path):
    from cogniframe.api.coupons import coupon_file

    target = tmp_path / "coupon.stl"
    target.write_bytes(b"solid mine\n")
    with pytest.raises(OutputError, match="was not written by cogniframe"):
        coupon_file(CARBON, target)
    assert target.read_bytes() == b"solid mine\n"


# -- presets, new, schema -------------------------------------------------------------------

def test_printer_presets_are_the_shipped_table():
    from cogniframe.printers import PRINTERS

    got = presets.printer_presets()
    assert got == tuple(PRINTERS.values())
    by_key = {p.key: p for p in got}
    assert by_key["prusa_mini"].bed == (180.0, 180.0, 180.0)  # Prusa's MINI+ specification page
    assert by_key["prusa_mk4"].bed == (250.0, 210.0, 220.0)  # Prusa's MK4 specification page


def test_params_schema_is_the_shipped_schema_and_knows_the_keys():
    schema = presets.params_schema()
    assert schema == json.loads((ROOT / "cogniframe" / "data" / "params.schema.json").read_text(encoding="utf-8"))
    assert {"frame", "rods", "joints", "printer"} <= set(schema["properties"])


def test_new_params_is_the_preset_named_after_its_file(tmp_path):
    made = presets.new_params(tmp_path / "mydrone.yaml", "bamboo")
    assert made == presets.NewParams(tmp_path / "mydrone.yaml", "bamboo")
    text = made.path.read_text(encoding="utf-8")
    first = text.splitlines()[0]
    assert first.startswith(presets.SCHEMA_LINE)
    assert (tmp_path / first[len(presets.SCHEMA_LINE):]).resolve() == presets.schema_path().resolve()
    spec = spec_mod.load(made.path)
    bamboo = spec_mod.load(ROOT / "params" / "bamboo.yaml")
    assert spec.name == "mydrone"
    assert spec.model_dump(exclude={"name"}) == bamboo.model_dump(exclude={"name"})


def test_new_params_refuses_what_it_cannot_write_and_writes_nothing(tmp_path):
    keep = tmp_path / "mine.yaml"
    keep.write_text("keep me\n", encoding="utf-8")
    with pytest.raises(UserError, match="already exists; `cogniframe new` never overwrites a file"):
        presets.new_params(tmp_path / "mine")
    assert keep.read_text(encoding="utf-8") == "keep me\n"
    with pytest.raises(UserError, match="steel: unknown preset. Fix: use one of carbon, bamboo"):
        presets.new_params(tmp_path / "x", "steel")
    with pytest.raises(UserError, match="not a usable design name .* e.g. hidden"):
        presets.new_params(tmp_path / ".hidden")
    with pytest.raises(UserError, match="no such folder"):
        presets.new_params(tmp_path / "nowhere" / "x")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.yaml"]
