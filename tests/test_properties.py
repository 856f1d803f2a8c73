"""Property-based tests of `cogniframe check` (hypothesis): random params within and just outside the
schema's ranges never crash it.

Every rejection is exit 2 with one paragraph that starts with the params file; every accepted
design has finite, positive masses and stiffness. The `ci` profile (conftest.py) runs 15
reproducible examples per property; `HYPOTHESIS_PROFILE=nightly` runs 2000. The designs use the
analytic joint model (`model.stiffness_model: analytic`, the sweeps' fast path): the solid FE of
every new joint geometry would take seconds per example; the FE path has its own tests.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
from pathlib import Path

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pydantic import BaseModel

from cogniframe import spec as spec_mod
from cogniframe.cli import main
from cogniframe.materials import MOTOR_PRESETS

ROOT = Path(__file__).resolve().parents[1]
BASE = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text())


def numeric_fields(model: type[BaseModel] = spec_mod.Spec, prefix: str = "") -> list[tuple[str, type, float, float]]:
    """(dotted key, int|float, lo, hi) for every bounded number in the params schema."""
    out = []
    for name, field in model.model_fields.items():
        ann = field.annotation
        if getattr(ann, "__origin__", None) in (dict, tuple):  # user materials, components: not a fixed key
            continue
        sub = [a for a in (ann, *getattr(ann, "__args__", ())) if isinstance(a, type) and issubclass(a, BaseModel)]
        if sub:
            out += numeric_fields(sub[0], f"{prefix}{name}.")
            continue
        lo = hi = None
        for meta in field.metadata:
            lo = getattr(meta, "ge", None) if getattr(meta, "ge", None) is not None else getattr(meta, "gt", lo)
            hi = getattr(meta, "le", None) if getattr(meta, "le", None) is not None else getattr(meta, "lt", hi)
        kinds = {a for a in (ann, *getattr(ann, "__args__", ())) if a in (int, float)}
        if lo is not None and hi is not None and kinds:
            out.append((prefix + name, int if kinds == {int} else float, float(lo), float(hi)))
    return out


FIELDS = numeric_fields()


@st.composite
def value_for(draw, field):
    key, kind, lo, hi = field
    span = hi - lo
    where = draw(st.sampled_from(["inside", "inside", "inside", "edge", "below", "above"]))
    if where == "inside":
        v = draw(st.integers(int(lo), int(hi))) if kind is int else draw(st.floats(lo, hi, allow_nan=False))
    elif where == "edge":
        v = draw(st.sampled_from([lo, hi]))
    else:
        step = 1 if kind is int else max(span * draw(st.floats(1e-4, 0.2)), 1e-6)
        v = lo - step if where == "below" else hi + step
    return key, (int(v) if kind is int else float(v))


@st.composite
def overrides(draw):
    fields = draw(st.lists(st.sampled_from(FIELDS), min_size=1, max_size=3, unique_by=lambda f: f[0]))
    return [draw(value_for(f)) for f in fields]


def params_with(changes) -> dict:
    data = json.loads(json.dumps(BASE))
    data.setdefault("model", {})["stiffness_model"] = "analytic"
    for key, value in changes:
        node = data
        *parents, leaf = key.split(".")
        for p in parents:
            node = node.setdefault(p, {}) if isinstance(node.get(p), dict) or p not in node else node[p]
        if isinstance(node, dict):
            node[leaf] = value
    return data


def run_check(path: Path) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["check", str(path), "--json"])
    return code, out.getvalue(), err.getvalue()


def test_the_schema_has_bounded_numbers_in_every_section():
    sections = {k.split(".")[0] for k, *_ in FIELDS}
    assert {"frame", "rods", "joints", "core", "motors", "printer", "requirements", "model"} <= sections
    assert len(FIELDS) >= 30


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(changes=overrides())
def test_check_never_crashes_and_accepts_only_sound_designs(changes, tmp_path):
    path = tmp_path / "design.yaml"
    path.write_text(yaml.safe_dump(params_with(changes)))
    code, out, err = run_check(path)
    assert code in (0, 1, 2), (changes, code, err)
    assert "Traceback" not in err and "internal error" not in err, (changes, err)
    if code == 2:
        assert err.startswith(f"error: {path}: ") and "Fix" in err, (changes, err)
        assert out == ""
        return
    data = json.loads(out)
    mass = data["mass"]
    assert math.isfinite(mass["total_g"]) and mass["total_g"] > 0, changes
    assert all(math.isfinite(i["mass_g"]) and i["mass_g"] >= 0 for i in mass["items"]), changes
    k = data["drop"]["k_n_per_m"]
    assert math.isfinite(k) and k > 0, (changes, k)
    assert all(math.isfinite(h["x_max_mm"]) and h["x_max_mm"] > 0 for h in data["drop"]["heights"]), changes
    assert data["verdict"] == ("PASS" if code == 0 else "FAIL")
    # every design check accepts bolts together: its screws, holes and motor pattern fit
    assert data["fit"]["ok"], (changes, data["fit"]["problems"])


@settings(deadline=None)
@given(seed=st.integers(0, 2**32 - 1), model=st.sampled_from(sorted(MOTOR_PRESETS)))
def test_every_design_that_builds_passes_the_fit_check(seed, model):
    """Random designs across the schema (tests/design_space.py) with each motor of the catalogue:
    the part list is refused with a key, or its screws pass through their holes into their threads,
    its holes clear the rods and its motor holes are the motor's (analysis/fit_check.py)."""
    import random

    import design_space
    from cogniframe.analysis.verdict import fit_of
    from cogniframe.design import design
    from cogniframe.errors import UserError

    doc = design_space.random_design(random.Random(seed))
    doc["motors"]["model"] = model
    try:
        spec = spec_mod.from_dict(doc, "design.yaml")
        d = design(spec)
    except UserError as e:
        assert e.key or "design.yaml: " in str(e), str(e)
        return
    fit = fit_of(spec, d)
    assert fit.ok, (seed, model, fit.messages())
    mount = next(p for p in d.parts if p.family == "motor_mount")
    assert len(mount.param("holes")) in (2, 4)


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(field=st.sampled_from(FIELDS), side=st.sampled_from(["below", "above"]))
def test_a_value_outside_its_range_is_refused_naming_file_and_key(field, side, tmp_path):
    key, kind, lo, hi = field
    if kind is int:
        value = int(lo) - 1 if side == "below" else int(hi) + 1
    else:
        value = lo - max(abs(lo), 1.0) * 0.01 if side == "below" else hi + max(abs(hi), 1.0) * 0.01
    path = tmp_path / "design.yaml"
    path.write_text(yaml.safe_dump(params_with([(key, value)])))
    code, out, err = run_check(path)
    assert code == 2 and err.startswith(f"error: {path}: ") and key in err, (key, value, err)
