"""AnalogBase with Appearance "tank": a vessel whose liquid follows the value (an extension).

The demo's tank was a picture with a painted level, showing ~35 % forever while the level read
96 %; a mimic must not lie. The vessel is drawn once into the cached layer, the liquid and the
value over it; the liquid takes the zone's colour (amber low, red high) so a limit shows on the
picture too, and nothing is drawn while the value is unknown.
"""

from __future__ import annotations

from collections.abc import Hashable

from PySide6.QtCore import QRectF, Qt
from PySide6.QtGui import QColor, QPainter, QPainterPath, QPen

from hmi_forms.elements.analog import AnalogBase
from hmi_forms.widgets import theme
from hmi_forms.widgets.base import ElementWidget

LIQUID = QColor("#5b9bd5")


class TankWidget(ElementWidget):
    model: AnalogBase
    default_back = None  # the vessel stands on the form

    def vessel(self, r: QRectF) -> QRectF:
        label = max(12.0, min(18.0, r.height() * 0.14))
        return QRectF(r.left() + 6, r.top() + 10, r.width() - 12, r.height() - 16 - label)

    def layer_key(self) -> Hashable:
        return ()

    def paint_static(self, p: QPainter, r: QRectF) -> None:
        v = self.vessel(r)
        p.setPen(QPen(theme.BORDER.darker(150), 2.5))
        p.setBrush(theme.PANEL_DARK)
        p.drawRoundedRect(v, 10, 10)
        p.drawLine(v.center().x(), r.top(), v.center().x(), v.top())  # the inlet

    def paint_dynamic(self, p: QPainter, r: QRectF) -> None:
        m = self.model
        v = self.vessel(r).adjusted(2, 2, -2, -2)
        if m.hw is not None:
            level = v.height() * min(max(m.fraction, 0.0), 1.0)
            vessel = QPainterPath()
            vessel.addRoundedRect(v, 8, 8)
            liquid = QPainterPath()
            liquid.addRect(QRectF(v.left(), v.bottom() - level, v.width(), level))
            p.setPen(Qt.PenStyle.NoPen)
            p.setBrush(theme.ZONE_COLORS.get(m.zone or "", LIQUID))
            p.drawPath(vessel.intersected(liquid))
        units = f" {m.Units}" if m.Units else ""
        top = self.vessel(r).bottom() + 2
        label = QRectF(r.left(), top, r.width(), r.bottom() - top)
        p.setPen(theme.TEXT)
        p.setFont(theme.sized_font(label.height() * 0.8, bold=True, family=theme.MONO))
        p.drawText(label, Qt.AlignmentFlag.AlignCenter, (m.text or "---") + units)
