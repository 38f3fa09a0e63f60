"""Pixmaps of what a form draws again and again: value texts and dial needles, rendered once.

A readout shows a few hundred distinct texts over a shift and a needle a few hundred positions,
and dials and readouts of one size share them all; laying out a text or rasterising an
antialiased polygon costs several times a pixmap copy. So a tick draws each changing value as one
pixmap copy from a cache shared by the whole process, keyed by everything that decides its
pixels, least recently used first out, bounded in bytes.
"""

from __future__ import annotations

import math
from collections.abc import Hashable

from PySide6.QtCore import QPoint, QRect, QRectF, QSize, Qt
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


class TextSlot:
    """A text box drawn from cached pixmaps, pixel for pixel what `drawText(box, align, text)` gives.

    The pixmaps cover `area` (by default the box with a margin for glyphs that overhang it) inside
    `bounds` (the element's rectangle: a sprite never needs a clip): opaque when drawn with `back`,
    the flat colour of that area, transparent without."""

    def __init__(self, box: QRectF, font: QFont, align: Qt.AlignmentFlag, dpr: float = 1.0,
                 area: QRectF | None = None, bounds: QRectF | None = None) -> None:
        area = box.adjusted(-3, -3, 3, 3) if area is None else area
        if bounds is not None:
            area = area.intersected(bounds)
        left, top = math.ceil(area.left()), math.ceil(area.top())
        self.at = QPoint(left, top)
        self.left, self.top = left, top
        self.size = QSize(max(1, math.floor(area.right()) - left), max(1, math.floor(area.bottom()) - top))
        self.box = box
        self.font = font
        self.align = align
        self.dpr = dpr
        # the texts of every box like this one, by text and colours
        inside = box.translated(-left, -top).getRect()
        family = (inside, self.size.toTuple(), font.key(), int(align.value), dpr)
        self.sprites = SPRITES.family(family)
        # the widest text the pixmaps hold where the alignment puts it (with a pixel for overhang)
        right = left + self.size.width()
        if align & Qt.AlignmentFlag.AlignRight:
            span = box.right() - left
        elif align & Qt.AlignmentFlag.AlignHCenter:
            span = 2 * min(box.center().x() - left, right - box.center().x())
        else:
            span = right - box.left()
        self.span = span - 2
        self.metrics = QFontMetricsF(font)

    @property
    def rect(self) -> QRect:
        """What a new text repaints, in the element's coordinates."""
        return QRect(self.at, self.size)

    def sprite(self, text: str, ink: Ink) -> Sprite | None:
        """The text's pixmap, or None for a text wider than the pixmaps hold (a value far out of
        its range), which is drawn whole instead (`draw`)."""
        left, top = self.left, self.top
        key = (text, ink.key)
        sprite = self.sprites.get(key)
        if sprite is None:
            if self.metrics.horizontalAdvance(text) > self.span:
                return None
            sprite = SPRITES.put(self.sprites, key, (left, top, self._render(text, ink.fore, ink.back)))
        return sprite

    def draw(self, p: QPainter, text: str, ink: Ink) -> None:
        sprite = self.sprite(text, ink)
        if sprite is None:
            p.setFont(self.font)
            p.setPen(ink.fore)
            p.drawText(self.box, self.align, text)  # drawn whole, as before there was a cache
            return
        p.drawPixmap(*sprite)

    def _render(self, text: str, fore: QColor, back: QColor | None) -> QPixmap:
        pix = blank(self.size, self.dpr, back)
        p = QPainter(pix)
        try:  # a painter left open on a pixmap crashes Qt when the pixmap goes
            p.setRenderHint(QPainter.RenderHint.Antialiasing)
            # moved by whole pixels, the text is laid out where it would be drawn: the same
            # rounding, the same pixels
            p.translate(-self.at.x(), -self.at.y())
            p.setFont(self.font)
            p.setPen(fore)
            p.drawText(self.box, self.align, text)
        finally:
            p.end()
        return pix
