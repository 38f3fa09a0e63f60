"""Safe defaults of a station: its paths stay in its folder, it never writes over its own inputs, and
Modbus clients cannot write the special bits 03700-03777 unless station.toml names them."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.cli import main as cli
from app.station.config import DEFAULT_WRITABLE, ConfigError, load_station, read_station
from app.station.runtime import Runtime
from netplc.records import Record
from tests.app.conftest import write_station

PROGRAM = {"p.stl": "TNA $03760\nYON $02000\n", "s.csv": "X,02001,\n"}


def problems(folder: Path) -> list[str]:
    _, found = read_station(folder)
    return [p.removeprefix(f"{folder / 'station.toml'}: ") for p in found]


def test_paths_outside_the_station_folder_are_refused_unless_allowed(tmp_path: Path) -> None:
    outside = tmp_path / "elsewhere.stl"
    outside.write_text("JMP 0\n", encoding="utf-8")
    st = tmp_path / "st"
    write_station(st, 'NetPlcProgram = "../elsewhere.stl"\nHMIload = "/etc"\nArchive = "/tmp/a.sqlite"\n'
                      '[[simulators]]\nnode = 0\nprogram = "../elsewhere.stl"\n')
    why = f"is outside the station folder {st} (allow_outside = true permits it)"
    assert problems(st) == [f"NetPlcProgram: {outside} {why}", f"HMIload: /etc {why}",
                            f"Archive: /tmp/a.sqlite {why}", f"simulators[0].program: {outside} {why}"]
    with pytest.raises(ConfigError):
        load_station(st)
    write_station(st, 'allow_outside = true\nNetPlcProgram = "../elsewhere.stl"\nArchive = "../a.sqlite"\n')
    station = load_station(st)
    assert station.NetPlcProgram == outside and station.Archive == tmp_path / "a.sqlite"


@pytest.mark.parametrize(("key", "value", "what"), [
    ("Retain", "p.stl", "NetPlcProgram"),
    ("Retain", "station.toml", "station.toml"),
    ("Archive", "s.csv", "Symbols"),
    ("Retain", "forms/a.hmi", "a form of HMIload"),
    ("Archive", "node.stl", "simulators[0].program"),
])
def test_retain_or_archive_on_a_station_input_is_refused_by_check_and_start(
        tmp_path: Path, key: str, value: str, what: str, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "forms").mkdir()
    toml = (f'NetPlcProgram = "p.stl"\nSymbols = "s.csv"\nHMIload = "forms"\n{key} = "{value}"\n'
            '[modbus_server]\nenabled = false\n[[simulators]]\nnode = 0\nprogram = "node.stl"\n')
    write_station(tmp_path, toml, {**PROGRAM, "node.stl": "JMP 0\n"})
    path = (tmp_path / value).resolve()
    expected = f"{key}: {path} is a station input ({what}): writing there would overwrite it"
    assert problems(tmp_path) == [expected]
    assert cli(["check", str(tmp_path)]) == 1  # `main.py check`, its exit code
    assert f"{tmp_path / 'station.toml'}: {expected}" in capsys.readouterr().out
    before = (tmp_path / value).read_bytes() if (tmp_path / value).exists() else None
    with pytest.raises(ConfigError):
        Runtime(load_station(tmp_path))
    assert ((tmp_path / value).read_bytes() if (tmp_path / value).exists() else None) == before


def test_the_special_bits_are_writable_only_when_named(tmp_path: Path) -> None:
    from pymodbus.client import ModbusTcpClient

    write_station(tmp_path, 'NetPlcProgram = "p.stl"\n[modbus_server]\nport = 0\n', PROGRAM)
    assert not any(lo <= 0o3770 <= hi for lo, hi in DEFAULT_WRITABLE)
    runtime = Runtime(load_station(tmp_path))
    records: list[Record] = []
    runtime.subscribe(records.append)
    runtime.start()
    try:
        assert runtime.modbus is not None
        client = ModbusTcpClient("127.0.0.1", port=runtime.modbus.port)
        assert client.connect()
        assert client.write_coil(0o3770, True).exception_code == 2  # emergency stop: refused
        assert not client.write_coil(0o3677, True).isError()  # the last default-writable bit
        peer = f"modbus 127.0.0.1:{client.socket.getsockname()[1]}"
        client.close()
    finally:
        runtime.stop()
    assert runtime.status().state == "running"
    refused = [r for r in records if r.kind == "operator" and (r.text or "").startswith("refused")]
    assert [(r.source, r.text) for r in refused] == [
        (peer, "refused write 03770: not writable over Modbus (station.toml [modbus_server] writable)")]
    write_station(tmp_path, 'NetPlcProgram = "p.stl"\n[modbus_server]\nwritable = [["02000", "03777"]]\n')
    assert load_station(tmp_path).modbus_server.writable == ((0o2000, 0o3777),)


def test_modbus_clients_act_with_the_role_the_station_grants_and_a_bounded_share_per_peer(
        tmp_path: Path) -> None:
    from pymodbus.client import ModbusTcpClient

    write_station(tmp_path, 'NetPlcProgram = "p.stl"\n', PROGRAM)
    server = load_station(tmp_path).modbus_server
    assert (server.role, server.max_per_peer) == ("operator", 4)  # the defaults
    write_station(tmp_path, 'NetPlcProgram = "p.stl"\n[modbus_server]\nport = 0\nrole = "viewer"\n'
                            'max_per_peer = 2\n')
    runtime = Runtime(load_station(tmp_path))
    runtime.start()
    try:
        assert runtime.modbus is not None and runtime.modbus._server.limits.max_per_peer == 2
        client = ModbusTcpClient("127.0.0.1", port=runtime.modbus.port)
        assert client.connect()
        assert client.write_register(1024, 1).exception_code == 1  # read-only: no write function
        assert not client.read_holding_registers(1024, count=1).isError()
        client.close()
    finally:
        runtime.stop()
    write_station(tmp_path, 'NetPlcProgram = "p.stl"\n[modbus_server]\nrole = "root"\nmax_per_peer = 0\n')
    assert problems(tmp_path) == [
        "modbus_server.max_per_peer: 0 is outside 1-1000",
        "modbus_server.role: 'root' is not one of viewer, operator, engineer, admin"]
