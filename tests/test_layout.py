"""The plan of the code holds (tools/layout.py): data flows one way between the rooms, no two
modules import each other, and no module or function grows past what a reader takes in at once.
And the joints' plan geometry, which `check` reads, pulls in no CAD kernel. One name per idea: no
two modules share a file name, and one function is called `build` (the API's)."""

from __future__ import annotations

import ast
import collections
import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest


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


@pytest.mark.process
def test_the_joints_plan_imports_no_cad_kernel():
    code = ("import sys, cogniframe.families.joint, cogniframe.parts.joint_plan, cogniframe.parts.record; "
            "print(sorted(m for m in ('cadquery', 'OCP') if m in sys.modules))")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120,
                       env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "[]"


def test_no_two_modules_share_a_name():
    """A name found in a traceback, a grep or a cache-key glob points at one file."""
    names = collections.defaultdict(list)
    for f in sorted((ROOT / "cogniframe").rglob("*.py")):
        if f.name != "__init__.py":
            names[f.name].append(f.relative_to(ROOT / "cogniframe").as_posix())
    assert {n: paths for n, paths in names.items() if len(paths) > 1} == {}


def _functions_named(tree: ast.AST, name: str, prefix: str = "") -> list[str]:
    """Qualified names (Class.method, outer.inner) of the functions called `name` in `tree`."""
    found = []
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            if node.name == name and not isinstance(node, ast.ClassDef):
                found.append(prefix + node.name)
            found += _functions_named(node, name, f"{prefix}{node.name}.")
        else:
            found += _functions_named(node, name, prefix)
    return found


def test_one_function_is_called_build():
    """`build` is the API's (`Design.build`); the CLI command, the studio's and the CAD's have names of their own."""
    builds = [f"{f.relative_to(ROOT / 'cogniframe').as_posix()}:{q}"
              for f in sorted((ROOT / "cogniframe").rglob("*.py"))
              for q in _functions_named(ast.parse(f.read_text()), "build")]
    assert builds == ["api/__init__.py:Design.build"]
