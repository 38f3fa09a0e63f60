"""The station runtime ("FregatServer" without a window): registrar, retentive memory, simulated
nodes, exchange, Modbus server, the NetPlc scan on the NetSyncTime tick, and what the forms do.

It imports no Qt, so `--no-gui` is this module alone and the workstation only attaches to it.
Start and stop run in opposite orders: the registrar is the first thing up and the last thing
down, so every record produced while the rest starts or stops (link lost, final retentive save,
'stop') is written; memory is saved only after the scan thread has ended, so the save is of a
finished scan.

Whatever the station does, it does here, with or without a window: the forms' models are loaded
headless and their behaviour (sync generators, RegData/RegMessages and limit records) is evaluated
from every scan's snapshot on the engine thread (`hmi_forms/behaviour.py`). Later per-scan
consumers (tags and quality, alarms) attach the same way, as engine listeners beside it.
"""

from __future__ import annotations

import logging
import os
import socket
import sqlite3
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor, wait
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

from app.authority import Commands, Source, Ticket, Who
from app.authority.modbus import ModbusCommands
from app.authority.users import USERS_FILE, Users
from app.publish.station import start_publishers
from app.scada.alarms import Alarm
from app.scada.readings import Readings
from app.scada.station import STATE_FILE as ALARM_STATE_FILE
from app.scada.station import StationAlarms
from app.scada.words import ENGLISH, phrase, words
from app.station.config import Station
from app.station.load import load, load_station_forms
from app.station.lock import StationLock, StationRunning
from netplc.engine import Engine
from netplc.exchange import Exchange, NodeConfig
from netplc.forcing import Force, load_forces, save_forces
from netplc.modbus import REOPEN, ModbusServer, ServerLimits, parse_endpoint
from netplc.problems import Problems
from netplc.records import Record
from netplc.scheduler import ScanThread
from netplc.simulator import Simulator
from registrar.retain import Retainer
from registrar.store import Store, StoreStats

if TYPE_CHECKING:
    from app.publish.mqtt import SparkplugPublisher
    from app.station.pair import Pair
    from hmi_forms.form import Form
    from registrar.plant.forward import Forwarder

logger = logging.getLogger(__name__)
RecordObserver = Callable[[Record], None]
RESOLVE_TIMEOUT = 5.0  # seconds for the host names of all TCP nodes to resolve
CODE_CACHE = "compiled"  # beside the archive: the compiled program, for a fast next start
PARSE_CACHE = "parsed"  # beside it: the parsed programs (the station's and its simulated nodes')


class StartError(Problems):
    """The station cannot start: every problem found (program, symbols, messages, addresses)."""


@dataclass(frozen=True)
class NodeStatus:
    node: int
    endpoint: str
    up: bool


@dataclass(frozen=True)
class RuntimeStatus:
    """One consistent look at the station for the status line and the status bar."""

    running: bool  # the runtime is started
    state: str  # NetPlc state text: running / halted / stopped, code 11
    scans: int
    scan_last_ms: float
    scan_max_ms: float
    scan_mean_ms: float
    overruns: int
    tick_ms: int
    nodes: tuple[NodeStatus, ...]
    records_written: int
    records_pending: int
    records_lost: int
    modbus_port: int | None
    modbus_serial: str = ""  # the serial port the Modbus server answers on (transport = "rtu")
    problems: tuple[str, ...] = field(default=())  # what an operator must see (disk, server, ...)
    forced: int = 0  # forces in effect: the always-visible "F: n forced"
    pair: str = ""  # one of a hot-standby pair: its role and link (PairStatus.line), else ""
    consoles: tuple[str, ...] = ()  # the OPC UA sessions logged in: user@host:port since when

    @property
    def nodes_up(self) -> int:
        return sum(n.up for n in self.nodes)

    def line(self) -> str:
        """The one-line status of `--no-gui`; once stopped, what the run did (a stopped station
        has no program state or links to report: "running" and "DOWN" there read as faults)."""
        if not self.running:
            text = f"{self.scans} scans, {self.records_written} records written"
            if self.records_lost:
                text += f", {self.records_lost} lost"
            return text
        nodes = ", ".join(f"{n.node}:{'up' if n.up else 'DOWN'}" for n in self.nodes) or "none"
        text = (f"NetPlc {self.state} | scan {self.scan_last_ms:.2f} ms (max {self.scan_max_ms:.2f}, "
                f"tick {self.tick_ms} ms, {self.overruns} overruns, {self.scans} scans) | "
                f"nodes {self.nodes_up}/{len(self.nodes)} up [{nodes}] | records {self.records_written}")
        if self.pair:
            text += f" | {self.pair}"
        if self.consoles:
            text += f" | consoles: {', '.join(self.consoles)}"
        if self.problems:
            text += " | " + "; ".join(self.problems)
        return text


