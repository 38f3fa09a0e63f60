"""What a form draws again and again, kept apart from the values: value texts and dial needles.

A value is drawn from parts that do not depend on the value. Its text is one glyph run
(`QPainter.drawGlyphRun`): the font's glyph indexes at the places Qt's own text layout gives them,
drawn from Qt's glyph cache; that is the call `drawText` ends in after laying the text out, so the
pixels are drawText's, without a layout per text (the costly part) and without a picture per
value. What is kept for texts is bounded by the characters and advances of the fonts a form uses.
A needle is a pixmap by the pixel its tip travels to. So whatever the values, the caches stay
bounded: a plant's words over their whole range cost no more memory than a demo's few. Pixmaps
of all families are shared by the whole process and bounded in bytes.
"""
from __future__ import annotations

import math
from collections.abc import Hashable

from PySide6.QtCore import QPoint, QPointF, QRect, QRectF, QSize, Qt
from PySide6.QtGui import QColor, QFont, QFontMetricsF, QGlyphRun, QPainter, QPixmap, QRawFont

BUDGET = 64 * 2**20  # bytes of cached pixmaps in all


Sprite = tuple[int, int, QPixmap]  # where a pixmap's top-left corner goes, and the pixmap
# where a text's run starts, where it is cut (None: nowhere), and whether that cut is its box alone
# with its ink inside its element's sides (`boxed`: a form may cut it with others, `FormView`)
Plan = tuple[QPointF, QRect | None, bool]


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


PAD = 3  # px around a glyph's advance that its ink may reach (bold, antialiasing): past a clip, it is cut
MAX_RUNS = 4096  # layouts kept per font (`Glyphs.layout`), by the advances of a text, not its characters
MAX_PLANS = 64  # places kept per text slot (`TextSlot._plan`), by width and the slot's offset


class Glyphs:
    """The glyphs of one font: advances, kerning checks, glyph indexes and the layouts of texts
    (the same at every device pixel ratio: Qt's glyph cache renders them for the device)."""

    def __init__(self, font: QFont) -> None:
        self.font = font
        self.metrics = QFontMetricsF(font)
        self.raw = QRawFont.fromFont(font)
        self.ascent = math.ceil(self.metrics.ascent())
        self.below = math.ceil(self.metrics.height()) + PAD + 1 - self.ascent  # ink rows below the base
        self.advances: dict[str, float] = {}
        self.advances64: dict[str, int] = {}  # the same in 64ths of a pixel, as Qt keeps them
        self.indexes: dict[str, int] = {}  # glyph index in the font
        self.alone: set[str] = set()  # characters whose advance is the same beside every other here
        self.kerned: set[str] = set()  # kerned, or not in the font itself (drawText takes another font)
        self.layouts: dict[tuple[int, ...], tuple[int, list[QPointF]]] = {}  # `layout`
        self.steps: set[int] = set()  # the advances of the characters known, in 64ths
        self.lengths: dict[int, tuple[int, list[QPointF]]] = {}  # `layout` by length, while one step

    def learn(self, text: str) -> bool:
        """Whether `text` can be drawn as a glyph run: each character a glyph of the font itself
        and no two kerned together (drawText would move them); each new character is checked once
        against those known."""
        for c in set(text) - self.alone:
            if c in self.kerned:
                return False
            found = self.raw.glyphIndexesForString(c)
            adv = self.metrics.horizontalAdvance
            own = self.advances[c] = adv(c)
            if len(found) != 1 or not found[0] or any(
                    adv(c + k) != own + self.advances[k] or adv(k + c) != own + self.advances[k]
                    for k in (*self.alone, c) if k != c) or adv(c + c) != 2 * own:
                self.kerned.add(c)
                return False
            self.indexes[c] = found[0]
            self.advances64[c] = step = round(own * 64)
            self.steps.add(step)
            self.alone.add(c)
        return True

    def width(self, text: str) -> float:
        advances = self.advances
        return sum([advances[c] for c in text])

    def layout(self, text: str) -> tuple[int, list[QPointF]]:
        """The width of `text` and its glyphs' places from its start, in 64ths of a pixel as Qt
        lays a line out: advanced by each glyph's advance, itself whole 64ths. Kept by the
        advances (the digits of a value share theirs), so a few layouts serve every value; in a
        font whose characters known all advance alike (a monospaced one), by the length alone."""
        alike = len(self.steps) == 1
        if alike:
            found = self.lengths.get(len(text))
            if found is not None:
                return found
        key = tuple(map(self.advances64.__getitem__, text))
        found = self.layouts.get(key)
        if found is None:
            at, places = 0, []
            for step in key:
                places.append(QPointF(at / 64, 0))
                at += step
            if len(self.layouts) >= MAX_RUNS:
                self.layouts.clear()
            found = self.layouts[key] = (at, places)
        if alike:  # (as many lengths as a value's text has: a few)
            self.lengths[len(text)] = found
        return found


GLYPHS: dict[str, Glyphs] = {}  # by font key


