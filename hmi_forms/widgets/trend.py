"""Trends with pyqtgraph: the Graph element (a bit) and AnalogBase with Appearance "graph".

Following docs/architecture.md section 9: the plot and its curves are created once per widget and
fed with `setData` (bare PlotCurveItems: PlotDataItem's per-call bookkeeping cost five times the
data itself); the y range is fixed (no autorange per frame) and the axes are cached as pixmaps.
The x axis is time: the form (FormView) redraws all its trends in the same tick, on the same
time, so two trends of one form never disagree about when something happened. Live, the axis is a
fixed scale of seconds before now (the curves move under it, the axis, grid and view never
change, so a redraw paints the curve alone: half the cost of the hand-drawn polylines of
bench/hmi.py, where a clock-time axis moving under every plot cost twice theirs, issue 28);
paused, it shows clock time. The operator may pause a trend (its button, or by dragging or wheeling in it: the
form's trends are linked and all pause), pan and zoom in time, read the value under the mouse,
and scroll back into the archive's history, drawn lighter behind the live samples.
"""

from __future__ import annotations

import math
import time
from collections.abc import Hashable

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QCoreApplication, QPointF, QRect, QRectF, Qt
from PySide6.QtGui import QColor, QFont, QFontMetrics, QPainter, QPen, QPixmap
from PySide6.QtWidgets import QGraphicsItem, QStyleOptionGraphicsItem, QToolButton, QWidget

from hmi_forms.elements import formats
from hmi_forms.elements.analog import AnalogBase
from hmi_forms.elements.graph import Graph
from hmi_forms.elements.props import Color
from hmi_forms.elements.trend import Trend
from hmi_forms.widgets import theme
from hmi_forms.widgets.base import Images, SelfPainted

REDRAW_INTERVAL = 1.0  # seconds between redraws of a form's plots (samples are kept every scan)
PAUSE, LIVE = "\u275a\u275a", "\u25b6"


def _pen_color(color: Color | None) -> QColor:
    return theme.qcolor(color, theme.ACCENT)


# seconds between the clock-time axis's labels: the first that leaves LABEL_GAP px per label
STEPS = (1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600, 7200, 10800, 21600, 43200, 86400)
LABEL_GAP = 64
TICK_PX = 12  # the axes' labels: an operator reads them from a step back
LABELS_KEPT = 4096  # label pixmaps of all trends of the process, started afresh when full
_labels: dict[tuple[str, str, int, float], QPixmap] = {}


def _label(text: str, font: QFont, color: QColor, ratio: float) -> QPixmap:
    """The pixmap of one axis label, shared by every trend that shows the same text."""
    key = (text, font.key(), color.rgba(), ratio)
    pixmap = _labels.get(key)
    if pixmap is None:
        if len(_labels) >= LABELS_KEPT:
            _labels.clear()
        metrics = QFontMetrics(font)
        pixmap = QPixmap(round(metrics.horizontalAdvance(text) * ratio) + 1, round(metrics.height() * ratio))
        pixmap.setDevicePixelRatio(ratio)
        pixmap.fill(Qt.GlobalColor.transparent)
        p = QPainter(pixmap)
        p.setFont(font)
        p.setPen(color)
        p.drawText(0, metrics.ascent(), text)
        p.end()
        _labels[key] = pixmap
    return pixmap


