"""The parts of NetPlc's memory a console watches: a form's operands as few ranges of the station's
memory variables (indexes of NetPlc.Memory.Bits and NetPlc.Memory.Data, both ends included)."""

from __future__ import annotations

import logging

import pytest

from app.publish.memory_items import RETIRED_KEPT, WHOLE, Ranges, _retired, merge, ranges_of
from hmi_forms.elements.analog import AnalogBase
from hmi_forms.elements.reads import operands
from netplc.address import BitRef, parse_octal


def test_operands_become_the_indexes_of_the_memory_variables_merged_when_close() -> None:
    ranges = ranges_of([(parse_octal("02120"), 0),  # an I/O bit: its byte of Bits
                        (parse_octal("04010"), 2), (parse_octal("04012"), 2),  # words of bank 0: Data 8-11
                        (parse_octal("040005"), 0),  # bit 5 of 04000: Data 0
                        (parse_octal("014000"), 2),  # bank 1: Data 2048-2049
                        (parse_octal("02000"), 2)])  # a word of I/O bits: 16 bits
    assert ranges == Ranges(bits=((0o2000, 0o2017), (0o2120, 0o2120)), data=((0, 11), (2048, 2049)))
    assert ranges.size == 16 + 1 + 12 + 2
    assert merge([(0, 1), (40, 41)]) == ((0, 1), (40, 41)) and merge([(0, 1), (30, 31)]) == ((0, 31),)


def test_ranges_cover_and_unite() -> None:
    a = Ranges(data=((8, 25),))
    b = Ranges(bits=((1024, 1027),))
    both = a | b
    assert both.covers(a) and both.covers(b) and not a.covers(b) and not a.covers(both)
    assert WHOLE.covers(both) and Ranges().covers(Ranges())
    assert (Ranges(data=((0, 4),)) | Ranges(data=((5, 9),))).data == ((0, 9),)


def test_a_forms_operands_are_all_it_reads_gates_included() -> None:
    gauge = AnalogBase(InAddr=parse_octal("04010"), QualityAddr=BitRef(parse_octal("02131")),
                       SyncType=BitRef(parse_octal("02151")))
    assert operands([gauge]) == [(0o2131, 0), (0o2151, 0), (0o4010, 2)]


def test_a_late_notification_for_an_item_given_up_is_not_a_warning_and_any_other_is(
        caplog: pytest.LogCaptureFixture) -> None:
    log = logging.getLogger("asyncua.common.subscription")
    _retired.retire([900_001])
    with caplog.at_level(logging.WARNING, logger="asyncua.common.subscription"):
        log.warning("Received a notification for unknown handle: %s", 900_001)
        log.warning("Received a notification for unknown handle: %s", 900_002)
    assert [r.getMessage() for r in caplog.records] == ["Received a notification for unknown handle: 900002"]
    _retired.retire(range(1_000_000, 1_000_000 + RETIRED_KEPT))  # bounded: the oldest forgotten
    assert 900_001 not in _retired.handles and len(_retired.handles) == RETIRED_KEPT
