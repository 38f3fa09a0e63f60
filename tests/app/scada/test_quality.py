"""Quality derived from the program's NREADs: which node fills which address, and each tag's
quality from link states, data age, NetPlc's run state and forcing; then from a real exchange
with a simulated node that is killed, and from NetPlc stopped."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from app.scada.quality import LinkView, Quality, QualityMap, link_outputs, nread_feeds
from app.scada.readings import Readings
from app.scada.tag import Scaling, Tag, TagType, span
from netplc.exchange import Exchange, NodeConfig
from netplc.memory import Memory
from netplc.program import parse
from netplc.simulator import Simulator
from tests.netplc.test_exchange import NODE_PROGRAM, TICK, Station, wait_until

PROGRAM = """\
TNA $03760
FON C:$02120 N:NREAD S:0 D:$02200 R:2       ; before any NODE: the last NODE's node (2)
TNA $03760
FON C:$02100 N:NODE S:1
TNA $03760
FON C:$02104 N:NREAD S:4000 D:$04000 R:4    ; node 1 fills 04000-04003
TNA $03760
FON C:$02110 N:NODE S:2
TNA $03760
FON C:$02114 N:NREAD S:4000 D:$04003 R:2    ; node 2 fills 04003-04004
JMP 0
"""

TAGS = [Tag("A", 0o4000, TagType.WORD), Tag("SPAN", 0o4002, TagType.INT32),  # 04002-04005: both
        Tag("B", 0o4004, TagType.WORD), Tag("LOCAL", 0o4100, TagType.WORD),
        Tag("BIT", 0o2207, TagType.BIT), Tag("DATABIT", 0o40000 + 7, TagType.BIT),
        Tag("OUTSIDE", 0o2220, TagType.BIT)]


def asking() -> Memory:
    """Memory as after a scan in which every NREAD's rung was on."""
    mem = Memory()
    for coil in (0o2104, 0o2114, 0o2120):
        mem.set_bit(coil, 1)
    return mem


def test_which_node_fills_which_address_comes_from_the_nreads() -> None:
    feeds = nread_feeds(parse(PROGRAM))
    assert [(f.node, f.coil, f.line) for f in feeds] == [(2, 0o2120, 2), (1, 0o2104, 6), (2, 0o2114, 10)]
    qmap = QualityMap(parse(PROGRAM), TAGS)
    fed = {t.name: sorted(f.node for f in qmap.fed_by(t)) for t in TAGS}
    assert fed == {"A": [1], "SPAN": [1, 2], "B": [2], "LOCAL": [], "BIT": [2], "DATABIT": [1],
                   "OUTSIDE": []}


def qualities(view: Memory, links: LinkView) -> dict[str, str]:
    qmap = QualityMap(parse(PROGRAM), TAGS)
    return {t.name: Quality(int(q)).word for t, q in zip(TAGS, qmap.evaluate(view.snapshot(10), links),
                                                          strict=True)}


def test_all_good_while_running_with_links_up_and_fresh_data() -> None:
    links = LinkView(links={1: True, 2: True}, refreshed={f.key: 9 for f in nread_feeds(parse(PROGRAM))})
    assert set(qualities(asking(), links).values()) == {"good"}


def test_a_node_down_fails_what_it_fills_and_only_that() -> None:
    got = qualities(asking(), LinkView(links={1: False, 2: True}))
    assert got == {"A": "comm-fail", "SPAN": "comm-fail", "B": "good", "LOCAL": "good", "BIT": "good",
                   "DATABIT": "comm-fail", "OUTSIDE": "good"}


def test_stale_after_more_than_two_ticks_beyond_the_normal_one() -> None:
    prog = parse(PROGRAM)
    node1_key = next(f.key for f in nread_feeds(prog) if f.node == 1)
    fresh = {f.key: 10 for f in nread_feeds(prog)}
    qmap = QualityMap(prog, TAGS)
    for landed, expected in ((9, Quality.GOOD), (7, Quality.GOOD), (6, Quality.STALE)):
        links = LinkView(refreshed={**fresh, node1_key: landed})
        assert qmap.quality(TAGS[0], asking().snapshot(10), links) is expected
    never = LinkView(refreshed={})
    assert qmap.quality(TAGS[0], asking().snapshot(10), never) is Quality.STALE
    idle = Memory()  # the NREAD's rung is off: nothing is expected, nothing is late
    assert qmap.quality(TAGS[0], idle.snapshot(10), never) is Quality.GOOD


