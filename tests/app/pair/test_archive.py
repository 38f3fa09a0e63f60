"""Archive continuity across a switchover (issue 26): both stations of a pair forward to one plant
archive under their one name, each its own records with ids of its letter, so none collide; the
standby journals no copy of the primary's records, so none is doubled; the old primary's records
reach the plant archive once it comes back; nothing is lost."""

from __future__ import annotations

import sqlite3
import threading
from dataclasses import replace
from pathlib import Path

import psycopg
import pytest

from app.cli import main
from app.scada.alarms import State
from app.station.config import load_station
from app.station.pair import query
from netplc.simulator import Simulator
from registrar.plant.schema import PAIR_ID_BASE
from registrar.schema import DAY_GLOB
from tests.app.pair.conftest import OPERATOR, TICK_MS, Proxy, Station, make_pair, start_pair, wait_for
from tests.app.pair.test_alarms import BITS, TAGS, alarm

TRIP = "TRIP.ALARM"


def local_records(station: Station) -> list[tuple[int, str, str]]:
    """(id as forwarded: its pid, else its id with its letter's base; kind, text) of every record
    of the station's local archive."""
    letter = station.folder.name
    path = load_station(station.folder).Archive
    con = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
    try:
        out = []
        for (name,) in con.execute("SELECT name FROM sqlite_master WHERE type = 'table' AND name GLOB ?",
                                   (DAY_GLOB,)):
            out += [(i + PAIR_ID_BASE[letter] if pid is None else pid, kind, text or "")
                    for i, kind, text, pid in con.execute(f'SELECT id, kind, text, pid FROM "{name}"')]
        return out
    finally:
        con.close()


def test_the_pair_forwards_to_one_plant_archive_nothing_lost_nothing_doubled(
        tmp_path: Path, node: Simulator, pg_url: str, capsys: pytest.CaptureFixture[str]) -> None:
    a, b = make_pair(tmp_path, node, top=f'Archive = "{pg_url}"\nTags = "tags.csv"\n',
                     files={"tags.csv": TAGS})
    try:
        start_pair(a, b)
        assert a.rt.engine is not None and a.rt.engine.write_bit(BITS[TRIP], 1, user="test")
        wait_for(lambda: alarm(b, TRIP).state is State.UNACK, what="the alarm on both")
        assert a.write(0o4000, 1111).ok
        a.kill()
        wait_for(lambda: b.role == "primary", what="takeover")
        assert b.write(0o4000, 2222).ok
        a.start()  # back as the standby: forwards what it had not yet
        assert a.role == "standby"
        assert a.write(0o4000, 3333).reason.name == "STANDBY"  # A's refusal naming B, A's alone
    finally:
        b.stop()
        a.stop()
    with psycopg.connect(pg_url) as con:
        plant = con.execute("SELECT id, kind, coalesce(text, '') FROM records "
                            "WHERE station = 'pair'").fetchall()
    ours = set(local_records(a) + local_records(b))  # a record both hold has one pid
    assert sorted(plant) == sorted(ours)  # every record of both archives, once, no id of two
    assert len({i for i, _kind, _text in ours}) == len(ours)
    texts = [text for _id, _kind, text in plant]
    assert sum(f"{TRIP} normal -> active-unacknowledged" in t for t in texts) == 1  # not the standby's too
    for done in ("write 04000: 0 -> 1111", "write 04000: 1111 -> 2222", "the primary is B"):
        assert sum(done in t for t in texts) == 1, [r for r in plant if done in r[2]]
    assert any("standby -> primary" in t for t in texts)  # B's takeover, as B journaled it
    for st in (a, b):  # `archive migrate` of either folder sends them as its letter: nothing new
        assert main(["archive", "migrate", str(st.folder), pg_url]) == 0
        assert "0 records copied" in capsys.readouterr().out


# TRIP raised 1 s after its bit: time for the bit to reach the standby before the test holds the
# link, so that the transition is made in a scan the standby never gets, and made again by it; the
# standby waits 2.5 s before it takes over (put after loading, beyond the 1 s that station.toml
# allows: a slow machine still raises TRIP on A first)
DELAYED = TAGS.replace("TRIP,02600,bit,,,,,,,Pump trip,,,,,,,,1,2,,,",
                       "TRIP,02600,bit,,,,,,,Pump trip,,,,,,1.0,,1,2,,,")
PATIENT = 2500 // TICK_MS
RAISED = f"{TRIP} normal -> active-unacknowledged"


