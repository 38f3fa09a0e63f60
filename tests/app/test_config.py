"""station.toml: the manual's settings, paths relative to the file, every problem named by key."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.station.config import ConfigError, load_station, read_station
from netplc.exchange import NodeConfig
from netplc.modbus import Endpoint
from tests.app.conftest import DEMO, write_station


def test_demo_station_loads_with_paths_relative_to_its_file() -> None:
    st = load_station(DEMO)
    assert st.NetPlcLoad is True
    assert st.NetPlcProgram == DEMO / "netplc.stl"
    assert st.HMIload == DEMO / "forms"
    assert st.NetSyncTime == 100 and st.tick == 0.1
    assert st.Archive == DEMO / "archive" / "journal.sqlite"
    assert st.modbus_server.writable == ((0o2000, 0o2177), (0o4000, 0o4777))
    assert [s.node for s in st.simulators] == [0]
    node = st.nodes[0]
    assert (node.node, node.endpoint, node.timeout) == (0, "", 0.5)  # the simulator fills it in
    assert st.operator.default_user == "viewer" and st.operator.idle_logout == 900


def test_defaults(tmp_path: Path) -> None:
    write_station(tmp_path, 'NetPlcProgram = "p.stl"\n', {"p.stl": "JMP 0\n"})
    st = load_station(tmp_path / "station.toml")
    assert st.NetSyncTime == 100
    assert st.Archive == tmp_path / "archive" / "journal.sqlite"
    assert st.Retain == tmp_path / "archive" / "retain.bin"
    assert st.keep_days == 0 and st.nodes == () and st.operator.default_user == ""
    assert st.modbus_server.host == "127.0.0.1"


def test_every_problem_is_named_by_its_key(tmp_path: Path) -> None:
    write_station(tmp_path, """
NetPlcProgram = "missing.stl"
Language = "de"
NetSyncTime = "fast"
keep_days = -1
Colour = "red"
[modbus_server]
port = 70000
writable = [["04000"], ["09000", "04777"], ["04777", "04000"], ["02000", "04000"]]
[[nodes]]
node = 3
endpoint = "tcp://plc:99999"
profile = "s7"
[[nodes]]
node = 3
endpoint = "com1"
[[nodes]]
node = 5
name = "Pump/house"
[[nodes]]
node = 6
endpoint = "tcp://plc:502"
name = "Node3"
[[simulators]]
node = 9
program = "nowhere.stl"
[operator]
users = []
idle_logout = -5
""")
    with pytest.raises(ConfigError) as e:
        load_station(tmp_path)
    text = "\n".join(e.value.problems)
    for expected in (
        "NetPlcProgram: file", "NetSyncTime: expected an integer", "keep_days: -1 is outside",
        "Colour: unknown setting", "modbus_server.port: 70000 is outside", "modbus_server.writable[0]",
        "modbus_server.writable[1]: '09000' is not an octal number",
        "modbus_server.writable[2]: 04777 is above",
        "modbus_server.writable[3]: a range must lie within", "nodes[0].endpoint: endpoint 'tcp://plc:99999'",
        "nodes[0].profile: 's7'", "nodes[1].node: node 3 is configured twice",
        "nodes[1].endpoint: endpoint 'com1'",
        "nodes[2].name: 'Pump/house' may not hold '/', '+', '#'",
        "nodes[3].name: 'Node3' already names node 3",
        "node 5 has no endpoint and no simulator", "simulators[0].program: file",
        "operator.users: users are kept in users.json",
        "operator.idle_logout: -5 is outside", "Language: 'de' is not one of ru, en",
    ):
        assert expected in text, expected
    assert all(p.startswith(str(tmp_path / "station.toml")) for p in e.value.problems)


def test_not_toml_and_missing(tmp_path: Path) -> None:
    write_station(tmp_path, "NetSyncTime = = 3\n")
    station, problems = read_station(tmp_path)
    assert station is None and "not valid TOML" in problems[0]
    with pytest.raises(ConfigError, match="no station file"):
        load_station(tmp_path / "nothere")


def test_simulator_with_a_fixed_port_gives_its_node_an_endpoint(tmp_path: Path) -> None:
    write_station(tmp_path, """
NetPlcLoad = false
[[simulators]]
node = 2
program = "n.stl"
port = 5020
""", {"n.stl": "JMP 0\n"})
    st = load_station(tmp_path)
    assert st.nodes[0].endpoint == "tcp://127.0.0.1:5020"
    assert st.NetPlcProgram is None


def test_node_back_off_and_server_unit_pass_through(tmp_path: Path) -> None:
    write_station(tmp_path, """
