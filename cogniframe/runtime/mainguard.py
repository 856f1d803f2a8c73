"""Whether the code running now is a script's unguarded top level, which spawned processes run again.

multiprocessing's spawn and forkserver start methods prepare every child by running the parent's
main script again (as `__mp_main__`), so that functions defined there can be found. Code a script
runs at its top level outside `if __name__ == "__main__":` therefore runs once more in every child:
a sweep or a build started there would start again in each of its own worker processes. The Dask
sweep and `Design.build` ask `unguarded_main_script` before they start worker processes.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path


def unguarded_main_script(frame=None) -> tuple[str, int] | None:
    """The main script's path and line when the caller runs inside the script's top-level code outside
    `if __name__ == "__main__":` (the code a spawned worker process runs again); else None.

    None too where spawn runs nothing again: no main file (REPL, Jupyter), a package's `__main__`
    run with `python -m` (multiprocessing skips those), or no top-level frame of the main script on
    the stack (then it cannot be told, and the caller keeps its worker processes). `frame`: where
    to start looking up the stack (default: the caller's frame)."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    spec = getattr(main, "__spec__", None)
    if main is None or path is None or (spec is not None and spec.name.rpartition(".")[2] == "__main__"):
        return None
    f = frame or sys._getframe(1)
    while f is not None and not (f.f_globals is main.__dict__ and f.f_code.co_name == "<module>"):
        f = f.f_back
    if f is None:
        return None
    try:
        tree = ast.parse(Path(path).read_text(encoding="utf-8"))
    except (OSError, SyntaxError, ValueError):
        return None
    line = f.f_lineno
    for node in tree.body:
        if isinstance(node, ast.If) and _is_main_test(node.test) and node.lineno <= line <= (node.end_lineno or line):
            return None
    return path, line


def _is_main_test(test) -> bool:
    """`__name__ == "__main__"` (either way round)."""
    if not (isinstance(test, ast.Compare) and len(test.ops) == 1 and isinstance(test.ops[0], ast.Eq)):
        return False
    sides = [test.left, test.comparators[0]]
    names = [s.id for s in sides if isinstance(s, ast.Name)]
    consts = [s.value for s in sides if isinstance(s, ast.Constant)]
    return names == ["__name__"] and consts == ["__main__"]