def test_not_running_marks_everything_and_forcing_wins() -> None:
    got = qualities(asking(), LinkView(running=False, links={1: False}, forced=[0o4100, 0o2207]))
    assert got == {"A": "not running", "SPAN": "not running", "B": "not running", "LOCAL": "forced",
                   "BIT": "forced", "DATABIT": "not running", "OUTSIDE": "not running"}
    assert Quality.NOT_RUNNING.bad and Quality.STALE.bad and Quality.COMM_FAIL.bad
    assert not Quality.FORCED.bad and not Quality.GOOD.bad


LIVE_PROGRAM = "TNA $03760\nFON C:$02110 N:NREAD S:4000 D:$04000 R:2\nJMP 0\n"


def test_the_quality_of_any_address() -> None:
    qmap = QualityMap(parse(PROGRAM), [])
    links = LinkView(links={1: False, 2: True}, forced=[0o4100])
    view = asking().snapshot(10)
    assert qmap.at(0o4000, 2, view, links) is Quality.COMM_FAIL  # node 1
    assert qmap.at(0o4004, 1, view, links) is Quality.GOOD  # node 2
    assert qmap.at(0o4003 * 8 + 7, 0, view, links) is Quality.COMM_FAIL  # bit 7 of 04003: both
    assert qmap.at(0o2200, 0, view, links) is Quality.GOOD  # bit 02200, node 2
    assert qmap.at(0o4100, 2, view, links) is Quality.FORCED
    assert qmap.at(0o4200, 2, view, LinkView(running=False)) is Quality.NOT_RUNNING


def test_the_quality_of_an_address_asked_again_follows_the_links_of_each_scan(monkeypatch) -> None:
    """Which NREADs fill an operand is worked out once; what they say is judged every time."""
    qmap = QualityMap(parse(PROGRAM), [])
    view = asking().snapshot(10)
    assert qmap.at(0o4000, 2, view, LinkView(links={1: True, 2: True})) is Quality.GOOD
    assert qmap.at(0o4000, 2, view, LinkView(links={1: False, 2: True})) is Quality.COMM_FAIL
    assert [f.node for f in qmap.feeding(*span(0o4002, 4))] == [1, 2]
    monkeypatch.setattr("app.scada.quality.MAX_SPANS", 2)  # more spans asked than a station has
    for addr in (0o4000, 0o4002, 0o4004, 0o4100):
        qmap.at(addr, 2, view, LinkView())
    assert len(qmap._over) <= 2
    assert qmap.at(0o4004, 1, view, LinkView(links={1: False, 2: True})) is Quality.GOOD


@pytest.fixture
def live() -> Iterator[tuple[Station, Simulator]]:
    """NetPlc NREADing 04000 from a real simulated node over Modbus TCP on 127.0.0.1."""
    node = Simulator(parse(NODE_PROGRAM), port=0, tick=TICK)
    node.start()
    station = Station(LIVE_PROGRAM,
                      [NodeConfig(0, f"tcp://127.0.0.1:{node.port}", timeout=0.2, retries=0)])
    station.start()
    yield station, node
    station.stop()
    node.stop()


def test_quality_from_a_real_exchange_a_killed_node_and_netplc_stopped(
        live: tuple[Station, Simulator]) -> None:
    station, node = live
    ex: Exchange = station.exchange
    qmap = QualityMap(parse(LIVE_PROGRAM), [Tag("TRIG", 0o4000, TagType.WORD)])

    def quality() -> Quality:
        eng = station.engine
        links = LinkView(running=eng.state == "running", links={0: ex.link_up(0)},
                         refreshed=dict(ex.refreshed))
        return Quality(int(qmap.evaluate(eng.snapshot, links)[0]))

    wait_until(lambda: quality() is Quality.GOOD)
    node.stop()
    wait_until(lambda: quality() is Quality.COMM_FAIL)
    station.engine.post(lambda _m: station.engine.stop())
    wait_until(lambda: quality() is Quality.NOT_RUNNING)


