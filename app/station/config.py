"""The station file `station.toml`: the manual's FregatServer settings plus what the PC needs.

Keys keep the manual's spelling (NetPlcLoad, NetPlcProgram, HMIload, NetSyncTime). Paths are
relative to the station file so that a station folder can be copied to another machine and run
there. Every problem is collected and reported together as `station.toml: key: problem`, so an
engineer fixes a broken station in one pass instead of one error per start.
"""

from __future__ import annotations

import sys
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from app.authority.policy import OPERATOR, ROLES
from app.scada.tag import TagType
from app.scada.words import Words, words
from netplc.address import fmt_octal, is_data_byte, is_io_bit, parse_hmi_bit, parse_octal
from netplc.exchange import NODE_DEFAULTS, NodeConfig, shared_problems
from netplc.modbus import Endpoint, default_stopbits, line_problems
from netplc.problems import Problems
from netplc.textfile import TextFileError, file_problem, read_text, resolve
from registrar.plant.url import is_url, url_problem

STATION_FILE = "station.toml"
DEMO_STATION = Path(__file__).resolve().parent / "demo"  # the built-in demo, package data
# What Modbus clients may write when station.toml names nothing: the internal bits and the first
# data bank, but not the special bits 03700-03777 (03770 stops NetPlc, 03771/03772 are the error
# flags, 03773/03774 the time base): a range that names them explicitly still opens them.
DEFAULT_WRITABLE = ((0o2000, 0o3677), (0o4000, 0o7777))
TRANSPORTS = ("tcp", "rtu")  # [modbus_server] transport
# the [modbus_server] keys that only one transport has
_SERVER_KEYS = {"tcp": ("host", "max_connections", "idle_timeout", "max_inflight", "max_per_peer"),
                "rtu": ("baudrate", "parity", "stopbits")}


class ConfigError(Problems):
    """Every problem of a station file, each naming the key."""


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
    unit: int | None = None  # the unit id answered; None: every unit id (TCP only)
    max_connections: int = 16  # the next connection is closed (one journal line a minute)
    idle_timeout: float = 60.0  # s without a whole request before a connection is closed
    max_inflight: int = 32  # answers (of the longest size) a connection may leave unread or waiting
    max_per_peer: int = 4  # connections from one address; the next one is closed
    role: str = OPERATOR  # what Modbus clients may do (they have no users): viewer = read-only
    serial: Endpoint | None = None  # transport = "rtu": the serial port and its line; None: TCP

    @property
    def transport(self) -> str:
        return "tcp" if self.serial is None else "rtu"


@dataclass(frozen=True)
class OperatorSettings:
    """Who is at the workstation before anyone logs in, and when a user is logged out again.
    The users themselves are in users.json (app/authority/users.py), managed by `main.py users`."""

    default_user: str = ""  # a viewer shown as logged in while nobody is; "": logged out
    idle_logout: int = 0  # seconds without input before a user is logged out; 0: never
    fullscreen: bool = False  # the operator mode: the workstation opens full screen, no window chrome


LANGUAGES = ("ru", "en")


@dataclass(frozen=True)
class OpcUaSettings:
    """[opcua]: the OPC UA server (app/publish/opcua.py)."""

    enabled: bool = False
    endpoint: str = "opc.tcp://127.0.0.1:4840/netplc/"
    writable: tuple[str, ...] = ()  # tag names or patterns a client may write
    # host names and addresses the server's certificate names besides the host's own (clients
    # check that the name they connect to is one of them): a DNS alias, a NAT address
    certificate_names: tuple[str, ...] = ()
    max_consoles: int = 16  # client sessions at once (consoles, monitors, other clients); more are refused


@dataclass(frozen=True)
class MqttSettings:
    """[mqtt]: the Sparkplug B publisher (app/publish/mqtt.py)."""

    enabled: bool = False
    broker: str = "mqtt://127.0.0.1:1883"
    ca_file: Path | None = None  # for mqtts://
    group_id: str = "NetPlc"
    edge_node_id: str = ""  # empty: the station name
    username: str = ""
    password: str = ""
    deadband: tuple[tuple[str, float], ...] = ()  # (tag type, absolute deadband)
    publish_period: int = 0  # ms between NDATA messages at least; 0: every tick
    writable: tuple[str, ...] = ()
    buffer: int = 10_000  # NDATA/DDATA messages kept while no Sparkplug session is up
    # the Primary Host Application's id: births only while its STATE is online; "": none awaited
    primary_host: str = ""
    role: str = OPERATOR  # what NCMD/DCMD may do (they name no user): viewer = read-only


LETTERS = ("A", "B")  # HSBNumPLC of seed 000: 1 = A, 0 = B
FAILOVER_MAX_MS = 1000  # a takeover within about a second: failover_after is bounded by it
# failover_after's default, in ms: a loaded PC (load average 14 on 2 cores) stalls a scan or the
# pair link's thread by a tenth of a second and more, which a few ticks of silence took for a dead
# primary; half a second keeps a takeover within the second
FAILOVER_DEFAULT_MS = 500


