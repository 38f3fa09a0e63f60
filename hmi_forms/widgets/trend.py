"""Trends with pyqtgraph: the Graph element (a bit) and AnalogBase with Appearance "graph".

Following docs/architecture.md section 9: the plot and its curve are created once per widget and fed with
`setData` (a bare PlotCurveItem: PlotDataItem's per-call bookkeeping cost five times the data
itself); the axes have fixed ranges (no autorange per frame) and are cached as pixmaps; mouse
interaction, menus and buttons are off (an operator panel, not an analysis tool); and redraws are
throttled: the model samples every scan, the plot is redrawn when `flush_due` says its turn has
come. Plots are never destroyed while the form lives (the PySide6 PlotItem leak).
"""

from __future__ import annotations

from collections.abc import Hashable

import pyqtgraph as pg
from PySide6.QtCore import QRect, QRectF, Qt
from PySide6.QtGui import QColor, QPainter, QPen
from PySide6.QtWidgets import QGraphicsItem, QWidget

from hmi_forms.elements.analog import AnalogBase
from hmi_forms.elements.graph import Graph
from hmi_forms.elements.props import Color
from hmi_forms.elements.trend import Trend
from hmi_forms.widgets import theme
from hmi_forms.widgets.base import Images, SelfPainted

REDRAW_INTERVAL = 1.0  # seconds between redraws of one plot (samples are kept every scan)


def _pen_color(color: Color | None) -> QColor:
    return theme.qcolor(color, theme.ACCENT)


def extent(points: int, lo: float, hi: float) -> QRectF:
    """The data rectangle of a trend of `points` samples ending at x = 0, with room for the pen."""
    pad_x, pad_y = points * 0.05, (hi - lo) * 0.05
    return QRectF(-(points - 1) - pad_x, lo - pad_y, points - 1 + 2 * pad_x, hi - lo + 2 * pad_y)


class FixedCurve(pg.PlotCurveItem):
    """A curve whose extent is the plot's fixed range: pyqtgraph would otherwise measure the data
    (with pixel padding) after every setData, for nothing, since the view never rescales to it."""

    def __init__(self, extent: QRectF, **opts: object) -> None:
        super().__init__(**opts)
        self.extent = extent

    def boundingRect(self) -> QRectF:
        return self.extent


