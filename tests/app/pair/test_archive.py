"""Archive continuity across a switchover (issue 26): both stations of a pair forward to one plant
archive under their one name, each its own records with ids of its letter, so none collide; the
standby journals no copy of the primary's records, so none is doubled; the old primary's records
reach the plant archive once it comes back; nothing is lost."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import psycopg
import pytest

from app.cli import main
from app.scada.alarms import State
from app.station.config import load_station
from netplc.simulator import Simulator
from registrar.plant.schema import PAIR_ID_BASE
from registrar.schema import DAY_GLOB
from tests.app.pair.conftest import Station, make_pair, wait_for
from tests.app.pair.test_alarms import BITS, TAGS, alarm

TRIP = "TRIP.ALARM"


def local_records(station: Station) -> list[tuple[int, str, str]]:
    """(id as forwarded, kind, text) of every record of the station's local archive."""
    letter = station.folder.name
    path = load_station(station.folder).Archive
    con = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
    try:
        out = []
        for (name,) in con.execute("SELECT name FROM sqlite_master WHERE type = 'table' AND name GLOB ?",
                                   (DAY_GLOB,)):
            out += [(i + PAIR_ID_BASE[letter], kind, text or "")
                    for i, kind, text in con.execute(f'SELECT id, kind, text FROM "{name}"')]
        return out
    finally:
        con.close()


def test_the_pair_forwards_to_one_plant_archive_nothing_lost_nothing_doubled(
        tmp_path: Path, node: Simulator, pg_url: str, capsys: pytest.CaptureFixture[str]) -> None:
    a, b = make_pair(tmp_path, node, top=f'Archive = "{pg_url}"\nTags = "tags.csv"\n',
                     files={"tags.csv": TAGS})
    try:
        a.start()
        b.start()
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
    ours = local_records(a) + local_records(b)
    assert sorted(plant) == sorted(ours)  # every record of both archives, once, no id of two
    texts = [text for _id, _kind, text in plant]
    assert sum(f"{TRIP} normal -> active-unacknowledged" in t for t in texts) == 1  # not the standby's too
    for done in ("write 04000: 0 -> 1111", "write 04000: 1111 -> 2222", "the primary is B"):
        assert sum(done in t for t in texts) == 1, [r for r in plant if done in r[2]]
    assert any("standby -> primary" in t for t in texts)  # B's takeover, as B journaled it
    for st in (a, b):  # `archive migrate` of either folder sends them as its letter: nothing new
        assert main(["archive", "migrate", str(st.folder), pg_url]) == 0
        assert "0 records copied" in capsys.readouterr().out