NetPlcLoad = false
[modbus_server]
unit = 5
[[nodes]]
node = 1
endpoint = "tcp://127.0.0.1:5020"
backoff = 0.5
backoff_max = 2
""")
    st = load_station(tmp_path)
    cfg = st.nodes[0]  # the exchange's own model: nothing is copied field by field
    assert isinstance(cfg, NodeConfig) and cfg.parsed is not None and cfg.parsed.port == 5020
    assert (cfg.backoff, cfg.backoff_max, cfg.key) == (0.5, 2.0, "nodes[0]")
    assert st.modbus_server.unit == 5
    write_station(tmp_path, "NetPlcLoad = false\n")
    assert load_station(tmp_path).modbus_server.unit is None  # every unit id is answered


def test_modbus_server_limits_have_safe_defaults_and_are_checked(tmp_path: Path) -> None:
    write_station(tmp_path, "NetPlcLoad = false\n")
    server = load_station(tmp_path).modbus_server
    assert (server.max_connections, server.idle_timeout, server.max_inflight) == (16, 60.0, 32)
    write_station(tmp_path, """
NetPlcLoad = false
[modbus_server]
max_connections = 4
idle_timeout = 5
max_inflight = 8
""")
    server = load_station(tmp_path).modbus_server
    assert (server.max_connections, server.idle_timeout, server.max_inflight) == (4, 5.0, 8)
    write_station(tmp_path, """
NetPlcLoad = false
[modbus_server]
max_connections = 0
idle_timeout = -1
max_inflight = "many"
""")
    with pytest.raises(ConfigError) as e:
        load_station(tmp_path)
    text = str(e.value)
    for key in ("max_connections: 0 is outside", "idle_timeout:", "max_inflight: expected an integer"):
        assert f"modbus_server.{key}" in text


def test_node_timing_and_line_problems_are_named_by_key(tmp_path: Path) -> None:
    write_station(tmp_path, """
NetPlcLoad = false
[modbus_server]
unit = 300
[[nodes]]
node = 1
endpoint = "tcp://127.0.0.1:5020"
backoff = "fast"
backoff_max = 0
timeout = true
[[nodes]]
node = 2
endpoint = "tcp://127.0.0.1:5021"
backoff = 3
backoff_max = 1
[[nodes]]
node = 3
endpoint = "tcp://bad..name:502"
[[nodes]]
node = 4
endpoint = "rtu:///dev/ttyX?baudrate=9600"
[[nodes]]
node = 5
endpoint = "rtu:///dev/ttyX?baudrate=19200"
""")
    with pytest.raises(ConfigError) as e:
        load_station(tmp_path)
    problems = [p.removeprefix(f"{tmp_path / 'station.toml'}: ") for p in e.value.problems]
    assert problems == [
        "modbus_server.unit: 300 is outside 1-247",
        "nodes[0].timeout: expected a number, got True",
        "nodes[0].backoff: expected a number, got 'fast'",
        "nodes[0].backoff_max: 0 s is outside 0.01-3600 s",
        "nodes[1].backoff: 3 s is more than backoff_max 1 s",
        "nodes[2].endpoint: endpoint 'tcp://bad..name:502': 'bad..name' is not a valid host name",
        "nodes[4].endpoint: rtu:///dev/ttyX?baudrate=19200&parity=E and node 4's "
        "rtu:///dev/ttyX?baudrate=9600&parity=E share /dev/ttyX with different line settings",
    ]


WHY = "(0 is broadcast, which never answers; 248-255 are reserved)"


def test_node_unit_ranges_are_the_models_per_scheme(tmp_path: Path) -> None:
    write_station(tmp_path, """
NetPlcLoad = false
[[nodes]]
node = 1
endpoint = "tcp://127.0.0.1:5020"
unit = 255
[[nodes]]
node = 2
endpoint = "rtu:///dev/ttyX?baudrate=9600"
unit = 0
[[nodes]]
node = 3
endpoint = "rtu:///dev/ttyX?baudrate=9600"
unit = 248
[[nodes]]
node = 4
endpoint = "tcp://127.0.0.1:5021"
unit = 256
""")
    station, problems = read_station(tmp_path)
    problems = [p.removeprefix(f"{tmp_path / 'station.toml'}: ") for p in problems]
    assert problems == [
        f"nodes[1].unit: unit 0 is not 1-247 on rtu {WHY}",
        f"nodes[2].unit: unit 248 is not 1-247 on rtu {WHY}",
        "nodes[3].unit: unit 256 is not 0-255 on tcp",
    ]
    assert station is not None and station.nodes[0].unit == 255


def test_ports_the_station_would_listen_on_twice(tmp_path: Path) -> None:
    write_station(tmp_path, """
