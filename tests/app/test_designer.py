"""The form designer: adding every element type, editing and refusing properties, undo/redo, saving,
the problems pane, the clipboard, arranging, the live preview over a real Modbus server, the CLI."""

from __future__ import annotations

import copy
import itertools
import json
import logging
import socket
from pathlib import Path

import pytest
from PySide6.QtCore import QPoint, QPointF, QRectF, Qt
from PySide6.QtGui import QDropEvent, QImage, QMouseEvent, QPainter
from PySide6.QtWidgets import QApplication, QWidget
from pytestqt.qtbot import QtBot

from app.cli import main
from app.gui.designer.canvas import ELEMENT_MIME
from app.gui.designer.commands import MISSING
from app.gui.designer.editors import BoolEditor, ColorEditor, ComboEditor, FontEditor, LineEditor
from app.gui.designer.properties import PropertyPanel
from app.gui.designer.station import open_target
from app.gui.designer.window import DesignerWindow
from hmi_forms.elements import ELEMENT_TYPES
from hmi_forms.form import load_form
from hmi_forms.form_doc import read_doc
from netplc.program import load_symbols, parse
from netplc.simulator import Simulator
from tests.app.conftest import DEMO, copy_demo


def make_window(qtbot: QtBot, target: Path) -> DesignerWindow:
    window = DesignerWindow(open_target(target))
    window.confirm = lambda question: True  # type: ignore[method-assign]
    window.warned = []  # type: ignore[attr-defined]
    window.warn = window.warned.append  # type: ignore[attr-defined,method-assign]
    qtbot.addWidget(window)
    return window


@pytest.fixture
def demo_copy(tmp_path: Path) -> Path:
    """An English copy of the demo: these tests read the designer's problems word for word, which it
    says in the station's Language (the demo's Russian: test_problems_pane_speaks_the_station_language)."""
    return copy_demo(tmp_path / "station", "en")


@pytest.fixture
def window(qtbot: QtBot, demo_copy: Path) -> DesignerWindow:
    return make_window(qtbot, demo_copy / "forms" / "01_trigger.hmi")


def named(window: DesignerWindow, name: str) -> dict:
    return next(e for e in window.design.doc.elements if e.get("Name") == name)


def select(window: DesignerWindow, *names: str) -> None:
    window.design.select([named(window, n) for n in names])


def rendered(window: DesignerWindow) -> QImage:
    window.show()
    return window.canvas.viewport().grab().toImage()


def test_edit_add_element_offers_every_type_of_the_manual_and_draws_each(
        window: DesignerWindow, qtbot: QtBot) -> None:
    assert list(window.add_actions) == list(ELEMENT_TYPES) and len(ELEMENT_TYPES) == 13
    before = len(window.design.doc.elements)
    for kind, action in window.add_actions.items():
        action.trigger()
        raw = window.design.doc.elements[-1]
        assert raw["type"] == kind and window.design.selected() == [raw]
        item = window.design.items[id(raw)]
        assert item.model is not None and type(item.model).__name__ == kind
    assert len(window.design.doc.elements) == before + 13
    rendered(window)
    drawn = [window.design.items[id(r)].widget for r in window.design.doc.elements[before:]]
    assert all(w is not None for w in drawn)  # made by the workstation's widget classes when shown
    assert {type(w).__module__ for w in drawn} <= {
        "hmi_forms.widgets.discrete", "hmi_forms.widgets.gauges", "hmi_forms.widgets.analog_output",
        "hmi_forms.widgets.static", "hmi_forms.widgets.trend", "hmi_forms.widgets.journal"}
    names = [r["Name"] for r in window.design.doc.elements]
    assert len(names) == len(set(names))


def test_an_element_dropped_from_the_palette_lands_where_it_is_dropped(window: DesignerWindow) -> None:
    mime = window.palette.mimeData([window.palette.item(2)])
    assert bytes(mime.data(ELEMENT_MIME).data()) == b"DiscreteBase"
    window.show()
    target = window.canvas.mapFromScene(QPointF(101, 203))
    event = QDropEvent(QPointF(target), Qt.DropAction.CopyAction, mime, Qt.MouseButton.LeftButton,
                       Qt.KeyboardModifier.NoModifier)
    window.canvas.dropEvent(event)
    raw = window.design.doc.elements[-1]
    assert raw["type"] == "DiscreteBase" and (raw["x"], raw["y"]) == (104, 200)  # snapped to the 8 px grid