@dataclass(frozen=True)
class RedundancySettings:
    """[redundancy]: this station as one of a hot-standby pair (app/station/pair.py)."""

    letter: str  # "A" or "B": A wins when both start together
    partner: str  # HOST:PORT of the partner's pair link
    listen: str = "127.0.0.1:0"  # HOST:PORT of this station's pair link (0: a free port, tests)
    failover_after: int = 3  # NetSyncTime ticks of silence from the primary before a takeover
    # (loaded: the ticks of FAILOVER_DEFAULT_MS unless station.toml says)
    arbiter: str = "none"  # "none", or the plant archive's postgresql:// URL (a lease)

    @property
    def listen_address(self) -> tuple[str, int]:
        return split_address(self.listen)

    @property
    def partner_address(self) -> tuple[str, int]:
        return split_address(self.partner)


def split_address(text: str) -> tuple[str, int]:
    """HOST:PORT as (host, port); ValueError when it is not one."""
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 <= int(port) <= 65535:
        raise ValueError(f"{text!r} is not HOST:PORT")
    return host.strip("[]"), int(port)


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
    nodes: tuple[NodeConfig, ...] = ()
    simulators: tuple[SimulatorSettings, ...] = ()
    operator: OperatorSettings = OperatorSettings()
    Language: str = ""  # "ru" or "en"; "" follows the system locale
    Tags: Path | None = None  # tags.csv: tags and their alarms (app/scada/)
    allow_outside: bool = False  # may station paths (and form images) leave the station folder?
    RetainForces: bool = False  # forces survive a restart (netplc/forcing.py); off: a restart unforces
    plant_archive: str | None = None  # `Archive` given as a postgresql:// URL: forwarded there
    plant_keep_days: int = 0  # days the plant archive keeps (for every station in it); 0: all
    alarm_sound: bool = True  # a new alarm of priority 1-2 sounds until acknowledged or silenced
    alarm_sounds: tuple[Path | None, Path | None] = (None, None)  # priority 1, 2; None: the shipped WAV
    alarm_horn: int | None = None  # HMI bit set while an alarm sounds (app/scada/horn.py)
    opcua: OpcUaSettings = OpcUaSettings()
    mqtt: MqttSettings = MqttSettings()
    redundancy: RedundancySettings | None = None  # None: a station on its own

    @property
    def folder(self) -> Path:
        return self.path.parent

    @property
    def forces_file(self) -> Path:
        """Where the forces are kept across a restart when RetainForces is true: beside Retain."""
        return self.Retain.with_name(self.Retain.stem + ".forces.json")

    @property
    def tick(self) -> float:
        return self.NetSyncTime / 1000.0


@dataclass(frozen=True)
class Key:
    """One station.toml setting as the parser reads it (its kind, default and bounds) and as the
    manual's reference prints it (docs/gen_reference.py): one table, so the two cannot differ. A
    key the parser reads that is not here is a KeyError at every load."""

    name: str
    kind: type | tuple[type, ...]
    default: Any
    meaning: str
    bounds: tuple[float, float] | None = None  # of a number
    said: str = ""  # the default in words where it is settled at load (the folder's name...)


def _keys(*keys: Key) -> dict[str, Key]:
    return {k.name: k for k in keys}


