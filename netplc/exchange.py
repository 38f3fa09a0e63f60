"""Exchange with the PLC network: NODE / NREAD / NWRITE block requests over Modbus
(docs/architecture.md sections 1 and 7).

The scan never waits for the network. NREAD/NWRITE hand a block request to the exchange's thread
(Modbus TCP nodes: the selector thread of netplc/tcp_exchange.py; serial lines and pymodbus's
client: a task per node on an asyncio loop thread) and return at once with the node's link state;
while a request of an instruction is in flight, the instruction asks for nothing more. The results
come back through `engine.post`, so they are applied to memory at the start of a later scan, by
the engine thread, like every other write. Link-state changes reach the presence list
077740-077777 the same way.

Each node has its own connection, timeout, retries and reconnect back-off, so a dead or slow
node only ever delays its own requests (the nodes of one RS-485 line share its connection, one
transaction at a time, as they share the wire). While a node is backing off, its requests fail at once
(the instruction's output shows the link is down) and the first request after the back-off tries
to reconnect.

A link state is only as fresh as the last transaction, and NetPlc may ask a node nothing for a long
time (the program stopped, a rung that is rarely on). So a node without a request for
max(timeout, PROBE_IDLE) gets a liveness probe, a one-register read through the same attempts,
back-off and link-state path: the presence list, `link_up()` and the link up/down records never
show a dead node as up (nor, after its back-off, a live one as down) for longer than that plus the
timeouts of the probe. The probe asks register 0, which a device need not have: exception 1, 2
or 3 in answer to it is an answer, and the link is up.

A node that answers, but only with Modbus exceptions, serves no data either: one whose answers
are exceptions `retries + 1` times in a row (its budget of attempts), with one of its requests
refused twice in that run (so every request it is asked, not one bad address among good ones),
is down like a silent one: link down, presence 00, back-off, journaled once with the exception
("answers only exception 4 (server device failure)"); its first normal answer brings it up.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections import deque
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any

from netplc.address import PRESENCE_LIST, PRESENCE_NODES, AddressError, check_operand
from netplc.links import PROBE_IDLE as PROBE_IDLE  # where the probe's idle time is read
from netplc.links import LinkState, NodeStats, Request
from netplc.memory import Memory
from netplc.modbus import (
    PROFILES,
    TABLES,
    WRITABLE_TABLES,
    DeviceError,
    Endpoint,
    LinkError,
    LoopThread,
    MapError,
    locate,
    open_client,
    parse_endpoint,
)
from netplc.program import Diagnostic, Program
from netplc.records import NullSink, Record, RecordSink
from netplc.tcp_exchange import TcpHub, TcpNode
from netplc.words import Phrase, Say, WordedError, english, phrase, said

if TYPE_CHECKING:
    from netplc.engine import Engine
    from netplc.program import Instr

NODE, NREAD, NWRITE = 300, 301, 302

logger = logging.getLogger(__name__)


# What a node's settings may be (docs/architecture.md section 7); `node_problems` is the one check.
NODE_NUMBERS = (0, 255)  # the manual's node range, as in NODE S:n
UNITS = {"tcp": (0, 255), "rtu": (1, 247)}  # Modbus unit id per scheme (docs/architecture.md section 7)
LIMITS: dict[str, tuple[float, float]] = {"timeout": (0.01, 60.0), "retries": (0, 10),
                                          "backoff": (0.01, 600.0), "backoff_max": (0.01, 3600.0)}
NAME_RESERVED = "/+#"  # a node's name is a level of MQTT topics (Sparkplug device id) and of paths
Problem = tuple[str, Phrase]  # (setting, what is wrong with it: a phrase of netplc/words.py)


def unit_problem(scheme: str, unit: int) -> Phrase | None:
    """Why `unit` cannot address a device over `scheme` (tcp or rtu), or None."""
    lo, hi = UNITS[scheme]
    if lo <= unit <= hi:
        return None
    why = "" if scheme == "tcp" else phrase("node unit why")
    return phrase("node unit", unit=unit, lo=lo, hi=hi, scheme=scheme, why=why)


def node_problems(settings: Mapping[str, Any]) -> tuple[Endpoint | None, list[Problem]]:
    """The parsed endpoint (None while there is none) and every setting of a node that is out of
    bounds, by its station.toml key: the one node validation, which NodeConfig raises and
    station.toml's reader (app/station/config.py) reports key by key."""
    found: list[Problem] = []
    node = settings["node"]
    lo, hi = NODE_NUMBERS
    if not isinstance(node, int) or isinstance(node, bool) or not lo <= node <= hi:
        found.append(("node", phrase("node outside", node=node, lo=lo, hi=hi)))
    endpoint = None
    if settings["endpoint"]:
        try:
            endpoint = parse_endpoint(settings["endpoint"])
        except WordedError as e:
            found.append(("endpoint", e.phrase))
    if problem := unit_problem(endpoint.scheme if endpoint else "tcp", settings["unit"]):
        found.append(("unit", problem))
    for key, names in (("profile", PROFILES), ("table", TABLES)):
        if settings[key] not in names:
            found.append((key, phrase("node not one of", value=settings[key], names=", ".join(names))))
    for key, (least, most) in LIMITS.items():
        value = settings[key]
        if not least <= value <= most:
            if key == "retries":  # a count, perhaps of 400 digits: not a float
                found.append((key, phrase("node count outside", value=value, least=least, most=most)))
            else:
                found.append((key, phrase("node seconds outside", value=value, least=least, most=most)))
    name = settings["name"]
    if any(c in name for c in NAME_RESERVED) or not name.isprintable() or name != name.strip():
        found.append(("name", phrase("node name", name=name)))
    backoff, backoff_max = settings["backoff"], settings["backoff_max"]
    if not any(key.startswith("backoff") for key, _ in found) and backoff > backoff_max:
        found.append(("backoff", phrase("node backoff", backoff=backoff, most=backoff_max)))
    return endpoint, found


