"""stack.py: the library versions in every manifest and cache key, looked up without heavy imports."""

from __future__ import annotations

import json
import subprocess
import sys
from importlib import metadata

import pytest

from cogniframe import __version__, stack


def test_installed_lists_cogniframe_and_every_stack_library_at_its_installed_version():
    v = stack.installed()
    assert list(v) == ["cogniframe", *stack.LIBRARIES]
    assert v["cogniframe"] == __version__
    assert v["cadquery"] == metadata.version("cadquery") and v["numpy"] == metadata.version("numpy")


def test_the_versions_add_the_extra_libraries_and_are_stable():
    f = json.loads(stack.versions())
    assert set(f) == {"cogniframe", *stack.LIBRARIES, *stack.EXTRA_LIBRARIES}
    assert f["rich"] == metadata.version("rich") and stack.versions() == stack.versions()


@pytest.mark.process
def test_the_server_key_needs_no_heavy_import():
    """`cogniframe build` computes the CAD server's key first thing (to start the server while it
    validates the params): numpy, pydantic and the CAD libraries stay unimported for that."""
    code = ("import sys; from cogniframe import stack; from cogniframe.runtime import cad_server; "
            "cad_server.server_key(stack.versions()); "
            "print(sorted(m for m in ('numpy', 'pydantic', 'cadquery', 'OCP', 'trimesh', 'yaml') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0 and out.stdout.strip() == "[]", out.stderr