def unresolved_hosts(station: Station) -> list[str]:
    """The TCP nodes whose host name does not resolve, each naming its key. A typo in a host name
    would otherwise be a node that is silently down forever; the names are looked up together,
    so a dead name server costs RESOLVE_TIMEOUT once, not once per node."""
    hosts: dict[str, list[str]] = {}
    for n in station.nodes:
        ep = parse_endpoint(n.endpoint) if n.endpoint else None
        if ep is not None and ep.scheme == "tcp":
            hosts.setdefault(ep.host, []).append(f"{n.key}.endpoint")
    if not hosts:
        return []
    pool = ThreadPoolExecutor(len(hosts), thread_name_prefix="resolve")
    lookups = {pool.submit(socket.getaddrinfo, host, None, type=socket.SOCK_STREAM): host for host in hosts}
    wait(lookups, RESOLVE_TIMEOUT)
    pool.shutdown(wait=False, cancel_futures=True)
    problems = []
    for lookup, host in lookups.items():
        if not lookup.done():
            why = f"did not resolve within {RESOLVE_TIMEOUT:g} s"
        elif isinstance(error := lookup.exception(), OSError):
            why = f"does not resolve: {error.strerror or error}"
        elif error is not None:  # a name the resolver cannot even encode (UnicodeError)
            why = f"is not a host name: {error}"
        else:
            continue
        problems += [f"{station.path}: {key}: host {host!r} {why}" for key in hosts[host]]
    return problems


def _reason(e: OSError) -> str:
    """The OS's words for a socket error (asyncio wraps them in a sentence of its own)."""
    return os.strerror(e.errno) if e.errno else str(e)


