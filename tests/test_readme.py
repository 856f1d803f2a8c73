"""The README's worked example runs as written, on the data shipped in examples/ (no ../shared)."""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def readme_command(prefix: str) -> list[str]:
    text = (ROOT / "README.md").read_text()
    for block in re.findall(r"```bash\n(.*?)```", text, re.S):
        cmd = block.replace("\\\n", " ").strip()
        if cmd.startswith(prefix):
            return shlex.split(cmd)[1:]
    raise AssertionError(f"no `{prefix}` example in README.md")


def test_readme_fit_example_gives_the_numbers_it_states(run_cli):
    args = readme_command("cogniframe fit examples/")
    code, out, err = run_cli(*args, "--json", cwd=ROOT)
    assert code == 0, err
    r = json.loads(out)
    assert abs(r["c_n_s_per_m"] - 69.5) < 1.0 and abs(r["k_n_per_m"] - 4323) < 60
    assert abs(r["static_k_n_per_m"] - 7040) < 5
    text = (ROOT / "README.md").read_text()
    assert "c = 69.5 N s/m" in text and "k = 4323 N/m" in text and "k = 7040 N/m" in text


def test_readme_says_what_the_cad_server_is_and_how_to_stop_it(run_cli):
    """The README's CAD server section names the commands, and they exist; its idle time is the server's."""
    from cogniframe.runtime import cad_server

    section = re.search(r"## The CAD server\n(.*?)\n## ", (ROOT / "README.md").read_text(), re.S).group(1)
    assert "`cogniframe server stop`" in section and "`cogniframe server status`" in section
    assert "10 minutes" in section and cad_server.IDLE_S == 600
    assert "COGNIFRAME_CAD_SERVER=0" in section and "--no-server" in section
    code, out, _ = run_cli("server", "status")
    assert code == 0 and ("CAD server running" in out or "no CAD server running" in out)
