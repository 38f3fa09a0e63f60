"""Property parsers for .hmi files: one function per kind of value the manual's properties take.

Each parser takes the JSON value and the load context and returns the typed value or raises
PropError with a message an engineer can act on. Element models declare their properties as
dataclass fields carrying a parser in their metadata (see `prop`), so the schema of every element
type lives next to the model that uses it and the loader needs no per-type code.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from app.scada.table import TagTable
from app.scada.tag import Scaling, TagType  # the one conversion, shared with tags, journal and viewer
from app.scada.words import ENGLISH, Phrase, phrase
from netplc.address import AddressError, BitRef, check_operand, parse_hmi_bit, parse_octal
from netplc.textfile import MAX_DIGITS, MISSING, TextFileError, file_problem, resolve
from netplc.words import WordedError

Color = tuple[int, int, int, int]  # r, g, b, alpha


class PropError(WordedError):
    """A property value the loader refuses: a phrase of app/scada/words.py, the `problem` part of
    the report, said in the station's language by the loader."""

    in_english = ENGLISH


class Outside(PropError):
    """A file outside the folders a form may read: reported, and the element shows without it."""


@dataclass(frozen=True, slots=True)
class Font:
    Family: str = "DejaVu Sans"
    Size: float = 10.0
    Bold: bool = False
    Italic: bool = False


@dataclass
class Context:
    """What a property value may refer to: symbols, the form's folder, devices and image list."""

    symbols: dict[str, int]
    folder: Path
    devices: dict[str, Scaling] = field(default_factory=dict)
    images: list[Path | None] = field(default_factory=list)
    roots: tuple[Path, ...] = ()  # folders files may come from besides `folder` (the station's)
    allow_outside: bool = False  # the station allows files anywhere
    tags: TagTable = field(default_factory=TagTable)  # an address may name a tag of tags.csv


Parser = Callable[[Any, Context], Any]


def prop(parser: Parser, *, required: bool = False, alias: str | None = None) -> dict[str, Any]:
    """Field metadata marking a dataclass field as an .hmi property."""
    return {"parser": parser, "required": required, "alias": alias}


@dataclass(frozen=True, slots=True)
class LongNumber:
    """A JSON integer with more digits than int() converts (Python's limit is 4300): kept as its
    text, so that every property parser refuses it by name instead of json raising ValueError."""

    text: str

    def __repr__(self) -> str:
        return str(ENGLISH.say(self.said))

    @property
    def said(self) -> Phrase:
        return phrase("form digits", n=len(self.text.lstrip("-")))


def json_int(text: str) -> int | LongNumber:
    """`parse_int` for json.loads."""
    return int(text) if len(text) <= MAX_DIGITS else LongNumber(text)


def _show(value: Any) -> str:
    try:
        text = repr(value) if not isinstance(value, str) else f'"{value}"'
    except RecursionError:  # json.loads nests deeper than repr can
        return "a deeply nested value"
    return text if len(text) <= 40 else text[:37] + "..."


def text(value: Any, _ctx: Context) -> str:
    if not isinstance(value, str):
        raise PropError("form expected text", value=_show(value))
    return value


def boolean(value: Any, _ctx: Context) -> bool:
    if not isinstance(value, bool):
        raise PropError("form expected bool", value=_show(value))
    return value


def integer(lo: int, hi: int) -> Parser:
    def parse(value: Any, _ctx: Context) -> int:
        if isinstance(value, LongNumber):
            raise PropError("form out of range", value=value.said, lo=lo, hi=hi)
        if isinstance(value, bool) or not isinstance(value, int):
            raise PropError("form expected integer", lo=lo, hi=hi, value=_show(value))
        if not lo <= value <= hi:
            raise PropError("form out of range", value=value, lo=lo, hi=hi)
        return value

    return parse


MAX_NUMBER = 1e15  # past this a scaled value loses its units digit in a float


def number(value: Any, _ctx: Context) -> float:
    if isinstance(value, LongNumber):
        raise PropError("form out of range", value=value.said, lo="-1e15", hi="1e15")
    if isinstance(value, bool) or not isinstance(value, int | float) or (
            isinstance(value, float) and not math.isfinite(value)):
        raise PropError("form expected number", value=_show(value))
    if not -MAX_NUMBER <= value <= MAX_NUMBER:  # exact for ints too, which float() may not hold
        raise PropError("form out of range", value=_show(value), lo="-1e15", hi="1e15")
    return float(value)


def choice(*options: str) -> Parser:
    def parse(value: Any, _ctx: Context) -> str:
        if value not in options:
            raise PropError("form not one of", value=_show(value), options=", ".join(options))
        return value

    return parse


