"""The joint kinds (families/joint_kinds/): one suite over every registered kind, each on a design
that makes it, and a new kind is one module and one registry line (`kinds.KINDS`)."""

from __future__ import annotations

import functools
import types
from pathlib import Path

import numpy as np
import pytest

from cogniframe import frame as frame_mod
from cogniframe import partlist
from cogniframe import spec as spec_mod
from cogniframe.families import registry
from cogniframe.families.joint_kinds import kinds
from cogniframe.families.joint_kinds.kind import JointKind
from cogniframe.parts.joint_plan import FLIP_X, map_sockets, transform
from cogniframe.parts.record import Estimate

ROOT = Path(__file__).resolve().parents[1]

# A design that makes each registered kind: the carbon preset (pegged links), its tab link on its
# level arms (the flat link) and on bent arms (the tab link). A new kind adds its line here.
DESIGNS = {
    "corner_top": {},
    "corner_bottom": {},
    "knee": {},
    "core_link_pegs": {},
    "core_link_flat": {"core": {"link": "tab"}},
    "core_link_tab": {"core": {"link": "tab"}, "frame": {"level_arms": False}},
}


@functools.lru_cache(maxsize=None)
def _planned(label: str):
    import yaml

    data = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text())
    for section, values in DESIGNS.get(label, {}).items():
        data.setdefault(section, {}).update(values)
    spec = spec_mod.from_dict(data)
    frame = frame_mod.frame_of(spec)
    return spec, frame, partlist.part_list(spec, frame)


def _parts_of(kind: JointKind, parts):
    return [p for p in parts if p.family == "joint" and kinds.kind_of(p) is kind]


def _check_kind(spec, kind: JointKind, part) -> None:
    """What every joint kind answers, on one of its parts (no CAD)."""
    from cogniframe.analysis.joints import analytic_joint
    from cogniframe.analysis.joints.surrogate import family_of

    assert kinds.node_of(part) == kind.node and kinds.kind_of(part) is kind
    # the plan stored the kind's own closed form
    assert part.estimate == kind.estimate(spec, list(part.sockets), dict(part.params))
    est = part.estimate
    assert est.volume > 0 and est.area_h > 0 and est.area_v > 0
    assert list(est.envelope) == sorted(est.envelope, reverse=True)
    # print orientation: a rigid turn, every socket's axis at least a sleeve radius above the bed
    m = kinds.print_from_local(part)
    assert np.allclose(m[:3, :3] @ m[:3, :3].T, np.eye(3)) and np.linalg.det(m[:3, :3]) == pytest.approx(1.0)
    assert np.array_equal(m, registry.print_from_local(part))
    r = (part.sockets[0].bore + 2 * part.wall) / 2
    low = min(float(z) for s in map_sockets(part, m) for z in (s.port[2], s.mouth[2]))
    assert low >= r - 1e-6, f"{part.name}: a socket's axis {low:.3f} mm above the bed, under its sleeve's radius {r:.3f}"
    # the FE holds a support body exactly where the kind says it has one
    assert (kind.support_faces(part, m, 0.1, 8) is not None) == kind.has_body
    assert family_of(part) == kind.surrogate_family
    if kind.closed_form_stiffness:
        js = analytic_joint(spec, part)
        assert ("body" in js.labels) == kind.has_body
        assert len(js.labels) == len(part.sockets) + kind.has_body
    else:
        with pytest.raises(ValueError, match="no closed form"):
            analytic_joint(spec, part)


def test_every_registered_kind_has_a_design_in_this_suite():
    assert set(DESIGNS) == set(kinds.labels())
    assert len(set(kinds.labels())) == len(kinds.KINDS)


@pytest.mark.parametrize("label", kinds.labels())
def test_joint_kind_keeps_the_kind_contract(label):
    kind = next(k for k in kinds.KINDS if k.label == label)
    spec, _, parts = _planned(label)
    mine = _parts_of(kind, parts)
    assert mine, f"the design for {label} makes no {label} joint"
    assert kinds.resolve(kind.node, dict(mine[0].params), mine[0].sockets) is kind
    for p in mine:
        _check_kind(spec, kind, p)


