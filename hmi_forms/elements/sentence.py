"""A sentence a Qt-free model says to the operator, kept translatable.

The models cannot call Qt's tr(); a model's message (an entry refused, a value set) is English text
where the models are tested, and the console's language where a widget shows it. A `Sentence` is
both: the English sentence itself (a str), carrying its source text with `{0}` places and the
values for them, which a widget passes through QCoreApplication.translate and fills in."""

from __future__ import annotations


class Sentence(str):
    source: str
    values: tuple[str, ...]

    def __new__(cls, source: str, *values: object) -> Sentence:
        shown = tuple(str(v) for v in values)
        self = super().__new__(cls, source.format(*shown))
        self.source, self.values = source, shown
        return self
