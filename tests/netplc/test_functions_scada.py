"""NSTORE and NMSG hand records to the engine's sink; being level-triggered, they are driven from
an edge in a real program. Records go to an in-memory ListSink here (the registrar's SQLite sink
takes the same Record)."""

from __future__ import annotations

from netplc.engine import Engine, FakeClock
from netplc.program import parse
from netplc.records import ListSink, Record

# The manual's pulse former: 02101 is 1 for exactly one scan after input 02000 rises.
PULSE = """
TNA $02000
TFA $02100
YON $02101
TNA $02000
YON $02100
"""


Writes = dict[int, int]  # address -> value: a bit below 04000, else a word


def poke(e: Engine, writes: Writes) -> None:
    for a, v in writes.items():
        if a < 0o4000:
            e.mem.set_bit(a, v)
        else:
            e.mem.set_word(a, v)


def run(text: str, scans: int, setup: Writes, at: dict[int, Writes] | None = None) -> tuple[Engine, ListSink]:
    """Scan `text` `scans` times at 0.1 s; `at[k]` is written before scan k. Wall time = 1.7e9 + clock."""
    sink = ListSink()
    clock = FakeClock(0.0)
    e = Engine(parse(text, source="t.stl"), clock=clock, wallclock=lambda: 1.7e9 + clock(), sink=sink)
    poke(e, setup)
    for k in range(scans):
        poke(e, (at or {}).get(k, {}))
        clock.advance(0.1)
        e.scan()
    return e, sink


def test_nstore_record_carries_time_group_type_source_and_value() -> None:
    _, sink = run("TNA $02000\nFON C:$03000 N:NSTORE S:$04010 D:7 R:2\n", 1, {0o2000: 1, 0o4010: 0xFFFF})
    assert sink.records == [
        Record(ts=1_700_000_000.1, kind="data", grp=7, type=2, source="04010", value=65535.0)
    ]


def test_nmsg_record_carries_number_group_type_and_leaves_the_text_to_the_registrar() -> None:
    _, sink = run("TNA $02000\nFON C:$03000 N:NMSG S:17 D:2 R:3\n", 1, {0o2000: 1})
    assert sink.records == [Record(ts=1_700_000_000.1, kind="message", grp=2, type=3, number=17, text=None)]


def test_a_level_rung_records_on_every_scan() -> None:
    _, sink = run("TNA $02000\nFON C:$03000 N:NMSG S:17 D:2 R:3\n", 5, {0o2000: 1})
    assert len(sink.records) == 5


def test_driven_from_a_one_scan_pulse_one_event_is_one_record() -> None:
    text = PULSE + (
        "TNA $02101\nFON C:$03000 N:NMSG S:17 D:2 R:3\n"
        "TNA $02101\nFON C:$03004 N:NSTORE S:$04000 D:1 R:0\n"
    )
    # the input rises at scan 2, stays on to scan 6, falls, rises again at scan 9
    _, sink = run(text, 12, {0o4000: 42}, at={2: {0o2000: 1}, 7: {0o2000: 0}, 9: {0o2000: 1}})
    assert [(r.kind, r.ts) for r in sink.records] == [
        ("message", 1_700_000_000.3), ("data", 1_700_000_000.3),
        ("message", 1_700_000_001.0), ("data", 1_700_000_001.0),
    ]


def test_driven_from_a_counter_edge() -> None:
    """CTR done (C+2) rises on the 3rd input pulse; the pulse former turns that into one record."""
    text = (
        "TNA $02000\nCTR $02200 N:3\n"
        "TNA $02202\nTFA $02210\nYON $02211\nTNA $02202\nYON $02210\n"
        "TNA $02211\nFON C:$03000 N:NSTORE S:$04000 D:1 R:0\n"
    )
    toggles = {k: {0o2000: k % 2} for k in range(12)}
    _, sink = run(text, 12, {0o4000: 5}, at=toggles)
    assert len(sink.records) == 1


def test_nsync_paces_nstore() -> None:
    text = "TNA $03760\nFON C:$03000 N:NSYNC S:10 D:3\nTNA $03001\nFON C:$03004 N:NSTORE S:$04000 D:1 R:0\n"
    _, sink = run(text, 30, {0o4000: 9})
    assert len(sink.records) == 3
