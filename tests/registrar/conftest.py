"""Shared helpers for the registrar tests: real archive files under tmp_path."""

from __future__ import annotations

import sqlite3
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from registrar.plant.forward import Forwarder
from registrar.query import Archive


def wait_for(condition: Callable[[], bool], timeout: float = 10.0) -> None:
    """Poll a condition another thread makes true (the writer commits on its own schedule)."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError("condition not reached in time")
        time.sleep(0.005)


def rows(path: Path, table: str, columns: str = "*") -> list[tuple]:
    con = sqlite3.connect(path)
    try:
        return con.execute(f'SELECT {columns} FROM "{table}" ORDER BY id').fetchall()
    finally:
        con.close()


@pytest.fixture
def db(tmp_path: Path) -> Path:
    return tmp_path / "archive" / "journal.sqlite"


@pytest.fixture(params=["sqlite", "postgresql"])
def opened(request) -> Callable[[Path], Archive]:
    """How a query test opens the archive it wrote: the SQLite file itself, or the plant archive
    on PostgreSQL after the file was forwarded there (so one test checks both engines)."""
    if request.param == "sqlite":
        return Archive
    url = request.getfixturevalue("pg_url")

    def forwarded(path: Path) -> Archive:
        Forwarder(path, url, "station").forward_all()
        return Archive(url)

    return forwarded
