"""No split brain (issue 26): the link between the pair is cut while both run (a proxy between
them that the test stops); with the plant archive's PostgreSQL as the arbiter exactly one acts as
primary, and both journal it. Without an arbiter both act, as the manual says
(docs/integration/redundancy.md)."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from app.station.config import load_station
from netplc.simulator import Simulator
from tests.app.pair.conftest import TICK_MS, Proxy, Station, make_pair, wait_for


@pytest.fixture
def proxy() -> Iterator[Proxy]:
    p = Proxy()
    yield p
    p.cut()


def cut_pair(tmp_path: Path, node: Simulator, proxy: Proxy, arbiter: str) -> tuple[Station, Station]:
    a, b = make_pair(tmp_path, node, arbiter, b_dials=proxy.port)
    proxy.target = load_station(a.folder).redundancy.listen_address[1]  # type: ignore[union-attr]
    a.start()
    b.start()
    assert (a.role, b.role) == ("primary", "standby")
    proxy.cut()
    time.sleep(6 * TICK_MS / 1000)  # twice failover_after: a standby that may lead has led by now
    return a, b


def test_with_the_arbiter_exactly_one_primary_when_the_link_is_cut(
        tmp_path: Path, node: Simulator, proxy: Proxy, pg_url: str) -> None:
    a, b = cut_pair(tmp_path, node, proxy, pg_url)
    try:
        wait_for(lambda: any("the arbiter decides" in t for t in b.texts()), what="B asked the arbiter")
        assert (a.role, b.role) == ("primary", "standby")
        assert any("link to the partner lost (primary)" in t for t in a.texts())
        assert any("link to the partner lost (standby)" in t for t in b.texts())
        assert "link DOWN" in b.rt.status().pair
    finally:
        b.stop()
        a.stop()


def test_without_an_arbiter_both_act(
        tmp_path: Path, node: Simulator, proxy: Proxy) -> None:
    a, b = cut_pair(tmp_path, node, proxy, "none")
    try:
        wait_for(lambda: b.role == "primary", what="B leads too")
        assert a.role == "primary"
    finally:
        b.stop()
        a.stop()
