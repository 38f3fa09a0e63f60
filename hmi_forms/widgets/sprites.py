"""Pixmaps of what a form draws again and again: glyphs of value texts and dial needles.

A value is drawn from pictures that do not depend on the value: its text glyph by glyph, each
glyph a pixmap cached by character, colours and the fraction of a pixel it starts at (a font's
advances are whole 64ths of a pixel, so a character has at most 64 x 64 of those), and a needle
by the pixel its tip travels to. So what the caches hold is bounded by the characters, colours
and sizes a form uses, whatever the values: a plant's words over their whole range cost no more
memory than a demo's few. Copying a few small pixmaps costs less than laying out a text, and the
pixels are the same: each glyph is drawn into its pixmap at the same fraction of a pixel it has
on the form, so Qt rounds and antialiases it there exactly as it would drawing the whole text.
Pixmaps of all families are shared by the whole process and bounded in bytes.
"""

from __future__ import annotations

import math
from collections.abc import Hashable

from PySide6.QtCore import QPoint, QPointF, QRect, QRectF, QSize, Qt
from PySide6.QtGui import QColor, QFont, QFontMetricsF, QPainter, QPixmap

BUDGET = 64 * 2**20  # bytes of cached pixmaps in all


Sprite = tuple[int, int, QPixmap]  # where a pixmap's top-left corner goes, and the pixmap


class SpriteCache:
    """Sprites in families (the pictures of one kind of text box or needle, by text or position),
    so that a hit costs one lookup of a short key in the family a widget holds. Once `budget`
    bytes are held it starts afresh: what is on screen is back within a tick."""

    def __init__(self, budget: int = BUDGET) -> None:
        self.budget = budget
        self.bytes = 0
        self.families: dict[Hashable, dict[Hashable, Sprite]] = {}

    def __len__(self) -> int:
        return sum(len(family) for family in self.families.values())

    def family(self, key: Hashable) -> dict[Hashable, Sprite]:
        return self.families.setdefault(key, {})

    def put(self, family: dict[Hashable, Sprite], key: Hashable, sprite: Sprite) -> Sprite:
        pix = sprite[2]
        size = pix.width() * pix.height() * 4
        if self.bytes + size > self.budget:
            self.clear()
        family[key] = sprite
        self.bytes += size
        return sprite

    def clear(self) -> None:
        for family in self.families.values():  # emptied in place: widgets hold them
            family.clear()
        self.bytes = 0


SPRITES = SpriteCache()


def blank(size: QSize, dpr: float, fill: QColor | None) -> QPixmap:
    """A pixmap of `size` logical pixels, filled (opaque: copied without blending) or transparent."""
    pix = QPixmap(size * dpr)
    pix.setDevicePixelRatio(dpr)
    pix.fill(fill if fill is not None else Qt.GlobalColor.transparent)
    return pix


class Ink:
    """A text colour and the flat colour under it (None: whatever is there), with their key."""

    __slots__ = ("back", "fore", "key")

    def __init__(self, fore: QColor, back: QColor | None = None) -> None:
        self.fore, self.back = fore, back
        self.key = fore.rgba() << 33 | (0 if back is None else 1 << 32 | back.rgba())  # one int: fast to hash


PAD = 3  # px around a glyph's pixmap for what overhangs its advance (bold, antialiasing)


