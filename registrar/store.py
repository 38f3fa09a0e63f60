"""The archive writer: records from the engine and the station go to daily SQLite tables.

`put` is called from the scan thread, so it only appends to a bounded deque; a writer thread of
its own commits what has queued at least every `flush_interval` seconds, one transaction per batch
(the transaction, not the insert, is what costs in SQLite). WAL with synchronous=NORMAL keeps
every committed batch through a crash of the process; a crash loses at most the batch being
written. When the disk fails the batch is kept and retried, and when the queue is full records are
dropped and counted; both are reported in 'system' records and in `stats`, never silently.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import logging
import math
import operator
import sqlite3
import stat
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from app.scada.table import TagTable
from app.scada.words import Words, words
from netplc.records import Record
from netplc.textfile import kind
from registrar.catalog import Catalog
from registrar.schema import (
    DAY_COLUMNS_SQL,
    DAY_GLOB,
    MESSAGES_SQL,
    META_SQL,
    SCHEMA_VERSION,
    SERIES_SQL,
    TAG_FIELDS,
    TAG_ROWS_SQL,
    TAGS_SQL,
    add_tag_source,
    aux_fill_sql,
    aux_sql,
    fts_table,
    has_pid,
    index_sql,
    local_day_bounds,
    local_zone_key,
    minutes_table,
    parse_table_name,
    table_name,
    tag_rows,
)

logger = logging.getLogger(__name__)

SOURCE = "registrar"
BATCH_MAX = 50_000  # records per transaction: bounds the time one commit holds the writer
RETRY_MAX = 5.0  # seconds between attempts while the disk keeps failing
BUSY_TIMEOUT_MS = 1000
SQLITE_HEADER = b"SQLite format 3\x00"  # the first 16 bytes of every SQLite database file

Row = tuple[int, str, int | None, int | None, str | None, int | None, float | None, str | None, int | None]
_TS = operator.attrgetter("ts")
_REST = operator.attrgetter("kind", "grp", "type", "source", "number", "value", "text", "pid")
_KIND, _KEY = operator.itemgetter(1), operator.itemgetter(1, 2, 3, 4)


# What a record that breaks the Record contract raises while its row is built or bound.
_MALFORMED = (TypeError, ValueError, OverflowError, AttributeError, sqlite3.InterfaceError,
              sqlite3.ProgrammingError)
_INT64 = range(-(2**63), 2**63)


def _well_formed(r: object) -> bool:
    return (isinstance(r, Record) and isinstance(r.ts, int | float) and math.isfinite(r.ts)
            and abs(r.ts) < 1e12 and isinstance(r.kind, str)
            and all(v is None or (isinstance(v, int) and v in _INT64)
                    for v in (r.grp, r.type, r.number, r.pid))
            and all(v is None or isinstance(v, str) for v in (r.source, r.text))
            and (r.value is None or isinstance(r.value, float)
                 or (isinstance(r.value, int) and r.value in _INT64)))


def _rollback(con: sqlite3.Connection) -> None:
    if con.in_transaction:
        with contextlib.suppress(sqlite3.Error):  # if it fails, SQLite has rolled back already
            con.execute("ROLLBACK")


def _day_of(ms: int) -> tuple[int, int, str]:
    """The [start, end) milliseconds of the local day holding `ms`, and its table's name."""
    day, start, end = local_day_bounds(ms / 1000)
    return round(start * 1000), round(end * 1000), table_name(day)


def archive_problem(path: Path) -> str | None:
    """Why the archive file at `path` cannot be opened, found without writing anything (what
    `check` reports and a start refuses); None when it is an SQLite database, or is not there yet
    and can be created."""
    try:
        info = path.stat()
    except (FileNotFoundError, NotADirectoryError):
        folder = next((f for f in path.parents if f.exists()), None)
        if folder is not None and not folder.is_dir():
            return f"cannot create it: {folder} is a file, not a folder"
        return None
    except OSError as e:
        return e.strerror or str(e)
    if not stat.S_ISREG(info.st_mode):
        return f"it is {kind(info.st_mode)}, not an archive file"
    try:
        with path.open("rb") as f:
            head = f.read(len(SQLITE_HEADER))
    except OSError as e:
        return f"cannot read it: {e.strerror or e}"
    if head and head != SQLITE_HEADER:  # SQLite makes an empty file a database
        return "not an SQLite database: is another file named as the Archive?"
    return None


