"""A hot-standby pair of stations (seed 000's HSB; docs/architecture.md section 11).

One station of the pair is the primary: it runs the program, the exchange with the nodes and
accepts commands; after every scan it sends the standby what changed (app/station/mirror.py). The
standby's engine follows (`Engine.follower`): it runs no program, so its exchange asks the nodes
for nothing, and its command layer refuses writes and commands naming the primary, while its
Modbus and OPC UA servers answer reads from the mirrored memory.

One TCP link between the two, always dialled by B to A (one dialler: two stations starting
together never cross two connections); once both said hello the roles decide who sends. The
roles at a hello: a primary stays primary and the other follows; two primaries (a link healed
after both acted): the one that led more scans; none (both starting): A. A station that hears
no partner within its start window (failover_after ticks and two more, 0.5 s at least) leads;
one whose partner has connected but not yet said hello (a loaded PC) waits for that hello, as
long as a link waits for any frame, rather than lead beside it.

The standby takes over when the primary's frames have stopped for failover_after ticks: the
newest mirrored state is put into its engine and the program runs on from it in the next scan
(timers keep their elapsed time, edges their memory, NWRITEs resume from the mirrored words).

The primary archives a scan's records once the standby holds that scan; they ride in its frame
too, each with its pid, and the standby keeps them until the primary says they are on its disk:
taking over, it archives what it kept, so a primary that died first loses none, and a copy both
archived is one record in the plant archive, keyed by the pid.
"""

from __future__ import annotations

import contextlib
import json
import logging
import select
import socket
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from enum import StrEnum
from typing import TYPE_CHECKING

from app.scada.words import Phrase, phrase, words
from app.station.config import RedundancySettings
from app.station.fingerprint import differing
from app.station.mirror import (
    ACK,
    HANDOVER,
    HELLO,
    STATE,
    TAKEN,
    Capture,
    Encoder,
    LinkClosed,
    LinkError,
    Mirror,
    capture,
    read_frame,
    send_frame,
)
from netplc.engine import Engine
from netplc.memory import Memory, Snapshot
from netplc.records import Record

if TYPE_CHECKING:
    from app.station.runtime import Runtime
    from registrar.plant.lease import Lease

logger = logging.getLogger(__name__)


class Role(StrEnum):
    STARTING = "starting"
    PRIMARY = "primary"
    STANDBY = "standby"


def said_role(role: Role) -> Phrase:
    """A role as the records name it, in the station's language."""
    return phrase(f"role {role.value}")


# HSBStatus of seed 000 by role: 0 after power-on, 4 standby, 5 master (6 defect: refused partner)
HSB_STATUS = {Role.STARTING: 0, Role.PRIMARY: 5, Role.STANDBY: 4}
# OPC UA ServiceLevel by role (Part 4 6.6.2.4.2: 0 maintenance, 1 no data, 2-199 degraded, 200-255
# healthy): the standby serves reads but no writes, degraded; a client of the pair takes the highest
SERVICE_LEVEL = {Role.STARTING: 1, Role.PRIMARY: 255, Role.STANDBY: 100}
DEFECT = 6
# The pair's status words in NetPlc memory, beside the RTC (077700-077707), each station's own
# (written after the mirrored memory is put), for a program and an HMI (docs/operations/redundancy.md)
HSB_NUM_PLC = 0o77710  # byte: 1 = A, 0 = B (HSBNumPLC)
HSB_STATUS_BYTE = 0o77711  # byte: HSBStatus
DGN_HSB = 0o77712  # word: b7 the partner's station differs, b9 the pair link is down, b15 a switchover
HSB_SWITCH = 0o77714  # word: low byte the last switchover's cause, high byte the switchovers
HSB_LAG = 0o77716  # byte: the standby's lag in the primary's scans (255 at most)
START_WINDOW = 0.5  # s at least a starting station waits for a partner before it leads alone
# switchover causes (the low byte of HSB_SWITCH), after seed 000's hardware codes; TAKEN_OVER: a
# primary told by its standby that it took over (it had heard no frame for failover_after)
SILENT, HANDED_OVER, STEPPED_DOWN, TAKEN_OVER = 50, 51, 52, 53
# a held record's pid (its identity in both stations' archives and the plant archive): its time in
# ms shifted by this, or the last pid + 1 if that is higher, so pids only grow across the pair's
# takeovers and restarts, far above the ids of a letter (registrar/plant/schema.py PAIR_ID_BASE)
PID_SHIFT = 12


