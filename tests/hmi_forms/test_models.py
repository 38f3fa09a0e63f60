"""Element models without Qt: conversion, zones, sync generators, gating and data quality."""

from __future__ import annotations

import datetime as dt
import math

import pytest

from hmi_forms.elements.props import Scaling
from hmi_forms.elements.static import format_span
from tests.hmi_forms.helpers import ListTarget, element, snap

LEVEL = [{"Name": "Level", "AppMin": 0, "AppMax": 4095, "PhyMin": 0, "PhyMax": 100}]
TEMP = Scaling(0, 1000, -50, 150)


@pytest.mark.parametrize(
    ("scaling", "hw", "phy"),
    [
        (Scaling(0, 4095, 0, 100), 0, 0.0),
        (Scaling(0, 4095, 0, 100), 4095, 100.0),
        (TEMP, 0, -50.0),
        (TEMP, 1000, 150.0),
        (TEMP, 250, 0.0),
        (Scaling(4000, 0, 0, 10), 4000, 0.0),  # a reversed hardware range
        (Scaling(4000, 0, 0, 10), 0, 10.0),
    ],
)
def test_conversion_and_inverse_at_range_ends(scaling: Scaling, hw: int, phy: float) -> None:
    assert scaling.to_phy(hw) == pytest.approx(phy)
    assert scaling.to_hw(phy) == hw


def test_inverse_rounds_and_clamps_to_the_hardware_range() -> None:
    s = Scaling(0, 4095, 0, 100)
    assert s.to_hw(50) == 2048  # 2047.5 rounds to even
    assert s.to_hw(50.01) == 2048
    assert s.to_hw(120) == 4095
    assert s.to_hw(-5) == 0
    assert Scaling(100, 200, 0, 1).to_hw(-1) == 100
    assert Scaling(0, 100000, 0, 1).to_hw(1) == 0xFFFF  # never more than a word
    assert TEMP.fraction(-80) == 0.0 and TEMP.fraction(200) == 1.0 and TEMP.fraction(50) == 0.5


def test_analog_base_shows_precision_units_and_keeps_the_maximum(tmp_path) -> None:
    a = element(tmp_path, "AnalogBase", InAddr="04010", Device="Level", Precision=2, Units="%",
                KeepMaxValue=True, devices=LEVEL)
    assert a.update(snap(words={0o4010: 4095}))
    assert a.text == "100.00" and a.maximum == 100.0 and a.fraction == 1.0
    assert a.update(snap(words={0o4010: 2048}))
    assert a.text == "50.01" and a.maximum == 100.0
    assert not a.update(snap(words={0o4010: 2048}))  # same value: nothing to repaint
    a.reset_max()
    assert a.maximum == pytest.approx(50.012, abs=1e-3)


def test_inline_ranges_work_without_a_device(tmp_path) -> None:
    a = element(tmp_path, "AnalogBase", InAddr="04012", AppMin=0, AppMax=1000, PhyMin=-50, PhyMax=150)
    a.update(snap(words={0o4012: 500}))
    assert a.phy == 50.0 and a.text == "50.0"


def test_low_normal_high_transitions_record_their_messages(tmp_path) -> None:
    a = element(tmp_path, "AnalogBase", InAddr="04010", Device="Level", devices=LEVEL, RegMessages=True,
                PhyLow=10, PhyHigh=90, Hysteresis=2, LowMessage="Level low", NormalMessage="Level normal",
                HighMessage="Level high", Name="LT1")
    t = ListTarget()
    a.effects = t  # the runtime's copy: it records and writes

    def feed(percent: float) -> str | None:
        a.update(snap(words={0o4010: round(percent * 40.95)}, wall=1000.0))
        return a.zone

    assert feed(50) == "normal" and t.records == []  # normal at start is no news
    assert feed(95) == "high"
    assert feed(89) == "high"  # inside the hysteresis band: still high
    assert feed(87) == "normal"
    assert feed(5) == "low"
    assert feed(11) == "low"
    assert feed(13) == "normal"
    assert [(r.kind, r.type, r.text, r.source) for r in t.records] == [
        ("message", 2, "Level high", "LT1"),
        ("message", 0, "Level normal", "LT1"),
        ("message", 2, "Level low", "LT1"),
        ("message", 0, "Level normal", "LT1"),
    ]
    assert t.records[0].ts == 1000.0 and t.records[0].value == pytest.approx(95, abs=0.05)


