"""No split brain (issue 26): the link between the pair is cut while both run (a proxy between
them that the test stops); with the plant archive's PostgreSQL as the arbiter exactly one acts as
primary, and both journal it. Without an arbiter both act, as the manual says
(docs/operations/redundancy.md)."""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

from app.station.config import load_station
from netplc.simulator import Simulator
from registrar.plant.lease import LEASE_CLIENT_GIVES_UP, LEASE_SERVER_DROP, Lease
from tests.app.pair.conftest import OPERATOR, Proxy, Station, make_pair, start_pair, wait_for


def cut_pair(tmp_path: Path, node: Simulator, proxy: Proxy, arbiter: str) -> tuple[Station, Station]:
    a, b = make_pair(tmp_path, node, arbiter, b_dials=proxy.port)
    proxy.target = load_station(a.folder).redundancy.listen_address[1]  # type: ignore[union-attr]
    start_pair(a, b)
    assert (a.role, b.role) == ("primary", "standby")
    proxy.cut()
    return a, b


def test_with_the_arbiter_exactly_one_primary_when_the_link_is_cut(
        tmp_path: Path, node: Simulator, proxy: Proxy, pg_url: str) -> None:
    a, b = cut_pair(tmp_path, node, proxy, pg_url)
    try:
        assert b.rt.pair is not None
        time.sleep(2 * b.rt.pair.failover)  # twice failover_after: a standby that may lead has led by now
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


def test_a_primary_that_loses_the_arbiter_and_its_partner_steps_down(
        tmp_path: Path, node: Simulator, proxy: Proxy, pg_url: str) -> None:
    """A reaches the arbiter through a proxy of its own: both cut, A is alone and cannot know
    whether B leads, so it steps down; B, which still reaches the arbiter, takes the lease."""
    to_arbiter = Proxy()
    port = int(pg_url.rsplit(":", 1)[1].split("/")[0])
    to_arbiter.target = port
    a, b = make_pair(tmp_path, node, pg_url, b_dials=proxy.port)
    via_proxy = pg_url.replace(f":{port}/", f":{to_arbiter.port}/")
    a.adjust = lambda st: replace(st, redundancy=replace(st.redundancy, arbiter=via_proxy))  # type: ignore[arg-type]
    proxy.target = load_station(a.folder).redundancy.listen_address[1]  # type: ignore[union-attr]
    try:
        start_pair(a, b)
        assert (a.role, b.role) == ("primary", "standby")
        to_arbiter.cut()
        proxy.cut()
        wait_for(lambda: a.role == "standby", what="A steps down")
        wait_for(lambda: b.role == "primary", what="B takes the lease")
        assert a.role == "standby"
        wait_for(lambda: any("lost the arbiter" in t and "and the partner" in t for t in a.texts()),
                 timeout=10, what="A journals why it stepped down")
        assert a.rt.commands is not None
        assert not a.rt.commands.write_word(OPERATOR, 0o4000, 5).result(3).ok  # A refuses
    finally:
        to_arbiter.cut()
        b.stop()
        a.stop()


def test_the_lease_session_is_dropped_by_the_server_only_after_the_primary_gave_up(pg_url: str) -> None:
    """A network that parts the primary from the arbiter: the primary's check fails first."""
    lease = Lease(pg_url, "pair")
    try:
        assert lease.take()
        assert lease._con is not None
        settings = dict(lease._con.execute(
            "SELECT name, setting FROM pg_settings WHERE name LIKE 'tcp_keepalives_%'").fetchall())
        dropped = int(settings["tcp_keepalives_idle"]) + int(settings["tcp_keepalives_interval"]) \
            * int(settings["tcp_keepalives_count"])
        assert dropped == LEASE_SERVER_DROP > 2 * LEASE_CLIENT_GIVES_UP
        gives_up = lease._con.info.get_parameters()["tcp_user_timeout"]
        assert gives_up == str(round(LEASE_CLIENT_GIVES_UP * 1000))
    finally:
        lease.release()
