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
        self.below = math.ceil(self.metrics.height()) + PAD + 1 - self.ascent  # pixmap rows below the base
        self.height = math.ceil(self.metrics.height()) + 2 * PAD + 1  # of its pixmaps
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
            pix = blank(QSize(width, self.height), self.dpr, None)  # (`TextSlot.draw` cuts it)
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
        self.left, self.top = left, top
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
        if align & Qt.AlignmentFlag.AlignRight:  # a line of width w starts at anchor - pull * w
            self.anchor, self.pull = box.right(), 1.0
        elif align & Qt.AlignmentFlag.AlignHCenter:
            self.anchor, self.pull = box.left() + box.width() / 2, 0.5
        else:
            self.anchor, self.pull = box.left(), 0.0
        self.row, self.fy = divmod(int(self.base * 64), 64)  # the baseline in pixels and 64ths
        self.span64, self.box64 = self.span * 64, box.width() * 64

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
        return self.anchor - self.pull * width

    def draw(self, p: QPainter, text: str, ink: Ink, x: int = 0, y: int = 0) -> None:
        """The text with the slot's box moved by (x, y) whole pixels (a form draws its elements
        at their places)."""
        if self.fits(text):
            self.paint(p, text, ink, x, y)
            return
        p.setFont(self.font)
        p.setPen(ink.fore)
        p.drawText(self.box.translated(x, y), self.align, text)  # drawn whole, as drawText would

    def paint(self, p: QPainter, text: str, ink: Ink, x: int = 0, y: int = 0) -> None:
        """`draw` of a text that `fits`, glyph by glyph. Positions are in 64ths of a pixel, as Qt
        lays a line out in the element: its start made whole 64ths once (QFixed::fromReal), then
        advanced by each glyph's advance, itself whole 64ths."""
        glyphs = self.glyphs
        advances = glyphs.advances64
        width = sum(map(advances.__getitem__, text))
        if ink.back is not None and width <= self.span64:  # the flat colour under the text, opaque
            p.fillRect(x + self.left, y + self.top, self.size.width(), self.size.height(), ink.back)
        at = int(self._left(width / 64) * 64) + (x << 6)
        gy, fy = self.row + y, self.fy
        clip = self.cut if width > self.box64 or self.tall else self.sides
        get, glyph, key = glyphs.pixmaps.get, glyphs.glyph, ink.key
        if clip is None or (clip[0] + x <= (at >> 6) - PAD and (at + width >> 6) + PAD + 2 <= clip[2] + x and
                            clip[1] + y <= gy - PAD - glyphs.ascent and gy + glyphs.below <= clip[3] + y):
            for c in text:  # (the usual case: nothing to cut)
                fx = at & 63
                dx, dy, pix = get((c, key, fx, fy)) or glyph(c, ink, fx, fy)
                p.drawPixmap((at >> 6) + dx, gy + dy, pix)
                at += advances[c]
            return
        x0, y0, x1, y1 = clip[0] + x, clip[1] + y, clip[2] + x, clip[3] + y
        dpr, height = glyphs.dpr, glyphs.height
        for c in text:
            fx = at & 63
            dx, dy, pix = get((c, key, fx, fy)) or glyph(c, ink, fx, fy)
            gx, top = (at >> 6) + dx, gy + dy
            right, bottom = gx + glyphs.widths[c], top + height
            if x0 <= gx and right <= x1 and y0 <= top and bottom <= y1:
                p.drawPixmap(gx, top, pix)
            elif gx < x1 and x0 < right and top < y1 and y0 < bottom:  # cut as a clip would cut it
                a, b, t, u = max(x0, gx), min(x1, right), max(y0, top), min(y1, bottom)
                if dpr == 1.0:
                    p.drawPixmap(a, t, pix, a - gx, t - top, b - a, u - t)
                else:
                    p.drawPixmap(a, t, pix, round((a - gx) * dpr), round((t - top) * dpr),
                                 round((b - a) * dpr), round((u - t) * dpr))
            at += advances[c]


def draw_text(p: QPainter, slot: TextSlot, x: int, y: int, text: str, ink: Ink) -> None:
    """A form's composition step (`base.Op`) for a value's text at the element's place (x, y): a
    text the gauge found `fits`."""
    slot.paint(p, text, ink, x, y)
