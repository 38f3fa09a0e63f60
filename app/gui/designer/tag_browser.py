"""The tag browser: the station's tags, searched by name, description or unit, dragged onto the canvas.

A dropped tag becomes the element that fits its type, bound by the tag's name and with no
conversion, unit or limits of its own, so it shows what the tag is (`Design.add_tag`).
"""

from __future__ import annotations

from collections.abc import Callable

from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QLineEdit,
    QListWidgetItem,
    QVBoxLayout,
    QWidget,
)

from app.gui.designer.canvas import TAG_MIME
from app.gui.designer.design import TAG_ELEMENTS
from app.gui.designer.palette import DragList
from app.scada.table import TagTable
from app.scada.tag import Tag


def matches(tag: Tag, words: str) -> bool:
    """Every word of the search in the tag's name, description, unit or type (any case)."""
    text = f"{tag.name} {tag.description} {tag.unit} {tag.type}".casefold()
    return all(w in text for w in words.casefold().split())


class TagBrowser(QWidget):
    """`add(name)` is called for a double-clicked tag (a drop goes to the canvas)."""

    def __init__(self, tags: TagTable, add: Callable[[str], object], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.tags = tags
        self.search = QLineEdit()
        self.search.setPlaceholderText(self.tr("Search tags: name, description, unit"))
        self.search.setClearButtonEnabled(True)
        self.list = DragList(TAG_MIME, add)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.search)
        layout.addWidget(self.list)
        self.search.textChanged.connect(self.show_matching)
        self.show_matching()

    def show_matching(self, words: str = "") -> None:
        self.list.clear()
        for tag in self.tags.tags:
            if not matches(tag, words):
                continue
            unit = f", {tag.unit}" if tag.unit else ""
            item = QListWidgetItem(f"{tag.name}  {tag.description}".rstrip())
            item.setData(Qt.ItemDataRole.UserRole, tag.name)
            kind = TAG_ELEMENTS.get(tag.type)
            if kind is None:
                item.setFlags(item.flags() & ~Qt.ItemFlag.ItemIsDragEnabled)
                item.setToolTip(self.tr("{0} ({1}{2}): no form element shows this type").format(
                    tag.name, tag.type, unit))
            else:
                item.setToolTip(self.tr("{0} ({1}{2}): drag onto the form for a {3} bound to it").format(
                    tag.name, tag.type, unit, kind))
            self.list.addItem(item)
        if not self.tags.tags:
            item = QListWidgetItem(self.tr("The station has no tags (tags.csv)"))
            item.setFlags(Qt.ItemFlag.NoItemFlags)
            self.list.addItem(item)
