"""The canvas view: rubber-band and Ctrl+click selection, keyboard moves, drops from the palette and
the tag browser."""

from __future__ import annotations

import logging

from PySide6.QtCore import Qt
from PySide6.QtGui import QDragEnterEvent, QDragMoveEvent, QDropEvent, QKeyEvent, QPainter, QWheelEvent
from PySide6.QtWidgets import QGraphicsView, QWidget

from app.gui.designer.design import Design
from hmi_forms.elements import ELEMENT_TYPES

logger = logging.getLogger(__name__)
ELEMENT_MIME = "application/x-netplc-element-type"
TAG_MIME = "application/x-netplc-tag"  # a tag's name, from the tag browser
ARROWS = {Qt.Key.Key_Left: (-1, 0), Qt.Key.Key_Right: (1, 0), Qt.Key.Key_Up: (0, -1), Qt.Key.Key_Down: (0, 1)}


class Canvas(QGraphicsView):
    def __init__(self, design: Design, parent: QWidget | None = None) -> None:
        super().__init__(design.scene, parent)
        self.design = design
        self.setDragMode(QGraphicsView.DragMode.RubberBandDrag)
        self.setRubberBandSelectionMode(Qt.ItemSelectionMode.IntersectsItemShape)
        self.setRenderHint(QPainter.RenderHint.Antialiasing)
        self.setViewportUpdateMode(QGraphicsView.ViewportUpdateMode.SmartViewportUpdate)
        self.setAlignment(Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignTop)
        self.setAcceptDrops(True)
        self.setFocusPolicy(Qt.FocusPolicy.StrongFocus)

    def set_design(self, design: Design) -> None:
        self.design = design
        self.setScene(design.scene)

    def home(self) -> None:
        """Show the form's top-left corner."""
        self.horizontalScrollBar().setValue(self.horizontalScrollBar().minimum())
        self.verticalScrollBar().setValue(self.verticalScrollBar().minimum())

    def keyPressEvent(self, event: QKeyEvent) -> None:
        """Arrows move the selection by a pixel (Ctrl: by a grid step); Shift+arrows resize it;
        Delete and Backspace remove it (also where the scene takes Delete before the menu's shortcut)."""
        step = ARROWS.get(Qt.Key(event.key()))
        raws = self.design.selected()
        if event.key() in (Qt.Key.Key_Delete, Qt.Key.Key_Backspace) and raws:
            self.design.delete(raws)
            event.accept()
            return
        if step is None or not raws:
            super().keyPressEvent(event)
            return
        mods = event.modifiers()
        k = self.design.grid if mods & Qt.KeyboardModifier.ControlModifier else 1
        dx, dy = step[0] * k, step[1] * k
        if mods & Qt.KeyboardModifier.ShiftModifier:
            self.design.move_by(raws, 0, 0, dx, dy)
        else:
            self.design.move_by(raws, dx, dy)
        event.accept()

    def wheelEvent(self, event: QWheelEvent) -> None:
        """Ctrl+wheel zooms; the wheel alone scrolls."""
        if event.modifiers() & Qt.KeyboardModifier.ControlModifier:
            f = 1.15 if event.angleDelta().y() > 0 else 1 / 1.15
            self.scale(f, f)
            event.accept()
            return
        super().wheelEvent(event)

    def _dragged(self, event: QDragEnterEvent | QDragMoveEvent | QDropEvent) -> tuple[str, str] | None:
        """("element", type) from the palette or ("tag", name) from the tag browser; None: neither."""
        data = event.mimeData()
        if data.hasFormat(ELEMENT_MIME):
            kind = bytes(data.data(ELEMENT_MIME).data()).decode()
            return ("element", kind) if kind in ELEMENT_TYPES else None
        if data.hasFormat(TAG_MIME):
            name = bytes(data.data(TAG_MIME).data()).decode()
            return ("tag", name) if name in self.design.doc.tags.by_name else None
        return None

    def dragEnterEvent(self, event: QDragEnterEvent) -> None:
        if self._dragged(event):
            event.acceptProposedAction()
        else:
            super().dragEnterEvent(event)

    def dragMoveEvent(self, event: QDragMoveEvent) -> None:
        if self._dragged(event):
            event.acceptProposedAction()
        else:
            super().dragMoveEvent(event)

    def dropEvent(self, event: QDropEvent) -> None:
        dragged = self._dragged(event)
        if dragged is None:
            super().dropEvent(event)
            return
        at = self.mapToScene(event.position().toPoint())
        what, name = dragged
        try:
            if what == "tag":
                self.design.add_tag(name, at)
            else:
                self.design.add(name, at)
        except ValueError:  # a tag no element shows: the browser does not let it be dragged
            logger.exception("designer: drop of %s %r refused", what, name)
            event.ignore()
            return
        event.acceptProposedAction()
        self.setFocus()