def decide(mine: Role, letter: str, theirs: Role, my_scans: int = 0, their_scans: int = 0) -> Role:
    """This station's role once both said hello; both sides reach the same answer. Two
    primaries: the one that led more scans (a station that led alone for its start window while
    the link was slow to come gives way to the one that has the plant's state), then A."""
    if mine is Role.PRIMARY and theirs is not Role.PRIMARY:
        return Role.PRIMARY
    if theirs is Role.PRIMARY and mine is not Role.PRIMARY:
        return Role.STANDBY
    if mine is Role.PRIMARY and my_scans != their_scans:
        return Role.PRIMARY if my_scans > their_scans else Role.STANDBY
    return Role.PRIMARY if letter == "A" else Role.STANDBY


@dataclass(frozen=True)
class PairStatus:
    """What `main.py redundancy status` and the health strip show."""

    letter: str
    role: str
    partner: str
    link: bool  # a partner of the same station is connected
    last_takeover: str  # when and why this station last became primary, "" never
    lag: int  # the standby: scans of the primary's since its last frame; the primary: 0
    switchovers: int

    def line(self) -> str:
        link = "up" if self.link else "DOWN"
        text = f"pair {self.letter}: {self.role}, partner {self.partner} link {link}"
        if self.role == Role.STANDBY:
            text += f", lag {self.lag} scans"
        if self.last_takeover:
            text += f"; last takeover: {self.last_takeover}"
        return text

    def as_dict(self) -> dict[str, object]:
        return {"letter": self.letter, "role": self.role, "partner": self.partner, "link": self.link,
                "last_takeover": self.last_takeover, "lag": self.lag, "switchovers": self.switchovers}


