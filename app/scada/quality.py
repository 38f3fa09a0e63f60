"""Data quality: whether a value in NetPlc memory can be trusted, derived and never configured.

The program's NREADs say which node fills which bytes (known at load time: the nearest NODE above
each NREAD, as the exchange itself resolves it). At run time the node's link, the age of the
block's data in scans, NetPlc's run state and forcing give each address its quality:

- forced: the value is forced by an engineer (it is what it is, but not the plant's);
- not running: NetPlc is stopped or halted, so nothing in memory changes any more. The value
  cannot be trusted (bad), but no quality alarm comes of it: a deliberate stop would flood the
  alarm list with one per tag. One station alarm says it instead (NETPLC.STOPPED,
  app/scada/station.py), and the tags' alarms are frozen where they were (`Quality.alarmed`);
- comm-fail: the node whose NREAD fills the address is down (its answers fail or are malformed);
- stale: the NREAD asks (its rung is on) but its data has not landed for more than STALE_TICKS
  scans beyond the one scan an answer normally takes;
- initial: nothing is known yet, so the value is not the plant's, but nothing has failed either:
  the node has not had its first exchange attempt since the station started, or NetPlc has just
  started (again) and the node's first data since then is still within its normal time to land.
  It is shown like any quality that is not good, but it is not bad: no quality alarm comes of
  it (every start would otherwise raise one per tag before the first answer), and process alarms
  wait for the first real value (`Quality.held`). It turns into good when the data lands, into
  comm-fail when the first attempt fails, into stale when the data is late;
- good: anything else, including what the program computes itself while it runs;
- station unreachable: only at a remote console (app/gui/console/), whose link to the station is
  lost: what it shows is the last it knew, not the plant's now.

Qualities are ordered so that the worst of several blocks (a tag spanning two NREADs) is the
highest; an address no NREAD fills is good while NetPlc runs.

An NREAD's or NWRITE's link output (C+1) is the program's copy of its node's link, frozen while
NetPlc is stopped. Readers show the link itself there (`link_outputs`, `Readings.live`): a
"связь есть" label follows the link, not the last value the program wrote.

Forcing (netplc/forcing.py) reaches quality through one hook: `LinkView.forced`, the forced
operand addresses of the scan, which the runtime fills from the snapshot's forces
(`Force.operands`, app/scada/station.py).
"""

from __future__ import annotations

import functools
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass
from enum import IntEnum

from app.scada.tag import Tag, span
from netplc.address import IO_BITS
from netplc.exchange import NODE, NREAD, NWRITE, _fon_nodes
from netplc.lazy import lazy
from netplc.memory import MemoryView
from netplc.program import Instr, Program

np = lazy("numpy")  # loaded at first use: only a station with tags or forms needs it

STALE_TICKS = 2  # scans of lateness tolerated beyond the normal one-scan answer
NORMAL_AGE = 1  # scans from a request to its data in memory, normally


class Quality(IntEnum):
    GOOD = 0
    INITIAL = 1
    STALE = 2
    COMM_FAIL = 3
    NOT_RUNNING = 4
    FORCED = 5
    UNREACHABLE = 6  # a remote console's: the link to the station is lost (never the station's own)

    @property
    def word(self) -> str:
        """The word an operator reads in a tooltip or a journal record."""
        return _WORDS[self]

    @property
    def bad(self) -> bool:
        """The value cannot be trusted (forced is shown, but it is not bad: someone chose it)."""
        return self in (Quality.STALE, Quality.COMM_FAIL, Quality.NOT_RUNNING, Quality.UNREACHABLE)

    @property
    def alarmed(self) -> bool:
        """A tag's quality alarm comes of it: the plant's data is failing. Not running and initial
        hold a tag's alarms, its quality alarm too, where they are: NetPlc's own state is one
        station alarm, and nothing has failed yet while the first data is on its way."""
        return self in (Quality.STALE, Quality.COMM_FAIL)

    @property
    def held(self) -> bool:
        """Process alarms wait: the value says nothing about the plant (bad, or not known yet)."""
        return self.bad or self is Quality.INITIAL


_WORDS = {Quality.GOOD: "good", Quality.INITIAL: "initial", Quality.STALE: "stale",
          Quality.COMM_FAIL: "comm-fail", Quality.NOT_RUNNING: "not running", Quality.FORCED: "forced",
          Quality.UNREACHABLE: "station unreachable"}


@functools.cache
def code_flags() -> tuple[np.ndarray, np.ndarray]:
    """Alarmed and held, indexed by quality code: made at first use (numpy loads with tags)."""
    return (np.array([q.alarmed for q in Quality], dtype=bool),
            np.array([q.held for q in Quality], dtype=bool))