@pytest.mark.parametrize("node", kinds.NODES)
def test_each_node_of_a_design_has_one_planned_kind(node):
    for label in DESIGNS:
        spec, _, parts = _planned(label)
        k = kinds.planned(spec, node)
        assert k.node == node and sum(1 for x in kinds.KINDS if x.node == node and x.plans(spec)) == 1
        # the parts of that node are the planned kind or a kind its plan becomes on its sockets (the flat link)
        assert {kinds.kind_of(p).node for p in parts if p.family == "joint" and kinds.node_of(p) == node} == {node}


@pytest.mark.cad  # main's test tiers (tests/tiers.py) register it: the fast tier leaves this out
@pytest.mark.parametrize("label", kinds.labels())
def test_joint_kind_closed_form_tracks_its_solid(label):
    kind = next(k for k in kinds.KINDS if k.label == label)
    _, _, parts = _planned(label)
    part = _parts_of(kind, parts)[0]
    built = kinds.solid(part)
    assert np.array_equal(built.print_from_local, kinds.print_from_local(part))
    vol = built.shape.Volume()
    assert abs(part.estimate.volume / vol - 1) < 0.15, f"{label}: estimate {part.estimate.volume:.0f} vs CAD {vol:.0f} mm^3"


def _toy_module() -> types.ModuleType:
    """A kind's module, as a file in families/joint_kinds/ would be: a top corner made another way
    (a `toy` param on the part), with its own closed form and print orientation."""
    mod = types.ModuleType("toy_corner")

    class ToyCorner(JointKind):
        node = "corner_top"
        variant = "toy"

        def params(self, spec, frame, corner, origin, sockets):
            return [("toy", True)]

        def claims(self, params, sockets):
            return bool(params.get("toy"))

        def estimate(self, spec, sockets, params):
            return Estimate(1000.0 + len(sockets), 500.0, 400.0, (20.0, 10.0, 5.0))

        def print_from_local(self, part):
            return transform(FLIP_X, (0.0, 0.0, (part.sockets[0].bore + 2 * part.wall) / 2 + 5.0))  # upside down, 5 mm up

    mod.ToyCorner = ToyCorner
    return mod


def test_a_new_joint_kind_is_one_module_and_one_registry_line(monkeypatch):
    """A kind registered in `kinds.KINDS` (before the kind it replaces at its node) is planned into
    the part list, its params, closed form and print orientation are the part's, the joint
    stiffness asks it, and the suite over the kinds holds for it: nothing else needs to know it."""
    toy = _toy_module().ToyCorner()
    spec, frame, before = _planned("corner_top")
    monkeypatch.setattr(kinds, "KINDS", (toy, *kinds.KINDS))  # the registry line
    after = partlist.part_list(spec, frame)
    assert [p.name for p in after] == [p.name for p in before]
    part = next(p for p in after if p.name == "corner_top")
    assert dict(part.params)["toy"] is True and kinds.kind_of(part) is toy
    assert part.estimate == Estimate(1000.0 + len(part.sockets), 500.0, 400.0, (20.0, 10.0, 5.0))
    assert part.digest != next(p for p in before if p.name == "corner_top").digest
    assert [p for p in after if p.name != "corner_top"] == [p for p in before if p.name != "corner_top"]
    assert kinds.print_from_local(part)[2, 3] == pytest.approx(part.wall + part.sockets[0].bore / 2 + 5.0)
    assert "corner_top_toy" in kinds.labels()
    _check_kind(spec, toy, part)


def test_no_module_but_the_kinds_dispatches_on_a_joint_kind_string():
    """Outside families/joint_kinds/ nothing compares a core link's style (`"pegs"`, `"tab"`), a
    part's kind string or a tuple of kind names: it asks the kind. spec.py and frame.py sit below
    the families (the params' checks, the frame's geometry) and read core.link themselves."""
    import re

    pattern = re.compile(r'[!=]=\s*"(pegs|tab|flat)"|kind\w*\([^)]*\)\s*[!=]=\s*"|in \(\s*"(corner_top|corner_bottom|knee|core_link)"')
    allowed = {"spec.py", "frame.py"}
    pkg = ROOT / "cogniframe"
    found = [f"{f.relative_to(pkg)}:{i}" for f in sorted(pkg.rglob("*.py"))
             if "joint_kinds" not in f.parts and f.relative_to(pkg).as_posix() not in allowed
             for i, line in enumerate(f.read_text().splitlines(), 1) if pattern.search(line)]
    assert found == []
