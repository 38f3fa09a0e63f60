"""`python -m netplc run`: output format, options and exit status 2. The command runs in this process
(`netplc.cli.main`, what `python -m netplc` calls, tests/commands.py); the malformed program's run is
a real subprocess, for the status and the streams of the process itself."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from netplc.cli import main
from tests.commands import run_in_process

COUNTER = "TNA TTC\nCTR TA N:2\nTNA TA[2]\nYON $02000\n"


def netplc_process(*args: str | Path, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "netplc", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=60)


@pytest.fixture
def netplc(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch):
    """`python -m netplc ARGS` run in `cwd`, in this process."""
    def run(*args: str | Path, cwd: Path) -> subprocess.CompletedProcess:
        monkeypatch.chdir(cwd)
        return run_in_process(main, args, capsys)

    return run


@pytest.fixture
def prog(tmp_path):
    def write(text: str, name: str = "p.stl") -> Path:
        path = tmp_path / name
        path.write_text(text, encoding="utf-8")
        return path

    return write


def test_bits_words_and_bytes_are_printed(prog, tmp_path, netplc):
    p = prog("TNA $00000\nYON $02005\nTFA $00000\nYON $02006\n")
    r = netplc("run", p, "--set", "00000=1", "--set", "04000=0x9876", "--set", "04002=0o17",
               "--print", "02005", "--print", "02006", "--print", "04000", "--print", "04000:4",
               "--print", "02000:1", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines() == ["02005 = 1", "02006 = 0", "04000 = 0x9876", "04000:4 = 76 98 0f 00",
                                     "02000:1 = 20"]
    assert r.stderr == ""


def test_scans_dt_and_timed_sets_drive_a_timer(prog, tmp_path, netplc):
    p = prog("TNA $00000\nTIM $03000 N:5\n")
    base = ["run", p, "--at", "1:00000=1", "--print", "03001"]
    # scan 1 starts the timer; 5 ticks of 0.1 s later (scan 6) it is done
    assert netplc(*base, "--scans", "6", cwd=tmp_path).stdout == "03001 = 0\n"
    assert netplc(*base, "--scans", "7", cwd=tmp_path).stdout == "03001 = 1\n"
    assert netplc(*base, "--scans", "4", "--dt", "0.25", cwd=tmp_path).stdout == "03001 = 1\n"
    off = netplc(*base, "--scans", "9", "--at", "8:00000=0", cwd=tmp_path)
    assert off.stdout == "03001 = 0\n"


def test_symbols_file(prog, tmp_path, netplc):
    sym = tmp_path / "symbols.csv"
    sym.write_text("name,address,comment\nTTC,02042,input\nTA,02003,counter\n", encoding="utf-8")
    p = prog(COUNTER)
    pulses = ["--at", "1:02042=1", "--at", "2:02042=0", "--at", "4:02042=1"]
    r = netplc("run", p, "--symbols", sym, "--scans", "6", *pulses, "--print", "02005", "--print", "02000",
               cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout == "02005 = 1\n02000 = 1\n"  # two rising edges reach N:2


def test_halt_state_is_reported_on_stderr(prog, tmp_path, netplc):
    r = netplc("run", prog("HLT\n"), cwd=tmp_path)
    assert r.returncode == 0 and "state: halted" in r.stderr


def test_malformed_program_goes_to_stderr_with_status_2(prog, tmp_path):
    p = prog("TNA $02042\nTIM $03000 N:300\nFOO\n")
    r = netplc_process("run", p, cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == ""
    expected = [f"{p}:2:14: N: 300 is outside 0-255", f"{p}:3:1: unknown instruction 'FOO'"]
    assert r.stderr.splitlines() == expected


@pytest.mark.parametrize("args, message", [
    (["--set", "04000"], "expected ADDR=VALUE"),
    (["--set", "02000=2"], "takes 0 or 1"),
    (["--set", "04000=70000"], "0-65535"),
    (["--set", "010000=1"], "not a valid address"),
    (["--set", "0800=1"], "not an octal number"),
    (["--at", "x:02000=1"], "expected K:ADDR=VALUE"),
    (["--print", "010000"], "not a valid address"),
    (["--print", "04000:0"], "LEN must be at least 1"),
    (["--print", "07777:2"], "runs past the end of its bank"),
    (["--scans", "-1"], "expected a number of scans"),
    (["--symbols", "missing.csv"], "cannot read symbols"),
])
def test_bad_options_go_to_stderr_with_status_2(prog, tmp_path, args, message, netplc):
    r = netplc("run", prog("NOP\n"), *args, cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == ""
    assert message in r.stderr


def test_missing_program_file(tmp_path, netplc):
    r = netplc("run", tmp_path / "none.stl", cwd=tmp_path)
    assert r.returncode == 2 and "cannot read program" in r.stderr
