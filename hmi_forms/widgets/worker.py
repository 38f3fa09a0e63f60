"""Work off the GUI thread: one thread of jobs per view, each answer handed back as a signal.

A view that reads the archive (the journal element and dock, the viewer's pages and series, trend
history, the alarm-system health) or a station (the remote monitor's login, the designer's live
preview) must not wait for it on the GUI thread: a journal page of 100,000 rows or a day of a
10 Hz series takes up to a second, a station that does not answer a few, and a window that waits
that long stops repainting and answering. Every such view runs its work through this one base.
Each view gets one thread, so its reads run in order and never share a connection at once; each
answer comes back to the GUI thread as a queued signal carrying the request's token. Requests
under one topic supersede each other (the newest request wins): a newer one cancels the older
ones still queued and drops the answer of one already running, so a slow read never piles up a
queue behind it and the view never shows an answer older than the last thing asked. A failure is
logged (with its traceback unless it is one the view expects) and answered, for the view to say.

The thread's state is a plain object apart from the QObject, so that a view destroyed by its
parent still stops its thread (`destroyed`) and no answer is emitted on a deleted object.

Closing (a window that closes) drops the queued jobs and waits for the one under way at most
`CLOSE_WAIT_S`: a day of a 10 Hz series is read in about half a second, but a station's archive
read from a console waits up to a minute for a station that does not answer, and a plant archive
up to its connect timeout, which the GUI thread must not wait for. A job still running then ends
on its own, its answer dropped; what it opened is closed (`on_close`) on the worker thread once
it has ended, never under it.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Hashable
from concurrent.futures import Future, ThreadPoolExecutor, wait

from PySide6.QtCore import QObject, Signal

logger = logging.getLogger(__name__)

Job = Callable[[], object]
CLOSE_WAIT_S = 1.0  # how long a close waits for the job under way (the window's GUI thread waits)


class Worker(QObject):
    answered = Signal(int, object)  # token, what the job returned
    failed = Signal(int, str)  # token, why

    def __init__(self, name: str, expected: tuple[type[Exception], ...] = (),
                 parent: QObject | None = None, *, on_close: Callable[[], None] | None = None) -> None:
        """`expected`: the errors a job may meet in normal use (an archive gone or unreadable, a
        link down), answered as `failed` and logged without a traceback, once while the same one
        repeats; any other is logged with its own.
        `on_close`: runs once no job runs any more (closes what the jobs opened)."""
        super().__init__(parent)
        self._thread = _Thread(name, expected, self.answered.emit, self.failed.emit, on_close)
        self._token = 0
        self.destroyed.connect(self._thread.close)

    def submit(self, job: Job, topic: Hashable | None = None) -> int:
        """Run `job` on the worker thread; the token its `answered` or `failed` will carry."""
        self._token += 1
        self._thread.submit(self._token, job, topic)
        return self._token

    @property
    def closed(self) -> bool:
        return self._thread.closed

    def close(self) -> None:
        """Drop the queued jobs and wait for the one under way, at most CLOSE_WAIT_S (a second call
        does nothing)."""
        self._thread.close()


class _Thread:
    """What the GUI thread and the worker thread share; it outlives the QObject."""

    def __init__(self, name: str, expected: tuple[type[Exception], ...],
                 answer: Callable[[int, object], None], fail: Callable[[int, str], None],
                 on_close: Callable[[], None] | None) -> None:
        self.name = name
        self.expected = expected
        self.answer, self.fail = answer, fail
        self.on_close = on_close
        self.pool = ThreadPoolExecutor(1, thread_name_prefix=name)
        self.lock = threading.Lock()  # held while answering: closing waits for an answer under way
        self.closed = False
        self.newest: dict[Hashable, int] = {}
        self.queued: dict[Hashable, Future] = {}
        self.pending: set[Future] = set()  # every job not yet ended, to drop the queued ones at close
        self.said: str | None = None  # the expected failure logged last, until a job succeeds

    def submit(self, token: int, job: Job, topic: Hashable | None) -> None:
        with self.lock:
            if self.closed:
                raise RuntimeError(f"{self.name}: the worker is closed")
            if topic is not None:
                self.newest[topic] = token
                older = self.queued.pop(topic, None)
                if older is not None:
                    older.cancel()  # only if it has not started; its answer is dropped otherwise
            future = self.pool.submit(self.run, token, job, topic)
            self.pending.add(future)
            future.add_done_callback(self.pending.discard)
            if topic is not None:
                self.queued[topic] = future

    def current(self, token: int, topic: Hashable | None) -> bool:
        return not self.closed and (topic is None or self.newest.get(topic) == token)

    def run(self, token: int, job: Job, topic: Hashable | None) -> None:
        if not self.current(token, topic):
            return
        try:
            result = job()
        except self.expected as e:
            if str(e) != self.said:  # one that repeats (a link down, polled) is logged once
                self.said = str(e)
                logger.warning("%s: %s", self.name, e)
            self.answer_with(token, topic, self.fail, str(e))
        except Exception as e:
            logger.exception("%s: a job failed", self.name)
            self.answer_with(token, topic, self.fail, f"{type(e).__name__}: {e}")
        else:
            self.said = None
            self.answer_with(token, topic, self.answer, result)

    def answer_with(self, token: int, topic: Hashable | None, emit: Callable, what: object) -> None:
        with self.lock:
            if self.current(token, topic):
                emit(token, what)

    def close(self) -> None:
        with self.lock:
            if self.closed:
                return
            self.closed = True
            for future in self.pending.copy():
                future.cancel()  # the queued ones; the one under way runs on, its answer dropped
        running = wait([f for f in self.pending.copy() if not f.cancelled()], CLOSE_WAIT_S).not_done
        if running:  # one at most: the pool has one thread
            logger.warning("%s: closed while a job has run for more than %g s: it ends on its own "
                           "(its answer dropped, then what it opened closed)", self.name, CLOSE_WAIT_S)
            running.pop().add_done_callback(lambda _job: self.closing())  # on the worker thread
            self.pool.shutdown(wait=False)
            return
        self.pool.shutdown(wait=True)  # nothing runs: the thread ends at once
        self.closing()

    def closing(self) -> None:
        if self.on_close is None:
            return
        try:
            self.on_close()
        except Exception:  # after a job that outlived the close, nobody is there to be told
            logger.exception("%s: closing what the jobs opened failed", self.name)