def test_property_edit_is_one_undo_step_and_the_canvas_follows(window: DesignerWindow) -> None:
    select(window, "Пуск")
    editor = window.properties.editors["TextFalse"]
    assert isinstance(editor, LineEditor) and editor.line.text() == "Пуск"
    editor.line.setText("Старт")
    editor.line.editingFinished.emit()
    raw = named(window, "Пуск")
    assert raw["TextFalse"] == "Старт"
    assert window.design.items[id(raw)].model.TextFalse == "Старт"  # type: ignore[union-attr]
    window.design.undo.undo()
    assert raw["TextFalse"] == "Пуск" and editor.line.text() == "Пуск"
    window.design.undo.redo()
    assert raw["TextFalse"] == "Старт"


def test_editors_know_the_kind_of_each_property(window: DesignerWindow) -> None:
    select(window, "Связь с узлом 0")
    e = window.properties.editors
    assert isinstance(e["InAddr"], LineEditor) and e["InAddr"].line.completer() is not None
    assert isinstance(e["BackColorFalse"], ColorEditor)
    assert isinstance(e["Font"], FontEditor)
    assert isinstance(e["Enabled"], BoolEditor)
    assert isinstance(e["BorderStyle"], ComboEditor) and e["BorderStyle"].combo.findText("Fixed3D") > 0
    assert isinstance(e["ImageTrue"], ComboEditor)
    completions = e["InAddr"].line.completer().model().stringList()
    assert "NRD_OK" in completions and "LEVEL" in completions


def test_bad_values_are_refused_with_the_reason(window: DesignerWindow) -> None:
    select(window, "Пуск")
    raw = copy.deepcopy(named(window, "Пуск"))
    addr = window.properties.editors["InAddr"]
    assert isinstance(addr, LineEditor)
    addr.line.setText("09999")
    addr.line.textEdited.emit("09999")  # validated as it is typed
    assert not addr.reason.isHidden() and "not an octal address" in addr.reason.text()
    addr.line.editingFinished.emit()
    assert named(window, "Пуск") == raw and not window.design.undo.canUndo()
    for key, text, reason in (("InAddr", "NO_SUCH", 'unknown tag or symbol "NO_SUCH"'),
                              ("h", "-5", "out of range"),
                              ("Name", "Время", "taken by another element")):
        editor = window.properties.editors[key]
        assert isinstance(editor, LineEditor)
        editor.line.setText(text)
        editor.line.editingFinished.emit()
        assert reason in editor.reason.text(), key
    color = window.properties.editors["BackColor"]
    color.submit("#12345")
    assert "is not a colour" in color.reason.text()
    assert named(window, "Пуск") == raw
    addr.line.setText("START_WORD.3")  # a symbol's bit: accepted
    addr.line.editingFinished.emit()
    assert named(window, "Пуск")["InAddr"] == "START_WORD.3" and addr.reason.isHidden()


def test_conversion_limits_and_sync_type_are_checked_together(qtbot: QtBot, demo_copy: Path) -> None:
    w = make_window(qtbot, demo_copy / "forms" / "02_analog.hmi")
    select(w, "Уровень")
    device = w.properties.editors["Device"]
    assert isinstance(device, ComboEditor) and device.combo.findText("Temperature") > 0
    w.properties.commit("AppMin", 0)
    assert "either Device or AppMin" in w.properties.editors["AppMin"].reason.text()
    w.properties.commit("Device", MISSING)  # bound to tag LEVEL: takes the tag's conversion
    assert "Device" not in named(w, "Уровень") and not w.properties.editors["Device"].reason.text()
    assert w.design.items[id(named(w, "Уровень"))].model.scaling.AppMax == 4095
    w.properties.commit("SyncType", "PACE_1S")
    assert named(w, "Уровень")["SyncType"] == "PACE_1S"
    w.properties.commit("SyncType", "010000")
    assert "SyncType" in w.properties.editors["SyncType"].reason.text()