_SERVER, _OPCUA = ModbusServerSettings(), OpcUaSettings()
_MQTT, _OPERATOR = MqttSettings(), OperatorSettings()
# what each node setting means; its kind and default are NodeConfig's own (netplc/exchange.py)
_NODE_MEANINGS = {
    "name": "what the station calls the node (its Sparkplug device id); empty: Node<n>",
    "endpoint": "`tcp://host:port` or `rtu:///dev/ttyS0?baudrate=19200&parity=E` (even parity by default); "
                "empty: its simulator's",
    "unit": "Modbus unit id: 0-255 over TCP, 1-247 over RTU",
    "profile": "`cpu165` (a NetPlc node) or `modbus` (any Modbus device)",
    "timeout": "seconds per attempt (0.01-60)",
    "retries": "further attempts (0-10) before the link is down",
    "table": "profile `modbus`: `holding`, `input`, `coils` or `discrete`",
    "backoff": "seconds before the first reconnect after the link went down",
    "backoff_max": "the reconnect delay doubles up to this (backoff <= backoff_max)",
}
# The station.toml keys by table: "" is the top level, the others are its [tables] and
# [[arrays of tables]].
KEYS: dict[str, dict[str, Key]] = {
    "": _keys(
        Key("name", str, "", "the station's name (journal, MQTT edge node, window title)",
            said="the station folder's name"),
        Key("NetPlcLoad", bool, True, "run the NetPlc program"),
        Key("NetPlcProgram", str, None, "the STL program (required when NetPlcLoad is true)"),
        Key("Symbols", str, None, "symbols.csv: name,address,comment for the program and the forms"),
        Key("HMIload", str, None, "the folder of `.hmi` forms, each opens as a tab"),
        Key("NetSyncTime", int, 100, "the tick and scan period, ms", (10, 60_000)),
        Key("Archive", str, "archive/journal.sqlite",
            "the journal (SQLite); a `postgresql://` URL forwards it to a plant archive, the local "
            "journal staying at the default path"),
        Key("Messages", str, None, "messages.csv: number,group,type,text for NMSG"),
        Key("keep_days", int, 0, "days the local archive keeps; 0: every day", (0, 36_500)),
        Key("plant_keep_days", int, 0, "days the plant archive keeps, for every station in it; 0: all",
            (0, 36_500)),
        Key("Retain", str, None, "the retentive memory's save", said="retain.bin beside the Archive"),
        Key("Tags", str, None, "tags.csv: the tags, their conversion and alarms"),
        Key("RetainForces", bool, False, "forces survive a restart (`<Retain>.forces.json`)"),
        Key("alarm_sound", bool, True, "a new alarm of priority 1-2 sounds until acknowledged or silenced"),
        Key("alarm_sound_p1", str, None, "the sound file (WAV) of priority 1, played in a loop until "
            "acknowledged or silenced", said="the shipped one"),
        Key("alarm_sound_p2", str, None, "the sound file (WAV) of priority 2", said="the shipped one"),
        Key("alarm_horn", str, None, "an HMI bit (`03600`, `040060`) the station sets to 1 while an alarm "
            "of priority 1-2 sounds and to 0 once acknowledged or silenced; the program only reads it, "
            "to drive a real horn", said="none"),
        Key("allow_outside", bool, False, "station paths (and form images) may leave the station folder"),
        Key("Language", str, "", f"the console's language: {', '.join(LANGUAGES)}",
            said="the system locale"),
        Key("modbus_server", dict, {}, "the Modbus server's table"),
        Key("nodes", list, [], "the exchange's remote nodes"),
        Key("simulators", list, [], "embedded simulated CPU-165 nodes"),
        Key("operator", dict, {}, "who is at the workstation"),
        Key("opcua", dict, {}, "the OPC UA server's table"),
        Key("mqtt", dict, {}, "the MQTT Sparkplug B publisher's table"),
        Key("redundancy", dict, None, "the hot-standby pair's table; none: a single station"),
    ),
    "modbus_server": _keys(
        Key("enabled", bool, _SERVER.enabled, "serve NetPlc memory over Modbus"),
        Key("transport", str, "tcp", f"one of {', '.join(TRANSPORTS)}"),
        Key("host", str, _SERVER.host, "tcp: the address it listens on"),
        Key("port", (int, str), _SERVER.port,
            'tcp: the port it listens on; rtu: the serial port ("/dev/ttyUSB0", "COM3"), required',
            (0, 65535)),
        Key("writable", list, None, "octal ranges clients may write, `[[\"04000\", \"04777\"], ...]`",
            said="02000-03677 and 04000-07777 (not the special bits 03700-03777)"),
        Key("unit", int, None, "the only unit id answered", (1, 247), said="tcp: every unit; rtu: 1"),
        Key("role", str, _SERVER.role, f"the role its clients act with: {', '.join(ROLES)}"),
        Key("max_connections", int, _SERVER.max_connections, "tcp: connections at once", (1, 1000)),
        Key("idle_timeout", float, _SERVER.idle_timeout,
            "tcp: seconds without a whole request before a connection is closed", (0.1, 86_400.0)),
        Key("max_inflight", int, _SERVER.max_inflight,
            "tcp: answers a connection may leave unread before it is no longer read", (1, 10_000)),
        Key("max_per_peer", int, _SERVER.max_per_peer, "tcp: connections from one address", (1, 1000)),
        Key("baudrate", int, 19200, "rtu: the line's rate"),
        Key("parity", str, "E", "rtu: N, E or O"),
        Key("stopbits", int, 1, "rtu: 1 or 2", said="1; 2 with parity N"),
    ),
    "nodes": _keys(
        Key("node", int, None, "the node number, 0-255 (required)"),
        *(Key(k, float if isinstance(v, float) else type(v), v, _NODE_MEANINGS[k])
          for k, v in NODE_DEFAULTS.items()),
    ),
    "simulators": _keys(
        Key("node", int, -1, "the node it simulates (required)", (0, 255)),
        Key("program", str, None, "its STL program (required)"),
        Key("symbols", str, None, "its symbols.csv"),
        Key("host", str, "127.0.0.1", "the address it listens on"),
        Key("port", int, 0, "the port it listens on; 0: a free one, filled into the node", (0, 65535)),
        Key("unit", int, 1, "its Modbus unit id", (0, 247)),
        Key("tick", int, 100, "ms per scan", (10, 60_000)),
    ),
    "redundancy": _keys(
        Key("letter", str, "A", "this station's letter in the hot-standby pair: A or B (required)"),
        Key("partner", str, "", "the partner's pair link, `host:port` (required)"),
        Key("listen", str, "127.0.0.1:0", "this station's pair link, `host:port`"),
        Key("failover_after", int, 3, "NetSyncTime ticks of the primary's silence before the standby "
            "takes over, within about a second", (2, 6_000),
            said="the ticks of 0.5 s: 3 at least, 1 s at most"),
        Key("arbiter", str, "none", "`postgresql://...` (a lease in the plant archive's PostgreSQL) or "
            "`none` (a cut pair link makes both primary)"),
    ),
    "operator": _keys(
        Key("default_user", str, _OPERATOR.default_user,
            "a user of role viewer shown while nobody is logged in; empty: logged out"),
        Key("idle_logout", int, _OPERATOR.idle_logout,
            "seconds without input before the user is logged out; 0: never", (0, 86_400)),
        Key("fullscreen", bool, _OPERATOR.fullscreen,
            "the operator mode: the workstation opens full screen, with no window chrome (also "
            "`main.py STATION --fullscreen`)"),
    ),
    "opcua": _keys(
        Key("enabled", bool, _OPCUA.enabled, "run the OPC UA server"),
        Key("endpoint", str, _OPCUA.endpoint, "its `opc.tcp://` address"),
        Key("writable", list, [], "tag names or patterns (`TEMP_*`) clients may write"),
        Key("certificate_names", list, [], "names and addresses its certificate holds besides the host's"),
        Key("max_consoles", int, _OPCUA.max_consoles,
            "client sessions at once (consoles, monitors, other clients); one more is refused", (1, 1000)),
    ),
    "mqtt": _keys(
        Key("enabled", bool, _MQTT.enabled, "run the Sparkplug B publisher"),
        Key("broker", str, _MQTT.broker, "`mqtt://host:1883` or `mqtts://host:8883`"),
        Key("ca_file", str, None, "the CA certificate for mqtts://"),
        Key("group_id", str, _MQTT.group_id, "the Sparkplug group id"),
        Key("edge_node_id", str, _MQTT.edge_node_id, "the Sparkplug edge node id", said="the station name"),
        Key("username", str, _MQTT.username, "for the broker"),
        Key("password", str, _MQTT.password, "for the broker"),
        Key("deadband", dict, {}, "per tag type, in physical units: `{ float32 = 0.5, word = 2 }`"),
        Key("publish_period", int, _MQTT.publish_period, "ms between NDATA messages at least; 0: every tick",
            (0, 3_600_000)),
        Key("writable", list, [], "tag names or patterns an NCMD or a DCMD may write"),
        Key("buffer", int, _MQTT.buffer, "NDATA/DDATA messages kept while no Sparkplug session is up",
            (0, 10_000_000)),
        Key("primary_host", str, _MQTT.primary_host,
            "the Primary Host Application's id: births only while its STATE is online; empty: none"),
        Key("role", str, _MQTT.role, f"what NCMD/DCMD may do (they name no user): {', '.join(ROLES)}"),
    ),
}
_DECLARED: Any = object()  # get()'s default: the one KEYS declares


