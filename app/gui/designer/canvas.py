"""The canvas view: rubber-band and Ctrl+click selection, keyboard moves, drops from the palette."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtGui import QDragEnterEvent, QDragMoveEvent, QDropEvent, QKeyEvent, QPainter, QWheelEvent
from PySide6.QtWidgets import QGraphicsView, QWidget

from app.gui.designer.design import Design
from hmi_forms.elements import ELEMENT_TYPES

ELEMENT_MIME = "application/x-netplc-element-type"
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

    def _element_drag(self, event: QDragEnterEvent | QDragMoveEvent | QDropEvent) -> str | None:
        data = event.mimeData()
        if not data.hasFormat(ELEMENT_MIME):
            return None
        kind = bytes(data.data(ELEMENT_MIME).data()).decode()
        return kind if kind in ELEMENT_TYPES else None

    def dragEnterEvent(self, event: QDragEnterEvent) -> None:
        if self._element_drag(event):
            event.acceptProposedAction()
        else:
            super().dragEnterEvent(event)

    def dragMoveEvent(self, event: QDragMoveEvent) -> None:
        if self._element_drag(event):
            event.acceptProposedAction()
        else:
            super().dragMoveEvent(event)

    def dropEvent(self, event: QDropEvent) -> None:
        kind = self._element_drag(event)
        if kind is None:
            super().dropEvent(event)
            return
        self.design.add(kind, self.mapToScene(event.position().toPoint()))
        event.acceptProposedAction()
        self.setFocus()