def held_transition(tmp_path: Path, node: Simulator, proxy: Proxy, top: str = "") -> tuple[Station, Station]:
    """A and B started, B dialling through `proxy`; TRIP's bit set on A and mirrored to B, then
    the link held from A to B: A raises TRIP in a scan B never gets."""
    a, b = make_pair(tmp_path, node, b_dials=proxy.port, top=f'Tags = "tags.csv"\n{top}',
                     files={"tags.csv": DELAYED})
    proxy.target = load_station(a.folder).redundancy.listen_address[1]  # type: ignore[union-attr]
    b.adjust = lambda st: replace(st, redundancy=replace(st.redundancy, failover_after=PATIENT))
    start_pair(a, b)
    assert a.rt.engine is not None and a.rt.engine.write_bit(BITS[TRIP], 1, user="test")
    wait_for(lambda: b.rt.engine is not None and b.rt.engine.snapshot.get_bit(BITS[TRIP]), what="bit on B")
    proxy.hold()
    assert alarm(a, TRIP).state is State.NORMAL, "raised before the link was held: the machine is too slow"
    wait_for(lambda: alarm(a, TRIP).state is State.UNACK, what="A raises TRIP")
    return a, b


def raised(station: Station) -> int:
    return sum(RAISED in text for _id, _kind, text in local_records(station))


def test_a_transition_of_a_scan_the_standby_never_got_is_archived_once(
        tmp_path: Path, node: Simulator, proxy: Proxy, pg_url: str) -> None:
    """The primary dies with the frame of its last scan on its way: the standby, taking over
    from the scan before, raises the alarm again; the primary had archived it only once the
    standby held that scan, so the plant archive has it once (ids of two letters never collide,
    so its unique key could not have refused the second)."""
    a, b = held_transition(tmp_path, node, proxy, f'Archive = "{pg_url}"\n')
    try:
        a.kill()
        wait_for(lambda: b.role == "primary", what="takeover")
        wait_for(lambda: alarm(b, TRIP).state is State.UNACK, what="B raises TRIP")
    finally:
        b.stop()
        a.stop()
    assert (raised(a), raised(b)) == (0, 1)
    with psycopg.connect(pg_url) as con:
        texts = [t for (t,) in con.execute("SELECT coalesce(text, '') FROM records WHERE station = 'pair'")]
    assert sum(RAISED in t for t in texts) == 1


def test_a_primary_told_that_its_standby_took_over_follows_and_answers_nothing_it_does_not_hold(
        tmp_path: Path, node: Simulator, proxy: Proxy) -> None:
    """A live primary whose frames stopped reaching its standby (a loaded PC) is told by the
    standby that took over, and follows: no flip-back. A write it applied in a scan the standby
    never got is not acknowledged (the new primary never had it), and its record of the alarm
    raised in such a scan is not archived: the new primary raises it once."""
    a, b = held_transition(tmp_path, node, proxy)
    try:
        assert a.rt.commands is not None
        ticket = a.rt.commands.write_word(OPERATOR, 0o4000, 4321)  # applied by A, never held by B
        wait_for(lambda: a.word(0o4000) == 4321, what="A applies the write")
        wait_for(lambda: b.role == "primary" and a.role == "standby", what="B takes over, A follows")
        wait_for(lambda: alarm(b, TRIP).state is State.UNACK, what="B raises TRIP")
        wait_for(lambda: b.rt.pair is not None and b.rt.pair.status().link, what="A is B's standby")
        assert not ticket.done() or not ticket.result().ok
        assert b.word(0o4000) != 4321
        assert b.write(0o4000, 1357).ok  # B leads, with A its standby
        wait_for(lambda: a.word(0o4000) == 1357, what="A follows B")
        assert any("the partner took over from scan" in t for t in a.texts())
    finally:
        b.stop()
        a.stop()
    assert (raised(a), raised(b)) == (0, 1)


def test_a_status_query_answers_no_write_that_waits_for_the_standby(
        tmp_path: Path, node: Simulator, proxy: Proxy) -> None:
    """The end of a connection to the pair link that is not the link (`redundancy status`) is no
    word about the standby: a write waiting for it stays unanswered."""
    a, b = make_pair(tmp_path, node, b_dials=proxy.port)
    proxy.target = load_station(a.folder).redundancy.listen_address[1]  # type: ignore[union-attr]
    b.adjust = lambda st: replace(st, redundancy=replace(st.redundancy, failover_after=PATIENT))
    try:
        start_pair(a, b)
        proxy.hold()  # A's frames lost on their way: B acknowledges nothing more
        assert a.rt.commands is not None and a.rt.pair is not None
        ticket = a.rt.commands.write_word(OPERATOR, 0o4000, 99)
        wait_for(lambda: a.word(0o4000) == 99, what="A applies the write")
        links = sum(t.name == "pair link" for t in threading.enumerate())
        assert query(f"127.0.0.1:{a.rt.pair.port}")["role"] == "primary"
        wait_for(lambda: sum(t.name == "pair link" for t in threading.enumerate()) == links,
                 what="the query's connection ended on A")
        # a commit and a retentive save asked for now end after any the write's answer waited for
        committed, saved = threading.Event(), threading.Event()
        assert a.rt.store is not None and a.rt.retainer is not None
        a.rt.store.after_commit(committed.set)
        a.rt.retainer.after_save(saved.set)
        wait_for(lambda: committed.is_set() and saved.is_set(), what="A's commit and save")
        assert not ticket.done()
    finally:
        b.stop()
        a.stop()


