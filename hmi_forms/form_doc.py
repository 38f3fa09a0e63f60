"""A form as the designer edits it: the file's JSON document, read by the same loader as the runtime.

The document (not the models) is what gets edited and saved, so a value keeps the spelling its
author chose and an untouched form saves unchanged (`form_writer`). The loader reads it for two
purposes: `problems` lists exactly what `check` would report for the file, and `Reader` gives
the model each element's widget draws and says why an edit is refused. An element with a problem
is still drawn, from the properties that are good (each bad or missing one at its default), so a
form being built shows what it will show.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from app.scada.table import TagTable
from app.scada.words import phrase, words
from hmi_forms.elements import ELEMENT_TYPES, Element
from hmi_forms.elements import props as p
from hmi_forms.form import FormError, _Loader, not_a_form, parse_form
from hmi_forms.form_writer import dump_form, save_form

# What a required property stands in with while it is missing or bad, for drawing only.
PLACEHOLDERS: dict[Any, Any] = {p.bit: "00000", p.word: "04000", p.image_index: -1}
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".gif", ".svg")


@dataclass
class FormDoc:
    path: Path
    data: dict[str, Any] = field(default_factory=dict)  # the file's JSON object
    station: Path | None = None  # the station folder: images may come from it as well as the form's
    allow_outside: bool = False  # the station lets paths leave its folder
    tags: TagTable = field(default_factory=TagTable)  # the station's: their conversion, unit, limits
    language: str = ""  # the station's Language, its problems are said in ("": the system locale's)

    @property
    def settings(self) -> dict[str, Any]:
        return self.data.setdefault("form", {})

    @property
    def elements(self) -> list[dict[str, Any]]:
        return self.data.setdefault("elements", [])

    def text(self) -> str:
        return dump_form(self.data)


def new_doc(path: str | Path, width: int = 960, height: int = 540) -> FormDoc:
    return FormDoc(Path(path), {"form": {"title": Path(path).stem, "width": width, "height": height},
                                "elements": []})


def read_doc(path: str | Path) -> FormDoc:
    """The document of a form file; FormError when it cannot be edited at all (not JSON, no list
    of element objects). Every other problem is the problems pane's."""
    path = Path(path)
    data = parse_form(path, parse_int=int)  # plain ints: the writer saves what it read
    if not isinstance(data, dict):
        raise not_a_form(str(path), phrase("form not object"))
    elements = data.get("elements", [])
    if not isinstance(elements, list) or not all(isinstance(e, dict) for e in elements):
        raise not_a_form(str(path), phrase("form elements not list"))
    if not isinstance(data.get("form", {}), dict):
        raise not_a_form(str(path), phrase("form settings not object"))
    return FormDoc(path, data)


def _loader(doc: FormDoc, symbols: dict[str, int]) -> _Loader:
    """The loader of the document's station, saying its problems in the station's language."""
    return _Loader(doc.path, symbols, doc.station, doc.allow_outside, doc.tags, words(doc.language))


def problems(doc: FormDoc, symbols: dict[str, int]) -> list[str]:
    """What `check` would report for this document if it were saved now."""
    return checked(doc, symbols)[0]


def checked(doc: FormDoc, symbols: dict[str, int]) -> tuple[list[str], list[str]]:
    """What `check` would report for this document if it were saved now: its problems, and its
    warnings (an element whose conversion or unit contradicts its tag's)."""
    loader = _loader(doc, symbols)
    try:
        loader.build(json.loads(json.dumps(doc.data)))
    except FormError as e:
        return e.problems, loader.warnings
    return [], loader.warnings


class Reader:
    """The loader bound to one state of a document's devices and images, reading elements one by one
    (the designer re-reads only the element an edit touched)."""

    def __init__(self, doc: FormDoc, symbols: dict[str, int]) -> None:
        self.path = doc.path
        self.symbols = symbols
        self.loader = _loader(doc, symbols)
        self.loader.ctx.devices = self.loader.devices(doc.data.get("devices", []))
        self.loader.ctx.images = self.loader.images(doc.data.get("images", []))
        self.ctx = self.loader.ctx

    def element(self, raw: dict[str, Any]) -> tuple[Element | None, list[str]]:
        """The model of one element and its problems, as the loader reports them."""
        self.loader.problems = []
        model = self.loader.element(self._where(raw), raw)
        return model, self.loader.problems

    def _where(self, raw: dict[str, Any]) -> str:
        name = raw.get("Name")
        say = self.loader.say  # the loader's words, so that its problems are found by their place
        return say("form where element", name=name) if isinstance(name, str) else say("form where an element")

    def _props(self, raw: dict[str, Any], found: list[str]) -> list[tuple[str, str]]:
        """The loader's problems of one element as (property, problem)."""
        head = f"{self.path}: {self._where(raw)}: "
        return [tuple(t[len(head):].split(": ", 1)) for t in found  # type: ignore[misc]
                if t.startswith(head) and ": " in t[len(head):]]

    def drawable(self, raw: dict[str, Any]) -> tuple[Element | None, list[str]]:
        """The model to draw: bad and missing properties at their defaults. None: unknown type."""
        model, found = self.element(raw)
        cls = ELEMENT_TYPES.get(raw.get("type"))  # type: ignore[arg-type]
        if model is not None or cls is None:
            return model, found
        bad = {key for key, _ in self._props(raw, found)}
        kept = {k: v for k, v in raw.items() if k not in bad}
        for f in fields(cls):
            if f.metadata.get("required") and f.name not in kept and f.metadata["alias"] not in kept:
                kept[f.name] = PLACEHOLDERS.get(f.metadata["parser"], f.default)
        model, _ = self.element(kept)
        return model, found

    def refusal(self, before: dict[str, Any], after: dict[str, Any]) -> str | None:
        """Why an edit from `before` to `after` is refused: the first problem it adds to the
        element (a bad value, or one that contradicts another property). None: accepted."""
        old = set(self._props(before, self.element(before)[1]))
        new = [pt for pt in self._props(after, self.element(after)[1]) if pt not in old]
        return f"{new[0][0]}: {new[0][1]}" if new else None


def image_files(folder: Path) -> list[str]:
    """Picture files under a form's folder, as a form names them (relative, with /)."""
    return sorted(str(f.relative_to(folder)).replace("\\", "/") for f in folder.rglob("*")
                  if f.suffix.lower() in IMAGE_SUFFIXES and f.is_file())


def main(argv: list[str] | None = None) -> int:
    """`python -m hmi_forms.form_doc FORM.hmi...`: re-save forms in the canonical layout (what the
    designer writes), e.g. a form edited in a text editor before it is committed."""
    paths = sys.argv[1:] if argv is None else argv
    if not paths:
        print("usage: python -m hmi_forms.form_doc FORM.hmi...", file=sys.stderr)
        return 2
    status = 0
    for name in paths:
        try:
            save_form(read_doc(name).data, name)
        except FormError as e:
            print("\n".join(e.problems), file=sys.stderr)
            status = 1
        except OSError as e:
            print(f"{name}: cannot write the form: {e}", file=sys.stderr)
            status = 1
    return status


if __name__ == "__main__":
    sys.exit(main())
