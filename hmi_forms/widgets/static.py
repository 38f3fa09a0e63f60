"""Widgets that only paint: static text and picture, date and time, and the sync generators."""

from __future__ import annotations

from collections.abc import Hashable

from PySide6.QtCore import QCoreApplication, QRectF, Qt
from PySide6.QtGui import QColor, QPainter, QPen

from hmi_forms.elements.static import DateTime, StaticPicture, StaticText
from hmi_forms.elements.sync import SyncGenerator, SyncTimer
from hmi_forms.widgets import theme
from hmi_forms.widgets.base import ElementWidget, draw_pixmap


class StaticTextWidget(ElementWidget):
    model: StaticText
    default_back = None

    def look(self) -> tuple[object, ...]:
        return (*super().look(), self.model.Text)

    def paint_static(self, p: QPainter, r: QRectF) -> None:
        p.setFont(theme.qfont(self.model.Font, 11))
        p.setPen(self.fore_color())
        p.drawText(r.adjusted(4, 2, -4, -2), theme.alignment(self.model.TextAlign) | theme.WRAP,
                   self.model.Text)


class StaticPictureWidget(ElementWidget):
    model: StaticPicture
    default_back = None

    def look(self) -> tuple[object, ...]:
        return (*super().look(), self.model.Image, self.model.SizeMode)

    def paint_static(self, p: QPainter, r: QRectF) -> None:
        if self.model.Image is not None:
            p.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
            draw_pixmap(p, self.images.get(self.model.Image), r, self.model.SizeMode,
                        theme.alignment(self.model.ImageAlign))


class DateTimeWidget(ElementWidget):
    model: DateTime

    def paint_dynamic(self, p: QPainter, r: QRectF) -> None:
        m = self.model
        lines = 1 + m.ShowDate + m.ShowUptime
        big = min(r.height() / (lines * 0.75 + 0.6), r.width() / 5.2)
        fg = self.fore_color()
        p.setPen(fg)
        p.setFont(theme.sized_font(big, bold=True, family=theme.MONO))
        clock_h = big * 1.25
        top = r.top() + (r.height() - clock_h - (lines - 1) * big * 0.75) / 2
        p.drawText(QRectF(r.left(), top, r.width(), clock_h), Qt.AlignmentFlag.AlignCenter,
                   m.clock or "--.--.--")
        p.setFont(theme.sized_font(big * 0.5))
        p.setPen(theme.TEXT_DIM if m.ForeColor is None else fg)
        y = top + clock_h
        if m.ShowDate:
            p.drawText(QRectF(r.left(), y, r.width(), big * 0.75), Qt.AlignmentFlag.AlignCenter, m.date)
            y += big * 0.75
        if m.ShowUptime:
            p.drawText(QRectF(r.left(), y, r.width(), big * 0.75), Qt.AlignmentFlag.AlignCenter,
                       QCoreApplication.translate("DateTimeWidget", "since start {0}").format(m.uptime))


class SyncWidget(ElementWidget):
    """A generator's state at a glance: its pair (period, phase), enable, and the output pulse."""

    model: SyncGenerator

    def look(self) -> tuple[object, ...]:
        m = self.model
        return (*super().look(), m.Name, m.Period0, m.Phase0, m.Period1, m.Phase1, type(m))

    def layer_key(self) -> Hashable:
        return self.model.pair, self.model.output, self.model.enabled

    def paint_static(self, p: QPainter, r: QRectF) -> None:
        m = self.model
        h = min(r.height() / 3, 22.0)
        p.setFont(theme.sized_font(h * 0.62, bold=True))
        p.setPen(theme.TEXT_DIM)
        p.drawText(QRectF(6, 2, r.width() - 12 - h, h), theme.LEFT,
                   m.Name)
        d = h * 0.7
        lamp = QRectF(r.right() - d - 6, 2 + (h - d) / 2, d, d)
        p.setPen(QPen(theme.BORDER, 1))
        p.setBrush(theme.ON if m.output else theme.OFF.lighter(125))
        p.drawEllipse(lamp)
        p.setFont(theme.sized_font(h * 0.6, family=theme.MONO))
        pairs = ((m.Period0, m.Phase0), (m.Period1, m.Phase1))
        for i, (period, phase) in enumerate(pairs):
            row = QRectF(6, 2 + h * (i + 1), r.width() - 12, h)
            if i == m.pair:
                p.fillRect(row.adjusted(-2, 1, 2, -1), QColor("#dbe4f3"))
            p.setPen(theme.TEXT if i == m.pair else theme.TEXT_DIM)
            p.drawText(row, theme.LEFT,
                       QCoreApplication.translate("SyncWidget", "{0}: period {1}, phase {2}").format(
                           i, period, phase))
        if isinstance(m, SyncTimer) and not m.enabled:
            p.setPen(theme.TEXT_DIM)
            p.setFont(theme.sized_font(h * 0.55, bold=True))
            p.drawText(QRectF(6, 2, r.width() - 18 - d, h), theme.RIGHT,
                       QCoreApplication.translate("SyncWidget", "disabled"))