@dataclass
class NodeConfig:
    """One remote node: where it is and how to talk to it. The one model of a node: station.toml's
    [[nodes]] tables and embedded simulators become these (app/station/config.py), the exchange runs them.
    ValueError names the node and every setting that is out of bounds."""

    node: int
    endpoint: str  # tcp://host:port or rtu://device?...; "" until a simulator on port 0 fills it in
    unit: int = 1
    profile: str = "cpu165"
    timeout: float = 1.0  # seconds per attempt
    retries: int = 1  # further attempts after a failed one
    table: str = "holding"  # profile "modbus": holding, input, coils or discrete
    backoff: float = 0.2  # first reconnect delay after the link went down, seconds
    backoff_max: float = 5.0  # the delay doubles up to this
    name: str = ""  # what the station calls the node (its Sparkplug device id); "": Node<n>
    key: str = field(default="nodes", compare=False)  # where station.toml sets it (nodes[2]), for messages

    def __post_init__(self) -> None:
        endpoint, found = node_problems(vars(self))
        if found:
            raise ValueError(f"node {self.node}: " + "; ".join(_named(p) for p in found))
        self.parsed: Endpoint | None = endpoint

    @property
    def title(self) -> str:
        """The node's name, or Node<n> where it has none: unique among a station's nodes."""
        return self.name or f"Node{self.node}"

    @classmethod
    def settled(cls, settings: dict[str, Any], key: str) -> tuple[NodeConfig | None, list[Problem]]:
        """A node from station.toml's `settings`: every problem by setting, and the node with each
        bad setting at its default (a bad back-off pair both), so that one pass over the file finds
        every problem; None when the node number itself is bad."""
        _, found = node_problems({**NODE_DEFAULTS, **settings})
        bad = {setting for setting, _ in found}
        if "node" in bad:
            return None, found
        if bad & {"backoff", "backoff_max"}:
            bad |= {"backoff", "backoff_max"}
        return cls(**{**NODE_DEFAULTS, **settings, **{k: NODE_DEFAULTS[k] for k in bad}}, key=key), found


NODE_DEFAULTS: dict[str, Any] = {"endpoint": "", **{f.name: f.default for f in fields(NodeConfig)
                                                   if f.name not in ("node", "endpoint", "key")}}


