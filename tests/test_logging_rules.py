"""Faults reach a person (docs/architecture.md section 1), enforced on the source.

- A handler that catches everything (`except Exception`, a bare `except:`) and carries on, instead
  of raising, logs what it caught: its module has `logger = logging.getLogger(__name__)` and the
  handler calls `logger.exception/error/warning/critical` (a level the default `--log-level`
  shows). A handler that hands the fault to code that logs it says so where it is caught, with a
  `# no log: <why>` comment on its `except` line.
- Nothing catches `BaseException`: KeyboardInterrupt and SystemExit stop the station; cleanup that
  must run for them too belongs in `finally`.
- `contextlib.suppress` names the errors it expects, never `Exception` or `BaseException`: what it
  swallows cannot be logged.
"""

from __future__ import annotations

import ast
import functools
from collections.abc import Callable

from tests import project_sources
from tests.project_sources import REPO, sources

SEEN_LEVELS = {"exception", "error", "warning", "critical"}
NO_LOG = "# no log:"


def _names(node: ast.expr | None) -> set[str]:
    """The exception class names a handler catches ("" for a bare `except:`)."""
    if node is None:
        return {""}
    if isinstance(node, ast.Tuple):
        return set().union(*(_names(e) for e in node.elts))
    if isinstance(node, ast.Name):
        return {node.id}
    if isinstance(node, ast.Attribute):
        return {node.attr}
    return set()


def _walk_body(body: list[ast.stmt]) -> list[ast.AST]:
    """Every node of a handler's own code: not of functions or classes defined in it, which run
    later, elsewhere."""
    later = (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)
    out: list[ast.AST] = []
    todo: list[ast.AST] = [node for node in body if not isinstance(node, later)]
    while todo:
        node = todo.pop()
        out.append(node)
        todo += [child for child in ast.iter_child_nodes(node) if not isinstance(child, later)]
    return out


def _has_module_logger(tree: ast.Module) -> bool:
    for node in tree.body:
        if (isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "logger"
                                                 for t in node.targets)
                and isinstance(node.value, ast.Call) and isinstance(node.value.func, ast.Attribute)
                and node.value.func.attr == "getLogger"
                and [ast.unparse(a) for a in node.value.args] == ["__name__"]):
            return True
    return False


def _logs(handler: ast.ExceptHandler) -> bool:
    return any(isinstance(n, ast.Call) and isinstance(n.func, ast.Attribute) and n.func.attr in SEEN_LEVELS
               and isinstance(n.func.value, ast.Name) and n.func.value.id == "logger"
               for n in _walk_body(handler.body))


def _raises(handler: ast.ExceptHandler) -> bool:
    return any(isinstance(n, ast.Raise) for n in _walk_body(handler.body))


def _suppress(func: ast.expr) -> bool:
    """`func` is `suppress` or `contextlib.suppress` (without unparsing every call of the project)."""
    if isinstance(func, ast.Name):
        return func.id == "suppress"
    return (isinstance(func, ast.Attribute) and func.attr == "suppress" and isinstance(func.value, ast.Name)
            and func.value.id == "contextlib")


def violations(text: str, where: str, parsed: Callable[[], ast.Module] | None = None) -> list[str]:
    """What breaks the rules in the module `text` (its tree from `parsed`, if given), each at
    `where:line`. A module that neither says `except` nor `suppress` has nothing the rules look at:
    it is not parsed."""
    if "except" not in text and "suppress" not in text:
        return []
    lines = text.splitlines()
    tree = parsed() if parsed else ast.parse(text, filename=where)
    has_logger = _has_module_logger(tree)
    out = []
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and _suppress(node.func)
                and _names(ast.Tuple(node.args)) & {"Exception", "BaseException"}):
            out.append(f"{where}:{node.lineno}: suppresses every error (name the ones expected)")
        if not isinstance(node, ast.ExceptHandler):
            continue
        names = _names(node.type)
        at = f"{where}:{node.lineno}"
        if "BaseException" in names:
            out.append(f"{at}: catches BaseException (use finally for cleanup)")
            continue
        if not names & {"", "Exception"} or _raises(node) or NO_LOG in lines[node.lineno - 1]:
            continue
        if not has_logger:
            out.append(f"{at}: catches Exception and carries on, and the module has no "
                       "logger = logging.getLogger(__name__)")
        elif not _logs(node):
            out.append(f"{at}: catches Exception and carries on without logger.exception/warning/...")
    return sorted(out, key=lambda v: int(v[len(where) + 1:].split(":")[0]))


def test_every_handler_that_catches_everything_logs() -> None:
    found = [v for path in sources()
             for v in violations(project_sources.text(path), path.relative_to(REPO).as_posix(),
                                 functools.partial(project_sources.tree, path))]
    assert found == [], "\n".join(found)


def test_the_rule_sees_what_it_is_for() -> None:
    """The check itself: each kind of handler it must catch, and what it must let pass."""
    found = violations(
        "import logging\n"
        "logger = logging.getLogger(__name__)\n"
        "def f():\n"
        "    try:\n        g()\n    except Exception:\n        pass\n"  # 6: silent
        "    try:\n        g()\n    except:\n        pass\n"  # 10: bare, silent
        "    try:\n        g()\n    except BaseException:\n        raise\n"  # 14: BaseException
        "    try:\n        g()\n    except (ValueError, Exception) as e:\n"  # 18: logs only later
        "        def later():\n            logger.exception('x')\n"
        "    try:\n        g()\n    except Exception:\n        logger.exception('x')\n"  # fine
        "    try:\n        g()\n    except Exception as e:\n        raise KeyError() from e\n"  # fine
        "    try:\n        g()\n    except Exception:  # no log: h() logs it\n        h()\n"  # fine
        "    try:\n        g()\n    except OSError:\n        pass\n"  # not this rule's
        "    with contextlib.suppress(ValueError, Exception):\n        g()\n",  # 37: silent
        "sample.py")
    assert [v.split(":")[1] for v in found] == ["6", "10", "14", "18", "37"], found
    without = violations("def f():\n    try:\n        g()\n"
                         "    except Exception:\n        logger.exception('x')\n", "bare.py")
    assert len(without) == 1 and "no logger" in without[0]
