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
            width = math.ceil(self.advances[c]) + 2 * PAD + 1
            pix = blank(QSize(width, self.size[1] + 1), self.dpr, None)
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
    element's rectangle: a glyph never needs a clip) is what a new text repaints: filled with
    `back`, the flat colour of that area, when the ink has one. A text wider than the area, or
    one whose characters the font kerns, is drawn whole by the painter (`fits` says which)."""

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

    @property
    def rect(self) -> QRect:
        """What a new text repaints, in the element's coordinates."""
        return QRect(self.at, self.size)

    def fits(self, text: str) -> bool:
        """Whether `text` is drawn from glyphs: not kerned, and not wider than the area (a value far
        out of its range is drawn whole by the painter instead)."""
        glyphs = self.glyphs
        return (glyphs.alone.issuperset(text) or glyphs.learn(text)) and glyphs.width(text) <= self.span

    def draw(self, p: QPainter, text: str, ink: Ink, x: int = 0, y: int = 0) -> None:
        """The text with the slot's box moved by (x, y) whole pixels (a form draws its elements
        at their places)."""
        if not self.fits(text):
            p.setFont(self.font)
            p.setPen(ink.fore)
            p.drawText(self.box.translated(x, y), self.align, text)  # drawn whole, as drawText would
            return
        glyphs = self.glyphs
        if ink.back is not None:
            p.fillRect(x + self.at.x(), y + self.at.y(), self.size.width(), self.size.height(), ink.back)
        box, align, advances, glyph = self.box, self.align, glyphs.advances, glyphs.glyph
        if align & Qt.AlignmentFlag.AlignRight:
            left = box.right() - glyphs.width(text)
        elif align & Qt.AlignmentFlag.AlignHCenter:
            left = box.left() + (box.width() - glyphs.width(text)) / 2
        else:
            left = box.left()
        base = self.base + y
        row = math.floor(base)
        fy = int((base - row) * 64)  # as Qt turns a position into 64ths (QFixed::fromReal)
        ox = left + x
        for c in text:
            column = math.floor(ox)
            dx, dy, pix = glyph(c, ink, int((ox - column) * 64), fy)
            p.drawPixmap(column + dx, row + dy, pix)
            ox += advances[c]


def draw_text(p: QPainter, slot: TextSlot, x: int, y: int, text: str, ink: Ink) -> None:
    """A form's composition step (`base.Op`) for a value's text at the element's place (x, y)."""
    slot.draw(p, text, ink, x, y)
