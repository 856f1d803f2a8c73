"""Output folders cogniframe owns: it only ever replaces a folder it made, never a file it did not.

A folder is cogniframe's when its `manifest.json` was written by cogniframe and lists every file
in it. `writing(final)` is how every command that writes a whole folder does it:

1. take the folder's lock (`.<name>.cogniframe-lock` beside it; a second writer gets an
   `OutputError` naming the process that holds it, instead of a mix of two builds);
2. clean up after a killed build: remove its stale temp folders (`.<name>.cogniframe-tmp-*`,
   only ever made by cogniframe under this lock) and, if a swap was cut off half-way, put the
   previous output back;
3. refuse, before any work, a folder that is not cogniframe's or holds foreign files;
4. hand out a fresh temp folder beside the final one; on success swap it in atomically
   (renameat2 RENAME_EXCHANGE where the filesystem has it), so readers see the old folder or the
   new one, never a mix; on any failure or Ctrl-C remove the temp folder and leave the old
   output exactly as it was.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import errno
import fcntl
import json
import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path

from .errors import OutputError

MANIFEST = "manifest.json"
GENERATOR = "cogniframe"
TEMP_MARK = ".cogniframe-temp"  # in every temp folder cogniframe makes
_SHOW = 8  # foreign files named in a message


def manifest_files(folder: Path) -> set[str] | None:
    """The files a cogniframe manifest in `folder` lists (plus the manifest), or None if there is none."""
    try:
        m = json.loads((folder / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(m, dict) or not isinstance(m.get("files"), list):
        return None
    if m.get("generator") != GENERATOR and "build_key" not in m:  # builds before the field existed had build_key
        return None
    try:
        return {str(f["path"]) for f in m["files"]} | {MANIFEST}
    except (TypeError, KeyError):
        return None


def foreign_entries(folder: Path, listed: set[str]) -> list[str]:
    """Files (and folders holding none of the listed files) in `folder` that `listed` does not name."""
    keep_dirs = {p for f in listed for p in Path(f).parents if str(p) != "."}
    out = []
    for dirpath, dirnames, filenames in os.walk(folder):
        rel = Path(dirpath).relative_to(folder)
        for d in list(dirnames):
            r = (rel / d)
            if (folder / r).is_symlink() or r not in keep_dirs:
                out.append(r.as_posix() + "/")
                dirnames.remove(d)
        out += [(rel / f).as_posix() for f in filenames if (rel / f).as_posix() not in listed]
    return sorted(out)


def check_replaceable(final: Path) -> None:
    """Raise OutputError unless `final` is absent, empty, or a cogniframe output holding only its own files."""
    if not os.path.lexists(final):
        return
    if final.is_symlink() or not final.is_dir():
        raise OutputError(f"{final} exists and is not a folder cogniframe made, so it will not be replaced. "
                          f"Fix: choose another output folder with -o, or move {final} away.")
    if not any(final.iterdir()):
        return
    listed = manifest_files(final)
    if listed is None:
        present = foreign_entries(final, set())
        raise OutputError(f"{final} already exists and is not a cogniframe output folder (it has no manifest.json "
                          f"written by cogniframe), so nothing in it will be touched. It holds {_names(present)}. "
                          f"Fix: choose another output folder with -o, or move those files away.")
    foreign = foreign_entries(final, listed)
    if foreign:
        raise OutputError(f"{final} is a cogniframe output folder, but it also holds files cogniframe did not make: "
                          f"{_names(foreign)}. Nothing was changed. Fix: move those files out of {final}, or build "
                          f"into another folder with -o.")


def _names(entries: list[str]) -> str:
    shown = ", ".join(entries[:_SHOW])
    return shown + (f" and {len(entries) - _SHOW} more" if len(entries) > _SHOW else "")


@contextmanager
def lock(final: Path):
    """Hold the exclusive lock of output folder `final` (non-blocking: a second writer is an OutputError).

    Parent folders it has to create are removed again if they are still empty at the end (a failed
    build leaves no trace)."""
    made = [p for p in (final.parent, *final.parent.parents) if not os.path.lexists(p)]
    final.parent.mkdir(parents=True, exist_ok=True)
    try:
        with _locked(final) as path:
            yield path
    finally:
        for p in made:  # deepest first
            try:
                p.rmdir()
            except OSError:
                break


@contextmanager
def _locked(final: Path):
    path = final.parent / f".{final.name}.cogniframe-lock"
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "another process"
            os.close(fd)
            raise OutputError(f"another cogniframe command (pid {holder}) is writing {final} right now; two builds "
                              f"into one folder would mix. Fix: wait for it to finish and run again, or write to "
                              f"another folder with -o.") from None
        try:  # the previous holder may have unlinked the file between our open and our lock
            same = os.stat(path).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode(), 0)
        yield path
    finally:
        try:
            os.unlink(path)
        finally:
            os.close(fd)


def _temp_prefix(final: Path) -> str:
    return f".{final.name}.cogniframe-tmp-"


def clean_stale(final: Path) -> list[Path]:
    """Under the lock: undo what a killed writer left beside `final`. Returns what was removed."""
    removed = []
    stale = sorted(p for p in final.parent.glob(_temp_prefix(final) + "*") if p.is_dir() and not p.is_symlink())
    if not os.path.lexists(final):
        # A swap cut off between its two renames leaves the previous output under a temp name.
        previous = [p for p in stale if (p / "old").is_dir() and manifest_files(p / "old") is not None]
        if previous:
            (previous[-1] / "old").rename(final)
    for p in stale:
        if (p / TEMP_MARK).is_file() or manifest_files(p) is not None or (p / "old").is_dir():
            shutil.rmtree(p, ignore_errors=True)
            removed.append(p)
    return removed


@contextmanager
def writing(final: Path):
    """Lock `final`, check it may be replaced, and yield a temp folder; on success it becomes `final`."""
    final = Path(final)
    with lock(final):
        clean_stale(final)
        check_replaceable(final)
        tmp = Path(tempfile.mkdtemp(prefix=_temp_prefix(final), dir=final.parent))
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o777 & ~umask)  # mkdtemp makes 0700; the output is an ordinary folder
        (tmp / TEMP_MARK).touch()
        try:
            yield tmp
            (tmp / TEMP_MARK).unlink()
            check_replaceable(final)  # nothing foreign appeared while we built
            _swap_in(tmp, final)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)


def _swap_in(new: Path, final: Path) -> None:
    """Make `new` the folder at `final`; `new`'s path is left holding the old content (or nothing)."""
    if not os.path.lexists(final):
        new.rename(final)
        return
    if _exchange(new, final):
        return
    # No atomic exchange here: two renames, with the old output parked inside the temp folder so a
    # kill between them is undone by the next writer's clean_stale.
    parked = new.parent / (new.name + "-x")
    new.rename(parked)
    new.mkdir()
    (new / TEMP_MARK).touch()
    final.rename(new / "old")
    parked.rename(final)


