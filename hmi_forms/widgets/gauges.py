"""AnalogBase gauges painted with QPainter: digital readout, horizontal bar, dial and semicircular dial.

The scale (face, zone bands, ticks, labels, name) does not change while the form runs, so it is
painted once per size into a pixmap; a tick then only draws the pointer and the readout, and a
gauge whose texts are unchanged and whose pointers moved less than a pixel is not repainted at
all. That keeps a form of a hundred dials well inside the update budget. Sizes of text and strokes follow
the element's size, so a gauge stays legible from a 90-pixel tile to a full panel.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable

from PySide6.QtCore import QCoreApplication, QPointF, QRect, QRectF, Qt
from PySide6.QtGui import (
    QColor,
    QFont,
    QFontMetricsF,
    QMouseEvent,
    QPainter,
    QPainterPath,
    QPen,
    QPolygonF,
    QResizeEvent,
    QTransform,
)
from PySide6.QtWidgets import QWidget

from hmi_forms.elements.analog import AnalogBase, Shown
from hmi_forms.elements.bank import WordBank
from hmi_forms.widgets import theme
from hmi_forms.widgets.base import FILL, PIX, STYLE, ElementWidget, Face, Images, Op
from hmi_forms.widgets.sprites import SPRITES, Ink, Sprite, TextSlot, blank, draw_text


def nice_step(span: float, max_ticks: int) -> float:
    raw = abs(span) / max(max_ticks, 1)
    mag = 10 ** math.floor(math.log10(raw)) if raw > 0 else 1.0
    for m in (1, 2, 2.5, 5, 10):
        if m * mag >= raw * 0.999:
            return m * mag
    return 10 * mag


def scale_ticks(lo: float, hi: float, max_major: int) -> tuple[list[float], list[float], int]:
    """Major and minor tick values in lo..hi, and the decimals their labels need."""
    step = nice_step(hi - lo, max_major)
    minor = step / (4 if str(step / 10 ** math.floor(math.log10(step)))[0] == "2" else 5)
    first = math.ceil(lo / step - 1e-9) * step
    majors = [first + i * step for i in range(int((hi - first) / step + 1e-9) + 1)]
    first_minor = math.ceil(lo / minor - 1e-9) * minor
    minors = [first_minor + i * minor for i in range(int((hi - first_minor) / minor + 1e-9) + 1)]
    decimals = max(0, -math.floor(math.log10(step) + 1e-9)) if step < 1 else 0
    if step == 2.5 * 10 ** math.floor(math.log10(step)) and step < 10:
        decimals += 1
    return majors, minors, decimals


SMALL_DIAL = 45.0  # radius in px below which a dial drops its labels and enlarges the readout
SPRITE_DIAL = 64.0  # radius in px up to which needles are cached pixmaps (larger: drawn each time)
PART_AREA = 150 * 150  # px²: from this size on, a change of text alone repaints only its box
SEMI_END_LABEL = 12.0  # degrees: a semidial's end labels stand this far above its baseline
HUB = QColor("#33393f")
WHITE = QColor("#ffffff")
# the value's colours by zone: in a readout box (dials, digital) and over the element (bars)
BOXED = {None: Ink(theme.TEXT, WHITE), "normal": Ink(theme.TEXT, WHITE), "low": Ink(theme.TEXT, theme.WARN),
         "high": Ink(WHITE, theme.ALARM)}
BARE = {None: Ink(theme.TEXT), "normal": Ink(theme.TEXT), "low": Ink(theme.WARN.darker(115)),
        "high": Ink(theme.ALARM.darker(115))}


class GaugeWidget(ElementWidget):
    """AnalogBase with Appearance digital, hbar, dial or semidial."""

    model: AnalogBase

    def __init__(self, model: AnalogBase, images: Images, parent: QWidget | None = None) -> None:
        super().__init__(model, images, parent)
        lo, hi = model.scaling.phy_range
        self.digits = max(len(model.format(lo)), len(model.format(hi)))
        self._laid_out = False  # the geometry below is for the current size (reset on resize)
        self._dial: tuple[QPointF, float, float, float] = (QPointF(), 0.0, 0.0, 0.0)
        self._box: tuple[QRectF, float] = (QRectF(), 0.0)
        self._digital: tuple[QRectF, float, float] = (QRectF(), 0.0, 0.0)
        self._needle = QPolygonF()  # pointing at 3 o'clock from the centre; the painter turns it
        self._travel = 0.0  # pixels the pointer (needle tip, bar end) travels over the whole scale
        self._units = f" {model.Units}" if model.Units else ""
        self._fill = QRect()  # the bar's fill at zero length
        self._track = QRectF()  # the bar's track
        self._value: TextSlot | None = None  # where the value text goes, drawn as a glyph run
        self._part: QRect | None = None  # what a new text alone repaints (None: the whole element)
        self._paint_value: Callable[[QPainter], None] = self._paint_needle  # by Appearance
        self._bar: tuple[int, int, int, float] = (0, 0, 0, 0.0)  # the fill's left, top, height and travel
        self._needles: dict[Hashable, Sprite] | None = None  # the needle by position (None: drawn each time)
        self._contained = True  # the dial lies inside the element (its sprites need no clip)
        self.setToolTip(QCoreApplication.translate("AnalogWidget", "{0}: word {1}, {2} … {3}{4}").format(
            model.Name, oct(model.InAddr or 0)[2:].rjust(5, "0"), model.format(lo), model.format(hi),
            self._units)
            + (QCoreApplication.translate("AnalogWidget", "; double-click resets the maximum")
               if model.KeepMaxValue else ""))

    # --- geometry shared by the static layer and the pointer ----------------------------------

    def _name_height(self) -> float:
        return max(15.5, min(18.0, self.height() * 0.11)) if self.model.Name else 0.0  # text >= 12 px

    def _layout(self) -> None:
        if not self._laid_out:
            self._laid_out = True
            self._dial = self._compute_dial_geometry()
            self._box = self._compute_readout_box()
            self._digital = self._compute_digital_geometry()
            appearance = self.model.Appearance
            dpr = self.devicePixelRatioF()
            bounds = QRectF(self.rect())  # the value and needle never reach past the element
            if appearance == "hbar":
                self._paint_value = self._paint_bar_value
                track = self._track = self._bar_geometry()
                self._travel = track.width()
                top = math.ceil(track.top() + 1)  # pixel-aligned: a fractional fill costs twice as much
                self._fill = QRect(math.ceil(track.left() + 1), top, 0, math.floor(track.bottom()) - top)
                self._bar = (self._fill.x(), top, self._fill.height(), track.width() - 1)
                nh = max(self._name_height(), self.height() * 0.28)
                font = self._bar_font(nh)
                box = QRectF(6, 2, self.width() - 12, nh + 2)
                # the pixmaps cover the widest value, not the name on the same line
                widest = QFontMetricsF(font).horizontalAdvance("0" * self.digits + self._units) + 6
                area = box.adjusted(-3, -3, 3, 3)
                area.setLeft(max(area.left(), area.right() - widest))
                self._value = TextSlot(box, font, theme.RIGHT, area, bounds)
            elif appearance == "digital":
                self._paint_value = self._paint_digital_value
                box, size, units_w = self._digital
                text = box.adjusted(6, 0, -6 - units_w, 0)  # the units keep 8 px clear on its right
                fill = QRectF(box.left() + 2, box.top() + 2, text.right() + 6 - box.left(), box.height() - 4)
                font = theme.sized_font(size, bold=True, family=theme.MONO)
                self._value = TextSlot(text, font, theme.RIGHT, fill, bounds)
            else:
                self._paint_value = self._paint_needle
                c, r, start, sweep = self._dial
                self._travel = abs(math.radians(sweep)) * r  # the maximum mark's outer corner
                self._needle = QPolygonF([QPointF(0.8 * r, 0), QPointF(0, 0.045 * r),
                                          QPointF(-0.12 * r, 0), QPointF(0, -0.045 * r)])
                box, size = self._box
                self._value = TextSlot(box, theme.sized_font(size, bold=True, family=theme.MONO),
                                       Qt.AlignmentFlag.AlignCenter, box.adjusted(2, 2, -2, -2), bounds)
                key = (c.toTuple(), r, start, sweep, self._travel, dpr)
                self._needles = SPRITES.family(key) if r <= SPRITE_DIAL else None
                # a dial squeezed below its least radius pokes out: its needle needs the clip (a
                # semidial's needle reaches below its centre only by its tail)
                below = r * 0.12 if sweep == -180.0 else r
                reach = QRectF(c.x() - r - 2, c.y() - r - 2, 2 * r + 4, r + below + 4)
                self._contained = bounds.contains(reach)
            # a new text alone repaints its box, in a large gauge: in a small one the pixels
            # saved are fewer than what cutting the form's repainted region into more
            # rectangles costs Qt
            part = self._value.rect
            area = self.width() * self.height()
            self._part = part if area >= PART_AREA and part.width() * part.height() * 4 < area else None

    def resizeEvent(self, event: QResizeEvent) -> None:
        self._laid_out = False
        super().resizeEvent(event)

    def style_props(self) -> tuple[str, ...]:
        return (*STYLE, "Name")  # the name is drawn in the layer

    def look(self) -> tuple[object, ...]:
        m = self.model
        return (*super().look(), m.Appearance, m.Units, m.scaling, m.Precision, m.PhyLow, m.PhyHigh)

    def restyle(self) -> None:
        super().restyle()
        self._laid_out = False

    def shown(self) -> tuple[object, ...]:
        """What the operator can see change: the texts, and the pointers to the nearest pixel."""
        self._layout()
        m = self.model
        travel = self._travel
        pointer = None if m.hw is None else round(m.fraction * travel)
        if m.maximum is None:
            peak: object = None
        elif travel:
            peak = round(m.scaling.fraction(m.maximum) * travel)
        else:
            peak = m.format(m.maximum)
        return m.text, pointer, peak, m.zone, m.quality

    def _dial_geometry(self) -> tuple[QPointF, float, float, float]:
        """Centre, radius, start angle and sweep (degrees, counter-clockwise from 3 o'clock)."""
        self._layout()
        return self._dial

    def _compute_dial_geometry(self) -> tuple[QPointF, float, float, float]:
        w, h = self.width(), self.height()
        top = self._name_height() + 4
        if self.model.Appearance == "semidial":
            readout = max(14.0, h * 0.16)
            r = max(10.0, min(w / 2 - 8, h - top - readout - 8))
            return QPointF(w / 2, top + r + 2), r, 180.0, -180.0
        r = max(10.0, min(w, h - top) / 2 - 4)
        return QPointF(w / 2, top + (h - top) / 2), r, 225.0, -270.0

    @staticmethod
    def _at(c: QPointF, r: float, deg: float) -> QPointF:
        a = math.radians(deg)
        return QPointF(c.x() + r * math.cos(a), c.y() - r * math.sin(a))

    def _bar_geometry(self) -> QRectF:
        h = self.height()
        top = max(self._name_height(), h * 0.28) + 6
        track_h = max(6.0, min(22.0, (h - top) * 0.35))
        inset = max(14.0, min(24.0, self.height() * 0.2))  # room for the end labels
        return QRectF(inset, top, self.width() - 2 * inset, track_h)

    # --- painting: the layer (name, scale, readout box) and the dynamic part --------------------

    def layer_key(self) -> Hashable:
        return self.model.zone  # the readout box is coloured by zone

    def paint_static(self, p: QPainter, r: QRectF) -> None:
        p.setRenderHint(QPainter.RenderHint.TextAntialiasing)
        appearance = self.model.Appearance
        if appearance == "digital":
            self._paint_digital_box(p, r)
            return
        self._paint_name(p)
        if appearance == "hbar":
            self._paint_bar_scale(p)
        else:
            self._paint_dial_scale(p)
            box, _ = self._readout_box()
            zone_color = theme.ZONE_COLORS.get(self.model.zone or "")
            p.setPen(QPen(theme.BORDER, 1))
            p.setBrush(zone_color if zone_color is not None else QColor("#ffffff"))
            p.drawRoundedRect(box, 3, 3)

    def paint_dynamic(self, p: QPainter, r: QRectF) -> None:
        self._layout()
        self._paint_value(p)

    def _paint_name(self, p: QPainter) -> None:
        nh = self._name_height()
        if not nh:
            return
        p.setFont(theme.sized_font(nh * 0.78, bold=True))
        p.setPen(theme.TEXT_DIM)
        align = theme.LEFT if self.model.Appearance == "hbar" else Qt.AlignmentFlag.AlignCenter
        p.drawText(QRectF(6, 2, self.width() - 12, nh + 2), align,
                   self.model.Name)

    def _zones(self) -> list[tuple[float, float, QColor]]:
        m = self.model
        lo, hi = m.scaling.PhyMin, m.scaling.PhyMax
        zones = []
        if m.PhyLow is not None:
            zones.append((m.scaling.fraction(lo), m.scaling.fraction(m.PhyLow), theme.WARN))
        if m.PhyHigh is not None:
            zones.append((m.scaling.fraction(m.PhyHigh), m.scaling.fraction(hi), theme.ALARM))
        return [(min(a, b), max(a, b), c) for a, b, c in zones]

    def _paint_dial_scale(self, p: QPainter) -> None:
        m = self.model
        c, r, start, sweep = self._dial_geometry()
        face = QRectF(c.x() - r, c.y() - r, 2 * r, 2 * r)
        p.setPen(QPen(theme.BORDER, max(1.0, r * 0.02)))
        p.setBrush(QColor("#fbfbfc"))
        if sweep == -180.0:
            path = QPainterPath()
            path.moveTo(c.x() - r, c.y() + r * 0.06)
            path.arcTo(face, 180, -180)
            path.lineTo(c.x() + r, c.y() + r * 0.06)
            path.closeSubpath()
            p.drawPath(path)
        else:
            p.drawEllipse(face)
        band = r * 0.07
        for f0, f1, color in self._zones():
            rr = r * 0.925
            p.setPen(QPen(color, band, Qt.PenStyle.SolidLine, Qt.PenCapStyle.FlatCap))
            p.setBrush(Qt.BrushStyle.NoBrush)
            p.drawArc(QRectF(c.x() - rr, c.y() - rr, 2 * rr, 2 * rr), round((start + sweep * f0) * 16),
                      round(sweep * (f1 - f0) * 16))
        lo, hi = m.scaling.phy_range
        small = r < SMALL_DIAL  # a tile: ticks only, the readout carries the number
        max_major = 4 if r < 45 else 6 if r < 90 else 10
        if sweep != -270.0:
            max_major = max(3, max_major - 1)
        majors, minors, decimals = scale_ticks(lo, hi, max_major)
        p.setPen(QPen(theme.TEXT, max(1.0, r * 0.012)))
        for v in [] if small else minors:
            a = start + sweep * m.scaling.fraction(v)
            p.drawLine(self._at(c, r * 0.88, a), self._at(c, r * 0.81, a))
        p.setPen(QPen(theme.TEXT, max(1.3, r * 0.025), Qt.PenStyle.SolidLine, Qt.PenCapStyle.FlatCap))
        font = theme.sized_font(max(8.0, r * 0.14))
        p.setFont(font)
        metrics = QFontMetricsF(font)
        # a semidial's end labels stand above its baseline, where the next ones were: it labels
        # every other major tick once there are more than five
        every = 2 if sweep == -180.0 and len(majors) > 5 else 1
        for i, v in enumerate(majors):
            a = start + sweep * m.scaling.fraction(v)
            p.drawLine(self._at(c, r * 0.88, a), self._at(c, r * 0.74, a))
            if small or i % every:
                continue
            # each label keeps the same gap to its tick whatever its width: a wide "-50" or "100"
            # at the ends of the scale moves inwards instead of running into the tick and the band
            text = f"{v:.{decimals}f}"
            w, h = metrics.horizontalAdvance(text), metrics.capHeight()
            if sweep == -180.0:  # the needle rests on the baseline at either end: labels sit above it
                a = min(max(a, SEMI_END_LABEL), 180.0 - SEMI_END_LABEL)
            rad = math.radians(a)
            reach = abs(math.cos(rad)) * w / 2 + abs(math.sin(rad)) * h / 2
            label_at = self._at(c, r * 0.68 - reach, a)
            lh = metrics.height()
            box = QRectF(label_at.x() - w / 2 - 2, label_at.y() - lh / 2, w + 4, lh)
            p.drawText(box, Qt.AlignmentFlag.AlignCenter, text)
        if m.Units and not small:
            p.setPen(theme.TEXT_DIM)
            p.setFont(theme.sized_font(max(8.0, r * 0.13)))
            if sweep == -270.0:
                p.drawText(QRectF(c.x() - r * 0.5, c.y() + r * 0.16, r, r * 0.18),
                           Qt.AlignmentFlag.AlignCenter, m.Units)
            else:  # right of the readout, under the baseline: no needle position covers it
                p.drawText(QRectF(c.x() + r * 0.5, c.y() + r * 0.1, r * 0.5, r * 0.3),
                           Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter, m.Units)

    def _paint_bar_scale(self, p: QPainter) -> None:
        m = self.model
        track = self._bar_geometry()
        p.setPen(QPen(theme.BORDER, 1))
        p.setBrush(QColor("#ffffff"))
        p.drawRect(track)
        for f0, f1, color in self._zones():
            x0, x1 = track.left() + f0 * track.width(), track.left() + f1 * track.width()
            p.fillRect(QRectF(x0, track.bottom() + 1, x1 - x0, 3), color)
        lo, hi = m.scaling.phy_range
        majors, minors, decimals = scale_ticks(lo, hi, max(2, int(track.width() / 55)))
        y = track.bottom() + 4
        tick_len = max(4.0, min(8.0, self.height() * 0.08))
        p.setPen(QPen(theme.TEXT, 1))
        for v in minors:
            x = track.left() + m.scaling.fraction(v) * track.width()
            p.drawLine(QPointF(x, y), QPointF(x, y + tick_len * 0.55))
        font_px = max(8.0, min(14.0, self.height() * 0.16))
        p.setFont(theme.sized_font(font_px))
        for v in majors:
            x = track.left() + m.scaling.fraction(v) * track.width()
            p.drawLine(QPointF(x, y), QPointF(x, y + tick_len))
            p.drawText(QRectF(x - 30, y + tick_len, 60, font_px * 1.4), Qt.AlignmentFlag.AlignHCenter,
                       f"{v:.{decimals}f}")

    def _readout_box(self) -> tuple[QRectF, float]:
        self._layout()
        return self._box

    def _compute_readout_box(self) -> tuple[QRectF, float]:
        c, r, _, sweep = self._dial
        if r < SMALL_DIAL:  # the number matters more than the face: a wide readout over the gap
            size = max(9.0, r * 0.36)
            return QRectF(c.x() - r * 0.8, c.y() + r * 0.38, r * 1.6, size * 1.35), size
        size = max(9.0, r * 0.2)
        if sweep == -270.0:  # in the gap at the bottom, clear of the end labels
            return QRectF(c.x() - r * 0.36, c.y() + r * 0.6, r * 0.72, size * 1.45), size
        top = c.y() + max(6.0, r * 0.1)  # below the centre, in the strip the layout keeps free
        height = min(size * 1.5, self.height() - top - 4)
        return QRectF(c.x() - r * 0.45, top, r * 0.9, height), height / 1.5

    def _paint_needle(self, p: QPainter) -> None:
        m = self.model
        c, r, start, sweep = self._dial
        if m.maximum is not None:
            a = start + sweep * m.scaling.fraction(m.maximum)
            tip, left, right = self._at(c, r * 0.9, a), self._at(c, r, a + 4), self._at(c, r, a - 4)
            p.setPen(Qt.PenStyle.NoPen)
            p.setBrush(theme.ALARM)
            p.drawPolygon(QPolygonF([tip, left, right]))
        assert self._value is not None
        self._value.draw(p, m.text or "---", BOXED[m.zone])
        if m.hw is None:
            return
        if self._needles is None:
            self._draw_needle(p, c, r, start + sweep * m.fraction)
            return
        p.drawPixmap(*self._needle_sprite(round(m.fraction * self._travel)))

    def _needle_sprite(self, pointer: int) -> Sprite:
        """The needle at `pointer`, the pixel its tip travels to (as `shown` tells a move)."""
        assert self._needles is not None
        sprite = self._needles.get(pointer)
        if sprite is None:
            c, r, start, sweep = self._dial
            sprite = SPRITES.put(self._needles, pointer,
                                 self._render_needle(c, r, start + sweep * pointer / self._travel))
        return sprite

    def _render_needle(self, c: QPointF, r: float, angle: float) -> Sprite:
        """The needle at `angle` in a pixmap just large enough for it (less to blend per tick)."""
        hub = r * 0.07
        turned = QTransform().translate(c.x(), c.y()).rotate(-angle).map(self._needle)
        box = turned.boundingRect().united(QRectF(c.x() - hub, c.y() - hub, 2 * hub, 2 * hub))
        at = box.adjusted(-1, -1, 1, 1).toAlignedRect()
        pix = blank(at.size(), self.devicePixelRatioF(), None)
        p = QPainter(pix)
        try:  # a painter left open on a pixmap crashes Qt when the pixmap goes
            p.setRenderHint(QPainter.RenderHint.Antialiasing)
            p.translate(-at.x(), -at.y())
            self._draw_needle(p, c, r, angle)
        finally:
            p.end()
        return at.x(), at.y(), pix

    def _draw_needle(self, p: QPainter, c: QPointF, r: float, angle: float) -> None:
        at = p.transform()
        p.translate(c)
        p.rotate(-angle)  # the needle is laid out pointing at 3 o'clock
        p.setPen(Qt.PenStyle.NoPen)  # filled only: a stroke would double the rasterising
        p.setBrush(theme.ACCENT)
        p.drawPolygon(self._needle)
        p.setTransform(at)
        p.setBrush(HUB)
        hub = r * 0.07
        p.drawEllipse(c, hub, hub)

    def _paint_bar_value(self, p: QPainter) -> None:
        m = self.model
        track = self._track
        zone_color = theme.ZONE_COLORS.get(m.zone or "")
        if m.hw is not None:
            fill = self._fill
            fill.setWidth(round((track.width() - 1) * m.fraction))
            p.fillRect(fill, zone_color or theme.ACCENT)
        if m.maximum is not None:
            x = track.left() + m.scaling.fraction(m.maximum) * track.width()
            p.setPen(QPen(theme.ALARM, 2))
            p.drawLine(QPointF(x, track.top() - 3), QPointF(x, track.bottom()))
        assert self._value is not None
        self._value.draw(p, (m.text or "---") + self._units, BARE[m.zone])

    @staticmethod
    def _bar_font(name_height: float) -> QFont:
        return theme.sized_font(max(10.0, name_height * 0.8), bold=True, family=theme.MONO)

    def _digital_geometry(self) -> tuple[QRectF, float, float]:
        self._layout()
        return self._digital

    def _compute_digital_geometry(self) -> tuple[QRectF, float, float]:
        """Readout box, value font size (fixed by the widest value of the range) and units width."""
        h = self.height()
        nh = self._name_height() if h >= 40 else 0.0
        box = QRectF(4, nh + 4, self.width() - 8, h - nh - 8)
        size = max(9.0, min(box.height() * 0.62, box.width() / (self.digits + 2) * 1.5))
        units_w = 0.0
        if self.model.Units:
            metrics = QFontMetricsF(theme.sized_font(size * 0.55))
            units_w = metrics.horizontalAdvance(self.model.Units) + 8
        return box, size, units_w

    def _paint_digital_box(self, p: QPainter, r: QRectF) -> None:
        m = self.model
        nh = self._name_height() if r.height() >= 40 else 0.0
        if nh:
            p.setFont(theme.sized_font(nh * 0.78, bold=True))
            p.setPen(theme.TEXT_DIM)
            p.drawText(QRectF(6, 2, r.width() - 12, nh + 2), theme.LEFT, m.Name)
        box, size, _ = self._digital_geometry()
        zone_color = theme.ZONE_COLORS.get(m.zone or "")
        p.setPen(QPen(theme.BORDER, 1))
        p.setBrush(zone_color if zone_color is not None else QColor("#ffffff"))
        p.drawRoundedRect(box, 3, 3)
        if m.Units:
            p.setFont(theme.sized_font(size * 0.55))
            p.setPen(QColor("#ffffff") if m.zone == "high" else theme.TEXT if zone_color else theme.TEXT_DIM)
            p.drawText(box.adjusted(0, 0, -6, -box.height() * 0.12),
                       Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignBottom, m.Units)

    def _paint_digital_value(self, p: QPainter) -> None:
        m = self.model
        box, size, _ = self._digital_geometry()
        assert self._value is not None
        ink = BOXED[m.zone]
        self._value.draw(p, m.text or "---", ink)
        if m.maximum is not None and box.height() > 30:
            fg = ink.fore
            p.setFont(theme.sized_font(max(8.0, size * 0.38)))
            p.setPen(fg if m.zone else theme.ALARM)
            p.drawText(box.adjusted(6, 2, 0, 0), Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignTop,
                       QCoreApplication.translate("AnalogWidget", "max {0}").format(m.format(m.maximum)))

    def mouseDoubleClickEvent(self, event: QMouseEvent) -> None:
        if self.model.KeepMaxValue:
            self.model.reset_max()
            self.sync()


class GaugeFace(Face):
    """A gauge's composition: the layer of its zone, the value's text and the needle or the bar's
    fill, each from the caches; the maximum mark, a text no sprite holds, a needle of a dial too
    large for sprites or one that pokes out of its element are drawn with a painter. Repainted
    only when something moved by a pixel or a text changed (a value that creeps below a pixel
    per tick costs no paint until it has moved one), in a large gauge only the text's box when
    that is all that changed. What the model shows (its `Shown`) is composed by one function
    (`_ops`) on every path; a plant's words over their whole range rarely recur, so nothing is
    kept per word: composing one costs less than looking it up did."""

    __slots__ = ("alone", "bar", "contained", "inks", "kind", "needles", "painted", "part", "slot", "tall",
                 "text_op", "travel", "units", "zones")

    bank = WordBank

    def load(self) -> None:
        super().load()
        widget = self.widget
        assert isinstance(widget, GaugeWidget)
        widget._layout()
        assert widget._value is not None
        kind = self.kind = widget.model.Appearance
        self.slot = widget._value
        self.alone = self.slot.glyphs.alone  # the characters drawn from glyphs (`TextSlot.fits`)
        self.zones: dict[str | None, tuple[Op, Ink, QColor]] = {}  # `_zone`, by zone
        self.inks, self.units = (BARE, widget._units) if kind == "hbar" else (BOXED, "")
        self.needles, self.travel, self.contained = widget._needles, widget._travel, widget._contained
        self.bar, self.tall = widget._bar, widget._digital[0].height() > 30
        part = widget._part
        self.part = None if part is None else part.translated(self.rect.topLeft()).intersected(self.rect)
        self.painted: tuple[object, ...] | None = None  # what a painter drew last (`GaugeWidget.shown`)
        self.text_op: Op | None = None

    def sync(self) -> None:
        if not self.fresh:
            self.load()
        old = self.drawn
        drawn = self.compose()
        if drawn is None:  # drawn with a painter: told by what the operator sees
            shown, was = self.widget.shown(), self.painted
            if old is None and shown == was:
                return
            self.painted = shown
            text_only = old is None and was is not None and was[1:] == shown[1:]
        elif drawn == old:
            return
        else:
            self.painted = None
            text_only = self.part is not None and old is not None and len(old) == len(drawn) and all(
                a == b or b is self.text_op for a, b in zip(old, drawn))
        self.drawn = drawn
        self.show(self.part if text_only and self.part is not None else self.rect)

    def put(self, shown: Shown) -> bool:
        """`Face.put`: the composition of what the model shows, in one step."""
        if not self.fresh:
            self.load()
        if not self.contained or self.style_of(self.attrs) != self.style:
            self.sync()
            return False
        drawn = self._ops(shown)
        if drawn is None:  # a painter draws it
            self.sync()
            return False
        if drawn == self.drawn:
            return False
        self.drawn, self.painted = drawn, None
        if self.marked:
            self.unmark()
        return True

    def compose(self) -> list[Op] | None:
        m = self.model
        marked = m.maximum is not None and (self.kind != "digital" or self.tall)  # drawn by a painter
        if m.stale or not self.contained or marked or self.restyled():
            return None
        return self._ops(m.shown)

    def _ops(self, shown: Shown) -> list[Op] | None:
        """The composition of `shown` at the element's place: its zone's layer, the text, the
        needle or the fill; None where a painter must draw (a text past the glyphs or, in a
        large gauge, past its area: repainted with its whole element; a needle too large)."""
        text = (shown.text or "---") + self.units
        slot = self.slot
        if not (self.alone.issuperset(text) or slot.fits(text)) or (
                self.part is not None and not slot.inside(text)):  # (a gauge's slot cuts at its sides)
            return None
        zone, x, y = shown.zone, self.x, self.y
        base, ink, fill = self.zones.get(zone) or self._zone(zone)
        value = self.text_op = (draw_text, (slot, x, y, text, ink))
        kind = self.kind
        if shown.hw is None or kind == "digital":
            return [base, value]
        if kind == "hbar":
            left, top, height, travel = self.bar
            return [base, (FILL, (x + left, y + top, round(travel * shown.fraction), height, fill)), value]
        needles = self.needles
        if needles is None:
            return None
        pointer = round(shown.fraction * self.travel)
        nx, ny, needle = needles.get(pointer) or self.widget._needle_sprite(pointer)
        return [base, value, (PIX, (x + nx, y + ny, needle))]

    def _zone(self, zone: str | None) -> tuple[Op, Ink, QColor]:
        """What a zone draws with: its layer's copy, the value's ink and a bar's fill colour."""
        layer = self.layers.get(zone)  # (not `or`: the truth of a QPixmap is a call into Qt)
        base = (PIX, (self.x, self.y, self.widget.layer() if layer is None else layer))
        fill = theme.ZONE_COLORS.get(zone or "") or theme.ACCENT
        made = self.zones[zone] = (base, self.inks[zone], fill)
        return made


GaugeWidget.face_class = GaugeFace
