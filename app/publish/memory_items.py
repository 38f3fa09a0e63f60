"""What a console reads of NetPlc's memory: the ranges its open form shows, watched as monitored
items of one subscription, each with an IndexRange on the station's `NetPlc.Memory.Bits` or
`NetPlc.Memory.Data` (Part 4 7.27, honoured by the station: index_range.py), besides the scan's
`NetPlc.Tick`, `NetPlc.State`, `NetPlc.Forces` and the Server's ServiceLevel. The station then
sends, once per publishing interval, only the parts that changed: a few words of a 20 KB memory,
where polling read it whole every 100 ms.

Any standard client can watch the memory the same way. The parts are kept in full-size copies of
the two arrays, so a console's views read a `Snapshot` as the local workstation's do; `covered`
says which parts hold the station's values (a view is shown a snapshot only once it covers
what the view reads). A range newly wanted is read first (one Read with its IndexRange) and
then watched, so a form switched to shows the station's values at once, not zeros until the
next publish.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from asyncua import Client, ua

from netplc.address import DATA_SIZE, IO_BITS, data_index

logger = logging.getLogger(__name__)

GAP = 32  # bytes between two operands below which they are watched as one range: an item costs more
PUBLISH_MIN_MS = 20.0  # the shortest publishing interval asked (the station's tick otherwise)
Span = tuple[int, int]  # first and last index, both included (a NumericRange's)
Apply = Callable[[ua.DataValue], None]  # what a monitored item's value is given to
RETIRED_KEPT = 1024  # client handles of deleted items whose late notifications are expected


class _Retired(logging.Filter):
    """A publish the station sent before it deleted an item may still reach the client after
    (Part 4 5.12.6: the queued notifications are not recalled), and asyncua warns of a
    notification for an unknown handle at each form switched. For a handle this process's
    consoles deleted that is expected, not a fault, and a warning for it would bury the real
    ones in the console's log: such warnings are dropped, any other kept."""

    UNKNOWN = "Received a notification for unknown handle: %s"

    def __init__(self) -> None:
        super().__init__()
        self.handles: dict[int, None] = {}  # insertion-ordered: the oldest go first

    def retire(self, handles: Iterable[int]) -> None:
        for handle in handles:
            self.handles[handle] = None
        for handle in list(self.handles)[: max(0, len(self.handles) - RETIRED_KEPT)]:
            del self.handles[handle]

    def filter(self, record: logging.LogRecord) -> bool:
        return not (record.msg == self.UNKNOWN and record.args and record.args[0] in self.handles)


_retired = _Retired()
logging.getLogger("asyncua.common.subscription").addFilter(_retired)


def merge(spans: Iterable[Span], gap: int = GAP) -> tuple[Span, ...]:
    """`spans` sorted, those less than `gap` apart made one."""
    out: list[Span] = []
    for first, last in sorted(spans):
        if out and first <= out[-1][1] + gap + 1:
            out[-1] = (out[-1][0], max(out[-1][1], last))
        else:
            out.append((first, last))
    return tuple(out)


@dataclass(frozen=True)
class Ranges:
    """Parts of the memory variables: indexes into Bits (one byte a bit) and into Data."""

    bits: tuple[Span, ...] = ()
    data: tuple[Span, ...] = ()

    def __or__(self, other: Ranges) -> Ranges:
        return Ranges(merge(self.bits + other.bits, 0), merge(self.data + other.data, 0))

    def covers(self, other: Ranges) -> bool:
        """Does every part of `other` lie within a part of this?"""
        return all(any(a <= first and last <= b for a, b in mine) for mine, theirs in
                   ((self.bits, other.bits), (self.data, other.data)) for first, last in theirs)

    @property
    def size(self) -> int:
        """Bytes in all parts."""
        return sum(last - first + 1 for first, last in self.bits + self.data)


WHOLE = Ranges(((0, IO_BITS - 1),), ((0, DATA_SIZE - 1),))
NOTHING = Ranges()


