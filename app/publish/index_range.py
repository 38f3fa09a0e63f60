"""IndexRange (OPC UA Part 4, 7.27 NumericRange) on Read and on monitored items, which asyncua's
Read and subscription services ignore: a client that reads or monitors a part of an array, a
ByteString or a String (NetPlc's memory: 16 KB of data, 2 KB of bits) is answered that part, not
the whole value, and a monitored part is reported only when that part changed (a console watches
the few ranges its open form shows, not 20 KB at every scan).

One dimension only (every array the station serves has one): "i" or "i:j" with i < j, both
inclusive; a range reaching past the end is answered what exists, one starting past it
Bad_IndexRangeNoData, one that is no range (or more dimensions than the value has)
Bad_IndexRangeInvalid. Applied after the read (a PostRead callback), so the value's status and
timestamps stay the server's; on a monitored item, to each value sampled before it is compared with
the last one reported (`RangedItems`, installed in each session's subscriptions by opcua.py).

The same items keep the value sampled last as it is when it cannot change in place (a number, a
string, a ByteString...): asyncua deep-copies every value of every item of every subscription, the
better part of what each scan costs the station per console.
"""

from __future__ import annotations

import copy
import datetime as dt
import re
from dataclasses import replace
from functools import lru_cache

from asyncua import ua
from asyncua.common.callback import ServerItemCallback
from asyncua.server.internal_subscription import InternalSubscription
from asyncua.server.monitored_item_service import MonitoredItemData, MonitoredItemService, MonitoredItemValues

_RANGE = re.compile(r"(\d+)(?::(\d+))?")
_S = ua.StatusCodes
FIXED = (bool, int, float, str, bytes, dt.datetime, type(None))  # values nobody changes in place


@lru_cache(maxsize=1024)
def numeric_range(text: str) -> tuple[int, int] | None:
    """The first and last index of `text`, None when it is not a one-dimensional NumericRange."""
    m = _RANGE.fullmatch(text)
    if m is None:
        return None
    first = int(m.group(1))
    last = int(m.group(2)) if m.group(2) is not None else first
    return (first, last) if m.group(2) is None or first < last else None


def part(dv: ua.DataValue, text: str) -> ua.DataValue:
    """The part `text` of a read value (a bad one as it was)."""
    if dv.StatusCode is not None and not dv.StatusCode.is_good():
        return dv
    where = numeric_range(text)
    value = dv.Value
    whole = value.Value if value is not None else None
    if where is None or not isinstance(whole, (bytes, str, list)) or (value.Dimensions or [0])[1:]:
        return ua.DataValue(StatusCode=ua.StatusCode(_S.BadIndexRangeInvalid))
    first, last = where
    if first >= len(whole):
        return ua.DataValue(StatusCode=ua.StatusCode(_S.BadIndexRangeNoData))
    return replace(dv, Value=ua.Variant(whole[first:last + 1], value.VariantType, is_array=value.is_array))


def index_ranges(event: ServerItemCallback, _service: object) -> None:
    """PostRead: each Value read with an IndexRange answered its part."""
    results = event.response_params
    for n, rv in enumerate(event.request_params.NodesToRead):
        if rv.IndexRange and rv.AttributeId == ua.AttributeIds.Value:
            results[n] = part(results[n], rv.IndexRange)


class Sampled(MonitoredItemValues):
    """An item's values as last sampled: one that cannot change in place is kept as it is (the
    address space replaces a DataValue, never changes one), others deep-copied as asyncua does."""

    def set_current_datavalue(self, cur_val: ua.DataValue) -> None:
        value = cur_val.Value.Value if cur_val.Value is not None else None
        self.old_dvalue = self.current_dvalue
        self.current_dvalue = cur_val if isinstance(value, FIXED) else copy.deepcopy(cur_val)


class RangedItems(MonitoredItemService):
    """A subscription's monitored items, each value cut to its item's IndexRange before asyncua
    compares it with the last one reported: a change elsewhere in the array reports nothing, and
    only the part is copied and sent. A range that is no NumericRange is refused at creation
    (Bad_IndexRangeInvalid), one past the end reports Bad_IndexRangeNoData, as a Read would.
    A part the same as the one sampled last is not handed to asyncua at all (which would copy it
    deeply to find so), unless the item's filter reports a new timestamp too. Every item keeps its
    values `Sampled`."""

    def __init__(self, isub: InternalSubscription, aspace: object) -> None:
        super().__init__(isub, aspace)  # type: ignore[arg-type]
        self._parts: dict[int, tuple[object, object]] = {}  # by item: its part and status last sampled

    def _make_monitored_item_common(self, params: ua.MonitoredItemCreateRequest
                                    ) -> tuple[ua.MonitoredItemCreateResult, MonitoredItemData]:
        result, item = super()._make_monitored_item_common(params)
        item.mvalue = Sampled()
        return result, item

    async def _create_data_change_monitored_item(
            self, params: ua.MonitoredItemCreateRequest) -> ua.MonitoredItemCreateResult:
        text = params.ItemToMonitor.IndexRange
        if text and numeric_range(text) is None:
            return ua.MonitoredItemCreateResult(StatusCode=ua.StatusCode(_S.BadIndexRangeInvalid))
        return await super()._create_data_change_monitored_item(params)

    async def datachange_callback(self, handle: int, value: ua.DataValue,
                                  error: ua.StatusCode | None = None) -> None:
        if error is None:
            mid = self._monitored_datachange.get(handle)
            item = self._monitored_items.get(mid) if mid is not None else None
            read = item.read_value_id if item is not None else None
            if item is not None and read is not None and read.IndexRange and \
                    read.AttributeId == ua.AttributeIds.Value:
                value = part(value, read.IndexRange)
                sampled = (value.Value.Value if value.Value is not None else None, value.StatusCode)
                stamped = item.filter is not None and \
                    getattr(item.filter, "Trigger", None) == ua.DataChangeTrigger.StatusValueTimestamp
                if not stamped and self._parts.get(mid) == sampled:  # type: ignore[arg-type]
                    return
                self._parts[mid] = sampled  # type: ignore[index]
        await super().datachange_callback(handle, value, error)

    async def _set_monitoring_mode(self, mode: ua.MonitoringMode, mid: int) -> ua.StatusCode:
        self._parts.pop(mid, None)  # enabled again: its part is sampled anew, as asyncua samples others
        return await super()._set_monitoring_mode(mode, mid)

    def _delete_monitored_items(self, mid: int) -> ua.StatusCode:
        self._parts.pop(mid, None)
        return super()._delete_monitored_items(mid)


def ranged(subscription: InternalSubscription) -> None:
    """Monitored items of `subscription` (new, with none yet) honour their IndexRange."""
    service = subscription.monitored_item_srv
    subscription.monitored_item_srv = RangedItems(subscription, service.aspace)
