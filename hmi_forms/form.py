"""Load and validate `.hmi` forms (docs/architecture.md section 9).

A form file is JSON:

    {"form": {"title": ..., "width": ..., "height": ..., "BackColor": ..., "ForeColor": ..., "Font": ...},
     "devices": [{"Name": ..., "AppMin": ..., "AppMax": ..., "PhyMin": ..., "PhyMax": ...}],
     "images": ["pump0.png", ...],
     "elements": [{"type": ..., "Name": ..., "x": ..., "y": ..., "w": ..., "h": ..., <properties>}]}

Every problem of a file is collected and reported at once as `file: element "Name": property:
problem`, because an engineer fixing a form wants the whole list, not one error per attempt.
`load_forms` loads a folder so that one broken form does not stop the others from opening.
"""

from __future__ import annotations

import difflib
import json
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from app.scada.table import TagTable
from app.scada.words import ENGLISH, Phrase, Words, json_error, phrase, words
from hmi_forms.elements import ELEMENT_TYPES, Element
from hmi_forms.elements import props as p
from hmi_forms.elements.analog import Scaled, scaling_problems
from netplc.problems import Problem, Problems
from netplc.textfile import TextFileError, confine, read_text

FORM_BACK = (0xDD, 0xE1, 0xE6, 255)
FORM_FORE = (0x1A, 0x1A, 0x1A, 255)


MAX_NESTING = 100  # a form too deep for json.loads is reported where it passes this depth


def _too_deep(raw: str) -> tuple[int, int]:
    """Line and column where brackets outside strings first nest deeper than MAX_NESTING."""
    depth, line, col = 0, 1, 0
    in_string = escaped = False
    for ch in raw:
        col += 1
        if ch == "\n":
            line, col = line + 1, 0
        elif in_string:
            in_string = escaped or ch != '"'
            escaped = not escaped and ch == "\\"
        elif ch == '"':
            in_string = True
        elif ch in "[{":
            depth += 1
            if depth > MAX_NESTING:
                return line, col
        elif ch in "]}":
            depth -= 1
    return line, col


class FormError(Problems):
    """Every problem of one form file, each naming the element and property."""


@dataclass
class Form:
    path: Path
    title: str
    width: int
    height: int
    BackColor: p.Color = FORM_BACK
    ForeColor: p.Color = FORM_FORE
    Font: p.Font = field(default_factory=p.Font)
    BackgroundImage: Path | None = None
    devices: dict[str, p.Scaling] = field(default_factory=dict)
    images: list[Path | None] = field(default_factory=list)  # None: not shown (see props.Outside)
    elements: list[Element] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)  # of a form that loads all the same
    warnings: list[str] = field(default_factory=list)  # allowed, but contradicting the station's tags


FORM_PROPS: dict[str, p.Parser] = {
    "title": p.text,
    "width": p.integer(1, 10000),
    "height": p.integer(1, 10000),
    "BackColor": p.color,
    "ForeColor": p.color,
    "Font": p.font,
    "BackgroundImage": p.image_file,
}
DEVICE_PROPS = ("Name", "AppMin", "AppMax", "PhyMin", "PhyMax")


def _unknown(name: str, known: list[str]) -> Phrase:
    close = difflib.get_close_matches(name, known, n=1)
    return phrase("form unknown close", close=close[0]) if close else phrase("form unknown property")


def parse_form(path: Path, parse_int: Callable[[str], Any] = p.json_int) -> Any:
    """The JSON of a form file; FormError naming the file and the place for anything else (not
    text, not JSON, nested too deeply, with the default `parse_int` never a number too long), its
    problem a phrase its reporter says in the station's language (`FormError.said`)."""
    try:
        raw = read_text(path, "read form")
    except TextFileError as e:
        raise FormError([e]) from None
    try:
        return json.loads(raw, parse_int=parse_int)
    except json.JSONDecodeError as e:
        where, text = f"{path}:{e.lineno}:{e.colno}", phrase("form bad json", error=json_error(e.msg))
        raise not_a_form(where, text) from None
    except RecursionError:
        line, col = _too_deep(raw)
        raise not_a_form(f"{path}:{line}:{col}", phrase("form too deep", n=MAX_NESTING)) from None
    except ValueError as e:  # a `parse_int` that refuses a number (int: past 4300 digits)
        raise not_a_form(str(path), phrase("form bad json", error=e)) from None


def not_a_form(where: str, text: Phrase) -> FormError:
    """A form file that is no form at all: the place as it is, the problem a phrase (English in
    `problems`, said in a station's language by `said`)."""
    return FormError([Problem(where, text, ENGLISH)])


