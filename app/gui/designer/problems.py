"""The problems pane: what `check` would report for the form as it stands, a click going to the element.

The list is worked out by the loader itself on the unsaved document (`form_doc.problems`), a
moment after the last edit (so a burst of arrow-key moves costs one check, not one per step).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

from PySide6.QtCore import Qt, QTimer
from PySide6.QtWidgets import QListWidget, QListWidgetItem, QStyle, QWidget

from app.gui.designer.design import Design
from app.scada.words import TEXTS

# `element "Name"` or `element #3` in every language a problem may be said in (the station's)
_ELEMENT_WORD = "|".join(sorted({re.escape(t["form where element n"].split(" #")[0])
                                 for t in TEXTS.values()}))
ELEMENT = re.compile(rf': (?:{_ELEMENT_WORD}) (?:"(?P<name>.*?)"|#(?P<index>\d+)): ')
DELAY_MS = 250


def element_of(problem: str, elements: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The element a problem line names (by Name, or by number when it has none)."""
    m = ELEMENT.search(problem)
    if m is None:
        return None
    if m["index"] is not None:
        i = int(m["index"]) - 1
        return elements[i] if 0 <= i < len(elements) else None
    return next((e for e in elements if e.get("Name") == m["name"]), None)


class ProblemsPane(QListWidget):
    def __init__(self, design: Design, on_count: Callable[[int, int], None],
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.design = design
        self.on_count = on_count
        self.problems: list[str] = []
        self.warnings: list[str] = []
        self.timer = QTimer(self)
        self.timer.setSingleShot(True)
        self.timer.setInterval(DELAY_MS)
        self.timer.timeout.connect(self.recheck)
        self.itemClicked.connect(self.go_to)
        self.itemActivated.connect(self.go_to)

    def set_design(self, design: Design) -> None:
        self.design = design
        self.recheck()

    def schedule(self) -> None:
        self.timer.start()

    def recheck(self) -> list[str]:
        """List the problems, then the warnings (marked as such: the station opens the form all the
        same); returns the problems."""
        self.timer.stop()
        self.problems, self.warnings = self.design.checked()
        prefix = f"{self.design.doc.path}: "
        self.clear()
        warning = self.tr("warning: {0}")
        icon = self.style().standardIcon(QStyle.StandardPixmap.SP_MessageBoxWarning)
        for text in self.problems + self.warnings:
            shown = text.removeprefix(prefix)
            item = QListWidgetItem(shown)
            if text in self.warnings:
                item.setText(warning.format(shown))
                item.setIcon(icon)
            item.setData(Qt.ItemDataRole.UserRole, text)
            item.setToolTip(text)
            self.addItem(item)
        self.on_count(len(self.problems), len(self.warnings))
        self.design.flag([e for e in map(self._element, self.problems + self.warnings) if e is not None])
        return self.problems

    def _element(self, problem: str) -> dict[str, Any] | None:
        return element_of(problem, self.design.doc.elements)

    def go_to(self, item: QListWidgetItem) -> None:
        raw = self._element(item.data(Qt.ItemDataRole.UserRole))
        if raw is None:
            return
        self.design.select([raw])
        target = self.design.items[id(raw)]
        for view in self.design.scene.views():
            view.ensureVisible(target)
