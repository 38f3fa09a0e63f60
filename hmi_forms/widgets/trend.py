"""Form trends: the Graph element (a bit) and AnalogBase with Appearance "graph", drawn with QPainter.

A form redraws all its trends once a second, in the same tick and on the same time (FormView), so
two trends of one form never disagree about when something happened. Live, the time axis is a
fixed scale of seconds before now; paused, it shows clock times. The operator may pause the trends
(the button, or by dragging or wheeling in one: the form's trends follow together), pan and zoom
in time, read the value under the mouse, and scroll back into the archive's history, drawn lighter
behind the live samples.

Why not a pyqtgraph plot, as before: each of its redraws went through a graphics scene, a view
box, two axis items and a curve item in Python, and a form of 50 trends stalled the console for
two to three times what the same curves cost drawn by hand (issue 28). Here a redraw is what a
hand-drawn polyline costs and no more: the samples are copied once into a QPolygonF (through its
buffer, no point objects) in data coordinates (seconds, value), the painter's transform puts them
on the screen, and the axes are one cached pixmap (trend_axes.py) drawn anew only when their
labels change. Samples taken while the data were bad (NaN) break the line.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable

import numpy as np
from PySide6.QtCore import QCoreApplication, QPointF, QRect, QRectF, Qt
from PySide6.QtGui import QColor, QMouseEvent, QPainter, QPaintEvent, QPen, QPolygonF, QTransform, QWheelEvent
from PySide6.QtWidgets import QToolButton, QWidget
from shiboken6 import VoidPtr

from hmi_forms.elements import formats
from hmi_forms.elements.analog import AnalogBase
from hmi_forms.elements.graph import Graph
from hmi_forms.elements.props import Color
from hmi_forms.elements.trend import Trend
from hmi_forms.widgets import theme
from hmi_forms.widgets.base import Images, SelfPainted
from hmi_forms.widgets.trend_axes import Axes, Scale

REDRAW_INTERVAL = 1.0  # seconds between redraws of a form's plots (samples are kept every scan)
PAUSE, LIVE = "\u275a\u275a", "\u25b6"
ZOOM = 0.8  # the time shown after one notch of the wheel, as a share of what it was
SHORTEST, LONGEST = 1.0, 31 * 86400.0  # seconds a zoom may show


def _pen_color(color: Color | None) -> QColor:
    return theme.qcolor(color, theme.ACCENT)


def polygon(n: int) -> tuple[QPolygonF, np.ndarray]:
    """A polygon of n points and its points as an (n, 2) array over the same memory."""
    poly = QPolygonF()
    poly.resize(n)
    return poly, np.frombuffer(VoidPtr(poly.data(), n * 16, True), dtype=np.float64).reshape(n, 2)


def fill(xy: np.ndarray, t: np.ndarray, v: np.ndarray, steps: bool) -> None:
    """Write the samples (t, v) as points: `steps`, each value held until the next sample's time
    (2n - 1 points), else one point a sample."""
    if steps:
        xy[0::2, 0], xy[1::2, 0], xy[0::2, 1], xy[1::2, 1] = t, t[1:], v, v[:-1]
    else:
        xy[:, 0], xy[:, 1] = t, v


class Curve:
    """The polylines through a trend's samples, in data coordinates (seconds from the trend's
    base, value), broken where a sample is NaN. Without a gap it is one polygon, kept and written
    over at each redraw; `steps`: each value held until the next sample (a bit), else straight
    lines between samples."""

    def __init__(self, steps: bool) -> None:
        self.steps = steps
        self.lines: list[QPolygonF] = []
        self._kept: tuple[QPolygonF, np.ndarray] | None = None

    def set(self, t: np.ndarray, v: np.ndarray, gaps: bool) -> None:
        if not len(t):
            self.lines = []
        elif not gaps:
            n = 2 * len(t) - 1 if self.steps else len(t)
            if self._kept is None or len(self._kept[1]) != n:
                self._kept = polygon(n)
            fill(self._kept[1], t, v, self.steps)
            self.lines = [self._kept[0]]
        else:
            self.lines = [self._run(t, v, a, b) for a, b in runs(np.isnan(t) | np.isnan(v))]

    def _run(self, t: np.ndarray, v: np.ndarray, a: int, b: int) -> QPolygonF:
        """Samples a..b-1, all known: a bit's last value is held until the bad sample's time."""
        if not self.steps:
            poly, xy = polygon(b - a)
            fill(xy, t[a:b], v[a:b], False)
            return poly
        held = b < len(t) and not math.isnan(t[b])
        poly, xy = polygon(2 * (b - a) - 1 + held)
        fill(xy[: 2 * (b - a) - 1], t[a:b], v[a:b], True)
        if held:
            xy[-1] = (t[b], v[b - 1])
        return poly


def runs(bad: np.ndarray) -> list[tuple[int, int]]:
    """The runs [a, b) of samples that are not `bad`."""
    edges = np.flatnonzero(np.diff(np.concatenate(([1], bad.view(np.int8), [1]))))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


class TrendPlot(QWidget):
    """The plot area of a trend: the cached axes, the curves through the painter's transform, and
    the value under the mouse. Dragging pans and wheeling zooms in time (through `owner.moved`)."""

    def __init__(self, owner: TrendWidget) -> None:
        super().__init__(owner)
        self.owner = owner
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)
        self.setMouseTracking(True)
        self.mouse: QPointF | None = None  # where the mouse is, for the value under it
        self._drag: tuple[float, Scale] | None = None

    def paintEvent(self, _event: QPaintEvent) -> None:
        owner = self.owner
        p = QPainter(self)
        try:  # a painter left active after an error would crash Qt
            axes, scale = owner.axes, owner.scale
            axes.update(self.width(), self.height(), self.devicePixelRatioF(), scale)
            p.drawPixmap(0, 0, axes.pixmap)
            r = axes.plot
            p.setClipRect(r)
            sx = r.width() / max(scale.t1 - scale.t0, 1e-9)
            sy = -r.height() / (scale.hi - scale.lo)
            onto = QTransform(sx, 0, 0, sy, r.left() - (scale.t0 - (owner.base or 0.0)) * sx,
                              r.bottom() - scale.lo * sy)
            for pen, curve in ((owner.faded, owner.history), (owner.pen, owner.curve)):
                if curve.lines:
                    p.setPen(pen)
                    for dx, dy in owner.stamps:  # a wide line: a thin one at each pixel of its width
                        p.setTransform(onto * QTransform.fromTranslate(dx, dy) if dx or dy else onto)
                        for poly in curve.lines:
                            p.drawPolyline(poly)
            p.resetTransform()
            if self.mouse is not None and r.contains(self.mouse):
                self._cursor(p, r, scale)
        finally:
            p.end()

    def _cursor(self, p: QPainter, r: QRectF, scale: Scale) -> None:
        """The sample nearest to the mouse: a dotted line at it, its time and value beside."""
        found = self.owner.value_at(self.time_at(self.mouse.x()))
        if found is None:
            return
        t, y = found
        x = r.left() + (t - scale.t0) * r.width() / max(scale.t1 - scale.t0, 1e-9)
        p.setPen(QPen(theme.TEXT_DIM, 1, Qt.PenStyle.DotLine))
        p.drawLine(QPointF(x, r.top()), QPointF(x, r.bottom()))
        text = f"{formats.clock(t)}  {self.owner.show_value(y)}"
        m = self.owner.axes.metrics
        w, h = m.horizontalAdvance(text) + 8, m.height() + 2
        box = QRectF(x - w if x > r.center().x() else x, r.top(), w, h)
        p.fillRect(box, QColor(255, 255, 255, 220))
        p.setPen(theme.TEXT)
        p.setFont(self.owner.axes.font)
        p.drawText(box, Qt.AlignmentFlag.AlignCenter, text)

    def time_at(self, x: float) -> float:
        r, s = self.owner.axes.plot, self.owner.scale
        return s.t0 + (x - r.left()) * (s.t1 - s.t0) / max(r.width(), 1.0)

    def mousePressEvent(self, event: QMouseEvent) -> None:
        if event.button() != Qt.MouseButton.LeftButton:
            event.ignore()
            return
        self._drag = (event.position().x(), self.owner.scale)

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        self.mouse = event.position()
        if self._drag is not None:
            x, s = self._drag
            shift = (x - self.mouse.x()) * (s.t1 - s.t0) / max(self.owner.axes.plot.width(), 1.0)
            if shift:
                self.owner.moved(s.t0 + shift, s.t1 + shift)
        self.update()

    def mouseReleaseEvent(self, _event: QMouseEvent) -> None:
        self._drag = None

    def mouseDoubleClickEvent(self, event: QMouseEvent) -> None:
        event.ignore()  # the element's (a faceplate opens on it)

    def leaveEvent(self, _event: object) -> None:
        self.mouse = None
        self.update()

    def wheelEvent(self, event: QWheelEvent) -> None:
        """Zoom in time about the time under the mouse."""
        s = self.owner.scale
        factor = ZOOM ** (event.angleDelta().y() / 120)
        span = min(max((s.t1 - s.t0) * factor, SHORTEST), LONGEST)
        at = self.time_at(event.position().x())
        share = (at - s.t0) / max(s.t1 - s.t0, 1e-9)
        self.owner.moved(at - share * span, at + (1 - share) * span)


class TrendWidget(SelfPainted):
    model: Graph | AnalogBase

    def __init__(self, model: Graph | AnalogBase, images: Images, parent: QWidget | None = None) -> None:
        super().__init__(model, images, parent)
        self.trend: Trend = model.trend  # type: ignore[assignment]
        self.header = max(16, min(22, round(model.h * 0.14)))
        color = _pen_color(model.Colors)
        back = theme.qcolor(model.BackColor, QColor("#fff"))
        share = 0.43  # the history's colour: the pen's, this much over the background (opaque)
        faded = QColor.fromRgbF(*(share * c + (1 - share) * b for c, b in zip(
            color.getRgbF()[:3], back.getRgbF()[:3], strict=True)))
        self.pen, self.faded = QPen(color, 1), QPen(faded, 1)
        for pen in (self.pen, self.faded):
            pen.setCosmetic(True)  # one pixel wide whatever the transform
        # LineWidth px drawn as a thin line at each pixel of a LineWidth-square: Qt strokes a wide
        # line as a filled outline, 20-30 times the cost of a thin one (a 2 px trend took 9 ms)
        offsets = range(-((model.LineWidth - 1) // 2), model.LineWidth // 2 + 1)
        self.stamps = [(dx, dy) for dx in offsets for dy in offsets]
        if isinstance(model, Graph):
            self.lo, self.hi = -0.15, 1.15
            self.axes = Axes(back, [(0.0, "0"), (1.0, "1")], "", [])
        else:
            lo, hi = model.scaling.phy_range
            pad = (hi - lo) * 0.04 if hi > lo else 1.0
            self.lo, self.hi = lo - pad, hi + pad
            zones = ((model.PhyLow, theme.WARN), (model.PhyHigh, theme.ALARM))
            limits = [(limit, zone) for limit, zone in zones if limit is not None]
            self.axes = Axes(back, None, model.Units, limits)
        self.plot = TrendPlot(self)
        self.plot.setGeometry(1, self.header, model.w - 2, model.h - self.header - 1)
        self.pause_button = QToolButton(self)
        self.pause_button.setObjectName("trendPause")
        self.pause_button.setAutoRaise(True)
        self.pause_button.setGeometry(model.w - self.header - 2, 1, self.header, self.header - 2)
        self.pause_button.setText(PAUSE)
        self.shown = -1  # trend.count when last drawn
        self.base: float | None = None  # the time at x 0 of the curves' data: the first sample's
        self.span = self.trend.size * 0.1  # seconds of the live window, measured at each redraw
        self.scale = Scale(-self.span, 0.0, self.lo, self.hi, True)
        self.live = True
        self.set_live(True)
        self.stale_mark.raise_()
        self.curve, self.history = Curve(isinstance(model, Graph)), Curve(isinstance(model, Graph))
        self.hist_times = self.hist_values = np.empty(0)
        self.moved: Callable[[float, float], None] = self.show_window  # the form links its trends here
        self._header_shown: tuple[object, ...] = ()

    def sync(self) -> None:
        """A new sample: the plot waits for the form's redraw; the header is repainted if it changed."""
        shown = (self.layer_key(), getattr(self.model, "text", None), self.model.quality)
        if shown != self._header_shown:
            self._header_shown = shown
            super().sync()

    def changed_rect(self) -> QRect:
        return QRect(0, 0, self.width(), self.header)  # the plot is redrawn by the form

    def _base(self, t: np.ndarray) -> float:
        if self.base is None and len(t) and not math.isnan(t[0]):
            self.base = float(t[0])
        return self.base or 0.0

    def flush(self) -> None:
        """The samples taken since the last redraw into the curve (drawn at the next paint)."""
        if self.trend.count == self.shown:
            return
        t, y = self.trend.times(), self.trend.values()
        period = float(t[-1] - t[0]) / (len(t) - 1) if len(t) > 2 else math.nan
        if period > 0:  # the samples the element keeps, at their mean period (NaN: not known)
            self.span = self.trend.size * period
        self.curve.set(t - self._base(t), y, self.trend.gaps > 0)
        self.shown = self.trend.count
        self.plot.update()

    def show_window(self, t0: float, t1: float) -> None:
        """Show the times t0..t1 (the form shows the same on each of its trends)."""
        scale = Scale(t0, t1, self.lo, self.hi, self.live)
        if scale != self.scale:
            self.scale = scale
            self.plot.update()

    def window(self) -> tuple[float, float]:
        """The times shown."""
        return self.scale.t0, self.scale.t1

    def set_live(self, live: bool) -> None:
        """Live: the time axis counts seconds before now; paused: clock times."""
        self.live = live
        self.show_window(*self.window())
        self.pause_button.setText(PAUSE if live else LIVE)
        self.pause_button.setToolTip(
            QCoreApplication.translate("TrendWidget", "Pause (dragging or wheeling in the plot also pauses)")
            if live else QCoreApplication.translate("TrendWidget", "Back to live"))

    def set_history(self, times: np.ndarray, values: np.ndarray) -> None:
        """The archive's samples of this trend, drawn lighter behind the live ones."""
        self.hist_times, self.hist_values = times, values
        self.history.set(times - self._base(times), values, gaps=True)
        self.plot.update()

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

    def show_value(self, y: float) -> str:
        """A sample as the cursor tells it."""
        if math.isnan(y):
            return "---"
        if isinstance(self.model, Graph):
            return str(int(y))
        return f"{self.model.format(y)} {self.model.Units}".rstrip()

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
