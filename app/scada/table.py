"""`tags.csv`: the station's tags and their alarms, one per line, checked as a whole.

Read as every station text file is (netplc/textfile.py: UTF-8 or cp1251, a size limit, one row a
line): a header line naming the columns (any order; only `name, address, type` are required), `#`
or `;` comment lines. Every problem is collected and reported as `tags.csv:LINE: TAG: problem`, so
that `check` and the start name all of them at once; the lines that are good still load, so one
typo does not take every other tag's alarms away.
"""

from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from app.scada.tag import BYTE_ORDERS, NETPLC_ORDER, WIDE, Scaling, Tag, TagType, check_address
from app.scada.words import Phrase, Words, phrase, words
from netplc.address import AddressError, parse_hmi_bit, parse_octal
from netplc.problems import Problems
from netplc.textfile import TextFileError, csv_rows, read_text

REQUIRED = ("name", "address", "type")
TAG_COLUMNS = ("unit", "app_min", "app_max", "phy_min", "phy_max", "decimals", "description", "byte_order")
ALARM_COLUMNS = ("hh", "h", "l", "ll", "deadband", "delay", "on_delay", "off_delay", "alarm_when", "priority",
                 "latching", "suppress_by", "quality_alarm")
COLUMNS = REQUIRED + TAG_COLUMNS + ALARM_COLUMNS
LIMIT_KEYS = ("ll", "l", "h", "hh")  # in the order their values must keep
TYPES = {t.value for t in TagType}
ALIASES = {"uint16": "word", "int": "int16", "dint": "int32", "real": "float32"}  # IEC 61131-3 names
# byte orders by the letters other tools use (A the most significant byte)
ORDER_LETTERS = {"ABCD": "1234", "DCBA": "4321", "BADC": "2143", "CDAB": "3412"}
DEFAULT_PRIORITY = 3  # medium
_NAME = re.compile(r"[^\W\d]\w*")
_YES = {"1": True, "yes": True, "true": True, "0": False, "no": False, "false": False}


class TagError(Problems):
    """A tags file that cannot be used: every problem, each `file:line: ...`."""


@dataclass(frozen=True)
class TagAlarms:
    """The alarm columns of one tag (physical units, seconds)."""

    hh: float | None = None
    h: float | None = None
    l: float | None = None  # noqa: E741 - the ISA-18.2 name
    ll: float | None = None
    deadband: float = 0.0
    on_delay: float = 0.0
    off_delay: float = 0.0
    alarm_when: int | None = None  # a bit tag: alarm while the bit has this value
    priority: int = DEFAULT_PRIORITY  # 1 critical, 2 high, 3 medium, 4 low
    latching: bool = False
    suppress_by: int | None = None  # HMI bit address: suppressed by design while it is 1
    quality_alarm: bool = False  # an alarm of its own class while the tag's quality is bad

    def limits(self) -> list[tuple[str, float]]:
        """The limits set, as (HH/H/L/LL, value)."""
        return [(k.upper(), v) for k in ("hh", "h", "l", "ll") if (v := getattr(self, k)) is not None]

    @property
    def any(self) -> bool:
        return bool(self.limits()) or self.alarm_when is not None or self.quality_alarm


@dataclass
class TagTable:
    tags: list[Tag] = field(default_factory=list)
    alarms: dict[str, TagAlarms] = field(default_factory=dict)  # tag name -> its alarm columns
    source: str = "tags.csv"

    def __post_init__(self) -> None:
        self.by_name = {t.name: t for t in self.tags}

    def get(self, name: str) -> Tag | None:
        return self.by_name.get(name)


def load_tags(path: str | Path, symbols: dict[str, int] | None = None, say: Words | None = None) -> TagTable:
    """The tags of a file; TagError lists every problem (in the language of `say`)."""
    table, problems = read_tags(path, symbols, say)
    if problems:
        raise TagError(problems)
    return table