class _Loader:
    def __init__(self, path: Path, symbols: dict[str, int], station: Path | None,
                 allow_outside: bool, tags: TagTable | None = None, say: Words | None = None) -> None:
        self.path = path
        self.say = say or words()  # the station's Language (the system locale's without a station)
        self.problems: list[str] = []
        self.warnings: list[str] = []
        self.fatal = 0  # problems that stop the form from opening (the others only lose a picture)
        self.ctx = p.Context(symbols, path.parent, roots=(station,) if station else (),
                             allow_outside=allow_outside, tags=tags or TagTable())

    def problem(self, where: str, prop: str | None, text: object, fatal: bool = True) -> None:
        """`text`: a phrase of app/scada/words.py (or a PropError carrying one), said here."""
        head = f"{self.path}: {where}: {prop}" if prop else f"{self.path}: {where}"
        self.problems.append(f"{head}: {self.say.say(text)}")
        self.fatal += fatal

    def warn(self, where: str, prop: str, text: object) -> None:
        self.warnings.append(f"{self.path}: {where}: {prop}: {self.say.say(text)}")

    def load(self) -> Form:
        """The form of the file. A station's form is read only from inside the station folder,
        links followed (unless allow_outside): one that is a link to /dev/zero or to another
        station's file is a problem, not read."""
        if self.ctx.roots and not self.ctx.allow_outside:
            try:
                confine(self.path, self.ctx.roots[0])
            except TextFileError as e:
                raise FormError([e.said(self.say)]) from None
        try:
            doc = parse_form(self.path)
        except FormError as e:
            raise FormError(e.said(self.say)) from None
        return self.build(doc)

    def build(self, doc: Any) -> Form:
        """The form of a parsed document (the designer checks its unsaved document through this)."""
        if not isinstance(doc, dict):
            raise FormError([f"{self.path}: {self.say('form not object')}"])
        for key in sorted(set(doc) - {"form", "devices", "images", "elements"}):
            self.problem(self.say("form where file"), key, phrase("form unknown section"))
        form = self.form_settings(doc.get("form"))
        form.devices = self.ctx.devices = self.devices(doc.get("devices", []))
        form.images = self.ctx.images = self.images(doc.get("images", []))
        form.elements = self.elements(doc.get("elements"))
        for el in form.elements:
            if el.x + el.w > form.width or el.y + el.h > form.height:
                self.problem(self.say("form where element", name=el.Name),
                             "w" if el.x + el.w > form.width else "h",
                             phrase("form past", x=el.x, y=el.y, w=el.w, h=el.h, width=form.width,
                                    height=form.height))
        if self.fatal:
            raise FormError(self.problems)
        form.problems = self.problems
        form.warnings = self.warnings
        return form

    def form_settings(self, raw: Any) -> Form:
        form = Form(self.path, self.path.stem, 800, 600)
        if not isinstance(raw, dict):
            self.problem("form", None, phrase("form no settings"))
            return form
        for key, value in raw.items():
            parser = FORM_PROPS.get(key)
            if parser is None:
                self.problem("form", key, _unknown(key, list(FORM_PROPS)))
                continue
            try:
                setattr(form, key, parser(value, self.ctx))
            except p.PropError as e:
                self.problem("form", key, e, fatal=not isinstance(e, p.Outside))
        for key in ("width", "height"):
            if key not in raw:
                self.problem("form", key, phrase("form missing"))
        return form

    def devices(self, raw: Any) -> dict[str, p.Scaling]:
        out: dict[str, p.Scaling] = {}
        if not isinstance(raw, list):
            self.problem("devices", None, phrase("form devices list"))
            return out
        for i, dev in enumerate(raw):
            named = isinstance(dev, dict) and isinstance(dev.get("Name"), str)
            where = (self.say("form where device", name=dev["Name"]) if named
                     else self.say("form where device n", n=i + 1))
            if not isinstance(dev, dict):
                self.problem(where, None, phrase("form device object"))
                continue
            values: dict[str, Any] = {}
            for key, value in dev.items():
                if key not in DEVICE_PROPS:
                    self.problem(where, key, _unknown(key, list(DEVICE_PROPS)))
                    continue
                try:
                    values[key] = (p.text if key == "Name" else p.number)(value, self.ctx)
                except p.PropError as e:
                    self.problem(where, key, e)
            missing = [k for k in DEVICE_PROPS if k not in dev]
            for key in missing:
                self.problem(where, key, phrase("form missing"))
            if len(values) < len(DEVICE_PROPS):
                continue
            name = values.pop("Name")
            bad = scaling_problems(values)
            for key, text in bad:
                self.problem(where, key, text)
            if name in out:
                self.problem(where, "Name", phrase("form duplicate device"))
            elif not bad:
                out[name] = p.Scaling(**values)
        return out

    def images(self, raw: Any) -> list[Path | None]:
        if not isinstance(raw, list):
            self.problem("images", None, phrase("form images list"))
            return []
        out: list[Path | None] = []
        for i, name in enumerate(raw):
            try:
                out.append(p.image_file(name, self.ctx))
            except p.PropError as e:
                self.problem(self.say("form where image", n=i), None, e, fatal=not isinstance(e, p.Outside))
                out.append(None)  # keeps the indices of later images
        return out

    def elements(self, raw: Any) -> list[Element]:
        if not isinstance(raw, list):
            self.problem("elements", None, phrase("form elements list"))
            return []
        out: list[Element] = []
        names: set[str] = set()
        for i, el in enumerate(raw):
            name = el.get("Name") if isinstance(el, dict) else None
            where = (self.say("form where element", name=name) if isinstance(name, str)
                     else self.say("form where element n", n=i + 1))
            if not isinstance(el, dict):
                self.problem(where, None, phrase("form element object"))
                continue
            if isinstance(name, str):
                if name in names:
                    self.problem(where, "Name", phrase("form duplicate element"))
                names.add(name)
            element = self.element(where, el)
            if element is not None:
                out.append(element)
        return out

    def element(self, where: str, raw: dict[str, Any]) -> Element | None:
        kind = raw.get("type")
        cls = ELEMENT_TYPES.get(kind) if isinstance(kind, str) else None
        if cls is None:
            hint = phrase("form did you mean", close=m[0]) if isinstance(kind, str) and (
                m := difflib.get_close_matches(kind, list(ELEMENT_TYPES), n=1)) else ""
            text = (phrase("form type missing") if kind is None
                    else phrase("form unknown type", kind=kind, hint=hint))
            self.problem(where, "type", phrase("form types", text=text, types=", ".join(ELEMENT_TYPES)))
            return None
        schema = {f.name: f for f in fields(cls) if "parser" in f.metadata}
        aliases = {f.metadata["alias"]: f.name for f in schema.values() if f.metadata["alias"]}
        values: dict[str, Any] = {}
        seen: dict[str, str] = {}
        before = self.fatal
        for key, value in raw.items():
            if key == "type":
                continue
            target = aliases.get(key, key)
            f = schema.get(target)
            if f is None:
                self.problem(where, key, _unknown(key, list(schema)))
                continue
            if target in seen:
                self.problem(where, key, phrase("form given twice", first=seen[target], key=key))
                continue
            seen[target] = key
            try:
                values[target] = f.metadata["parser"](value, self.ctx)
            except p.PropError as e:
                self.problem(where, key, e, fatal=not isinstance(e, p.Outside))
        for f in schema.values():
            if f.metadata["required"] and f.name not in raw and f.metadata["alias"] not in raw:
                self.problem(where, f.name, phrase("form missing"))
        if self.fatal > before:
            return None
        element = cls(**values)
        element.take_tag(raw, self.ctx.tags)
        problems = element.check(self.ctx)
        for key, text in problems:
            self.problem(where, key, text)
        if isinstance(element, Scaled) and not problems:
            for key, text in element.disagreements(raw, self.ctx.tags):
                self.warn(where, key, text)
        return element


def load_form(path: str | Path, symbols: dict[str, int] | None = None, *, station: Path | None = None,
              allow_outside: bool = False, tags: TagTable | None = None, say: Words | None = None) -> Form:
    """Load one form; FormError lists every problem of the file (in the language of `say`). Files
    it names must be in its folder or in the `station` folder unless `allow_outside`; one that is
    not is left out and named in `Form.problems`. Addresses may name the station's `tags`."""
    return _Loader(Path(path), symbols or {}, station, allow_outside, tags, say).load()


def load_forms(folder: str | Path, symbols: dict[str, int] | None = None, *, station: Path | None = None,
               allow_outside: bool = False, tags: TagTable | None = None,
               say: Words | None = None) -> tuple[list[Form], list[str]]:
    """Load every `*.hmi` of a folder (sorted by name): the forms that open, and every problem
    (those of the forms that do not open, and the files left out of those that do)."""
    forms: list[Form] = []
    problems: list[str] = []
    for path in sorted(Path(folder).glob("*.hmi")):
        try:
            form = load_form(path, symbols, station=station, allow_outside=allow_outside, tags=tags, say=say)
        except FormError as e:
            problems.extend(e.problems)
        else:
            forms.append(form)
            problems.extend(form.problems)
    return forms, problems