class Glyphs:
    """The glyphs of one font at one device pixel ratio: advances, kerning checks and pixmaps."""

    def __init__(self, font: QFont, dpr: float) -> None:
        self.font, self.dpr = font, dpr
        self.metrics = QFontMetricsF(font)
        self.ascent = math.ceil(self.metrics.ascent())
        self.size = (0, math.ceil(self.metrics.height()) + 2 * PAD)
        self.advances: dict[str, float] = {}
        self.advances64: dict[str, int] = {}  # the same in 64ths of a pixel, as Qt keeps them
        self.widths: dict[str, int] = {}
        self.alone: set[str] = set()  # characters whose advance is the same beside every other here
        self.kerned: set[str] = set()  # characters whose advance changes beside one of them
        self.pixmaps = SPRITES.family(("glyphs", font.key(), dpr))  # (char, ink, fx, fy) -> Sprite

    def learn(self, text: str) -> bool:
        """Whether `text` can be drawn glyph by glyph: no two of its characters kerned together
        (drawText would move them); each new character is checked once against those known."""
        for c in set(text) - self.alone:
            if c in self.kerned:
                return False
            adv = self.metrics.horizontalAdvance
            own = self.advances[c] = adv(c)
            self.advances64[c] = round(own * 64)
            self.widths[c] = math.ceil(own) + 2 * PAD + 1  # of its pixmaps
            if any(adv(c + k) != own + self.advances[k] or adv(k + c) != own + self.advances[k]
                   for k in (*self.alone, c) if k != c) or adv(c + c) != 2 * own:
                self.kerned.add(c)
                return False
            self.alone.add(c)
        return True

    def width(self, text: str) -> float:
        advances = self.advances
        return sum([advances[c] for c in text])

    def glyph(self, c: str, ink: Ink, fx: int, fy: int) -> Sprite:
        """The glyph of `c` in `ink` whose origin lies (fx, fy) 64ths of a pixel right of and below
        a whole pixel (Qt places glyphs in 64ths too): its pixmap's corner relative to that pixel."""
        key = (c, ink.key, fx, fy)
        sprite = self.pixmaps.get(key)
        if sprite is None:
            width = self.widths[c]
            pix = blank(QSize(width, self.size[1] + 1), self.dpr, None)  # (`TextSlot.draw` cuts it)
            p = QPainter(pix)
            try:  # a painter left open on a pixmap crashes Qt when the pixmap goes
                p.setRenderHint(QPainter.RenderHint.Antialiasing)
                p.setFont(self.font)
                p.setPen(ink.fore)
                p.drawText(QPointF(PAD + fx / 64, PAD + self.ascent + fy / 64), c)
            finally:
                p.end()
            sprite = SPRITES.put(self.pixmaps, key, (-PAD, -PAD - self.ascent, pix))
        return sprite


GLYPHS: dict[tuple[str, float], Glyphs] = {}  # by font key and device pixel ratio


