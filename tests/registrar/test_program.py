"""NSTORE and NMSG from a running NetPlc program arrive in the archive with group, type, value, text."""

import datetime as dt

from netplc.engine import Engine, FakeClock
from netplc.program import parse
from registrar.catalog import Catalog, Message
from registrar.query import Archive, Filter
from registrar.store import Store

PROGRAM = """
; store the word 04000 and journal message 3 while 02000 is on
TNA $02000
FON C:$02001 N:NSTORE S:$04000 D:5 R:7
TNA $02000
FON C:$02002 N:NMSG S:3 D:1 R:2
TNA $02003
FON C:$02004 N:303 S:77 D:4 R:1
JMP 0
"""
WALL = dt.datetime(2026, 3, 5, 23, 59, 59).timestamp()


def test_nstore_and_nmsg_from_a_running_program(db):
    catalog = Catalog({3: Message(3, 1, 2, "Уровень выше 90 %")})
    wall = [WALL]
    store = Store(db, catalog=catalog, wallclock=lambda: wall[0])
    store.start()
    clock = FakeClock()
    engine = Engine(parse(PROGRAM), clock=clock, wallclock=lambda: wall[0], sink=store)
    engine.mem.set_word(0o4000, 1234)
    engine.mem.set_bit(0o2000, 1)
    engine.scan()  # one scan: one NSTORE record and one NMSG record
    engine.mem.set_bit(0o2000, 0)
    clock.advance(0.1)
    engine.scan()  # the rung is off: nothing
    wall[0] += 2.0  # past midnight
    engine.mem.set_word(0o4000, 4321)
    engine.mem.set_bit(0o2000, 1)
    engine.mem.set_bit(0o2003, 1)
    engine.write_word(0o4030, 7, user="ivanov")
    clock.advance(0.1)
    engine.scan()
    store.close()

    with Archive(db) as archive:
        before, after = dt.date(2026, 3, 5), dt.date(2026, 3, 6)
        assert archive.days() == [after, before]
        first = archive.records(before, newest_first=False)
        assert [(r.ts, r.kind, r.grp, r.type, r.source, r.number, r.value, r.text) for r in first] == [
            (WALL, "data", 5, 7, "04000", None, 1234.0, None),
            (WALL, "message", 1, 2, None, 3, None, "Уровень выше 90 %"),
        ]
        second = archive.records(after, newest_first=False)
        assert [(r.kind, r.grp, r.type, r.value, r.number) for r in second if r.kind != "operator"] == [
            ("data", 5, 7, 4321.0, None), ("message", 1, 2, None, 3), ("message", 4, 1, None, 77)]
        assert second[-1].text == "unknown message 77 (not in the catalog)"
        (op,) = archive.records(after, Filter(kinds={"operator"}))
        assert op.source == "ivanov" and op.value == 7.0 and "04030" in op.text
        ts, values = archive.series(before, grp=5, type=7, source="04000")
        assert list(ts) == [WALL] and list(values) == [1234.0]