def read_tags(path: str | Path, symbols: dict[str, int] | None = None,
              say: Words | None = None) -> tuple[TagTable, list[str]]:
    """The good lines' tags and every problem (for `check`, which reports and goes on), its fixed
    wording in the language of `say` (the station's; the system locale's without it), each
    naming the file, the line, the tag, the column and the value as they are."""
    say = say or words()
    path = Path(path)
    fname = str(path)
    try:
        text = read_text(path, "read tags")
    except TextFileError as e:
        return TagTable(source=fname), [f"{fname}:{e.line}: {say.say(e)}"]
    problems: list[str] = []
    rows: list[tuple[int, list[str]]] = []
    for n, row in csv_rows(text):
        if isinstance(row, Phrase):
            problems.append(f"{fname}:{n}: {say.say(row)}")
        elif row and "".join(row).strip() and not row[0].lstrip().startswith(("#", ";")):
            rows.append((n, row))
    if not rows:
        return TagTable(source=fname), problems
    line, header = rows[0]
    columns = [c.strip().lower() for c in header]
    missing = [c for c in REQUIRED if c not in columns]
    if missing:
        problems.append(f"{fname}:{line}: " + say("tags header", required=", ".join(REQUIRED),
                                                  missing=", ".join(missing), known=", ".join(COLUMNS)))
        return TagTable(source=fname), problems
    for c in columns:
        if c not in COLUMNS:
            problems.append(f"{fname}:{line}: " + say("tags unknown column", column=c,
                                                      known=", ".join(COLUMNS)))
        elif columns.count(c) > 1:
            problems.append(f"{fname}:{line}: " + say("tags column twice", column=c))
    tags: list[Tag] = []
    alarms: dict[str, TagAlarms] = {}
    first_line: dict[str, int] = {}
    for lineno, row in rows[1:]:
        if len(row) > len(columns) and any(v.strip() for v in row[len(columns):]):
            problems.append(f"{fname}:{lineno}: " + say("tags fields", n=len(row), header=len(columns)))
            continue
        cells = {c: (row[i].strip() if i < len(row) else "") for i, c in enumerate(columns)}
        parser = _Row(f"{fname}:{lineno}", cells, symbols or {}, say)
        result = parser.parse()
        problems += parser.problems
        if result is None:
            continue
        tag, tag_alarms = result
        if tag.name in first_line:
            problems.append(f"{fname}:{lineno}: {tag.name}: "
                            + say("tags name used", line=first_line[tag.name]))
            continue
        first_line[tag.name] = lineno
        tags.append(tag)
        if tag_alarms.any:
            alarms[tag.name] = tag_alarms
    return TagTable(tags, alarms, fname), problems