def station_file(path: str | Path) -> Path:
    """A station is named by its folder or by its station.toml."""
    p = Path(path)
    return p / STATION_FILE if p.is_dir() else p


class Found(list[str]):
    """The problems of one station.toml, and the words its readers say them in: the file's
    `Language` (app/scada/words.py), read before anything else is; each names its key as it is."""

    def __init__(self, say: Words) -> None:
        super().__init__()
        self.say = say


class _Reader:
    """Typed access to one TOML table that records problems instead of raising at the first."""

    def __init__(self, problems: Found, fname: str, table: dict[str, Any], section: str = "",
                 prefix: str | None = None, allow_outside: bool = False) -> None:
        self.problems = problems
        self.say = problems.say
        self.fname = fname
        self.table = table
        self.keys = KEYS[section]
        self.prefix = f"{section}." if prefix is None and section else prefix or ""
        self.allow_outside = allow_outside  # may paths leave the station folder?
        self.known: set[str] = set()

    def bad(self, key: str, problem: object) -> None:
        """`problem`: text, or a phrase of the catalogue (a node's own checks, netplc/words.py)."""
        self.problems.append(f"{self.fname}: {self.prefix}{key}: {self.say.say(problem)}")

    def get(self, key: str, default: Any = _DECLARED, required: bool = False,
            kind: type | tuple[type, ...] | None = None) -> Any:
        """The key's value, of the kind KEYS declares (or `kind`, of a key that takes several)."""
        declared = self.keys[key]
        kind = declared.kind if kind is None else kind
        default = declared.default if default is _DECLARED else default
        self.known.add(key)
        if key not in self.table:
            if required:
                self.bad(key, self.say("cfg missing"))
            return default
        value = self.table[key]
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            if abs(value) > 1e300:  # float() would overflow
                self.bad(key, self.say("cfg too large", n=len(str(abs(value)))))
                return default
            return float(value)
        if (isinstance(value, bool) and kind is not bool) or not isinstance(value, kind):
            self.bad(key, self.say("cfg expected", kind=_kind_name(kind, self.say), value=value))
            return default
        return value

    def number(self, key: str, default: Any = _DECLARED, required: bool = False) -> Any:
        """An integer within the bounds KEYS declares."""
        declared = self.keys[key]
        default = declared.default if default is _DECLARED else default
        value = self.get(key, default, required, kind=int)
        lo, hi = declared.bounds or (value, value)
        if value is not None and not lo <= value <= hi:
            self.bad(key, self.say("cfg outside", value=value, lo=lo, hi=hi))
            return default
        return value

    def path(self, key: str, base: Path, required: bool = False) -> Path | None:
        value = self.get(key, required=required)
        if value is None:
            return None
        if not value.strip():
            self.bad(key, self.say("cfg empty path"))
            return None
        if "\0" in value:
            self.bad(key, self.say("cfg nul"))
            return None
        try:
            path = resolve(base / value)
        except TextFileError as e:
            self.bad(key, e.said(self.say))
            return None
        if not self.allow_outside and not path.is_relative_to(base):
            self.bad(key, self.say("cfg outside folder", path=path, base=base))
            return None
        return path

    def finish(self) -> None:
        for key in self.table:
            if key not in self.known:
                self.bad(key, self.say("cfg unknown"))


def _kind_name(kind: type | tuple[type, ...], say: Words) -> str:
    kinds = kind if isinstance(kind, tuple) else (kind,)
    return say("cfg or").join(say(f"kind {k.__name__}") if say.knows(f"kind {k.__name__}") else k.__name__
                             for k in kinds)


