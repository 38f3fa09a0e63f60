"""Widgets really rendered (offscreen), operator input through a real Engine, and the demo forms."""

from __future__ import annotations

import logging
import shutil
from pathlib import Path

import pytest
from PySide6.QtCore import Qt
from PySide6.QtGui import QImage

from app.station.config import DEMO_STATION
from hmi_forms.elements import ELEMENT_TYPES
from hmi_forms.form import Form, load_form, load_forms
from hmi_forms.widgets.form_view import FormView
from netplc.engine import Engine, FakeClock
from netplc.program import load_symbols, parse
from netplc.records import ListSink
from tests.hmi_forms.helpers import engine_target, snap, write_form

EXAMPLE = DEMO_STATION
Q = "02101"  # quality bit used where an element has no state of its own
LEVEL = [{"Name": "Level", "AppMin": 0, "AppMax": 4095, "PhyMin": 0, "PhyMax": 100}]


def engine() -> tuple[Engine, ListSink]:
    sink = ListSink()
    return Engine(parse(""), clock=FakeClock(), wallclock=lambda: 1_800_000_000.0, sink=sink), sink


def image(view: FormView, qtbot) -> QImage:
    view.flush()
    return view.grab().toImage()


def differs(a: QImage, b: QImage) -> int:
    """Number of differing pixels (sampled every 2 px)."""
    assert a.size() == b.size()
    points = ((x, y) for x in range(0, a.width(), 2) for y in range(0, a.height(), 2))
    return sum(a.pixel(x, y) != b.pixel(x, y) for x, y in points)


def one(tmp_path: Path, type_: str, w: int = 220, h: int = 140, **props) -> Form:
    extra = {k: props.pop(k) for k in ("devices", "images") if k in props}
    raw = {"type": type_, "Name": "E", "x": 0, "y": 0, "w": w, "h": h, **props}
    doc = write_form(tmp_path, [raw], **extra)
    form = load_form(doc)
    form.width, form.height = w, h
    return form


def pump_images(tmp_path: Path) -> list[str]:
    for name in ("pump_off.png", "pump_on_0.png", "pump_on_1.png", "tank.png"):
        shutil.copy(EXAMPLE / "forms" / "images" / name, tmp_path / name)
    return ["pump_off.png", "pump_on_0.png", "pump_on_1.png"]


# type: (properties, bits of state A, bits of state B, what the model must say in A and in B)
CASES = {
    "SyncGenerator": ({"OutAddr": "02001", "InAddr": "02000", "Period0": 5, "Period1": 10, "Phase1": 1},
                      {0o2000: 0}, {0o2000: 1}, lambda m: m.period_phase, (5, 0), (10, 1)),
    "SyncTimer": ({"OutAddr": "02001", "Ainput": "02002", "Period0": 1}, {0o2002: 1}, {0o2002: 0},
                  lambda m: m.enabled, True, False),
    "DiscreteBase": ({"InAddr": "02120", "TextFalse": "Стоп", "TextTrue": "Работа"},
                     {0o2120: 0}, {0o2120: 1}, lambda m: (m.value, m.text), (0, "Стоп"), (1, "Работа")),
    "DiscreteColorLabel": ({"InAddr": "02120", "TextTrue": "ON", "BackColorTrue": "#2e7d32"},
                           {0o2120: 0}, {0o2120: 1}, lambda m: (m.value, m.back_color),
                           (0, None), (1, (0x2E, 0x7D, 0x32, 255))),
    "DiscreteControlledEnable": ({"InAddr": "02120", "EnableAddr": "02121", "TextTrue": "ON",
                                  "BackColorTrue": "#2e7d32"},
                                 {0o2120: 1, 0o2121: 0}, {0o2120: 1, 0o2121: 1},
                                 lambda m: (m.indicating, m.text), (False, ""), (True, "ON")),
    "DiscreteAnimation": ({"InAddr": "02120", "EnableAddr": "03760", "ImageFalse": 0, "ImageFirst": 1,
                           "ImageLast": 2}, {0o2120: 0, 0o3760: 1}, {0o2120: 1, 0o3760: 1},
                          lambda m: (m.value, m.image in (1, 2)), (0, False), (1, True)),
    "StaticPicture": ({"Image": "tank.png", "QualityAddr": Q}, {0o2101: 1}, {0o2101: 0},
                      lambda m: m.stale, False, True),
    "StaticText": ({"Text": "Узел 0", "QualityAddr": Q}, {0o2101: 1}, {0o2101: 0},
                   lambda m: m.stale, False, True),
    "Graph": ({"Address": "040005", "Elements": 20}, {0o40005: 0}, {0o40005: 1},
              lambda m: (m.trend.last, m.trend.count), (0.0, 12), (1.0, 24)),
    "DateTime": ({"QualityAddr": Q}, {0o2101: 1}, {0o2101: 0},
                 lambda m: (m.stale, len(m.clock)), (False, 8), (True, 8)),
}


