"""What forms do by themselves, evaluated from every snapshot on the engine (no Qt, no view)."""

from __future__ import annotations

import logging
from pathlib import Path

from hmi_forms.behaviour import FormBehaviour
from hmi_forms.form import load_form
from netplc.engine import Engine, FakeClock
from netplc.program import parse
from netplc.records import ListSink
from tests.hmi_forms.helpers import write_form

GEN = {"type": "SyncGenerator", "Name": "G", "x": 0, "y": 0, "w": 100, "h": 50, "InAddr": "02000",
       "OutAddr": "02001", "Period0": 5, "Phase0": 0, "Period1": 10, "Phase1": 1}
PUMP = {"type": "DiscreteBase", "Name": "Насос", "x": 0, "y": 60, "w": 100, "h": 40, "InAddr": "02120",
        "TextFalse": "Насос остановлен", "TextTrue": "Насос работает", "RegMessages": True}
LEVEL = {"type": "AnalogBase", "Name": "LT1", "x": 0, "y": 110, "w": 100, "h": 100, "InAddr": "04010",
         "AppMin": 0, "AppMax": 4095, "PhyMin": 0, "PhyMax": 100, "PhyHigh": 90, "RegMessages": True,
         "HighMessage": "Уровень высокий", "NormalMessage": "Уровень в норме"}


def rig(tmp_path: Path, *elements: dict, program: str = "") -> tuple[Engine, ListSink, FormBehaviour]:
    sink = ListSink()
    engine = Engine(parse(program), clock=FakeClock(), wallclock=lambda: 1_800_000_000.0, sink=sink)
    behaviour = FormBehaviour([load_form(write_form(tmp_path, list(elements)))], engine.mem, sink)
    behaviour.attach(engine)
    return engine, sink, behaviour


def test_a_generator_pulses_in_the_scans_of_fig_2_4_3_without_any_view(tmp_path) -> None:
    engine, sink, _ = rig(tmp_path, GEN)
    seen = []
    for scan in range(32):
        if scan == 12:
            engine.write_bit(0o2000, 1, user="test")
        seen.append(engine.scan().get_bit(0o2001))
    assert [i for i, v in enumerate(seen) if v] == [0, 5, 10, 21, 31]
    assert [r.kind for r in sink.records] == ["operator"]  # generator writes are not journaled


def test_the_program_sees_the_pulse_in_its_own_scan(tmp_path) -> None:
    # the program copies the generator's output to 02002 in the scan it runs in
    engine, _, _ = rig(tmp_path, GEN, program="TNA $02001\nYON $02002\n")
    copied = [engine.scan().get_bit(0o2002) for _ in range(11)]
    assert [i for i, v in enumerate(copied) if v] == [0, 5, 10]


def test_transitions_and_limits_are_journaled_once_each_in_scan_order(tmp_path) -> None:
    engine, sink, _ = rig(tmp_path, PUMP, LEVEL)
    engine.scan()
    engine.write_bit(0o2120, 1, user="test")
    engine.write_word(0o4010, 4000, user="test")
    for _ in range(3):
        engine.scan()
    engine.write_word(0o4010, 100, user="test")
    engine.scan()
    engine.scan()
    assert [(r.kind, r.source, r.text, r.type) for r in sink.records if r.kind == "message"] == [
        ("message", "Насос", "Насос работает", 0),
        ("message", "LT1", "Уровень высокий", 2),
        ("message", "LT1", "Уровень в норме", 0),
    ]


def test_only_acting_elements_are_evaluated_and_a_failing_one_is_reported_once(tmp_path, caplog) -> None:
    quiet = {**PUMP, "Name": "Лампа", "RegMessages": False, "y": 220}
    reports: list[str] = []
    sink = ListSink()
    engine = Engine(parse(""), clock=FakeClock(), sink=sink)
    form = load_form(write_form(tmp_path, [GEN, PUMP, quiet]))
    behaviour = FormBehaviour([form], engine.mem, sink, reports.append)
    assert [el.Name for _, el in behaviour.elements] == ["G", "Насос"]

    def broken(snapshot) -> bool:
        raise RuntimeError("boom")

    form.elements[1].refresh = broken
    with caplog.at_level(logging.ERROR, logger="hmi_forms.behaviour"):
        behaviour.attach(engine)
        for _ in range(6):
            engine.scan()
    assert len(reports) == 1 and 'element "Насос": evaluation failed' in reports[0]
    [logged] = caplog.records  # and logged, with the traceback
    assert "boom" in str(logged.exc_info[1])
    assert engine.snapshot.get_bit(0o2001) == 1  # scan 5: the generator goes on
