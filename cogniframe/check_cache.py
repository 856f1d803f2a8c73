"""`cogniframe check` answered from the cache when nothing it depends on has changed.

The whole printed answer (the JSON, or the terminal tables as rendered for this terminal) and
the exit code are stored under a key of: the params file's bytes and stem (a file without
`name:` is named after it), the source of every cogniframe module, the Python version and the
installed numerical stack (each package's path and mtime: an upgrade changes them). A hit
imports neither pydantic nor numpy, so a repeated `check` costs little more than Python's
start-up. Only successful checks are stored: bad input is always validated and reported.

`quick(argv)` answers a plain `check PARAMS [--json]` before the CLI is even imported (typer
builds pydantic adapters for every option it parses); `cli.check` uses the same entries.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
from pathlib import Path

CHECK_LIBRARIES = ("numpy", "scipy", "pydantic", "pydantic_core", "yaml", "Pynite", "rich")


def _stack() -> list:
    from importlib.util import find_spec

    out = []
    for name in CHECK_LIBRARIES:
        try:
            spec = find_spec(name)
            origin = spec.origin if spec is not None else None
            out.append([name, origin, os.stat(origin).st_mtime_ns if origin else None])
        except (ImportError, OSError, ValueError):
            out.append([name, None, None])
    return out


def variant(json_out: bool, console=None) -> dict:
    """What the stored text depends on besides the inputs: JSON, or the terminal's width and colours."""
    if json_out:
        return {"json": True}
    if console is None:
        from rich.console import Console

        console = Console()
    return {"width": console.width, "colour": console.color_system, "no_colour": console.no_color,
            "terminal": console.is_terminal}


def quick(argv: list[str]) -> int | None:
    """Answer `check PARAMS [--json]` from the cache: print it and return the exit code; None otherwise."""
    if not argv or argv[0] != "check":
        return None
    rest = [a for a in argv[1:] if a != "--json"]
    if len(rest) != 1 or rest[0].startswith("-"):
        return None
    hit = load(key(Path(rest[0]), variant("--json" in argv[1:])))
    if hit is None:
        return None
    sys.stdout.write(hit[0])
    sys.stdout.flush()
    return hit[1]


def key(params: Path, variant: dict) -> str | None:
    """Cache key of one check answer; None when the params file cannot be read (the check reports it)."""
    from . import cache

    try:
        data = Path(params).read_bytes()
    except OSError:
        return None
    return cache.key([hashlib.sha256(data).hexdigest(), Path(params).stem, sys.version, variant], ("**/*.py",),
                     json.dumps(_stack(), sort_keys=True))


def load(k: str | None) -> tuple[str, int] | None:
    from . import cache

    if k is None:
        return None
    hit = cache.load_json("check", k)
    if not hit or not isinstance(hit.get("text"), str) or not isinstance(hit.get("code"), int):
        return None
    return hit["text"], hit["code"]


def store(k: str | None, text: str, code: int) -> None:
    from . import cache

    if k is not None:
        cache.store_json("check", k, {"text": text, "code": code})