def load_station(path: str | Path) -> Station:
    """Read and validate a station; ConfigError lists every problem."""
    station, problems = read_station(path)
    if problems or station is None:
        raise ConfigError(problems)
    return station


def archive_owner(archive: str | Path) -> tuple[Station | None, list[str]]:
    """The station whose station.toml, in the archive's folder or one above it, names `archive` as
    its Archive (what `archive migrate` forwards it as), and that file's problems; with no such
    station, the problems of the station files on the way that could not be read."""
    target = Path(archive).resolve()
    unread: list[str] = []
    for folder in target.parents:
        if not (folder / STATION_FILE).is_file():
            continue
        station, problems = read_station(folder)
        if station is None:
            unread += problems
        elif station.Archive.resolve() == target:
            return station, problems
    return None, unread


def read_station(path: str | Path) -> tuple[Station | None, list[str]]:
    """The station as far as it can be read, and its problems (for `check`, which goes on to
    check the program and forms even when a setting is wrong). Files that do not exist are None
    in the returned station; None instead of a station when the file is not TOML at all."""
    file = station_file(path)
    fname = str(file)
    say = words()  # the file's language is not known until it is read
    if not (file.exists() or file.is_symlink()):  # a link that leads nowhere is named by read_text
        return None, [say("cfg no file", file=fname)]
    try:
        data = tomllib.loads(read_text(file, "read station"))
    except TextFileError as e:
        return None, [e.said(say)]
    except tomllib.TOMLDecodeError as e:
        return None, [say("cfg not toml", file=fname, error=e)]
    except ValueError:  # from int(), which tomllib calls without saying where
        return None, [say("cfg toml digits", file=fname, n=sys.get_int_max_str_digits())]
    except RecursionError:
        return None, [say("cfg toml deep", file=fname)]
    said = data.get("Language")
    problems = Found(words(said if said in LANGUAGES else ""))
    base = file.parent.resolve()
    top = _Reader(problems, fname, data)
    top.allow_outside = bool(top.get("allow_outside"))
    name = top.get("name")
    load = top.get("NetPlcLoad")
    program = top.path("NetPlcProgram", base, required=bool(load))
    symbols = top.path("Symbols", base)
    hmi = top.path("HMIload", base)
    sync = top.number("NetSyncTime")
    plant = _plant_archive(top)  # marks a URL `Archive` known, valid or not
    archive = None if "Archive" in top.known else top.path("Archive", base)
    messages = top.path("Messages", base)
    keep_days = top.number("keep_days")
    plant_keep_days = top.number("plant_keep_days")
    retain = top.path("Retain", base)
    tags = top.path("Tags", base)
    retain_forces = top.get("RetainForces")
    alarm_sound = bool(top.get("alarm_sound"))
    alarm_sounds = (top.path("alarm_sound_p1", base), top.path("alarm_sound_p2", base))
    for key, sound in zip(("alarm_sound_p1", "alarm_sound_p2"), alarm_sounds, strict=True):
        if sound is not None and not sound.is_file():
            top.bad(key, top.say("cfg not a file", path=sound))
    alarm_horn = _horn_bit(top)
    server = _modbus_server(problems, fname, top.get("modbus_server"))
    nodes = _nodes(problems, fname, top.get("nodes"))
    simulators = _simulators(problems, fname, top.get("simulators"), base, top.allow_outside)
    operator = _operator(problems, fname, top.get("operator"))
    language = top.get("Language")
    if language and language not in LANGUAGES:
        top.bad("Language", top.say("cfg not one of", value=language, names=", ".join(LANGUAGES)))
        language = ""
    opcua = _opcua(problems, fname, top.get("opcua"))
    mqtt = _mqtt(problems, fname, top.get("mqtt"), base, top.allow_outside)
    redundancy = _redundancy(problems, fname, top.get("redundancy"), sync)
    top.finish()
    nodes = _with_simulated_nodes(problems, fname, nodes, simulators)
    _ports_in_common(problems, fname, server, simulators, nodes)
    program, symbols, hmi, messages, tags = (
        _existing(top, key, p, must_be_dir)
        for key, p, must_be_dir in (("NetPlcProgram", program, False), ("Symbols", symbols, False),
                                    ("HMIload", hmi, True), ("Messages", messages, False),
                                    ("Tags", tags, False)))
    runnable: list[SimulatorSettings] = []
    for i, sim in enumerate(simulators):
        missing = [(key, p, why) for key, p in (("program", sim.program), ("symbols", sim.symbols))
                   if p is not None and (why := file_problem(p))]
        for key, p, why in missing:
            problems.append(f"{fname}: simulators[{i}].{key}: file {p} {why}")
        if not missing:
            runnable.append(sim)
    archive = archive or base / "archive" / "journal.sqlite"
    retain = retain or archive.with_name("retain.bin")
    _outputs_apart(top, file.resolve(), archive, retain, program, symbols, messages, tags, hmi, simulators)
    station = Station(
        path=file.resolve(), name=name or base.name, NetPlcLoad=bool(load), NetPlcProgram=program,
        Symbols=symbols, HMIload=hmi, NetSyncTime=sync, Archive=archive, Messages=messages,
        keep_days=keep_days, Retain=retain, modbus_server=server,
        nodes=tuple(nodes), simulators=tuple(runnable), operator=operator, Language=language, Tags=tags,
        allow_outside=top.allow_outside, RetainForces=bool(retain_forces), plant_archive=plant,
        plant_keep_days=plant_keep_days,
        alarm_sound=alarm_sound, alarm_sounds=alarm_sounds, alarm_horn=alarm_horn, opcua=opcua,
        mqtt=mqtt, redundancy=redundancy,
    )
    return station, problems


