"""Widgets of the discrete elements: an indicator, or a button when the element is Enabled.

An Enabled element is drawn raised (a button) and a disabled one flat, so the operator can tell
what a click will do before clicking. A base element without state colours gets a lamp on its
left: its state must be visible even when TextFalse and TextTrue are empty.
"""

from __future__ import annotations

from collections.abc import Hashable

from PySide6.QtCore import QCoreApplication, QRectF, Qt
from PySide6.QtGui import QColor, QLinearGradient, QMouseEvent, QPainter, QPen
from PySide6.QtWidgets import QWidget

from hmi_forms.elements.bank import BitBank
from hmi_forms.elements.discrete import DiscreteBase, DiscreteColorLabel
from hmi_forms.widgets import theme
from hmi_forms.widgets.base import PIX, STYLE, ElementWidget, Face, Images, Op, draw_pixmap


class DiscreteFace(Face):
    """A discrete element's composition: the layer of its state. For an element whose state is its
    bit alone (`plain`), the layer is looked up by the bit and the press, not by asking the model
    for every property the layer is drawn from."""

    __slots__ = ("by_state", "pressed", "simple")

    bank = BitBank

    def __init__(self, widget: ElementWidget) -> None:
        super().__init__(widget)
        self.pressed = False  # the operator holds the mouse button on it
        self.by_state: dict[tuple[int | None, bool], list[Op]] = {}  # the composition of each
        self.simple = False

    def load(self) -> None:
        super().load()
        self.by_state = {}
        self.simple = type(self.model) in (DiscreteBase, DiscreteColorLabel)

    def put(self, shown: int) -> bool:
        """`Face.put` in one step: the composition by the bit and the press (a plain element is
        simple), the same list while its layer is: an unchanged one is told by identity."""
        if not self.fresh:
            self.load()
        if self.style_of(self.attrs) != self.style:
            return super().put(shown)
        drawn = self._composed()
        if drawn is self.drawn:
            return False
        self.drawn = drawn
        if self.marked:
            self.unmark()
        return True

    def compose(self) -> list[Op] | None:
        if not self.simple:
            return super().compose()
        m = self.model
        if m.stale or self.restyled():
            return None
        return self._composed()

    def _composed(self) -> list[Op]:
        state = (self.model.value, self.pressed)
        drawn = self.by_state.get(state)
        if drawn is None:
            drawn = self.by_state[state] = [(PIX, (self.x, self.y, self.widget.layer()))]
        return drawn


