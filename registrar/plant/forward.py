"""Store-and-forward: committed records of the local SQLite archive copied to the plant archive.

The station never waits for PostgreSQL: the Store writes locally as always, and this thread reads
what the Store has committed, day table by day table in id order, and sends it in batches by
binary COPY. The last id sent per station and day lives in the plant archive's `forwarded` table,
written in the batch's own transaction, so a batch is in PostgreSQL with its position or not at
all: PostgreSQL away, the network down, a SIGKILL in the middle of a batch (the server rolls the
open transaction back) all end in a replay from the committed position, and the unique key
(station, day, id) refuses anything sent twice. While the copy lags by more than a minute the
station is told, once by a 'system' record and continuously by `stats.lag`.

Each station of a hot-standby pair forwards its own archive, under the pair's one name, as its
letter (schema.py: PAIR_ID_BASE, `forwarded_pair`): both run their forwarders whatever their
role, so the records a primary committed before it died are forwarded when it comes back, and a
standby journals no copy of the primary's records (its alarms are the primary's, adopted, not
evaluated: app/scada/station.py) but those a takeover leaves it, which both may hold: those have
a pid (app/station/pair.py), sent as their id, so the plant archive keeps one.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import logging
import sqlite3
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import quote

import psycopg

from app.scada.words import Words, phrase, words
from netplc.records import Record
from registrar.plant import schema as plant
from registrar.reading import ArchiveError
from registrar.schema import DAY_GLOB, KEYED_TAG_ROWS_SQL, has_pid, parse_table_name, table_name

logger = logging.getLogger(__name__)

SOURCE = "forwarder"
BATCH = 20_000  # records per PostgreSQL transaction
LAG_ALARM = 60.0  # seconds of lag that the station is told about
RETRY_MAX = 5.0  # seconds between attempts while PostgreSQL is away
Progress = Callable[[int, int], None]  # (records sent, records to send)


@dataclass(frozen=True)
class ForwardStats:
    forwarded: int = 0  # records copied since the start
    backlog: int = 0  # records committed locally and not yet in the plant archive
    lag: float = 0.0  # seconds the oldest of them has waited (0 when caught up)
    connected: bool = False
    last_error: str = ""  # why the last attempt failed ("" once forwarding works)


class Forwarder:
    def __init__(
        self,
        local: str | Path,
        url: str,
        station: str,
        *,
        keep_days: int = 0,
        sink: Callable[[Record], None] | None = None,
        wallclock: Callable[[], float] = time.time,
        interval: float = 0.5,
        batch: int = BATCH,
        lag_alarm: float = LAG_ALARM,
        letter: str = "",
        say: Words | None = None,
    ) -> None:
        """`letter`: this station's in a hot-standby pair ("A", "B"), "" for a station alone;
        `say`: the station's words for its records (app/scada/words.py)."""
        self.local = Path(local)
        self.say = say or words()
        self.url = url
        self.station = station
        self.keep_days = keep_days
        self.sink = sink  # where the 'system' records go (the station's put)
        self.wallclock = wallclock
        self.interval = interval
        self.batch = batch
        self.lag_alarm = lag_alarm
        self.letter = letter
        self.id_base = plant.PAIR_ID_BASE[letter] if letter else 0
        self._pg: psycopg.Connection | None = None
        self._sqlite: sqlite3.Connection | None = None
        self._tz: dt.tzinfo | None = None
        self._done: dict[dt.date, int] = {}  # local day -> last id in the plant archive
        self._known: set[tuple] = set()  # (partition, series key) already listed in `series`
        self._pid: dict[str, bool] = {}  # local day table -> whether it has the pid column
        self._partitions: set[dt.date] = set()
        self._wake = threading.Event()
        self._stopping = threading.Event()
        self._thread: threading.Thread | None = None
        self._started = wallclock()
        self._forwarded = self._backlog = 0
        self._lag = 0.0
        self._max_lag = 0.0
        self._alarmed = False
        self._answered = False  # the plant archive answered once (the position is known)
        self._published = False  # the station's meta and catalog are in the plant archive
        self._error = ""

    @property
    def stats(self) -> ForwardStats:
        return ForwardStats(self._forwarded, self._backlog, self._lag, self._pg is not None, self._error)

    # --- lifecycle -----------------------------------------------------------------------------

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="plant-forwarder", daemon=True)
        self._thread.start()

    def wake(self) -> None:
        """Look for new records now (the Store calls this after a commit)."""
        self._wake.set()

    def close(self, timeout: float = 10.0) -> None:
        """Send what the local archive holds if the plant archive answers, then stop."""
        self._stopping.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout)
            self._thread = None
        self._disconnect()

    def forward_all(self, progress: Progress | None = None) -> int:
        """Copy everything committed now, in the caller's thread (`archive migrate`); raises
        ArchiveError when the plant archive fails, sqlite3.Error when the local one does. The
        number of records sent."""
        try:
            self._connect()
            total = self._measure()[0]
            sent = 0
            while n := self._cycle():
                sent += n
                if progress is not None:
                    progress(sent, total)
            return sent
        except psycopg.Error as e:
            raise ArchiveError(str(e)) from e
        finally:
            self._disconnect()

    # --- the thread ----------------------------------------------------------------------------

    def _run(self) -> None:
        wait = 0.0
        while True:
            self._wake.wait(wait)
            self._wake.clear()
            stopping = self._stopping.is_set()
            if stopping and self._pg is None:
                break
            try:
                if self._pg is None:
                    self._connect()
                n = self._cycle()
                self._error = ""
                wait = 0.0 if n else self.interval  # more may wait (this day or the next)
            except (psycopg.Error, sqlite3.Error, OSError) as e:  # PostgreSQL away: retried
                error = f"plant archive: {e}".strip()
                if error != self._error:  # once per cause, not at every retry
                    logger.warning("forwarding to the plant archive failed, retrying: %s", error)
                self._error = error
                self._disconnect()
                wait = min(RETRY_MAX, max(2 * wait, self.interval))
                n = 0
            self._watch_lag()
            if stopping and (n == 0 or self._pg is None):
                break

    def _watch_lag(self) -> None:
        try:
            self._backlog, oldest = self._measure()
        except sqlite3.Error:
            return  # the same file fails the next cycle, which says why
        now = self.wallclock()
        if oldest is None:
            self._lag = 0.0
        else:  # before the first answer the position is unknown: count from the start
            self._lag = max(0.0, now - (oldest if self._answered else max(oldest, self._started)))
        self._max_lag = max(self._max_lag, self._lag)
        if self._lag > self.lag_alarm and not self._alarmed:
            self._alarmed = True
            self._tell("plant lags", lag=self._lag, why=self._error or phrase("plant slow"))
        elif self._alarmed and self._backlog == 0:
            self._alarmed = False
            self._tell("plant caught up", lag=self._max_lag)
            self._max_lag = 0.0

    def _tell(self, name: str, /, **values: object) -> None:
        if self.sink is not None:
            self.sink(Record(self.wallclock(), "system", source=SOURCE, text=self.say(name, **values)))

    # --- the two ends --------------------------------------------------------------------------

    def _local_con(self) -> sqlite3.Connection | None:
        if self._sqlite is None:
            if not self.local.is_file():
                return None
            uri = f"file:{quote(str(self.local.resolve()))}?mode=ro"
            self._sqlite = sqlite3.connect(uri, uri=True, isolation_level=None, check_same_thread=False)
        return self._sqlite

    def _connect(self) -> None:
        con = plant.connect(self.url)
        connected = False
        try:
            self._tz = plant.ensure_schema(con)
            self._published = False
            self._publish(con)
            self._done = {d: n for d, n in (con.execute(
                "SELECT day, last_id FROM forwarded_pair WHERE station = %s AND letter = %s",
                (self.station, self.letter)) if self.letter else con.execute(
                "SELECT day, last_id FROM forwarded WHERE station = %s", (self.station,)))}
            self._known.clear()
            self._partitions = set(plant.partitions(con))
            self._retain(con)
            self._answered = True
            connected = True
        finally:
            if not connected:  # whatever ended it, Ctrl+C too: no connection left open
                con.close()
        self._pg = con

    def _disconnect(self) -> None:
        con, self._pg = self._pg, None
        if con is not None:
            with contextlib.suppress(psycopg.Error):
                con.close()
        local, self._sqlite = self._sqlite, None
        if local is not None:
            local.close()

    def _publish(self, con: psycopg.Connection) -> None:
        """The station's meta, message catalog and tags, as its local archive holds them (read in
        one transaction, so tags and `tags_since` agree though the Store rewrites them)."""
        local = self._local_con()
        if local is None:
            return  # the Store has not made the file yet: published with the first batch
        local.execute("BEGIN")
        try:
            meta = local.execute("SELECT key, value FROM meta").fetchall()
            messages = local.execute("SELECT number, grp, type, text FROM messages").fetchall()
            tags = (local.execute(KEYED_TAG_ROWS_SQL).fetchall() if local.execute(
                "SELECT 1 FROM sqlite_master WHERE name = 'tags'").fetchone() else [])
        finally:
            local.execute("COMMIT")
        since = dict(meta).get("tags_since")
        with con.transaction(), con.cursor() as cur:
            cur.executemany("INSERT INTO meta VALUES (%s, %s, %s) ON CONFLICT (station, key) "
                            "DO UPDATE SET value = excluded.value",
                            [(self.station, k, v) for k, v in meta])
            cur.execute("DELETE FROM messages WHERE station = %s", (self.station,))
            cur.executemany("INSERT INTO messages VALUES (%s, %s, %s, %s, %s)",
                            [(self.station, *m) for m in messages])
            plant.publish_tags(con, self.station, tags, int(since) if since and since.isdigit() else None)
        self._published = True

    def _retain(self, con: psycopg.Connection) -> None:
        oldest = self._oldest()
        if oldest is not None and any(d < oldest for d in self._partitions):
            plant.drop_days_before(con, oldest)
            self._partitions = set(plant.partitions(con))

    def _oldest(self) -> dt.date | None:
        if self.keep_days <= 0:
            return None
        today = dt.datetime.fromtimestamp(self.wallclock(), self._tz).date()
        return today - dt.timedelta(days=self.keep_days - 1)

    # --- copying -------------------------------------------------------------------------------

    def _days(self, local: sqlite3.Connection) -> list[tuple[dt.date, str, int]]:
        """The local day tables with records not yet forwarded, oldest first, and their max id."""
        names = [n for (n,) in local.execute(
            "SELECT name FROM sqlite_master WHERE type = 'table' AND name GLOB ?", (DAY_GLOB,))]
        oldest = self._oldest()
        out = []
        for day, name in sorted((d, n) for n in names if (d := parse_table_name(n)) is not None):
            if oldest is not None and day < oldest:
                continue
            hi = local.execute(f'SELECT max(id) FROM "{name}"').fetchone()[0] or 0
            if hi > self._done.get(day, 0):
                out.append((day, name, hi))
        return out

    def _measure(self) -> tuple[int, float | None]:
        """Records waiting, and the time of the oldest of them."""
        local = self._local_con()
        if local is None:
            return 0, None
        days = self._days(local)
        if not days:
            return 0, None
        backlog = sum(hi - self._done.get(day, 0) for day, _name, hi in days)
        day, name, _hi = days[0]
        row = local.execute(f'SELECT ts FROM "{name}" WHERE id > ? ORDER BY id LIMIT 1',
                            (self._done.get(day, 0),)).fetchone()
        return backlog, (row[0] / 1000 if row else None)

    def _cycle(self) -> int:
        """Send one batch of the oldest day with records waiting; the number sent."""
        local = self._local_con()
        con = self._pg
        assert con is not None
        if local is None:
            return 0
        if not self._published:
            self._publish(con)
        days = self._days(local)
        if not days:
            return 0
        day, name, _hi = days[0]
        done = self._done.get(day, 0)
        pid = self._pid.get(name)
        if pid is None:
            pid = self._pid[name] = has_pid(local, name)
        rows = local.execute(
            f'SELECT id, ts, kind, grp, type, source, number, value, text, {"pid" if pid else "NULL"} '
            f'FROM "{name}" WHERE id > ? ORDER BY id LIMIT ?', (done, self.batch)).fetchall()
        if not rows:
            return 0
        station, base = self.station, self.id_base
        # a pair's record that both stations may hold is keyed by its pid, the same in both
        out = [(station, day, r[0] + base if r[9] is None else r[9], *r[1:9]) for r in rows]
        last = rows[-1][0]
        try:
            self._send(con, day, out, last, plant.copy_rows)
        except psycopg.errors.UniqueViolation:
            # Rows already there (a position lost with a dropped plant day, or a migrate run
            # beside the station): keep the ones that are new.
            self._send(con, day, out, last, plant.insert_rows_once)
        except psycopg.DataError:
            self._send(con, day, [_clean(r) for r in out], last, plant.insert_rows_once)
        self._done[day] = last
        self._forwarded += len(rows)
        return len(rows)

    def _send(self, con: psycopg.Connection, day: dt.date, rows: list[tuple], last: int,
              write: Callable[[psycopg.Connection, list[tuple]], None]) -> None:
        tz = self._tz
        first_day, last_day = plant.plant_day(rows[0][3], tz), plant.plant_day(rows[-1][3], tz)
        if first_day == last_day:
            days = {first_day: rows}
        else:  # across a plant-zone midnight (or a clock set back): split by partition
            days = {}
            for row in rows:
                days.setdefault(plant.plant_day(row[3], tz), []).append(row)
        try:
            with con.transaction():
                if not set(days) <= self._partitions:
                    plant.ensure_partitions(con, days, tz)
                write(con, rows)
                self._list_series(con, days)
                if self.letter:
                    con.execute("INSERT INTO forwarded_pair VALUES (%s, %s, %s, %s) ON CONFLICT "
                                "(station, letter, day) DO UPDATE SET last_id = excluded.last_id",
                                (self.station, self.letter, day, last))
                else:
                    con.execute("INSERT INTO forwarded VALUES (%s, %s, %s) ON CONFLICT (station, day) "
                                "DO UPDATE SET last_id = excluded.last_id", (self.station, day, last))
        except psycopg.Error:
            self._known.clear()
            self._partitions.clear()
            raise
        if not set(days) <= self._partitions:
            self._partitions |= set(days)
            self._retain(con)

    def _list_series(self, con: psycopg.Connection, days: dict[dt.date, list[tuple]]) -> None:
        new = []
        for day, rows in days.items():
            part = table_name(day)
            keys = {(part, r[4:8]) for r in rows if r[4] == "data"} - self._known
            new += keys
        if new:
            with con.cursor() as cur:
                cur.executemany("INSERT INTO series VALUES (%s, %s, %s, %s, %s, %s) ON CONFLICT DO NOTHING",
                                [(self.station, part, *key) for part, key in new])
            self._known.update(new)


def _clean(row: tuple) -> tuple:
    """PostgreSQL text holds no NUL character: it is shown as U+FFFD."""
    return tuple(v.replace("\x00", "\ufffd") if isinstance(v, str) else v for v in row)