def _outputs_apart(r: _Reader, file: Path, archive: Path, retain: Path, program: Path | None,
                   symbols: Path | None, messages: Path | None, tags: Path | None, hmi: Path | None,
                   sims: list[SimulatorSettings]) -> None:
    """The station writes Archive and Retain: neither may be one of its input files (the first save
    would overwrite the program or station.toml), a form, or the other one."""
    inputs = {p: key for key, p in (("station.toml", file), ("NetPlcProgram", program), ("Symbols", symbols),
                                    ("Messages", messages), ("Tags", tags)) if p is not None}
    for i, sim in enumerate(sims):
        inputs.update({p: f"simulators[{i}].{key}" for key, p in (("program", sim.program),
                                                                  ("symbols", sim.symbols)) if p})
    for key, path in (("Archive", archive), ("Retain", retain)):
        what = inputs.get(path)
        if what is None and hmi is not None and path.parent == hmi and path.suffix == ".hmi":
            what = "a form of HMIload"
        if what is not None:
            r.bad(key, f"{path} is a station input ({what}): writing there would overwrite it")
    if retain == archive:
        r.bad("Retain", f"{retain} is the Archive as well")


def _plant_archive(top: _Reader) -> str | None:
    """`Archive` as a PostgreSQL URL: the station still writes its default local archive first."""
    value = top.table.get("Archive")
    if not is_url(value):
        return None

    top.known.add("Archive")
    problem = url_problem(value)
    if problem:
        top.bad("Archive", problem)
        return None
    return value


def _existing(r: _Reader, key: str, path: Path | None, must_be_dir: bool) -> Path | None:
    """`path` if it is an existing file (folder); else None and the problem, which says what is
    there instead (a folder, a FIFO, a device) when something is."""
    why = file_problem(path, must_be_dir) if path is not None else None
    if why is not None:
        r.bad(key, f"{'folder' if must_be_dir else 'file'} {path} {why}")
        return None
    return path


def _role(r: _Reader) -> str:
    """`role`: what the clients of a protocol without users may do (viewer: read-only)."""
    role = r.get("role")
    if role not in ROLES:
        r.bad("role", r.say("cfg not one of", value=role, names=", ".join(ROLES)))
        return OPERATOR
    return role


def _modbus_server(problems: Found, fname: str, table: dict[str, Any]) -> ModbusServerSettings:
    r = _Reader(problems, fname, table, "modbus_server")
    d = ModbusServerSettings()
    enabled = r.get("enabled")
    transport = r.get("transport")
    if transport not in TRANSPORTS:
        r.bad("transport", r.say("cfg not one of", value=transport, names=", ".join(TRANSPORTS)))
        transport = "tcp"
    rtu = transport == "rtu"
    for key in _SERVER_KEYS["tcp" if rtu else "rtu"]:
        if key in table:
            r.known.add(key)
            r.bad(key, f'applies to transport = "{"tcp" if rtu else "rtu"}" only')
    ranges = r.get("writable")
    unit = r.number("unit", 1 if rtu else None)  # a slave on a shared line has one address
    if rtu:
        server = replace(d, port=0, serial=_serial_port(r))  # port 0: no TCP port of its own
    else:
        server = ModbusServerSettings(
            host=r.get("host"), port=r.number("port"),
            max_connections=r.number("max_connections"),
            idle_timeout=_seconds(r, "idle_timeout"),
            max_inflight=r.number("max_inflight"),
            max_per_peer=r.number("max_per_peer"))
    role = _role(r)
    r.finish()
    writable = DEFAULT_WRITABLE if ranges is None else _ranges(r, ranges)
    return replace(server, enabled=enabled, writable=writable, unit=unit, role=role)


def _serial_port(r: _Reader) -> Endpoint | None:
    """transport = "rtu": `port` names the serial port, and its line settings: 19200 baud, 8 data
    bits, even parity, as the Modbus over Serial Line specification (2.5.1) makes the default;
    one stop bit, or two without parity, as it requires."""
    device = r.get("port", None, kind=str)
    if device is None:
        if "port" not in r.table:
            r.bad("port", 'missing: transport = "rtu" answers on a serial port, '
                          'such as "/dev/ttyUSB0" or "COM3"')
        return None
    if not device.strip() or "\0" in device:
        r.bad("port", f"{device!r} is not a serial port")
        return None
    baudrate = r.get("baudrate")
    parity = r.get("parity").upper()
    stopbits = r.get("stopbits", default_stopbits(parity))
    serial = Endpoint("rtu", device=device, baudrate=baudrate, parity=parity, stopbits=stopbits)
    found = line_problems(serial)
    for key, text in found:
        r.bad(key, text)
    return None if found else serial


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


