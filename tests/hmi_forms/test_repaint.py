"""What a form repaints and what it caches: each optimisation of the widgets keeps its test here.

Painted elements are drawn by the form (`ElementWidget.draw`, or from their compositions over the
form's backdrop), so a repaint of an element is counted as a paint of the form whose region reaches
it; the pictures are really rendered with grab(), and what the screen shows after repaints of
parts is read back from the window's backing store (`QScreen.grabWindow`)."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

from PySide6.QtCore import QEvent, QObject, QPoint, QRect, QRectF, QSize, Qt
from PySide6.QtGui import QColor, QImage, QPainter
from PySide6.QtWidgets import QApplication

from hmi_forms.elements.target import NullTarget
from hmi_forms.form import load_form
from hmi_forms.widgets import theme
from hmi_forms.widgets.form_view import FormView
from hmi_forms.widgets.gauges import BOXED
from hmi_forms.widgets.sprites import Ink, SpriteCache, TextSlot, blank
from tests.hmi_forms.helpers import snap

LEVEL = {"Name": "Level", "AppMin": 0, "AppMax": 4095, "PhyMin": 0, "PhyMax": 100}


def form_of(tmp_path: Path, elements: list[dict], width: int = 600, height: int = 300) -> FormView:
    doc = {"form": {"title": "t", "width": width, "height": height}, "devices": [LEVEL], "elements": elements}
    path = tmp_path / "t.hmi"
    path.write_text(json.dumps(doc), encoding="utf-8")
    view = FormView(load_form(path), NullTarget())
    view.show()
    return view


def dial(name: str, x: int, addr: str, size: int = 140, **props) -> dict:
    return {"type": "AnalogBase", "Name": name, "x": x, "y": 0, "w": size, "h": size, "InAddr": addr,
            "Device": "Level", "Appearance": "dial", "Precision": 0, **props}


class Draws(QObject):
    """Counts the form's draws of each painted element: the paints whose region reaches it."""

    def __init__(self, view: FormView) -> None:
        super().__init__(view)
        self.places = {w.model.Name: w.geometry() for w in view.painted}
        self.counts = dict.fromkeys(self.places, 0)
        view.installEventFilter(self)

    def eventFilter(self, obj: QObject, event: QEvent) -> bool:
        if event.type() == QEvent.Type.Paint:
            region = event.region()  # type: ignore[attr-defined]
            for name, place in self.places.items():
                self.counts[name] += region.intersects(place)
        return False

    def reset(self) -> None:
        self.counts = dict.fromkeys(self.counts, 0)


def settle() -> None:
    """Let Qt paint what the refresh asked for."""
    QApplication.processEvents()


def test_only_the_element_whose_shown_value_changed_is_repainted(qtbot, tmp_path) -> None:
    view = form_of(tmp_path, [dial("A", 0, "04010"), dial("B", 200, "04012"),
                              {"type": "DiscreteColorLabel", "Name": "L", "x": 400, "y": 0, "w": 120, "h": 40,
                               "InAddr": "02120", "TextFalse": "OFF", "TextTrue": "ON"}])
    qtbot.addWidget(view)
    draws = Draws(view)
    view.refresh(snap(words={0o4010: 1000, 0o4012: 1000}))
    view.repaint()
    settle()
    assert draws.counts == {"A": 1, "B": 1, "L": 1}
    draws.reset()
    view.refresh(snap(scan=1, words={0o4010: 3000, 0o4012: 1000}))  # A moves, B and L stay
    settle()
    assert draws.counts == {"A": 1, "B": 0, "L": 0}
    view.refresh(snap(scan=2, words={0o4010: 3000, 0o4012: 1000}))  # an equal value: nothing at all
    settle()
    assert draws.counts == {"A": 1, "B": 0, "L": 0}
    view.refresh(snap(scan=3, words={0o4010: 3000, 0o4012: 1000}, bits={0o2120: 1}))
    settle()
    assert draws.counts == {"A": 1, "B": 0, "L": 1}


