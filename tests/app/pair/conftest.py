"""Two stations of a hot-standby pair in one test run, on loopback, and the node they poll."""

from __future__ import annotations

import contextlib
import socket
import struct
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from pathlib import Path

import pytest

from app.authority import Source, Who
from app.authority.users import USERS_FILE, Users
from app.station.config import Station as StationSettings
from app.station.config import load_station
from app.station.runtime import Runtime
from netplc.program import parse
from netplc.records import Record
from netplc.simulator import Simulator
from tests.app.conftest import write_station
from tests.ports import free_port

TICK_MS = 40
# the node's link, the operator's word 04000 written to the node's 04100 every scan, a 10 s timer
# (elapsed time mirrored) and a counter of the 0.4 s generator's rising edges (edge memory)
PROGRAM = """\
TNA $03760
FON C:$02140 N:NODE S:1
TNA $03760
FON C:$02134 N:NWRITE S:4000 D:4100 R:2
TNA $03760
TIM C:$03000 N:100
TNA $03752
CTR C:$03010 N:255
JMP 0
"""
STATION = """\
name = "pair"
NetPlcProgram = "pair.stl"
NetSyncTime = {tick}
{top}[modbus_server]
port = 0
writable = [["04000", "04777"]]
[[nodes]]
node = 1
endpoint = "tcp://127.0.0.1:{node}"
timeout = 0.3
retries = 0
backoff = 0.05
[redundancy]
letter = "{letter}"
listen = "127.0.0.1:{listen}"
partner = "127.0.0.1:{partner}"
arbiter = "{arbiter}"
"""
OPERATOR = Who("", Source.MODBUS, "test")


def wait_for(condition: Callable[[], object], timeout: float = 15.0, what: str = "") -> None:
    """`condition` within `timeout` (generous: a loaded CI machine; speed is for bench/)."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"not within {timeout} s: {what}")
        time.sleep(0.01)


def wait_paired(primary: Station, standby: Station) -> None:
    """Both ends of the link up and the roles decided: a station that started beside a loaded
    partner may first lead alone (its start window is 0.5 s) and follow once the hellos cross."""
    wait_for(lambda: primary.role == "primary" and standby.role == "standby"
             and primary.rt.pair is not None and primary.rt.pair.status().link
             and standby.rt.pair is not None and standby.rt.pair.status().link, what="the pair linked")


def start_pair(a: Station, b: Station) -> None:
    """A started, and B as soon as A's pair link listens: their hellos cross at once and A leads,
    as when both start together, instead of A waiting out its start window (0.5 s) alone first.
    B dials a link that listens, so it never leads alone beside a loaded A: a starting station
    whose partner has connected waits for its hello."""
    def listening() -> int:
        return sum(t.name == "pair accept" for t in threading.enumerate())

    before = listening()
    with ThreadPoolExecutor(1, thread_name_prefix="start A") as pool:
        started = pool.submit(a.start)
        wait_for(lambda: started.done() or listening() > before, timeout=60, what="A's pair link listening")
        try:
            b.start()
        finally:
            started.result()


class Station:
    """One station of the pair: its folder, the runtime while it runs, and its journal."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.runtime: Runtime | None = None
        self.journal: list[Record] = []
        # the settings as this station differs from its partner on one host (a port, the arbiter
        # through a proxy), put after loading: the folder's hash, which the pair compares, is unchanged
        self.adjust: Callable[[StationSettings], StationSettings] = lambda settings: settings

    def start(self) -> Runtime:
        runtime = Runtime(self.adjust(load_station(self.folder)))
        runtime.subscribe(self.journal.append)
        runtime.start()
        self.runtime = runtime
        return runtime

    @property
    def rt(self) -> Runtime:
        assert self.runtime is not None
        return self.runtime

    @property
    def role(self) -> str:
        assert self.rt.pair is not None
        return self.rt.pair.role.value

    def word(self, addr: int) -> int:
        assert self.rt.engine is not None
        return self.rt.engine.snapshot.get_word(addr)

    def bit(self, addr: int) -> int:
        assert self.rt.engine is not None
        return self.rt.engine.snapshot.get_hmi_bit(addr)

    def write(self, addr: int, value: int) -> object:
        assert self.rt.commands is not None
        return self.rt.commands.write_word(OPERATOR, addr, value).result(3)

    def kill(self) -> None:
        """Dead at once: no more scans, the link cut with no word to the partner."""
        rt = self.rt
        assert rt.scan_thread is not None and rt.pair is not None
        rt.scan_thread.stop()
        rt.scan_thread = None
        pair, rt.pair = rt.pair, None
        pair.kill()
        rt.stop()
        self.runtime = None

    def stop(self) -> None:
        if self.runtime is not None:
            self.runtime.stop()
            self.runtime = None

    def texts(self) -> list[str]:
        return [r.text for r in self.journal if r.text]


