"""What cannot start is named by its key or file: in Runtime, in `check`, and from `--no-gui`."""

from __future__ import annotations

import asyncio
import socket
import sqlite3
import threading
import time
from pathlib import Path

import pytest

from app.cli import main as cli
from app.station.check import check_station
from app.station.config import load_station
from app.station.runtime import Runtime, StartError, unresolved_hosts
from netplc.modbus import DeviceError, LeanTcpClient, parse_endpoint
from netplc.program import parse
from netplc.simulator import Simulator
from tests.app.conftest import write_station
from tests.commands import run_in_process

SIMULATED = """
NetPlcLoad = false
[modbus_server]
port = 0
unit = 5
[[simulators]]
node = 0
program = "node.stl"
port = {port}
"""
UNRESOLVABLE = """
NetPlcLoad = false
[modbus_server]
enabled = false
[[nodes]]
node = 1
endpoint = "tcp://127.0.0.1:5020"
[[nodes]]
node = 2
endpoint = "tcp://nohost.invalid:{port}"
backoff = 0.05
backoff_max = 0.1
"""


def headless(station: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    """`main.py --no-gui STATION --duration 0.5` run in this process (tests/app/test_headless.py runs
    it as a process of its own): its exit code and stderr."""
    done = run_in_process(cli, ["--no-gui", station, "--duration", "0.5"], capsys)
    return done.returncode, done.stderr


def system_texts(archive: Path) -> list[str]:
    con = sqlite3.connect(f"file:{archive}?mode=ro", uri=True)
    try:
        tables = [r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type='table'")
                  if r[0][:2].isdigit()]
        query = 'SELECT text FROM "{}" WHERE kind = \'system\''
        return [r[0] for t in tables for r in con.execute(query.format(t))]
    finally:
        con.close()


def test_the_modbus_server_answers_the_configured_unit_only(tmp_path: Path) -> None:
    write_station(tmp_path, SIMULATED.format(port=0), {"node.stl": "JMP 0\n"})
    runtime = Runtime(load_station(tmp_path))
    runtime.start()
    try:
        assert runtime.modbus is not None and runtime.modbus.unit == 5

        async def read(unit: int) -> list[int]:
            client = LeanTcpClient(parse_endpoint(f"tcp://127.0.0.1:{runtime.modbus.port}"), 2.0)
            await client.connect()
            try:
                return await client.read(unit, "holding", 0o2000, 1)
            finally:
                client.close()

        assert asyncio.run(read(5)) == [0]
        with pytest.raises(DeviceError, match="Modbus exception 11"):
            asyncio.run(read(1))
    finally:
        runtime.stop()


def test_a_simulator_port_in_use_names_the_key_and_starts_nothing(tmp_path: Path) -> None:
    with socket.create_server(("127.0.0.1", 0)) as taken:
        port = taken.getsockname()[1]
        write_station(tmp_path, SIMULATED.format(port=port), {"node.stl": "JMP 0\n"})
        runtime = Runtime(load_station(tmp_path))
        with pytest.raises(StartError) as e:
            runtime.start()
    problem = (f"{tmp_path / 'station.toml'}: simulators[0].port: cannot listen on 127.0.0.1:{port}: "
               "Address already in use")
    assert e.value.problems == [problem]
    assert runtime.simulators == [] and runtime.exchange is None and runtime.modbus is None
    assert not runtime.started
    texts = system_texts(tmp_path / "archive" / "journal.sqlite")
    assert f"station cannot start: {problem}" in texts and "station stopped" not in texts
    runtime.stop()  # a second stop after a failed start does nothing


def test_a_start_interrupted_by_ctrl_c_stops_what_had_started(tmp_path: Path, monkeypatch) -> None:
    write_station(tmp_path, SIMULATED.format(port=0), {"node.stl": "JMP 0\n"})
    runtime = Runtime(load_station(tmp_path))

    def interrupted(*args: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(runtime, "_fill_endpoint", interrupted)  # once the first simulator listens
    with pytest.raises(KeyboardInterrupt):
        runtime.start()
    assert runtime.simulators == [] and runtime.store is None and runtime.retainer is None
    assert not runtime.started
    assert "station starting" in " ".join(system_texts(tmp_path / "archive" / "journal.sqlite"))


def test_a_node_host_that_does_not_resolve_is_journaled_and_the_node_comes_up_once_it_does(
        tmp_path: Path, monkeypatch) -> None:
    # The resolver is this test's: "not found" until the name server is "up", then 127.0.0.1, where
    # a simulated node listens. No query leaves this machine.
    real = socket.getaddrinfo
    name_server_up = threading.Event()

    def resolve(host, *args, **kwargs):
        if host == "nohost.invalid":
            if not name_server_up.is_set():
                raise socket.gaierror(socket.EAI_NONAME, "Name or service not known")
            host = "127.0.0.1"
        return real(host, *args, **kwargs)

    monkeypatch.setattr(socket, "getaddrinfo", resolve)
    node = Simulator(parse("JMP 0\n"))
    node.start()
    write_station(tmp_path, UNRESOLVABLE.format(port=node.port))
    where = f"{tmp_path / 'station.toml'}: nodes[1].endpoint: host 'nohost.invalid' does not resolve"
    report = check_station(tmp_path)
    assert next(p for p in report.problems if "endpoint" in p).startswith(where)
    runtime = Runtime(load_station(tmp_path))
    texts: list[str] = []
    runtime.subscribe(lambda r: texts.append(r.text or "") if r.kind == "system" else None)
    runtime.start()
    try:
        assert wait_for(lambda: any(t.startswith(where) for t in texts))
        assert [n.up for n in runtime.status().nodes] == [False, False]
        name_server_up.set()
        assert wait_for(lambda: runtime.status().nodes[1].up)
    finally:
        runtime.stop()
        node.stop()


def test_a_host_the_resolver_cannot_encode_is_a_problem_too(tmp_path: Path, monkeypatch) -> None:
    def resolve(host, *args, **kwargs):
        raise UnicodeError("encoding with 'idna' codec failed")

    monkeypatch.setattr(socket, "getaddrinfo", resolve)
    write_station(tmp_path, UNRESOLVABLE.format(port=5020))
    assert [p.split(": ", 2)[1:] for p in unresolved_hosts(load_station(tmp_path))] == [
        ["nodes[0].endpoint", "host '127.0.0.1' is not a host name: encoding with 'idna' codec failed"],
        ["nodes[1].endpoint", "host 'nohost.invalid' is not a host name: encoding with 'idna' codec failed"]]


def wait_for(condition, seconds: float = 15.0) -> bool:
    deadline = time.monotonic() + seconds
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.02)
    return True


def test_a_missing_program_file_exits_2_naming_the_key(tmp_path: Path, capsys) -> None:
    write_station(tmp_path, 'NetPlcProgram = "gone.stl"\n')
    code, err = headless(tmp_path, capsys)
    assert code == 2 and "Traceback" not in err
    assert err.strip() == (f"{tmp_path / 'station.toml'}: NetPlcProgram: file {tmp_path / 'gone.stl'} "
                           "does not exist")


def test_headless_with_a_simulator_port_in_use_exits_2_naming_the_key(tmp_path: Path, capsys) -> None:
    with socket.create_server(("127.0.0.1", 0)) as taken:
        port = taken.getsockname()[1]
        write_station(tmp_path, SIMULATED.format(port=port), {"node.stl": "JMP 0\n"})
        code, err = headless(tmp_path, capsys)
    assert code == 2 and "Traceback" not in err
    assert f"simulators[0].port: cannot listen on 127.0.0.1:{port}" in err


def test_the_modbus_server_port_in_use_is_a_problem_shown_not_a_stop(tmp_path: Path) -> None:
    with socket.create_server(("127.0.0.1", 0)) as taken:
        port = taken.getsockname()[1]
        write_station(tmp_path, SIMULATED.format(port=0).replace("port = 0\nunit = 5", f"port = {port}"),
                      {"node.stl": "JMP 0\n"})
        runtime = Runtime(load_station(tmp_path))
        runtime.start()
        try:
            status = runtime.status()
            assert status.running and status.modbus_port is None
            assert status.problems == (f"Modbus server not started: {tmp_path / 'station.toml'}: "
                                       f"modbus_server.port: cannot listen on 127.0.0.1:{port}: "
                                       "Address already in use",)
        finally:
            runtime.stop()


def test_an_archive_that_cannot_be_made_names_the_key(tmp_path: Path) -> None:
    write_station(tmp_path, 'NetPlcLoad = false\nArchive = "blocker/journal.sqlite"\n')
    (tmp_path / "blocker").write_text("a file where the archive folder should be", encoding="utf-8")
    runtime = Runtime(load_station(tmp_path))
    with pytest.raises(StartError) as e:
        runtime.start()
    [problem] = e.value.problems
    assert problem.startswith(f"{tmp_path / 'station.toml'}: Archive: ") and "blocker" in problem
    assert runtime.store is None and not runtime.started
