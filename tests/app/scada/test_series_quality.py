"""The quality of the archive's data series: NSTORE and RegData records of a value that is not
good carry its quality word, and a series turning held is marked at once (app/scada/series.py)."""

from __future__ import annotations

from app.scada.quality import LinkView
from app.scada.series import GAP_WORDS, SeriesQuality
from netplc.memory import Memory
from netplc.program import parse
from netplc.records import Record

PROGRAM = ("TNA $03760\nFON C:$02110 N:NREAD S:4010 D:$04010 R:2\n"
           "FON C:$02170 N:NSTORE S:$04010 D:1 R:1\nFON C:$02174 N:NSTORE S:$04020 D:1 R:2\n")
T = 1_800_000_000.0


def marks(records: list[Record]) -> list[tuple[int | None, int | None, str | None, str | None]]:
    assert all(r.kind == "data" and r.value is None for r in records)
    return sorted(((r.grp, r.type, r.source, r.text) for r in records), key=str)


def test_records_of_values_not_good_carry_their_quality_and_a_series_turning_held_is_marked() -> None:
    series = SeriesQuality(parse(PROGRAM), {"LT1": ((0o4010, 2),), "PUMP": ((0o2005, 0),)})
    view = Memory().snapshot()
    level = Record(T, "data", 1, 1, "04010", value=3817.0)
    own = Record(T, "data", 1, 2, "04020", value=5.0)
    assert series.evaluate(view, LinkView(links={0: True}), T) == []  # a start marks nothing
    assert series.stamp(level) is level and series.stamp(own) is own  # good: text stays NULL

    down = series.evaluate(view, LinkView(links={0: False}), T + 1)  # node 0 is down
    assert marks(down) == [(1, 1, "04010", "comm-fail"), (None, None, "LT1", "comm-fail")]
    assert series.stamp(level).text == "comm-fail" and series.stamp(level).value == 3817.0
    assert series.stamp(own) is own  # the program's own word: nothing fills it, still good
    assert series.evaluate(view, LinkView(links={0: False}), T + 2) == []  # once per outage

    stopped = series.evaluate(view, LinkView(running=False, links={0: False}), T + 3)
    assert marks(stopped) == [(1, 2, "04020", "not running"), (None, None, "PUMP", "not running")]
    assert series.stamp(Record(T, "data", source="PUMP", value=1.0)).text == "not running"

    assert series.evaluate(view, LinkView(links={0: True}), T + 4) == []  # good again: NSTORE resumes
    assert series.stamp(level) is level
    forced = series.evaluate(view, LinkView(links={0: True}, forced=[0o4010]), T + 5)
    assert forced == [] and series.stamp(level).text == "forced"  # forced is shown, not a gap
    assert "forced" not in GAP_WORDS and "comm-fail" in GAP_WORDS and "initial" in GAP_WORDS


def test_a_record_that_has_a_text_or_no_series_is_left_as_it_is() -> None:
    series = SeriesQuality(parse(PROGRAM), {})
    series.evaluate(Memory().snapshot(), LinkView(running=False), T)
    other = Record(T, "data", 9, 9, "ELEMENT", value=1.0)
    texted = Record(T, "data", 1, 1, "04010", value=1.0, text="comm-fail")
    assert series.stamp(other) is other and series.stamp(texted) is texted
