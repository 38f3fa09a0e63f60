"""Shared builders for the HMI form tests: snapshots with chosen contents, and elements from dicts."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from app.authority import Commands, Source, Who
from app.scada.table import TagTable
from hmi_forms.elements import Element
from hmi_forms.elements.target import EngineTarget
from hmi_forms.form import load_form
from netplc.engine import Engine
from netplc.memory import Memory, Snapshot
from netplc.records import Record


def snap(bits: dict[int, int] | None = None, words: dict[int, int] | None = None, scan: int = 0,
         time: float = 0.0, wall: float = 0.0) -> Snapshot:
    mem = Memory()
    for addr, v in (bits or {}).items():
        mem.set_hmi_bit(addr, v)
    for addr, v in (words or {}).items():
        mem.set_word(addr, v)
    return mem.snapshot(scan, time, wall)


def engine_target(engine: Engine, tags: TagTable | None = None, role: str = "operator",
                  **kwargs: Any) -> EngineTarget:
    """A form's writes through the command layer of `engine`, every user acting with `role`."""
    commands = Commands(engine, engine.sink, role_of=lambda _name: role, tags=tags.tags if tags else ())
    return EngineTarget(commands, lambda user: Who(user, Source.CONSOLE), **kwargs)


class ListTarget:
    """Collects what elements write and record: as a Target, the operator's writes a view forwards;
    as Effects (the runtime's copy of a model), the generators' bits and the element records."""

    def __init__(self) -> None:
        self.writes: list[tuple[str, int, int, str | None]] = []
        self.records: list[Record] = []

    def write_bit(self, addr: int, value: int, *, user: str, label: str | None = None,
                  at_least: str | None = None) -> None:
        self.writes.append(("bit", addr, value, user))

    def write_word(self, addr: int, value: int, *, user: str, label: str | None = None,
                   at_least: str | None = None, describe: object = None) -> None:
        self.writes.append(("word", addr, value, user))

    def set_bit(self, addr: int, value: int) -> None:
        self.writes.append(("set", addr, value, None))

    def put(self, record: Record) -> None:
        self.records.append(record)


def write_form(folder: Path, elements: list[dict[str, Any]], name: str = "t.hmi", **extra: Any) -> Path:
    doc = {"form": {"title": "Test", "width": 800, "height": 600}, "elements": elements, **extra}
    path = folder / name
    path.write_text(json.dumps(doc, ensure_ascii=False, indent=1), encoding="utf-8")
    return path


def shown_form(qtbot: Any, tmp_path: Path, elements: list[dict[str, Any]], size: tuple[int, int]) -> Any:
    """A FormView of `elements` on a form of `size`, shown (Qt is imported here only: the other
    helpers serve Qt-free tests too)."""
    from hmi_forms.elements.target import NullTarget
    from hmi_forms.widgets.form_view import FormView

    form = load_form(write_form(tmp_path, elements))
    form.width, form.height = size
    view = FormView(form, NullTarget())
    qtbot.addWidget(view)
    view.show()
    return view


def element(tmp_path: Path, type_: str, **props: Any) -> Element:
    """One element loaded through the real loader (so the tests cover the property parsers too)."""
    extra = {k: props.pop(k) for k in ("devices", "images") if k in props}
    raw = {"type": type_, "Name": props.pop("Name", "e1"), "x": 10, "y": 10, "w": 200, "h": 120, **props}
    return load_form(write_form(tmp_path, [raw], **extra)).elements[0]