class _Barrier:
    """A place in the queue: its callback runs once every record queued before it is committed."""

    __slots__ = ("callback",)

    def __init__(self, callback: Callable[[], None]) -> None:
        self.callback = callback


@dataclass(frozen=True)
class StoreStats:
    queued: int = 0  # records waiting in the queue
    committed: int = 0  # records known to be on disk
    batches: int = 0  # transactions committed
    overflows: int = 0  # times the queue filled up
    dropped: int = 0  # records lost because the queue was full
    last_error: str = ""  # the last write failure ("" once writing works again)
    db_path: str = ""


class Store:
    def __init__(
        self,
        path: str | Path,
        *,
        catalog: Catalog | None = None,
        keep_days: int = 0,
        wallclock: Callable[[], float] = time.time,
        queue_size: int = 100_000,
        flush_interval: float = 1.0,
        on_commit: Callable[[int], None] | None = None,
        tags: TagTable | None = None,
        station: str = "",
        say: Words | None = None,
    ) -> None:
        self.path = Path(path)
        self.say = say or words()  # its own records in the station's language (app/scada/words.py)
        self.station = station  # its name, kept in `meta` so the file says whose it is
        self.catalog = catalog or Catalog()
        self.tags = tags or TagTable()  # copied in, like the catalog, so the file explains its data
        self.keep_days = keep_days
        self.wallclock = wallclock
        self.queue_size = queue_size
        self.flush_interval = flush_interval
        self.on_commit = on_commit  # called in the writer thread with the committed total
        self._queue: deque[Record] = deque()
        self._wake = threading.Event()
        self._stopping = threading.Event()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()  # guards the overflow counters (put runs in several threads)
        self._overflowing = False
        # Counters: committed, batches and last_error are written by the writer thread only;
        # overflows and dropped by producers, under the lock.
        self._committed = self._batches = self._overflows = self._dropped = 0
        self._last_error = ""
        self._con: sqlite3.Connection | None = None
        self._known: dict[str, set[tuple]] = {}  # day table -> data series keys already listed
        self._day: tuple[int, int, str] = (0, 0, "")  # [start, end) ms of the last local day seen
        self._reported_drops = 0
        self._failing_since: float | None = None
        self._new_day = False  # a day table was opened: run retention after the commit
        self._barriers = 0  # _Barrier items in the queue (under the lock)
        self._due: list[_Barrier] = []  # barriers taken with the batch being written

    # --- producer side (any thread) ------------------------------------------------------------

    def put(self, record: Record) -> None:
        """Queue a record; never blocks. A full queue drops the record and counts it."""
        queue = self._queue
        if len(queue) >= self.queue_size:
            with self._lock:
                if not self._overflowing:
                    self._overflowing = True
                    self._overflows += 1
                self._dropped += 1
            self._wake.set()
            return
        queue.append(record)
        if len(queue) >= BATCH_MAX:
            self._wake.set()

    def after_commit(self, callback: Callable[[], None], wake: bool = True) -> None:
        """Call `callback()` in the writer thread once every record put before this call is
        committed (durable through a crash of the process): a Modbus write is answered only then.
        The writer is woken at once, so the wait is one commit rather than a flush interval, and
        the barriers of one moment share that commit; `wake` False: no commit of its own, the
        next one's (a pair's primary telling its standby what it has on disk, app/station/pair.py).
        A record dropped by a full queue is never committed, so writers check `room()` before
        they produce records that must not be lost."""
        with self._lock:
            self._barriers += 1
            self._queue.append(_Barrier(callback))  # type: ignore[arg-type]
        if wake:
            self._wake.set()

    def room(self) -> int:
        """Records the queue takes before it drops."""
        return self.queue_size - len(self._queue)

    @property
    def stats(self) -> StoreStats:
        return StoreStats(len(self._queue), self._committed, self._batches, self._overflows,
                          self._dropped, self._last_error, str(self.path))

    @property
    def committed(self) -> int:
        return self._committed

    # --- lifecycle -----------------------------------------------------------------------------

    def start(self) -> None:
        """Open (or create) the archive and start the writer; sqlite3.Error names the file."""
        problem = archive_problem(self.path)
        if problem is not None:
            raise sqlite3.DatabaseError(f"{self.path}: cannot open the archive: {problem}")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        try:
            self._con = self._open()
        except sqlite3.Error as e:
            raise type(e)(f"{self.path}: cannot open the archive: {e}") from e
        self._thread = threading.Thread(target=self._run, name="registrar-writer", daemon=True)
        self._thread.start()

    def close(self, timeout: float = 30.0) -> None:
        """Write everything queued, then stop the writer and close the file."""
        self._stopping.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout)
            self._thread = None

    # --- writer thread -------------------------------------------------------------------------

    def _open(self) -> sqlite3.Connection:
        con = sqlite3.connect(self.path, isolation_level=None, check_same_thread=False)
        prepared = False
        try:
            self._prepare(con)
            prepared = True
        finally:
            if not prepared:  # whatever ended it, Ctrl+C too: the file is not left open
                con.close()
        self._retain(con)
        return con

    def _prepare(self, con: sqlite3.Connection) -> None:
        """WAL, the shared tables, and the catalog copied in so the file explains itself."""
        con.execute(f"PRAGMA busy_timeout={BUSY_TIMEOUT_MS}")
        con.execute("PRAGMA journal_mode=WAL")
        con.execute("PRAGMA synchronous=NORMAL")
        con.execute("BEGIN IMMEDIATE")
        con.execute(META_SQL)
        con.execute(MESSAGES_SQL)
        con.execute(SERIES_SQL)
        con.execute(TAGS_SQL)
        add_tag_source(con)
        meta = {
            "schema_version": SCHEMA_VERSION,
            "ts_unit": "milliseconds since 1970-01-01 UTC",
            "day_tables": "one per local day, named DD_MM_YYYY",
            "timezone": time.strftime("%Z %z"),
            "timezone_key": local_zone_key(),  # IANA: readers in another zone cut days as written
            "message_types": "0 info, 1 warning, 2 alarm, 3 critical",
        }
        if self.station:
            meta["station"] = self.station
        con.execute("INSERT OR IGNORE INTO meta VALUES ('created', ?)",
                    (dt.datetime.fromtimestamp(self.wallclock()).isoformat(timespec="seconds"),))
        con.executemany("INSERT OR REPLACE INTO meta VALUES (?, ?)", meta.items())
        if len(self.catalog):
            con.execute("DELETE FROM messages")
            con.executemany("INSERT INTO messages VALUES (?, ?, ?, ?)",
                            [(m.number, m.grp, m.type, m.text) for m in self.catalog])
        self._copy_tags(con)
        con.execute("COMMIT")

    def _copy_tags(self, con: sqlite3.Connection) -> None:
        """The station's tags, when they are not the ones the file holds already, and since when
        (`tags_since`, ms like `ts`): the plant archive keeps a version of the tags per change and
        converts each record by the version of its time (registrar/plant/schema.py)."""
        rows = tag_rows(self.tags)
        if not rows or con.execute(TAG_ROWS_SQL).fetchall() == rows:
            return
        con.execute("DELETE FROM tags")
        con.executemany(f"INSERT INTO tags ({', '.join(TAG_FIELDS)}) VALUES "
                        f"({', '.join('?' * len(TAG_FIELDS))})", rows)
        con.execute("INSERT OR REPLACE INTO meta VALUES ('tags_since', ?)",
                    (str(round(self.wallclock() * 1000)),))

    def _run(self) -> None:
        pending: list[Record] = []
        wait = self.flush_interval
        while True:
            self._wake.wait(wait)
            self._wake.clear()
            stopping = self._stopping.is_set()
            pending = self._drain(pending)
            if pending:  # the disk fails: back off, keep the batch
                if stopping:
                    break  # nothing more can be kept; stats.last_error says why
                wait = min(RETRY_MAX, max(wait * 2, self.flush_interval))
            elif stopping:
                if not self._queue:
                    break
                wait = 0.0
            else:
                wait = self.flush_interval
                if self._new_day:
                    self._new_day = False
                    self._retain(self._con)
        assert self._con is not None
        self._con.close()

    def _drain(self, pending: list[Record]) -> list[Record]:
        """Write until the queue is empty; return the batch that failed, if any."""
        while True:
            if not pending:
                pending = self._take()
                if not pending:
                    self._release()  # barriers with no record behind them
                    return []
            if not self._write(pending):
                return pending
            pending = []
            self._release()

    def _release(self) -> None:
        """The barriers taken with a committed batch: their writers may now be answered."""
        due, self._due = self._due, []
        for barrier in due:
            try:
                barrier.callback()
            except Exception as e:  # a waiter's bug must not stop the archive
                logger.exception("archive commit waiter failed")
                self._queue.append(Record(self.wallclock(), "system", source=SOURCE,
                                          text=self.say("waiter failed", error=repr(e))))

    def _take(self) -> list[Record]:
        queue = self._queue
        n = min(len(queue), BATCH_MAX)
        with self._lock:
            batch = [queue.popleft() for _ in range(n)]
            if self._barriers:
                due = [b for b in batch if type(b) is _Barrier]
                if due:
                    self._barriers -= len(due)
                    self._due += due  # type: ignore[arg-type]
                    batch = [r for r in batch if type(r) is not _Barrier]
            dropped = self._dropped
            if self._overflowing and len(queue) < self.queue_size:
                self._overflowing = False
        if dropped > self._reported_drops:
            lost = dropped - self._reported_drops
            self._reported_drops = dropped
            batch.append(Record(self.wallclock(), "system", source=SOURCE,
                                text=self.say("queue full", lost=lost, size=self.queue_size)))
        return batch

    def _write(self, batch: list[Record]) -> bool:
        """One transaction for the batch; on failure keep it for a retry and say so once."""
        con = self._con
        assert con is not None
        try:
            try:
                self._insert(con, batch)
            except _MALFORMED:
                _rollback(con)
                batch[:] = self._valid(batch)
                self._insert(con, batch)
        except (sqlite3.Error, OSError) as e:
            self._failed(con, e, batch)
            return False
        self._committed += len(batch)
        self._batches += 1
        self._last_error = ""
        committed = self._committed
        if self._failing_since is not None:
            seconds = self.wallclock() - self._failing_since
            self._failing_since = None
            logger.warning("archive writing resumed after %.0f s; no records were lost", seconds)
            self._queue.appendleft(Record(self.wallclock(), "system", source=SOURCE,
                                          text=self.say("writing resumed", seconds=seconds)))
            self._wake.set()
        if self.on_commit is not None:
            try:
                self.on_commit(committed)
            except Exception as e:  # a listener's bug must not stop the archive
                logger.exception("archive commit listener failed and was removed")
                self.on_commit = None
                self._queue.append(Record(self.wallclock(), "system", source=SOURCE,
                                          text=self.say("listener removed", error=repr(e))))
        return True

    def _insert(self, con: sqlite3.Connection, batch: list[Record]) -> None:
        tables = self._rows_by_table(batch)
        con.execute("BEGIN IMMEDIATE")
        for table, rows in tables.items():
            self._ensure_table(con, table, rows)
            last = con.execute(f'SELECT max(id) FROM "{table}"').fetchone()[0] or 0
            con.executemany(
                f'INSERT INTO "{table}" (ts, kind, grp, type, source, number, value, text, pid) '
                "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)", rows)
            for sql in aux_fill_sql(table):  # the text index and the per-minute summary
                con.execute(sql, (last,))
        con.execute("COMMIT")

    def _valid(self, batch: list[Record]) -> list[Record]:
        """The well-formed records, and a 'system' record naming what was refused."""
        good = [r for r in batch if _well_formed(r)]
        if len(good) < len(batch):
            bad = [r for r in batch if not _well_formed(r)]
            logger.error("archive refused %d malformed record(s), the first: %.300r", len(bad), bad[0])
            good.append(Record(self.wallclock(), "system", source=SOURCE,
                               text=self.say("malformed", n=len(bad), first=repr(bad[0]))))
        return good

    def _failed(self, con: sqlite3.Connection, error: Exception, batch: list[Record]) -> None:
        _rollback(con)
        self._known.clear()  # tables created in the failed transaction are gone
        text = f"archive write failed: {error}"
        self._last_error = text
        if self._failing_since is None:  # said once; the health strip shows it while it lasts
            logger.warning("%s; records are kept in memory and retried", text)
            self._failing_since = self.wallclock()
            batch.append(Record(self.wallclock(), "system", source=SOURCE,
                                text=self.say("write failed kept", error=error)))

    def _rows_by_table(self, batch: list[Record]) -> dict[str, list[Row]]:
        """Rows for each day table, built in C loops where it counts (a batch is mostly one day)."""
        stamps = [round(ts * 1000) for ts in map(_TS, batch)]
        rows = list(map(operator.add, zip(stamps), map(_REST, batch)))
        kinds = list(map(_KIND, rows))
        i = 0
        with contextlib.suppress(ValueError):  # raised when no message is left
            while True:
                i = kinds.index("message", i)
                rows[i] = self._resolve(rows[i])
                i += 1
        start, end, name = self._day
        if name and start <= min(stamps) and max(stamps) < end:
            return {name: rows}
        tables: dict[str, list[Row]] = {}
        for row in rows:
            if not start <= row[0] < end:
                start, end, name = _day_of(row[0])
            tables.setdefault(name, []).append(row)
        self._day = (start, end, name)
        return tables

    def _resolve(self, row: Row) -> Row:
        """An NMSG record gets its catalog text (and group and type if it named none)."""
        ms, kind, grp, typ, source, number, value, text, pid = row
        if number is None:
            return row
        if text is None:
            text = self.catalog.text_for(number)
        message = self.catalog.get(number)
        if message is not None:
            grp = message.grp if grp is None else grp
            typ = message.type if typ is None else typ
        return (ms, kind, grp, typ, source, number, value, text, pid)

    def _ensure_table(self, con: sqlite3.Connection, table: str, rows: list[Row]) -> None:
        known = self._known.get(table)
        if known is None:
            con.execute(f'CREATE TABLE IF NOT EXISTS "{table}" {DAY_COLUMNS_SQL}')
            if not has_pid(con, table):  # a day table of an archive from before the column
                con.execute(f'ALTER TABLE "{table}" ADD COLUMN pid INTEGER')
            for sql in index_sql(table):
                con.execute(sql)
            older = con.execute("SELECT 1 FROM sqlite_master WHERE name = ?",
                                (fts_table(table),)).fetchone() is None
            for sql in aux_sql(table):
                con.execute(sql)
            if older:  # a day written before the text index and summary (or a new one): fill them
                for sql in aux_fill_sql(table):
                    con.execute(sql, (0,))
            known = {tuple(k) for k in con.execute(
                "SELECT kind, grp, type, source FROM series WHERE day = ?", (table,))}
            self._known[table] = known
            self._new_day = True
        new = {key for key in set(map(_KEY, rows)) if key[0] == "data"} - known
        if new:
            con.executemany("INSERT OR IGNORE INTO series VALUES (?, ?, ?, ?, ?)",
                            [(table, *key) for key in new])
            known |= new

    def _retain(self, con: sqlite3.Connection | None) -> None:
        """Retention, run after a commit that opened a day table (and at start); never VACUUM."""
        if self.keep_days <= 0 or con is None:
            return
        try:
            self._drop_old_days(con)
        except sqlite3.Error as e:
            _rollback(con)
            self._last_error = f"dropping old days failed: {e}"
            logger.warning("archive %s: %s", self.path, self._last_error)

    def _drop_old_days(self, con: sqlite3.Connection) -> None:
        """Whole day tables older than keep_days go; their pages are reused by later days."""
        today = dt.date.fromtimestamp(self.wallclock())
        oldest = today - dt.timedelta(days=self.keep_days - 1)
        names = [n for (n,) in con.execute(
            "SELECT name FROM sqlite_master WHERE type = 'table' AND name GLOB ?", (DAY_GLOB,))]
        old = [n for n in names if (d := parse_table_name(n)) is not None and d < oldest]
        if not old:
            return
        con.execute("BEGIN IMMEDIATE")
        for name in old:
            con.execute(f'DROP TABLE "{name}"')
            con.execute(f'DROP TABLE IF EXISTS "{fts_table(name)}"')
            con.execute(f'DROP TABLE IF EXISTS "{minutes_table(name)}"')
            con.execute("DELETE FROM series WHERE day = ?", (name,))
            self._known.pop(name, None)
        con.execute("COMMIT")
