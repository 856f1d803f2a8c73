#!/usr/bin/env python3
"""Write constraints.txt: the exact release of every package cogniframe[test] pulls in, as
installed in this environment (the one the golden hashes were made in).

    pip install ".[test]"                   # or -U for the newest allowed releases
    python -m pytest                        # green here first
    python tools/lock_constraints.py        # then record what was installed

CI installs with it (`pip install -c constraints.txt ".[test]"`), so a new release of a
dependency cannot turn CI red unseen; `pip install -U ".[test]"` (no -c) runs against the newest
releases pyproject.toml allows instead. Only the dependency closure of cogniframe[test] is
written (walked through the installed packages' own requirements, extras included), not
whatever else the environment holds, and never cogniframe itself.
"""

from __future__ import annotations

import argparse
import re
from importlib import metadata
from pathlib import Path

from packaging.markers import default_environment
from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "constraints.txt"


def _norm(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def closure(root: str = "cogniframe", extras: tuple[str, ...] = ("test",)) -> dict[str, str]:
    """name -> installed version, for every distribution `root[extras]` requires, transitively."""
    env = default_environment()
    seen: dict[str, str] = {}
    todo: list[tuple[str, tuple[str, ...]]] = [(root, extras)]
    done: set[tuple[str, tuple[str, ...]]] = set()
    while todo:
        name, ext = todo.pop()
        if (_norm(name), ext) in done:
            continue
        done.add((_norm(name), ext))
        try:
            dist = metadata.distribution(name)
        except metadata.PackageNotFoundError:
            continue  # a requirement whose marker holds but is not installed: pip would have said
        if _norm(name) != _norm(root):
            seen[dist.metadata["Name"]] = dist.version
        for line in dist.requires or ():
            req = Requirement(line)
            if req.marker is not None and not any(req.marker.evaluate({**env, "extra": e}) for e in ("", *ext)):
                continue
            todo.append((req.name, tuple(sorted(req.extras))))
    return seen


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("-o", "--out", type=Path, default=OUT)
    a = ap.parse_args()
    pins = closure()
    head = ["# cogniframe[test]'s dependency closure as installed where the golden hashes were made and the",
            "# suite was green (python tools/lock_constraints.py writes it). CI: pip install -c constraints.txt \".[test]\".",
            "# Newest allowed releases instead: pip install -U \".[test]\" (no -c)."]
    body = [f"{n}=={v}" for n, v in sorted(pins.items(), key=lambda kv: _norm(kv[0]))]
    a.out.write_text("\n".join(head + body) + "\n")
    print(f"wrote {a.out}: {len(body)} pins")


if __name__ == "__main__":
    main()