def test_a_value_outside_the_limits_at_start_is_reported(tmp_path) -> None:
    a = element(tmp_path, "AnalogBase", InAddr="04010", Device="Level", devices=LEVEL, RegMessages=True,
                PhyHigh=90)
    t = ListTarget()
    a.effects = t  # the runtime's copy: it records and writes
    a.update(snap(words={0o4010: 4000}))
    assert [(r.type, r.text) for r in t.records] == [(2, "high: 97.7")]


def test_reg_data_records_each_change_of_the_shown_value(tmp_path) -> None:
    a = element(tmp_path, "AnalogBase", InAddr="04010", Device="Level", devices=LEVEL, RegData=True,
                Precision=0)
    t = ListTarget()
    a.effects = t  # the runtime's copy: it records and writes
    for hw in (0, 1, 2, 41, 41, 4095):
        a.update(snap(words={0o4010: hw}))
    assert [round(r.value) for r in t.records] == [0, 1, 100]  # 1 and 2 still show "0"
    assert {r.kind for r in t.records} == {"data"}


def sequence(gen, select: list[int], enable: int = 1) -> list[int]:
    """Run a generator on scans 0..n-1 and collect its output for each scan."""
    t = ListTarget()
    gen.effects = t  # the runtime's copy: it records and writes
    out = []
    for scan, sel in enumerate(select):
        gen.update(snap(bits={0o2000: sel, 0o2002: enable}, scan=scan))
        out.append(t.writes[-1][2])
        assert t.writes[-1][:2] == ("set", 0o2001)
    return out


def test_sync_generator_sequences_of_fig_2_4_3(tmp_path) -> None:
    gen = element(tmp_path, "SyncGenerator", InAddr="02000", OutAddr="02001", Period0=5, Phase0=0,
                  Period1=10, Phase1=1)
    out0 = sequence(gen, [0] * 21)
    assert [i for i, v in enumerate(out0) if v] == [0, 5, 10, 15, 20]
    gen = element(tmp_path, "SyncGenerator", InAddr="02000", OutAddr="02001", Period0=5, Phase0=0,
                  Period1=10, Phase1=1)
    out1 = sequence(gen, [1] * 32)
    assert [i for i, v in enumerate(out1) if v] == [1, 11, 21, 31]
    gen = element(tmp_path, "SyncGenerator", InAddr="02000", OutAddr="02001", Period0=5, Phase0=0,
                  Period1=10, Phase1=1)
    mixed = sequence(gen, [0] * 10 + [1] * 12)  # the select bit switches the pair at scan 10
    assert [i for i, v in enumerate(mixed) if v] == [0, 5, 11, 21]


def test_sync_generator_writes_once_per_scan(tmp_path) -> None:
    gen = element(tmp_path, "SyncGenerator", OutAddr="02001", Period0=2)
    t = ListTarget()
    gen.effects = t  # the runtime's copy: it records and writes
    s = snap(scan=4)
    gen.update(s)
    gen.update(s)
    assert t.writes == [("set", 0o2001, 1, None)]


def test_sync_timer_is_enabled_by_ainput(tmp_path) -> None:
    gen = element(tmp_path, "SyncTimer", InAddr="02000", OutAddr="02001", Ainput="02002", Period0=2)
    assert sequence(gen, [0] * 4, enable=0) == [0, 0, 0, 0]
    assert sequence(gen, [0] * 4, enable=1)[-4:] == [1, 0, 1, 0]


def test_sync_type_gates_updates(tmp_path) -> None:
    a = element(tmp_path, "AnalogBase", InAddr="04010", Device="Level", devices=LEVEL, SyncType="02050")
    assert not a.update(snap(words={0o4010: 4095}, bits={0o2050: 0}))
    assert a.hw is None
    assert a.update(snap(words={0o4010: 4095}, bits={0o2050: 1}))
    assert a.text == "100.0"
    assert not a.update(snap(words={0o4010: 0}, bits={0o2050: 0}))
    assert a.text == "100.0"
    d = element(tmp_path, "DiscreteBase", InAddr="02042", SyncType=0)
    assert d.SyncType is None and d.update(snap(bits={0o2042: 1})) and d.value == 1


def test_quality_bit_0_keeps_the_last_value_and_marks_it_stale(tmp_path) -> None:
    a = element(tmp_path, "AnalogBase", InAddr="04010", Device="Level", devices=LEVEL, QualityAddr="02101")
    assert a.update(snap(words={0o4010: 4095}, bits={0o2101: 1}))
    assert not a.stale and a.text == "100.0"
    assert a.update(snap(words={0o4010: 0}, bits={0o2101: 0}))  # the change to stale is news
    assert a.stale and a.text == "100.0"
    assert not a.update(snap(words={0o4010: 0}, bits={0o2101: 0}))
    assert a.update(snap(words={0o4010: 0}, bits={0o2101: 1}))
    assert not a.stale and a.text == "0.0"