def test_initial_until_the_first_attempt_then_the_first_data_within_its_normal_time() -> None:
    prog = parse(PROGRAM)
    qmap = QualityMap(prog, TAGS[:1])  # A: node 1
    key = next(f.key for f in nread_feeds(prog) if f.node == 1)
    view = asking().snapshot(10)

    def at(**kw: object) -> Quality:
        return qmap.quality(TAGS[0], view, LinkView(**kw))  # type: ignore[arg-type]

    assert at(links={1: False}, refreshed={}, since={}) is Quality.INITIAL  # no attempt yet
    assert at(links={1: True}, refreshed={}, since={1: 8}) is Quality.INITIAL  # data on its way
    assert at(links={1: True}, refreshed={}, since={1: 6}) is Quality.STALE  # late
    assert at(links={1: False}, refreshed={}, since={1: 9}) is Quality.COMM_FAIL  # first attempt failed
    assert at(links={1: True}, refreshed={key: 10}, since={1: 9}) is Quality.GOOD  # data landed
    # NetPlc started again: data landed before the start does not count, within its normal time
    assert at(links={1: True}, refreshed={key: 3}, since={1: 9}) is Quality.INITIAL
    assert Quality.INITIAL.held and not Quality.INITIAL.bad and Quality.INITIAL.word == "initial"


def test_readings_give_value_quality_and_time_of_tags_and_addresses() -> None:
    level = Tag("LEVEL", 0o4000, TagType.WORD, "%", Scaling(0, 4095, 0, 100), 1)
    qmap = QualityMap(parse(PROGRAM), [level])
    mem = asking()
    mem.set_word(0o4000, 4095)
    links = LinkView(links={1: False, 2: True})
    snap = mem.snapshot(10, 0.0, 1234.5, "running")
    readings = Readings(snap, qmap, links, qmap.evaluate(snap, links))
    r = readings.tag("LEVEL")
    assert (r.value, r.raw, r.unit, r.quality, r.time) == (100.0, 4095, "%", Quality.COMM_FAIL, 1234.5)
    assert r.text(1) == "100.0 % ?" and not r.good
    assert readings.quality("LEVEL") is Quality.COMM_FAIL
    assert readings.address(0o4004, 1) is Quality.GOOD
    assert readings.word(0o4000).quality is Quality.COMM_FAIL
    with pytest.raises(KeyError):
        readings.tag("NOPE")


def test_link_outputs_show_the_link_itself() -> None:
    prog = parse(PROGRAM)
    assert link_outputs(prog) == {0o2121: 2, 0o2105: 1, 0o2115: 2}
    qmap = QualityMap(prog, [])
    mem = asking()
    mem.set_bit(0o2105, 1)  # the program's copy: node 1 up, as of its last scan
    stopped = LinkView(running=False, links={1: False, 2: True})
    snap = mem.snapshot(10, 1.0, 1234.5, "stopped")
    readings = Readings(snap, qmap, stopped, qmap.evaluate(snap, stopped))
    live = readings.live(snap)
    assert (live.get_bit(0o2105), live.get_bit(0o2115), live.get_bit(0o2121)) == (0, 1, 1)
    assert readings.address(0o2105, 0) is Quality.GOOD  # the link is known, NetPlc or not
    assert readings.address(0o2104, 0) is Quality.NOT_RUNNING  # the program's own coil
    up = LinkView(links={1: True, 2: True}, since={})
    assert qmap.at(0o2105, 0, snap, up) is Quality.INITIAL  # no exchange attempt yet
    same = mem.snapshot(11)
    assert Readings(same, qmap, LinkView(links={1: True, 2: False}), qmap.evaluate(same)).live(same) is same


@pytest.mark.parametrize("links", [
    LinkView(), LinkView(links={1: False, 2: True}), LinkView(running=False),
    LinkView(links={1: True, 2: True}, since={1: 0}), LinkView(forced=[0o4003, 0o2207]),
    LinkView(links={1: True, 2: True}, refreshed={5: 0}),
])
def test_operands_judged_at_once_are_judged_as_one_by_one(links: LinkView) -> None:
    """What a large form asks per refresh (`Readings.judge`) agrees with `at` for every operand."""
    qmap = QualityMap(parse(PROGRAM), TAGS)
    operands = [(0o4000, 2), (0o4002, 4), (0o4003, 1), (0o4004, 2), (0o4100, 2), (0o2207, 0),
                (0o40000 + 7, 0), (0o40030, 0), (0o2220, 0), (0o2200, 1), (0o4004, 2)]
    view = asking().snapshot(9, 0.9, 0)
    codes = qmap.judge(qmap.operands(operands), view, links)
    assert [Quality(int(c)) for c in codes] == [qmap.at(a, n, view, links) for a, n in operands]