def ranges_of(operands: Iterable[tuple[int, int]], gap: int = GAP) -> Ranges:
    """The parts that hold `operands`, given as an element's `sources()` names them: (address,
    bytes), bytes 0 for one HMI bit (an I/O bit, or byte*8+bit of a data byte)."""
    bits: list[Span] = []
    data: list[Span] = []
    for addr, nbytes in operands:
        if nbytes == 0:
            if addr < IO_BITS:
                bits.append((addr, addr))
            else:
                i = data_index(addr >> 3)
                data.append((i, i))
        elif addr < IO_BITS:
            bits.append((addr, min(IO_BITS, addr + 8 * nbytes) - 1))
        else:
            i = data_index(addr)
            data.append((i, i + nbytes - 1))
    return Ranges(merge(bits, gap), merge(data, gap))


def _text(span: Span) -> str:
    first, last = span
    return str(first) if first == last else f"{first}:{last}"


class MemoryItems:
    """The memory of one session's subscription: `open()` in each new session, `follow()` the
    ranges wanted; `on_batch` is called on the client's loop after each publish that changed
    something (all of its notifications applied)."""

    def __init__(self, node: Callable[[str], ua.NodeId]) -> None:
        self.node = node
        self.bits = bytearray(IO_BITS)
        self.data = bytearray(DATA_SIZE)
        self.tick = 0
        self.wall = 0.0  # the scan's wall time: NetPlc.Tick's source timestamp
        self.state = ""
        self.forces = "[]"
        self.service_level: int | None = None
        self.covered = NOTHING  # the parts that hold the station's values
        self.batches = 0  # publishes taken
        self.client: Client | None = None  # the session the subscription is of
        self.on_batch: Callable[[], None] = lambda: None
        self._subscription: object = None
        self._items: dict[tuple[str, Span], tuple[int, int]] = {}  # (Bits or Data, part) ->
        # (monitored item id, client handle)
        self._apply: dict[int, Callable[[ua.DataValue], None]] = {}  # by client handle
        self._handle = 0
        self._pending = False

    async def open(self, client: Client, tick_ms: float) -> None:
        """A subscription in `client`'s session, publishing at the station's tick (the station ends
        each cycle right after a scan: app/publish/aligned.py), with the scan's variables; no part
        of the memory yet (`follow`)."""
        self.client, self._items, self._apply, self.covered = client, {}, {}, NOTHING
        period = max(PUBLISH_MIN_MS, tick_ms)
        self._subscription = await client.create_subscription(period, self)
        scalars: list[tuple[ua.NodeId, Callable[[ua.DataValue], None]]] = [
            (self.node("NetPlc.Tick"), self._tick), (self.node("NetPlc.State"), self._state),
            (self.node("NetPlc.Forces"), self._forces),
            (ua.NodeId(ua.ObjectIds.Server_ServiceLevel), self._level)]
        await self.values(scalars)

    async def values(self, items: list[tuple[ua.NodeId, Callable[[ua.DataValue], None]]]) -> None:
        """Watch the variables of `items` whole in the same subscription, each applied its value
        read now and then each change the station pushes (before `on_batch`)."""
        assert self._subscription is not None, "open() first"
        for dv, (_, apply) in zip(await self._read([(n, "") for n, _ in items]), items):
            apply(dv)
        await self._watch(self._subscription, [(n, "", apply) for n, apply in items])

    async def follow(self, wanted: Ranges) -> bool:
        """Watch the parts of `wanted` and no others; True when what is watched changed."""
        client, subscription = self.client, self._subscription
        assert client is not None and subscription is not None, "open() first"
        want = {("Bits", s) for s in wanted.bits} | {("Data", s) for s in wanted.data}
        new = sorted(want - self._items.keys())
        gone = self._items.keys() - want
        if not new and not gone:
            return False
        targets = {"Bits": self.bits, "Data": self.data}
        parts = [(self.node(f"NetPlc.Memory.{name}"), _text(span)) for name, span in new]
        for dv, (name, span) in zip(await self._read(parts), new):
            self._part(targets[name], span[0], dv)
        made = await self._watch(subscription, [(node, text, self._setter(targets[name], span[0]))
                                                for (node, text), (name, span) in zip(parts, new)])
        self._items.update(zip(new, made))
        if gone:
            items = [self._items.pop(k) for k in gone]
            _retired.retire(handle for _, handle in items)
            await subscription.unsubscribe([mid for mid, _ in items])  # type: ignore[attr-defined]
            for _, handle in items:
                del self._apply[handle]
        self.covered = wanted
        self.on_batch()
        return True

    @property
    def watched(self) -> int:
        """Memory parts watched."""
        return len(self._items)

    # --- asyncua's subscription handler (on the client's loop) -----------------------------------

    def datachange_notification(self, node: object, value: object, data: object) -> None:
        item: ua.MonitoredItemNotification = data.monitored_item  # type: ignore[attr-defined]
        apply = self._apply.get(item.ClientHandle)
        if apply is None or item.Value is None:
            return
        apply(item.Value)
        if not self._pending:  # after the other notifications of this publish, each a task of its own
            self._pending = True
            asyncio.get_running_loop().call_soon(self._batch)

    def status_change_notification(self, status: ua.StatusChangeNotification) -> None:
        logger.warning("the station's subscription: %s", status.Status)

    def _batch(self) -> None:
        self._pending = False
        self.batches += 1
        self.on_batch()

    # --- parts ----------------------------------------------------------------------------------

    async def _read(self, parts: list[tuple[ua.NodeId, str]]) -> list[ua.DataValue]:
        assert self.client is not None
        params = ua.ReadParameters()
        params.NodesToRead = [ua.ReadValueId(NodeId=node, AttributeId=ua.AttributeIds.Value, IndexRange=text)
                              for node, text in parts]
        return await self.client.uaclient.read(params)

    async def _watch(self, subscription: object,
                     items: list[tuple[ua.NodeId, str, Apply]]) -> list[tuple[int, int]]:
        """Each item's (monitored item id, client handle)."""
        requests = []
        for node, text, apply in items:
            self._handle += 1
            self._apply[self._handle] = apply
            params = ua.MonitoringParameters(ClientHandle=self._handle, SamplingInterval=0, QueueSize=1,
                                             DiscardOldest=True)
            requests.append(ua.MonitoredItemCreateRequest(
                ItemToMonitor=ua.ReadValueId(NodeId=node, AttributeId=ua.AttributeIds.Value, IndexRange=text),
                MonitoringMode=ua.MonitoringMode.Reporting, RequestedParameters=params))
        made = await subscription.create_monitored_items(requests) if requests else []  # type: ignore[attr-defined]
        for result in made:
            if isinstance(result, ua.StatusCode):
                raise ua.UaStatusCodeError(result.value)  # the station's memory is not what it was
        return [(int(m), r.RequestedParameters.ClientHandle) for m, r in zip(made, requests)]

    def _setter(self, target: bytearray, first: int) -> Callable[[ua.DataValue], None]:
        return lambda dv: self._part(target, first, dv)

    @staticmethod
    def _part(target: bytearray, first: int, dv: ua.DataValue) -> None:
        if dv.StatusCode is not None and not dv.StatusCode.is_good():
            raise ua.UaStatusCodeError(dv.StatusCode.value)
        value = dv.Value.Value if dv.Value is not None else None
        if isinstance(value, (bytes, bytearray)):
            target[first:first + len(value)] = value

    def _tick(self, dv: ua.DataValue) -> None:
        self.tick = int(dv.Value.Value or 0) if dv.Value is not None else 0
        if dv.SourceTimestamp is not None:
            self.wall = dv.SourceTimestamp.timestamp()

    def _state(self, dv: ua.DataValue) -> None:
        self.state = str(dv.Value.Value or "") if dv.Value is not None else ""

    def _forces(self, dv: ua.DataValue) -> None:
        self.forces = str(dv.Value.Value or "[]") if dv.Value is not None else "[]"

    def _level(self, dv: ua.DataValue) -> None:
        value = dv.Value.Value if dv.Value is not None else None
        self.service_level = None if value is None else int(value)
