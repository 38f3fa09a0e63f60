"""The data quality of what elements show, from the runtime's Readings, drawn the same way on every
element type: greyed and hatched, "?" and the quality word in the tooltip; the last value kept,
trends broken; a forced value shown as it is, marked."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from PySide6.QtGui import QColor, QImage

from app.scada.quality import LinkView, Quality, QualityMap
from app.scada.readings import Readings
from hmi_forms.elements.target import NullTarget
from hmi_forms.form import load_form
from hmi_forms.widgets import theme
from hmi_forms.widgets.form_view import FormView
from netplc.memory import Memory
from netplc.program import parse
from tests.hmi_forms.helpers import shown_form, write_form
from tests.hmi_forms.test_widgets import differs

PROGRAM = "TNA $03760\nFON C:$02110 N:NREAD S:4000 D:$04010 R:4\nJMP 0\n"  # node 0 fills 04010-04013
BOX = {"x": 0, "y": 0, "w": 200, "h": 120}
LEVEL = {"AppMin": 0, "AppMax": 4095, "PhyMin": 0, "PhyMax": 100}
ELEMENTS = [
    {"type": "AnalogBase", "Name": "dial", **BOX, "InAddr": "04010", **LEVEL, "Appearance": "dial"},
    {"type": "AnalogBase", "Name": "digital", **BOX, "x": 200, "InAddr": "04010", **LEVEL},
    {"type": "AnalogBase", "Name": "trend", **BOX, "x": 400, "InAddr": "04010", **LEVEL,
     "Appearance": "graph"},
    {"type": "AnalogOutput", "Name": "setpoint", **BOX, "y": 120, "OutAddr": "04012", **LEVEL},
    {"type": "DiscreteColorLabel", "Name": "label", **BOX, "x": 200, "y": 120, "InAddr": "040100",
     "TextTrue": "связь есть", "TextFalse": "нет связи"},
    {"type": "Graph", "Name": "bits", **BOX, "x": 400, "y": 120, "Address": "040101"},
    {"type": "AnalogBase", "Name": "local", **BOX, "y": 240, "InAddr": "04100", **LEVEL},
]
FED = ["dial", "digital", "trend", "setpoint", "label", "bits"]  # all but "local" are filled by node 0


def readings(mem: Memory, scan: int, links: LinkView) -> tuple[Readings, object]:
    qmap = QualityMap(parse(PROGRAM), [])
    snap = mem.snapshot(scan, scan * 0.1, 1_800_000_000.0 + scan, "running" if links.running else "stopped")
    return Readings(snap, qmap, links, qmap.evaluate(snap, links)), snap


@pytest.fixture
def view(qtbot, tmp_path: Path) -> FormView:
    return shown_form(qtbot, tmp_path, ELEMENTS, (600, 360))


def models(view: FormView) -> dict:
    return {m.Name: (m, w) for m, w in view.pairs}


@pytest.mark.parametrize(("links", "word"), [
    (LinkView(links={0: False}), "comm-fail"),
    (LinkView(running=False), "not running"),
    (LinkView(links={0: True}, since={}), "initial"),
])
def test_every_element_marks_a_value_that_is_not_good_the_same_way(view: FormView, links: LinkView,
                                                                   word: str) -> None:
    mem = Memory()
    mem.set_word(0o4010, 2048)
    mem.set_hmi_bit(0o40100, 1)
    good = LinkView(links={0: True})
    for scan in (1, 2):
        r, snap = readings(mem, scan, good)
        view.refresh(snap, r)
    by_name = models(view)
    assert all(not m.stale for m, _ in by_name.values())
    live = view.grab().toImage()

    mem.set_word(0o4010, 0)  # a value that arrives while the quality is not good is not shown
    r, snap = readings(mem, 3, links)
    view.refresh(snap, r)
    for name in FED:
        model, widget = by_name[name]
        assert model.quality == word, name
        tip = widget.stale_mark.toolTip() if hasattr(widget, "stale_mark") else widget.toolTip()
        assert tip.startswith(f"? {word}"), (name, tip)
    assert by_name["digital"][0].text == "50.0"  # the last good value, marked
    assert math.isnan(by_name["trend"][0].trend.last) and math.isnan(by_name["bits"][0].trend.last)
    local, _ = by_name["local"]
    assert local.quality == ("not running" if word == "not running" else "")  # nothing fills it
    assert differs(live, view.grab().toImage()) > 1000  # greyed and hatched


def test_a_forced_value_is_shown_as_it_is_and_marked(view: FormView) -> None:
    mem = Memory()
    mem.set_word(0o4100, 4095)
    r, snap = readings(mem, 1, LinkView(links={0: True}, forced=[0o4100]))
    view.refresh(snap, r)
    local, widget = models(view)["local"]
    assert local.quality == Quality.FORCED.word and local.text == "100.0"
    assert widget.toolTip().startswith("F forced")


def colour_count(image: QImage, colour: QColor) -> int:
    """Pixels of (nearly) `colour`, sampled every 2 px."""
    return sum(_near(QColor(image.pixel(x, y)), colour)
               for x in range(0, image.width(), 2) for y in range(0, image.height(), 2))


def _near(a: QColor, b: QColor) -> bool:
    return abs(a.red() - b.red()) + abs(a.green() - b.green()) + abs(a.blue() - b.blue()) < 30


@pytest.mark.parametrize("name", ["local", "setpoint"])  # drawn by the form; with child widgets
def test_a_forced_element_has_its_own_mark_not_the_stale_hatch(view: FormView, name: str) -> None:
    """The same element at the same value, forced and then stale: orange frame and "F" against
    the grey hatch; the two pictures differ and only the forced one has the force colour."""
    mem = Memory()
    addr = 0o4100 if name == "local" else 0o4012
    mem.set_word(addr, 4095)
    model, widget = models(view)[name]
    view.refresh(*reversed(readings(mem, 1, LinkView(links={0: True}, forced=[addr]))))
    assert model.quality == Quality.FORCED.word
    forced = grab_element(view, widget)
    view.refresh(*reversed(readings(mem, 2, LinkView(running=False))))
    assert model.quality == Quality.NOT_RUNNING.word
    stale = grab_element(view, widget)
    assert differs(forced, stale) > 200
    assert colour_count(forced, theme.FORCED) > 100
    assert colour_count(stale, theme.FORCED) == 0


def grab_element(view: FormView, widget) -> QImage:
    """The element as the operator sees it: the form's pixels where it is (the form paints most
    elements itself; those with child widgets paint over it)."""
    view.repaint()
    return view.grab(widget.geometry()).toImage()


def test_a_value_that_arrived_while_marked_is_shown_once_the_data_are_good_again(view: FormView) -> None:
    mem = Memory()
    mem.set_word(0o4010, 2048)
    view.refresh(*reversed(readings(mem, 1, LinkView(links={0: True}))))
    mem.set_word(0o4010, 4095)
    view.refresh(*reversed(readings(mem, 2, LinkView(links={0: False}))))
    dial, digital = models(view)["dial"][0], models(view)["digital"][0]
    assert dial.stale and digital.text == "50.0"
    view.refresh(*reversed(readings(mem, 3, LinkView(links={0: True}))))
    assert not dial.stale and (dial.text, digital.text) == ("100.0", "100.0")
    view.refresh(*reversed(readings(mem, 4, LinkView(links={0: True}))))  # and stays so
    assert not digital.stale and digital.text == "100.0"


def test_a_lamp_on_a_link_output_shows_the_link_itself(qtbot, tmp_path: Path) -> None:
    """The link output bit (C+1) of an NREAD is judged by its own rule among banked lamps: the
    link as it is now is good data, while it is not yet known it is initial."""
    lamp = {"type": "DiscreteColorLabel", "Name": "link", **BOX, "InAddr": "02111", "TextTrue": "связь",
            "TextFalse": "нет связи"}
    form = load_form(write_form(tmp_path, [lamp, {**lamp, "Name": "data", "x": 200, "InAddr": "040100"}]))
    view = FormView(form, NullTarget())
    qtbot.addWidget(view)
    link, data = form.elements
    mem = Memory()
    mem.set_hmi_bit(0o2111, 1)
    view.refresh(*reversed(readings(mem, 1, LinkView(links={0: False}))))
    assert (link.quality, link.value) == ("", 0)  # down, as the link is now, not as the program left it
    assert data.quality == "comm-fail"
    view.refresh(*reversed(readings(mem, 2, LinkView(links={0: True}, since={}))))
    assert link.quality == "initial" and data.quality == "initial"
    view.refresh(*reversed(readings(mem, 3, LinkView(links={0: True}))))
    assert (link.quality, link.value, data.quality) == ("", 1, "")


def test_a_mark_goes_when_the_view_is_refreshed_without_readings(view: FormView) -> None:
    mem = Memory()
    view.refresh(*reversed(readings(mem, 1, LinkView(links={0: False}))))
    assert models(view)["digital"][0].stale
    view.refresh(mem.snapshot(2, 0.2, 1_800_000_002.0))
    assert not any(m.stale for m, _ in models(view).values())