def _named(problem: Problem) -> str:
    """A problem as a sentence: its text, after its setting unless the text names it already
    (`unit 256 is not 0-255 on tcp`, `endpoint 'x': ...`)."""
    key, phrase = problem
    text = str(said(english, phrase))
    return text if text.startswith(f"{key} ") else f"{key} {text}"


def shared_problems(nodes: Iterable[NodeConfig]) -> list[tuple[NodeConfig, Problem]]:
    """What nodes get wrong together, each named on the later node: a number configured twice, a
    name given twice (or the Node<n> of a node without one), and nodes of one serial port with
    different line settings (they share one line)."""
    found: list[tuple[NodeConfig, Problem]] = []
    numbers: set[int] = set()
    titles: dict[str, int] = {}  # name -> the first node called so
    lines: dict[str, NodeConfig] = {}  # serial device -> the first node on it
    for cfg in nodes:
        if cfg.node in numbers:
            found.append((cfg, ("node", phrase("node twice", node=cfg.node))))
        elif titles.setdefault(cfg.title, cfg.node) != cfg.node:
            found.append((cfg, ("name", phrase("node title used", title=cfg.title, node=titles[cfg.title]))))
        numbers.add(cfg.node)
        ep = cfg.parsed
        if ep is not None and ep.scheme == "rtu":
            first = lines.setdefault(ep.device, cfg)
            if first.parsed != ep:
                found.append((cfg, ("endpoint", phrase("node shared line", endpoint=str(ep), node=first.node,
                                                       first=str(first.parsed), device=ep.device))))
    return found


class _Line:
    """One asyncio connection: a serial RS-485 line shared by the nodes on it, whose transactions
    the lock keeps one at a time (a silent slave holds its line for the timeout, as it would on the
    wire, but never another line), or a TCP node's own through pymodbus's client."""

    def __init__(self, endpoint: Endpoint, timeout: float, lean: bool) -> None:
        self.client = open_client(endpoint, timeout, lean)
        self.serial = endpoint.scheme == "rtu"
        self.lock = asyncio.Lock()

    def failed(self) -> None:
        """After a transport failure: a TCP connection is dropped and made again for the next
        attempt; a serial port stays open (a timeout is the slave's, not the port's) unless the
        port itself went away."""
        if not self.serial or not self.client.connected:
            self.client.close()


class _Node(LinkState):
    """A node served by an asyncio task on the exchange's loop thread (serial lines, pymodbus's
    TCP client): the same link state and request steps as the TCP hot path's."""

    def __init__(self, config: NodeConfig, exchange: Exchange, stats: NodeStats, line: _Line) -> None:
        super().__init__(config, exchange, stats)
        self.line = line
        self.client = line.client
        self.queue: asyncio.Queue[Request] = asyncio.Queue()
        self.busy = False  # a request or probe is being served

    async def run(self) -> None:
        watch = asyncio.get_running_loop().create_task(self.watch(), name=f"node {self.config.node} probe")
        try:
            while True:
                req = await self.queue.get()
                self.busy = True
                try:
                    req.data, req.error = await self.serve(req)
                except Exception as e:  # a bug must not end the node's task, nor show the link up
                    logger.exception("node %d: request failed inside the exchange", self.config.node)
                    self.line.failed()
                    req.data, req.error = None, f"internal error: {e!r}"
                    self.down(req.error)
                self.active, self.busy = time.monotonic(), False
                if req is not self.probe:
                    self.exchange.complete(self, req)
        finally:
            watch.cancel()
            self.client.close()

    async def watch(self) -> None:
        """Queue a probe once the node has been idle for `idle` (and its back-off has run out)."""
        while True:
            due = max(self.active + self.idle, self.retry_at)
            now = time.monotonic()
            if self.busy or not self.queue.empty():  # the link state comes with the requests
                await asyncio.sleep(self.idle)
            elif now < due:
                await asyncio.sleep(due - now)
            else:
                self.active = now
                self.stats.probes += 1
                self.queue.put_nowait(self.probe)

    async def serve(self, req: Request) -> tuple[bytes | None, str]:
        if req is not self.probe and time.monotonic() < self.retry_at:
            return None, self.stats.last_error or "link down"
        steps, where = self.steps(req)
        if steps is None:
            return None, where
        try:
            result = await self.attempts(req)
        except (DeviceError, MapError, LinkError) as e:
            return None, self.failed(e, where, req.key)
        self.answered()
        return result, ""

    async def attempts(self, req: Request) -> bytes:
        """The request's steps, started over after a failed attempt while the node's retries last."""
        for attempt in range(self.config.retries + 1):
            try:
                if not self.line.serial:  # a TCP node's connection is its own: nothing to share
                    return await self.drive(req)
                async with self.line.lock:
                    return await self.drive(req)
            except LinkError:
                self.line.failed()
                if attempt == self.config.retries:
                    raise
        raise AssertionError("unreachable")

    async def drive(self, req: Request) -> bytes:
        if not self.client.connected:
            await self.client.connect()
        steps, _ = self.steps(req)
        assert steps is not None
        answer = None
        unit, client = self.config.unit, self.client
        try:
            while True:
                frame = steps.send(answer)  # type: ignore[arg-type]
                if frame.values is None:
                    answer = await client.read_bytes(unit, frame.table, frame.address, frame.count)
                else:
                    await client.write(unit, frame.table, frame.address, frame.values)
                    answer = b""
        except StopIteration as done:
            return done.value