def test_a_tag_name_is_accepted_like_a_symbol(qtbot: QtBot, demo_copy: Path) -> None:
    tags = "name,address,type,unit\nPUMP_RUNNING,02122,bool,\n"
    (demo_copy / "tags.csv").write_text(tags, encoding="utf-8")
    w = make_window(qtbot, demo_copy / "forms" / "02_analog.hmi")
    w.design.add("DiscreteBase")
    w.properties.commit("InAddr", "PUMP_RUNNING")
    assert w.design.doc.elements[-1]["InAddr"] == "PUMP_RUNNING"
    assert "PUMP_RUNNING" in w.properties.names


def test_several_selected_elements_are_edited_at_once(window: DesignerWindow) -> None:
    select(window, "ТА: счётный вход", "TA[2]: выход триггера")
    editors = window.properties.editors
    assert "Name" not in editors and editors["LineWidth"].line.text() == "2"  # type: ignore[attr-defined]
    window.properties.commit("LineWidth", 3)
    widths = {named(window, n)["LineWidth"] for n in ("ТА: счётный вход", "TA[2]: выход триггера")}
    assert widths == {3}
    window.design.undo.undo()
    assert named(window, "ТА: счётный вход")["LineWidth"] == 2


def test_undo_redo_chain_gives_back_each_state(window: DesignerWindow) -> None:
    d = window.design
    states = [copy.deepcopy(d.doc.data)]
    d.add("StaticText")
    states.append(copy.deepcopy(d.doc.data))
    d.move_by(d.selected(), 5, 0)
    d.move_by(d.selected(), 5, 3)  # merged with the previous move: one step
    states.append(copy.deepcopy(d.doc.data))
    select(window, "Пуск", "Время")
    d.align("top")
    states.append(copy.deepcopy(d.doc.data))
    d.z_order("back")
    states.append(copy.deepcopy(d.doc.data))
    d.delete(d.selected())
    states.append(copy.deepcopy(d.doc.data))
    window.properties.commit("title", "Новый")  # a form setting, nothing selected
    states.append(copy.deepcopy(d.doc.data))
    assert d.undo.count() == len(states) - 1
    for state in reversed(states[:-1]):
        d.undo.undo()
        assert d.doc.data == state
    assert d.undo.isClean()
    for state in states[1:]:
        d.undo.redo()
        assert d.doc.data == state
    assert len(d.items) == len(d.doc.elements)


def drag(qtbot: QtBot, window: DesignerWindow, start: QPointF, end: QPointF) -> None:
    """Press at scene point `start`, move in steps, release at `end` (QTest's mouseMove carries no
    pressed button, so the moves are sent as events)."""
    vp = window.canvas.viewport()
    a, b = window.canvas.mapFromScene(start), window.canvas.mapFromScene(end)
    qtbot.mousePress(vp, Qt.MouseButton.LeftButton, pos=a)
    for k in (1, 2, 3):
        to = a + (b - a) * k / 3
        move = QMouseEvent(QMouseEvent.Type.MouseMove, QPointF(to), QPointF(vp.mapToGlobal(to)),
                           Qt.MouseButton.NoButton, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier)
        QApplication.sendEvent(vp, move)
    qtbot.mouseRelease(vp, Qt.MouseButton.LeftButton, pos=b)


def test_move_with_the_mouse_snaps_to_the_grid_and_is_one_step(window: DesignerWindow,
                                                               qtbot: QtBot) -> None:
    window.show()
    qtbot.waitExposed(window)
    d = window.design
    raw = named(window, "Время")
    item = d.items[id(raw)]
    centre = item.sceneBoundingRect().center()
    drag(qtbot, window, centre, centre + QPointF(-33, 33))
    assert (raw["x"], raw["y"]) != (745, 245)
    assert raw["x"] % 8 == 0 and raw["y"] % 8 == 0
    assert d.undo.count() == 1
    d.undo.undo()
    assert (raw["x"], raw["y"]) == (745, 245) and item.pos() == QPointF(745, 245)


