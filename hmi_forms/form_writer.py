""".hmi forms written in one canonical layout, so a saved form diffs line by line and an untouched
form in this layout saves byte for byte as it was read (a hand-written one takes the layout once).

The layout: the sections in the order form, devices, images, elements (then any unknown section, kept
so `check` still reports it); the form settings one per line; a device or an image per line; every
element a block of its own, with one property per line except the geometry, which shares a line
(a move is then one changed line). Keys follow a fixed order: an element's `type`, `Name`, `x`,
`y`, `w`, `h`, then the properties of its type in the order its model declares them (its addresses
first), then the look every element shares; keys no model knows go last, in the order they came.
Values are kept as the file wrote them (a symbol stays a symbol, `1` stays `1` and `1.0` stays
`1.0`), since the document is the file and the models are only its reading.
"""

from __future__ import annotations

import json
import os
from dataclasses import fields
from functools import cache
from pathlib import Path
from typing import Any

from hmi_forms.elements import ELEMENT_TYPES, Element
from hmi_forms.elements import props as p
from hmi_forms.form import DEVICE_PROPS, FORM_PROPS

SECTIONS = ("form", "devices", "images", "elements")
GEOMETRY = ("x", "y", "w", "h")
FONT_KEYS = ("Family", "Size", "Bold", "Italic")


@cache
def element_keys(kind: str) -> tuple[str, ...]:
    """The canonical key order of an element type; an alias sorts where its property does."""
    base = [f for f in fields(Element) if "parser" in f.metadata]
    own = [f for f in fields(ELEMENT_TYPES[kind]) if "parser" in f.metadata and f not in base] \
        if kind in ELEMENT_TYPES else []
    own.sort(key=lambda f: f.metadata["parser"] not in (p.bit, p.word))  # addresses first
    keys = ["type", "Name", *GEOMETRY]
    for f in own + base:
        keys += [k for k in (f.name, f.metadata["alias"]) if k and k not in keys]
    return tuple(keys)


def ordered(raw: dict[str, Any], order: tuple[str, ...]) -> list[tuple[str, Any]]:
    """The items of `raw` in `order`, then the keys `order` does not know in their own order."""
    known = [(k, raw[k]) for k in order if k in raw]
    return known + [(k, v) for k, v in raw.items() if k not in order]


def _value(key: str, value: Any) -> str:
    if key == "Font" and isinstance(value, dict):
        value = dict(ordered(value, FONT_KEYS))
    return json.dumps(value, ensure_ascii=False)


def _pairs(items: list[tuple[str, Any]]) -> str:
    return ", ".join(f"{json.dumps(k, ensure_ascii=False)}: {_value(k, v)}" for k, v in items)


def _block(items: list[tuple[str, Any]], indent: str) -> str:
    """`{ ... }` with a property per line, the geometry sharing one."""
    lines: list[str] = []
    geometry = [(k, v) for k, v in items if k in GEOMETRY]
    for k, v in items:
        if k in GEOMETRY:
            if k == geometry[0][0]:
                lines.append(_pairs(geometry))
            continue
        lines.append(_pairs([(k, v)]))
    inner = indent + " "
    return "{\n" + ",\n".join(inner + line for line in lines) + "\n" + indent + "}"


def _list(items: list[str]) -> str:
    return "[\n" + ",\n".join(f"  {item}" for item in items) + "\n ]"


def _element(raw: Any) -> str:
    if not isinstance(raw, dict):
        return json.dumps(raw, ensure_ascii=False)
    kind = raw.get("type")
    return _block(ordered(raw, element_keys(kind if isinstance(kind, str) else "")), "  ")


def dump_form(doc: dict[str, Any]) -> str:
    """The canonical text of a form document (the JSON object of a `.hmi` file)."""
    parts: list[str] = []
    for section, value in ordered(doc, SECTIONS):
        if section == "form" and isinstance(value, dict):
            text = _block(ordered(value, tuple(FORM_PROPS)), " ")
        elif section == "devices" and isinstance(value, list):
            text = _list(["{" + _pairs(ordered(d, DEVICE_PROPS)) + "}" if isinstance(d, dict)
                          else _value("", d) for d in value]) if value else "[]"
        elif section == "images" and isinstance(value, list):
            text = _list([_value("", v) for v in value]) if value else "[]"
        elif section == "elements" and isinstance(value, list):
            text = _list([_element(e) for e in value]) if value else "[]"
        else:
            text = _value(section, value)
        parts.append(f" {json.dumps(section, ensure_ascii=False)}: {text}")
    return "{\n" + ",\n".join(parts) + "\n}\n"


def save_form(doc: dict[str, Any], path: str | Path) -> None:
    """Write atomically (a crash while saving leaves the old form, never half of the new one)."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(dump_form(doc), encoding="utf-8", newline="\n")
    os.replace(tmp, path)
