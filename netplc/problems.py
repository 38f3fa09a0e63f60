"""The one exception for input that cannot be used: every problem found, each a line naming its file
and place (`file:line: ...`, `station.toml: key: ...`).

An engineer fixing a station wants the whole list at once, not one error per attempt, so loaders
collect problems and raise this once. Each input keeps a subclass of its own name (ConfigError,
ProgramError, CatalogError, FormError, TagError, UsersFileError, StartError) only so a caller can
tell what failed; they add nothing, and whoever just reports catches `Problems`.
"""

from __future__ import annotations


class Problems(Exception):
    def __init__(self, problems: list[str]) -> None:
        self.problems = problems
        super().__init__("\n".join(problems))
