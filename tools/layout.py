#!/usr/bin/env python3
"""The plan of the code: rooms (cogniframe's top-level modules and sub-packages), floors (layers
of the import graph between rooms: a room sits one floor above the highest room it imports),
arrows back up (imports between rooms that import each other, directly or round a cycle, and
imports from the package root's __init__.py, which every room sits under), import circles
between modules (also inside one room), and the largest module and function.

    python tools/layout.py [--root DIR] [--json]

Every import counts, at module level or inside a function.
"""

from __future__ import annotations

import argparse
import ast
import json
from pathlib import Path

import networkx as nx


def rooms_and_imports(package: Path) -> tuple[dict[str, int], nx.DiGraph]:
    sizes: dict[str, int] = {}
    g = nx.DiGraph()

    def room_of(rel: Path) -> str:
        return rel.parts[0] if len(rel.parts) > 1 else rel.stem

    for f in sorted(package.rglob("*.py")):
        rel = f.relative_to(package)
        if rel.name == "__main__.py" or rel.as_posix() == "__init__.py":
            continue
        room = room_of(rel)
        sizes[room] = sizes.get(room, 0) + len(f.read_text().splitlines())
        g.add_node(room)
        mod = [package.name, *rel.with_suffix("").parts]
        if mod[-1] == "__init__":
            mod = mod[:-1]
        pkg = mod if rel.name == "__init__.py" else mod[:-1]
        for node in ast.walk(ast.parse(f.read_text())):
            targets = []
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = pkg[: len(pkg) - node.level + 1]
                    full = base + (node.module.split(".") if node.module else [])
                    targets = [full + [a.name] if not node.module else full for a in node.names]
                elif node.module and node.module.split(".")[0] == package.name:
                    targets = [node.module.split(".") + [a.name] for a in node.names]
            elif isinstance(node, ast.Import):
                targets = [a.name.split(".") for a in node.names if a.name.split(".")[0] == package.name]
            for t in targets:
                if len(t) < 2:
                    continue
                target = t[1]
                if (package / target).is_dir() or (package / f"{target}.py").is_file():
                    if target != room:
                        g.add_edge(room, target)
    return sizes, g


def module_imports(package: Path) -> nx.DiGraph:
    """Module-level graph: an edge per import of one cogniframe module by another (a package's
    __init__ counts as the package)."""
    g = nx.DiGraph()
    names = {}
    for f in sorted(package.rglob("*.py")):
        rel = f.relative_to(package).with_suffix("")
        parts = [package.name, *rel.parts]
        names[f] = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
    known = set(names.values())
    for f, mod in names.items():
        pkg = mod.split(".") if f.name == "__init__.py" else mod.split(".")[:-1]
        g.add_node(mod)
        for node in ast.walk(ast.parse(f.read_text())):
            targets = []
            if isinstance(node, ast.ImportFrom):
                base = pkg[: len(pkg) - node.level + 1] if node.level else []
                full = ".".join(base + (node.module.split(".") if node.module else []))
                # `from X import name`: the module X.name when there is one, else X itself
                targets = [f"{full}.{a.name}" if f"{full}.{a.name}" in known else full for a in node.names]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            for t in targets:
                if t in known and t != mod:
                    g.add_edge(mod, t)
    return g


def largest_functions(package: Path, n: int = 3) -> list[tuple[int, str]]:
    found = []
    for f in package.rglob("*.py"):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                found.append((node.end_lineno - node.lineno + 1,
                              f"{f.relative_to(package.parent).as_posix()}:{node.name}"))
    return sorted(found, reverse=True)[:n]


def figures(root: Path) -> dict:
    sizes, g = rooms_and_imports(root / "cogniframe")
    mods = module_imports(root / "cogniframe")
    from_root = sorted(t for t in mods.successors("cogniframe"))
    cond = nx.condensation(g)
    floor = {}
    for c in reversed(list(nx.topological_sort(cond))):
        below = [floor[s] for s in cond.successors(c)]
        floor[c] = 1 + max(below, default=0)
    back = sorted((a, b) for a, b in g.edges if cond.graph["mapping"][a] == cond.graph["mapping"][b])
    largest = sorted(((len(p.read_text().splitlines()), p.relative_to(root).as_posix())
                      for p in (root / "cogniframe").rglob("*.py")), reverse=True)[:6]
    circles = sorted(sorted(c) for c in nx.strongly_connected_components(mods) if len(c) > 1)
    # the root's imports run back up when a module it reaches imports the root again
    up = [t for t in from_root if any("cogniframe" in c and t in c for c in circles)]
    return {"rooms": g.number_of_nodes(), "floors": max(floor.values()),
            "arrows_back_up": len(back) + len(up), "root_imports": up,
            "cycles": [sorted(c) for c in nx.strongly_connected_components(g) if len(c) > 1],
            "module_circles": circles, "largest_modules": largest,
            "largest_functions": largest_functions(root / "cogniframe")}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--root", type=Path, default=Path(__file__).resolve().parents[1])
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    f = figures(a.root)
    if a.json:
        print(json.dumps(f, indent=2))
        return
    print(f"rooms {f['rooms']}, floors {f['floors']}, arrows back up {f['arrows_back_up']}, "
          f"import circles {len(f['module_circles'])}")
    for c in f["cycles"]:
        print("  rooms that import each other:", ", ".join(c))
    for t in f["root_imports"]:
        print("  the package root imports, and is imported back:", t)
    for c in f["module_circles"]:
        print("  modules that import each other:", ", ".join(c))
    for n, p in f["largest_modules"]:
        print(f"  {n:5d} {p}")
    for n, p in f["largest_functions"]:
        print(f"  {n:5d} lines: {p}")


if __name__ == "__main__":
    main()