def test_painted_elements_get_no_paint_events_of_their_own(qtbot, tmp_path) -> None:
    """The form draws them: a paint event per element widget would cost more than the drawing."""
    view = form_of(tmp_path, [dial("A", 0, "04010")])
    qtbot.addWidget(view)
    widget = view.painted[0]
    seen: list[QEvent.Type] = []

    class Spy(QObject):
        def eventFilter(self, obj: QObject, event: QEvent) -> bool:
            seen.append(event.type())
            return False

    spy = Spy()
    widget.installEventFilter(spy)
    before = view.grab().toImage()
    view.refresh(snap(scan=1, words={0o4010: 3000}))
    settle()
    assert QEvent.Type.Paint not in seen
    assert before != view.grab().toImage()  # ...and yet it is repainted, by the form


def test_a_new_text_alone_repaints_only_its_box_in_a_large_gauge(qtbot, tmp_path) -> None:
    view = form_of(tmp_path, [dial("A", 0, "04010", size=280)], height=300)
    qtbot.addWidget(view)
    asked: list[tuple] = []
    view.update = lambda *rect: asked.append(rect)  # type: ignore[method-assign]
    view.refresh(snap(words={0o4010: 2067}))  # 50.48 %: "50"
    view.refresh(snap(scan=1, words={0o4010: 2068}))  # "51", the needle stays within its pixel
    view.refresh(snap(scan=2, words={0o4010: 3000}))  # the needle moves
    whole = QRect(0, 0, 280, 280)
    assert asked[0] == (whole,) and asked[2] == (whole,)
    (part,) = asked[1]
    assert whole.contains(part) and part.width() * part.height() * 10 < 280 * 280


def test_two_trends_alike_but_for_their_name_keep_their_own_headers(qtbot, tmp_path) -> None:
    graph = {"type": "Graph", "y": 0, "w": 280, "h": 120, "Elements": 50}
    view = form_of(tmp_path, [{**graph, "Name": "TA", "x": 0, "Address": "040003"},
                              {**graph, "Name": "TA[2]", "x": 290, "Address": "040005"}])
    qtbot.addWidget(view)
    view.refresh(snap())
    one, two = (w.layer() for w in view.trends)
    assert one is not two and one.toImage() != two.toImage()


def test_a_cached_face_is_rebuilt_when_the_colours_or_the_size_change(qtbot, tmp_path) -> None:
    view = form_of(tmp_path, [dial("A", 0, "04010")])
    qtbot.addWidget(view)
    view.refresh(snap(words={0o4010: 1000}))
    widget = view.painted[0]
    corner = view.grab().toImage().pixelColor(2, 2)
    assert corner == theme.PANEL
    widget.model.BackColor = (200, 30, 30, 255)  # as a form designer would set it
    view.update()  # drawn from what it was composed of: the new colour comes with the next change
    assert view.grab().toImage().pixelColor(2, 2) == theme.PANEL
    widget.sync()
    assert view.grab().toImage().pixelColor(2, 2) == QColor(200, 30, 30)
    assert widget.layer().size() == QSize(140, 140)
    widget.resize(100, 100)
    assert widget.layer().size() == QSize(100, 100)
    assert view.errors == []


def test_elements_that_look_alike_share_their_layers(qtbot, tmp_path) -> None:
    label = {"type": "DiscreteColorLabel", "y": 0, "w": 100, "h": 40, "InAddr": "02120", "TextFalse": "OFF",
             "TextTrue": "ON", "BackColorTrue": "#2e7d32"}
    view = form_of(tmp_path, [{**label, "Name": "L1", "x": 0}, {**label, "Name": "L2", "x": 110},
                              {**label, "Name": "L3", "x": 220, "TextTrue": "RUN"}])
    qtbot.addWidget(view)
    view.refresh(snap(bits={0o2120: 1}))
    one, two, three = (w.layer() for w in view.painted)
    assert one is two and one is not three
    assert two.toImage().pixelColor(50, 2) == QColor("#2e7d32")


