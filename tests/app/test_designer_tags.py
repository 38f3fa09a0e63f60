"""The designer keeps a tag's truth: a new gauge takes its tag's conversion, the tag browser makes
the element fitting a tag, and `check` and the problems pane warn of a contradicting conversion."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from PySide6.QtCore import QMimeData, QPointF, Qt
from PySide6.QtGui import QDropEvent
from pytestqt.qtbot import QtBot

from app.cli import main
from app.gui.designer.canvas import TAG_MIME
from app.gui.designer.window import DesignerWindow
from netplc.address import data_index
from netplc.memory import Snapshot
from tests.app.test_designer import make_window
from tests.commands import run_in_process

TEMP_ADDR = 0o4012  # symbols.csv: TEMP, raw 0..1000 for -50..150 °C


def temperature(word: int) -> Snapshot:
    empty = Snapshot.empty()
    data = bytearray(empty.data)
    i = data_index(TEMP_ADDR)
    data[i], data[i + 1] = word & 0xFF, word >> 8
    return Snapshot(empty.bits, bytes(data), 1, 0.0, 0.0, "run")


def test_a_new_gauge_on_temp_shows_the_tags_value(qtbot: QtBot, demo_copy: Path) -> None:
    w = make_window(qtbot, demo_copy / "forms" / "02_analog.hmi")
    raw = w.design.add("AnalogBase")
    assert not {"AppMin", "AppMax", "PhyMin", "PhyMax", "Device"} & set(raw)  # none of its own
    w.properties.commit("InAddr", "TEMP")
    raw = w.design.doc.elements[-1]
    assert raw["InAddr"] == "TEMP" and raw["Name"] == "Температура 1"  # named by the tag, one step
    w.design.undo.undo()
    assert "InAddr" not in raw and raw["Name"] == "AnalogBase"
    w.design.undo.redo()
    item = w.design.items[id(raw)]
    assert item.problems == [] and item.model is not None
    w.design.show_snapshot(temperature(990))  # 148 °C by the tag (the bug showed 24.2 with 0..4095)
    assert item.model.text == "148.0"
    assert item.model.Units == "°C" and item.model.PhyHigh == 120  # the tag's unit and H limit
    assert w.problems.recheck() == [] and w.problems.warnings == []


def test_a_tag_dropped_on_the_canvas_becomes_its_element(qtbot: QtBot, demo_copy: Path) -> None:
    w = make_window(qtbot, demo_copy / "forms" / "02_analog.hmi")
    browser = w.tag_browser
    browser.search.setText("темпер")  # the description, any case
    shown = [browser.list.item(i).data(Qt.ItemDataRole.UserRole) for i in range(browser.list.count())]
    assert shown == ["TEMP", "TEMP_SP"]
    w.show()
    data = QMimeData()
    data.setData(TAG_MIME, b"TEMP")
    at = w.canvas.mapFromScene(QPointF(400, 296))
    drop = QDropEvent(at.toPointF(), Qt.DropAction.CopyAction, data, Qt.MouseButton.LeftButton,
                      Qt.KeyboardModifier.NoModifier)
    w.canvas.dropEvent(drop)
    raw = w.design.doc.elements[-1]
    assert raw["type"] == "AnalogBase" and raw["InAddr"] == "TEMP" and raw["Name"] == "Температура 1"
    assert (raw["x"], raw["y"]) == (400, 296)
    model = w.design.items[id(raw)].model
    assert model is not None and model.Units == "°C" and model.scaling.PhyMax == 150
    w.design.undo.undo()
    assert raw not in w.design.doc.elements
    browser.search.setText("TRIGGER")
    browser.list.itemDoubleClicked.emit(browser.list.item(0))
    raw = w.design.doc.elements[-1]
    assert raw["type"] == "DiscreteBase" and raw["InAddr"] == "TRIGGER"
    assert w.design.items[id(raw)].problems == []


def test_a_trend_takes_a_bit_tag_as_check_does(qtbot: QtBot, demo_copy: Path) -> None:
    w = make_window(qtbot, demo_copy / "forms" / "02_analog.hmi")
    w.design.add("Graph")
    w.properties.commit("Address", "TRIGGER")
    raw = w.design.doc.elements[-1]
    assert raw["Address"] == "TRIGGER" and w.design.items[id(raw)].problems == []


def contradict(form: Path) -> None:
    doc = json.loads(form.read_text(encoding="utf-8"))
    gauge = next(e for e in doc["elements"] if e.get("InAddr") == "TEMP")
    gauge.pop("Device")
    gauge.update({"AppMin": 0, "AppMax": 4095, "PhyMin": 0, "PhyMax": 100, "Units": "K"})
    form.write_text(json.dumps(doc, ensure_ascii=False), encoding="utf-8")


def test_check_and_the_problems_pane_warn_of_a_contradicting_conversion(
        qtbot: QtBot, demo_copy: Path, capsys: pytest.CaptureFixture[str]) -> None:
    form = demo_copy / "forms" / "02_analog.hmi"
    contradict(form)
    r = run_in_process(main, ["check", demo_copy], capsys)  # test_check.py runs `main.py check` itself
    assert r.returncode == 0, r.stdout + r.stderr  # a warning: the station still opens the form
    warned = [line for line in r.stdout.splitlines() if line.startswith("предупреждение:")]  # the demo is ru
    assert any("02_analog.hmi" in line and "AppMax: 0..4095 -> 0..100 противоречит тегу TEMP с "
               "0..1000 -> -50..150: слово 1000 здесь показывает 24.4, у тега 150.0 °C" in line
               for line in warned), warned
    assert any('Units: "K" противоречит тегу TEMP с единицей "°C"' in line for line in warned), warned
    w: DesignerWindow = make_window(qtbot, form)
    assert w.problems.recheck() == []
    assert len(w.problems.warnings) == 2
    texts = [w.problems.item(i).text() for i in range(w.problems.count())]
    assert all(t.startswith('warning: элемент "') for t in texts), texts  # check's words
    flagged = [i.raw.get("Name") for i in w.design.items.values() if i.flagged]
    assert len(flagged) == 1
    assert "warning" in w.problems_label.text()


def test_the_canvas_shows_the_tags_alarm_zones_and_unit_under_a_gauge(qtbot: QtBot, demo_copy: Path) -> None:
    from PySide6.QtGui import QColor, QImage, QPainter
    from PySide6.QtWidgets import QStyleOptionGraphicsItem

    w = make_window(qtbot, demo_copy / "forms" / "02_analog.hmi")
    raw = w.design.add_tag("TEMP")
    item = w.design.items[id(raw)]
    w.design.select([])  # no selection outline or handles over the band
    image = QImage(int(raw["w"]), int(raw["h"]), QImage.Format.Format_ARGB32)
    image.fill(QColor("#ffffff"))
    painter = QPainter(image)
    item.paint(painter, QStyleOptionGraphicsItem(), None)
    painter.end()
    y = image.height() - 3

    def at(fraction: float) -> str:
        return image.pixelColor(int(fraction * (image.width() - 1)), y).name()

    # TEMP: -50..150 °C, H 120 (amber from 0.85), HH 140 (red from 0.95)
    assert (at(0.5), at(0.9), at(0.98)) == ("#c8d2dc", "#f2a900", "#d32f2f")


def test_the_designer_speaks_russian(qtbot: QtBot, demo_copy: Path) -> None:
    from PySide6.QtWidgets import QApplication

    from app.gui import i18n

    app = QApplication.instance()
    assert isinstance(app, QApplication)
    i18n.install(app, "ru")
    try:
        w = make_window(qtbot, demo_copy / "forms" / "02_analog.hmi")
        assert [a.text() for a in w.menuBar().actions()] == ["&Файл", "&Правка", "&Упорядочить", "&Вид"]
        assert w.tag_browser.search.placeholderText().startswith("Поиск тегов")
        hints = [w.palette.item(i).text().replace("\u200b", "") for i in range(w.palette.count())]
        assert "StaticText\nнадпись" in hints
        assert w.windowTitle() == "02_analog.hmi — конструктор форм NetPlc"
        assert w.properties.title.text() == "Форма 02_analog.hmi"
        w.design.add("AnalogBase")
        appearance = w.properties.editors["Appearance"]
        assert appearance.combo.itemText(0) == "(по умолчанию)"  # type: ignore[attr-defined]
    finally:
        i18n.uninstall(app)
