"""What a form trend draws under its curves: background, grid, time and value axes, limit lines.

A trend's axes change only when their labels do: live, the time axis counts seconds before now
("-10 s"), a scale that stays while the curves move under it; paused, it shows clock times, which
change as the operator pans. So the axes are drawn once into a pixmap (`Axes.pixmap`), kept while
the labels, the size and the range stay, and a redraw of the trend is one copy of it and the
curves: the once-a-second stall of a form full of trends came from laying out and painting these
axes at every redraw (issue 28). Everything is laid out from the font's metrics, so no label is
cut: the value axis is as wide as its widest label, the time labels that do not fit are left out.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

from PySide6.QtCore import QCoreApplication, QPointF, QRectF, Qt
from PySide6.QtGui import QColor, QFontMetrics, QPainter, QPen, QPixmap

from hmi_forms.elements import formats
from hmi_forms.widgets import theme

# seconds between the time axis's labels: the first that leaves LABEL_GAP px per label
STEPS = (1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600, 7200, 10800, 21600, 43200, 86400)
LABEL_GAP = 64
TICK_PX = 12  # the axes' labels: an operator reads them from a step back
TICK_LEN = 4  # the tick marks, inside the plot
GRID_ALPHA = 64


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


def value_ticks(lo: float, hi: float, pixels: float, gap: float) -> list[tuple[float, str]]:
    """Round values in [lo, hi] (1, 2, 2.5 or 5 times a power of ten apart), at least `gap` px
    apart, with their labels in as many decimals as the step needs."""
    span = hi - lo
    if not span > 0 or not math.isfinite(span):
        return []
    raw = span / max(1, int(pixels // gap))
    power = 10 ** math.floor(math.log10(raw))
    step = next(m * power for m in (1, 2, 2.5, 5, 10) if m * power >= raw * (1 - 1e-9))
    decimals = max(0, -math.floor(math.log10(step) + 1e-9) + (1 if step / power == 2.5 else 0))
    first = math.ceil(lo / step - 1e-9)
    return [(k * step, f"{k * step:.{decimals}f}") for k in range(first, math.floor(hi / step + 1e-9) + 1)]


@dataclass(frozen=True)
class Scale:
    """What the axes show: the times t0..t1 (live: seconds before t1), the values lo..hi."""

    t0: float
    t1: float
    lo: float
    hi: float
    live: bool


class Axes:
    """The layout and the cached picture of one trend's axes, for one size and one scale."""

    def __init__(self, back: QColor, values: list[tuple[float, str]] | None, unit: str,
                 limits: list[tuple[float, QColor]]) -> None:
        """`values`: fixed value ticks (a bit trend's 0 and 1), or None to choose them by height."""
        self.back, self.fixed, self.unit, self.limits = back, values, unit, limits
        self.font = theme.sized_font(TICK_PX)
        self.metrics = QFontMetrics(self.font)
        self.key: tuple[object, ...] = ()
        self.pixmap = QPixmap()
        self.plot = QRectF()  # where the curves go
        self.labels: list[tuple[str, QRectF]] = []  # the texts drawn, each where it is

    def value_ticks(self, lo: float, hi: float, height: float) -> list[tuple[float, str]]:
        if self.fixed is not None:
            return self.fixed
        return value_ticks(lo, hi, height, self.metrics.height() * 1.5)

    def layout(self, width: int, height: int, scale: Scale) -> None:
        """The plot's rectangle: the value axis as wide as its labels (and the unit under them),
        the time axis as high as one line."""
        line = self.metrics.height()
        plot_h = max(1, height - line - 2)
        texts = [text for _, text in self.value_ticks(scale.lo, scale.hi, plot_h)] + [self.unit]
        left = max(self.metrics.horizontalAdvance(t) for t in texts) + 6
        self.plot = QRectF(left, 0, max(1, width - left - 1), plot_h)

    def update(self, width: int, height: int, ratio: float, scale: Scale) -> bool:
        """Draw the axes anew if what they show changed; True if they were."""
        key = (width, height, ratio, scale if not scale.live else (scale.t1 - scale.t0, scale.lo, scale.hi))
        if key == self.key:
            return False
        self.key = key
        self.layout(width, height, scale)
        pixmap = QPixmap(max(1, round(width * ratio)), max(1, round(height * ratio)))
        pixmap.setDevicePixelRatio(ratio)
        pixmap.fill(self.back)
        p = QPainter(pixmap)
        try:
            self._draw(p, width, height, scale)
        finally:
            p.end()
        self.pixmap = pixmap
        return True

    def y_of(self, v: float, scale: Scale) -> float:
        r = self.plot
        return r.bottom() - (v - scale.lo) * r.height() / (scale.hi - scale.lo)

    def _draw(self, p: QPainter, width: int, height: int, scale: Scale) -> None:
        r, m = self.plot, self.metrics
        grid, line = QColor(theme.BORDER), m.height()
        grid.setAlpha(GRID_ALPHA)
        p.setFont(self.font)
        self.labels = []

        def text_at(left: float, top: float, text: str) -> None:
            self.labels.append((text, QRectF(left, top, m.horizontalAdvance(text), line)))
            p.drawText(QPointF(left, top + m.ascent()), text)
        # the value axis: grid, ticks and labels, right-aligned against the axis, never cut
        for v, text in self.value_ticks(scale.lo, scale.hi, r.height()):
            y = round(self.y_of(v, scale)) + 0.5
            p.setPen(grid)
            p.drawLine(QPointF(r.left(), y), QPointF(r.right(), y))
            p.setPen(theme.BORDER)
            p.drawLine(QPointF(r.left(), y), QPointF(r.left() + TICK_LEN, y))
            top = min(max(y - line / 2, 0), r.bottom() - line / 2)
            p.setPen(theme.TEXT_DIM)
            text_at(r.left() - 4 - m.horizontalAdvance(text), top, text)
        if self.unit:
            text_at(r.left() - 4 - m.horizontalAdvance(self.unit), r.bottom() + 1, self.unit)
        # the time axis: seconds before now (live) or clock times, each label centred on its tick
        per_second = r.width() / max(scale.t1 - scale.t0, 1e-9)
        if scale.live:
            span = scale.t1 - scale.t0
            step, ticks = round_ticks(-span, 0.0, r.width())
            places = [(r.right() + x * per_second, ago_label(x, step)) for x in ticks]
        else:
            zone = time.localtime(scale.t0).tm_gmtoff if abs(scale.t0) < 1e11 else 0
            step, ticks = round_ticks(scale.t0, scale.t1, r.width(), zone)
            places = [(r.left() + (t - scale.t0) * per_second, clock_label(t, step)) for t in ticks]
        for x, text in places:
            x = round(x) + 0.5
            p.setPen(grid)
            p.drawLine(QPointF(x, r.top()), QPointF(x, r.bottom()))
            p.setPen(theme.BORDER)
            p.drawLine(QPointF(x, r.bottom() - TICK_LEN), QPointF(x, r.bottom()))
            w = m.horizontalAdvance(text)
            left = min(x - w / 2, width - w - 1)  # the newest label (now) ends at the right end
            if left >= r.left():
                p.setPen(theme.TEXT_DIM)
                text_at(left, r.bottom() + 1, text)
        # the limits, dashed in their zone's colour
        for limit, color in self.limits:
            if scale.lo <= limit <= scale.hi:
                y = round(self.y_of(limit, scale)) + 0.5
                p.setPen(QPen(color, 1, Qt.PenStyle.DashLine))
                p.drawLine(QPointF(r.left(), y), QPointF(r.right(), y))
        p.setPen(theme.BORDER)
        p.drawLine(QPointF(r.left() + 0.5, r.top()), QPointF(r.left() + 0.5, r.bottom() + 0.5))
        p.drawLine(QPointF(r.left(), r.bottom() + 0.5), QPointF(r.right(), r.bottom() + 0.5))