def test_a_text_drawn_from_glyphs_is_pixel_for_pixel_the_drawn_text(qtbot) -> None:
    """Digits drawn from cached glyphs against drawText of the whole text, in boxes at whole and
    fractional places (where Qt rounds each glyph's position), on a flat colour and on none."""
    texts = ("-12.5", "1234.5", "9876.0", "---", "10000.0", "0.1 %")
    fitted = 0
    mono = theme.MONO
    for font in (theme.sized_font(15, bold=True, family=mono), theme.sized_font(11, bold=True, family=mono),
                 theme.sized_font(12)):
        for box in (QRectF(10.4, 6.7, 61.3, 21.2), QRectF(10, 6, 61, 21), QRectF(3.5, 2.25, 70.1, 17.9)):
            for ink, align in ((Ink(theme.TEXT, QColor("#ffffff")), Qt.AlignmentFlag.AlignCenter),
                               (Ink(theme.TEXT), theme.RIGHT),
                               (Ink(QColor("#ffffff"), theme.ALARM), theme.RIGHT)):
                area = box.adjusted(2, 2, -2, -2) if ink.back is not None else None
                slot = TextSlot(box, font, align, area=area)
                for text in texts:
                    # one wider than the area is drawn whole (the same pixels: compared all the same)
                    fitted += slot.fits(text) or slot.glyphs.width(text) <= slot.span
                    pictures = []
                    for how in ("drawn", "from glyphs rendered now", "from cached glyphs"):
                        picture = QImage(90, 40, QImage.Format.Format_ARGB32)
                        picture.fill(ink.back or QColor("#ffffff"))
                        p = QPainter(picture)
                        p.setRenderHint(QPainter.RenderHint.Antialiasing)
                        if how == "drawn":
                            p.setFont(font)
                            p.setPen(ink.fore)
                            p.drawText(box, align, text)
                        else:
                            slot.draw(p, text, ink)
                        p.end()
                        pictures.append(picture)
                    assert pictures[0] == pictures[1] == pictures[2], (font.key(), box, text)
    assert fitted > 100  # of 162: most from glyphs
    for align in (theme.RIGHT, Qt.AlignmentFlag.AlignCenter):  # wider than its element: cut at its sides
        box, bounds = QRectF(16.3, 4.6, 30.2, 18), QRectF(10, 0, 40, 30)
        slot = TextSlot(box, theme.sized_font(12, bold=True, family=mono), align, bounds=bounds)
        assert slot.fits("-1234.5 %") and not slot.inside("-1234.5 %")
        pictures = []
        for how in ("drawn, clipped", "from glyphs"):
            picture = QImage(90, 40, QImage.Format.Format_ARGB32)
            picture.fill(QColor("#ffffff"))
            p = QPainter(picture)
            p.setRenderHint(QPainter.RenderHint.Antialiasing)
            if how == "drawn, clipped":
                p.setClipRect(bounds.toRect())
                p.setFont(slot.font)
                p.setPen(theme.TEXT)
                p.drawText(box, align, "-1234.5 %")
            else:
                slot.draw(p, "-1234.5 %", Ink(theme.TEXT))
            p.end()
            pictures.append(picture)
        assert pictures[0] == pictures[1]
    # what is kept is by the advances of a text, not its characters: all digits share one advance
    assert len({text for text in ("-1234.5 %", "-9876.0 %", "-5555.5 %")
                if slot.fits(text) and slot.glyphs.layout(text) is slot.glyphs.layout("-1234.5 %")}) == 3


