"""Where element models send what they do: the operator's input, and the form's own behaviour.

Two channels, because they run in different places (docs/architecture.md section 9):
- `Target` (`write_bit`, `write_word`): operator input a widget forwards (a click, an entered
  setpoint). At the workstation it is the station's command layer (`EngineTarget`): it checks the
  role (the policy's, raised by the element's `Role`), queues the write to the next scan and
  journals it naming the user, or refuses it, journaled throttled, with the reason. Views have it;
  the runtime does not need it.
- `Effects` (`set_bit`, `put`): what a form does to the station by itself: a sync generator's
  output and the RegData/RegMessages and limit records. Only the runtime has it: it evaluates the
  forms' models from every scan's snapshot on the engine thread (`hmi_forms/behaviour.py`), with
  or without a GUI, so a view never pulses or journals, and a view that lags loses nothing.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Protocol

from app.scada.tag import Tag, TagType
from netplc.address import fmt_octal
from netplc.records import Record

if TYPE_CHECKING:
    from app.authority import Action, Answer, Commands, Refusal, Ticket, Who

logger = logging.getLogger(__name__)


class Target(Protocol):
    """`write_*` return why the write was refused at once (a sentence for the operator: the role,
    a full queue), or None once it is sent; `at_least` is the element's Role, which may ask more
    than the station's policy, never less; `describe(old, new)` says a word's change in physical
    terms for the journal when no tag does (an element's own conversion)."""

    def write_bit(self, addr: int, value: int, *, user: str, label: str | None = None,
                  at_least: str | None = None) -> str | None: ...

    def write_word(self, addr: int, value: int, *, user: str, label: str | None = None,
                   at_least: str | None = None,
                   describe: Callable[[int, int], str] | None = None) -> str | None: ...


class Effects(Protocol):
    def set_bit(self, addr: int, value: int) -> None:
        """Set an HMI bit before the next scan, unjournaled (a generator is not an operator)."""
        ...

    def put(self, record: Record) -> None: ...


class CommandTarget:
    """A command layer as the operator's Target: what both the station's own layer
    (`EngineTarget`) and a remote console's (the station's methods, app/gui/console/window.py)
    share. The refusal names what the operator acted on (the element's label, else its tag's
    description or name, else the address); `who(user)` says who writes from where;
    `on_answer(what, ticket)` is given every ticket, so the view says a refusal, at once or when
    the layer answers later; `say(what, answer)` words a refusal (the console's language).
    `bit` and `word` send the command, each source's own way; so do a tag's faceplate's commands
    (`write_tag`, `force_tag`, `unforce_tag`, in the tag's units, and `denial`, what the layer
    would refuse `who`), which the faceplate follows itself (app/gui/faceplate.py)."""

    def __init__(self, who: Callable[[str], Who], tags: Iterable[Tag] = (),
                 on_answer: Callable[[str, Ticket], object] | None = None,
                 say: Callable[[str, Answer], str] | None = None) -> None:
        self.who = who
        self.on_answer = on_answer
        self.say = say or said
        tags = tuple(tags)
        self._bits = {t.address: t for t in tags if t.type is TagType.BIT}
        self._words = {t.address: t for t in tags if t.type in ONE_WORD}

    def write_bit(self, addr: int, value: int, *, user: str, label: str | None = None,
                  at_least: str | None = None) -> str | None:
        tag = self._bits.get(addr)
        return self._told(self.bit(self.who(user), addr, value, label, at_least), _said(label, tag, addr))

    def write_word(self, addr: int, value: int, *, user: str, label: str | None = None,
                   at_least: str | None = None,
                   describe: Callable[[int, int], str] | None = None) -> str | None:
        tag = self._words.get(addr)
        return self._told(self.word(self.who(user), addr, value, label, at_least, describe),
                          _said(label, tag, addr))

    def bit(self, who: Who, addr: int, value: int, label: str | None, at_least: str | None) -> Ticket:
        raise NotImplementedError

    def word(self, who: Who, addr: int, value: int, label: str | None, at_least: str | None,
             describe: Callable[[int, int], str] | None = None) -> Ticket:
        raise NotImplementedError

    def denial(self, who: Who, action: Action, what: str | None = None) -> Refusal | None:
        raise NotImplementedError

    def write_tag(self, who: Who, tag: Tag, value: float) -> Ticket:
        raise NotImplementedError

    def force_tag(self, who: Who, tag: Tag, phy: float | None) -> Ticket:
        """`phy` None: at its present value (bumpless)."""
        raise NotImplementedError

    def unforce_tag(self, who: Who, tag: Tag) -> Ticket:
        raise NotImplementedError

    def _told(self, ticket: Ticket, what: str) -> str | None:
        if self.on_answer is not None:
            self.on_answer(what, ticket)
        if not ticket.done():
            return None
        answer: Answer = ticket.result()
        return None if answer.ok else self.say(what, answer)


class EngineTarget(CommandTarget):
    """The station's command layer as the operator's Target. A write to a tag's address is
    journaled with the tag's name and, for a word, its physical values and unit besides the raw
    ones (`write Уставка температуры TEMP_SP: 0.0 -> 130.0 °C (raw ...)`)."""

    def __init__(self, commands: Commands, who: Callable[[str], Who],
                 on_answer: Callable[[str, Ticket], object] | None = None,
                 say: Callable[[str, Answer], str] | None = None) -> None:
        super().__init__(who, commands.tags.values(), on_answer, say)
        self.commands = commands

    def bit(self, who: Who, addr: int, value: int, label: str | None, at_least: str | None) -> Ticket:
        """The command of a form's bit write, as `who` (a remote console's too: app/publish/methods.py)."""
        return self.commands.write_bit(who, addr, value, label=_named(label, self._bits.get(addr)),
                                       at_least=at_least)

    def word(self, who: Who, addr: int, value: int, label: str | None, at_least: str | None,
             describe: Callable[[int, int], str] | None = None) -> Ticket:
        tag = self._words.get(addr)
        return self.commands.write_word(who, addr, value, label=_named(label, tag), at_least=at_least,
                                        describe=tag.change if tag else describe)

    def denial(self, who: Who, action: Action, what: str | None = None) -> Refusal | None:
        return self.commands.denial(who, action, what=what)

    def write_tag(self, who: Who, tag: Tag, value: float) -> Ticket:
        return self.commands.write_tag(who, tag.name, value)

    def force_tag(self, who: Who, tag: Tag, phy: float | None) -> Ticket:
        return self.commands.force_tag(who, tag.name, phy)

    def unforce_tag(self, who: Who, tag: Tag) -> Ticket:
        return self.commands.unforce_tag(who, tag.name)


def said(what: str, answer: Answer) -> str:
    """The layer's refusal as the element says it, naming what was asked."""
    if answer.refusal is not None:
        return str(dataclasses.replace(answer.refusal, action=what))
    return f"{what}: {answer.text}"


ONE_WORD = (TagType.WORD, TagType.INT16, TagType.BCD)


def _named(label: str | None, tag: Tag | None) -> str | None:
    """The element's label with the tag's name; without a label, the tag's description."""
    if tag is None:
        return label
    return f"{label or tag.description} {tag.name}".strip()


def _said(label: str | None, tag: Tag | None, addr: int) -> str:
    """What the operator is told a refusal was about: the element's label, else its tag's
    description or name, else the address."""
    return label or (tag.description or tag.name if tag is not None else "") or fmt_octal(addr)


class NullTarget:
    """A form shown without a station (the viewer, a benchmark): the operator's writes go nowhere."""

    def write_bit(self, addr: int, value: int, *, user: str, label: str | None = None,
                  at_least: str | None = None) -> str | None:
        return None

    def write_word(self, addr: int, value: int, *, user: str, label: str | None = None,
                   at_least: str | None = None,
                   describe: Callable[[int, int], str] | None = None) -> str | None:
        return None
