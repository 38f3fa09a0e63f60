"""A module imported at its first use, not where it is named: a headless station loads what its
configuration uses and nothing more (issue 28: numpy only for tags and forms).

`lazy("numpy")` stands for the module: the first attribute read imports it (through the import
system's own per-module lock, so two threads racing to it get the one module) and copies its
names onto the stand-in, so every later read is a plain attribute read that costs nothing more.
"""

from __future__ import annotations

import importlib
from types import ModuleType
from typing import Any


class lazy(ModuleType):
    def __getattr__(self, name: str) -> Any:  # only for names not copied yet: the first use
        module = importlib.import_module(self.__name__)
        self.__dict__.update(vars(module))
        return getattr(module, name)