def round_ticks(x0: float, x1: float, pixels: float, offset: float = 0.0) -> tuple[int, list[float]]:
    """Round times in [x0, x1], multiples of a step from STEPS after `offset` is added (the zone's
    offset for clock times), at least LABEL_GAP px apart."""
    per_second = pixels / max(x1 - x0, 1e-9)
    step = next((s for s in STEPS if s * per_second >= LABEL_GAP), STEPS[-1])
    while step * per_second < LABEL_GAP:  # zoomed out past the longest step: multiples of it
        step *= 2
    first = math.ceil((x0 + offset) / step) * step - offset
    return step, [first + k * step for k in range(int((x1 - first) // step) + 1)]


def clock_label(t: float, step: int) -> str:
    if step >= 86400:
        return formats.date(t)
    return time.strftime(formats.TIME if step < 60 else "%H:%M", time.localtime(t))


def ago_label(x: float, step: int) -> str:
    """`x` seconds from now (0 or less) in the unit of `step`."""
    for unit, text in ((3600, "%1 h"), (60, "%1 min"), (1, "%1 s")):
        if step >= unit and step % unit == 0:
            return QCoreApplication.translate("TrendWidget", text).replace("%1", f"{x / unit:g}")
    return ""  # not reached: every step is a whole number of seconds


class KeptAxis(pg.AxisItem):
    """An axis that keeps its bounding rectangle until it or its view is resized or moved: Qt asks
    for it several times in every paint of the plot, and pyqtgraph maps it afresh each time
    (with the grid, the rectangle of the view), a fifth of the plot's paint."""

    _bounds: QRectF | None = None  # a class default: pyqtgraph resizes the axis in its __init__

    def boundingRect(self) -> QRectF:
        if self._bounds is None:
            self._bounds = super().boundingRect()
        return self._bounds

    def _forget(self) -> None:
        if self._bounds is not None:
            self.prepareGeometryChange()
            self._bounds = None

    def resizeEvent(self, ev: object = None) -> None:
        self._forget()
        super().resizeEvent(ev)

    def linkedViewChanged(self, view: object, newRange: object = None) -> None:
        self._forget()
        super().linkedViewChanged(view, newRange)

    def setGrid(self, grid: int | float | bool) -> None:
        self._forget()
        super().setGrid(grid)


class ClockAxis(KeptAxis):
    """The time axis under a trend, in seconds from `origin` (the view's x 0): live, the seconds
    before now ("-10 s"), which never change, so the axis and its grid are painted once and kept
    as a pixmap; paused, clock times. Ticks on round seconds (minutes, hours, days as zoomed),
    each label a pixmap shared by all trends of the process (pyqtgraph's DateAxisItem lays out
    every label at each change)."""

    def __init__(self, font: QFont) -> None:
        super().__init__(orientation="bottom")
        self.enableAutoSIPrefix(False)  # else every change of the range sets the axis's HTML label
        self.setHeight(QFontMetrics(font).height() + self.style["tickTextOffset"][1])
        self.setCacheMode(QGraphicsItem.CacheMode.DeviceCoordinateCache)
        self.origin = 0.0
        self.clock = False

    def place(self, origin: float, clock: bool) -> None:
        """Clock times from `origin`, or seconds before it: repainted only if its labels change."""
        if clock != self.clock or (clock and origin != self.origin):
            self.update()
        self.origin, self.clock = origin, clock

    def paint(self, p: QPainter, _opt: QStyleOptionGraphicsItem, _widget: QWidget | None = None) -> None:
        view = self.linkedView()
        if view is None:
            return
        bounds = self.mapRectFromParent(self.geometry())
        grid = self.grid is not False
        top = view.mapRectToItem(self, view.boundingRect()).top() if grid else bounds.top() - 4
        x0, x1 = self.range
        scale = bounds.width() / max(x1 - x0, 1e-9)
        if self.clock:
            start = x0 + self.origin
            zone = time.localtime(start).tm_gmtoff if abs(start) < 1e11 else 0
            step, ticks = round_ticks(start, x1 + self.origin, bounds.width(), zone)
            ticks = [t - self.origin for t in ticks]
        else:
            step, ticks = round_ticks(x0, x1, bounds.width())
        pen = QPen(self.pen())
        p.setPen(pen)
        p.drawLine(bounds.topLeft(), bounds.topRight())
        if grid:
            color = pen.color()
            color.setAlpha(self.grid)
            pen.setColor(color)
            p.setPen(pen)
        font, color = self.style["tickFont"], self.textPen().color()
        ratio = p.device().devicePixelRatioF() if p.device() is not None else 1.0
        y = bounds.top() + self.style["tickTextOffset"][1]
        for t in ticks:
            x = bounds.left() + (t - x0) * scale
            p.drawLine(QPointF(x, top), QPointF(x, bounds.top()))
            text = clock_label(t + self.origin, step) if self.clock else ago_label(t, step)
            label = _label(text, font, color, ratio)
            w = label.width() / ratio
            left = min(x - w / 2, bounds.right() - w)  # the newest label (now) ends at the right end
            if bounds.left() <= left:
                p.drawPixmap(QPointF(left, y), label)


class FixedCurve(pg.PlotCurveItem):
    """A curve whose extent is set from outside: pyqtgraph would otherwise measure the data (with
    pixel padding) after every setData, for nothing, since the view never rescales to it."""

    def __init__(self, extent: QRectF, **opts: object) -> None:
        super().__init__(**opts)
        self.extent = extent

    def set_extent(self, extent: QRectF) -> None:
        if extent != self.extent:
            self.prepareGeometryChange()
            self.extent = extent

    def boundingRect(self) -> QRectF:
        return self.extent


class TrendWidget(SelfPainted):
    model: Graph | AnalogBase

    def __init__(self, model: Graph | AnalogBase, images: Images, parent: QWidget | None = None) -> None:
        super().__init__(model, images, parent)
        self.trend: Trend = model.trend  # type: ignore[assignment]
        self.header = max(16, min(22, round(model.h * 0.14)))
        axes = {"bottom": ClockAxis(theme.sized_font(TICK_PX)), "left": KeptAxis(orientation="left")}
        plot = pg.PlotWidget(self, background=theme.qcolor(model.BackColor, QColor("#fff")), axisItems=axes)
        self.axis: ClockAxis = plot.getPlotItem().getAxis("bottom")
        plot.setGeometry(1, self.header, model.w - 2, model.h - self.header - 1)
        plot.setFrameShape(plot.Shape.NoFrame)
        item = plot.getPlotItem()
        item.setMouseEnabled(x=True, y=False)  # pan and zoom in time; the y range is the scale's
        item.setMenuEnabled(False)
        item.hideButtons()
        item.showGrid(x=True, y=isinstance(model, AnalogBase), alpha=0.25)
        tick_font = theme.sized_font(TICK_PX)
        for name in ("left", "bottom"):
            axis = item.getAxis(name)
            axis.setPen(pg.mkPen(theme.BORDER))
            axis.setTextPen(pg.mkPen(theme.TEXT_DIM))
            axis.setStyle(tickFont=tick_font, tickLength=-4)
        color = _pen_color(model.Colors)
        pen = pg.mkPen(color, width=model.LineWidth)
        faded = QColor(color)
        faded.setAlpha(110)
        if isinstance(model, Graph):
            self.lo, self.hi = -0.15, 1.15
            item.setYRange(self.lo, self.hi, padding=0)
            item.getAxis("left").setTicks([[(0, "0"), (1, "1")]])
            item.getAxis("left").setWidth(18)
            step = {"stepMode": "left"}
        else:
            self.lo, self.hi = model.scaling.phy_range
            item.setYRange(self.lo, self.hi, padding=0.04)
            item.getAxis("left").setWidth(38)
            for limit, zone in ((model.PhyLow, theme.WARN), (model.PhyHigh, theme.ALARM)):
                if limit is not None:
                    dash = pg.mkPen(zone, style=Qt.PenStyle.DashLine)
                    item.addItem(pg.InfiniteLine(limit, angle=0, pen=dash))
            step = {}
        self.history = FixedCurve(QRectF(), pen=pg.mkPen(faded, width=model.LineWidth), connect="finite",
                                  **step)
        self.curve = FixedCurve(QRectF(), pen=pen, connect="finite", **step)
        item.addItem(self.history)
        item.addItem(self.curve)
        self.cursor = pg.InfiniteLine(angle=90, pen=pg.mkPen(theme.TEXT_DIM, style=Qt.PenStyle.DotLine))
        self.cursor_label = pg.TextItem(color=theme.TEXT, fill=pg.mkBrush(255, 255, 255, 220), anchor=(0, 0))
        for extra in (self.cursor, self.cursor_label):
            extra.setVisible(False)
            item.addItem(extra, ignoreBounds=True)
        item.getAxis("left").setCacheMode(QGraphicsItem.CacheMode.DeviceCoordinateCache)
        plot.scene().sigMouseMoved.connect(self._mouse_moved)
        self.plot = plot
        self.view_box = item.getViewBox()
        self.pause_button = QToolButton(self)
        self.pause_button.setObjectName("trendPause")
        self.pause_button.setAutoRaise(True)
        self.pause_button.setGeometry(model.w - self.header - 2, 1, self.header, self.header - 2)
        self.pause_button.setText(PAUSE)
        self.set_live(True)
        self.stale_mark.raise_()
        self.shown = -1  # trend.count when last drawn
        self.origin = 0.0  # the time at the view's x 0
        self._drawn_at = 0.0  # the origin of the live curve's data
        self.history.setVisible(False)
        self.span = self.trend.size * 0.1  # seconds of the live window, measured at each redraw
        self.hist_times = self.hist_values = np.empty(0)
        self._header_shown: tuple[object, ...] = ()

    def sync(self) -> None:
        """A new sample: the plot waits for the form's redraw; the header is repainted if it changed."""
        shown = (self.layer_key(), getattr(self.model, "text", None), self.model.quality)
        if shown != self._header_shown:
            self._header_shown = shown
            super().sync()

    def changed_rect(self) -> QRect:
        return QRect(0, 0, self.width(), self.header)  # the plot is redrawn by the form

    def flush(self) -> None:
        if self.trend.count == self.shown and self.origin == self._drawn_at:
            return
        t, y = self.trend.times(), self.trend.values()
        known = t[~np.isnan(t)]
        if len(known) > 2:  # the samples the element keeps, at their mean period
            self.span = self.trend.size * max(float(known[-1] - known[0]) / (len(known) - 1), 0.001)
        if len(t):
            x = t - self.origin
            self.curve.setData(x, y)
            self.curve.set_extent(QRectF(x[0], self.lo, max(x[-1] - x[0], 1e-3), self.hi - self.lo))
        self.shown, self._drawn_at = self.trend.count, self.origin

    def place(self, origin: float, live: bool) -> None:
        """Put time `origin` at the view's x 0: the curves move (at the next flush), the view does
        not (live, the axis says seconds before it; paused, the clock times)."""
        if origin != self.origin:
            self.origin = origin
            if self.history.isVisible():  # long: moved, not set again (the live samples are, at flush)
                self.history.setPos(-origin, 0)
        self.axis.place(origin, not live)

    def show_window(self, t0: float, t1: float) -> None:
        """Show the times t0..t1 (the view of each trend linked to this one follows)."""
        self.view_box.setXRange(t0 - self.origin, t1 - self.origin, padding=0)

    def window(self) -> tuple[float, float]:
        """The times shown."""
        x0, x1 = self.view_box.viewRange()[0]
        return x0 + self.origin, x1 + self.origin

    def set_live(self, live: bool) -> None:
        self.pause_button.setText(PAUSE if live else LIVE)
        self.pause_button.setToolTip(
            QCoreApplication.translate("TrendWidget", "Pause (dragging or wheeling in the plot also pauses)")
            if live else QCoreApplication.translate("TrendWidget", "Back to live"))

    def set_history(self, times: np.ndarray, values: np.ndarray) -> None:
        """The archive's samples of this trend, drawn lighter behind the live ones."""
        self.hist_times, self.hist_values = times, values
        self.history.setData(times, values)
        self.history.setPos(-self.origin, 0)
        self.history.setVisible(len(times) > 0)
        if len(times):
            self.history.set_extent(QRectF(times[0], self.lo, max(times[-1] - times[0], 1e-3),
                                           self.hi - self.lo))

    def value_at(self, x: float) -> tuple[float, float] | None:
        """The sample nearest to time `x`, live or from the history: (time, value)."""
        best: tuple[float, float] | None = None
        for t, y in ((self.trend.times(), self.trend.values()), (self.hist_times, self.hist_values)):
            if not len(t):
                continue
            i = int(np.clip(np.searchsorted(t, x), 1, len(t) - 1)) if len(t) > 1 else 0
            j = i - 1 if len(t) > 1 and abs(t[i - 1] - x) < abs(t[i] - x) else i
            if not math.isnan(t[j]) and (best is None or abs(t[j] - x) < abs(best[0] - x)):
                best = (float(t[j]), float(y[j]))
        return best

    def _mouse_moved(self, pos: QPointF) -> None:
        inside = self.view_box.sceneBoundingRect().contains(pos)
        found = self.value_at(self.view_box.mapSceneToView(pos).x() + self.origin) if inside else None
        self.cursor.setVisible(found is not None)
        self.cursor_label.setVisible(found is not None)
        if found is None:
            return
        t, y = found
        value = "---" if math.isnan(y) else (str(int(y)) if isinstance(self.model, Graph)
                                             else f"{self.model.format(y)} {self.model.Units}".rstrip())
        x = t - self.origin
        self.cursor.setPos(x)
        self.cursor_label.setText(f"{formats.clock(t)}  {value}")
        (x0, x1), (_, y1) = self.view_box.viewRange()
        self.cursor_label.setAnchor((1, 0) if x > (x0 + x1) / 2 else (0, 0))
        self.cursor_label.setPos(x, y1)

    def look(self) -> tuple[object, ...]:
        """The header's name, address and lamp colour are in the cached layer (paint_static)."""
        m = self.model
        return (*super().look(), type(m), m.Name, getattr(m, "Address", None), getattr(m, "Colors", None))

    def layer_key(self) -> Hashable:
        m = self.model
        return self.trend.last == 1 if isinstance(m, Graph) else m.zone

    def paint_static(self, p: QPainter, r: QRectF) -> None:
        m = self.model
        hr = QRectF(6, 0, r.width() - 12 - self.header, self.header)
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
            p.drawText(QRectF(6, 0, r.width() - 12 - self.header, self.header), theme.RIGHT,
                       (m.text or "---") + units)
