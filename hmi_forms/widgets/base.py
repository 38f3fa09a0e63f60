"""The base of every element widget: geometry from the model, UObject frame, and the stale mark.

Painting is split in two: a layer (background, frame and everything that depends only on a few
states, such as a discrete element's text or a gauge's scale) rendered once per state into a
pixmap, and a dynamic part (a pointer, a value) drawn over it. A form of hundreds of elements then
costs one pixmap copy per element and tick plus the few strokes that really change. Where the
dynamic part also comes from cached pixmaps (texts, needles, bar fills), a change composes the
element into a short list of pixmap copies at its place on the form (`Face`): painting it then
needs no painter state, and an unchanged composition is not repainted at all.

Widgets only draw what their model computed, and never write it. The stale mark (grey wash,
hatching and a "?" badge) is a child widget kept above everything else, so it also covers plots
and input fields, and it is drawn identically for all element types: an operator learns it once.
A forced value is not bad data, and must not look like it: its mark is an orange frame with an "F"
badge and no hatching (`paint_forced`), so a commissioning force left behind is seen at a glance.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from operator import itemgetter
from pathlib import Path
from typing import ClassVar

from PySide6.QtCore import QT_TRANSLATE_NOOP, QCoreApplication, QEvent, QPoint, QPointF, QRect, QRectF, Qt
from PySide6.QtGui import QBrush, QColor, QMoveEvent, QPainter, QPaintEvent, QPen, QPixmap, QResizeEvent
from PySide6.QtWidgets import QWidget

from hmi_forms.elements import Element
from hmi_forms.elements.bank import Bank
from hmi_forms.widgets import theme

Op = tuple[Callable[..., None], tuple[object, ...]]  # an unbound QPainter method (or a function of the
# painter: sprites.draw_text) and its arguments:
PIX, FILL = QPainter.drawPixmap, QPainter.fillRect  # (x, y, pixmap) and (x, y, w, h, colour)
STYLE = ("BackColor", "ForeColor", "BorderStyle", "Font")  # checked at every draw (`style`)
ORIGIN = QPoint(0, 0)
MAX_LAYERS = 6  # cached layers per widget: enough for every state of a discrete element
MAX_SHARED = 4096  # layers kept for widgets that look alike (by type, look, state and size)
SHARED_LAYERS: dict[Hashable, QPixmap] = {}
CURSORS = {"Hand": Qt.CursorShape.PointingHandCursor, "Cross": Qt.CursorShape.CrossCursor,
           "IBeam": Qt.CursorShape.IBeamCursor, "No": Qt.CursorShape.ForbiddenCursor}


class Images:
    """The pictures of one form, loaded once and shared by its widgets."""

    def __init__(self, files: list[Path | None]) -> None:
        self.files = files
        self._cache: dict[Path, QPixmap] = {}

    def get(self, path: Path) -> QPixmap:
        pix = self._cache.get(path)
        if pix is None:
            pix = self._cache[path] = QPixmap(str(path))
        return pix

    def index(self, i: int) -> QPixmap | None:
        path = self.files[i] if 0 <= i < len(self.files) else None  # None: left out by the loader
        return self.get(path) if path is not None else None


def draw_pixmap(p: QPainter, pix: QPixmap, rect: QRectF, mode: str = "Zoom",
                align: Qt.AlignmentFlag = Qt.AlignmentFlag.AlignCenter) -> None:
    if pix.isNull() or rect.width() <= 0 or rect.height() <= 0:
        return
    w, h = pix.width(), pix.height()
    if mode == "Stretch":
        p.drawPixmap(rect.toRect(), pix)
        return
    if mode == "Zoom":
        k = min(rect.width() / w, rect.height() / h)
        w, h = w * k, h * k
    x = rect.left() + (rect.width() - w) * (0 if align & Qt.AlignmentFlag.AlignLeft else
                                            1 if align & Qt.AlignmentFlag.AlignRight else 0.5)
    y = rect.top() + (rect.height() - h) * (0 if align & Qt.AlignmentFlag.AlignTop else
                                            1 if align & Qt.AlignmentFlag.AlignBottom else 0.5)
    p.drawPixmap(QRectF(x, y, w, h), pix, QRectF(0, 0, pix.width(), pix.height()))


STALE_TIP = QT_TRANSLATE_NOOP(
    "quality", "Stale: the data source of this element is not answering; the last value is shown")
QUALITY_TIPS = {
    "stale": STALE_TIP,
    "initial": QT_TRANSLATE_NOOP(
        "quality", "? initial: no value from the plant yet (the node has not answered since the start)"),
    "comm-fail": QT_TRANSLATE_NOOP(
        "quality", "? comm-fail: the node that fills this value is down; the last value is shown"),
    "not running": QT_TRANSLATE_NOOP(
        "quality", "? not running: NetPlc is stopped; the last value is shown, nothing changes"),
    "forced": QT_TRANSLATE_NOOP("quality", "F forced: the value is forced by an engineer, not the plant's"),
    "station unreachable": QT_TRANSLATE_NOOP(
        "quality", "? station unreachable: the console's link to the station is lost; "
                   "the last value is shown"),
}


def quality_tip(word: str) -> str:
    """The tooltip of the quality mark: the quality word first, then what it means, in the
    console's language (the words are Quality.word's, app/scada/quality.py)."""
    tip = QUALITY_TIPS.get(word)
    return QCoreApplication.translate("quality", tip) if tip else f"? {word}"


def paint_stale(p: QPainter, r: QRectF) -> None:
    """Greyed, hatched, with a "?" badge: the same mark on every element type."""
    p.fillRect(r, QColor(221, 225, 230, 150))
    p.fillRect(r, QBrush(QColor(90, 96, 106, 110), Qt.BrushStyle.BDiagPattern))
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    d = max(16.0, min(22.0, min(r.width(), r.height()) * 0.35))  # its glyph >= 12 px
    badge = QRectF(r.right() - d - 2, r.top() + 2, d, d)
    p.setPen(QPen(QColor("#ffffff"), 1.5))
    p.setBrush(theme.STALE)
    p.drawEllipse(badge)
    p.setFont(theme.sized_font(d * 0.75, bold=True))
    p.drawText(badge, Qt.AlignmentFlag.AlignCenter, "?")


def paint_forced(p: QPainter, r: QRectF) -> None:
    """An orange frame and an "F" badge, the value left readable: forced is not bad quality."""
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    p.fillRect(r, QColor(theme.FORCED.red(), theme.FORCED.green(), theme.FORCED.blue(), 40))
    p.setPen(QPen(theme.FORCED, 3))
    p.setBrush(Qt.BrushStyle.NoBrush)
    p.drawRect(r.adjusted(1.5, 1.5, -1.5, -1.5))
    d = max(16.0, min(22.0, min(r.width(), r.height()) * 0.35))  # its glyph >= 12 px
    badge = QRectF(r.right() - d - 2, r.top() + 2, d, d)
    p.setPen(Qt.PenStyle.NoPen)
    p.setBrush(theme.FORCED)
    p.drawRect(badge)
    p.setPen(QColor("#ffffff"))
    p.setFont(theme.sized_font(d * 0.75, bold=True))
    p.drawText(badge, Qt.AlignmentFlag.AlignCenter, "F")


def paint_quality(p: QPainter, r: QRectF, word: str) -> None:
    """The mark of what is not good about the value shown: forced, or stale (any other word)."""
    if word == "forced":
        paint_forced(p, r)
    else:
        paint_stale(p, r)


class StaleMark(QWidget):
    """The quality mark as a child on top of elements made of child widgets (plots, input fields)."""

    def __init__(self, parent: QWidget) -> None:
        super().__init__(parent)
        self.setAttribute(Qt.WidgetAttribute.WA_TransparentForMouseEvents)
        self.word = "stale"
        self.setToolTip(quality_tip(self.word))
        self.hide()

    def show_word(self, word: str) -> None:
        if word != self.word:
            self.word = word
            self.update()
        self.setToolTip(quality_tip(word))

    def paintEvent(self, event: QPaintEvent) -> None:
        p = QPainter(self)
        try:
            paint_quality(p, QRectF(self.rect()), self.word)
        finally:
            p.end()


class ElementWidget(QWidget):
    """An element on a form: its geometry, input and tooltip, and the code that draws it.

    Elements drawn only with QPainter are painted by the form itself, in one pass with one painter
    (`draw`), and their widget stays an invisible proxy for the mouse, cursor and tooltip, with
    its own updates off: a QPainter, or only a paint event, per widget per tick costs more than
    drawing a whole gauge. Elements made of child widgets (`SelfPainted`) paint themselves and
    carry a StaleMark child instead.
    """

    default_back: QColor | None = theme.PANEL  # None = transparent
    face_class: type[Face]  # Face, given below its definition; a widget class may have its own

    def __init__(self, model: Element, images: Images, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.face = self.face_class(self)  # how its form draws it (made ready at the first change)
        self.images = images
        self.setGeometry(model.x, model.y, model.w, model.h)
        # drawn by the form (`draw`): Qt is spared a paint event of this widget's own, which costs
        # more than drawing the element (SelfPainted widgets turn it back on)
        self.setUpdatesEnabled(False)
        if model.Cursor in CURSORS:
            self.setCursor(CURSORS[model.Cursor])
        self._layers: dict[Hashable, QPixmap] = {}
        # read from the model's attributes in one call in C at every draw and composition (an
        # attrgetter would ask the model's class for each name first, at twice the cost)
        self._style_of = itemgetter(*self.style_props())
        self._style = self.style()
        self._look = self.look()
        # the form and the rectangle on it, kept: asking Qt for them costs more than the repaint
        self._where: tuple[Callable[[QRect], None] | None, QRect, int, int] | None = None
        self._stale = False
        self._tip = ""  # the element's own tooltip, kept while the quality mark's is shown

    def back_color(self) -> QColor | None:
        if self.model.BackColor is not None:
            return QColor(*self.model.BackColor)
        return self.default_back

    def fore_color(self) -> QColor:
        return theme.qcolor(self.model.ForeColor, theme.TEXT)

    def covers(self) -> bool:
        """Whether the element paints every pixel of its rectangle in every state (an opaque
        background): the form need not paint its own background there first."""
        back = self.back_color()
        return back is not None and back.alpha() == 255

    def sync(self) -> None:
        """The model changed: compose the element anew and have the form repaint it, unless it
        looks exactly as it did (a value that moved less than a pixel costs no paint)."""
        self.face.sync()

    def mark_quality(self) -> None:
        """The quality mark's tooltip while the data are not good; the element's own after."""
        stale = self.model.stale
        if stale != self._stale:
            self._stale = stale
            if stale:
                self._tip = self.toolTip()
            else:
                self.setToolTip(self._tip)
        if stale:
            self.setToolTip(quality_tip(self.model.quality or "stale"))

    def _locate(self) -> tuple[Callable[[QRect], None] | None, QRect, int, int]:
        """What repaints a part of the form (the form's own scheduler when it has one), and where
        the element is on it."""
        parent = self.parentWidget()
        rect = self.geometry()
        update = None if parent is None else getattr(parent, "schedule", parent.update)
        where = self._where = (update, rect, rect.x(), rect.y())
        return where

    def style_props(self) -> tuple[str, ...]:
        """The model's properties `style` is made of."""
        return STYLE

    def style(self) -> tuple[object, ...]:
        """The colours, frame and font: checked at every draw and composition, so that a change
        (a form designer sets a colour) rebuilds the cached pictures by itself. Other properties the
        pictures are drawn from are in `look`: after changing one, call `restyle`."""
        return self._style_of(vars(self.model))

    def look(self) -> tuple[object, ...]:
        """Everything the cached layer is drawn from besides the state and the size: widgets
        with equal looks share their layers."""
        m = self.model
        return (*self.style(), m.BackgroundImage, m.ImageAlign, m.TextAlign)

    def restyle(self) -> None:
        """Forget the cached pictures: the look changed."""
        self.face.forget()
        self._layers.clear()
        self._style = self.style()
        self._look = self.look()

    def flush(self) -> None:
        """Bring throttled parts (plots, queries) up to date; plain painted widgets have none."""

    def layer_key(self) -> Hashable:
        """What the cached layer (background, frame, `paint_static`) depends on."""
        return ()

    def draw(self, p: QPainter, r: QRectF) -> None:
        """Draw the element into `r`, its own rectangle, with its top-left corner at the origin."""
        if self.style() != self._style:
            self.restyle()
        p.drawPixmap(ORIGIN, self.layer())
        self.paint_dynamic(p, r)
        if self.model.stale:
            paint_quality(p, r, self.model.quality)

    def layer(self) -> QPixmap:
        key = self.layer_key()
        layer = self._layers.get(key)
        if layer is None:
            # elements that look alike share their layers: fewer pixmaps to render, and a copy
            # of a pixmap still in the processor's cache is several times faster
            shared = (type(self), self._look, key, self.size().toTuple(), self.devicePixelRatioF())
            layer = SHARED_LAYERS.get(shared)
            if layer is None:
                if len(SHARED_LAYERS) >= MAX_SHARED:
                    SHARED_LAYERS.clear()  # the widgets keep those they use
                layer = SHARED_LAYERS[shared] = self._render_layer()
            self._layers[key] = layer
            if len(self._layers) > MAX_LAYERS:
                del self._layers[next(iter(self._layers))]
        return layer

    def _render_layer(self) -> QPixmap:
        dpr = self.devicePixelRatioF()
        pix = QPixmap(self.size() * dpr)
        pix.setDevicePixelRatio(dpr)
        back = self.back_color()
        opaque = back is not None and back.alpha() == 255
        pix.fill(back if opaque else Qt.GlobalColor.transparent)  # opaque layers copy without blending
        p = QPainter(pix)
        try:  # a painter left open on a pixmap crashes Qt when the pixmap goes
            p.setRenderHint(QPainter.RenderHint.Antialiasing)
            self.paint_layer(p, QRectF(self.rect()))
        finally:
            p.end()
        return pix

    def paint_layer(self, p: QPainter, r: QRectF) -> None:
        back = self.back_color()
        if back is not None:
            p.fillRect(r, back)
        if self.model.BackgroundImage is not None:
            draw_pixmap(p, self.images.get(self.model.BackgroundImage), r, "Zoom",
                        theme.alignment(self.model.ImageAlign))
        self.paint_static(p, r)
        self.paint_border(p, r)

    def paint_static(self, p: QPainter, r: QRectF) -> None:
        """Draw what changes rarely (it is cached per `layer_key`)."""

    def paint_dynamic(self, p: QPainter, r: QRectF) -> None:
        """Draw what changes every tick, over the cached layer."""

    def resizeEvent(self, event: QResizeEvent) -> None:
        self._layers.clear()
        self._where = None
        self.face.forget()
        super().resizeEvent(event)

    def moveEvent(self, event: QMoveEvent) -> None:
        self._where = None
        self.face.forget()
        super().moveEvent(event)

    def changeEvent(self, event: QEvent) -> None:
        if event.type() == QEvent.Type.ParentChange:
            self._where = None
            self.face.forget()
        super().changeEvent(event)

    def paint_border(self, p: QPainter, r: QRectF) -> None:
        style = self.model.BorderStyle
        if style == "FixedSingle":
            p.setPen(QPen(theme.qcolor(self.model.ForeColor, theme.BORDER), 1))
            p.setBrush(Qt.BrushStyle.NoBrush)
            p.drawRect(r.adjusted(0.5, 0.5, -0.5, -0.5))
        elif style == "Fixed3D":
            bevel(p, r, sunken=True)


class Face:
    """The element as its form draws it now: its composition, pixmap copies and flat fills from
    the caches at its place on the form, with no painter state and no clip (each lies inside the
    element). A tick of a large form then costs a C++ call per part instead of a painter set up
    per element, and two compositions compare equal exactly when the pixels would: an unchanged
    one is not repainted. What a composition is made from is kept here, in a plain object with
    slots: a tick's loop reads it several times faster than a PySide widget's own attributes.
    `drawn` None: the element is drawn with a painter (`ElementWidget.draw`) this time. A face
    lives as long as its widget; what it read of the widget is read again at the first change
    after the widget moved, was resized or restyled (`forget`)."""

    __slots__ = ("attrs", "drawn", "fresh", "key", "layers", "marked", "model", "plain", "rect", "repaint",
                 "style", "style_of", "widget", "x", "y")

    bank: ClassVar[type[Bank] | None] = None  # what reads the operand of a `plain` element it draws

    def __init__(self, widget: ElementWidget) -> None:
        self.widget, self.model = widget, widget.model
        self.drawn: list[Op] | None = None
        self.fresh = False  # what is below is read from the widget (`load`)
        self.marked = False  # the widget shows the quality mark's tooltip

    def load(self) -> None:
        widget = self.widget
        self.repaint, self.rect, self.x, self.y = widget._where or widget._locate()
        self.layers, self.key = widget._layers, widget.layer_key
        self.style_of, self.style, self.attrs = widget._style_of, widget._style, vars(self.model)
        self.plain = type(widget).paint_dynamic is ElementWidget.paint_dynamic  # the layer is all of it
        self.marked = widget._stale
        self.fresh = True

    def forget(self) -> None:
        """The widget moved, was resized or restyled: drawn with a painter until the next change."""
        self.drawn = None
        self.fresh = False

    def sync(self) -> None:
        if not self.fresh:
            self.load()
        drawn = self.compose()
        if drawn is not None and drawn == self.drawn:
            return
        self.drawn = drawn
        self.show(self.rect)

    def put(self, shown: object) -> bool:
        """Draw what a plain element shows now (what its model `settle`d from a value read with
        the rest of the form's, in a `Bank`). True: the caller is to repaint the element (the form
        does, in one piece with the rest); otherwise it is scheduled already."""
        self.sync()
        return False

    def unmark(self) -> None:
        """Good data again, shown by a `put`: the element's own tooltip comes back."""
        self.widget.mark_quality()
        self.marked = False

    def show(self, part: QRect) -> None:
        """Have the form repaint `part` of it (form coordinates), and the quality mark follow."""
        if self.repaint is not None:
            self.repaint(part)
        stale = self.model.stale
        if stale or self.marked:
            self.widget.mark_quality()
            self.marked = stale

    def compose(self) -> list[Op] | None:
        m = self.model
        if m.stale or not self.plain or self.restyled():  # the stale mark, or a dynamic part: a painter
            return None
        layer = self.layers.get(self.key())  # (not `or`: the truth of a QPixmap is a call into Qt)
        return [(PIX, (self.x, self.y, self.widget.layer() if layer is None else layer))]

    def restyled(self) -> bool:
        """Whether the colours, frame or font changed since the face was read: the widget is then
        restyled, drawn with a painter once, and read again at the next change."""
        if self.style_of(self.attrs) == self.style:
            return False
        self.widget.restyle()
        return True


ElementWidget.face_class = Face


class SelfPainted(ElementWidget):
    """An element made of child widgets: it paints its own background and frame under them."""

    def __init__(self, model: Element, images: Images, parent: QWidget | None = None) -> None:
        super().__init__(model, images, parent)
        self.setUpdatesEnabled(True)
        self.stale_mark = StaleMark(self)
        self.stale_mark.setGeometry(self.rect())
        back = self.back_color()
        if back is not None and back.alpha() == 255:  # the form need not repaint what is beneath
            self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)

    def sync(self) -> None:
        if self.model.stale != self.stale_mark.isVisibleTo(self):
            self.stale_mark.setVisible(self.model.stale)
            self.stale_mark.raise_()
        if self.model.stale:
            self.stale_mark.show_word(self.model.quality or "stale")
        self.update(self.changed_rect())

    def changed_rect(self) -> QRect:
        """The part to repaint after a change (children repaint themselves)."""
        return self.rect()

    def paintEvent(self, event: QPaintEvent) -> None:
        p = QPainter(self)
        try:  # a painter left active after an error would crash Qt
            if self.style() != self._style:
                self.restyle()
            p.drawPixmap(0, 0, self.layer())
            p.setRenderHint(QPainter.RenderHint.Antialiasing)
            self.paint_dynamic(p, QRectF(self.rect()))
        finally:
            p.end()

    def resizeEvent(self, event: QResizeEvent) -> None:
        self.stale_mark.setGeometry(self.rect())
        super().resizeEvent(event)


def bevel(p: QPainter, r: QRectF, sunken: bool) -> None:
    """A 3D edge: light top-left and dark bottom-right (swapped when sunken)."""
    light, dark = QColor("#ffffff"), QColor("#7d848e")
    if sunken:
        light, dark = dark, light
    r = r.adjusted(0.5, 0.5, -0.5, -0.5)
    p.setPen(QPen(light, 1))
    p.drawPolyline([QPointF(r.left(), r.bottom()), r.topLeft(), QPointF(r.right(), r.top())])
    p.setPen(QPen(dark, 1))
    p.drawPolyline([QPointF(r.right(), r.top()), r.bottomRight(), QPointF(r.left(), r.bottom())])
