"""The plan of the code holds (tools/layout.py): data flows one way between the rooms, no two
modules import each other, and no module or function grows past what a reader takes in at once.
And the joints' plan geometry, which `check` reads, pulls in no CAD kernel."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("layout", ROOT / "tools" / "layout.py")
layout = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(layout)


def test_no_room_imports_back_up_and_no_module_circle():
    f = layout.figures(ROOT)
    assert f["cycles"] == [], "rooms that import each other"
    assert f["module_circles"] == [], "modules that import each other"
    assert f["arrows_back_up"] == 0


def test_parts_sit_below_families():
    """The CAD helpers and the joints' plan never read a part family: the families build on them."""
    _, g = layout.rooms_and_imports(ROOT / "cogniframe")
    assert g.has_edge("families", "parts")
    assert "families" not in g.successors("parts")


def test_no_module_over_650_lines_and_no_function_over_100():
    f = layout.figures(ROOT)
    lines, path = f["largest_modules"][0]
    assert lines <= 650, path
    lines, where = f["largest_functions"][0]
    assert lines <= 100, where


def test_the_joints_plan_imports_no_cad_kernel():
    code = ("import sys, cogniframe.families.joint, cogniframe.parts.joint_plan, cogniframe.parts.record; "
            "print(sorted(m for m in ('cadquery', 'OCP') if m in sys.modules))")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120,
                       env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "[]"