class Runtime:
    """The running station. `start()`, then `status()` as often as wanted, then `stop()`."""

    def __init__(self, station: Station, *, wallclock: Callable[[], float] = time.time) -> None:
        self.station = station
        self.wallclock = wallclock
        self.words = words(station.Language)  # what its records say (app/scada/words.py)
        loaded = load(station, parse_cache=station.Archive.parent / PARSE_CACHE)
        if loaded.problems:
            raise StartError(loaded.problems)
        self.symbols, self.catalog, self.program = loaded.symbols, loaded.catalog, loaded.program
        self.tags = loaded.tags
        self.node_programs = loaded.node_programs
        self.forms: list[Form] = loaded.forms  # the runtime's own models: evaluated, never shown
        self.form_problems = loaded.form_problems
        self.store: Store | None = None
        self.forwarder: Forwarder | None = None  # to the plant archive, when Archive is a URL
        self.engine: Engine | None = None
        self.retainer: Retainer | None = None
        self.simulators: list[Simulator] = []
        self.silent: set[int] = set()  # simulators stopped by `simulator_answers`
        self.exchange: Exchange | None = None
        self.modbus: ModbusServer | None = None
        self.alarms: StationAlarms | None = None  # tags, quality and alarms, evaluated every scan
        self.commands: Commands | None = None  # the one authority: every outside action goes through it
        self._users: tuple[float, Users] | None = None  # users.json as last read, by its mtime
        self.scan_thread: ScanThread | None = None
        self.publishers: list = []  # OPC UA server, MQTT publisher (app/publish/)
        self.pair: Pair | None = None  # [redundancy]: this station's side of a hot-standby pair
        self.nodes: list[NodeConfig] = list(station.nodes)
        self.restored = ""  # which retentive save was used: current / previous / zeroes
        self.started_clock: float | None = None
        self._saved_forces: tuple[Force, ...] | None = None  # the forces as last written (RetainForces)
        self._observers: list[RecordObserver] = []
        self._problems: list[str] = []
        self._lock = threading.Lock()
        self._final_store: StoreStats | None = None  # the archive's figures after stop
        self._final_retain_error = ""  # why the final retentive save failed, if it did
        self._folder_lock = StationLock(station.folder)  # one station per folder (app/station/lock.py)
        self.started = False

    # --- records -------------------------------------------------------------------------------

    def put(self, record: Record) -> None:
        """The sink every part writes to: the registrar, then whoever watches (alarm banner). The
        primary of a pair archives a record once its standby holds the scan that made it
        (`Pair.hold`); the watchers see it at once."""
        alarms = self.alarms
        if record.kind == "data" and alarms is not None:
            record = alarms.stamp(record)  # a value that is not good keeps its quality in the archive
        pair = self.pair
        if pair is None or not pair.hold(record):
            self.archive(record)
        for observer in list(self._observers):
            observer(record)

    def archive(self, record: Record) -> None:
        """`record` to the registrar (a pair's primary: once its standby holds the record's scan)."""
        if self.store is not None:
            self.store.put(record)

    def after_commit(self, callback: Callable[[], None]) -> None:
        """`callback()` once a pair's standby holds the scan running now (app/station/pair.py),
        then once every record put so far is on disk (a pair's primary archives them once the
        standby holds their scan), and so is the retentive memory of the scan that put them
        (registrar/retain.py): the engine answers an outside writer then, so an acknowledged
        write survives a crash both in the journal and in memory, and a takeover."""
        pair = self.pair
        if pair is not None:
            pair.after_mirrored(lambda: self._after_local_commit(callback))
        else:
            self._after_local_commit(callback)

    def after_archived(self, callback: Callable[[], None]) -> None:
        """`callback()` once the records archived so far are committed to the local archive, by
        the commit that comes anyway (none of its own): a pair's primary tells its standby the
        scans whose records it has on disk (app/station/pair.py)."""
        if self.store is not None:
            self.store.after_commit(callback, wake=False)
        else:
            callback()

    def _after_local_commit(self, callback: Callable[[], None]) -> None:
        parts: list[Callable[[Callable[[], None]], None]] = []
        if self.store is not None:
            parts.append(self.store.after_commit)
        if self.retainer is not None:
            parts.append(self.retainer.after_save)
        if not parts:
            callback()
            return
        left = [len(parts)]
        lock = threading.Lock()

        def part_done() -> None:
            with lock:
                left[0] -= 1
                last = left[0] == 0
            if last:
                callback()

        for part in parts:
            part(part_done)

    def room(self) -> int:
        """Records the archive queue takes before it drops (the engine applies no write beyond it)."""
        return self.store.room() if self.store is not None else 1 << 30

    def subscribe(self, observer: RecordObserver) -> None:
        """Call `observer(record)` for every record, from the thread that produced it."""
        self._observers.append(observer)

    def unsubscribe(self, observer: RecordObserver) -> None:
        if observer in self._observers:
            self._observers.remove(observer)

    def say(self, name: str, level: int = logging.INFO, **values: object) -> None:
        """A 'system' record of the catalogue (app/scada/words.py: `name` and its `values`) in the
        station's `Language`, and the same in English in the log (at `level`), which is read by
        whoever supports the station, not only by its operators."""
        logger.log(level, "%s", ENGLISH(name, **values))
        self.put(Record(self.wallclock(), "system", source="station", text=self.words(name, **values)))

    # --- start and stop ------------------------------------------------------------------------

    def start(self) -> None:
        """Start every part; StartError names the key of what could not start (the archive, a
        simulator's port, the nodes), after what did start is stopped again; a station already
        running in the folder is refused before anything is opened."""
        st = self.station
        try:
            self._folder_lock.acquire()
        except StationRunning as e:
            raise StartError([str(e)]) from None
        except OSError as e:
            raise StartError([f"{st.path}: cannot lock the station folder: {self._folder_lock.path}: "
                              f"{e.strerror or e}"]) from None
        store = Store(st.Archive, catalog=self.catalog, keep_days=st.keep_days, wallclock=self.wallclock,
                      tags=self.tags, station=st.name, say=self.words)
        try:
            store.start()
        except (OSError, sqlite3.Error) as e:
            self._folder_lock.release()
            raise StartError([f"{st.path}: Archive: {e}"]) from None
        self.store = store
        if st.plant_archive:
            from registrar.plant.forward import Forwarder  # psycopg only where a plant archive is named

            self.forwarder = Forwarder(st.Archive, st.plant_archive, st.name, keep_days=st.plant_keep_days,
                                       sink=self.put, wallclock=self.wallclock, say=self.words,
                                       letter=st.redundancy.letter if st.redundancy is not None else "")
            self.forwarder.start()  # never fails: PostgreSQL away is a lag, not a start error
        started = False
        try:
            self._start_parts()
            started = True
        except StartError as e:
            for problem in e.problems:
                self.say("cannot start", problem=problem)
            raise
        finally:
            if not started:  # whatever ended the start, Ctrl+C too: what did start stops again
                self.stop()

    def _start_parts(self) -> None:
        st = self.station
        self.say("starting", path=st.path)
        self.engine = Engine(self.program, sink=self, tick=st.tick, wallclock=self.wallclock,
                             code_cache=st.Archive.parent / CODE_CACHE)
        self.engine.words = self.words
        self.started_clock = self.engine.now  # engine-clock time of the start (DateTime elements)
        for problem in self.form_problems:
            self.say("form not loaded", problem=problem)
        if not st.NetPlcLoad:
            self.engine.stop()
        self.retainer = Retainer(st.Retain, self.engine, self, say=self.words)
        self.restored = self.retainer.restore()
        self._restore_forces()
        regdata: dict[str, tuple[tuple[int, int], ...]] = {}
        if self.forms:  # the form code loads only for a station that has forms
            from hmi_forms.behaviour import FormBehaviour

            behaviour = FormBehaviour(self.forms, self.engine.mem, self, self.problem)
            behaviour.attach(self.engine)
            self.say("forms loaded", forms=len(self.forms), elements=len(behaviour.elements))
            regdata = {el.Name: el.sources() for _, el in behaviour.elements if el.RegData}
        for i, (sim, program) in enumerate(zip(st.simulators, self.node_programs, strict=True)):
            simulator = Simulator(program, host=sim.host, port=sim.port, unit=sim.unit,
                                  tick=sim.tick_ms / 1000)
            try:
                simulator.start()
            except OSError as e:
                raise StartError([f"{st.path}: simulators[{i}].port: cannot listen on "
                                  f"{sim.host}:{sim.port}: {_reason(e)}"]) from None
            self.simulators.append(simulator)
            self._fill_endpoint(sim.node, f"tcp://{sim.host}:{simulator.port}")
        self.exchange = Exchange(self.nodes, self)
        self.exchange.words = self.words
        self.exchange.attach(self.engine)
        self.exchange.start()
        self.alarms = StationAlarms(st.Tags, self.program, list(self.catalog), self,
                                    st.Archive.with_name(ALARM_STATE_FILE), self.symbols, regdata,
                                    self._no_standby if st.redundancy is not None else None,
                                    horn=st.alarm_horn, language=st.Language)
        self.subscribe(self.alarms.observe)
        self.alarms.attach(self.engine, self.exchange)
        self.commands = Commands(self.engine, self, role_of=self.role_of, tags=self.alarms.table.tags,
                                 alarms=self.alarms, wallclock=self.wallclock, standby=self._standby,
                                 hand_over=self._hand_over if st.redundancy is not None else None,
                                 say=self.words)
        server = st.modbus_server
        if server.enabled:
            self.commands.grant(Source.MODBUS, server.role)
            limits = ServerLimits(server.max_connections, server.idle_timeout, server.max_inflight,
                                  server.max_per_peer)
            modbus = ModbusServer(ModbusCommands(self.commands, server.writable), host=server.host,
                                  port=server.port, unit=server.unit, serial=server.serial,
                                  limits=limits, sink=self, words=self.words)
            try:
                modbus.start(retry=True)
                self.modbus = modbus
            except OSError as e:  # the station runs on without it; the operator sees why
                self.problem("modbus not started", path=st.path, host=server.host, port=server.port,
                             error=_reason(e))
            if modbus.fault:  # a serial port not there yet, or not ours to open: tried again
                self.say("modbus not yet", logging.WARNING, path=st.path, fault=modbus.fault, every=REOPEN)
        self.publishers = start_publishers(self)
        self.say("program loaded", source=self.program.source, instrs=len(self.program.instrs),
                    words=self.program.words)
        self.retainer.start()  # before the first scan: its writers wait for its saves
        if st.redundancy is not None:
            self._start_pair()
        self.scan_thread = ScanThread(self.engine, st.tick, on_error=self._scan_error)
        self.scan_thread.start()
        self.started = True
        self.say("started", sync=st.NetSyncTime, restored=phrase(f"retained {self.restored}"))
        threading.Thread(target=self._report_unresolved, name="resolve", daemon=True).start()

    def _start_pair(self) -> None:
        """Join the pair: the role is decided (a partner heard within the start window, or none)
        before the first scan, so no program scan and no node request precede it."""
        from app.station.fingerprint import fingerprint
        from app.station.pair import Pair

        st = self.station
        assert st.redundancy is not None and self.engine is not None
        pair = Pair(self, st.redundancy, fingerprint(st))
        try:
            pair.start(self.engine)
        except OSError as e:
            pair.stop()
            raise StartError([f"{st.path}: redundancy.listen: cannot listen on {st.redundancy.listen}: "
                              f"{_reason(e)}"]) from None
        self.pair = pair

    def leads(self) -> bool:
        """Does this station act now: alone, or the primary of its pair (MQTT publishes only then)."""
        return self._standby() is None

    def sparkplug(self) -> SparkplugPublisher | None:
        """The station's MQTT Sparkplug edge node, if it publishes one (a pair mirrors its bdSeq)."""
        if not self.station.mqtt.enabled:
            return None
        from app.publish.mqtt import SparkplugPublisher  # loaded already: the station publishes MQTT

        return next((p for p in self.publishers if isinstance(p, SparkplugPublisher)), None)

    def _no_standby(self) -> str:
        """Why this pair's primary has no standby now (PAIR.NO_STANDBY), "" while it has one."""
        pair = self.pair
        if pair is None or pair.role != "primary":
            return ""
        status = pair.status()
        if pair.refused:
            return pair.refused
        return "" if status.link else self.words("pair link down", partner=status.partner)

    def _standby(self) -> str | None:
        """Why the command layer refuses a write or command now: this station is not the primary."""
        pair = self.pair
        if pair is None:
            return None if self.station.redundancy is None else self.words("joining")
        return pair.refusal()

    def _hand_over(self, user: str) -> str | None:
        """IntoStandBy by `user`, for the command layer: None once asked for, else why not."""
        pair = self.pair
        if pair is None or not pair.into_standby(self.words("into standby", user=user)):
            return self.words("nothing to hand over")
        return None

    def _restore_forces(self) -> None:
        """RetainForces = true: the forces of the last run are in effect again from the first scan,
        each journaled; otherwise a restart starts unforced."""
        st = self.station
        if not st.RetainForces or self.engine is None:
            return
        forces, problems = load_forces(st.forces_file)
        for problem in problems:
            self.problem("force not restored", problem=problem)
        self.engine.forces.restore(forces, user="station (RetainForces)")
        if forces:
            self.say("forces restored", n=len(forces), file=st.forces_file)
        self.engine.subscribe(self._save_forces)

    def _save_forces(self, _snapshot: object) -> None:
        """An engine listener: the forces are written whenever they changed, so a crash keeps them too."""
        assert self.engine is not None
        listing = self.engine.forces.listing
        if listing is self._saved_forces:
            return
        self._saved_forces = listing
        try:
            save_forces(self.station.forces_file, listing)
        except OSError as e:
            self.say("forces not saved", logging.WARNING, file=self.station.forces_file,
                     error=e.strerror or e)

    def _report_unresolved(self) -> None:
        """Journal each node host name that does not resolve, by its key. The station starts all the
        same: the name server may come up after the PC does, and the exchange keeps trying the node
        (shown down meanwhile); `check` reports the name as a problem, for the typo it may be."""
        for text in unresolved_hosts(self.station):
            if self.started:
                self.say("stays down", text=text)

    def service_level(self) -> int:
        """OPC UA ServiceLevel: 255 alone; one of a pair, by its role (pair.SERVICE_LEVEL)."""
        from app.station.pair import SERVICE_LEVEL, Role

        pair = self.pair
        if pair is not None:
            return SERVICE_LEVEL[pair.role]
        return SERVICE_LEVEL[Role.PRIMARY if self.station.redundancy is None else Role.STARTING]

    def role_of(self, name: str) -> str | None:
        """A user's role as users.json says now (read again when the file changed, so a role changed
        or a user removed counts at the next command); None when there is no such user."""
        path = self.station.folder / USERS_FILE
        try:
            mtime = path.stat().st_mtime_ns
        except OSError:
            return None
        cached = self._users
        if cached is None or cached[0] != mtime:
            cached = self._users = (mtime, Users(self.station.folder))
        user = cached[1].get(name)
        return None if user is None else user.role

    def open_forms(self) -> tuple[list[Form], list[str]]:
        """Fresh models of the station's forms for a view, which only shows them (the runtime
        evaluates its own); and the problems of the forms that did not load."""
        return load_station_forms(self.station, self.symbols, self.tags)

    def _fill_endpoint(self, node: int, endpoint: str) -> None:
        self.nodes = [replace(n, endpoint=endpoint) if n.node == node and not n.endpoint else n
                      for n in self.nodes]

    def _scan_error(self, error: BaseException) -> None:
        self.problem("scan failed", error=repr(error))

    def problem(self, name: str, /, **values: object) -> None:
        """What an operator must see, said once (a server that did not start, a scan that failed):
        the health strip (`RuntimeStatus.problems`) for as long as the station runs and a 'system'
        record, in the station's language (the catalogue's `name` and `values`), and a warning in
        the log."""
        text = self.words(name, **values)
        with self._lock:
            if text in self._problems:
                return
            self._problems.append(text)
        self.say(name, logging.WARNING, **values)

    def stop(self) -> None:
        """Stop everything in the reverse order of start; safe to call twice or after a failed start.
        The primary of a pair hands over to its standby first."""
        if self.pair is not None:
            self.pair.into_standby(self.words("primary stopping"), wait=1.0)
            self.pair.stop()
            self.pair = None
        if self.scan_thread is not None:
            self.scan_thread.stop()
            self.scan_thread = None
        for publisher in reversed(self.publishers):
            publisher.stop()
        self.publishers = []
        if self.alarms is not None:
            self.unsubscribe(self.alarms.observe)
            self.alarms.close()  # the last alarm states, after the last scan
            self.alarms = None
        if self.retainer is not None:
            self.retainer.stop()  # the final save, of the last finished scan
            self._final_retain_error = self.retainer.last_error
            self.retainer = None
        if self.modbus is not None:
            self.modbus.stop()
            self.modbus = None
        if self.exchange is not None:
            self.exchange.stop()
            self.exchange = None
        for i, simulator in reversed(list(enumerate(self.simulators))):
            if i not in self.silent:
                simulator.stop()
        self.simulators.clear()
        self.silent.clear()
        if self.store is not None:
            if self.started:
                self.say("station stopped")
            store, self.store = self.store, None
            store.close()  # flushes every queued record
            self._final_store = store.stats
        if self.forwarder is not None:
            self.forwarder.close()  # sends the rest if the plant archive answers
            self.forwarder = None
        self.started = False
        self._folder_lock.release()  # last: every file of the station is closed

    def simulator_answers(self, index: int, answering: bool) -> None:
        """Stop simulated node `index` of station.toml (a pulled cable: its tags go comm-fail and
        their quality alarms come) or start it again on the same port: the demo's bad-quality case
        an operator can provoke. Journaled as a 'system' record."""
        sim, old = self.station.simulators[index], self.simulators[index]
        if answering == (index not in self.silent):
            return
        if not answering:
            old.stop()
            self.silent.add(index)
        else:
            self.silent.discard(index)
            new = Simulator(self.node_programs[index], host=sim.host, port=old.port, unit=sim.unit,
                            tick=sim.tick_ms / 1000)
            new.engine.mem.load(old.engine.snapshot)  # the plant goes on where it stopped
            new.start()
            self.simulators[index] = new
        self.say("node answers" if answering else "node silent", node=sim.node)

    def watch(self, callback: Callable[[Readings], None], name: str | None = None) -> Callable[[], None]:
        """The station's public feed: `callback(readings)` on the engine thread after every scan,
        once that scan's quality and alarms are evaluated, with the values and their quality of
        that one scan together (`readings.snapshot` is the scan's snapshot). What the GUI, the
        publishers and the consoles read; isolated like every engine listener. Returns the call
        that stops it. Call after `start()`."""
        engine = self.engine
        if engine is None:
            raise RuntimeError("the station is not started")

        def on_scan(snapshot: object) -> None:
            alarms = self.alarms
            readings = alarms.readings if alarms is not None else None
            if readings is not None and readings.snapshot is snapshot:
                callback(readings)

        return engine.subscribe(on_scan, name or getattr(callback, "__qualname__", None))

    def alarm_definitions(self) -> list[Alarm]:
        """The station's alarms, their identities and states as of now: for a publisher that
        builds its address space before the first scan (their transitions follow as records)."""
        alarms = self.alarms
        return list(alarms.system.alarms) if alarms is not None else []

    def readings(self) -> Readings | None:
        """Every tag's and address's value with its quality and time as of the last scan
        (app/scada/readings.py): what the HMI, the journal and the publishers read; None while
        the station is not started (a reader then shows its values as not running)."""
        alarms = self.alarms
        return alarms.readings if alarms is not None else None

    # --- NetPlc run control as a user (scripts and tests; the workstation sends its own commands) -

    def run_program(self, user: str) -> Ticket:
        """Run NetPlc as `user` at the console: the command layer's `run` (checked, journaled,
        answered once applied)."""
        assert self.commands is not None, "the station is not started"
        return self.commands.run(Who(user, Source.CONSOLE))

    def stop_program(self, user: str) -> Ticket:
        assert self.commands is not None, "the station is not started"
        return self.commands.stop(Who(user, Source.CONSOLE))

    def operator(self, user: str, name: str, /, **values: object) -> None:
        """What a user did at the workstation that is not a command (log in and out): an 'operator'
        record naming the user, as the commands' records do, in the station's language."""
        self.put(Record(self.wallclock(), "operator", source=user or "nobody",
                        text=self.words(name, **values)))

    # --- status --------------------------------------------------------------------------------

    def status(self) -> RuntimeStatus:
        engine = self.engine
        stats = engine.stats if engine else None
        exchange = self.exchange
        nodes = tuple(NodeStatus(n.node, n.endpoint, bool(exchange and exchange.link_up(n.node)))
                      for n in self.nodes)
        problems = list(self._problems) + [f"form problem: {p}" for p in self.form_problems[:3]]
        if self.modbus is not None and self.modbus.fault:  # journaled when it began and when it ended
            problems.append(self.modbus.fault)
        if engine is not None:
            faults = engine.listener_faults.items()
            problems += [f"engine listener {name} failed: {why}" for name, why in faults]
        retain_error = self.retainer.last_error if self.retainer is not None else self._final_retain_error
        if retain_error:  # journaled once by the retainer; shown for as long as saves fail
            problems.append(f"retentive memory not saved: {retain_error}")
        written = pending = lost = 0
        s = self.store.stats if self.store is not None else self._final_store
        if s is not None:
            written, pending, lost = s.committed, s.queued, s.dropped
            if s.last_error:
                problems.append(f"archive: {s.last_error}")
            if s.dropped:
                problems.append(f"archive: {s.dropped} records lost (disk too slow or full)")
        forwarder = self.forwarder
        if forwarder is not None and (f := forwarder.stats).lag > forwarder.lag_alarm:
            problems.append(f"archive: forwarding to the plant archive lags by {f.lag:.0f} s, "
                            f"{f.backlog} records ({f.last_error or 'catching up'})")
        pair = self.pair.status() if self.pair is not None else None
        if self.pair is not None and self.pair.refused:
            problems.append(self.pair.refused)
        if pair is not None and not pair.link:
            problems.append(f"pair link to {pair.partner} down: no standby")
        return RuntimeStatus(
            running=self.started,
            state=engine.state_text if engine else "not started",
            scans=stats.count if stats else 0,
            scan_last_ms=stats.last_ms if stats else 0.0,
            scan_max_ms=stats.max_ms if stats else 0.0,
            scan_mean_ms=stats.mean_ms if stats else 0.0,
            overruns=stats.overruns if stats else 0,
            tick_ms=self.station.NetSyncTime,
            nodes=nodes,
            records_written=written,
            records_pending=pending,
            records_lost=lost,
            modbus_port=self.modbus.port if self.modbus and self.modbus.serial is None else None,
            modbus_serial=self.modbus.serial.device if self.modbus and self.modbus.serial else "",
            problems=tuple(problems),
            forced=engine.forces.count if engine else 0,
            pair=pair.line() if pair is not None else "",
            consoles=tuple(seat.line() for p in self.publishers if hasattr(p, "seats")
                           for seat in p.seats.seats()),
        )
