"""Output folders cogniframe owns: it never deletes or overwrites what it did not make.

Each test reproduces a way the earlier build destroyed a user's files, then checks the fix.
The folder logic runs before any CAD, so most of these are fast; `fake_output` makes a folder
exactly as a finished build leaves it (a manifest listing its files).
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import pytest

from cogniframe import outdir
from cogniframe.errors import OutputError

ROOT = Path(__file__).resolve().parents[1]


def fake_output(folder: Path, files: dict[str, bytes]) -> Path:
    """A folder as a cogniframe build leaves it: its files plus a manifest that lists them."""
    folder.mkdir(parents=True)
    entries = []
    for rel, data in sorted(files.items()):
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        (folder / rel).write_bytes(data)
        entries.append({"path": rel, "size": len(data), "sha256": hashlib.sha256(data).hexdigest()})
    (folder / "manifest.json").write_text(json.dumps({"generator": "cogniframe", "name": folder.name,
                                                      "files": entries}))
    return folder


def snapshot(root: Path) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


# ---- the reported damage, reproduced through the CLI -----------------------------------------

def test_build_into_a_folder_of_user_files_refuses_and_keeps_them(run_cli, tmp_path):
    docs = tmp_path / "mydocs"
    docs.mkdir()
    (docs / "thesis.tex").write_text("four years of work")
    (docs / "figs").mkdir()
    (docs / "figs" / "a.png").write_bytes(b"png")
    code, out, err = run_cli("build", ROOT / "params" / "carbon.yaml", "-o", docs, cwd=tmp_path)
    assert code == 2
    assert "mydocs" in err and "thesis.tex" in err and "figs/" in err and "-o" in err
    assert snapshot(docs) == {"thesis.tex": b"four years of work", "figs/a.png": b"png"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mydocs"]  # no lock, no temp folder left


def test_empty_name_cannot_make_out_itself_the_output(run_cli, tmp_path):
    other = fake_output(tmp_path / "out" / "bamboo", {"report.html": b"<html>cogniframe</html>"})
    before = snapshot(tmp_path / "out")
    params = tmp_path / "x.yaml"
    params.write_text('name: ""\n')
    code, _, err = run_cli("build", params, cwd=tmp_path)
    assert code == 2 and "name (line 1)" in err and "x.yaml" in err
    assert snapshot(tmp_path / "out") == before and other.is_dir()


def test_out_parent_with_another_design_is_not_a_cogniframe_folder(run_cli, tmp_path):
    """Even by -o, the folder that holds other designs' builds is never replaced."""
    fake_output(tmp_path / "out" / "bamboo", {"check.json": b"{}"})
    before = snapshot(tmp_path / "out")
    code, _, err = run_cli("build", ROOT / "params" / "carbon.yaml", "-o", tmp_path / "out", cwd=tmp_path)
    assert code == 2 and "not a cogniframe output folder" in err and "bamboo/" in err
    assert snapshot(tmp_path / "out") == before


@pytest.mark.parametrize("name", ["../../escaped", "/tmp/escaped", "a/b", ".hidden", "x" * 65, "sp ace", ".."])
def test_names_that_leave_out_are_refused(run_cli, tmp_path, name):
    params = tmp_path / "x.yaml"
    params.write_text(f"name: {json.dumps(name)}\n")
    code, _, err = run_cli("build", params, cwd=tmp_path)
    assert code == 2 and "x.yaml: name (line 1)" in err and "for example `name: " in err
    assert sorted(p.name for p in tmp_path.parent.iterdir() if "escaped" in p.name) == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.yaml"]


def test_a_file_name_stem_that_is_not_a_slug_becomes_one(tmp_path):
    from cogniframe import spec as spec_mod

    p = tmp_path / "My Frame (v2).yaml"
    p.write_text("frame: {width: 210}\n")
    assert spec_mod.load(p).name == "My-Frame-v2"


# ---- the ownership rules ------------------------------------------------------------------

def test_absent_and_empty_folders_may_be_written(tmp_path):
    outdir.check_replaceable(tmp_path / "new")
    (tmp_path / "empty").mkdir()
    outdir.check_replaceable(tmp_path / "empty")


