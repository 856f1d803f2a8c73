"""On-disk cache location and a tiny JSON cache for expensive pure results.

$COGNIFRAME_CACHE, else $XDG_CACHE_HOME/cogniframe, else ~/.cache/cogniframe. Entries are
keyed by a hash of exactly their inputs, so a stale entry is never read; deleting the folder is
always safe.
"""

from __future__ import annotations

import json
import os
from pathlib import Path


def cache_dir() -> Path:
    env = os.environ.get("COGNIFRAME_CACHE")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "cogniframe"


def load_json(kind: str, key: str) -> dict | None:
    path = cache_dir() / kind / f"{key}.json"
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def store_json(kind: str, key: str, value: dict) -> None:
    """Write atomically; a cache that cannot be written is skipped, never an error."""
    folder = cache_dir() / kind
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tmp = folder / f".{key}.{os.getpid()}.tmp"
        tmp.write_text(json.dumps(value, sort_keys=True))
        tmp.replace(folder / f"{key}.json")
    except OSError:
        pass