@pytest.mark.parametrize("type_", list(CASES))
def test_each_element_type_renders_its_state(qtbot, tmp_path, type_: str) -> None:
    props, state_a, state_b, probe, *expected = CASES[type_]
    images = pump_images(tmp_path)
    form = one(tmp_path, type_, images=images, **props)
    view = FormView(form, engine_target(engine()[0]))
    qtbot.addWidget(view)
    model = form.elements[0]
    pictures = []
    for scan, (bits, want) in enumerate(zip((state_a, state_b), expected, strict=True)):
        for k in range(12):  # several scans: graphs fill, animations step
            view.refresh(snap(bits=bits, scan=scan * 100 + k, time=k, wall=1_800_000_000.0 + k))
        assert probe(model) == want, type_
        pictures.append(image(view, qtbot))
        assert view.errors == [], type_  # a refresh or a drawing that raised would also change pixels
    assert differs(*pictures) > 20, type_


def test_an_element_whose_refresh_raises_fails_the_rendering_checks(qtbot, tmp_path) -> None:
    form = one(tmp_path, "DiscreteBase", InAddr="02120", TextFalse="Стоп", TextTrue="Работа")
    view = FormView(form, engine_target(engine()[0]))
    qtbot.addWidget(view)
    model = form.elements[0]
    view.refresh(snap(bits={0o2120: 0}))
    before = image(view, qtbot)

    def broken(snapshot) -> bool:
        raise RuntimeError("boom")

    model.refresh = model.settle = broken  # whichever reads it: its own update, or the form's bank
    view.refresh(snap(bits={0o2120: 1}, scan=1))
    assert differs(before, image(view, qtbot)) > 20  # the stale mark alone changes the picture...
    assert model.value == 0 and view.errors  # ...which is why the model and the errors are checked


@pytest.mark.parametrize("appearance", ["digital", "hbar", "dial", "semidial", "graph"])
def test_analog_appearances_render_the_value(qtbot, tmp_path, appearance: str) -> None:
    form = one(tmp_path, "AnalogBase", w=240, h=200, InAddr="04010", Device="Level", Units="%",
               Appearance=appearance, PhyHigh=90, devices=LEVEL)
    view = FormView(form, engine_target(engine()[0]))
    qtbot.addWidget(view)
    pictures = []
    for base, hw in ((0, 400), (100, 4000)):
        for k in range(5):
            view.refresh(snap(words={0o4010: hw}, scan=base + k))
        pictures.append(image(view, qtbot))
    assert differs(*pictures) > 50
    model = form.elements[0]
    assert model.text == "97.7" and model.zone == "high"
    for small in ((90, 70), (400, 320)):  # small and large sizes render without errors
        view.pairs[0][1].resize(*small)
        view.grab()
        assert view.errors == []


def test_stale_mark_covers_the_last_value(qtbot, tmp_path) -> None:
    form = one(tmp_path, "AnalogBase", InAddr="04010", Device="Level", Appearance="digital", QualityAddr=Q,
               devices=LEVEL)
    view = FormView(form, engine_target(engine()[0]))
    qtbot.addWidget(view)
    view.refresh(snap(words={0o4010: 2048}, bits={0o2101: 1}))
    live = image(view, qtbot)
    view.refresh(snap(words={0o4010: 0}, bits={0o2101: 0}))
    stale = image(view, qtbot)
    widget = view.pairs[0][1]
    assert widget.toolTip().startswith("Stale") and form.elements[0].text == "50.0"
    assert differs(live, stale) > 100