NetPlcLoad = false
[modbus_server]
port = 5020
[[simulators]]
node = 1
program = "n.stl"
port = 5020
[[simulators]]
node = 2
program = "n.stl"
port = 5021
[[simulators]]
node = 3
program = "n.stl"
port = 5021
""", {"n.stl": "JMP 0\n"})
    with pytest.raises(ConfigError) as e:
        load_station(tmp_path)
    assert [p.split(": ", 1)[1] for p in e.value.problems] == [
        "simulators[0].port: 127.0.0.1:5020 is also modbus_server.port",
        "simulators[2].port: 127.0.0.1:5021 is also simulators[1].port",
    ]


def test_a_path_says_what_is_there_instead_of_a_file(tmp_path: Path) -> None:
    """A loop of links, a FIFO or a folder where a file belongs is named by its key and what it is,
    never a traceback (Python 3.11's Path.resolve raises RuntimeError for a loop) or "does not exist"."""
    import os

    (tmp_path / "node0.stl").mkdir()
    os.mkfifo(tmp_path / "messages.csv")
    os.symlink("p.stl", tmp_path / "p.stl")
    (tmp_path / "forms").write_text("", encoding="utf-8")
    write_station(tmp_path, 'NetPlcProgram = "p.stl"\nMessages = "messages.csv"\nHMIload = "forms"\n'
                            '[[simulators]]\nnode = 0\nprogram = "node0.stl"\n')
    toml = tmp_path / "station.toml"
    assert read_station(tmp_path)[1] == [
        f"{toml}: NetPlcProgram: {tmp_path / 'p.stl'}: a loop of symbolic links",
        f"{toml}: HMIload: folder {tmp_path / 'forms'} is a file, not a folder",
        f"{toml}: Messages: file {tmp_path / 'messages.csv'} is a FIFO (named pipe), not a file",
        f"{toml}: simulators[0].program: file {tmp_path / 'node0.stl'} is a folder, not a file",
    ]
    toml.unlink()
    os.symlink("station.toml", toml)
    assert read_station(tmp_path)[1] == [
        f"{toml}: cannot read the station file: Too many levels of symbolic links"]


def test_modbus_server_over_rtu_reads_its_serial_port_and_line(tmp_path: Path) -> None:
    write_station(tmp_path, 'NetPlcLoad = false\n[modbus_server]\ntransport = "rtu"\nport = "/dev/ttyUSB0"\n')
    server = load_station(tmp_path).modbus_server
    assert server.transport == "rtu" and server.unit == 1  # a slave on a shared line has one address
    assert server.serial == Endpoint("rtu", device="/dev/ttyUSB0", baudrate=19200, parity="E", stopbits=1)
    write_station(tmp_path, """
NetPlcLoad = false
[modbus_server]
transport = "rtu"
port = "COM3"
baudrate = 9600
parity = "n"
unit = 17
role = "viewer"
""")
    server = load_station(tmp_path).modbus_server
    assert server.serial == Endpoint("rtu", device="COM3", baudrate=9600, parity="N", stopbits=2)
    assert (server.unit, server.role) == (17, "viewer")
    assert load_station(DEMO).modbus_server.transport == "tcp"


@pytest.mark.parametrize(("server", "expected"), [
    ('transport = "rtu"', ['modbus_server.port: missing: transport = "rtu" answers on a serial port, '
                           'such as "/dev/ttyUSB0" or "COM3"']),
    ('transport = "rtu"\nport = 1502', ["modbus_server.port: expected a string, got 1502"]),
    ('transport = "rtu"\nport = " "', ["modbus_server.port: ' ' is not a serial port"]),
    ('transport = "rtu"\nport = "/dev/ttyS1"\nbaudrate = 19000\nparity = "X"\nstopbits = 3',
     ["modbus_server.baudrate: baudrate 19000 is not one of 50, 75, 110, 134, 150, 200, 300, 600, 1200, "
      "1800, 2400, 4800, 9600, 19200, 38400, 57600, 115200, 230400, 460800, 500000, 576000, 921600, "
      "1000000, 1152000, 1500000, 2000000, 2500000, 3000000, 3500000, 4000000",
      "modbus_server.parity: parity 'X' is not one of N, E, O",
      "modbus_server.stopbits: stopbits 3 is not one of 1, 2"]),
    ('transport = "rtu"\nport = "/dev/ttyS1"\nbaudrate = "fast"',
     ["modbus_server.baudrate: expected an integer, got 'fast'"]),
    ('transport = "rtu"\nport = "/dev/ttyS1"\nhost = "0.0.0.0"\nmax_connections = 2\nunit = 0',
     ['modbus_server.host: applies to transport = "tcp" only',
      'modbus_server.max_connections: applies to transport = "tcp" only',
      "modbus_server.unit: 0 is outside 1-247"]),
    ('baudrate = 9600', ['modbus_server.baudrate: applies to transport = "rtu" only']),
    ('transport = "ascii"', ["modbus_server.transport: 'ascii' is not one of tcp, rtu"]),
    ('transport = "rtu"\nport = "/dev/ttyS1"\n[[nodes]]\nnode = 1\nendpoint = "rtu:///dev/ttyS1"',
     ["modbus_server.port: /dev/ttyS1 is also the serial port of nodes[0].endpoint: the station cannot "
      "be the master and a slave on one line"]),
])
def test_modbus_server_over_rtu_problems_are_named_by_key(tmp_path: Path, server: str,
                                                          expected: list[str]) -> None:
    write_station(tmp_path, f"NetPlcLoad = false\n[modbus_server]\n{server}\n")
    _, problems = read_station(tmp_path)
    assert [p.removeprefix(f"{tmp_path / 'station.toml'}: ") for p in problems] == expected
