"""The property editor: the properties of the selected element(s), or of the form when none is.

Properties are listed in the file's order (form_writer) with an editor for their kind (editors.py).
With several elements selected, the properties they share are shown; a field whose values differ
shows none, and an edit sets it on all of them as one undo step. A value is refused, with the
reason, when it would add a problem to any of the elements (the loader's own words: a bad
address, an unknown symbol, PhyMax equal to PhyMin, a Phase not below its Period, a taken Name).
"""

from __future__ import annotations

import copy
from dataclasses import fields, replace
from typing import Any

from PySide6.QtGui import QShowEvent
from PySide6.QtWidgets import QFormLayout, QLabel, QScrollArea, QVBoxLayout, QWidget

from app.gui.designer.commands import MISSING
from app.gui.designer.design import Design
from app.gui.designer.editors import (
    BoolEditor,
    ColorEditor,
    ComboEditor,
    Editor,
    FontEditor,
    LineEditor,
    choices,
    kind_of,
)
from hmi_forms.elements import ELEMENT_TYPES, Element
from hmi_forms.form import FORM_PROPS
from hmi_forms.form_doc import FormDoc, problems
from hmi_forms.form_writer import element_keys

FORM_SECTIONS = ("devices", "images")  # edited as JSON in the form's properties
ADD_IMAGE = "add image"  # an image index editor's pick of a picture not yet in the form's list


def field_parsers(kind: str) -> dict[str, Any]:
    """Property name (and alias) -> parser, for one element type."""
    out: dict[str, Any] = {}
    for f in fields(ELEMENT_TYPES.get(kind, Element)):
        if "parser" in f.metadata:
            out[f.name] = f.metadata["parser"]
            if f.metadata["alias"]:
                out[f.metadata["alias"]] = f.metadata["parser"]
    return out


def shown_keys(raw: dict[str, Any]) -> list[str]:
    """The properties to offer for an element: every one of its type (an alias only where the file
    uses it instead of the property) and any unknown key it has, so it can be fixed or cleared."""
    kind = raw.get("type") if isinstance(raw.get("type"), str) else ""
    aliases = {f.metadata["alias"]: f.name for f in fields(ELEMENT_TYPES.get(kind, Element))
               if "parser" in f.metadata and f.metadata["alias"]}
    keys = []
    for key in element_keys(kind):  # type: ignore[arg-type]
        if key == "type":
            continue
        if key in aliases:
            if key in raw and aliases[key] not in raw:
                keys[keys.index(aliases[key])] = key
            continue
        keys.append(key)
    return keys + [k for k in raw if k not in keys and k not in aliases and k != "type"]


