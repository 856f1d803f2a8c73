"""examples/notebook.ipynb runs top to bottom in a fresh Jupyter kernel (nbclient + ipykernel) and
shows what it says: the check, the what-if table, the CLI's message for a bad value, the 3D
view, a build and a sweep. It runs in a copy of the repository's layout (examples/ beside
params/), so its build goes to that copy's out/, never the repository's.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.process
def test_example_notebook_runs(tmp_path):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    (tmp_path / "examples").mkdir()
    (tmp_path / "params").mkdir()
    shutil.copy(ROOT / "examples" / "notebook.ipynb", tmp_path / "examples")
    shutil.copy(ROOT / "params" / "carbon.yaml", tmp_path / "params")
    nb = nbformat.read(tmp_path / "examples" / "notebook.ipynb", as_version=4)
    assert not any(c.get("outputs") for c in nb.cells if c.cell_type == "code"), "the notebook is kept without outputs"
    nbclient.NotebookClient(nb, timeout=1200, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path / "examples")}}).execute()

    def text(cell) -> str:
        out = []
        for o in cell.get("outputs", []):
            if o.get("output_type") == "stream":
                out.append(o["text"])
            for mime in ("text/plain", "text/html"):
                if mime in o.get("data", {}):
                    out.append(o["data"][mime])
        return "\n".join(out)

    code = [c for c in nb.cells if c.cell_type == "code"]
    assert not [o for c in code for o in c.outputs if o.output_type == "error"]
    assert "<cogniframe.Design 'carbon' from ../params/carbon.yaml>" in text(code[0])
    assert "<table>" in text(code[1]) and "PASS" in text(code[1])
    assert text(code[2]).startswith("PASS: ")
    assert "rods.diameter" in text(code[3]) and "4.0" in text(code[3])
    line = next(i for i, ln in enumerate((ROOT / "params" / "carbon.yaml").read_text().splitlines(), 1)
                if ln.startswith("  diameter:"))
    assert text(code[4]).strip() == (f"../params/carbon.yaml: rods.diameter (line {line}): input should be less than or equal to 8 "
                                     "(got 20). Fix: set rods.diameter to a valid value (rod diameter, mm; must be >= 1.0; "
                                     "must be <= 8.0).")
    view = text(code[5])
    assert 'class="cf-viewer"' in view and "three.js" in view and "cf-view-wrap" in view
    assert "PASS ../out/carbon-notebook" in text(code[6]) and ".3mf" in text(code[6])
    manifest = json.loads((tmp_path / "out" / "carbon-notebook" / "manifest.json").read_text())
    assert manifest["params_file"] == "carbon.yaml"
    assert "max_safe_drop_cm" in text(code[7])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["examples", "out", "params"]
    assert sorted(p.name for p in (tmp_path / "examples").iterdir()) == ["notebook.ipynb"]