_RENAME_EXCHANGE = 2


def _exchange(a: Path, b: Path) -> bool:
    """Atomically swap two paths (Linux renameat2). False when the system cannot."""
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd = -100
    rc = fn(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), _RENAME_EXCHANGE)
    if rc == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP, errno.EXDEV):
        return False
    raise OSError(err, os.strerror(err), str(b))


MARK = b"cogniframe"  # in the first bytes of every single file cogniframe writes (STL header, PNG text)


def claim_file(path: Path) -> None:
    """Raise OutputError if `path` exists and is not a file cogniframe wrote (it would be overwritten)."""
    path = Path(path)
    if not os.path.lexists(path):
        return
    if path.is_file() and not path.is_symlink():
        with open(path, "rb") as f:
            if MARK in f.read(4096):
                return
    raise OutputError(f"{path} already exists and was not written by cogniframe, so it will not be overwritten. "
                      f"Fix: give another path, or move that file away.")


def record(folder: Path, added: list[Path]) -> None:
    """Add files a later command wrote into a cogniframe output folder (e.g. `slice`) to its manifest,
    so they stay cogniframe's: the next build may replace them, and nothing looks foreign."""
    from .cache import file_sha256

    path = folder / MANIFEST
    m = json.loads(path.read_text(encoding="utf-8"))
    entries = {f["path"]: f for f in m["files"]}
    for p in added:
        rel = p.relative_to(folder).as_posix()
        entries[rel] = {"path": rel, "size": p.stat().st_size, "sha256": file_sha256(p)}
    m["files"] = [entries[k] for k in sorted(entries)]
    # G-code is outside the identical-rebuild promise ): say so, as `build --gcode` does
    m["not_reproducible"] = sorted(set(m.get("not_reproducible", [])) | {k for k in entries if k.endswith(".gcode")})
    tmp = path.with_name(f".{MANIFEST}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(m, indent=2) + "\n", encoding="utf-8")
    tmp.replace(path)


def output_dir(spec, out: Path | None) -> Path:
    return out if out is not None else Path("out") / spec.name