class DiscreteWidget(ElementWidget):
    model: DiscreteBase
    face_class = DiscreteFace
    face: DiscreteFace

    def __init__(self, model: DiscreteBase, images: Images, parent: QWidget | None = None) -> None:
        super().__init__(model, images, parent)
        has_images = model.ImageFalse >= 0 or model.ImageTrue >= 0
        self.has_lamp = not isinstance(model, DiscreteColorLabel) and not has_images
        if model.Enabled and model.Cursor == "Default":
            self.setCursor(Qt.CursorShape.PointingHandCursor)
        self.setToolTip(f"{model.Name}: {model.InAddr}" + (QCoreApplication.translate(
            "DiscreteWidget", " (click to toggle)") if model.Enabled else ""))

    def back_color(self) -> QColor | None:
        if isinstance(self.model, DiscreteColorLabel):
            return theme.qcolor(self.model.back_color, theme.PANEL)
        return super().back_color()

    def covers(self) -> bool:
        m = self.model
        if not isinstance(m, DiscreteColorLabel):
            return super().covers()
        backs = (m.BackColor, m.BackColorFalse or m.BackColor, m.BackColorTrue or m.BackColor)
        return all(theme.qcolor(back, theme.PANEL).alpha() == 255 for back in backs)

    def fore_color(self) -> QColor:
        if isinstance(self.model, DiscreteColorLabel):
            return theme.qcolor(self.model.fore_color, theme.TEXT)
        return super().fore_color()

    def style_props(self) -> tuple[str, ...]:
        if isinstance(self.model, DiscreteColorLabel):
            return (*STYLE, "BackColorFalse", "BackColorTrue", "ForeColorFalse", "ForeColorTrue")
        return STYLE

    def look(self) -> tuple[object, ...]:
        m = self.model
        # image numbers index the form's own list: the files themselves tell two forms apart
        return (*super().look(), m.TextFalse, m.TextTrue, m.ImageFalse, m.ImageTrue, m.Enabled,
                tuple(self.images.files))

    def layer_key(self) -> Hashable:
        m = self.model
        return m.value, m.indicating, m.image, m.text, m.clickable, self.face.pressed

    def paint_layer(self, p: QPainter, r: QRectF) -> None:
        if not self.model.Enabled:
            super().paint_layer(p, r)
            return
        r = r.adjusted(1, 1, -1, -1)
        base = self.back_color() or theme.PANEL
        if self.face.pressed:
            top, bottom = base.darker(112), base.darker(104)
        else:
            top, bottom = base.lighter(108), base.darker(108)
        grad = QLinearGradient(r.topLeft(), r.bottomLeft())
        grad.setColorAt(0, top)
        grad.setColorAt(1, bottom)
        p.setPen(QPen(theme.BORDER.darker(115) if self.model.clickable else theme.BORDER, 1))
        p.setBrush(grad)
        p.drawRoundedRect(r, 4, 4)
        if not self.face.pressed:
            p.setPen(QPen(QColor(255, 255, 255, 160), 1))
            p.drawLine(r.left() + 4, r.top() + 1.5, r.right() - 4, r.top() + 1.5)
        self.paint_static(p, r.adjusted(3, 2, -3, -2).translated(0, 1 if self.face.pressed else 0))

    def paint_static(self, p: QPainter, r: QRectF) -> None:
        m = self.model
        if self.has_lamp:
            d = min(r.height() * 0.55, 18.0)
            lamp = QRectF(r.left() + 6, r.center().y() - d / 2, d, d)
            on = bool(m.value) and m.indicating
            p.setPen(QPen(theme.ON.darker(140) if on else theme.BORDER, 1))
            p.setBrush(theme.ON if on else theme.OFF.lighter(125))
            p.drawEllipse(lamp)
            if on:
                p.setPen(Qt.PenStyle.NoPen)
                p.setBrush(QColor(255, 255, 255, 110))
                p.drawEllipse(QRectF(lamp.left() + d * 0.22, lamp.top() + d * 0.15, d * 0.35, d * 0.3))
            r = r.adjusted(d + 12, 0, 0, 0)
        pix = self.images.index(m.image)
        text = m.text
        if pix is not None:
            box = QRectF(r.left(), r.top(), r.height(), r.height()) if text else r
            draw_pixmap(p, pix, box.adjusted(1, 1, -1, -1), "Zoom")
            if text:
                r = r.adjusted(r.height() + 4, 0, 0, 0)
        if text:
            p.setFont(theme.qfont(m.Font, bold=m.Enabled))
            p.setPen(self.fore_color() if m.value is not None else theme.TEXT_DIM)
            p.drawText(r.adjusted(4, 0, -4, 0), theme.alignment(m.TextAlign) | theme.WRAP,
                       text)
        elif not m.indicating:  # switched off by its EnableAddr: say so, not an empty box
            p.setFont(theme.qfont(m.Font))
            p.setPen(theme.TEXT_DIM)
            p.drawText(r, Qt.AlignmentFlag.AlignCenter, QCoreApplication.translate("DiscreteWidget",
                                                                                  "(indication off)"))

    def mousePressEvent(self, event: QMouseEvent) -> None:
        if event.button() == Qt.MouseButton.LeftButton and self.model.clickable:
            self.face.pressed = True
            self.sync()

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        if not self.face.pressed:
            return
        self.sync()
        if self.rect().contains(event.position().toPoint()):
            self.model.click()
