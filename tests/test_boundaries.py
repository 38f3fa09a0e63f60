"""The package boundaries of docs/architecture.md, enforced on the source (what import-linter would do).

- The headless parts never import Qt, not even through another module of the project: the soft
  PLC, the archive, the form models and loader, the runtime, the station configuration.
- Only the Modbus sub-package imports pymodbus (its API changes at every minor release).
- The Modbus stack imports no engine, not even through another module: what a write to our server
  does is its handler's (the station's command layer, a simulated node's engine).
- Only `app/publish/` imports asyncua, paho-mqtt and protobuf (docs/architecture.md section 2).
- Only the plant archive (`registrar/plant/`) imports psycopg, and nothing loads it before a plant
  archive is named: the viewer, the CLI and the station file's check go through registrar.
- The user roles live in the command layer (`app/authority/policy.py`): `hmi_forms` imports them
  and names no roles of its own.
- No import cycles between modules of the project. Imports under `if TYPE_CHECKING:` are left out:
  they never run. Imports inside functions count: they run, only later.
"""

from __future__ import annotations

import ast
import functools
import subprocess
import sys
from pathlib import Path

from tests.project_sources import REPO, sources, tree

QT = ("PySide6", "shiboken6", "pyqtgraph")
HEADLESS = ("netplc", "registrar", "hmi_forms.elements", "hmi_forms.form", "hmi_forms.behaviour",
            "app.station", "app.scada", "app.authority")


def module_name(path: Path) -> str:
    parts = path.relative_to(REPO).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


@functools.cache
def modules() -> dict[str, Path]:
    """Every module of the project by name (read once per session: the tests only look)."""
    found = {module_name(p): p for p in sources()}
    found["main"] = REPO / "main.py"
    return found


def _type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _statements(node: ast.AST) -> list[ast.AST]:
    """The statements (and except/match clauses) directly inside `node`: an import is a statement,
    and an expression holds none, so only these are looked into."""
    return [child for field in ("body", "orelse", "finalbody", "handlers", "cases")
            for child in getattr(node, field, ())]


def imports(path: Path, known: frozenset[str]) -> set[str]:
    """Every module `path` imports when it runs: project modules by name, others by top package."""
    out: set[str] = set()
    todo = _statements(tree(path))
    while todo:
        node = todo.pop()
        if isinstance(node, ast.If) and _type_checking(node):
            todo += node.orelse
        elif isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.module and not node.level:
                for alias in node.names:
                    sub = f"{node.module}.{alias.name}"
                    out.add(sub if sub in known else node.module)
        else:
            todo += _statements(node)
    return out


@functools.cache
def graph() -> dict[str, set[str]]:
    """Each module's imports, parsed once per session (the tests only look)."""
    mods = modules()
    known = frozenset(mods)
    return {name: imports(path, known) for name, path in mods.items()}


def under(name: str, prefixes: tuple[str, ...]) -> bool:
    return any(name == p or name.startswith(p + ".") for p in prefixes)


def test_headless_parts_import_no_qt_even_indirectly() -> None:
    g = graph()
    bad = []
    for start in (m for m in g if under(m, HEADLESS)):
        seen, todo = {start}, [start]
        while todo:
            mod = todo.pop()
            for dep in g.get(mod, ()):
                if under(dep, QT):
                    bad.append(f"{start} imports {dep} (through {mod})")
                elif dep in g and dep not in seen:
                    seen.add(dep)
                    todo.append(dep)
    assert bad == []


@functools.cache
def loaded_by_imports() -> tuple[str, str]:
    """One fresh interpreter for both import checks (its start is most of their cost): the Qt
    modules loaded once the headless parts are imported, then the psycopg modules loaded once the
    CLI, the configuration and the plant archive's URL are imported too (what a station does before
    it names a plant archive)."""
    code = ("import sys, app.station.check, app.station.runtime, hmi_forms.behaviour, netplc.simulator\n"
            "import registrar.query\n"
            f"print(sorted(m for m in sys.modules if m.split('.')[0] in {QT!r}))\n"
            "import app.cli, app.station.config, registrar.plant.url\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'psycopg'))")
    r = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    qt, psycopg = r.stdout.splitlines()
    return qt, psycopg


def test_headless_parts_run_without_qt_loaded() -> None:
    assert loaded_by_imports()[0] == "[]"


def test_only_the_modbus_subpackage_imports_pymodbus() -> None:
    users = sorted(m for m, deps in graph().items() if any(under(d, ("pymodbus",)) for d in deps))
    assert users and all(under(m, ("netplc.modbus",)) for m in users), users


