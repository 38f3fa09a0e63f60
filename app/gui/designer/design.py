"""The form being designed: its document, the canvas items that draw it, and the undo stack.

Every edit goes through a command (commands.py) that calls back here, so the document, the canvas
and the undo history never disagree. Elements are known by their dict in the document (`id(raw)`),
which survives renames, moves and z-order changes.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

from PySide6.QtCore import QObject, QPointF, QRectF, Signal
from PySide6.QtGui import QUndoStack

from app.gui.designer.arrange import Z_ORDERS, aligned, box, distributed, number, restacked
from app.gui.designer.commands import MISSING, NUDGE_ID, Insert, Remove, Reorder, SetProps
from app.gui.designer.items import ElementItem
from app.gui.designer.scene import FormScene
from app.scada.tag import TagType
from hmi_forms.elements import ELEMENT_TYPES, Element
from hmi_forms.form_doc import FormDoc, Reader, checked, image_files
from hmi_forms.form_writer import save_form
from hmi_forms.widgets.base import ElementWidget, Images
from hmi_forms.widgets.form_view import FormView
from netplc.memory import Snapshot

GRID = 8
# the size a new element gets, and the properties it needs that have a sensible default
NEW_SIZE = {"SyncGenerator": (195, 72), "SyncTimer": (195, 72), "AnalogBase": (250, 200),
            "AnalogOutput": (280, 110), "StaticPicture": (120, 120), "StaticText": (240, 36),
            "Graph": (500, 160), "MessageJournal": (600, 260), "DateTime": (195, 100)}
STATES = {"TextFalse": "0", "TextTrue": "1"}
NEW_PROPS: dict[str, dict[str, Any]] = {
    "DiscreteBase": STATES, "DiscreteColorLabel": STATES, "DiscreteControlledEnable": STATES,
    "DiscreteAnimation": {**STATES, "ImageFirst": -1, "ImageLast": -1},
    "StaticText": {"Text": "Text"},
    "AnalogBase": {"Appearance": "digital"},  # no conversion of its own: its tag's (Scaled.take_tag)
}
# the element a tag dropped from the tag browser becomes (the types the elements' addresses take)
TAG_ELEMENTS = {TagType.BIT: "DiscreteBase", TagType.WORD: "AnalogBase"}


class Design(QObject):
    """Its signals forward those of its scene and undo stack, so whoever listens is disconnected
    before those children go (Qt drops a receiver's connections before deleting its children)."""

    changed = Signal()  # the document changed (problems, title, properties follow it)
    selection_changed = Signal()
    clean_changed = Signal(bool)

    def __init__(self, doc: FormDoc, symbols: dict[str, int], archive: Path | None = None,
                 parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.symbols = symbols
        self.archive = archive
        self.grid = GRID
        self.grid_visible = True
        self.snapping = True
        self.undo = QUndoStack(self)
        self.scene = FormScene(self)
        self.undo.cleanChanged.connect(self.clean_changed)
        self.scene.selectionChanged.connect(self.selection_changed)
        self.reader = Reader(doc, symbols)
        self.images = Images(self.reader.ctx.images)
        self.items: dict[int, ElementItem] = {}
        self.snapshot = self._first_snapshot()
        for raw in doc.elements:
            self._add_item(raw)
        self.restack()
        self._fit_scene()

    @staticmethod
    def _first_snapshot() -> Snapshot:
        """All memory 0 at the current time: what the workstation shows before the first scan."""
        empty = Snapshot.empty()
        return Snapshot(empty.bits, empty.data, 0, time.monotonic(), time.time(), "design")

    # --- reading the document -------------------------------------------------------------------

    def widget_for(self, model: Element) -> ElementWidget:
        return FormView.element_widget(model, self.images, self.archive)

    def form_rect(self) -> QRectF:
        s = self.doc.settings
        w, h = s.get("width"), s.get("height")
        return QRectF(0, 0, w if isinstance(w, int) and w > 0 else 800,
                      h if isinstance(h, int) and h > 0 else 600)

    def _fit_scene(self) -> None:
        self.scene.setSceneRect(self.form_rect().adjusted(-40, -40, 40, 40)
                                .united(self.scene.itemsBoundingRect().adjusted(-40, -40, 40, 40)))
        self.scene.update()

    def _add_item(self, raw: dict[str, Any]) -> ElementItem:
        item = ElementItem(self, raw)
        self.items[id(raw)] = item
        self.scene.addItem(item)
        return item

    def item(self, raw: dict[str, Any]) -> ElementItem:
        return self.items[id(raw)]

    def checked(self) -> tuple[list[str], list[str]]:
        """What `check` would report: the problems, and the warnings."""
        return checked(self.doc, self.symbols)

    def image_files(self) -> list[str]:
        return image_files(self.doc.path.parent)

    def flag(self, raws: list[dict[str, Any]]) -> None:
        """Outline in red the elements the problems pane names (also problems between an element and
        the form, such as reaching past its edge, which reading the element alone cannot see)."""
        named = {id(r) for r in raws}
        for key, item in self.items.items():
            item.set_flagged(key in named)

    def selected(self) -> list[dict[str, Any]]:
        """The selected elements in z-order."""
        chosen = {id(i.raw) for i in self.scene.selectedItems() if isinstance(i, ElementItem)}
        return [raw for raw in self.doc.elements if id(raw) in chosen]

    def select(self, raws: list[dict[str, Any]]) -> None:
        """Select `raws`, said once (the scene says each item's change: as many panels shown)."""
        before = [id(r) for r in self.selected()]
        self.blockSignals(True)
        try:
            self.scene.clearSelection()
            for raw in raws:
                if id(raw) in self.items:
                    self.items[id(raw)].setSelected(True)
        finally:
            self.blockSignals(False)
        if [id(r) for r in self.selected()] != before:
            self.selection_changed.emit()

    # --- changing it (called by the commands) ---------------------------------------------------

    def apply(self, changes: list[tuple[dict[str, Any], dict[str, Any]]]) -> None:
        whole = False
        for target, values in changes:
            for key, value in values.items():
                if value is MISSING:
                    target.pop(key, None)
                else:
                    target[key] = value
            if target is self.doc.data:  # devices or images: every element may read differently
                whole = True
            elif id(target) in self.items:
                item = self.items[id(target)]
                if set(values) <= {"x", "y"} and not item.problems:
                    item.place()
                else:
                    item.rebuild()
        if whole:
            self.reader = Reader(self.doc, self.symbols)
            self.images = Images(self.reader.ctx.images)
            for item in self.items.values():
                item.rebuild()
        self._fit_scene()
        self.changed.emit()

    def insert(self, at: list[tuple[int, dict[str, Any]]]) -> None:
        for index, raw in sorted(at, key=lambda t: t[0]):
            self.doc.elements.insert(index, raw)
            self._add_item(raw)
        self.restack()
        self._fit_scene()
        self.changed.emit()

    def remove(self, raws: list[dict[str, Any]]) -> None:
        gone = {id(r) for r in raws}
        self.doc.elements[:] = [r for r in self.doc.elements if id(r) not in gone]
        for key in gone:
            item = self.items.pop(key)
            self.scene.removeItem(item)
            if item.widget is not None:
                item.widget.deleteLater()
        self.changed.emit()

    def reorder(self, order: list[dict[str, Any]]) -> None:
        self.doc.elements[:] = order
        self.restack()
        self.changed.emit()

    def restack(self) -> None:
        for i, raw in enumerate(self.doc.elements):
            self.items[id(raw)].setZValue(i)

    # --- edits (each one undoable step) ---------------------------------------------------------

    def snap(self, v: float) -> float:
        return round(v / self.grid) * self.grid if self.snapping and self.grid > 1 else round(v)

    def snap_point(self, point: QPointF) -> QPointF:
        return QPointF(max(0.0, self.snap(point.x())), max(0.0, self.snap(point.y())))

    def set_props(self, changes: list[tuple[dict[str, Any], dict[str, Any]]], text: str,
                  merge: int = -1) -> None:
        changes = [(t, v) for t, v in changes if any(t.get(k, MISSING) != x for k, x in v.items())]
        if changes:
            self.undo.push(SetProps(self, changes, text, merge))

    def set_geometry(self, geometry: dict[int, tuple[int, int, int, int]], text: str,
                     merge: int = -1) -> None:
        raws = {id(r): r for r in self.doc.elements}
        self.set_props([(raws[k], dict(zip(("x", "y", "w", "h"), g))) for k, g in geometry.items()],
                       text, merge)

    def snap_selection(self) -> None:
        """While the selection is dragged: each element onto the grid (and not off the form's left
        or top). Done here rather than in itemChange, which every item would run for every change."""
        for item in self.scene.selectedItems():
            item.setPos(self.snap_point(item.pos()))

    def commit_moves(self) -> None:
        """After a mouse drag: the moved elements' new places as one step."""
        moved = []
        for raw in self.selected():
            pos = self.items[id(raw)].pos()
            x, y = round(pos.x()), round(pos.y())
            if (x, y) != (raw.get("x"), raw.get("y")):
                moved.append((raw, {"x": x, "y": y}))
        self.set_props(moved, f"Move {len(moved)} element(s)")

    def move_by(self, raws: list[dict[str, Any]], dx: int, dy: int, dw: int = 0, dh: int = 0) -> None:
        """Arrow keys: move (or with dw/dh resize) by a step; repeated presses merge into one undo step."""
        changes = []
        for raw in raws:
            x, y, w, h = box(raw)
            changes.append((raw, {"x": max(0, x + dx), "y": max(0, y + dy),
                                  "w": max(1, w + dw), "h": max(1, h + dh)}))
        self.set_props(changes, "Resize" if dw or dh else "Move", NUDGE_ID)

    def unique_name(self, base: str, taken: set[str] | None = None) -> str:
        names = {r.get("Name") for r in self.doc.elements} | (taken or set())
        if base not in names:
            return base
        stem = base.rstrip("0123456789").rstrip() or base
        n = 1
        while f"{stem} {n}" in names:
            n += 1
        return f"{stem} {n}"

    def new_element(self, kind: str, x: float, y: float) -> dict[str, Any]:
        w, h = NEW_SIZE.get(kind, (195, 44))
        point = self.snap_point(QPointF(x, y))
        raw: dict[str, Any] = {"type": kind, "Name": self.unique_name(kind), "x": int(point.x()),
                               "y": int(point.y()), "w": w, "h": h, **NEW_PROPS.get(kind, {})}
        if kind == "StaticPicture":
            files = self.image_files()
            if files:
                raw["Image"] = files[0]
        return raw

    def add(self, kind: str, at: QPointF | None = None, props: dict[str, Any] | None = None,
            text: str = "") -> dict[str, Any]:
        """Edit -> Add element: a new element of `kind` (with `props`), selected (at `at`, else near
        the top left)."""
        if kind not in ELEMENT_TYPES:
            raise ValueError(f"unknown element type {kind!r}")
        if at is None:
            n = len(self.doc.elements) % 20
            at = QPointF(16 + n * self.grid * 2, 16 + n * self.grid * 2)
        raw = {**self.new_element(kind, at.x(), at.y()), **(props or {})}
        self.undo.push(Insert(self, [raw], text or f"Add {kind}"))
        self.select([raw])
        return raw

    def add_tag(self, name: str, at: QPointF | None = None) -> dict[str, Any]:
        """A tag dropped from the tag browser: the element fitting its type, named by the tag's
        description, bound by the tag's name and with nothing of its own that the tag gives
        (conversion, unit, decimals, limits), so it shows the tag's truth."""
        tag = self.doc.tags.get(name)
        kind = TAG_ELEMENTS.get(tag.type) if tag is not None else None
        if tag is None or kind is None:
            raise ValueError(f"no element shows tag {name!r}")
        raw = self.add(kind, at, {"Name": self.unique_name(tag.description or tag.name), "InAddr": tag.name},
                       f"Add {kind} of {tag.name}")
        return raw

    def named_by_tag(self, raw: dict[str, Any], key: str, value: Any) -> dict[str, Any]:
        """Binding an element that still has its type's name (`AnalogBase 2`) to a tag also names it
        by the tag's description, as a tag dropped from the browser is: its face and the operator's
        confirmations then say what it shows. {} for anything else."""
        tag = self.doc.tags.get(value) if isinstance(value, str) else None
        kind = raw.get("type")
        stem = str(raw.get("Name", "")).rstrip("0123456789").rstrip()
        if tag is None or key not in Element.ADDRESS_KEYS or stem not in ("", kind):
            return {}
        return {"Name": self.unique_name(tag.description or tag.name)}

    def delete(self, raws: list[dict[str, Any]]) -> None:
        if raws:
            self.undo.push(Remove(self, raws, f"Delete {len(raws)} element(s)"))

    def copy_text(self, raws: list[dict[str, Any]]) -> str:
        return json.dumps(raws, ensure_ascii=False)

    def paste_text(self, text: str) -> list[dict[str, Any]]:
        """Paste elements copied as JSON (from this designer or a form file), renamed where the name
        is taken and moved by one grid step so they do not hide their originals."""
        try:
            data = json.loads(text)
        except json.JSONDecodeError:
            return []
        data = data if isinstance(data, list) else [data]
        raws: list[dict[str, Any]] = []
        taken: set[str] = set()
        for el in data:
            if not isinstance(el, dict) or el.get("type") not in ELEMENT_TYPES:
                continue
            raw = dict(el)
            raw["Name"] = name = self.unique_name(str(el.get("Name", el["type"])), taken)
            taken.add(name)
            for k in ("x", "y"):
                raw[k] = number(el.get(k), 0) + self.grid
            raws.append(raw)
        if raws:
            self.undo.push(Insert(self, raws, f"Paste {len(raws)} element(s)"))
            self.select(raws)
        return raws

    def align(self, how: str) -> None:
        """Align the selected elements (arrange.aligned)."""
        raws = self.selected()
        if len(raws) > 1:
            boxes = aligned([box(r) for r in raws], how)
            self.set_geometry({id(r): b for r, b in zip(raws, boxes)}, f"Align {how}")

    def distribute(self, axis: str) -> None:
        """Equal gaps between the selected elements (arrange.distributed)."""
        raws = self.selected()
        if len(raws) > 2:
            boxes = distributed([box(r) for r in raws], axis)
            self.set_geometry({id(r): b for r, b in zip(raws, boxes)}, "Distribute")

    def z_order(self, how: str) -> None:
        """front, back, raise (one step up), lower (one step down): arrange.restacked."""
        ids = {id(r) for r in self.selected()}
        order = restacked(self.doc.elements, lambda r: id(r) in ids, how)
        if [id(r) for r in order] != [id(r) for r in self.doc.elements]:
            self.undo.push(Reorder(self, order, Z_ORDERS[how]))

    def save(self, path: Path | None = None) -> Path:
        """Write the form (to `path`: save as); OSError leaves the document as it was."""
        target = Path(path) if path is not None else self.doc.path
        save_form(self.doc.data, target)
        self.doc.path = target
        self.undo.setClean()
        return target

    def show_snapshot(self, snap: Snapshot) -> None:
        """Live preview: every element reads the station's memory as the workstation would."""
        self.snapshot = snap
        for item in self.items.values():
            item.show_snapshot(snap)