MAX_SPANS = 65536  # operand spans whose feeding NREADs are kept (QualityMap.feeding)


@dataclass(frozen=True, slots=True)
class Feed:
    """One NREAD: the node it asks, its coil (1 while the rung asks) and what it fills."""

    key: int  # the FON's instruction index, as the exchange knows the request
    node: int
    coil: int
    first: int  # [first, last) in the HMI bit space (I/O bit n = n, data byte b = bits 8b..8b+7)
    last: int
    line: int = 0  # of the program text, for messages


Exchanges = list[tuple[int, int, Instr, int]]  # (index, NREAD or NWRITE, instruction, node)


def _exchanges(program: Program) -> Exchanges:
    """(index, function, instruction, node) of every NREAD and NWRITE. One above the first NODE
    talks to the node of the last NODE in the text (the one selected when the previous scan ended)."""
    nodes = [i.s for i in program.instrs if i.op == "FON" and i.n == NODE]
    wrap = nodes[-1] if nodes else 0
    return [(k, fn, ins, wrap if node is None else node) for k, fn, ins, node in _fon_nodes(program)]


def nread_feeds(program: Program, exchanges: Exchanges | None = None) -> list[Feed]:
    """Every NREAD of the program with the node it talks to and the bytes it fills."""
    feeds = []
    for k, fn, ins, node in _exchanges(program) if exchanges is None else exchanges:
        if fn == NREAD:
            first, last = span(ins.d or 0, ins.r or 0)
            feeds.append(Feed(k, node, ins.c or 0, first, last, ins.line))
    return feeds


def link_outputs(program: Program, exchanges: Exchanges | None = None) -> dict[int, int]:
    """The link output bit (C+1) of every NREAD and NWRITE -> the node whose link it copies."""
    found = _exchanges(program) if exchanges is None else exchanges
    return {(ins.c or 0) + 1: node for _, fn, ins, node in found if fn in (NREAD, NWRITE)}


@dataclass(frozen=True)
class LinkView:
    """What the quality of a scan depends on besides memory (the runtime fills it per scan)."""

    running: bool = True  # NetPlc runs its program
    links: Mapping[int, bool] | None = None  # node -> link up; None: every node is up
    refreshed: Mapping[int, int] | None = None  # NREAD key -> scan its data last landed; None: now
    forced: Collection[int] = ()  # forced operand addresses: I/O bits and data bytes
    # node -> the scan from which its data is expected: the first scan of this run of NetPlc in
    # which the node's link state was known (its first exchange attempt done). A node not in it
    # is initial; None: every node's data has been expected for long.
    since: Mapping[int, int] | None = None


class Operands:
    """Spans of the HMI bit space grouped by the set of NREAD blocks they overlap (usually a
    handful of groups), so that a scan judges each group once and every span by one numpy gather:
    the station's tags, or the operands a large HMI form shows."""

    def __init__(self, feeds: Sequence[Feed], spans: Sequence[tuple[int, int]]) -> None:
        groups: dict[tuple[int, ...], int] = {}
        members = []
        for first, last in spans:
            fed = tuple(k for k, f in enumerate(feeds) if f.first < last and first < f.last)
            members.append(groups.setdefault(fed, len(groups)))
        self.groups = list(groups)  # group -> indexes into the feeds
        self.member = np.array(members, dtype=np.intp)
        bounds = np.array(spans, dtype=np.int64).reshape(-1, 2)
        self.first, self.last = bounds[:, 0], bounds[:, 1]
        self.used = sorted({k for g in self.groups for k in g})  # the feeds any span depends on

    def evaluate(self, per_feed: Mapping[int, Quality], running: bool, forced: Collection[int]) -> np.ndarray:
        """Each span's quality code, from the quality of each feed in `used`."""
        idle = Quality.GOOD if running else Quality.NOT_RUNNING
        per_group = np.array([max((per_feed[k] for k in g), default=idle) for g in self.groups],
                             dtype=np.int8)
        out = per_group[self.member] if len(self.member) else np.zeros(0, dtype=np.int8)
        for addr in forced:
            first, last = _forced(addr)
            out[(self.first < last) & (first < self.last)] = Quality.FORCED
        return out