def test_click_on_an_enabled_discrete_toggles_the_bit_through_the_scan(qtbot, tmp_path) -> None:
    eng, sink = engine()
    form = load_form(write_form(tmp_path, [
        {"type": "DiscreteBase", "Name": "Пуск", "x": 0, "y": 0, "w": 120, "h": 40, "InAddr": "040042",
         "Enabled": True},
        {"type": "DiscreteBase", "Name": "Lamp", "x": 0, "y": 50, "w": 120, "h": 40, "InAddr": "02120"},
    ]))
    view = FormView(form, engine_target(eng), user="ivanov")
    qtbot.addWidget(view)
    view.refresh(eng.snapshot)
    button, lamp = (w for _, w in view.pairs)
    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
    assert eng.snapshot.get_hmi_bit(0o40042) == 0  # queued, not yet applied
    view.refresh(eng.scan())
    assert eng.snapshot.get_hmi_bit(0o40042) == 1 and eng.snapshot.get_byte(0o4004) == 0b100
    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
    view.refresh(eng.scan())
    assert eng.snapshot.get_hmi_bit(0o40042) == 0
    assert [(r.kind, r.source, r.text) for r in sink.records] == [
        ("operator", "ivanov", "write Пуск (040042): 0 -> 1"),
        ("operator", "ivanov", "write Пуск (040042): 1 -> 0"),
    ]
    qtbot.mouseClick(lamp, Qt.MouseButton.LeftButton)
    view.refresh(eng.scan())
    assert eng.snapshot.get_hmi_bit(0o2120) == 0 and len(sink.records) == 2


def test_analog_output_rejects_text_and_out_of_range_values_visibly(qtbot, tmp_path) -> None:
    eng, sink = engine()
    form = one(tmp_path, "AnalogOutput", w=280, h=110, OutAddr="04030", AppMin=0, AppMax=4095, PhyMin=-50,
               PhyMax=150, Units="°C")
    view = FormView(form, engine_target(eng))
    qtbot.addWidget(view)
    view.show()
    widget = view.pairs[0][1]
    before = image(view, qtbot)
    for entry, message in (("abc", '"abc" is not a number'), ("200", "200 is out of range -50.0 … 150.0 °C")):
        widget.edit.setText("")
        qtbot.keyClicks(widget.edit, entry)
        qtbot.keyClick(widget.edit, Qt.Key.Key_Return)
        assert widget.message.text() == message and widget.message.isVisible()
        assert "color: #d32f2f" in widget.message.styleSheet() and widget.edit.text() == entry
    rejected = image(view, qtbot)
    assert differs(before, rejected) > 20
    view.refresh(eng.scan())
    assert eng.snapshot.get_word(0o4030) == 0 and sink.records == []
    widget.edit.setText("50")
    qtbot.mouseClick(widget.button, Qt.MouseButton.LeftButton)
    view.refresh(eng.scan())
    assert eng.snapshot.get_word(0o4030) == 2048 and widget.message.text() == "Set to 50.0 °C"
    assert widget.current.text() == "50.0 °C" and sink.records[0].kind == "operator"


def test_a_view_only_shows_a_generator_and_journals_nothing(qtbot, tmp_path) -> None:
    """Sync pulses and element records are the runtime's (hmi_forms/behaviour.py), not the view's:
    a view that lags or is closed must not change what the station does."""
    eng, sink = engine()
    form = load_form(write_form(tmp_path, [
        {"type": "SyncGenerator", "Name": "G", "x": 0, "y": 0, "w": 120, "h": 60, "OutAddr": "02001",
         "Period0": 2},
        {"type": "DiscreteBase", "Name": "P", "x": 0, "y": 70, "w": 120, "h": 40, "InAddr": "02120",
         "TextTrue": "Насос работает", "RegMessages": True, "RegData": True},
    ]))
    view = FormView(form, engine_target(eng))
    qtbot.addWidget(view)
    gen = form.elements[0]
    outputs = []
    for k in range(6):
        if k == 2:
            eng.write_bit(0o2120, 1, user="test")
        view.refresh(eng.snapshot)
        outputs.append(gen.output)
        assert eng.scan().get_bit(0o2001) == 0  # nothing written
    assert outputs == [1, 0, 1, 0, 1, 0] and form.elements[1].value == 1  # shown all the same
    assert [r.kind for r in sink.records] == ["operator"] and view.errors == []