class _Row:
    """One line: typed cells, and the problems found in it."""

    def __init__(self, where: str, cells: dict[str, str], symbols: dict[str, int], say: Words) -> None:
        self.where = where
        self.say = say
        self.cells = cells
        self.symbols = symbols
        self.name = cells.get("name", "")
        self.problems: list[str] = []

    def bad(self, name: str, /, **values: object) -> None:
        """A problem of the catalogue (`name`, `values`) in the reader's language."""
        who = self.name or self.say("tag no name given")
        self.problems.append(f"{self.where}: {who}: {self.say(name, **values)}")

    def number(self, key: str, default: float | None = None) -> float | None:
        text = self.cells.get(key, "")
        if not text:
            return default
        try:
            value = float(text.replace(",", "."))
        except ValueError:
            self.bad("tag not number", key=key, text=text)
            return default
        if not math.isfinite(value):
            self.bad("tag not finite", key=key, text=text)
            return default
        return value

    def whole(self, key: str, default: int | None, lo: int, hi: int, meaning: object = "") -> int | None:
        value = self.number(key)
        if value is None:
            return default
        if value != int(value) or not lo <= value <= hi:
            self.bad("tag not whole", key=key, text=self.cells[key], lo=lo, hi=hi, meaning=meaning)
            return default
        return int(value)

    def flag(self, key: str, default: bool) -> bool:
        text = self.cells.get(key, "").lower()
        if not text:
            return default
        if text not in _YES:
            self.bad("tag not yes no", key=key, text=self.cells[key])
            return default
        return _YES[text]

    def address(self, kind: TagType | None) -> int | None:
        text = self.cells["address"]
        if not text:
            self.bad("tag no address")
            return None
        try:
            addr = self.symbols[text] if text in self.symbols else parse_octal(text)
        except ValueError:
            self.bad("tag bad address", text=text)
            return None
        if kind is not None:
            try:
                check_address(addr, kind)
            except AddressError as e:
                what = phrase("tag bit kind") if kind is TagType.BIT else phrase("tag value kind", kind=kind)
                self.bad("tag cannot hold", text=text, what=what, error=e)
                return None
        return addr

    def parse(self) -> tuple[Tag, TagAlarms] | None:
        ok = True
        if not self.name:
            self.bad("tag no name")
            ok = False
        elif not _NAME.fullmatch(self.name):
            self.bad("tag bad name", name=self.name)
            ok = False
        type_text = self.cells["type"].strip().lower()
        type_text = ALIASES.get(type_text, type_text)
        kind = TagType(type_text) if type_text in TYPES else None
        if kind is None:
            self.bad("tag bad type", text=self.cells["type"], types=", ".join(TagType))
            ok = False
        addr = self.address(kind)
        scaling = self.scaling(kind)
        decimals = self.whole("decimals", 0, 0, 10)
        order = self.byte_order(kind)
        alarms = self.alarms(kind, scaling)
        if not ok or addr is None or kind is None or self.problems:
            return None
        tag = Tag(self.name, addr, kind, self.cells.get("unit", ""), scaling, decimals or 0,
                  self.cells.get("description", ""), order)
        if alarms is not None:
            self.fits(tag, alarms)
        if self.problems or alarms is None:
            return None
        return tag, alarms

    def byte_order(self, kind: TagType | None) -> str:
        """How the device that fills a 32-bit tag placed its bytes (empty: NetPlc's own)."""
        text = self.cells.get("byte_order", "")
        if not text:
            return NETPLC_ORDER
        order = ORDER_LETTERS.get(text.upper(), text)
        if order not in BYTE_ORDERS:
            self.bad("tag bad order", text=text, orders=", ".join(BYTE_ORDERS),
                     letters=", ".join(ORDER_LETTERS))
        elif kind is not None and kind not in WIDE:
            self.bad("tag order narrow", kind=kind)
        return order if order in BYTE_ORDERS else NETPLC_ORDER

    def scaling(self, kind: TagType | None) -> Scaling | None:
        keys = ("app_min", "app_max", "phy_min", "phy_max")
        values = [self.number(k) for k in keys]
        given = [k for k, v in zip(keys, values, strict=True) if v is not None]
        if not given:
            return None
        if len(given) < 4:
            missing = [k for k in keys if k not in given]
            self.bad("tag scaling partial", missing=", ".join(missing))
            return None
        app_min, app_max, phy_min, phy_max = values
        if kind is TagType.BIT:
            self.bad("tag bit scaling")
            return None
        if app_min == app_max:
            self.bad("tag app undefined", value=app_min)
            return None
        if phy_min == phy_max:
            self.bad("tag phy undefined", value=phy_min)
            return None
        return Scaling(app_min, app_max, phy_min, phy_max)  # type: ignore[arg-type]

    def alarms(self, kind: TagType | None, scaling: Scaling | None) -> TagAlarms | None:
        limits = {k: self.number(k) for k in LIMIT_KEYS}
        deadband = self.number("deadband", 0.0)
        delay = self.number("delay", 0.0) or 0.0  # both ways, unless on_delay / off_delay say otherwise
        if delay < 0:
            self.bad("tag negative", key="delay", value=delay)
            delay = 0.0
        on_delay = self.number("on_delay", delay)
        off_delay = self.number("off_delay", delay)
        when = self.whole("alarm_when", None, 0, 1, phrase("tag when meaning"))
        priority = self.whole("priority", DEFAULT_PRIORITY, 1, 4, phrase("tag priority meaning"))
        latching = self.flag("latching", False)
        suppress = self.suppress_bit()
        for key, value in (("deadband", deadband), ("on_delay", on_delay), ("off_delay", off_delay)):
            if value is not None and value < 0:
                self.bad("tag negative", key=key, value=value)
        given = [(k, v) for k, v in limits.items() if v is not None]
        for (k1, v1), (k2, v2) in itertools.pairwise(given):
            if v2 < v1:
                self.bad("tag limits order", upper=k2.upper(), value=v2, lower=k1.upper(), below=v1)
        process = bool(given) or when is not None
        quality = self.flag("quality_alarm", process)
        if self.problems:
            return None
        return TagAlarms(limits["hh"], limits["h"], limits["l"], limits["ll"], deadband or 0.0,
                         on_delay or 0.0, off_delay or 0.0, when, priority or DEFAULT_PRIORITY, latching,
                         suppress, quality)

    def suppress_bit(self) -> int | None:
        text = self.cells.get("suppress_by", "")
        if not text:
            return None
        try:
            addr = self.symbols[text] if text in self.symbols else parse_octal(text)
            return parse_hmi_bit(addr).hmi
        except (ValueError, AddressError) as e:
            self.bad("tag bad suppress", text=text, error=e)
            return None

    def fits(self, tag: Tag, alarms: TagAlarms) -> None:
        """An alarm the tag's type cannot hold: limits on a bit, alarm_when on a value, a limit
        the tag can never reach."""
        if tag.type is TagType.BIT:
            if alarms.limits():
                self.bad("tag bit limits")
            return
        if alarms.alarm_when is not None:
            self.bad("tag when needs bit", type=tag.type)
        lo, hi = tag.phy_limits
        for key, value in alarms.limits():
            if not lo <= value <= hi:
                self.bad("tag limit outside", key=key, value=value, type=tag.type, lo=lo, hi=hi)