def _array_tables(problems: Found, fname: str, items: list[Any], key: str) -> list[tuple[int, _Reader]]:
    """A reader for each table of an array of tables ([[nodes]], [[simulators]]); an item that is
    not a table is a problem naming its index."""
    readers = []
    for i, table in enumerate(items):
        if isinstance(table, dict):
            readers.append((i, _Reader(problems, fname, table, key, f"{key}[{i}].")))
        else:
            problems.append(f"{fname}: {key}[{i}]: expected a [[{key}]] table")
    return readers


def _nodes(problems: Found, fname: str, items: list[Any]) -> list[NodeConfig]:
    """The [[nodes]] tables as NodeConfig, with every problem named by its key: this reads the
    TOML types, the model checks the values (netplc/exchange.py `node_problems`), so a node
    station.toml accepts is one the exchange runs."""
    nodes: list[NodeConfig] = []
    readers: dict[str, _Reader] = {}  # by the node's key, nodes[i]
    for i, r in _array_tables(problems, fname, items, "nodes"):
        settings = {"node": r.get("node", required=True)}
        for key in NODE_DEFAULTS:
            value = r.get(key, None)
            if value is not None:
                settings[key] = value
        r.finish()
        if settings["node"] is None:
            continue
        node, found = NodeConfig.settled(settings, key=f"nodes[{i}]")
        for key, text in found:
            r.bad(key, text)
        if node is not None:
            nodes.append(node)
            readers[node.key] = r
    for node, (key, text) in shared_problems(nodes):
        readers[node.key].bad(key, text)
    return nodes


def _seconds(r: _Reader, key: str) -> float:
    default = r.keys[key].default
    lo, hi = r.keys[key].bounds or (default, default)
    value = r.get(key)
    if not lo <= value <= hi:
        r.bad(key, f"{value:g} s is outside {lo:g}-{hi:g} s")
        return default
    return value


def _simulators(problems: Found, fname: str, items: list[Any], base: Path,
                allow_outside: bool) -> list[SimulatorSettings]:
    sims: list[SimulatorSettings] = []
    for _i, r in _array_tables(problems, fname, items, "simulators"):
        r.allow_outside = allow_outside
        node = r.number("node", required=True)
        program = r.path("program", base, required=True)
        symbols = r.path("symbols", base)
        host = r.get("host")
        port = r.number("port")
        unit = r.number("unit")
        tick = r.number("tick")
        r.finish()
        if node >= 0 and program is not None:
            sims.append(SimulatorSettings(node, program, symbols, host, port, unit, tick))
    return sims


def _horn_bit(top: _Reader) -> int | None:
    """`alarm_horn`: an HMI bit address in octal, as the forms write them."""
    text = top.get("alarm_horn")
    if text is None:
        return None
    try:
        return parse_hmi_bit(text).hmi
    except ValueError as e:
        top.bad("alarm_horn", f"{text!r} is not an HMI bit address: {e}")
        return None


def _operator(problems: Found, fname: str, table: dict[str, Any]) -> OperatorSettings:
    r = _Reader(problems, fname, table, "operator")
    if "users" in table:
        r.known.add("users")
        r.bad("users", "users are kept in users.json with their roles and passwords now: "
                       "`main.py users add NAME --role viewer|operator|engineer|admin`")
    default = r.get("default_user")
    idle = r.number("idle_logout")
    fullscreen = r.get("fullscreen")
    r.finish()
    return OperatorSettings(default.strip(), idle, bool(fullscreen))


def _ports_in_common(problems: list[str], fname: str, server: ModbusServerSettings,
                     sims: list[SimulatorSettings], nodes: list[NodeConfig]) -> None:
    """Fixed ports that the station itself would listen on twice (port 0 is always a free one), and
    a serial port it would answer on as a slave while its exchange polls nodes there as the master."""
    serial = server.serial if server.enabled else None
    for n in nodes:
        if serial is not None and n.parsed is not None and n.parsed.device == serial.device:
            problems.append(f"{fname}: modbus_server.port: {serial.device} is also the serial port of "
                            f"{n.key}.endpoint: the station cannot be the master and a slave on one line")
    taken: dict[tuple[str, int], str] = {}
    if server.enabled and server.port:
        taken[server.host, server.port] = "modbus_server.port"
    for i, sim in enumerate(sims):
        if sim.port:
            first = taken.setdefault((sim.host, sim.port), f"simulators[{i}].port")
            if first != f"simulators[{i}].port":
                problems.append(f"{fname}: simulators[{i}].port: {sim.host}:{sim.port} is also {first}")


def _with_simulated_nodes(problems: list[str], fname: str, nodes: list[NodeConfig],
                          sims: list[SimulatorSettings]) -> list[NodeConfig]:
    """A simulator serves its node: its endpoint is the simulator's address (filled at start if port 0)."""
    by_node = {n.node: n for n in nodes}
    for i, sim in enumerate(sims):
        if sum(s.node == sim.node for s in sims) > 1:
            problems.append(f"{fname}: simulators[{i}].node: node {sim.node} is simulated twice")
        node = by_node.get(sim.node)
        endpoint = f"tcp://{sim.host}:{sim.port}" if sim.port else ""
        if node is None:
            by_node[sim.node] = NodeConfig(sim.node, endpoint, unit=sim.unit, key=f"simulators[{i}]")
        elif node.endpoint and sim.port and node.endpoint != endpoint:
            problems.append(f"{fname}: simulators[{i}].port: node {sim.node} has endpoint "
                            f"{node.endpoint}, but its simulator listens on {endpoint}")
    for n in by_node.values():
        reported = any(p.startswith(f"{fname}: {n.key}.endpoint: ") for p in problems)
        if not n.endpoint and not reported and not any(s.node == n.node for s in sims):
            problems.append(f"{fname}: nodes: node {n.node} has no endpoint and no simulator")
    return sorted(by_node.values(), key=lambda n: n.node)


