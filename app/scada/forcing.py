"""Forcing a tag: the station's words for NetPlc's forces (netplc/forcing.py).

The soft PLC forces bits, bytes and words; a tag is the station's name for memory with a type and
a conversion, so forcing one by its physical value is the SCADA layer's: the forces that pin a
tag (its bit, its word, or both words of a 32-bit tag, in its byte order), converted as an operator's
write is, installed and released as one command and journaled once with the tag's name and unit.
The command layer (app/authority/layer.py) queues these closures to the engine thread.
"""

from __future__ import annotations

from collections.abc import Callable

from app.scada.tag import Tag, TagType
from netplc.address import IO_BITS
from netplc.forcing import Force, ForceError, Forces, Kind
from netplc.memory import Memory
from netplc.records import Record


def tag_forces(tag: Tag, phy: float, user: str = "") -> tuple[Force, ...]:
    """The forces that pin `tag` at the physical value `phy`: its bit, its word, or both words of a
    32-bit tag (in its byte order), converted by the tag's Scaling and type like an operator's write."""
    raw = tag.to_raw(phy)
    if tag.type is TagType.BIT:
        return (Force("bit", tag.address, 1 if raw else 0, user),)
    data = tag.encode(raw)
    return tuple(Force("word", addr, int.from_bytes(data[i:i + 2], "little"), user)
                 for i, addr in zip(range(0, len(data), 2), tag_words(tag), strict=True))


def tag_words(tag: Tag) -> tuple[int, ...]:
    """The word addresses a word or 32-bit tag occupies (an I/O word is 16 bits on)."""
    step = 16 if tag.address < IO_BITS else 2
    words = 2 if tag.type in (TagType.INT32, TagType.FLOAT32) else 1
    return tuple(tag.address + step * k for k in range(words))


def tag_keys(tag: Tag) -> tuple[tuple[Kind, int], ...]:
    if tag.type is TagType.BIT:
        return (("bit", tag.address),)
    return tuple(("word", a) for a in tag_words(tag))


def forcing_tag(forces: Forces, tag: Tag, phy: float | None = None, *,
                user: str) -> Callable[[Memory], None]:
    """Force every word of `tag` (or its bit) as one command to the physical value `phy`, or
    bumpless to what it holds when applied; journaled with the tag's name and unit."""
    if phy is not None and phy != phy:
        raise ForceError("force NaN", name=tag.name)

    def apply(mem: Memory) -> None:
        keys = tag_keys(tag)
        was_forced = all(forces.forced(*k) for k in keys)
        old = tag.value(mem)
        new = tag_forces(tag, old if phy is None else phy, user)
        if phy is None:  # bumpless: the raw words as they are, not the round trip of their value
            new = tuple(Force(f.kind, f.addr, f.read(mem), user) for f in new)
        forces.listing = (*(f for f in forces.listing if f.key not in keys), *new)
        for f in new:
            f.apply(mem)
        value = tag.value(mem)
        say = forces.host.words
        before = f"{old:.{tag.decimals}f}"
        was = say("forced value", value=before) if was_forced else before
        how = say("bumpless") if phy is None else ""
        raw = str(new[0].value) if tag.type is TagType.BIT else " ".join(f"{f.value:04X}h" for f in new)
        _journal(forces, user, tag, value, say("force", where=tag.name, was=was, how=how,
                                                value=say("raw value", value=tag.format(value), raw=raw)))

    return apply


def unforcing_tag(forces: Forces, tag: Tag, *, user: str) -> Callable[[Memory], None]:
    """Release every word (or the bit) of `tag` in one command, journaled once with its name."""

    def apply(mem: Memory) -> None:
        keys = tag_keys(tag)
        if any(forces.forced(*k) for k in keys):
            forces.listing = tuple(f for f in forces.listing if f.key not in keys)
            value = tag.value(mem)
            _journal(forces, user, tag, value,
                     forces.host.words("unforce", where=tag.name, value=tag.format(value)))

    return apply


def _journal(forces: Forces, user: str, tag: Tag, value: float, text: str) -> None:
    host = forces.host
    host.sink.put(Record(host.wall_time(), "operator", source=user, number=tag.address,
                         value=float(value), text=text))