def test_a_stale_graph_records_gaps(tmp_path) -> None:
    g = element(tmp_path, "Graph", Address="040005", Elements=4, QualityAddr="02101")
    for scan, (v, q) in enumerate([(1, 1), (0, 1), (1, 0), (1, 1), (0, 1)]):
        assert g.update(snap(bits={0o40005: v, 0o2101: q}, scan=scan))
    values = g.trend.values()
    assert values[0] == 0 and math.isnan(values[1]) and list(values[2:]) == [1, 0]


def test_discrete_click_toggles_the_shown_value_through_operator_writes(tmp_path) -> None:
    d = element(tmp_path, "DiscreteBase", InAddr="040042", Enabled=True, TextFalse="Стоп", TextTrue="Пуск")
    t = ListTarget()
    d.bind(t, user="ivanov")
    assert not d.click()  # nothing shown yet: nothing to toggle
    d.update(snap())
    assert d.text == "Стоп" and d.click()
    d.update(snap(bits={0o40042: 1}))
    assert d.text == "Пуск" and d.click()
    assert t.writes == [("bit", 0o40042, 1, "ivanov"), ("bit", 0o40042, 0, "ivanov")]


def test_discrete_writes_out_addr_and_refuses_when_disabled_or_stale(tmp_path) -> None:
    d = element(tmp_path, "DiscreteBase", InAddr="02120", OutAddr="02122", Enabled=True, QualityAddr="02101")
    t = ListTarget()
    d.bind(t)
    d.update(snap(bits={0o2101: 1}))
    assert d.click() and t.writes[-1][:3] == ("bit", 0o2122, 1)
    d.update(snap(bits={0o2101: 0}))
    assert not d.click()
    off = element(tmp_path, "DiscreteBase", InAddr="02120")
    off.bind(t)
    off.update(snap())
    assert not off.click() and len(t.writes) == 1


def test_discrete_transitions_record_text_and_value(tmp_path) -> None:
    d = element(tmp_path, "DiscreteBase", InAddr="02120", TextFalse="Насос остановлен",
                TextTrue="Насос работает", RegMessages=True, RegData=True, Name="P1")
    t = ListTarget()
    d.effects = t  # the runtime's copy: it records and writes
    for v in (0, 1, 1, 0):
        d.update(snap(bits={0o2120: v}))
    assert [(r.kind, r.text, r.value) for r in t.records] == [
        ("message", "Насос работает", None), ("data", None, 1.0),
        ("message", "Насос остановлен", None), ("data", None, 0.0),
    ]


def test_a_hidden_state_is_still_journaled_by_its_text(tmp_path) -> None:
    d = element(tmp_path, "DiscreteControlledEnable", InAddr="02120", EnableAddr="02121",
                TextFalse="Насос остановлен", TextTrue="Насос работает", RegMessages=True)
    t = ListTarget()
    d.effects = t  # the runtime's copy: it records and writes
    d.update(snap(bits={0o2120: 0, 0o2121: 0}))
    d.update(snap(bits={0o2120: 1, 0o2121: 0}))
    assert d.text == "" and [r.text for r in t.records] == ["Насос работает"]


def test_color_label_and_controlled_enable(tmp_path) -> None:
    d = element(tmp_path, "DiscreteControlledEnable", InAddr="02120", EnableAddr="02121", Enabled=True,
                BackColor="#c0c0c0", BackColorFalse="#808080", BackColorTrue="#00ff00", TextTrue="ON")
    d.bind(ListTarget())
    d.update(snap(bits={0o2120: 1, 0o2121: 1}))
    assert d.back_color == (0, 255, 0, 255) and d.text == "ON" and d.clickable
    assert d.update(snap(bits={0o2120: 1, 0o2121: 0}))
    assert d.back_color == (192, 192, 192, 255) and d.text == "" and not d.clickable


def test_animation_cycles_images_while_the_bit_is_1(tmp_path) -> None:
    (tmp_path / "a.png").write_bytes(b"")
    d = element(tmp_path, "DiscreteAnimation", InAddr="02120", EnableAddr="03760", ImageFalse=0,
                ImageFirst=1, ImageLast=3, images=["a.png"] * 4)
    frames = []
    for v in (0, 1, 1, 1, 1, 0):
        d.update(snap(bits={0o2120: v, 0o3760: 1}))
        frames.append(d.image)
    assert frames == [0, 2, 3, 1, 2, 0]


