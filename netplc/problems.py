"""The one exception for input that cannot be used: every problem found, each a line naming its file
and place (`file:line: ...`, `station.toml: key: ...`).

An engineer fixing a station wants the whole list at once, not one error per attempt, so loaders
collect problems and raise this once. Each input keeps a subclass of its own name (ConfigError,
ProgramError, CatalogError, FormError, TagError, UsersFileError, StartError) only so a caller can
tell what failed; they add nothing, and whoever just reports catches `Problems`. A problem is a
line of text, or a `Problem` (its place, and a phrase of a catalogue) that a host with a station
says in the station's language (`said`); `problems` is every one in English, for the log.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

from netplc.words import Phrase, Say, english, said


class Sayable(Protocol):
    def said(self, say: Say) -> str: ...


@dataclass(frozen=True, slots=True)
class Problem:
    """`where: text`: the place as it is (file, line, key; a phrase where it has a word of its
    own), the text a phrase, both said in a language; `in_english` is the catalogue's English
    (netplc's; a reader of registrar or app names its own)."""

    where: Phrase | str
    text: Phrase | str
    in_english: Say = field(default=english, repr=False, compare=False)

    def said(self, say: Say) -> str:
        return f"{said(say, self.where)}: {said(say, self.text)}"

    def __str__(self) -> str:
        return self.said(self.in_english)


class Problems(Exception):
    def __init__(self, problems: Sequence[str | Sayable]) -> None:
        self.found = list(problems)
        self.problems = [str(p) for p in self.found]
        super().__init__("\n".join(self.problems))

    def said(self, say: Say) -> list[str]:
        """Every problem in the language of `say`."""
        return [p if isinstance(p, str) else p.said(say) for p in self.found]
