"""The clash check's pair memo (analysis/clash.py `memo`, kept between builds by cache.Memo):
remembered pairs give the same result as testing again, and after one solid moves only the
pairs that hold it are tested again (what makes a one-part rebuild's clash check cheap)."""

from __future__ import annotations

import pytest
import trimesh

from cogniframe import cache
from cogniframe.analysis import clash


class Counting(dict):
    """A memo that counts the pairs it had to be told (tested) and those it answered."""

    def __init__(self, *a):
        super().__init__(*a)
        self.stored, self.hits = 0, 0

    def get(self, key, default=None):
        hit = super().get(key, default)
        self.hits += hit is not None
        return hit

    def __setitem__(self, key, value):
        self.stored += 1
        super().__setitem__(key, value)


def _box(x: float, name: str) -> clash.Body:
    m = trimesh.creation.box(extents=(10, 10, 10))
    return clash.Body(name, "part", m, trimesh.transformations.translation_matrix((x, 0, 0)))


def _bodies(c_x: float = 40.0) -> list[clash.Body]:
    disc = trimesh.creation.cylinder(radius=10, height=1, sections=64)
    return [_box(0, "a"), _box(5, "b"),  # a and b: 5 x 10 x 10 = 500 mm^3 in common
            _box(c_x, "c"),
            clash.Body("prop", "propeller", disc, trimesh.transformations.translation_matrix((0, 0, 8.0)), disc=True)]


def test_overlap_of_two_boxes_is_their_common_volume_with_or_without_memo():
    plain = clash.check(_bodies(), prop_margin=5.0)
    memo = Counting()
    first = clash.check(_bodies(), prop_margin=5.0, memo=memo)
    again = clash.check(_bodies(), prop_margin=5.0, memo=memo)
    assert plain == first == again
    (ab,) = [c for c in plain.clashes if {c.a, c.b} == {"a", "b"}]
    assert ab.volume_mm3 == pytest.approx(500.0, rel=1e-6)
    # the disc (z 7.5..8.5) sits 2.5 mm above the boxes' tops (z 5): a margin clash with a and b
    assert {(c.a, c.kind) for c in plain.clashes if c.a == "prop"} == {("prop", "prop_margin")}
    assert dict((p, g) for p, _, g in plain.prop_gaps)["prop"] == pytest.approx(2.5, abs=1e-3)
    assert memo.stored == plain.pairs_tested and memo.hits == plain.pairs_tested  # second run: all remembered


def test_moving_one_solid_retests_only_its_pairs():
    memo = Counting()
    clash.check(_bodies(c_x=40.0), prop_margin=5.0, memo=memo)
    memo.stored = memo.hits = 0
    moved = clash.check(_bodies(c_x=12.0), prop_margin=5.0, memo=memo)  # c now overlaps b by 3 x 10 x 10
    # c's pairs that pass the box prefilter: with b (overlap) and with the disc (margin); a-b, a-prop, b-prop remembered
    assert memo.stored == 2 and memo.hits == moved.pairs_tested - 2
    assert moved == clash.check(_bodies(c_x=12.0), prop_margin=5.0)
    (bc,) = [c for c in moved.clashes if {c.a, c.b} == {"b", "c"}]
    assert bc.volume_mm3 == pytest.approx(300.0, rel=1e-6)


def test_a_margin_change_retests_the_disc_pairs_only():
    memo = Counting()
    clash.check(_bodies(), prop_margin=5.0, memo=memo)
    memo.stored = memo.hits = 0
    closer = clash.check(_bodies(), prop_margin=3.0, memo=memo)
    assert memo.stored == 2 and memo.hits == 1  # prop-a and prop-b again; a-b remembered
    assert {c.b for c in closer.clashes if c.kind == "prop_margin"} == {"a", "b"}  # 2.5 mm < 3 mm
    memo.stored = memo.hits = 0
    wide = clash.check(_bodies(), prop_margin=2.0, memo=memo)
    assert memo.stored == 0 and wide.pairs_tested == 1  # a disc 2.5 mm away is outside a 2 mm margin's box
    assert not [c for c in wide.clashes if c.kind == "prop_margin"]


def test_the_disk_memo_survives_processes_and_its_salt_separates_code_versions(tmp_path):
    store = cache.Memo("clash-pairs", "v1", tmp_path)
    clash.check(_bodies(), prop_margin=5.0, memo=store)
    files = sorted((tmp_path / "clash-pairs").glob("*.json"))
    result = clash.check(_bodies(), prop_margin=5.0)
    assert len(files) == result.pairs_tested
    assert clash.check(_bodies(), prop_margin=5.0, memo=cache.Memo("clash-pairs", "v1", tmp_path)) == result
    other = cache.Memo("clash-pairs", "v2", tmp_path)  # e.g. clash.py edited: nothing is reused
    clash.check(_bodies(), prop_margin=5.0, memo=other)
    assert len(list((tmp_path / "clash-pairs").glob("*.json"))) == 2 * result.pairs_tested
    # a damaged file is a miss, not an error
    files[0].write_text("{not json")
    assert clash.check(_bodies(), prop_margin=5.0, memo=store) == result