def test_analog_output_validates_converts_and_writes(tmp_path) -> None:
    o = element(tmp_path, "AnalogOutput", OutAddr="04030", AppMin=0, AppMax=1000, PhyMin=-50, PhyMax=150,
                Units="°C")
    t = ListTarget()
    o.bind(t)
    assert o.submit("abc") == (False, '"abc" is not a number')
    assert o.submit("nan") == (False, '"nan" is not a number')
    assert o.submit("151") == (False, "151 is out of range -50.0 … 150.0 °C")
    assert t.writes == []
    assert o.submit(" 75,5 ") == (True, "Set to 75.6 °C")  # the value the hardware word gives
    assert o.submit("-50") == (True, "Set to -50.0 °C")
    assert t.writes == [("word", 0o4030, 628, "operator"), ("word", 0o4030, 0, "operator")]
    o.update(snap(words={0o4030: 628}))
    assert o.text == "75.6"


def test_date_time_shows_clock_and_time_since_start(tmp_path) -> None:
    d = element(tmp_path, "DateTime")
    assert d.update(snap(time=100.0, wall=0.0))
    assert d.uptime == "00:00:00" and len(d.clock) == 8 and d.clock.count(":") == 2
    assert not d.update(snap(time=100.2, wall=0.2))
    assert d.update(snap(time=100.0 + 3723, wall=3723.0))
    assert d.uptime == "01:02:03"
    assert format_span(2 * 86400 + 61) == "2 d 00:01:01"


def test_journal_refreshes_today_every_refresh_ticks(tmp_path) -> None:
    j = element(tmp_path, "MessageJournal", RefreshTicks=3, Kinds=["message"], MinType=2)
    assert [j.update(snap()) for _ in range(6)] == [False, False, True, False, False, True]
    assert j.kinds == ("message",) and j.min_type == 2
    j.day = dt.date(2026, 1, 1)
    assert not any(j.update(snap()) for _ in range(6))


def test_a_write_the_station_refuses_with_a_full_queue_is_not_taken_for_done(tmp_path) -> None:
    """Back-pressure reaches the operator: a full queue of outside writes refuses the click and
    the setpoint, and the view is told why (the engine keeps the scan period whatever comes)."""
    from netplc.engine import Engine, FakeClock
    from netplc.program import parse
    from tests.hmi_forms.helpers import engine_target

    engine = Engine(parse("JMP 0\n"), clock=FakeClock(), write_queue=1)
    told: list[str] = []
    target = engine_target(engine, on_answer=lambda what, ticket: told.append(what) if ticket.done() and
                           not ticket.result().ok else None)
    (tmp_path / "b").mkdir()
    (tmp_path / "s").mkdir()
    button = element(tmp_path / "b", "DiscreteBase", Name="Пуск", InAddr="040042", Enabled=True)
    setpoint = element(tmp_path / "s", "AnalogOutput", Name="Уставка", OutAddr="04030", AppMin=0,
                       AppMax=4095, PhyMin=0, PhyMax=100)
    for model in (button, setpoint):
        model.bind(target, "operator")
        model.refresh(engine.snapshot)
    assert button.click()  # the queue takes one write
    assert not button.click() and told == ["Пуск"]
    ok, why = setpoint.submit("50")
    assert not ok and why.startswith("Уставка: the station is busy")
    engine.scan()  # the queue drains: writes are taken again
    assert setpoint.submit("50")[0]


def test_a_write_asks_at_least_the_elements_role_of_the_command_layer(tmp_path) -> None:
    """The element's Role may ask more than the station's policy: an operator may not click an
    element that asks for an engineer, and the refusal names the element and the role."""
    from netplc.engine import Engine, FakeClock
    from netplc.program import parse
    from tests.hmi_forms.helpers import engine_target

    engine = Engine(parse("JMP 0\n"), clock=FakeClock())
    button = element(tmp_path, "DiscreteBase", Name="Пуск", InAddr="040042", Enabled=True, Role="engineer")
    button.bind(engine_target(engine, role="operator"), "olga")
    button.refresh(engine.snapshot)
    assert not button.click() and engine.writes_waiting == 0
    button.bind(engine_target(engine, role="engineer"), "egor")
    assert button.click() and engine.writes_waiting == 1
