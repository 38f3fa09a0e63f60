"""Headless Qt for the whole suite (without it, Qt aborts the process when there is no display),
bytecode caches, PostgreSQL clusters, and OPC UA servers that share one fill of the standard
address space."""

import gc
import itertools
import json
import os
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

# --- hypothesis -----------------------------------------------------------------------------------
# No example has a deadline and none is "too slow": on a loaded machine (CI runs more workers than
# cores) an example's time says nothing about the code, and either check would fail a test that
# holds. Each property sets its own number of examples, for its own space.
settings.register_profile("suite", deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("suite")

# Bytecode caches (__pycache__, ignored by git) are written even where PYTHONDONTWRITEBYTECODE is set,
# as container images often do: without them each xdist worker compiles and assertion-rewrites every
# module again at collection (8 s of CPU each) and each `python main.py` the tests start compiles
# the project again (a third of its start).
sys.dont_write_bytecode = False

_databases = itertools.count(1)


# --- assertion rewriting, once before the workers start -------------------------------------------
# A fresh clone has no bytecode cache: each xdist worker then rewrites the asserts of every test file
# as it collects (pytest's rewriting walks each assert's tree: 8-9 s of CPU a worker, 45 s of the
# suite's with 5 workers, each worker doing the same). The controller does it once, split over the
# cores, before the workers start: they find the rewritten files in __pycache__, as a second run
# does, and so do the project's modules, compiled here as well. So with hypothesis's constants of
# each local module (its plugin gathers them at each worker's collection, 1.6 s a worker without
# its cache in .hypothesis/).


def _rewrite_and_compile(paths: list[tuple[bool, Path]]) -> None:
    import py_compile
    import types

    from _pytest.assertion.rewrite import (
        PYC_TAIL,
        _read_pyc,
        _rewrite_test,
        _write_pyc,
        assertstate_key,
        get_cache_dir,
        try_makedirs,
    )
    from hypothesis.internal.constants_ast import constants_from_module

    state = _config.stash[assertstate_key]
    for test, path in paths:
        module = types.ModuleType(path.stem)
        module.__file__ = str(path)
        constants_from_module(module)  # read from the file, kept in .hypothesis/constants
        if not test:
            py_compile.compile(str(path), doraise=False, quiet=1)  # project modules: plain bytecode
            continue
        cache = get_cache_dir(path)
        pyc = cache / (path.name[:-3] + PYC_TAIL)
        if _read_pyc(path, pyc, state.trace) is not None or not try_makedirs(cache):
            continue
        try:
            source_hash, code = _rewrite_test(path, _config)
        except SyntaxError:
            continue  # the worker that collects the file reports it, as pytest always does
        _write_pyc(state, code, source_hash, pyc)


_config: pytest.Config


def pytest_configure(config: pytest.Config) -> None:
    if hasattr(config, "workerinput") or not config.getoption("numprocesses", None):
        return
    if config.getoption("assertmode") != "rewrite" or sys.dont_write_bytecode:
        return
    from concurrent.futures import ProcessPoolExecutor
    from multiprocessing import get_context

    global _config
    _config = config
    root = Path(config.rootpath)
    patterns = ["conftest.py", *config.getini("python_files")]
    tests = {p for pattern in patterns for p in (root / "tests").rglob(pattern)}
    modules = [p for package in ("netplc", "registrar", "hmi_forms", "app", "tests")
               for p in (root / package).rglob("*.py") if p not in tests]
    paths = sorted([(True, p) for p in tests] + [(False, p) for p in modules],
                   key=lambda item: -item[1].stat().st_size)
    cores = os.cpu_count() or 1
    with ProcessPoolExecutor(cores, mp_context=get_context("fork")) as pool:
        list(pool.map(_rewrite_and_compile, [paths[i::cores] for i in range(cores)]))


def _cluster():
    from tests.pgcluster import PgCluster

    try:
        cluster = PgCluster()
        cluster.start()
    except RuntimeError as e:
        pytest.skip(f"no PostgreSQL for the plant-archive tests: {e}")
    return cluster


@pytest.fixture(scope="session")
def pg_cluster():
    """One throwaway PostgreSQL cluster for the session (see tests/pgcluster.py)."""
    cluster = _cluster()
    yield cluster
    cluster.remove()


@pytest.fixture
def own_pg_cluster():
    """A cluster of the test's own, for tests that stop and restart the server."""
    cluster = _cluster()
    yield cluster
    cluster.remove()


@pytest.fixture
def pg_url(pg_cluster) -> str:
    """A fresh, empty database in the session's cluster."""
    return pg_cluster.create_database(f"plant_{next(_databases)}")


@pytest.fixture(autouse=True)
def _collect_on_the_gui_thread(request: pytest.FixtureRequest):
    """A test with Qt collects Python's garbage on the GUI thread, as our windows do
    (app/gui/application.py), and leaves none of its Qt objects to be freed later by another
    thread, nor its translation; the other tests keep Python's own collection."""
    if "qapp" not in request.fixturenames:
        yield
        return
    from app.gui.application import MainThreadCollector

    app = request.getfixturevalue("qapp")
    MainThreadCollector(parent=app)
    yield
    from app.gui import i18n

    i18n.uninstall(app)  # a window that installed its station's language leaves none to the next test
    for collector in app.findChildren(MainThreadCollector):
        collector.stop()
        collector.setParent(None)
    gc.collect()


@pytest.fixture(autouse=True)
def _no_log_handler_outlives_its_test():
    """A test that runs a `main.py` command in this process (app.cli.main) has the station's log
    configured onto the stderr pytest captured for that test (app/logs.py), which is closed when
    the test ends: a later warning from a thread of another test would then fail to write
    ("--- Logging error ---") instead of reaching the report. The station's handlers (pytest's own
    come and go by phase) and the excepthooks go with their test."""
    import logging
    import threading

    root = logging.getLogger()
    handlers, level = list(root.handlers), root.level
    hooks = sys.excepthook, threading.excepthook
    yield
    for handler in [h for h in root.handlers if getattr(h, "_netplc", False) and h not in handlers]:
        root.removeHandler(handler)
        handler.close()
    root.setLevel(level)
    sys.excepthook, threading.excepthook = hooks


@pytest.fixture
def russian(qapp):
    """The console's Russian installed for the test (and removed after it)."""
    from app.gui import i18n

    assert i18n.install(qapp, "ru") == "ru"
    try:
        yield
    finally:
        i18n.uninstall(qapp)


def _freeze() -> None:
    """What is alive between test files (every imported module, class and test item, the session's
    fixtures, the standard OPC UA address space the servers copy, caches: most of a worker's
    objects, and it lives to the end of the run) leaves the collector's generations: each Qt test
    ends on two full collections (above), which otherwise walk all of it again. After the first
    OPC UA server of a worker, 400,000 objects: 0.35 s of CPU per Qt test, a quarter of the
    suite's. Objects the tests make are collected as before: a file's own objects, module-scoped
    fixtures included, are gone before the next file starts."""
    gc.collect()
    gc.freeze()


def pytest_collection_finish(session: pytest.Session) -> None:
    _freeze()


_last_file: list[str] = []


def pytest_runtest_setup(item: pytest.Item) -> None:
    filled = False
    if "asyncua" in sys.modules:  # OPC UA servers may start: see tests/opcua_address_space.py
        from tests.opcua_address_space import fill_once

        filled = fill_once()
    if filled or _last_file != [_file(item.nodeid)]:  # the first test of a file
        _last_file[:] = [_file(item.nodeid)]
        _freeze()


# --- longest files first ----------------------------------------------------------------------
# Each run keeps how long each test file took (setup, call and teardown) in pytest's cache; the next
# run starts with the longest files, so that its two workers end on short tests together instead of
# one running a long file alone at the end. Tests of a file stay together, in their order.

DURATIONS = "netplc/file_durations"
# a clean clone (CI) has no cache yet: the times of a full run, kept in the repository, order it
# (refresh them with `make durations` after adding long tests)
KEPT = Path(__file__).with_name("file_durations.json")
_spent: dict[str, float] = {}


def _file(nodeid: str) -> str:
    return nodeid.split("::")[0]


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    cache = getattr(config, "cache", None)  # None under -p no:cacheprovider
    last: dict[str, float] = cache.get(DURATIONS, {}) if cache is not None else {}
    if not last and KEPT.exists():
        last = json.loads(KEPT.read_text(encoding="utf-8"))
    if not last:
        return
    unknown = max(last.values())  # a new file may be long: it goes among the first
    order = {}
    for item in items:
        order.setdefault(_file(item.nodeid), (-last.get(_file(item.nodeid), unknown), len(order)))
    items.sort(key=lambda item: order[_file(item.nodeid)])  # stable: a file's tests keep their order


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    _spent[_file(report.nodeid)] = _spent.get(_file(report.nodeid), 0.0) + report.duration


def pytest_sessionfinish(session: pytest.Session) -> None:
    cache = getattr(session.config, "cache", None)
    if cache is None or hasattr(session.config, "workerinput") or not _spent:
        return  # an xdist worker's times reach the controller, which keeps them
    cache.set(DURATIONS, {**cache.get(DURATIONS, {}), **_spent})
