"""Every operand a form's elements read, found from their address properties rather than asked of
each element: what a remote console watches of the station's memory while the form is shown
(app/publish/memory_items.py), so that an element gated by a bit (SyncType, QualityAddr,
EnableAddr) or reading one more than it is judged on reads it too. An output address is read as
well: it is a few bytes, and an element may show what it wrote."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import fields

from hmi_forms.elements import props as p
from hmi_forms.elements.base import Element
from netplc.address import BitRef

WORD_PARSERS = (p.word,)
BIT_PARSERS = (p.bit, p.sync_type)


def operands(elements: Iterable[Element]) -> list[tuple[int, int]]:
    """(address, bytes) of every operand of `elements`, bytes 0 for one HMI bit, as `sources()`
    gives them; each once."""
    out: set[tuple[int, int]] = set()
    for element in elements:
        out.update(element.sources())
        for f in fields(element):
            parser = f.metadata.get("parser")
            value = getattr(element, f.name, None)
            if parser in WORD_PARSERS and isinstance(value, int):
                out.add((value, 2))
            elif parser in BIT_PARSERS and isinstance(value, BitRef):
                out.add((value.hmi, 0))
    return sorted(out)
