"""One element on the designer's canvas, drawn by the workstation's own widget class.

The item owns the element's model and widget (never shown, never parented, made when the element
first comes into view): a widget painted by
its form is drawn straight into the canvas with `draw`, exactly as the form draws it; a widget made
of child widgets (plots, input fields, the journal) is rendered once into a pixmap per change. The
item adds only what a designer needs on top: selection outline and handles, a red outline while
the element has problems, resizing by its handles, and under an analog element its scale's band
with the alarm zones of its tag (or its own PhyLow/PhyHigh) and its unit: what the engineer must
see while placing it, before any value arrives.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from PySide6.QtCore import QPointF, QRectF, Qt
from PySide6.QtGui import QBrush, QColor, QPainter, QPainterPath, QPen, QPixmap
from PySide6.QtWidgets import QGraphicsItem, QGraphicsSceneMouseEvent, QStyleOptionGraphicsItem, QWidget

from app.scada.table import TagAlarms
from hmi_forms.elements import Element
from hmi_forms.elements.analog import AnalogBase, Scaled
from hmi_forms.widgets import theme
from hmi_forms.widgets.base import ElementWidget, SelfPainted
from hmi_forms.widgets.journal import JournalWidget
from netplc.memory import Snapshot

if TYPE_CHECKING:
    from app.gui.designer.design import Design

logger = logging.getLogger(__name__)

HANDLE = 7.0
SELECTED = QColor("#1e6fd9")
PROBLEM = QColor("#d32f2f")
# handle name -> which edges it moves (left, top, right, bottom)
HANDLES = {"tl": (1, 1, 0, 0), "t": (0, 1, 0, 0), "tr": (0, 1, 1, 0), "r": (0, 0, 1, 0),
           "br": (0, 0, 1, 1), "b": (0, 0, 0, 1), "bl": (1, 0, 0, 1), "l": (1, 0, 0, 0)}
CURSORS = {"tl": Qt.CursorShape.SizeFDiagCursor, "br": Qt.CursorShape.SizeFDiagCursor,
           "tr": Qt.CursorShape.SizeBDiagCursor, "bl": Qt.CursorShape.SizeBDiagCursor,
           "t": Qt.CursorShape.SizeVerCursor, "b": Qt.CursorShape.SizeVerCursor,
           "l": Qt.CursorShape.SizeHorCursor, "r": Qt.CursorShape.SizeHorCursor}


BAND = 5.0  # the scale band's height


def zones(model: Scaled, alarms: TagAlarms | None) -> list[tuple[float, float, QColor]]:
    """The alarm zones on the element's scale as (from, to) fractions of PhyMin..PhyMax and a colour:
    the tag's LL/L and H/HH limits (amber beyond L and H, red beyond LL and HH), else the element's
    own PhyLow/PhyHigh."""
    lo, hi = model.scaling.phy_range
    if alarms is not None and alarms.limits():
        marks = [(lo, alarms.ll, theme.ALARM), (lo, alarms.l, theme.WARN),
                 (alarms.h, hi, theme.WARN), (alarms.hh, hi, theme.ALARM)]
    elif isinstance(model, AnalogBase):
        marks = [(lo, model.PhyLow, theme.WARN), (model.PhyHigh, hi, theme.ALARM)]
    else:
        marks = []
    out = []
    for a, b, color in marks:
        if a is not None and b is not None:
            fa, fb = model.scaling.fraction(a), model.scaling.fraction(b)
            out.append((min(fa, fb), max(fa, fb), color))
    return out


def handle_points(r: QRectF) -> dict[str, QPointF]:
    cx, cy = r.center().x(), r.center().y()
    return {"tl": r.topLeft(), "t": QPointF(cx, r.top()), "tr": r.topRight(),
            "r": QPointF(r.right(), cy), "br": r.bottomRight(), "b": QPointF(cx, r.bottom()),
            "bl": r.bottomLeft(), "l": QPointF(r.left(), cy)}


class ElementItem(QGraphicsItem):
    def __init__(self, design: Design, raw: dict[str, Any]) -> None:
        super().__init__()
        self.design = design
        self.raw = raw
        self.model: Element | None = None
        self.widget: ElementWidget | None = None
        self.problems: list[str] = []
        self._pixmap: QPixmap | None = None
        self._size = (1.0, 1.0)
        self._unread = False
        self._resize: tuple[str, QPointF, QRectF] | None = None  # handle, press point, start rect
        self.resize_rect: QRectF | None = None
        self.flagged = False  # named by the problems pane
        self.setFlags(QGraphicsItem.GraphicsItemFlag.ItemIsSelectable
                      | QGraphicsItem.GraphicsItemFlag.ItemIsMovable)
        self.setAcceptHoverEvents(True)
        self.rebuild()

    # --- the element ---------------------------------------------------------------------------

    def rebuild(self) -> None:
        """Read the element again (after an edit): new model, new widget, same item."""
        self.prepareGeometryChange()
        self.model, self.problems = self.design.reader.drawable(self.raw)
        if self.widget is not None:
            self.widget.deleteLater()
        self.widget = None
        self._pixmap = None
        self._unread = self.model is not None  # reads the design's snapshot when first drawn
        self._size = (float(self.model.w), float(self.model.h)) if self.model is not None else (
            float(_int(self.raw.get("w"), 40)), float(_int(self.raw.get("h"), 20)))
        self.setToolTip(f'{self.raw.get("type")} "{self.raw.get("Name")}"'
                        + "".join(f"\n{t.split(': ', 2)[-1]}" for t in self.problems))
        self.place()

    def place(self) -> None:
        """Follow x and y of the document."""
        self.setPos(_int(self.raw.get("x"), 0), _int(self.raw.get("y"), 0))

    def show_snapshot(self, snap: Snapshot) -> None:
        """Update the model from a snapshot (live preview) and redraw; a model that cannot read it
        (a missing address drawn from its placeholder) keeps its first look. One that has no
        problem and still fails is a fault: logged, and marked as a problem of the element."""
        if self.model is None:
            return
        self._unread = False
        if self.problems and snap.scan:
            return  # placeholders must not show live values as if they were the element's
        try:
            changed = self.model.update(snap)
        except Exception as e:
            changed = False
            if not self.problems:  # with problems its placeholders may fail to read: expected
                logger.exception('designer: element "%s" cannot show the snapshot', self.raw.get("Name"))
                self.problems = [*self.problems, f"update failed: {e!r}"]
        if changed and self.widget is not None:
            self.widget.sync()
            self._pixmap = None
            self.update()

    def _read_again(self, *_: object) -> None:
        """A journal's page arrived: the canvas shows a picture of the widget taken before, which
        the widget's own repaint does not reach; drawn again with the rows."""
        self._pixmap = None
        self.update()

    def _placeholder(self, p: QPainter, r: QRectF) -> None:
        """An element no widget can draw (an unknown type): its type and name on a hatched box."""
        p.fillRect(r, QBrush(QColor(211, 47, 47, 60), Qt.BrushStyle.BDiagPattern))
        p.setPen(QColor("#1a1a1a"))
        p.drawText(r, Qt.AlignmentFlag.AlignCenter, f'{self.raw.get("type")}\n{self.raw.get("Name")}')

    def set_flagged(self, on: bool) -> None:
        if on != self.flagged:
            self.flagged = on
            self.update()

    # --- drawing --------------------------------------------------------------------------------

    def boundingRect(self) -> QRectF:
        """The element with room for its handles (and, while resized, for the new outline)."""
        w, h = self._size
        box = QRectF(-HANDLE, -HANDLE, w + 2 * HANDLE, h + 2 * HANDLE)
        return box if self.resize_rect is None else box.united(self.resize_rect.adjusted(-2, -2, 2, 2))

    def rect(self) -> QRectF:
        return QRectF(0, 0, *self._size)

    def shape(self) -> QPainterPath:
        """The element's rectangle (and, while selected, its handles): where a click picks it."""
        path = QPainterPath()
        path.addRect(self.rect())
        if self.isSelected():
            for point in handle_points(self.rect()).values():
                path.addRect(QRectF(point.x() - HANDLE, point.y() - HANDLE, 2 * HANDLE, 2 * HANDLE))
        return path

    def paint(self, p: QPainter, option: QStyleOptionGraphicsItem, _w: QWidget | None = None) -> None:
        r = self.rect()
        if self._unread:  # read and made when first seen: opening a big form stays fast
            self.show_snapshot(self.design.snapshot)
        if self.widget is None and self.model is not None:
            self.widget = self.design.widget_for(self.model)
            if isinstance(self.widget, JournalWidget):  # its page is read in a thread, after this
                self.widget.worker.answered.connect(self._read_again)
        widget = self.widget
        p.save()
        try:
            if widget is None:
                self._placeholder(p, r)
            elif isinstance(widget, SelfPainted):
                if self._pixmap is None:
                    widget.flush()
                    self._pixmap = widget.grab()
                p.drawPixmap(0, 0, self._pixmap)
            else:
                p.setClipRect(r)
                widget.draw(p, r)
        except Exception as e:  # a widget that cannot draw this model: say so, keep the canvas going
            logger.exception('designer: element "%s" cannot be drawn', self.raw.get("Name"))
            self.problems = [*self.problems, f"drawing failed: {e!r}"]
            self.model = self.widget = None
        finally:
            p.restore()
        if isinstance(self.model, Scaled) and not self.problems:
            self._scale_band(p, r, self.model)
        if self.problems or self.flagged:
            p.setPen(QPen(PROBLEM, 1.5, Qt.PenStyle.DashLine))
            p.setBrush(Qt.BrushStyle.NoBrush)
            p.drawRect(r.adjusted(0.75, 0.75, -0.75, -0.75))
        if self.isSelected():
            p.setPen(QPen(SELECTED, 1, Qt.PenStyle.DashLine))
            p.setBrush(Qt.BrushStyle.NoBrush)
            p.drawRect(r)
            if self.resize_rect is not None:
                p.setPen(QPen(SELECTED, 1.5))
                p.drawRect(self.resize_rect)
            p.setPen(QPen(QColor("#ffffff"), 1))
            p.setBrush(SELECTED)
            for point in handle_points(r).values():
                p.drawRect(QRectF(point.x() - HANDLE / 2, point.y() - HANDLE / 2, HANDLE, HANDLE))

    def _scale_band(self, p: QPainter, r: QRectF, model: Scaled) -> None:
        """The scale as a band along the element's bottom edge, its alarm zones coloured, and the
        unit (with the tag it comes from) above its right end."""
        alarms = self.design.doc.tags.alarms.get(model.tag) if model.tag else None
        band = QRectF(r.left(), r.bottom() - BAND, r.width(), BAND)
        p.save()
        p.setPen(Qt.PenStyle.NoPen)
        p.fillRect(band, QColor("#c8d2dc"))
        for f0, f1, color in zones(model, alarms):
            p.fillRect(QRectF(band.left() + f0 * band.width(), band.top(), (f1 - f0) * band.width(),
                              band.height()), color)
        caption = " ".join(t for t in (model.tag, model.Units) if t)
        if caption and r.height() > 3 * BAND:
            font = p.font()
            font.setPixelSize(10)
            p.setFont(font)
            p.setPen(theme.TEXT_DIM)
            p.drawText(QRectF(r.left(), band.top() - 13, r.width() - 3, 13),
                       int(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter), caption)
        p.restore()

    # --- moving and resizing ---------------------------------------------------------------------

    def handle_at(self, pos: QPointF) -> str | None:
        if len(self.design.scene.selectedItems()) != 1:
            return None
        for name, point in handle_points(self.rect()).items():
            if abs(pos.x() - point.x()) <= HANDLE and abs(pos.y() - point.y()) <= HANDLE:
                return name
        return None

    def hoverMoveEvent(self, event: Any) -> None:
        handle = self.handle_at(event.pos()) if self.isSelected() else None
        if handle is None:
            self.unsetCursor()
        else:
            self.setCursor(CURSORS[handle])
        super().hoverMoveEvent(event)

    def mousePressEvent(self, event: QGraphicsSceneMouseEvent) -> None:
        handle = self.handle_at(event.pos()) if self.isSelected() else None
        if handle is not None and event.button() == Qt.MouseButton.LeftButton:
            self._resize = (handle, event.scenePos(), QRectF(self.pos(), self.rect().size()))
            event.accept()
            return
        super().mousePressEvent(event)

    def mouseMoveEvent(self, event: QGraphicsSceneMouseEvent) -> None:
        if self._resize is None:
            super().mouseMoveEvent(event)  # moves the whole selection
            self.design.snap_selection()
            return
        handle, start, rect = self._resize
        d = event.scenePos() - start
        left, top, right, bottom = HANDLES[handle]
        snap = self.design.snap
        r = QRectF(rect)
        if left:
            r.setLeft(min(snap(rect.left() + d.x()), rect.right() - 1))
        if top:
            r.setTop(min(snap(rect.top() + d.y()), rect.bottom() - 1))
        if right:
            r.setRight(max(snap(rect.right() + d.x()), rect.left() + 1))
        if bottom:
            r.setBottom(max(snap(rect.bottom() + d.y()), rect.top() + 1))
        self.prepareGeometryChange()
        self.resize_rect = r.translated(-self.pos())

    def mouseReleaseEvent(self, event: QGraphicsSceneMouseEvent) -> None:
        if self._resize is not None:
            r = self.resize_rect
            self.prepareGeometryChange()
            self._resize = self.resize_rect = None
            if r is not None:
                r = r.translated(self.pos())
                self.design.set_geometry({id(self.raw): (round(r.x()), round(r.y()), round(r.width()),
                                                         round(r.height()))}, "Resize")
            return
        super().mouseReleaseEvent(event)
        self.design.commit_moves()


def _int(value: Any, default: int) -> int:
    return value if isinstance(value, int) and not isinstance(value, bool) else default
