"""A whole HMI form as one widget: element widgets placed as in the file, refreshed once per tick.

The workstation calls `refresh(snapshot)` with the snapshots the bridge hands to the GUI thread (it
skips some when the window lags: a view only shows, and forwards the operator's input; what the
form does to the station, the runtime does from every snapshot, hmi_forms/behaviour.py). Every
model reads the snapshot; only widgets whose model reports a change compose themselves anew
(pixmaps from the caches at their places) and, if that differs from what is shown, are scheduled
for repainting. Qt paints them all in one pass, and one rectangle stands for them when most of a
large form changed. Trend plots are redrawn once a second (as PyDM does by default), all plots of
a form in the same tick on one clock-time axis, so two trends never disagree about when something
happened.
An element whose update or drawing raises is marked stale (its mark shows it) and the rest of the
form keeps running; the fault is logged with its traceback and reported (`report`: the workstation's
health strip) once per element and kind of fault, not at every refresh.
With the runtime's `Readings` of the scan, each element is also given the quality of what it shows
(one judgement per distinct operand per refresh), and marks anything but good.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from PySide6.QtCore import QPointF, QRect, QRectF, QSize, Qt
from PySide6.QtGui import QColor, QGlyphRun, QPainter, QPaintEvent, QPixmap, QRegion, QTransform
from PySide6.QtWidgets import QWidget

from app.scada.quality import Quality
from app.scada.readings import Readings
from hmi_forms.elements import Element
from hmi_forms.elements.analog import AnalogBase, AnalogOutput
from hmi_forms.elements.bank import Banked, BitBank, WordBank
from hmi_forms.elements.base import Guard, Writer
from hmi_forms.elements.discrete import DiscreteBase
from hmi_forms.elements.graph import Graph
from hmi_forms.elements.journal import MessageJournal
from hmi_forms.elements.static import DateTime, StaticPicture, StaticText
from hmi_forms.elements.sync import SyncGenerator
from hmi_forms.elements.target import Target
from hmi_forms.form import Form
from hmi_forms.widgets.analog_output import AnalogOutputWidget
from hmi_forms.widgets.base import PIX, ElementWidget, Face, Images, Op, SelfPainted, draw_pixmap
from hmi_forms.widgets.discrete import DiscreteWidget
from hmi_forms.widgets.gauges import GaugeWidget
from hmi_forms.widgets.journal import JournalWidget
from hmi_forms.widgets.sprites import Ink, TextSlot, blank, draw_text
from hmi_forms.widgets.static import DateTimeWidget, StaticPictureWidget, StaticTextWidget, SyncWidget
from hmi_forms.widgets.tank import TankWidget
from hmi_forms.widgets.trend import REDRAW_INTERVAL, TrendWidget
from netplc.memory import Snapshot

logger = logging.getLogger(__name__)
Text = tuple[TextSlot, int, int, str, Ink]  # a composed text's arguments (`sprites.draw_text`)
BATCH = 100  # changed elements from which a refresh that changed most of the form repaints it whole


class FormView(QWidget):
    def __init__(self, form: Form, target: Target, *, archive_path: str | Path | None = None,
                 user: str = "operator", started: float | None = None,
                 clock: Callable[[], float] = time.monotonic, guard: Guard | None = None,
                 report: Callable[[str], None] | None = None, parent: QWidget | None = None) -> None:
        """`started` is the engine-clock time the station started (for DateTime's time since start);
        `clock` paces the plot redraws (a benchmark replays ticks faster than real time); `guard`
        decides each write of the operator before it is made (role, confirmation); `report` hears
        of each element fault once, in words for the operator."""
        super().__init__(parent)
        self.form = form
        self.setFixedSize(QSize(form.width, form.height))
        self.setWindowTitle(form.title)
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)
        self._back = QColor(*form.BackColor)
        self.images = Images(form.images)
        self.pairs: list[tuple[Element, ElementWidget]] = []
        self.trends: list[TrendWidget] = []
        self.painted: list[ElementWidget] = []  # drawn by this widget's paintEvent, in file order
        self.errors: list[str] = []  # each element fault as reported, once
        self.report = report
        self._faults: set[tuple[int, str, type]] = set()  # (element, what failed, exception type)
        self._last: Snapshot | None = None
        self.clock = clock
        self._dirty: list[QRect] | None = None  # parts to repaint, gathered during a refresh
        archive = Path(archive_path) if archive_path is not None else None
        for model in form.elements:
            model.bind(target, user)
            if isinstance(model, Writer):
                model.guard = guard
            if isinstance(model, DateTime) and started is not None:
                model.started = started
            widget = self.element_widget(model, self.images, archive)
            widget.setParent(self)
            self.pairs.append((model, widget))
            if isinstance(widget, TrendWidget):
                self.trends.append(widget)
            if not isinstance(widget, SelfPainted):
                self.painted.append(widget)
        # what each element shows is read from fixed operands, and its change goes straight to
        # what draws it: the face of a painted element
        syncs = [(model, model.sources(),
                  widget.face.sync if type(widget).sync is ElementWidget.sync else widget.sync)
                 for model, widget in self.pairs]
        # the elements whose operand is all they show (`plain`) are read together, in one array per
        # bank their face draws from (`Face.bank`: the gauges' words, the lamps' bits)
        kinds = [w.face.bank if m.plain else None for m, w in self.pairs]
        self._syncs = [s for s, kind in zip(syncs, kinds) if kind is None]
        self._banks: list[Banked] = []
        for kind in (WordBank, BitBank):
            members = [(s, w) for s, (_, w), k in zip(syncs, self.pairs, kinds) if k is kind]
            if members:
                models = [m for (m, _, _), _ in members]
                faces, shows = [w.face for _, w in members], [s for (_, _, s), _ in members]
                self._banks.append(Banked(kind, models, faces, shows,
                                          lambda model, e: self._fault(model, e, "update")))
        # where each painted element goes, worked out once: the paint loop runs 200 times a tick
        self._extent = QRect()  # what the painted elements take
        self._bare = QRegion(self.rect())  # what no element covers: the form's background shows
        for w in self.painted:
            self._extent = self._extent.united(w.geometry())
            if w.covers():
                self._bare -= QRegion(w.geometry())
        self._faces = [w.face for w in self.painted]
        self._places = [w.geometry() for w in self.painted]
        self._slots = {w.face: (w, QTransform.fromTranslate(w.x(), w.y()), QRectF(w.rect()))
                       for w in self.painted}
        self._apart = _apart(self._places)  # the texts can be drawn in a pass of their own
        self._ground: QPixmap | None = None  # the backdrop (`_backdrop`), made at the first paint
        self._tiles: list[QPixmap | None] = []  # the layer at each painted element's place in it
        self._boxes: dict[Face, QRect] = {}  # the box of each text cut at its box (`_paint_boxed`)
        self._box_clip: QRegion | None = None  # the region of them all (None: to be made again)
        self.live = True  # the trends follow the clock; paused, the operator pans and zooms them
        self.history_wanted: Callable[[TrendWidget, float, float], None] | None = None
        self._next_flush = clock()
        for w in self.trends:  # one time axis for the form: panning one pans them all
            w.moved = self.move_trends
            w.pause_button.clicked.connect(self.toggle_live)

    @staticmethod
    def element_widget(model: Element, images: Images, archive: Path | None) -> ElementWidget:
        """The widget class that draws `model` (the form designer draws its canvas with these too)."""
        if isinstance(model, DiscreteBase):
            return DiscreteWidget(model, images)
        if isinstance(model, AnalogBase):
            if model.Appearance == "tank":
                return TankWidget(model, images)
            return TrendWidget(model, images) if model.Appearance == "graph" else GaugeWidget(model, images)
        if isinstance(model, Graph):
            return TrendWidget(model, images)
        if isinstance(model, AnalogOutput):
            return AnalogOutputWidget(model, images)
        if isinstance(model, MessageJournal):
            return JournalWidget(model, images, archive)
        if isinstance(model, SyncGenerator):
            return SyncWidget(model, images)
        if isinstance(model, DateTime):
            return DateTimeWidget(model, images)
        if isinstance(model, StaticText):
            return StaticTextWidget(model, images)
        if isinstance(model, StaticPicture):
            return StaticPictureWidget(model, images)
        raise TypeError(f"no widget for element type {model.TYPE}")

    def refresh(self, snapshot: Snapshot, readings: Readings | None = None) -> None:
        """Update every element from one snapshot, and the quality of what each shows from the
        runtime's `readings` (None: not judged); repaint only what changed."""
        if snapshot is self._last:
            return
        self._last = snapshot
        if readings is not None:
            snapshot = readings.live(snapshot)  # link outputs follow the link, not the last scan
        judged: dict[tuple[int, int], Quality] = {}
        dirty = self._dirty = []
        try:
            for model, sources, sync in self._syncs:
                try:
                    quality = None if readings is None else _worst(sources, readings, judged)
                    if model.update(snapshot, quality):
                        sync()
                except Exception as e:  # no log: _fault logs it, once
                    self._fault(model, e, "update")
                    sync()  # marked stale: drawn with a painter, which shows the mark
            shown = [(banked, banked.refresh(snapshot, readings)) for banked in self._banks]
        finally:
            self._dirty = None
        count = len(dirty) + sum(len(positions) for _, positions in shown)
        if count > BATCH and count * 2 > len(self._faces):
            # most of a large form: one rectangle costs Qt far less than hundreds (a region of n
            # rectangles costs n² to build), and an element unchanged is one more pixmap copy
            self.update()
        else:
            for part in dirty:
                self.update(part)
            for banked, positions in shown:
                for i in positions:
                    self.update(banked.faces[i].rect)
        now = self.clock()
        if self.trends and now >= self._next_flush:  # all plots of the form in the same tick
            self._next_flush = max(self._next_flush + REDRAW_INTERVAL, now)
            self.redraw_trends(snapshot.wall)

    def schedule(self, part: QRect) -> None:
        """Repaint `part` of the form: at once, or with the rest of a refresh."""
        if self._dirty is None:
            self.update(part)
        else:
            self._dirty.append(part)

    def redraw_trends(self, wall: float) -> None:
        """Draw every trend of the form at `wall`: live, ending then (once per REDRAW_INTERVAL)."""
        for trend in self.trends:
            trend.flush()
        if self.live:  # the samples kept, to two digits: the axes' labels stay as the period jitters
            span = float(f"{max(t.span for t in self.trends):.2g}")
            for trend in self.trends:
                trend.show_window(wall - span, wall)

    def pause(self) -> None:
        """Stop following the clock (the operator pans, zooms or reads a value)."""
        if self.live:
            self.live = False
            for trend in self.trends:
                trend.set_live(False)

    def resume(self) -> None:
        self.live = True
        for trend in self.trends:
            trend.set_live(True)
        if self._last is not None:
            self.redraw_trends(self._last.wall)

    def toggle_live(self) -> None:
        if self.live:
            self.pause()
        else:
            self.resume()

    def move_trends(self, t0: float, t1: float) -> None:
        """The operator dragged or wheeled in a trend: all trends of the form pause and show the
        times t0..t1; scrolled back past the live samples, each asks for its history there."""
        self.pause()
        for trend in self.trends:
            trend.show_window(t0, t1)
        if self.history_wanted is None:
            return
        for trend in self.trends:
            t = trend.trend.times()
            first = t[0] if len(t) and not np.isnan(t[0]) else float("inf")
            if t0 < first:
                self.history_wanted(trend, t0, t1)

    def _fault(self, model: Element, error: Exception, what: str) -> None:
        """Mark the element stale; log and report the fault the first time (it recurs at every
        refresh or repaint until the data that cause it change)."""
        model.failed()
        key = (id(model), what, type(error))
        if key in self._faults:
            return
        self._faults.add(key)
        text = f'{self.form.path}: element "{model.Name}": {what} failed: {error!r}'
        logger.error("%s", text, exc_info=error)
        self.errors.append(text)
        if self.report is not None:
            self.report(text)

    def flush(self) -> None:
        """Bring every throttled part up to date (before a screenshot)."""
        for _, widget in self.pairs:
            widget.flush()
        if self.trends and self._last is not None and self.live:
            self.redraw_trends(self._last.wall)

    def save_png(self, path: str | Path) -> bool:
        self.flush()
        return self.grab().save(str(path))

    def paintEvent(self, event: QPaintEvent) -> None:
        """The background, and every QPainter-drawn element in the repainted region, with one
        painter: a composed element (`Face.compose`) costs a C++ call per part; the
        others are drawn with the painter moved and clipped to them. Elements apart are drawn
        over the backdrop (`_backdrop`; without one, over their layers drawn first), overlapping
        ones each from its layer up."""
        region = event.region()
        backdrop = self._backdrop() if self._apart else None
        p = QPainter(self)
        try:  # a painter left active after an error would crash Qt
            if backdrop is not None:
                self._paint_over(p, region, backdrop)
                return
            bare = region.intersected(self._bare)  # the background under an opaque element is not seen
            if not bare.isEmpty():
                p.setClipRegion(bare)
                p.fillRect(bare.boundingRect(), self._back)
                self._paint_ground(p)
                p.setClipping(False)
            p.setRenderHint(QPainter.RenderHint.Antialiasing)
            whole = region.rectCount() == 1 and event.rect().contains(self._extent)  # no test per element
            faces = self._faces if whole else [
                f for f, g in zip(self._faces, self._places) if region.intersects(g)]
            if self._apart:  # at a fractional device pixel ratio: the layers, then the passes
                for face in faces:
                    ops = face.drawn
                    if ops is not None:
                        PIX(p, *ops[0][1])
                self._paint_passes(p, faces)
                return
            for face in faces:
                self._paint_one(p, face)
        finally:
            p.end()

    def _paint_ground(self, p: QPainter) -> None:
        """The form's background picture, where the painter is clipped to."""
        if self.form.BackgroundImage is not None:
            draw_pixmap(p, self.images.get(self.form.BackgroundImage), QRectF(self.rect()), "Stretch")

    def _backdrop(self) -> QPixmap | None:
        """The form as it looks under the elements' dynamic parts: its background, and the layer
        of each composed element at its place (`_tiles`), made at the first paint; a tile is
        composed anew only when its element's layer is another (a lamp's state, a restyle, a
        stale mark). A whole repaint then costs one copy of the form, not one per element (each
        a call into Qt that streams its pixels through memory). None at a fractional device
        pixel ratio, where a part of the form copied might not land on whole pixels."""
        dpr = self.devicePixelRatioF()
        if dpr != int(dpr):
            return None
        backdrop = self._ground
        if backdrop is None or backdrop.devicePixelRatio() != dpr:
            backdrop = self._ground = blank(self.size(), dpr, self._back)
            self._tiles = [None] * len(self._faces)
            if self.form.BackgroundImage is not None:
                p = QPainter(backdrop)
                try:
                    self._paint_ground(p)
                finally:
                    p.end()
        tiles, p = self._tiles, None
        try:
            for i, face in enumerate(self._faces):  # the loop runs a thousand times a tick on a large form
                ops = face.drawn
                layer = None if ops is None else ops[0][1][2]  # the first part: the layer (`Face`)
                if layer is not tiles[i]:
                    if p is None:
                        p = QPainter(backdrop)
                    if layer is None or layer.hasAlphaChannel():  # type: ignore[union-attr]
                        self._compose_tile(p, self._places[i], layer)  # type: ignore[arg-type]
                    else:  # an opaque layer covers its tile: its composition's own copy
                        PIX(p, *ops[0][1])  # type: ignore[index]
                    tiles[i] = layer
        finally:
            if p is not None:
                p.end()
        return backdrop

    def _compose_tile(self, p: QPainter, place: QRect, layer: QPixmap | None) -> None:
        """The backdrop at one element's place: a layer that is not opaque over the background
        (None: the background alone; the element is drawn with a painter)."""
        p.fillRect(place, self._back)
        if self.form.BackgroundImage is not None:
            p.setClipRect(place)
            self._paint_ground(p)
            p.setClipping(False)
        if layer is not None:
            p.drawPixmap(place.x(), place.y(), layer)

    def _paint_over(self, p: QPainter, region: QRegion, backdrop: QPixmap) -> None:
        """The repainted region of the backdrop in one copy, then the elements in it past their
        layers, which the backdrop holds."""
        rect = region.boundingRect()
        several = region.rectCount() > 1
        if several:  # the copy stays inside the region: the elements outside it are not redrawn
            p.setClipRegion(region)
        dpr = backdrop.devicePixelRatio()
        p.drawPixmap(rect.topLeft(), backdrop, QRect(rect.topLeft() * dpr, rect.size() * dpr))
        if several:
            p.setClipping(False)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        if several or not rect.contains(self._extent):  # no test per element on a whole repaint
            faces = [f for f, g in zip(self._faces, self._places) if region.intersects(g)]
        else:
            faces = self._faces
        self._paint_passes(p, faces)

    def _paint_passes(self, p: QPainter, faces: list[Face]) -> None:
        """The elements over the backdrop, in three passes: each element up to its value's text, then
        the texts, then what lies over them (a dial's needle). Drawn element by element, a text cut
        at its box or its element's sides needs a clip turned on before it and off after it, and
        that costs Qt more than its glyphs; in a pass of their own each text sets its clip in
        turn, it is turned off once, and the texts share the pen while their colour does. The
        elements do not overlap (`_apart`) and each draws only inside its own rectangle (a text
        is cut at its element's sides, or its ink lies inside them: a slot with `sides`), so
        this is pixel for pixel the order element by element."""
        texts: list[tuple[Face, Text]] = []
        over: list[tuple[Face, Op]] = []  # drawn after the texts
        for face in faces:  # the loop runs a thousand times a tick on a large form
            ops = face.drawn
            if ops is None:
                self._paint_one(p, face)
                continue
            if len(ops) == 1:  # its layer alone (a lamp): the backdrop holds it
                continue
            try:
                later = False
                for op in ops[1:]:  # past the layer
                    method, args = op
                    if later:
                        over.append((face, op))
                    elif method is draw_text and args[0].sides is not None:  # type: ignore[attr-defined]
                        texts.append((face, args))  # type: ignore[arg-type]
                        later = True
                    else:
                        method(p, *args)
            except Exception as e:  # no log: _fault logs it, once
                self._fault(face.model, e, "drawing")
        self._paint_texts(p, texts)
        for face, (method, args) in over:
            try:
                method(p, *args)
            except Exception as e:  # no log: _fault logs it, once
                self._fault(face.model, e, "drawing")

    def _paint_texts(self, p: QPainter, texts: list[tuple[Face, Text]]) -> None:
        """The value texts of `_paint_passes`, each as `TextSlot.paint` draws it. A text cut at
        its box alone, its ink inside its element (a `Plan` `boxed`), waits for the last pass."""
        clipped, pen = False, None
        boxed: list[tuple[Face, QPointF, QGlyphRun, Ink, QRect]] = []
        for face, (slot, x, y, text, ink) in texts:
            try:
                width, origin, cut, alone = slot.ready(text, x, y)
                if ink.back is not None and width <= slot.span64:
                    if clipped:
                        p.setClipping(False)
                        clipped = False
                    slot.fill(p, ink, x, y)
                if alone:
                    boxed.append((face, origin, slot.run, ink, cut))  # type: ignore[arg-type]
                    continue
                if ink is not pen:
                    p.setPen(ink.fore)
                    pen = ink
                if cut is not None:
                    p.setClipRect(cut)
                    clipped = True
                elif clipped:
                    p.setClipping(False)
                    clipped = False
                p.drawGlyphRun(origin, slot.run)
            except Exception as e:  # no log: _fault logs it, once
                self._fault(face.model, e, "drawing")
        if clipped:
            p.setClipping(False)
        if boxed:
            self._paint_boxed(p, boxed)

    def _paint_boxed(self, p: QPainter, boxed: list[tuple[Face, QPointF, QGlyphRun, Ink, QRect]]) -> None:
        """Texts each cut at its box, all under one clip: the boxes of every text of the form
        known to be cut at its box (`_boxes`, the region made again when one is new). Within a
        text's element that region is its own box (the others lie in other elements, and its ink
        does not leave its element), so each is cut as alone; one clip costs Qt less than a
        clip switched per text, and the glyphs drawn under it half as much as under those."""
        boxes = self._boxes
        for face, _, _, _, cut in boxed:
            known = boxes.get(face)
            if known is None or known != cut:
                boxes[face] = cut
                self._box_clip = None
        region = self._box_clip
        if region is None:
            region = self._box_clip = _union(list(boxes.values()))
        p.save()  # (Qt 6.11 cuts cached glyphs at a clip of many rectangles set inside a save only)
        try:
            p.setClipRegion(region)
            pen = None
            for face, origin, run, ink, _ in boxed:
                try:
                    if ink is not pen:
                        p.setPen(ink.fore)
                        pen = ink
                    p.drawGlyphRun(origin, run)
                except Exception as e:  # no log: _fault logs it, once
                    self._fault(face.model, e, "drawing")
        finally:
            p.restore()

    def _paint_one(self, p: QPainter, face: Face) -> None:
        """One element: from its composition, or with the painter moved and clipped to it."""
        widget, at, rect = self._slots[face]
        try:
            ops = face.drawn
            if ops is not None:
                for method, args in ops:
                    method(p, *args)
                return
            p.setTransform(at)  # each sets the pens, fonts... it uses
            p.setClipRect(rect)
            widget.draw(p, rect)
        except Exception as e:  # no log: _fault logs it, once
            self._fault(widget.model, e, "drawing")
        p.setClipping(False)
        p.resetTransform()


def _apart(places: list[QRect]) -> bool:
    """Whether no two of the rectangles overlap (touching is not overlapping)."""
    covered = QRegion()
    for rect in places:
        if covered.intersects(rect):
            return False
        covered += rect
    return True


def _union(rects: list[QRect]) -> QRegion:
    """The region the rectangles cover, joined by halves (one at a time costs time squared)."""
    if len(rects) <= 8:
        region = QRegion()
        for rect in rects:
            region += rect
        return region
    half = len(rects) // 2
    return _union(rects[:half]) | _union(rects[half:])


def _worst(sources: tuple[tuple[int, int], ...], readings: Readings,
           judged: dict[tuple[int, int], Quality]) -> Quality:
    """The worst quality of an element's operands, each judged once per refresh."""
    worst = Quality.GOOD
    for source in sources:
        quality = judged.get(source)
        if quality is None:
            quality = judged[source] = readings.address(*source)
        worst = max(worst, quality)
    return worst