def test_the_picture_caches_stay_bounded_whatever_the_values(qtbot, tmp_path) -> None:
    """A plant's words over their whole range: what the gauges cache is bounded by characters,
    inks and pixels, never by the values (MAX_SHOWN, the glyphs)."""
    from hmi_forms.elements.analog import MAX_SHOWN
    from hmi_forms.widgets.sprites import SPRITES

    wide = {**LEVEL, "Name": "Wide", "AppMax": 65535, "PhyMax": 10000}
    doc = [{**dial("D", 0, "04010", Device="Wide", Precision=1)},
           {**dial("R", 150, "04012", Device="Wide", Precision=1), "Appearance": "digital", "h": 60},
           {**dial("B", 300, "04014", Device="Wide", Precision=1), "Appearance": "hbar", "h": 60,
            "Units": "%"}]
    path = tmp_path / "t.hmi"
    path.write_text(json.dumps({"form": {"title": "t", "width": 600, "height": 300}, "devices": [wide],
                                "elements": doc}), encoding="utf-8")
    view = FormView(load_form(path), NullTarget())
    view.show()
    qtbot.addWidget(view)

    scans = itertools.count(1)

    def feed(words: list[int]) -> int:
        for hw in words:
            view.refresh(snap(scan=next(scans), words={0o4010: hw, 0o4012: hw ^ 0x5555, 0o4014: hw ^ 0xAAAA}))
            settle()
        return SPRITES.bytes  # what the pictures hold (entries and remembered words: counted below)

    # the whole range in even steps: every pixel a needle can move to (a dial's needle has 266)
    warm = feed([round(j * 0xFFFF / 511) for j in range(512)])
    # then 700 words spread as a plant's are: 1,212 distinct values in all, drawn from the
    # needles the sweep cached
    assert feed([k * 40503 & 0xFFFF for k in range(1, 701)]) <= warm * 1.05
    for widget in view.painted:
        model = widget.model
        assert len(model.remembered) <= MAX_SHOWN
        assert len(widget._value.plans) <= 8  # by the width and place of a text: a few widths
    assert all(len(slot.glyphs.layouts) <= 8 for slot in {w._value for w in view.painted})  # by advances
    assert view.errors == []


def test_the_sprite_cache_starts_afresh_past_its_budget(qtbot) -> None:
    cache = SpriteCache(budget=3 * 10 * 10 * 4)
    family = cache.family("f")
    for k in range(3):
        cache.put(family, k, (0, 0, blank(QSize(10, 10), 1.0, None)))
    assert len(cache) == 3 and cache.bytes == 1200
    cache.put(family, 3, (0, 0, blank(QSize(10, 10), 1.0, None)))
    assert list(family) == [3] and cache.bytes == 400  # the family the widgets hold stays the same dict


def test_dial_needles_come_from_the_cache_and_follow_the_value(qtbot, tmp_path) -> None:
    view = form_of(tmp_path, [dial("A", 0, "04010"), dial("B", 200, "04012")])
    qtbot.addWidget(view)
    a, b = view.painted
    pictures = []
    for hw in (0, 2048, 4095):
        view.refresh(snap(scan=hw, words={0o4010: hw, 0o4012: hw}))
        pictures.append(view.grab().toImage())
    assert pictures[0] != pictures[1] != pictures[2]
    assert a._needles is b._needles  # two dials of one size share them
    assert {0, round(a._travel * 2048 / 4095), round(a._travel)} <= set(a._needles)
    assert view.errors == []


def test_a_high_value_is_white_on_the_alarm_colour(qtbot, tmp_path) -> None:
    view = form_of(tmp_path, [dial("A", 0, "04010", PhyHigh=90)])
    qtbot.addWidget(view)
    view.refresh(snap(words={0o4010: 4095}))
    assert view.pairs[0][0].zone == "high" and BOXED["high"].back == theme.ALARM
    box = view.painted[0]._value.rect
    picture = view.grab().toImage()
    colours = {picture.pixelColor(x, box.center().y()).name() for x in range(box.left(), box.right())}
    assert theme.ALARM.name() in colours and "#ffffff" in colours