class _LoopLinks:
    """The asyncio nodes' side of the hand-over from the engine thread: one wake-up of the loop per
    batch of requests, not one per request."""

    def __init__(self) -> None:
        self.thread = LoopThread("netplc-exchange")
        self.nodes: dict[int, _Node] = {}
        self.outbox: deque[Request] = deque()
        self.wake = False

    def submit(self, req: Request) -> None:
        self.outbox.append(req)
        if not self.wake:
            self.wake = True
            self.thread.call(self.dispatch)

    def dispatch(self) -> None:
        self.wake = False  # first: a request appended from now on schedules another wake-up
        outbox, nodes = self.outbox, self.nodes
        while outbox:
            req = outbox.popleft()
            nodes[req.node].queue.put_nowait(req)


class Exchange:
    """Implements `NetLink` for the engine: block requests to configured nodes over Modbus. Modbus
    TCP nodes are served by the hot path (netplc/tcp_exchange.py), serial lines and pymodbus's
    client by asyncio tasks."""

    def __init__(self, nodes: list[NodeConfig], sink: RecordSink | None = None, *, lean: bool = True) -> None:
        self.lean = lean  # our own Modbus TCP hot path; False: pymodbus's client (bench/exchange.py compares)
        for cfg in nodes:
            if cfg.parsed is None:
                raise ValueError(f"node {cfg.node}: no endpoint")
        for cfg, (key, text) in shared_problems(nodes):
            raise ValueError(f"node {cfg.node}: {key}: {said(english, text)}")
        self.configs: dict[int, NodeConfig] = {cfg.node: cfg for cfg in nodes}
        self.sink: RecordSink = sink or NullSink()
        self.words: Say = english  # the station's words for its records (netplc/words.py)
        self.engine: Engine | None = None
        self.stats: dict[int, NodeStats] = {
            n: NodeStats(n, str(cfg.parsed)) for n, cfg in self.configs.items()
        }
        self._hub: TcpHub | None = None
        self._loop: _LoopLinks | None = None
        # node -> how the engine thread hands it a request (the TCP hub's or the loop's submit)
        self._targets: dict[int, Callable[[Request], None]] = {}
        # Touched by the engine thread only: instruction keys with a request in flight, the nodes
        # whose link is up as of this scan (changes arrive with the presence-list update), and
        # each NREAD's request, made once and sent again whenever the instruction asks anew.
        self._inflight: set[int] = set()
        self._present: set[int] = set()
        self._reads: dict[int, Request] = {}
        # NREAD key -> the scan at the start of which its data last landed (data age for quality)
        self.refreshed: dict[int, int] = {}
        self._done: deque[Request] = deque()  # finished requests, applied at the start of a scan
        self._applying = False  # an `_apply` is posted to the engine and has not started

    # --- wiring ----------------------------------------------------------------------------------

    def attach(self, engine: Engine) -> None:
        """Results and presence-list changes go to `engine.post`; the engine's NREAD/NWRITE call us."""
        self.engine = engine
        engine.exchange = self

    def start(self) -> None:
        if self.engine is None:
            raise RuntimeError("Exchange.attach(engine) must come before start()")
        self._post_reset()
        lines: dict[str, _Line] = {}
        for n, cfg in self.configs.items():
            ep = cfg.parsed
            assert ep is not None
            if ep.scheme == "tcp" and self.lean:
                hub = self._hub = self._hub or TcpHub()
                hub.add(TcpNode(cfg, self, self.stats[n], hub))
                self._targets[n] = hub.submit
                continue
            links = self._loop = self._loop or _LoopLinks()
            if ep.scheme == "rtu":  # the nodes of one serial port share its line
                if ep.device not in lines:
                    timeout = max(c.timeout for c in self.configs.values()
                                  if c.parsed is not None and c.parsed.device == ep.device)
                    lines[ep.device] = _Line(ep, timeout, self.lean)
                line = lines[ep.device]
            else:
                line = _Line(ep, cfg.timeout, self.lean)
            links.nodes[n] = _Node(cfg, self, self.stats[n], line)
            self._targets[n] = links.submit
        if self._hub is not None:
            self._hub.start()
        if self._loop is not None:
            self._loop.thread.start()
            self._loop.thread.run(self._spawn(self._loop))

    @staticmethod
    async def _spawn(links: _LoopLinks) -> None:
        for n, node in links.nodes.items():
            asyncio.get_running_loop().create_task(node.run(), name=f"node {n}")

    def stop(self) -> None:
        hub, loop, self._hub, self._loop = self._hub, self._loop, None, None
        self._targets.clear()
        if hub is not None:
            hub.stop()
        if loop is not None:
            loop.thread.stop()
        for stats in self.stats.values():
            stats.up = False
        if self.engine is not None:
            self._post_reset()

    def _post_reset(self) -> None:
        """No link and nothing in flight as of the next scan (requests of a stopped run never complete)."""
        inflight, present, nodes, done = self._inflight, self._present, list(self.configs), self._done

        def reset(mem: Memory) -> None:
            inflight.clear()
            present.clear()
            done.clear()
            for n in nodes:
                if n < PRESENCE_NODES:
                    mem.set_byte(PRESENCE_LIST + n, 0)

        assert self.engine is not None
        self.engine.post(reset)

    # --- NetLink (called by NREAD/NWRITE on the engine thread) -----------------------------------

    def link_up(self, node: int) -> bool:
        stats = self.stats.get(node)
        return stats is not None and stats.up

    @property
    def in_flight(self) -> int:
        """Requests handed to the nodes whose outcome has not reached memory yet."""
        return len(self._inflight)

    def link_known(self, node: int) -> bool:
        """The node has had its first exchange attempt (up or down is known, not assumed)."""
        stats = self.stats.get(node)
        return stats is not None and stats.changed > 0

    def request_read(self, key: int, node: int, remote: int, local: int, length: int) -> bool:
        if key in self._inflight:  # the usual case at a fast tick: nothing to do
            return node in self._present
        req = self._reads.get(key)
        if req is None or (req.node, req.remote, req.local, req.length) != (node, remote, local, length):
            req = self._reads[key] = Request(key, node, remote, local, length)
        return self._request(req)

    def request_write(self, key: int, node: int, remote: int, payload: bytes) -> bool:
        if key in self._inflight:
            return node in self._present
        return self._request(Request(key, node, remote, payload=bytes(payload)))

    def _request(self, req: Request) -> bool:
        submit = self._targets.get(req.node)
        if submit is None:
            return False
        self._inflight.add(req.key)
        req.scan = self.engine.scan_counter if self.engine is not None else 0
        submit(req)
        return req.node in self._present

    # --- back on the engine thread ---------------------------------------------------------------

    def complete(self, node: LinkState, req: Request) -> None:
        """A request is done (exchange thread): count it; its result is applied at the next scan,
        with every other result that is done by then, by one function posted to the engine."""
        stats = node.stats
        if req.error:
            stats.errors += 1
            stats.last_error = req.error
        elif req.payload is None:
            stats.reads += 1
        else:
            stats.writes += 1
        self._done.append(req)
        if not self._applying:
            self._applying = True
            assert self.engine is not None
            self.engine.post(self._apply)

    def _apply(self, mem: Memory) -> None:
        self._applying = False  # first: a request done from now on posts another `_apply`
        done, inflight, refreshed, stats = self._done, self._inflight, self.refreshed, self.stats
        assert self.engine is not None
        scan = self.engine.scan_counter
        while done:
            req = done.popleft()
            inflight.discard(req.key)
            data = req.data
            if data:
                node = stats[req.node]
                node.age = age = scan - req.scan
                if age > node.age_max:
                    node.age_max = age
                mem.write(req.local, data)
                if req.payload is None:
                    refreshed[req.key] = scan

    def link_changed(self, node: LinkState, up: bool, error: str) -> None:
        n = node.config.node
        name = "link up" if up else "link down because" if error else "link down"
        self.sink.put(Record(time.time(), "system", source=f"node {n}", number=n, value=1.0 if up else 0.0,
                             text=self.words(name, node=n, endpoint=node.stats.endpoint, error=error)))
        present = self._present

        def apply(mem: Memory) -> None:
            if up:
                present.add(n)
            else:
                present.discard(n)
            if n < PRESENCE_NODES:
                mem.set_byte(PRESENCE_LIST + n, 0xFF if up else 0x00)

        assert self.engine is not None
        self.engine.post(apply)