def whole_pair(tmp_path: Path, node: Simulator, pg_url: str,
               proxy: Proxy | None = None) -> tuple[Station, Station]:
    """A and B started, forwarding to the plant archive (B dialling through `proxy`, if given),
    the pair whole."""
    a, b = make_pair(tmp_path, node, b_dials=proxy.port if proxy else None,
                     top=f'Archive = "{pg_url}"\nTags = "tags.csv"\n', files={"tags.csv": TAGS})
    if proxy is not None:
        proxy.target = load_station(a.folder).redundancy.listen_address[1]  # type: ignore[union-attr]
    start_pair(a, b)
    wait_for(lambda: a.rt.pair is not None and a.rt.pair.status().link, what="the pair whole")
    return a, b


def raised_in_plant(pg_url: str) -> int:
    with psycopg.connect(pg_url) as con:
        return sum(RAISED in t for (t,) in con.execute(
            "SELECT coalesce(text, '') FROM records WHERE station = 'pair'"))


def test_a_transition_of_a_scan_the_standby_acknowledged_survives_a_primary_that_never_read_that(
        tmp_path: Path, node: Simulator, proxy: Proxy, pg_url: str) -> None:
    """The standby acknowledged the scan that raised TRIP; the primary died before it read that
    acknowledgement, so it had not archived the transition, and the new primary, holding the
    raised state, raises nothing again. The standby keeps the primary's records of the scans it
    holds until the primary says they are on its disk, and archives them when it takes over."""
    a, b = whole_pair(tmp_path, node, pg_url, proxy)
    try:
        proxy.hold(back=True)  # B's acknowledgements lost on their way: A archives nothing more
        assert a.rt.engine is not None and a.rt.engine.write_bit(BITS[TRIP], 1, user="test")
        wait_for(lambda: alarm(b, TRIP).state is State.UNACK, what="B holds the scan that raised TRIP")
        a.kill()
        wait_for(lambda: b.role == "primary", what="takeover")
    finally:
        b.stop()
        a.stop()
    assert (raised(a), raised(b)) == (0, 1)
    assert raised_in_plant(pg_url) == 1


def test_a_transition_the_primary_archived_but_had_not_on_disk_when_it_died_survives(
        tmp_path: Path, node: Simulator, pg_url: str) -> None:
    """The primary read the acknowledgement and handed TRIP's transition to its archive, which
    had not committed it when the primary died (here: its archive locked by another writer, as a
    slow disk would keep it): the standby, told of no commit, archives it when it takes over."""
    a, b = whole_pair(tmp_path, node, pg_url)
    lock = sqlite3.connect(load_station(a.folder).Archive, timeout=10)
    try:
        lock.execute("BEGIN IMMEDIATE")  # A's archive commits nothing more
        assert a.rt.engine is not None and a.rt.engine.write_bit(BITS[TRIP], 1, user="test")
        wait_for(lambda: alarm(b, TRIP).state is State.UNACK, what="B holds the scan that raised TRIP")
        assert a.rt.pair is not None
        pair = a.rt.pair  # its records wait for B's acknowledgement, then go to its archive
        wait_for(lambda: not pair._held, what="A hands the transition to its archive")
        a.kill()  # its archive's queue dies with it
        lock.rollback()
        wait_for(lambda: b.role == "primary", what="takeover")
    finally:
        lock.close()
        b.stop()
        a.stop()
    assert (raised(a), raised(b)) == (0, 1)
    assert raised_in_plant(pg_url) == 1


def test_a_record_both_stations_archive_is_one_record_of_the_plant_archive(
        tmp_path: Path, node: Simulator, proxy: Proxy, pg_url: str) -> None:
    """IntoStandBy while the standby's acknowledgements are late: the new primary archives the
    transition its partner may not have on disk, and the old primary archives it too once the
    link ends; with one identity (its pid) the plant archive refuses the second copy."""
    a, b = whole_pair(tmp_path, node, pg_url, proxy)
    try:
        proxy.hold(back=True)
        assert a.rt.engine is not None and a.rt.engine.write_bit(BITS[TRIP], 1, user="test")
        wait_for(lambda: alarm(b, TRIP).state is State.UNACK, what="B holds the scan that raised TRIP")
        assert a.rt.pair is not None and a.rt.pair.into_standby("test", wait=5)
        wait_for(lambda: b.role == "primary", what="the handover")
        proxy.held.clear()  # B's frames reach A again (else A, hearing none, would take over)
        a.stop()  # the link ends: A archives what waited for B's acknowledgement
    finally:
        b.stop()
        a.stop()
    assert (raised(a), raised(b)) == (1, 1)
    assert raised_in_plant(pg_url) == 1
