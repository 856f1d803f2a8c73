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
    text = load_text(kind, key, ".json")
    try:
        return None if text is None else json.loads(text)
    except ValueError:
        return None


def store_json(kind: str, key: str, value: dict) -> None:
    """Write atomically; a cache that cannot be written is skipped, never an error."""
    store_text(kind, key, json.dumps(value, sort_keys=True), ".json")


def load_text(kind: str, key: str, suffix: str = ".txt") -> str | None:
    """A text stored by `store_text`, or None."""
    try:
        return (cache_dir() / kind / f"{key}{suffix}").read_text()
    except (OSError, ValueError):
        return None


def store_text(kind: str, key: str, text: str, suffix: str = ".txt") -> None:
    """Write atomically (a reader sees the whole text or none); skipped when the cache cannot be written."""
    folder = cache_dir() / kind
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tmp = folder / f".{key}.{os.getpid()}.tmp"
        tmp.write_text(text)
        tmp.replace(folder / f"{key}{suffix}")
    except OSError:
        pass


class BytesMemo:
    """Files of bytes under `cache_dir()/kind/`, one per key, the key salted (e.g. with the code
    and library versions that made the values): for results worth keeping piece by piece, such as
    the assembly guide's pictures. A write is atomic (a reader sees the whole file or none) and
    skipped when the cache cannot be written. `root`: the cache folder (given explicitly to worker
    processes, which may not share this process's environment)."""

    def __init__(self, kind: str, salt: str, suffix: str = ".bin", root: str | Path | None = None):
        self.kind, self.salt, self.suffix, self.root = kind, salt, suffix, Path(root) if root is not None else None

    def _path(self, key: str) -> Path:
        import hashlib

        name = hashlib.sha256(f"{self.salt}/{key}".encode()).hexdigest()[:32]
        return (self.root if self.root is not None else cache_dir()) / self.kind / f"{name}{self.suffix}"

    def get(self, key: str) -> bytes | None:
        try:
            return self._path(key).read_bytes()
        except OSError:
            return None

    def put(self, key: str, data: bytes) -> None:
        path = self._path(key)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
            tmp.write_bytes(data)
            tmp.replace(path)
        except OSError:
            pass


class Memo:
    """A dict-like store of small JSON values (`BytesMemo`'s files, `.json`): for results worth
    keeping piece by piece, such as the clash check's pairs."""

    def __init__(self, kind: str, salt: str, root: str | Path | None = None):
        self._files = BytesMemo(kind, salt, ".json", root)

    def get(self, key: str, default=None):
        data = self._files.get(key)
        try:
            return json.loads(data)["value"] if data is not None else default
        except (ValueError, KeyError, TypeError):
            return default

    def __setitem__(self, key: str, value) -> None:
        self._files.put(key, json.dumps({"value": value}).encode())


# -- file entries: a step's output files + its JSON value, verified on every read -------------

def file_sha256(path: Path) -> str:
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def entry_dir(kind: str, key: str, root: Path | None = None) -> Path:
    return Path(root if root is not None else cache_dir()) / kind / key


def get_files(kind: str, key: str, dest: Path, root: Path | None = None):
    """Copy a stored entry's files into `dest` (same relative paths) and return its value.

    Returns None (a miss) when the entry is missing, its meta.json is unreadable, or any file's
    sha256 differs from the one recorded when it was stored (a truncated or edited entry); a bad
    entry is deleted so the step runs and stores it again."""
    import shutil

    entry = entry_dir(kind, key, root)
    try:
        meta = json.loads((entry / "meta.json").read_text())
        files = meta["files"]
        for rel, sha in files.items():
            src = entry / "files" / rel
            if file_sha256(src) != sha:
                raise ValueError(f"{src}: sha256 differs from the one stored")
        for rel in files:
            dst = Path(dest) / rel
            dst.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(entry / "files" / rel, dst)
        return {"value": meta["value"]}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        if entry.exists():  # half an entry (meta.json or a file missing, damaged): drop it, it is rebuilt
            shutil.rmtree(entry, ignore_errors=True)
        return None


def put_files(kind: str, key: str, src: Path, files, value, root: Path | None = None) -> None:
    """Store `files` (paths relative to `src`) and a JSON `value` atomically: the entry appears
    whole (renamed into place after meta.json, which lists every file's sha256, is written) or
    not at all. A cache that cannot be written is skipped, never an error."""
    import shutil

    entry = entry_dir(kind, key, root)
    tmp = entry.with_name(f".{entry.name}.{os.getpid()}.{id(files)}.tmp")
    try:
        tmp.mkdir(parents=True)
        meta = {"files": {}, "value": value}
        for rel in sorted(files):
            dst = tmp / "files" / rel
            dst.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(Path(src) / rel, dst)
            meta["files"][rel] = file_sha256(dst)
        (tmp / "meta.json").write_text(json.dumps(meta, sort_keys=True))
        try:
            tmp.rename(entry)
        except OSError:  # stored meanwhile by another build (same key, same content): keep that one
            pass
    except OSError:
        pass
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


_CODE: dict[tuple[str, ...], str] = {}


def code_hash(*patterns: str) -> str:
    """sha256 of cogniframe's source files matching `patterns` (globs relative to the package,
    e.g. "parts/*.py"): part of a cache key, so editing the code that makes a result invalidates it."""
    if patterns not in _CODE:
        _CODE[patterns] = sources_hash(Path(__file__).resolve().parent, patterns)
    return _CODE[patterns]


def sources_hash(root: Path, patterns) -> str:
    """sha256 of the files under `root` matching the glob `patterns`, by relative path and bytes.
    Files only: an installed package has `__pycache__` folders beside the sources (a pattern
    such as "report/viewer/*" matches them), and their presence must not change the key."""
    import hashlib

    h = hashlib.sha256()
    for pat in patterns:
        found = sorted(p for p in root.glob(pat) if p.is_file())
        if not found:
            raise FileNotFoundError(f"cache.code_hash: no cogniframe source matches {pat!r}")
        for src in found:
            h.update(src.relative_to(root).as_posix().encode() + b"\0" + src.read_bytes())
    return h.hexdigest()[:16]


def key(inputs, code: tuple[str, ...] = (), stack: str = "") -> str:
    """The one recipe for a cache key: the sha256 of what the result is made from: `inputs` (plain
    data, dataclasses, numpy values: `fingerprint`), the cogniframe source files that make it
    (`code`: globs relative to the package, `code_hash`) and the library versions (`stack`)."""
    import hashlib

    payload = fingerprint([inputs, code_hash(*code) if code else "", stack])
    return hashlib.sha256(payload.encode()).hexdigest()[:32]


def fingerprint(obj) -> str:
    """Deterministic JSON of plain data, dataclasses and numpy values (for keys)."""
    import dataclasses

    def default(o):
        if dataclasses.is_dataclass(o) and not isinstance(o, type):
            return {f.name: getattr(o, f.name) for f in dataclasses.fields(o)}
        if hasattr(o, "tolist"):
            return o.tolist()
        if isinstance(o, Path):
            return o.as_posix()
        if isinstance(o, (set, frozenset)):
            return sorted(o)
        raise TypeError(f"cannot fingerprint {type(o).__name__}")

    return json.dumps(obj, sort_keys=True, default=default, separators=(",", ":"))
