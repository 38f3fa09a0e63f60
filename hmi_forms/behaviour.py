"""What the station's forms do by themselves, evaluated in the runtime from every scan's snapshot.

A form is not only a picture: its sync generators drive bits the program reads, and its RegData,
RegMessages and limit (PhyLow/PhyHigh) elements write the journal. That is station behaviour, so
it must not depend on a window being open, nor on how fast a window keeps up: the runtime loads
the forms' Qt-free models headless too and calls `FormBehaviour` as an engine listener, on the
engine thread, right after each scan publishes its snapshot (docs/architecture.md section 1). Every
snapshot is seen exactly once, so `--no-gui` and the workstation produce the same pulses and
records, scan for scan; the views keep their own copies of the models and only draw them.

A generator's output is written straight into memory here, between two scans, on the engine
thread that owns memory: it is read by the next scan's program exactly as a queued write would be,
but it never waits behind outside writers in the engine's queue. Records go to the station's sink
from the same thread, in scan order.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING

from hmi_forms.elements import Element
from hmi_forms.form import Form
from netplc.memory import Memory, Snapshot
from netplc.records import Record, RecordSink

if TYPE_CHECKING:
    from netplc.engine import Engine

logger = logging.getLogger(__name__)


class FormBehaviour:
    """The acting elements of some forms, bound to NetPlc memory and a record sink.

    `report(text)` hears of an element whose evaluation raised, once per element; that element is
    skipped from then on and the others go on."""

    def __init__(self, forms: Iterable[Form], memory: Memory, sink: RecordSink,
                 report: Callable[[str], None] | None = None) -> None:
        self.memory = memory
        self.sink = sink
        self.report = report
        self.elements: list[tuple[Form, Element]] = [
            (form, element) for form in forms for element in form.elements if element.acts]
        for _, element in self.elements:
            element.effects = self

    def attach(self, engine: Engine) -> None:
        """Evaluate the snapshot the engine holds now (so scan 0 has its pulses too), then every
        snapshot it publishes. Call it before the scan thread starts, after memory is restored."""
        self(engine.snapshot)
        engine.subscribe(self)

    def set_bit(self, addr: int, value: int) -> None:
        self.memory.set_hmi_bit(addr, value)

    def put(self, record: Record) -> None:
        self.sink.put(record)

    def __call__(self, snapshot: Snapshot) -> None:
        failed = []
        for form, element in self.elements:
            try:
                element.update(snapshot)
            except Exception as e:  # a faulty element must not cost the scan or the other elements
                failed.append(element)
                text = f'{form.path}: element "{element.Name}": evaluation failed, the element is skipped'
                logger.exception("%s", text)
                if self.report is not None:
                    self.report(f"{text}: {e!r}")
        if failed:
            self.elements = [(f, el) for f, el in self.elements if el not in failed]
