"""The arbiter of a hot-standby pair: the primary's lease on the plant archive's PostgreSQL.

When the link between the two stations of a pair breaks while both run, each sees its partner
silent; only the one that holds this lease may act as primary (docs/architecture.md section 11).
The lease is a session-level advisory lock (`pg_try_advisory_lock`) on a connection of its own:
PostgreSQL releases it when that session ends, so a primary that dies, or loses the server for
longer than its TCP keepalive, frees it for the standby without anyone's help.

The order of the two ends matters when the network parts the primary from the server: the
primary must give up before the server frees the lock for the standby. The lease's session asks
the server to drop a silent client after LEASE_SERVER_DROP s (its TCP keepalive), while the
primary's check gives up on an unanswered query after LEASE_CLIENT_GIVES_UP s (libpq's
tcp_user_timeout): the primary steps down seconds before its partner may lead.
"""

from __future__ import annotations

import hashlib
import logging

import psycopg

from registrar.plant.schema import connect

logger = logging.getLogger(__name__)

LEASE_CLIENT_GIVES_UP = 1.0  # s: an unacknowledged query to the arbiter fails the check
KEEPALIVE_IDLE, KEEPALIVE_INTERVAL, KEEPALIVE_COUNT = 2, 1, 2  # the server's probes of the client
LEASE_SERVER_DROP = KEEPALIVE_IDLE + KEEPALIVE_INTERVAL * KEEPALIVE_COUNT  # s before the lock is freed
_SERVER_KEEPALIVE = (f"-c tcp_keepalives_idle={KEEPALIVE_IDLE}"
                     f" -c tcp_keepalives_interval={KEEPALIVE_INTERVAL}"
                     f" -c tcp_keepalives_count={KEEPALIVE_COUNT}")


def lease_key(station: str) -> int:
    """The advisory lock's 64-bit key for one station's pair (both stations share the name)."""
    return int.from_bytes(hashlib.sha256(f"netplc pair {station}".encode()).digest()[:8], "big",
                          signed=True)


class Lease:
    """`take()` as often as wanted, `alive()` to learn that it is still held, `release()`."""

    def __init__(self, url: str, station: str, timeout: float = 1.0) -> None:
        self.url = url
        self.key = lease_key(station)
        self.timeout = timeout
        self.held = False
        self.last_error = ""
        self._con: psycopg.Connection | None = None

    def take(self) -> bool:
        """True when this station holds the lease now (taken, or held already); False when the
        partner holds it or the server does not answer (`last_error` says which)."""
        if self.held and self.alive():
            return True
        try:
            if self._con is None or self._con.closed:
                self._con = connect(self.url, timeout=self.timeout, options=_SERVER_KEEPALIVE,
                                    tcp_user_timeout=round(LEASE_CLIENT_GIVES_UP * 1000))
            row = self._con.execute("SELECT pg_try_advisory_lock(%s)", (self.key,)).fetchone()
        except psycopg.Error as e:
            self._lost(e)
            return False
        self.held = bool(row and row[0])
        self.last_error = "" if self.held else "the partner holds the lease"
        return self.held

    def alive(self) -> bool:
        """The lease's session still answers (a primary checks this every tick)."""
        if self._con is None or not self.held:
            return False
        try:
            self._con.execute("SELECT 1")
        except psycopg.Error as e:
            self._lost(e)
            return False
        return True

    def release(self) -> None:
        """End the session: PostgreSQL frees the lock with it."""
        con, self._con, self.held = self._con, None, False
        if con is not None:
            con.close()

    def _lost(self, e: psycopg.Error) -> None:
        self.last_error = f"the arbiter does not answer: {str(e).strip() or type(e).__name__}"
        logger.warning("pair arbiter: %s", self.last_error)
        self.release()
