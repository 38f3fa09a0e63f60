"""Every change of the designer's document as an undoable command (QUndoStack).

Commands touch the document only through `Design`, which keeps the canvas in step, so undo and
redo redraw exactly what they change. A property that was absent is restored as absent (`MISSING`),
so undo gives back the very file that was read.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from PySide6.QtGui import QUndoCommand

if TYPE_CHECKING:
    from app.gui.designer.design import Design

MISSING: Any = object()  # "no such key" as a property value: setting it removes the key
NUDGE_ID = 1  # arrow-key moves of the same elements merge into one step


class SetProps(QUndoCommand):
    """New values for properties of elements, or of the form (`target` is then the form's dict)."""

    def __init__(self, design: Design, changes: list[tuple[dict[str, Any], dict[str, Any]]], text: str,
                 merge: int = -1) -> None:
        super().__init__(text)
        self.design = design
        self.new = changes
        self.old = [(target, {k: target.get(k, MISSING) for k in values}) for target, values in changes]
        self.merge = merge

    def id(self) -> int:
        return self.merge

    def mergeWith(self, other: QUndoCommand) -> bool:
        if not isinstance(other, SetProps) or other.merge != self.merge:
            return False
        if [id(t) for t, _ in other.new] != [id(t) for t, _ in self.new]:
            return False
        self.new = other.new
        return True

    def redo(self) -> None:
        self.design.apply(self.new)

    def undo(self) -> None:
        self.design.apply(self.old)


class Insert(QUndoCommand):
    """New elements (added, pasted, dropped) at the top of the z-order."""

    def __init__(self, design: Design, raws: list[dict[str, Any]], text: str) -> None:
        super().__init__(text)
        self.design = design
        self.raws = raws

    def redo(self) -> None:
        n = len(self.design.doc.elements)
        self.design.insert([(n + i, raw) for i, raw in enumerate(self.raws)])

    def undo(self) -> None:
        self.design.remove(self.raws)


class Remove(QUndoCommand):
    def __init__(self, design: Design, raws: list[dict[str, Any]], text: str) -> None:
        super().__init__(text)
        self.design = design
        index = {id(r): i for i, r in enumerate(design.doc.elements)}
        self.at = sorted((index[id(raw)], raw) for raw in raws)

    def redo(self) -> None:
        self.design.remove([raw for _, raw in self.at])

    def undo(self) -> None:
        self.design.insert(self.at)


class Reorder(QUndoCommand):
    """A new z-order (file order: later elements are drawn over earlier ones, as the runtime does)."""

    def __init__(self, design: Design, order: list[dict[str, Any]], text: str) -> None:
        super().__init__(text)
        self.design = design
        self.before = list(design.doc.elements)
        self.after = order

    def redo(self) -> None:
        self.design.reorder(self.after)

    def undo(self) -> None:
        self.design.reorder(self.before)
