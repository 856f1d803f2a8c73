"""`cf.sweep(...)` from a script file, with and without `if __name__ == "__main__":` (run as a user runs
it: `python script.py` in a subprocess). Dask's spawned worker processes run an unguarded script
again, so the sweep then checks its designs in the calling process and says so."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SWEEP = ('{"base": %r, "samples": 2, "sampler": "random", "seed": 1, "vary": {"joints.wall": [1.6, 2.0]}}'
         % str(ROOT / "params" / "carbon.yaml"))


def _run(script: Path, timeout: float = 600, env: dict | None = None) -> subprocess.CompletedProcess:
    env = {**(os.environ if env is None else env), "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, str(script)], capture_output=True, text=True, cwd=script.parent, env=env,
                          timeout=timeout)


@pytest.mark.process
def test_unguarded_script_sweeps_in_its_own_process_and_says_how_to_get_workers(tmp_path):
    script = tmp_path / "unguarded.py"
    script.write_text("import cogniframe as cf\n"
                      f"df = cf.sweep({SWEEP}, workers=2)\n"
                      "s = df.attrs['summary']\n"
                      "print('ROWS', len(df), 'WORKERS', s['workers'], 'SCHEDULER', s['scheduler'])\n", encoding="utf-8")
    r = _run(script)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "Nanny failed to start" not in r.stderr
    assert "ROWS 2 WORKERS 1 SCHEDULER inproc://" in r.stdout
    # the warning names the script and its line, and the fix
    assert f"{script}:2: UserWarning" in r.stderr
    assert 'if __name__ == "__main__":' in r.stderr and "on 2 worker processes" in r.stderr


@pytest.mark.process
@pytest.mark.cluster
def test_guarded_script_keeps_its_worker_processes(tmp_path):
    script = tmp_path / "guarded.py"
    script.write_text("import cogniframe as cf\n\n\n"
                      "def main():\n"
                      f"    df = cf.sweep({SWEEP}, workers=2)\n"
                      "    s = df.attrs['summary']\n"
                      "    print('ROWS', len(df), 'WORKERS', s['workers'], 'SCHEDULER', s['scheduler'])\n\n\n"
                      "if __name__ == '__main__':\n"
                      "    main()\n", encoding="utf-8")
    r = _run(script)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "ROWS 2 WORKERS 2 SCHEDULER tcp://127.0.0.1:" in r.stdout
    assert "UserWarning" not in r.stderr


def test_main_guard_is_read_from_the_script_at_the_calling_line(tmp_path, monkeypatch):
    """unguarded_main_script reads the main script's own text: a call under the guard (either way round)
    is guarded, one before it is not."""
    import types

    from cogniframe.runtime.mainguard import unguarded_main_script

    script = tmp_path / "m.py"
    script.write_text("x = 1\n"               # line 1: top level
                      "if '__main__' == __name__:\n"
                      "    y = 2\n"           # line 3: under the guard
                      "if __name__ == '__mp_main__':\n"
                      "    z = 3\n", encoding="utf-8")  # line 5: not the main guard
    main = types.ModuleType("__main__")
    main.__file__ = str(script)
    main.__spec__ = None
    monkeypatch.setitem(sys.modules, "__main__", main)
    found = {}
    main.__dict__.update({"found": found, "where": unguarded_main_script, "sys": sys})
    for line in (1, 3, 5):  # top-level code of "m.py" at that line, run in the main module's globals
        exec(compile("\n" * (line - 1) + f"found[{line}] = where(sys._getframe())", str(script), "exec"), main.__dict__)
    assert found == {1: (str(script), 1), 3: None, 5: (str(script), 5)}


@pytest.mark.process
def test_readme_python_example_runs_as_written(tmp_path):
    """The README's Python block, saved as a script and run as `python example.py` (no main guard), from
    a folder holding the params and sweep files it names, as a user runs it: with the CAD server (its
    workers are forks of a server started with `python -c`, which run no script again), in a cache of
    its own, the server stopped at the end. The sweep file it names is the example's with 12 samples
    instead of 300 (checked one at a time here, they were 3 of this test's 5 minutes): the block's
    code is what is tested, on a file of the same keys."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"## From Python and notebooks\n\n```python\n(.*?)```", text, re.S).group(1)
    assert "cf.sweep(" in block and "__main__" not in block
    shutil.copytree(ROOT / "params", tmp_path / "params")
    shutil.copytree(ROOT / "examples" / "sweeps", tmp_path / "examples" / "sweeps")
    example = tmp_path / "examples" / "sweeps" / "carbon.yaml"
    text = example.read_text(encoding="utf-8")
    assert "\nsamples: 300\n" in text
    example.write_text(text.replace("\nsamples: 300\n", "\nsamples: 12\n"), encoding="utf-8")
    script = tmp_path / "example.py"
    script.write_text(block, encoding="utf-8")
    env = {k: v for k, v in os.environ.items() if k != "COGNIFRAME_CAD_SERVER"}
    env["COGNIFRAME_CACHE"] = str(tmp_path / "cache")
    try:
        r = _run(script, timeout=1800, env=env)
    finally:
        subprocess.run([sys.executable, "-m", "cogniframe", "server", "stop"], env={**env, "PYTHONPATH": str(ROOT)},
                       capture_output=True, timeout=120)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "Nanny failed to start" not in r.stderr
    assert (tmp_path / "out" / "carbon-4mm" / "report.html").is_file()
    import pandas as pd

    assert len(pd.read_parquet(tmp_path / "out" / "sweeps" / "carbon" / "results.parquet")) == 12
    assert f"{script}:8: UserWarning" in r.stderr  # the sweep's line: checked in this process, and said so


def test_unguarded_build_without_the_cad_server_is_refused_with_the_fix(tmp_path):
    """Without the CAD server a build's CAD workers come from forkserver, which runs the script again:
    refused before anything is written, naming the script's line and the two fixes."""
    script = tmp_path / "build.py"
    script.write_text("import cogniframe as cf\n"
                      f"cf.load({str(ROOT / 'params' / 'carbon.yaml')!r}).build('out/x')\n", encoding="utf-8")
    env = {**os.environ, "COGNIFRAME_CAD_SERVER": "0"}
    r = _run(script, timeout=300, env=env)
    assert r.returncode == 1
    assert f"{script}, line 2: this build runs at the script's top level" in r.stderr
    assert "COGNIFRAME_CAD_SERVER=0" in r.stderr and 'if __name__ == "__main__":' in r.stderr
    assert not (tmp_path / "out").exists()
