"""The simulated CPU-165 node: in process, and as `python -m netplc.simulator` from the command line."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from pymodbus.client import ModbusTcpClient

from netplc.program import parse
from netplc.simulator import Simulator, main
from tests.netplc.test_exchange import NODE_PROGRAM, wait_until

ROOT = Path(__file__).resolve().parents[2]


def test_simulator_runs_its_program_and_serves_all_memory_writable() -> None:
    sim = Simulator(parse(NODE_PROGRAM, "node.stl"), tick=0.01)
    sim.start()
    try:
        c = ModbusTcpClient("127.0.0.1", port=sim.port, timeout=2)
        assert c.connect()
        assert not c.write_register(0o4004 // 2, 0b100, device_id=1).isError()  # Пуск: 04004 bit 2
        wait_until(lambda: sim.engine.snapshot.get_bit(0o2005) == 1)  # trigger output set
        assert c.read_holding_registers(1024, count=1, device_id=1).registers[0] & 0b101000 == 0b101000
        assert not c.write_coil(0o100, True, device_id=1).isError()  # any I/O bit is writable too
        wait_until(lambda: sim.engine.snapshot.get_bit(0o100) == 1)
        c.close()
    finally:
        sim.stop()


def test_main_reports_bad_arguments(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.stl"
    bad.write_text("TNA $09999\n", encoding="utf-8")
    assert main([str(bad), "--port", "0"]) == 2
    assert f"{bad}:1:" in capsys.readouterr().err
    assert main([str(tmp_path / "missing.stl"), "--port", "0"]) == 2
    assert "missing.stl" in capsys.readouterr().err
    good = tmp_path / "node.stl"
    good.write_text(NODE_PROGRAM, encoding="utf-8")
    assert main([str(good), "--tick", "0"]) == 2
    assert "--tick 0" in capsys.readouterr().err


def test_command_line_simulator(tmp_path: Path) -> None:
    program = tmp_path / "node.stl"
    program.write_text("v = $04000\nTNA $03760\nFON C:$03000 N:MOV S:$04002 D:v\nJMP 0\n", encoding="utf-8")
    errors = tmp_path / "stderr.txt"
    with open(errors, "wb") as err:  # a file, not a pipe nobody reads: a full pipe would block it
        # started as a script's background job is: with SIGINT ignored (`trap "" INT`), which Ctrl-C
        # must stop all the same
        proc = subprocess.Popen(
            ["sh", "-c", 'trap "" INT; exec "$@"', "sh", sys.executable, "-m", "netplc.simulator",
             str(program), "--port", "0", "--tick", "10", "--unit", "3"],
            cwd=ROOT, stdout=subprocess.PIPE, stderr=err, text=True,
            env={**os.environ, "PYTHONUNBUFFERED": "1", "PYTHONFAULTHANDLER": "1"},
        )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        m = re.search(r"Modbus TCP on 127\.0\.0\.1:(\d+) unit 3", line)
        assert m, line + (errors.read_text() if proc.poll() is not None else "")
        c = ModbusTcpClient("127.0.0.1", port=int(m.group(1)), timeout=2)
        assert c.connect()
        assert not c.write_register(1025, 4242, device_id=3).isError()
        wait_until(lambda: c.read_holding_registers(1024, count=1, device_id=3).registers == [4242])
        c.close()
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            code = proc.wait(60)
        except subprocess.TimeoutExpired:
            proc.send_signal(signal.SIGABRT)  # PYTHONFAULTHANDLER: every thread's stack to stderr
            proc.wait(10)
            pytest.fail("the simulator did not stop on Ctrl-C:\n" + errors.read_text(errors="replace"))
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait(10)
    assert code == 0, errors.read_text(errors="replace")
