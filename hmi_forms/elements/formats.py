"""The one time format and the one date format of the console (docs/architecture.md section 9).

Times were written three ways (07:30:44, 07.30.44, 07:30:39.171); now every clock, journal,
banner and cursor shows HH:MM:SS, with milliseconds only in the archive tables, where the order
of records within a second matters. The date follows the console's language: DD.MM.YYYY in
Russian, YYYY-MM-DD (ISO 8601, read the same everywhere) in English. Qt-free: form models format
their own clocks.
"""

from __future__ import annotations

import datetime as dt

TIME = "%H:%M:%S"
DATES = {"ru": "%d.%m.%Y", "en": "%Y-%m-%d"}
QT_DATES = {"ru": "dd.MM.yyyy", "en": "yyyy-MM-dd"}  # the same, for Qt's date pickers
_language = "ru"


def set_language(language: str) -> None:
    global _language
    _language = language if language in DATES else "ru"


def qt_date() -> str:
    """The date picker's format: its dates read as the journal's beside it."""
    return QT_DATES[_language]


def clock(ts: float, tz: dt.tzinfo | None = None) -> str:
    """The wall clock of `ts` in `tz` (an archive's zone; None: this machine's)."""
    return dt.datetime.fromtimestamp(ts, tz).strftime(TIME)


def clock_ms(ts: float, tz: dt.tzinfo | None = None) -> str:
    return f"{clock(ts, tz)}.{int(ts * 1000) % 1000:03d}"


def date(day: dt.date | float) -> str:
    if isinstance(day, float | int):
        day = dt.date.fromtimestamp(day)
    return day.strftime(DATES[_language])


def date_time(ts: float) -> str:
    return f"{date(ts)}  {clock(ts)}"