def test_a_3000_element_bench_form_fits_the_form_limits(tmp_path) -> None:
    import importlib.util

    spec = importlib.util.spec_from_file_location("bench_hmi", Path(__file__).parents[2] / "bench" / "hmi.py")
    assert spec is not None and spec.loader is not None
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    form = load_form(bench.generate(tmp_path, 3000, False))
    assert len(form.elements) == 3000 and form.height <= 10_000 and form.width <= 10_000
    plots = load_form(bench.generate(tmp_path, 600, True))
    assert sum(e.TYPE == "Graph" for e in plots.elements) == 100


def test_a_text_too_wide_for_its_area_is_drawn_whole(qtbot, tmp_path) -> None:
    """A word far beyond AppMax gives a value wider than the scale's: it must not be cut."""
    doc = [{"type": "AnalogBase", "Name": "B", "x": 0, "y": 0, "w": 160, "h": 64, "InAddr": "04010",
            "Device": "Level", "Appearance": "hbar", "Units": "%"}]
    view = form_of(tmp_path, doc)
    qtbot.addWidget(view)
    slot = view.painted[0]
    view.refresh(snap(words={0o4010: 65535}))  # 1600.4 %
    assert view.pairs[0][0].text == "1600.4"
    picture = view.grab().toImage()
    value = slot._value
    assert value.fits("1600.4 %") and not value.inside("1600.4 %")  # from glyphs, past the area...
    start = round(value.box.right() - value.metrics.horizontalAdvance("1600.4 %"))
    assert start < value.at.x() - 2  # ...since it starts left of the area
    left_of_cache = [(x, y) for x in range(start, value.at.x()) for y in range(2, 22)]
    assert any(picture.pixelColor(x, y).lightness() < 120 for x, y in left_of_cache)  # drawn all the same


def gallery(tmp_path: Path) -> FormView:
    """Every kind of element the form draws from its composition, side by side, some touching."""
    def gauge(name: str, x: int, y: int, appearance: str, addr: str, size: int = 90, **props) -> dict:
        return {**dial(name, x, addr, size, Appearance=appearance, PhyHigh=80, **props), "y": y}

    label = {"type": "DiscreteColorLabel", "w": 90, "h": 40, "TextFalse": "OFF", "TextTrue": "ON",
             "BackColorTrue": "#2e7d32", "ForeColorTrue": "#ffffff"}
    return form_of(tmp_path, [
        gauge("D", 0, 0, "dial", "04010"), gauge("S", 90, 0, "semidial", "04012"),
        gauge("G", 180, 0, "digital", "04014", Units="%"), gauge("B", 270, 0, "hbar", "04016", Units="%"),
        gauge("H", 360, 0, "hbar", "04020", size=64, Precision=1),
        gauge("T", 0, 90, "dial", "04022", size=64), gauge("N", 64, 90, "digital", "04024", size=64),
        {**label, "Name": "L1", "x": 180, "y": 100, "InAddr": "02120"},
        {**label, "Name": "L2", "x": 270, "y": 100, "InAddr": "02121"},
        {"type": "DiscreteBase", "Name": "K", "x": 360, "y": 100, "w": 90, "h": 30, "InAddr": "02122",
         "TextFalse": "Stop", "TextTrue": "Run"},
    ], width=460, height=160)


def test_a_composed_form_is_pixel_for_pixel_the_form_drawn_with_a_painter(qtbot, tmp_path) -> None:
    view = gallery(tmp_path)
    qtbot.addWidget(view)
    values = [{0o4010: 1234, 0o4012: 3900, 0o4014: 4000, 0o4016: 2000, 0o4020: 0, 0o4022: 4095, 0o4024: 7},
              {0o4010: 0, 0o4012: 17, 0o4014: 3333, 0o4016: 4095, 0o4020: 4095, 0o4022: 2048, 0o4024: 3500}]
    for scan, words in enumerate(values):
        view.refresh(snap(scan=scan, words=words, bits={0o2120: 1, 0o2122: scan}))
        assert [w.model.Name for w in view.painted if w.face.drawn is None] == []  # all composed
        composed = view.grab().toImage()
        kept = [w.face.drawn for w in view.painted]
        for widget in view.painted:
            widget.face.drawn = None  # ...and the same elements drawn with a painter, moved and clipped
        assert view.grab().toImage() == composed
        for widget, drawn in zip(view.painted, kept):
            widget.face.drawn = drawn
    assert view.errors == []