def test_resize_by_a_handle_and_select_by_rubber_band(window: DesignerWindow, qtbot: QtBot) -> None:
    window.show()
    qtbot.waitExposed(window)
    d = window.design
    select(window, "Время")
    raw = named(window, "Время")  # 745, 245, 195 x 100
    drag(qtbot, window, QPointF(745 + 195, 245 + 100), QPointF(745 + 195 - 50, 245 + 100 + 21))
    assert (raw["x"], raw["y"], raw["w"], raw["h"]) == (745, 245, 143, 123)  # moved edges snap
    assert d.undo.count() == 1
    d.scene.clearSelection()
    drag(qtbot, window, QPointF(735, 130), QPointF(950, 230))  # from the empty form around two labels
    assert sorted(r["Name"] for r in d.selected()) == ["Выход триггера", "Связь с узлом 0"]


def test_arrow_keys_move_and_resize_the_selection(window: DesignerWindow, qtbot: QtBot) -> None:
    select(window, "Пуск")
    raw = named(window, "Пуск")
    window.canvas.setFocus()
    qtbot.keyClick(window.canvas, Qt.Key.Key_Right)
    qtbot.keyClick(window.canvas, Qt.Key.Key_Down, Qt.KeyboardModifier.ControlModifier)
    qtbot.keyClick(window.canvas, Qt.Key.Key_Left, Qt.KeyboardModifier.ShiftModifier)
    assert (raw["x"], raw["y"], raw["w"], raw["h"]) == (746, 68, 194, 64)


def test_align_distribute_and_z_order(window: DesignerWindow) -> None:
    d = window.design
    select(window, "Пуск", "Связь с узлом 0", "Время")
    d.align("right")
    rights = {named(window, n)["x"] + named(window, n)["w"] for n in ("Пуск", "Связь с узлом 0", "Время")}
    assert rights == {940}
    d.distribute("v")
    boxes = sorted((named(window, n)["y"], named(window, n)["h"])
                   for n in ("Пуск", "Связь с узлом 0", "Время"))
    gaps = [b[0] - (a[0] + a[1]) for a, b in itertools.pairwise(boxes)]
    assert max(gaps) - min(gaps) <= 1
    select(window, "Заголовок")
    d.z_order("front")
    assert d.doc.elements[-1]["Name"] == "Заголовок"
    assert d.items[id(d.doc.elements[-1])].zValue() == len(d.doc.elements) - 1
    d.z_order("lower")
    assert d.doc.elements[-2]["Name"] == "Заголовок"


def test_copy_paste_renames_and_offsets(window: DesignerWindow) -> None:
    select(window, "Пуск", "Время")
    window.copy()
    window.paste()
    pasted = window.design.selected()
    assert [r["Name"] for r in pasted] == ["Пуск 1", "Время 1"]
    assert pasted[0]["x"] == named(window, "Пуск")["x"] + 8
    window.cut()
    assert "Пуск 1" not in [r.get("Name") for r in window.design.doc.elements]


def test_problems_pane_lists_what_check_reports_and_goes_to_the_element(window: DesignerWindow) -> None:
    assert window.problems.count() == 0
    window.design.add("DiscreteBase")
    raw = window.design.doc.elements[-1]
    window.design.add("SyncGenerator")
    found = window.problems.recheck()
    assert [t.split(": ", 1)[1] for t in found] == [
        'element "DiscreteBase": InAddr: missing required property',
        'element "SyncGenerator": OutAddr: missing required property']
    window.problems.go_to(window.problems.item(0))
    assert window.design.selected() == [raw]
    assert window.design.items[id(raw)].flagged
    assert window.undo_action.text() == "&Undo Add SyncGenerator"
    select(window, "Время")
    window.properties.commit("w", 400)  # now past the form's right edge: a problem of the form
    found = window.problems.recheck()
    assert any('element "Время": w: the element (745,245 400x100) extends past the form' in t for t in found)
    assert window.design.items[id(named(window, "Время"))].flagged