class Pair:
    """This station's side of the pair: `start()` (returns once the role is decided), `stop()`."""

    def __init__(self, runtime: Runtime, settings: RedundancySettings, files: dict[str, str],
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.runtime = runtime
        self.settings = settings
        self.files = files
        self.clock = clock
        self.role = Role.STARTING
        self.mirror = Mirror()
        self.switchovers = 0
        self.last_takeover = ""
        self.refused = ""  # why the partner was refused (files differ), for the health strip
        self._engine: Engine | None = None
        self._lock = threading.Lock()
        self._changed = threading.Condition(self._lock)  # a new capture, or a new role
        self._capture: Capture | None = None
        self._link: socket.socket | None = None  # the pair link, once both said hello
        self._last_frame = clock()
        self._load_pending = False
        self._handing_over = ""  # into_standby asked for, done by the next scan's listener
        self._handover = ""  # the cause the link's thread sends after the last frame
        self._handed = threading.Event()  # the handover was sent (or the link ended)
        self._stopping = threading.Event()
        self._decided = threading.Event()
        self._greeting = 0  # links connected whose hellos have not yet crossed
        self._server: socket.socket | None = None
        self._threads: list[threading.Thread] = []
        self.port = 0  # the port this station's link listens on
        self.lease: Lease | None = None  # arbiter = "postgresql://...": the primary's lease
        if settings.arbiter != "none":
            from registrar.plant.lease import Lease  # psycopg only where an arbiter is named

            self.lease = Lease(settings.arbiter, runtime.station.name)
        self._waiting = ""  # why this station may not lead now, as last journaled
        self.cause = 0  # the last switchover's cause code (HSB_SWITCH)
        self.led_scans = 0  # scans run as the primary: of two primaries, the one with more leads
        self._awaiting: list[tuple[int, Callable[[], None]]] = []  # (scan, callback): after_mirrored
        # The primary's records, archived once the standby holds their scan (`hold`): those of the
        # scan running now, then those of the scans sent and not yet acknowledged, by scan
        self._records: list[Record] = []
        self._held: list[tuple[int, list[Record]]] = []
        self._last_pid = 0  # the last pid given to a held record (`hold`), or seen in the mirror
        self._on_disk = -1  # the last scan whose held records are committed to the local archive
        self._taken = False  # told TAKEN: until the engine follows, the scan's records are dropped
        self._told: socket.socket | None = None  # the link this station took over on: drained, closed
        self._send_lock = threading.Lock()  # frames on the link: its sender, its reader, the watch
        self._whole_alarms = True  # the next capture holds every alarm's state (a new link's first)
        self._bdseq = -1  # the primary's MQTT bdSeq as last handed to this station's publisher

    @property
    def tick(self) -> float:
        return self.runtime.station.tick

    @property
    def failover(self) -> float:
        return self.settings.failover_after * self.tick

    @property
    def partner_name(self) -> str:
        return f"{'B' if self.settings.letter == 'A' else 'A'} at {self.settings.partner}"

    # --- start and stop ------------------------------------------------------------------------

    def start(self, engine: Engine) -> None:
        """Listen, dial (B), and decide the role within the start window: a partner heard is
        followed or leads; none heard, this station is the primary."""
        self._engine = engine
        engine.follower = True  # no program and no node request before the role is decided
        engine.subscribe(self._on_scan, "pair link")
        host, port = self.settings.listen_address
        server = socket.create_server((host, port))
        server.settimeout(self.tick)
        self._server = server
        self.port = server.getsockname()[1]
        self._spawn(self._accept, "pair accept")
        if self.settings.letter == "B":
            self._spawn(self._dial, "pair dial")
        self._spawn(self._watch, "pair watch")
        window = max(self.failover + 2 * self.tick, START_WINDOW)
        if not self._decided.wait(window):
            with self._changed:  # a partner connected is a partner: its hello decides, or its silence
                self._changed.wait_for(lambda: self._decided.is_set() or not self._greeting,
                                       self.failover + 1.0)
        if not self._decided.is_set():
            self._become(Role.PRIMARY, phrase("no partner", ms=window * 1000))

    def _spawn(self, target: Callable[[], None], name: str) -> None:
        thread = threading.Thread(target=target, name=name, daemon=True)
        thread.start()
        self._threads.append(thread)

    def stop(self) -> None:
        self._stopping.set()
        if self.lease is not None:
            self.lease.release()
        with self._changed:
            self._changed.notify_all()
        self._drop_link()
        if self._server is not None:
            self._server.close()
        for thread in self._threads:
            thread.join(5)
        self._threads.clear()
        if self._engine is not None:
            self._engine.unsubscribe(self._on_scan)

    def kill(self) -> None:
        """End the link at once with no word to the partner, as a dying station's would (tests,
        bench/failover.py): the partner learns of it only by the silence, and the writers waiting
        for the standby are never answered and the records of the scans it does not hold never
        archived, as by a dead process."""
        with self._lock:
            self._awaiting.clear()
            self._records, self._held = [], []
            self._taken = True  # what comes before the stop is dropped as well
        self.stop()

    # --- the role ------------------------------------------------------------------------------

    def refusal(self) -> str | None:
        """Why this station takes no writes or commands now (its command layer's STANDBY), or None."""
        if self.role is Role.PRIMARY:
            return None
        if self.role is Role.STARTING:
            return self.runtime.words("pair starting")
        return self.runtime.words("pair standby", letter=self.settings.letter, primary=self.partner_name)

    def _may_lead(self, cause: Phrase, patience: float = 0.0) -> bool:
        """Without an arbiter, always; with one, once this station holds its lease (`patience`:
        seconds to keep trying, for a lease the partner is releasing as it hands over). A
        refusal is journaled once per cause."""
        lease = self.lease
        if lease is None:
            return True
        deadline = self.clock() + patience
        while not lease.take():
            if self.clock() >= deadline or self._stopping.is_set():
                if lease.last_error != self._waiting:  # once per cause, not per silent tick
                    self._waiting = lease.last_error
                    self.runtime.say("pair stays", logging.WARNING, letter=self.settings.letter,
                                     role=said_role(self.role), cause=cause, error=lease.last_error)
                return False
            self._stopping.wait(self.tick / 4)
        self._waiting = ""
        return True

    def _become(self, role: Role, cause: Phrase, patience: float = 0.0, code: int = 0) -> None:
        if role is Role.PRIMARY and self.role is not Role.PRIMARY and not self._may_lead(cause, patience):
            if self.role is Role.STARTING:
                role, cause = Role.STANDBY, phrase("lease held", cause=cause)
            else:
                return
        if role is not Role.PRIMARY and self.lease is not None:
            self.lease.release()
        with self._changed:
            old = self.role
            if old is role:
                self._decided.set()
                return
            self.role = role
            self._changed.notify_all()
        engine = self._engine
        assert engine is not None
        if code:
            self.cause = code
        if role is Role.PRIMARY:
            if old is Role.STANDBY:
                self.switchovers += 1
            said = words(self.runtime.station.Language)
            self.last_takeover = f"{time.strftime(said.stamp)}: {said.say(cause)}"
            engine.post(self._lead)
        else:
            engine.post(self._follow)
        self._decided.set()
        level = logging.WARNING if old is not Role.STARTING else logging.INFO
        self.runtime.say("pair role", level, letter=self.settings.letter, old=said_role(old),
                         new=said_role(role), cause=cause)

    def _lead(self, mem: Memory) -> None:
        """On the engine thread: the newest mirrored state, then the program runs on from it."""
        engine = self._engine
        assert engine is not None
        if engine.follower and self.mirror.complete:
            self._load_mirror(engine, mem)
            with self._lock:  # what the old primary may not have on disk: archived here, under its pids
                pending = self.mirror.take_pending()
                self._last_pid = max(self._last_pid, self.mirror.last_pid)
            self._archive(pending)
        engine.follower = False
        self._put_words(mem)

    def _load_mirror(self, engine: Engine, mem: Memory) -> None:
        """On the engine thread: the mirrored memory and engine state, and the alarm states."""
        with self._lock:
            self.mirror.load_into(engine, mem)
            alarms, silenced = self.mirror.take_alarms(), self.mirror.silenced
        if self.runtime.alarms is not None:
            self.runtime.alarms.follow_horn(silenced)
            self.runtime.alarms.adopt(alarms)

    def _follow(self, _mem: Memory) -> None:
        engine = self._engine
        assert engine is not None
        engine.follower = True

    def into_standby(self, cause: str, wait: float = 0.0) -> bool:
        """Hand the primary role to the standby (IntoStandBy) at the end of the next scan: that
        scan's state is the last frame, then the handover. False when this station is no primary
        with a standby on the link. `wait`: seconds to wait for the handover to be sent. `cause`
        is said in the station's language: the partner, whose Language is ours, journals it."""
        with self._changed:
            if self.role is not Role.PRIMARY or self._link is None:
                return False
            self._handing_over = cause
            self._handed.clear()
        if wait:
            self._handed.wait(wait)
        return True

    # --- the link ------------------------------------------------------------------------------

    def _accept(self) -> None:
        server = self._server
        assert server is not None
        while not self._stopping.is_set():
            try:
                conn, _peer = server.accept()
            except TimeoutError:
                continue
            except OSError:
                if not self._stopping.is_set():
                    logger.exception("pair link: accept failed")
                return
            if self._stopping.is_set():
                conn.close()
                return
            self._spawn_link(conn)

    def _dial(self) -> None:
        host, port = self.settings.partner_address
        while not self._stopping.is_set():
            if self._link is None:
                try:
                    conn = socket.create_connection((host, port), timeout=self.tick)
                except OSError:
                    self._stopping.wait(self.tick)
                    continue
                self._serve(conn)
            self._stopping.wait(self.tick)

    def _spawn_link(self, conn: socket.socket) -> None:
        threading.Thread(target=self._serve, args=(conn,), name="pair link", daemon=True).start()

    def _serve(self, conn: socket.socket) -> None:
        """One link, from hello to its end (a status query answered and closed, or the pair's)."""
        paired = greeting = False
        try:
            # longer than failover_after: the watch takes over first and tells the partner (TAKEN)
            conn.settimeout(self.failover + 1.0)
            with self._changed:
                self._greeting += 1
                greeting = True
            send_frame(conn, HELLO, json.dumps(self._hello()).encode())
            kind, payload = read_frame(conn)
            hello = json.loads(payload) if kind == HELLO else None
            if not isinstance(hello, dict) or "letter" not in hello:
                raise LinkError("the partner did not say hello")
            if hello.get("query"):
                return  # `main.py redundancy status`: our hello was the answer
            if not self._pairs_with(hello):
                return
            with self._changed:
                if self._link is not None:
                    old = self._link
                    old.close()
                self._link = conn
                self._last_frame = self.clock()
                self._whole_alarms = True
            self._become(decide(self.role, self.settings.letter, Role(hello["role"]), self.led_scans,
                                int(hello.get("led", 0))),
                         phrase("partner is", letter=hello["letter"], role=said_role(Role(hello["role"]))))
            self.refused = ""
            paired = True
            self._greeted()
            greeting = False
            self._run_link(conn)
        except (OSError, LinkError, ValueError) as e:
            if paired and not self._stopping.is_set() and conn is not self._told:  # told: journaled
                # a reset or a broken pipe is the partner's close met by a write (an ACK, a frame)
                closed = isinstance(e, (LinkClosed, BrokenPipeError, ConnectionResetError))
                self.runtime.say("pair link lost", logging.WARNING, letter=self.settings.letter,
                                 role=said_role(self.role), error=phrase("link closed")
                                 if closed else e or type(e).__name__)
            elif not self._stopping.is_set():
                logger.info("pair link ended: %s", e)
        finally:
            if greeting:
                self._greeted()
            with self._changed:
                if self._link is conn:
                    self._link = None
                alone = self._link is None  # else a new link's standby acknowledges what waits
                self._changed.notify_all()  # the link's sender ends
            self._handed.set()
            if conn is self._told:  # taken over on it: what the partner sends after TAKEN is
                _drain(conn)  # read, so that it reads TAKEN rather than a reset
            conn.close()
            if alone:
                self._mirrored(None)  # no standby to wait for: the primary's own commit stands

    def _greeted(self) -> None:
        """A link's hellos have crossed, or it ended before: a starting station waits no more for it."""
        with self._changed:
            self._greeting -= 1
            self._changed.notify_all()

    def _hello(self) -> dict[str, object]:
        return {"letter": self.settings.letter, "role": self.role.value, "led": self.led_scans,
                "files": self.files, "status": self.status().as_dict()}

    def _pairs_with(self, hello: dict[str, object]) -> bool:
        """The partner holds the same station, and the other letter; else refused, journaled."""
        theirs = hello.get("files")
        differ = differing(self.files, theirs if isinstance(theirs, dict) else {})
        if hello["letter"] == self.settings.letter:
            why = phrase("same letter", letter=self.settings.letter)
        elif differ:
            why = phrase("station differs", files=", ".join(differ))
        else:
            return True
        text = words(self.runtime.station.Language)("pair refused", letter=self.settings.letter, why=why)
        if text != self.refused:
            self.refused = text
            self.runtime.say("pair refused", logging.WARNING, letter=self.settings.letter, why=why)
        return False

    def _run_link(self, conn: socket.socket) -> None:
        """This thread reads every frame of the link whatever the role (the standby the primary's
        state, the primary its standby's acknowledgements as they come: its records and its
        writers wait for them); a thread of its own sends the primary's frames. The role may turn
        over on a handover."""
        threading.Thread(target=self._send_frames, args=(conn,), name="pair send", daemon=True).start()
        while not self._stopping.is_set():
            # the primary: a standby with nothing to acknowledge is no end
            if self.role is Role.PRIMARY and not select.select([conn], [], [], self.tick)[0]:
                if self._link is not conn:
                    return
                continue
            # the standby: a read that times out ends the link; the watch decided on a takeover first
            if self._received(*read_frame(conn), conn):
                return

    def _send_frames(self, conn: socket.socket) -> None:
        """The primary's frames on `conn`, each capture as the engine's listener hands it over
        (the engine thread never waits for the link), until the link ends."""
        encoder = Encoder()
        try:
            while not self._stopping.is_set():
                with self._changed:
                    self._changed.wait_for(lambda: self._capture is not None or bool(self._handover)
                                           or self._stopping.is_set() or self._link is not conn, self.tick)
                    if self._link is not conn:
                        return
                    if self.role is not Role.PRIMARY and not self._handover:
                        encoder.last = None  # if this station leads again, its first frame is whole
                        continue
                    cap, self._capture = self._capture, None
                    handover, self._handover = self._handover, ""
                if cap is not None:
                    self._send(conn, STATE, encoder.frame(cap))
                if handover:
                    if self.lease is not None:
                        self.lease.release()  # for the partner to take
                    self._send(conn, HANDOVER, json.dumps({"cause": handover}).encode())
                    self._handed.set()
        except OSError as e:  # the link's reading thread ends it and says why
            logger.info("pair link: a frame not sent: %s", e)
            with contextlib.suppress(OSError):
                conn.shutdown(socket.SHUT_RDWR)

    def _send(self, conn: socket.socket, kind: int, payload: bytes) -> None:
        with self._send_lock:
            send_frame(conn, kind, payload)

    def _received(self, kind: int, payload: bytes, conn: socket.socket) -> bool:
        """One frame from the partner; True when the link ends with it (TAKEN)."""
        if kind == STATE:
            with self._lock:
                if self._link is not conn:  # taken over: the mirror stays the scan TAKEN named
                    return False
                self.mirror.apply(payload)
                self._last_frame = self.clock()
                post = not self._load_pending
                self._load_pending = True
                scan, bdseq = self.mirror.scan, self.mirror.bdseq
            if post and self._engine is not None:
                self._engine.post(self._load)
            sparkplug = self.runtime.sparkplug()
            if sparkplug is not None and bdseq != self._bdseq:  # one edge node: the primary's session,
                self._bdseq = bdseq  # whose bdSeq this station goes on from, before it could lead
                sparkplug.follow(bdseq)
            self._send(conn, ACK, struct.pack(">q", scan))
        elif kind == ACK and len(payload) == 8:
            self._mirrored(struct.unpack(">q", payload)[0])
        elif kind == HANDOVER:
            cause = json.loads(payload).get("cause", "IntoStandBy")
            self._become(Role.PRIMARY, phrase("handed over", cause=cause), patience=self.failover,
                         code=HANDED_OVER)
        elif kind == TAKEN and len(payload) == 8:
            self._taken_over(struct.unpack(">q", payload)[0], conn)
            return True
        return False

    def _taken_over(self, scan: int, conn: socket.socket) -> None:
        """The standby took over from `scan` (it heard no frame of this primary's for
        failover_after: a stalled scan, a loaded PC) while this station lives: it follows at once
        rather than lead beside the partner. What the partner holds stands (its writers are
        answered, its records archived); what it does not, the partner runs again: the writers
        of those scans are not answered (as by a dead primary), their records not archived."""
        engine = self._engine
        assert engine is not None
        with self._changed:
            if self._link is conn:
                self._link = None
            if self.role is not Role.PRIMARY:
                return
            self.role = Role.STANDBY
            engine.follower = True  # the scan running now evaluates no alarm, and no write follows
            self._taken = True  # until the next scan: its records are the partner's to make
            self.switchovers += 1
            self.cause = TAKEN_OVER
            self._last_frame = self.clock()
            ready = [cb for at, cb in self._awaiting if at <= scan]
            self._awaiting = []
            keep = [records for at, records in self._held if at <= scan]
            dropped = sum(len(records) for at, records in self._held if at > scan) + len(self._records)
            self._held, self._records = [], []
            self._changed.notify_all()
        if self.lease is not None:
            self.lease.release()
        engine.post(self._followed)
        for records in keep:
            self._archive(records)
        for callback in ready:
            callback()
        self.runtime.say("pair handover", logging.WARNING, letter=self.settings.letter,
                         cause=phrase("taken over", scan=scan, ms=self.failover * 1000, dropped=dropped))

    def _followed(self, _mem: Memory) -> None:
        """On the engine thread, the scan after a TAKEN: the records from now on are this station's."""
        with self._lock:
            self._taken = False

    def hold(self, record: Record) -> bool:
        """The runtime's record, kept back while this station is the primary with a standby until
        the standby holds the scan that made it (a record of a scan the standby never got would
        be made again by the standby taking over from the scan before: twice in the plant
        archive). False: archive it now. A 'system' record (this station's own) is never held."""
        if record.kind == "system":
            return False
        with self._lock:
            if self._taken:
                return True  # a scan the new primary runs again
            if self.role is not Role.PRIMARY or self._link is None:
                return False
            # its identity in both archives: the standby keeps it until this station has it on
            # disk, and archives it if it takes over before (`_lead`)
            self._last_pid = pid = max(round(record.ts * 1000) << PID_SHIFT, self._last_pid + 1)
            r = record  # made whole rather than by dataclasses.replace: half the cost per record
            self._records.append(Record(r.ts, r.kind, r.grp, r.type, r.source, r.number, r.value, r.text,
                                        pid))
            return True

    def _archive(self, records: list[Record]) -> None:
        for record in records:
            self.runtime.archive(record)

    def after_mirrored(self, callback: Callable[[], None]) -> None:
        """`callback()` once the standby holds the scan running now (its acknowledgement of that
        scan's frame), at once without a standby: the runtime answers an outside write only then,
        so a write acknowledged by the primary is not lost when the standby takes over."""
        engine = self._engine
        with self._lock:
            if self.role is Role.PRIMARY and self._link is not None and engine is not None:
                self._awaiting.append((engine.scan_counter + 1, callback))
                return
        callback()

    def _mirrored(self, scan: int | None) -> None:
        """The standby holds `scan` (or None: it is gone): the records of the scans it holds are
        archived, then the callbacks waiting for them called (a writer is answered once its
        record is committed, Runtime.after_commit)."""
        with self._lock:
            ready = [cb for at, cb in self._awaiting if scan is None or at <= scan]
            self._awaiting = [] if scan is None else [(at, cb) for at, cb in self._awaiting if at > scan]
            records = [r for at, held in self._held if scan is None or at <= scan for r in held]
            self._held = [] if scan is None else [(at, held) for at, held in self._held if at > scan]
            if scan is None:
                records += self._records
                self._records = []
        self._archive(records)
        if records and scan is not None:  # the standby is told in a frame once they are on disk
            self.runtime.after_archived(lambda: self._committed(scan))
        for callback in ready:
            callback()

    def _committed(self, scan: int) -> None:
        """The records of the scans up to `scan` are on this station's disk: the next frame says
        so, and the standby forgets them (Mirror.pending)."""
        with self._lock:
            self._on_disk = max(self._on_disk, scan)

    def _load(self, mem: Memory) -> None:
        """On the engine thread: the newest mirrored state, while this station follows."""
        engine = self._engine
        assert engine is not None
        with self._lock:
            self._load_pending = False
        if engine.follower and self.mirror.complete:
            self._load_mirror(engine, mem)
        self._put_words(mem)

    def _put_words(self, mem: Memory) -> None:
        """This station's HSB status words (on the engine thread)."""
        status = self.status()
        mem.set_byte(HSB_NUM_PLC, 1 if self.settings.letter == "A" else 0)
        mem.set_byte(HSB_STATUS_BYTE, DEFECT if self.refused else HSB_STATUS[self.role])
        mem.set_word(DGN_HSB, (1 << 7 if self.refused else 0) | (0 if status.link else 1 << 9)
                     | (1 << 15 if self.switchovers else 0))
        mem.set_word(HSB_SWITCH, min(self.switchovers, 255) << 8 | self.cause)
        mem.set_byte(HSB_LAG, min(status.lag, 255))

    def _on_scan(self, snapshot: Snapshot) -> None:
        """An engine listener: the primary's scan, for the link's thread to send. A handover
        asked for happens here, between two scans: this scan's state is the last one sent, and
        from the next scan on this engine follows (writes still queued are refused, unapplied)."""
        engine = self._engine
        if engine is None:
            return
        self._put_words(engine.mem)  # for the next scan's program and snapshot
        if self.role is Role.PRIMARY:
            self.led_scans += 1
        with self._lock:  # this scan's records wait for the standby to hold it
            records, self._records = self._records, []
            mirrored: tuple[Record, ...] = ()
            if records and self.role is Role.PRIMARY and self._link is not None:
                self._held.append((snapshot.scan, records))
                mirrored, records = tuple(records), []
            on_disk = self._on_disk
        self._archive(records)  # no standby (any more): at once
        if self.role is not Role.PRIMARY or self._link is None:
            return
        alarms = self.runtime.alarms
        states = alarms.changes_for_standby(self._whole_alarms) if alarms is not None else {}
        self._whole_alarms = False
        sparkplug = self.runtime.sparkplug()
        cap = capture(engine, snapshot, states, sparkplug.bdseq if sparkplug is not None else -1,
                      alarms.horn.silenced_at if alarms is not None else 0.0, mirrored, on_disk)
        with self._changed:
            unsent = self._capture
            if unsent is not None and (unsent.alarms or unsent.records):  # not sent yet: none is lost
                cap = replace(cap, alarms={**unsent.alarms, **cap.alarms},
                              records=unsent.records + cap.records)
            self._capture = cap
            if self._handing_over:
                self._handover, self._handing_over = self._handing_over, ""
                self.role = Role.STANDBY
                engine.follower = True
                self.switchovers += 1
                self.cause = HANDED_OVER
                self._last_frame = self.clock()
            self._changed.notify_all()
        if self._handover:
            self.runtime.say("pair handover", logging.WARNING, letter=self.settings.letter,
                             cause=self._handover)

    def _watch(self) -> None:
        """The standby's watch on the primary's silence; the primary's on its lease: one that
        lost both its arbiter and its partner steps down, as the partner may lead by now."""
        while not self._stopping.wait(self.tick / 2):
            lease = self.lease
            if self.role is Role.PRIMARY and lease is not None and not lease.alive() \
                    and not lease.take() and self._link is None:
                self._become(Role.STANDBY, phrase("lost both", error=lease.last_error),
                             code=STEPPED_DOWN)
            if self.role is not Role.STANDBY:
                continue
            silent = self.clock() - self._last_frame
            if silent >= self.failover:
                cause = phrase("partner silent", ms=silent * 1000)
                if not self._may_lead(cause):  # the arbiter first: a primary it keeps is told nothing
                    continue
                self._tell_taken()
                self._become(Role.PRIMARY, cause, code=SILENT)

    def _tell_taken(self) -> None:
        """End the link on a takeover, telling the partner, if it still lives, the scan this
        station leads from (TAKEN): it follows then rather than lead beside this station. The link's
        thread reads on until the partner closes (or a second), so the partner reads TAKEN."""
        with self._changed:
            link, self._link = self._link, None
            scan = self.mirror.scan
            self._told = link
            self._changed.notify_all()
        if link is None:
            return
        try:
            self._send(link, TAKEN, struct.pack(">q", scan))
            link.shutdown(socket.SHUT_WR)
        except OSError as e:  # the partner is gone: nobody to tell
            logger.info("pair link: TAKEN not sent: %s", e)

    def _drop_link(self) -> None:
        with self._changed:
            link, self._link = self._link, None
            self._changed.notify_all()
        if link is not None:
            try:
                link.shutdown(socket.SHUT_RDWR)
            except OSError:
                logger.debug("pair link already down")
            link.close()

    # --- status --------------------------------------------------------------------------------

    def status(self) -> PairStatus:
        lag = 0
        if self.role is Role.STANDBY:
            lag = int((self.clock() - self._last_frame) / self.tick)
        return PairStatus(self.settings.letter, self.role.value, self.settings.partner,
                          self._link is not None, self.last_takeover, lag, self.switchovers)


def _drain(conn: socket.socket, wait: float = 1.0) -> None:
    """Read and drop what `conn` holds, until its end or `wait` seconds with nothing more."""
    try:
        conn.settimeout(wait)
        while conn.recv(65536):
            pass
    except TimeoutError:
        return
    except OSError as e:
        logger.debug("pair link drained: %s", e)


def query(address: str, timeout: float = 3.0) -> dict[str, object]:
    """The status of the station whose pair link listens at HOST:PORT (`main.py redundancy
    status`): its hello. LinkError or OSError when it does not answer."""
    from app.station.config import split_address

    host, port = split_address(address)
    with socket.create_connection((host, port), timeout=timeout) as conn:
        conn.settimeout(timeout)
        kind, payload = read_frame(conn)
        send_frame(conn, HELLO, json.dumps({"letter": "?", "query": True}).encode())
        if kind != HELLO:
            raise LinkError("no hello from the station")
        status = json.loads(payload).get("status")
        if not isinstance(status, dict):
            raise LinkError("the station's hello has no status")
        return status