_users: dict[tuple[tuple[str, str, str], ...], bytes] = {}


def give_users(stations: tuple[Station, ...], *users: tuple[str, str, str]) -> None:
    """`users` (name, role, password) in each station's users.json, as `users add` writes it and
    an engineer copies it to the partner: hashed once per process (scrypt, 70 ms a user) and the
    file copied, the owner's alone as Users leaves it."""
    if users not in _users:
        made = Users(stations[0].folder)
        for name, role, password in users:
            made.add(name, role, password)
        _users[users] = made.path.read_bytes()
    for station in stations:
        path = station.folder / USERS_FILE
        if not path.exists():
            path.touch(mode=0o600)
            path.write_bytes(_users[users])


def serve_opcua(station: Station) -> str:
    """The station's OPC UA endpoint on a free loopback port (the folder's hash unchanged)."""
    url = f"opc.tcp://127.0.0.1:{free_port()}/netplc/"
    station.adjust = lambda st: replace(st, opcua=replace(st.opcua, enabled=True, endpoint=url))
    return url


@pytest.fixture
def node() -> Iterator[Simulator]:
    sim = Simulator(parse("JMP 0\n", "node.stl"), tick=TICK_MS / 1000)
    sim.start()
    yield sim
    sim.stop()


def make_pair(tmp_path: Path, node: Simulator, arbiter: str = "none", b_dials: int | None = None,
              top: str = "", files: dict[str, str] | None = None) -> tuple[Station, Station]:
    """A and B of one station; B dials `b_dials` (a proxy's port) instead of A's link. `top`:
    more top-level keys of station.toml, `files`: more files of the station folder."""
    ports = {"A": free_port(), "B": free_port()}
    stations = []
    for letter, other in (("A", "B"), ("B", "A")):
        partner = b_dials if letter == "B" and b_dials else ports[other]
        folder = write_station(tmp_path / letter, STATION.format(
            tick=TICK_MS, node=node.port, letter=letter, listen=ports[letter], partner=partner,
            arbiter=arbiter, top=top), {"pair.stl": PROGRAM, **(files or {})})
        stations.append(Station(folder))
    return stations[0], stations[1]


@pytest.fixture
def pair(tmp_path: Path, node: Simulator) -> Iterator[tuple[Station, Station]]:
    a, b = make_pair(tmp_path, node)
    yield a, b
    for st in (b, a):
        st.stop()


class Proxy:
    """A TCP proxy between the pair that the test cuts (every connection and the listener), or
    whose connections so far it holds from the dialler (`hold`: what the listening side sends
    on them is lost on its way, its end still passes; new connections pass), or, `back`, from
    the listening side (what the dialler sends is lost)."""

    def __init__(self) -> None:
        self.target = 0
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.sockets: list[socket.socket] = []
        self.held: set[socket.socket] = set()  # upstream sockets whose data is dropped
        threading.Thread(target=self._accept, daemon=True).start()

    def hold(self, back: bool = False) -> None:
        self.held.update(self.sockets[0::2] if back else self.sockets[1::2])

    def _accept(self) -> None:
        while True:
            try:
                conn, _ = self.server.accept()
                upstream = socket.create_connection(("127.0.0.1", self.target))
            except OSError:
                return
            self.sockets += [conn, upstream]
            for one, other in ((conn, upstream), (upstream, conn)):
                threading.Thread(target=self._pipe, args=(one, other), daemon=True).start()

    def _pipe(self, src: socket.socket, dst: socket.socket) -> None:
        try:
            while data := src.recv(65536):
                if src not in self.held:
                    dst.sendall(data)
            dst.shutdown(socket.SHUT_WR)  # the end passes
        except OSError:
            return

    def cut(self) -> None:
        with contextlib.suppress(OSError):
            self.server.shutdown(socket.SHUT_RDWR)  # wakes the accept (close alone does not)
        self.server.close()
        for s in self.sockets:
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)
            s.close()


@pytest.fixture
def proxy() -> Iterator[Proxy]:
    p = Proxy()
    yield p
    p.cut()


def modbus_write(port: int, register: int, value: int) -> int:
    """FC06 to the station's Modbus server: 0 when applied, else the exception code."""
    with socket.create_connection(("127.0.0.1", port), timeout=3) as s:
        s.sendall(struct.pack(">HHHBBHH", 1, 0, 6, 1, 6, register, value))
        answer = s.recv(64)
    function = answer[7]
    return answer[8] if function & 0x80 else 0