class PropertyPanel(QWidget):
    def __init__(self, design: Design, names: list[str], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.design = design
        self.names = names
        self.targets: list[dict[str, Any]] = []
        self._editors: dict[str, Editor] = {}
        self._key: tuple[object, ...] | None = None
        self._stale = False  # the selection changed while the panel was not seen: shown when it is
        # the editors made for a kind of selection, kept to be filled again when another selection
        # of the same kind (type and properties) is shown: building them is most of a click's time
        self._panels: dict[tuple[object, ...], tuple[QWidget, dict[str, Editor]]] = {}
        self._offered: tuple[str, str] | None = None
        self.title = QLabel()
        self.title.setWordWrap(True)
        self.title.setStyleSheet("font-weight: bold; padding: 4px;")
        self.scroll = QScrollArea()
        self.scroll.setWidgetResizable(True)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.title)
        layout.addWidget(self.scroll)

    def set_design(self, design: Design) -> None:
        self.design = design
        self._key = None
        self._forget_panels()  # another form: its own pictures and devices to offer
        self.show_selection()

    @property
    def form_mode(self) -> bool:
        return not self.targets or self.targets[0] is self.design.doc.settings

    @property
    def editors(self) -> dict[str, Editor]:
        """The editors of the selection's properties (made now if the panel was not seen yet)."""
        self._catch_up()
        return self._editors

    def show_selection(self) -> None:
        """Show the editors of another selection (or of what the editors offer changing) from the
        top, now if the panel is seen, else when it is (a window not shown yet, a closed dock); for
        the same selection only refresh their values."""
        raws = self.design.selected()
        offered = (str(self.design.doc.data.get("images")), str(self.design.doc.data.get("devices")))
        key = (*(id(r) for r in raws), *(str(r.get("type")) for r in raws), *offered)
        if key == self._key:
            self.refresh()
            return
        self._key = key
        if offered != self._offered:  # the image and device pickers offer other entries now
            self._forget_panels()
            self._offered = offered
        self.targets = raws or [self.design.doc.settings]
        self._stale = True
        if self.isVisible():
            self._catch_up()
        else:
            self.refresh()  # the title

    def showEvent(self, event: QShowEvent) -> None:
        self._catch_up()
        super().showEvent(event)

    def _catch_up(self) -> None:
        if not self._stale:
            return
        self._stale = False
        self._show([] if self.form_mode else self.targets)
        self.scroll.verticalScrollBar().setValue(0)

    def _forget_panels(self) -> None:
        shown = self.scroll.takeWidget()  # the scroll area would delete it when given the next
        if shown is not None:
            shown.setParent(self)
            shown.hide()
        for body, _ in self._panels.values():
            body.deleteLater()
        self._panels.clear()

    def _show(self, raws: list[dict[str, Any]]) -> None:
        """The editors of the selection's kind: those made for an earlier selection of the same type
        and properties when there are (each editor's set_value leaves it as a new one), else new."""
        keys, parsers = self._offer(raws)
        kind = (str(raws[0].get("type")) if raws else None, *keys)
        if kind not in self._panels:
            self._panels[kind] = self._build(keys, parsers)
        body, self._editors = self._panels[kind]
        if self.scroll.widget() is not body:
            shown = self.scroll.takeWidget()
            if shown is not None:
                shown.setParent(self)  # kept, hidden, for the next selection of its kind
                shown.hide()
            self.scroll.setWidget(body)
            body.show()
        self.refresh()

    def _offer(self, raws: list[dict[str, Any]]) -> tuple[list[str], dict[str, Any]]:
        """The properties to edit for `raws` (the form's when empty), and their parsers."""
        if raws:
            keys = shown_keys(raws[0])
            for raw in raws[1:]:
                theirs = set(shown_keys(raw))
                keys = [k for k in keys if k in theirs]
            if len(raws) > 1:
                keys = [k for k in keys if k != "Name"]
            parsers = field_parsers(str(raws[0].get("type")))
        else:
            keys = [*FORM_PROPS, *FORM_SECTIONS]
            parsers = dict(FORM_PROPS)
        return keys, parsers

    def _build(self, keys: list[str], parsers: dict[str, Any]) -> tuple[QWidget, dict[str, Editor]]:
        body = QWidget()
        form = QFormLayout(body)
        form.setFieldGrowthPolicy(QFormLayout.FieldGrowthPolicy.AllNonFixedFieldsGrow)
        editors: dict[str, Editor] = {}
        for k in keys:
            editor = self._editor(k, parsers.get(k))
            editor.edited.connect(lambda value, k=k: self.commit(k, value))
            editors[k] = editor
            label = QLabel(k)
            label.setToolTip(f"{k}: {kind_of(parsers[k]) if k in parsers else 'JSON'}")
            form.addRow(label, editor)
        return body, editors

    def _editor(self, key: str, parser: Any) -> Editor:
        def check(value: Any, key: str = key) -> str | None:
            return self.refusal(key, value)

        kind = kind_of(parser) if parser is not None else "json"
        if kind == "address":
            return LineEditor(kind, check, self.names)
        if kind == "bool":
            return BoolEditor(check)
        if kind == "color":
            return ColorEditor(check)
        if kind == "font":
            return FontEditor(check)
        if kind == "choice":
            return ComboEditor([(c, c) for c in choices(parser)], check)
        if kind == "image_file":
            return ComboEditor([(f, f) for f in self.design.image_files()], check, editable=True)
        if kind == "image_index":  # the form's pictures, and those of its folder it may take in
            images = self._images()
            options = [("-1: none", -1)] + [(f"{i}: {name}", i) for i, name in enumerate(images)]
            options += [(f"+ {name}", (ADD_IMAGE, name)) for name in self.design.image_files()
                        if name not in images]
            return ComboEditor(options, check)
        if kind == "text" and key == "Device":
            return ComboEditor([(d, d) for d in self.design.reader.ctx.devices], check, editable=True)
        return LineEditor(kind, check)

    def refresh(self) -> None:
        """Show the targets' current values (after an edit, an undo, a move)."""
        t = self.targets
        one = f'{t[0].get("type")} "{t[0].get("Name")}"'
        self.title.setText(self.tr("Form {0}").format(self.design.doc.path.name) if self.form_mode else
                           one if len(t) == 1 else self.tr("{0} elements").format(len(t)))
        if self._stale:
            return  # the editors are made and filled when the panel is seen
        for key, editor in self._editors.items():
            values = [self._source(t, key).get(key, MISSING) for t in self.targets]
            mixed = any(v != values[0] for v in values[1:])
            editor.set_value(values[0], mixed)

    def _source(self, target: dict[str, Any], key: str) -> dict[str, Any]:
        return self.design.doc.data if self.form_mode and key in FORM_SECTIONS else target

    def refusal(self, key: str, value: Any) -> str | None:
        """Why setting `key` to `value` on every target is refused; None: accepted."""
        design = self.design
        if isinstance(value, tuple):  # (ADD_IMAGE, file): a picture of the form's folder, listed
            return None
        if self.form_mode:
            return _form_refusal(design.doc, design.symbols, key, value)
        if key == "Name":
            others = {r.get("Name") for r in design.doc.elements if r is not self.targets[0]}
            if value in others:
                return f'Name: "{value}" is taken by another element'
        for raw in self.targets:
            after = dict(raw)
            if value is MISSING:
                after.pop(key, None)
            else:
                after[key] = value
            reason = design.reader.refusal(raw, after)
            if reason:
                return reason
        return None

    def commit(self, key: str, value: Any) -> None:
        editor = self.editors.get(key)
        reason = self.refusal(key, value)
        if editor is not None:
            editor.refuse(reason)
        if reason:
            return
        targets = [self._source(t, key) for t in self.targets]
        if isinstance(value, tuple):
            self._add_image(key, value[1], targets)
            return
        named = self.design.named_by_tag(targets[0], key, value) if len(targets) == 1 else {}
        self.design.set_props([(t, {key: value, **named}) for t in targets], f"Set {key}")

    def _images(self) -> list[Any]:
        """The form's images list (none while the section is not a list: a problem to fix first)."""
        images = self.design.doc.data.get("images", [])
        return list(images) if isinstance(images, list) else []

    def _add_image(self, key: str, name: str, targets: list[dict[str, Any]]) -> None:
        """Append a picture to the form's images and point `key` at it, as one undo step."""
        design = self.design
        images = self._images()
        design.undo.beginMacro(f"Set {key}")
        design.set_props([(design.doc.data, {"images": [*images, name]})], "Add image")
        design.set_props([(t, {key: len(images)}) for t in targets], f"Set {key}")
        design.undo.endMacro()


def _form_refusal(doc: FormDoc, symbols: dict[str, int], key: str, value: Any) -> str | None:
    """A form setting, device list or image list is refused when it adds a problem to the form."""
    after = replace(doc, data=copy.deepcopy(doc.data))
    target = after.data if key in FORM_SECTIONS else after.settings
    if value is MISSING:
        target.pop(key, None)
    else:
        target[key] = value
    old = set(problems(doc, symbols))
    new = [t for t in problems(after, symbols) if t not in old]
    return new[0].split(": ", 1)[-1] if new else None
