"""Logins of remote clients (OPC UA today, any seat that takes a name and a password over a network).

A password is guessed by trying, so each host that fails gets slower answers: after `free` failed
logins the next attempts from that host within a back-off (1 s, doubling to `longest`) are refused
without looking at the password, and the count is forgotten after `forget` seconds without a
failure. Every failure is journaled through the command layer's refusals, so one record per user
name and host per minute carries the count of the others. An unknown name costs the same scrypt as
a wrong password (`Users.verify`): the time of a refusal does not say which names exist.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

from app.authority.layer import Commands, Reason, Who
from app.authority.policy import Source
from app.authority.users import User, UserError, Users

logger = logging.getLogger(__name__)

LOG_IN = "log in"  # the refusal's action word (no role is needed to try)
FREE = 3  # failed logins from one host before the back-off starts
LONGEST = 60.0  # s: the longest back-off
FORGET = 900.0  # s without a failure after which a host's failures are forgotten
HOSTS = 4096  # hosts remembered at most (the oldest forgotten first)


class Logins:
    def __init__(self, users: Callable[[], Users], commands: Commands, source: Source, *, free: int = FREE,
                 longest: float = LONGEST, forget: float = FORGET,
                 monotonic: Callable[[], float] = time.monotonic) -> None:
        """`users()` reads the station's users at each login, so a user added or removed counts
        at once."""
        self.users = users
        self.commands = commands
        self.source = source
        self.free = free
        self.longest = longest
        self.forget = forget
        self.monotonic = monotonic
        self._failed: dict[str, tuple[int, float]] = {}  # host -> (failures, time of the last)
        self._lock = threading.Lock()

    def backoff(self, failures: int) -> float:
        """Seconds a host waits after its last failure, having failed `failures` times."""
        if failures < self.free:
            return 0.0
        return min(2.0 ** (failures - self.free), self.longest)

    def login(self, name: str, password: str, peer: str) -> User | None:
        """The user if `password` is theirs and `peer` (host:port) is not backing off; else None,
        journaled."""
        host = peer.rsplit(":", 1)[0]
        who = Who("", self.source, f"{name}@{peer}")  # not a user until the password is checked
        now = self.monotonic()
        with self._lock:
            failures, last = self._failed.get(host, (0, now))
            if now - last > self.forget:
                failures = 0
        wait = self.backoff(failures) - (now - last)
        if wait > 0:
            self.commands.refuse(who, LOG_IN, "", Reason.BUSY,
                                 self.commands.say("login waits", n=failures, host=host, wait=wait))
            return None
        try:
            user = self.users().verify(name, password)
        except UserError as e:  # a broken users file: nobody logs in, and the journal says why
            logger.exception("users not readable at a login from %s", peer)
            self.commands.refuse(who, LOG_IN, "", Reason.FAILED, str(e))
            return None
        if user is not None:
            return user
        with self._lock:
            failures, last = self._failed.get(host, (0, now))
            failures = 1 if now - last > self.forget else failures + 1
            self._failed[host] = (failures, now)
            if len(self._failed) > HOSTS:
                for old in sorted(self._failed, key=lambda h: self._failed[h][1])[:HOSTS // 4]:
                    del self._failed[old]
        why = self.commands.say("login wrong wait", wait=self.backoff(failures)) if failures >= self.free \
            else self.commands.say("login wrong")
        self.commands.refuse(who, LOG_IN, "", Reason.DENIED, why)
        return None
