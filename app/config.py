"""The station file `station.toml`: the manual's FregatServer settings plus what the PC needs.

Keys keep the manual's spelling (NetPlcLoad, NetPlcProgram, HMIload, NetSyncTime). Paths are
relative to the station file so that a station folder can be copied to another machine and run
there. Every problem is collected and reported together as `station.toml: key: problem`, so an
engineer fixes a broken station in one pass instead of one error per start.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from netplc.address import fmt_octal, is_data_byte, is_io_bit, parse_octal
from netplc.modbus.driver import Endpoint, parse_endpoint

STATION_FILE = "station.toml"
DEMO_STATION = Path(__file__).resolve().parent.parent / "resources" / "example"  # the built-in demo
PROFILES = ("cpu165", "modbus")
TABLES = ("holding", "input", "coils", "discrete")
BAD_ENDPOINT = "?"  # an endpoint already reported as wrong: not "missing" as well
DEFAULT_WRITABLE = ((0o2000, 0o3777), (0o4000, 0o7777))


class ConfigError(Exception):
    """Every problem of a station file, each naming the key."""

    def __init__(self, problems: list[str]) -> None:
        self.problems = problems
        super().__init__("\n".join(problems))


@dataclass(frozen=True)
class NodeSettings:
    node: int
    endpoint: str  # tcp://host:port or rtu:///dev/ttyX?baudrate=..&parity=..; "" until a simulator fills it
    unit: int = 1
    profile: str = "cpu165"
    timeout: float = 1.0
    retries: int = 1
    table: str = "holding"
    backoff: float = 0.2  # s, the first reconnect delay after the link went down
    backoff_max: float = 5.0  # s, the delay doubles up to this
    key: str = "nodes"  # where it is set in station.toml (nodes[2], simulators[0]), for messages


@dataclass(frozen=True)
class SimulatorSettings:
    node: int
    program: Path
    symbols: Path | None = None
    host: str = "127.0.0.1"
    port: int = 0  # 0: an ephemeral port, and the node's endpoint is filled in at start
    unit: int = 1
    tick_ms: int = 100


@dataclass(frozen=True)
class ModbusServerSettings:
    enabled: bool = True
    host: str = "127.0.0.1"
    port: int = 1502
    writable: tuple[tuple[int, int], ...] = DEFAULT_WRITABLE
    unit: int | None = None  # the unit id answered; None: every unit id
    max_connections: int = 16  # the next connection is closed (one journal line a minute)
    idle_timeout: float = 60.0  # s without a whole request before a connection is closed
    max_inflight: int = 32  # answers (of the longest size) a connection may leave unread or waiting


@dataclass(frozen=True)
class Station:
    path: Path  # the station.toml file
    name: str
    NetPlcLoad: bool
    NetPlcProgram: Path | None
    Symbols: Path | None
    HMIload: Path | None
    NetSyncTime: int  # ms
    Archive: Path
    Messages: Path | None
    keep_days: int
    Retain: Path
    modbus_server: ModbusServerSettings
    nodes: tuple[NodeSettings, ...] = ()
    simulators: tuple[SimulatorSettings, ...] = ()
    users: tuple[str, ...] = ("operator",)

    @property
    def folder(self) -> Path:
        return self.path.parent

    @property
    def tick(self) -> float:
        return self.NetSyncTime / 1000.0


def station_file(path: str | Path) -> Path:
    """A station is named by its folder or by its station.toml."""
    p = Path(path)
    return p / STATION_FILE if p.is_dir() else p


class _Reader:
    """Typed access to one TOML table that records problems instead of raising at the first."""

    def __init__(self, problems: list[str], fname: str, table: dict[str, Any], prefix: str = "") -> None:
        self.problems = problems
        self.fname = fname
        self.table = table
        self.prefix = prefix
        self.known: set[str] = set()

    def bad(self, key: str, problem: str) -> None:
        self.problems.append(f"{self.fname}: {self.prefix}{key}: {problem}")

    def get(self, key: str, kind: type | tuple[type, ...], default: Any = None,
            required: bool = False) -> Any:
        self.known.add(key)
        if key not in self.table:
            if required:
                self.bad(key, "missing")
            return default
        value = self.table[key]
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            return float(value)
        if isinstance(value, bool) and kind is not bool:
            self.bad(key, f"expected {_kind_name(kind)}, got {value!r}")
            return default
        if not isinstance(value, kind):
            self.bad(key, f"expected {_kind_name(kind)}, got {value!r}")
            return default
        return value

    def number(self, key: str, default: int | None, lo: int, hi: int, required: bool = False) -> Any:
        value = self.get(key, int, default, required)
        if value is not None and not lo <= value <= hi:
            self.bad(key, f"{value} is outside {lo}-{hi}")
            return default
        return value

    def path(self, key: str, base: Path, default: str | None = None, required: bool = False) -> Path | None:
        value = self.get(key, str, default, required)
        if value is None:
            return None
        if not value.strip():
            self.bad(key, "empty path")
            return None
        return (base / value).resolve() if not Path(value).is_absolute() else Path(value)

    def finish(self) -> None:
        for key in self.table:
            if key not in self.known:
                self.bad(key, "unknown setting")


def _kind_name(kind: type | tuple[type, ...]) -> str:
    names = {bool: "true or false", int: "an integer", float: "a number", str: "a string",
             list: "a list", dict: "a table"}
    kinds = kind if isinstance(kind, tuple) else (kind,)
    return " or ".join(names.get(k, k.__name__) for k in kinds)


def load_station(path: str | Path) -> Station:
    """Read and validate a station; ConfigError lists every problem."""
    station, problems = read_station(path)
    if problems or station is None:
        raise ConfigError(problems)
    return station


def read_station(path: str | Path) -> tuple[Station | None, list[str]]:
    """The station as far as it can be read, and its problems (for `check`, which goes on to
    check the program and forms even when a setting is wrong). Files that do not exist are None
    in the returned station; None instead of a station when the file is not TOML at all."""
    file = station_file(path)
    fname = str(file)
    try:
        data = tomllib.loads(file.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None, [f"{fname}: no station file here"]
    except OSError as e:
        return None, [f"{fname}: cannot read: {e.strerror}"]
    except UnicodeDecodeError as e:
        return None, [f"{fname}: not UTF-8 text: {e.reason}"]
    except tomllib.TOMLDecodeError as e:
        return None, [f"{fname}: not valid TOML: {e}"]
    problems: list[str] = []
    base = file.parent.resolve()
    top = _Reader(problems, fname, data)
    name = top.get("name", str, base.name)
    load = top.get("NetPlcLoad", bool, True)
    program = top.path("NetPlcProgram", base, required=bool(load))
    symbols = top.path("Symbols", base)
    hmi = top.path("HMIload", base)
    sync = top.number("NetSyncTime", 100, 10, 60_000)
    archive = top.path("Archive", base, "archive/journal.sqlite")
    messages = top.path("Messages", base)
    keep_days = top.number("keep_days", 0, 0, 36_500)
    retain = top.path("Retain", base)
    server = _modbus_server(problems, fname, top.get("modbus_server", dict, {}))
    nodes = _nodes(problems, fname, top.get("nodes", list, []))
    simulators = _simulators(problems, fname, top.get("simulators", list, []), base)
    users = _users(problems, fname, top.get("operator", dict, {}))
    top.finish()
    nodes = _with_simulated_nodes(problems, fname, nodes, simulators)
    _ports_in_common(problems, fname, server, simulators)
    program, symbols, hmi, messages = (
        _existing(top, key, p, must_be_dir)
        for key, p, must_be_dir in (("NetPlcProgram", program, False), ("Symbols", symbols, False),
                                    ("HMIload", hmi, True), ("Messages", messages, False)))
    runnable: list[SimulatorSettings] = []
    for i, sim in enumerate(simulators):
        missing = [(key, p) for key, p in (("program", sim.program), ("symbols", sim.symbols))
                   if p is not None and not p.is_file()]
        for key, p in missing:
            problems.append(f"{fname}: simulators[{i}].{key}: file {p} does not exist")
        if not missing:
            runnable.append(sim)
    archive = archive or base / "archive" / "journal.sqlite"
    station = Station(
        path=file.resolve(), name=name or base.name, NetPlcLoad=bool(load), NetPlcProgram=program,
        Symbols=symbols, HMIload=hmi, NetSyncTime=sync, Archive=archive, Messages=messages,
        keep_days=keep_days, Retain=retain or archive.with_name("retain.bin"), modbus_server=server,
        nodes=tuple(nodes), simulators=tuple(runnable), users=users,
    )
    return station, problems


def _existing(r: _Reader, key: str, path: Path | None, must_be_dir: bool) -> Path | None:
    if path is not None and not (path.is_dir() if must_be_dir else path.is_file()):
        r.bad(key, f"{'folder' if must_be_dir else 'file'} {path} does not exist")
        return None
    return path


def _modbus_server(problems: list[str], fname: str, table: dict[str, Any]) -> ModbusServerSettings:
    r = _Reader(problems, fname, table, "modbus_server.")
    enabled = r.get("enabled", bool, True)
    host = r.get("host", str, "127.0.0.1")
    port = r.number("port", 1502, 0, 65535)
    ranges = r.get("writable", list, None)
    unit = r.number("unit", None, 1, 247)
    max_connections = r.number("max_connections", 16, 1, 1000)
    max_inflight = r.number("max_inflight", 32, 1, 10_000)
    idle_timeout = _seconds(r, "idle_timeout", 60.0, 0.1, 86_400.0)
    r.finish()
    writable = DEFAULT_WRITABLE if ranges is None else _ranges(r, ranges)
    return ModbusServerSettings(enabled, host, port, writable, unit, max_connections, idle_timeout,
                                max_inflight)


def _ranges(r: _Reader, ranges: list[Any]) -> tuple[tuple[int, int], ...]:
    """Writable ranges are pairs of octal address strings: [["04000", "04777"], ...]."""
    out: list[tuple[int, int]] = []
    for i, pair in enumerate(ranges):
        key = f"writable[{i}]"
        if not (isinstance(pair, list) and len(pair) == 2 and all(isinstance(a, str) for a in pair)):
            r.bad(key, f'expected a pair of octal addresses like ["04000", "04777"], got {pair!r}')
            continue
        try:
            lo, hi = parse_octal(pair[0]), parse_octal(pair[1])
        except ValueError as e:
            r.bad(key, str(e))
            continue
        ok = True
        for a in (lo, hi):
            if not (is_io_bit(a) or is_data_byte(a)):
                r.bad(key, f"{fmt_octal(a)} is neither an I/O bit nor a data address")
                ok = False
        if ok and lo > hi:
            r.bad(key, f"{fmt_octal(lo)} is above {fmt_octal(hi)}")
        elif ok and is_io_bit(lo) != is_io_bit(hi):
            r.bad(key, "a range must lie within the I/O bits or within data memory")
        elif ok:
            out.append((lo, hi))
    return tuple(out)


def _array_tables(problems: list[str], fname: str, items: list[Any], key: str) -> list[tuple[int, _Reader]]:
    """A reader for each table of an array of tables ([[nodes]], [[simulators]]); an item that is
    not a table is a problem naming its index."""
    readers = []
    for i, table in enumerate(items):
        if isinstance(table, dict):
            readers.append((i, _Reader(problems, fname, table, f"{key}[{i}].")))
        else:
            problems.append(f"{fname}: {key}[{i}]: expected a [[{key}]] table")
    return readers


def _nodes(problems: list[str], fname: str, items: list[Any]) -> list[NodeSettings]:
    nodes: list[NodeSettings] = []
    seen: set[int] = set()
    lines: dict[str, tuple[int, Endpoint]] = {}  # serial device -> the first node on it
    for i, r in _array_tables(problems, fname, items, "nodes"):
        node = r.number("node", -1, 0, 255, required=True)
        endpoint = r.get("endpoint", str, "")
        unit = r.number("unit", 1, 0, 247)
        profile = r.get("profile", str, "cpu165")
        timeout = _seconds(r, "timeout", 1.0, 0.01, 60)
        retries = r.number("retries", 1, 0, 10)
        table_name = r.get("table", str, "holding")
        backoff = _seconds(r, "backoff", 0.2, 0.01, 600)
        backoff_max = _seconds(r, "backoff_max", 5.0, 0.01, 3600)
        r.finish()
        if backoff > backoff_max:
            r.bad("backoff", f"{backoff:g} s is more than backoff_max {backoff_max:g} s")
            backoff = min(0.2, backoff_max)
        if endpoint:
            try:
                ep = parse_endpoint(endpoint)
            except ValueError as e:
                r.bad("endpoint", str(e))
                endpoint = BAD_ENDPOINT
            else:
                first, line = lines.setdefault(ep.device, (node, ep)) if ep.scheme == "rtu" else (node, ep)
                if line != ep:
                    r.bad("endpoint", f"{ep} and node {first}'s {line} share {ep.device} with "
                                      "different line settings")
        if profile not in PROFILES:
            r.bad("profile", f"{profile!r} is not one of {', '.join(PROFILES)}")
        if table_name not in TABLES:
            r.bad("table", f"{table_name!r} is not one of {', '.join(TABLES)}")
        if node in seen:
            r.bad("node", f"node {node} is configured twice")
        if node >= 0:
            seen.add(node)
            nodes.append(NodeSettings(node, endpoint, unit, profile, timeout, retries, table_name,
                                      backoff, backoff_max, key=f"nodes[{i}]"))
    return nodes


def _seconds(r: _Reader, key: str, default: float, lo: float, hi: float) -> float:
    value = r.get(key, float, default)
    if not lo <= value <= hi:
        r.bad(key, f"{value:g} s is outside {lo:g}-{hi:g} s")
        return default
    return value


def _simulators(problems: list[str], fname: str, items: list[Any], base: Path) -> list[SimulatorSettings]:
    sims: list[SimulatorSettings] = []
    for _i, r in _array_tables(problems, fname, items, "simulators"):
        node = r.number("node", -1, 0, 255, required=True)
        program = r.path("program", base, required=True)
        symbols = r.path("symbols", base)
        host = r.get("host", str, "127.0.0.1")
        port = r.number("port", 0, 0, 65535)
        unit = r.number("unit", 1, 0, 247)
        tick = r.number("tick", 100, 10, 60_000)
        r.finish()
        if node >= 0 and program is not None:
            sims.append(SimulatorSettings(node, program, symbols, host, port, unit, tick))
    return sims


def _users(problems: list[str], fname: str, table: dict[str, Any]) -> tuple[str, ...]:
    r = _Reader(problems, fname, table, "operator.")
    users = r.get("users", list, ["operator"])
    r.finish()
    if not users or not all(isinstance(u, str) and u.strip() for u in users):
        r.bad("users", "expected a non-empty list of user names")
        return ("operator",)
    return tuple(users)


def _ports_in_common(problems: list[str], fname: str, server: ModbusServerSettings,
                     sims: list[SimulatorSettings]) -> None:
    """Fixed ports that the station itself would listen on twice (port 0 is always a free one)."""
    taken: dict[tuple[str, int], str] = {}
    if server.enabled and server.port:
        taken[server.host, server.port] = "modbus_server.port"
    for i, sim in enumerate(sims):
        if sim.port:
            first = taken.setdefault((sim.host, sim.port), f"simulators[{i}].port")
            if first != f"simulators[{i}].port":
                problems.append(f"{fname}: simulators[{i}].port: {sim.host}:{sim.port} is also {first}")


def _with_simulated_nodes(problems: list[str], fname: str, nodes: list[NodeSettings],
                          sims: list[SimulatorSettings]) -> list[NodeSettings]:
    """A simulator serves its node: its endpoint is the simulator's address (filled at start if port 0)."""
    by_node = {n.node: n for n in nodes}
    for i, sim in enumerate(sims):
        if sum(s.node == sim.node for s in sims) > 1:
            problems.append(f"{fname}: simulators[{i}].node: node {sim.node} is simulated twice")
        node = by_node.get(sim.node)
        endpoint = f"tcp://{sim.host}:{sim.port}" if sim.port else ""
        if node is None:
            by_node[sim.node] = NodeSettings(sim.node, endpoint, unit=sim.unit, key=f"simulators[{i}]")
        elif node.endpoint not in ("", BAD_ENDPOINT) and sim.port and node.endpoint != endpoint:
            problems.append(f"{fname}: simulators[{i}].port: node {sim.node} has endpoint "
                            f"{node.endpoint}, but its simulator listens on {endpoint}")
    for n in by_node.values():
        if not n.endpoint and not any(s.node == n.node for s in sims):
            problems.append(f"{fname}: nodes: node {n.node} has no endpoint and no simulator")
    return sorted((replace(n, endpoint="") if n.endpoint == BAD_ENDPOINT else n for n in by_node.values()),
                  key=lambda n: n.node)