class TrendWidget(SelfPainted):
    model: Graph | AnalogBase

    def __init__(self, model: Graph | AnalogBase, images: Images, parent: QWidget | None = None) -> None:
        super().__init__(model, images, parent)
        self.trend: Trend = model.trend  # type: ignore[assignment]
        self.header = max(16, min(22, round(model.h * 0.14)))
        plot = pg.PlotWidget(self, background=theme.qcolor(model.BackColor, QColor("#ffffff")))
        plot.setGeometry(1, self.header, model.w - 2, model.h - self.header - 1)
        plot.setFrameShape(plot.Shape.NoFrame)
        item = plot.getPlotItem()
        item.setMouseEnabled(x=False, y=False)
        item.setMenuEnabled(False)
        item.hideButtons()
        item.showGrid(x=True, y=isinstance(model, AnalogBase), alpha=0.25)
        tick_font = theme.sized_font(10)
        for name in ("left", "bottom"):
            axis = item.getAxis(name)
            axis.setPen(pg.mkPen(theme.BORDER))
            axis.setTextPen(pg.mkPen(theme.TEXT_DIM))
            axis.setStyle(tickFont=tick_font, tickLength=-4)
        n = model.Elements
        item.setXRange(-(n - 1), 0, padding=0.02)
        item.getAxis("bottom").setTickSpacing(major=model.LabelInt, minor=max(1, model.LabelInt / 5))
        pen = pg.mkPen(_pen_color(model.Colors), width=model.LineWidth)
        if isinstance(model, Graph):
            lo, hi = -0.15, 1.15
            item.setYRange(lo, hi, padding=0)
            item.getAxis("left").setTicks([[(0, "0"), (1, "1")]])
            item.getAxis("left").setWidth(18)
            self.curve = FixedCurve(extent(n, lo, hi), pen=pen, stepMode="left", connect="finite")
        else:
            lo, hi = model.scaling.phy_range
            item.setYRange(lo, hi, padding=0.04)
            item.getAxis("left").setWidth(38)
            for limit, color in ((model.PhyLow, theme.WARN), (model.PhyHigh, theme.ALARM)):
                if limit is not None:
                    pen_limit = pg.mkPen(color, style=Qt.PenStyle.DashLine)
                    item.addItem(pg.InfiniteLine(limit, angle=0, pen=pen_limit))
            self.curve = FixedCurve(extent(n, lo, hi), pen=pen, connect="finite")
        item.addItem(self.curve)
        for name in ("left", "bottom"):  # fixed ranges: axes and grid are blitted, not re-stroked
            item.getAxis(name).setCacheMode(QGraphicsItem.CacheMode.DeviceCoordinateCache)
        self.plot = plot
        self.stale_mark.raise_()
        self.dirty = False
        self.shown = -1  # trend.count when last drawn
        self.next_flush = 0.0
        self._header_shown: tuple[object, ...] = ()

    def sync(self) -> None:
        """A new sample: the plot waits for its turn; the header is repainted only if it changed."""
        self.dirty = True
        shown = (self.layer_key(), getattr(self.model, "text", None), self.model.quality)
        if shown != self._header_shown:
            self._header_shown = shown
            super().sync()

    def changed_rect(self) -> QRect:
        return QRect(0, 0, self.width(), self.header)  # the plot is redrawn by flush_due

    def flush(self) -> None:
        if self.trend.count == self.shown:
            return
        y = self.trend.values()
        n = len(y)
        self.curve.setData(self.trend.x[:n] - (n - 1), y)
        self.shown = self.trend.count
        self.dirty = False

    def flush_due(self, now: float) -> None:
        """Redraw if there is news and this plot's turn has come (turns are staggered by the form)."""
        if self.dirty and now >= self.next_flush:
            self.flush()
            self.next_flush = max(self.next_flush + REDRAW_INTERVAL, now)

    def layer_key(self) -> Hashable:
        m = self.model
        return self.trend.last == 1 if isinstance(m, Graph) else m.zone

    def paint_static(self, p: QPainter, r: QRectF) -> None:
        m = self.model
        hr = QRectF(6, 0, r.width() - 12, self.header)
        p.setFont(theme.sized_font(self.header * 0.62, bold=True))
        p.setPen(theme.TEXT_DIM)
        p.drawText(hr, theme.LEFT, m.Name)
        if isinstance(m, Graph):
            d = self.header * 0.5
            lamp = QRectF(hr.right() - d, hr.center().y() - d / 2, d, d)
            p.setPen(QPen(theme.BORDER, 1))
            p.setBrush(_pen_color(m.Colors) if self.trend.last == 1 else theme.OFF.lighter(125))
            p.drawEllipse(lamp)
            p.setPen(theme.TEXT_DIM)
            p.setFont(theme.sized_font(self.header * 0.55))
            p.drawText(hr.adjusted(0, 0, -d - 6, 0), theme.RIGHT, str(m.Address))

    def paint_dynamic(self, p: QPainter, r: QRectF) -> None:
        m = self.model
        if isinstance(m, AnalogBase):
            units = f" {m.Units}" if m.Units else ""
            color = theme.ZONE_COLORS.get(m.zone or "")
            p.setPen(color.darker(115) if color is not None else theme.TEXT)
            p.setFont(theme.sized_font(self.header * 0.66, bold=True, family=theme.MONO))
            p.drawText(QRectF(6, 0, r.width() - 12, self.header), theme.RIGHT, (m.text or "---") + units)