def test_own_folder_is_replaced_whole(tmp_path):
    final = fake_output(tmp_path / "carbon", {"a.txt": b"old", "sub/b.txt": b"old"})
    with outdir.writing(final) as tmp:
        (tmp / "a.txt").write_bytes(b"new")
    assert snapshot(final) == {"a.txt": b"new"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["carbon"]
    assert oct(final.stat().st_mode & 0o777) != oct(0o700)  # an ordinary folder, not mkdtemp's 0700


def test_foreign_file_inside_own_folder_is_refused(tmp_path):
    final = fake_output(tmp_path / "carbon", {"a.txt": b"old"})
    (final / "notes.txt").write_text("mine")
    (final / "drafts").mkdir()
    with pytest.raises(OutputError) as e:
        with outdir.writing(final):
            pytest.fail("must not get a temp folder")
    assert "notes.txt" in str(e.value) and "drafts/" in str(e.value)
    assert snapshot(final)["notes.txt"] == b"mine"


def test_a_file_where_the_folder_should_be_is_refused(tmp_path):
    (tmp_path / "carbon").write_text("a file")
    with pytest.raises(OutputError):
        outdir.check_replaceable(tmp_path / "carbon")


def test_foreign_file_appearing_during_the_build_stops_the_swap(tmp_path):
    final = fake_output(tmp_path / "carbon", {"a.txt": b"old"})
    with pytest.raises(OutputError):
        with outdir.writing(final) as tmp:
            (tmp / "a.txt").write_bytes(b"new")
            (final / "late.txt").write_text("user saved this meanwhile")
    assert snapshot(final) == {"a.txt": b"old", "late.txt": b"user saved this meanwhile",
                               "manifest.json": snapshot(final)["manifest.json"]}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["carbon"]


def test_an_error_during_the_build_leaves_the_old_output(tmp_path):
    final = fake_output(tmp_path / "carbon", {"a.txt": b"old"})
    before = snapshot(final)
    with pytest.raises(KeyboardInterrupt):
        with outdir.writing(final) as tmp:
            (tmp / "a.txt").write_bytes(b"half")
            raise KeyboardInterrupt
    assert snapshot(final) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["carbon"]


def test_a_second_writer_is_refused_while_the_first_holds_the_lock(tmp_path):
    final = tmp_path / "carbon"
    with outdir.lock(final):
        with pytest.raises(OutputError) as e:
            with outdir.lock(final):
                pass
        assert f"pid {os.getpid()}" in str(e.value)
    with outdir.lock(final):  # released: the next one gets it
        pass
    assert list(tmp_path.iterdir()) == []


def test_lock_removes_the_parents_it_had_to_create_when_nothing_was_written(tmp_path):
    with outdir.lock(tmp_path / "a" / "b" / "carbon"):
        assert (tmp_path / "a" / "b").is_dir()
    assert list(tmp_path.iterdir()) == []


def test_stale_temp_folders_of_a_killed_build_are_cleaned(tmp_path):
    final = fake_output(tmp_path / "carbon", {"a.txt": b"old"})
    stale = tmp_path / ".carbon.cogniframe-tmp-dead1"
    stale.mkdir()
    (stale / outdir.TEMP_MARK).touch()
    (stale / "half.stl").write_bytes(b"x")
    users = tmp_path / ".carbon.mine"  # not cogniframe's pattern: untouched
    users.mkdir()
    with outdir.writing(final) as tmp:
        (tmp / "a.txt").write_bytes(b"new")
    assert not stale.exists() and users.is_dir()
    assert sorted(p.name for p in tmp_path.iterdir()) == [".carbon.mine", "carbon"]


def test_a_swap_cut_off_half_way_is_undone(tmp_path):
    """Killed between the two renames of the non-atomic swap: the old output is put back."""
    old = fake_output(tmp_path / "park" / "old", {"a.txt": b"old"})
    temp = tmp_path / ".carbon.cogniframe-tmp-dead2"
    (tmp_path / "park").rename(temp)
    (temp / outdir.TEMP_MARK).touch()
    assert not (tmp_path / "carbon").exists() and (temp / "old" / "a.txt").is_file()
    del old
    outdir.clean_stale(tmp_path / "carbon")
    assert snapshot(tmp_path / "carbon")["a.txt"] == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["carbon"]


def test_non_atomic_swap_path_also_replaces(tmp_path, monkeypatch):
    monkeypatch.setattr(outdir, "_exchange", lambda a, b: False)
    final = fake_output(tmp_path / "carbon", {"a.txt": b"old"})
    with outdir.writing(final) as tmp:
        (tmp / "a.txt").write_bytes(b"new")
    assert snapshot(final) == {"a.txt": b"new"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["carbon"]


# ---- single files -------------------------------------------------------------------------

@pytest.mark.fe
def test_check_plots_never_overwrite_a_users_png(run_cli, tmp_path):
    plots = tmp_path / "plots"
    plots.mkdir()
    (plots / "energy_split.png").write_bytes(b"\x89PNG my own figure")
    code, _, err = run_cli("check", ROOT / "params" / "carbon.yaml", "--plots", plots)
    assert code == 2 and "energy_split.png" in err
    assert sorted(p.name for p in plots.iterdir()) == ["energy_split.png"]  # the other one not written either
    assert (plots / "energy_split.png").read_bytes() == b"\x89PNG my own figure"


@pytest.mark.fe
def test_check_plots_may_overwrite_its_own_pngs(run_cli, tmp_path):
    for _ in range(2):
        code, _, err = run_cli("check", ROOT / "params" / "carbon.yaml", "--plots", tmp_path, "--json")
        assert code == 0, err
    assert outdir.MARK in (tmp_path / "drop_response.png").read_bytes()[:4096]


def test_coupon_never_overwrites_a_users_stl(run_cli, tmp_path):
    target = tmp_path / "coupon.stl"
    target.write_bytes(b"solid mine\nendsolid mine\n")
    code, _, err = run_cli("coupon", ROOT / "params" / "carbon.yaml", "-o", target)
    assert code == 2 and "coupon.stl" in err and "not written by cogniframe" in err
    assert target.read_bytes() == b"solid mine\nendsolid mine\n"
