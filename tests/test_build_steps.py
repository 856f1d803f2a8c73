"""The build's step table (pipeline/steps.py): the docs show it as it is, and every cached step's key
covers the source files its make function imports (a forgotten one would leave the
cache stale without an error)."""

from __future__ import annotations

import ast
import fnmatch
import inspect
import sys
import textwrap
from pathlib import Path

import pytest

from cogniframe.pipeline import steps

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "cogniframe"
# Modules whose code cannot change a step's files: the cache and graph machinery, the process
# machinery, and the cache-key helpers.
NO_OUTPUT = ("cache.py", "pipeline/graph.py", "pipeline/context.py", "runtime/*", "stack.py")


def _functions(fn) -> list:
    """`fn` and the functions of its own module that it calls, transitively."""
    module = sys.modules[fn.__module__]
    seen, todo = [], [fn]
    while todo:
        f = todo.pop()
        if f in seen:
            continue
        seen.append(f)
        for node in ast.walk(ast.parse(textwrap.dedent(inspect.getsource(f)))):
            if isinstance(node, ast.Name):
                g = getattr(module, node.id, None)
                if inspect.isfunction(g) and g.__module__ == module.__name__:
                    todo.append(g)
    return seen


def _imported_files(fn) -> set[str]:
    """The cogniframe source files (relative to the package) that `fn` and its module's helpers
    import in their bodies."""
    out = set()
    for f in _functions(fn):
        package = f.__module__.rsplit(".", 1)[0].split(".")
        for node in ast.walk(ast.parse(textwrap.dedent(inspect.getsource(f)))):
            if isinstance(node, ast.ImportFrom) and node.level:
                base = package[: len(package) - node.level + 1]
                mods = [".".join(base + ([node.module] if node.module else []))]
                if node.module is None or (PACKAGE / "/".join(mods[0].split(".")[1:])).is_dir():
                    mods = [f"{mods[0]}.{a.name}" for a in node.names]
                for m in mods:
                    rel = "/".join(m.split(".")[1:])
                    if (PACKAGE / f"{rel}.py").is_file():
                        out.add(f"{rel}.py")
                    elif (PACKAGE / rel / "__init__.py").is_file():
                        out.add(f"{rel}/__init__.py")
    return out


def test_the_docs_show_the_step_table_as_it_is():
    assert steps.table() in (ROOT / "docs" / "build.md").read_text()


@pytest.mark.parametrize("step", [s for s in steps.STEPS if s.key is not None], ids=lambda s: s.name)
def test_a_cached_steps_code_covers_every_source_its_make_function_imports(step):
    missing = []
    for rel in sorted(_imported_files(step.run)):
        if not any(fnmatch.fnmatchcase(rel, g) for g in step.code + NO_OUTPUT):
            missing.append(rel)
    assert missing == [], f"{step.name}: add {missing} to its code (or its output does not depend on them)"


def test_the_check_finds_a_forgotten_source():
    """The test above fails for a step whose code misses a module its make function imports."""
    from dataclasses import replace

    plates = next(s for s in steps.STEPS if s.name.startswith("plates:"))
    forgot = replace(plates, code=())
    with pytest.raises(AssertionError, match="export/plates.py"):
        test_a_cached_steps_code_covers_every_source_its_make_function_imports(forgot)