@pytest.mark.parametrize("language", ["ru", "en"])
def test_problems_pane_speaks_the_station_language(qtbot: QtBot, tmp_path: Path, language: str) -> None:
    """The pane says a form's problems as `check` does, in the Language of the station whose form it
    edits, naming element and property as they are; a click goes to the element in either."""
    from app.station.check import check_station

    station = copy_demo(tmp_path / "st", language)
    w = make_window(qtbot, station / "forms" / "01_trigger.hmi")
    w.design.add("DiscreteBase")
    raw = w.design.doc.elements[-1]
    found = w.problems.recheck()
    said = {"ru": 'элемент "DiscreteBase": InAddr: нет обязательного свойства',
            "en": 'element "DiscreteBase": InAddr: missing required property'}[language]
    assert [t.split(": ", 1)[1] for t in found] == [said]
    w.problems.go_to(w.problems.item(0))
    assert w.design.selected() == [raw]
    assert w.save() is True
    assert any(p.endswith(said) for p in check_station(station).problems)  # what check says of the saved form
    (station / "forms" / "zz.hmi").write_text("{", encoding="utf-8")
    assert w.open_path(station / "forms" / "zz.hmi") is False
    assert w.warned == [f"{station / 'forms' / 'zz.hmi'}:1:2: " + {
        "ru": "ошибка JSON: ожидается имя свойства в двойных кавычках",
        "en": "bad JSON: Expecting property name enclosed in double quotes"}[language]]


def test_save_with_problems_asks_first(window: DesignerWindow) -> None:
    path = window.design.doc.path
    before = path.read_bytes()
    window.design.add("DiscreteBase")
    window.confirm = lambda question: False  # type: ignore[method-assign]
    assert window.save() is False
    assert path.read_bytes() == before and window.problems.count() == 1
    window.confirm = lambda question: True  # type: ignore[method-assign]
    assert window.save() is True
    assert read_doc(path).elements[-1]["type"] == "DiscreteBase"


def test_save_and_reload_equal(window: DesignerWindow, demo_copy: Path) -> None:
    d = window.design
    d.add("StaticText")
    window.properties.commit("Text", "Подпись")
    select(window, "Пуск")
    window.properties.commit("Font", {"Family": "DejaVu Sans", "Size": 12, "Bold": True})
    window.properties.commit("BackColor", "#a0b0c0")
    assert window.save() and d.undo.isClean()
    again = read_doc(d.doc.path)
    assert again.data == d.doc.data
    form = load_form(d.doc.path, load_symbols(demo_copy / "symbols.csv"))
    assert form.elements[-1].Text == "Подпись"  # type: ignore[attr-defined]


@pytest.mark.parametrize("name", ["01_trigger.hmi", "02_analog.hmi", "03_sync.hmi"])
def test_designer_saves_an_untouched_demo_form_byte_identical(qtbot: QtBot, demo_copy: Path,
                                                               name: str) -> None:
    path = demo_copy / "forms" / name
    before = path.read_bytes()
    w = make_window(qtbot, path)
    rendered(w)
    out = demo_copy / "forms" / f"copy_{name}"
    assert w.save(out)
    assert out.read_bytes() == before == (DEMO / "forms" / name).read_bytes()


def test_canvas_shows_what_the_workstation_shows(window: DesignerWindow) -> None:
    """The canvas draws with the workstation's widgets: a discrete button's colours appear."""
    image = rendered(window)
    assert image.width() > 200
    colors = {image.pixelColor(x, y).name()
              for x in range(0, image.width(), 7) for y in range(0, image.height(), 7)}
    assert "#d32f2f" in colors  # "Узел 0: нет связи": BackColorFalse of a DiscreteColorLabel


