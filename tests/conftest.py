"""Headless Qt for the whole suite (without it, Qt aborts the process when there is no display),
bytecode caches, PostgreSQL clusters, and OPC UA servers that share one fill of the standard
address space."""

import itertools
import os
import sys

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

# Bytecode caches (__pycache__, ignored by git) are written even where PYTHONDONTWRITEBYTECODE is set,
# as container images often do: without them each xdist worker compiles and assertion-rewrites every
# module again at collection (8 s of CPU each) and each `python main.py` the tests start compiles
# the project again (a third of its start).
sys.dont_write_bytecode = False

_databases = itertools.count(1)


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


def pytest_runtest_setup(item: pytest.Item) -> None:
    if "asyncua" in sys.modules:  # OPC UA servers may start: see tests/opcua_address_space.py
        from tests.opcua_address_space import fill_once

        fill_once()