class TextSlot:
    """A text box drawn as a glyph run, pixel for pixel what `drawText(box, align, text)` gives.

    `area` (by default the box with a margin for glyphs that overhang it) inside `bounds` (the
    element's rectangle) is what a new text repaints: filled with `back`, the flat colour of that
    area, when the ink has one and the text lies inside it (`inside`). A text wider than the area
    (a small gauge's readout of a wide range) is drawn as a glyph run too, over what is there, cut
    where drawText cuts a text wider than its box (the box, its edges rounded to whole pixels)
    and where the form's clip cuts the element (`bounds`); without `bounds`, or when the font
    kerns its characters, a text is drawn whole by the painter (`fits` says which)."""

    def __init__(self, box: QRectF, font: QFont, align: Qt.AlignmentFlag, area: QRectF | None = None,
                 bounds: QRectF | None = None) -> None:
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
        key = font.key()
        glyphs = self.glyphs = GLYPHS.get(key) or GLYPHS.setdefault(key, Glyphs(font))
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
        self.plans: dict[int, Plan] = {}  # `_plan`, by width and place in one int (no tuple per text)
        self.run = QGlyphRun()  # the text shown last, laid out
        self.run.setRawFont(glyphs.raw)
        self.text, self.places = "", glyphs.layout("")[1]

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
        """`draw` of a text that `fits`, as one glyph run (the slot's own: refilled only with a
        new text, its places only with new advances)."""
        width, origin, cut, _ = self.ready(text, x, y)
        if ink.back is not None and width <= self.span64:
            self.fill(p, ink, x, y)
        run = self.run
        p.setPen(ink.fore)
        if cut is None:  # (the usual case: nothing to cut)
            p.drawGlyphRun(origin, run)
        elif p.hasClipping():  # drawn with a painter, clipped to its element already
            p.save()
            p.setClipRect(cut, Qt.ClipOperation.IntersectClip)
            p.drawGlyphRun(origin, run)
            p.restore()
        else:
            p.setClipRect(cut)
            p.drawGlyphRun(origin, run)
            p.setClipping(False)

    def ready(self, text: str, x: int, y: int) -> tuple[int, QPointF, QRect | None, bool]:
        """The slot's run made to hold `text` (a text that `fits`); its width in 64ths, where the
        run starts with the box moved by (x, y), where it is cut (None: nowhere), and whether
        that cut is the box alone (`Plan`)."""
        width, places = self.glyphs.layout(text)
        origin, cut, boxed = self.plans.get((width << 40) + (x << 20) + y) or self._plan(width, x, y)
        if text != self.text:
            self.text = text
            run = self.run
            run.setGlyphIndexes(list(map(self.glyphs.indexes.__getitem__, text)))
            if places is not self.places:
                self.places = places
                run.setPositions(places)
        return width, origin, cut, boxed

    def fill(self, p: QPainter, ink: Ink, x: int, y: int) -> None:
        """The flat colour under a text (`ink.back`, opaque) that lies inside the area (what a new
        text alone repaints), drawn before the text."""
        p.fillRect(x + self.left, y + self.top, self.size.width(), self.size.height(), ink.back)

    def _plan(self, width: int, x: int, y: int) -> Plan:
        """Where a text of `width` 64ths starts with the box moved by (x, y), and where it is cut
        (None: nowhere). Its start is made whole 64ths once, as Qt makes it (QFixed::fromReal);
        where its glyphs may reach past the element's sides or past the box drawText clips a too
        wide text to, it is clipped there as drawText would be. Kept per width and place: a
        slot shows texts of a few widths at one or two places."""
        glyphs = self.glyphs
        at = int(self._left(width / 64) * 64) + (x << 6)
        gy = self.row + y
        left, right = (at >> 6) - PAD, (at + width >> 6) + PAD + 2  # what its ink may reach
        top, bottom = gy - PAD - glyphs.ascent, gy + glyphs.below

        def holds(clip: tuple[int, ...]) -> bool:
            return (clip[0] + x <= left and right <= clip[2] + x and
                    clip[1] + y <= top and bottom <= clip[3] + y)

        clip = self.cut if width > self.box64 or self.tall else self.sides
        cut = None
        if clip is not None and not holds(clip):
            cut = QRect(clip[0] + x, clip[1] + y, clip[2] - clip[0], clip[3] - clip[1])
        boxed = cut is not None and clip is self.cut and holds(self.sides)  # type: ignore[arg-type]
        if len(self.plans) >= MAX_PLANS:
            self.plans.clear()
        plan = self.plans[(width << 40) + (x << 20) + y] = (QPointF(at / 64, gy + self.fy / 64), cut, boxed)
        return plan


def draw_text(p: QPainter, slot: TextSlot, x: int, y: int, text: str, ink: Ink) -> None:
    """A form's composition step (`base.Op`) for a value's text at the element's place (x, y): a
    text the gauge found `fits`."""
    slot.paint(p, text, ink, x, y)