def _names(r: _Reader, key: str) -> tuple[str, ...]:
    """A list of tag names or patterns."""
    items = r.get(key)
    if not all(isinstance(x, str) and x.strip() for x in items):
        r.bad(key, "expected a list of tag names or patterns")
        return ()
    return tuple(items)


def _host_names(r: _Reader, key: str) -> tuple[str, ...]:
    """A list of DNS names (RFC 1123) and IP addresses."""
    import ipaddress
    import re

    label = re.compile(r"(?!-)[A-Za-z0-9-]{1,63}(?<!-)")
    names = []
    for item in r.get(key):
        if isinstance(item, str):
            try:
                names.append(str(ipaddress.ip_address(item)))
                continue
            except ValueError:
                if len(item) <= 253 and all(label.fullmatch(part) for part in item.split(".")):
                    names.append(item)
                    continue
        r.bad(key, f"{item!r} is not a host name or an IP address")
    return tuple(names)


def _opcua(problems: Found, fname: str, table: dict[str, Any]) -> OpcUaSettings:
    r = _Reader(problems, fname, table, "opcua")
    d = OpcUaSettings()
    enabled = r.get("enabled")
    endpoint = r.get("endpoint")
    writable = _names(r, "writable")
    certificate_names = _host_names(r, "certificate_names")
    max_consoles = r.number("max_consoles")
    r.finish()
    if not endpoint.startswith("opc.tcp://"):
        r.bad("endpoint", f"{endpoint!r} is not an opc.tcp:// address")
        endpoint = d.endpoint
    return OpcUaSettings(enabled, endpoint, writable, certificate_names, max_consoles)


def _mqtt(problems: Found, fname: str, table: dict[str, Any], base: Path,
          allow_outside: bool) -> MqttSettings:
    r = _Reader(problems, fname, table, "mqtt", allow_outside=allow_outside)
    d = MqttSettings()
    enabled = r.get("enabled")
    broker = r.get("broker")
    ca_file = r.path("ca_file", base)
    group = r.get("group_id")
    edge = r.get("edge_node_id")
    username = r.get("username")
    password = r.get("password")
    deadband = r.get("deadband")
    period = r.number("publish_period")
    writable = _names(r, "writable")
    buffer = r.number("buffer")
    primary = r.get("primary_host")
    role = _role(r)
    r.finish()
    if not broker.startswith(("mqtt://", "mqtts://")):
        r.bad("broker", f"{broker!r} is not an mqtt:// or mqtts:// address")
        broker = d.broker
    for key, value in (("group_id", group), ("edge_node_id", edge), ("primary_host", primary)):
        if any(c in value for c in "/+#"):
            r.bad(key, f"{value!r} may not hold '/', '+' or '#' (Sparkplug topic levels)")
    bands: list[tuple[str, float]] = []
    for kind, value in deadband.items():
        if kind not in {t.value for t in TagType}:
            r.bad(f"deadband.{kind}", f"not a tag type ({', '.join(t.value for t in TagType)})")
        elif isinstance(value, bool) or not isinstance(value, int | float) or value < 0:
            r.bad(f"deadband.{kind}", f"expected a number >= 0, got {value!r}")
        else:
            bands.append((kind, float(value)))
    return MqttSettings(enabled, broker, ca_file, group, edge, username, password, tuple(bands), period,
                        writable, buffer, primary, role)


def _redundancy(problems: Found, fname: str, table: dict[str, Any] | None,
                sync: int) -> RedundancySettings | None:
    """[redundancy], or None when the station has none. failover_after counts NetSyncTime ticks
    and is bounded so that a takeover comes within about a second (FAILOVER_MAX_MS)."""
    if table is None:
        return None
    r = _Reader(problems, fname, table, "redundancy")
    letter = r.get("letter", required=True)
    partner = r.get("partner", required=True)
    listen = r.get("listen")
    most = max(2, FAILOVER_MAX_MS // sync)  # the declared bounds hold; the tick bounds it further
    failover = r.number("failover_after", min(max(3, -(-FAILOVER_DEFAULT_MS // sync)), most))
    if failover > most:
        r.bad("failover_after", f"{failover} is outside 2-{most} (ticks of {sync} ms: a takeover within "
                                f"about {FAILOVER_MAX_MS} ms)")
        failover = most
    arbiter = r.get("arbiter")
    r.finish()
    if letter not in LETTERS:
        r.bad("letter", f"{letter!r} is not A or B")
        letter = "A"
    for key, value in (("partner", partner), ("listen", listen)):
        if key == "partner" and not value:
            continue  # reported missing
        try:
            split_address(value)
        except ValueError as e:
            r.bad(key, str(e))
    if arbiter != "none" and (problem := url_problem(arbiter) if is_url(arbiter) else
                              f"{arbiter!r} is neither \"none\" nor a postgresql:// URL"):
        r.bad("arbiter", problem)
        arbiter = "none"
    return RedundancySettings(letter, partner, listen, failover, arbiter)