def test_preview_live_reads_a_running_modbus_server(qtbot: QtBot, demo_copy: Path) -> None:
    sim = Simulator(parse("TNA $03760\nYON $02131\nJMP 0\n"), tick=0.02)  # 02131 = LEVEL_OK
    sim.start()
    try:
        sim.engine.write_word(0o4010, 2048, user="test")  # LEVEL: half of 0..4095
        w = make_window(qtbot, demo_copy / "forms" / "02_analog.hmi")
        item = w.design.items[id(named(w, "Уровень"))]
        w.start_preview("127.0.0.1", sim.port)
        assert w.preview is not None
        assert any(t == "holding" and a <= 0o4010 // 2 < a + n for t, a, n in w.preview.requests)
        qtbot.waitUntil(lambda: getattr(item.model, "hw", None) == 2048, timeout=5000)
        assert not item.model.stale  # type: ignore[union-attr]
        assert "Preview live" in w.preview_label.text()
        w.stop_preview()
    finally:
        sim.stop()
    assert sim.engine.snapshot.get_word(0o4030) == 0  # nothing was written (the setpoint stays 0)


def test_preview_of_a_station_that_is_down_says_so_and_goes_live_when_it_answers(
        qtbot: QtBot, demo_copy: Path, caplog) -> None:
    """Polled in the preview's worker thread: each failure is said in the status bar, the log has it
    once, and the preview goes live as soon as the station answers on that port."""
    with socket.socket() as s:  # a port nothing listens on, for now
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    w = make_window(qtbot, demo_copy / "forms" / "02_analog.hmi")
    said: list[str] = []
    with caplog.at_level(logging.WARNING, logger="hmi_forms.widgets.worker"):
        w.start_preview("127.0.0.1", port)
        assert w.preview is not None
        w.preview.status.connect(said.append)
        qtbot.waitUntil(lambda: len(said) >= 3, timeout=5000)  # polled again and again, 0.2 s apart
        assert all(text.startswith("Preview: cannot connect") for text in said)
        assert "cannot connect" in w.preview_label.text()
        assert len([r for r in caplog.records if "cannot connect" in r.getMessage()]) == 1
        sim = Simulator(parse("JMP 0\n"), port=port, tick=0.02)
        sim.start()
        try:
            qtbot.waitUntil(lambda: "Preview live" in w.preview_label.text(), timeout=5000)
        finally:
            w.stop_preview()
            sim.stop()


def test_cli_opens_a_form_and_a_station(demo_copy: Path, tmp_path: Path, qtbot: QtBot) -> None:
    png = tmp_path / "form.png"
    assert main(["design", str(demo_copy / "forms" / "03_sync.hmi"), "--screenshot", str(png)]) == 0
    image = QImage(str(png))
    assert (image.width(), image.height()) == (1366, 768)
    png2 = tmp_path / "station.png"
    assert main(["design", str(demo_copy), "--screenshot", str(png2)]) == 0
    assert png2.is_file()
    assert main(["design", str(tmp_path / "nowhere")]) == 2


def test_a_new_form_is_created_where_it_is_named(qtbot: QtBot, tmp_path: Path) -> None:
    path = tmp_path / "new.hmi"
    w = make_window(qtbot, path)
    w.design.add("StaticText")
    assert w.save()
    assert json.loads(path.read_text(encoding="utf-8"))["elements"][0]["Text"] == "Text"
    assert w.preview_action.isEnabled() is False  # no station beside it


def test_a_station_opens_its_first_form_and_offers_the_others(qtbot: QtBot, demo_copy: Path) -> None:
    w = make_window(qtbot, demo_copy)
    assert w.design.doc.path.name == "01_trigger.hmi"
    assert w.preview_action.isEnabled()
    menu = next(a.menu() for a in w.menuBar().actions() if a.text() == "&File")
    forms = next(a.menu() for a in menu.actions() if a.text() == "Forms of the station")
    assert [a.text() for a in forms.actions()] == ["01_trigger.hmi", "02_analog.hmi", "03_sync.hmi"]
    forms.actions()[2].trigger()
    assert w.design.doc.path.name == "03_sync.hmi" and w.windowTitle().startswith("03_sync.hmi")
    w.design.add("DateTime")
    assert w.undo_action.isEnabled() and w.windowTitle().startswith("03_sync.hmi*")


def test_an_image_of_the_forms_folder_is_taken_into_the_form_in_one_step(qtbot: QtBot,
                                                                          demo_copy: Path) -> None:
    w = make_window(qtbot, demo_copy / "forms" / "01_trigger.hmi")  # a form without images
    select(w, "Пуск")
    editor = w.properties.editors["ImageTrue"]
    assert isinstance(editor, ComboEditor)
    labels = [editor.combo.itemText(i) for i in range(editor.combo.count())]
    assert "+ images/pump_on_0.png" in labels and "-1: none" in labels
    editor.combo.activated.emit(labels.index("+ images/pump_on_0.png"))
    assert w.design.doc.data["images"] == ["images/pump_on_0.png"] and named(w, "Пуск")["ImageTrue"] == 0
    assert w.design.items[id(named(w, "Пуск"))].problems == []
    assert w.properties.editors["ImageTrue"].combo.currentText() == "0: images/pump_on_0.png"
    w.design.undo.undo()
    assert "images" not in w.design.doc.data and "ImageTrue" not in named(w, "Пуск")
    picture = w.design.add("StaticPicture")
    assert picture["Image"] in w.design.image_files()


def test_a_broken_form_opens_with_its_problems_and_an_uneditable_one_is_refused(
        qtbot: QtBot, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    broken = tmp_path / "broken.hmi"
    broken.write_text(json.dumps({
        "form": {"title": 3}, "devices": "x", "images": [5],
        "elements": [{"type": "Nope", "Name": 5, "x": "a"}, {"type": "DiscreteBase"},
                     {"type": "StaticText", "Name": "T", "x": 0, "y": 0, "w": 99, "h": 30, "Text": "t",
                      "Font": {"Size": 1000}}]}), encoding="utf-8")
    w = make_window(qtbot, broken)
    found = w.problems.recheck()
    assert 'form: title: expected text, got 3' in "\n".join(found)
    assert any('element "T": Font: font size 1000 is out of range' in t for t in found)
    rendered(w)
    items = [w.design.items[id(r)] for r in w.design.doc.elements]
    assert items[0].model is None and items[2].model is not None  # drawn from its good properties
    assert all(i.flagged or i.problems for i in items)
    w.design.undo.setClean()
    (tmp_path / "list.hmi").write_text('{"form": [1], "elements": []}', encoding="utf-8")
    assert main(["design", str(tmp_path / "list.hmi")]) == 2
    assert "list.hmi: form: must be an object" in capsys.readouterr().err


def test_click_and_ctrl_click_select_and_delete_removes(window: DesignerWindow, qtbot: QtBot) -> None:
    window.show()
    qtbot.waitExposed(window)
    d = window.design
    vp = window.canvas.viewport()

    def at(name: str) -> QPoint:
        return window.canvas.mapFromScene(d.items[id(named(window, name))].sceneBoundingRect().center())

    qtbot.mouseClick(vp, Qt.MouseButton.LeftButton, pos=at("Пуск"))
    assert [r["Name"] for r in d.selected()] == ["Пуск"]
    qtbot.mouseClick(vp, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.ControlModifier, at("Время"))
    assert sorted(r["Name"] for r in d.selected()) == ["Время", "Пуск"]
    qtbot.mouseClick(vp, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.ControlModifier, at("Пуск"))
    assert [r["Name"] for r in d.selected()] == ["Время"]
    window.activateWindow()
    qtbot.waitActive(window)
    window.canvas.setFocus()
    qtbot.keyClick(window.canvas, Qt.Key.Key_Delete)
    assert "Время" not in [r["Name"] for r in d.doc.elements]
    d.undo.undo()
    assert "Время" in [r["Name"] for r in d.doc.elements]


def test_a_failed_save_says_why_and_keeps_the_form(window: DesignerWindow, tmp_path: Path) -> None:
    path = window.design.doc.path
    window.design.add("DateTime")
    assert window.save(tmp_path / "no" / "such" / "folder" / "f.hmi") is False
    assert "The form was not saved" in window.warned[0]  # type: ignore[attr-defined]
    assert window.design.doc.path == path and not window.design.undo.isClean()


def editor_states(panel: PropertyPanel) -> list[tuple[object, ...]]:
    """What each editor of the panel shows, the entries of its lists too (not in a picture)."""
    states: list[tuple[object, ...]] = [(panel.title.text(),)]
    for key, e in panel.editors.items():
        refusal = (e.reason.isVisibleTo(e), e.reason.text())
        if isinstance(e, LineEditor):  # ColorEditor too
            shown = (e.line.text(), e.line.placeholderText(), e.line.styleSheet())
        elif isinstance(e, ComboEditor):
            shown = ([e.combo.itemText(i) for i in range(e.combo.count())], e.combo.currentIndex())
        elif isinstance(e, BoolEditor):
            shown = (e.box.checkState(),)
        else:
            assert isinstance(e, FontEditor)
            shown = (e.button.text(),)
        states.append((key, type(e).__name__, *shown, *refusal))
    return states


def picture(widget: QWidget) -> QImage:
    """The widget as drawn on a white page (a docked panel and a window have other backgrounds)."""
    image = QImage(widget.size(), QImage.Format.Format_RGB32)
    image.fill(Qt.GlobalColor.white)
    widget.render(image)
    return image


def test_another_element_of_the_same_type_fills_the_same_editors_and_looks_as_if_new(
        window: DesignerWindow, qtbot: QtBot) -> None:
    """A click on an element of the type shown already refills its editors instead of making them
    again (most of a click's time): what it shows, a refusal of the last element's cleared and the
    panel scrolled back to the top, is what a panel made afresh for the element shows."""
    window.show()
    qtbot.waitExposed(window)
    panel = window.properties
    select(window, "Связь с узлом 0")
    editors = dict(panel.editors)
    addr = panel.editors["InAddr"]
    assert isinstance(addr, LineEditor)
    addr.line.setText("NO_SUCH")
    addr.line.editingFinished.emit()
    assert addr.reason.isVisibleTo(addr)
    panel.scroll.verticalScrollBar().setValue(panel.scroll.verticalScrollBar().maximum())
    select(window, "Выход триггера")  # DiscreteColorLabel as well
    assert panel.editors == editors  # the same editor objects
    assert not addr.reason.isVisibleTo(addr) and addr.line.text() == "040005"
    QApplication.processEvents()  # laid out: the window's docks, a refusal's line gone, the title
    fresh = PropertyPanel(window.design, panel.names)
    qtbot.addWidget(fresh)
    fresh.show_selection()
    fresh.resize(panel.size())
    fresh.show()
    qtbot.waitExposed(fresh)
    QApplication.processEvents()
    assert [id(e) for e in fresh.editors.values()] != [id(e) for e in editors.values()]
    assert editor_states(panel) == editor_states(fresh)
    assert picture(panel) == picture(fresh)
    select(window, "Пуск")  # another type: other editors; back to the first type: its own again
    assert "TextFalse" in panel.editors and panel.editors["InAddr"] is not addr
    select(window, "Связь с узлом 0")
    assert panel.editors == editors
    fresh.show_selection()  # of the same design: the element selected now
    assert editor_states(panel) == editor_states(fresh)


def test_a_journal_on_the_canvas_is_drawn_again_when_its_page_is_read(qtbot: QtBot, demo_copy: Path) -> None:
    """The canvas shows a picture of each element's widget; a journal's page is read in a thread
    after the first picture was taken, and the canvas shows the page once it is read."""
    from hmi_forms.elements.journal import MessageJournal
    from tests.app.held_archive import archive_with

    archive_with(demo_copy / "archive" / "journal.sqlite", ["первая запись", "вторая запись"])
    w = make_window(qtbot, demo_copy / "forms" / "02_analog.hmi")
    item = next(i for i in w.design.items.values() if isinstance(i.model, MessageJournal))
    w.show()
    qtbot.waitExposed(w)
    qtbot.waitUntil(lambda: item.widget is not None and item.widget.table.rowCount() == 2, timeout=10_000)
    widget = item.widget

    def drawn_as_shown() -> bool:  # the element's area of the canvas, as the widget shows itself
        shown = widget.grab().toImage().convertToFormat(QImage.Format.Format_RGB32)
        drawn = QImage(shown.size(), QImage.Format.Format_RGB32)
        painter = QPainter(drawn)
        try:
            w.design.scene.render(painter, QRectF(drawn.rect()), item.mapToScene(item.rect()).boundingRect())
        finally:
            painter.end()
        return drawn == shown

    qtbot.waitUntil(drawn_as_shown, timeout=10_000)