def test_the_modbus_stack_imports_no_engine_even_indirectly() -> None:
    g = graph()
    bad = []
    for start in (m for m in g if under(m, ("netplc.modbus",))):
        seen, todo = {start}, [start]
        while todo:
            mod = todo.pop()
            for dep in g.get(mod, ()):
                if dep == "netplc.engine":
                    bad.append(f"{start} imports {dep} (through {mod})")
                elif dep in g and dep not in seen:
                    seen.add(dep)
                    todo.append(dep)
    assert bad == []


def test_only_the_publishers_import_opcua_mqtt_and_protobuf() -> None:
    users = sorted(m for m, deps in graph().items() if any(under(d, ("asyncua", "paho", "google.protobuf"))
                                                           for d in deps))
    assert users and all(under(m, ("app.publish",)) for m in users), users


def test_only_the_plant_archive_imports_psycopg() -> None:
    users = sorted(m for m, deps in graph().items() if any(under(d, ("psycopg",)) for d in deps))
    assert users and all(under(m, ("registrar.plant",)) for m in users), users


def test_psycopg_is_not_loaded_until_a_plant_archive_is_named() -> None:
    assert loaded_by_imports()[1] == "[]"


def test_hmi_forms_names_no_roles_of_its_own() -> None:
    from app.authority.policy import ROLES

    bad = []
    for name, path in modules().items():
        if not under(name, ("hmi_forms",)):
            continue
        for node in ast.walk(tree(path)):
            targets = (node.targets if isinstance(node, ast.Assign)
                       else [node.target] if isinstance(node, (ast.AnnAssign, ast.AugAssign)) else [])
            if any(isinstance(t, ast.Name) and t.id == "ROLES" for t in targets):
                bad.append(f"{name}:{node.lineno} assigns ROLES")
            if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
                words = {e.value for e in node.elts if isinstance(e, ast.Constant)}
                if len(words & set(ROLES)) >= 2:
                    bad.append(f"{name}:{node.lineno} lists roles {sorted(words & set(ROLES))}")
    assert bad == []


def test_the_rest_reaches_the_modbus_stack_through_its_face() -> None:
    inner = sorted(f"{m} imports {d}" for m, deps in graph().items() if not under(m, ("netplc.modbus",))
                   for d in deps if d.startswith("netplc.modbus."))
    assert inner == []


def test_no_import_cycles() -> None:
    mods = modules()
    g = {m: {d for d in deps if d in mods} for m, deps in graph().items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    cycles: list[list[str]] = []

    def strongconnect(v: str) -> None:  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in g[v]:
            if w not in index:
                strongconnect(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1 or v in g[v]:
                cycles.append(sorted(component))

    for v in sorted(g):
        if v not in index:
            strongconnect(v)
    assert cycles == []


def test_the_soft_plc_knows_nothing_of_the_station() -> None:
    """netplc/ is the soft PLC: no tags, alarms, archive, forms or station (DESIGN 1, layers)."""
    above = sorted(f"{m} imports {d}" for m, deps in graph().items() if under(m, ("netplc",))
                   for d in deps if under(d, ("app", "registrar", "hmi_forms")))
    assert above == []


def test_a_headless_station_imports_only_what_its_configuration_uses(tmp_path: Path) -> None:
    """Issue 28: `main.py --no-gui` of a station with a program, an archive and the Modbus server
    (no forms, no serial line, no OPC UA, MQTT or plant archive) imports no Qt, no form code and
    none of pymodbus, asyncua, paho or psycopg: `-X importtime` lists every module it loaded."""
    (tmp_path / "station.toml").write_text('NetPlcProgram = "p.stl"\nArchive = "archive/journal.sqlite"\n'
                                           "[modbus_server]\nport = 0\n", encoding="utf-8")
    (tmp_path / "p.stl").write_text("JMP 0\n", encoding="utf-8")
    r = subprocess.run([sys.executable, "-X", "importtime", "main.py", "--no-gui", str(tmp_path),
                        "--duration", "0.2"], cwd=REPO, capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr[-2000:]
    loaded = {line.rsplit("|", 1)[1].strip() for line in r.stderr.splitlines()
              if line.startswith("import time:") and line.count("|") == 2}
    assert "app.station.runtime" in loaded  # what importtime lists is the station's start
    unused = (*QT, "hmi_forms", "pymodbus", "asyncua", "paho", "psycopg", "google.protobuf")
    assert sorted(m for m in loaded if under(m, unused)) == []