def test_demo_forms_load_and_use_every_element_type(qtbot) -> None:
    symbols = load_symbols(EXAMPLE / "symbols.csv")
    forms, found = load_forms(EXAMPLE / "forms", symbols)
    assert found == [] and len(forms) >= 3
    used = {el.TYPE for f in forms for el in f.elements}
    assert used == set(ELEMENT_TYPES)
    trigger = next(f for f in forms if any(el.Name == "Пуск" for el in f.elements))
    start = next(el for el in trigger.elements if el.Name == "Пуск")
    assert start.TYPE == "DiscreteBase" and start.InAddr.hmi == 0o40042 and start.Enabled
    assert sorted(el.Address.hmi for el in trigger.elements if el.TYPE == "Graph") == [0o40003, 0o40005]
    eng = engine()[0]
    for form in forms:
        view = FormView(form, engine_target(eng))
        qtbot.addWidget(view)
        view.refresh(eng.snapshot)
        assert not view.grab().isNull() and view.errors == []


def test_a_failing_element_is_reported_and_the_others_go_on(qtbot, tmp_path, caplog) -> None:
    form = load_form(write_form(tmp_path, [
        {"type": "DiscreteBase", "Name": "A", "x": 0, "y": 0, "w": 100, "h": 30, "InAddr": "02120"},
        {"type": "DiscreteBase", "Name": "B", "x": 0, "y": 40, "w": 100, "h": 30, "InAddr": "02121"},
    ]))
    reported: list[str] = []
    view = FormView(form, engine_target(engine()[0]), report=reported.append)
    qtbot.addWidget(view)

    def broken(snapshot) -> bool:
        raise RuntimeError("boom")

    form.elements[0].refresh = form.elements[0].settle = broken  # read by its update or the form's bank
    with caplog.at_level(logging.ERROR, logger="hmi_forms.widgets.form_view"):
        for scan in range(4):  # it fails at every refresh: said once
            view.refresh(snap(bits={0o2120: scan % 2, 0o2121: 1 - scan % 2}, scan=scan))
    assert len(view.errors) == 1 and 'element "A": update failed' in view.errors[0]
    assert reported == view.errors  # to the operator (the workstation's health strip)...
    [logged] = caplog.records  # ...and to the log, with the traceback
    assert logged.getMessage() == view.errors[0] and "boom" in str(logged.exc_info[1])
    assert form.elements[0].stale and form.elements[1].value == 0
    assert not view.grab().isNull()


def test_a_dial_repaints_when_its_text_changes_or_its_needle_moves_a_pixel(qtbot, tmp_path) -> None:
    form = one(tmp_path, "AnalogBase", w=140, h=140, InAddr="04010", devices=LEVEL, Device="Level",
               Appearance="dial", Precision=0)
    view = FormView(form, engine_target(engine()[0]))
    qtbot.addWidget(view)
    asked: list[object] = []
    view.update = lambda *rect: asked.append(rect)  # type: ignore[method-assign]
    view.refresh(snap(words={0o4010: 2048}))
    assert len(asked) == 1
    view.refresh(snap(scan=1, words={0o4010: 2049}))  # 50.0 %: same text, the needle moves < 1 px
    assert len(asked) == 1
    view.refresh(snap(scan=2, words={0o4010: 2100}))  # 51 %: the text changes
    assert len(asked) == 2
    before = image(view, qtbot)
    view.refresh(snap(scan=3, words={0o4010: 2048}))
    assert len(asked) == 3 and differs(before, image(view, qtbot)) > 0
