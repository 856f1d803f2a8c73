"""Golden-file tests: every bad params file in tests/bad_inputs/ gives exactly its expected message.

Each `NAME.yaml` is one mistake a maker makes; `NAME.expected` is the one paragraph cogniframe
must print for it (exit 2, nothing written), for `check` and for `build`. The corpus covers every
stage that can refuse a design: parsing (encoding, YAML, duplicate keys), the schema, cross-field
rules (printer sanity, walls, sockets, names), the frame graph, the part list / printer fit and
the cut list. Regenerate the expected texts after a deliberate wording change with
`COGNIFRAME_REGEN_GOLDEN=1 python -m pytest tests/test_bad_inputs.py` and review the diff.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

CORPUS = Path(__file__).resolve().parent / "bad_inputs"
CASES = sorted(p.stem for p in CORPUS.glob("*.yaml"))
REGEN = os.environ.get("COGNIFRAME_REGEN_GOLDEN") == "1"


def _tree(root: Path) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): (p.read_bytes() if p.is_file() else b"<dir>") for p in root.rglob("*")}


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("command", ["check", "build"])
def test_bad_input_gives_its_expected_paragraph(case, command, run_cli, tmp_path):
    shutil.copy(CORPUS / f"{case}.yaml", tmp_path / f"{case}.yaml")
    before = _tree(tmp_path)
    code, out, err = run_cli(command, f"{case}.yaml", cwd=tmp_path)
    assert code == 2, (code, out, err)
    assert "Traceback" not in err and out == ""
    expected_path = CORPUS / f"{case}.expected"
    if REGEN and command == "check":
        expected_path.write_text(err, encoding="utf-8")
    expected = expected_path.read_text(encoding="utf-8")
    assert err == expected
    assert err.startswith(f"error: {case}.yaml: ")  # the file is named first
    assert "Fix" in err
    assert _tree(tmp_path) == before  # nothing written, not even out/


def test_corpus_is_complete():
    """Every case has its expected text, and the corpus spans the stages (see the module docstring)."""
    assert len(CASES) >= 30
    assert sorted(p.stem for p in CORPUS.glob("*.expected")) == CASES