class QualityMap:
    """Which NREADs fill each tag, worked out once at load time; per scan, every tag's quality."""

    def __init__(self, program: Program, tags: Sequence[Tag]) -> None:
        exchanges = _exchanges(program)  # once: a plant program has thousands of instructions
        self.feeds = nread_feeds(program, exchanges)
        self.link_bits = link_outputs(program, exchanges)
        self.tags = list(tags)
        self._tags = Operands(self.feeds, [t.footprint() for t in self.tags])
        self._pos = {t.name: i for i, t in enumerate(self.tags)}
        # operand span -> the NREADs that fill it: an HMI form asks about thousands of operands on
        # every refresh, and a plant program has hundreds of NREADs to look through for each
        self._over: dict[tuple[int, int], tuple[Feed, ...]] = {}

    def position(self, name: str) -> int:
        """The index of a tag in `tags` and in what `evaluate` returns (KeyError if none)."""
        return self._pos[name]

    def fed_by(self, tag: Tag) -> list[Feed]:
        """The NREADs whose block overlaps the tag."""
        return [self.feeds[k] for k in self._tags.groups[self._tags.member[self._pos[tag.name]]]]

    def feed_quality(self, feed: Feed, view: MemoryView, links: LinkView, scan: int) -> Quality:
        if not links.running:
            return Quality.NOT_RUNNING
        since = None
        if links.since is not None:
            since = links.since.get(feed.node)
            if since is None:
                return Quality.INITIAL
        if links.links is not None and not links.links.get(feed.node, False):
            return Quality.COMM_FAIL
        if links.refreshed is not None and view.get_bit(feed.coil):
            landed = links.refreshed.get(feed.key)
            if since is not None and (landed is None or landed < since):  # nothing since the start
                late = scan - since > NORMAL_AGE + STALE_TICKS
                return Quality.STALE if late else Quality.INITIAL
            if landed is None or scan - landed > NORMAL_AGE + STALE_TICKS:
                return Quality.STALE
        return Quality.GOOD

    def evaluate(self, view: MemoryView, links: LinkView | None = None,
                 scan: int | None = None) -> np.ndarray:
        """Every tag's quality code (a `Quality` value) as of this snapshot, in the order of tags."""
        return self.judge(self._tags, view, links, scan)

    def operands(self, operands: Sequence[tuple[int, int]]) -> Operands:
        """Operands as `at` takes them, (address, bytes), grouped for `judge`. A link output bit
        among them is judged by its own rule (`at`): `judge` leaves it to the caller."""
        return Operands(self.feeds, [(a, a + 1) if n == 0 else span(a, n) for a, n in operands])

    def judge(self, operands: Operands, view: MemoryView, links: LinkView | None = None,
              scan: int | None = None) -> np.ndarray:
        """The quality code of every operand of `operands` as of this snapshot."""
        links = links or LinkView()
        scan = getattr(view, "scan", 0) if scan is None else scan
        per_feed = {k: self.feed_quality(self.feeds[k], view, links, scan) for k in operands.used}
        return operands.evaluate(per_feed, links.running, links.forced)

    def at(self, address: int, nbytes: int, view: MemoryView, links: LinkView | None = None) -> Quality:
        """The quality of any address, tag or not: `nbytes` bytes of operand at an I/O bit or data
        address, or with `nbytes` 0 the one bit of an HMI bit address (02042, 040005)."""
        links = links or LinkView()
        first, last = (address, address + 1) if nbytes == 0 else span(address, nbytes)
        for addr in links.forced:
            f_first, f_last = _forced(addr)
            if f_first < last and first < f_last:
                return Quality.FORCED
        node = self.link_bits.get(address) if nbytes == 0 and links.links is not None else None
        if node is not None:  # a link output shows the link itself (`Readings.live`), known or not
            known = links.since is None or node in links.since or not links.running
            return Quality.GOOD if known else Quality.INITIAL
        scan = getattr(view, "scan", 0)
        fed = [self.feed_quality(f, view, links, scan) for f in self.feeding(first, last)]
        return max(fed, default=Quality.GOOD if links.running else Quality.NOT_RUNNING)

    def feeding(self, first: int, last: int) -> tuple[Feed, ...]:
        """The NREADs whose block overlaps [first, last) of the HMI bit space."""
        over = self._over.get((first, last))
        if over is None:
            if len(self._over) >= MAX_SPANS:
                self._over.clear()  # asked about more spans than a station has operands: start afresh
            over = self._over[first, last] = tuple(f for f in self.feeds if f.first < last and first < f.last)
        return over

    def quality(self, tag: Tag, view: MemoryView, links: LinkView | None = None) -> Quality:
        """One tag's quality (the runtime's per-scan path is `evaluate`)."""
        return Quality(int(self.evaluate(view, links)[self._pos[tag.name]]))


def _forced(addr: int) -> tuple[int, int]:
    """What a forced operand address covers: one I/O bit, or one data byte."""
    return (addr, addr + 1) if addr < IO_BITS else span(addr, 1)
