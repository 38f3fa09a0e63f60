"""The form's area on the canvas: its background colour and picture, and the grid dots."""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING, Any

from PySide6.QtCore import QPointF, QRectF
from PySide6.QtGui import QColor, QPainter, QPolygonF
from PySide6.QtWidgets import QGraphicsScene

from hmi_forms.elements import props as p
from hmi_forms.form import FORM_BACK
from hmi_forms.widgets.base import draw_pixmap

if TYPE_CHECKING:
    from app.gui.designer.design import Design

OUTSIDE = QColor("#9aa1ab")
GRID_DOT = QColor(0, 0, 0, 60)
MAX_DOTS = 60_000  # zoomed far out the grid would be a grey wash: leave it out


def _color(value: Any, default: QColor) -> QColor:
    try:
        return QColor(*p.color(value, None))  # type: ignore[arg-type]
    except p.PropError:
        return default


class FormScene(QGraphicsScene):
    """The form's area: its background colour and image, and the grid."""

    def __init__(self, design: Design) -> None:
        super().__init__(design)
        self.design = design

    def drawBackground(self, painter: QPainter, rect: QRectF) -> None:
        painter.fillRect(rect, OUTSIDE)
        d = self.design
        form = d.form_rect()
        settings = d.doc.settings
        painter.fillRect(form, _color(settings.get("BackColor"), QColor(*FORM_BACK)))
        image = settings.get("BackgroundImage")
        if isinstance(image, str) and (d.doc.path.parent / image).is_file():
            draw_pixmap(painter, d.images.get((d.doc.path.parent / image).resolve()), form, "Stretch")
        if d.grid_visible and d.grid >= 4:
            painter.setPen(GRID_DOT)
            visible = rect.intersected(form)
            g = d.grid
            dots = _dots(int(visible.left()) // g * g, int(visible.top()) // g * g, int(visible.right()),
                         int(visible.bottom()), g)
            if dots is not None:
                painter.drawPoints(dots)


@lru_cache(maxsize=16)
def _dots(x0: int, y0: int, right: int, bottom: int, g: int) -> QPolygonF | None:
    """The grid's dots in a rectangle (None: too many to draw), kept for the next repaint of the same
    area (an element's at each preview snapshot, the whole canvas when scrolled back): making
    thousands of points in Python was most of a repaint's time."""
    if ((right - x0) // g + 1) * ((bottom - y0) // g + 1) >= MAX_DOTS:
        return None
    return QPolygonF([QPointF(x, y) for x in range(x0, right + 1, g) for y in range(y0, bottom + 1, g)])