def test_texts_drawn_in_a_pass_of_their_own_are_the_texts_drawn_element_by_element(qtbot, tmp_path) -> None:
    """A form whose elements do not overlap draws the value texts after every element, each
    setting its clip in turn (`FormView._paint_passes`): the same pixels as element by element,
    with words over their whole range in 64 px tiles (texts wider than their boxes, cut as drawText
    cuts them, and wider than their elements), lamps, and a stale element drawn with a painter."""
    wide = {**LEVEL, "Name": "Wide", "AppMax": 65535, "PhyMax": 10000}
    kinds = ("dial", "digital", "hbar", "semidial", "digital", "dial") * 2
    doc = [{**dial(f"A{i}", i % 6 * 64, f"0{0o4010 + 2 * i:o}", size=64, Device="Wide", Precision=1,
                   Appearance=kind, Units="%", PhyHigh=9000), "y": i // 6 * 64}
           for i, kind in enumerate(kinds)]
    doc += [{"type": "DiscreteColorLabel", "Name": f"L{i}", "x": i * 64, "y": 128, "w": 64, "h": 64,
             "InAddr": f"0{0o2120 + i:o}", "TextFalse": "OFF", "TextTrue": "ON", "BackColorTrue": "#2e7d32"}
            for i in range(6)]
    path = tmp_path / "t.hmi"
    path.write_text(json.dumps({"form": {"title": "t", "width": 400, "height": 200}, "devices": [wide],
                                "elements": doc}), encoding="utf-8")
    view = FormView(load_form(path), NullTarget())
    view.show()
    qtbot.addWidget(view)
    assert view._apart
    for scan in range(4):
        words = {0o4010 + 2 * i: (scan * 40503 + i * 9973) & 0xFFFF for i in range(12)}
        view.refresh(snap(scan=scan, words=words, bits={0o2120 + i: (scan + i) % 2 for i in range(6)}))
        if scan == 3:
            view.painted[4].model.stale = True  # drawn with a painter, among the others
            view.painted[4].sync()
        passes = view.grab().toImage()
        view._backdrop = lambda: None  # type: ignore[method-assign]  # as at a fractional pixel ratio
        layers_first = view.grab().toImage()
        del view._backdrop
        view._apart = False
        assert view.grab().toImage() == passes == layers_first, scan
        view._apart = True
    plans = [plan for w in view.painted[:12] for plan in w._value.plans.values()]
    assert any(boxed for _, _, boxed in plans)  # under the one clip of the boxes
    assert any(cut is not None and not boxed for _, cut, boxed in plans)  # each under its own
    assert view.errors == []


def test_elements_that_overlap_are_drawn_element_by_element(qtbot, tmp_path) -> None:
    apart = form_of(tmp_path, [dial("A", 0, "04010"), dial("B", 140, "04012")])  # touching
    over = form_of(tmp_path, [dial("A", 0, "04010"), dial("B", 100, "04012")])
    qtbot.addWidget(apart)
    qtbot.addWidget(over)
    assert apart._apart and not over._apart


def test_an_element_with_no_value_yet_or_a_stale_one_is_drawn_with_a_painter(qtbot, tmp_path) -> None:
    view = gallery(tmp_path)
    qtbot.addWidget(view)
    dial_widget = view.painted[0]
    view.refresh(snap(words={0o4010: 1000}))
    assert dial_widget.face.drawn is not None
    dial_widget.model.stale = True  # the stale mark needs a painter
    dial_widget.sync()
    assert dial_widget.face.drawn is None
    composed_then_painted = view.grab().toImage()
    assert composed_then_painted.pixelColor(dial_widget.x() + 45, dial_widget.y() + 45) != theme.PANEL


def test_an_elements_own_tooltip_outlives_refreshes_and_a_quality_mark(qtbot, tmp_path) -> None:
    view = form_of(tmp_path, [dial("A", 0, "04010")])
    qtbot.addWidget(view)
    widget = view.painted[0]
    own = widget.toolTip()
    assert own.startswith("A: word 04010")
    view.refresh(snap(words={0o4010: 1000}))
    view.refresh(snap(scan=1, words={0o4010: 2000}))
    assert widget.toolTip() == own
    widget.model.stale, widget.model.quality = True, "comm-fail"
    widget.sync()
    assert widget.toolTip().startswith("? comm-fail")
    widget.model.stale, widget.model.quality = False, ""
    widget.sync()
    assert widget.toolTip() == own


def test_a_refresh_that_changes_most_of_a_large_form_repaints_it_in_one_piece(qtbot, tmp_path) -> None:
    """Hundreds of rectangles cost Qt more than the one around them; a few stay apart."""
    labels = [{"type": "DiscreteColorLabel", "Name": f"L{i}", "x": i % 20 * 30, "y": i // 20 * 30, "w": 30,
               "h": 30, "InAddr": f"0{0o2000 + i:o}", "TextFalse": "0", "TextTrue": "1"} for i in range(200)]
    view = form_of(tmp_path, labels, width=600, height=300)
    qtbot.addWidget(view)
    view.refresh(snap())
    asked: list[tuple] = []
    view.update = lambda *rect: asked.append(rect)  # type: ignore[method-assign]
    view.refresh(snap(scan=1, bits={0o2000 + i: 1 for i in range(150)}))
    assert asked == [()]
    asked.clear()
    view.refresh(snap(scan=2, bits={0o2000 + i: 1 for i in (*range(150), 160, 161)}))
    assert asked == [(view.painted[160].geometry(),), (view.painted[161].geometry(),)]


def test_the_forms_background_is_painted_only_where_no_element_covers_it(qtbot, tmp_path) -> None:
    """Under an opaque element the background is never seen: a large form skips filling it."""
    text = {"type": "StaticText", "Name": "T", "x": 200, "y": 0, "w": 100, "h": 40, "Text": ""}
    label = {"type": "DiscreteColorLabel", "Name": "L", "x": 320, "y": 0, "w": 100, "h": 40,
             "InAddr": "02120", "TextFalse": "", "TextTrue": "", "BackColorTrue": "#80ff0000"}
    view = form_of(tmp_path, [dial("A", 0, "04010"), text, label])
    qtbot.addWidget(view)
    bare = view._bare
    assert not bare.contains(QPoint(70, 70))  # the dial covers its rectangle in every state
    assert bare.contains(QPoint(250, 20))  # a transparent text does not
    assert bare.contains(QPoint(370, 20))  # nor a label half transparent in one of its states
    view.refresh(snap(words={0o4010: 2000}))
    image = view.grab().toImage()
    assert image.pixelColor(250, 20) == QColor(*view.form.BackColor)
    assert image.pixelColor(2, 2) == theme.PANEL


def test_repaints_over_the_backdrop_show_the_form_drawn_element_by_element(qtbot, tmp_path) -> None:
    """Elements apart are drawn over the form's backdrop (`FormView._backdrop`: the background and
    each composed element's layer, a tile composed anew when its layer changes). After refreshes
    that repaint parts of the form (one needle, a lamp's state, a text alone in a large gauge, an
    element turned stale and good again), the screen shows what a whole paint element by element
    from the layers gives, on a form with a background picture and a lamp half transparent."""
    background = QImage(37, 23, QImage.Format.Format_RGB32)
    for x, y in itertools.product(range(37), range(23)):
        background.setPixelColor(x, y, QColor(x * 7, y * 11, (x * y) % 256))
    background.save(str(tmp_path / "bg.png"))
    label = {"type": "DiscreteColorLabel", "w": 90, "h": 40, "TextFalse": "OFF", "TextTrue": "ON",
             "BackColorTrue": "#2e7d32", "ForeColorTrue": "#ffffff"}
    doc = {"form": {"title": "t", "width": 460, "height": 260}, "devices": [LEVEL], "elements": [
        dial("D", 0, "04010", size=90, PhyHigh=80), dial("Big", 90, "04012", size=150),
        {**dial("B", 250, "04014", size=90, Units="%"), "Appearance": "hbar", "h": 64},
        {**dial("G", 340, "04016", size=90, Units="%"), "Appearance": "digital", "h": 64},
        {**label, "Name": "L1", "x": 250, "y": 100, "InAddr": "02120"},
        {**label, "Name": "L2", "x": 340, "y": 100, "InAddr": "02121", "BackColorTrue": "#80ff0000"},
        {"type": "DiscreteBase", "Name": "K", "x": 0, "y": 180, "w": 90, "h": 30, "InAddr": "02122",
         "TextFalse": "Stop", "TextTrue": "Run"}]}
    path = tmp_path / "t.hmi"
    path.write_text(json.dumps(doc), encoding="utf-8")
    form = load_form(path)
    form.BackgroundImage = tmp_path / "bg.png"
    view = FormView(form, NullTarget())
    view.show()
    qtbot.addWidget(view)
    assert view._apart
    dial_widget, big = view.painted[:2]
    words = {0o4010: 1000, 0o4012: 2067, 0o4014: 500, 0o4016: 4000}
    steps = [({}, {}), ({0o4010: 3900}, {}), ({0o4012: 2068}, {0o2121: 1}), ({}, {0o2120: 1, 0o2122: 1}),
             ({0o4010: 0}, {0o2121: 0}), ({0o4014: 4095, 0o4016: 17}, {0o2120: 0})]
    bits: dict[int, int] = {}
    for scan, (changed, flipped) in enumerate(steps):
        words.update(changed)
        bits.update(flipped)
        view.refresh(snap(scan=scan, words=words, bits=bits))
        if scan == 3:  # drawn with a painter over the background alone, then composed again
            dial_widget.model.stale = True
            dial_widget.sync()
        if scan == 4:
            dial_widget.model.stale = False
            dial_widget.sync()
        settle()
        assert [w.model.Name for w in view.painted if w.face.drawn is None] == (["D"] if scan == 3 else [])
        screen = QApplication.primaryScreen().grabWindow(view.winId()).toImage()
        view._apart = False  # the whole form, element by element from the layers
        whole = view.grab().toImage()
        view._apart = True
        assert screen.convertToFormat(whole.format()) == whole, scan
    assert big.face.part is not None  # a text alone repainted its box (scan 2)
    assert view._ground is not None and view.errors == []


def test_layouts_kept_by_length_while_every_character_known_advances_alike(qtbot) -> None:
    """A monospaced font's texts are laid out by their length alone (`Glyphs.layout`); once a
    character of another advance is known, by the advances again: the places are Qt's either way."""
    from hmi_forms.widgets.sprites import Glyphs

    glyphs = Glyphs(theme.sized_font(12))  # proportional, its digits all of one advance
    assert glyphs.learn("0123456789") and len(glyphs.steps) == 1

    def places(text: str) -> list[float]:
        return [point.x() for point in glyphs.layout(text)[1]]

    digits = places("1234")
    assert glyphs.lengths[4][1] == glyphs.layout("9876")[1]  # by length: the same places
    assert glyphs.learn("1.5") and len(glyphs.steps) == 2  # a point narrower than a digit
    assert places("1.55") != places("1234") == digits
    step = glyphs.advances64["1"] / 64
    assert digits == [k * step for k in range(4)]
    assert places("1.55")[2] == (glyphs.advances64["1"] + glyphs.advances64["."]) / 64
