"""The project's own modules, read and parsed once per process: the rules enforced on the source
(tests/test_boundaries.py, tests/test_logging_rules.py) look at the same trees, and parsing them
is most of what those tests cost."""

from __future__ import annotations

import ast
import functools
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("app", "netplc", "registrar", "hmi_forms")


@functools.cache
def sources() -> tuple[Path, ...]:
    """Every module of the four packages (main.py aside), in a stable order."""
    return tuple(sorted(p for pkg in PACKAGES for p in (REPO / pkg).rglob("*.py")))


@functools.cache
def text(path: Path) -> str:
    return path.read_text(encoding="utf-8")


@functools.cache
def tree(path: Path) -> ast.Module:
    return ast.parse(text(path), filename=str(path))