def _fon_nodes(program: Program) -> list[tuple[int, int, Instr, int | None]]:
    """(index, function, instruction, node it talks to) of each NREAD and NWRITE: the nearest NODE
    above it in the text; node 0 when the program has no NODE; None above the first NODE (the last
    NODE of the previous scan). Over the FONs alone: a plant program is mostly contacts and coils."""
    fons = [(k, ins) for k, ins in enumerate(program.instrs) if ins.op == "FON"]
    current: int | None = None if any(ins.n == NODE for _, ins in fons) else 0
    out = []
    for k, ins in fons:
        if ins.n == NODE:
            current = ins.s
        elif ins.n in (NREAD, NWRITE):
            out.append((k, ins.n, ins, current))
    return out


def check_program_nodes(program: Program, nodes: list[NodeConfig]) -> list[Diagnostic]:
    """Load-time check of the program's network instructions against the configured nodes.

    Every NODE must name a configured node; an NREAD/NWRITE before any NODE talks to node 0 (the
    engine's initial node), which must then be configured. The remote block is checked against
    the profile of the node selected by the nearest NODE above it, and the local block against
    NetPlc memory.
    """
    configs = {c.node: c for c in nodes}
    have: object = ", ".join(str(n) for n in sorted(configs)) or phrase("stl no nodes")
    out: list[Diagnostic] = []

    def err(ins: Instr, name: str, /, **values: object) -> None:
        out.append(Diagnostic(program.source, ins.line, 1, phrase(name, **values)))

    for ins in program.instrs:
        if ins.op == "FON" and ins.n == NODE and ins.s not in configs:
            err(ins, "stl node not configured", node=ins.s, have=have)
    for _, fn, ins, node in _fon_nodes(program):
        name = "NREAD" if fn == NREAD else "NWRITE"
        remote, local = (ins.s, ins.d) if fn == NREAD else (ins.d, ins.s)
        length = ins.r or 0
        try:
            check_operand(local, length)
        except AddressError as e:
            err(ins, "stl local block", name=name, length=length, error=e)
        if node is None:
            continue
        cfg = configs.get(node)
        if cfg is None:
            if not any(i.op == "FON" and i.n == NODE for i in program.instrs):
                err(ins, "stl no node", name=name, have=have)
            continue  # otherwise its NODE is reported above
        try:
            block = locate(cfg.profile, cfg.table, remote, length)
        except MapError as e:
            err(ins, "stl node map", name=name, node=node, error=e)
            continue
        if fn == NWRITE and block.table not in WRITABLE_TABLES:
            err(ins, "stl read only", node=node, table=block.table)
    return out
