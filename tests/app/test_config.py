"""station.toml: the manual's settings, paths relative to the file, every problem named by key."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.config import ConfigError, load_station, read_station
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
    assert st.users == ("operator", "engineer")


def test_defaults(tmp_path: Path) -> None:
    write_station(tmp_path, 'NetPlcProgram = "p.stl"\n', {"p.stl": "JMP 0\n"})
    st = load_station(tmp_path / "station.toml")
    assert st.NetSyncTime == 100
    assert st.Archive == tmp_path / "archive" / "journal.sqlite"
    assert st.Retain == tmp_path / "archive" / "retain.bin"
    assert st.keep_days == 0 and st.nodes == () and st.users == ("operator",)
    assert st.modbus_server.host == "127.0.0.1"


def test_every_problem_is_named_by_its_key(tmp_path: Path) -> None:
    write_station(tmp_path, """
NetPlcProgram = "missing.stl"
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
[[simulators]]
node = 9
program = "nowhere.stl"
[operator]
users = []
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
        "node 5 has no endpoint and no simulator", "simulators[0].program: file", "operator.users",
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
