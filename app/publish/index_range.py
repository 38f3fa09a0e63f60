"""IndexRange on Read (OPC UA Part 4, 7.27 NumericRange), which asyncua's Read service ignores:
a client that reads a part of an array, a ByteString or a String (NetPlc's memory: 16 KB of
data, 2 KB of bits) is answered that part, not the whole value.

One dimension only (every array the station serves has one): "i" or "i:j" with i < j, both
inclusive; a range reaching past the end is answered what exists, one starting past it
Bad_IndexRangeNoData, one that is no range (or more dimensions than the value has)
Bad_IndexRangeInvalid. Applied after the read (a PostRead callback), so the value's status and
timestamps stay the server's.
"""

from __future__ import annotations

import re
from dataclasses import replace

from asyncua import ua
from asyncua.common.callback import ServerItemCallback

_RANGE = re.compile(r"(\d+)(?::(\d+))?")
_S = ua.StatusCodes


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