class TextSlot:
    """A text box drawn glyph by glyph from cached pixmaps, pixel for pixel what
    `drawText(box, align, text)` gives.

    `area` (by default the box with a margin for glyphs that overhang it) inside `bounds` (the
    element's rectangle) is what a new text repaints: filled with `back`, the flat colour of that
    area, when the ink has one and the text lies inside it (`inside`). A text wider than the area
    (a small gauge's readout of a wide range) is drawn from glyphs too, over what is there, cut
    where drawText cuts a text wider than its box (the box, its edges rounded to whole pixels)
    and where the form's clip cuts the element (`bounds`); without `bounds`, or when the font
    kerns its characters, a text is drawn whole by the painter (`fits` says which)."""

    def __init__(self, box: QRectF, font: QFont, align: Qt.AlignmentFlag, dpr: float = 1.0,
                 area: QRectF | None = None, bounds: QRectF | None = None) -> None:
        area = box.adjusted(-3, -3, 3, 3) if area is None else area
        if bounds is not None:
            area = area.intersected(bounds)
        left, top = math.ceil(area.left()), math.ceil(area.top())
        self.at = QPoint(left, top)
        self.size = QSize(max(1, math.floor(area.right()) - left), max(1, math.floor(area.bottom()) - top))
        self.box = box
        self.font = font
        self.align = align
        key = (font.key(), dpr)
        glyphs = self.glyphs = GLYPHS.get(key) or GLYPHS.setdefault(key, Glyphs(font, dpr))
        self.metrics = glyphs.metrics
        # where drawText puts the baseline of one line in this box: the same for every text
        self.base = self.metrics.boundingRect(box, int(align.value), "0").top() + self.metrics.ascent()
        # the widest text the area holds where the alignment puts it (with a pixel for overhang)
        right = left + self.size.width()
        if align & Qt.AlignmentFlag.AlignRight:
            span = box.right() - left
        elif align & Qt.AlignmentFlag.AlignHCenter:
            span = 2 * min(box.center().x() - left, right - box.center().x())
        else:
            span = right - box.left()
        self.span = span - 2
        # where glyphs are cut (left, top, right, bottom; None: nowhere): at the element's sides,
        # as the form clips an element, and, for a text wider or taller than its box, at the box
        # as drawText clips it (its edges rounded half up to whole pixels, as Qt rounds a clip)
        self.sides: tuple[int, ...] | None = None
        self.cut: tuple[int, ...] | None = None
        if bounds is not None:
            self.sides = sides = (math.ceil(bounds.left()), math.ceil(bounds.top()),
                                  math.floor(bounds.right()), math.floor(bounds.bottom()))
            edges = [math.floor(v + 0.5) for v in (box.left(), box.top(), box.right(), box.bottom())]
            self.cut = (max(sides[0], edges[0]), max(sides[1], edges[1]), min(sides[2], edges[2]),
                        min(sides[3], edges[3]))
        self.tall = self.metrics.height() > box.height()  # drawText clips every text to the box

    @property
    def rect(self) -> QRect:
        """What a new text repaints, in the element's coordinates."""
        return QRect(self.at, self.size)

    def fits(self, text: str) -> bool:
        """Whether `text` is drawn from glyphs: not kerned, and inside the area or cut at the
        element's sides (without those a text wider than the area is drawn whole instead)."""
        glyphs = self.glyphs
        if not (glyphs.alone.issuperset(text) or glyphs.learn(text)):
            return False
        return self.sides is not None or glyphs.width(text) <= self.span

    def inside(self, text: str) -> bool:
        """Whether a text that `fits` lies inside the area (what a new text alone repaints)."""
        return self.glyphs.width(text) <= self.span

    def _left(self, width: float) -> float:
        """Where drawText starts a line of `width` in the box."""
        box, align = self.box, self.align
        if align & Qt.AlignmentFlag.AlignRight:
            return box.right() - width
        if align & Qt.AlignmentFlag.AlignHCenter:
            return box.left() + (box.width() - width) / 2
        return box.left()

    def draw(self, p: QPainter, text: str, ink: Ink, x: int = 0, y: int = 0) -> None:
        """The text with the slot's box moved by (x, y) whole pixels (a form draws its elements
        at their places)."""
        if not self.fits(text):
            p.setFont(self.font)
            p.setPen(ink.fore)
            p.drawText(self.box.translated(x, y), self.align, text)  # drawn whole, as drawText would
            return
        glyphs = self.glyphs
        width = glyphs.width(text)
        if ink.back is not None and width <= self.span:  # the flat colour under the text, opaque
            p.fillRect(x + self.at.x(), y + self.at.y(), self.size.width(), self.size.height(), ink.back)
        advances, glyph = glyphs.advances64, glyphs.glyph
        left = self._left(width)
        clip = self.cut if width > self.box.width() or self.tall else self.sides
        far = 1 << 30
        x0, y0, x1, y1 = (-far, -far, far, far) if clip is None else (clip[0] + x, clip[1] + y,
                                                                       clip[2] + x, clip[3] + y)
        dpr, height = glyphs.dpr, glyphs.size[1] + 1
        # positions in 64ths of a pixel, as Qt lays a line out: the start made whole 64ths once
        # (QFixed::fromReal), then advanced by each glyph's advance, itself whole 64ths
        row, fy = divmod(int((self.base + y) * 64), 64)
        at = int((left + x) * 64)
        for c in text:
            column, fx = divmod(at, 64)
            dx, dy, pix = glyph(c, ink, fx, fy)
            gx, gy = column + dx, row + dy
            right, bottom = gx + glyphs.widths[c], gy + height
            if x0 <= gx and right <= x1 and y0 <= gy and bottom <= y1:
                p.drawPixmap(gx, gy, pix)
            elif gx < x1 and x0 < right and gy < y1 and y0 < bottom:  # cut as a clip would cut it
                a, b, t, u = max(x0, gx), min(x1, right), max(y0, gy), min(y1, bottom)
                p.drawPixmap(a, t, pix, round((a - gx) * dpr), round((t - gy) * dpr), round((b - a) * dpr),
                             round((u - t) * dpr))
            at += advances[c]


def draw_text(p: QPainter, slot: TextSlot, x: int, y: int, text: str, ink: Ink) -> None:
    """A form's composition step (`base.Op`) for a value's text at the element's place (x, y)."""
    slot.draw(p, text, ink, x, y)
