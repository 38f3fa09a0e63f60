"""The look shared by all element widgets: a muted high-performance-HMI palette.

Grey surfaces and dark text for the normal state, so that colour is left for what needs the
operator: amber for warnings, red for alarms, and the hatched grey of stale data. Elements that set
BackColor/ForeColor in the form override the defaults.
"""

from __future__ import annotations

import functools

from PySide6.QtCore import Qt
from PySide6.QtGui import QColor, QFont

from hmi_forms.elements.props import Color, Font

PANEL = QColor("#f4f5f7")
PANEL_DARK = QColor("#e3e6ea")
BORDER = QColor("#8a9099")
TEXT = QColor("#1a1a1a")
TEXT_DIM = QColor("#5a6270")
ACCENT = QColor("#0b3d91")  # needles, bars, trend lines
OFF = QColor("#9aa1ab")  # a bit at 0
ON = QColor("#2e7d32")  # a bit at 1
WARN = QColor("#f2a900")
ALARM = QColor("#d32f2f")
STALE = QColor("#7a808a")
FORCED = QColor("#e65100")  # an engineer's force: orange, never the grey of stale data
FAMILY = "DejaVu Sans"
MONO = "DejaVu Sans Mono"

ZONE_COLORS = {"low": WARN, "high": ALARM}
LEFT = Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter
RIGHT = Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter
WRAP = Qt.TextFlag.TextWordWrap

_ALIGN_V = {"Top": Qt.AlignmentFlag.AlignTop, "Middle": Qt.AlignmentFlag.AlignVCenter,
            "Bottom": Qt.AlignmentFlag.AlignBottom}
_ALIGN_H = {"Left": Qt.AlignmentFlag.AlignLeft, "Center": Qt.AlignmentFlag.AlignHCenter,
            "Right": Qt.AlignmentFlag.AlignRight}


def qcolor(color: Color | None, default: QColor) -> QColor:
    return default if color is None else QColor(*color)


def qfont(font: Font | None, default_size: float = 10.0, bold: bool = False) -> QFont:
    f = QFont(font.Family if font else FAMILY)
    f.setPointSizeF(font.Size if font else default_size)
    f.setBold(font.Bold if font else bold)
    f.setItalic(font.Italic if font else False)
    return f


@functools.lru_cache(maxsize=512)
def sized_font(size_px: float, bold: bool = False, family: str = FAMILY) -> QFont:
    """A font sized in pixels, for gauges whose text scales with the element (shared: do not modify)."""
    f = QFont(family)
    f.setPixelSize(max(7, round(size_px)))
    f.setBold(bold)
    return f


def alignment(name: str) -> Qt.AlignmentFlag:
    """WinForms ContentAlignment names (TopLeft ... BottomRight) as Qt flags."""
    for v, vf in _ALIGN_V.items():
        if name.startswith(v):
            return vf | _ALIGN_H[name[len(v):]]
    return Qt.AlignmentFlag.AlignCenter