def _address(value: Any, ctx: Context, kinds: tuple[TagType, ...] = ()) -> int:
    """Octal text (`"02000"`), a tag of one of `kinds`, a symbol, or `symbol.k` (bit k of the byte
    a symbol names)."""
    if not isinstance(value, str):
        raise PropError("form address text", value=_show(value))
    tag = ctx.tags.get(value)
    if tag is not None:
        if tag.type not in kinds:
            raise PropError("form tag type" if kinds else "form no tag", tag=value, type=tag.type,
                            kinds=" | ".join(kinds))
        return tag.address
    name, _, bit = value.partition(".")
    if name in ctx.symbols:
        addr = ctx.symbols[name]
        if not bit:
            return addr
        if bit not in tuple("01234567"):
            raise PropError("form bit number", name=name, bit=bit)
        return addr * 8 + int(bit)
    if re.fullmatch(r"[A-Za-z_]\w*(\.\d+)?", value):
        raise PropError("form unknown tag" if ctx.tags.tags else "form unknown symbol", name=name)
    try:
        return parse_octal(value)
    except ValueError:
        raise PropError("form not address", value=value) from None


def bit(value: Any, ctx: Context) -> BitRef:
    """An HMI bit: an I/O bit below 04000, or byte*8+bit at 040000 and above."""
    try:
        return parse_hmi_bit(_address(value, ctx, (TagType.BIT,)))
    except AddressError as e:
        raise PropError("form as is", error=e) from None


def word(value: Any, ctx: Context) -> int:
    """The byte address of a 2-byte analog value (an unsigned word, as the elements read it)."""
    addr = _address(value, ctx, (TagType.WORD,))
    try:
        check_operand(addr, 2)
    except AddressError as e:
        raise PropError("form as is", error=e) from None
    return addr


def sync_type(value: Any, ctx: Context) -> BitRef | None:
    """0 = every tick, else the bit whose level 1 lets the element update."""
    if value in (0, "0"):
        return None
    return bit(value, ctx)


_NAMED_COLORS = {
    "black": "#000000", "white": "#ffffff", "red": "#d32f2f", "green": "#2e7d32", "blue": "#1565c0",
    "yellow": "#f2c400", "orange": "#ef8a00", "gray": "#808080", "grey": "#808080",
    "lightgray": "#d3d3d3", "darkgray": "#505050", "transparent": "#00000000",
}


def color(value: Any, _ctx: Context) -> Color:
    """`#RRGGBB`, `#AARRGGBB` (as Qt and .NET write them) or one of a few names."""
    if not isinstance(value, str):
        raise PropError("form expected colour", value=_show(value))
    v = _NAMED_COLORS.get(value.lower(), value)
    if re.fullmatch(r"#[0-9a-fA-F]{6}", v):
        return int(v[1:3], 16), int(v[3:5], 16), int(v[5:7], 16), 255
    if re.fullmatch(r"#[0-9a-fA-F]{8}", v):
        return int(v[3:5], 16), int(v[5:7], 16), int(v[7:9], 16), int(v[1:3], 16)
    raise PropError("form not colour", value=value, names=", ".join(sorted(_NAMED_COLORS)))


def font(value: Any, ctx: Context) -> Font:
    if not isinstance(value, dict):
        raise PropError("form expected font", value=_show(value))
    unknown = sorted(set(value) - {"Family", "Size", "Bold", "Italic"})
    if unknown:
        raise PropError("form font field", fields=", ".join(unknown))
    size = number(value.get("Size", 10), ctx)
    if not 4 <= size <= 200:
        raise PropError("form font size", size=size)
    return Font(
        text(value.get("Family", Font.Family), ctx),
        size,
        boolean(value.get("Bold", False), ctx),
        boolean(value.get("Italic", False), ctx),
    )


def image_file(value: Any, ctx: Context) -> Path:
    """A picture file relative to the form's folder (forms travel with their images). It must be
    inside that folder or the station's (after symbolic links), unless the station allows files
    anywhere: a form must not make the workstation read /etc/passwd or another station's files."""
    name = text(value, ctx)
    if "\0" in name:
        raise PropError("form image nul", name=_show(name))
    try:
        path = resolve(ctx.folder / name)
    except TextFileError as e:
        raise PropError("form image problem", name=name, problem=e.phrase) from None
    roots = (ctx.folder, *ctx.roots)
    if not ctx.allow_outside and not any(path.is_relative_to(root.resolve()) for root in roots):
        folders: object = str(roots[0])
        for root in roots[1:]:
            folders = phrase("form and", first=folders, then=str(root))
        raise Outside("form image outside", name=name, roots=folders)
    if (why := file_problem(path)) == MISSING:
        raise PropError("form image missing", name=name, folder=ctx.folder)
    if why is not None:
        raise PropError("form image why", name=name, why=why)
    return path


def image_index(value: Any, ctx: Context) -> int:
    """An index into the form's "images" list; -1 = no image."""
    n = len(ctx.images)
    if isinstance(value, bool) or not isinstance(value, int):
        raise PropError("form expected index", value=_show(value))
    if not -1 <= value < n:
        raise PropError("form index range", value=value, n=n)
    return value


ALIGNMENTS = tuple(f"{v}{h}" for v in ("Top", "Middle", "Bottom") for h in ("Left", "Center", "Right"))
alignment = choice(*ALIGNMENTS)
